//! Quantities as messages print them.

/// `bytes` in KiB, MiB, GiB or TiB.
pub fn human_bytes(bytes: f64) -> String {
    let mib = bytes / (1u64 << 20) as f64;
    if mib < 1.0 {
        format!("{:.1} KiB", bytes / 1024.0)
    } else if mib < 1024.0 {
        format!("{mib:.1} MiB")
    } else if mib < 1024.0 * 1024.0 {
        format!("{:.1} GiB", mib / 1024.0)
    } else {
        format!("{:.1} TiB", mib / (1024.0 * 1024.0))
    }
}
