//! Direct forcing of the flow by immersed spheres (Izard et al. 2014,
//! eq. 3–7) and the hydrodynamic loads it implies.
//!
//! Within a Runge–Kutta stage of length `h = α_k Δt`, after the prediction
//! `V` of the flow and before its projection, every face of every velocity
//! component receives
//!
//! ```text
//! f = Σ_p w_p (U_p − V) / h,      U_p = u_p + ω_p × r,      (eq. 7)
//! w_p = α_p / max(1, Σ_q α_q),
//! ```
//!
//! with `α_p` the solid fraction of particle `p` at the face (eq. 8–10),
//! so that `V + h f` moves with the particle where it is solid. Where the
//! transition layers of touching particles overlap, the weights are scaled
//! so that they never add up to more than one (the velocity is then the
//! fraction-weighted mean of the particles' rigid velocities, whatever
//! their order). The particle receives the opposite of what it gives the
//! fluid: per unit fluid density,
//!
//! ```text
//! F_p = −Σ_faces w_p (U_p − V) / h dV,      T_p = −Σ_faces r × w_p (U_p − V) / h dV,
//! ```
//!
//! the discrete `−∫ f dϑ` and `−∫ r × f dϑ` of eq. 5–6. The fluid's
//! momentum inside each particle, `∫ α_p u dV` and `∫ r × α_p u dV`, is
//! measured on the same faces for the coupling that accounts for it.
//!
//! The forcing reaches the walls of the flow domain, as the paper's does,
//! unless a case leaves the first layer of cells there to the fluid
//! ([`WallLayer`], `coupling.wall_layer = "free"`; glued grains, the
//! wall's roughness, force it either way): that cell holds the film
//! between a grain and the wall, which the flow cannot resolve and eq. 19
//! models. Measured on this version, the forced layer bounces a sphere
//! within the experiments' band at every Stokes number (its suction takes
//! 0.02 of the rebound at St ≈ 311) and is the closer to Stokes flow for a
//! grain sliding or rolling along the wall (`docs/validation.md`,
//! section 7).
//!
//! Every particle whose support reaches this rank's cells acts on them:
//! its owned particles and the ghosts the DEM keeps within
//! [`ghost_reach`] of the subdomain, periodic images included. So a
//! forcing region may straddle a periodic edge or a subdomain edge: the
//! loads are computed per local particle (owned, then ghosts) and the
//! ghosts' shares are added to their owners by the DEM
//! (`DemSystem::sum_onto_owners`).

use grainflow_core::{Dimension, Vec3};
use grainflow_dem::Particles;
use grainflow_fluid::{Block, Grid, Location};
use rayon::prelude::*;

use crate::body::Body;
pub use crate::exponents::Exponents;
use crate::faces::{FaceRows, FaceScratch};
use crate::layer_forcing::{LayerForcing, SLIP_SUMS};
pub use crate::loads::{vectors_on_owners, Loads};
use crate::overlaps::pressed_bodies;
use crate::solid_fraction::{solid_fraction, support, transition_width};
pub use crate::wall_layer::WallLayer;

/// How far from a subdomain's faces the DEM must keep ghosts for the
/// immersed boundaries of grains of radius up to `max_radius` on `grid`:
/// the support of eq. 8 plus a cell (a rank's cells and its particle box
/// may differ by less than one).
pub fn ghost_reach(grid: &Grid, max_radius: f64) -> f64 {
    let dim = grid.dim();
    let widest = grid.spacing[..dim].iter().copied().fold(0.0, f64::max);
    support(max_radius, transition_width(&grid.spacing[..dim])) + widest
}

/// The particles of a subdomain as the grid sees them: every local
/// particle (owned or ghost) whose support reaches its cells. Built once
/// per stage ([`ImmersedBoundaries::bodies`]), while the particles stand
/// still.
pub struct Bodies {
    /// Local particles (the loads have one entry each).
    pub(crate) count: usize,
    pub(crate) list: Vec<Body>,
    /// Whether the forcing's sums of eq. 7 over these bodies are made
    /// already (`bodies_with_inner_momentum`), from the fractions before
    /// their shares.
    pub(crate) forcing_sums_made: bool,
}

/// The immersed spheres' action on the flow of one subdomain.
pub struct ImmersedBoundaries {
    /// `Δ` of eq. 8.
    pub width: f64,
    /// How fast the forcing relaxes the transition layer
    /// ([`crate::layer_forcing`]); eq. 7 at every stage unless set.
    pub layer: LayerForcing,
    /// The layers of cells along the walls that the moving grains leave to
    /// the fluid ([`WallLayer::along_walls`]); empty, the paper's forcing, which
    /// reaches the walls.
    pub free_wall_layers: Vec<WallLayer>,
    dimension: Dimension,
    /// `Σ_p α_p` on the faces of each component (zero outside the stencils
    /// between stages).
    pub(crate) total_fraction: Vec<Vec<f64>>,
    /// `Σ_p α_p U_p` on the faces of each component.
    pub(crate) solid_velocity: Vec<Vec<f64>>,
    /// `Σ V*` over the passes of a stage forced in several, `V*` the
    /// velocity before each pass's forcing (`forcing_passes.rs`); empty
    /// until a stage takes two passes.
    pub(crate) velocity_before_passes: Vec<Vec<f64>>,
    /// Whether the two sums above hold a stage's forcing until `apply`.
    forcing_sums_pending: bool,
}

