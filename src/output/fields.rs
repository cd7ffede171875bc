//! The field files of a scene with a fluid: `fields/fields_NNNNNN.vti`
//! (cell-centred velocity, pressure in Pa, vorticity, and any extra cell
//! scalars such as the solid fraction) indexed by `fields.pvd`; on several
//! ranks one piece per rank and output, assembled by a `.pvti`. An
//! axisymmetric scene writes its meridian plane (r, z).

use crate::case::Case;
use grainflow_fluid::{FlowSolver, Grid};
use grainflow_ibm::axisymmetric::AxisymmetricCoupledSystem;
use grainflow_io::{write_field_pieces_index, CellLayout, FieldFrame, FieldPiece, PvdIndex};
use rayon::prelude::*;
use std::path::Path;

/// Cell-centred velocity (mean of a cell's two faces along each axis),
/// pressure [Pa] and vorticity (the curl on the cell's edges, averaged to
/// its centre) of a flow, for ParaView; one value per cell of the rank, x
/// fastest. Kept between frames, so that a frame allocates nothing.
#[derive(Default)]
pub struct CellFields {
    pub velocity: Vec<[f64; 3]>,
    pub pressure: Vec<f64>,
    pub vorticity: Vec<[f64; 3]>,
}

impl CellFields {
    /// The fields of the current flow of `solver` (fluid density `density`).
    pub fn compute(&mut self, solver: &mut FlowSolver, density: f64) -> &Self {
        solver.fill_velocity_ghosts();
        let grid = &solver.grid;
        let dim = grid.dim();
        let velocity = &solver.velocity;
        let cells = grid.cell_block();
        let [nx, ny, nz] = [0, 1, 2].map(|a| cells.end[a] - cells.start[a]);
        let count = nx * ny * nz;
        self.velocity.resize(count, [0.0; 3]);
        self.pressure.resize(count, 0.0);
        self.vorticity.resize(count, [0.0; 3]);
        // The inverse distances between the centres on either side of an
        // edge: one per axis across the line axis (the last), one per
        // plane along it.
        let line = grid.line_axis();
        let inverse_spacing = grid.spacing.map(|h| 1.0 / h);
        let inverse_line_gaps: Vec<f64> = (0..grid.padded()[line])
            .map(|plane| 1.0 / grid.gap(line, plane))
            .collect();
        let (sy, sz) = (grid.stride(1), grid.stride(2));
        // One row of cells along x per task, in the order of `Grid::for_each`;
        // each cell is computed alone, whatever the number of threads.
        let rows = self
            .velocity
            .par_chunks_mut(nx)
            .zip(self.pressure.par_chunks_mut(nx))
            .zip(self.vorticity.par_chunks_mut(nx))
            .enumerate()
            .with_min_len(8);
        rows.for_each(|(row, ((velocity_row, pressure_row), vorticity_row))| {
            let (j, k) = (cells.start[1] + row % ny, cells.start[2] + row / ny);
            let first = grid.index(0, j, k);
            for (local, i) in (cells.start[0]..cells.end[0]).enumerate() {
                let index = first + i;
                let mut u = [0.0; 3];
                for a in 0..dim {
                    u[a] = 0.5 * (velocity[a][index - grid.stride(a)] + velocity[a][index]);
                }
                velocity_row[local] = u;
                pressure_row[local] = density * solver.pressure[index];
                // ω_c = ∂u_b/∂x_a − ∂u_a/∂x_b on the four edges of the cell
                // along c, averaged; each difference spans the distance
                // between the centres on either side of its edge (the edge
                // below face `e` of the line axis lies on plane `e`).
                vorticity_row[local] = if dim == 3 {
                    let [ix, iy, _] = inverse_spacing;
                    let iz = [inverse_line_gaps[k], inverse_line_gaps[k - 1]];
                    let [vx, vy, vz] = [&velocity[0], &velocity[1], &velocity[2]];
                    let (mut wx, mut wy, mut wz) = (0.0, 0.0, 0.0);
                    for (shift, inverse_z) in [(1, iz[1]), (0, iz[0])] {
                        for lower in [1, 0] {
                            // Edges along x: shift in z, `lower` in y.
                            let edge = index - lower * sy - shift * sz;
                            wx += (vz[edge + sy] - vz[edge]) * iy
                                - (vy[edge + sz] - vy[edge]) * inverse_z;
                            // Edges along y: shift in z, `lower` in x.
                            let edge = index - shift * sz - lower;
                            wy += (vx[edge + sz] - vx[edge]) * inverse_z
                                - (vz[edge + 1] - vz[edge]) * ix;
                        }
                    }
                    for shift_x in [1, 0] {
                        for shift_y in [1, 0] {
                            let edge = index - shift_x - shift_y * sy;
                            wz += (vy[edge + 1] - vy[edge]) * ix - (vx[edge + sy] - vx[edge]) * iy;
                        }
                    }
                    [0.25 * wx, 0.25 * wy, 0.25 * wz]
                } else {
                    let ix = inverse_spacing[0];
                    let iy = [inverse_line_gaps[j], inverse_line_gaps[j - 1]];
                    let [vx, vy] = [&velocity[0], &velocity[1]];
                    let mut wz = 0.0;
                    for shift_x in [1, 0] {
                        for (shift_y, inverse_y) in [(1, iy[1]), (0, iy[0])] {
                            let edge = index - shift_x - shift_y * sy;
                            wz += (vy[edge + 1] - vy[edge]) * ix
                                - (vx[edge + sy] - vx[edge]) * inverse_y;
                        }
                    }
                    [0.0, 0.0, 0.25 * wz]
                };
            }
        });
        self
    }
}

