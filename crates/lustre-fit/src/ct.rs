//! Two-slice Cook-Torrance fits (004 §V.4).
//!
//! Per RGB channel (004 §V.4.1) the model is 004 Eq. III.1,
//! f = ρd/π + (ρs/π) F(θd) D(θh) G1(θi) G1(θo)/(cos θi cos θo), with the SGD (004 Eq. V.2),
//! Beckmann or GGX distribution and the generalized Schlick Fresnel F = F0 + (1 − F0)(1 − cos θd)⁵
//! − F1 cos θd (004 Eq. V.5). [`fit`] proceeds as 004 §V.4.2:
//!
//! 1. On the θd = 0 slice m_h(θh) (sampled at the 90 MERL θh bin nodes, [`bin_node`]) fit
//!    ρ_h = ρd/π + (Fr/π) D(θh) G1²(θh)/cos²θh for (ρd, Fr, α, p) (Eq. V.6), with weights
//!    w_i = sin θh cos²θh Δθh (the slice's share of the Ngan measure), from several starts.
//!    For SGD the starts use G1 = 1 and the best is polished once more with the numeric Smith
//!    G1 of its (α, p); Beckmann and GGX use their closed forms.
//! 2. On the θh = 0 slice m_d(θd) (MERL θd bin nodes up to `max_theta_d_deg`), fit
//!    ρs F(θd) = (m_d − ρd/π) π cos²θd / (D(0) G1²(θd)) with Eq. V.5 for (ρs, F0, F1) (ρs is
//!    F's value at θd = 90°, where F = 1).
//! 3. Optional refinement (beyond the paper, [`CtOptions::refine`]): per channel, one LM on all
//!    parameters minimizing the Ngan-weighted residual Σ w (f − m)² over a fixed quadrature set
//!    of direction pairs ([`crate::metrics::NganQuadrature`], 32 × 16 × 16 nodes in θh × θd ×
//!    φd, the data evaluated once), with the SGD shadowing held at the numeric Smith G1 of the
//!    two-slice (α, p) (Beckmann, GGX: closed forms). Variables ln ρd, ln ρs, ln α, the
//!    Fresnel variables of [`fresnel_of`] (and p); the result is kept only where it lowers the weighted error, recomputed with
//!    the numeric G1 of the refined (α, p). For SGD a second refinement starts from the refined
//!    Beckmann fit (SGD with p = 0, α = α_B² is Beckmann). Among the two-slice fit and the
//!    refined ones, the one with the lowest weighted error on the full default
//!    [`crate::metrics::NganQuadrature`] (the metric's own nodes) is kept.
//! 4. SGD: the Eq. V.3 shadowing approximation (λ, c, k) by `SgdG1Approx::fit` of the numeric
//!    G1 table of the final (α, p), and kap = 1/(αΓ(1−p, α)).
//!
//! 5. Albedo bound (`metrics::albedo_bound`, shared with the Kurt fits): where the data's
//!    directional albedo stays ≤ 1 (max over θo = 0°, 10°, …, 80°), a channel whose model
//!    albedo exceeds 0.999 has ρd capped at 0.999 and ρs scaled down until
//!    ρd + ρs·a_s(θo) ≤ 0.999 at every such θo (a_s: the specular albedo at ρs = 1; the margin
//!    covers the quadrature's error); the fit's message says so ([`CtFit::notes`]).
//!
//! # Physical by construction
//! Every optimization is `levenberg_marquardt::LevenbergMarquardt` with a forward-difference
//! Jacobian. Positivity and ranges come from the parametrization: ρd, ρs, Fr, α are exp of the
//! LM variable (α clamped to [1e-5, 5]), SGD p = −1.9 + 4.8·sigmoid (inside the library's
//! range), F0 = sigmoid(a) ∈ (0, 1) and F1 = F0 − sigmoid(c) ∈ (F0 − 1, F0). With F0 ∈ [0, 1]
//! and F0 − 1 ≤ F1 ≤ F0, Eq. V.5 stays in [0, 1] for every cos θd ∈ [0, 1]: F(c) = F0(1 − c −
//! m) + m + c − F1·c with m = (1 − c)⁵ ≤ 1 − c, so F ≥ F0(1 − c − m) + m ≥ 0 when F1 ≤ F0 and
//! F ≤ (1 − c − m) + m + c = 1 when F1 ≥ F0 − 1. The model is therefore never negative. (The
//! published SGD fits use F0 up to 8.5 and F1 < 0, i.e. a Fresnel "reflectance" above 1; we do
//! not.)

use crate::metrics::NganQuadrature;
use crate::{FitError, FitStatus, Result};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::frame::{from_half_diff, HalfDiff};
/// The fit's distribution and per-channel parameters are the material file's own types (one
/// name each across the workspace): a [`CtFit`] becomes a material with no conversion.
pub use lustre_brdf::material::{CtChannelParams, CtDistribution};
use lustre_brdf::measured::merl::{bin_node, MerlCoverage, RES_THETA_D, RES_THETA_H};
use lustre_brdf::microfacet::fresnel::Fresnel;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::microfacet::smith::{g1_beckmann, g1_ggx, G1Table, SgdG1Approx};
use lustre_brdf::models::cook_torrance::CookTorrance;
use lustre_brdf::numeric::upper_gamma;
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, PI};

