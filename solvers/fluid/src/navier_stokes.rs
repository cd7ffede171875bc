//! One time step of the incompressible Navier–Stokes equations (Izard et
//! al. 2014, eq. 1–2), with kinematic pressure `p/ρ` and viscosity `ν`:
//!
//! ```text
//! ∂u/∂t = −∇·(u u) − ∇p + ν ∇²u + f − ∇⟨p⟩,     ∇·u = 0,
//! ```
//!
//! where `f` is a body acceleration (gravity, later the immersed-boundary
//! forcing) and `∇⟨p⟩` an imposed mean pressure gradient (per unit density)
//! that drives periodic channels.
//!
//! Each step has three stages `k = 1, 2, 3` of Wray's low-storage
//! Runge–Kutta scheme, `γ = (8/15, 5/12, 3/4)`, `ζ = (0, −17/60, −5/12)`,
//! `α_k = γ_k + ζ_k`, with the viscous term by Crank–Nicolson and a
//! projection at every stage. With `N(u) = −∇·(u u)`:
//!
//! 1. prediction, in increment form `δu = u* − u^{k−1}`:
//!    `(I − α_k ν Δt/2 L) δu = Δt [γ_k N(u^{k−1}) + ζ_k N(u^{k−2}) − α_k G p^{k−1}
//!                                  + α_k ν L u^{k−1} + α_k (f − ∇⟨p⟩)]`;
//!    the boundary values of `u` do not change in time, so `δu` meets
//!    homogeneous conditions and the Helmholtz solve is direct;
//! 2. projection: `L φ = D u* / (α_k Δt)`, `u^k = u* − α_k Δt G φ`;
//! 3. pressure: `p^k = p^{k−1} + φ − α_k ν Δt/2 L φ`.
//!
//! The velocity is second order in time (Crank–Nicolson and the
//! incremental pressure) and in space (central differences on the
//! staggered grid); the pressure after a step is first order in time (see
//! [`FlowSolver::pressure`]). After every projection `D u` vanishes to
//! round-off.
//!
//! With [`ViscousScheme::Explicit`] the Helmholtz solve is skipped (the
//! viscous term is then forward Euler over each stage's `α_k Δt`, first
//! order, stable up to [`EXPLICIT_VISCOUS_LIMIT`]) and the pressure update
//! drops its Crank–Nicolson part.

use grainflow_core::Communicator;

use crate::boundary::{
    fill_ghosts_on, fill_ghosts_together, homogeneous, local_ends, unknowns, Boundaries, FieldEnds,
    GhostedField, HaloExchange,
};
use crate::error::FluidError;
use crate::grid::{Block, Grid, Location};
use crate::operators::{add_laplacian, convective_tendency, divergence, subtract_gradient};
use crate::partition::Partition;
use crate::poisson::{DirectSolver, TransformBackend};

mod measures;
mod step_limits;
pub(crate) use step_limits::larger_magnitude;

pub use step_limits::time_step_for_cfl_rates;

/// Stages of a step.
pub const STAGES: usize = 3;

/// Wray's low-storage RK3: weight of the explicit terms at the current stage.
const GAMMA: [f64; 3] = [8.0 / 15.0, 5.0 / 12.0, 3.0 / 4.0];
/// Weight of the explicit terms of the previous stage.
const ZETA: [f64; 3] = [0.0, -17.0 / 60.0, -5.0 / 12.0];

/// The fraction `α_k = γ_k + ζ_k` of a step that stage `stage` advances
/// (8/15, 2/15, 1/3: they add up to 1).
pub fn stage_fraction(stage: usize) -> f64 {
    GAMMA[stage] + ZETA[stage]
}

/// Stability limit of the convective CFL number `Δt max_cells Σ_a |u_a| / h_a`
/// ([`FlowSolver::max_cfl`]): central differences put the eigenvalues of
/// convection on the imaginary axis, up to `i Σ_a |u_a| / h_a` where the
/// velocity is `u` (frozen coefficients), and the RK3 amplification factor
/// `|1 + z + z²/2 + z³/6|` exceeds 1 on the imaginary axis beyond `|z| = √3`.
/// The viscous term is implicit and sets no limit.
pub const CFL_LIMIT: f64 = 1.732_050_807_568_877_2;

