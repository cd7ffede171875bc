//! Fluid scene assembly: turns the `[fluid]` table of a validated [`Case`]
//! into a [`FlowSolver`], and the exact solutions its analyses compare with.
//!
//! The solver works with the kinematic pressure p/ρ and viscosity ν = μ/ρ;
//! the case speaks in Pa, Pa/m and Pa s, converted here once.

use crate::case::{AnalysisSection, Case, InitialFlowSection};
use grainflow_core::{Communicator, Dimension};
use grainflow_fluid::{
    clustered_faces, flow_process_grid, Boundaries, BoundaryCondition, Clustering, FlowSolver,
    Grid, TransformBackend, ViscousScheme,
};
use std::f64::consts::PI;

fn axis_values(values: &[f64]) -> [f64; 3] {
    let mut out = [0.0; 3];
    out[..values.len().min(3)].copy_from_slice(&values[..values.len().min(3)]);
    out
}

/// The grid of a validated case.
pub fn grid(case: &Case) -> Grid {
    try_grid(case).expect("validated stretching")
}

/// The grid of the `[fluid]` table, uniform or stretched along its last
/// axis; the reason if the stretching's faces do not make a grid.
pub fn try_grid(case: &Case) -> Result<Grid, String> {
    let f = case.fluid_section();
    let dimension = if case.dimension() == 2 {
        Dimension::Two
    } else {
        Dimension::Three
    };
    let mut cells = [1; 3];
    cells[..f.cells.len()].copy_from_slice(&f.cells);
    let lower = axis_values(&case.domain.lower);
    let mut upper = axis_values(&case.domain.upper);
    if dimension == Dimension::Two {
        upper[2] = 1.0;
    }
    let Some(stretching) = &f.stretching else {
        return Ok(Grid::new(dimension, cells, lower, upper));
    };
    let line = case.dimension() - 1;
    let faces = match (&stretching.faces, &stretching.cluster, stretching.factor) {
        (Some(faces), _, _) => faces.clone(),
        (None, Some(cluster), Some(factor)) => {
            let clustering = match cluster.as_str() {
                "both_walls" => Clustering::BothEnds,
                "lower_wall" => Clustering::Lower,
                "upper_wall" => Clustering::Upper,
                other => return Err(format!("unknown cluster {other}")),
            };
            clustered_faces(clustering, factor, cells[line], lower[line], upper[line])
        }
        _ => return Err("give cluster and factor, or faces".to_string()),
    };
    Grid::stretched(dimension, cells, lower, upper, &faces).map_err(|e| e.to_string())
}

pub fn boundaries(case: &Case) -> Boundaries {
    let f = case.fluid_section();
    let mut boundaries = Boundaries::periodic();
    for axis in 0..case.dimension() {
        let Some(faces) = f.boundary.faces(axis) else {
            continue;
        };
        let condition = |side: usize| match faces[side].as_str() {
            "periodic" => BoundaryCondition::Periodic,
            "no_slip" => BoundaryCondition::NoSlip,
            "free_slip" => BoundaryCondition::FreeSlip,
            "outflow" => BoundaryCondition::Outflow,
            "moving" => BoundaryCondition::MovingWall(axis_values(
                f.boundary.velocity(axis, side).expect("validated"),
            )),
            other => unreachable!("validated face kind {other}"),
        };
        boundaries = boundaries.with(axis, condition(0), condition(1));
    }
    boundaries
}

/// The transforms a case asks for (`fluid.transforms`), or the build's default.
pub fn transform_backend(case: &Case) -> TransformBackend {
    match case.fluid_section().transforms.as_deref() {
        Some("rust") => TransformBackend::Rust,
        Some("fftw") => TransformBackend::Fftw,
        _ => TransformBackend::preferred(),
    }
}

/// The flow of the scene at t = 0.
pub fn build(case: &Case) -> Result<FlowSolver, String> {
    build_on(case, Communicator::serial())
}

/// The flow's process grid on `size` ranks: `parallel.process_grid` if
/// given (and more than one rank runs), else the split of x and y with the
/// least area of cuts.
pub fn process_grid_of(case: &Case, grid: &Grid, size: usize) -> Result<[usize; 3], String> {
    match case
        .parallel
        .as_ref()
        .and_then(|p| p.ranks())
        .filter(|_| size > 1)
    {
        Some(ranks) => Ok(ranks),
        None => flow_process_grid(grid, size).map_err(|e| format!("fluid: {e}")),
    }
}

