//! Case files: TOML in SI units, read once into typed structs.
//!
//! Every table denies unknown keys; [`Case::validate`] checks ranges and
//! consistency and names the key and what is allowed. Nothing below this
//! module reads TOML.

use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum CaseError {
    #[error("cannot read case file {path}: {source}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    #[error("case file {path}: {message}")]
    Parse { path: String, message: String },
    #[error("--set {assignment}: {message}")]
    Override { assignment: String, message: String },
    #[error("{key} = {value}: {allowed}")]
    Invalid {
        key: String,
        value: String,
        allowed: String,
    },
}

fn invalid(key: &str, value: impl std::fmt::Display, allowed: &str) -> CaseError {
    CaseError::Invalid {
        key: key.to_string(),
        value: value.to_string(),
        allowed: allowed.to_string(),
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    pub domain: DomainSection,
    /// The fluid (absent in a dry scene: no grid is allocated).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fluid: Option<FluidSection>,
    /// The grains and their contacts (absent in a fluid-only scene).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub particles: Option<ParticlesSection>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSection>,
    #[serde(default)]
    pub walls: Vec<WallSection>,
    /// How grains and fluid exchange momentum (a scene with both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coupling: Option<CouplingSection>,
    /// The film force between close grains (a scene with both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lubrication: Option<LubricationSection>,
    pub time: TimeSection,
    #[serde(default)]
    pub output: OutputSection,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub analysis: Option<AnalysisSection>,
    /// How the scene is shared among MPI ranks (default: the process grid
    /// with the least area of cuts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parallel: Option<ParallelSection>,
    /// When checkpoints are written (default: only when the run is told
    /// to stop, by a signal or `time.wall_limit`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checkpoint: Option<CheckpointSection>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParallelSection {
    /// Ranks along each axis; their product must be the number of ranks
    /// the run is started on (default: chosen by the run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub process_grid: Option<Vec<usize>>,
    /// Whether ranks on one node read one another's arrays directly in the
    /// flow's transposes (default true); false sends messages, as between
    /// nodes.
    #[serde(default = "default_true")]
    pub shared_memory: bool,
    /// Threads of each rank (`grainflow run --threads N` sets it; default:
    /// chosen from the scene's size, see `grainflow_dem::threads`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threads: Option<usize>,
}

impl ParallelSection {
    /// The process grid along x, y, z (1 along an axis the case omits), if
    /// the case sets one.
    pub fn ranks(&self) -> Option<[usize; 3]> {
        let grid = self.process_grid.as_ref()?;
        let mut ranks = [1; 3];
        ranks[..grid.len()].copy_from_slice(grid);
        Some(ranks)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DomainSection {
    /// 2 (discs in the x–y plane) or 3 (spheres).
    pub dimension: u8,
    /// Lower and upper corners [m], one value per dimension.
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
    /// Periodicity per axis (default: none).
    #[serde(default)]
    pub periodic: Vec<bool>,
    /// Gravity vector [m/s²] (default: none).
    #[serde(default)]
    pub gravity: Vec<f64>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidSection {
    /// Cells along each axis (one entry per axis).
    pub cells: Vec<usize>,
    /// Density ρ [kg/m³].
    pub density: f64,
    /// Dynamic viscosity μ [Pa s].
    pub viscosity: f64,
    /// Conditions on the faces of the domain.
    #[serde(default)]
    pub boundary: FluidBoundarySection,
    /// Imposed mean pressure gradient [Pa/m], one entry per axis (drives a
    /// periodic channel: a negative x entry pushes the flow towards +x).
    #[serde(default)]
    pub pressure_gradient: Vec<f64>,
    /// Bulk velocity held constant along periodic axes [m/s] (a constant
    /// flow rate, instead of a pressure gradient along that axis).
    #[serde(default)]
    pub bulk_velocity: BulkVelocitySection,
    /// Velocity field at t = 0.
    #[serde(default)]
    pub initial: InitialFlowSection,
    /// Viscous term: "crank_nicolson" (implicit, no stability limit) or
    /// "explicit" (no solve; ν Δt Σ 4/h² ≤ 8.61).
    #[serde(default = "default_viscous_scheme")]
    pub viscous: String,
    /// Cells clustered towards the walls of the last axis (z in 3D, y in
    /// 2D); uniform without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stretching: Option<StretchingSection>,
    /// Transforms of the direct solvers: "rust" (rustfft/rustdct) or
    /// "fftw" (a build with `--features fftw`); that build's default
    /// without it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transforms: Option<String>,
}

/// How the last axis is stretched: a tanh map clustering cells at one or
/// both walls (`cluster` and `factor`), or the face coordinates themselves.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StretchingSection {
    /// "both_walls", "lower_wall" or "upper_wall".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cluster: Option<String>,
    /// β of the map f(ξ) (see `grainflow_fluid::clustered_faces`): the
    /// clustered end cells are 2β / sinh 2β of the mean width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factor: Option<f64>,
    /// Face coordinates [m], `cells + 1` of them from the lower to the
    /// upper end of the axis, strictly increasing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub faces: Option<Vec<f64>>,
}

pub const CLUSTER_KINDS: &str = "\"both_walls\", \"lower_wall\" or \"upper_wall\"";

/// Largest tanh factor: at β = 12 the end cells are 1e-9 of the mean width.
pub const MAX_STRETCHING_FACTOR: f64 = 12.0;

fn default_viscous_scheme() -> String {
    "crank_nicolson".to_string()
}

/// Bulk velocity per periodic axis (the mean of that velocity component
/// over the grid's cells).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BulkVelocitySection {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
}

impl BulkVelocitySection {
    pub fn along(&self, axis: usize) -> Option<f64> {
        [self.x, self.y, self.z][axis]
    }
}

/// Face conditions per axis, `[lower, upper]`, each one of "periodic",
/// "no_slip", "free_slip" or "moving" (a wall sliding in its plane at
/// `<axis>_<side>_velocity`). An axis left out is periodic if the domain is.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FluidBoundarySection {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x_lower_velocity: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x_upper_velocity: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y_lower_velocity: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y_upper_velocity: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z_lower_velocity: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z_upper_velocity: Option<Vec<f64>>,
}

pub const FACE_KINDS: &str =
    "\"periodic\", \"no_slip\", \"free_slip\", \"moving\" or \"outflow\" (upper face of the last axis)";

impl FluidBoundarySection {
    /// The `[lower, upper]` face kinds given for `axis`.
    pub fn faces(&self, axis: usize) -> Option<&Vec<String>> {
        [&self.x, &self.y, &self.z][axis].as_ref()
    }

    /// The velocity of a moving face.
    pub fn velocity(&self, axis: usize, side: usize) -> Option<&Vec<f64>> {
        [
            [&self.x_lower_velocity, &self.x_upper_velocity],
            [&self.y_lower_velocity, &self.y_upper_velocity],
            [&self.z_lower_velocity, &self.z_upper_velocity],
        ][axis][side]
            .as_ref()
    }
}

/// The velocity at t = 0.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum InitialFlowSection {
    /// Fluid at rest.
    #[default]
    Rest,
    /// The same velocity everywhere [m/s].
    Uniform { velocity: Vec<f64> },
    /// The Taylor–Green vortex in the x–y plane, u = U sin(kx) cos(ky),
    /// v = −U cos(kx) sin(ky), k = 2π/L, carried by a uniform `stream`
    /// [m/s]; an exact solution of the Navier–Stokes equations (in 3D
    /// uniform along z) on a periodic square.
    TaylorGreen {
        /// Amplitude U [m/s].
        velocity: f64,
        #[serde(default)]
        stream: Vec<f64>,
    },
    /// The Arnold–Beltrami–Childress flow u = U (sin kz + cos ky,
    /// sin kx + cos kz, sin ky + cos kx): its vorticity is k u, so the
    /// convective term is a gradient and it decays as exp(−ν k² t), an
    /// exact 3D solution on a periodic cube.
    Beltrami { velocity: f64 },
}

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