/// How the cells of `grid` are laid out for a field file: a uniform grid
/// by its `origin` and spacing, a stretched one by its `faces` (from
/// `Grid::face_coordinates`).
pub fn cell_layout<'a>(grid: &Grid, origin: [f64; 3], faces: &'a [Vec<f64>; 3]) -> CellLayout<'a> {
    if grid.is_uniform(grid.line_axis()) {
        CellLayout::Uniform {
            origin,
            spacing: grid.spacing,
        }
    } else {
        CellLayout::Rectilinear {
            faces: [&faces[0], &faces[1], &faces[2]],
        }
    }
}

/// The field files of a scene with a fluid: `fields/fields_NNNNNN.vti`
/// (cell-centred velocity, pressure in Pa, vorticity, and any extra
/// scalars) indexed by `fields.pvd`.
pub struct FieldFiles {
    dir: std::path::PathBuf,
    /// `fields.pvd` (the root's).
    index: Option<PvdIndex>,
    /// Lower corner of the domain: the origin of every piece's extent.
    origin: [f64; 3],
    pub frames: usize,
    cell_fields: CellFields,
}

impl FieldFiles {
    /// The field files of a run in `dir` (their folder is made here); a
    /// resumed run passes the index entries it had.
    pub fn create(
        dir: &Path,
        case: &Case,
        root: bool,
        entries: Vec<(f64, String)>,
    ) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir.join("fields"))?;
        let mut origin = [0.0; 3];
        origin[..case.domain.lower.len()].copy_from_slice(&case.domain.lower);
        Ok(FieldFiles {
            dir: dir.to_path_buf(),
            index: root.then(|| PvdIndex::with_entries(dir.join("fields.pvd"), entries.clone())),
            origin,
            frames: entries.len(),
            cell_fields: CellFields::default(),
        })
    }

    /// The index entries so far (the root's; empty elsewhere).
    pub fn entries(&self) -> Vec<(f64, String)> {
        self.index
            .as_ref()
            .map_or_else(Vec::new, |i| i.entries().to_vec())
    }

    /// A field file of the current flow with `extra` cell scalars.
    pub fn write(
        &mut self,
        solver: &mut FlowSolver,
        density: f64,
        extra: &[(&str, &[f64])],
    ) -> std::io::Result<()> {
        let fields = self.cell_fields.compute(solver, density);
        let grid = &solver.grid;
        let partition = solver.partition();
        let (ranks, rank) = (partition.size(), solver.communicator().rank());
        let faces = [0, 1, 2].map(|axis| grid.face_coordinates(axis));
        let layout = cell_layout(grid, self.origin, &faces);
        let extension = layout.extension();
        let piece = |r: usize| format!("fields_{:06}_{r:04}.{extension}", self.frames);
        let name = if ranks == 1 {
            format!("fields/fields_{:06}.{extension}", self.frames)
        } else {
            format!("fields/{}", piece(rank))
        };
        let mut scalars: Vec<(&str, &[f64])> = vec![("pressure", &fields.pressure)];
        scalars.extend_from_slice(extra);
        FieldFrame {
            cells: grid.cells,
            offset: partition.offset(),
            layout,
            scalars: &scalars,
            vectors: &[
                ("velocity", &fields.velocity),
                ("vorticity", &fields.vorticity),
            ],
        }
        .write(&self.dir.join(&name))
        .map_err(|e| std::io::Error::new(e.kind(), format!("{name}: {e}")))?;
        // Every rank's piece is whole before the root's index lists it.
        if ranks > 1 {
            solver.communicator().barrier();
        }
        if let Some(index) = &mut self.index {
            if ranks == 1 {
                index.add(solver.time, &name)?;
            } else {
                let pieces: Vec<FieldPiece> = (0..ranks)
                    .map(|r| {
                        let (offset, cells) = partition.share_of(r);
                        FieldPiece {
                            source: piece(r),
                            offset,
                            cells,
                        }
                    })
                    .collect();
                let names: Vec<&str> = scalars.iter().map(|(n, _)| *n).collect();
                let index_name = format!("fields/fields_{:06}.p{extension}", self.frames);
                write_field_pieces_index(
                    &self.dir.join(&index_name),
                    partition.global_cells,
                    &layout,
                    &names,
                    &["velocity", "vorticity"],
                    &pieces,
                )?;
                index.add(solver.time, &index_name)?;
            }
        }
        self.frames += 1;
        Ok(())
    }
}

