//! How many steps a run of grains in a fluid adapted to `time.cfl` makes,
//! for `check`, which cannot run the flow to see. Each step is the one at
//! which the larger of the flow's CFL rate, `max_cells Σ_a |u_a|/w_a`, and
//! the fastest grain's speed over the cell size reaches the CFL number, at
//! most `time.dt` (`simulation::coupled::step_size`). `check` takes the
//! speed scales the scene is set up to reach:
//!
//! - grains settling from rest towards their Schiller–Naumann terminal
//!   velocity `U_t`, as `U_t tanh(a₀ t/U_t)` from the start of eq. 20,
//!   `a₀ = (ρ_p − ρ) g/(ρ_p + C_m ρ)`;
//! - a flow that a body force `A` drives along a periodic axis between the
//!   walls across it, above the grains' bed: its laminar start-up, whose
//!   fastest point reaches `A W²/(8ν)` between two walls `W` apart (`W` is
//!   twice the depth under a free-slip top) over the time `W²/ν`;
//!
//! and counts `N = ∫ max(1/Δt_max, K U(t)/(C h)) dt` to the end time, `U`
//! the larger of the two, `C` the CFL number, `h` the smallest cell. `K`,
//! the flow's CFL rate over the settling grain's `U/h`, is 1.28 in the
//! ten Cate run E4 at its plateau (steps of 8.6 ms at 0.114 m/s on cells of
//! 1.25 mm at CFL 1; 1.22 for the falling sphere at D/Δx = 24): the fastest
//! flow, beside the grain, is a little faster than the grain. The counts
//! against the steps the cases made: ten Cate 201 (149: the sphere stops on
//! the floor, and the step grows to its largest), the immersed avalanche
//! 8,376 (7,511: the bed's grains move slower than the film above them).
//! Each is an upper bound within a factor 2.

use grainflow_fluid::BoundaryCondition;
use grainflow_ibm::settling::{
    added_mass_coefficient, archimedes_number, schiller_naumann_reynolds,
};
use grainflow_ibm::{particle_volume, CoupledSystem};
use std::f64::consts::PI;

/// The flow's CFL rate, `max_cells Σ_a |u_a|/w_a`, over the settling
/// grain's speed over the cell size (measured on the ten Cate run).
pub const FLOW_RATE_OVER_GRAIN_RATE: f64 = 1.28;

/// Plane-averaged solid fraction above which a grain layer counts as the
/// bed the driven flow runs over.
pub const BED_FRACTION: f64 = 0.3;

/// How the walls across a driven flow hold it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Confinement {
    /// Two no-slip (or sliding) walls `width` apart.
    Channel { width: f64 },
    /// A no-slip wall under a free-slip one, `depth` apart: half a
    /// channel of twice the depth.
    Film { depth: f64 },
    /// No wall holds it back: it accelerates freely.
    Free,
}

/// A flow driven along a periodic axis by an acceleration no pressure
/// balances.
#[derive(Clone, Copy, Debug)]
pub struct DrivenFlow {
    pub acceleration: f64,
    pub confinement: Confinement,
    pub viscosity: f64,
}

impl DrivenFlow {
    /// The fastest speed of the laminar start-up from rest at time `t`:
    /// `A W²/(8ν) [1 − (32/π³) Σ_n (−1)ⁿ/(2n+1)³ exp(−(2n+1)² π² ν t/W²)]`
    /// at the centre of a channel of width `W`.
    pub fn fastest_speed(&self, t: f64) -> f64 {
        let width = match self.confinement {
            Confinement::Channel { width } => width,
            Confinement::Film { depth } => 2.0 * depth,
            Confinement::Free => return self.acceleration * t,
        };
        if t <= 0.0 {
            return 0.0; // the series converges slowest here
        }
        let nu = self.viscosity;
        let steady = self.acceleration * width * width / (8.0 * nu);
        let mut transient = 0.0;
        for n in 0..200 {
            let m = (2 * n + 1) as f64;
            let decay = (-(m * m) * PI * PI * nu * t / (width * width)).exp();
            let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
            transient += sign * decay / (m * m * m);
            if decay < 1e-17 {
                break;
            }
        }
        steady * (1.0 - 32.0 / PI.powi(3) * transient)
    }
}

/// A grain settling from rest.
#[derive(Clone, Copy, Debug, Default)]
pub struct Settling {
    /// Schiller–Naumann terminal velocity (m/s).
    pub terminal: f64,
    /// Acceleration from rest, eq. 20 (m/s²).
    pub initial_acceleration: f64,
}

impl Settling {
    /// A grain of density `rho_p` and diameter `diameter` in a fluid of
    /// density `rho` and viscosity `mu` under gravity `g`: its
    /// Schiller–Naumann terminal velocity and its acceleration from rest
    /// (eq. 20, added-mass coefficient `added_mass`).
    pub fn from_rest(
        rho: f64,
        rho_p: f64,
        mu: f64,
        diameter: f64,
        g: f64,
        added_mass: f64,
    ) -> Self {
        let archimedes = archimedes_number(rho, rho_p, mu, diameter, g);
        Settling {
            terminal: schiller_naumann_reynolds(archimedes) * mu / (rho * diameter),
            initial_acceleration: (rho_p - rho).abs() * g / (rho_p + added_mass * rho),
        }
    }

