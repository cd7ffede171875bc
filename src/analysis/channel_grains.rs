//! The grains of a channel in bins along the slope and in layers across
//! it: the mass profile h(x), which bins flow, the raised volume that
//! places a front, and the velocity profile u_x(z) with its static/flowing
//! interface ([`super::ErodibleBed`]).

use super::erodible_bed::{BIN_DIAMETERS, FRONT_GRAINS, PROBE_DIAMETERS};
use grainflow_core::{Dimension, Vec3};
use grainflow_dem::DemSystem;

/// The grains in the channel's frame: centres, heights along the bed
/// normal above the floor, radii, velocities along x.
pub(super) struct Grains {
    pub(super) centre: Vec<Vec3>,
    pub(super) radius: Vec<f64>,
    pub(super) fixed: Vec<bool>,
    pub(super) velocity_x: Vec<f64>,
    pub(super) mass: Vec<f64>,
    pub(super) normal: usize,
    pub(super) floor: f64,
    /// Volume of a grain of radius r per unit span (2D) or the grain's
    /// volume (3D), and the span.
    pub(super) dimension: Dimension,
    pub(super) span: f64,
}

impl Grains {
    pub(super) fn of(system: &DemSystem) -> Self {
        let p = &system.particles;
        let n = p.n_owned;
        let g = system.domain.gravity;
        let normal = if system.domain.dimension == Dimension::Two {
            1
        } else {
            (1..3)
                .max_by(|&a, &b| g[a].abs().total_cmp(&g[b].abs()))
                .unwrap()
        };
        let span = match system.domain.dimension {
            Dimension::Two => 1.0,
            Dimension::Three => system.domain.extent()[3 - normal],
        };
        Grains {
            centre: p.position[..n].to_vec(),
            radius: p.radius[..n].to_vec(),
            fixed: (0..n).map(|k| p.is_fixed(k)).collect(),
            velocity_x: (0..n).map(|k| p.velocity[k].x).collect(),
            mass: p.mass[..n].to_vec(),
            normal,
            floor: system.domain.lower[normal],
            dimension: system.domain.dimension,
            span,
        }
    }

    /// Height of grain k's centre above the floor.
    pub(super) fn height(&self, k: usize) -> f64 {
        self.centre[k][self.normal] - self.floor
    }

    /// The largest down-slope velocity of a mobile grain (zero where none
    /// moves down the slope).
    pub(super) fn fastest_down_slope(&self) -> f64 {
        (0..self.centre.len())
            .filter(|&k| !self.fixed[k])
            .map(|k| self.velocity_x[k])
            .fold(0.0, f64::max)
    }

    /// Mean solid volume of the mobile grains per unit span.
    pub(super) fn mean_volume_per_span(&self) -> f64 {
        let mobile: Vec<usize> = (0..self.centre.len()).filter(|&k| !self.fixed[k]).collect();
        mobile.iter().map(|&k| self.volume_per_span(k)).sum::<f64>() / mobile.len().max(1) as f64
    }

    /// The raised volume per unit span that places the front:
    /// [`FRONT_GRAINS`] mean grains per mean diameter `diameter` of span.
    /// In 2D, five discs; in 3D, the same raised thickness across the
    /// width (five spheres over a channel 25 diameters wide would be a
    /// few stragglers ahead of the flow).
    pub(super) fn front_volume(&self, diameter: f64) -> f64 {
        let rows = match self.dimension {
            Dimension::Two => 1.0,
            Dimension::Three => self.span / diameter,
        };
        FRONT_GRAINS * self.mean_volume_per_span() * rows
    }

    /// Solid volume of grain k per unit span.
    pub(super) fn volume_per_span(&self, k: usize) -> f64 {
        let r = self.radius[k];
        match self.dimension {
            Dimension::Two => std::f64::consts::PI * r * r,
            Dimension::Three => 4.0 / 3.0 * std::f64::consts::PI * r * r * r / self.span,
        }
    }
}

/// Bins along x from the back wall.
pub(super) struct Bins {
    pub(super) lower: f64,
    pub(super) width: f64,
    pub(super) count: usize,
}

impl Bins {
    pub(super) fn new(system: &DemSystem, diameter: f64) -> Self {
        let width = BIN_DIAMETERS * diameter;
        Bins {
            lower: system.domain.lower.x,
            width,
            count: ((system.domain.extent().x / width).ceil() as usize).max(1),
        }
    }

    pub(super) fn of(&self, x: f64) -> usize {
        (((x - self.lower) / self.width).max(0.0) as usize).min(self.count - 1)
    }

    pub(super) fn centre(&self, bin: usize) -> f64 {
        self.lower + (bin as f64 + 0.5) * self.width
    }

