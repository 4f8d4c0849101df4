//! Error metrics and albedos.
//!
//! # Ngan's normalized L2 (004 §V.5.3)
//!
//! E = (∫∫ (m(i, o) − ρ(i, o))² cos θi cos θo dωi dωo)^½ / A_max per channel, where A_max is the
//! maximum directional albedo of the *data* in that channel over θo ∈ {0°, 10°, …, 80°}.
//!
//! Quadrature ([`NganQuadrature`]): the double integral over both upper hemispheres is written in
//! Rusinkiewicz half/difference angles, dωi dωo = 4 cos θd sin θh sin θd dθh dφh dθd dφd (for
//! fixed o, dωi = 4 (o·h) dωh; d is a rotation of o about h). θh = (π/2) u² (the MERL
//! mapping, which resolves specular peaks: the first node sits at θh ≈ 1e-4 rad) with composite
//! Gauss-Legendre in u; θd by composite Gauss-Legendre on [0, π/2]; φd by the midpoint rule on
//! [0, 2π) (periodic, so spectrally accurate); φh integrated out exactly (2π) when both BSDFs are
//! isotropic, else by the midpoint rule. Pairs with a direction below the horizon contribute 0.
//!
//! # L1 of 000 Eq. 3.7
//!
//! error = Σ_t w(ωo) |cos θi| |p_data(ωo|ωi) − p_model(ωo|ωi)| / Σ_t w(ωo), with the transfer
//! probability p = f |cos θo| (000 Eq. 2.4) and w = |sin θo| (solid-angle correction), over a
//! regular grid of measurement tuples: θi, θo at the midpoints of 18 intervals of 5° each on
//! (0°, 90°), φo at 36 midpoints of [0°, 360°), φi = 0 (and 4 values when a BSDF is anisotropic);
//! with `transmission`, θo also covers (90°, 180°).
//!
//! # Masked data
//! With a coverage mask (a MERL table's measured bins, [`MerlCoverage`]) the Ngan integral and
//! the L1 leave out the pairs whose bin was not measured (the `*_masked` functions). The data's
//! albedos and maximum albedo integrate the table as it evaluates (unmeasured corners left out of
//! the trilinear interpolation), since an albedo needs the whole hemisphere.
//!
//! # Albedos (000 Eq. 2.6, Tables 3.1–3.3)
//!
//! a(o) = ∫ f(i, o) |cos θi| dωi at normal incidence o = +z, by the half-vector parametrization
//! dωi = 4 (o·h) dωh with θh = (π/2) u² (peaks resolved), 48 φh midpoints and for each φh Gauss
//! nodes in u up to the exact horizon cut of i (so Lambert's albedo comes out to 1e-6); plus the
//! lower hemisphere (around −z, same mapping) when `transmission`. [`average_albedo`] averages
//! a(o) over all view directions (cosine-weighted).

use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::frame::{from_half_diff, reflect, spherical, HalfDiff};
use lustre_brdf::measured::merl::MerlCoverage;
use lustre_brdf::numeric::gauss_legendre;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Fit errors and albedos of a model against data, per RGB channel.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ErrorReport {
    /// Ngan's L2 normalized by the data's maximum albedo (004 §V.5.3).
    pub ngan_l2: [f64; 3],
    /// The L1 of transfer probabilities (000 Eq. 3.7).
    pub l1: [f64; 3],
    /// Directional albedo of the data at normal incidence.
    pub albedo_data: [f64; 3],
    /// Directional albedo of the model at normal incidence.
    pub albedo_model: [f64; 3],
}

impl ErrorReport {
    /// The mean of the three channels' Ngan errors.
    pub fn ngan_mean(&self) -> f64 {
        self.ngan_l2.iter().sum::<f64>() / 3.0
    }

    /// The mean of the three channels' L1 errors.
    pub fn l1_mean(&self) -> f64 {
        self.l1.iter().sum::<f64>() / 3.0
    }
}

/// Composite Gauss-Legendre nodes and weights on [a, b] with `panels` panels of `n` points.
pub fn composite_gauss(a: f64, b: f64, panels: usize, n: usize) -> Vec<(f64, f64)> {
    let (x, w) = gauss_legendre(n);
    let mut out = Vec::with_capacity(panels * n);
    let h = (b - a) / panels as f64;
    for p in 0..panels {
        let c = a + h * (p as f64 + 0.5);
        for (xi, wi) in x.iter().zip(&w) {
            out.push((c + 0.5 * h * xi, 0.5 * h * wi));
        }
    }
    out
}

