//! The same granular column in 2D and in a 3D channel (Martin et al. 2022,
//! §4.2): R0 × H0 = 20 × 14 cm released on a rough bed inclined by 22°,
//! μ = 0.3 with the grains and the walls, the soft DEM in both. In 3D the
//! column spans a channel 20 cm wide between two side walls, which take
//! momentum from the flow that a 2D scene has no way to lose; the paper
//! found the 2D front 32 % ahead at t = 1 s at 22° (d = 4 mm).
//!
//! The scene of the test is the coarse one of `docs/validation.md` §11:
//! d = 16 mm ± 10 % (1,491 spheres in 3D, 111 discs in 2D), whose
//! deposits are `cases/data/channel_collapse_3d_coarse.csv` and
//! `column_2d_coarse.csv`.

mod common;

use common::{metric, run};

const SLOPE_DEGREES: f64 = 22.0;

/// Gravity tilted by the slope in the channel's frame, `extra` added
/// along the slope (an ensemble's perturbation).
fn gravity(dimension: usize, extra: f64) -> String {
    let theta = SLOPE_DEGREES.to_radians();
    let (along, normal) = (9.81 * theta.sin() + extra, -9.81 * theta.cos());
    match dimension {
        2 => format!("domain.gravity=[{along},{normal}]"),
        _ => format!("domain.gravity=[{along},0.0,{normal}]"),
    }
}

/// The coarse grains' settings shared by both scenes: d = 16 mm, the soft
/// contact of the 3D runs with t_c scaled with d, μ = 0.3, to t = 1 s.
const COARSE: [&str; 6] = [
    "particles.radius=8e-3",
    "particles.block[0].spacing=0.0176",
    "contact.model=\"soft\"",
    "contact.friction=0.3",
    "contact.contact_time=2e-4",
    "time.end=1.0",
];

/// r_f/R0 at t = 1 s in the 3D channel.
fn front_in_3d() -> f64 {
    let gravity = gravity(3, 0.0);
    let mut sets = COARSE.to_vec();
    sets.extend([
        gravity.as_str(),
        "domain.upper=[1.5,0.2,0.6]",
        "particles.block[0].lower=[0.0088,0.0,0.0]",
        "particles.block[0].upper=[1.5,0.2,0.0176]",
        "particles.block[1].path=\"data/channel_collapse_3d_coarse.csv\"",
        "walls[2].point=[1.5,0.0,0.0]",
    ]);
    let (summary, _dir) = run("channel_collapse_3d.toml", &sets);
    metric(&summary, "final_front") / metric(&summary, "initial_length")
}

/// r_f/R0 at t = 1 s in 2D, gravity perturbed by `extra` along the slope.
fn front_in_2d(extra: f64) -> f64 {
    let gravity = gravity(2, extra);
    let mut sets = COARSE.to_vec();
    sets.extend([
        gravity.as_str(),
        "particles.block[0].upper=[2.5,0.0176]",
        "particles.block[1].path=\"data/column_2d_coarse.csv\"",
        "contact.restitution=0.5",
        "time.dt=1e-5",
    ]);
    let (summary, _dir) = run("erodible_bed_2d.toml", &sets);
    metric(&summary, "final_front") / metric(&summary, "initial_length")
}

/// At 22° the 2D front runs ahead of the 3D one. A 2D run of 111 discs is
/// one draw of the collapse's chaos (r_f/R0 from 4.9 to 5.4 at 1 s under
/// gravity perturbed in its seventh digit), so the 2D front is the mean
/// of four such runs. Measured: 2D 1.24 times the 3D front (the paper:
/// 1.32 at d = 4 mm; 1.20 at d = 8 mm, §11). Asserted: between 1.10 and
/// 1.40, the effect's sign and size, not its digits.
#[test]
fn a_column_in_a_3d_channel_at_22_degrees_runs_behind_the_same_column_in_2d() {
    let (three, two) = std::thread::scope(|scope| {
        let three = scope.spawn(front_in_3d);
        let runs: Vec<f64> = (0..4).map(|k| front_in_2d(1e-7 * k as f64)).collect();
        (three.join().unwrap(), runs)
    });
    let mean = two.iter().sum::<f64>() / two.len() as f64;
    let ratio = mean / three;
    println!("r_f/R0 at 1 s: 3D {three:.3}, 2D {two:.3?} (mean {mean:.3}), ratio {ratio:.3}");
    assert!((1.10..=1.40).contains(&ratio), "{ratio}");
}
