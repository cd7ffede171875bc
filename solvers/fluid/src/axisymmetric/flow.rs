//! The time step of an axisymmetric flow without swirl, the same scheme as
//! the Cartesian one ([`crate::navier_stokes`]): Wray's low-storage RK3,
//! Crank–Nicolson viscous terms and a projection at every stage, with the
//! cylindrical operators of [`super::operators`] and [`super::radial`]:
//!
//! 1. `(I − α_k ν Δt/2 L) δu = Δt [γ_k N(u^{k−1}) + ζ_k N(u^{k−2}) − α_k G p^{k−1}
//!                                 + α_k ν L u^{k−1} + α_k f]`, `u* = u^{k−1} + δu`;
//! 2. `L φ = D u* / (α_k Δt)`, `u^k = u* − α_k Δt G φ`;
//! 3. `p^k = p^{k−1} + φ − α_k ν Δt/2 L φ`.
//!
//! `L` is the vector Laplacian without swirl: `∇²u_z` for `u_z`,
//! `∇²u_r − u_r/r²` for `u_r`. Every solve is direct ([`super::solver`]).

use crate::error::FluidError;
use crate::navier_stokes::{larger_magnitude, stage_fraction, StepReport, CFL_LIMIT, STAGES};
use crate::transform::AxisTransform;

use super::grid::RzGrid;
use super::operators::{add_axial_second_difference, convection, divergence, subtract_gradient};
use super::radial::{OuterClosure, RadialOperator};
use super::solver::RzDirectSolver;
use super::walls::{OuterWall, RzField, RzWalls};

const GAMMA: [f64; 3] = [8.0 / 15.0, 5.0 / 12.0, 3.0 / 4.0];
const ZETA: [f64; 3] = [0.0, -17.0 / 60.0, -5.0 / 12.0];

/// An incompressible axisymmetric flow in (r, z) and its time stepping.
pub struct AxisymmetricFlow {
    pub grid: RzGrid,
    pub walls: RzWalls,
    /// Kinematic viscosity ν (m²/s).
    pub viscosity: f64,
    /// Body acceleration along z (m/s²): gravity, or a mean pressure
    /// gradient driving a periodic pipe (`−(1/ρ) dp/dz`).
    pub body_force: f64,
    /// `u_r` on the radial faces (m/s), padded.
    pub radial: Vec<f64>,
    /// `u_z` on the axial faces (m/s), padded.
    pub axial: Vec<f64>,
    /// Kinematic pressure `p/ρ` at centres (m²/s²), zero volume mean.
    pub pressure: Vec<f64>,
    /// Simulated time (s).
    pub time: f64,
    /// A step whose CFL number at its start exceeds this is refused.
    pub cfl_limit: f64,
    radial_solver: RzDirectSolver,
    axial_solver: RzDirectSolver,
    pressure_solver: RzDirectSolver,
    /// The pressure's radial operator, for the Crank–Nicolson part of its update.
    pressure_radial: RadialOperator,
    tendency: [Vec<f64>; 2],
    previous_tendency: [Vec<f64>; 2],
    increment: [Vec<f64>; 2],
    correction: Vec<f64>,
    divergence: Vec<f64>,
}

impl AxisymmetricFlow {
    /// A fluid at rest on `grid` within `walls`.
    pub fn new(grid: RzGrid, walls: RzWalls, viscosity: f64) -> Result<Self, FluidError> {
        if !viscosity.is_finite() || viscosity <= 0.0 {
            return Err(FluidError::Parameter(format!(
                "the viscosity must be positive and finite, got {viscosity}"
            )));
        }
        let solver = |field: RzField, radial: RadialOperator, singular: bool| {
            let rows = walls.z_unknowns(&grid, field);
            let transform = AxisTransform::new(walls.z_transform(field), rows.len());
            RzDirectSolver::new(&grid, radial, rows, transform, singular)
        };
        let velocity_closure = match walls.outer {
            OuterWall::FreeSlip => OuterClosure::ZeroGradient,
            _ => OuterClosure::WallValue,
        };
        let pressure_radial = RadialOperator::centres(&grid, OuterClosure::ZeroGradient);
        let radial_solver = solver(RzField::Radial, RadialOperator::faces(&grid), false);
        let axial_solver = solver(
            RzField::Axial,
            RadialOperator::centres(&grid, velocity_closure),
            false,
        );
        let pressure_solver = solver(RzField::Pressure, pressure_radial.clone(), true);
        let zeros = grid.zeros();
        let mut flow = AxisymmetricFlow {
            walls,
            viscosity,
            body_force: 0.0,
            radial: zeros.clone(),
            axial: zeros.clone(),
            pressure: zeros.clone(),
            time: 0.0,
            cfl_limit: CFL_LIMIT,
            radial_solver,
            axial_solver,
            pressure_solver,
            pressure_radial,
            tendency: [zeros.clone(), zeros.clone()],
            previous_tendency: [zeros.clone(), zeros.clone()],
            increment: [zeros.clone(), zeros.clone()],
            correction: zeros.clone(),
            divergence: zeros,
            grid,
        };
        flow.fill_velocity_ghosts();
        Ok(flow)
    }

