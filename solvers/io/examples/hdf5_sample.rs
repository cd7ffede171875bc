//! Writes a small sample run of HDF5 frames with their XDMF indices into
//! the folder given as argument, for readers to check against (CI opens it
//! in ParaView with `tests/paraview_xdmf.py`):
//!
//! - `fields.xdmf`: three frames of a uniform 3D grid of 6 × 4 × 3 cells
//!   (pressure, solid_fraction, velocity, vorticity) at t = 0, 0.5, 1;
//! - `stretched.xdmf`: one frame of a 2D grid of 5 × 4 cells stretched
//!   along y (one cell thick along z), at t = 0.25;
//! - `particles.xdmf`: three frames of 7, 9 and no grains at t = 0, 0.5, 1.
//!
//! Every value is a function of the cell, the field and the time, so a
//! reader can check them against the HDF5 datasets. The same frames are
//! also written as VTK files beside them (`fields.pvd`, `stretched.pvd`,
//! `particles.pvd`), for readers of both formats to compare
//! (`postprocess/read_output.py --compare DIR`).
//!
//! usage: cargo run --release -p grainflow-io --features hdf5 --example hdf5_sample -- DIR

use grainflow_io::hdf5::{FieldFrameH5, FieldGridDescription, ParticleFrameH5, Writers, XdmfIndex};
use grainflow_io::{CellLayout, FieldFrame, ParticleFrame, PvdIndex};
use std::path::Path;

fn main() -> std::io::Result<()> {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: hdf5_sample DIR");
        std::process::exit(2);
    };
    let dir = Path::new(&dir);
    std::fs::create_dir_all(dir.join("fields"))?;
    std::fs::create_dir_all(dir.join("particles"))?;
    let writers = Writers::serial();

    let cells = [6, 4, 3];
    let (origin, spacing) = ([-1.0, 0.0, 0.5], [0.25, 0.5, 1.0]);
    let mut index = XdmfIndex::new(dir.join("fields.xdmf"), "fields");
    let mut pvd = PvdIndex::new(dir.join("fields.pvd"));
    for (frame, time) in [0.0, 0.5, 1.0].into_iter().enumerate() {
        let name = format!("fields/fields_{frame:06}");
        write_fields(
            dir,
            &name,
            &writers,
            time,
            cells,
            CellLayout::Uniform { origin, spacing },
        )?;
        index.add_fields(
            time,
            &format!("{name}.h5"),
            &description(cells, Some((origin, spacing))),
        )?;
        pvd.add(time, &format!("{name}.vti"))?;
    }

    let cells = [5, 4, 1];
    let faces = [
        vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0],
        vec![0.0, 0.1, 0.3, 0.6, 1.0],
        vec![0.0, 0.2],
    ];
    let layout = CellLayout::Rectilinear {
        faces: [&faces[0], &faces[1], &faces[2]],
    };
    let name = "fields/stretched_000000";
    write_fields(dir, name, &writers, 0.25, cells, layout)?;
    XdmfIndex::new(dir.join("stretched.xdmf"), "stretched").add_fields(
        0.25,
        &format!("{name}.h5"),
        &description(cells, None),
    )?;
    PvdIndex::new(dir.join("stretched.pvd")).add(0.25, &format!("{name}.vtr"))?;

    let mut index = XdmfIndex::new(dir.join("particles.xdmf"), "particles");
    let mut pvd = PvdIndex::new(dir.join("particles.pvd"));
    for (frame, (time, n)) in [(0.0, 7u64), (0.5, 9), (1.0, 0)].into_iter().enumerate() {
        let name = format!("particles/particles_{frame:06}");
        let id: Vec<u64> = (0..n).collect();
        let v = |s: f64| -> Vec<[f64; 3]> {
            id.iter()
                .map(|&k| [0.0, 1.0, 2.0].map(|c| s * k as f64 + c + time))
                .collect()
        };
        let (position, velocity, spin, force) = (v(0.1), v(-1.0), v(2.0), v(0.5));
        let radius: Vec<f64> = id.iter().map(|&k| 0.01 * (1.0 + k as f64)).collect();
        let fixed: Vec<u8> = id.iter().map(|&k| u8::from(k == 0)).collect();
        let group = vec![0u64; id.len()];
        let contacts: Vec<u32> = id.iter().map(|&k| (k % 4) as u32).collect();
        let count = ParticleFrameH5 {
            time,
            id: &id,
            position: &position,
            velocity: &velocity,
            angular_velocity: &spin,
            force: &force,
            radius: &radius,
            contacts: &contacts,
            fixed: &fixed,
            group: &group,
        }
        .write(&dir.join(format!("{name}.h5")), &writers)?;
        index.add_particles(time, &format!("{name}.h5"), count)?;
        ParticleFrame {
            id: &id,
            position: &position,
            velocity: &velocity,
            angular_velocity: &spin,
            force: &force,
            radius: &radius,
            fixed: &fixed,
            group: &group,
        }
        .write(&dir.join(format!("{name}.vtp")))?;
        pvd.add(time, &format!("{name}.vtp"))?;
    }
    println!("sample HDF5 frames and XDMF indices in {}", dir.display());
    Ok(())
}

const SCALARS: [&str; 2] = ["pressure", "solid_fraction"];
const VECTORS: [&str; 2] = ["velocity", "vorticity"];

fn description(
    cells: [usize; 3],
    uniform: Option<([f64; 3], [f64; 3])>,
) -> FieldGridDescription<'static> {
    FieldGridDescription {
        cells,
        uniform,
        scalars: &SCALARS,
        vectors: &VECTORS,
    }
}

/// Fields whose value in cell (i, j, k) is `f·100 + i + 10 j + 0.01 k + t`
/// (plus `c·1000` for component c of a vector), as `dir/name.h5` and as
/// the VTK file `dir/name.vti` (uniform) or `.vtr` (rectilinear).
fn write_fields(
    dir: &Path,
    name: &str,
    writers: &Writers,
    time: f64,
    cells: [usize; 3],
    layout: CellLayout,
) -> std::io::Result<()> {
    let mut indices = Vec::new();
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                indices.push([i, j, k].map(|n| n as f64));
            }
        }
    }
    let value = |f: usize, c: usize, [i, j, k]: [f64; 3]| {
        100.0 * f as f64 + 1000.0 * c as f64 + i + 10.0 * j + 0.01 * k + time
    };
    let scalars: Vec<Vec<f64>> = (0..2)
        .map(|f| indices.iter().map(|&x| value(f, 0, x)).collect())
        .collect();
    let vectors: Vec<Vec<[f64; 3]>> = (2..4)
        .map(|f| {
            indices
                .iter()
                .map(|&x| [0, 1, 2].map(|c| value(f, c, x)))
                .collect()
        })
        .collect();
    let scalars: Vec<(&str, &[f64])> = SCALARS
        .iter()
        .zip(&scalars)
        .map(|(n, v)| (*n, &v[..]))
        .collect();
    let vectors: Vec<(&str, &[[f64; 3]])> = VECTORS
        .iter()
        .zip(&vectors)
        .map(|(n, v)| (*n, &v[..]))
        .collect();
    FieldFrame {
        cells,
        offset: [0; 3],
        layout,
        scalars: &scalars,
        vectors: &vectors,
    }
    .write(&dir.join(format!("{name}.{}", layout.extension())))?;
    FieldFrameH5 {
        time,
        global_cells: cells,
        offset: [0; 3],
        cells,
        layout,
        scalars: &scalars,
        vectors: &vectors,
    }
    .write(&dir.join(format!("{name}.h5")), writers)
}
