//! The few lines a person reads at the end of a run: how it ended, what it
//! cost and where the time went, the case's metrics beside their
//! references with the relative error, and where the outputs are. The
//! whole record stays in `summary.json` (and `grainflow run --json` prints
//! it, for scripts).

use crate::case::{AnalysisSection, Case};
use serde_json::Value;
use std::fmt::Write;
use std::path::Path;

/// A metric and the value it is measured against.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    pub metric: String,
    pub value: f64,
    pub reference: f64,
    /// Where the reference comes from.
    pub source: String,
}

impl Comparison {
    pub fn relative_error(&self) -> f64 {
        (self.value - self.reference) / self.reference
    }
}

/// The metrics of `summary` that have a reference: set by the case (the
/// restitution e_n a collision should give back) or computed beside them
/// by the analysis (Schiller–Naumann, the added mass, the sliding law), or
/// the published law of the benchmark (the 2D DEM runout of Kumar 2015).
pub fn comparisons(case: &Case, summary: &Value) -> Vec<Comparison> {
    let metrics = &summary["metrics"];
    let number = |name: &str| metrics.get(name).and_then(Value::as_f64);
    let mut found = Vec::new();
    let mut compare = |metric: &str, reference: Option<f64>, source: &str| {
        if let (Some(value), Some(reference)) = (number(metric), reference) {
            found.push(Comparison {
                metric: metric.to_string(),
                value,
                reference,
                source: source.to_string(),
            });
        }
    };
    let restitution = case.contact.as_ref().and_then(|c| c.restitution);
    match &case.analysis {
        Some(AnalysisSection::BinaryCollision) => {
            compare("restitution", restitution, "contact.restitution");
            compare(
                "psi_sliding_offset",
                number("psi_sliding_offset_theory"),
                "the sliding law 3.5 mu (1 + e_n)",
            );
        }
        Some(AnalysisSection::Bouncing) => {
            compare("restitution", restitution, "contact.restitution");
            compare(
                "energy_ratio_per_impact",
                restitution.map(|e| e * e),
                "e_n^2",
            );
        }
        Some(AnalysisSection::ColumnCollapse { .. }) => {
            let kumar = number("aspect_ratio").map(|a| {
                if a < 2.3 {
                    1.67 * a
                } else {
                    2.5 * a.powf(2.0 / 3.0)
                }
            });
            compare("runout", kumar, "2D DEM of Kumar (2015)");
        }
        _ => {}
    }
    compare(
        "terminal_reynolds",
        number("schiller_naumann_reynolds"),
        "Schiller-Naumann",
    );
    compare(
        "terminal_reynolds",
        number("drag_curve_reynolds"),
        "the standard drag curve (Clift, Grace & Weber)",
    );
    compare(
        "initial_acceleration",
        number("initial_acceleration_reference"),
        "buoyant weight over the mass with its added mass",
    );
    found
}

