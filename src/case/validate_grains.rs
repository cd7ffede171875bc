//! [`Case::validate`] for the grains: placement, pours, soft and hard
//! contact.

use super::*;

impl Case {
    pub(super) fn validate_grains(
        &self,
        p: &ParticlesSection,
        c: &ContactSection,
    ) -> Result<(), CaseError> {
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        if matches!(
            self.analysis,
            Some(AnalysisSection::ExactDecay | AnalysisSection::Channel)
        ) {
            return Err(invalid(
                "analysis.kind",
                "(a fluid analysis)",
                "a scene of grains allows \"binary_collision\", \"bouncing\", \"silo\", \
                 \"column_collapse\", \"erodible_bed\", \"static_box\" or, in a fluid, \
                 \"falling_sphere\", \"bouncing_sphere\" or \"inclined_bed\"",
            ));
        }
        if self.fluid.is_none()
            && matches!(
                self.analysis,
                Some(
                    AnalysisSection::FallingSphere
                        | AnalysisSection::BouncingSphere
                        | AnalysisSection::InclinedBed { .. }
                )
            )
        {
            return Err(invalid(
                "analysis.kind",
                "(an analysis of grains in a fluid)",
                "falling_sphere, bouncing_sphere and inclined_bed need a [fluid]",
            ));
        }
        if self.time.cfl.is_some() && self.fluid.is_none() {
            return Err(invalid(
                "time.cfl",
                "(dry scene)",
                "time.cfl sets the step of a fluid; a dry scene uses time.dt or \
                 time.dt_over_contact_time",
            ));
        }
        positive("particles.density", p.density)?;
        positive("particles.radius", p.radius)?;
        if !(0.0..1.0).contains(&p.radius_spread) {
            return Err(invalid(
                "particles.radius_spread",
                p.radius_spread,
                "allowed: 0 ≤ radius_spread < 1",
            ));
        }
        if p.block.is_empty() && p.pour.is_empty() {
            return Err(invalid(
                "particles.block",
                "[]",
                "allowed: at least one [[particles.block]] generator or [[particles.pour]]",
            ));
        }
        self.validate_pours(p, c)?;
        for (k, block) in p.block.iter().enumerate() {
            let key = |name: &str| format!("particles.block[{k}].{name}");
            match block {
                BlockSection::Lattice {
                    lower,
                    upper,
                    spacing,
                    layer_spacing,
                    jitter,
                    velocity,
                    ..
                } => {
                    if let Some(layer) = layer_spacing {
                        if *layer < *spacing {
                            return Err(invalid(
                                &key("layer_spacing"),
                                layer,
                                "allowed: at least `spacing`",
                            ));
                        }
                    }
                    check_len(&key("lower"), lower, dim, &need)?;
                    check_len(&key("upper"), upper, dim, &need)?;
                    if *spacing < 2.0 * p.radius * (1.0 + p.radius_spread) * (1.0 - 1e-12) {
                        return Err(invalid(
                            &key("spacing"),
                            spacing,
                            "allowed: at least the largest diameter, 2 radius (1 + radius_spread)",
                        ));
                    }
                    if !(0.0..=1.0).contains(jitter) {
                        return Err(invalid(&key("jitter"), jitter, "allowed: 0 ≤ jitter ≤ 1"));
                    }
                    if !velocity.is_empty() {
                        check_len(&key("velocity"), velocity, dim, &need)?;
                    }
                }
                BlockSection::Random {
                    lower,
                    upper,
                    count,
                    velocity,
                    ..
                } => {
                    check_len(&key("lower"), lower, dim, &need)?;
                    check_len(&key("upper"), upper, dim, &need)?;
                    if *count == 0 {
                        return Err(invalid(&key("count"), count, "allowed: at least 1"));
                    }
                    let room = random_placement_room(dim, lower, upper, p);
                    if *count as f64 > room {
                        return Err(invalid(
                            &key("count"),
                            count,
                            &format!(
                                "random placement (random sequential addition) jams at a solid \
                                 fraction of {}: this region holds at most {room:.0} grains of \
                                 the smallest radius; allowed: count ≤ {room:.0}, or a larger \
                                 region, or a lattice block",
                                RANDOM_PLACEMENT_JAMMING[dim - 2]
                            ),
                        ));
                    }
                    if !velocity.is_empty() {
                        check_len(&key("velocity"), velocity, dim, &need)?;
                    }
                }
                BlockSection::Explicit {
                    positions,
                    velocities,
                    angular_velocities,
                    radii,
                    ..
                } => {
                    if positions.is_empty() {
                        return Err(invalid(
                            &key("positions"),
                            "[]",
                            "allowed: at least one position",
                        ));
                    }
                    for (name, list) in [("positions", positions), ("velocities", velocities)] {
                        if !list.is_empty() && list.len() != positions.len() {
                            return Err(invalid(
                                &key(name),
                                list.len(),
                                "allowed: as many entries as positions",
                            ));
                        }
                        for v in list {
                            check_len(&key(name), v, dim, &need)?;
                        }
                    }
                    if !angular_velocities.is_empty() && angular_velocities.len() != positions.len()
                    {
                        return Err(invalid(
                            &key("angular_velocities"),
                            angular_velocities.len(),
                            "allowed: as many entries as positions",
                        ));
                    }
                    for w in angular_velocities {
                        check_len(
                            &key("angular_velocities"),
                            w,
                            3,
                            "allowed: a list of 3 numbers (rad/s about x, y, z)",
                        )?;
                    }
                    if !radii.is_empty() && radii.len() != positions.len() {
                        return Err(invalid(
                            &key("radii"),
                            radii.len(),
                            "allowed: as many radii as positions",
                        ));
                    }
                    for r in radii {
                        positive(&key("radii"), *r)?;
                    }
                }
                BlockSection::File {
                    path,
                    fixed,
                    fixed_groups,
                } => {
                    if path.is_empty() {
                        return Err(invalid(
                            &key("path"),
                            "\"\"",
                            "allowed: the path of a CSV file",
                        ));
                    }
                    if *fixed && !fixed_groups.is_empty() {
                        return Err(invalid(
                            &key("fixed_groups"),
                            format!("{fixed_groups:?}"),
                            "allowed: fixed_groups with fixed = false (fixed = true glues every grain of the file)",
                        ));
                    }
                }
                BlockSection::CollisionPairs {
                    count,
                    impact_speed,
                    psi_max,
                    gap,
                } => {
                    if *count == 0 {
                        return Err(invalid(&key("count"), count, "allowed: at least 1"));
                    }
                    positive(&key("impact_speed"), *impact_speed)?;
                    if *psi_max < 0.0 {
                        return Err(invalid(&key("psi_max"), psi_max, "allowed: psi_max ≥ 0"));
                    }
                    if *gap < 0.0 {
                        return Err(invalid(&key("gap"), gap, "allowed: gap ≥ 0"));
                    }
                }
            }
        }
        match c.model {
            ContactModel::Soft => self.validate_soft_contact(c)?,
            ContactModel::Cocd | ContactModel::Nscd => self.validate_hard_contact(c)?,
        }
        non_negative("contact.friction", c.friction)?;
        non_negative("contact.rolling_friction", c.rolling_friction)?;
        if let Some(f) = c.wall_friction {
            non_negative("contact.wall_friction", f)?;
        }
        if let Some(s) = c.skin {
            positive("contact.skin", s)?;
        }
        Ok(())
    }