/// Stability limit of an explicit viscous step, on the viscous number
/// `ν Δt Σ_a 4/h_a²` (the largest |eigenvalue| of the discrete Laplacian
/// times ν Δt): each stage advances the viscous term by forward Euler over
/// `α_k Δt`, so a step multiplies a Laplacian mode by
/// `G(z) = Π_k (1 + α_k z)`, `α = (8/15, 2/15, 1/3)`, which leaves [−1, 1]
/// below `z = −8.6148…` (the root of `G(z) = −1`).
pub const EXPLICIT_VISCOUS_LIMIT: f64 = 8.614_810_406_648_447;

/// How the viscous term is advanced within each Runge–Kutta stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViscousScheme {
    /// Crank–Nicolson: one Helmholtz solve per component and stage, no
    /// stability limit from the viscosity.
    CrankNicolson,
    /// Explicit (forward Euler over each stage's `α_k Δt`): no solve, but
    /// the step must keep the viscous number below [`EXPLICIT_VISCOUS_LIMIT`];
    /// first order in time for the viscous term.
    Explicit,
}

/// Diagnostics of the flow after a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepReport {
    /// `½ ∫ |u|² dV` (m⁵/s² per unit density; m⁴/s² per unit depth in 2D).
    pub kinetic_energy: f64,
    /// `Δt max_cells Σ_a |u_a| / h_a`, the convective CFL number cell by
    /// cell ([`FlowSolver::max_cfl`]).
    pub max_cfl: f64,
    /// Largest `|D u|` (1/s) after any of the step's three projections.
    pub max_divergence: f64,
}

/// The incompressible flow on one subdomain and its time stepping.
pub struct FlowSolver {
    /// The grid and the walls the solvers were planned for: read them, do
    /// not change them (build a new solver for another grid or walls).
    pub grid: Grid,
    pub boundaries: Boundaries,
    /// Kinematic viscosity ν (m²/s).
    pub viscosity: f64,
    /// Body acceleration `f` (m/s²): gravity and other volume forces per unit mass.
    pub body_force: [f64; 3],
    /// Imposed mean pressure gradient per unit density, `∇⟨p⟩/ρ` (m/s²);
    /// a negative x entry drives a flow towards +x.
    pub mean_pressure_gradient: [f64; 3],
    /// Bulk velocity held constant along each periodic axis that has one
    /// (m/s): at every stage a uniform forcing `f` enters the prediction
    /// beside the mean pressure gradient, chosen so that the velocity along
    /// that axis averages to it after the Helmholtz solve (the projection
    /// leaves a periodic axis' mean unchanged). Since `f` goes through the
    /// same implicit solve as a pressure gradient, the steady state is the
    /// one that pressure gradient would give.
    pub bulk_velocity: [Option<f64>; 3],
    /// The mean pressure gradient per unit density (m/s²) that held the
    /// bulk velocity during the last step, `−Σ_k α_k f_k`.
    pub flow_rate_gradient: [f64; 3],
    /// Velocity components on the faces: `velocity[a]` is normal to axis `a` (m/s).
    pub velocity: Vec<Vec<f64>>,
    /// Kinematic pressure `p/ρ` at cell centres (m²/s²), zero mean, the
    /// mean gradient excluded. After a step it is first order in time at
    /// the step's end (the velocity is second order): the last stage's
    /// projection balances convection centred near `t + 5Δt/6`.
    pub pressure: Vec<f64>,
    /// Simulated time (s).
    pub time: f64,
    /// A step whose CFL number at its start exceeds this is refused;
    /// [`CFL_LIMIT`] unless set otherwise.
    pub cfl_limit: f64,
    /// Crank–Nicolson unless set otherwise.
    pub viscous_scheme: ViscousScheme,
    /// With the explicit viscous scheme, a step whose viscous number
    /// exceeds this is refused; [`EXPLICIT_VISCOUS_LIMIT`] unless set otherwise.
    pub viscous_limit: f64,
    /// This rank's share of the cells (all of them on one rank), the
    /// periodic axes and the communicator: what the ghost fills across
    /// ranks and the reductions need.
    ranks: HaloExchange,
    /// End conditions of this rank's fields (halos where another rank's
    /// cells lie beyond).
    velocity_ends: Vec<FieldEnds>,
    pressure_ends: FieldEnds,
    velocity_unknowns: Vec<Block>,
    velocity_solvers: Vec<DirectSolver>,
    pressure_solver: DirectSolver,
    /// `N(u^{k−1})` of the current stage.
    tendency: Vec<Vec<f64>>,
    /// `N(u^{k−2})` of the previous stage.
    previous_tendency: Vec<Vec<f64>>,
    /// Right-hand side, then solution, of the Helmholtz equation for `δu`.
    increment: Vec<Vec<f64>>,
    /// The projection's potential `φ`.
    correction: Vec<f64>,
    /// Response of the increment to a unit uniform forcing (bulk velocity).
    bulk_response: Vec<f64>,
    divergence: Vec<f64>,
}

