//! What the coupled tests in a triply periodic box share: one sphere at
//! the centre of a cube of fluid.

use grainflow_core::{Communicator, Dimension, Domain, Vec3};
use grainflow_dem::particles::NewParticle;
use grainflow_dem::{ContactLaw, DemSystem, NormalCalibration, NormalStiffness};
use grainflow_fluid::{Boundaries, FlowSolver, Grid};
use grainflow_ibm::{CoupledSystem, Coupling};

/// A sphere of `diameter` in a triply periodic cube of 4 diameters on
/// `cells` cells a side, of kinematic viscosity `viscosity`: fluid and
/// sphere start drifting at `drift` along x, the sphere spinning at `spin`
/// rad/s about z, of density `density` (fluid 1000 kg/m³). No gravity.
pub struct PeriodicSphere {
    pub diameter: f64,
    pub cells: usize,
    pub viscosity: f64,
    pub density: f64,
    pub drift: f64,
    pub spin: f64,
}

pub const FLUID_DENSITY: f64 = 1000.0;

impl PeriodicSphere {
    pub fn build(&self, coupling: Coupling) -> CoupledSystem {
        let extent = [4.0 * self.diameter; 3];
        let grid = Grid::new(Dimension::Three, [self.cells; 3], [0.0; 3], extent);
        let mut flow = FlowSolver::new(
            grid,
            Boundaries::periodic(),
            self.viscosity,
            Communicator::serial(),
        )
        .unwrap();
        let drift = self.drift;
        flow.set_velocity(|component, _| if component == 0 { drift } else { 0.0 });
        let domain = Domain {
            dimension: Dimension::Three,
            lower: Vec3::zeros(),
            upper: Vec3::from(extent),
            periodic: [true; 3],
            gravity: Vec3::zeros(),
        };
        let law = ContactLaw {
            normal: NormalStiffness::from_restitution(0.9, 1e-3, NormalCalibration::Exact),
            tangential_ratio: 0.2,
            friction: 0.25,
            rolling_friction: 0.0,
        };
        let mut dem = DemSystem::new(domain, law, Vec::new(), 0.1 * self.diameter);
        dem.add_particles(&[NewParticle {
            position: Vec3::from(extent) * 0.5,
            velocity: Vec3::new(drift, 0.0, 0.0),
            angular_velocity: Vec3::new(0.0, 0.0, self.spin),
            radius: 0.5 * self.diameter,
            density: self.density,
            fixed: false,
        }]);
        CoupledSystem::new(flow, dem, FLUID_DENSITY, coupling, 1e-4)
    }
}
