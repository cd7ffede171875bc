//! [`Case::validate`] for the fluid: grid, boundaries, stretching and the
//! coupling with grains.

use super::*;

impl Case {
    pub(super) fn validate_fluid(&self, f: &FluidSection) -> Result<(), CaseError> {
        let dim = self.dimension();
        if f.cells.len() != dim || f.cells.iter().any(|&n| n < 2) {
            return Err(invalid(
                "fluid.cells",
                format!("{:?}", f.cells),
                &format!("allowed: a list of {dim} cell counts, each at least 2"),
            ));
        }
        positive("fluid.density", f.density)?;
        positive("fluid.viscosity", f.viscosity)?;
        if f.viscous != "crank_nicolson" && f.viscous != "explicit" {
            return Err(invalid(
                "fluid.viscous",
                &f.viscous,
                "allowed: \"crank_nicolson\" or \"explicit\"",
            ));
        }
        match f.transforms.as_deref() {
            None | Some("rust") => {}
            Some("fftw") => {
                if !grainflow_fluid::TransformBackend::Fftw.is_available() {
                    return Err(invalid(
                        "fluid.transforms",
                        "fftw",
                        "this grainflow was built without FFTW: rebuild with `cargo build \
                         --release --features fftw` (needs the system's libfftw3), or allowed: \
                         \"rust\"",
                    ));
                }
            }
            Some(other) => {
                return Err(invalid(
                    "fluid.transforms",
                    other,
                    "allowed: \"rust\" (rustfft/rustdct) or \"fftw\" (a build with \
                     --features fftw)",
                ))
            }
        }
        if !f.pressure_gradient.is_empty() {
            check_len(
                "fluid.pressure_gradient",
                &f.pressure_gradient,
                dim,
                &format!("allowed: a list of {dim} numbers [Pa/m]"),
            )?;
        }
        let axes = ["x", "y", "z"];
        for (axis, name) in axes.iter().enumerate() {
            let Some(bulk) = f.bulk_velocity.along(axis) else {
                continue;
            };
            let key = format!("fluid.bulk_velocity.{name}");
            if axis >= dim || !self.domain.periodic.get(axis).copied().unwrap_or(false) {
                return Err(invalid(
                    &key,
                    bulk,
                    "allowed only along an axis the domain marks periodic",
                ));
            }
            if !bulk.is_finite() {
                return Err(invalid(&key, bulk, "allowed: a finite velocity [m/s]"));
            }
            if f.pressure_gradient.get(axis).is_some_and(|&g| g != 0.0) {
                return Err(invalid(
                    &key,
                    bulk,
                    "a held bulk velocity sets the pressure gradient along its axis: leave \
                     fluid.pressure_gradient zero there",
                ));
            }
        }
        for axis in 0..dim {
            let key = format!("fluid.boundary.{}", axes[axis]);
            let domain_periodic = self.domain.periodic.get(axis).copied().unwrap_or(false);
            let Some(faces) = f.boundary.faces(axis) else {
                if !domain_periodic {
                    return Err(invalid(
                        &key,
                        "(missing)",
                        &format!(
                            "axis {} is not periodic in domain.periodic: give its two faces, \
                             each {FACE_KINDS}",
                            axes[axis]
                        ),
                    ));
                }
                continue;
            };
            if faces.len() != 2 {
                return Err(invalid(
                    &key,
                    format!("{faces:?}"),
                    &format!("allowed: [lower, upper], each {FACE_KINDS}"),
                ));
            }
            for (side, face) in faces.iter().enumerate() {
                let side_name = ["lower", "upper"][side];
                match face.as_str() {
                    "periodic" | "no_slip" | "free_slip" | "moving" => {}
                    "outflow" => {
                        if side != 1 || axis != dim - 1 {
                            return Err(invalid(
                                &key,
                                format!("{faces:?}"),
                                &format!(
                                    "\"outflow\" is allowed only on the upper face of the last \
                                     axis ({}), whose lines are solved by elimination",
                                    axes[dim - 1]
                                ),
                            ));
                        }
                        if self.has_grains() {
                            return Err(invalid(
                                &key,
                                format!("{faces:?}"),
                                "\"outflow\" is for fluid-only scenes in this version",
                            ));
                        }
                    }
                    other => return Err(invalid(&key, other, &format!("allowed: {FACE_KINDS}"))),
                }
                if (face == "periodic") != domain_periodic {
                    return Err(invalid(
                        &key,
                        format!("{faces:?}"),
                        "allowed: \"periodic\" on both faces exactly when domain.periodic \
                         marks the axis periodic",
                    ));
                }
                let velocity_key = format!("fluid.boundary.{}_{side_name}_velocity", axes[axis]);
                match (face.as_str(), f.boundary.velocity(axis, side)) {
                    ("moving", Some(v)) => {
                        check_len(
                            &velocity_key,
                            v,
                            dim,
                            &format!("allowed: a list of {dim} numbers [m/s]"),
                        )?;
                        if !v.iter().all(|x| x.is_finite()) {
                            return Err(invalid(
                                &velocity_key,
                                format!("{v:?}"),
                                "allowed: finite velocities [m/s]",
                            ));
                        }
                    }
                    ("moving", None) => {
                        return Err(invalid(
                            &velocity_key,
                            "(missing)",
                            "a \"moving\" face needs its velocity [m/s]",
                        ))
                    }
                    (_, Some(_)) => {
                        return Err(invalid(
                            &velocity_key,
                            "(given)",
                            "allowed only for a \"moving\" face",
                        ))
                    }
                    (_, None) => {}
                }
            }
            // Fluid through the faces (blowing, suction): as much must
            // leave through one face as enters through the other.
            let normal = |side: usize| {
                (faces[side] == "moving")
                    .then(|| f.boundary.velocity(axis, side))
                    .flatten()
                    .map_or(0.0, |v| v[axis])
            };
            if faces[1] != "outflow" && normal(0) != normal(1) {
                return Err(invalid(
                    &format!("fluid.boundary.{}_upper_velocity", axes[axis]),
                    format!("normal component {} against {} below", normal(1), normal(0)),
                    "allowed: a through-flow (blowing in through one face, suction out through \
                     the other) with the same normal velocity on both faces of the axis, so that \
                     as much fluid leaves as enters; a wall sliding in its plane has none",
                ));
            }
        }
        let periodic = |axis: usize| self.domain.periodic.get(axis).copied().unwrap_or(false);
        let extent = |axis: usize| self.domain.upper[axis] - self.domain.lower[axis];
        if let Some(stretching) = &f.stretching {
            self.validate_stretching(stretching, periodic(dim - 1))?;
        }
        match &f.initial {
            InitialFlowSection::Rest => {}
            InitialFlowSection::Uniform { velocity } => check_len(
                "fluid.initial.velocity",
                velocity,
                dim,
                &format!("allowed: a list of {dim} numbers [m/s]"),
            )?,
            InitialFlowSection::TaylorGreen { velocity, stream } => {
                non_negative("fluid.initial.velocity", *velocity)?;
                if !stream.is_empty() {
                    check_len(
                        "fluid.initial.stream",
                        stream,
                        dim,
                        &format!("allowed: a list of {dim} numbers [m/s]"),
                    )?;
                }
                if !(periodic(0) && periodic(1))
                    || (extent(0) - extent(1)).abs() > 1e-12 * extent(0)
                {
                    return Err(invalid(
                        "fluid.initial.kind",
                        "taylor_green",
                        "needs a domain periodic along x and y with equal x and y extents",
                    ));
                }
            }
            InitialFlowSection::Beltrami { velocity } => {
                non_negative("fluid.initial.velocity", *velocity)?;
                if dim != 3
                    || !(0..3).all(periodic)
                    || (0..3).any(|a| (extent(a) - extent(0)).abs() > 1e-12 * extent(0))
                {
                    return Err(invalid(
                        "fluid.initial.kind",
                        "beltrami",
                        "needs a 3D domain periodic along every axis with equal extents (a cube)",
                    ));
                }
            }
        }
        if let Some(cfl) = self.time.cfl {
            if !(cfl > 0.0 && cfl <= grainflow_fluid::CFL_LIMIT) {
                return Err(invalid(
                    "time.cfl",
                    cfl,
                    "allowed: 0 < cfl ≤ √3 = 1.732 (the stability limit of RK3 with central \
                     convection)",
                ));
            }
        }
        match (&self.analysis, &f.initial) {
            (Some(AnalysisSection::ExactDecay), InitialFlowSection::TaylorGreen { .. })
            | (Some(AnalysisSection::ExactDecay), InitialFlowSection::Beltrami { .. }) => {}
            (Some(AnalysisSection::ExactDecay), _) => {
                return Err(invalid(
                    "analysis.kind",
                    "exact_decay",
                    "needs fluid.initial.kind = \"taylor_green\" or \"beltrami\"",
                ))
            }
            (Some(AnalysisSection::Channel), _) => {
                let last = dim - 1;
                if periodic(last) || (0..last).any(|a| !periodic(a)) {
                    return Err(invalid(
                        "analysis.kind",
                        "channel",
                        "needs walls on the faces of the last axis and periodic other axes",
                    ));
                }
                let through_flow = f
                    .boundary
                    .velocity(last, 0)
                    .is_some_and(|v| v.get(last).is_some_and(|&n| n != 0.0));
                let held = (0..dim).any(|a| f.bulk_velocity.along(a).is_some());
                if through_flow && held {
                    return Err(invalid(
                        "analysis.kind",
                        "channel",
                        "with fluid through the walls the profile is known under a pressure \
                         gradient, not a held bulk velocity",
                    ));
                }
            }
            (Some(_), _) if !self.has_grains() => {
                return Err(invalid(
                    "analysis.kind",
                    "(a particle analysis)",
                    "a fluid-only scene allows \"exact_decay\" or \"channel\"",
                ))
            }
            (Some(_), _) | (None, _) => {}
        }
        Ok(())
    }