/// [`build`] shared among the ranks of `communicator`: the process grid of
/// `parallel.process_grid`, else the one with the least area of cuts.
pub fn build_on(case: &Case, communicator: Communicator) -> Result<FlowSolver, String> {
    let f = case.fluid_section();
    let grid = grid(case);
    let ranks = process_grid_of(case, &grid, communicator.size())?;
    let shared_memory = case.parallel.as_ref().is_none_or(|p| p.shared_memory);
    let mut solver = FlowSolver::distributed(
        grid,
        boundaries(case),
        f.viscosity / f.density,
        communicator.with_shared_memory(shared_memory),
        ranks,
        transform_backend(case),
    )
    .map_err(|e| format!("fluid: {e}; parallel.process_grid: {ranks:?}"))?;
    if f.viscous == "explicit" {
        solver.viscous_scheme = ViscousScheme::Explicit;
    }
    solver.bulk_velocity = [0, 1, 2].map(|axis| f.bulk_velocity.along(axis));
    solver.body_force = axis_values(&case.domain.gravity);
    let gradient = axis_values(&f.pressure_gradient);
    solver.mean_pressure_gradient = gradient.map(|g| g / f.density);
    match &f.initial {
        InitialFlowSection::Rest => {}
        InitialFlowSection::Uniform { velocity } => {
            let velocity = axis_values(velocity);
            solver.set_velocity(|component, _| velocity[component]);
        }
        InitialFlowSection::TaylorGreen { .. } | InitialFlowSection::Beltrami { .. } => {
            let exact = ExactFlow::of(case).expect("an exact initial flow");
            solver.set_velocity(|component, x| exact.velocity(component, x, 0.0));
            solver.set_pressure(|x| exact.kinematic_pressure(x, 0.0));
        }
    }
    // A sampled field is divergence free only up to truncation error, and
    // walls may contradict it: start from its discrete projection.
    solver.remove_divergence();
    Ok(solver)
}

/// An exact unsteady solution of the Navier–Stokes equations.
#[derive(Clone, Copy, Debug)]
pub enum ExactFlow {
    /// u = S + U (sin kX cos kY, −cos kX sin kY, 0) e^{−2νk²t} with
    /// X = x − x0 − S_x t, Y = y − y0 − S_y t;
    /// p/ρ = U²/4 (cos 2kX + cos 2kY) e^{−4νk²t}.
    TaylorGreen {
        amplitude: f64,
        stream: [f64; 3],
        wavenumber: f64,
        origin: [f64; 3],
        viscosity: f64,
    },
    /// u = U (sin kZ + cos kY, sin kX + cos kZ, sin kY + cos kX) e^{−νk²t}
    /// (X = x − x0, ...); p/ρ = −|u|²/2.
    Beltrami {
        amplitude: f64,
        wavenumber: f64,
        origin: [f64; 3],
        viscosity: f64,
    },
}

impl ExactFlow {
    /// The exact solution the case's initial flow follows, if any.
    pub fn of(case: &Case) -> Option<ExactFlow> {
        let f = case.fluid_section();
        let origin = axis_values(&case.domain.lower);
        let wavenumber = 2.0 * PI / (case.domain.upper[0] - case.domain.lower[0]);
        let viscosity = f.viscosity / f.density;
        match &f.initial {
            InitialFlowSection::TaylorGreen { velocity, stream } => Some(ExactFlow::TaylorGreen {
                amplitude: *velocity,
                stream: axis_values(stream),
                wavenumber,
                origin,
                viscosity,
            }),
            InitialFlowSection::Beltrami { velocity } => Some(ExactFlow::Beltrami {
                amplitude: *velocity,
                wavenumber,
                origin,
                viscosity,
            }),
            _ => None,
        }
    }

