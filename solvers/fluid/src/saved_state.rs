//! What a checkpoint keeps of the flow: the velocity and pressure with
//! their ghost layers, the time, and the pressure gradient that held a bulk
//! velocity over the last step. Nothing else carries from one step to the
//! next: the first RK3 stage takes no share of the previous tendency
//! (ζ₁ = 0), and the solvers are rebuilt from the case.

use crate::FlowSolver;
use grainflow_core::{State, StateError};

impl FlowSolver {
    /// Saves this rank's share of the flow under `flow.`.
    pub fn save_state(&self, state: &mut State) {
        for (component, values) in self.velocity.iter().enumerate() {
            state.put_f64s(&format!("flow.velocity.{component}"), values);
        }
        state.put_f64s("flow.pressure", &self.pressure);
        state.put_f64("flow.time", self.time);
        state.put_f64s("flow.flow_rate_gradient", &self.flow_rate_gradient);
    }

    /// Takes back what [`FlowSolver::save_state`] saved, into a flow built
    /// from the same case on a rank of a job of the same size.
    pub fn restore_state(&mut self, state: &mut State) -> Result<(), StateError> {
        for component in 0..self.velocity.len() {
            let len = self.velocity[component].len();
            self.velocity[component] =
                state.take_f64s_of_len(&format!("flow.velocity.{component}"), len)?;
        }
        self.pressure = state.take_f64s_of_len("flow.pressure", self.pressure.len())?;
        self.time = state.take_f64("flow.time")?;
        let gradient = state.take_f64s_of_len("flow.flow_rate_gradient", 3)?;
        self.flow_rate_gradient.copy_from_slice(&gradient);
        Ok(())
    }
}
