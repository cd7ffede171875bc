//! `output.format = "hdf5"`: refused by a build without the HDF5 writers;
//! with them (cargo feature `hdf5`), the frames `Hdf5Fields` and
//! `Hdf5Particles` write of a real flow and of real grains hold the
//! solver's state, and their XDMF indices list them.

use grainflow::case::{Case, OutputFormat};
use std::path::Path;

fn taylor_green(overrides: &[&str]) -> Result<Case, grainflow::case::CaseError> {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Case::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/taylor_green_2d.toml"),
        &overrides,
    )
}

#[test]
fn the_output_format_is_vtk_unless_the_case_says_otherwise() {
    let case = taylor_green(&[]).unwrap();
    assert_eq!(case.output.format, OutputFormat::Vtk);
    assert!(!case.to_toml().contains("format"));
    let error = taylor_green(&["output.format=\"netcdf\""]).unwrap_err();
    assert!(error.to_string().contains("netcdf"), "{error}");
}

#[cfg(not(feature = "hdf5"))]
#[test]
fn hdf5_output_is_refused_by_a_build_without_the_feature() {
    let error = taylor_green(&["output.format=\"hdf5\""])
        .unwrap_err()
        .to_string();
    assert!(error.contains("output.format"), "{error}");
    assert!(
        error.contains("cargo build --release --features hdf5"),
        "{error}"
    );
}

#[cfg(feature = "hdf5")]
mod with_hdf5 {
    use super::*;
    use grainflow::hdf5_output::{Hdf5Fields, Hdf5Particles};
    use grainflow_core::Communicator;
    use grainflow_io::hdf5::hdf5_metno::File;

    #[test]
    fn field_frames_of_a_flow_hold_its_grid_and_times() {
        let case = taylor_green(&["output.format=\"hdf5\"", "fluid.cells=[16, 8]"]).unwrap();
        assert_eq!(case.output.format, OutputFormat::Hdf5);
        let dir = tempfile::tempdir().unwrap();
        let serial = Communicator::serial();
        let mut solver = grainflow::scene::fluid::build(&case).unwrap();
        let mut fields = Hdf5Fields::create(dir.path(), &case, &serial, Default::default())
            .unwrap()
            .expect("output.format = \"hdf5\" writes fields");
        let phi = vec![0.5; 16 * 8];
        fields
            .write(&mut solver, 1000.0, &[("solid_fraction", &phi)])
            .unwrap();
        solver.step(0.01).unwrap();
        fields
            .write(&mut solver, 1000.0, &[("solid_fraction", &phi)])
            .unwrap();

        let file = File::open(dir.path().join("fields/fields_000001.h5")).unwrap();
        let time: f64 = file.attr("time").unwrap().read_scalar().unwrap();
        assert_eq!(time, solver.time);
        let velocity = file.dataset("velocity").unwrap().read_dyn::<f64>().unwrap();
        assert_eq!(velocity.shape(), &[1, 8, 16, 3]);
        // The stream (1, 0.5) plus the vortex: the mean velocity is the
        // stream's.
        let n = 16.0 * 8.0;
        let mean_u: f64 = velocity.iter().step_by(3).sum::<f64>() / n;
        assert!((mean_u - 1.0).abs() < 1e-9, "{mean_u}");
        let phi_read: Vec<f64> = file.dataset("solid_fraction").unwrap().read_raw().unwrap();
        assert_eq!(phi_read, phi);
        let x: Vec<f64> = file.dataset("grid/x").unwrap().read_raw().unwrap();
        assert_eq!(x.len(), 17);
        assert!((x[16] - 2.0 * std::f64::consts::PI).abs() < 1e-12);

        let index = std::fs::read_to_string(dir.path().join("fields.xdmf")).unwrap();
        assert_eq!(index.matches("<Time ").count(), 2);
        assert!(index.contains("3DCoRectMesh"));
        assert!(index.contains("fields/fields_000001.h5:/solid_fraction"));
    }

    #[test]
    fn a_stretched_grid_writes_its_face_coordinates() {
        let case = Case::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/channel_suction.toml"),
            &["output.format=\"hdf5\"".to_string()],
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let mut solver = grainflow::scene::fluid::build(&case).unwrap();
        let mut fields = Hdf5Fields::create(
            dir.path(),
            &case,
            &Communicator::serial(),
            Default::default(),
        )
        .unwrap()
        .unwrap();
        fields.write(&mut solver, 1000.0, &[]).unwrap();
        let file = File::open(dir.path().join("fields/fields_000000.h5")).unwrap();
        let y: Vec<f64> = file.dataset("grid/y").unwrap().read_raw().unwrap();
        assert_eq!(y, solver.grid.face_coordinates(1));
        let index = std::fs::read_to_string(dir.path().join("fields.xdmf")).unwrap();
        assert!(index.contains("3DRectMesh"));
    }

