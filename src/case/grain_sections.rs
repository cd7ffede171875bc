//! The tables of a case that describe the grains, their contacts, the
//! walls and the coupling with a fluid.

use grainflow_ibm::{Coupling, LayerForcing};
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticlesSection {
    /// Grain density [kg/m³].
    pub density: f64,
    /// Mean radius [m].
    pub radius: f64,
    /// Relative half-width of the uniform radius distribution (0.1 = ±10 %).
    #[serde(default)]
    pub radius_spread: f64,
    /// Seed of the random generator (placement, radii).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Ids of particles written to `tracked.csv`.
    #[serde(default)]
    pub tracked: Vec<u64>,
    /// Generators, applied in order; ids follow the order of creation.
    #[serde(default)]
    pub block: Vec<BlockSection>,
    /// Grains poured during the run, batch after batch, each released
    /// just above the deposit (dry scenes with soft contact).
    #[serde(default)]
    pub pour: Vec<PourSection>,
}

/// A pour: batches of grains on a jittered lattice, the first at t = 0 and
/// then every `interval`, each lifted along −gravity so that its lowest
/// grain is `gap` above the highest mobile grain. Grains land from a
/// small height whatever the height the deposit has reached, as in a
/// filling that follows the free surface.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PourSection {
    /// The batch's box at its lowest position (a batch is never placed
    /// below it).
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// Lattice spacing of a batch [m].
    pub spacing: f64,
    /// Random displacement as a fraction of each site's free room.
    #[serde(default)]
    pub jitter: f64,
    /// Grains to pour in all (the last batch keeps its lowest sites).
    pub count: usize,
    /// Time between two batches [s].
    pub interval: f64,
    /// Gap between the highest mobile grain and a new batch [m].
    #[serde(default)]
    pub gap: f64,
    /// A batch also waits until the rms speed of the previous batch's
    /// grains is below this [m/s] (it has landed); no wait if absent.
    #[serde(default)]
    pub settled_speed: Option<f64>,
    #[serde(default)]
    pub velocity: Vec<f64>,
}

fn default_seed() -> u64 {
    1
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum BlockSection {
    /// Simple cubic (square) lattice filling a box.
    Lattice {
        lower: Vec<f64>,
        upper: Vec<f64>,
        /// Lattice spacing [m].
        spacing: f64,
        /// Spacing between layers along the last axis (y in 2D, z in 3D)
        /// [m]; default `spacing`. Sparse layers rain down one after the
        /// other, like a poured fill.
        #[serde(default)]
        layer_spacing: Option<f64>,
        /// Random displacement as a fraction of each site's free room.
        #[serde(default)]
        jitter: f64,
        #[serde(default)]
        fixed: bool,
        #[serde(default)]
        velocity: Vec<f64>,
    },
    /// Random non-overlapping placement (a sedimentation starts from it).
    Random {
        lower: Vec<f64>,
        upper: Vec<f64>,
        count: usize,
        #[serde(default)]
        fixed: bool,
        #[serde(default)]
        velocity: Vec<f64>,
    },
    /// Particles given one by one.
    Explicit {
        positions: Vec<Vec<f64>>,
        #[serde(default)]
        velocities: Vec<Vec<f64>>,
        #[serde(default)]
        angular_velocities: Vec<Vec<f64>>,
        #[serde(default)]
        radii: Vec<f64>,
        #[serde(default)]
        fixed: bool,
    },
    /// Particles read from a CSV file with the header `x,y,z,radius`
    /// (2D: `x,y,radius`), optionally followed by velocity columns
    /// `vx,vy[,vz]` and a `group` column. A relative path is relative to
    /// the case file.
    File {
        path: String,
        #[serde(default)]
        fixed: bool,
        /// Groups of the file whose grains are glued where they lie (an
        /// erodible layer made a rigid bed of its own roughness).
        #[serde(default)]
        fixed_groups: Vec<u64>,
    },
    /// Independent binary collisions, one pair per impact parameter
    /// Ψ1 = v_t / v_n from 0 to `psi_max`: particle 2k moves towards the
    /// resting particle 2k + 1 with normal speed `impact_speed`.
    CollisionPairs {
        count: usize,
        impact_speed: f64,
        psi_max: f64,
        /// Initial gap between the surfaces of a pair [m].
        #[serde(default)]
        gap: f64,
    },
}

/// How grains touch (`contact.model`). The rest of a case is the same for
/// the three.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactModel {
    /// The soft-sphere DEM of Izard et al. 2014: "soft".
    Soft,
    /// Hard contact by convex optimization contact dynamics, one conic
    /// program per step (Martin et al. 2022): "cocd".
    Cocd,
    /// Hard contact by non-smooth contact dynamics, Gauss–Seidel over the
    /// contacts (Martin et al. 2022): "nscd".
    Nscd,
}

