//! Candidate contacts and the bodies they move (Martin et al. 2022, section
//! 2 and 3.3).
//!
//! A candidate α joins grain i to grain j or to a wall when their gap D_α
//! is below the threshold D. Its normal n points from j to i; the contact
//! points are C_i = c_i − r_i n and C_j = c_j + r_j n, so the relative
//! velocity of eq. 2 is
//!   A_α u = v_i + ω_i × (−r_i n) − v_j − ω_j × (r_j n).
//! An impulse P on i (and −P on j) changes v_i by P/m_i, ω_i by
//! −r_i (n × P)/J_i, v_j by −P/m_j and ω_j by −r_j (n × P)/J_j (the
//! transpose A_αᵀ of eq. 1).
//!
//! The unknowns are the moving grains that have at least one candidate
//! ("bodies", one column each); glued grains and walls have infinite mass
//! and do not move. A periodic image stands for its source grain.
//!
//! On several ranks a rank lists the pairs of its own grains, and a pair
//! with a copy (ghost) of another rank's grain is held by the rank of the
//! lower id: every pair is in exactly one rank's set. The copies a rank's
//! pairs touch are bodies there too ([`Bodies::owned`] counts the columns
//! of its own grains, which come first).

use grainflow_core::{Dimension, Vec3};
use grainflow_dem::DemSystem;

/// Column of a side that does not move (a wall or a glued grain).
pub const STATIC: u32 = u32::MAX;

/// What grain i of a contact touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Partner {
    /// Local grain: owned (the source, for a periodic image of an owned
    /// grain), or the ghost copy of another rank's grain.
    Grain(u32),
    Wall(u32),
}

/// Candidate contacts as flat arrays.
#[derive(Clone, Debug, Default)]
pub struct ContactSet {
    /// Owned grain i of each contact.
    pub grain: Vec<u32>,
    pub partner: Vec<Partner>,
    /// Columns of i and j among the bodies (`STATIC` if it does not move).
    pub body_i: Vec<u32>,
    pub body_j: Vec<u32>,
    /// Unit normal from j to i.
    pub normal: Vec<Vec3>,
    /// Gap D_α(c^k) between the surfaces (negative: overlap).
    pub gap: Vec<f64>,
    /// Lever arms r_i, r_j (0 for a wall).
    pub lever_i: Vec<f64>,
    pub lever_j: Vec<f64>,
    /// Coulomb coefficient μ of the pair.
    pub friction: Vec<f64>,
}

impl ContactSet {
    pub fn len(&self) -> usize {
        self.grain.len()
    }

