//! The staggered (r, z) grid of an axisymmetric scene.
//!
//! The domain is the cylinder `0 ≤ r ≤ R`, `z_lower ≤ z ≤ z_upper`. Its
//! cells are annuli: cell `(i, k)` spans `r_{i−1} ≤ r ≤ r_i` and one step
//! `h` of z, with volume `2π r̄_i w_i h`, where `w_i = r_i − r_{i−1}` is its
//! width and `r̄_i = (r_{i−1} + r_i)/2` its centre. Pressure lives at the
//! centres, `u_r` on the faces `r = r_i` (the axis `r_0 = 0` and the outer
//! wall `r_n = R` among them, where it vanishes), `u_z` on the faces
//! normal to z.
//!
//! The radial faces may be spaced at will (uniform, the uniform core and
//! arithmetic growth of Izard et al. 2014 §3.1, or a tanh clustering at
//! the outer wall): the solvers eliminate along r. The axial spacing is
//! uniform: the solvers diagonalise z by transforms.
//!
//! Every field is a flat `Vec<f64>` over the padded block of
//! `(n_r + 2) × (n_z + 2)` entries, r fastest. Padded index `i = 1..=n_r`
//! is cell `i` (`i = 0` lies across the axis, `n_r + 1` beyond the outer
//! wall); face `i` is the outer face of cell `i`, so faces 0 and `n_r` are
//! the axis and the wall. Along z the same with `k`, faces 0 and `n_z`
//! being the two ends.

use crate::error::FluidError;

/// The (r, z) grid.
#[derive(Clone, Debug)]
pub struct RzGrid {
    /// Cells along r and along z.
    pub cells: [usize; 2],
    /// Outer radius `R` (m).
    pub radius: f64,
    /// Lower and upper ends along z (m).
    pub z_range: [f64; 2],
    /// Axial step `h` (m).
    pub dz: f64,
    /// Face radii `r_i`, padded `i = 0..=n_r + 1` (`r_{n_r+1}` mirrors the
    /// last width beyond the wall).
    faces: Vec<f64>,
    /// Centre radii `r̄_i`, padded `i = 0..=n_r + 1` (`r̄_0 = −r̄_1`, the
    /// mirror across the axis).
    centres: Vec<f64>,
    /// Widths `w_i`, padded (ghosts repeat their neighbour's width).
    widths: Vec<f64>,
    /// Distances `g_i = r̄_{i+1} − r̄_i` between centres across face `i`.
    gaps: Vec<f64>,
}

impl RzGrid {
    /// `cells[0]` equal annuli out to `radius` and `cells[1]` equal steps
    /// over `z_range`.
    pub fn uniform(cells: [usize; 2], radius: f64, z_range: [f64; 2]) -> Result<Self, FluidError> {
        let faces: Vec<f64> = (0..=cells[0])
            .map(|i| radius * i as f64 / cells[0].max(1) as f64)
            .collect();
        Self::from_radial_faces(&faces, cells[1], z_range)
    }

    /// The grid whose radial faces are `faces` (`0 = r_0 < r_1 < … < r_n = R`)
    /// and `z_cells` equal steps over `z_range`.
    pub fn from_radial_faces(
        faces: &[f64],
        z_cells: usize,
        z_range: [f64; 2],
    ) -> Result<Self, FluidError> {
        let n = faces.len().saturating_sub(1);
        if n < 2 {
            return Err(FluidError::Parameter(format!(
                "an (r, z) grid needs at least 2 cells along r, got {n}"
            )));
        }
        if faces[0] != 0.0 {
            return Err(FluidError::Parameter(format!(
                "the first radial face must be the axis, r = 0, got {}",
                faces[0]
            )));
        }
        if let Some(i) = (1..=n).find(|&i| !faces[i].is_finite() || faces[i] <= faces[i - 1]) {
            return Err(FluidError::Parameter(format!(
                "radial faces must increase: r_{} = {} after r_{} = {}",
                i,
                faces[i],
                i - 1,
                faces[i - 1]
            )));
        }
        let increasing = z_range.iter().all(|z| z.is_finite()) && z_range[1] > z_range[0];
        if z_cells < 2 || !increasing {
            return Err(FluidError::Parameter(format!(
                "an (r, z) grid needs at least 2 cells along z over an increasing range, got {} \
                 cells over [{}, {}]",
                z_cells, z_range[0], z_range[1]
            )));
        }
        let mut widths = vec![0.0; n + 2];
        for i in 1..=n {
            widths[i] = faces[i] - faces[i - 1];
        }
        widths[0] = widths[1];
        widths[n + 1] = widths[n];
        let mut padded_faces = faces.to_vec();
        padded_faces.push(faces[n] + widths[n + 1]);
        let mut centres = vec![0.0; n + 2];
        for i in 1..=n + 1 {
            centres[i] = 0.5 * (padded_faces[i - 1] + padded_faces[i]);
        }
        centres[0] = -centres[1];
        let mut gaps = vec![0.0; n + 2];
        for i in 0..=n {
            gaps[i] = centres[i + 1] - centres[i];
        }
        gaps[n + 1] = widths[n + 1];
        Ok(RzGrid {
            cells: [n, z_cells],
            radius: faces[n],
            z_range,
            dz: (z_range[1] - z_range[0]) / z_cells as f64,
            faces: padded_faces,
            centres,
            widths,
            gaps,
        })
    }