    /// `U_t tanh(a₀ t/U_t)`: the start of eq. 20 and the terminal plateau.
    pub fn speed(&self, t: f64) -> f64 {
        if self.terminal > 0.0 {
            self.terminal * (self.initial_acceleration * t / self.terminal).tanh()
        } else {
            0.0
        }
    }
}

/// The speed scales of a scene and its step limits.
pub struct SpeedScales {
    /// The grain with the fastest terminal velocity.
    pub settling: Settling,
    pub driven: Option<DrivenFlow>,
}

impl SpeedScales {
    /// The steps to `end` of a run whose steps are at most `largest` and
    /// adapted to `cfl` on cells of `cell`: the integral above, in 4,000
    /// slices.
    pub fn steps(&self, end: f64, largest: f64, cfl: f64, cell: f64) -> f64 {
        let slices = 4000;
        let width = end / slices as f64;
        (0..slices)
            .map(|i| {
                let t = (i as f64 + 0.5) * width;
                let driven = self.driven.map_or(0.0, |d| d.fastest_speed(t));
                let speed = self.settling.speed(t).max(driven);
                (1.0 / largest).max(FLOW_RATE_OVER_GRAIN_RATE * speed / (cfl * cell)) * width
            })
            .sum::<f64>()
            .ceil()
    }
}

/// The height of the grains' bed over the wall at `floor` along an axis
/// running from `lower` to `upper`: the farthest point from the floor
/// where the grains' solid fraction, averaged over the plane across, is at
/// least [`BED_FRACTION`] (0 without one). `grains` are (distance along
/// the axis, radius); `plane_area` the area of the plane across (its
/// length in 2D, where grains are discs).
pub fn bed_height(
    grains: &[(f64, f64)],
    lower: f64,
    upper: f64,
    plane_area: f64,
    three_d: bool,
) -> f64 {
    let smallest = grains.iter().map(|g| g.1).fold(f64::INFINITY, f64::min);
    if grains.is_empty() || !smallest.is_finite() {
        return 0.0;
    }
    // Slices a tenth of the smallest radius thick, the section of every
    // grain through each slice's middle.
    let thickness = 0.1 * smallest;
    let slices = ((upper - lower) / thickness).ceil() as usize;
    let mut section = vec![0.0; slices];
    for &(centre, radius) in grains {
        let first = (((centre - radius - lower) / thickness).floor().max(0.0)) as usize;
        let last = (((centre + radius - lower) / thickness).ceil() as usize).min(slices);
        for (slice, area) in section.iter_mut().enumerate().take(last).skip(first) {
            let offset = lower + (slice as f64 + 0.5) * thickness - centre;
            let half_chord_squared = radius * radius - offset * offset;
            if half_chord_squared > 0.0 {
                *area += if three_d {
                    PI * half_chord_squared
                } else {
                    2.0 * half_chord_squared.sqrt()
                };
            }
        }
    }
    section
        .iter()
        .rposition(|area| area / plane_area >= BED_FRACTION)
        .map_or(0.0, |slice| (slice + 1) as f64 * thickness)
}

