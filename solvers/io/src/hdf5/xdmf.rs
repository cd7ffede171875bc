//! XDMF 3 indices of HDF5 frames: `fields.xdmf` and `particles.xdmf`, each
//! a temporal collection (`GridType="Collection"
//! CollectionType="Temporal"`) with one grid per output time whose arrays
//! are the datasets of that time's frame, which ParaView (the XDMF 3
//! reader) and VisIt open as one time series.
//!
//! - Fields: a `3DCoRectMesh` (uniform grid, origin and spacing) or a
//!   `3DRectMesh` (face coordinates read from the frame's `grid/x`, `y`,
//!   `z`), of `nz+1 × ny+1 × nx+1` points; the arrays are cell-centred
//!   attributes. A 2D grid is a 3D grid one cell thick.
//! - Particles: a `Polyvertex` topology of the grains, one node each at
//!   `position`, with the other arrays as node attributes.
//!
//! XDMF lists sizes and coordinates slowest axis first (z, y, x). The index
//! is rewritten whole after each frame is added ([`crate::write_whole`]):
//! a killed run leaves an index that opens and lists only whole frames.

use crate::whole::write_whole;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;

/// How the cells of a field frame are laid out, for its XDMF grid.
#[derive(Clone, Debug)]
pub struct FieldGridDescription<'a> {
    /// Cells of the whole grid along x, y, z (1 along z in 2D).
    pub cells: [usize; 3],
    /// A uniform grid's origin and spacing (x, y, z); `None` for a
    /// rectilinear grid, whose coordinates are read from the frame.
    pub uniform: Option<([f64; 3], [f64; 3])>,
    /// The frame's scalar datasets (`[nz, ny, nx]`).
    pub scalars: &'a [&'a str],
    /// The frame's vector datasets (`[nz, ny, nx, 3]`).
    pub vectors: &'a [&'a str],
}

/// An XDMF temporal collection of HDF5 frames, written whole after each
/// addition. Add a frame once its file is whole.
pub struct XdmfIndex {
    path: PathBuf,
    name: String,
    /// The `<Grid>` element of each frame, in time order.
    grids: Vec<String>,
}

impl XdmfIndex {
    /// An empty index to be written at `path`, its collection named `name`.
    pub fn new(path: PathBuf, name: &str) -> Self {
        XdmfIndex {
            path,
            name: name.to_string(),
            grids: Vec::new(),
        }
    }

    /// An index that already lists `grids` (a resumed run's).
    pub fn with_grids(path: PathBuf, name: &str, grids: Vec<String>) -> Self {
        XdmfIndex {
            path,
            name: name.to_string(),
            grids,
        }
    }

    /// The `<Grid>` element of each frame listed so far.
    pub fn grids(&self) -> &[String] {
        &self.grids
    }

    /// The frames listed so far.
    pub fn len(&self) -> usize {
        self.grids.len()
    }

    /// Whether no frame is listed yet.
    pub fn is_empty(&self) -> bool {
        self.grids.is_empty()
    }

