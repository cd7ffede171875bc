//! The hydrodynamic load a stage hands each grain (Izard et al. 2014,
//! eq. 5–6): from the forcing's loads and the rate of change of the fluid's
//! momentum in the volume moving with the grain, with the buoyancy and the
//! virtual mass of the inner-fluid-momentum form, or the paper's rigid
//! inner fluid. Shared by the 3D and the (r, z) coupled steps.

use grainflow_core::Vec3;
use grainflow_dem::DemSystem;

use crate::coupled::{particle_volume, Coupling};
use crate::forcing::Loads;
use crate::layer_forcing::LayerForcing;

/// How the grains take their hydrodynamic loads.
#[derive(Clone, Copy, Debug)]
pub(crate) struct GrainLoad {
    pub coupling: Coupling,
    /// ρ (kg/m³).
    pub fluid_density: f64,
    /// `C_v` of the virtual mass.
    pub virtual_mass: f64,
    /// When the virtual mass's impulse is handed back.
    pub virtual_mass_return: VirtualMassReturn,
}

/// When the load hands back the impulse the grain's virtual mass
/// `C_v ρ V_p` took from it: the fluid the DEM moves with the grain is the
/// grid's, which answers a change of the grain's velocity as the forcing
/// makes the layer follow.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum VirtualMassReturn {
    /// `C_v ρ V_p Δu / h`, `Δu` the grain's velocity change over the
    /// previous stage: eq. 7 sets a share `α` of each face to the rigid
    /// motion at every stage, so the fluid answers within about a stage.
    NextStage,
    /// `C_v ρ d/dt ∫_{V_p(t)} u`, as the fluid in the grain's volume
    /// answers: a layer relaxed more slowly than eq. 7 (held, renewal)
    /// follows a change over several stages, and handing the impulse back
    /// at once pushed the grain ahead of its fluid (a bounce at St 225
    /// came back at 0.99 of the dry rebound; docs/validation.md, §10).
    AsTheFluidAnswers,
}

impl VirtualMassReturn {
    /// The form that matches how `layer` relaxes the layer.
    pub(crate) fn for_layer(layer: &LayerForcing) -> Self {
        match layer {
            LayerForcing::EveryStage => VirtualMassReturn::NextStage,
            LayerForcing::Held { .. } | LayerForcing::Renewal => {
                VirtualMassReturn::AsTheFluidAnswers
            }
        }
    }
}

/// What a stage measured on the grid for each owned grain, per unit
/// density: the forcing's loads, the rate of change of the inner momentum
/// over the volume moving with the grain, and (with a body force on the
/// fluid) the grain's volume on the faces of each component.
pub(crate) struct StageMeasures<'a> {
    pub forcing: &'a Loads,
    pub inner_rate: &'a Loads,
    pub grid_volumes: Option<&'a [Vec3]>,
}

/// `d/dt ∫_{V_p(t)} u`: over the stage where the particle stands,
/// `(I⁺ − I⁻)/h`, and the transport of its last move,
/// `(I⁻ − I⁺_prev)/h_prev`.
pub(crate) fn inner_momentum_rate(
    before: &Loads,
    after: &Loads,
    moved_from: &Loads,
    moved_over: f64,
    stage_dt: f64,
) -> Loads {
    let rate = |after: &[Vec3], before: &[Vec3], from: &[Vec3]| -> Vec<Vec3> {
        (0..before.len())
            .map(|k| (after[k] - before[k]) / stage_dt + (before[k] - from[k]) / moved_over)
            .collect()
    };
    Loads {
        force: rate(&after.force, &before.force, &moved_from.force),
        torque: rate(&after.torque, &before.torque, &moved_from.torque),
    }
}

/// The load (N, N m) the DEM holds fixed over a stage of length
/// `stage_dt` on each owned grain of `dem`, from what the stage measured
/// (per unit density), plus the buoyancy in the form that needs it; the
/// DEM adds gravity `m_p g`. `body_force` is the fluid's body force b
/// (gravity along periodic axes).
pub(crate) fn hydrodynamic_loads(
    dem: &DemSystem,
    grain_load: GrainLoad,
    body_force: Vec3,
    measured: &StageMeasures,
    stage_dt: f64,
) -> Loads {
    let rho = grain_load.fluid_density;
    let p = &dem.particles;
    let gravity = dem.domain.gravity;
    let dimension = dem.dimension();
    let n = p.n_owned;
    let (forcing, inner_rate) = (measured.forcing, measured.inner_rate);
    let mut loads = Loads {
        force: vec![Vec3::zeros(); n],
        torque: vec![Vec3::zeros(); n],
    };
    for k in 0..n {
        if p.inverse_mass[k] == 0.0 {
            continue;
        }
        let volume = particle_volume(dimension, p.radius[k]);
        match grain_load.coupling {
            Coupling::InnerFluidMomentum => {
                let carried = grain_load.virtual_mass * rho * volume;
                let handed_back = match grain_load.virtual_mass_return {
                    VirtualMassReturn::NextStage => {
                        carried * (p.velocity[k] - p.dem_start_velocity[k]) / stage_dt
                    }
                    VirtualMassReturn::AsTheFluidAnswers => {
                        grain_load.virtual_mass * rho * inner_rate.force[k]
                    }
                };
                // −ρ V g where the hydrostatic pressure balances
                // gravity; along the axes where the fluid carries it
                // as b, the body force the forcing handed over,
                // −ρ V_grid b, so that a grain moving with the fluid
                // feels none (eq. 3–6 with b in the fluid's momentum).
                let buoyancy = match measured.grid_volumes {
                    Some(grid_volume) => {
                        -rho * (volume * (gravity - body_force)
                            + grid_volume[k].component_mul(&body_force))
                    }
                    None => -rho * volume * gravity,
                };
                loads.force[k] =
                    rho * (forcing.force[k] + inner_rate.force[k]) + buoyancy + handed_back;
                loads.torque[k] = rho * (forcing.torque[k] + inner_rate.torque[k]);
            }
            Coupling::RigidInnerFluid => {
                // Eq. 5–6: ρ ρ_p/(ρ_p − ρ) with ρ_p = m_p / V_p.
                let particle_density = p.mass[k] / volume;
                let factor = rho * particle_density / (particle_density - rho);
                loads.force[k] = factor * forcing.force[k];
                loads.torque[k] = factor * forcing.torque[k];
            }
        }
    }
    loads
}

/// Hands the DEM a stage's loads, and keeps with each owned grain its
/// velocity before the DEM and the inner momentum `after` the next stage
/// starts from (they travel with the particles).
pub(crate) fn set_stage_loads(dem: &mut DemSystem, loads: &Loads, after: &Loads) {
    dem.set_external_loads(&loads.force, &loads.torque);
    let p = &mut dem.particles;
    let n = p.n_owned;
    p.dem_start_velocity[..n].copy_from_slice(&p.velocity[..n]);
    p.inner_fluid_momentum[..n].copy_from_slice(&after.force);
    p.inner_fluid_angular_momentum[..n].copy_from_slice(&after.torque);
}
