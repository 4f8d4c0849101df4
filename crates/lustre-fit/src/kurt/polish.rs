//! Levenberg-Marquardt polish of the brute-force result ([`marquardt`]: normal equations, see
//! there why not the `levenberg-marquardt` crate's QR here).
//!
//! LM minimizes a sum of squares; the L1 metric of Eq. 3.7 is approximated by the
//! pseudo-Huber loss ρ(e) = √(e² + δ²) − δ (≈ |e| for |e| ≫ δ, smooth at 0) with
//! residuals r = sign(e)·√(a·ρ(e)), so that Σ r² = Σ a·ρ(e). δ is 1 % of the weighted mean
//! |data|. All free parameters are polished jointly (kd, every ks/kt channel, mx, my, r0, α of
//! every lobe; mx, my in ln; a tied my follows mx), each projected onto its range. The Jacobian is taken by forward
//! differences. Two stages: on every 4th pair, then on all pairs from there ([`polish`]).
//! The polished model is kept only when it lowers the true Eq. 3.7 error (on all pairs).

use super::params::{Param, Space};
use super::samples::{LobeConst, PairSet, Samples};
use lustre_brdf::models::kurt::{Kurt, LobeKind};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::cell::Cell;
use std::f64::consts::PI;

/// What a free parameter of the polish points to.
#[derive(Clone, Copy, Debug)]
enum Target {
    Kd(usize),
    Ks(bool, usize, usize),
    Shape(bool, usize, usize),
}

/// A free parameter: its target, its range in coordinates and its scale.
#[derive(Clone, Copy, Debug)]
struct Slot {
    target: Target,
    param: Param,
    lo: f64,
    hi: f64,
}

/// The least-squares problem handed to LM.
struct Problem<'a> {
    s: &'a Samples,
    base: Kurt,
    slots: Vec<Slot>,
    /// Lobes whose my follows mx: (transmission?, index).
    ties: Vec<(bool, usize)>,
    delta: f64,
    evaluations: Cell<usize>,
}

/// Collects the free parameters of `space` with their current values in `model`.
fn free_slots(space: &Space, model: &Kurt) -> (Vec<Slot>, Vec<f64>) {
    let mut slots = Vec::new();
    let mut x = Vec::new();
    let mut push = |target: Target, param: Param, v: f64| {
        if let Some((lo, hi)) = param.coord_range() {
            // kd's open upper end: bounded for the clamp only.
            let hi = if hi.is_finite() { hi } else { f64::MAX };
            slots.push(Slot {
                target,
                param,
                lo,
                hi,
            });
            x.push(param.to_coord(v).clamp(lo, hi));
        }
    };
    for c in 0..3 {
        push(Target::Kd(c), space.kd[c], model.kd[c]);
    }
    for (trans, spaces, lobes) in [
        (false, &space.refl, &model.reflection),
        (true, &space.trans, &model.transmission),
    ] {
        for (i, (sp, l)) in spaces.iter().zip(lobes).enumerate() {
            for c in 0..3 {
                push(Target::Ks(trans, i, c), sp.ks[c], l.ks[c]);
            }
            let vals = [l.mx, l.my, l.r0, l.alpha];
            for (k, (&param, &v)) in sp.shape.iter().zip(&vals).enumerate() {
                if !(k == 1 && sp.tie_my) {
                    push(Target::Shape(trans, i, k), param, v);
                }
            }
        }
    }
    (slots, x)
}