/// The quadrature of the Ngan L2 (see the module notes): node counts per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NganQuadrature {
    /// Gauss panels in u (θh = π/2 u²), 8 points each.
    pub theta_h_panels: usize,
    /// Gauss panels in θd, 8 points each.
    pub theta_d_panels: usize,
    /// Midpoints in φd over [0, 2π).
    pub phi_d: usize,
    /// Midpoints in φh over [0, 2π) (only used for anisotropic BSDFs).
    pub phi_h: usize,
}

impl Default for NganQuadrature {
    /// 64 × 32 × 48 nodes (θh × θd × φd); 8 φh nodes for anisotropic data.
    fn default() -> Self {
        NganQuadrature {
            theta_h_panels: 8,
            theta_d_panels: 4,
            phi_d: 48,
            phi_h: 8,
        }
    }
}

/// One node of the Ngan quadrature: a direction pair and its weight, which includes
/// cos θi cos θo and the Jacobian, so that Σ w g(i, o)² ≈ ∫∫ g² cos θi cos θo dωi dωo.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedPair {
    /// Direction to the light.
    pub wi: DVec3,
    /// Direction to the viewer.
    pub wo: DVec3,
    /// Quadrature weight.
    pub w: f64,
}

impl NganQuadrature {
    /// The nodes with both directions strictly above the horizon, grouped by θh node (one inner
    /// vector per θh node, for parallel evaluation). `isotropic` integrates φh out exactly.
    pub fn pairs(&self, isotropic: bool) -> Vec<Vec<WeightedPair>> {
        let uh = composite_gauss(0.0, 1.0, self.theta_h_panels.max(1), 8);
        let td = composite_gauss(0.0, FRAC_PI_2, self.theta_d_panels.max(1), 8);
        let nd = self.phi_d.max(1);
        let nh = if isotropic { 1 } else { self.phi_h.max(1) };
        let (dphi_d, dphi_h) = (2.0 * PI / nd as f64, 2.0 * PI / nh as f64);
        uh.iter()
            .map(|&(u, wu)| {
                let theta_h = FRAC_PI_2 * u * u;
                // dθh = π u du.
                let w_h = wu * PI * u * theta_h.sin();
                let mut row = Vec::with_capacity(td.len() * nd * nh);
                for &(theta_d, wd) in &td {
                    let w_hd = w_h * wd * 4.0 * theta_d.cos() * theta_d.sin() * dphi_d * dphi_h;
                    for kd in 0..nd {
                        let phi_d = (kd as f64 + 0.5) * dphi_d;
                        for kh in 0..nh {
                            let phi_h = if isotropic {
                                0.0
                            } else {
                                (kh as f64 + 0.5) * dphi_h
                            };
                            let (wi, wo) = from_half_diff(&HalfDiff {
                                theta_h,
                                phi_h,
                                theta_d,
                                phi_d,
                            });
                            if wi.z > 0.0 && wo.z > 0.0 {
                                row.push(WeightedPair {
                                    wi,
                                    wo,
                                    w: w_hd * wi.z * wo.z,
                                });
                            }
                        }
                    }
                }
                row
            })
            .collect()
    }
}

/// The un-normalized Ngan integral ∫∫ (a − b)² cos θi cos θo dωi dωo per channel, by
/// [`NganQuadrature`] (rayon over θh nodes).
pub fn ngan_integral(a: &dyn Bsdf, b: &dyn Bsdf, q: &NganQuadrature) -> [f64; 3] {
    ngan_integral_masked(a, b, q, None)
}

/// [`ngan_integral`] over the pairs `mask` covers (all without a mask).
pub fn ngan_integral_masked(
    a: &dyn Bsdf,
    b: &dyn Bsdf,
    q: &NganQuadrature,
    mask: Option<&MerlCoverage>,
) -> [f64; 3] {
    let iso = !a.flags().anisotropic && !b.flags().anisotropic;
    NganRows::new(a, q, iso, mask).integral(b)
}

/// The Ngan quadrature nodes that `mask` covers with the data's values there, grouped by θh
/// node: the data side of [`ngan_integral_masked`], evaluated once.
#[derive(Clone, Debug)]
struct NganRows(Vec<Vec<(WeightedPair, [f64; 3])>>);