/// Options of [`fit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CtOptions {
    /// Run the refinement over the full data after the two-slice fit (module notes, step 4).
    pub refine: bool,
    /// Step 2 discards θd beyond this angle (degrees; 004 §V.4.2 uses 70°).
    pub max_theta_d_deg: f64,
}

impl Default for CtOptions {
    /// Refinement on, θd ≤ 70°.
    fn default() -> Self {
        CtOptions {
            refine: true,
            max_theta_d_deg: 70.0,
        }
    }
}

/// A Cook-Torrance fit of three channels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CtFit {
    /// The distribution.
    pub distribution: CtDistribution,
    /// Parameters per channel (r, g, b).
    pub channels: [CtChannelParams; 3],
    /// Whether every final optimization converged.
    pub status: FitStatus,
    /// Residual evaluations of all Levenberg-Marquardt runs together.
    pub iterations: usize,
    /// What the fit changed to stay physical (e.g. an albedo cap), in words; empty otherwise.
    pub notes: Vec<String>,
}

impl CtFit {
    /// The fitted model as a [`CookTorrance`] BSDF named `name`.
    pub fn to_bsdf(&self, name: &str) -> lustre_brdf::Result<CookTorrance> {
        let [r, g, b] = &self.channels;
        let d = self.distribution;
        CookTorrance::new(name, [r.to_channel(d)?, g.to_channel(d)?, b.to_channel(d)?])
    }
}

// ---------------------------------------------------------------------------------------------
// Levenberg-Marquardt on a closure, central-difference Jacobian.

/// Stand-in for a non-finite residual: LM then rejects the step.
const BAD_RESIDUAL: f64 = 1e100;

struct Lsq<'a> {
    x: DVector<f64>,
    m: usize,
    f: &'a (dyn Fn(&[f64], &mut [f64]) + Sync),
}

impl Lsq<'_> {
    fn eval(&self, x: &[f64]) -> DVector<f64> {
        let mut r = vec![0.0; self.m];
        (self.f)(x, &mut r);
        for v in &mut r {
            if !v.is_finite() {
                *v = BAD_RESIDUAL;
            }
        }
        DVector::from_vec(r)
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Lsq<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        Some(self.eval(self.x.as_slice()))
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        // Forward differences: one extra residual evaluation per parameter.
        let n = self.x.len();
        let mut j = DMatrix::zeros(self.m, n);
        let mut x = self.x.as_slice().to_vec();
        let r0 = self.eval(&x);
        for k in 0..n {
            let h = 1e-7 * (1.0 + x[k].abs());
            let x0 = x[k];
            x[k] = x0 + h;
            let rp = self.eval(&x);
            x[k] = x0;
            let mut col = (rp - &r0) / h;
            col.iter_mut().for_each(|v| {
                if !v.is_finite() || v.abs() > 1e90 {
                    *v = 0.0;
                }
            });
            j.set_column(k, &col);
        }
        Some(j)
    }
}

/// Result of one LM run: parameters, ½‖r‖², success, residual evaluations.
struct LmOut {
    x: Vec<f64>,
    cost: f64,
    ok: bool,
    evals: usize,
}

/// LM patience of the slice fits (steps 1, 2): at most 60·(n + 1) residual evaluations.
const SLICE_PATIENCE: usize = 60;

/// LM patience of the refinement (step 3): at most REFINE_PATIENCE·(n + 1) residual
/// evaluations. With 60 the SGD refinement from the two-slice fit often crept to its limit (420
/// evaluations, ≈ 1 s per channel: green-latex, black-soft-plastic, pink-fabric2) for a final
/// Ngan L2 equal to 4 digits on all 105 inputs of `examples/merl100.rs` (BENCHMARKS.md).
const REFINE_PATIENCE: usize = 20;

fn minimize(
    f: &(dyn Fn(&[f64], &mut [f64]) + Sync),
    m: usize,
    x0: &[f64],
    patience: usize,
) -> LmOut {
    let problem = Lsq {
        x: DVector::from_column_slice(x0),
        m,
        f,
    };
    let (done, report) = LevenbergMarquardt::new()
        .with_patience(patience)
        .minimize(problem);
    let x = done.x.as_slice().to_vec();
    let r = done.eval(&x);
    LmOut {
        cost: 0.5 * r.norm_squared(),
        ok: report.termination.was_successful(),
        evals: report.number_of_evaluations,
        x,
    }
}

// ---------------------------------------------------------------------------------------------
// The channel model.

const P_LO: f64 = -1.9;
const P_SPAN: f64 = 4.8;
const LN_ALPHA: (f64, f64) = (-11.512925464970229, 1.6094379124341003); // ln 1e-5, ln 5

fn alpha_of(x: f64) -> f64 {
    x.clamp(LN_ALPHA.0, LN_ALPHA.1).exp()
}
fn p_of(q: f64) -> f64 {
    P_LO + P_SPAN / (1.0 + (-q.clamp(-40.0, 40.0)).exp())
}
fn q_of(p: f64) -> f64 {
    let s = ((p - P_LO) / P_SPAN).clamp(1e-9, 1.0 - 1e-9);
    (s / (1.0 - s)).ln()
}
fn pos_of(x: f64) -> f64 {
    x.clamp(-60.0, 30.0).exp()
}
fn ln_pos(v: f64) -> f64 {
    v.max(1e-26).ln()
}

fn sigmoid(x: f64) -> f64 {
    1.0 / (1.0 + (-x.clamp(-40.0, 40.0)).exp())
}
fn logit(s: f64) -> f64 {
    let s = s.clamp(1e-9, 1.0 - 1e-9);
    (s / (1.0 - s)).ln()
}