impl ContactModel {
    /// The name a case file gives it.
    pub fn name(self) -> &'static str {
        match self {
            ContactModel::Soft => "soft",
            ContactModel::Cocd => "cocd",
            ContactModel::Nscd => "nscd",
        }
    }

    /// Whether grains are hard (no overlap, no contact time).
    pub fn is_hard(self) -> bool {
        self != ContactModel::Soft
    }
}

impl std::fmt::Display for ContactModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSection {
    /// "soft", "cocd" or "nscd" ([`ContactModel`]).
    pub model: ContactModel,
    /// Normal restitution e_n (soft: with contact_time; nscd: Newton's
    /// restitution, default 0; cocd is inelastic).
    #[serde(default)]
    pub restitution: Option<f64>,
    /// Soft: contact time t_c [s] (eq. 17–18) ...
    #[serde(default)]
    pub contact_time: Option<f64>,
    /// ... turned into k_n, γ_n by "exact" (restitution exactly e_n with the
    /// no-attraction clamp, the default) or "paper" (eq. 17–18 as printed).
    #[serde(default)]
    pub calibration: Option<String>,
    /// Soft: or the same k_n [N/m] and γ_n [N s/m] for every pair.
    #[serde(default)]
    pub stiffness: Option<f64>,
    #[serde(default)]
    pub damping: Option<f64>,
    /// Soft: k_t / k_n (default 0.2).
    #[serde(default)]
    pub tangential_ratio: Option<f64>,
    /// Coulomb coefficient between particles.
    pub friction: f64,
    /// Soft: rolling resistance μ_r (torque μ_r R* F_n against rolling; 0: none).
    #[serde(default)]
    pub rolling_friction: f64,
    /// Coulomb coefficient with walls (default: `friction`).
    #[serde(default)]
    pub wall_friction: Option<f64>,
    /// Verlet skin [m] (default: 0.1 mean diameter).
    #[serde(default)]
    pub skin: Option<f64>,
    /// Hard: the solver tolerance ε (cocd: the interior point's relative
    /// gap and feasibility, default 1e-8; nscd: the residual of the contact
    /// law at which Gauss–Seidel stops, default 1e-6).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// Hard: interior-point iterations (default 200) or Gauss–Seidel
    /// sweeps (default 5000) allowed per step.
    #[serde(default)]
    pub max_iterations: Option<u32>,
    /// Hard: candidate threshold D [m]: pairs closer than this enter the
    /// step's problem (default 0.1 mean diameter; widened to what the
    /// fastest grain closes in a step).
    #[serde(default)]
    pub threshold: Option<f64>,
    /// cocd: "interior_point" (grainflow's, on the normal equations, 2D
    /// and 3D; the default), "clarabel" (the reference) or
    /// "projected_gradient" (grainflow's first-order solver of the dual,
    /// one rank).
    #[serde(default)]
    pub conic_solver: Option<String>,
    /// Hard: which listed pairs enter the step's program: "reachable"
    /// (those the step's motion can bring to their constraint, the others
    /// checked at the solution; the default) or "listed" (every pair
    /// within the threshold: the reference).
    #[serde(default)]
    pub candidates: Option<String>,
}

impl ContactSection {
    /// Whether the model is hard contact (cocd or nscd).
    pub fn is_hard(&self) -> bool {
        self.model.is_hard()
    }

    /// The COCD program's solver `conic_solver` names (validated:
    /// "interior_point", the default, "clarabel" or "projected_gradient").
    pub fn conic_solver(&self) -> grainflow_contact::ConicSolver {
        use grainflow_contact::ConicSolver;
        match self.conic_solver.as_deref() {
            Some("clarabel") => ConicSolver::Clarabel,
            Some("projected_gradient") => ConicSolver::ProjectedGradient,
            _ => ConicSolver::InteriorPoint,
        }
    }

    pub fn calibration(&self) -> &str {
        self.calibration.as_deref().unwrap_or("exact")
    }