    pub fn is_empty(&self) -> bool {
        self.grain.is_empty()
    }

    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        grain: usize,
        partner: Partner,
        normal: Vec3,
        gap: f64,
        lever_i: f64,
        lever_j: f64,
        friction: f64,
    ) {
        self.grain.push(grain as u32);
        self.partner.push(partner);
        self.normal.push(normal);
        self.gap.push(gap);
        self.lever_i.push(lever_i);
        self.lever_j.push(lever_j);
        self.friction.push(friction);
    }

    /// The contacts `a` with `keep[a]`, in order, without bodies.
    pub fn subset(&self, keep: &[bool]) -> ContactSet {
        let mut kept = ContactSet::default();
        for a in (0..self.len()).filter(|&a| keep[a]) {
            kept.push(
                self.grain[a] as usize,
                self.partner[a],
                self.normal[a],
                self.gap[a],
                self.lever_i[a],
                self.lever_j[a],
                self.friction[a],
            );
        }
        kept
    }

    /// Relative velocity A_α u at the contact points, u by body column.
    #[inline]
    pub fn relative_velocity(&self, a: usize, velocity: &[Vec3], spin: &[Vec3]) -> Vec3 {
        let motion =
            |body: u32| (body != STATIC).then(|| (velocity[body as usize], spin[body as usize]));
        self.relative_velocity_of(a, motion(self.body_i[a]), motion(self.body_j[a]))
    }

    /// Relative velocity of contact α from the velocity and spin of i and
    /// of j (None for a side that does not move).
    #[inline]
    pub fn relative_velocity_of(
        &self,
        a: usize,
        motion_i: Option<(Vec3, Vec3)>,
        motion_j: Option<(Vec3, Vec3)>,
    ) -> Vec3 {
        let n = self.normal[a];
        let mut relative = Vec3::zeros();
        if let Some((v, w)) = motion_i {
            relative += v - self.lever_i[a] * w.cross(&n);
        }
        if let Some((v, w)) = motion_j {
            relative -= v + self.lever_j[a] * w.cross(&n);
        }
        relative
    }

    /// Applies impulse `impulse` on i (and its opposite on j).
    #[inline]
    pub fn apply_impulse(
        &self,
        a: usize,
        impulse: Vec3,
        bodies: &Bodies,
        velocity: &mut [Vec3],
        spin: &mut [Vec3],
    ) {
        let n_cross_p = self.normal[a].cross(&impulse);
        let bi = self.body_i[a];
        if bi != STATIC {
            let b = bi as usize;
            velocity[b] += bodies.inverse_mass[b] * impulse;
            spin[b] -= self.lever_i[a] * bodies.inverse_inertia[b] * n_cross_p;
        }
        let bj = self.body_j[a];
        if bj != STATIC {
            let b = bj as usize;
            velocity[b] -= bodies.inverse_mass[b] * impulse;
            spin[b] -= self.lever_j[a] * bodies.inverse_inertia[b] * n_cross_p;
        }
    }

    /// Inverse effective masses of contact α along the normal and in the
    /// tangent plane: A_α M⁻¹ A_αᵀ = w_n n nᵀ + w_t (I − n nᵀ) for spheres and
    /// discs, so normal and tangential impulses do not couple locally.
    #[inline]
    pub fn inverse_effective_masses(&self, a: usize, bodies: &Bodies) -> (f64, f64) {
        let (mut w_n, mut w_t) = (0.0, 0.0);
        for (body, lever) in [
            (self.body_i[a], self.lever_i[a]),
            (self.body_j[a], self.lever_j[a]),
        ] {
            if body != STATIC {
                let b = body as usize;
                w_n += bodies.inverse_mass[b];
                w_t += bodies.inverse_mass[b] + lever * lever * bodies.inverse_inertia[b];
            }
        }
        (w_n, w_t)
    }
}

/// The moving grains with candidate contacts, one column each.
#[derive(Clone, Debug, Default)]
pub struct Bodies {
    /// Column of each local grain, owned then ghosts (`STATIC` if glued or
    /// without candidate).
    pub column: Vec<u32>,
    /// Local grain of each column: the owned ones first.
    pub grain: Vec<u32>,
    /// Columns of owned grains (the rest are copies of other ranks').
    pub owned: usize,
    /// Centre at the start of the step (the factor's ordering cuts the
    /// packing by planes).
    pub position: Vec<Vec3>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inverse_mass: Vec<f64>,
    pub inverse_inertia: Vec<f64>,
    /// Velocity and spin at the start of the step, u^k.
    pub start_velocity: Vec<Vec3>,
    pub start_spin: Vec<Vec3>,
    /// Velocity and spin without contacts, U = u^k + Δt M⁻¹ f_ext (eq. 10).
    pub free_velocity: Vec<Vec3>,
    pub free_spin: Vec<Vec3>,
}

impl Bodies {
    pub fn len(&self) -> usize {
        self.grain.len()
    }

    pub fn is_empty(&self) -> bool {
        self.grain.is_empty()
    }
}

/// Units of a step's conic problem and of its checks, so that every
/// quantity is of order one and the tolerances are relative: the mean
/// diameter L and mass m̄ of the bodies, the time step, and a velocity V,
/// the largest free speed of a body (at least |g| Δt; L/Δt when nothing
/// moves).
#[derive(Clone, Copy, Debug)]
pub struct Scales {
    pub length: f64,
    pub mass: f64,
    pub time: f64,
    pub velocity: f64,
}

impl Scales {
    /// This rank's share of the scales: the sums of the diameters and the
    /// masses of its own bodies, their count and the largest free speed.
    pub fn partial(bodies: &Bodies) -> [f64; 4] {
        let own = 0..bodies.owned;
        let fastest = own
            .clone()
            .map(|b| {
                bodies.free_velocity[b]
                    .norm()
                    .max(bodies.free_spin[b].norm() * bodies.radius[b])
            })
            .fold(0.0, f64::max);
        [
            own.clone().map(|b| 2.0 * bodies.radius[b]).sum(),
            own.clone().map(|b| bodies.mass[b]).sum(),
            own.len() as f64,
            fastest,
        ]
    }