/// (ρs, F0, F1) from the LM variables (x, a, c): ρs = eˣ, F0 = sigmoid(a) ∈ (0, 1),
/// F1 = F0 − sigmoid(c) ∈ (F0 − 1, F0), so that F(θd) ∈ [0, 1] everywhere (module notes).
fn fresnel_of(x: f64, a: f64, c: f64) -> (f64, f64, f64) {
    let f0 = sigmoid(a);
    (pos_of(x), f0, f0 - sigmoid(c))
}

/// The LM variables of [`fresnel_of`] for (ρs, F0, F1), after projecting F0 into [0, 1] and
/// F1 into [F0 − 1, F0].
fn fresnel_vars(rs: f64, f0: f64, f1: f64) -> [f64; 3] {
    let f0 = f0.clamp(0.0, 1.0);
    let f1 = f1.clamp(f0 - 1.0, f0);
    [ln_pos(rs), logit(f0), logit(f0 - f1)]
}

/// Eq. V.5 from the basis (m5 = (1 − cos θd)⁵, cos θd).
#[inline]
fn fresnel_basis(f0: f64, f1: f64, m5: f64, c: f64) -> f64 {
    f0 * (1.0 - m5) + m5 - f1 * c
}

/// A distribution with its parameters and precomputed normalization.
#[derive(Clone, Copy, Debug)]
struct Dist {
    kind: CtDistribution,
    alpha: f64,
    p: f64,
    ln_kap: f64,
}

impl Dist {
    fn new(kind: CtDistribution, alpha: f64, p: f64) -> Dist {
        let ln_kap = match kind {
            CtDistribution::Sgd => -alpha.ln() - upper_gamma(1.0 - p, alpha).ln(),
            _ => 0.0,
        };
        Dist {
            kind,
            alpha,
            p,
            ln_kap,
        }
    }

    /// D(θh) = P22(tan²θh)/(π cos⁴θh) (004 Eq. III.2, V.2).
    #[inline]
    fn d(&self, ch: f64) -> f64 {
        if ch.is_nan() || ch <= 0.0 {
            return 0.0;
        }
        let c2 = (ch * ch).min(1.0);
        let s2 = 1.0 - c2;
        let a = self.alpha;
        match self.kind {
            CtDistribution::Sgd => {
                let x = s2 / c2;
                let big_a = a + x / a;
                (self.ln_kap - big_a - self.p * big_a.ln()).exp() * FRAC_1_PI / (c2 * c2)
            }
            CtDistribution::Beckmann => {
                let a2 = a * a;
                (-(s2 / c2) / a2).exp() * FRAC_1_PI / (a2 * c2 * c2)
            }
            CtDistribution::Ggx => {
                let a2 = a * a;
                let d = a2 * c2 + s2;
                a2 * FRAC_1_PI / (d * d)
            }
        }
    }

    /// The closed-form Smith G1 (Beckmann, GGX); `None` for SGD.
    #[inline]
    fn g1_closed(&self, cos_t: f64) -> Option<f64> {
        match self.kind {
            CtDistribution::Beckmann => Some(g1_beckmann(self.alpha, cos_t)),
            CtDistribution::Ggx => Some(g1_ggx(self.alpha, cos_t)),
            CtDistribution::Sgd => None,
        }
    }

    fn ndf(&self) -> lustre_brdf::Result<Ndf> {
        match self.kind {
            CtDistribution::Sgd => Ndf::sgd(self.alpha, self.p),
            CtDistribution::Beckmann => Ndf::beckmann(self.alpha),
            CtDistribution::Ggx => Ndf::ggx(self.alpha),
        }
    }
}

/// The SGD shadowing term held fixed during an LM run.
#[derive(Clone, Debug)]
enum SgdG1 {
    One,
    Table(Box<G1Table>),
}

impl SgdG1 {
    #[inline]
    fn eval(&self, cos_t: f64) -> f64 {
        match self {
            SgdG1::One => 1.0,
            SgdG1::Table(t) => t.eval(cos_t),
        }
    }
}

/// G1 of `d` at cos θ: closed form where one exists, else the fixed SGD term.
#[inline]
fn g1_of(d: &Dist, fixed: &SgdG1, cos_t: f64) -> f64 {
    d.g1_closed(cos_t).unwrap_or_else(|| fixed.eval(cos_t))
}

// ---------------------------------------------------------------------------------------------
// Slices.

/// The data's value in `channel` at (θh, θd, φd) (φh = 0).
fn data_at(data: &dyn Bsdf, theta_h: f64, theta_d: f64, phi_d: f64) -> [f64; 3] {
    let (wi, wo) = from_half_diff(&HalfDiff {
        theta_h,
        phi_h: 0.0,
        theta_d,
        phi_d,
    });
    data.eval(wi, wo).0
}

