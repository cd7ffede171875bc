//! [`Case::validate`] for `domain.geometry = "axisymmetric"`: the fluid of
//! a 3D scene solved in (r, z) about the axis x = y = 0. The case reads as
//! a 3D one — the box around the cylinder, `fluid.cells` over the box,
//! faces x and y for the cylinder's wall — and what the (r, z) model cannot
//! hold is refused here, naming the key.

use super::*;

const GEOMETRY: &str = "domain.geometry";

impl Case {
    pub(super) fn validate_axisymmetric(&self, f: &FluidSection) -> Result<(), CaseError> {
        let d = &self.domain;
        if d.dimension != 3 {
            return Err(invalid(
                GEOMETRY,
                "axisymmetric",
                "an axisymmetric scene is a 3D one solved in (r, z): domain.dimension = 3",
            ));
        }
        if !self.has_grains() {
            return Err(invalid(
                GEOMETRY,
                "axisymmetric",
                "this version runs axisymmetric scenes with grains on the axis (a sphere \
                 settling or bouncing); a fluid alone in (r, z) is not run from a case yet",
            ));
        }
        let radius = d.upper[0];
        let centred = d.lower[0] == -radius && d.lower[1] == -radius && d.upper[1] == radius;
        if !centred {
            return Err(invalid(
                "domain.lower",
                format!("{:?} to {:?}", d.lower, d.upper),
                "an axisymmetric scene's box surrounds the cylinder about x = y = 0: lower = \
                 [-R, -R, z0], upper = [R, R, z1] with R the cylinder's radius",
            ));
        }
        if d.periodic.iter().take(2).any(|&p| p) {
            return Err(invalid(
                "domain.periodic",
                format!("{:?}", d.periodic),
                "an axisymmetric scene may be periodic along z only",
            ));
        }
        if d.gravity.iter().take(2).any(|&g| g != 0.0) {
            return Err(invalid(
                "domain.gravity",
                format!("{:?}", d.gravity),
                "an axisymmetric scene takes gravity along the axis (z) only",
            ));
        }
        if f.cells.len() != 3
            || f.cells[0] != f.cells[1]
            || !f.cells[0].is_multiple_of(2)
            || f.cells[0] < 4
        {
            return Err(invalid(
                "fluid.cells",
                format!("{:?}", f.cells),
                "allowed: [2 n, 2 n, n_z] over the box (n radial cells from the axis to the wall, \
                 n ≥ 2, n_z ≥ 2 along z)",
            ));
        }
        if f.cells[2] < 2 {
            return Err(invalid("fluid.cells", format!("{:?}", f.cells), "n_z ≥ 2"));
        }
        positive("fluid.density", f.density)?;
        positive("fluid.viscosity", f.viscosity)?;
        if f.viscous != "crank_nicolson" {
            return Err(invalid(
                "fluid.viscous",
                &f.viscous,
                "allowed in an axisymmetric scene: \"crank_nicolson\"",
            ));
        }
        if f.transforms.as_deref().is_some_and(|t| t != "rust") {
            return Err(invalid(
                "fluid.transforms",
                f.transforms.as_deref().unwrap_or_default(),
                "an axisymmetric scene uses rustfft/rustdct along z: allowed \"rust\" or leave it out",
            ));
        }
        if f.pressure_gradient.iter().take(2).any(|&g| g != 0.0) || f.pressure_gradient.len() > 3 {
            return Err(invalid(
                "fluid.pressure_gradient",
                format!("{:?}", f.pressure_gradient),
                "an axisymmetric scene takes a pressure gradient along z only: [0, 0, dp/dz]",
            ));
        }
        if (0..3).any(|axis| f.bulk_velocity.along(axis).is_some()) {
            return Err(invalid(
                "fluid.bulk_velocity",
                "(given)",
                "not in an axisymmetric scene: drive it by fluid.pressure_gradient along z",
            ));
        }
        if !matches!(f.initial, InitialFlowSection::Rest) {
            return Err(invalid(
                "fluid.initial.kind",
                "(given)",
                "an axisymmetric scene starts from rest: allowed \"rest\"",
            ));
        }
        self.validate_axisymmetric_faces(f)?;
        if let Some(s) = &f.stretching {
            self.validate_radial_stretching(s)?;
        }
        if self.output.format == OutputFormat::Hdf5 {
            return Err(invalid(
                "output.format",
                "hdf5",
                "an axisymmetric scene writes its (r, z) fields as VTK: allowed \"vtk\"",
            ));
        }
        if let Some(grid) = self.parallel.as_ref().and_then(|p| p.process_grid.as_ref()) {
            if grid.iter().product::<usize>() > 1 {
                return Err(invalid(
                    "parallel.process_grid",
                    format!("{grid:?}"),
                    "an axisymmetric scene runs on one rank",
                ));
            }
        }
        match &self.analysis {
            None | Some(AnalysisSection::FallingSphere) | Some(AnalysisSection::BouncingSphere) => {
                Ok(())
            }
            Some(_) => Err(invalid(
                "analysis.kind",
                "(given)",
                "an axisymmetric scene allows \"falling_sphere\" or \"bouncing_sphere\"",
            )),
        }
    }

