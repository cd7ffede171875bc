//! The tables of a case that describe the run: time, checkpoints,
//! outputs and the analysis.

use serde::{Deserialize, Serialize};

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

fn default_front_interval() -> f64 {
    0.01
}

fn default_profile_interval() -> f64 {
    0.1
}

/// The paper's criterion for static grains: u_x < 1 cm/s.
fn default_flowing_speed() -> f64 {
    0.01
}

fn default_front_smoothing() -> f64 {
    0.05
}

pub(super) fn default_true() -> bool {
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
    /// A column released onto a channel covered by an erodible layer
    /// (Martin et al. 2022, section 5; [`crate::analysis::ErodibleBed`]):
    /// the front and its phases, the bed's energy, mass and velocity
    /// profiles, the static/flowing interface.
    ErodibleBed {
        /// Times after the release [s] at which h(x) is written to
        /// `profiles.csv`.
        #[serde(default)]
        profile_times: Vec<f64>,
        /// Positions along the channel [m] of the velocity profiles.
        #[serde(default)]
        probes: Vec<f64>,
        /// Interval [s] of the front and energy samples (`front.csv`).
        #[serde(default = "default_front_interval")]
        sample_interval: f64,
        /// Interval [s] of the velocity profiles and of the interface.
        #[serde(default = "default_profile_interval")]
        profile_interval: f64,
        /// Speed along the slope [m/s] below which grains are static.
        #[serde(default = "default_flowing_speed")]
        flowing_speed: f64,
        /// Window [s] over which the front speed is averaged.
        #[serde(default = "default_front_smoothing")]
        smoothing: f64,
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
    /// Shields number at its surface ([`crate::analysis::bed`]).
    InclinedBed {
        /// Height of the slabs the grains are averaged over [m] (default
        /// half their mean diameter).
        #[serde(default)]
        slab: Option<f64>,
    },
}