/// Step 1 for one channel; returns (ρd, Fr, α, p), success, evaluations.
fn step1(
    input: &str,
    kind: CtDistribution,
    th: &[f64],
    m: &[f64],
    sw: &[f64],
    valid: &[bool],
) -> Result<([f64; 4], bool, usize)> {
    let sgd = kind == CtDistribution::Sgd;
    let n = th.len();
    let cos: Vec<f64> = th.iter().map(|t| t.cos()).collect();
    let valid: Vec<f64> = m
        .iter()
        .zip(valid)
        .filter(|(_, v)| **v)
        .map(|(x, _)| *x)
        .collect();
    let tail = valid
        .iter()
        .rev()
        .take(20)
        .cloned()
        .fold(f64::INFINITY, f64::min)
        .max(0.0);
    let peak = valid.first().copied().unwrap_or(0.0);
    let mut evals = 0;
    let run = |x0: &[f64], g1: &SgdG1| {
        let f = |x: &[f64], r: &mut [f64]| {
            let (rd, fr, a) = (pos_of(x[0]), pos_of(x[1]), alpha_of(x[2]));
            let p = if sgd { p_of(x[3]) } else { 0.0 };
            let d = Dist::new(kind, a, p);
            for i in 0..n {
                let c = cos[i];
                let g = g1_of(&d, g1, c);
                let v = rd * FRAC_1_PI + fr * FRAC_1_PI * d.d(c) * g * g / (c * c);
                r[i] = sw[i] * (v - m[i]);
            }
        };
        minimize(&f, n, x0, SLICE_PATIENCE)
    };
    // Starts: a grid of α (and p); ρd from the tail, Fr from the peak height.
    let alphas: &[f64] = if sgd {
        &[1e-3, 1e-2, 0.05, 0.2]
    } else {
        &[0.01, 0.05, 0.2, 0.5]
    };
    let ps: &[f64] = if sgd { &[0.2, 0.8, 1.4] } else { &[0.0] };
    let mut best: Option<LmOut> = None;
    for &a in alphas {
        for &p in ps {
            let d = Dist::new(kind, a, p);
            let rd = (tail * PI).max(1e-6);
            let fr = ((peak - tail).max(1e-9) * PI / d.d(1.0)).max(1e-9);
            let mut x0 = vec![ln_pos(rd), ln_pos(fr), a.ln()];
            if sgd {
                x0.push(q_of(p));
            }
            let out = run(&x0, &SgdG1::One);
            evals += out.evals;
            if out.cost.is_finite() && best.as_ref().is_none_or(|b| out.cost < b.cost) {
                best = Some(out);
            }
        }
    }
    let mut best = best.ok_or_else(|| FitError::Data {
        input: input.to_string(),
        problem: "step 1 (θd = 0 slice): no start gave a finite fit".into(),
    })?;
    if sgd {
        // Rounds with the numeric Smith G1 of the current (α, p).
        let d = Dist::new(kind, alpha_of(best.x[2]), p_of(best.x[3]));
        let table = G1Table::new(&d.ndf()?);
        let out = run(&best.x, &SgdG1::Table(Box::new(table)));
        evals += out.evals;
        best = out;
    }
    let x = &best.x;
    let p = if sgd { p_of(x[3]) } else { 0.0 };
    Ok((
        [pos_of(x[0]), pos_of(x[1]), alpha_of(x[2]), p],
        best.ok,
        evals,
    ))
}

/// Step 2 for one channel: (ρs, F0, F1) from the θh = 0 slice, success, evaluations.
fn step2(
    td: &[f64],
    m: &[f64],
    w: &[f64],
    rho_d: f64,
    d: &Dist,
    g1: &SgdG1,
) -> Result<([f64; 3], bool, usize)> {
    let n = td.len();
    let d0 = d.d(1.0);
    // y = ρs F(θd) = (m − ρd/π) π cos²θd/(D(0) G1²(θd)).
    let y: Vec<f64> = td
        .iter()
        .zip(m)
        .map(|(&t, &mv)| {
            let c = t.cos();
            let g = g1_of(d, g1, c);
            (mv - rho_d * FRAC_1_PI) * PI * c * c / (d0 * g * g)
        })
        .collect();
    let basis: Vec<(f64, f64)> = td
        .iter()
        .map(|&t| {
            let c = t.cos();
            let m1 = 1.0 - c;
            (m1 * m1 * m1 * m1 * m1, c)
        })
        .collect();
    // Start: linear least squares in (ρs F0, ρs, ρs F1) of y = ρsF0(1−m5) + ρs m5 − ρsF1 c.
    let a = DMatrix::from_fn(n, 3, |i, j| {
        w[i] * match j {
            0 => 1.0 - basis[i].0,
            1 => basis[i].0,
            _ => -basis[i].1,
        }
    });
    let b = DVector::from_iterator(n, y.iter().zip(w).map(|(y, w)| y * w));
    let (mut rs, mut f0, mut f1) = (y.iter().cloned().fold(0.0, f64::max).max(1e-9), 1.0, 0.0);
    if let Ok(sol) = a.svd(true, true).solve(&b, 1e-12) {
        if sol[1] > 0.0 && sol.iter().all(|v| v.is_finite()) {
            rs = sol[1];
            f0 = sol[0] / rs;
            f1 = sol[2] / rs;
        }
    }
    let f = |x: &[f64], r: &mut [f64]| {
        let (rs, f0, f1) = fresnel_of(x[0], x[1], x[2]);
        for i in 0..n {
            let (m5, c) = basis[i];
            r[i] = w[i] * (rs * fresnel_basis(f0, f1, m5, c) - y[i]);
        }
    };
    let out = minimize(&f, n, &fresnel_vars(rs, f0, f1), SLICE_PATIENCE);
    let (rs, f0, f1) = fresnel_of(out.x[0], out.x[1], out.x[2]);
    Ok(([rs, f0, f1], out.ok, out.evals))
}

