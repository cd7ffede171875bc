use super::*;
use crate::contact_law::{NormalCalibration, NormalStiffness};
use crate::particles::NewParticle;
use rand::{Rng, SeedableRng};
use std::collections::BTreeSet;

/// Random spheres in a box periodic along x and y: the pair list holds
/// exactly the pairs within r_i + r_j + skin under the minimum image.
#[test]
fn the_pair_list_matches_a_brute_force_search_with_periodic_images() {
    let domain = Domain {
        dimension: Dimension::Three,
        lower: Vec3::zeros(),
        upper: Vec3::new(0.1, 0.08, 0.12),
        periodic: [true, true, false],
        gravity: Vec3::zeros(),
    };
    let law = ContactLaw {
        normal: NormalStiffness::from_restitution(0.5, 1e-4, NormalCalibration::Exact),
        tangential_ratio: 0.2,
        friction: 0.5,
        rolling_friction: 0.0,
    };
    let skin = 1e-3;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
    let new: Vec<NewParticle> = (0..1500)
        .map(|_| NewParticle {
            position: Vec3::new(
                rng.gen::<f64>() * 0.1,
                rng.gen::<f64>() * 0.08,
                rng.gen::<f64>() * 0.12,
            ),
            velocity: Vec3::zeros(),
            angular_velocity: Vec3::zeros(),
            radius: 0.003 + 0.002 * rng.gen::<f64>(),
            density: 2500.0,
            fixed: false,
        })
        .collect();
    let mut system = DemSystem::new(domain.clone(), law, Vec::new(), skin);
    system.add_particles(&new);

    let p = &system.particles;
    let mut listed = BTreeSet::new();
    let mut entries = Vec::new();
    for i in 0..p.n_owned {
        for e in system.neighbours.range(i) {
            let j = system.neighbours.partner[e] as usize;
            entries.push((p.id[i], p.id[j]));
            listed.insert((p.id[i].min(p.id[j]), p.id[i].max(p.id[j])));
        }
    }
    // A full list: each pair from both sides, exactly once each.
    let unique: BTreeSet<(u64, u64)> = entries.iter().copied().collect();
    assert_eq!(unique.len(), entries.len());
    assert_eq!(entries.len(), 2 * listed.len());
    let mut expected = BTreeSet::new();
    let extent = domain.extent();
    for a in 0..new.len() {
        for b in a + 1..new.len() {
            let mut d = new[a].position - new[b].position;
            for axis in 0..2 {
                d[axis] -= extent[axis] * (d[axis] / extent[axis]).round();
            }
            if d.norm() < new[a].radius + new[b].radius + skin {
                expected.insert((a as u64, b as u64));
            }
        }
    }
    assert!(expected.len() > 1000);
    assert_eq!(listed, expected);
}
