//! Importance sampling of any reflection BRDF by numerical inversion of tabulated CDFs, as 004
//! §IV.4.3 does for acquired materials (after Lawrence et al. 2004: the CDF of the BRDF,
//! tabulated per view direction and inverted).
//!
//! For each of `view_bins` view elevations θo_k = (k + ½)/K · π/2 (and, for an anisotropic
//! BRDF, each of `azimuth_bins` view azimuths φo_a = (a + ½)/A · 2π in the local frame, x
//! along the tangent), the luminance of f(ωi, ωo) cos θi is integrated over the cells of a
//! (θi, φ) grid of the upper hemisphere, `supersample`² points per cell, uniform in cos θi and
//! φ: θi uniform in [0, π/2), φ = φi − φo the azimuth relative to the view. An isotropic BRDF
//! is even in φ, so its grid covers φ ∈ [0, π] with `phi_bins` cells and a sample takes either
//! sign with probability ½ (the half-plane folded onto itself); an anisotropic one's covers
//! φ ∈ [0, 2π) with `phi_bins` cells, unfolded and twice as wide (its `azimuth_bins` tables per
//! elevation already multiply the memory: 16.8 MB per material with the defaults). The cell weights are the
//! piecewise-constant density to sample from: a cell is picked by inverting the cumulative sum
//! of its weights, then a point inside it uniformly in solid angle. The table of the nearest
//! view elevation serves `wo`, so `sample` and `pdf` use the same table. A fraction `defensive` of the samples is drawn
//! from the cosine hemisphere, so the density is positive wherever f cos θi may be (cells whose
//! supersampled weight missed a narrow peak, or where every channel is 0 at the cell's points):
//!
//! p(ωi | ωo) = ε cos θi / π + (1 − ε) w_c / (W · Ω_c)
//!
//! with w_c the weight of the cell holding (θi, φ) (|φ| when folded), W the table's total and
//! Ω_c the cell's solid angle ((cos θa − cos θb) Δφ, doubled when folded). An anisotropic
//! BRDF's view azimuth falls between two azimuth bins: their tables are mixed with linear
//! weights (one picked per sample by u2, the density their weighted sum), so the density
//! follows φo continuously.

use crate::bsdf::{finish_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{Error, Result};
use crate::rgb::Rgb;
use crate::sampling::cosine_hemisphere;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// The grid of a [`TabulatedSampler`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TabulatedOptions {
    /// View elevations θo (one table each), uniform in [0, π/2).
    pub view_bins: usize,
    /// View azimuths φo per view elevation, uniform in [0, 2π), for anisotropic BRDFs (an
    /// isotropic BRDF has one table per elevation).
    pub azimuth_bins: usize,
    /// Cells along θi, uniform in [0, π/2).
    pub theta_bins: usize,
    /// Cells along φ = φi − φo in [0, π] (an anisotropic BRDF's tables: over [0, 2π)).
    pub phi_bins: usize,
    /// Points per cell and axis at which f cos θi is evaluated.
    pub supersample: usize,
    /// The fraction ε of samples drawn from the cosine hemisphere, in (0, 1].
    pub defensive: f64,
}

impl Default for TabulatedOptions {
    fn default() -> Self {
        Self {
            view_bins: 32,
            azimuth_bins: 16,
            theta_bins: 64,
            phi_bins: 64,
            supersample: 2,
            defensive: 0.1,
        }
    }
}

/// The tabulated CDFs of one BRDF: per view bin, the cumulative weights of its cells.
#[derive(Clone, Debug, PartialEq)]
pub struct TabulatedSampler {
    options: TabulatedOptions,
    /// Unfolded tables per view azimuth (an anisotropic BRDF).
    anisotropic: bool,
    /// `view_bins` (× `azimuth_bins` when anisotropic, azimuth inner) tables of `theta_bins ·`
    /// [`TabulatedSampler::phi_cells`] `+ 1` cumulative weights (row-major, θi outer), each
    /// starting at 0 and ending at the table's total.
    cdf: Vec<f64>,
    /// cos θ at the θi rows' edges, `theta_bins + 1` values from 1 to 0 ([`theta_cos_range`]'s,
    /// found once).
    cos_edges: Vec<f64>,
}

/// The grid of one table: its φ cells and their width (radians), and whether φ is folded.
#[derive(Clone, Copy, Debug)]
struct Grid {
    theta_bins: usize,
    phi_cells: usize,
    dphi: f64,
    folded: bool,
}