impl NganRows {
    fn new(data: &dyn Bsdf, q: &NganQuadrature, iso: bool, mask: Option<&MerlCoverage>) -> Self {
        NganRows(
            q.pairs(iso)
                .into_par_iter()
                .map(|row| {
                    row.into_iter()
                        .filter(|p| mask.is_none_or(|m| m.covers(p.wi, p.wo)))
                        .map(|p| (p, data.eval(p.wi, p.wo).0))
                        .collect()
                })
                .collect(),
        )
    }

    /// ∫∫ (data − model)² cos θi cos θo dωi dωo per channel.
    fn integral(&self, model: &dyn Bsdf) -> [f64; 3] {
        self.0
            .par_iter()
            .map(|row| {
                let mut s = [0.0; 3];
                for (p, fa) in row {
                    let fb = model.eval(p.wi, p.wo);
                    for (c, sc) in s.iter_mut().enumerate() {
                        let d = fa[c] - fb.0[c];
                        *sc += p.w * d * d;
                    }
                }
                s
            })
            // Collected, then summed in row order: the same bits whatever the thread count
            // (rayon's `reduce` groups the sums by how the work was split).
            .collect::<Vec<_>>()
            .into_iter()
            .fold([0.0; 3], |x, y| [x[0] + y[0], x[1] + y[1], x[2] + y[2]])
    }
}

/// Directional albedo a(wo) = ∫ f(wi, wo) |cos θi| dωi per channel (000 Eq. 2.6), by the
/// half-vector quadrature of the module notes (`transmission`: plus the lower hemisphere).
pub fn albedo(bsdf: &dyn Bsdf, wo: DVec3, transmission: bool) -> [f64; 3] {
    let gauss = composite_gauss(0.0, 1.0, 6, 8);
    let nphi = 48;
    let dphi = 2.0 * PI / nphi as f64;
    let mut s = [0.0; 3];
    // In the frame where wo has azimuth 0: wo = (sin θo, 0, cos θo).
    let phi_o = wo.y.atan2(wo.x);
    let (so, co) = ((wo.x * wo.x + wo.y * wo.y).sqrt(), wo.z);
    for k in 0..nphi {
        let phi = (k as f64 + 0.5) * dphi;
        // wi.z = 2(o·h) cos θh − cos θo = R cos(2θh − δ), δ = atan2(sin θo cos φ, cos θo), so
        // wi lies above the horizon exactly for θh < (δ + π/2)/2: integrate up to that cut.
        let delta = (so * phi.cos()).atan2(co);
        let theta_max = 0.5 * (delta + FRAC_PI_2);
        let u_max = (theta_max / FRAC_PI_2).max(0.0).sqrt();
        for &(v, wv) in &gauss {
            let u = v * u_max;
            let theta_h = FRAC_PI_2 * u * u;
            let h = spherical(theta_h, phi + phi_o);
            let oh = wo.dot(h);
            let wi = reflect(wo, h);
            if oh <= 0.0 || wi.z <= 0.0 {
                continue;
            }
            let f = bsdf.eval(wi, wo);
            let w = wv * u_max * PI * u * theta_h.sin() * dphi * 4.0 * oh * wi.z;
            for (sc, fc) in s.iter_mut().zip(f.0) {
                *sc += w * fc;
            }
        }
        if transmission {
            // Lower hemisphere around −z with the same mapping: dω = sin θ dθ dφ.
            for &(u, wu) in &gauss {
                let theta = FRAC_PI_2 * u * u;
                let d = spherical(theta, phi);
                let wi = DVec3::new(d.x, d.y, -d.z);
                let f = bsdf.eval(wi, wo);
                let w = wu * PI * u * theta.sin() * dphi * wi.z.abs();
                for (sc, fc) in s.iter_mut().zip(f.0) {
                    *sc += w * fc;
                }
            }
        }
    }
    s
}

/// The L1 of 000 Eq. 3.7 per channel (see the module notes for the grid).
pub fn l1_error(data: &dyn Bsdf, model: &dyn Bsdf, transmission: bool) -> [f64; 3] {
    l1_error_masked(data, model, transmission, None)
}

/// [`l1_error`] over the tuples `mask` covers (all without a mask).
pub fn l1_error_masked(
    data: &dyn Bsdf,
    model: &dyn Bsdf,
    transmission: bool,
    mask: Option<&MerlCoverage>,
) -> [f64; 3] {
    let aniso = data.flags().anisotropic || model.flags().anisotropic;
    L1Rows::new(data, transmission, aniso, mask).error(model)
}