    /// The scales of the bodies of every rank from the sums of their
    /// [`Scales::partial`] (the largest speed: their largest).
    pub fn of_sums(
        [diameters, masses, count, fastest]: [f64; 4],
        dt: f64,
        gravity: &Vec3,
    ) -> Scales {
        let n = count.max(1.0);
        let length = diameters / n;
        let length = if length > 0.0 { length } else { 1.0 };
        let mass = masses / n;
        let fastest = fastest.max(gravity.norm() * dt);
        Scales {
            length,
            mass: if mass > 0.0 { mass } else { 1.0 },
            time: dt,
            velocity: if fastest > 0.0 { fastest } else { length / dt },
        }
    }

    pub fn of(bodies: &Bodies, dt: f64, gravity: &Vec3) -> Scales {
        let n = bodies.len().max(1) as f64;
        let length = 2.0 * bodies.radius.iter().sum::<f64>() / n;
        let length = if length > 0.0 { length } else { 1.0 };
        let mass = bodies.mass.iter().sum::<f64>() / n;
        let fastest = (0..bodies.len())
            .map(|b| {
                bodies.free_velocity[b]
                    .norm()
                    .max(bodies.free_spin[b].norm() * bodies.radius[b])
            })
            .fold(gravity.norm() * dt, f64::max);
        Scales {
            length,
            mass: if mass > 0.0 { mass } else { 1.0 },
            time: dt,
            velocity: if fastest > 0.0 { fastest } else { length / dt },
        }
    }

    /// κ = V Δt / L: the gap, in units of L, that a speed V closes in a step.
    pub fn gap_per_velocity(&self) -> f64 {
        self.velocity * self.time / self.length
    }

    /// The unit of impulse of the program's dual variables, m̄ V κ.
    pub fn impulse(&self) -> f64 {
        self.mass * self.velocity * self.gap_per_velocity()
    }
}

/// The candidate contacts of the current configuration with gap below
/// `threshold`, and the bodies they move. `free_velocity`, `free_spin`:
/// U for every owned grain.
pub fn gather(
    system: &DemSystem,
    threshold: f64,
    free_velocity: &[Vec3],
    free_spin: &[Vec3],
) -> (ContactSet, Bodies) {
    with_bodies(system, listed(system, threshold), free_velocity, free_spin)
}

/// Which rank holds a pair across two ranks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CrossingPairs {
    /// The rank of the grain of lower id (NSCD: the pairs a rank sweeps are
    /// spread over both sides of a boundary).
    LowerId,
    /// The lower rank (COCD: the grains whose columns stand on two ranks
    /// are then the higher rank's layer along the boundary, not grains of
    /// both sides; a 3D packing of 8,748 spheres cut in two, 510 grains
    /// instead of 720, and the dense Schur complement goes as their cube).
    LowerRank,
}

/// Every pair and grain–wall pair of the neighbour list with gap below
/// `threshold`, without bodies (`body_i`, `body_j` empty), in the order of
/// the list: grain by grain, its pairs, then its walls. A pair across two
/// ranks is held by the rank of its lower id.
pub fn listed(system: &DemSystem, threshold: f64) -> ContactSet {
    listed_held(system, threshold, CrossingPairs::LowerId)
}

/// [`listed`], a pair across two ranks held by the rank `holder` says
/// (collective for [`CrossingPairs::LowerRank`]).
pub fn listed_held(system: &DemSystem, threshold: f64, holder: CrossingPairs) -> ContactSet {
    let p = &system.particles;
    let n_owned = p.n_owned;
    // The rank owning each local grain (copies learn it from their owner).
    let owner_rank = match holder {
        CrossingPairs::LowerId => Vec::new(),
        CrossingPairs::LowerRank => {
            let mut rank = vec![system.communicator.rank() as f64; p.len()];
            system.copy_onto_ghosts(&mut rank, 1);
            rank
        }
    };
    let here = system.communicator.rank() as f64;
    let list = &system.neighbours;
    let mut contacts = ContactSet::default();
    for i in 0..n_owned {
        for e in list.range(i) {
            let j = list.partner[e] as usize;
            let source = if j < n_owned {
                if j < i {
                    continue; // listed from j's side
                }
                j
            } else {
                let source = system.ghost_source(j);
                if source == usize::MAX {
                    // A copy of another rank's grain.
                    let elsewhere = match holder {
                        CrossingPairs::LowerId => p.id[j] < p.id[i],
                        CrossingPairs::LowerRank => owner_rank[j] < here,
                    };
                    if elsewhere {
                        continue;
                    }
                    j
                } else {
                    // The pair across the periodic edge is listed from both
                    // grains; the lower one holds it.
                    if source <= i {
                        continue;
                    }
                    source
                }
            };
            if p.is_fixed(i) && p.is_fixed(source) {
                continue;
            }
            let branch = p.position[i] - p.position[j];
            let distance = branch.norm();
            let gap = distance - p.radius[i] - p.radius[j];
            if gap >= threshold {
                continue;
            }
            contacts.push(
                i,
                Partner::Grain(source as u32),
                branch / distance,
                gap,
                p.radius[i],
                p.radius[j],
                system.law.friction,
            );
        }
        if p.is_fixed(i) {
            continue;
        }
        for (w, wall) in system.walls.iter().enumerate() {
            if !wall.is_present(system.time) {
                continue;
            }
            let gap = wall.distance(&p.position[i]) - p.radius[i];
            if gap < threshold {
                contacts.push(
                    i,
                    Partner::Wall(w as u32),
                    wall.normal_towards(&p.position[i]),
                    gap,
                    p.radius[i],
                    0.0,
                    wall.friction,
                );
            }
        }
    }
    contacts
}