    /// Sets `u_r` from `radial(r, z)` and `u_z` from `axial(r, z)` on their
    /// unknowns (the boundary values stay the walls'). Follow with
    /// [`AxisymmetricFlow::remove_divergence`] unless the field is discretely
    /// divergence free.
    pub fn set_velocity(
        &mut self,
        radial: impl Fn(f64, f64) -> f64,
        axial: impl Fn(f64, f64) -> f64,
    ) {
        let grid = &self.grid;
        let [nr, nz] = grid.cells;
        for k in 1..=nz {
            for i in 1..nr {
                self.radial[grid.index(i, k)] = radial(grid.face(i), grid.z_centre(k));
            }
        }
        for k in self.walls.z_unknowns(grid, RzField::Axial) {
            for i in 1..=nr {
                self.axial[grid.index(i, k)] = axial(grid.centre(i), grid.z_face(k));
            }
        }
        self.fill_velocity_ghosts();
    }

    /// Advances the flow by `dt` and reports on it; refuses, leaving the
    /// flow as it was, a step whose CFL number exceeds the limit.
    pub fn step(&mut self, dt: f64) -> Result<StepReport, FluidError> {
        self.begin_step(dt)?;
        let mut max_divergence: f64 = 0.0;
        for stage in 0..STAGES {
            self.predict(stage, dt);
            max_divergence = max_divergence.max(self.project(stage, dt));
        }
        Ok(self.end_step(dt, max_divergence))
    }

    /// Checks the CFL number of a step of `dt` before its first stage.
    pub fn begin_step(&mut self, dt: f64) -> Result<(), FluidError> {
        let cfl = self.max_cfl(dt);
        if cfl > self.cfl_limit || cfl.is_nan() {
            return Err(FluidError::Unstable {
                cfl,
                limit: self.cfl_limit,
            });
        }
        Ok(())
    }

    /// Stage `stage`'s prediction (step 1): the predicted velocity is left
    /// in [`AxisymmetricFlow::radial`] and [`AxisymmetricFlow::axial`] for a
    /// forcing to act on before [`AxisymmetricFlow::project`].
    pub fn predict(&mut self, stage: usize, dt: f64) {
        let (gamma, zeta) = (GAMMA[stage], ZETA[stage]);
        let alpha = gamma + zeta;
        self.fill_velocity_ghosts();
        let grid = &self.grid;
        let [nr, nz] = grid.cells;
        self.walls.fill_centre_ghosts(grid, &mut self.pressure);
        let axial_rows = self.walls.z_unknowns(grid, RzField::Axial);
        let [tendency_r, tendency_z] = &mut self.tendency;
        convection(
            grid,
            &self.radial,
            &self.axial,
            axial_rows.clone(),
            tendency_r,
            tendency_z,
        );
        let viscous = alpha * dt * self.viscosity;
        for component in 0..2 {
            let (rows, radii) = match component {
                0 => (1..nz + 1, 1..nr),
                _ => (axial_rows.clone(), 1..nr + 1),
            };
            let force = if component == 0 { 0.0 } else { self.body_force };
            let rhs = &mut self.increment[component];
            rhs.iter_mut().for_each(|x| *x = 0.0);
            let (now, before) = (
                &self.tendency[component],
                &self.previous_tendency[component],
            );
            for k in rows.clone() {
                for i in radii.clone() {
                    let at = grid.index(i, k);
                    rhs[at] = dt * (gamma * now[at] + zeta * before[at] + alpha * force);
                }
            }
            let (velocity, solver, wall) = match component {
                0 => (&self.radial, &self.radial_solver, 0.0),
                _ => (&self.axial, &self.axial_solver, self.walls.outer_speed()),
            };
            solver
                .radial()
                .apply_add(grid, velocity, wall, viscous, rows.clone(), rhs);
            add_axial_second_difference(grid, velocity, viscous, radii, rows, rhs);
        }
        // −α Δt G p^{k−1}, both components at once.
        {
            let [rhs_r, rhs_z] = &mut self.increment;
            subtract_gradient(grid, &self.pressure, alpha * dt, axial_rows, rhs_r, rhs_z);
        }
        std::mem::swap(&mut self.tendency, &mut self.previous_tendency);
        let implicit = 0.5 * viscous;
        self.radial_solver
            .solve(grid, &mut self.increment[0], 1.0, -implicit);
        self.axial_solver
            .solve(grid, &mut self.increment[1], 1.0, -implicit);
        add_unknowns(
            grid,
            &self.radial_solver,
            &self.increment[0],
            &mut self.radial,
        );
        add_unknowns(
            grid,
            &self.axial_solver,
            &self.increment[1],
            &mut self.axial,
        );
        self.fill_velocity_ghosts();
    }