/// The solid fraction at which random sequential addition of equal discs
/// (2D) and spheres (3D) jams: no further grain finds room (Hinrichsen,
/// Feder & Jøssang 1986, 0.547; Torquato, Uche & Stillinger 2006, 0.384).
const RANDOM_PLACEMENT_JAMMING: [f64; 2] = [0.547, 0.384];

/// How many grains of the smallest radius random placement can put in the
/// box `[lower, upper]` before it jams: an upper bound of what a `random`
/// block can place (larger grains fill it sooner).
fn random_placement_room(dim: usize, lower: &[f64], upper: &[f64], p: &ParticlesSection) -> f64 {
    let region: f64 = (0..dim).map(|a| (upper[a] - lower[a]).max(0.0)).product();
    let radius = p.radius * (1.0 - p.radius_spread);
    let grain = if dim == 2 {
        std::f64::consts::PI * radius * radius
    } else {
        4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
    };
    (RANDOM_PLACEMENT_JAMMING[dim - 2] * region / grain).floor()
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
    /// `vx,vy[,vz]`. A relative path is relative to the case file.
    File {
        path: String,
        #[serde(default)]
        fixed: bool,
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

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSection {
    /// "soft" (the DEM of Izard et al. 2014), or hard contact: "cocd"
    /// (convex optimization contact dynamics) or "nscd" (non-smooth
    /// contact dynamics), Martin et al. 2022. The rest of a case is the same
    /// for the three.
    pub model: String,
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
    /// cocd: "interior_point" (grainflow's, on the normal equations, where
    /// the cones are linear: 2D discs; the default) or "clarabel" (the
    /// reference; always used for 3D frictional contacts).
    #[serde(default)]
    pub conic_solver: Option<String>,
}

impl ContactSection {
    /// Whether the model is hard contact (cocd or nscd).
    pub fn is_hard(&self) -> bool {
        self.model == "cocd" || self.model == "nscd"
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
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CouplingSection {
    /// "inner_fluid_momentum" (default: the rate of change of the fluid
    /// momentum inside each grain enters its load; any density ratio) or
    /// "rigid_inner_fluid" (eq. 5–6 of the paper; unstable as ρ_p/ρ → 1).
    #[serde(default = "default_formulation")]
    pub formulation: String,
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
    /// The first layer of fluid cells along the domain's walls: "free"
    /// (default: the moving grains do not force it; it holds the film of
    /// eq. 19, which the flow does not resolve; glued grains still do) or
    /// "forced" (the paper's forcing, which reaches the walls and seals
    /// them under a grain at contact).
    #[serde(default = "default_wall_layer")]
    pub wall_layer: String,
}

impl Default for CouplingSection {
    fn default() -> Self {
        CouplingSection {
            formulation: default_formulation(),
            contact_gap: default_contact_gap(),
            forcing_step: None,
            wall_layer: default_wall_layer(),
        }
    }
}

fn default_wall_layer() -> String {
    "free".into()
}

fn default_contact_gap() -> f64 {
    0.0
}

fn default_formulation() -> String {
    "inner_fluid_momentum".into()
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

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimeSection {
    /// Simulated end time [s].
    pub end: f64,
    /// Time step [s]; or ...
    #[serde(default)]
    pub dt: Option<f64>,
    /// ... as a fraction of the binary contact time (default 0.02 = t_c/50).
    #[serde(default)]
    pub dt_over_contact_time: Option<f64>,
    /// Stop early once the rms speed of the grains in contact with other
    /// grains is below this [m/s] ...
    #[serde(default)]
    pub rest_speed: Option<f64>,
    /// ... but not before this time [s] (default: after the last wall removal).
    #[serde(default)]
    pub rest_after: Option<f64>,
    /// Largest overlap / radius before the run is declared unstable.
    #[serde(default = "default_overlap_limit")]
    pub overlap_limit: f64,
    /// Fluid: adapt the time step to this convective CFL number instead
    /// of a fixed `dt` (at most the RK3 limit √3).
    #[serde(default)]
    pub cfl: Option<f64>,
    /// Wall-clock seconds the run may take (a batch job's limit): before
    /// it, the run writes a checkpoint and stops, to be resumed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_limit: Option<f64>,
}

/// When a run writes checkpoints (besides on SIGTERM, SIGINT and
/// `time.wall_limit`): every `interval` of simulated time, every `steps`
/// steps, every `wall_interval` seconds of wall clock, whichever comes
/// first; the last `keep` are kept.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CheckpointSection {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub steps: Option<u64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall_interval: Option<f64>,
    #[serde(default = "default_keep")]
    pub keep: usize,
}

impl Default for CheckpointSection {
    fn default() -> Self {
        CheckpointSection {
            interval: None,
            steps: None,
            wall_interval: None,
            keep: default_keep(),
        }
    }
}

fn default_keep() -> usize {
    2
}

fn default_overlap_limit() -> f64 {
    0.25
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Simulated time between two outputs (series row, particle file) [s].
    #[serde(default)]
    pub interval: Option<f64>,
    /// Time between two rows of `tracked.csv` (default: `interval`).
    #[serde(default)]
    pub tracked_interval: Option<f64>,
    /// Write particle files for ParaView.
    #[serde(default = "default_true")]
    pub particles: bool,
    /// Write fluid field files (velocity, pressure, vorticity) for ParaView.
    #[serde(default = "default_true")]
    pub fields: bool,
    /// The format of the particle and field files (default `"vtk"`).
    #[serde(default, skip_serializing_if = "OutputFormat::is_vtk")]
    pub format: OutputFormat,
}

/// The format of a run's particle and field files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum OutputFormat {
    /// VTK XML: `particles/*.vtp` and `fields/*.vti` (`.vtr` on a
    /// stretched grid), one piece per rank, indexed by `particles.pvd` and
    /// `fields.pvd`.
    #[default]
    Vtk,
    /// HDF5: `particles/particles_NNNNNN.h5` and `fields/fields_NNNNNN.h5`,
    /// one file per output time on any number of ranks, indexed by the
    /// XDMF files `particles.xdmf` and `fields.xdmf` (needs a build with
    /// the cargo feature `hdf5`).
    Hdf5,
}

impl OutputFormat {
    /// Whether this is the default format, VTK.
    pub fn is_vtk(&self) -> bool {
        *self == OutputFormat::Vtk
    }
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            interval: None,
            tracked_interval: None,
            particles: true,
            fields: true,
            format: OutputFormat::Vtk,
        }
    }
}

fn default_true() -> bool {
    true
}

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum AnalysisSection {
    /// Ψ2 against Ψ1 and the restitution of `collision_pairs`.
    BinaryCollision,
    /// Restitution and energy loss of each impact of particle 0 on the walls.
    Bouncing,
    /// Coarse-grained pressure profile along gravity and its Janssen fit.
    Silo {
        /// Height of the averaging slabs [m].
        slab: f64,
        /// Slabs closer than this to the floor are left out of the fit [m].
        #[serde(default)]
        exclude_bottom: f64,
    },
    /// Runout (R∞ − R0)/R0 and aspect ratio H0/R0 of a symmetric collapse
    /// released by removing the walls named `gate`.
    ColumnCollapse {
        /// Times after the release [s] at which the height profile h(x) of
        /// the grains is written to `profiles.csv`.
        #[serde(default)]
        profile_times: Vec<f64>,
    },
    /// Grains at rest in a box (Martin et al. 2022, Fig. 3): the largest
    /// ratio of kinetic to potential energy after they settle.
    StaticBox {
        /// Time given to the grains to settle from their placement [s].
        settle: f64,
    },
    /// Fluid: relative L2 error of the velocity against the exact decaying
    /// solution of `fluid.initial` (Taylor–Green or Beltrami) at the end.
    ExactDecay,
    /// Fluid: the Poiseuille–Couette profile between the walls of the last
    /// axis, driven by `fluid.pressure_gradient` and moving walls, against
    /// the computed one at the end: the exact start-up from rest when the
    /// flow starts at rest under a pressure gradient, else the steady one.
    Channel,
    /// Grain in a fluid: particle 0 released from rest; its initial
    /// acceleration against the added-mass estimate (eq. 20) and its
    /// terminal velocity and Reynolds number against Schiller–Naumann (eq. 21).
    FallingSphere,
    /// Grain in a fluid: particle 0 settling onto a wall; its approach and
    /// rebound velocities, restitution over e_n and Stokes number (eq. 23).
    BouncingSphere,
    /// Grains in a fluid flowing down an inclined plane along x (section
    /// 4.2): profiles of the fluid and the grains, the bed's motion and the
    /// Shields number at its surface ([`crate::bed_analysis`]).
    InclinedBed {
        /// Height of the slabs the grains are averaged over [m] (default
        /// half their mean diameter).
        #[serde(default)]
        slab: Option<f64>,
    },
}

impl Case {
    /// Reads a case file and applies `--set key=value` overrides.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Case, CaseError> {
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Read {
            path: path.display().to_string(),
            source,
        })?;
        let mut case = Self::from_text(&text, &path.display().to_string(), overrides)?;
        // Files named by the case are relative to it.
        let base = path.parent().unwrap_or(Path::new("."));
        for block in case.particles.iter_mut().flat_map(|p| &mut p.block) {
            if let BlockSection::File { path: file, .. } = block {
                if Path::new(file.as_str()).is_relative() {
                    *file = base.join(file.as_str()).display().to_string();
                }
            }
        }
        Ok(case)
    }

    pub fn from_text(text: &str, origin: &str, overrides: &[String]) -> Result<Case, CaseError> {
        let mut document: toml::Table = toml::from_str(text).map_err(|e| CaseError::Parse {
            path: origin.to_string(),
            message: e.to_string(),
        })?;
        for assignment in overrides {
            apply_override(&mut document, assignment)?;
        }
        let case: Case =
            Case::deserialize(toml::Value::Table(document)).map_err(|e| CaseError::Parse {
                path: origin.to_string(),
                message: e.to_string().trim().to_string(),
            })?;
        case.validate()?;
        Ok(case)
    }

    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("a case always serialises")
    }

    pub fn dimension(&self) -> usize {
        self.domain.dimension as usize
    }

    /// The particle section of a scene with grains (validation guarantees
    /// it with the contact section whenever either is present).
    pub fn particles_section(&self) -> &ParticlesSection {
        self.particles.as_ref().expect("a scene with grains")
    }

    pub fn contact_section(&self) -> &ContactSection {
        self.contact.as_ref().expect("a scene with grains")
    }

    /// The fluid section of a fluid scene.
    pub fn fluid_section(&self) -> &FluidSection {
        self.fluid.as_ref().expect("a fluid scene")
    }

    /// Whether the scene has grains (else it is fluid only).
    pub fn has_grains(&self) -> bool {
        self.particles.is_some()
    }

    /// Checks ranges and consistency; the error names the key and what is
    /// allowed.
    pub fn validate(&self) -> Result<(), CaseError> {
        self.validate_checkpoints()?;
        let d = &self.domain;
        if d.dimension != 2 && d.dimension != 3 {
            return Err(invalid("domain.dimension", d.dimension, "allowed: 2 or 3"));
        }
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        check_len("domain.lower", &d.lower, dim, &need)?;
        check_len("domain.upper", &d.upper, dim, &need)?;
        for axis in 0..dim {
            if d.upper[axis] <= d.lower[axis] {
                return Err(invalid(
                    "domain.upper",
                    format!("{:?}", d.upper),
                    "allowed: each bound above domain.lower",
                ));
            }
        }
        if !d.periodic.is_empty() && d.periodic.len() != dim {
            return Err(invalid(
                "domain.periodic",
                format!("{:?}", d.periodic),
                &format!("allowed: a list of {dim} booleans"),
            ));
        }
        if !d.gravity.is_empty() {
            check_len("domain.gravity", &d.gravity, dim, &need)?;
        }
        if let Some(grid) = self.parallel.as_ref().and_then(|p| p.process_grid.as_ref()) {
            if grid.len() != dim || grid.contains(&0) {
                return Err(invalid(
                    "parallel.process_grid",
                    format!("{grid:?}"),
                    &format!("allowed: {dim} positive rank counts, one per axis"),
                ));
            }
        }
        if self.parallel.as_ref().and_then(|p| p.threads) == Some(0) {
            return Err(invalid(
                "parallel.threads",
                0,
                "allowed: at least 1 (or leave it out to choose from the scene's size)",
            ));
        }

        match (&self.particles, &self.contact, &self.fluid) {
            (Some(p), Some(c), _) => self.validate_grains(p, c)?,
            (Some(_), None, _) => {
                return Err(invalid(
                    "contact",
                    "(missing)",
                    "a scene with [particles] needs a [contact] table",
                ))
            }
            (None, Some(_), _) => {
                return Err(invalid(
                    "particles",
                    "(missing)",
                    "a [contact] table needs [particles]",
                ))
            }
            (None, None, None) => {
                return Err(invalid(
                    "particles",
                    "(missing)",
                    "a scene needs [particles] (with [contact]), a [fluid], or both",
                ))
            }
            (None, None, Some(_)) => {}
        }
        if let Some(fluid) = &self.fluid {
            self.validate_fluid(fluid)?;
        }
        self.validate_coupling()?;
        self.validate_walls_time_output()
    }

    fn validate_checkpoints(&self) -> Result<(), CaseError> {
        let positive = |key: &str, value: Option<f64>| match value {
            Some(v) if !(v > 0.0 && v.is_finite()) => {
                Err(invalid(key, v, "allowed: a positive number of seconds"))
            }
            _ => Ok(()),
        };
        positive("time.wall_limit", self.time.wall_limit)?;
        if let Some(c) = &self.checkpoint {
            positive("checkpoint.interval", c.interval)?;
            positive("checkpoint.wall_interval", c.wall_interval)?;
            if c.steps == Some(0) {
                return Err(invalid("checkpoint.steps", 0, "allowed: at least 1"));
            }
            if c.keep == 0 {
                return Err(invalid(
                    "checkpoint.keep",
                    0,
                    "allowed: at least 1 (the checkpoint a run resumes from)",
                ));
            }
        }
        Ok(())
    }

    fn validate_grains(&self, p: &ParticlesSection, c: &ContactSection) -> Result<(), CaseError> {
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        if matches!(
            self.analysis,
            Some(AnalysisSection::ExactDecay | AnalysisSection::Channel)
        ) {
            return Err(invalid(
                "analysis.kind",
                "(a fluid analysis)",
                "a scene of grains allows \"binary_collision\", \"bouncing\", \"silo\", \
                 \"column_collapse\", \"static_box\" or, in a fluid, \"falling_sphere\", \
                 \"bouncing_sphere\" or \"inclined_bed\"",
            ));
        }
        if self.fluid.is_none()
            && matches!(
                self.analysis,
                Some(
                    AnalysisSection::FallingSphere
                        | AnalysisSection::BouncingSphere
                        | AnalysisSection::InclinedBed { .. }
                )
            )
        {
            return Err(invalid(
                "analysis.kind",
                "(an analysis of grains in a fluid)",
                "falling_sphere, bouncing_sphere and inclined_bed need a [fluid]",
            ));
        }
        if self.time.cfl.is_some() && self.fluid.is_none() {
            return Err(invalid(
                "time.cfl",
                "(dry scene)",
                "time.cfl sets the step of a fluid; a dry scene uses time.dt or \
                 time.dt_over_contact_time",
            ));
        }
        positive("particles.density", p.density)?;
        positive("particles.radius", p.radius)?;
        if !(0.0..1.0).contains(&p.radius_spread) {
            return Err(invalid(
                "particles.radius_spread",
                p.radius_spread,
                "allowed: 0 ≤ radius_spread < 1",
            ));
        }
        if p.block.is_empty() && p.pour.is_empty() {
            return Err(invalid(
                "particles.block",
                "[]",
                "allowed: at least one [[particles.block]] generator or [[particles.pour]]",
            ));
        }
        self.validate_pours(p, c)?;
        for (k, block) in p.block.iter().enumerate() {
            let key = |name: &str| format!("particles.block[{k}].{name}");
            match block {
                BlockSection::Lattice {
                    lower,
                    upper,
                    spacing,
                    layer_spacing,
                    jitter,
                    velocity,
                    ..
                } => {
                    if let Some(layer) = layer_spacing {
                        if *layer < *spacing {
                            return Err(invalid(
                                &key("layer_spacing"),
                                layer,
                                "allowed: at least `spacing`",
                            ));
                        }
                    }
                    check_len(&key("lower"), lower, dim, &need)?;
                    check_len(&key("upper"), upper, dim, &need)?;
                    if *spacing < 2.0 * p.radius * (1.0 + p.radius_spread) * (1.0 - 1e-12) {
                        return Err(invalid(
                            &key("spacing"),
                            spacing,
                            "allowed: at least the largest diameter, 2 radius (1 + radius_spread)",
                        ));
                    }
                    if !(0.0..=1.0).contains(jitter) {
                        return Err(invalid(&key("jitter"), jitter, "allowed: 0 ≤ jitter ≤ 1"));
                    }
                    if !velocity.is_empty() {
                        check_len(&key("velocity"), velocity, dim, &need)?;
                    }
                }
                BlockSection::Random {
                    lower,
                    upper,
                    count,
                    velocity,
                    ..
                } => {
                    check_len(&key("lower"), lower, dim, &need)?;
                    check_len(&key("upper"), upper, dim, &need)?;
                    if *count == 0 {
                        return Err(invalid(&key("count"), count, "allowed: at least 1"));
                    }
                    let room = random_placement_room(dim, lower, upper, p);
                    if *count as f64 > room {
                        return Err(invalid(
                            &key("count"),
                            count,
                            &format!(
                                "random placement (random sequential addition) jams at a solid \
                                 fraction of {}: this region holds at most {room:.0} grains of \
                                 the smallest radius; allowed: count ≤ {room:.0}, or a larger \
                                 region, or a lattice block",
                                RANDOM_PLACEMENT_JAMMING[dim - 2]
                            ),
                        ));
                    }
                    if !velocity.is_empty() {
                        check_len(&key("velocity"), velocity, dim, &need)?;
                    }
                }
                BlockSection::Explicit {
                    positions,
                    velocities,
                    angular_velocities,
                    radii,
                    ..
                } => {
                    if positions.is_empty() {
                        return Err(invalid(
                            &key("positions"),
                            "[]",
                            "allowed: at least one position",
                        ));
                    }
                    for (name, list) in [("positions", positions), ("velocities", velocities)] {
                        if !list.is_empty() && list.len() != positions.len() {
                            return Err(invalid(
                                &key(name),
                                list.len(),
                                "allowed: as many entries as positions",
                            ));
                        }
                        for v in list {
                            check_len(&key(name), v, dim, &need)?;
                        }
                    }
                    if !angular_velocities.is_empty() && angular_velocities.len() != positions.len()
                    {
                        return Err(invalid(
                            &key("angular_velocities"),
                            angular_velocities.len(),
                            "allowed: as many entries as positions",
                        ));
                    }
                    for w in angular_velocities {
                        check_len(
                            &key("angular_velocities"),
                            w,
                            3,
                            "allowed: a list of 3 numbers (rad/s about x, y, z)",
                        )?;
                    }
                    if !radii.is_empty() && radii.len() != positions.len() {
                        return Err(invalid(
                            &key("radii"),
                            radii.len(),
                            "allowed: as many radii as positions",
                        ));
                    }
                    for r in radii {
                        positive(&key("radii"), *r)?;
                    }
                }
                BlockSection::File { path, .. } => {
                    if path.is_empty() {
                        return Err(invalid(
                            &key("path"),
                            "\"\"",
                            "allowed: the path of a CSV file",
                        ));
                    }
                }
                BlockSection::CollisionPairs {
                    count,
                    impact_speed,
                    psi_max,
                    gap,
                } => {
                    if *count == 0 {
                        return Err(invalid(&key("count"), count, "allowed: at least 1"));
                    }
                    positive(&key("impact_speed"), *impact_speed)?;
                    if *psi_max < 0.0 {
                        return Err(invalid(&key("psi_max"), psi_max, "allowed: psi_max ≥ 0"));
                    }
                    if *gap < 0.0 {
                        return Err(invalid(&key("gap"), gap, "allowed: gap ≥ 0"));
                    }
                }
            }
        }
        match c.model.as_str() {
            "soft" => self.validate_soft_contact(c)?,
            "cocd" | "nscd" => self.validate_hard_contact(c)?,
            other => {
                return Err(invalid(
                    "contact.model",
                    other,
                    "allowed: \"soft\", \"cocd\", \"nscd\"",
                ))
            }
        }
        non_negative("contact.friction", c.friction)?;
        non_negative("contact.rolling_friction", c.rolling_friction)?;
        if let Some(f) = c.wall_friction {
            non_negative("contact.wall_friction", f)?;
        }
        if let Some(s) = c.skin {
            positive("contact.skin", s)?;
        }
        Ok(())
    }

    fn validate_pours(&self, p: &ParticlesSection, c: &ContactSection) -> Result<(), CaseError> {
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        for (k, pour) in p.pour.iter().enumerate() {
            let key = |name: &str| format!("particles.pour[{k}].{name}");
            if self.fluid.is_some() || c.model != "soft" {
                return Err(invalid(
                    &key("count"),
                    pour.count,
                    "a pour runs in a dry scene with contact.model = \"soft\" in this version; \
                     allowed elsewhere: [[particles.block]] generators",
                ));
            }
            if self.domain.gravity.iter().all(|g| *g == 0.0) {
                return Err(invalid(
                    "domain.gravity",
                    format!("{:?}", self.domain.gravity),
                    "a pour needs gravity: its batches are released above the deposit, \
                     against gravity",
                ));
            }
            check_len(&key("lower"), &pour.lower, dim, &need)?;
            check_len(&key("upper"), &pour.upper, dim, &need)?;
            if pour.spacing < 2.0 * p.radius * (1.0 + p.radius_spread) * (1.0 - 1e-12) {
                return Err(invalid(
                    &key("spacing"),
                    pour.spacing,
                    "allowed: at least the largest diameter, 2 radius (1 + radius_spread)",
                ));
            }
            let d = &self.domain;
            for a in 0..dim {
                let periodic = d.periodic.get(a).copied().unwrap_or(false);
                if !periodic && (pour.lower[a] < d.lower[a] || pour.upper[a] > d.upper[a]) {
                    return Err(invalid(
                        &key("lower"),
                        format!("{:?} .. {:?}", pour.lower, pour.upper),
                        "allowed: a box inside domain.lower .. domain.upper",
                    ));
                }
            }
            let sites: f64 = (0..dim)
                .map(|a| ((pour.upper[a] - pour.lower[a]) / pour.spacing + 1e-9).floor())
                .product();
            if sites < 1.0 || sites.is_nan() {
                return Err(invalid(
                    &key("upper"),
                    format!("{:?}", pour.upper),
                    "allowed: a box that holds at least one lattice site (upper − lower ≥ \
                     spacing along every axis)",
                ));
            }
            if !(0.0..=1.0).contains(&pour.jitter) {
                return Err(invalid(
                    &key("jitter"),
                    pour.jitter,
                    "allowed: 0 ≤ jitter ≤ 1",
                ));
            }
            if pour.count == 0 {
                return Err(invalid(&key("count"), pour.count, "allowed: at least 1"));
            }
            positive(&key("interval"), pour.interval)?;
            non_negative(&key("gap"), pour.gap)?;
            if let Some(speed) = pour.settled_speed {
                positive(&key("settled_speed"), speed)?;
                // A batch released at rest falls faster than the settled
                // speed only after speed/g: an earlier test would pass at
                // once and stack the next batch on a falling one.
                let g = self
                    .domain
                    .gravity
                    .iter()
                    .map(|g| g * g)
                    .sum::<f64>()
                    .sqrt();
                let least = 1.2 * speed / g;
                if pour.interval < least {
                    return Err(invalid(
                        &key("interval"),
                        pour.interval,
                        &format!(
                            "allowed with settled_speed = {speed}: interval ≥ {least:.3e} s \
                             (1.2 settled_speed/|g|: a batch released at rest must be falling \
                             faster than settled_speed before the next one is considered)"
                        ),
                    ));
                }
            }
            if !pour.velocity.is_empty() {
                check_len(&key("velocity"), &pour.velocity, dim, &need)?;
            }
        }
        Ok(())
    }

    fn validate_soft_contact(&self, c: &ContactSection) -> Result<(), CaseError> {
        for (key, given) in [
            ("contact.tolerance", c.tolerance.is_some()),
            ("contact.max_iterations", c.max_iterations.is_some()),
            ("contact.threshold", c.threshold.is_some()),
            ("contact.conic_solver", c.conic_solver.is_some()),
        ] {
            if given {
                return Err(invalid(
                    key,
                    "(given)",
                    "a hard-contact key: allowed only with contact.model = \"cocd\" or \"nscd\"",
                ));
            }
        }
        match (c.restitution, c.contact_time, c.stiffness, c.damping) {
            (Some(e), Some(tc), None, None) => {
                if !(e > 0.0 && e <= 1.0) {
                    return Err(invalid(
                        "contact.restitution",
                        e,
                        "allowed: 0 < restitution ≤ 1",
                    ));
                }
                if c.calibration() == "exact"
                    && e <= grainflow_dem::contact_law::MIN_EXACT_RESTITUTION
                {
                    return Err(invalid(
                        "contact.restitution",
                        e,
                        "with calibration = \"exact\" allowed: restitution > e^-2 = 0.1353 (no \
                         force-clamped contact reaches a lower one in t_c); use calibration = \"paper\"",
                    ));
                }
                positive("contact.contact_time", tc)?;
            }
            (None, None, Some(k), Some(g)) => {
                positive("contact.stiffness", k)?;
                if g < 0.0 {
                    return Err(invalid("contact.damping", g, "allowed: damping ≥ 0"));
                }
            }
            _ => {
                return Err(invalid(
                    "contact",
                    "(restitution, contact_time, stiffness, damping)",
                    "allowed: either restitution and contact_time, or stiffness and damping",
                ))
            }
        }
        if c.calibration() != "exact" && c.calibration() != "paper" {
            return Err(invalid(
                "contact.calibration",
                c.calibration(),
                "allowed: \"exact\" or \"paper\"",
            ));
        }
        non_negative("contact.tangential_ratio", c.tangential_ratio())?;
        Ok(())
    }

    /// Hard contact: a dry scene, a fixed time step, and none of the soft
    /// law's keys.
    fn validate_hard_contact(&self, c: &ContactSection) -> Result<(), CaseError> {
        if self.fluid.is_some() {
            return Err(invalid(
                "contact.model",
                &c.model,
                "hard contact runs in dry scenes; grains in a fluid allowed: \"soft\"",
            ));
        }
        for (key, given) in [
            ("contact.contact_time", c.contact_time.is_some()),
            ("contact.calibration", c.calibration.is_some()),
            ("contact.stiffness", c.stiffness.is_some()),
            ("contact.damping", c.damping.is_some()),
            ("contact.tangential_ratio", c.tangential_ratio.is_some()),
            ("contact.rolling_friction", c.rolling_friction != 0.0),
        ] {
            if given {
                return Err(invalid(
                    key,
                    "(given)",
                    &format!(
                        "a soft-contact key: not used by contact.model = \"{}\" (grains do not overlap)",
                        c.model
                    ),
                ));
            }
        }
        if let Some(e) = c.restitution {
            if c.model == "cocd" {
                return Err(invalid(
                    "contact.restitution",
                    e,
                    "COCD is inelastic (Martin et al. 2022, eq. 5–9): leave restitution out, or use \"nscd\"",
                ));
            }
            if !(0.0..=1.0).contains(&e) {
                return Err(invalid(
                    "contact.restitution",
                    e,
                    "allowed: 0 ≤ restitution ≤ 1",
                ));
            }
        }
        if let Some(tolerance) = c.tolerance {
            if !(tolerance > 0.0 && tolerance < 1.0) {
                return Err(invalid(
                    "contact.tolerance",
                    tolerance,
                    "allowed: 0 < tolerance < 1",
                ));
            }
        }
        if c.max_iterations == Some(0) {
            return Err(invalid("contact.max_iterations", 0, "allowed: at least 1"));
        }
        if let Some(threshold) = c.threshold {
            positive("contact.threshold", threshold)?;
        }
        match (c.model.as_str(), c.conic_solver.as_deref()) {
            (_, None) | ("cocd", Some("interior_point" | "clarabel")) => {}
            ("cocd", Some(other)) => {
                return Err(invalid(
                    "contact.conic_solver",
                    other,
                    "allowed: \"interior_point\" or \"clarabel\"",
                ))
            }
            (_, Some(_)) => {
                return Err(invalid(
                    "contact.conic_solver",
                    "(given)",
                    "a COCD key: allowed only with contact.model = \"cocd\"",
                ))
            }
        }
        if self.time.dt.is_none() {
            return Err(invalid(
                "time.dt",
                "(missing)",
                "hard contact has no contact time: give time.dt (e.g. 1e-3 s for 2D columns, \
                 Martin et al. 2022 section 3.4.1)",
            ));
        }
        if self.time.dt_over_contact_time.is_some() {
            return Err(invalid(
                "time.dt_over_contact_time",
                "(given)",
                "hard contact has no contact time: allowed: time.dt",
            ));
        }
        Ok(())
    }

    fn validate_fluid(&self, f: &FluidSection) -> Result<(), CaseError> {
        let dim = self.dimension();
        if f.cells.len() != dim || f.cells.iter().any(|&n| n < 2) {
            return Err(invalid(
                "fluid.cells",
                format!("{:?}", f.cells),
                &format!("allowed: a list of {dim} cell counts, each at least 2"),
            ));
        }
        positive("fluid.density", f.density)?;
        positive("fluid.viscosity", f.viscosity)?;
        if f.viscous != "crank_nicolson" && f.viscous != "explicit" {
            return Err(invalid(
                "fluid.viscous",
                &f.viscous,
                "allowed: \"crank_nicolson\" or \"explicit\"",
            ));
        }
        match f.transforms.as_deref() {
            None | Some("rust") => {}
            Some("fftw") => {
                if !grainflow_fluid::TransformBackend::Fftw.is_available() {
                    return Err(invalid(
                        "fluid.transforms",
                        "fftw",
                        "this grainflow was built without FFTW: rebuild with `cargo build \
                         --release --features fftw` (needs the system's libfftw3), or allowed: \
                         \"rust\"",
                    ));
                }
            }
            Some(other) => {
                return Err(invalid(
                    "fluid.transforms",
                    other,
                    "allowed: \"rust\" (rustfft/rustdct) or \"fftw\" (a build with \
                     --features fftw)",
                ))
            }
        }
        if !f.pressure_gradient.is_empty() {
            check_len(
                "fluid.pressure_gradient",
                &f.pressure_gradient,
                dim,
                &format!("allowed: a list of {dim} numbers [Pa/m]"),
            )?;
        }
        let axes = ["x", "y", "z"];
        for (axis, name) in axes.iter().enumerate() {
            let Some(bulk) = f.bulk_velocity.along(axis) else {
                continue;
            };
            let key = format!("fluid.bulk_velocity.{name}");
            if axis >= dim || !self.domain.periodic.get(axis).copied().unwrap_or(false) {
                return Err(invalid(
                    &key,
                    bulk,
                    "allowed only along an axis the domain marks periodic",
                ));
            }
            if !bulk.is_finite() {
                return Err(invalid(&key, bulk, "allowed: a finite velocity [m/s]"));
            }
            if f.pressure_gradient.get(axis).is_some_and(|&g| g != 0.0) {
                return Err(invalid(
                    &key,
                    bulk,
                    "a held bulk velocity sets the pressure gradient along its axis: leave \
                     fluid.pressure_gradient zero there",
                ));
            }
        }
        for axis in 0..dim {
            let key = format!("fluid.boundary.{}", axes[axis]);
            let domain_periodic = self.domain.periodic.get(axis).copied().unwrap_or(false);
            let Some(faces) = f.boundary.faces(axis) else {
                if !domain_periodic {
                    return Err(invalid(
                        &key,
                        "(missing)",
                        &format!(
                            "axis {} is not periodic in domain.periodic: give its two faces, \
                             each {FACE_KINDS}",
                            axes[axis]
                        ),
                    ));
                }
                continue;
            };
            if faces.len() != 2 {
                return Err(invalid(
                    &key,
                    format!("{faces:?}"),
                    &format!("allowed: [lower, upper], each {FACE_KINDS}"),
                ));
            }
            for (side, face) in faces.iter().enumerate() {
                let side_name = ["lower", "upper"][side];
                match face.as_str() {
                    "periodic" | "no_slip" | "free_slip" | "moving" => {}
                    "outflow" => {
                        if side != 1 || axis != dim - 1 {
                            return Err(invalid(
                                &key,
                                format!("{faces:?}"),
                                &format!(
                                    "\"outflow\" is allowed only on the upper face of the last \
                                     axis ({}), whose lines are solved by elimination",
                                    axes[dim - 1]
                                ),
                            ));
                        }
                        if self.has_grains() {
                            return Err(invalid(
                                &key,
                                format!("{faces:?}"),
                                "\"outflow\" is for fluid-only scenes in this version",
                            ));
                        }
                    }
                    other => return Err(invalid(&key, other, &format!("allowed: {FACE_KINDS}"))),
                }
                if (face == "periodic") != domain_periodic {
                    return Err(invalid(
                        &key,
                        format!("{faces:?}"),
                        "allowed: \"periodic\" on both faces exactly when domain.periodic \
                         marks the axis periodic",
                    ));
                }
                let velocity_key = format!("fluid.boundary.{}_{side_name}_velocity", axes[axis]);
                match (face.as_str(), f.boundary.velocity(axis, side)) {
                    ("moving", Some(v)) => {
                        check_len(
                            &velocity_key,
                            v,
                            dim,
                            &format!("allowed: a list of {dim} numbers [m/s]"),
                        )?;
                        if !v.iter().all(|x| x.is_finite()) {
                            return Err(invalid(
                                &velocity_key,
                                format!("{v:?}"),
                                "allowed: finite velocities [m/s]",
                            ));
                        }
                    }
                    ("moving", None) => {
                        return Err(invalid(
                            &velocity_key,
                            "(missing)",
                            "a \"moving\" face needs its velocity [m/s]",
                        ))
                    }
                    (_, Some(_)) => {
                        return Err(invalid(
                            &velocity_key,
                            "(given)",
                            "allowed only for a \"moving\" face",
                        ))
                    }
                    (_, None) => {}
                }
            }
            // Fluid through the faces (blowing, suction): as much must
            // leave through one face as enters through the other.
            let normal = |side: usize| {
                (faces[side] == "moving")
                    .then(|| f.boundary.velocity(axis, side))
                    .flatten()
                    .map_or(0.0, |v| v[axis])
            };
            if faces[1] != "outflow" && normal(0) != normal(1) {
                return Err(invalid(
                    &format!("fluid.boundary.{}_upper_velocity", axes[axis]),
                    format!("normal component {} against {} below", normal(1), normal(0)),
                    "allowed: a through-flow (blowing in through one face, suction out through \
                     the other) with the same normal velocity on both faces of the axis, so that \
                     as much fluid leaves as enters; a wall sliding in its plane has none",
                ));
            }
        }
        let periodic = |axis: usize| self.domain.periodic.get(axis).copied().unwrap_or(false);
        let extent = |axis: usize| self.domain.upper[axis] - self.domain.lower[axis];
        if let Some(stretching) = &f.stretching {
            self.validate_stretching(stretching, periodic(dim - 1))?;
        }
        match &f.initial {
            InitialFlowSection::Rest => {}
            InitialFlowSection::Uniform { velocity } => check_len(
                "fluid.initial.velocity",
                velocity,
                dim,
                &format!("allowed: a list of {dim} numbers [m/s]"),
            )?,
            InitialFlowSection::TaylorGreen { velocity, stream } => {
                non_negative("fluid.initial.velocity", *velocity)?;
                if !stream.is_empty() {
                    check_len(
                        "fluid.initial.stream",
                        stream,
                        dim,
                        &format!("allowed: a list of {dim} numbers [m/s]"),
                    )?;
                }
                if !(periodic(0) && periodic(1))
                    || (extent(0) - extent(1)).abs() > 1e-12 * extent(0)
                {
                    return Err(invalid(
                        "fluid.initial.kind",
                        "taylor_green",
                        "needs a domain periodic along x and y with equal x and y extents",
                    ));
                }
            }
            InitialFlowSection::Beltrami { velocity } => {
                non_negative("fluid.initial.velocity", *velocity)?;
                if dim != 3
                    || !(0..3).all(periodic)
                    || (0..3).any(|a| (extent(a) - extent(0)).abs() > 1e-12 * extent(0))
                {
                    return Err(invalid(
                        "fluid.initial.kind",
                        "beltrami",
                        "needs a 3D domain periodic along every axis with equal extents (a cube)",
                    ));
                }
            }
        }
        if let Some(cfl) = self.time.cfl {
            if !(cfl > 0.0 && cfl <= grainflow_fluid::CFL_LIMIT) {
                return Err(invalid(
                    "time.cfl",
                    cfl,
                    "allowed: 0 < cfl ≤ √3 = 1.732 (the stability limit of RK3 with central \
                     convection)",
                ));
            }
        }
        match (&self.analysis, &f.initial) {
            (Some(AnalysisSection::ExactDecay), InitialFlowSection::TaylorGreen { .. })
            | (Some(AnalysisSection::ExactDecay), InitialFlowSection::Beltrami { .. }) => {}
            (Some(AnalysisSection::ExactDecay), _) => {
                return Err(invalid(
                    "analysis.kind",
                    "exact_decay",
                    "needs fluid.initial.kind = \"taylor_green\" or \"beltrami\"",
                ))
            }
            (Some(AnalysisSection::Channel), _) => {
                let last = dim - 1;
                if periodic(last) || (0..last).any(|a| !periodic(a)) {
                    return Err(invalid(
                        "analysis.kind",
                        "channel",
                        "needs walls on the faces of the last axis and periodic other axes",
                    ));
                }
                let through_flow = f
                    .boundary
                    .velocity(last, 0)
                    .is_some_and(|v| v.get(last).is_some_and(|&n| n != 0.0));
                let held = (0..dim).any(|a| f.bulk_velocity.along(a).is_some());
                if through_flow && held {
                    return Err(invalid(
                        "analysis.kind",
                        "channel",
                        "with fluid through the walls the profile is known under a pressure \
                         gradient, not a held bulk velocity",
                    ));
                }
            }
            (Some(_), _) if !self.has_grains() => {
                return Err(invalid(
                    "analysis.kind",
                    "(a particle analysis)",
                    "a fluid-only scene allows \"exact_decay\" or \"channel\"",
                ))
            }
            (Some(_), _) | (None, _) => {}
        }
        Ok(())
    }

    /// `[fluid.stretching]`: one of its two forms, along an axis with walls,
    /// in a scene without grains, giving faces that make a grid.
    fn validate_stretching(
        &self,
        s: &StretchingSection,
        periodic_line: bool,
    ) -> Result<(), CaseError> {
        let line = ["x", "y", "z"][self.dimension() - 1];
        if periodic_line {
            return Err(invalid(
                "fluid.stretching",
                "(given)",
                &format!(
                    "the stretched axis is the last one ({line}), which must have walls, not be \
                     periodic"
                ),
            ));
        }
        if self.has_grains() {
            return Err(invalid(
                "fluid.stretching",
                "(given)",
                "grains in a fluid need uniform cells (the immersed boundary's smoothing \
                 length is a cell size): stretching is for fluid-only scenes",
            ));
        }
        match (&s.cluster, s.factor, &s.faces) {
            (Some(cluster), Some(factor), None) => {
                if !matches!(cluster.as_str(), "both_walls" | "lower_wall" | "upper_wall") {
                    return Err(invalid(
                        "fluid.stretching.cluster",
                        cluster,
                        &format!("allowed: {CLUSTER_KINDS}"),
                    ));
                }
                if !(factor > 0.0 && factor <= MAX_STRETCHING_FACTOR) {
                    return Err(invalid(
                        "fluid.stretching.factor",
                        factor,
                        &format!(
                            "allowed: 0 < factor ≤ {MAX_STRETCHING_FACTOR} (the clustered end \
                             cells are 2β/sinh 2β of the mean width)"
                        ),
                    ));
                }
            }
            (None, None, Some(_)) => {}
            _ => {
                return Err(invalid(
                    "fluid.stretching",
                    "(incomplete or mixed)",
                    &format!(
                        "allowed: cluster ({CLUSTER_KINDS}) with factor, or faces (the {line} \
                         face coordinates [m]), not both"
                    ),
                ))
            }
        }
        crate::fluid_scene::try_grid(self)
            .map_err(|message| invalid("fluid.stretching.faces", "(the faces given)", &message))?;
        Ok(())
    }

    /// The tables of a scene with grains in a fluid.
    fn validate_coupling(&self) -> Result<(), CaseError> {
        let coupled = self.fluid.is_some() && self.has_grains();
        if !coupled && self.coupling.is_some() {
            return Err(invalid(
                "coupling",
                "(without grains in a fluid)",
                "[coupling] needs both [fluid] and [particles]",
            ));
        }
        if !coupled && self.lubrication.is_some() {
            return Err(invalid(
                "lubrication",
                "(without a fluid)",
                "the lubrication force exists only for grains in a fluid: [lubrication] needs \
                 both [fluid] and [particles]",
            ));
        }
        if let Some(c) = &self.coupling {
            if !matches!(
                c.formulation.as_str(),
                "inner_fluid_momentum" | "rigid_inner_fluid"
            ) {
                return Err(invalid(
                    "coupling.formulation",
                    &c.formulation,
                    "allowed: \"inner_fluid_momentum\" or \"rigid_inner_fluid\"",
                ));
            }
        }
        if let Some(c) = &self.coupling {
            if !(c.contact_gap >= 0.0 && c.contact_gap <= 3.0) {
                return Err(invalid(
                    "coupling.contact_gap",
                    c.contact_gap,
                    "allowed: 0 ≤ contact_gap ≤ 3 (fluid cells)",
                ));
            }
            if let Some(step) = c.forcing_step {
                positive("coupling.forcing_step", step)?;
            }
            if !matches!(c.wall_layer.as_str(), "free" | "forced") {
                return Err(invalid(
                    "coupling.wall_layer",
                    &c.wall_layer,
                    "allowed: \"free\" (the grains leave the first cells along a wall to the \
                     fluid) or \"forced\" (the paper's forcing)",
                ));
            }
        }
        if let Some(l) = &self.lubrication {
            positive("lubrication.roughness", l.roughness)?;
            if !(l.range > 0.0 && l.range <= 1.0) {
                return Err(invalid(
                    "lubrication.range",
                    l.range,
                    "allowed: 0 < range ≤ 1 (gap over the smaller radius; the paper uses 0.5)",
                ));
            }
        }
        if coupled {
            if !matches!(
                self.analysis,
                None | Some(
                    AnalysisSection::FallingSphere
                        | AnalysisSection::BouncingSphere
                        | AnalysisSection::InclinedBed { .. }
                )
            ) {
                return Err(invalid(
                    "analysis.kind",
                    "(grains in a fluid)",
                    "grains in a fluid allow \"falling_sphere\", \"bouncing_sphere\" or \
                     \"inclined_bed\" (or no analysis)",
                ));
            }
            if let Some(AnalysisSection::InclinedBed { slab: Some(slab) }) = &self.analysis {
                if !(slab.is_finite() && *slab > 0.0) {
                    return Err(invalid(
                        "analysis.slab",
                        slab,
                        "allowed: a positive height [m]",
                    ));
                }
            }
            if self.time.dt.is_none() {
                return Err(invalid(
                    "time.dt",
                    "(missing)",
                    "grains in a fluid need the fluid step time.dt [s] (with time.cfl, the \
                     largest step); the DEM sub-step is time.dt_over_contact_time × t_c \
                     (default 0.02)",
                ));
            }
        }
        Ok(())
    }

    fn validate_walls_time_output(&self) -> Result<(), CaseError> {
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        if !self.walls.is_empty() && !self.has_grains() {
            return Err(invalid(
                "walls",
                self.walls.len(),
                "[[walls]] are particle walls; a fluid-only scene sets fluid.boundary",
            ));
        }

        if self.walls.len() > 64 {
            return Err(invalid(
                "walls",
                self.walls.len(),
                "allowed: at most 64 walls",
            ));
        }
        for (k, w) in self.walls.iter().enumerate() {
            let key = |name: &str| format!("walls[{k}].{name}");
            check_len(&key("point"), &w.point, dim, &need)?;
            check_len(&key("normal"), &w.normal, dim, &need)?;
            if w.normal.iter().map(|x| x * x).sum::<f64>() == 0.0 {
                return Err(invalid(
                    &key("normal"),
                    format!("{:?}", w.normal),
                    "allowed: a non-zero vector",
                ));
            }
            if let Some(f) = w.friction {
                non_negative(&key("friction"), f)?;
            }
        }

        let t = &self.time;
        positive("time.end", t.end)?;
        let coupled = self.fluid.is_some() && self.has_grains();
        match (t.dt, t.dt_over_contact_time) {
            (Some(dt), Some(f)) if coupled => {
                positive("time.dt", dt)?;
                positive("time.dt_over_contact_time", f)?;
            }
            (Some(_), Some(_)) => {
                return Err(invalid(
                    "time.dt",
                    "(dt, dt_over_contact_time)",
                    "allowed: one of time.dt and time.dt_over_contact_time",
                ))
            }
            (Some(dt), None) => positive("time.dt", dt)?,
            (None, Some(f)) => positive("time.dt_over_contact_time", f)?,
            (None, None) => {}
        }
        if let Some(v) = t.rest_speed {
            positive("time.rest_speed", v)?;
        }
        positive("time.overlap_limit", t.overlap_limit)?;

        if let Some(i) = self.output.interval {
            positive("output.interval", i)?;
        }
        if let Some(i) = self.output.tracked_interval {
            positive("output.tracked_interval", i)?;
        }
        if self.output.format == OutputFormat::Hdf5 && !cfg!(feature = "hdf5") {
            return Err(invalid(
                "output.format",
                "\"hdf5\"",
                "this grainflow was built without the HDF5 writers: build it with \
                 `cargo build --release --features hdf5` (needs the system's HDF5 library, e.g. \
                 Debian's libhdf5-dev; with --features mpi too, libhdf5-openmpi-dev), or use \
                 output.format = \"vtk\"",
            ));
        }
        if self.time.cfl.is_some() && self.time.dt.is_some() && !coupled {
            return Err(invalid(
                "time.cfl",
                "(with time.dt)",
                "allowed: one of time.dt and time.cfl",
            ));
        }
        if self.fluid.is_some() && self.time.cfl.is_none() && self.time.dt.is_none() {
            return Err(invalid(
                "time.dt",
                "(missing)",
                "a fluid scene needs time.dt [s] or time.cfl",
            ));
        }
        if let Some(AnalysisSection::Silo { slab, .. }) = &self.analysis {
            positive("analysis.slab", *slab)?;
        }
        if let Some(AnalysisSection::StaticBox { settle }) = &self.analysis {
            if !(*settle >= 0.0 && *settle < self.time.end) {
                return Err(invalid(
                    "analysis.settle",
                    settle,
                    "allowed: 0 ≤ settle < time.end",
                ));
            }
        }
        if let Some(AnalysisSection::ColumnCollapse { profile_times }) = &self.analysis {
            if profile_times.iter().any(|t| t.is_nan() || *t < 0.0) {
                return Err(invalid(
                    "analysis.profile_times",
                    format!("{profile_times:?}"),
                    "allowed: times ≥ 0 after the release [s]",
                ));
            }
        }
        if matches!(self.analysis, Some(AnalysisSection::ColumnCollapse { .. }))
            && !self.walls.iter().any(|w| w.remove_at.is_some())
        {
            return Err(invalid(
                "analysis.kind",
                "column_collapse",
                "needs walls with remove_at (the gates)",
            ));
        }
        Ok(())
    }
}