/// Cell-centred fields of an (r, z) flow for ParaView, r fastest: the
/// velocity `(u_r, 0, u_z)` in the meridian plane y = 0 (x = r), the
/// pressure [Pa], the vorticity `(0, ω_θ, 0)`, `ω_θ = ∂u_r/∂z − ∂u_z/∂r`
/// (the curl on the cell's four corners, averaged to its centre), and the
/// grains' solid fraction.
fn rz_cell_fields(system: &mut AxisymmetricCoupledSystem) -> RzCellFields {
    system.flow.fill_velocity_ghosts();
    let flow = &system.flow;
    let grid = &flow.grid;
    let [nr, nz] = grid.cells;
    let density = system.fluid_density;
    let mut velocity = Vec::with_capacity(nr * nz);
    let mut pressure = Vec::with_capacity(nr * nz);
    let mut vorticity = Vec::with_capacity(nr * nz);
    let up = grid.index(0, 1);
    for k in 1..=nz {
        for i in 1..=nr {
            let at = grid.index(i, k);
            let u_r = 0.5 * (flow.radial[at - 1] + flow.radial[at]);
            let u_z = 0.5 * (flow.axial[at - up] + flow.axial[at]);
            velocity.push([u_r, 0.0, u_z]);
            pressure.push(density * flow.pressure[at]);
            // Corner (r_j, z_l) for j = i − 1, i and l = k − 1, k.
            let mut curl = 0.0;
            for j in [i - 1, i] {
                for l in [k - 1, k] {
                    let corner = grid.index(j, l);
                    let d_ur_dz = (flow.radial[corner + up] - flow.radial[corner]) / grid.dz;
                    let d_uz_dr = (flow.axial[corner + 1] - flow.axial[corner]) / grid.gap(j);
                    curl += d_ur_dz - d_uz_dr;
                }
            }
            vorticity.push([0.0, 0.25 * curl, 0.0]);
        }
    }
    let solid = system
        .immersed
        .cell_solid_fraction(grid, &system.dem.particles);
    RzCellFields {
        velocity,
        pressure,
        vorticity,
        solid,
    }
}

/// The cell fields of an (r, z) flow, r fastest.
struct RzCellFields {
    velocity: Vec<[f64; 3]>,
    pressure: Vec<f64>,
    vorticity: Vec<[f64; 3]>,
    solid: Vec<f64>,
}

