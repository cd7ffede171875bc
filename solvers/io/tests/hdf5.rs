//! HDF5 frames and their XDMF indices (cargo feature `hdf5`): what is
//! written is read back exactly with the HDF5 library, the indices parse as
//! XML and name the datasets, shapes and times written. With the feature
//! `mpi` too, two ranks started with `mpirun` write the same files as one
//! process (needs Open MPI's `mpirun` and a parallel HDF5 library).

#![cfg(feature = "hdf5")]

use grainflow_io::hdf5::{FieldFrameH5, FieldGridDescription, ParticleFrameH5, Writers, XdmfIndex};
use grainflow_io::CellLayout;
use hdf5_metno::File;
use std::path::Path;

/// The value of field `field` (component `c`) in global cell `(i, j, k)`:
/// distinct for every cell, field and component.
fn value(field: usize, c: usize, [i, j, k]: [usize; 3]) -> f64 {
    field as f64 * 1e4 + c as f64 * 1e3 + i as f64 + 10.0 * j as f64 + 100.0 * k as f64 + 0.25
}

/// Scalars `pressure`, `solid_fraction` and vectors `velocity`, `vorticity`
/// of the block of `cells` cells from `offset`, x fastest.
struct Block {
    scalars: Vec<Vec<f64>>,
    vectors: Vec<Vec<[f64; 3]>>,
}

const SCALARS: [&str; 2] = ["pressure", "solid_fraction"];
const VECTORS: [&str; 2] = ["velocity", "vorticity"];

fn block(offset: [usize; 3], cells: [usize; 3]) -> Block {
    let mut indices = Vec::new();
    for k in 0..cells[2] {
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                indices.push([offset[0] + i, offset[1] + j, offset[2] + k]);
            }
        }
    }
    Block {
        scalars: (0..2)
            .map(|f| indices.iter().map(|&c| value(f, 0, c)).collect())
            .collect(),
        vectors: (2..4)
            .map(|f| {
                indices
                    .iter()
                    .map(|&c| [0, 1, 2].map(|a| value(f, a, c)))
                    .collect()
            })
            .collect(),
    }
}

/// Writes the block of `cells` from `offset` of a `global` grid to `path`.
fn write_block(
    path: &Path,
    writers: &Writers,
    time: f64,
    global: [usize; 3],
    offset: [usize; 3],
    cells: [usize; 3],
    layout: CellLayout,
) -> std::io::Result<()> {
    let b = block(offset, cells);
    let scalars: Vec<(&str, &[f64])> = SCALARS
        .iter()
        .zip(&b.scalars)
        .map(|(n, v)| (*n, &v[..]))
        .collect();
    let vectors: Vec<(&str, &[[f64; 3]])> = VECTORS
        .iter()
        .zip(&b.vectors)
        .map(|(n, v)| (*n, &v[..]))
        .collect();
    FieldFrameH5 {
        time,
        global_cells: global,
        offset,
        cells,
        layout,
        scalars: &scalars,
        vectors: &vectors,
    }
    .write(path, writers)
}

/// Asserts that the field frame at `path` holds exactly the values of a
/// `global` grid with face coordinates `faces` at `time`.
fn assert_field_frame(path: &Path, global: [usize; 3], faces: &[Vec<f64>; 3], time: f64) {
    let file = File::open(path).unwrap();
    let [nx, ny, nz] = global;
    let whole = block([0; 3], global);
    for (f, name) in SCALARS.iter().enumerate() {
        let data = file.dataset(name).unwrap().read_dyn::<f64>().unwrap();
        assert_eq!(data.shape(), &[nz, ny, nx], "{name}");
        assert_eq!(data.as_slice().unwrap(), &whole.scalars[f][..], "{name}");
        assert_eq!(data[[nz - 1, 0, nx - 1]], value(f, 0, [nx - 1, 0, nz - 1]));
    }
    for (f, name) in VECTORS.iter().enumerate() {
        let data = file.dataset(name).unwrap().read_dyn::<f64>().unwrap();
        assert_eq!(data.shape(), &[nz, ny, nx, 3], "{name}");
        assert_eq!(
            data.as_slice().unwrap(),
            whole.vectors[f].as_flattened(),
            "{name}"
        );
        assert_eq!(data[[0, ny - 1, 0, 2]], value(f + 2, 2, [0, ny - 1, 0]));
    }
    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
        let data = file
            .dataset(&format!("grid/{name}"))
            .unwrap()
            .read_raw::<f64>()
            .unwrap();
        assert_eq!(data, faces[axis], "grid/{name}");
    }
    let written: f64 = file.attr("time").unwrap().read_scalar().unwrap();
    assert_eq!(written, time);
    let cells: Vec<u64> = file.attr("cells").unwrap().read_raw().unwrap();
    assert_eq!(cells, global.map(|c| c as u64));
}

