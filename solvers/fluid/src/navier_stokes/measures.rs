//! Measures of the flow over every rank: the largest divergence and the
//! kinetic energy.

use super::FlowSolver;
use crate::boundary::EndKind;
use crate::operators::divergence;

impl FlowSolver {
    /// Largest `|D u|` over the cells of every rank (1/s).
    pub fn max_divergence(&mut self) -> f64 {
        divergence(&self.grid, &self.velocity, &mut self.divergence);
        let divergence = &self.divergence;
        let largest = self
            .grid
            .par_max(&self.grid.cell_block(), |index, _| divergence[index].abs());
        self.ranks.communicator.max(largest)
    }

    /// `½ ∫ |u|² dV` over the domain, each component integrated on its own
    /// faces (trapezoidal weights ½ on wall faces; along a stretched axis
    /// each value weighted by its cell width or face control length).
    pub fn kinetic_energy(&self) -> f64 {
        let grid = &self.grid;
        let line = grid.line_axis();
        let uniform = grid.is_uniform(line);
        let mut sum = 0.0;
        for (component, field) in self.velocity.iter().enumerate() {
            // Wall faces of this rank (prescribed, not unknowns) join the
            // sum with weight ½.
            let mut block = self.velocity_unknowns[component];
            let ends = &self.velocity_ends[component][component];
            let walls = ends.map(|end| end.kind == EndKind::DirichletFace);
            if walls[0] {
                block.start[component] -= 1;
            }
            if walls[1] {
                block.end[component] += 1;
            }
            let (first, last) = (block.start[component], block.end[component] - 1);
            let on_face = component == line;
            sum += grid.par_sum(&block, |index, point| {
                let on_wall = (walls[0] && point[component] == first)
                    || (walls[1] && point[component] == last);
                let weight = if on_wall { 0.5 } else { 1.0 };
                let length = match (uniform, on_face) {
                    (true, _) => 1.0,
                    (false, true) => grid.gap(line, point[line]),
                    (false, false) => grid.width(line, point[line]),
                };
                weight * length * field[index] * field[index]
            });
        }
        let volume = if uniform {
            grid.cell_volume()
        } else {
            grid.section_area()
        };
        self.ranks.communicator.sum(0.5 * sum * volume)
    }
}