/// The fixed direction pairs of the refinement with their geometry and weights.
struct RefineSet {
    /// (cos θi, cos θo, cos θh, cos θd).
    geo: Vec<[f64; 4]>,
    /// [`G1Table::coord`] of θi and θo.
    coord: Vec<[f64; 2]>,
    /// √w of the Ngan quadrature.
    sw: Vec<f64>,
    /// Data per channel.
    m: [Vec<f64>; 3],
    /// The index of each pair's cos θh in `cos_h`: D depends on θh only, so it is evaluated
    /// once per distinct value, not once per pair.
    row: Vec<usize>,
    /// The distinct values (to the bit) of cos θh over the pairs (a few per θh node of the
    /// quadrature: the half vectors of one node agree to rounding).
    cos_h: Vec<f64>,
}

/// The quadrature of the refinement LM.
const REFINE_QUADRATURE: NganQuadrature = NganQuadrature {
    theta_h_panels: 4,
    theta_d_panels: 2,
    phi_d: 16,
    phi_h: 1,
};

impl RefineSet {
    fn new(data: &dyn Bsdf, q: &NganQuadrature, mask: Option<&MerlCoverage>) -> RefineSet {
        let pairs: Vec<_> = q
            .pairs(true)
            .into_iter()
            .flatten()
            .filter(|p| mask.is_none_or(|m| m.covers(p.wi, p.wo)))
            .collect();
        let vals: Vec<[f64; 3]> = pairs.par_iter().map(|p| data.eval(p.wi, p.wo).0).collect();
        let geo: Vec<[f64; 4]> = pairs
            .iter()
            .map(|p| {
                let h = (p.wi + p.wo).normalize();
                let (ci, co) = (p.wi.z, p.wo.z);
                [ci, co, h.z, p.wi.dot(h)]
            })
            .collect();
        let mut index = std::collections::HashMap::new();
        let mut cos_h = Vec::new();
        let row = geo
            .iter()
            .map(|g| {
                *index.entry(g[2].to_bits()).or_insert_with(|| {
                    cos_h.push(g[2]);
                    cos_h.len() - 1
                })
            })
            .collect();
        RefineSet {
            coord: geo
                .iter()
                .map(|g| [G1Table::coord(g[0]), G1Table::coord(g[1])])
                .collect(),
            geo,
            sw: pairs.iter().map(|p| p.w.sqrt()).collect(),
            m: std::array::from_fn(|c| vals.iter().map(|v| v[c]).collect()),
            row,
            cos_h,
        }
    }
}

/// The shadowing of a channel during refinement: the SGD's numeric table (fixed per round) or
/// the closed form of Beckmann / GGX.
fn shadowing_of(kind: CtDistribution, alpha: f64, p: f64) -> Result<SgdG1> {
    Ok(match kind {
        CtDistribution::Sgd => {
            SgdG1::Table(Box::new(G1Table::new(&Dist::new(kind, alpha, p).ndf()?)))
        }
        _ => SgdG1::One,
    })
}

/// G1(θi) and G1(θo) of one pair of the set (`g`: its geometry, `s`: its table coordinates).
#[inline]
fn shadowing(d: &Dist, g1: &SgdG1, g: &[f64; 4], s: &[f64; 2]) -> (f64, f64) {
    match (d.kind, g1) {
        // The table at the precomputed coordinates of θi, θo (no logarithm per pair).
        (CtDistribution::Sgd, SgdG1::Table(t)) => {
            (t.eval_coord(g[0], s[0]), t.eval_coord(g[1], s[1]))
        }
        _ => (g1_of(d, g1, g[0]), g1_of(d, g1, g[1])),
    }
}

/// G1(θi), G1(θo) of every pair when they do not change with (α, p) during an LM run: the
/// SGD's fixed numeric table (`None` for the closed forms of Beckmann and GGX, which follow α).
fn fixed_shadowing(kind: CtDistribution, g1: &SgdG1, set: &RefineSet) -> Option<Vec<(f64, f64)>> {
    if kind != CtDistribution::Sgd {
        return None;
    }
    let d = Dist {
        kind,
        alpha: 1.0,
        p: 0.0,
        ln_kap: 0.0,
    };
    Some(
        set.geo
            .iter()
            .zip(&set.coord)
            .map(|(g, s)| shadowing(&d, g1, g, s))
            .collect(),
    )
}

/// D(θh) G1(θi) G1(θo)/(cos θi cos θo) at every point of the set; D once per distinct cos θh,
/// the shadowing from `fixed` when given ([`fixed_shadowing`]). The same operations per pair
/// as evaluating everything per pair, so the same bits.
fn spec_factor(d: &Dist, g1: &SgdG1, set: &RefineSet, fixed: Option<&[(f64, f64)]>) -> Vec<f64> {
    let dh: Vec<f64> = set.cos_h.iter().map(|&c| d.d(c)).collect();
    let one = |g: &[f64; 4], r: usize, (gi, go): (f64, f64)| dh[r] * gi * go / (g[0] * g[1]);
    match fixed {
        Some(f) => set
            .geo
            .iter()
            .zip(&set.row)
            .zip(f)
            .map(|((g, &r), &s)| one(g, r, s))
            .collect(),
        None => set
            .geo
            .iter()
            .zip(&set.coord)
            .zip(&set.row)
            .map(|((g, s), &r)| one(g, r, shadowing(d, g1, g, s)))
            .collect(),
    }
}

