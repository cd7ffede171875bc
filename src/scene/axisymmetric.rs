//! Axisymmetric scene assembly (`domain.geometry = "axisymmetric"`): the
//! `[fluid]` table of a validated 3D case read as the cylinder inscribed in
//! its box — radius `R = domain.upper[0]`, `fluid.cells[0] / 2` radial
//! cells, the faces along x and y its wall, those along z its ends — and
//! the grains on its axis coupled to it.

use crate::case::{Case, WallLayerName};
use crate::scene;
use grainflow_core::Communicator;
use grainflow_fluid::axisymmetric::{
    core_and_growth_faces, AxialEnd, AxisymmetricFlow, OuterWall, RzGrid, RzWalls,
};
use grainflow_fluid::{clustered_faces, Clustering};
use grainflow_ibm::axisymmetric::{AxisymmetricCoupledSystem, EndLayers};

/// The radial faces `0 = r_0 < … < r_n = R` of the case: uniform, or as
/// `[fluid.stretching]` spaces them; the reason if they make no grid.
pub fn radial_faces(case: &Case) -> Result<Vec<f64>, String> {
    let f = case.fluid_section();
    let radius = case.domain.upper[0];
    let cells = f.cells[0] / 2;
    let Some(s) = &f.stretching else {
        return Ok((0..=cells)
            .map(|i| radius * i as f64 / cells as f64)
            .collect());
    };
    if let (Some(core_radius), Some(core_cells)) = (s.core_radius, s.core_cells) {
        return core_and_growth_faces(core_radius, core_cells, radius, cells)
            .map_err(|e| e.to_string());
    }
    if let Some(factor) = s.factor {
        return Ok(clustered_faces(
            Clustering::Upper,
            factor,
            cells,
            0.0,
            radius,
        ));
    }
    match &s.faces {
        Some(faces) if faces.len() == cells + 1 => Ok(faces.clone()),
        Some(faces) => Err(format!(
            "{} radial faces given for {cells} radial cells (fluid.cells[0] / 2): give {}",
            faces.len(),
            cells + 1
        )),
        None => Err("give core_radius with core_cells, cluster with factor, or faces".into()),
    }
}

/// The (r, z) grid of a validated case.
pub fn grid(case: &Case) -> Result<RzGrid, String> {
    let f = case.fluid_section();
    let d = &case.domain;
    RzGrid::from_radial_faces(&radial_faces(case)?, f.cells[2], [d.lower[2], d.upper[2]])
        .map_err(|e| e.to_string())
}

/// The wall and ends of a validated case.
pub fn walls(case: &Case) -> RzWalls {
    let b = &case.fluid_section().boundary;
    let wall = b.faces(0).map_or("no_slip", |faces| faces[0].as_str());
    let outer = match wall {
        "free_slip" => OuterWall::FreeSlip,
        "moving" => OuterWall::Sliding(b.velocity(0, 0).map_or(0.0, |v| v[2])),
        _ => OuterWall::NoSlip,
    };
    let end = |side: usize| match b.faces(2).map(|faces| faces[side].as_str()) {
        Some("free_slip") => AxialEnd::FreeSlip,
        Some("no_slip") => AxialEnd::NoSlip,
        _ if case.domain.periodic.get(2) == Some(&true) => AxialEnd::Periodic,
        Some("periodic") => AxialEnd::Periodic,
        _ => AxialEnd::NoSlip,
    };
    RzWalls::new(outer, [end(0), end(1)]).expect("validated ends")
}

/// The fluid of a validated case at rest, driven along z by
/// `fluid.pressure_gradient` where the ends are periodic (gravity acts on
/// the grains; along an axis closed by walls the hydrostatic pressure
/// balances it on the fluid).
pub fn flow(case: &Case) -> Result<AxisymmetricFlow, String> {
    let f = case.fluid_section();
    let walls = walls(case);
    let mut flow = AxisymmetricFlow::new(grid(case)?, walls, f.viscosity / f.density)
        .map_err(|e| e.to_string())?;
    if walls.periodic() {
        let gradient = f.pressure_gradient.get(2).copied().unwrap_or(0.0);
        let gravity = case.domain.gravity.get(2).copied().unwrap_or(0.0);
        flow.body_force = gravity - gradient / f.density;
    }
    Ok(flow)
}

/// The coupled scene of a validated axisymmetric case with grains, on one
/// rank, and its DEM sub-step's ratio to the shortest contact time.
pub fn build(
    case: &Case,
    communicator: Communicator,
) -> Result<(AxisymmetricCoupledSystem, f64), String> {
    if communicator.size() > 1 {
        return Err(format!(
            "an axisymmetric scene runs on one rank, not {}: run it without mpirun (its 2D grid \
             is small; threads share its work)",
            communicator.size()
        ));
    }
    let flow = flow(case)?;
    let dem = scene::build_with(case, communicator, None, |_| 0.0)?;
    let contact_time = crate::simulation::dry::shortest_contact_time(&dem);
    let ratio = case.time.dt_over_contact_time.unwrap_or(0.02);
    let section = case.coupling.clone().unwrap_or_default();
    let density = case.fluid_section().density;
    let mut system = AxisymmetricCoupledSystem::new(
        flow,
        dem,
        density,
        section.coupling(),
        ratio * contact_time,
    )
    .map_err(|e| e.to_string())?;
    system.immersed.layer = section.layer_forcing();
    if section.wall_layer == WallLayerName::Free {
        system.immersed.free_end_layers = EndLayers::at_walls(&system.flow.walls);
    }
    Ok((system, contact_time))
}