/// The bodies `contacts` move (the moving grains with at least one of
/// them, one column each, in grain order), with the contacts' columns set.
/// `free_velocity`, `free_spin`: U of every local grain the contacts touch.
pub fn with_bodies(
    system: &DemSystem,
    contacts: ContactSet,
    free_velocity: &[Vec3],
    free_spin: &[Vec3],
) -> (ContactSet, Bodies) {
    with_bodies_marked(system, contacts, free_velocity, free_spin, &[])
}

/// [`with_bodies`], with also a body for each owned grain `marked` (on
/// several ranks: the grains whose copies other ranks' contacts touch).
pub fn with_bodies_marked(
    system: &DemSystem,
    mut contacts: ContactSet,
    free_velocity: &[Vec3],
    free_spin: &[Vec3],
    marked: &[bool],
) -> (ContactSet, Bodies) {
    let p = &system.particles;
    let n_owned = p.n_owned;
    let mut bodies = Bodies {
        column: vec![STATIC; p.len()],
        ..Bodies::default()
    };
    let mark = |k: usize, bodies: &mut Bodies| {
        if !p.is_fixed(k) {
            bodies.column[k] = 0;
        }
    };
    for a in 0..contacts.len() {
        mark(contacts.grain[a] as usize, &mut bodies);
        if let Partner::Grain(j) = contacts.partner[a] {
            mark(j as usize, &mut bodies);
        }
    }
    for (k, _) in marked.iter().enumerate().filter(|(_, &m)| m) {
        mark(k, &mut bodies);
    }
    for k in 0..p.len() {
        if bodies.column[k] == STATIC {
            continue;
        }
        if k < n_owned {
            bodies.owned += 1;
        }
        bodies.column[k] = bodies.grain.len() as u32;
        bodies.grain.push(k as u32);
        bodies.position.push(p.position[k]);
        bodies.radius.push(p.radius[k]);
        bodies.mass.push(p.mass[k]);
        bodies.inverse_mass.push(p.inverse_mass[k]);
        bodies.inverse_inertia.push(p.inverse_inertia[k]);
        bodies.start_velocity.push(p.velocity[k]);
        bodies.start_spin.push(p.angular_velocity[k]);
        bodies.free_velocity.push(free_velocity[k]);
        bodies.free_spin.push(free_spin[k]);
    }
    contacts.body_i = contacts
        .grain
        .iter()
        .map(|&i| bodies.column[i as usize])
        .collect();
    contacts.body_j = contacts
        .partner
        .iter()
        .map(|partner| match partner {
            Partner::Grain(j) => bodies.column[*j as usize],
            Partner::Wall(_) => STATIC,
        })
        .collect();
    (contacts, bodies)
}

/// Unit tangents (t1, t2) completing n to an orthonormal basis; in 2D t1
/// lies in the plane and t2 is unused.
pub fn tangents(dimension: Dimension, n: &Vec3) -> (Vec3, Vec3) {
    match dimension {
        Dimension::Two => (Vec3::new(-n.y, n.x, 0.0), Vec3::zeros()),
        Dimension::Three => {
            let axis = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
                Vec3::x()
            } else if n.y.abs() <= n.z.abs() {
                Vec3::y()
            } else {
                Vec3::z()
            };
            let t1 = n.cross(&axis).normalize();
            (t1, n.cross(&t1))
        }
    }
}