impl FlowSolver {
    /// A fluid at rest on `grid` with walls `boundaries`, its direct
    /// solvers using [`TransformBackend::preferred`].
    pub fn new(
        grid: Grid,
        boundaries: Boundaries,
        viscosity: f64,
        communicator: Communicator,
    ) -> Result<Self, FluidError> {
        Self::with_transforms(
            grid,
            boundaries,
            viscosity,
            communicator,
            TransformBackend::preferred(),
        )
    }

    /// [`FlowSolver::new`] with the transforms of `backend`.
    pub fn with_transforms(
        grid: Grid,
        boundaries: Boundaries,
        viscosity: f64,
        communicator: Communicator,
        backend: TransformBackend,
    ) -> Result<Self, FluidError> {
        let ranks = crate::partition::flow_process_grid(&grid, communicator.size())?;
        Self::distributed(grid, boundaries, viscosity, communicator, ranks, backend)
    }

    /// The flow on `global` shared among the ranks of `communicator` in a
    /// process grid of `ranks` ([`crate::flow_process_grid`] chooses one):
    /// this rank holds its share of the cells ([`Partition`]), and
    /// [`FlowSolver::grid`] is its part of the grid. Every rank builds its
    /// solver and steps together (the steps are collective).
    pub fn distributed(
        global: Grid,
        boundaries: Boundaries,
        viscosity: f64,
        communicator: Communicator,
        ranks: [usize; 3],
        backend: TransformBackend,
    ) -> Result<Self, FluidError> {
        boundaries.validate(&global)?;
        if !(viscosity.is_finite() && viscosity >= 0.0) {
            return Err(FluidError::Parameter(format!(
                "the kinematic viscosity must be finite and non-negative, got {viscosity}"
            )));
        }
        if ranks.iter().product::<usize>() != communicator.size() {
            return Err(FluidError::Parameter(format!(
                "the process grid {ranks:?} does not hold the {} ranks of the run",
                communicator.size()
            )));
        }
        let partition = Partition::new(&global, ranks, communicator.rank())?;
        let grid = partition.local_grid(&global);
        let dim = grid.dim();
        let global_velocity_ends: Vec<FieldEnds> = (0..dim)
            .map(|component| boundaries.velocity_ends(&global, component))
            .collect();
        let global_pressure_ends = boundaries.pressure_ends(&global);
        let solver_for = |ends: &FieldEnds| {
            DirectSolver::distributed(
                &global,
                ends,
                &grid,
                &partition,
                communicator.clone(),
                backend,
            )
        };
        let velocity_solvers = global_velocity_ends
            .iter()
            .map(|ends| solver_for(&homogeneous(ends)))
            .collect::<Result<Vec<_>, _>>()?;
        let pressure_solver = solver_for(&global_pressure_ends)?;
        let velocity_ends: Vec<FieldEnds> = global_velocity_ends
            .iter()
            .map(|ends| local_ends(ends, &partition))
            .collect();
        let pressure_ends = local_ends(&global_pressure_ends, &partition);
        let velocity_unknowns = velocity_ends
            .iter()
            .map(|ends| unknowns(&grid, ends))
            .collect();
        let periodic = [0, 1, 2]
            .map(|axis| boundaries.faces[axis][0] == crate::boundary::BoundaryCondition::Periodic);
        let field = || grid.zeros();
        let fields = |count: usize| (0..count).map(|_| grid.zeros()).collect::<Vec<_>>();
        let mut solver = FlowSolver {
            viscosity,
            body_force: [0.0; 3],
            mean_pressure_gradient: [0.0; 3],
            bulk_velocity: [None; 3],
            flow_rate_gradient: [0.0; 3],
            velocity: fields(dim),
            pressure: field(),
            time: 0.0,
            cfl_limit: CFL_LIMIT,
            viscous_scheme: ViscousScheme::CrankNicolson,
            viscous_limit: EXPLICIT_VISCOUS_LIMIT,
            ranks: HaloExchange {
                partition,
                periodic,
                communicator,
            },
            velocity_ends,
            pressure_ends,
            velocity_unknowns,
            velocity_solvers,
            pressure_solver,
            tendency: fields(dim),
            previous_tendency: fields(dim),
            increment: fields(dim),
            correction: field(),
            bulk_response: field(),
            divergence: field(),
            boundaries,
            grid,
        };
        solver.fill_velocity_ghosts();
        Ok(solver)
    }