/// Σ w (f − m)² of channel `ch` on the refinement set with shadowing `g1`.
fn refine_cost(
    kind: CtDistribution,
    c: &CtChannelParams,
    g1: &SgdG1,
    set: &RefineSet,
    ch: usize,
) -> f64 {
    let d = Dist::new(kind, c.alpha, c.p);
    let fr = Fresnel::GeneralizedSchlick { f0: c.f0, f1: c.f1 };
    spec_factor(&d, g1, set, fixed_shadowing(kind, g1, set).as_deref())
        .iter()
        .zip(&set.geo)
        .zip(&set.sw)
        .zip(&set.m[ch])
        .map(|(((&sf, g), &s), &m)| {
            let r = s * ((c.rho_d + c.rho_s * fr.eval(g[3]) * sf) * FRAC_1_PI - m);
            r * r
        })
        .sum()
}

/// The SGD shadowing approximation: Eq. V.3 fitted to the numeric table. `None` when the
/// stored (λ, c, k) cannot rebuild it (c underflows to 0 for very large k, seen for
/// α ≈ 1e-3, p ≈ 1.5); the channel then keeps the numeric Smith G1.
fn sgd_g1_fit(table: &G1Table) -> Option<[f64; 3]> {
    let (a, _) = SgdG1Approx::fit(table);
    SgdG1Approx::from_lck(a.lambda, a.c, a.k).ok()?;
    Some([a.lambda, a.c, a.k])
}

/// One refinement LM of channel `ch` with the SGD shadowing held at `g1` (a numeric table).
/// Variables: ln ρd, ln ρs, ln α, the Fresnel variables of [`fresnel_of`] and, for SGD, q
/// (p = −1.9 + 4.8 sigmoid q). D is evaluated once per θh node of the set, the SGD shadowing
/// (a fixed table during the run) once per pair and run; D·G is cached per (α, p), so the
/// Jacobian columns of the linear parameters cost a few multiplies per point.
fn refine_round(
    kind: CtDistribution,
    c: &CtChannelParams,
    g1: &SgdG1,
    set: &RefineSet,
    ch: usize,
) -> (CtChannelParams, bool, usize) {
    let sgd = kind == CtDistribution::Sgd;
    let n = set.geo.len();
    let m = &set.m[ch];
    let basis: Vec<(f64, f64)> = set
        .geo
        .iter()
        .map(|g| {
            let cd = g[3].clamp(0.0, 1.0);
            let m1 = 1.0 - cd;
            (m1 * m1 * m1 * m1 * m1, cd)
        })
        .collect();
    // Two entries, most recent first: a forward-difference Jacobian steps α and p away from
    // the current point and back, so the current point's factor is reused.
    type Cache = Vec<([f64; 2], Vec<f64>)>;
    let cache: std::sync::Mutex<Cache> = std::sync::Mutex::new(Vec::with_capacity(2));
    // The SGD shadowing is held fixed during the run: computed once, not once per evaluation.
    let fixed = fixed_shadowing(kind, g1, set);
    let f = |x: &[f64], r: &mut [f64]| {
        let (rd, a) = (pos_of(x[0]), alpha_of(x[2]));
        let p = if sgd { p_of(x[5]) } else { 0.0 };
        let (rs, f0, f1) = fresnel_of(x[1], x[3], x[4]);
        let mut guard = cache.lock().unwrap_or_else(|e| e.into_inner());
        match guard.iter().position(|(k, _)| *k == [a, p]) {
            Some(0) => {}
            Some(i) => guard.swap(0, i),
            None => {
                guard.truncate(1);
                let sf = spec_factor(&Dist::new(kind, a, p), g1, set, fixed.as_deref());
                guard.insert(0, ([a, p], sf));
            }
        }
        if let Some((_, sf)) = guard.first() {
            for i in 0..n {
                let (m5, cd) = basis[i];
                let fres = rs * fresnel_basis(f0, f1, m5, cd);
                r[i] = set.sw[i] * ((rd + fres * sf[i]) * FRAC_1_PI - m[i]);
            }
        }
    };
    let [xs, fa, fc] = fresnel_vars(c.rho_s, c.f0, c.f1);
    let mut x0 = vec![ln_pos(c.rho_d), xs, c.alpha.ln(), fa, fc];
    if sgd {
        x0.push(q_of(c.p));
    }
    let out = minimize(&f, n, &x0, REFINE_PATIENCE);
    let x = &out.x;
    let (rho_s, f0, f1) = fresnel_of(x[1], x[3], x[4]);
    let next = CtChannelParams {
        rho_d: pos_of(x[0]),
        rho_s,
        alpha: alpha_of(x[2]),
        p: if sgd { p_of(x[5]) } else { 0.0 },
        kap: 0.0,
        f0,
        f1,
        g1: None,
    };
    (next, out.ok, out.evals)
}

/// Steps 1 and 2 for one channel, as a [`Candidate`] (with the shadowing of its (α, p)).
fn two_slice(
    input: &str,
    kind: CtDistribution,
    ch: usize,
    slices: &Slices,
) -> Result<(Candidate, usize)> {
    let (s1, ok1, e1) = step1(
        input,
        kind,
        &slices.th,
        &slices.mh[ch],
        &slices.sw_h,
        &slices.valid_h,
    )?;
    let [rho_d, _fr, alpha, p] = s1;
    let d = Dist::new(kind, alpha, p);
    let g1 = shadowing_of(kind, alpha, p)?;
    let (s2, ok2, e2) = step2(&slices.td, &slices.md[ch], &slices.w_d, rho_d, &d, &g1)?;
    let [rho_s, f0, f1] = s2;
    let c = CtChannelParams {
        rho_d,
        rho_s,
        alpha,
        p,
        kap: 0.0,
        f0,
        f1,
        g1: None,
    };
    Ok((
        Candidate {
            c,
            g1,
            ok: ok1 && ok2,
        },
        e1 + e2,
    ))
}