    pub(super) fn validate_pours(
        &self,
        p: &ParticlesSection,
        c: &ContactSection,
    ) -> Result<(), CaseError> {
        let dim = self.dimension();
        let need = format!("allowed: a list of {dim} numbers (one per axis)");
        for (k, pour) in p.pour.iter().enumerate() {
            let key = |name: &str| format!("particles.pour[{k}].{name}");
            if self.fluid.is_some() || c.model != ContactModel::Soft {
                return Err(invalid(
                    &key("count"),
                    pour.count,
                    "a pour runs in a dry scene with contact.model = \"soft\" in this version; \
                     allowed elsewhere: [[particles.block]] generators",
                ));
            }
            if self.domain.gravity.iter().all(|g| *g == 0.0) {
                return Err(invalid(
                    "domain.gravity",
                    format!("{:?}", self.domain.gravity),
                    "a pour needs gravity: its batches are released above the deposit, \
                     against gravity",
                ));
            }
            check_len(&key("lower"), &pour.lower, dim, &need)?;
            check_len(&key("upper"), &pour.upper, dim, &need)?;
            if pour.spacing < 2.0 * p.radius * (1.0 + p.radius_spread) * (1.0 - 1e-12) {
                return Err(invalid(
                    &key("spacing"),
                    pour.spacing,
                    "allowed: at least the largest diameter, 2 radius (1 + radius_spread)",
                ));
            }
            let d = &self.domain;
            for a in 0..dim {
                let periodic = d.periodic.get(a).copied().unwrap_or(false);
                if !periodic && (pour.lower[a] < d.lower[a] || pour.upper[a] > d.upper[a]) {
                    return Err(invalid(
                        &key("lower"),
                        format!("{:?} .. {:?}", pour.lower, pour.upper),
                        "allowed: a box inside domain.lower .. domain.upper",
                    ));
                }
            }
            let sites: f64 = (0..dim)
                .map(|a| ((pour.upper[a] - pour.lower[a]) / pour.spacing + 1e-9).floor())
                .product();
            if sites < 1.0 || sites.is_nan() {
                return Err(invalid(
                    &key("upper"),
                    format!("{:?}", pour.upper),
                    "allowed: a box that holds at least one lattice site (upper − lower ≥ \
                     spacing along every axis)",
                ));
            }
            if !(0.0..=1.0).contains(&pour.jitter) {
                return Err(invalid(
                    &key("jitter"),
                    pour.jitter,
                    "allowed: 0 ≤ jitter ≤ 1",
                ));
            }
            if pour.count == 0 {
                return Err(invalid(&key("count"), pour.count, "allowed: at least 1"));
            }
            positive(&key("interval"), pour.interval)?;
            non_negative(&key("gap"), pour.gap)?;
            if let Some(speed) = pour.settled_speed {
                positive(&key("settled_speed"), speed)?;
                // A batch released at rest falls faster than the settled
                // speed only after speed/g: an earlier test would pass at
                // once and stack the next batch on a falling one.
                let g = self
                    .domain
                    .gravity
                    .iter()
                    .map(|g| g * g)
                    .sum::<f64>()
                    .sqrt();
                let least = 1.2 * speed / g;
                if pour.interval < least {
                    return Err(invalid(
                        &key("interval"),
                        pour.interval,
                        &format!(
                            "allowed with settled_speed = {speed}: interval ≥ {least:.3e} s \
                             (1.2 settled_speed/|g|: a batch released at rest must be falling \
                             faster than settled_speed before the next one is considered)"
                        ),
                    ));
                }
            }
            if !pour.velocity.is_empty() {
                check_len(&key("velocity"), &pour.velocity, dim, &need)?;
            }
        }
        Ok(())
    }