    /// Stage `stage`'s projection and pressure update (steps 2 and 3);
    /// returns the largest `|D u|` after it (1/s).
    pub fn project(&mut self, stage: usize, dt: f64) -> f64 {
        let scale = stage_fraction(stage) * dt;
        self.project_with_scale(scale);
        // p^k = p^{k−1} + φ − α ν Δt/2 L φ.
        let grid = &self.grid;
        let [nr, nz] = grid.cells;
        let implicit = -0.5 * scale * self.viscosity;
        for k in 1..=nz {
            for i in 1..=nr {
                let at = grid.index(i, k);
                self.pressure[at] += self.correction[at];
            }
        }
        self.pressure_radial.apply_add(
            grid,
            &self.correction,
            0.0,
            implicit,
            1..nz + 1,
            &mut self.pressure,
        );
        add_axial_second_difference(
            grid,
            &self.correction,
            implicit,
            1..nr + 1,
            1..nz + 1,
            &mut self.pressure,
        );
        self.walls.fill_centre_ghosts(grid, &mut self.pressure);
        self.max_divergence()
    }

    /// Closes a step of `dt`: advances the time and reports.
    pub fn end_step(&mut self, dt: f64, max_divergence: f64) -> StepReport {
        self.time += dt;
        StepReport {
            kinetic_energy: self.kinetic_energy(),
            max_cfl: self.max_cfl(dt),
            max_divergence,
        }
    }

    /// Removes the divergence of the current velocity, leaving the
    /// pressure alone.
    pub fn remove_divergence(&mut self) {
        self.project_with_scale(1.0);
    }

    /// `L φ = D u / scale`, `u −= scale G φ`; `φ` kept in `correction`.
    fn project_with_scale(&mut self, scale: f64) {
        self.fill_velocity_ghosts();
        let grid = &self.grid;
        divergence(grid, &self.radial, &self.axial, &mut self.divergence);
        let correction = &mut self.correction;
        correction.copy_from_slice(&self.divergence);
        correction.iter_mut().for_each(|x| *x /= scale);
        self.pressure_solver.solve(grid, correction, 0.0, 1.0);
        self.walls.fill_centre_ghosts(grid, correction);
        let rows = self.walls.z_unknowns(grid, RzField::Axial);
        subtract_gradient(
            grid,
            correction,
            scale,
            rows,
            &mut self.radial,
            &mut self.axial,
        );
        self.fill_velocity_ghosts();
    }

    /// Sets the ghosts of both velocity components.
    pub fn fill_velocity_ghosts(&mut self) {
        self.walls.fill_radial_ghosts(&self.grid, &mut self.radial);
        self.walls.fill_axial_ghosts(&self.grid, &mut self.axial);
    }

    /// The largest `|D u|` over the cells (1/s).
    pub fn max_divergence(&mut self) -> f64 {
        divergence(&self.grid, &self.radial, &self.axial, &mut self.divergence);
        let grid = &self.grid;
        let [nr, nz] = grid.cells;
        let mut largest: f64 = 0.0;
        for k in 1..=nz {
            for i in 1..=nr {
                largest = largest.max(self.divergence[grid.index(i, k)].abs());
            }
        }
        largest
    }