impl ImmersedBoundaries {
    /// Immersed boundaries on the flow grid `grid` (a rank's share). The
    /// grid must be uniform: the transition width of eq. 10 is a cell size
    /// and the loads integrate with one cell volume (the case refuses a
    /// stretched grid with grains before this).
    pub fn new(grid: &Grid) -> Self {
        let dim = grid.dim();
        assert!(
            grid.is_uniform(grid.line_axis()),
            "immersed boundaries need a uniform grid"
        );
        ImmersedBoundaries {
            width: transition_width(&grid.spacing[..dim]),
            layer: LayerForcing::EveryStage,
            free_wall_layers: Vec::new(),
            dimension: grid.dimension,
            total_fraction: (0..dim).map(|_| grid.zeros()).collect(),
            solid_velocity: (0..dim).map(|_| grid.zeros()).collect(),
            velocity_before_passes: Vec::new(),
            forcing_sums_pending: false,
        }
    }

    /// `Σ_faces α_p dV` over this rank's faces of each velocity component,
    /// for each local particle: the volume the grid sees (area in 2D),
    /// which exceeds the sphere's by a few per cent (the tanh layer of
    /// eq. 8 is not symmetric about R in volume).
    /// Read off the fractions the bodies hold for the stage.
    pub fn grid_volumes(&self, grid: &Grid, bodies: &Bodies) -> Vec<Vec3> {
        let volume = grid.cell_volume();
        let mut volumes = vec![Vec3::zeros(); bodies.count];
        for body in &bodies.list {
            for (component, faces) in body.faces.iter().enumerate() {
                let sum = match body.fraction_sums {
                    Some(sums) => sums[component],
                    None => faces.sum(),
                };
                volumes[body.particle][component] += sum * volume;
            }
        }
        volumes
    }

    /// The fluid's momentum and angular momentum (about each centre) inside
    /// each local particle, `∫ α_p u dV` and `∫ r × α_p u dV` over this
    /// rank's faces, per unit density.
    pub fn inner_momentum(&self, grid: &Grid, velocity: &[Vec<f64>], bodies: &Bodies) -> Loads {
        let volume = grid.cell_volume();
        let per_body: Vec<(Vec3, Vec3)> = bodies
            .list
            .par_iter()
            .map(|body| body.inner_momentum(velocity, volume))
            .collect();
        self.gather(bodies, &per_body)
    }

    /// [`ImmersedBoundaries::bodies`] and their
    /// [`ImmersedBoundaries::inner_momentum`] in `velocity`, each body's
    /// momentum measured as soon as its fractions are final (while they
    /// are in cache: one pass over them the fewer).
    ///
    /// With eq. 7 at every stage (no forcing step) the forcing's sums are
    /// made here too, from the fractions before the shares: with
    /// `T = Σ_q α_q` on a face, the shares `α_p / max(1, T)` give
    /// `Σ_p share_p U_p = (Σ_p α_p U_p)/max(1, T)` and `Σ_p share_p =
    /// T/max(1, T)`, so eq. 7 moves the face by the same
    /// `(Σ α_p U_p − T V)/max(1, T)`, and `T` is the sum the shares are
    /// made of. One pass over the faces makes both, where the shares
    /// alone took three. [`ImmersedBoundaries::apply`] must follow,
    /// before any other call that makes bodies.
    pub fn bodies_with_inner_momentum(
        &mut self,
        particles: &Particles,
        grid: &Grid,
        unknowns: &[Block],
        velocity: &[Vec<f64>],
    ) -> (Bodies, Loads) {
        let volume = grid.cell_volume();
        let mut bodies = self.local_bodies(particles, grid);
        // Grains pressed into others take their shares of the faces first
        // (`overlaps.rs`): they are measured after.
        let pressed = pressed_bodies(&bodies, self.width);
        let every_stage = self.layer == LayerForcing::EveryStage;
        let per_body: Vec<Option<(Vec3, Vec3)>> =
            if every_stage && rayon::current_num_threads() == 1 {
                // One thread: each body's forcing sums added as soon as its
                // fractions are made, in list order (the same bits as the pass
                // over all bodies, one read of the fractions the fewer).
                let mut scratch = FaceScratch::default();
                let mut per_body = Vec::with_capacity(bodies.list.len());
                for (body, &pressed) in bodies.list.iter_mut().zip(&pressed) {
                    body.faces = self.body_faces(particles, grid, unknowns, body, &mut scratch);
                    self.add_forcing_sums_of(grid, body, &Exponents::Uniform(1.0));
                    per_body.push((!pressed).then(|| body.inner_momentum(velocity, volume)));
                }
                per_body
            } else {
                let per_body = bodies
                    .list
                    .par_iter_mut()
                    .zip(&pressed)
                    .map_init(FaceScratch::default, |scratch, (body, &pressed)| {
                        body.faces = self.body_faces(particles, grid, unknowns, body, scratch);
                        (!pressed).then(|| body.inner_momentum(velocity, volume))
                    })
                    .collect();
                if every_stage {
                    self.add_forcing_sums(grid, &bodies, &Exponents::Uniform(1.0));
                }
                per_body
            };
        let per_body: Vec<(Vec3, Vec3)> = if every_stage {
            bodies.forcing_sums_made = true;
            self.forcing_sums_pending = true;
            let totals = &self.total_fraction;
            bodies
                .list
                .par_iter_mut()
                .zip(per_body)
                .map(|(body, measured)| {
                    measured.unwrap_or_else(|| body.share_and_weigh(totals, velocity, volume))
                })
                .collect()
        } else {
            self.share_overlaps(grid, &mut bodies, &pressed);
            bodies
                .list
                .par_iter()
                .zip(per_body)
                .map(|(body, measured)| {
                    measured.unwrap_or_else(|| body.inner_momentum(velocity, volume))
                })
                .collect()
        };
        let momentum = self.gather(&bodies, &per_body);
        (bodies, momentum)
    }