/// One measurement tuple of the L1 grid: directions, the weight |sin θo| |cos θi| |cos θo| and
/// the data's value.
type L1Tuple = (DVec3, DVec3, f64, [f64; 3]);

/// The tuples of the L1 grid that `mask` covers with the data's values, per θi row, and the
/// row's Σ |sin θo|: the data side of [`l1_error_masked`], evaluated once.
#[derive(Clone, Debug)]
struct L1Rows(Vec<(Vec<L1Tuple>, f64)>);

impl L1Rows {
    fn new(data: &dyn Bsdf, transmission: bool, aniso: bool, mask: Option<&MerlCoverage>) -> Self {
        let n_t = 18;
        let dt = FRAC_PI_2 / n_t as f64;
        let n_po = 36;
        let dpo = 2.0 * PI / n_po as f64;
        let phis_i: Vec<f64> = if aniso {
            (0..4).map(|k| k as f64 * FRAC_PI_2 / 2.0).collect()
        } else {
            vec![0.0]
        };
        let n_to = if transmission { 2 * n_t } else { n_t };
        L1Rows(
            (0..n_t)
                .into_par_iter()
                .map(|a| {
                    let ti = (a as f64 + 0.5) * dt;
                    let mut row = Vec::new();
                    let mut den = 0.0;
                    for &pi in &phis_i {
                        let wi = spherical(ti, pi);
                        for b in 0..n_to {
                            let to = (b as f64 + 0.5) * dt;
                            let w = to.sin().abs();
                            for k in 0..n_po {
                                let wo = spherical(to, (k as f64 + 0.5) * dpo);
                                if mask.is_some_and(|m| !m.covers(wi, wo)) {
                                    continue;
                                }
                                let g = w * wi.z.abs() * wo.z.abs();
                                row.push((wi, wo, g, data.eval(wi, wo).0));
                                den += w;
                            }
                        }
                    }
                    (row, den)
                })
                .collect(),
        )
    }

    /// The L1 of `model` per channel.
    fn error(&self, model: &dyn Bsdf) -> [f64; 3] {
        let (num, den) = self
            .0
            .par_iter()
            .map(|(row, den)| {
                let mut num = [0.0; 3];
                for (wi, wo, g, fd) in row {
                    let fm = model.eval(*wi, *wo);
                    for (c, nc) in num.iter_mut().enumerate() {
                        *nc += g * (fd[c] - fm.0[c]).abs();
                    }
                }
                (num, *den)
            })
            // Summed in order after collecting: the same bits whatever the thread count.
            .collect::<Vec<_>>()
            .into_iter()
            .fold(([0.0; 3], 0.0), |x, y| {
                (
                    [x.0[0] + y.0[0], x.0[1] + y.0[1], x.0[2] + y.0[2]],
                    x.1 + y.1,
                )
            });
        if den > 0.0 {
            num.map(|v| v / den)
        } else {
            [0.0; 3]
        }
    }
}

/// The maximum directional albedo per channel over θo ∈ {0°, 10°, …, 80°} (the normalization
/// of the Ngan error).
pub fn max_albedo(bsdf: &dyn Bsdf, transmission: bool) -> [f64; 3] {
    (0..9)
        .into_par_iter()
        .map(|k| {
            albedo(
                bsdf,
                spherical((10.0 * k as f64).to_radians(), 0.0),
                transmission,
            )
        })
        .reduce(
            || [0.0; 3],
            |x, y| [x[0].max(y[0]), x[1].max(y[1]), x[2].max(y[2])],
        )
}

/// One channel changed by [`albedo_bound`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct AlbedoCap {
    /// The channel (0, 1, 2: r, g, b).
    pub channel: usize,
    /// The model's largest directional albedo before the cap.
    pub before: f64,
    /// The data's largest directional albedo (≤ 1).
    pub data: f64,
    /// The diffuse albedo after the cap.
    pub diffuse: f64,
    /// The scale of the other terms after the cap.
    pub scale: f64,
}