    /// `½ ∫ |u|² dV` over the cylinder (m⁵/s² per unit density), each
    /// component weighed by its face's control ring.
    pub fn kinetic_energy(&self) -> f64 {
        let grid = &self.grid;
        let [nr, nz] = grid.cells;
        let volume = 2.0 * std::f64::consts::PI * grid.dz;
        let mut energy = 0.0;
        for k in 1..=nz {
            for i in 1..nr {
                let ring = 0.5 * (grid.centre(i) + grid.centre(i + 1)) * grid.gap(i);
                energy += ring * self.radial[grid.index(i, k)].powi(2);
            }
        }
        for k in self.walls.z_unknowns(grid, RzField::Axial) {
            for i in 1..=nr {
                energy += grid.ring(i) * self.axial[grid.index(i, k)].powi(2);
            }
        }
        0.5 * volume * energy
    }

    /// The step at which the CFL number of the current velocity is `cfl`
    /// (infinite for a fluid at rest between walls at rest).
    pub fn time_step_for_cfl(&self, cfl: f64) -> f64 {
        cfl / self.max_cfl(1.0)
    }

    /// The CFL number of a step of `dt` at the current velocity, cell by
    /// cell: `Δt max_cells (|u_r|/w_i + |u_z|/h)`, each speed the larger of
    /// the cell's two faces, as in 3D
    /// ([`FlowSolver::max_cfl`](crate::FlowSolver::max_cfl)); a sliding
    /// outer wall's speed over `h` if larger. NaN for a velocity that is
    /// not finite, which the CFL check refuses.
    pub fn max_cfl(&self, dt: f64) -> f64 {
        let grid = &self.grid;
        let [nr, nz] = grid.cells;
        let mut largest: f64 = 0.0;
        let mut finite = true;
        for k in 1..=nz {
            for i in 1..=nr {
                let (index, below) = (grid.index(i, k), grid.index(i, k - 1));
                let rate = larger_magnitude(self.radial[index], self.radial[index - 1])
                    / grid.width(i)
                    + larger_magnitude(self.axial[index], self.axial[below]) / grid.dz;
                finite &= rate.is_finite();
                largest = largest.max(rate);
            }
        }
        if !finite {
            return f64::NAN;
        }
        dt * largest.max(self.walls.outer_speed().abs() / grid.dz)
    }
}

/// `field += increment` on the unknowns of `solver`'s field.
fn add_unknowns(grid: &RzGrid, solver: &RzDirectSolver, increment: &[f64], field: &mut [f64]) {
    let radial = solver.radial();
    for k in solver.z_rows() {
        let start = grid.index(radial.first, k);
        for at in start..start + radial.len() {
            field[at] += increment[at];
        }
    }
}

impl AxisymmetricFlow {
    /// Saves what the next step reads: the velocity and pressure with their
    /// ghosts and the time (the first stage takes no share of the previous
    /// tendency, and the solvers are rebuilt from the case).
    pub fn save_state(&self, state: &mut grainflow_core::State) {
        state.put_f64s("rz_flow.radial", &self.radial);
        state.put_f64s("rz_flow.axial", &self.axial);
        state.put_f64s("rz_flow.pressure", &self.pressure);
        state.put_f64("rz_flow.time", self.time);
        state.put_usizes("rz_flow.cells", &self.grid.cells);
    }

    /// Takes back what [`AxisymmetricFlow::save_state`] saved, into a flow
    /// built from the same case.
    pub fn restore_state(
        &mut self,
        state: &mut grainflow_core::State,
    ) -> Result<(), grainflow_core::StateError> {
        let len = self.grid.len();
        self.radial = state.take_f64s_of_len("rz_flow.radial", len)?;
        self.axial = state.take_f64s_of_len("rz_flow.axial", len)?;
        self.pressure = state.take_f64s_of_len("rz_flow.pressure", len)?;
        self.time = state.take_f64("rz_flow.time")?;
        if state.take_usizes("rz_flow.cells")?[..] != self.grid.cells {
            return Err(grainflow_core::StateError(
                "the saved (r, z) flow has another number of cells".into(),
            ));
        }
        Ok(())
    }
}