    pub(super) fn validate_soft_contact(&self, c: &ContactSection) -> Result<(), CaseError> {
        for (key, given) in [
            ("contact.tolerance", c.tolerance.is_some()),
            ("contact.max_iterations", c.max_iterations.is_some()),
            ("contact.threshold", c.threshold.is_some()),
            ("contact.conic_solver", c.conic_solver.is_some()),
            ("contact.candidates", c.candidates.is_some()),
        ] {
            if given {
                return Err(invalid(
                    key,
                    "(given)",
                    "a hard-contact key: allowed only with contact.model = \"cocd\" or \"nscd\"",
                ));
            }
        }
        match (c.restitution, c.contact_time, c.stiffness, c.damping) {
            (Some(e), Some(tc), None, None) => {
                if !(e > 0.0 && e <= 1.0) {
                    return Err(invalid(
                        "contact.restitution",
                        e,
                        "allowed: 0 < restitution ≤ 1",
                    ));
                }
                if c.calibration() == "exact"
                    && e <= grainflow_dem::contact_law::MIN_EXACT_RESTITUTION
                {
                    return Err(invalid(
                        "contact.restitution",
                        e,
                        "with calibration = \"exact\" allowed: restitution > e^-2 = 0.1353 (no \
                         force-clamped contact reaches a lower one in t_c); use calibration = \"paper\"",
                    ));
                }
                positive("contact.contact_time", tc)?;
            }
            (None, None, Some(k), Some(g)) => {
                positive("contact.stiffness", k)?;
                if g < 0.0 {
                    return Err(invalid("contact.damping", g, "allowed: damping ≥ 0"));
                }
            }
            _ => {
                return Err(invalid(
                    "contact",
                    "(restitution, contact_time, stiffness, damping)",
                    "allowed: either restitution and contact_time, or stiffness and damping",
                ))
            }
        }
        if c.calibration() != "exact" && c.calibration() != "paper" {
            return Err(invalid(
                "contact.calibration",
                c.calibration(),
                "allowed: \"exact\" or \"paper\"",
            ));
        }
        non_negative("contact.tangential_ratio", c.tangential_ratio())?;
        Ok(())
    }

