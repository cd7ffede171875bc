//! Spheres on the axis of an (r, z) flow as the grid sees them: the faces
//! of each velocity component within a sphere's support, with their solid
//! fractions (eq. 8–10 in the meridian plane) and control volumes.
//!
//! A face at radius `r` and height `z` stands for the ring of revolution
//! through it: its solid fraction is eq. 8 at the offset `(r, z − z_p)`
//! from the centre, with `λ = |n_r| + |n_z|` and `Δ = √2 Δx` of the
//! meridian grid (the 2D form; the cells are squares in that plane where
//! the grain is), and its volume is the ring's, `2π r̄ Δr Δz`.

use grainflow_dem::Particles;
use grainflow_fluid::axisymmetric::{RzField, RzGrid, RzWalls};
use grainflow_fluid::FluidError;
use std::f64::consts::PI;

use crate::solid_fraction::{solid_fraction, support, transition_width};

/// The faces of one component within a body's support.
#[derive(Clone, Debug, Default)]
pub(crate) struct RingFaces {
    /// Flat indices of the faces.
    pub index: Vec<usize>,
    /// Solid fraction of each (the body's share where supports overlap).
    pub alpha: Vec<f64>,
    /// Ring volume of each (m³).
    pub volume: Vec<f64>,
}

/// One grain on the axis.
#[derive(Clone, Debug)]
pub(crate) struct AxialBody {
    /// Index of the grain among the DEM's particles.
    pub particle: usize,
    /// Height of the centre (m).
    pub z: f64,
    /// Velocity along the axis (m/s).
    pub velocity: f64,
    pub radius: f64,
    /// Faces of `u_r` and of `u_z`.
    pub faces: [RingFaces; 2],
}

/// The grains of an (r, z) flow, made once per stage.
pub struct AxialBodies {
    /// Grains (the loads have one entry each).
    pub(crate) count: usize,
    pub(crate) list: Vec<AxialBody>,
}

/// The layer of cells along each wall end of the domain that the moving
/// grains leave to the fluid: `u_r` at the first cell's centre height and
/// `u_z` on its far face (see [`crate::forcing`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EndLayers {
    /// Whether the lower and upper ends are walls with such a layer.
    pub ends: [bool; 2],
}

impl EndLayers {
    /// No layer: the paper's forcing, which reaches the walls.
    pub const NONE: EndLayers = EndLayers { ends: [false; 2] };

    /// A layer at every wall end of `walls`.
    pub fn at_walls(walls: &RzWalls) -> Self {
        let wall = !walls.periodic();
        EndLayers { ends: [wall; 2] }
    }

    /// Whether padded z index `k` of `field` lies in a layer.
    fn holds(&self, grid: &RzGrid, field: RzField, k: usize) -> bool {
        let n = grid.cells[1];
        match field {
            // Centres: the first and last cells.
            RzField::Radial => (self.ends[0] && k == 1) || (self.ends[1] && k == n),
            // Faces: the far faces of those cells.
            _ => (self.ends[0] && k == 1) || (self.ends[1] && k + 1 == n),
        }
    }
}

/// The transition width `Δ` of eq. 8 on `grid`, from its first radial
/// cell (the uniform core the grains stand in) and its axial step.
pub fn ring_width(grid: &RzGrid) -> f64 {
    transition_width(&[grid.width(1), grid.dz])
}

/// Checks that every grain of `particles` stands on the axis and that its
/// support lies in the uniform core of the radial grid, inside the outer
/// wall; names the grain and what is allowed otherwise.
pub fn check_grains_on_axis(particles: &Particles, grid: &RzGrid) -> Result<(), FluidError> {
    let width = ring_width(grid);
    let core = grid.width(1);
    let tolerance = 1e-9 * core;
    for k in 0..particles.n_owned {
        let position = particles.position[k];
        let off_axis = position.x.hypot(position.y);
        if off_axis > tolerance {
            return Err(FluidError::Unsupported(format!(
                "grain {k} stands {off_axis:.3e} m off the axis: an axisymmetric scene holds \
                 grains on the axis only (x = y = 0)"
            )));
        }
        let reach = support(particles.radius[k], width);
        if reach >= grid.radius {
            return Err(FluidError::Unsupported(format!(
                "grain {k}'s immersed boundary reaches r = {reach:.4e} m, past the outer wall at \
                 {:.4e} m: widen the domain",
                grid.radius
            )));
        }
        let stretched = (1..=grid.cells[0])
            .take_while(|&i| grid.face(i - 1) < reach)
            .find(|&i| (grid.width(i) - core).abs() > 1e-9 * core);
        if let Some(i) = stretched {
            return Err(FluidError::Unsupported(format!(
                "grain {k}'s immersed boundary reaches r = {reach:.4e} m, into the stretched \
                 radial cell {i} (width {:.4e} m against the core's {core:.4e} m): the forcing \
                 needs uniform cells; extend the uniform core past the grain's support",
                grid.width(i)
            )));
        }
    }
    Ok(())
}

