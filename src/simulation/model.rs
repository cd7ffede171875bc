//! The scene a run advances, whatever it holds: grains alone, a fluid
//! alone, or grains in a fluid. The time loop sees it through this narrow
//! interface: advance one step, the time, what the writers record, the
//! state to save and restore, and the summary at the end.

use super::axisymmetric::AxisymmetricModel;
use super::coupled::CoupledModel;
use super::dry::DryModel;
use super::fluid::FluidModel;
use crate::case::{Case, Geometry};
use crate::checkpoint::extent::Extent;
use crate::RunError;
use grainflow_core::{Communicator, State, StateError};
use grainflow_dem::DemSystem;
use grainflow_fluid::FlowSolver;
use serde_json::{Map, Value};
use std::path::Path;

/// What a field file of the flow is written from.
pub struct FieldOutput<'a> {
    pub solver: &'a mut FlowSolver,
    pub density: f64,
    pub solid_fraction: Option<Vec<f64>>,
}

pub enum Model {
    Dry(Box<DryModel>),
    Fluid(Box<FluidModel>),
    Coupled(Box<CoupledModel>),
    /// Grains on the axis of an (r, z) fluid.
    Axisymmetric(Box<AxisymmetricModel>),
}

impl Model {
    /// The scene of a validated case; refuses (before anything is written)
    /// what cannot run.
    pub fn build(case: &Case, communicator: Communicator) -> Result<Self, RunError> {
        Ok(if case.domain.geometry == Geometry::Axisymmetric {
            Model::Axisymmetric(Box::new(AxisymmetricModel::build(case, communicator)?))
        } else if !case.has_grains() {
            Model::Fluid(Box::new(FluidModel::build(case, communicator)?))
        } else if case.fluid.is_some() {
            Model::Coupled(Box::new(CoupledModel::build(case, communicator)?))
        } else {
            Model::Dry(Box::new(DryModel::build(case, communicator)?))
        })
    }