    #[test]
    fn particle_frames_hold_every_grain() {
        let case = Case::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/binary_collision.toml"),
            &[
                "output.format=\"hdf5\"".to_string(),
                "output.particles=true".to_string(),
            ],
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let system = grainflow::scene::build(&case).unwrap();
        let mut particles = Hdf5Particles::create(
            dir.path(),
            &case,
            &Communicator::serial(),
            Default::default(),
        )
        .unwrap()
        .unwrap();
        particles.write(&system).unwrap();
        let p = &system.particles;
        let file = File::open(dir.path().join("particles/particles_000000.h5")).unwrap();
        let id: Vec<u64> = file.dataset("id").unwrap().read_raw().unwrap();
        assert_eq!(id, p.id[..p.n_owned]);
        let position = file.dataset("position").unwrap().read_dyn::<f64>().unwrap();
        assert_eq!(position.shape(), &[p.n_owned, 3]);
        for k in 0..p.n_owned {
            for a in 0..3 {
                assert_eq!(position[[k, a]], p.position[k][a]);
            }
        }
        let radius: Vec<f64> = file.dataset("radius").unwrap().read_raw().unwrap();
        assert_eq!(radius, p.radius[..p.n_owned]);
        let index = std::fs::read_to_string(dir.path().join("particles.xdmf")).unwrap();
        assert!(index.contains(&format!("NumberOfElements=\"{}\"", p.n_owned)));
    }

    /// A run of grains in a fluid written as HDF5, resumed from its first
    /// checkpoint into a copy of its folder: the same indices, byte for
    /// byte, and the same arrays in its last frames.
    #[test]
    fn a_resumed_run_continues_its_hdf5_frames_and_indices() {
        let overrides: Vec<String> = [
            "output.format=\"hdf5\"",
            "output.fields=true",
            "output.interval=0.004",
            "fluid.cells=[32,32,96]",
            "time.end=0.02",
            "checkpoint.steps=4",
            "checkpoint.keep=10",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let case = Case::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/falling_sphere.toml"),
            &overrides,
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let (whole, resumed) = (dir.path().join("whole"), dir.path().join("resumed"));
        grainflow::simulation::run(&case, &whole, false).unwrap();
        let copied = std::process::Command::new("cp")
            .arg("-r")
            .arg(&whole)
            .arg(&resumed)
            .status()
            .unwrap();
        assert!(copied.success());
        let options = grainflow::simulation::RunOptions {
            restart: Some(grainflow::simulation::Restart::From(
                resumed.join("checkpoints/checkpoint_000000000004"),
            )),
            ..Default::default()
        };
        grainflow::simulation::run_with(&case, &resumed, Communicator::serial(), &options).unwrap();
        for index in [
            "fields.xdmf",
            "particles.xdmf",
            "series.csv",
            "flow_series.csv",
        ] {
            let (a, b) = (
                std::fs::read(whole.join(index)).unwrap(),
                std::fs::read(resumed.join(index)).unwrap(),
            );
            assert!(a == b, "{index} differs after the restart");
        }
        let frames = std::fs::read_dir(whole.join("fields")).unwrap().count();
        assert!(frames >= 3, "{frames} field frames");
        for (folder, prefix, array) in [
            ("fields", "fields", "velocity"),
            ("particles", "particles", "position"),
        ] {
            let name = format!("{folder}/{prefix}_{:06}.h5", frames - 1);
            let read = |run: &Path| -> Vec<f64> {
                File::open(run.join(&name))
                    .unwrap()
                    .dataset(array)
                    .unwrap()
                    .read_raw::<f64>()
                    .unwrap()
            };
            let (a, b) = (read(&whole), read(&resumed));
            assert!(!a.is_empty());
            assert!(
                a.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()),
                "{name}: {array} differs"
            );
        }
    }

    #[test]
    fn vtk_cases_get_no_hdf5_writers() {
        let case = taylor_green(&[]).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let serial = Communicator::serial();
        assert!(
            Hdf5Fields::create(dir.path(), &case, &serial, Default::default())
                .unwrap()
                .is_none()
        );
        assert!(
            Hdf5Particles::create(dir.path(), &case, &serial, Default::default())
                .unwrap()
                .is_none()
        );
    }
}

/// A flow and grains shared among two MPI ranks write the files of one
/// rank: the field frame of each is the same global array, and the grains
/// are the same (in rank order in the file, so compared by id). Needs the
/// features `hdf5` and `mpi`, Open MPI's `mpirun` and parallel HDF5.
#[cfg(all(feature = "hdf5", feature = "mpi"))]
mod on_two_ranks {
    use super::*;
    use grainflow::hdf5_output::{Hdf5Fields, Hdf5Particles};
    use grainflow_core::Communicator;
    use grainflow_io::hdf5::hdf5_metno::File;
    use std::collections::BTreeMap;