    /// Sets every velocity unknown to `profile(component, position)`, then
    /// the boundary values. The field is used as given: project it first
    /// ([`FlowSolver::remove_divergence`]) if it is not discretely divergence free.
    pub fn set_velocity(&mut self, profile: impl Fn(usize, [f64; 3]) -> f64) {
        for component in 0..self.grid.dim() {
            let grid = &self.grid;
            let field = &mut self.velocity[component];
            grid.for_each(&self.velocity_unknowns[component], |index, [i, j, k]| {
                field[index] =
                    profile(component, grid.position(Location::Face(component), i, j, k));
            });
        }
        self.fill_velocity_ghosts();
    }

    /// Sets the pressure at every cell to `profile(position)`.
    pub fn set_pressure(&mut self, profile: impl Fn([f64; 3]) -> f64) {
        let grid = &self.grid;
        let pressure = &mut self.pressure;
        grid.for_each(&grid.cell_block(), |index, [i, j, k]| {
            pressure[index] = profile(grid.position(Location::Centre, i, j, k));
        });
        fill_ghosts_on(
            grid,
            pressure,
            Location::Centre,
            &self.pressure_ends,
            Some(&self.ranks),
        );
    }

    /// Advances the flow by `dt` (three RK3 stages) and reports on it.
    /// Refuses, leaving the flow as it was, when the CFL number of the
    /// current velocity exceeds [`FlowSolver::cfl_limit`].
    ///
    /// A scene with immersed particles drives the same stages itself
    /// ([`FlowSolver::begin_step`], then [`FlowSolver::predict`] and
    /// [`FlowSolver::project`] for each stage, with its forcing between
    /// them, then [`FlowSolver::end_step`]).
    pub fn step(&mut self, dt: f64) -> Result<StepReport, FluidError> {
        self.begin_step(dt)?;
        let mut max_divergence: f64 = 0.0;
        for stage in 0..STAGES {
            self.predict(stage, dt);
            max_divergence = max_divergence.max(self.project(stage, dt));
        }
        Ok(self.end_step(dt, max_divergence))
    }

    /// Checks that a step of `dt` is within the stability limits (CFL
    /// number, and viscous number for an explicit viscous term) before its
    /// first stage; refuses it, leaving the flow as it was, otherwise.
    pub fn begin_step(&mut self, dt: f64) -> Result<(), FluidError> {
        let cfl = self.max_cfl(dt);
        // A NaN velocity is refused too.
        if cfl > self.cfl_limit || cfl.is_nan() {
            return Err(FluidError::Unstable {
                cfl,
                limit: self.cfl_limit,
            });
        }
        let viscous_number = self.viscous_number(dt);
        if self.viscous_scheme == ViscousScheme::Explicit && viscous_number > self.viscous_limit {
            return Err(FluidError::ViscousUnstable {
                number: viscous_number,
                limit: self.viscous_limit,
            });
        }
        self.flow_rate_gradient = [0.0; 3];
        Ok(())
    }