    /// The sums of each local particle's layer slip in the predicted
    /// `velocity` on this rank's faces ([`SLIP_SUMS`] numbers per local
    /// particle, owned then ghosts; zero for those without faces here):
    /// what [`LayerForcing::Renewal`] reads its rates from, once summed
    /// over the ranks.
    pub fn layer_slips(&self, velocity: &[Vec<f64>], bodies: &Bodies) -> Vec<f64> {
        let per_body: Vec<[f64; SLIP_SUMS]> = bodies
            .list
            .par_iter()
            .map(|body| body.layer_slip(velocity))
            .collect();
        let mut sums = vec![0.0; SLIP_SUMS * bodies.count];
        for (body, own) in bodies.list.iter().zip(&per_body) {
            let at = SLIP_SUMS * body.particle;
            for (sum, value) in sums[at..at + SLIP_SUMS].iter_mut().zip(own) {
                *sum += value;
            }
        }
        sums
    }

    /// Applies the direct forcing of a stage of length `stage_dt` to the
    /// predicted velocity and returns the loads on each local particle
    /// from this rank's faces, per unit fluid density (eq. 5–7 without the
    /// density factors).
    ///
    /// Each stage moves a face of solid fraction `α` by `β = 1 − (1 −
    /// α)^e` of the way to the rigid velocity, `e` the grain's exponent in
    /// `exponents` ([`crate::layer_forcing`]): 1 for eq. 7, `Δt/Δt_f` with
    /// the layer held at `Δt_f`, each grain's own under
    /// [`LayerForcing::Renewal`].
    pub fn apply(
        &mut self,
        grid: &Grid,
        velocity: &mut [Vec<f64>],
        bodies: &Bodies,
        stage_dt: f64,
        exponents: &Exponents,
    ) -> Loads {
        self.begin_forcing(grid, bodies, exponents);
        self.last_pass(grid, velocity, bodies, stage_dt, exponents, 1)
    }

    /// `Σ_p α_p` capped at 1 at every owned cell centre, in the order of
    /// [`Grid::for_each`] over the cell block: the solid fraction field for
    /// output.
    pub fn cell_solid_fraction(&self, grid: &Grid, particles: &Particles) -> Vec<f64> {
        let cells = grid.cell_block();
        let mut field = grid.zeros();
        for body in &self.local_bodies(particles, grid).list {
            let reach = support(body.radius, self.width);
            let mut stencil = cells;
            for axis in 0..grid.dim() {
                let (h, ghost) = (grid.spacing[axis], grid.ghost(axis) as f64);
                let index_of = |x: f64| (x - grid.lower[axis]) / h + ghost - 0.5;
                let first = index_of(body.centre[axis] - reach).ceil().max(0.0) as usize;
                let last = index_of(body.centre[axis] + reach).floor().max(-1.0) + 1.0;
                stencil.start[axis] = first.max(cells.start[axis]);
                stencil.end[axis] = (last as usize)
                    .min(cells.end[axis])
                    .max(stencil.start[axis]);
            }
            grid.for_each(&stencil, |index, point| {
                let mut r = [0.0; 3];
                for axis in 0..grid.dim() {
                    r[axis] =
                        grid.coordinate(Location::Centre, axis, point[axis]) - body.centre[axis];
                }
                field[index] += solid_fraction(r, body.radius, self.width);
            });
        }
        let mut out = Vec::with_capacity(grid.cells.iter().product());
        grid.for_each(&cells, |index, _| out.push(field[index].min(1.0)));
        out
    }