/// The summary of a finished run written to `out`, in a few lines.
pub fn text(case: &Case, summary: &Value, out: &Path) -> String {
    let mut text = String::new();
    let number = |name: &str| summary.get(name).and_then(Value::as_f64);
    let status = summary["status"].as_str().unwrap_or("?");
    let reason = summary["stop_reason"].as_str().unwrap_or("");
    let _ = writeln!(text, "{status}: {reason}");
    let wall = number("wall_seconds").unwrap_or(0.0);
    let rate = match (
        number("particle_steps_per_second"),
        number("cell_steps_per_second"),
    ) {
        (Some(r), _) => format!(", {r:.3e} particle-steps/s"),
        (None, Some(r)) => format!(", {r:.3e} cell-steps/s"),
        _ => String::new(),
    };
    let _ = writeln!(
        text,
        "  {} steps to t = {:.4e} s in {}{rate}",
        summary["steps"].as_u64().unwrap_or(0),
        number("simulated_time").unwrap_or(0.0),
        duration(wall)
    );
    let parts: Vec<(&str, f64)> = [
        ("flow", "seconds_flow"),
        ("forcing", "seconds_forcing"),
        ("loads", "seconds_loads"),
        ("DEM", "seconds_dem"),
    ]
    .iter()
    .filter_map(|&(name, key)| number(key).map(|s| (name, s)))
    .collect();
    if !parts.is_empty() && wall > 0.0 {
        let split: Vec<String> = parts
            .iter()
            .map(|(name, s)| format!("{name} {:.0} %", 100.0 * s / wall))
            .collect();
        let _ = writeln!(text, "  wall time: {}", split.join(", "));
    }
    let compared = comparisons(case, summary);
    for c in &compared {
        let _ = writeln!(
            text,
            "  {} = {:.5} against {:.5} ({}): {:+.2} %",
            c.metric,
            c.value,
            c.reference,
            c.source,
            100.0 * c.relative_error()
        );
    }
    let others: Vec<String> = summary["metrics"]
        .as_object()
        .into_iter()
        .flatten()
        .filter(|(name, _)| !compared.iter().any(|c| &c.metric == *name))
        .filter_map(|(name, value)| value.as_f64().map(|v| format!("{name} {v:.5}")))
        .collect();
    if !others.is_empty() {
        let _ = writeln!(text, "  metrics: {}", others.join(", "));
    }
    if let Some(first) = summary["metrics"]["first_fallback"].as_str() {
        let _ = writeln!(
            text,
            "  {} step(s) taken over where the chosen solver failed (grainflow's projected \
             gradient by its interior point, its interior point by Clarabel); the first at {first}",
            summary["metrics"]["fallback_steps"]
        );
    }
    if let Some(unconverged) = summary["metrics"]["unconverged_steps"]
        .as_u64()
        .filter(|&n| n > 0)
    {
        // A step stopped at its iteration cap: its forces are wherever the
        // solver stood, and a flow can stop or run on for that alone (NSCD
        // stopped a layer on a 22° slope at a long step, docs/validation.md
        // §11, the paper's 3D step).
        let _ = writeln!(
            text,
            "  warning: {unconverged} of {} step(s) stopped at contact.max_iterations before \
             reaching contact.tolerance (largest complementarity {:.1e}): their contact forces \
             are where the solver stood, not the contact law's; shorten time.dt or raise \
             contact.max_iterations",
            summary["steps"],
            summary["metrics"]["max_complementarity"]
                .as_f64()
                .unwrap_or(f64::NAN)
        );
    }
    let _ = writeln!(
        text,
        "  outputs in {} (summary.json holds all of it)",
        out.display()
    );
    text
}

/// `seconds` as "1 h 02 min", "3 min 05 s" or "12.3 s".
fn duration(seconds: f64) -> String {
    if seconds >= 3600.0 {
        let minutes = (seconds / 60.0).round() as u64;
        format!("{} h {:02} min", minutes / 60, minutes % 60)
    } else if seconds >= 60.0 {
        let s = seconds.round() as u64;
        format!("{} min {:02} s", s / 60, s % 60)
    } else if seconds >= 1.0 {
        format!("{seconds:.1} s")
    } else {
        format!("{seconds:.3} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn a_collision_reads_its_restitution_against_the_case_s() {
        let case = crate::case::Case::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/binary_collision.toml"),
            &[],
        )
        .unwrap();
        let restitution = case.contact.as_ref().unwrap().restitution.unwrap();
        let summary = json!({
            "status": "ok", "stop_reason": "end time reached", "steps": 1000,
            "simulated_time": 0.01, "wall_seconds": 75.0,
            "particle_steps_per_second": 2.0e6,
            "metrics": {"restitution": restitution * 0.99, "collisions": 21.0}
        });
        let text = text(&case, &summary, Path::new("out/binary_collision"));
        assert!(text.starts_with("ok: end time reached\n"), "{text}");
        assert!(
            text.contains("in 1 min 15 s, 2.000e6 particle-steps/s"),
            "{text}"
        );
        assert!(
            text.contains(&format!(
                "restitution = {:.5} against {restitution:.5} (contact.restitution): -1.00 %",
                restitution * 0.99
            )),
            "{text}"
        );
        assert!(text.contains("metrics: collisions 21.00000"), "{text}");
        assert!(text.contains("outputs in out/binary_collision"), "{text}");
    }
}