    /// h(x): the solid volume of the mobile grains centred in each bin over
    /// its width.
    pub(super) fn heights(&self, grains: &Grains) -> Vec<f64> {
        let mut h = vec![0.0; self.count];
        for k in 0..grains.centre.len() {
            if !grains.fixed[k] {
                h[self.of(grains.centre[k].x)] += grains.volume_per_span(k) / self.width;
            }
        }
        h
    }

    /// Whether the mobile grains centred in each bin move down the slope
    /// at `speed` or faster on average (mass-weighted).
    pub(super) fn flowing(&self, grains: &Grains, speed: f64) -> Vec<bool> {
        let mut momentum = vec![0.0; self.count];
        let mut mass = vec![0.0; self.count];
        for k in 0..grains.centre.len() {
            if !grains.fixed[k] {
                let b = self.of(grains.centre[k].x);
                momentum[b] += grains.mass[k] * grains.velocity_x[k];
                mass[b] += grains.mass[k];
            }
        }
        (0..self.count)
            .map(|b| mass[b] > 0.0 && momentum[b] >= speed * mass[b])
            .collect()
    }
}

/// The position beyond which the volume (per unit span) of the mobile
/// grains above their h at the release in the `flowing` bins,
/// `∫ max(h − initial, 0) dx` from the end of the channel, reaches
/// `volume`; `None` where it nowhere does.
pub(super) fn raised_front(
    bins: &Bins,
    heights: &[f64],
    initial: &[f64],
    flowing: &[bool],
    volume: f64,
) -> Option<f64> {
    let mut beyond = 0.0;
    for b in (0..bins.count).rev().filter(|&b| flowing[b]) {
        let raised = (heights[b] - initial[b]).max(0.0) * bins.width;
        if beyond + raised >= volume {
            // Uniform within the bin: the share still needed from its end.
            let needed = (volume - beyond) / raised;
            return Some(bins.lower + (b as f64 + 1.0 - needed) * bins.width);
        }
        beyond += raised;
    }
    None
}

/// Mass-weighted mean u_x of the mobile grains within a window of
/// [`PROBE_DIAMETERS`] mean diameters around `x`, in layers one mean
/// diameter thick from the rigid bed's top (`rigid_top` above the floor): (height of the layer's centre
/// above the rigid bed, u_x, grains), the layers that hold grains.
pub(super) fn velocity_layers(
    grains: &Grains,
    x: f64,
    diameter: f64,
    rigid_top: f64,
) -> Vec<(f64, f64, usize)> {
    let d = diameter;
    let half = 0.5 * PROBE_DIAMETERS * d;
    let mut layers: Vec<(f64, f64, usize)> = Vec::new();
    for k in 0..grains.centre.len() {
        if grains.fixed[k] || (grains.centre[k].x - x).abs() > half {
            continue;
        }
        let z = grains.height(k) - rigid_top;
        let layer = (z / d).max(0.0) as usize;
        if layers.len() <= layer {
            layers.resize(layer + 1, (0.0, 0.0, 0));
        }
        let l = &mut layers[layer];
        l.0 += grains.mass[k];
        l.1 += grains.mass[k] * grains.velocity_x[k];
        l.2 += 1;
    }
    layers
        .into_iter()
        .enumerate()
        .filter(|(_, l)| l.2 > 0)
        .map(|(i, l)| ((i as f64 + 0.5) * d, l.1 / l.0, l.2))
        .collect()
}

