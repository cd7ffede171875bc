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
        // Where this rank's block lies in the whole grid, for a job of
        // another size.
        state.put_usizes("flow.offset", &self.partition().offset());
        state.put_usizes("flow.cells", &self.grid.cells);
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
        let (offset, cells) = (
            state.take_usizes("flow.offset")?,
            state.take_usizes("flow.cells")?,
        );
        if offset[..] != self.partition().offset() || cells[..] != self.grid.cells {
            return Err(StateError(
                "the saved block of the flow is not this rank's".into(),
            ));
        }
        Ok(())
    }

    /// Takes back the flow from the blocks `states` saved on the ranks of a
    /// job of another size (every old rank's, read by every rank): each
    /// value of this rank's block, ghost layers included, is copied from
    /// the old block that owned its cell (or held it as a ghost, at the
    /// domain's ends). The values are the saved ones exactly.
    pub fn restore_redistributed(&mut self, states: &mut [State]) -> Result<(), StateError> {
        struct Block {
            offset: [i64; 3],
            cells: [i64; 3],
            velocity: Vec<Vec<f64>>,
            pressure: Vec<f64>,
        }
        let ghost: [i64; 3] = [0, 1, 2].map(|a| self.grid.ghost(a) as i64);
        let mut blocks = Vec::with_capacity(states.len());
        let mut scalars = None;
        for state in states.iter_mut() {
            let offset = state.take_usizes("flow.offset")?;
            let cells = state.take_usizes("flow.cells")?;
            if offset.len() != 3 || cells.len() != 3 {
                return Err(StateError(
                    "flow.offset and flow.cells hold three numbers".into(),
                ));
            }
            let offset = [0, 1, 2].map(|a| offset[a] as i64);
            let cells = [0, 1, 2].map(|a| cells[a] as i64);
            let len: i64 = (0..3).map(|a| cells[a] + 2 * ghost[a]).product();
            let velocity = (0..self.velocity.len())
                .map(|c| state.take_f64s_of_len(&format!("flow.velocity.{c}"), len as usize))
                .collect::<Result<Vec<_>, _>>()?;
            let pressure = state.take_f64s_of_len("flow.pressure", len as usize)?;
            scalars = Some((
                state.take_f64("flow.time")?,
                state.take_f64s_of_len("flow.flow_rate_gradient", 3)?,
            ));
            blocks.push(Block {
                offset,
                cells,
                velocity,
                pressure,
            });
        }
        let Some((time, gradient)) = scalars else {
            return Err(StateError("no saved flow to take".into()));
        };
        let here = self.partition().offset().map(|o| o as i64);
        let padded = self.grid.padded();
        // The old block and flat index holding global point `g` (padded
        // coordinates less the ghost width): one that owns it, else one
        // that holds it in its ghost layers.
        let locate = |g: [i64; 3]| -> Option<(usize, usize)> {
            let index = |b: &Block| -> Option<usize> {
                let p = [0, 1, 2].map(|a| g[a] - b.offset[a] + ghost[a]);
                let size = [0, 1, 2].map(|a| b.cells[a] + 2 * ghost[a]);
                ((0..3).all(|a| p[a] >= 0 && p[a] < size[a]))
                    .then(|| (p[0] + size[0] * (p[1] + size[1] * p[2])) as usize)
            };
            let owns =
                |b: &Block| (0..3).all(|a| g[a] >= b.offset[a] && g[a] < b.offset[a] + b.cells[a]);
            blocks
                .iter()
                .position(owns)
                .or_else(|| blocks.iter().position(|b| index(b).is_some()))
                .and_then(|n| index(&blocks[n]).map(|i| (n, i)))
        };
        for k in 0..padded[2] {
            for j in 0..padded[1] {
                for i in 0..padded[0] {
                    let g = [i as i64, j as i64, k as i64];
                    let g = [0, 1, 2].map(|a| g[a] - ghost[a] + here[a]);
                    let Some((n, at)) = locate(g) else {
                        return Err(StateError(
                            "the saved blocks of the flow do not cover this rank's".into(),
                        ));
                    };
                    let index = self.grid.index(i, j, k);
                    for (c, field) in self.velocity.iter_mut().enumerate() {
                        field[index] = blocks[n].velocity[c][at];
                    }
                    self.pressure[index] = blocks[n].pressure[at];
                }
            }
        }
        self.time = time;
        self.flow_rate_gradient.copy_from_slice(&gradient);
        Ok(())
    }
}