impl Problem<'_> {
    /// The model at parameter vector `x` (each coordinate clamped to its range).
    fn model(&self, x: &DVector<f64>) -> Kurt {
        let mut m = self.base.clone();
        for (s, &xi) in self.slots.iter().zip(x.iter()) {
            let v = s.param.value_at(xi.clamp(s.lo, s.hi));
            match s.target {
                Target::Kd(c) => m.kd[c] = v,
                Target::Ks(t, i, c) => {
                    let l = if t {
                        &mut m.transmission[i]
                    } else {
                        &mut m.reflection[i]
                    };
                    l.ks[c] = v;
                }
                Target::Shape(t, i, k) => {
                    let l = if t {
                        &mut m.transmission[i]
                    } else {
                        &mut m.reflection[i]
                    };
                    match k {
                        0 => l.mx = v,
                        1 => l.my = v,
                        2 => l.r0 = v,
                        _ => l.alpha = v,
                    }
                }
            }
        }
        for &(t, i) in &self.ties {
            let l = if t {
                &mut m.transmission[i]
            } else {
                &mut m.reflection[i]
            };
            l.my = l.mx;
        }
        m
    }

    /// The residual vector of a model.
    fn residuals_of(&self, m: &Kurt) -> DVector<f64> {
        self.evaluations.set(self.evaluations.get() + 1);
        let nr = self.s.refl.len();
        let nt = self.s.trans.len();
        let mut out = vec![0.0; 3 * (nr + nt)];
        let (ro, to) = out.split_at_mut(3 * nr);
        let delta = self.delta;
        let fill =
            |set: &PairSet, out: &mut [f64], kd: [f64; 3], lobes: &[(LobeConst, [f64; 3])]| {
                out.par_chunks_mut(3).enumerate().for_each(|(t, r)| {
                    let mut p = kd.map(|k| k / PI * set.cos_o[t]);
                    for (c, ks) in lobes {
                        let g = c.eval(set, t);
                        for ch in 0..3 {
                            p[ch] += ks[ch] * g;
                        }
                    }
                    for ch in 0..3 {
                        let e = set.data[ch][t] - p[ch];
                        let rho = (e * e + delta * delta).sqrt() - delta;
                        r[ch] = e.signum() * (set.weight[t] * rho).sqrt();
                    }
                });
            };
        let consts = |lobes: &[lustre_brdf::models::kurt::KurtLobe], kind| {
            lobes
                .iter()
                .map(|l| (LobeConst::new(l, kind), l.ks.0))
                .collect::<Vec<_>>()
        };
        fill(
            &self.s.refl,
            ro,
            m.kd.0,
            &consts(&m.reflection, LobeKind::Reflection),
        );
        fill(
            &self.s.trans,
            to,
            [0.0; 3],
            &consts(&m.transmission, LobeKind::Transmission),
        );
        DVector::from_vec(out)
    }
}

impl Problem<'_> {
    /// Projects a parameter vector onto the ranges of its slots.
    fn project(&self, x: &mut DVector<f64>) {
        for (s, v) in self.slots.iter().zip(x.iter_mut()) {
            *v = v.clamp(s.lo, s.hi);
        }
    }

    /// The residuals at `x`, `None` when one is not finite.
    fn residuals_at(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        let r = self.residuals_of(&self.model(x));
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    /// The Jacobian columns at `x` (residuals `r0` there) by forward differences (backward at
    /// the upper end of a range); `None` when one is not finite.
    fn jacobian_at(&self, x: &DVector<f64>, r0: &DVector<f64>) -> Option<Vec<DVector<f64>>> {
        let mut cols = Vec::with_capacity(x.len());
        for (k, s) in self.slots.iter().enumerate() {
            let xk = x[k];
            let h = 1e-6 * xk.abs().max(1e-3);
            let step = if xk + h <= s.hi { h } else { -h };
            let mut xs = x.clone();
            xs[k] = xk + step;
            let r = self.residuals_of(&self.model(&xs));
            let col = (r - r0) / step;
            if !col.iter().all(|v| v.is_finite()) {
                return None;
            }
            cols.push(col);
        }
        Some(cols)
    }
}

/// How [`marquardt`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stop {
    /// Relative reduction of ‖r‖², actual and predicted, below [`TOL`].
    Ftol,
    /// Scaled step below [`TOL`] times the scaled parameters.
    Xtol,
    /// Both of the above on the same step.
    Both,
    /// Zero gradient.
    Gtol,
    /// No step lowers the error even with the largest damping (a minimum at machine precision).
    Precision,
    /// The evaluation limit was reached.
    Limit,
    /// The residuals or the Jacobian at the start are not finite.
    NonFinite,
}

/// Relative tolerances of [`marquardt`] (those of MINPACK's and the `levenberg-marquardt`
/// crate's defaults: √ε).
const TOL: f64 = 1.490_116_119_384_765_6e-8;