    /// `[fluid.stretching]`: one of its two forms, along an axis with walls,
    /// in a scene without grains, giving faces that make a grid.
    pub(super) fn validate_stretching(
        &self,
        s: &StretchingSection,
        periodic_line: bool,
    ) -> Result<(), CaseError> {
        let line = ["x", "y", "z"][self.dimension() - 1];
        if periodic_line {
            return Err(invalid(
                "fluid.stretching",
                "(given)",
                &format!(
                    "the stretched axis is the last one ({line}), which must have walls, not be \
                     periodic"
                ),
            ));
        }
        if self.has_grains() {
            return Err(invalid(
                "fluid.stretching",
                "(given)",
                "grains in a fluid need uniform cells (the immersed boundary's smoothing \
                 length is a cell size): stretching is for fluid-only scenes",
            ));
        }
        match (&s.cluster, s.factor, &s.faces) {
            (Some(cluster), Some(factor), None) => {
                if !matches!(cluster.as_str(), "both_walls" | "lower_wall" | "upper_wall") {
                    return Err(invalid(
                        "fluid.stretching.cluster",
                        cluster,
                        &format!("allowed: {CLUSTER_KINDS}"),
                    ));
                }
                if !(factor > 0.0 && factor <= MAX_STRETCHING_FACTOR) {
                    return Err(invalid(
                        "fluid.stretching.factor",
                        factor,
                        &format!(
                            "allowed: 0 < factor ≤ {MAX_STRETCHING_FACTOR} (the clustered end \
                             cells are 2β/sinh 2β of the mean width)"
                        ),
                    ));
                }
            }
            (None, None, Some(_)) => {}
            _ => {
                return Err(invalid(
                    "fluid.stretching",
                    "(incomplete or mixed)",
                    &format!(
                        "allowed: cluster ({CLUSTER_KINDS}) with factor, or faces (the {line} \
                         face coordinates [m]), not both"
                    ),
                ))
            }
        }
        crate::scene::fluid::try_grid(self)
            .map_err(|message| invalid("fluid.stretching.faces", "(the faces given)", &message))?;
        Ok(())
    }

