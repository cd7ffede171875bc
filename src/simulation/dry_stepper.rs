//! How the grains of a dry scene advance: the soft DEM (velocity Verlet at
//! a fraction of the contact time) or hard contact (COCD or NSCD at a fixed
//! step), and what each checks after every step.

use super::dry::{check_time_step, time_step};
use crate::case::Case;
use crate::{scene, RunError};
use grainflow_contact::{HardContact, Method, StepReport};
use grainflow_core::{State, StateError};
use grainflow_dem::DemSystem;
use serde_json::{json, Map, Value};

/// The soft or hard stepping of a dry scene.
pub enum DryStepper {
    Soft {
        contact_time: f64,
    },
    Hard {
        contact: Box<HardContact>,
        record: HardRecord,
    },
}

/// Run-wide record of the hard-contact steps: their certificates, solver
/// effort and size.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct HardRecord {
    pub steps: u64,
    pub max_coulomb_violation: f64,
    pub max_penetration: f64,
    pub max_complementarity: f64,
    pub iterations: u64,
    pub max_iterations: u32,
    pub candidates: u64,
    /// Programs solved again because a pair left out of the first would
    /// have overlapped (saved apart, so that checkpoints written before it
    /// was counted still load).
    #[serde(skip)]
    pub extra_programs: u64,
    pub closed: u64,
    pub unconverged_steps: u64,
    /// Steps another solver took over (Clarabel from grainflow's interior
    /// point, the interior point from the projected gradient), and the
    /// first of them: when, and why the chosen solver failed (saved apart,
    /// as `extra_programs`).
    pub fallback_steps: u64,
    #[serde(skip)]
    pub first_fallback: Option<String>,
    pub seconds_solve: f64,
}

impl HardRecord {
    fn add(&mut self, report: &StepReport) {
        self.steps += 1;
        self.max_coulomb_violation = self.max_coulomb_violation.max(report.coulomb_violation);
        self.max_penetration = self.max_penetration.max(report.penetration);
        self.max_complementarity = self.max_complementarity.max(report.complementarity);
        self.iterations += report.iterations as u64;
        self.max_iterations = self.max_iterations.max(report.iterations);
        self.candidates += report.candidates as u64;
        self.extra_programs += u64::from(report.programs.saturating_sub(1));
        self.closed += report.closed as u64;
        self.unconverged_steps += u64::from(report.unconverged);
        self.fallback_steps += u64::from(report.fell_back);
        self.seconds_solve += report.seconds_solve;
    }

    /// The metrics of `summary.json`.
    pub fn metrics(&self) -> Map<String, Value> {
        let steps = self.steps.max(1) as f64;
        let mut metrics = Map::new();
        for (key, value) in [
            ("max_coulomb_violation", json!(self.max_coulomb_violation)),
            ("max_penetration", json!(self.max_penetration)),
            ("max_complementarity", json!(self.max_complementarity)),
            ("mean_iterations", json!(self.iterations as f64 / steps)),
            ("max_iterations", json!(self.max_iterations)),
            ("mean_candidates", json!(self.candidates as f64 / steps)),
            ("extra_programs", json!(self.extra_programs)),
            ("mean_closed_contacts", json!(self.closed as f64 / steps)),
            ("unconverged_steps", json!(self.unconverged_steps)),
            ("fallback_steps", json!(self.fallback_steps)),
            ("first_fallback", json!(self.first_fallback)),
            ("seconds_per_solve", json!(self.seconds_solve / steps)),
        ] {
            metrics.insert(key.into(), value);
        }
        metrics
    }
}

impl DryStepper {
    /// The stepper of a case, its time step, and the warnings to log. Refuses
    /// (before anything is written) a soft time step past the stability
    /// limit.
    pub fn new(case: &Case, system: &mut DemSystem) -> Result<(Self, f64, Vec<String>), RunError> {
        match scene::hard_contact(case) {
            Some(mut contact) => {
                contact.prepare(system);
                let ranks = system.communicator.size();
                if ranks > 1 && !crate::sharing::separator_factorised(case) {
                    // What a rank's memory leaves for the interior point's
                    // Σ where it takes over from the projected gradient.
                    contact.separator_room = crate::footprint::machine_memory().map(|memory| {
                        memory - crate::footprint::Footprint::of(case).per_rank_bytes(ranks, 0.0)
                    });
                }
                let dt = case.time.dt.expect("validated: hard contact has time.dt");
                let warnings = scene::hard_contact_warnings(&contact, dt, system);
                let stepper = DryStepper::Hard {
                    contact: Box::new(contact),
                    record: HardRecord::default(),
                };
                Ok((stepper, dt, warnings))
            }
            None => {
                let (dt, contact_time) = time_step(case, system);
                let warnings = check_time_step(dt, contact_time)?.into_iter().collect();
                Ok((DryStepper::Soft { contact_time }, dt, warnings))
            }
        }
    }

    /// One line for the log naming the model and its step.
    pub fn describe(&self, dt: f64) -> String {
        match self {
            DryStepper::Soft { contact_time } => format!(
                "soft-sphere DEM; dt = {dt:.4e} s = {:.4} t_c (t_c = {contact_time:.4e} s)",
                dt / contact_time
            ),
            DryStepper::Hard { contact, .. } => {
                let scheme = match contact.method {
                    Method::Cocd => {
                        let solver = contact.conic_solver.name();
                        format!("COCD (conic program per step, {solver})")
                    }
                    Method::Nscd { restitution } => {
                        format!("NSCD (Gauss-Seidel, restitution {restitution})")
                    }
                };
                format!(
                    "hard contact, {scheme}; dt = {dt:.4e} s, tolerance {:.1e}, candidate threshold {:.3e} m",
                    contact.tolerance, contact.threshold
                )
            }
        }
    }

