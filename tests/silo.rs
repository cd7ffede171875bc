//! The silo of Izard et al. 2014, section 3.3, reduced (cases/silo_small.toml):
//! coarse-grained stresses against force balance, and the mobilised wall
//! friction against the paper's direct measurement.

mod common;

use common::{metric, run};

fn profile(dir: &std::path::Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(dir.join("silo_profile.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect()
}

#[test]
fn with_frictionless_walls_the_vertical_stress_is_the_weight_above() {
    // Plain frictionless side walls, no glued grains, a ~0.3 m column: the
    // vertical stress at z must carry the weight of the grains above,
    // σ_zz(z) = ρ_p g ∫_z^h φ dz (φ the measured solid fraction).
    let (_summary, dir) = run(
        "silo_small.toml",
        &[
            "particles.block=[{kind = \"lattice\", lower = [0.0055, 0.0055, 0.0], upper = [0.0945, 0.0945, 0.6], spacing = 0.0112, jitter = 0.5}]",
            "contact.wall_friction=0.0",
            "domain.upper=[0.1, 0.1, 0.65]",
            "time.dt_over_contact_time=0.1",
            "output.particles=false",
        ],
    );
    let rows = profile(dir.path());
    let slab = rows[1][0] - rows[0][0];
    let weight_density = 1317.0 * 9.81;
    // Weight per unit area above the middle of each slab.
    let mut above = vec![0.0; rows.len()];
    let mut sum = 0.0;
    for k in (0..rows.len()).rev() {
        above[k] = sum + 0.5 * rows[k][4] * slab * weight_density;
        sum += rows[k][4] * slab * weight_density;
    }
    let height = rows.iter().filter(|r| r[4] > 0.3).count() as f64 * slab;
    let mut checked = 0;
    for (k, r) in rows.iter().enumerate() {
        let z = r[0];
        if z < 0.2 * height || z > 0.8 * height {
            continue;
        }
        let error = (r[2] - above[k]) / above[k];
        println!(
            "z = {z:.3}: σ_zz = {:.1} Pa, weight above {:.1} Pa ({:+.1} %)",
            r[2],
            above[k],
            100.0 * error
        );
        assert!(
            error.abs() < 0.15,
            "z = {z}: σ_zz = {} vs {}",
            r[2],
            above[k]
        );
        checked += 1;
    }
    assert!(checked >= 5);
}

#[test]
fn rough_walls_carry_the_column_with_the_published_wall_friction() {
    // Walls lined with glued grains: the mobilised wall friction times the
    // measured redirection K is the direct estimate of f_w K, which the
    // paper measured as 0.38 ± 0.11.
    let (summary, dir) = run(
        "silo_small.toml",
        &["time.dt_over_contact_time=0.1", "output.particles=false"],
    );
    let direct = metric(&summary, "janssen_fwK_direct");
    println!("{}", summary["metrics"]);
    assert!(
        (0.38 - 0.11..=0.38 + 0.11).contains(&direct),
        "direct f_w K = {direct}"
    );
    // The walls carry weight: at the bottom of the fitted region the vertical
    // stress is below the weight of the column above.
    let rows = profile(dir.path());
    let slab = rows[1][0] - rows[0][0];
    let weight: f64 = rows.iter().map(|r| r[4] * slab * 1317.0 * 9.81).sum();
    let bottom = rows.iter().find(|r| r[0] > 0.2).unwrap();
    assert!(
        bottom[2] < 0.6 * weight,
        "σ_zz = {} at z = {}, weight {}",
        bottom[2],
        bottom[0],
        weight
    );
}