/// A refinement candidate: parameters, the shadowing of its own (α, p), LM success.
struct Candidate {
    c: CtChannelParams,
    g1: SgdG1,
    ok: bool,
}

impl Candidate {
    fn new(kind: CtDistribution, c: CtChannelParams, ok: bool) -> Result<Self> {
        let g1 = shadowing_of(kind, c.alpha, c.p)?;
        Ok(Candidate { c, g1, ok })
    }

    /// Refines from this candidate; returns the refined one and the evaluations.
    fn refine(&self, kind: CtDistribution, set: &RefineSet, ch: usize) -> Result<(Self, usize)> {
        let (next, ok, e) = refine_round(kind, &self.c, &self.g1, set, ch);
        Ok((Candidate::new(kind, next, ok)?, e))
    }
}

/// Fits one channel: two slices, refinement, shadowing approximation. For SGD the refinement
/// also starts from the refined Beckmann fit (SGD with p = 0 and α = α_B² is Beckmann), so the
/// SGD result is never worse than Beckmann on the refinement set.
fn fit_channel(
    input: &str,
    kind: CtDistribution,
    ch: usize,
    slices: &Slices,
    sets: Option<(&RefineSet, &RefineSet)>,
) -> Result<(CtChannelParams, bool, usize)> {
    let (start, mut evals) = two_slice(input, kind, ch, slices)?;
    let (mut c, mut g1, mut ok) = (start.c, start.g1.clone(), start.ok);
    if let Some((set, select)) = sets {
        let (refined, e) = start.refine(kind, set, ch)?;
        evals += e;
        let mut cands = vec![start, refined];
        if kind == CtDistribution::Sgd {
            // A failure here (e.g. a Beckmann α beyond the SGD's range) only drops the candidate.
            let from_beckmann = || -> Result<(Candidate, Candidate, usize)> {
                let beck = CtDistribution::Beckmann;
                let (b0, eb) = two_slice(input, beck, ch, slices)?;
                let (b1, eb1) = b0.refine(beck, set, ch)?;
                let as_sgd = CtChannelParams {
                    alpha: (b1.c.alpha * b1.c.alpha).clamp(LN_ALPHA.0.exp(), LN_ALPHA.1.exp()),
                    p: 0.0,
                    ..b1.c
                };
                let embedded = Candidate::new(kind, as_sgd, b1.ok)?;
                let (s1, es) = embedded.refine(kind, set, ch)?;
                Ok((embedded, s1, eb + eb1 + es))
            };
            if let Ok((s0, s1, e)) = from_beckmann() {
                evals += e;
                cands.push(s0);
                cands.push(s1);
            }
        }
        // Choose on the full Ngan quadrature (the refinement set is coarser).
        let best = cands
            .into_iter()
            .map(|k| (refine_cost(kind, &k.c, &k.g1, select, ch), k))
            .filter(|(cost, _)| cost.is_finite())
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, k)| k);
        if let Some(best) = best {
            (c, g1, ok) = (best.c, best.g1, ok && best.ok);
        }
    }
    if kind == CtDistribution::Sgd {
        c.kap = Dist::new(kind, c.alpha, c.p).ln_kap.exp();
        if let SgdG1::Table(t) = &g1 {
            c.g1 = sgd_g1_fit(t);
        }
    }
    Ok((c, ok, evals))
}

/// The two slices of the data at MERL bin nodes; points the mask does not cover get weight 0.
struct Slices {
    th: Vec<f64>,
    sw_h: Vec<f64>,
    valid_h: Vec<bool>,
    mh: [Vec<f64>; 3],
    td: Vec<f64>,
    w_d: Vec<f64>,
    md: [Vec<f64>; 3],
}

/// Whether the mask covers the pair at (θh, θd, φd) (φh = 0).
fn covered(mask: Option<&MerlCoverage>, theta_h: f64, theta_d: f64, phi_d: f64) -> bool {
    let Some(m) = mask else {
        return true;
    };
    let (wi, wo) = from_half_diff(&HalfDiff {
        theta_h,
        phi_h: 0.0,
        theta_d,
        phi_d,
    });
    m.covers(wi, wo)
}

impl Slices {
    fn new(data: &dyn Bsdf, max_theta_d: f64, mask: Option<&MerlCoverage>) -> Slices {
        let th: Vec<f64> = (0..RES_THETA_H)
            .map(|i| bin_node(i, 0, 0).theta_h)
            .collect();
        let valid_h: Vec<bool> = th.iter().map(|&t| covered(mask, t, 0.0, 0.0)).collect();
        // Weights: sin θh cos²θh Δθh, Δθh = (2i+1)/90² · π/2 (the bin width of the u² mapping).
        let sw_h = th
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let dt = (2 * i + 1) as f64 / (RES_THETA_H * RES_THETA_H) as f64 * FRAC_PI_2;
                (t.sin() * t.cos() * t.cos() * dt).sqrt() * f64::from(u8::from(valid_h[i]))
            })
            .collect();
        let vh: Vec<[f64; 3]> = th.iter().map(|&t| data_at(data, t, 0.0, 0.0)).collect();
        let td: Vec<f64> = (0..RES_THETA_D)
            .map(|j| bin_node(0, j, 0).theta_d)
            .filter(|&t| t <= max_theta_d)
            .collect();
        let phi_d = FRAC_PI_2;
        let w_d = td
            .iter()
            .map(|&t| f64::from(u8::from(covered(mask, 0.0, t, phi_d))))
            .collect();
        let vd: Vec<[f64; 3]> = td.iter().map(|&t| data_at(data, 0.0, t, phi_d)).collect();
        Slices {
            th,
            sw_h,
            valid_h,
            mh: std::array::from_fn(|c| vh.iter().map(|v| v[c]).collect()),
            td,
            w_d,
            md: std::array::from_fn(|c| vd.iter().map(|v| v[c]).collect()),
        }
    }
}