impl TabulatedSampler {
    /// Tabulates `bsdf`, a reflection BRDF without Dirac lobes (isotropic or not); errors on
    /// absurd options (a zero count, more than 4096 bins along an axis, ε outside (0, 1]) and
    /// on a BRDF whose f cos θi is not finite at some table point (named with the point).
    pub fn new(bsdf: &dyn Bsdf, options: TabulatedOptions) -> Result<Self> {
        let o = options;
        let bad = |name: &str, value: f64, reason: &str| Error::Parameter {
            name: format!("{name} (tabulated sampling of {})", bsdf.name()),
            value,
            reason: reason.into(),
        };
        for (name, n) in [
            ("view_bins", o.view_bins),
            ("azimuth_bins", o.azimuth_bins),
            ("theta_bins", o.theta_bins),
            ("phi_bins", o.phi_bins),
            ("supersample", o.supersample),
        ] {
            if n == 0 || n > 4096 {
                return Err(bad(name, n as f64, "must be 1..=4096"));
            }
        }
        if !(o.defensive > 0.0 && o.defensive <= 1.0) {
            return Err(bad("defensive", o.defensive, "must lie in (0, 1]"));
        }
        let flags = bsdf.flags();
        if flags.transmission || flags.has_delta() {
            return Err(bad(
                "flags",
                0.0,
                "only reflection BRDFs without Dirac lobes are tabulated (the table covers the upper hemisphere)",
            ));
        }
        let anisotropic = flags.anisotropic;
        let azimuths = if anisotropic { o.azimuth_bins } else { 1 };
        let grid = Grid::new(&o, anisotropic);
        let tables: Vec<Vec<f64>> = (0..o.view_bins * azimuths)
            .into_par_iter()
            .map(|t| {
                let (k, a) = (t / azimuths, t % azimuths);
                let theta_o = (k as f64 + 0.5) / o.view_bins as f64 * FRAC_PI_2;
                let phi_o = (a as f64 + 0.5) / azimuths as f64 * 2.0 * PI;
                let phi_o = if anisotropic { phi_o } else { 0.0 };
                view_table(bsdf, &o, grid, theta_o, phi_o)
                    .map_err(|(v, what)| bad("f cos θi", v, &what))
            })
            .collect::<Result<_>>()?;
        let cdf = tables.concat();
        let n = o.theta_bins;
        let cos_edges = (0..=n)
            .map(|i| if i < n { theta_cos_range(i, n).0 } else { 0.0 })
            .collect();
        Ok(Self {
            options,
            anisotropic,
            cdf,
            cos_edges,
        })
    }

    /// Whether the tables are per view azimuth and unfolded (the BRDF was anisotropic).
    pub fn is_anisotropic(&self) -> bool {
        self.anisotropic
    }

    /// The φ cells of one table: `phi_bins`, over [0, π] (isotropic, folded) or [0, 2π)
    /// (anisotropic).
    pub fn phi_cells(&self) -> usize {
        Grid::new(&self.options, self.anisotropic).phi_cells
    }

    /// The tables: `view_bins` × ([`TabulatedSampler::is_anisotropic`]: `azimuth_bins`, else
    /// 1), azimuth inner.
    pub fn table_count(&self) -> usize {
        let o = &self.options;
        o.view_bins * if self.anisotropic { o.azimuth_bins } else { 1 }
    }

    /// The options the table was built with.
    pub fn options(&self) -> TabulatedOptions {
        self.options
    }

    /// The cumulative cell weights: [`TabulatedSampler::table_count`] tables of `theta_bins ·`
    /// [`TabulatedSampler::phi_cells`] `+ 1` values, each from 0 to its total (cells row-major,
    /// θi outer).
    pub fn cumulative(&self) -> &[f64] {
        &self.cdf
    }

