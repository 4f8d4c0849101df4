//! Importance sampling of an equirectangular environment (pbrt-v4 §12.5's piecewise-constant
//! 2D distribution, with exact texel solid angles instead of the sin θ Jacobian at texel centres).
//!
//! Texel (i, j) is chosen with probability P_ij = w_ij Ω_j / Σ w Ω, where Ω_j is the exact solid
//! angle of a texel of row j ([`EquirectMap::row_solid_angle`], the "sin θ weighting") and w_ij
//! the texel's weight: the channel mean of a 3×3 neighbourhood mixed with the texel itself,
//! w = ¾ m_ij + ¼ mean₃ₓ₃(m), so that every texel a bilinear lookup can draw light from has a
//! positive probability. Inside the texel the direction is uniform in solid angle (φ uniform,
//! cos θ uniform), so the density is exactly p(ω) = P_ij / Ω_j and [`EnvSampler::pdf`] agrees
//! with [`EnvSampler::sample`] to rounding.

use crate::equirect::{direction_uv, EquirectMap};
use crate::error::{EnvError, Result};
use glam::DVec3;
use std::f64::consts::PI;

/// A piecewise-constant distribution over `n` cells (pbrt-v4's `PiecewiseConstant1D`, discrete).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// Cell weights (≥ 0).
    weights: Vec<f64>,
    /// cdf[k] = Σ_{l<k} weights / total; n + 1 entries, cdf[n] = 1.
    cdf: Vec<f64>,
    /// Σ weights.
    total: f64,
    /// guide[g] = the number of cdf entries ≤ g / len() for g in 0..=len(): the cells of u in
    /// [g / n, (g + 1) / n) lie between guide[g] and guide[g + 1] (a guide table; Devroye 1986
    /// §III.2.4), so [`Distribution1D::sample`] searches a few entries instead of all.
    guide: Vec<u32>,
}

impl Distribution1D {
    /// The distribution of `weights` (negative or non-finite weights count as 0). With a zero
    /// total every cell is equally likely.
    pub fn new(weights: Vec<f64>) -> Self {
        let mut weights = weights;
        for w in &mut weights {
            if !(w.is_finite() && *w > 0.0) {
                *w = 0.0;
            }
        }
        let mut total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            weights.iter_mut().for_each(|w| *w = 1.0);
            total = weights.len() as f64;
        }
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for w in &weights {
            acc += w;
            cdf.push(acc / total);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        let m = weights.len().max(1);
        let guide = (0..=m)
            .map(|g| cdf.partition_point(|&c| c <= g as f64 / m as f64) as u32)
            .collect();
        Distribution1D {
            weights,
            cdf,
            total,
            guide,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.weights.len()
    }

    /// True when there are no cells.
    pub fn is_empty(&self) -> bool {
        self.weights.is_empty()
    }

    /// Sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The cumulative distribution: `len() + 1` entries from 0 to 1.
    pub fn cdf(&self) -> &[f64] {
        &self.cdf
    }

    /// Probability of cell `k`.
    pub fn probability(&self, k: usize) -> f64 {
        self.weights.get(k).map_or(0.0, |w| w / self.total)
    }

    /// The cell of `u` ∈ [0, 1) and `u` rescaled to [0, 1) inside that cell.
    pub fn sample(&self, u: f64) -> (usize, f64) {
        let n = self.weights.len();
        // Largest k with cdf[k] <= u, among cells of positive weight: searched between the
        // guide's entries one cell of the guide wider on each side than u's own, which holds
        // whatever u · n rounds to (the same k as a search of the whole cdf).
        let m = self.guide.len() - 1;
        let g = ((u * m as f64) as usize).min(m - 1);
        let lo = self.guide[g.saturating_sub(1)] as usize;
        let hi = self.guide[(g + 2).min(m)] as usize;
        let k = (lo + self.cdf[lo..hi].partition_point(|&c| c <= u))
            .saturating_sub(1)
            .min(n.saturating_sub(1));
        let lo = self.cdf[k];
        let hi = self.cdf[k + 1];
        let r = if hi > lo { (u - lo) / (hi - lo) } else { 0.5 };
        (k, r.clamp(0.0, 1.0 - f64::EPSILON))
    }
}

/// A sampled environment direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSample {
    /// Unit direction towards the light (world space, the map's frame).
    pub dir: DVec3,
    /// Solid-angle density of `dir`.
    pub pdf: f64,
    /// The texel (i, j) it was drawn from.
    pub texel: (usize, usize),
}

