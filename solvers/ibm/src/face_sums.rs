//! The forcing's sums on the grid's faces and its update of the velocity
//! (eq. 7): for every face, `Σ_p β_p` and `Σ_p β_p U_p` over the bodies
//! whose support holds it, then `V += (Σ β_p U_p − Σ β_p V)/max(1, Σ β_p)`.
//! Here, and in the shares of pressed grains (`overlaps.rs`), bodies meet
//! on the same faces: each face adds its bodies in list order on any
//! number of threads, so the bits do not depend on them.

use grainflow_fluid::{Block, Grid};
use rayon::prelude::*;

use crate::body::Body;
use crate::exponents::{forced_fraction, Exponents};
use crate::faces::{prefetch, Row, PREFETCH_ROWS};
use crate::forcing::{Bodies, ImmersedBoundaries};

impl ImmersedBoundaries {
    /// Adds `Σ_p β_p` and `Σ_p β_p U_p` of `bodies`, `β = 1 − (1 − α)^exponent`
    /// of each body's fraction on the face, into the scratch sums the
    /// forcing reads (`total_fraction`, `solid_velocity`).
    ///
    /// The planes of the slowest axis are cut into slabs shared among
    /// threads (one slab on one thread); within a slab the bodies that
    /// reach it add their rows one body after the other, in list order, so
    /// each face sums its bodies in list order whatever the number of
    /// threads, and a body's rows are read where they lie, one after the
    /// other (plane by plane, a body's rows of each plane were fetched
    /// apart, which took twice as long).
    pub(crate) fn add_forcing_sums(&mut self, grid: &Grid, bodies: &Bodies, exponents: &Exponents) {
        let dim = grid.dim();
        let slow = dim - 1;
        let plane = grid.stride(slow);
        let planes = grid.padded()[slow];
        let threads = rayon::current_num_threads();
        // Four slabs a thread even out the bodies per slab.
        let thickness = match threads {
            1 => planes,
            _ => planes.div_ceil(4 * threads).max(1),
        };
        for component in 0..dim {
            let fill_slab = |slab: usize, total: &mut [f64], target: &mut [f64]| {
                let layers = slab * thickness..((slab + 1) * thickness).min(planes);
                let first = layers.start * plane;
                for body in &bodies.list {
                    let faces = &body.faces[component];
                    let reach = faces.stencil.start[slow]..faces.stencil.end[slow];
                    if faces.is_empty() || reach.end <= layers.start || reach.start >= layers.end {
                        continue;
                    }
                    let rows = faces.rows_in(dim, layers.clone());
                    add_body_sums(body, component, rows, exponents, total, target, first);
                }
            };
            let (total, target) = (
                &mut self.total_fraction[component],
                &mut self.solid_velocity[component],
            );
            let slab = thickness * plane;
            if threads == 1 {
                fill_slab(0, total, target);
            } else {
                total
                    .par_chunks_mut(slab)
                    .zip(target.par_chunks_mut(slab))
                    .enumerate()
                    .for_each(|(index, (total, target))| fill_slab(index, total, target));
            }
        }
    }

    /// [`ImmersedBoundaries::add_forcing_sums`] of one body alone, on one
    /// thread: bodies added one after the other in list order, each as soon
    /// as its fractions are made (while they are in cache), give every face
    /// the same sum, in the same order, as the pass over all of them.
    pub(crate) fn add_forcing_sums_of(&mut self, grid: &Grid, body: &Body, exponents: &Exponents) {
        for component in 0..grid.dim() {
            let faces = &body.faces[component];
            if !faces.is_empty() {
                let (total, target) = (
                    &mut self.total_fraction[component],
                    &mut self.solid_velocity[component],
                );
                add_body_sums(body, component, faces.rows(), exponents, total, target, 0);
            }
        }
    }
}

/// Adds `β` and `β U` of `body` on its `rows` of faces of `component` into
/// `total` and `target`, which start at the flat face index `first`.
fn add_body_sums<'a>(
    body: &Body,
    component: usize,
    rows: impl Iterator<Item = Row<'a>> + Clone,
    exponents: &Exponents,
    total: &mut [f64],
    target: &mut [f64],
    first: usize,
) {
    let exponent = exponents.of(body.particle);
    let step = body.faces[component].step;
    let mut ahead = rows.clone().skip(PREFETCH_ROWS);
    for row in rows {
        if let Some(later) = ahead.next() {
            let later = later.first - first..later.first - first + later.len();
            prefetch(&[total, target], &later);
        }
        let (base, slope) = body.rigid_along(&row, component, step);
        let at = row.first - first..row.first - first + row.len();
        let sums = total[at.clone()].iter_mut().zip(&mut target[at]);
        for (i, (alpha, (total, target))) in row.alpha.iter().zip(sums).enumerate() {
            let beta = forced_fraction(*alpha, exponent);
            *total += beta;
            *target += beta * (base + i as f64 * slope);
        }
    }
}