    /// The tables serving `wo` with their weights (summing to 1), or `None` below or at the
    /// horizon: θo's nearest bin and, when anisotropic, the two azimuth bins around φo, weighted
    /// linearly (a mixture, so the density follows φo continuously); an isotropic BRDF's one
    /// table twice, weights 1 and 0.
    fn tables(&self, wo: DVec3) -> Option<[(&[f64], f64); 2]> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let o = &self.options;
        let theta_o = wo.z.min(1.0).acos();
        let k = ((theta_o / FRAC_PI_2 * o.view_bins as f64) as usize).min(o.view_bins - 1);
        let n = o.theta_bins * self.phi_cells() + 1;
        let table = |t: usize| &self.cdf[t * n..(t + 1) * n];
        if !self.anisotropic {
            return Some([(table(k), 1.0), (table(k), 0.0)]);
        }
        let az = o.azimuth_bins;
        let x = wo.y.atan2(wo.x).rem_euclid(2.0 * PI) / (2.0 * PI) * az as f64 - 0.5;
        let x = if x.is_finite() { x } else { 0.0 };
        let lo = x.floor();
        let t = (x - lo).clamp(0.0, 1.0);
        let a0 = (lo as i64).rem_euclid(az as i64) as usize;
        let a1 = (a0 + 1) % az;
        Some([(table(k * az + a0), 1.0 - t), (table(k * az + a1), t)])
    }

    /// The tabulated density of cell `c` of solid angle `omega` (the fold's mirror included),
    /// without the defensive part: w_c / (W · Ω_c); 0 for a black table.
    fn table_pdf(table: &[f64], c: usize, omega: f64) -> f64 {
        let total = table[table.len() - 1];
        if total <= 0.0 {
            return 0.0;
        }
        (table[c + 1] - table[c]) / (total * omega)
    }

    /// Draws `wi` for `wo` (local frame) from two uniform numbers: `None` when `wo` lies at or
    /// below the horizon. An anisotropic BRDF's table is picked by `u2` (rescaled) with the
    /// probabilities of its weights.
    pub fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<DVec3> {
        let [(ta, wa), (tb, _)] = self.tables(wo)?;
        // The table by u2 (rescaled), which then only places the point inside its cell's φ
        // range (unfolded tables): rounding in the rescale never moves a draw to another cell.
        let (table, u2) = if u2 < wa || wa >= 1.0 {
            (ta, u2 / wa)
        } else {
            (tb, (u2 - wa) / (1.0 - wa))
        };
        let u2 = u2.clamp(0.0, 1.0 - f64::EPSILON);
        let g = Grid::new(&self.options, self.anisotropic);
        let eps = self.options.defensive;
        let total = table[table.len() - 1];
        if u1 < eps || total <= 0.0 {
            let u = if total <= 0.0 { u1 } else { u1 / eps };
            return Some(cosine_hemisphere(u.min(1.0 - f64::EPSILON), u2));
        }
        let target = (u1 - eps) / (1.0 - eps) * total;
        // The first cell whose cumulative weight exceeds the target (cells of weight 0 are
        // never picked: their upper bound equals their lower one).
        let c = table[1..]
            .partition_point(|&v| v <= target)
            .min(g.theta_bins * g.phi_cells - 1);
        let (lo, hi) = (table[c], table[c + 1]);
        let r = if hi > lo {
            ((target - lo) / (hi - lo)).clamp(0.0, 1.0 - f64::EPSILON)
        } else {
            0.5
        };
        let (i, j) = (c / g.phi_cells, c % g.phi_cells);
        let (ca, cb) = (self.cos_edges[i], self.cos_edges[i + 1]);
        let cos_i = ca + (cb - ca) * r;
        let (sign, v) = if !g.folded {
            (1.0, u2)
        } else if u2 < 0.5 {
            (1.0, 2.0 * u2)
        } else {
            (-1.0, 2.0 * u2 - 1.0)
        };
        let phi = sign * (j as f64 + v) * g.dphi + wo.y.atan2(wo.x);
        let sin = (1.0 - cos_i * cos_i).max(0.0).sqrt();
        Some(DVec3::new(sin * phi.cos(), sin * phi.sin(), cos_i))
    }

    /// The luminance of f(ωi, ωo) as the tables hold it (the serving tables' weighted sum): the
    /// cell holding ωi, its ∫ f cos θi dω over its solid angle and its mean cosine (cos θa +
    /// cos θb)/2 — the cell's mean of f, piecewise constant, finite at the horizon. 0 at or
    /// below the horizon and for a black table. A lookup where `Bsdf::eval` may be a network
    /// or a table walk (the CPU bandwidth pass's weights, `lustre_adaptive::buffer`).
    pub fn brdf_luminance(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.luminance_view(wo).at(wi)
    }

    /// [`TabulatedSampler::brdf_luminance`] seen from `wo`: its tables and azimuth found once,
    /// for many ωi.
    pub fn luminance_view(&self, wo: DVec3) -> LuminanceView<'_> {
        LuminanceView {
            tables: self.tables(wo),
            grid: Grid::new(&self.options, self.anisotropic),
            cos_edges: &self.cos_edges,
            phi_o: wo.y.atan2(wo.x),
        }
    }

    /// The density (per solid angle) with which [`TabulatedSampler::sample`] draws `wi`: the
    /// weighted sum of its tables' densities.
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(tables) = self.tables(wo) else {
            return 0.0;
        };
        if wi.z.is_nan() || wi.z <= 0.0 {
            return 0.0;
        }
        let cosine = wi.z / PI;
        let (c, omega, _) =
            Grid::new(&self.options, self.anisotropic).cell(wi, wo, &self.cos_edges);
        let eps = self.options.defensive;
        tables
            .iter()
            .filter(|(_, w)| *w > 0.0)
            .map(|&(table, w)| {
                w * if table[table.len() - 1] <= 0.0 {
                    cosine
                } else {
                    eps * cosine + (1.0 - eps) * Self::table_pdf(table, c, omega)
                }
            })
            .sum()
    }
}

