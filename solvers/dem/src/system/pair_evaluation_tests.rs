use super::*;
use crate::contact_law::{NormalCalibration, NormalStiffness};
use rand::{Rng, SeedableRng};

/// Grains poured into a box periodic along x (ghost pairs) with a floor,
/// run long enough for rebuilds, reordering and sliding contacts. Each
/// pair is evaluated once (pass 1) and handed to its partner (pass 2);
/// the result must equal an independent evaluation of every contact
/// from its owner's side with the carried history, and Newton's third
/// law must hold exactly for pairs of owned grains.
#[test]
fn pairs_evaluated_once_match_an_evaluation_from_each_side() {
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::zeros(),
        upper: Vec3::new(0.04, 0.04, 0.2),
        periodic: [true, false, false],
        gravity: Vec3::new(0.0, 0.0, -9.81),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.5,
        rolling_friction: 0.05,
    };
    let walls = vec![
        PlaneWall {
            name: "floor".into(),
            point: Vec3::zeros(),
            normal: Vec3::z(),
            friction: 0.5,
            remove_at: None,
            two_sided: false,
        },
        PlaneWall {
            name: "front".into(),
            point: Vec3::zeros(),
            normal: Vec3::y(),
            friction: 0.5,
            remove_at: None,
            two_sided: false,
        },
        PlaneWall {
            name: "back".into(),
            point: Vec3::new(0.0, 0.04, 0.0),
            normal: -Vec3::y(),
            friction: 0.5,
            remove_at: None,
            two_sided: false,
        },
    ];
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let new: Vec<NewParticle> = (0..400)
        .map(|k| NewParticle {
            position: Vec3::new(
                0.004 + 0.008 * (k % 5) as f64,
                0.004 + 0.008 * ((k / 5) % 5) as f64,
                0.004 + 0.008 * (k / 25) as f64,
            ),
            velocity: Vec3::new(rng.gen::<f64>() - 0.5, rng.gen::<f64>() - 0.5, 0.0) * 0.2,
            angular_velocity: Vec3::zeros(),
            radius: 0.0025 + 0.001 * rng.gen::<f64>(),
            density: 2500.0,
            fixed: false,
        })
        .collect();
    let mut system = DemSystem::new(domain, law, walls, 5e-4);
    system.add_particles(&new);
    let dt = 5e-6;
    for _ in 0..40_000 {
        system.step(dt);
    }
    assert!(
        system.neighbours.builds > 10,
        "{}",
        system.neighbours.builds
    );
    let diagnostics = system.compute_forces(0.0);
    assert!(diagnostics.particle_contacts > 300, "{diagnostics:?}");

    let p = &system.particles;
    let n = p.n_owned;
    let scale = (0..n).map(|i| p.force[i].norm()).fold(0.0, f64::max);
    let mut ghost_pairs = 0;
    for i in 0..n {
        let mut expected = p.mass[i] * system.domain.gravity;
        for (_, contact) in system.wall_contacts_of(i) {
            expected += contact.force;
        }
        for contact in system.particle_contacts_of(i) {
            expected += contact.force;
            ghost_pairs += usize::from(contact.partner >= n);
        }
        let error = (p.force[i] - expected).norm() / scale;
        assert!(
            error < 1e-12,
            "particle {i}: relative force error {error:e}"
        );
    }
    assert!(
        ghost_pairs > 0,
        "the scene must test pairs across the periodic edge"
    );
    // Third law: the owned grains' contact forces cancel exactly.
    let total: Vec3 = (0..n)
        .flat_map(|i| system.particle_contacts_of(i))
        .filter(|c| c.partner < n)
        .map(|c| c.force)
        .sum();
    assert!(total.norm() / scale < 1e-12, "{total:?}");

    // Shifting the scene along its periodic direction reorders the
    // grains at the next build (many pairs swap their upper and lower
    // sides): every open contact keeps its history, seen from each side.
    let histories = |system: &DemSystem| {
        let p = &system.particles;
        let mut seen = std::collections::BTreeMap::new();
        for i in 0..p.n_owned {
            for e in system.neighbours.range(i) {
                let j = system.neighbours.partner[e] as usize;
                let history = system.neighbours.history_of(e);
                if history != Vec3::zeros() {
                    seen.insert((p.id[i], p.id[j]), (history, j >= p.n_owned));
                }
            }
        }
        seen
    };
    let before = histories(&system);
    let order_before = system.particles.id.clone();
    for x in &mut system.particles.position {
        x.x += 0.4 * 0.04;
    }
    system.rebuild();
    assert_ne!(
        order_before, system.particles.id,
        "the shift must reorder the grains"
    );
    let after = histories(&system);
    assert!(before.len() > 300, "{}", before.len());
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>()
    );
    // Exact for pairs of owned grains; a pair across the periodic edge
    // is evaluated from both sides, whose branch vectors differ by the
    // round-off of adding the period (amplified in ξ by the projection
    // on the tangent plane).
    let mut exact = 0;
    for (pair, &(history, ghost_before)) in &before {
        let (moved, ghost_after) = after[pair];
        if !ghost_before && !ghost_after {
            assert_eq!(moved, history, "{pair:?}");
            exact += 1;
        } else {
            let error = (moved - history).norm() / history.norm();
            assert!(error < 1e-6, "{pair:?}: {history:?} became {moved:?}");
        }
    }
    assert!(exact > 200, "{exact}");
}