fn uniform_faces(global: [usize; 3], origin: [f64; 3], spacing: [f64; 3]) -> [Vec<f64>; 3] {
    [0, 1, 2].map(|a| {
        (0..=global[a])
            .map(|i| origin[a] + i as f64 * spacing[a])
            .collect()
    })
}

/// Faces stretched along z (the line axis of a 3D grid).
fn stretched_faces(global: [usize; 3]) -> [Vec<f64>; 3] {
    [0, 1, 2].map(|a| {
        (0..=global[a])
            .map(|i| match a {
                2 => (i as f64 / global[2] as f64).powi(2),
                _ => -0.5 + 0.1 * i as f64,
            })
            .collect()
    })
}

/// The grains of rank `rank` of `ranks` out of `total`: ids `rank, rank +
/// ranks, …`, every value derived from the id.
struct Grains {
    id: Vec<u64>,
    position: Vec<[f64; 3]>,
    velocity: Vec<[f64; 3]>,
    spin: Vec<[f64; 3]>,
    force: Vec<[f64; 3]>,
    radius: Vec<f64>,
    contacts: Vec<u32>,
    fixed: Vec<u8>,
    group: Vec<u64>,
}

fn grains(ids: impl Iterator<Item = u64>) -> Grains {
    let id: Vec<u64> = ids.collect();
    let v = |s: f64| -> Vec<[f64; 3]> {
        id.iter()
            .map(|&n| [0.0, 1.0, 2.0].map(|c| s * n as f64 + c * 0.125))
            .collect()
    };
    Grains {
        position: v(1.0),
        velocity: v(-2.0),
        spin: v(3.0),
        force: v(0.5),
        radius: id.iter().map(|&n| 1e-3 * (1.0 + n as f64)).collect(),
        contacts: id.iter().map(|&n| (n % 7) as u32).collect(),
        fixed: id.iter().map(|&n| u8::from(n % 5 == 0)).collect(),
        group: id.iter().map(|&n| n % 3).collect(),
        id,
    }
}

fn write_grains(path: &Path, writers: &Writers, time: f64, g: &Grains) -> std::io::Result<usize> {
    ParticleFrameH5 {
        time,
        id: &g.id,
        position: &g.position,
        velocity: &g.velocity,
        angular_velocity: &g.spin,
        force: &g.force,
        radius: &g.radius,
        contacts: &g.contacts,
        fixed: &g.fixed,
        group: &g.group,
    }
    .write(path, writers)
}

/// Asserts the particle frame at `path` holds `expected`, in that order.
fn assert_particle_frame(path: &Path, expected: &Grains, time: f64) {
    let file = File::open(path).unwrap();
    let n = expected.id.len();
    for (name, values) in [
        ("position", &expected.position),
        ("velocity", &expected.velocity),
        ("angular_velocity", &expected.spin),
        ("force", &expected.force),
    ] {
        let data = file.dataset(name).unwrap().read_dyn::<f64>().unwrap();
        assert_eq!(data.shape(), &[n, 3], "{name}");
        assert_eq!(data.as_slice().unwrap(), values.as_flattened(), "{name}");
    }
    let radius: Vec<f64> = file.dataset("radius").unwrap().read_raw().unwrap();
    assert_eq!(radius, expected.radius);
    let id: Vec<u64> = file.dataset("id").unwrap().read_raw().unwrap();
    assert_eq!(id, expected.id);
    let contacts: Vec<u32> = file.dataset("contacts").unwrap().read_raw().unwrap();
    assert_eq!(contacts, expected.contacts);
    let fixed: Vec<u8> = file.dataset("fixed").unwrap().read_raw().unwrap();
    assert_eq!(fixed, expected.fixed);
    let group: Vec<u64> = file.dataset("group").unwrap().read_raw().unwrap();
    assert_eq!(group, expected.group);
    let written: f64 = file.attr("time").unwrap().read_scalar().unwrap();
    assert_eq!(written, time);
    let count: u64 = file.attr("count").unwrap().read_scalar().unwrap();
    assert_eq!(count, n as u64);
}