impl ImmersedBoundaries {
    /// [`force_block`] on the block each component's faces of `bodies`
    /// span.
    pub(crate) fn force_touched<const KEEP_PREDICTION: bool>(
        &mut self,
        grid: &Grid,
        velocity: &mut [Vec<f64>],
        bodies: &Bodies,
    ) {
        for component in 0..grid.dim() {
            if let Some(block) = touched_block(bodies, component) {
                force_block::<KEEP_PREDICTION>(
                    grid,
                    &block,
                    &mut velocity[component],
                    &mut self.total_fraction[component],
                    &mut self.solid_velocity[component],
                );
            }
        }
    }
}

/// The smallest block that holds the faces of `component` of every body.
pub(crate) fn touched_block(bodies: &Bodies, component: usize) -> Option<Block> {
    let mut touched: Option<Block> = None;
    for body in &bodies.list {
        let faces = &body.faces[component];
        if faces.is_empty() {
            continue;
        }
        let stencil = faces.stencil;
        touched = Some(match touched {
            None => stencil,
            Some(union) => Block {
                start: [0, 1, 2].map(|a| union.start[a].min(stencil.start[a])),
                end: [0, 1, 2].map(|a| union.end[a].max(stencil.end[a])),
            },
        });
    }
    touched
}

/// For each plane of the slowest axis (`planes` of them), the bodies
/// whose faces of `component` reach it, in list order: a plane's sums
/// visit only those.
pub(crate) fn bodies_by_plane(
    bodies: &Bodies,
    component: usize,
    slow: usize,
    planes: usize,
) -> Vec<Vec<usize>> {
    let mut reaching = vec![Vec::new(); planes];
    for (index, body) in bodies.list.iter().enumerate() {
        let faces = &body.faces[component];
        if !faces.is_empty() {
            for plane in faces.stencil.start[slow]..faces.stencil.end[slow] {
                reaching[plane].push(index);
            }
        }
    }
    reaching
}

/// `V += (Σ β_p U_p − Σ β_p V) / max(1, Σ β_p)` (eq. 7 with the weights
/// of overlapping bodies) on the faces of `block`, and the two sums set
/// back to zero there, or with `KEEP_PREDICTION` the first set to the
/// velocity before the forcing (`deferred_loads.rs`): one pass over the
/// three fields, the planes of the slowest axis shared among threads (each
/// face computed alone).
pub(crate) fn force_block<const KEEP_PREDICTION: bool>(
    grid: &Grid,
    block: &Block,
    velocity: &mut [f64],
    total: &mut [f64],
    target: &mut [f64],
) {
    let slow = grid.dim() - 1;
    let plane = grid.stride(slow);
    let mut inner = *block;
    inner.start[slow] = 0;
    inner.end[slow] = 1;
    let rows = |velocity: &mut [f64], total: &mut [f64], target: &mut [f64]| {
        for k in inner.start[2]..inner.end[2] {
            for j in inner.start[1]..inner.end[1] {
                let faces = grid.index(inner.start[0], j, k)..grid.index(inner.end[0], j, k);
                let rows = velocity[faces.clone()]
                    .iter_mut()
                    .zip(&mut total[faces.clone()])
                    .zip(&mut target[faces]);
                for ((v, total), target) in rows {
                    let predicted = *v;
                    *v += (*target - *total * predicted) / total.max(1.0);
                    *total = if KEEP_PREDICTION { predicted } else { 0.0 };
                    *target = 0.0;
                }
            }
        }
    };
    let planes = block.start[slow] * plane..block.end[slow] * plane;
    let (velocity, total, target) = (
        &mut velocity[planes.clone()],
        &mut total[planes.clone()],
        &mut target[planes],
    );
    if rayon::current_num_threads() == 1 {
        let planes = velocity
            .chunks_mut(plane)
            .zip(total.chunks_mut(plane))
            .zip(target.chunks_mut(plane));
        for ((velocity, total), target) in planes {
            rows(velocity, total, target);
        }
    } else {
        velocity
            .par_chunks_mut(plane)
            .zip(total.par_chunks_mut(plane))
            .zip(target.par_chunks_mut(plane))
            .for_each(|((velocity, total), target)| rows(velocity, total, target));
    }
}