/// The importance sampler of an equirect map (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvSampler {
    width: usize,
    height: usize,
    /// Rows, weight Σ_i w_ij Ω_j.
    rows: Distribution1D,
    /// Per row, the texels, weight w_ij.
    cols: Vec<Distribution1D>,
    /// Ω_j per row.
    row_omega: Vec<f64>,
    /// cos θ at the row borders, height + 1 entries.
    cos_border: Vec<f64>,
}

impl EnvSampler {
    /// Builds the sampler of `map`. Errors when no texel carries light (all weights zero).
    pub fn new(map: &EquirectMap) -> Result<Self> {
        let (w, h) = (map.width, map.height);
        let m: Vec<f64> = map
            .data
            .iter()
            .map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0)
            .map(|v| if v.is_finite() && v > 0.0 { v } else { 0.0 })
            .collect();
        let row_omega: Vec<f64> = (0..h).map(|j| map.row_solid_angle(j)).collect();
        let mut cols = Vec::with_capacity(h);
        let mut row_w = Vec::with_capacity(h);
        for j in 0..h {
            let weights: Vec<f64> = (0..w)
                .map(|i| {
                    let mut s = 0.0;
                    for dj in [-1i64, 0, 1] {
                        let jj = (j as i64 + dj).clamp(0, h as i64 - 1) as usize;
                        for di in [-1i64, 0, 1] {
                            let ii = (i as i64 + di).rem_euclid(w as i64) as usize;
                            s += m[jj * w + ii];
                        }
                    }
                    0.75 * m[j * w + i] + 0.25 * s / 9.0
                })
                .collect();
            // A row of zeros gets a uniform conditional but zero marginal weight.
            let sum: f64 = weights.iter().sum();
            row_w.push(sum * row_omega[j]);
            cols.push(Distribution1D::new(weights));
        }
        if !row_w.iter().any(|&x| x > 0.0) {
            return Err(EnvError::Parameter(
                "environment map carries no light: nothing to importance-sample".into(),
            ));
        }
        let cos_border = (0..=h).map(|j| (PI * j as f64 / h as f64).cos()).collect();
        Ok(EnvSampler {
            width: w,
            height: h,
            rows: Distribution1D::new(row_w),
            cols,
            row_omega,
            cos_border,
        })
    }

    /// Map width in texels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Map height in texels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The distribution over rows (weights Σ_i w_ij Ω_j).
    pub fn rows(&self) -> &Distribution1D {
        &self.rows
    }

    /// The distribution over row `j`'s texels (weights w_ij).
    pub fn row(&self, j: usize) -> &Distribution1D {
        &self.cols[j]
    }

    /// The exact solid angle Ω_j of a texel of row `j`.
    pub fn row_solid_angle(&self, j: usize) -> f64 {
        self.row_omega[j]
    }

    /// Probability of choosing texel (i, j).
    pub fn texel_probability(&self, i: usize, j: usize) -> f64 {
        self.rows.probability(j) * self.cols[j].probability(i)
    }

    /// Draws a direction from two uniform numbers in [0, 1).
    pub fn sample(&self, u1: f64, u2: f64) -> EnvSample {
        let (j, v) = self.rows.sample(u2);
        let (i, u) = self.cols[j].sample(u1);
        let (c0, c1) = (self.cos_border[j], self.cos_border[j + 1]);
        let cos_t = (c0 + v * (c1 - c0)).clamp(-1.0, 1.0);
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        let phi = 2.0 * PI * ((i as f64 + u) / self.width as f64 - 0.5);
        let dir = DVec3::new(sin_t * phi.sin(), cos_t, -sin_t * phi.cos());
        let pdf = self.texel_probability(i, j) / self.row_omega[j];
        EnvSample {
            dir,
            pdf,
            texel: (i, j),
        }
    }

    /// The texel holding direction `d` (need not be normalized; zero / non-finite reads +y).
    pub fn texel_of(&self, d: DVec3) -> (usize, usize) {
        let (u, v) = direction_uv(d);
        self.texel_of_uv(u, v)
    }

    /// The texel holding map coordinates (u, v) ∈ [0, 1]².
    fn texel_of_uv(&self, u: f64, v: f64) -> (usize, usize) {
        let i = ((u * self.width as f64) as usize).min(self.width - 1);
        let j = ((v * self.height as f64) as usize).min(self.height - 1);
        (i, j)
    }

    /// Solid-angle density with which [`EnvSampler::sample`] draws `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        let (u, v) = direction_uv(d);
        self.pdf_uv(u, v)
    }

    /// [`EnvSampler::pdf`] at map coordinates (u, v) of [`direction_uv`] (a caller that also
    /// reads the map there finds them once).
    pub fn pdf_uv(&self, u: f64, v: f64) -> f64 {
        let (i, j) = self.texel_of_uv(u, v);
        self.texel_probability(i, j) / self.row_omega[j]
    }
}