#[test]
fn a_uniform_field_frame_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields_000000.h5");
    let global = [4, 3, 2];
    let (origin, spacing) = ([-1.0, 0.0, 0.5], [0.25, 0.5, 1.0]);
    let layout = CellLayout::Uniform { origin, spacing };
    write_block(
        &path,
        &Writers::serial(),
        0.5,
        global,
        [0; 3],
        global,
        layout,
    )
    .unwrap();
    assert_field_frame(&path, global, &uniform_faces(global, origin, spacing), 0.5);
    let file = File::open(&path).unwrap();
    let grid = file.group("grid").unwrap();
    let read: Vec<f64> = grid.attr("origin").unwrap().read_raw().unwrap();
    assert_eq!(read, origin);
    let read: Vec<f64> = grid.attr("spacing").unwrap().read_raw().unwrap();
    assert_eq!(read, spacing);
    // Only the frame, no temporary beside it.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["fields_000000.h5"]);
}

#[test]
fn a_rectilinear_2d_field_frame_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields_000003.h5");
    // A 2D grid: one cell along z, stretched along y (its line axis).
    let global = [5, 4, 1];
    let faces = [
        (0..=5).map(|i| 0.2 * i as f64).collect::<Vec<_>>(),
        vec![0.0, 0.1, 0.3, 0.6, 1.0],
        vec![0.0, 0.2],
    ];
    let layout = CellLayout::Rectilinear {
        faces: [&faces[0], &faces[1], &faces[2]],
    };
    write_block(
        &path,
        &Writers::serial(),
        2.0,
        global,
        [0; 3],
        global,
        layout,
    )
    .unwrap();
    assert_field_frame(&path, global, &faces, 2.0);
}

#[test]
fn a_stretched_3d_field_frame_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let global = [3, 2, 4];
    let faces = stretched_faces(global);
    let path = dir.path().join("whole.h5");
    let layout = CellLayout::Rectilinear {
        faces: [&faces[0], &faces[1], &faces[2]],
    };
    write_block(
        &path,
        &Writers::serial(),
        1.0,
        global,
        [0; 3],
        global,
        layout,
    )
    .unwrap();
    assert_field_frame(&path, global, &faces, 1.0);
}

#[test]
fn a_particle_frame_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("particles_000001.h5");
    let g = grains(0..17);
    let total = write_grains(&path, &Writers::serial(), 0.25, &g).unwrap();
    assert_eq!(total, 17);
    assert_particle_frame(&path, &g, 0.25);
    // No grain at all is a frame too.
    let empty = grains(0..0);
    let path = dir.path().join("particles_000002.h5");
    assert_eq!(
        write_grains(&path, &Writers::serial(), 0.5, &empty).unwrap(),
        0
    );
    assert_particle_frame(&path, &empty, 0.5);
}

#[test]
fn wrong_frames_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("fields_000000.h5");
    let short = [1.0; 3];
    let error = FieldFrameH5 {
        time: 0.0,
        global_cells: [2, 2, 1],
        offset: [0; 3],
        cells: [2, 2, 1],
        layout: CellLayout::Uniform {
            origin: [0.0; 3],
            spacing: [1.0; 3],
        },
        scalars: &[("pressure", &short)],
        vectors: &[],
    }
    .write(&path, &Writers::serial())
    .unwrap_err();
    assert!(error.to_string().contains("fields_000000.h5"), "{error}");
    assert!(
        error.to_string().contains("pressure has 3 values"),
        "{error}"
    );
    assert!(!path.exists());

    // A folder that does not exist.
    let path = dir.path().join("missing/particles_000000.h5");
    let error = write_grains(&path, &Writers::serial(), 0.0, &grains(0..3)).unwrap_err();
    assert!(error.to_string().contains("particles_000000.h5"), "{error}");
}

/// The elements of `node` named `tag`.
fn children<'a, 'i>(
    node: roxmltree::Node<'a, 'i>,
    tag: &'a str,
) -> impl Iterator<Item = roxmltree::Node<'a, 'i>> {
    node.children().filter(move |c| c.has_tag_name(tag))
}