/// Fits Cook-Torrance with `distribution` to `data` (module notes). Errors: non-finite slice
/// data, too few θd samples, or a fit that ends with non-finite parameters (`FitError::Data`
/// naming the data); `FitStatus::NotConverged` when an optimization stopped at its limit.
pub fn fit(data: &dyn Bsdf, distribution: CtDistribution, opts: &CtOptions) -> Result<CtFit> {
    fit_masked(data, distribution, opts, None)
}

/// [`fit`] on the direction pairs `mask` covers (a MERL table's measured bins).
pub fn fit_masked(
    data: &dyn Bsdf,
    distribution: CtDistribution,
    opts: &CtOptions,
    mask: Option<&MerlCoverage>,
) -> Result<CtFit> {
    let input = data.name();
    let err = |problem: String| FitError::Data {
        input: input.clone(),
        problem,
    };
    if !(opts.max_theta_d_deg.is_finite()
        && opts.max_theta_d_deg > 5.0
        && opts.max_theta_d_deg <= 90.0)
    {
        return Err(FitError::Option(format!(
            "max_theta_d_deg = {} (must lie in (5, 90])",
            opts.max_theta_d_deg
        )));
    }
    let slices = Slices::new(data, opts.max_theta_d_deg.to_radians(), mask);
    for (c, (h, d)) in slices.mh.iter().zip(&slices.md).enumerate() {
        if h.iter().chain(d).any(|v| !v.is_finite()) {
            return Err(err(format!(
                "non-finite values on the fitting slices (channel {c})"
            )));
        }
        if h.iter()
            .zip(&slices.valid_h)
            .all(|(&v, &ok)| v <= 0.0 || !ok)
        {
            return Err(err(format!("channel {c} is zero on the θd = 0 slice")));
        }
    }
    let sets = opts.refine.then(|| {
        (
            RefineSet::new(data, &REFINE_QUADRATURE, mask),
            RefineSet::new(data, &NganQuadrature::default(), mask),
        )
    });
    let fits: Vec<Result<(CtChannelParams, bool, usize)>> = (0..3)
        .into_par_iter()
        .map(|ch| {
            fit_channel(
                &input,
                distribution,
                ch,
                &slices,
                sets.as_ref().map(|(a, b)| (a, b)),
            )
        })
        .collect();
    let mut channels = Vec::with_capacity(3);
    let (mut ok, mut iterations) = (true, 0);
    for f in fits {
        let (c, o, e) = f?;
        ok &= o;
        iterations += e;
        let finite = [c.rho_d, c.rho_s, c.alpha, c.p, c.kap, c.f0, c.f1]
            .iter()
            .chain(c.g1.iter().flatten())
            .all(|v| v.is_finite());
        if !finite {
            return Err(err(format!(
                "the fit produced non-finite parameters: {c:?}"
            )));
        }
        channels.push(c);
    }
    let mut channels: [CtChannelParams; 3] = [channels[0], channels[1], channels[2]];
    let notes = cap_albedo(data, distribution, &mut channels)?;
    Ok(CtFit {
        distribution,
        channels,
        status: if ok {
            FitStatus::Converged
        } else {
            FitStatus::NotConverged
        },
        iterations,
        notes,
    })
}

/// Step 5: caps ρd and scales ρs down where the model's directional albedo exceeds 1 while the
/// data's does not (`metrics::albedo_bound`); returns a note per changed channel.
fn cap_albedo(
    data: &dyn Bsdf,
    distribution: CtDistribution,
    channels: &mut [CtChannelParams; 3],
) -> Result<Vec<String>> {
    let data_max = crate::metrics::max_albedo(data, false);
    // The specular albedo per unit ρs: the model with ρd = 0, ρs = 1.
    let unit: [CtChannelParams; 3] = channels.map(|c| CtChannelParams {
        rho_d: 0.0,
        rho_s: 1.0,
        ..c
    });
    let spec = CtFit {
        distribution,
        channels: unit,
        status: FitStatus::Converged,
        iterations: 0,
        notes: Vec::new(),
    }
    .to_bsdf("unit specular")?;
    let caps = crate::metrics::albedo_bound(
        data_max,
        channels.map(|c| c.rho_d),
        channels.map(|c| c.rho_s),
        &spec,
        false,
    );
    let mut notes = Vec::new();
    for cap in caps {
        let ch = &mut channels[cap.channel];
        notes.push(cap.describe(("rho_d", ch.rho_d), ("rho_s", ch.rho_s)));
        ch.rho_d = cap.diffuse;
        ch.rho_s = cap.scale;
    }
    Ok(notes)
}