    pub fn velocity(&self, component: usize, x: [f64; 3], time: f64) -> f64 {
        match *self {
            ExactFlow::TaylorGreen {
                amplitude,
                stream,
                wavenumber: k,
                origin,
                viscosity,
            } => {
                let [along_x, along_y] = carried_phases(k, origin, stream, x, time);
                let decay = amplitude * (-2.0 * viscosity * k * k * time).exp();
                stream[component]
                    + match component {
                        0 => along_x.sin() * along_y.cos() * decay,
                        1 => -along_x.cos() * along_y.sin() * decay,
                        _ => 0.0,
                    }
            }
            ExactFlow::Beltrami {
                amplitude,
                wavenumber: k,
                origin,
                viscosity,
            } => {
                let [a, b, c] = [0, 1, 2].map(|axis| k * (x[axis] - origin[axis]));
                let decay = amplitude * (-viscosity * k * k * time).exp();
                decay
                    * match component {
                        0 => c.sin() + b.cos(),
                        1 => a.sin() + c.cos(),
                        _ => b.sin() + a.cos(),
                    }
            }
        }
    }

    pub fn kinematic_pressure(&self, x: [f64; 3], time: f64) -> f64 {
        match *self {
            ExactFlow::TaylorGreen {
                amplitude,
                stream,
                wavenumber: k,
                origin,
                viscosity,
            } => {
                let [along_x, along_y] = carried_phases(k, origin, stream, x, time);
                0.25 * amplitude
                    * amplitude
                    * ((2.0 * along_x).cos() + (2.0 * along_y).cos())
                    * (-4.0 * viscosity * k * k * time).exp()
            }
            ExactFlow::Beltrami { .. } => {
                let speed_sq: f64 = (0..3).map(|c| self.velocity(c, x, time).powi(2)).sum();
                -0.5 * speed_sq
            }
        }
    }
}

/// kX and kY of the Taylor–Green vortex, X = x − x0 − S_x t (the vortex
/// carried by the stream S).
fn carried_phases(k: f64, origin: [f64; 3], stream: [f64; 3], x: [f64; 3], time: f64) -> [f64; 2] {
    [0, 1].map(|axis| k * (x[axis] - origin[axis] - stream[axis] * time))
}

/// The Poiseuille–Couette profile between the walls of the last axis:
/// ν u_c'' = ∂p/∂x_c / ρ − g_c for each streamwise component c, with the
/// wall velocities as end values (second-order central differences are
/// exact for this parabola on a uniform grid, so the discrete steady state
/// matches it; on a stretched one it converges at second order).
///
/// A flow that starts from rest under a pressure gradient (not a held bulk
/// velocity) follows it through the start-up: with η = (y − y₀)/H and
/// `b_n` the sine coefficients of the steady profile `u_s`,
/// `u(y, t) = u_s(y) − Σ_n b_n sin(nπη) e^{−n²π²νt/H²}`, where for the
/// line `U₀(1 − η) + U₁ η` between the wall velocities
/// `b_n = 2 (U₀ − (−1)ⁿ U₁) / (nπ)` and for the parabola
/// `(K/2)(y − y₀)(y − y₀ − H)` `b_n = −2 K H² (1 − (−1)ⁿ) / (nπ)³`: a wall set
/// sliding under fluid at rest grows a boundary layer of thickness √(νt).
///
/// Walls that fluid crosses at V (blowing in through one, suction out
/// through the other) carry the flow across the channel: the wall-normal
/// velocity is V everywhere and the steady profile solves
/// `u'' − (V/ν) u' = K`: `u = U₀ + (U₁ − U₀ + K H ν/V) (e^{Vs/ν} − 1)/(e^{VH/ν} − 1)
/// − K s ν/V`, s = y − y₀ (the asymptotic suction profile when K = 0); it is
/// compared at the end, without a start-up.
///
/// With an outflow as the upper face (zero gradient, u'(H) = 0) the steady
/// profile is `u = U₀ + (K/a²)(e^{a(s − H)} − e^{−aH}) − K s/a`, a = V/ν,
/// under an inflow V through the lower wall, and the half parabola
/// `U₀ + (K/2) s (s − 2H)` without one.
pub struct ChannelProfile {
    pub wall_axis: usize,
    lower: f64,
    height: f64,
    /// u_c'' = ∂p/∂x_c / (ρ ν) − g_c / ν, or set by a held bulk velocity.
    pub curvature: [f64; 3],
    wall_velocity: [[f64; 3]; 2],
    /// ν, when the flow follows the start-up from rest (none: steady only).
    start_up_viscosity: Option<f64>,
    /// V/ν of a flow through the walls (1/m), zero without one.
    through_flow: f64,
    /// Whether the upper face is an outflow.
    outflow: bool,
}

