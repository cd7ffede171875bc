//! The tables of a case that describe the domain and the fluid.

use serde::{Deserialize, Serialize};

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
    /// "cartesian" (default) or "axisymmetric": the fluid of a 3D scene
    /// solved in (r, z) about the axis x = y = 0, the box around the
    /// cylinder of radius `upper[0]` (README, "Axisymmetric scenes").
    #[serde(default, skip_serializing_if = "Geometry::is_cartesian")]
    pub geometry: Geometry,
}

/// The geometry of the fluid's grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Geometry {
    /// A staggered grid over the box.
    #[default]
    Cartesian,
    /// Axisymmetric without swirl: the fluid in the meridian plane (r, z)
    /// of the cylinder inscribed in the box, about the axis x = y = 0.
    Axisymmetric,
}

impl Geometry {
    pub fn is_cartesian(&self) -> bool {
        *self == Geometry::Cartesian
    }
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
    /// Axisymmetric scenes: uniform radial cells out to this radius [m],
    /// then cells growing in arithmetic progression to the outer wall
    /// (Izard et al. 2014, §3.1), with `core_cells`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core_radius: Option<f64>,
    /// Axisymmetric scenes: the number of uniform cells within `core_radius`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub core_cells: Option<usize>,
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