    pub fn tangential_ratio(&self) -> f64 {
        self.tangential_ratio.unwrap_or(0.2)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallSection {
    #[serde(default)]
    pub name: Option<String>,
    /// A point of the plane [m].
    pub point: Vec<f64>,
    /// Normal pointing towards the particles (normalised on reading).
    pub normal: Vec<f64>,
    /// Coulomb coefficient (default: `contact.wall_friction`).
    #[serde(default)]
    pub friction: Option<f64>,
    /// Time [s] at which the wall is removed.
    #[serde(default)]
    pub remove_at: Option<f64>,
    /// A thin plate grains touch from either side (a gate between a
    /// column and an erodible layer); default: one-sided.
    #[serde(default)]
    pub two_sided: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingSection {
    /// "inner_fluid_momentum" (default: the rate of change of the fluid
    /// momentum inside each grain enters its load; any density ratio) or
    /// "rigid_inner_fluid" (eq. 5–6 of the paper; unstable as ρ_p/ρ → 1).
    #[serde(default)]
    pub formulation: FormulationName,
    /// Gap between surfaces, in fluid cells, at which grains start touching
    /// (each other or a wall); 0, the paper's choice, unless set.
    #[serde(default = "default_contact_gap")]
    pub contact_gap: f64,
    /// The step [s] at which the direct forcing relaxes each grain's
    /// transition layer as eq. 7 does; with it, the layer is relaxed at
    /// the same rate whatever the fluid step (`1 − (1 − α)^{Δt/forcing_step}`
    /// per stage), so a grain's apparent size does not change when the
    /// step does. Unset: eq. 7 at every step.
    #[serde(default)]
    pub forcing_step: Option<f64>,
    /// How fast the direct forcing relaxes each grain's transition layer:
    /// "every_stage" (default: eq. 7 at every stage, calibrated near a
    /// grain CFL number of 1) or "renewal" (at the rate the flow renews the
    /// layer, advection across a cell and diffusion across it: the grain
    /// the same at any step; `grainflow_ibm::layer_forcing`).
    #[serde(default)]
    pub layer_forcing: LayerForcingName,
    /// The first layer of fluid cells along the domain's walls: "forced"
    /// (default: the paper's forcing, which reaches the walls) or "free"
    /// (the moving grains do not force it; glued grains still do).
    #[serde(default)]
    pub wall_layer: WallLayerName,
}

/// `coupling.formulation` as the case names it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FormulationName {
    #[default]
    InnerFluidMomentum,
    RigidInnerFluid,
}

/// `coupling.wall_layer` as the case names it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WallLayerName {
    /// The paper's forcing, which reaches the walls (closer to Stokes
    /// flow for a grain sliding or rolling along a wall, and every bounce
    /// of the sweep at D/Δx = 8 in the experiments' band;
    /// docs/validation.md, §7).
    #[default]
    Forced,
    /// The moving grains leave the first cells along a wall to the fluid.
    Free,
}

/// `coupling.layer_forcing` as the case names it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LayerForcingName {
    #[default]
    EveryStage,
    Renewal,
}

impl CouplingSection {
    /// The load the section asks for.
    pub fn coupling(&self) -> Coupling {
        match self.formulation {
            FormulationName::InnerFluidMomentum => Coupling::InnerFluidMomentum,
            FormulationName::RigidInnerFluid => Coupling::RigidInnerFluid,
        }
    }

    /// The layer's forcing the section asks for: held at
    /// `coupling.forcing_step` where set (the case refuses it beside
    /// "renewal").
    pub fn layer_forcing(&self) -> LayerForcing {
        match (self.forcing_step, self.layer_forcing) {
            (Some(step), _) => LayerForcing::Held { step },
            (None, LayerForcingName::EveryStage) => LayerForcing::EveryStage,
            (None, LayerForcingName::Renewal) => LayerForcing::Renewal,
        }
    }
}

impl Default for CouplingSection {
    fn default() -> Self {
        CouplingSection {
            formulation: FormulationName::InnerFluidMomentum,
            contact_gap: default_contact_gap(),
            forcing_step: None,
            layer_forcing: LayerForcingName::EveryStage,
            wall_layer: WallLayerName::Forced,
        }
    }
}

fn default_contact_gap() -> f64 {
    0.0
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LubricationSection {
    /// Roughness length over the smaller radius of a pair, η/R (eq. 19).
    pub roughness: f64,
    /// Largest gap at which the force acts, over the smaller radius.
    #[serde(default = "default_lubrication_range")]
    pub range: f64,
}

fn default_lubrication_range() -> f64 {
    0.5
}