impl AlbedoCap {
    /// The cap in words: `channel b: albedo 1.011 > 1 where the data's is 0.93: kd 0.8 ->
    /// 0.8, ks 1 -> 0.97` with the callers' names of the diffuse term and of the scale.
    pub fn describe(&self, diffuse: (&str, f64), scale: (&str, f64)) -> String {
        format!(
            "channel {}: albedo {:.3} > 1 where the data's is {:.3}: {} {:.4} -> {:.4}, {} \
             {:.4} -> {:.4}",
            ["r", "g", "b"][self.channel],
            self.before,
            self.data,
            diffuse.0,
            diffuse.1,
            self.diffuse,
            scale.0,
            scale.1,
            self.scale
        )
    }
}

/// The albedo bound of the fits (`ct` step 5, `kurt` step 6), for a model that is per channel
/// `diffuse`·Lambert + `scale`·U, U (`unit`) the rest of the model at scale 1 (its albedo is
/// linear in the scale). Where the data's directional albedo stays ≤ 1 (`data_max`, from
/// [`max_albedo`]), a channel whose largest model albedo diffuse + scale·a_U(θo) over θo = 0°,
/// 10°, …, 80° exceeds 0.999 (a small margin keeps the quadrature's own error, ≈1e-4, on the
/// safe side) has the diffuse albedo capped at 0.999 and the scale lowered until
/// diffuse + scale·a_U(θo) ≤ 0.999 at every such θo. Returns the changed channels; the others
/// keep their values.
pub(crate) fn albedo_bound(
    data_max: [f64; 3],
    diffuse: [f64; 3],
    scale: [f64; 3],
    unit: &dyn Bsdf,
    transmission: bool,
) -> Vec<AlbedoCap> {
    const LIMIT: f64 = 0.999;
    let worst = max_albedo(unit, transmission);
    let mut caps = Vec::new();
    for c in 0..3 {
        if data_max[c] > 1.0 {
            continue;
        }
        let before = diffuse[c] + scale[c] * worst[c];
        if before <= LIMIT {
            continue;
        }
        let d = diffuse[c].min(LIMIT);
        let s = if worst[c] > 0.0 {
            scale[c].min((LIMIT - d).max(0.0) / worst[c])
        } else {
            scale[c]
        };
        caps.push(AlbedoCap {
            channel: c,
            before,
            data: data_max[c],
            diffuse: d,
            scale: s,
        });
    }
    caps
}

/// The cosine-weighted average of the directional albedo over all view directions,
/// (1/π) ∫ a(o) cos θo dωo per channel (the albedo under uniform illumination): Gauss nodes in
/// μ² = cos²θo (16 nodes, since (1/π)∫ cos θo dωo = ∫₀¹ d(μ²)), 8 azimuths for anisotropic
/// BSDFs (1 otherwise).
pub fn average_albedo(bsdf: &dyn Bsdf, transmission: bool) -> [f64; 3] {
    let nodes = composite_gauss(0.0, 1.0, 2, 8);
    let nphi = if bsdf.flags().anisotropic { 8 } else { 1 };
    let sums: Vec<[f64; 3]> = nodes
        .par_iter()
        .map(|&(s, w)| {
            let mu = s.sqrt();
            let sin_t = (1.0 - s).max(0.0).sqrt();
            let mut acc = [0.0; 3];
            for k in 0..nphi {
                let phi = 2.0 * PI * k as f64 / nphi as f64;
                let wo = DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), mu);
                let a = albedo(bsdf, wo, transmission);
                for (x, v) in acc.iter_mut().zip(a) {
                    *x += w * v / nphi as f64;
                }
            }
            acc
        })
        .collect();
    sums.iter()
        .fold([0.0; 3], |x, y| [x[0] + y[0], x[1] + y[1], x[2] + y[2]])
}

/// Ngan's normalized L2, the Eq. 3.7 L1 and the normal-incidence albedos of `model` against
/// `data` (module notes). A data channel with zero albedo is normalized by the largest channel
/// albedo instead (or not at all when every channel is zero).
pub fn evaluate(data: &dyn Bsdf, model: &dyn Bsdf, transmission: bool) -> ErrorReport {
    evaluate_masked(data, model, transmission, None)
}

/// [`evaluate`] with the errors over the pairs `mask` covers (see the module notes).
pub fn evaluate_masked(
    data: &dyn Bsdf,
    model: &dyn Bsdf,
    transmission: bool,
    mask: Option<&MerlCoverage>,
) -> ErrorReport {
    let amax = max_albedo(data, transmission);
    ErrorReport {
        ngan_l2: ngan_l2_masked(data, model, &amax, mask),
        l1: l1_error_masked(data, model, transmission, mask),
        albedo_data: albedo(data, DVec3::Z, transmission),
        albedo_model: albedo(model, DVec3::Z, transmission),
    }
}