#[test]
fn the_xdmf_indices_list_every_frame_with_its_time_shapes_and_datasets() {
    let dir = tempfile::tempdir().unwrap();
    let fields = dir.path().join("fields.xdmf");
    let mut index = XdmfIndex::new(fields.clone(), "fields");
    let uniform = FieldGridDescription {
        cells: [4, 3, 2],
        uniform: Some(([-1.0, 0.0, 0.5], [0.25, 0.5, 1.0])),
        scalars: &["pressure", "solid_fraction"],
        vectors: &["velocity", "vorticity"],
    };
    index
        .add_fields(0.0, "fields/fields_000000.h5", &uniform)
        .unwrap();
    index
        .add_fields(0.125, "fields/fields_000001.h5", &uniform)
        .unwrap();
    let rectilinear = FieldGridDescription {
        uniform: None,
        ..uniform.clone()
    };
    index
        .add_fields(0.25, "fields/fields_000002.h5", &rectilinear)
        .unwrap();
    assert_eq!(index.len(), 3);

    let text = std::fs::read_to_string(&fields).unwrap();
    let document = roxmltree::Document::parse(&text).unwrap();
    let root = document.root_element();
    assert_eq!(root.tag_name().name(), "Xdmf");
    assert_eq!(root.attribute("Version"), Some("3.0"));
    let domain = children(root, "Domain").next().unwrap();
    let collection = children(domain, "Grid").next().unwrap();
    assert_eq!(collection.attribute("GridType"), Some("Collection"));
    assert_eq!(collection.attribute("CollectionType"), Some("Temporal"));
    let grids: Vec<_> = children(collection, "Grid").collect();
    assert_eq!(grids.len(), 3);
    for (n, (grid, time)) in grids.iter().zip([0.0, 0.125, 0.25]).enumerate() {
        assert_eq!(grid.attribute("Name"), Some(&*format!("fields_{n:06}")));
        let t = children(*grid, "Time").next().unwrap();
        assert_eq!(t.attribute("Value").unwrap().parse::<f64>().unwrap(), time);
        let topology = children(*grid, "Topology").next().unwrap();
        assert_eq!(topology.attribute("Dimensions"), Some("3 4 5"));
        let mesh = if n < 2 { "3DCoRectMesh" } else { "3DRectMesh" };
        assert_eq!(topology.attribute("TopologyType"), Some(mesh));
        let attributes: Vec<_> = children(*grid, "Attribute")
            .map(|a| {
                let item = children(a, "DataItem").next().unwrap();
                (
                    a.attribute("Name").unwrap(),
                    a.attribute("Center").unwrap(),
                    item.attribute("Dimensions").unwrap(),
                    item.text().unwrap().trim(),
                )
            })
            .collect();
        let file = format!("fields/fields_{n:06}.h5");
        assert_eq!(
            attributes,
            [
                ("pressure", "Cell", "2 3 4", &*format!("{file}:/pressure")),
                (
                    "solid_fraction",
                    "Cell",
                    "2 3 4",
                    &*format!("{file}:/solid_fraction")
                ),
                ("velocity", "Cell", "2 3 4 3", &*format!("{file}:/velocity")),
                (
                    "vorticity",
                    "Cell",
                    "2 3 4 3",
                    &*format!("{file}:/vorticity")
                ),
            ]
        );
    }
    // The uniform grid's origin and spacing, z first.
    let geometry = children(grids[0], "Geometry").next().unwrap();
    assert_eq!(geometry.attribute("GeometryType"), Some("ORIGIN_DXDYDZ"));
    let items: Vec<Vec<f64>> = children(geometry, "DataItem")
        .map(|d| {
            d.text()
                .unwrap()
                .split_whitespace()
                .map(|v| v.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(items, [vec![0.5, 0.0, -1.0], vec![1.0, 0.5, 0.25]]);
    let geometry = children(grids[2], "Geometry").next().unwrap();
    assert_eq!(geometry.attribute("GeometryType"), Some("VXVYVZ"));
    let items: Vec<_> = children(geometry, "DataItem")
        .map(|d| (d.attribute("Dimensions").unwrap(), d.text().unwrap().trim()))
        .collect();
    assert_eq!(
        items,
        [
            ("5", "fields/fields_000002.h5:/grid/x"),
            ("4", "fields/fields_000002.h5:/grid/y"),
            ("3", "fields/fields_000002.h5:/grid/z"),
        ]
    );

    let particles = dir.path().join("particles.xdmf");
    let mut index = XdmfIndex::new(particles.clone(), "particles");
    index
        .add_particles(0.5, "particles/particles_000000.h5", 17)
        .unwrap();
    let text = std::fs::read_to_string(&particles).unwrap();
    let document = roxmltree::Document::parse(&text).unwrap();
    let grid = document
        .descendants()
        .find(|n| n.has_tag_name("Grid") && n.attribute("Name") == Some("particles_000000"))
        .unwrap();
    let topology = children(grid, "Topology").next().unwrap();
    assert_eq!(topology.attribute("TopologyType"), Some("Polyvertex"));
    assert_eq!(topology.attribute("NumberOfElements"), Some("17"));
    let names: Vec<_> = children(grid, "Attribute")
        .map(|a| (a.attribute("Name").unwrap(), a.attribute("Center").unwrap()))
        .collect();
    assert_eq!(
        names,
        [
            ("radius", "Node"),
            ("id", "Node"),
            ("group", "Node"),
            ("contacts", "Node"),
            ("fixed", "Node"),
            ("velocity", "Node"),
            ("angular_velocity", "Node"),
            ("force", "Node"),
        ]
    );
    // Only the indices: no temporary left.
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["fields.xdmf", "particles.xdmf"]);
}

/// Two MPI ranks write one field frame (the grid cut along x and z, the
/// faces of a stretched z) and one particle frame (uneven counts: 0 on a
/// rank is allowed) into one file each; the files hold what one process
/// writes. Run by `two_ranks_write_the_files_of_one` under `mpirun`.
#[cfg(feature = "mpi")]
#[test]
fn mpi_rank_side_of_the_two_rank_test() {
    let Ok(out) = std::env::var("GRAINFLOW_HDF5_MPI_OUT") else {
        return;
    };
    use mpi::traits::Communicator as _;
    let universe = mpi::initialize().unwrap();
    let world = universe.world();
    let writers = Writers::mpi(&world);
    let (rank, ranks) = (writers.rank(), writers.size());
    assert_eq!(ranks, world.size() as usize);
    let out = Path::new(&out);
    let global = [6, 2, 4];
    // Rank r of 2 holds x in [3r, 3r + 3) and all z.
    let (offset, cells) = ([3 * rank, 0, 0], [3, 2, 4]);
    let faces = stretched_faces(global);
    let local: Vec<Vec<f64>> = (0..3)
        .map(|a| faces[a][offset[a]..=offset[a] + cells[a]].to_vec())
        .collect();
    let layout = CellLayout::Rectilinear {
        faces: [&local[0], &local[1], &local[2]],
    };
    write_block(
        &out.join("fields.h5"),
        &writers,
        1.5,
        global,
        offset,
        cells,
        layout,
    )
    .unwrap();
    // Rank 0 holds grains 0..5, rank 1 5..12; and then none on rank 1.
    let mine = if rank == 0 { 0..5 } else { 5..12 };
    let total = write_grains(&out.join("particles.h5"), &writers, 1.5, &grains(mine)).unwrap();
    assert_eq!(total, 12);
    let mine = if rank == 0 { 0..4 } else { 4..4 };
    let total = write_grains(&out.join("few.h5"), &writers, 2.0, &grains(mine)).unwrap();
    assert_eq!(total, 4);
}

#[cfg(feature = "mpi")]
#[test]
fn two_ranks_write_the_files_of_one() {
    if std::env::var_os("GRAINFLOW_HDF5_MPI_OUT").is_some() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // The ranks' own test reports are shown only on a failure.
    let run = std::process::Command::new("mpirun")
        .args(["-n", "2", "--oversubscribe"])
        .arg(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "mpi_rank_side_of_the_two_rank_test",
            "--test-threads=1",
        ])
        .env("GRAINFLOW_HDF5_MPI_OUT", dir.path())
        .output()
        .expect("mpirun starts (is Open MPI installed?)");
    assert!(
        run.status.success(),
        "mpirun: {}\n{}\n{}",
        run.status,
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let global = [6, 2, 4];
    assert_field_frame(
        &dir.path().join("fields.h5"),
        global,
        &stretched_faces(global),
        1.5,
    );
    assert_particle_frame(&dir.path().join("particles.h5"), &grains(0..12), 1.5);
    assert_particle_frame(&dir.path().join("few.h5"), &grains(0..4), 2.0);
    // One process writes the same files.
    let serial = dir.path().join("serial.h5");
    let faces = stretched_faces(global);
    let layout = CellLayout::Rectilinear {
        faces: [&faces[0], &faces[1], &faces[2]],
    };
    write_block(
        &serial,
        &Writers::serial(),
        1.5,
        global,
        [0; 3],
        global,
        layout,
    )
    .unwrap();
    assert_field_frame(&serial, global, &faces, 1.5);
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(names.is_empty(), "{names:?}");
}