    /// Stage `stage`'s projection, `L φ = D u* / (α_k Δt)`,
    /// `u^k = u* − α_k Δt G φ`, and pressure update; returns the largest
    /// `|D u|` after it (1/s).
    pub fn project(&mut self, stage: usize, dt: f64) -> f64 {
        let scale = stage_fraction(stage) * dt;
        self.project_with_scale(scale);
        self.update_pressure(scale);
        self.max_divergence()
    }

    /// Closes a step of `dt` whose stages have all been run: advances the
    /// time and reports on the flow (`max_divergence` over the stages).
    pub fn end_step(&mut self, dt: f64, max_divergence: f64) -> StepReport {
        self.time += dt;
        StepReport {
            kinetic_energy: self.kinetic_energy(),
            max_cfl: self.max_cfl(dt),
            max_divergence,
        }
    }

    /// Stage `stage` prediction `u*`: explicit convection (RK3), body force
    /// and mean pressure gradient, pressure of the previous stage, and
    /// viscous term, Crank–Nicolson through one Helmholtz solve per
    /// component (or explicit, without the solve). The predicted velocity
    /// is left in [`FlowSolver::velocity`] for a forcing to act on before
    /// [`FlowSolver::project`].
    pub fn predict(&mut self, stage: usize, dt: f64) {
        let (gamma, zeta) = (GAMMA[stage], ZETA[stage]);
        let alpha = gamma + zeta;
        let dim = self.grid.dim();
        // The velocity and the pressure in one exchange per split axis.
        let mut fields = velocity_fields(&mut self.velocity, &self.velocity_ends);
        fields.push(GhostedField {
            values: &mut self.pressure,
            location: Location::Centre,
            ends: &self.pressure_ends,
        });
        fill_ghosts_together(&self.grid, &mut fields, Some(&self.ranks));
        // All explicit terms from u^{k−1} before any component moves.
        for component in 0..dim {
            let grid = &self.grid;
            let block = &self.velocity_unknowns[component];
            let tendency = &mut self.tendency[component];
            convective_tendency(grid, &self.velocity, component, block, tendency);
            let previous = &self.previous_tendency[component];
            let forcing = self.body_force[component] - self.mean_pressure_gradient[component];
            let rhs = &mut self.increment[component];
            grid.par_update(block, rhs, |index, _| {
                dt * (gamma * tendency[index] + zeta * previous[index] + alpha * forcing)
            });
            subtract_gradient(grid, &self.pressure, component, block, alpha * dt, rhs);
            add_laplacian(
                grid,
                &self.velocity[component],
                Location::Face(component),
                block,
                alpha * dt * self.viscosity,
                rhs,
            );
        }
        std::mem::swap(&mut self.tendency, &mut self.previous_tendency);
        let implicit = 0.5 * alpha * dt * self.viscosity;
        for component in 0..dim {
            let grid = &self.grid;
            let increment = &mut self.increment[component];
            if self.viscous_scheme == ViscousScheme::CrankNicolson {
                self.velocity_solvers[component].solve_helmholtz(grid, increment, implicit);
            }
            if let Some(target) = self.bulk_velocity[component] {
                // The increment's response to a unit uniform forcing,
                // g = (I − c L)⁻¹ 1 (1 for an explicit viscous term), and
                // the forcing that brings the mean to the target.
                let block = &self.velocity_unknowns[component];
                let response = &mut self.bulk_response;
                response.iter_mut().for_each(|r| *r = 0.0);
                grid.par_update(block, response, |_, _| 1.0);
                if self.viscous_scheme == ViscousScheme::CrankNicolson {
                    self.velocity_solvers[component].solve_helmholtz(grid, response, implicit);
                }
                let velocity = &self.velocity[component];
                // The mean over the cells' volumes: on a stretched line
                // each value weighs its cell's width (a bulk velocity runs
                // along a periodic axis, so its values sit at centres
                // along the line axis).
                let line = grid.line_axis();
                let uniform = grid.is_uniform(line);
                let weight = |point: [usize; 3]| {
                    if uniform {
                        1.0
                    } else {
                        grid.width(line, point[line])
                    }
                };
                let total = self
                    .ranks
                    .communicator
                    .sum(grid.par_sum(block, |_, point| weight(point)));
                let mean = self
                    .ranks
                    .communicator
                    .sum(grid.par_sum(block, |index, point| {
                        weight(point) * (velocity[index] + increment[index])
                    }))
                    / total;
                let response_mean = self
                    .ranks
                    .communicator
                    .sum(grid.par_sum(block, |index, point| weight(point) * response[index]))
                    / total;
                let forcing = (target - mean) / (alpha * dt * response_mean);
                let scale = alpha * dt * forcing;
                grid.par_update(block, increment, |index, value| {
                    value + scale * response[index]
                });
                self.flow_rate_gradient[component] -= alpha * forcing;
            }
            let velocity = &mut self.velocity[component];
            grid.par_update(
                &self.velocity_unknowns[component],
                velocity,
                |index, velocity| velocity + increment[index],
            );
        }
    }

