//! VTK XML PolyData (`.vtp`) particle files, ImageData (`.vti`) files of
//! cell-centred fields on a uniform grid, RectilinearGrid (`.vtr`) files
//! on a grid stretched along an axis, and the `.pvd` collection that lets
//! ParaView open any of them as one time series.
//!
//! Arrays are written in binary (base64, little-endian, with a UInt32 byte
//! count header), which ParaView reads directly; one vertex per particle.
//!
//! Every file here is written whole ([`crate::whole`]): under a temporary
//! name, then renamed, so that a run killed while writing leaves the
//! previous index or no data file, never one cut short.

use crate::whole::write_whole;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The particle state written at one output time.
pub struct ParticleFrame<'a> {
    pub id: &'a [u64],
    pub position: &'a [[f64; 3]],
    pub velocity: &'a [[f64; 3]],
    pub angular_velocity: &'a [[f64; 3]],
    pub force: &'a [[f64; 3]],
    pub radius: &'a [f64],
    pub fixed: &'a [u8],
}

impl ParticleFrame<'_> {
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let n = self.radius.len();
        write_whole(path, |out| {
            writeln!(out, r#"<?xml version="1.0"?>"#)?;
            writeln!(
                out,
                r#"<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt32">"#
            )?;
            writeln!(out, "<PolyData>")?;
            writeln!(
                out,
                r#"<Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="0">"#
            )?;
            writeln!(out, "<PointData Scalars=\"radius\" Vectors=\"velocity\">")?;
            write_array(out, "radius", "Float64", 1, &to_bytes_f64(self.radius))?;
            write_array(
                out,
                "id",
                "UInt64",
                1,
                &self
                    .id
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect::<Vec<_>>(),
            )?;
            write_array(out, "fixed", "UInt8", 1, self.fixed)?;
            write_array(
                out,
                "velocity",
                "Float64",
                3,
                &to_bytes_f64(self.velocity.as_flattened()),
            )?;
            write_array(
                out,
                "angular_velocity",
                "Float64",
                3,
                &to_bytes_f64(self.angular_velocity.as_flattened()),
            )?;
            write_array(
                out,
                "force",
                "Float64",
                3,
                &to_bytes_f64(self.force.as_flattened()),
            )?;
            writeln!(out, "</PointData>")?;
            writeln!(out, "<Points>")?;
            write_array(
                out,
                "position",
                "Float64",
                3,
                &to_bytes_f64(self.position.as_flattened()),
            )?;
            writeln!(out, "</Points>")?;
            writeln!(out, "<Verts>")?;
            let connectivity: Vec<u8> = (0..n as i64).flat_map(|k| k.to_le_bytes()).collect();
            let offsets: Vec<u8> = (1..=n as i64).flat_map(|k| k.to_le_bytes()).collect();
            write_array(out, "connectivity", "Int64", 1, &connectivity)?;
            write_array(out, "offsets", "Int64", 1, &offsets)?;
            writeln!(out, "</Verts>")?;
            writeln!(out, "</Piece>\n</PolyData>\n</VTKFile>")?;
            Ok(())
        })
    }
}