impl Grid {
    fn new(o: &TabulatedOptions, anisotropic: bool) -> Self {
        let span = if anisotropic { 2.0 * PI } else { PI };
        Self {
            theta_bins: o.theta_bins,
            phi_cells: o.phi_bins,
            dphi: span / o.phi_bins as f64,
            folded: !anisotropic,
        }
    }

    /// The cell holding `wi` (local, above the surface) relative to `wo`'s azimuth (|φ| when
    /// folded) and its solid angle (the fold's mirror cell included) and its cos θ range.
    /// `cos_edges`: the sampler's [`TabulatedSampler`] `cos_edges`.
    fn cell(&self, wi: DVec3, wo: DVec3, cos_edges: &[f64]) -> (usize, f64, (f64, f64)) {
        self.cell_polar(
            wi.z.clamp(0.0, 1.0).acos(),
            wi.y.atan2(wi.x) - wo.y.atan2(wo.x),
            cos_edges,
        )
    }

    /// [`Grid::cell`] from ωi's θ and its azimuth relative to ωo's (any multiple of 2π).
    fn cell_polar(
        &self,
        theta: f64,
        relative_phi: f64,
        cos_edges: &[f64],
    ) -> (usize, f64, (f64, f64)) {
        let rel = relative_phi.rem_euclid(2.0 * PI);
        let phi = if self.folded && rel > PI {
            2.0 * PI - rel
        } else {
            rel
        };
        let i = ((theta / FRAC_PI_2 * self.theta_bins as f64) as usize).min(self.theta_bins - 1);
        let j = ((phi / self.dphi) as usize).min(self.phi_cells - 1);
        let (ca, cb) = (cos_edges[i], cos_edges[i + 1]);
        let fold = if self.folded { 2.0 } else { 1.0 };
        (
            i * self.phi_cells + j,
            fold * (ca - cb) * self.dphi,
            (ca, cb),
        )
    }
}

/// [`TabulatedSampler::brdf_luminance`] at one ωo ([`TabulatedSampler::luminance_view`]).
#[derive(Clone, Copy, Debug)]
pub struct LuminanceView<'a> {
    tables: Option<[(&'a [f64], f64); 2]>,
    grid: Grid,
    cos_edges: &'a [f64],
    phi_o: f64,
}

impl LuminanceView<'_> {
    /// The luminance of f(ωi, ωo) as the tables hold it ([`TabulatedSampler::brdf_luminance`]).
    pub fn at(&self, wi: DVec3) -> f64 {
        self.at_polar(wi.z, wi.z.clamp(0.0, 1.0).acos(), wi.y.atan2(wi.x))
    }

    /// [`LuminanceView::at`] from ωi's cos θ, its θ = acos(clamp(cos θ, 0, 1)) and its azimuth
    /// atan2(y, x), when a caller knows them (a fixed set of directions).
    pub fn at_polar(&self, cos_theta: f64, theta: f64, phi: f64) -> f64 {
        let Some(tables) = self.tables else {
            return 0.0;
        };
        if cos_theta.is_nan() || cos_theta <= 0.0 {
            return 0.0;
        }
        let g = &self.grid;
        let (c, _, (ca, cb)) = g.cell_polar(theta, phi - self.phi_o, self.cos_edges);
        let scale = 1.0 / ((ca - cb) * g.dphi * 0.5 * (ca + cb));
        tables
            .iter()
            .filter(|(_, w)| *w > 0.0)
            .map(|&(table, w)| w * (table[c + 1] - table[c]) * scale)
            .sum()
    }
}