    /// Removes the divergence of the current velocity (a projection that
    /// leaves the pressure alone): for an initial field that is not
    /// discretely divergence free.
    pub fn remove_divergence(&mut self) {
        self.project_with_scale(1.0);
    }

    /// Projects the velocity onto discretely divergence-free fields with
    /// the potential `φ` of `L φ = D u / scale`, `u −= scale G φ`; `φ` is
    /// left in `self.correction`. `scale` is `α_k Δt` in a stage.
    fn project_with_scale(&mut self, scale: f64) {
        self.fill_velocity_ghosts();
        let grid = &self.grid;
        let correction = &mut self.correction;
        divergence(grid, &self.velocity, correction);
        grid.par_update(&grid.cell_block(), correction, |_, value| value / scale);
        self.pressure_solver.solve_poisson(grid, correction);
        fill_ghosts_on(
            grid,
            correction,
            Location::Centre,
            &self.pressure_ends,
            Some(&self.ranks),
        );
        for component in 0..grid.dim() {
            let block = &self.velocity_unknowns[component];
            subtract_gradient(
                grid,
                correction,
                component,
                block,
                scale,
                &mut self.velocity[component],
            );
        }
        self.fill_velocity_ghosts();
    }

    /// Pressure after a stage's projection, `p += φ − ν scale/2 L φ`: the
    /// second term is the part of the Crank–Nicolson viscous term that the
    /// projection moved into `φ`.
    fn update_pressure(&mut self, scale: f64) {
        let grid = &self.grid;
        let cells = grid.cell_block();
        let pressure = &mut self.pressure;
        let correction = &self.correction;
        grid.par_update(&cells, pressure, |index, pressure| {
            pressure + correction[index]
        });
        if self.viscous_scheme == ViscousScheme::CrankNicolson {
            add_laplacian(
                grid,
                correction,
                Location::Centre,
                &cells,
                -0.5 * scale * self.viscosity,
                pressure,
            );
        }
    }

    /// Ghost values and wall-face values of every velocity component (one
    /// exchange per split axis for all of them).
    pub fn fill_velocity_ghosts(&mut self) {
        let mut fields = velocity_fields(&mut self.velocity, &self.velocity_ends);
        fill_ghosts_together(&self.grid, &mut fields, Some(&self.ranks));
    }

    /// This rank's share of the cells.
    pub fn partition(&self) -> &Partition {
        &self.ranks.partition
    }

    /// The ranks the flow is shared among.
    pub fn communicator(&self) -> &Communicator {
        &self.ranks.communicator
    }

    /// The unknown faces of velocity component `component` (padded indices).
    pub fn velocity_unknowns(&self, component: usize) -> &Block {
        &self.velocity_unknowns[component]
    }
}

/// The velocity components with their locations and end conditions, for
/// [`fill_ghosts_together`].
fn velocity_fields<'a>(
    velocity: &'a mut [Vec<f64>],
    ends: &'a [FieldEnds],
) -> Vec<GhostedField<'a>> {
    velocity
        .iter_mut()
        .zip(ends)
        .enumerate()
        .map(|(component, (values, ends))| GhostedField {
            values,
            location: Location::Face(component),
            ends,
        })
        .collect()
}
