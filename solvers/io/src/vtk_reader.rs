//! Reading back the VTK XML files of [`crate::vtk`]: the arrays of one
//! file with raw appended data, for tests and tools that check what a run
//! wrote without ParaView. It reads what grainflow writes (every array
//! appended, UInt64 byte counts, little-endian), not VTK XML in general.

use std::collections::BTreeMap;

/// One array of a file: its VTK type, components and raw little-endian
/// bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct RawArray {
    pub vtk_type: String,
    pub components: usize,
    pub bytes: Vec<u8>,
}

impl RawArray {
    /// The values of a Float64 array.
    pub fn f64s(&self) -> Vec<f64> {
        assert_eq!(self.vtk_type, "Float64", "not a Float64 array");
        self.bytes
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
            .collect()
    }
}

/// A file read back: its XML (everything before the appended data) and
/// its arrays by name.
#[derive(Clone, Debug)]
pub struct VtkFile {
    pub xml: String,
    pub arrays: BTreeMap<String, RawArray>,
}

/// Reads a whole file; an error names what is missing or cut short (a
/// file killed while being written fails here).
pub fn read_vtk(bytes: &[u8]) -> Result<VtkFile, String> {
    const START: &[u8] = b"<AppendedData encoding=\"raw\">\n_";
    const END: &[u8] = b"\n</AppendedData>\n</VTKFile>\n";
    let start = find(bytes, START).ok_or("no raw appended data")?;
    let xml = std::str::from_utf8(&bytes[..start])
        .map_err(|_| "the XML part is not UTF-8")?
        .to_string();
    if !xml.starts_with("<?xml") {
        return Err("no XML declaration".into());
    }
    if !bytes.ends_with(END) {
        return Err("the file does not end with the appended block's closing tags".into());
    }
    let block = &bytes[start + START.len()..bytes.len() - END.len()];
    let mut arrays = BTreeMap::new();
    let mut expected_end = 0;
    for element in xml.split("<DataArray ").skip(1) {
        let attribute = |name: &str| -> Result<String, String> {
            let key = format!("{name}=\"");
            let rest = element
                .split_once(&key)
                .ok_or(format!("a DataArray without {name}"))?
                .1;
            Ok(rest.split('"').next().unwrap_or_default().to_string())
        };
        let offset: usize = attribute("offset")?
            .parse()
            .map_err(|_| "an offset that is not a number")?;
        let count_bytes = block
            .get(offset..offset + 8)
            .ok_or("an array beyond the appended block")?;
        let count = u64::from_le_bytes(count_bytes.try_into().expect("8 bytes")) as usize;
        let values = block
            .get(offset + 8..offset + 8 + count)
            .ok_or("an array cut short")?;
        expected_end = expected_end.max(offset + 8 + count);
        arrays.insert(
            attribute("Name")?,
            RawArray {
                vtk_type: attribute("type")?,
                components: attribute("NumberOfComponents")?
                    .parse()
                    .map_err(|_| "components that are not a number")?,
                bytes: values.to_vec(),
            },
        );
    }
    if expected_end != block.len() {
        return Err(format!(
            "the appended block holds {} bytes, its arrays {expected_end}",
            block.len()
        ));
    }
    Ok(VtkFile { xml, arrays })
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack
        .windows(needle.len())
        .position(|window| window == needle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vtk::{CellLayout, FieldFrame, ParticleFrame};

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("grainflow-vtk-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn a_field_frame_reads_back_bit_for_bit() {
        let dir = scratch("fields");
        let pressure: Vec<f64> = (0..24).map(|k| 0.1 * k as f64 - 1.0 / 3.0).collect();
        let velocity: Vec<[f64; 3]> = (0..24).map(|k| [k as f64, -1e-300, f64::MAX]).collect();
        let frame = FieldFrame {
            cells: [2, 3, 4],
            offset: [0; 3],
            layout: CellLayout::Uniform {
                origin: [0.0; 3],
                spacing: [0.5; 3],
            },
            scalars: &[("pressure", &pressure)],
            vectors: &[("velocity", &velocity)],
        };
        let path = dir.join("f.vti");
        frame.write(&path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let file = read_vtk(&bytes).unwrap();
        assert!(file.xml.contains(r#"<ImageData WholeExtent="0 2 0 3 0 4""#));
        assert_eq!(file.arrays["pressure"].f64s(), pressure);
        assert_eq!(file.arrays["velocity"].components, 3);
        assert_eq!(file.arrays["velocity"].f64s(), velocity.as_flattened());
        // Cut short anywhere, the file is refused.
        for cut in [bytes.len() - 1, bytes.len() - 30, bytes.len() / 2, 100] {
            assert!(read_vtk(&bytes[..cut]).is_err(), "cut at {cut}");
        }
    }

    #[test]
    fn a_particle_frame_reads_back_bit_for_bit() {
        let dir = scratch("particles");
        let position = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]];
        let frame = ParticleFrame {
            id: &[7, u64::MAX],
            position: &position,
            velocity: &[[0.5; 3]; 2],
            angular_velocity: &[[-0.5; 3]; 2],
            force: &[[1e-9; 3]; 2],
            radius: &[1e-3, 2e-3],
            fixed: &[0, 1],
            group: &[3, 0],
        };
        let path = dir.join("p.vtp");
        frame.write(&path).unwrap();
        let file = read_vtk(&std::fs::read(&path).unwrap()).unwrap();
        assert_eq!(file.arrays["position"].f64s(), position.as_flattened());
        assert_eq!(file.arrays["radius"].f64s(), [1e-3, 2e-3]);
        assert_eq!(file.arrays["fixed"].bytes, [0, 1]);
        assert_eq!(file.arrays["group"].bytes[..8], 3u64.to_le_bytes());
        let id = &file.arrays["id"];
        assert_eq!(id.vtk_type, "UInt64");
        assert_eq!(id.bytes[8..], u64::MAX.to_le_bytes());
        let offsets = &file.arrays["offsets"];
        assert_eq!(
            (offsets.vtk_type.as_str(), offsets.bytes.len()),
            ("Int64", 16)
        );
    }
}
