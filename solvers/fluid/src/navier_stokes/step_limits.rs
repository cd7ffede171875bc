//! How long a step the flow allows: the viscous number of an explicit
//! step and the CFL number a step reaches, from the current velocity, the
//! speeds the boundaries impose and the forces no pressure balances.

use super::FlowSolver;

impl FlowSolver {
    /// `ν Δt Σ_a 4/h_a²`: the viscous number an explicit step must keep
    /// below [`EXPLICIT_VISCOUS_LIMIT`](super::EXPLICIT_VISCOUS_LIMIT).
    /// Along a stretched axis `4/h²` is replaced by the Gershgorin bound of
    /// its Laplacian, [`Grid::laplacian_bound`](crate::grid::Grid::laplacian_bound).
    pub fn viscous_number(&self, dt: f64) -> f64 {
        let grid = &self.grid;
        self.viscosity
            * dt
            * (0..grid.dim())
                .map(|axis| grid.laplacian_bound(axis))
                .sum::<f64>()
    }

    /// The largest step whose CFL number stays at most `cfl` for every
    /// velocity that can enter it ([`FlowSolver::cfl_bound`]); infinite only
    /// for a fluid at rest between walls at rest with no unbalanced force.
    pub fn time_step_for_cfl(&self, cfl: f64) -> f64 {
        let (speed_rate, acceleration_rate) = self.cfl_rates();
        time_step_for_cfl_rates(cfl, speed_rate, acceleration_rate)
    }

    /// An upper bound of the CFL number a step of `dt` reaches from the
    /// current state: `Σ_a (U_a + A_a Δt) Δt / h_a`, where `U_a` is the
    /// largest of the current `|u_a|` and of the speeds the boundaries
    /// impose ([`FlowSolver::boundary_speeds`]), and `A_a` the acceleration
    /// no pressure can balance ([`FlowSolver::unbalanced_acceleration`]).
    /// From rest, the current velocity alone would say zero: a lid or an
    /// inflow sets the fluid moving within the first stage.
    pub fn cfl_bound(&self, dt: f64) -> f64 {
        let (speed_rate, acceleration_rate) = self.cfl_rates();
        (speed_rate + acceleration_rate * dt) * dt
    }

    /// `(S, Σ_a A_a / h_a)` of [`FlowSolver::cfl_bound`]: `S` the largest
    /// of the current velocity's pointwise rate ([`FlowSolver::max_cfl`] at
    /// `Δt = 1`) and the boundaries' `Σ_a U_a / h_a`, with `h_a` the
    /// smallest control length along `a` where it is stretched.
    pub fn cfl_rates(&self) -> (f64, f64) {
        let grid = &self.grid;
        let (speeds, accelerations) = (self.boundary_speeds(), self.unbalanced_acceleration());
        let (mut boundary_rate, mut acceleration_rate) = (0.0, 0.0);
        for axis in 0..grid.dim() {
            let block = &self.velocity_unknowns[axis];
            let h = (block.start[axis]..block.end[axis])
                .map(|plane| grid.gap(axis, plane))
                .fold(f64::INFINITY, f64::min);
            boundary_rate += speeds[axis] / h;
            acceleration_rate += accelerations[axis] / h;
        }
        (self.max_cfl(1.0).max(boundary_rate), acceleration_rate)
    }

    /// The largest speed along each axis that the boundaries impose on the
    /// fluid: sliding walls, flow through porous walls, and a bulk velocity
    /// held along a periodic axis (m/s).
    pub fn boundary_speeds(&self) -> [f64; 3] {
        let mut speeds = self.bulk_velocity.map(|bulk| bulk.map_or(0.0, f64::abs));
        for face in self.boundaries.faces.iter().flatten() {
            if let crate::boundary::BoundaryCondition::MovingWall(velocity) = face {
                for (speed, v) in speeds.iter_mut().zip(velocity) {
                    *speed = speed.max(v.abs());
                }
            }
        }
        speeds
    }

    /// The body force and mean pressure gradient along the axes where no
    /// pressure field can balance them (m/s²): the periodic axes and the
    /// one with an outflow. Along an axis closed by walls a uniform force is
    /// the gradient of a pressure and moves nothing; a held bulk velocity
    /// cancels the mean of the force along its axis.
    pub fn unbalanced_acceleration(&self) -> [f64; 3] {
        let outflow_axis = self
            .boundaries
            .has_outflow(&self.grid)
            .then(|| self.grid.line_axis());
        [0, 1, 2].map(|axis| {
            let open = self.ranks.periodic[axis] || outflow_axis == Some(axis);
            if open && self.bulk_velocity[axis].is_none() {
                (self.body_force[axis] - self.mean_pressure_gradient[axis]).abs()
            } else {
                0.0
            }
        })
    }

    /// The CFL number of a step of `dt` at the current velocity, cell by
    /// cell: `Δt max_cells Σ_a |u_a|/w_a`, with `|u_a|` the larger of the
    /// cell's two faces normal to `a` and `w_a` its width, over every rank.
    /// This is the frozen-coefficient bound of the centred convective
    /// operator's spectrum, `|λ| Δt ≤ Δt Σ_a |u_a|/w_a` at each point,
    /// which RK3 keeps stable up to √3. Each component's largest value
    /// anywhere in the box, summed, would overstate it wherever the
    /// fastest flow along each axis is in a different place (the wake and
    /// the sides of a settling grain) and shorten the step for nothing.
    /// A NaN velocity gives an infinite number.
    pub fn max_cfl(&self, dt: f64) -> f64 {
        let grid = &self.grid;
        let dim = grid.dim();
        let (line, strides) = (grid.line_axis(), [0, 1, 2].map(|a| grid.stride(a)));
        let inverse_widths = [0, 1, 2].map(|a| 1.0 / grid.spacing[a]);
        let stretched = [0, 1, 2].map(|a| a == line && !grid.is_uniform(a));
        let velocity = &self.velocity;
        let largest = grid.par_max(&grid.cell_block(), |index, plane| {
            let mut rate = 0.0;
            for axis in 0..dim {
                let field = &velocity[axis];
                let speed = larger_magnitude(field[index], field[index - strides[axis]]);
                rate += speed
                    * if stretched[axis] {
                        1.0 / grid.width(axis, plane)
                    } else {
                        inverse_widths[axis]
                    };
            }
            // `max` passes over a NaN: make it the largest instead.
            if rate.is_nan() {
                f64::INFINITY
            } else {
                rate
            }
        });
        self.ranks.communicator.max(largest) * dt
    }
}

/// The largest `Δt` with `a Δt² + b Δt ≤ cfl` for the rates
/// `b = speed_rate` (1/s) and `a = acceleration_rate` (1/s²) of
/// [`FlowSolver::cfl_rates`]: the positive root, written so that `a = 0`
/// gives `cfl / b` exactly; infinite when both rates vanish.
pub fn time_step_for_cfl_rates(cfl: f64, speed_rate: f64, acceleration_rate: f64) -> f64 {
    2.0 * cfl / (speed_rate + (speed_rate * speed_rate + 4.0 * acceleration_rate * cfl).sqrt())
}

/// The larger of `|a|` and `|b|`, written so that a NaN in either is kept
/// (`f64::max` would pass over it): the speed of a cell from its two faces.
#[inline]
pub(crate) fn larger_magnitude(a: f64, b: f64) -> f64 {
    let (a, b) = (a.abs(), b.abs());
    0.5 * (a + b + (a - b).abs())
}