    /// Padded extent `[n_r + 2, n_z + 2]`.
    pub fn padded(&self) -> [usize; 2] {
        [self.cells[0] + 2, self.cells[1] + 2]
    }

    /// Length of a padded field.
    pub fn len(&self) -> usize {
        let [a, b] = self.padded();
        a * b
    }

    pub fn is_empty(&self) -> bool {
        false
    }

    /// Flat index of padded `(i, k)`.
    #[inline]
    pub fn index(&self, i: usize, k: usize) -> usize {
        i + (self.cells[0] + 2) * k
    }

    /// A zero field.
    pub fn zeros(&self) -> Vec<f64> {
        vec![0.0; self.len()]
    }

    /// Radius of face `i` (`r_0 = 0` the axis, `r_{n_r} = R` the wall).
    #[inline]
    pub fn face(&self, i: usize) -> f64 {
        self.faces[i]
    }

    /// Radius of the centre of padded cell `i`.
    #[inline]
    pub fn centre(&self, i: usize) -> f64 {
        self.centres[i]
    }

    /// Width of padded cell `i`.
    #[inline]
    pub fn width(&self, i: usize) -> f64 {
        self.widths[i]
    }

    /// Distance between the centres on either side of face `i`.
    #[inline]
    pub fn gap(&self, i: usize) -> f64 {
        self.gaps[i]
    }

    /// Axial coordinate of the centre of padded cell `k`.
    #[inline]
    pub fn z_centre(&self, k: usize) -> f64 {
        self.z_range[0] + (k as f64 - 0.5) * self.dz
    }

    /// Axial coordinate of face `k`, the upper face of padded cell `k`.
    #[inline]
    pub fn z_face(&self, k: usize) -> f64 {
        self.z_range[0] + k as f64 * self.dz
    }

    /// `r̄_i w_i`: the volume of cell `i` over `2π h`.
    #[inline]
    pub fn ring(&self, i: usize) -> f64 {
        self.centres[i] * self.widths[i]
    }

    /// The narrowest radial width.
    pub fn smallest_width(&self) -> f64 {
        self.widths[1..=self.cells[0]]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }
}

/// Radial faces of Izard et al. (2014, §3.1): `core_cells` equal cells
/// out to `core_radius`, then cells whose widths grow in arithmetic
/// progression, `w_j = Δ + j δ` (`Δ = core_radius / core_cells`), so that
/// `cells` cells in all reach `radius`. Refused when the outer cells would
/// have to shrink (δ < 0: too many cells for the outer radius) or when
/// `cells ≤ core_cells`.
pub fn core_and_growth_faces(
    core_radius: f64,
    core_cells: usize,
    radius: f64,
    cells: usize,
) -> Result<Vec<f64>, FluidError> {
    let ordered = core_radius > 0.0 && radius > core_radius && radius.is_finite();
    if core_cells == 0 || cells <= core_cells || !ordered {
        return Err(FluidError::Parameter(format!(
            "a uniform core and a growing outer part need 0 < core radius < radius and more \
             cells than core cells; got core radius {core_radius}, {core_cells} core cells, \
             radius {radius}, {cells} cells"
        )));
    }
    let step = core_radius / core_cells as f64;
    let outer = (cells - core_cells) as f64;
    // Σ_{j=1}^{m} (Δ + j δ) = m Δ + δ m (m + 1)/2 = R − R_core.
    let growth = (radius - core_radius - outer * step) * 2.0 / (outer * (outer + 1.0));
    if growth < 0.0 {
        return Err(FluidError::Parameter(format!(
            "{} outer cells of at least {step:.4e} m reach past the radius {radius}: use fewer \
             cells or a larger radius",
            cells - core_cells
        )));
    }
    let mut faces = Vec::with_capacity(cells + 1);
    faces.push(0.0);
    for i in 1..=cells {
        let width = if i <= core_cells {
            step
        } else {
            step + (i - core_cells) as f64 * growth
        };
        faces.push(faces[i - 1] + width);
    }
    faces[cells] = radius;
    Ok(faces)
}