/// The `.pvtp` index of one particle output written in pieces, one per
/// rank: ParaView opens it as a single dataset. `pieces` are the piece
/// files' paths relative to the index.
pub fn write_particle_pieces_index(path: &Path, pieces: &[String]) -> std::io::Result<()> {
    write_whole(path, |out| {
        writeln!(out, r#"<?xml version="1.0"?>"#)?;
        writeln!(
            out,
            r#"<VTKFile type="PPolyData" version="1.0" byte_order="LittleEndian" header_type="UInt32">"#
        )?;
        writeln!(out, r#"<PPolyData GhostLevel="0">"#)?;
        writeln!(out, r#"<PPointData Scalars="radius" Vectors="velocity">"#)?;
        for (name, kind, components) in [
            ("radius", "Float64", 1),
            ("id", "UInt64", 1),
            ("fixed", "UInt8", 1),
            ("velocity", "Float64", 3),
            ("angular_velocity", "Float64", 3),
            ("force", "Float64", 3),
        ] {
            writeln!(
                out,
                r#"<PDataArray type="{kind}" Name="{name}" NumberOfComponents="{components}"/>"#
            )?;
        }
        writeln!(out, "</PPointData>")?;
        writeln!(
            out,
            r#"<PPoints><PDataArray type="Float64" Name="position" NumberOfComponents="3"/></PPoints>"#
        )?;
        for piece in pieces {
            writeln!(out, r#"<Piece Source="{piece}"/>"#)?;
        }
        writeln!(
            out,
            "</PPolyData>
</VTKFile>"
        )?;
        Ok(())
    })
}

/// How the cells of a field file are laid out.
#[derive(Clone, Copy, Debug)]
pub enum CellLayout<'a> {
    /// Cells of size `spacing` from `origin`: an ImageData file (`.vti`).
    Uniform { origin: [f64; 3], spacing: [f64; 3] },
    /// Cells between these face coordinates along each axis (`cells + 1`
    /// of them): a RectilinearGrid file (`.vtr`).
    Rectilinear { faces: [&'a [f64]; 3] },
}

impl CellLayout<'_> {
    /// The file extension ParaView expects for this layout.
    pub fn extension(&self) -> &'static str {
        match self {
            CellLayout::Uniform { .. } => "vti",
            CellLayout::Rectilinear { .. } => "vtr",
        }
    }
}

/// Cell-centred fields on a grid of `cells` cells (a 2D grid has one cell
/// along z); on several ranks one rank's piece, whose first cell is cell
/// `offset` of the whole grid (zero on one rank).
pub struct FieldFrame<'a> {
    pub cells: [usize; 3],
    pub offset: [usize; 3],
    pub layout: CellLayout<'a>,
    /// Scalar fields, one value per cell, x fastest.
    pub scalars: &'a [(&'a str, &'a [f64])],
    /// Vector fields, one [x, y, z] per cell, x fastest.
    pub vectors: &'a [(&'a str, &'a [[f64; 3]])],
}

impl FieldFrame<'_> {
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_whole(path, |out| {
            writeln!(out, r#"<?xml version="1.0"?>"#)?;
            let extent = extent_text(self.offset, self.cells);
            let kind = match self.layout {
                CellLayout::Uniform { .. } => "ImageData",
                CellLayout::Rectilinear { .. } => "RectilinearGrid",
            };
            writeln!(
                out,
                r#"<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" header_type="UInt32">"#
            )?;
            match &self.layout {
                CellLayout::Uniform { origin, spacing } => {
                    let [ox, oy, oz] = origin;
                    let [dx, dy, dz] = spacing;
                    writeln!(
                        out,
                        r#"<ImageData WholeExtent="{extent}" Origin="{ox:e} {oy:e} {oz:e}" Spacing="{dx:e} {dy:e} {dz:e}">"#
                    )?;
                    writeln!(out, r#"<Piece Extent="{extent}">"#)?;
                }
                CellLayout::Rectilinear { faces } => {
                    writeln!(out, r#"<RectilinearGrid WholeExtent="{extent}">"#)?;
                    writeln!(out, r#"<Piece Extent="{extent}">"#)?;
                    writeln!(out, "<Coordinates>")?;
                    for (axis, name) in ["x", "y", "z"].iter().enumerate() {
                        debug_assert_eq!(faces[axis].len(), self.cells[axis] + 1);
                        write_array(out, name, "Float64", 1, &to_bytes_f64(faces[axis]))?;
                    }
                    writeln!(out, "</Coordinates>")?;
                }
            }
            writeln!(out, "<CellData>")?;
            for (name, values) in self.scalars {
                write_array(out, name, "Float64", 1, &to_bytes_f64(values))?;
            }
            for (name, values) in self.vectors {
                write_array(
                    out,
                    name,
                    "Float64",
                    3,
                    &to_bytes_f64(values.as_flattened()),
                )?;
            }
            writeln!(out, "</CellData>")?;
            writeln!(out, "</Piece>\n</{kind}>\n</VTKFile>")?;
            Ok(())
        })
    }
}

/// A VTK extent: first and last point index along each axis.
fn extent_text(offset: [usize; 3], cells: [usize; 3]) -> String {
    let [ox, oy, oz] = offset;
    let [nx, ny, nz] = cells;
    format!("{ox} {} {oy} {} {oz} {}", ox + nx, oy + ny, oz + nz)
}

/// One rank's piece of a field output: its file (relative to the index),
/// first cell and cells.
pub struct FieldPiece {
    pub source: String,
    pub offset: [usize; 3],
    pub cells: [usize; 3],
}

/// The `.pvti` (uniform grid) or `.pvtr` (stretched) index of one field
/// output written in pieces, one per rank, over a grid of `cells` cells:
/// ParaView opens it as one dataset. Names the cell arrays of the pieces.
pub fn write_field_pieces_index(
    path: &Path,
    cells: [usize; 3],
    layout: &CellLayout,
    scalars: &[&str],
    vectors: &[&str],
    pieces: &[FieldPiece],
) -> std::io::Result<()> {
    write_whole(path, |out| {
        writeln!(out, r#"<?xml version="1.0"?>"#)?;
        let whole = extent_text([0; 3], cells);
        let kind = match layout {
            CellLayout::Uniform { .. } => "PImageData",
            CellLayout::Rectilinear { .. } => "PRectilinearGrid",
        };
        writeln!(
            out,
            r#"<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" header_type="UInt32">"#
        )?;
        match layout {
            CellLayout::Uniform { origin, spacing } => {
                let [ox, oy, oz] = origin;
                let [dx, dy, dz] = spacing;
                writeln!(
                    out,
                    r#"<PImageData WholeExtent="{whole}" GhostLevel="0" Origin="{ox:e} {oy:e} {oz:e}" Spacing="{dx:e} {dy:e} {dz:e}">"#
                )?;
            }
            CellLayout::Rectilinear { .. } => {
                writeln!(
                    out,
                    r#"<PRectilinearGrid WholeExtent="{whole}" GhostLevel="0">"#
                )?;
                writeln!(out, "<PCoordinates>")?;
                for name in ["x", "y", "z"] {
                    writeln!(
                        out,
                        r#"<PDataArray type="Float64" Name="{name}" NumberOfComponents="1"/>"#
                    )?;
                }
                writeln!(out, "</PCoordinates>")?;
            }
        }
        writeln!(out, "<PCellData>")?;
        for (names, components) in [(scalars, 1), (vectors, 3)] {
            for name in names {
                writeln!(
                    out,
                    r#"<PDataArray type="Float64" Name="{name}" NumberOfComponents="{components}"/>"#
                )?;
            }
        }
        writeln!(out, "</PCellData>")?;
        for piece in pieces {
            writeln!(
                out,
                r#"<Piece Extent="{}" Source="{}"/>"#,
                extent_text(piece.offset, piece.cells),
                piece.source
            )?;
        }
        writeln!(out, "</{kind}>\n</VTKFile>")?;
        Ok(())
    })
}

fn to_bytes_f64(values: &[f64]) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(8 * values.len());
    for v in values {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    bytes
}

fn write_array(
    out: &mut impl Write,
    name: &str,
    kind: &str,
    components: usize,
    bytes: &[u8],
) -> std::io::Result<()> {
    let mut block = Vec::with_capacity(bytes.len() + 4);
    block.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    block.extend_from_slice(bytes);
    writeln!(
        out,
        r#"<DataArray type="{kind}" Name="{name}" NumberOfComponents="{components}" format="binary">"#
    )?;
    out.write_all(base64(&block).as_bytes())?;
    writeln!(out, "\n</DataArray>")
}

/// Standard base64 with padding (RFC 4648).
pub fn base64(bytes: &[u8]) -> String {
    const TABLE: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut encoded = Vec::with_capacity(bytes.len().div_ceil(3) * 4);
    let whole = bytes.chunks_exact(3);
    let rest = whole.remainder();
    for chunk in whole {
        let n = (u32::from(chunk[0]) << 16) | (u32::from(chunk[1]) << 8) | u32::from(chunk[2]);
        encoded.extend_from_slice(&[
            TABLE[(n >> 18) as usize & 63],
            TABLE[(n >> 12) as usize & 63],
            TABLE[(n >> 6) as usize & 63],
            TABLE[n as usize & 63],
        ]);
    }
    if !rest.is_empty() {
        let b = [rest[0], *rest.get(1).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8);
        encoded.extend_from_slice(&[
            TABLE[(n >> 18) as usize & 63],
            TABLE[(n >> 12) as usize & 63],
            if rest.len() > 1 {
                TABLE[(n >> 6) as usize & 63]
            } else {
                b'='
            },
            b'=',
        ]);
    }
    String::from_utf8(encoded).expect("the base64 alphabet is ASCII")
}

/// A `.pvd` collection: one dataset per output time, rewritten whole after
/// each addition (written aside and renamed over the index) so that it is
/// valid at any moment of the run, a kill included. Add a dataset after its
/// file is written: the index then lists only files that are whole.
pub struct PvdIndex {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdIndex {
    pub fn new(path: PathBuf) -> Self {
        PvdIndex {
            path,
            entries: Vec::new(),
        }
    }

    /// An index that already lists `entries` (a resumed run's).
    pub fn with_entries(path: PathBuf, entries: Vec<(f64, String)>) -> Self {
        PvdIndex { path, entries }
    }

    /// The (time, file) entries listed so far.
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    pub fn add(&mut self, time: f64, file: &str) -> std::io::Result<()> {
        self.entries.push((time, file.to_string()));
        write_whole(&self.path, |out| {
            writeln!(out, r#"<?xml version="1.0"?>"#)?;
            writeln!(
                out,
                r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#
            )?;
            writeln!(out, "<Collection>")?;
            for (t, f) in &self.entries {
                writeln!(
                    out,
                    r#"<DataSet timestep="{t:e}" group="" part="0" file="{f}"/>"#
                )?;
            }
            writeln!(out, "</Collection>\n</VTKFile>")?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::base64;

    #[test]
    fn base64_matches_rfc4648_vectors() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foob"), "Zm9vYg==");
        assert_eq!(base64(b"fooba"), "Zm9vYmE=");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }
}
