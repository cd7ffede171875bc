//! Bytes and seconds of the HDF5 and VTK writers on the same data: a field
//! frame of 128³ cells (pressure, velocity, vorticity: what a fluid scene
//! writes) and a particle frame of 10⁵ grains. Each writer runs three
//! times; the best time is printed.
//!
//! On one process by default. Built with the feature `mpi` too and started
//! with `mpirun -n N`, the ranks share the grid along z and the grains
//! evenly, as a run does: VTK writes one piece per rank and the root its
//! `.pvti`/`.pvtp` index, HDF5 one file written collectively; the time is
//! the slowest rank's, the bytes those of every file of the frame.
//!
//! usage: cargo run --release -p grainflow-io --features hdf5 --example hdf5_vs_vtk [-- DIR [CELLS [GRAINS]]]

use grainflow_io::hdf5::{FieldFrameH5, ParticleFrameH5, Writers};
use grainflow_io::{
    write_field_pieces_index, write_particle_pieces_index, CellLayout, FieldFrame, FieldPiece,
    ParticleFrame,
};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn main() -> std::io::Result<()> {
    #[cfg(feature = "mpi")]
    let universe = mpi::initialize().expect("MPI initialises");
    #[cfg(feature = "mpi")]
    let world = universe.world();
    #[cfg(feature = "mpi")]
    let writers = Writers::mpi(&world);
    #[cfg(not(feature = "mpi"))]
    let writers = Writers::serial();
    let barrier = || {
        #[cfg(feature = "mpi")]
        mpi::traits::CommunicatorCollectives::barrier(&world);
    };
    let (rank, ranks) = (writers.rank(), writers.size());
    let root = rank == 0;

    let args: Vec<String> = std::env::args().collect();
    let dir = args
        .get(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| std::env::temp_dir().join("grainflow-hdf5-vs-vtk"));
    let n: usize = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(128);
    let grains: usize = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(100_000);
    std::fs::create_dir_all(&dir)?;

    // This rank's layers along z.
    let share = |total: usize, r: usize| (total * r / ranks, total * (r + 1) / ranks);
    let (z0, z1) = share(n, rank);
    let (global, offset, cells) = ([n, n, n], [0, 0, z0], [n, n, z1 - z0]);
    let first = z0 * n * n;
    let count = cells.iter().product::<usize>();
    let pressure: Vec<f64> = (first..first + count)
        .map(|c| (c as f64 * 1e-3).sin())
        .collect();
    let velocity: Vec<[f64; 3]> = (first..first + count)
        .map(|c| [0.0, 1.0, 2.0].map(|a| (c as f64 * 1e-3 + a).cos()))
        .collect();
    let vorticity: Vec<[f64; 3]> = velocity.iter().map(|v| v.map(|x| 2.0 * x - 1.0)).collect();
    let layout = CellLayout::Uniform {
        origin: [0.0; 3],
        spacing: [1.0 / n as f64; 3],
    };
    let scalars: [(&str, &[f64]); 1] = [("pressure", &pressure)];
    let vectors: [(&str, &[[f64; 3]]); 2] = [("velocity", &velocity), ("vorticity", &vorticity)];
    let piece = |r: usize| format!("fields_{r:04}.vti");
    let vtk_files: Vec<PathBuf> = if ranks == 1 {
        vec![dir.join("fields.vti")]
    } else {
        let mut files: Vec<PathBuf> = (0..ranks).map(|r| dir.join(piece(r))).collect();
        files.push(dir.join("fields.pvti"));
        files
    };
    let vtk_seconds = best_of_three(&barrier, || {
        FieldFrame {
            cells,
            offset,
            layout,
            scalars: &scalars,
            vectors: &vectors,
        }
        .write(&vtk_files[rank])?;
        if ranks > 1 {
            barrier();
            if root {
                let pieces: Vec<FieldPiece> = (0..ranks)
                    .map(|r| {
                        let (z0, z1) = share(n, r);
                        FieldPiece {
                            source: piece(r),
                            offset: [0, 0, z0],
                            cells: [n, n, z1 - z0],
                        }
                    })
                    .collect();
                let names = ["pressure"];
                let vectors = ["velocity", "vorticity"];
                let index = &vtk_files[ranks];
                write_field_pieces_index(index, global, &layout, &names, &vectors, &pieces)?;
            }
        }
        Ok(())
    })?;
    let h5 = dir.join("fields.h5");
    let hdf5_seconds = best_of_three(&barrier, || {
        FieldFrameH5 {
            time: 0.0,
            global_cells: global,
            offset,
            cells,
            layout,
            scalars: &scalars,
            vectors: &vectors,
        }
        .write(&h5, &writers)
    })?;
    if root {
        let raw = (n * n * n * 7 * 8) as f64;
        println!(
            "field frame, {n}^3 cells ({:.1} MB of float64) on {ranks} rank(s):",
            raw / 1e6
        );
        report("VTK  .vti", &vtk_files, vtk_seconds)?;
        report("HDF5 .h5 ", &[h5], hdf5_seconds)?;
    }

    let (g0, g1) = share(grains, rank);
    let id: Vec<u64> = (g0 as u64..g1 as u64).collect();
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
    let fixed = vec![0u8; id.len()];
    let group = vec![0u64; id.len()];
    let contacts: Vec<u32> = id.iter().map(|&k| (k % 7) as u32).collect();
    let piece = |r: usize| format!("particles_{r:04}.vtp");
    let vtk_files: Vec<PathBuf> = if ranks == 1 {
        vec![dir.join("particles.vtp")]
    } else {
        let mut files: Vec<PathBuf> = (0..ranks).map(|r| dir.join(piece(r))).collect();
        files.push(dir.join("particles.pvtp"));
        files
    };
    let vtk_seconds = best_of_three(&barrier, || {
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
        .write(&vtk_files[rank])?;
        if ranks > 1 {
            barrier();
            if root {
                let pieces: Vec<String> = (0..ranks).map(piece).collect();
                write_particle_pieces_index(&vtk_files[ranks], &pieces)?;
            }
        }
        Ok(())
    })?;
    let h5 = dir.join("particles.h5");
    let hdf5_seconds = best_of_three(&barrier, || {
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
            group: &group,
        }
        .write(&h5, &writers)
        .map(|_| ())
    })?;
    if root {
        println!("particle frame, {grains} grains on {ranks} rank(s):");
        report("VTK  .vtp", &vtk_files, vtk_seconds)?;
        report("HDF5 .h5 ", &[h5], hdf5_seconds)?;
        println!("(the HDF5 particle frame also holds a uint32 contact count per grain)");
    }
    Ok(())
}

/// The shortest of three runs of `write` from a barrier to a barrier [s]
/// (every rank writes its share).
fn best_of_three(
    barrier: &impl Fn(),
    mut write: impl FnMut() -> std::io::Result<()>,
) -> std::io::Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        barrier();
        let start = Instant::now();
        write()?;
        barrier();
        best = best.min(start.elapsed().as_secs_f64());
    }
    Ok(best)
}

/// Prints the bytes of `files` together and the speed of writing them.
fn report(label: &str, files: &[PathBuf], seconds: f64) -> std::io::Result<()> {
    let mut bytes = 0;
    for file in files {
        bytes += std::fs::metadata(Path::new(file))?.len();
    }
    println!(
        "  {label}: {bytes:>11} bytes in {} file(s), {seconds:.3} s ({:.0} MB/s)",
        files.len(),
        bytes as f64 / seconds / 1e6
    );
    Ok(())
}