fn check_len(key: &str, values: &[f64], n: usize, allowed: &str) -> Result<(), CaseError> {
    if values.len() != n || values.iter().any(|v| !v.is_finite()) {
        return Err(invalid(key, format!("{values:?}"), allowed));
    }
    Ok(())
}

fn non_negative(key: &str, value: f64) -> Result<(), CaseError> {
    if value >= 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, value, "allowed: a number ≥ 0"))
    }
}

fn positive(key: &str, value: f64) -> Result<(), CaseError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(invalid(key, value, "allowed: a positive number"))
    }
}

/// Sets `a.b.c = value` in the document; the value is read as TOML (a
/// number, boolean, array, ...) or else taken as a string.
fn apply_override(document: &mut toml::Table, assignment: &str) -> Result<(), CaseError> {
    let err = |message: &str| CaseError::Override {
        assignment: assignment.to_string(),
        message: message.to_string(),
    };
    let (key, raw) = assignment
        .split_once('=')
        .ok_or_else(|| err("expected key=value, e.g. time.end=0.1"))?;
    let key = key.trim();
    let value: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {}", raw.trim())) {
        Ok(mut t) => t.remove("v").unwrap(),
        Err(_) => toml::Value::String(raw.trim().to_string()),
    };
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(err("empty key segment"));
    }
    // Each segment is `name` or `name[index]` (an entry of an array of tables).
    let mut table = document;
    for (depth, part) in parts.iter().enumerate() {
        let (name, index) = match part.split_once('[') {
            Some((name, rest)) => {
                let index: usize = rest
                    .strip_suffix(']')
                    .and_then(|i| i.parse().ok())
                    .ok_or_else(|| err(&format!("bad index in `{part}`")))?;
                (name, Some(index))
            }
            None => (*part, None),
        };
        let last = depth + 1 == parts.len();
        if last && index.is_none() {
            table.insert(name.to_string(), value);
            return Ok(());
        }
        let entry = table
            .entry(name.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let entry = match (entry, index) {
            (toml::Value::Array(items), Some(i)) => items
                .get_mut(i)
                .ok_or_else(|| err(&format!("`{name}` has no entry {i}")))?,
            (entry, None) => entry,
            _ => return Err(err(&format!("`{name}` is not an array"))),
        };
        if last {
            *entry = value;
            return Ok(());
        }
        table = match entry {
            toml::Value::Table(t) => t,
            _ => return Err(err(&format!("`{part}` is not a table"))),
        };
    }
    Ok(())
}