impl AxialBodies {
    /// Every grain of `particles` with its faces on `grid` (the grains
    /// checked by [`check_grains_on_axis`]). Moving grains leave the faces
    /// of `layers` alone; where supports overlap each body takes the share
    /// `α_p / max(1, Σ_q α_q)` of a face.
    pub fn new(
        particles: &Particles,
        grid: &RzGrid,
        walls: &RzWalls,
        layers: &EndLayers,
        scratch: &mut [Vec<f64>; 2],
    ) -> Self {
        let width = ring_width(grid);
        let count = particles.n_owned;
        let mut list: Vec<AxialBody> = (0..count)
            .map(|k| {
                let moving = particles.inverse_mass[k] > 0.0;
                let mut body = AxialBody {
                    particle: k,
                    z: particles.position[k].z,
                    velocity: particles.velocity[k].z,
                    radius: particles.radius[k],
                    faces: Default::default(),
                };
                for (c, field) in [RzField::Radial, RzField::Axial].into_iter().enumerate() {
                    let skip = |k: usize| moving && layers.holds(grid, field, k);
                    body.faces[c] = ring_faces(grid, walls, field, &body, width, skip);
                }
                body
            })
            .collect();
        share_overlaps(&mut list, scratch);
        AxialBodies { count, list }
    }
}

/// The faces of `field` within `body`'s support and their fractions,
/// less those `skip` leaves out by their z index.
fn ring_faces(
    grid: &RzGrid,
    walls: &RzWalls,
    field: RzField,
    body: &AxialBody,
    width: f64,
    skip: impl Fn(usize) -> bool,
) -> RingFaces {
    let reach = support(body.radius, width);
    let [nr, _] = grid.cells;
    let mut faces = RingFaces::default();
    let radii = match field {
        RzField::Radial => 1..nr,
        _ => 1..nr + 1,
    };
    let height = |k: usize| match field {
        RzField::Radial => grid.z_centre(k),
        _ => grid.z_face(k),
    };
    let length = grid.z_range[1] - grid.z_range[0];
    for k in walls.z_unknowns(grid, field) {
        let mut dz = height(k) - body.z;
        if walls.periodic() {
            // The nearest image of the grain across the periodic ends.
            dz -= length * (dz / length).round();
        }
        if dz.abs() >= reach || skip(k) {
            continue;
        }
        for i in radii.clone() {
            let (r, ring) = match field {
                RzField::Radial => (
                    grid.face(i),
                    0.5 * (grid.centre(i) + grid.centre(i + 1)) * grid.gap(i),
                ),
                _ => (grid.centre(i), grid.ring(i)),
            };
            if r >= reach {
                break;
            }
            let alpha = solid_fraction([r, dz, 0.0], body.radius, width);
            if alpha > 0.0 {
                faces.index.push(grid.index(i, k));
                faces.alpha.push(alpha);
                faces.volume.push(2.0 * PI * ring * grid.dz);
            }
        }
    }
    faces
}

/// Each body's fraction on a face shared with others becomes its share,
/// `α_p / max(1, Σ_q α_q)`. `scratch` holds zeros on entry and on exit.
fn share_overlaps(list: &mut [AxialBody], scratch: &mut [Vec<f64>; 2]) {
    if list.len() < 2 {
        return;
    }
    for c in 0..2 {
        let total = &mut scratch[c];
        for body in list.iter() {
            let faces = &body.faces[c];
            for (&at, &alpha) in faces.index.iter().zip(&faces.alpha) {
                total[at] += alpha;
            }
        }
        for body in list.iter_mut() {
            let faces = &mut body.faces[c];
            for (&at, alpha) in faces.index.iter().zip(faces.alpha.iter_mut()) {
                *alpha /= total[at].max(1.0);
            }
        }
        for body in list.iter() {
            for &at in &body.faces[c].index {
                total[at] = 0.0;
            }
        }
    }
}