impl FieldFiles {
    /// A field file of an (r, z) flow: the meridian plane y = 0 from the
    /// axis (x = 0) to the wall (x = R), a slab one core cell thick along
    /// y, `.vti` on uniform radial cells, `.vtr` on stretched ones. A
    /// Rotational Extrusion about z in ParaView sweeps it into the cylinder.
    pub fn write_rz(&mut self, system: &mut AxisymmetricCoupledSystem) -> std::io::Result<()> {
        let RzCellFields {
            velocity,
            pressure,
            vorticity,
            solid,
        } = rz_cell_fields(system);
        let grid = &system.flow.grid;
        let [nr, nz] = grid.cells;
        let thickness = grid.width(1);
        let radial: Vec<f64> = (0..=nr).map(|i| grid.face(i)).collect();
        let across = [-0.5 * thickness, 0.5 * thickness];
        let axial: Vec<f64> = (0..=nz).map(|k| grid.z_face(k)).collect();
        let uniform = (1..=nr).all(|i| (grid.width(i) - thickness).abs() <= 1e-12 * thickness);
        let layout = if uniform {
            CellLayout::Uniform {
                origin: [0.0, across[0], grid.z_range[0]],
                spacing: [thickness, thickness, grid.dz],
            }
        } else {
            CellLayout::Rectilinear {
                faces: [&radial, &across, &axial],
            }
        };
        let name = format!("fields/fields_{:06}.{}", self.frames, layout.extension());
        let scalars: Vec<(&str, &[f64])> =
            vec![("pressure", &pressure), ("solid_fraction", &solid)];
        FieldFrame {
            cells: [nr, 1, nz],
            offset: [0; 3],
            layout,
            scalars: &scalars,
            vectors: &[("velocity", &velocity), ("vorticity", &vorticity)],
        }
        .write(&self.dir.join(&name))
        .map_err(|e| std::io::Error::new(e.kind(), format!("{name}: {e}")))?;
        if let Some(index) = &mut self.index {
            index.add(system.flow.time, &name)?;
        }
        self.frames += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use grainflow_core::{Communicator, Dimension};
    use grainflow_fluid::{Boundaries, BoundaryCondition};

    /// The cells at least one cell away from every side: their stencils
    /// reach only unknowns, not ghosts or wall faces.
    fn inner_cells(cells: [usize; 3], dim: usize) -> Vec<usize> {
        let [nx, ny, nz] = cells;
        let inner = |i: usize, n: usize| i > 0 && i + 1 < n;
        (0..nx * ny * nz.max(1))
            .filter(|&c| {
                let (i, j, k) = (c % nx, (c / nx) % ny, c / (nx * ny));
                inner(i, nx) && inner(j, ny) && (dim == 2 || inner(k, nz))
            })
            .collect()
    }

    /// A linear flow has a uniform curl, which the staggered differences
    /// take exactly (to round-off), also across a stretched line axis:
    /// u = (a y + b z, c x + d z, e x + f y) has ω = (f − d, b − e, c − a).
    #[test]
    fn the_cell_vorticity_of_a_linear_flow_is_its_curl_on_a_stretched_grid() {
        let cells = [6, 5, 7];
        let upper = [1.0, 1.2, 1.4];
        let faces: Vec<f64> = (0..=7).map(|i| 1.4 * (i as f64 / 7.0).powf(1.3)).collect();
        let grid = Grid::stretched(Dimension::Three, cells, [0.0; 3], upper, &faces).unwrap();
        let slip = BoundaryCondition::FreeSlip;
        let walls = Boundaries::periodic()
            .with(0, slip, slip)
            .with(1, slip, slip)
            .with(2, slip, slip);
        let mut solver = FlowSolver::new(grid, walls, 1e-3, Communicator::serial()).unwrap();
        let [a, b, c, d, e, f] = [0.3, -1.1, 0.7, 2.0, -0.4, 1.5];
        solver.set_velocity(|component, [x, y, z]| match component {
            0 => a * y + b * z,
            1 => c * x + d * z,
            _ => e * x + f * y,
        });
        let mut scratch = CellFields::default();
        let fields = scratch.compute(&mut solver, 1000.0);
        let expected = [f - d, b - e, c - a];
        for cell in inner_cells(cells, 3) {
            for (axis, (value, exact)) in fields.vorticity[cell].iter().zip(expected).enumerate() {
                let error = value - exact;
                assert!(error.abs() < 1e-12, "cell {cell}, axis {axis}: {error}");
            }
        }
    }

    /// The same in 2D, the line axis y stretched: u = (a y, c x) has
    /// ω_z = c − a.
    #[test]
    fn the_cell_vorticity_of_a_linear_plane_flow_is_its_curl() {
        let cells = [6, 7, 1];
        let faces: Vec<f64> = (0..=7).map(|i| (i as f64 / 7.0).powf(1.3)).collect();
        let grid =
            Grid::stretched(Dimension::Two, cells, [0.0; 3], [1.0, 1.0, 1.0], &faces).unwrap();
        let slip = BoundaryCondition::FreeSlip;
        let walls = Boundaries::periodic()
            .with(0, slip, slip)
            .with(1, slip, slip);
        let mut solver = FlowSolver::new(grid, walls, 1e-3, Communicator::serial()).unwrap();
        let (a, c) = (0.6, -1.7);
        solver.set_velocity(|component, [x, y, _]| if component == 0 { a * y } else { c * x });
        let mut scratch = CellFields::default();
        let fields = scratch.compute(&mut solver, 1000.0);
        for cell in inner_cells(cells, 2) {
            let error = fields.vorticity[cell][2] - (c - a);
            assert!(error.abs() < 1e-12, "cell {cell}: {error}");
            assert_eq!(fields.vorticity[cell][..2], [0.0, 0.0]);
        }
    }
}