impl ChannelProfile {
    pub fn of(case: &Case) -> Option<ChannelProfile> {
        if !matches!(case.analysis, Some(AnalysisSection::Channel)) {
            return None;
        }
        let f = case.fluid_section();
        let wall_axis = case.dimension() - 1;
        let viscosity = f.viscosity / f.density;
        let gradient = axis_values(&f.pressure_gradient);
        let gravity = axis_values(&case.domain.gravity);
        let wall_velocity = [0, 1].map(|side| {
            f.boundary
                .velocity(wall_axis, side)
                .map_or([0.0; 3], |v| axis_values(v))
        });
        let height = case.domain.upper[wall_axis] - case.domain.lower[wall_axis];
        // Σ w³ / H over the cells across the channel: h² when uniform.
        let grid = grid(case);
        let midpoint_defect = grid
            .interior(wall_axis)
            .map(|i| grid.width(wall_axis, i).powi(3))
            .sum::<f64>()
            / height;
        let curvature = [0, 1, 2].map(|c| match f.bulk_velocity.along(c) {
            // The held bulk velocity is the mean over the cells (midpoint
            // rule), which for this parabola is the exact mean minus
            // K Σ w³ / (24 H): (U_lower + U_upper)/2 − K H²/12 − K h²/24 = U_b
            // on a uniform grid.
            Some(bulk) => {
                (0.5 * (wall_velocity[0][c] + wall_velocity[1][c]) - bulk)
                    / (height * height / 12.0 + midpoint_defect / 24.0)
            }
            None => (gradient[c] / f.density - gravity[c]) / viscosity,
        });
        let through_flow = wall_velocity[0][wall_axis] / viscosity;
        let outflow = f
            .boundary
            .faces(wall_axis)
            .is_some_and(|faces| faces[1] == "outflow");
        let from_rest = matches!(f.initial, InitialFlowSection::Rest)
            && (0..3).all(|c| f.bulk_velocity.along(c).is_none())
            && through_flow == 0.0
            && !outflow;
        Some(ChannelProfile {
            wall_axis,
            lower: case.domain.lower[wall_axis],
            height,
            curvature,
            wall_velocity,
            start_up_viscosity: from_rest.then_some(viscosity),
            through_flow,
            outflow,
        })
    }

    /// Velocity component `component` at height `y` above the lower wall's
    /// coordinate origin, at time `time` (the steady profile unless the
    /// flow started from rest).
    pub fn velocity(&self, component: usize, y: f64, time: f64) -> f64 {
        if component == self.wall_axis {
            return self.wall_velocity[0][component];
        }
        let eta = (y - self.lower) / self.height;
        let [lower, upper] = self.wall_velocity.map(|v| v[component]);
        let curvature = self.curvature[component];
        let a = self.through_flow;
        if self.outflow {
            let (s, height) = (y - self.lower, self.height);
            return if a == 0.0 {
                lower + 0.5 * curvature * s * (s - 2.0 * height)
            } else {
                lower + curvature / (a * a) * ((a * (s - height)).exp() - (-a * height).exp())
                    - curvature * s / a
            };
        }
        if a != 0.0 {
            let (s, height) = (y - self.lower, self.height);
            // (e^{as} − 1)/(e^{aH} − 1) without overflow for large aH.
            let shape = if a > 0.0 {
                ((a * (s - height)).exp() - (-a * height).exp()) / (-(-a * height).exp_m1())
            } else {
                (a * s).exp_m1() / (a * height).exp_m1()
            };
            return lower + (upper - lower + curvature * height / a) * shape - curvature * s / a;
        }
        let steady = 0.5 * curvature * (y - self.lower) * (y - self.lower - self.height)
            + lower * (1.0 - eta)
            + upper * eta;
        let Some(viscosity) = self.start_up_viscosity else {
            return steady;
        };
        if time <= 0.0 {
            return 0.0;
        }
        // Terms until e^{−n²π²νt/H²} < 1e-18.
        let rate = PI * PI * viscosity * time / (self.height * self.height);
        let terms = ((41.5 / rate).sqrt().ceil() as usize).clamp(1, 200_000);
        let mut transient = 0.0;
        for n in 1..=terms {
            let n_pi = n as f64 * PI;
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            let coefficient = 2.0 * (lower - sign * upper) / n_pi
                - 2.0 * curvature * self.height * self.height * (1.0 - sign) / n_pi.powi(3);
            transient += coefficient * (n_pi * eta).sin() * (-rate * (n * n) as f64).exp();
        }
        steady - transient
    }
}