/// Levenberg-Marquardt with Marquardt's diagonal scaling, solved by the normal equations
/// (JᵀJ + λ·diag JᵀJ) δ = −Jᵀr with a Cholesky factorization, steps projected onto the
/// parameter ranges. With n ≤ a few dozen parameters and 3·N ≈ 33 000 residuals, forming JᵀJ
/// (n²/2 dot products) costs a few milliseconds where the pivoted QR of the 3N × n Jacobian
/// (crate `levenberg-marquardt`) took about 40 % of a 3-lobe fit, single-threaded. At most
/// `max_evals` residual evaluations (the Jacobian's n included).
fn marquardt(p: &Problem, x0: DVector<f64>, max_evals: usize) -> (DVector<f64>, Stop) {
    let mut x = x0;
    p.project(&mut x);
    let Some(mut r) = p.residuals_at(&x) else {
        return (x, Stop::NonFinite);
    };
    let mut cost = r.norm_squared();
    let n = x.len();
    let (mut lambda, mut nu) = (1e-3, 2.0);
    loop {
        if p.evaluations.get() + n + 1 > max_evals {
            return (x, Stop::Limit);
        }
        let Some(cols) = p.jacobian_at(&x, &r) else {
            return (x, Stop::NonFinite);
        };
        let mut a = DMatrix::zeros(n, n);
        for i in 0..n {
            for k in 0..=i {
                let v = cols[i].dot(&cols[k]);
                a[(i, k)] = v;
                a[(k, i)] = v;
            }
        }
        let g = DVector::from_fn(n, |i, _| cols[i].dot(&r));
        if g.iter().all(|v| *v == 0.0) {
            return (x, Stop::Gtol);
        }
        let dmax = (0..n).map(|i| a[(i, i)]).fold(0.0, f64::max);
        let d: Vec<f64> = (0..n)
            .map(|i| a[(i, i)].max(1e-12 * dmax).max(f64::MIN_POSITIVE))
            .collect();
        let xnorm = (0..n).map(|i| d[i] * x[i] * x[i]).sum::<f64>().sqrt();
        loop {
            if p.evaluations.get() >= max_evals {
                return (x, Stop::Limit);
            }
            let mut m = a.clone();
            for (i, di) in d.iter().enumerate() {
                m[(i, i)] += lambda * di;
            }
            let step = match m.cholesky() {
                Some(ch) => ch.solve(&(-&g)),
                None => {
                    lambda *= 4.0;
                    if lambda > 1e20 {
                        return (x, Stop::Precision);
                    }
                    continue;
                }
            };
            let mut xn = &x + &step;
            p.project(&mut xn);
            let s = &xn - &x;
            // Predicted reduction of ‖r‖² by the linear model: −2gᵀs − sᵀAs.
            let pred = -2.0 * g.dot(&s) - s.dot(&(&a * &s));
            let snorm = (0..n).map(|i| d[i] * s[i] * s[i]).sum::<f64>().sqrt();
            let trial = p.residuals_at(&xn).map(|rn| (rn.norm_squared(), rn));
            match trial {
                Some((cn, rn)) if cn < cost => {
                    let actual = cost - cn;
                    let ftol = actual <= TOL * cost && pred <= TOL * cost;
                    let xtol = snorm <= TOL * xnorm;
                    x = xn;
                    r = rn;
                    cost = cn;
                    // Nielsen's update from the gain ratio ρ = actual / predicted reduction.
                    let rho = if pred > 0.0 { actual / pred } else { 0.0 };
                    lambda =
                        (lambda * (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3))).max(1e-15);
                    nu = 2.0;
                    match (ftol, xtol) {
                        (true, true) => return (x, Stop::Both),
                        (true, false) => return (x, Stop::Ftol),
                        (false, true) => return (x, Stop::Xtol),
                        _ => break,
                    }
                }
                _ => {
                    if snorm <= TOL * xnorm.max(f64::MIN_POSITIVE) || lambda > 1e20 {
                        return (x, Stop::Precision);
                    }
                    lambda *= nu;
                    nu *= 2.0;
                }
            }
        }
    }
}

/// The polish's outcome.
pub(crate) struct Polished {
    /// The polished model (parameters clamped to their ranges).
    pub model: Kurt,
    /// Whether LM met one of its convergence criteria (or met them at machine precision).
    pub converged: bool,
    /// Residual-vector evaluations (each over all pairs).
    pub evaluations: usize,
    /// How LM ended, in words (its termination reason).
    pub reason: String,
}