    /// Hard contact: a dry scene, a fixed time step, and none of the soft
    /// law's keys.
    pub(super) fn validate_hard_contact(&self, c: &ContactSection) -> Result<(), CaseError> {
        if self.fluid.is_some() {
            return Err(invalid(
                "contact.model",
                c.model,
                "hard contact runs in dry scenes; grains in a fluid allowed: \"soft\"",
            ));
        }
        for (key, given) in [
            ("contact.contact_time", c.contact_time.is_some()),
            ("contact.calibration", c.calibration.is_some()),
            ("contact.stiffness", c.stiffness.is_some()),
            ("contact.damping", c.damping.is_some()),
            ("contact.tangential_ratio", c.tangential_ratio.is_some()),
            ("contact.rolling_friction", c.rolling_friction != 0.0),
        ] {
            if given {
                return Err(invalid(
                    key,
                    "(given)",
                    &format!(
                        "a soft-contact key: not used by contact.model = \"{}\" (grains do not overlap)",
                        c.model
                    ),
                ));
            }
        }
        if let Some(e) = c.restitution {
            if c.model == ContactModel::Cocd {
                return Err(invalid(
                    "contact.restitution",
                    e,
                    "COCD is inelastic (Martin et al. 2022, eq. 5–9): leave restitution out, or use \"nscd\"",
                ));
            }
            if !(0.0..=1.0).contains(&e) {
                return Err(invalid(
                    "contact.restitution",
                    e,
                    "allowed: 0 ≤ restitution ≤ 1",
                ));
            }
        }
        if let Some(tolerance) = c.tolerance {
            if !(tolerance > 0.0 && tolerance < 1.0) {
                return Err(invalid(
                    "contact.tolerance",
                    tolerance,
                    "allowed: 0 < tolerance < 1",
                ));
            }
        }
        if c.max_iterations == Some(0) {
            return Err(invalid("contact.max_iterations", 0, "allowed: at least 1"));
        }
        if let Some(threshold) = c.threshold {
            positive("contact.threshold", threshold)?;
        }
        if let Some(other) = c
            .candidates
            .as_deref()
            .filter(|v| !matches!(*v, "reachable" | "listed"))
        {
            return Err(invalid(
                "contact.candidates",
                other,
                "allowed: \"reachable\" or \"listed\"",
            ));
        }
        match (c.model, c.conic_solver.as_deref()) {
            (_, None)
            | (ContactModel::Cocd, Some("interior_point" | "clarabel" | "projected_gradient")) => {}
            (ContactModel::Cocd, Some(other)) => {
                return Err(invalid(
                    "contact.conic_solver",
                    other,
                    "allowed: \"interior_point\", \"clarabel\" or \"projected_gradient\"",
                ))
            }
            (_, Some(_)) => {
                return Err(invalid(
                    "contact.conic_solver",
                    "(given)",
                    "a COCD key: allowed only with contact.model = \"cocd\"",
                ))
            }
        }
        if self.time.dt.is_none() {
            return Err(invalid(
                "time.dt",
                "(missing)",
                "hard contact has no contact time: give time.dt (e.g. 1e-3 s for 2D columns, \
                 Martin et al. 2022 section 3.4.1)",
            ));
        }
        if self.time.dt_over_contact_time.is_some() {
            return Err(invalid(
                "time.dt_over_contact_time",
                "(given)",
                "hard contact has no contact time: allowed: time.dt",
            ));
        }
        Ok(())
    }
}

/// The solid fraction at which random sequential addition of equal discs
/// (2D) and spheres (3D) jams: no further grain finds room (Hinrichsen,
/// Feder & Jøssang 1986, 0.547; Torquato, Uche & Stillinger 2006, 0.384).
const RANDOM_PLACEMENT_JAMMING: [f64; 2] = [0.547, 0.384];

/// How many grains of the smallest radius random placement can put in the
/// box `[lower, upper]` before it jams: an upper bound of what a `random`
/// block can place (larger grains fill it sooner).
fn random_placement_room(dim: usize, lower: &[f64], upper: &[f64], p: &ParticlesSection) -> f64 {
    let region: f64 = (0..dim).map(|a| (upper[a] - lower[a]).max(0.0)).product();
    let radius = p.radius * (1.0 - p.radius_spread);
    let grain = if dim == 2 {
        std::f64::consts::PI * radius * radius
    } else {
        4.0 / 3.0 * std::f64::consts::PI * radius.powi(3)
    };
    (RANDOM_PLACEMENT_JAMMING[dim - 2] * region / grain).floor()
}