    /// Marks the scratch sums as holding a stage's forcing (or its kept
    /// prediction) until it is applied (or read).
    pub(crate) fn set_forcing_sums_pending(&mut self, pending: bool) {
        self.forcing_sums_pending = pending;
    }

    /// The local particles whose support reaches the cells of `grid`, with
    /// their solid fractions on the faces of the velocity unknowns
    /// `unknowns`.
    /// Where supports overlap, each fraction is the body's share of the
    /// face (`overlaps.rs`).
    pub fn bodies(&mut self, particles: &Particles, grid: &Grid, unknowns: &[Block]) -> Bodies {
        debug_assert!(
            !self.forcing_sums_pending,
            "the scratch sums hold a stage's forcing: apply it first"
        );
        let mut bodies = self.local_bodies(particles, grid);
        bodies
            .list
            .par_iter_mut()
            .for_each_init(FaceScratch::default, |scratch, body| {
                body.faces = self.body_faces(particles, grid, unknowns, body, scratch)
            });
        let pressed = pressed_bodies(&bodies, self.width);
        self.share_overlaps(grid, &mut bodies, &pressed);
        bodies
    }

    /// The faces of each velocity component within the support of `body`,
    /// with their fractions.
    fn body_faces(
        &self,
        particles: &Particles,
        grid: &Grid,
        unknowns: &[Block],
        body: &Body,
        scratch: &mut FaceScratch,
    ) -> Vec<FaceRows> {
        // Glued grains are the wall's roughness: they keep forcing it.
        let layers: &[WallLayer] = if particles.inverse_mass[body.particle] > 0.0 {
            &self.free_wall_layers
        } else {
            &[]
        };
        (0..grid.dim())
            .map(|component| {
                FaceRows::new(
                    self.width,
                    grid,
                    &unknowns[component],
                    component,
                    body.centre,
                    body.radius,
                    layers,
                    scratch,
                )
            })
            .collect()
    }

    /// The local particles (owned, then ghosts: periodic images and other
    /// ranks' grains) whose support reaches the cells of `grid`, without
    /// their solid fractions on the faces (what the cell-centred output
    /// needs).
    fn local_bodies(&self, particles: &Particles, grid: &Grid) -> Bodies {
        let dim = grid.dim();
        let reaches = |p: usize| {
            let reach = support(particles.radius[p], self.width);
            let centre = particles.position[p];
            (0..dim).all(|a| {
                let h = grid.spacing[a];
                centre[a] + reach > grid.lower[a] - h && centre[a] - reach < grid.upper[a] + h
            })
        };
        let list = (0..particles.len())
            .filter(|&p| reaches(p))
            .map(|p| Body {
                particle: p,
                centre: particles.position[p],
                velocity: particles.velocity[p],
                angular_velocity: particles.angular_velocity[p],
                radius: particles.radius[p],
                faces: Vec::new(),
                fraction_sums: None,
            })
            .collect();
        Bodies {
            count: particles.len(),
            list,
            forcing_sums_made: false,
        }
    }

    /// Adds the per-body results into per-particle loads, in body order.
    pub(crate) fn gather(&self, bodies: &Bodies, per_body: &[(Vec3, Vec3)]) -> Loads {
        let mut loads = Loads::zeros(bodies.count);
        for (body, (force, torque)) in bodies.list.iter().zip(per_body) {
            loads.force[body.particle] += force;
            loads.torque[body.particle] += torque;
        }
        if self.dimension == Dimension::Two {
            // Discs in the plane: no out-of-plane force, no in-plane torque.
            for (force, torque) in loads.force.iter_mut().zip(&mut loads.torque) {
                force.z = 0.0;
                torque.x = 0.0;
                torque.y = 0.0;
            }
        }
        loads
    }
}

impl Bodies {
    /// Bodies of `list`, one per particle, for tests.
    #[cfg(test)]
    pub(crate) fn of_list(list: Vec<Body>) -> Bodies {
        Bodies {
            count: list.len(),
            list,
            forcing_sums_made: false,
        }
    }

    /// Whether the forcing's sums of eq. 7 over these bodies are made
    /// (eq. 7 at every stage, [`ImmersedBoundaries::bodies_with_inner_momentum`]).
    pub fn forcing_sums_made(&self) -> bool {
        self.forcing_sums_made
    }
}