/// The speed scales a coupled run adapted to `time.cfl` is set to reach
/// (above): its grains' fastest Schiller–Naumann terminal velocity
/// (gravity along the walled axes against their buoyant weight), and the
/// flow a body force drives along a periodic axis between the walls across
/// it, over the grains' bed.
pub fn speed_scales(system: &CoupledSystem) -> SpeedScales {
    let flow = &system.flow;
    let grid = &flow.grid;
    let dim = grid.dim();
    let dem = &system.dem;
    let p = &dem.particles;
    let rho = system.fluid_density;
    let mu = flow.viscosity * rho;
    let gravity = dem.domain.gravity;
    let added_mass = added_mass_coefficient(dem.dimension());
    let settling = (0..p.n_owned)
        .filter(|&k| !p.is_fixed(k))
        .map(|k| {
            let diameter = 2.0 * p.radius[k];
            let rho_p = p.mass[k] / particle_volume(dem.dimension(), p.radius[k]);
            Settling::from_rest(rho, rho_p, mu, diameter, gravity.norm(), added_mass)
        })
        .fold(Settling::default(), |a, b| {
            if b.terminal > a.terminal {
                b
            } else {
                a
            }
        });
    let acceleration = flow.unbalanced_acceleration();
    let driven_axis = (0..dim)
        .filter(|&a| acceleration[a] > 0.0)
        .max_by(|&a, &b| acceleration[a].total_cmp(&acceleration[b]));
    let driven = driven_axis.map(|axis| {
        let (lower, upper) = (dem.domain.lower, dem.domain.upper);
        // The walls across: the narrowest walled axis.
        let across = (0..dim)
            .filter(|&b| b != axis && !dem.domain.periodic[b])
            .min_by(|&a, &b| (upper[a] - lower[a]).total_cmp(&(upper[b] - lower[b])));
        let confinement = across.map_or(Confinement::Free, |b| {
            let walls = flow.boundaries.faces[b];
            let holds = |c: &BoundaryCondition| {
                matches!(
                    c,
                    BoundaryCondition::NoSlip | BoundaryCondition::MovingWall(_)
                )
            };
            // The bed lies on the wall gravity points to.
            let plane: f64 = (0..dim)
                .filter(|&c| c != b)
                .map(|c| upper[c] - lower[c])
                .product();
            let grains: Vec<(f64, f64)> = (0..p.n_owned)
                .map(|k| {
                    let along = p.position[k][b];
                    let from_floor = if gravity[b] <= 0.0 {
                        along - lower[b]
                    } else {
                        upper[b] - along
                    };
                    (from_floor, p.radius[k])
                })
                .collect();
            let bed = if gravity[b] == 0.0 {
                0.0
            } else {
                bed_height(&grains, 0.0, upper[b] - lower[b], plane, dim == 3)
            };
            let open = upper[b] - lower[b] - bed;
            match (holds(&walls[0]), holds(&walls[1])) {
                (true, true) => Confinement::Channel { width: open },
                (true, false) | (false, true) if walls.contains(&BoundaryCondition::FreeSlip) => {
                    Confinement::Film { depth: open }
                }
                _ => Confinement::Free,
            }
        });
        DrivenFlow {
            acceleration: acceleration[axis],
            confinement,
            viscosity: flow.viscosity,
        }
    });
    SpeedScales { settling, driven }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From rest the start-up accelerates freely (`A t`) until viscosity
    /// reaches the centre, then settles on the Poiseuille speed.
    #[test]
    fn a_driven_channel_starts_at_the_free_acceleration_and_ends_at_poiseuille() {
        let flow = DrivenFlow {
            acceleration: 2.0,
            confinement: Confinement::Channel { width: 0.1 },
            viscosity: 1e-3,
        };
        let early = 1e-3; // ν t / W² = 1e-4
        assert!((flow.fastest_speed(early) / (2.0 * early) - 1.0).abs() < 1e-6);
        let poiseuille = 2.0 * 0.01 / 8e-3;
        assert!((flow.fastest_speed(100.0) / poiseuille - 1.0).abs() < 1e-9);
        assert_eq!(flow.fastest_speed(0.0), 0.0);
        let film = DrivenFlow {
            confinement: Confinement::Film { depth: 0.05 },
            ..flow
        };
        assert_eq!(film.fastest_speed(3.0), flow.fastest_speed(3.0));
    }

    /// A simple cubic lattice of spheres filling the lower half of a box
    /// (solid fraction π/6 ≈ 0.52, above the bed's 0.3) stands as high as
    /// its top layer's tops.
    #[test]
    fn a_lattice_bed_is_as_high_as_its_top_layer() {
        let (radius, layers) = (0.5, 5);
        let grains: Vec<(f64, f64)> = (0..layers)
            .flat_map(|k| (0..16).map(move |_| (radius + k as f64, radius)))
            .collect();
        let height = bed_height(&grains, 0.0, 10.0, 16.0, true);
        // The section falls below 0.3 × 1 where π (R² − d²) < 0.3: d above
        // 0.39 R from the top layer's centre.
        let top = (layers - 1) as f64 + radius + (radius * radius - 0.3 / PI).sqrt();
        assert!(
            (height - top).abs() < 0.1 * radius,
            "{height} against {top}"
        );
        assert_eq!(bed_height(&[], 0.0, 1.0, 1.0, true), 0.0);
    }

    /// A grain settling from rest makes `K/(C h) ∫ U_t tanh(a₀ t/U_t) dt =
    /// K U_t/(C h) (T − (U_t/a₀) ln cosh(a₀ T/U_t))` steps, and never fewer
    /// than those of the largest step.
    #[test]
    fn a_settling_grain_steps_at_the_cfl_number_of_its_speed() {
        let settling = Settling {
            terminal: 0.1,
            initial_acceleration: 0.5,
        };
        let scales = SpeedScales {
            settling,
            driven: None,
        };
        let (end, cfl, cell): (f64, f64, f64) = (2.0, 0.5, 1e-3);
        let ramp: f64 = 0.1 / 0.5;
        let exact =
            FLOW_RATE_OVER_GRAIN_RATE * 0.1 / (cfl * cell) * ramp * (end / ramp).cosh().ln();
        let steps = scales.steps(end, 0.1, cfl, cell);
        assert!(
            (steps - exact).abs() <= 1.0 + 1e-6 * exact,
            "{steps} against {exact}"
        );
        assert_eq!(scales.steps(end, 1e-3, cfl, cell), 2000.0);
        assert!((settling.speed(100.0) - 0.1).abs() < 1e-15);
    }
}