    const OUT: &str = "GRAINFLOW_HDF5_RANKS_OUT";

    fn flow_case() -> Case {
        taylor_green(&["output.format=\"hdf5\"", "fluid.cells=[16, 8]"]).unwrap()
    }

    fn grain_case() -> Case {
        Case::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/column_collapse_3d.toml"),
            &[
                "output.format=\"hdf5\"".to_string(),
                "particles.block[0].count=300".to_string(),
            ],
        )
        .unwrap()
    }

    /// Writes a field frame after two steps and a particle frame into `out`.
    fn write_frames(out: &Path, communicator: Communicator) {
        let case = flow_case();
        let mut solver = grainflow::scene::fluid::build_on(&case, communicator.clone()).unwrap();
        solver.step(0.01).unwrap();
        solver.step(0.01).unwrap();
        let mut fields = Hdf5Fields::create(out, &case, &communicator, Default::default())
            .unwrap()
            .unwrap();
        fields.write(&mut solver, 1000.0, &[]).unwrap();
        let case = grain_case();
        let system = grainflow::scene::build_on(&case, communicator.clone()).unwrap();
        let mut particles = Hdf5Particles::create(out, &case, &communicator, Default::default())
            .unwrap()
            .unwrap();
        particles.write(&system).unwrap();
    }

    #[test]
    fn rank_side_of_the_two_rank_run() {
        let Ok(out) = std::env::var(OUT) else {
            return;
        };
        let universe = grainflow_core::communicator::mpi_backend::initialize().unwrap();
        write_frames(Path::new(&out), Communicator::world(universe.world()));
    }

    fn datasets(path: &Path) -> BTreeMap<String, Vec<f64>> {
        let file = File::open(path).unwrap();
        let mut found = BTreeMap::new();
        for name in file.member_names().unwrap() {
            if let Ok(dataset) = file.dataset(&name) {
                found.insert(name, dataset.read_raw::<f64>().unwrap());
            }
        }
        if file.group("grid").is_ok() {
            for axis in ["x", "y", "z"] {
                let name = format!("grid/{axis}");
                let faces = file.dataset(&name).unwrap().read_raw().unwrap();
                found.insert(name, faces);
            }
        }
        found
    }

    /// Each grain's datasets' rows, by id.
    fn grains(path: &Path) -> BTreeMap<u64, Vec<f64>> {
        let all = datasets(path);
        let ids: Vec<u64> = File::open(path)
            .unwrap()
            .dataset("id")
            .unwrap()
            .read_raw()
            .unwrap();
        let n = ids.len();
        ids.iter()
            .enumerate()
            .map(|(k, &id)| {
                let row = all
                    .iter()
                    .filter(|(name, _)| !name.starts_with("grid/"))
                    .flat_map(|(_, v)| {
                        let width = v.len() / n.max(1);
                        v[k * width..(k + 1) * width].to_vec()
                    })
                    .collect();
                (id, row)
            })
            .collect()
    }

    #[test]
    fn two_ranks_write_the_frames_of_one() {
        if std::env::var_os(OUT).is_some() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let (one, two) = (dir.path().join("one"), dir.path().join("two"));
        std::fs::create_dir_all(&one).unwrap();
        std::fs::create_dir_all(&two).unwrap();
        write_frames(&one, Communicator::serial());
        let run = std::process::Command::new("mpirun")
            .args(["-n", "2", "--oversubscribe"])
            .arg(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "on_two_ranks::rank_side_of_the_two_rank_run",
                "--test-threads=1",
            ])
            .env(OUT, &two)
            .output()
            .expect("mpirun starts (is Open MPI installed?)");
        assert!(
            run.status.success(),
            "mpirun: {}\n{}\n{}",
            run.status,
            String::from_utf8_lossy(&run.stdout),
            String::from_utf8_lossy(&run.stderr)
        );
        let fields = "fields/fields_000000.h5";
        let (serial, shared) = (datasets(&one.join(fields)), datasets(&two.join(fields)));
        assert_eq!(
            serial.keys().collect::<Vec<_>>(),
            shared.keys().collect::<Vec<_>>()
        );
        for (name, values) in &serial {
            let other = &shared[name];
            assert_eq!(values.len(), other.len(), "{name}");
            let worst = values
                .iter()
                .zip(other)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            // The flow's contract across decompositions: round-off.
            assert!(worst < 1e-10, "{name}: {worst:e}");
        }
        let particles = "particles/particles_000000.h5";
        let (serial, shared) = (grains(&one.join(particles)), grains(&two.join(particles)));
        assert_eq!(serial.len(), 300);
        assert_eq!(serial, shared);
        for index in ["fields.xdmf", "particles.xdmf"] {
            let a = std::fs::read_to_string(one.join(index)).unwrap();
            let b = std::fs::read_to_string(two.join(index)).unwrap();
            assert_eq!(a, b, "{index}");
        }
    }
}