    /// The tables of a scene with grains in a fluid.
    pub(super) fn validate_coupling(&self) -> Result<(), CaseError> {
        let coupled = self.fluid.is_some() && self.has_grains();
        if !coupled && self.coupling.is_some() {
            return Err(invalid(
                "coupling",
                "(without grains in a fluid)",
                "[coupling] needs both [fluid] and [particles]",
            ));
        }
        if !coupled && self.lubrication.is_some() {
            return Err(invalid(
                "lubrication",
                "(without a fluid)",
                "the lubrication force exists only for grains in a fluid: [lubrication] needs \
                 both [fluid] and [particles]",
            ));
        }
        if let Some(c) = &self.coupling {
            if !(c.contact_gap >= 0.0 && c.contact_gap <= 3.0) {
                return Err(invalid(
                    "coupling.contact_gap",
                    c.contact_gap,
                    "allowed: 0 ≤ contact_gap ≤ 3 (fluid cells)",
                ));
            }
            if let Some(step) = c.forcing_step {
                positive("coupling.forcing_step", step)?;
                if c.layer_forcing == LayerForcingName::Renewal {
                    return Err(invalid(
                        "coupling.forcing_step",
                        step,
                        "not with coupling.layer_forcing = \"renewal\", which takes each \
                         grain's own rate: set one of the two",
                    ));
                }
            }
        }
        if let Some(l) = &self.lubrication {
            positive("lubrication.roughness", l.roughness)?;
            if !(l.range > 0.0 && l.range <= 1.0) {
                return Err(invalid(
                    "lubrication.range",
                    l.range,
                    "allowed: 0 < range ≤ 1 (gap over the smaller radius; the paper uses 0.5)",
                ));
            }
        }
        if coupled {
            if !matches!(
                self.analysis,
                None | Some(
                    AnalysisSection::FallingSphere
                        | AnalysisSection::BouncingSphere
                        | AnalysisSection::InclinedBed { .. }
                )
            ) {
                return Err(invalid(
                    "analysis.kind",
                    "(grains in a fluid)",
                    "grains in a fluid allow \"falling_sphere\", \"bouncing_sphere\" or \
                     \"inclined_bed\" (or no analysis)",
                ));
            }
            if let Some(AnalysisSection::InclinedBed { slab: Some(slab) }) = &self.analysis {
                if !(slab.is_finite() && *slab > 0.0) {
                    return Err(invalid(
                        "analysis.slab",
                        slab,
                        "allowed: a positive height [m]",
                    ));
                }
            }
            if self.time.dt.is_none() {
                return Err(invalid(
                    "time.dt",
                    "(missing)",
                    "grains in a fluid need the fluid step time.dt [s] (with time.cfl, the \
                     largest step); the DEM sub-step is time.dt_over_contact_time × t_c \
                     (default 0.02)",
                ));
            }
        }
        Ok(())
    }
}