/// The static/flowing interface of a column of layers (from
/// [`velocity_layers`]): the bottom of the lowest layer moving down the
/// slope at `flowing_speed` or faster (the paper's criterion u_x < 1
/// cm/s for static grains), or the surface where none does; and the
/// surface, the top of the highest layer. `None` for an empty column.
pub(super) fn static_flowing(
    layers: &[(f64, f64, usize)],
    diameter: f64,
    flowing_speed: f64,
) -> Option<(f64, f64)> {
    let surface = layers.last()?.0 + 0.5 * diameter;
    let interface = layers
        .iter()
        .find(|l| l.1 >= flowing_speed)
        .map_or(surface, |l| l.0 - 0.5 * diameter);
    Some((interface, surface))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grains(centres: &[[f64; 2]], velocities: &[f64]) -> Grains {
        let n = centres.len();
        Grains {
            centre: centres.iter().map(|c| Vec3::new(c[0], c[1], 0.0)).collect(),
            radius: vec![0.5; n],
            fixed: vec![false; n],
            velocity_x: velocities.to_vec(),
            mass: vec![1.0; n],
            normal: 1,
            floor: 0.0,
            dimension: Dimension::Two,
            span: 1.0,
        }
    }

    #[test]
    fn h_is_the_solid_volume_of_each_bin_over_its_width() {
        // Unit discs two high over x in [0, 6), one alone at x = 9.5.
        let mut centres = Vec::new();
        for i in 0..6 {
            centres.push([0.5 + i as f64, 0.5]);
            centres.push([0.5 + i as f64, 1.5]);
        }
        centres.push([9.5, 0.5]);
        let g = grains(&centres, &vec![0.0; centres.len()]);
        let bins = Bins {
            lower: 0.0,
            width: 2.0,
            count: 6,
        };
        let heights = bins.heights(&g);
        // Four discs of area π/4 in each bin two wide: h = π/2.
        assert!((heights[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((heights[4] - std::f64::consts::FRAC_PI_8).abs() < 1e-12);
        assert_eq!(heights[3], 0.0);
    }

    #[test]
    fn the_front_leaves_a_few_grains_of_raised_volume_ahead_of_it() {
        // Bins of 2: h raised by 1 over [0, 6), by 0.25 in [8, 10), and
        // the bin [6, 8) raised at the release already.
        let bins = Bins {
            lower: 0.0,
            width: 2.0,
            count: 5,
        };
        let heights = [1.0, 1.0, 1.0, 1.0, 0.25];
        let initial = [0.0, 0.0, 0.0, 1.0, 0.0];
        let all = [true; 5];
        // 0.5 beyond x = 8, none in [6, 8), then 2 in [4, 6): the other
        // 1.5 lie in [4.5, 6).
        let front = raised_front(&bins, &heights, &initial, &all, 2.0);
        assert!((front.unwrap() - 4.5).abs() < 1e-12, "{front:?}");
        // Less than the whole raised volume (6.5) in all: no front.
        assert_eq!(raised_front(&bins, &heights, &initial, &all, 7.0), None);
        // Mass removed (eroded) raises nothing.
        assert_eq!(raised_front(&bins, &initial, &heights, &all, 1.1), None);
        // The bin [8, 10) raised but static (a dilated bed): the 2 lie in
        // [4, 6) alone.
        let static_ahead = [true, true, true, true, false];
        let front = raised_front(&bins, &heights, &initial, &static_ahead, 2.0);
        assert!((front.unwrap() - 4.0).abs() < 1e-12, "{front:?}");
    }

    /// In 2D five discs; in 3D five spheres per diameter of span, the
    /// volume of a layer as thick as five discs' over a diameter.
    #[test]
    fn the_front_needs_five_grains_per_diameter_of_span() {
        let flat = grains(&[[0.5, 0.5], [1.5, 0.5]], &[0.0, 0.0]);
        let disc = std::f64::consts::PI * 0.25;
        assert!((flat.front_volume(1.0) - 5.0 * disc).abs() < 1e-12);
        let channel = Grains {
            dimension: Dimension::Three,
            span: 25.0,
            ..flat
        };
        let sphere = 4.0 / 3.0 * std::f64::consts::PI * 0.125;
        // Per unit span: 5 × 25 spheres over the span of 25.
        assert!((channel.front_volume(1.0) - 5.0 * sphere).abs() < 1e-12);
    }

    #[test]
    fn a_bin_flows_where_its_grains_move_down_the_slope_on_average() {
        // Unit discs: three at rest and one at 1 m/s in [0, 2), four at
        // 0.005 m/s in [2, 4), none in [4, 6).
        let g = grains(
            &[
                [0.5, 0.5],
                [1.5, 0.5],
                [0.5, 1.5],
                [1.5, 1.5],
                [2.5, 0.5],
                [3.5, 0.5],
                [2.5, 1.5],
                [3.5, 1.5],
            ],
            &[0.0, 0.0, 0.0, 1.0, 0.005, 0.005, 0.005, 0.005],
        );
        let bins = Bins {
            lower: 0.0,
            width: 2.0,
            count: 3,
        };
        assert_eq!(bins.flowing(&g, 0.01), [true, false, false]);
    }

    #[test]
    fn the_interface_is_the_bottom_of_the_lowest_flowing_layer() {
        // Unit discs stacked four high at x = 0: the two lower at rest,
        // the two upper at 0.5 and 1 m/s.
        let g = grains(
            &[[0.0, 0.5], [0.0, 1.5], [0.0, 2.5], [0.0, 3.5]],
            &[0.0, 0.005, 0.5, 1.0],
        );
        let layers = velocity_layers(&g, 0.0, 1.0, 0.0);
        assert_eq!(layers.len(), 4);
        assert_eq!(layers[2], (2.5, 0.5, 1));
        let (interface, surface) = static_flowing(&layers, 1.0, 0.01).unwrap();
        assert_eq!((interface, surface), (2.0, 4.0));
        // All at rest: the interface is the surface.
        let rest = grains(&[[0.0, 0.5], [0.0, 1.5]], &[0.0, 0.0]);
        let layers = velocity_layers(&rest, 0.0, 1.0, 0.0);
        assert_eq!(static_flowing(&layers, 1.0, 0.01), Some((2.0, 2.0)));
    }
}