    /// What the kind of scene is called in a checkpoint.
    pub fn kind(&self) -> &'static str {
        match self {
            Model::Dry(_) => "dry",
            Model::Fluid(_) => "fluid",
            Model::Coupled(_) => "coupled",
            Model::Axisymmetric(_) => "axisymmetric",
        }
    }

    /// The log lines that describe the scene, and its warnings.
    pub fn description(&self) -> (&[String], &[String]) {
        match self {
            Model::Dry(m) => (&m.description, &m.warnings),
            Model::Fluid(m) => (&m.description, &m.warnings),
            Model::Coupled(m) => (&m.description, &m.warnings),
            Model::Axisymmetric(m) => (&m.description, &m.warnings),
        }
    }

    pub fn time(&self) -> f64 {
        match self {
            Model::Dry(m) => m.system.time,
            Model::Fluid(m) => m.solver.time,
            Model::Coupled(m) => m.system.flow.time,
            Model::Axisymmetric(m) => m.system.flow.time,
        }
    }

    pub fn steps(&self) -> u64 {
        match self {
            Model::Dry(m) => m.system.steps,
            Model::Fluid(m) => m.steps(),
            Model::Coupled(m) => m.steps(),
            Model::Axisymmetric(m) => m.steps(),
        }
    }

    /// The last step's length (the first step's before any).
    pub fn dt(&self) -> f64 {
        match self {
            Model::Dry(m) => m.dt(),
            Model::Fluid(m) => m.dt(),
            Model::Coupled(m) => m.dt(),
            Model::Axisymmetric(m) => m.dt(),
        }
    }

    /// Whether the run has reached `end` (within half a step for the fixed
    /// step of the grains; the flow's last step lands on it).
    pub fn reached(&self, end: f64) -> bool {
        match self {
            Model::Dry(m) => m.reached(end),
            Model::Fluid(m) => m.reached(end),
            Model::Coupled(m) => m.reached(end),
            Model::Axisymmetric(m) => m.reached(end),
        }
    }

    /// Advances one step towards `end`: the lines for the log, or the
    /// diagnosis of a failure (the state is then not kept).
    pub fn advance(&mut self, case: &Case, end: f64) -> Result<Vec<String>, String> {
        match self {
            Model::Dry(m) => m.advance(),
            Model::Fluid(m) => m.advance(case, end).map(|()| Vec::new()),
            Model::Coupled(m) => m.advance(case, end).map(|()| Vec::new()),
            Model::Axisymmetric(m) => m.advance(case, end).map(|()| Vec::new()),
        }
    }

    /// Why the run stops before its end time (grains at rest), if it does.
    pub fn stop_before_end(&mut self) -> Option<String> {
        match self {
            Model::Dry(m) => m.at_rest(),
            _ => None,
        }
    }

    /// The grains, if the scene has any.
    pub fn grains(&self) -> Option<&DemSystem> {
        match self {
            Model::Dry(m) => Some(&m.system),
            Model::Fluid(_) => None,
            Model::Coupled(m) => Some(&m.system.dem),
            Model::Axisymmetric(m) => Some(&m.system.dem),
        }
    }

    /// The Cartesian flow, if the scene has one (an axisymmetric scene's
    /// is [`Model::axisymmetric`]).
    pub fn flow(&self) -> Option<&FlowSolver> {
        match self {
            Model::Dry(_) | Model::Axisymmetric(_) => None,
            Model::Fluid(m) => Some(&m.solver),
            Model::Coupled(m) => Some(&m.system.flow),
        }
    }

    /// The (r, z) scene, if the scene is axisymmetric.
    pub fn axisymmetric(&mut self) -> Option<&mut AxisymmetricModel> {
        match self {
            Model::Axisymmetric(m) => Some(m),
            _ => None,
        }
    }

    /// What this rank's saved state holds.
    pub fn held_extent(&self) -> Extent {
        Extent::held(self.grains(), self.flow())
    }

    /// What this rank needs to take its share on a resume on another
    /// number of ranks.
    pub fn needed_extent(&self) -> Extent {
        Extent::needed(self.grains(), self.flow())
    }

    pub fn has_flow(&self) -> bool {
        !matches!(self, Model::Dry(_))
    }

    /// A row of the flow's series after a step of `dt`, if the scene has a
    /// fluid.
    pub fn flow_row(&self, dt: f64) -> Option<[f64; 6]> {
        match self {
            Model::Dry(_) => None,
            Model::Fluid(m) => Some(m.series_row()),
            Model::Coupled(m) => Some(m.flow_row(dt)),
            Model::Axisymmetric(m) => Some(m.flow_row(dt)),
        }
    }

    /// The flow and what its field files hold besides velocity, pressure
    /// and vorticity (the solid fraction of grains in a fluid), if the
    /// scene has a fluid.
    pub fn field_output(&mut self) -> Option<FieldOutput<'_>> {
        match self {
            Model::Dry(_) | Model::Axisymmetric(_) => None,
            Model::Fluid(m) => Some(FieldOutput {
                density: m.density(),
                solver: &mut m.solver,
                solid_fraction: None,
            }),
            Model::Coupled(m) => {
                let system = &mut m.system;
                let solid = system
                    .immersed
                    .cell_solid_fraction(&system.flow.grid, &system.dem.particles);
                Some(FieldOutput {
                    density: system.fluid_density,
                    solver: &mut system.flow,
                    solid_fraction: Some(solid),
                })
            }
        }
    }

    /// The metrics of the scene's analyses at the end (their files written;
    /// collective). `failed`: the run stopped on a failure.
    pub fn metrics(
        &mut self,
        case: &Case,
        out: &Path,
        failed: bool,
    ) -> std::io::Result<Map<String, Value>> {
        match self {
            Model::Dry(m) => m.finish(out, failed),
            Model::Fluid(m) if !failed => Ok(m.metrics(case)),
            Model::Coupled(m) if !failed => Ok(m.metrics()),
            Model::Axisymmetric(m) if !failed => Ok(m.metrics()),
            _ => Ok(Map::new()),
        }
    }

    /// The scene's own entries of `summary.json`.
    pub fn summary(&self, case: &Case, wall_seconds: f64) -> Map<String, Value> {
        match self {
            Model::Dry(m) => m.summary(case, wall_seconds),
            Model::Fluid(m) => m.summary(wall_seconds),
            Model::Coupled(m) => m.summary(case, wall_seconds),
            Model::Axisymmetric(m) => m.summary(case, wall_seconds),
        }
    }

    /// The log's last line after `done: <stop reason>; `.
    pub fn done_line(&self, wall_seconds: f64) -> String {
        match self {
            Model::Dry(m) => m.done_line(wall_seconds),
            Model::Fluid(m) => m.done_line(wall_seconds),
            Model::Coupled(m) => m.done_line(wall_seconds),
            Model::Axisymmetric(m) => m.done_line(wall_seconds),
        }
    }

    /// Saves everything the next step reads (this rank's share).
    pub fn save_state(&self, state: &mut State) {
        match self {
            Model::Dry(m) => m.save_state(state),
            Model::Fluid(m) => m.save_state(state),
            Model::Coupled(m) => m.save_state(state),
            Model::Axisymmetric(m) => m.save_state(state),
        }
    }

    /// Takes back the states saved on every rank of a job of another size
    /// (all read by every rank; collective): grains by where they are, the
    /// flow block by block; the run continues within round-off.
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        match self {
            Model::Dry(m) => m.restore_redistributed(states),
            Model::Fluid(m) => m.restore_redistributed(states),
            Model::Coupled(m) => m.restore_redistributed(states),
            // One rank only: the states are this rank's.
            Model::Axisymmetric(m) => m.restore_state(&mut states[0]),
        }
    }

    /// Takes back what [`Model::save_state`] saved, into a scene built from
    /// the same case on a job of the same size.
    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        match self {
            Model::Dry(m) => m.restore_state(state),
            Model::Fluid(m) => m.restore_state(state),
            Model::Coupled(m) => m.restore_state(state),
            Model::Axisymmetric(m) => m.restore_state(state),
        }
    }
}