/// How the polish ended, in words.
fn reason_words(t: Stop, n: usize) -> String {
    match t {
        Stop::Ftol => "converged (relative reduction of the error below tolerance)".into(),
        Stop::Xtol => "converged (relative step below tolerance)".into(),
        Stop::Both => {
            "converged (relative reduction of the error and of the step below tolerance)".into()
        }
        Stop::Gtol => "converged (zero gradient)".into(),
        Stop::Precision => {
            "converged at machine precision (no step lowers the error at any damping)".into()
        }
        Stop::Limit => format!(
            "not converged: LM stopped at its evaluation limit ({} = {MAX_EVALS_PER_PARAM}·(n+1), n = {n})",
            MAX_EVALS_PER_PARAM * (n + 1)
        ),
        Stop::NonFinite => "not converged: the residuals are not finite at the start".into(),
    }
}

/// Evaluation limit of each polish stage per free parameter (plus one). 15 (the patience the
/// `levenberg-marquardt` crate's LM had here) stopped most multi-lobe polishes at the limit;
/// 50 lowers the Eq. 3.7 error further on 14 of 15 fits of the regression set (tests/kurt.rs).
const MAX_EVALS_PER_PARAM: usize = 50;

/// Thinning of the first polish stage (every `POLISH_THIN`-th pair, see [`polish`]).
const POLISH_THIN: usize = 4;

/// Runs LM from `model` over the free parameters of `space`, in two stages: first on every
/// [`POLISH_THIN`]-th pair (weights scaled up, [`PairSet::every`]), where each residual and
/// Jacobian costs a quarter, then on the whole set from that result (the thinned optimum alone
/// was up to 12 % worse on the whole set: pink-felt, one lobe). The second stage's outcome is
/// the polish's. Each stage may use up to [`MAX_EVALS_PER_PARAM`]·(n + 1) residual
/// evaluations, the Jacobian's n per iteration included (the crate's patience counted only
/// trial points, so this limit allows fewer iterations than its 15·(n + 1)).
pub(crate) fn polish(s: &Samples, space: &Space, model: &Kurt) -> Polished {
    let thin = s.every(POLISH_THIN);
    let first = polish_on(&thin, space, model);
    let mut out = polish_on(s, space, &first.model);
    // Residual evaluations over the whole set: the thinned ones count a quarter.
    out.evaluations += first.evaluations.div_ceil(POLISH_THIN);
    out
}

/// One LM run from `model` over the free parameters of `space` on the pairs of `s`.
fn polish_on(s: &Samples, space: &Space, model: &Kurt) -> Polished {
    let (slots, x) = free_slots(space, model);
    if slots.is_empty() {
        return Polished {
            model: model.clone(),
            converged: true,
            evaluations: 0,
            reason: "nothing to polish (every parameter is fixed)".into(),
        };
    }
    let (mut num, mut den) = (0.0, 0.0);
    for set in [&s.refl, &s.trans] {
        for t in 0..set.len() {
            num += set.weight[t] * (set.data[0][t] + set.data[1][t] + set.data[2][t]) / 3.0;
            den += set.weight[t];
        }
    }
    let delta = (0.01 * num / den.max(f64::MIN_POSITIVE)).max(1e-12);
    let ties = [(false, &space.refl), (true, &space.trans)]
        .into_iter()
        .flat_map(|(t, v)| {
            v.iter()
                .enumerate()
                .filter(|(_, l)| l.tie_my)
                .map(move |(i, _)| (t, i))
        })
        .collect();
    let n = slots.len();
    let problem = Problem {
        s,
        base: model.clone(),
        slots,
        ties,
        delta,
        evaluations: Cell::new(0),
    };
    let (x, stop) = marquardt(
        &problem,
        DVector::from_vec(x),
        MAX_EVALS_PER_PARAM * (n + 1),
    );
    Polished {
        model: problem.model(&x),
        converged: !matches!(stop, Stop::Limit | Stop::NonFinite),
        evaluations: problem.evaluations.get(),
        reason: reason_words(stop, n),
    }
}