    /// Adds the field frame `file` (relative to the index) at `time` and
    /// rewrites the index.
    pub fn add_fields(
        &mut self,
        time: f64,
        file: &str,
        grid: &FieldGridDescription,
    ) -> std::io::Result<()> {
        let [nx, ny, nz] = grid.cells;
        let mut xml = String::new();
        let name = frame_name(file);
        let _ = writeln!(xml, r#"<Grid Name="{name}" GridType="Uniform">"#);
        let _ = writeln!(xml, r#"<Time Value="{time:e}"/>"#);
        let points = format!("{} {} {}", nz + 1, ny + 1, nx + 1);
        match grid.uniform {
            Some((origin, spacing)) => {
                let _ = writeln!(
                    xml,
                    r#"<Topology TopologyType="3DCoRectMesh" Dimensions="{points}"/>"#
                );
                let _ = writeln!(xml, r#"<Geometry GeometryType="ORIGIN_DXDYDZ">"#);
                for (item, [x, y, z]) in [("Origin", origin), ("Spacing", spacing)] {
                    let _ = writeln!(
                        xml,
                        r#"<DataItem Name="{item}" Dimensions="3" NumberType="Float" Precision="8" Format="XML">{z:e} {y:e} {x:e}</DataItem>"#
                    );
                }
            }
            None => {
                let _ = writeln!(
                    xml,
                    r#"<Topology TopologyType="3DRectMesh" Dimensions="{points}"/>"#
                );
                let _ = writeln!(xml, r#"<Geometry GeometryType="VXVYVZ">"#);
                for (axis, n) in [("x", nx), ("y", ny), ("z", nz)] {
                    xml.push_str(&data_item(file, &format!("grid/{axis}"), &[n + 1], FLOAT));
                }
            }
        }
        xml.push_str("</Geometry>\n");
        let cells = [nz, ny, nx];
        for name in grid.scalars {
            xml.push_str(&attribute(file, name, "Scalar", "Cell", &cells, FLOAT));
        }
        for name in grid.vectors {
            let shape = [nz, ny, nx, 3];
            xml.push_str(&attribute(file, name, "Vector", "Cell", &shape, FLOAT));
        }
        xml.push_str("</Grid>\n");
        self.grids.push(xml);
        self.write()
    }

    /// Adds the particle frame `file` (relative to the index) of `count`
    /// grains at `time` and rewrites the index.
    pub fn add_particles(&mut self, time: f64, file: &str, count: usize) -> std::io::Result<()> {
        let mut xml = String::new();
        let name = frame_name(file);
        let _ = writeln!(xml, r#"<Grid Name="{name}" GridType="Uniform">"#);
        let _ = writeln!(xml, r#"<Time Value="{time:e}"/>"#);
        let _ = writeln!(
            xml,
            r#"<Topology TopologyType="Polyvertex" NumberOfElements="{count}" NodesPerElement="1"/>"#
        );
        let _ = writeln!(xml, r#"<Geometry GeometryType="XYZ">"#);
        xml.push_str(&data_item(file, "position", &[count, 3], FLOAT));
        xml.push_str("</Geometry>\n");
        for (name, kind) in [
            ("radius", FLOAT),
            ("id", UINT64),
            ("group", UINT64),
            ("contacts", UINT32),
        ] {
            xml.push_str(&attribute(file, name, "Scalar", "Node", &[count], kind));
        }
        xml.push_str(&attribute(file, "fixed", "Scalar", "Node", &[count], UINT8));
        for name in ["velocity", "angular_velocity", "force"] {
            xml.push_str(&attribute(file, name, "Vector", "Node", &[count, 3], FLOAT));
        }
        xml.push_str("</Grid>\n");
        self.grids.push(xml);
        self.write()
    }

    fn write(&self) -> std::io::Result<()> {
        write_whole(&self.path, |out| {
            writeln!(out, r#"<?xml version="1.0" ?>"#)?;
            writeln!(out, r#"<Xdmf Version="3.0">"#)?;
            writeln!(out, "<Domain>")?;
            writeln!(
                out,
                r#"<Grid Name="{}" GridType="Collection" CollectionType="Temporal">"#,
                self.name
            )?;
            for grid in &self.grids {
                out.write_all(grid.as_bytes())?;
            }
            writeln!(out, "</Grid>\n</Domain>\n</Xdmf>")
        })
        .map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", self.path.display())))
    }
}

/// XDMF's number type and precision of a dataset.
type NumberType = (&'static str, u8);
const FLOAT: NumberType = ("Float", 8);
const UINT64: NumberType = ("UInt", 8);
const UINT32: NumberType = ("UInt", 4);
const UINT8: NumberType = ("UChar", 1);

/// The grid name of a frame: its file name without folder or extension.
fn frame_name(file: &str) -> &str {
    let name = file.rsplit('/').next().unwrap_or(file);
    name.strip_suffix(".h5").unwrap_or(name)
}

/// A `<DataItem>` reading the dataset `dataset` of the HDF5 file `file`.
fn data_item(
    file: &str,
    dataset: &str,
    shape: &[usize],
    (number, precision): NumberType,
) -> String {
    let dimensions = shape
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(" ");
    format!(
        "<DataItem Dimensions=\"{dimensions}\" NumberType=\"{number}\" Precision=\"{precision}\" \
         Format=\"HDF\">{file}:/{dataset}</DataItem>\n"
    )
}

/// An `<Attribute>` of the dataset `name`, centred on `center`.
fn attribute(
    file: &str,
    name: &str,
    kind: &str,
    center: &str,
    shape: &[usize],
    number: NumberType,
) -> String {
    format!(
        "<Attribute Name=\"{name}\" AttributeType=\"{kind}\" Center=\"{center}\">\n{}</Attribute>\n",
        data_item(file, name, shape, number)
    )
}