    /// The cylinder's wall is given by the faces along x and y (the same
    /// pair, one kind on both sides); the ends by the faces along z.
    fn validate_axisymmetric_faces(&self, f: &FluidSection) -> Result<(), CaseError> {
        let b = &f.boundary;
        let wall = b.faces(0);
        let same_side = |faces: &Vec<String>| faces.len() == 2 && faces[0] == faces[1];
        let wall_allowed = "the cylinder's wall, the same on both sides of x and of y: \
                            [\"no_slip\", \"no_slip\"], [\"free_slip\", \"free_slip\"] or \
                            [\"moving\", \"moving\"] sliding along z";
        match (wall, b.faces(1)) {
            (Some(x), Some(y)) if x == y && same_side(x) => {
                let kind = x[0].as_str();
                if !matches!(kind, "no_slip" | "free_slip" | "moving") {
                    return Err(invalid("fluid.boundary.x", format!("{x:?}"), wall_allowed));
                }
                if kind == "moving" {
                    for (axis, name) in [(0, "x"), (1, "y")] {
                        for (side, side_name) in [(0, "lower"), (1, "upper")] {
                            let key = format!("fluid.boundary.{name}_{side_name}_velocity");
                            let velocity = b.velocity(axis, side);
                            let sliding = velocity.is_some_and(|v| {
                                v.len() == 3 && v[0] == 0.0 && v[1] == 0.0 && v[2].is_finite()
                            });
                            let same = velocity == b.velocity(0, 0);
                            if !sliding || !same {
                                return Err(invalid(
                                    &key,
                                    format!("{velocity:?}"),
                                    "the cylinder's wall slides along z, the same on every \
                                     side: [0, 0, w]",
                                ));
                            }
                        }
                    }
                }
            }
            _ => {
                return Err(invalid(
                    "fluid.boundary.x",
                    format!("{wall:?} and y {:?}", b.faces(1)),
                    wall_allowed,
                ))
            }
        }
        let ends = b.faces(2).cloned().unwrap_or_else(|| {
            let kind = if self.domain.periodic.get(2) == Some(&true) {
                "periodic"
            } else {
                "(none)"
            };
            vec![kind.to_string(); 2]
        });
        let allowed = ends.len() == 2
            && ends
                .iter()
                .all(|e| matches!(e.as_str(), "periodic" | "no_slip" | "free_slip"))
            && (ends[0] == "periodic") == (ends[1] == "periodic");
        if !allowed {
            return Err(invalid(
                "fluid.boundary.z",
                format!("{ends:?}"),
                "the ends along z: \"no_slip\" or \"free_slip\" on each, or both \"periodic\"",
            ));
        }
        Ok(())
    }

    /// `[fluid.stretching]` of an axisymmetric scene spaces the radial
    /// cells: a uniform core and arithmetic growth (`core_radius`,
    /// `core_cells`), a tanh clustering at the wall (`cluster =
    /// "upper_wall"`, `factor`), or the radial faces from 0 to R.
    fn validate_radial_stretching(&self, s: &StretchingSection) -> Result<(), CaseError> {
        let forms = (
            s.core_radius.is_some() || s.core_cells.is_some(),
            s.cluster.is_some() || s.factor.is_some(),
            s.faces.is_some(),
        );
        let allowed = "in an axisymmetric scene the radial cells: core_radius with core_cells \
                       (uniform, then growing in arithmetic progression), cluster = \
                       \"upper_wall\" with factor (tanh, fine at the wall), or faces (from 0 to \
                       R)";
        match forms {
            (true, false, false) | (false, true, false) | (false, false, true) => {}
            _ => {
                return Err(invalid(
                    "fluid.stretching",
                    "(incomplete or mixed)",
                    allowed,
                ))
            }
        }
        if forms.1 && s.cluster.as_deref() != Some("upper_wall") {
            return Err(invalid(
                "fluid.stretching.cluster",
                format!("{:?}", s.cluster),
                "an axisymmetric scene clusters radial cells at its wall only: \"upper_wall\"",
            ));
        }
        crate::scene::axisymmetric::radial_faces(self)
            .map(|_| ())
            .map_err(|message| invalid("fluid.stretching", "(the radial cells given)", &message))
    }
}

impl Case {
    /// Keys that belong to axisymmetric scenes, refused elsewhere.
    pub(super) fn refuse_axisymmetric_keys(&self, f: &FluidSection) -> Result<(), CaseError> {
        if let Some(s) = &f.stretching {
            if s.core_radius.is_some() || s.core_cells.is_some() {
                return Err(invalid(
                    "fluid.stretching.core_radius",
                    "(given)",
                    "a uniform core and growing cells are for the radial cells of an \
                     axisymmetric scene (domain.geometry = \"axisymmetric\")",
                ));
            }
        }
        Ok(())
    }
}
