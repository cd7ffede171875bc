//! Grains in a fluid run through the whole program: the falling sphere
//! (Izard et al. 2014, section 3.1) and the bouncing sphere (section 4.1)
//! reduced, the output contract, and the refusals of bad coupled tables.

mod common;

use common::run_cli;

#[test]
fn bad_coupled_tables_are_refused_with_the_key_and_nothing_is_written() {
    for (case, assignment, key) in [
        (
            "falling_sphere.toml",
            "coupling.formulation=\"loose\"",
            "coupling.formulation",
        ),
        (
            "bouncing_sphere.toml",
            "lubrication.roughness=-1.0",
            "lubrication.roughness",
        ),
        (
            "bouncing_sphere.toml",
            "lubrication.range=2.0",
            "lubrication.range",
        ),
        (
            "falling_sphere.toml",
            "analysis.kind=\"bouncing\"",
            "analysis.kind",
        ),
        // The paper's load fails below a density ratio of 1.7.
        (
            "falling_sphere.toml",
            "coupling.formulation=\"rigid_inner_fluid\"",
            "rigid_inner_fluid",
        ),
        // No fluid: lubrication has nothing to act in.
        (
            "bouncing_dry.toml",
            "lubrication.roughness=1e-3",
            "lubrication",
        ),
    ] {
        let mut overrides = vec![assignment];
        if assignment.contains("rigid_inner_fluid") {
            overrides.push("particles.density=1500.0");
        }
        let (code, stderr, written) = run_cli(case, &overrides);
        assert_ne!(code, Some(0), "{assignment}");
        assert!(stderr.contains(key), "{assignment}: {stderr}");
        assert!(!written, "{assignment}: output written");
    }
}