    /// Advances one step; returns the diagnosis if the run must stop.
    pub fn step(&mut self, system: &mut DemSystem, dt: f64, overlap_limit: f64) -> Option<String> {
        match self {
            DryStepper::Soft { contact_time } => {
                let diagnostics = system.step(dt);
                if diagnostics.non_finite {
                    Some(format!(
                        "unstable at t = {:.6e} s (step {}): a position or velocity is not finite; \
                         reduce time.dt (now {:.3} t_c)",
                        system.time,
                        system.steps,
                        dt / *contact_time
                    ))
                } else if diagnostics.max_overlap_ratio > overlap_limit {
                    Some(format!(
                        "unstable at t = {:.6e} s (step {}): overlap reached {:.3} of a radius, beyond \
                         time.overlap_limit = {overlap_limit}; the contacts are too soft for the load or \
                         the time step is too large (dt = {:.3} t_c)",
                        system.time,
                        system.steps,
                        diagnostics.max_overlap_ratio,
                        dt / *contact_time
                    ))
                } else {
                    None
                }
            }
            DryStepper::Hard { contact, record } => match contact.step(system, dt) {
                Err(why) => Some(format!(
                    "hard-contact step failed at t = {:.6e} s (step {}): {why}; {}",
                    system.time,
                    system.steps + 1,
                    failed_step_advice(contact.method, system)
                )),
                Ok(report) => {
                    record.add(&report);
                    if report.fell_back && record.first_fallback.is_none() {
                        record.first_fallback = Some(format!(
                            "step {}, t = {:.6e} s: {}",
                            system.steps,
                            system.time,
                            contact
                                .last_fallback
                                .as_deref()
                                .unwrap_or("(no reason given)")
                        ));
                    }
                    if report.non_finite {
                        Some(format!(
                            "unstable at t = {:.6e} s (step {}): a position or velocity is not finite",
                            system.time, system.steps
                        ))
                    } else if 2.0 * report.penetration > overlap_limit {
                        Some(format!(
                            "at t = {:.6e} s (step {}) grains overlap by {:.3} of a radius, beyond \
                             time.overlap_limit = {overlap_limit}: the solver did not hold the \
                             non-penetration constraint (tighten contact.tolerance)",
                            system.time,
                            system.steps,
                            2.0 * report.penetration
                        ))
                    } else {
                        None
                    }
                }
            },
        }
    }

    /// The soft contact time (None for hard contact).
    pub fn contact_time(&self) -> Option<f64> {
        match self {
            DryStepper::Soft { contact_time } => Some(*contact_time),
            DryStepper::Hard { .. } => None,
        }
    }

    /// Saves the warm start and the record of hard contact (nothing for
    /// soft contact: its state is the grains').
    pub fn save_state(&self, state: &mut State) {
        if let DryStepper::Hard { contact, record } = self {
            contact.save_state(state);
            state.put_value("hard_contact.record", record);
            state.put_u64("hard_contact.extra_programs", record.extra_programs);
            state.put_value("hard_contact.first_fallback", &record.first_fallback);
        }
    }

    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        if let DryStepper::Hard { contact, record } = self {
            contact.restore_state(state)?;
            *record = state.take_value("hard_contact.record")?;
            if state.contains("hard_contact.extra_programs") {
                record.extra_programs = state.take_u64("hard_contact.extra_programs")?;
            }
            if state.contains("hard_contact.first_fallback") {
                record.first_fallback = state.take_value("hard_contact.first_fallback")?;
            }
        }
        Ok(())
    }

    /// The hard-contact metrics of `summary.json` (empty for soft contact).
    pub fn metrics(&self) -> Map<String, Value> {
        match self {
            DryStepper::Soft { .. } => Map::new(),
            DryStepper::Hard { record, .. } => record.metrics(),
        }
    }
}

/// What to try after a hard-contact step failed on `system` (left at the
/// start of the step). COCD's convexified cone asks an overlapping pair to
/// separate at the overlap's rate plus μ |v_t| (Martin et al. 2022, eq. 9);
/// a grain wedged with overlaps into a pocket steeper than atan(1/μ), such
/// as the hole of a square bed of glued grains at μ = 0.9, cannot, and the
/// program has no solution at any step or tolerance.
fn failed_step_advice(method: Method, system: &DemSystem) -> String {
    let overlap = grainflow_contact::certificate::largest_overlap(system, 1.0);
    let p = &system.particles;
    let mean_radius = p.radius[..p.n_owned].iter().sum::<f64>() / p.n_owned.max(1) as f64;
    let frictional = system.law.friction > 0.0 || system.walls.iter().any(|w| w.friction > 0.0);
    if method == Method::Cocd && overlap > 0.0 && frictional {
        format!(
            "the step started with grains overlapping by up to {overlap:.3e} m ({:.2e} of the mean \
             radius): COCD's convexified cone asks overlapping grains to part at their overlap's \
             rate plus μ |v_t|, which a grain wedged into a pocket of its neighbours cannot do; \
             start from a deposit without overlaps (made with hard contact, or with the radii \
             shrunk by the overlap)",
            overlap / mean_radius
        )
    } else {
        "try a smaller time.dt or a looser contact.tolerance".into()
    }
}