/// The cumulative weights of the table of the view (θo, φo): `theta_bins · phi_cells + 1`
/// values from 0; a non-finite f cos θi gives the value and where it is.
fn view_table(
    bsdf: &dyn Bsdf,
    o: &TabulatedOptions,
    g: Grid,
    theta_o: f64,
    phi_o: f64,
) -> std::result::Result<Vec<f64>, (f64, String)> {
    let wo = DVec3::new(
        theta_o.sin() * phi_o.cos(),
        theta_o.sin() * phi_o.sin(),
        theta_o.cos(),
    );
    let s = o.supersample as f64;
    let mut cdf = Vec::with_capacity(g.theta_bins * g.phi_cells + 1);
    let mut acc = 0.0;
    cdf.push(0.0);
    for i in 0..g.theta_bins {
        let (ca, cb) = theta_cos_range(i, g.theta_bins);
        for j in 0..g.phi_cells {
            let mut sum = 0.0;
            for a in 0..o.supersample {
                let c = ca + (cb - ca) * (a as f64 + 0.5) / s;
                let sin = (1.0 - c * c).max(0.0).sqrt();
                for b in 0..o.supersample {
                    let phi = (j as f64 + (b as f64 + 0.5) / s) * g.dphi;
                    let wi = DVec3::new(sin * (phi + phi_o).cos(), sin * (phi + phi_o).sin(), c);
                    let v = bsdf.eval(wi, wo).luminance() * c;
                    if !v.is_finite() {
                        return Err((
                            v,
                            format!(
                                "not finite at θo = {:.2}°, φo = {:.2}°, θi = {:.2}°, φ = {:.2}°",
                                theta_o.to_degrees(),
                                phi_o.to_degrees(),
                                c.acos().to_degrees(),
                                phi.to_degrees()
                            ),
                        ));
                    }
                    sum += v.max(0.0);
                }
            }
            acc += sum / (s * s) * (ca - cb) * g.dphi;
            cdf.push(acc);
        }
    }
    Ok(cdf)
}

/// cos θ at the lower and upper θ edges of cell `i` of `n` (θ uniform in [0, π/2)): (cos θa,
/// cos θb) with cos θa > cos θb.
fn theta_cos_range(i: usize, n: usize) -> (f64, f64) {
    let a = i as f64 / n as f64 * FRAC_PI_2;
    let b = (i + 1) as f64 / n as f64 * FRAC_PI_2;
    (a.cos(), if i + 1 == n { 0.0 } else { b.cos() })
}

/// A BRDF sampled from its own tabulated CDFs: `eval` and `flags` are the inner BRDF's,
/// `sample` and `pdf` come from its [`TabulatedSampler`].
#[derive(Clone, Debug)]
pub struct Tabulated<B> {
    inner: B,
    sampler: TabulatedSampler,
}

impl<B: Bsdf> Tabulated<B> {
    /// Tabulates `inner` (see [`TabulatedSampler::new`]).
    pub fn new(inner: B, options: TabulatedOptions) -> Result<Self> {
        let sampler = TabulatedSampler::new(&inner, options)?;
        Ok(Self { inner, sampler })
    }

    /// The BRDF being sampled.
    pub fn inner(&self) -> &B {
        &self.inner
    }

    /// Its tables.
    pub fn sampler(&self) -> &TabulatedSampler {
        &self.sampler
    }
}

impl<B: Bsdf> Bsdf for Tabulated<B> {
    fn name(&self) -> String {
        format!("{} (tabulated sampling)", self.inner.name())
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        self.inner.eval(wi, wo)
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        let wi = self.sampler.sample(wo, u1, u2)?;
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        // The inner BRDF's kind: a diffuse-only model stays diffuse.
        let kind = if self.inner.flags().diffuse_only() {
            LobeFlags::DIFFUSE
        } else {
            LobeFlags::GLOSSY
        };
        finish_sample(wi, wo, self.sampler.pdf(wi, wo), kind, || {
            self.inner.eval(wi, wo)
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.sampler.pdf(wi, wo)
    }

    fn flags(&self) -> BsdfFlags {
        self.inner.flags()
    }
}
