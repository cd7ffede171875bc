//! Where hard contact's answers depend on its settings: the limits
//! `check` and `run` warn past (measured in `docs/validation.md` §11).

use grainflow_contact::{HardContact, Method};
use grainflow_dem::DemSystem;

/// The loosest COCD tolerance ε at which grains at rest stay at rest
/// where they lean on a slope. The erodible-bed release at 22° (d = 4 mm,
/// h_i = 5 d, Δt = 1 ms, two runs at each ε, 2026-12-05;
/// `docs/validation.md` §11): at ε = 1e-3 the resting layer a metre ahead
/// of the flow crept (0.9 mm on average by 1 s, up to 68 mm, grains at up
/// to 4 cm/s) and the front, which counts the raised flowing bins, read
/// 10.3–10.5 R0 against 3.79–3.93 at 1e-8; at 1e-4 the runouts were
/// 3.91–3.99 and the layer held as at 1e-8. (Spheres at rest on a flat
/// floor held to 1e-3, §8.)
pub const LOOSEST_COCD_TOLERANCE: f64 = 1e-4;

/// A warning for a COCD tolerance looser than [`LOOSEST_COCD_TOLERANCE`].
fn cocd_tolerance_warning(hard: &HardContact) -> Option<String> {
    (hard.method == Method::Cocd && hard.tolerance > LOOSEST_COCD_TOLERANCE).then(|| {
        format!(
            "warning: contact.tolerance = {:.1e} is looser than {LOOSEST_COCD_TOLERANCE:.0e}: grains \
             at rest on a slope creep (an erodible layer at 22° flowed ahead of the front at \
             1e-3); use contact.tolerance ≤ {LOOSEST_COCD_TOLERANCE:.0e} (the default is 1e-8)",
            hard.tolerance
        )
    })
}

/// The longest hard-contact step, as a fraction of the time √(d/g) in
/// which a grain falls through its own diameter, at which a slow flow
/// keeps its speed within about a tenth of a short step's. Both schemes
/// are first order in Δt and dissipate the more the longer the step. On
/// the narrow channel's 22° slope (d = 2 mm, μ = 0.3, frictionless side
/// walls; `scripts/chute_layer_arrest.py`, 2026-12-07) layers of 3, 5 and
/// 8 grains flowed under COCD at 0.77–0.89, 0.47–0.61, 0.27–0.34 and
/// 0.21–0.24 times their speed at Δt √(g/d) = 0.07 when the step was
/// 0.14, 0.35, 0.70 and 1.0 times √(d/g); the paper's 3D step, 10 ms for
/// its 1 mm grains, is 0.99. NSCD stopped the 3-grain layer within 0.34 s
/// at 1.0, its Gauss–Seidel unconverged, where at 0.07 it flowed.
pub const LONGEST_HARD_STEP: f64 = 0.1;

/// The warnings of a hard-contact scene's settings, as `check` prints
/// them and `run` logs them. Every rank must call it.
pub fn hard_contact_warnings(hard: &HardContact, dt: f64, system: &DemSystem) -> Vec<String> {
    cocd_tolerance_warning(hard)
        .into_iter()
        .chain(hard_step_warning(hard, dt, system))
        .collect()
}

/// A warning for a hard-contact step longer than [`LONGEST_HARD_STEP`]
/// times √(d/g), d the mean diameter of the grains that move and g the
/// magnitude of gravity (none without either).
fn hard_step_warning(hard: &HardContact, dt: f64, system: &DemSystem) -> Option<String> {
    let diameter = system.mean_moving_diameter()?;
    let gravity = system.domain.gravity.norm();
    if gravity == 0.0 {
        return None;
    }
    let fall_time = (diameter / gravity).sqrt();
    let ratio = dt / fall_time;
    if ratio <= LONGEST_HARD_STEP {
        return None;
    }
    let measured = match hard.method {
        Method::Cocd => {
            "COCD's slow flows slow down with the step (layers on a 22° slope flowed 4 \
                         to 5 times slower at 1.0 than at 0.07"
        }
        Method::Nscd { .. } => {
            "NSCD's slow flows slow down with the step (a layer flowing on a 22° \
                                slope at 0.07 stopped within 0.34 s at 1.0, unconverged"
        }
    };
    Some(format!(
        "warning: time.dt = {dt:.3e} s is {ratio:.2} times the grains' fall time over their \
             diameter, sqrt(d/g) = {fall_time:.3e} s (mean d = {diameter:.3e} m): {measured}, \
             docs/validation.md §11); use time.dt ≤ {:.3e} s ({LONGEST_HARD_STEP} sqrt(d/g)) where \
             a flow's speed matters",
        LONGEST_HARD_STEP * fall_time
    ))
}
