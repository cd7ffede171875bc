//! Which changes to a case a resumed run accepts. A run resumes the state
//! of the case that wrote its checkpoint; only keys that do not enter the
//! physics of the steps to come may differ: when it ends, what it writes
//! and how often, when it checkpoints, its wall-clock limit, its threads
//! and how it is shared among ranks (results do not depend on them beyond
//! round-off), and how a hard-contact step's program is solved (the same
//! solution to the solver's tolerance). Any other change is refused,
//! naming the keys, since it would silently change the physics.

/// The keys a resumed run may change, and the sections it may change
/// whole.
pub const SAFE_KEYS: &[&str] = &[
    "time.end",
    "time.wall_limit",
    "output.interval",
    "output.tracked_interval",
    "output.particles",
    "output.fields",
    "output.format",
    "parallel.threads",
    "parallel.process_grid",
    "parallel.shared_memory",
    // Which code solves a hard-contact step's program, and which listed
    // pairs enter it: the same program's solution, to the tolerance.
    "contact.conic_solver",
    "contact.candidates",
];
pub const SAFE_SECTIONS: &[&str] = &["checkpoint"];

fn is_safe(key: &str) -> bool {
    // An element of an array key (`parallel.process_grid[0]`) is the key's.
    let key = key.split('[').next().unwrap_or(key);
    SAFE_KEYS.contains(&key)
        || SAFE_SECTIONS
            .iter()
            .any(|s| key == *s || key.starts_with(&format!("{s}.")))
}

/// Flattens a TOML value into `dotted.key = value` pairs (array elements as
/// `key[i]`).
fn flatten(prefix: &str, value: &toml::Value, out: &mut Vec<(String, String)>) {
    match value {
        toml::Value::Table(table) => {
            for (key, value) in table {
                let key = if prefix.is_empty() {
                    key.clone()
                } else {
                    format!("{prefix}.{key}")
                };
                flatten(&key, value, out);
            }
        }
        toml::Value::Array(items) => {
            if items.is_empty() {
                out.push((prefix.to_string(), "[]".into()));
            }
            for (i, item) in items.iter().enumerate() {
                flatten(&format!("{prefix}[{i}]"), item, out);
            }
        }
        other => out.push((prefix.to_string(), other.to_string())),
    }
}

/// The keys whose values differ between two resolved cases (present in
/// one only included), sorted.
pub fn changed_keys(saved: &str, now: &str) -> Result<Vec<String>, String> {
    let parse = |text: &str| -> Result<Vec<(String, String)>, String> {
        let value: toml::Value = toml::from_str(text).map_err(|e| e.to_string())?;
        let mut pairs = Vec::new();
        flatten("", &value, &mut pairs);
        Ok(pairs)
    };
    let saved: std::collections::BTreeMap<_, _> = parse(saved)?.into_iter().collect();
    let now: std::collections::BTreeMap<_, _> = parse(now)?.into_iter().collect();
    let mut keys: Vec<String> = saved
        .keys()
        .chain(now.keys())
        .filter(|k| saved.get(*k) != now.get(*k))
        .cloned()
        .collect();
    keys.sort();
    keys.dedup();
    Ok(keys)
}

/// Refuses a case that changes a key a resumed run cannot change; the
/// error names the keys and what may change.
pub fn check(saved: &str, now: &str) -> Result<Vec<String>, String> {
    let changed = changed_keys(saved, now)
        .map_err(|e| format!("the checkpoint's case does not read back: {e}"))?;
    let refused: Vec<&String> = changed.iter().filter(|k| !is_safe(k)).collect();
    if !refused.is_empty() {
        let names: Vec<&str> = refused.iter().map(|k| k.as_str()).collect();
        return Err(format!(
            "the case differs from the checkpoint's in {}: a resumed run continues the \
             checkpoint's physics; allowed to change: {}, and the [checkpoint] section",
            names.join(", "),
            SAFE_KEYS.join(", ")
        ));
    }
    Ok(changed)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CASE: &str = "[time]\nend = 1.0\ndt = 1e-3\n[output]\ninterval = 0.1\n\
                        [[walls]]\nname = \"floor\"\nfriction = 0.5\n";

    #[test]
    fn the_end_time_and_the_outputs_may_change() {
        let now = CASE
            .replace("end = 1.0", "end = 2.0")
            .replace("interval = 0.1", "interval = 0.05")
            + "[checkpoint]\nsteps = 100\n";
        let changed = check(CASE, &now).unwrap();
        assert_eq!(changed, ["checkpoint.steps", "output.interval", "time.end"]);
    }

    #[test]
    fn a_change_to_the_physics_is_refused_naming_the_key() {
        let now = CASE.replace("dt = 1e-3", "dt = 2e-3").replace("0.5", "0.6");
        let error = check(CASE, &now).unwrap_err();
        assert!(
            error.contains("time.dt") && error.contains("walls[0].friction"),
            "{error}"
        );
        let added = CASE.to_string() + "[lubrication]\nroughness = 1e-5\n";
        assert!(check(CASE, &added)
            .unwrap_err()
            .contains("lubrication.roughness"));
    }
}
