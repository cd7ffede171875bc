//! Bytes and seconds of the HDF5 and VTK writers on the same data: a field
//! frame of 128³ cells (pressure, velocity, vorticity: what a fluid scene
//! writes) and a particle frame of 10⁵ grains, on one process. Each writer
//! runs three times; the best time is printed.
//!
//! usage: cargo run --release -p grainflow-io --features hdf5 --example hdf5_vs_vtk [-- DIR [CELLS [GRAINS]]]

use grainflow_io::hdf5::{FieldFrameH5, ParticleFrameH5, Writers};
use grainflow_io::{CellLayout, FieldFrame, ParticleFrame};
use std::path::Path;
use std::time::Instant;

fn main() -> std::io::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let dir = args
        .get(1)
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("grainflow-hdf5-vs-vtk"));
    let n: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(128);
    let grains: usize = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(100_000);
    std::fs::create_dir_all(&dir)?;

    let cells = [n, n, n];
    let count = n * n * n;
    let pressure: Vec<f64> = (0..count).map(|c| (c as f64 * 1e-3).sin()).collect();
    let velocity: Vec<[f64; 3]> = (0..count)
        .map(|c| [0.0, 1.0, 2.0].map(|a| (c as f64 * 1e-3 + a).cos()))
        .collect();
    let vorticity: Vec<[f64; 3]> = velocity.iter().map(|v| v.map(|x| 2.0 * x - 1.0)).collect();
    let layout = CellLayout::Uniform {
        origin: [0.0; 3],
        spacing: [1.0 / n as f64; 3],
    };
    let scalars: [(&str, &[f64]); 1] = [("pressure", &pressure)];
    let vectors: [(&str, &[[f64; 3]]); 2] = [("velocity", &velocity), ("vorticity", &vorticity)];
    let vti = dir.join("fields.vti");
    let h5 = dir.join("fields.h5");
    let vtk_seconds = best_of_three(|| {
        FieldFrame {
            cells,
            offset: [0; 3],
            layout,
            scalars: &scalars,
            vectors: &vectors,
        }
        .write(&vti)
    })?;
    let hdf5_seconds = best_of_three(|| {
        FieldFrameH5 {
            time: 0.0,
            global_cells: cells,
            offset: [0; 3],
            cells,
            layout,
            scalars: &scalars,
            vectors: &vectors,
        }
        .write(&h5, &Writers::serial())
    })?;
    let raw = (count * 7 * 8) as f64;
    println!("field frame, {n}^3 cells ({:.1} MB of float64):", raw / 1e6);
    report("VTK  .vti", &vti, vtk_seconds)?;
    report("HDF5 .h5 ", &h5, hdf5_seconds)?;

    let id: Vec<u64> = (0..grains as u64).collect();
    let v = |s: f64| -> Vec<[f64; 3]> {
        id.iter()
            .map(|&k| [0.0, 1.0, 2.0].map(|c| (s * k as f64 + c).sin()))
            .collect()
    };
    let (position, velocity, spin, force) = (v(1e-3), v(2e-3), v(3e-3), v(4e-3));
    let radius: Vec<f64> = id
        .iter()
        .map(|&k| 1e-3 * (1.0 + (k % 10) as f64 * 0.01))
        .collect();
    let fixed = vec![0u8; grains];
    let contacts: Vec<u32> = id.iter().map(|&k| (k % 7) as u32).collect();
    let vtp = dir.join("particles.vtp");
    let h5 = dir.join("particles.h5");
    let vtk_seconds = best_of_three(|| {
        ParticleFrame {
            id: &id,
            position: &position,
            velocity: &velocity,
            angular_velocity: &spin,
            force: &force,
            radius: &radius,
            fixed: &fixed,
        }
        .write(&vtp)
    })?;
    let hdf5_seconds = best_of_three(|| {
        ParticleFrameH5 {
            time: 0.0,
            id: &id,
            position: &position,
            velocity: &velocity,
            angular_velocity: &spin,
            force: &force,
            radius: &radius,
            contacts: &contacts,
            fixed: &fixed,
        }
        .write(&h5, &Writers::serial())
        .map(|_| ())
    })?;
    println!("particle frame, {grains} grains:");
    report("VTK  .vtp", &vtp, vtk_seconds)?;
    report("HDF5 .h5 ", &h5, hdf5_seconds)?;
    println!("(the HDF5 particle frame also holds a uint32 contact count per grain)");
    Ok(())
}

/// The shortest of three runs of `write` [s].
fn best_of_three(mut write: impl FnMut() -> std::io::Result<()>) -> std::io::Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let start = Instant::now();
        write()?;
        best = best.min(start.elapsed().as_secs_f64());
    }
    Ok(best)
}

fn report(label: &str, path: &Path, seconds: f64) -> std::io::Result<()> {
    let bytes = std::fs::metadata(path)?.len();
    println!(
        "  {label}: {bytes:>11} bytes, {seconds:.3} s ({:.0} MB/s)",
        bytes as f64 / seconds / 1e6
    );
    Ok(())
}
