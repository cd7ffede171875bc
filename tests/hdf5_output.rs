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
        let mut solver = grainflow::fluid_scene::build(&case).unwrap();
        let mut fields = Hdf5Fields::create(dir.path(), &case, &serial)
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
        let mut solver = grainflow::fluid_scene::build(&case).unwrap();
        let mut fields = Hdf5Fields::create(dir.path(), &case, &Communicator::serial())
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
        let mut particles = Hdf5Particles::create(dir.path(), &case, &Communicator::serial())
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

    #[test]
    fn vtk_cases_get_no_hdf5_writers() {
        let case = taylor_green(&[]).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let serial = Communicator::serial();
        assert!(Hdf5Fields::create(dir.path(), &case, &serial)
            .unwrap()
            .is_none());
        assert!(Hdf5Particles::create(dir.path(), &case, &serial)
            .unwrap()
            .is_none());
    }
}