/// Ngan's normalized L2 per channel given the data's maximum albedo `amax` (from
/// [`max_albedo`], so that a batch comparing several models computes it once).
pub fn ngan_l2(data: &dyn Bsdf, model: &dyn Bsdf, amax: &[f64; 3]) -> [f64; 3] {
    ngan_l2_masked(data, model, amax, None)
}

/// [`ngan_l2`] over the pairs `mask` covers.
pub fn ngan_l2_masked(
    data: &dyn Bsdf,
    model: &dyn Bsdf,
    amax: &[f64; 3],
    mask: Option<&MerlCoverage>,
) -> [f64; 3] {
    let integral = ngan_integral_masked(data, model, &NganQuadrature::default(), mask);
    ngan_normalized(integral, amax)
}

/// √integral / A_max per channel (a channel with zero albedo by the largest, see [`evaluate`]).
fn ngan_normalized(integral: [f64; 3], amax: &[f64; 3]) -> [f64; 3] {
    let top = amax.iter().cloned().fold(0.0, f64::max);
    std::array::from_fn(|c| {
        let norm = if amax[c] > 0.0 {
            amax[c]
        } else if top > 0.0 {
            top
        } else {
            1.0
        };
        integral[c].max(0.0).sqrt() / norm
    })
}

/// The metric a fit's candidates are judged by (`lustre fit --metric`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// Ngan's normalized L2 (004 §V.5.3), mean of the channels.
    #[default]
    NganL2,
    /// The L1 of transfer probabilities (000 Eq. 3.7) on the grid of [`l1_error`], mean of the
    /// channels.
    L1,
}

impl Metric {
    /// `ngan-l2` or `l1`.
    pub fn as_str(self) -> &'static str {
        match self {
            Metric::NganL2 => "ngan-l2",
            Metric::L1 => "l1",
        }
    }
}

/// A [`Metric`] against one data set, its data side evaluated once (on first use per isotropy
/// of the model), so that many candidate models of one fit are judged at the cost of evaluating
/// the models only. [`MetricJudge::of`] equals, to the bit, the mean over the channels of
/// [`ngan_l2_masked`] (with [`max_albedo`] of the data) or [`l1_error_masked`].
pub struct MetricJudge<'a> {
    metric: Metric,
    data: &'a dyn Bsdf,
    transmission: bool,
    mask: Option<&'a MerlCoverage>,
    amax: std::sync::OnceLock<[f64; 3]>,
    ngan: [std::sync::OnceLock<NganRows>; 2],
    l1: [std::sync::OnceLock<L1Rows>; 2],
}

impl<'a> MetricJudge<'a> {
    /// The judge of `metric` against `data` (with `transmission`, both hemispheres for the L1
    /// and the albedo), over the pairs `mask` covers.
    pub fn new(
        metric: Metric,
        data: &'a dyn Bsdf,
        transmission: bool,
        mask: Option<&'a MerlCoverage>,
    ) -> Self {
        MetricJudge {
            metric,
            data,
            transmission,
            mask,
            amax: Default::default(),
            ngan: Default::default(),
            l1: Default::default(),
        }
    }

    /// The metric judged.
    pub fn metric(&self) -> Metric {
        self.metric
    }

    /// The metric of `model` per channel.
    pub fn per_channel(&self, model: &dyn Bsdf) -> [f64; 3] {
        let (data, mask) = (self.data, self.mask);
        match self.metric {
            Metric::NganL2 => {
                let iso = !data.flags().anisotropic && !model.flags().anisotropic;
                let rows = self.ngan[usize::from(iso)]
                    .get_or_init(|| NganRows::new(data, &NganQuadrature::default(), iso, mask));
                let amax = self
                    .amax
                    .get_or_init(|| max_albedo(data, self.transmission));
                ngan_normalized(rows.integral(model), amax)
            }
            Metric::L1 => {
                let aniso = data.flags().anisotropic || model.flags().anisotropic;
                self.l1[usize::from(aniso)]
                    .get_or_init(|| L1Rows::new(data, self.transmission, aniso, mask))
                    .error(model)
            }
        }
    }

    /// The metric of `model`, mean of the channels.
    pub fn of(&self, model: &dyn Bsdf) -> f64 {
        self.per_channel(model).iter().sum::<f64>() / 3.0
    }
}
