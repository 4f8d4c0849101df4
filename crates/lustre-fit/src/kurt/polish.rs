//! Levenberg-Marquardt polish of the brute-force result ([`marquardt`]: normal equations, see
//! there why not the `levenberg-marquardt` crate's QR here).
//!
//! LM minimizes a sum of squares; the L1 metric of Eq. 3.7 is approximated by the
//! pseudo-Huber loss ρ(e) = √(e² + δ²) − δ (≈ |e| for |e| ≫ δ, smooth at 0) with
//! residuals r = sign(e)·√(a·ρ(e)), so that Σ r² = Σ a·ρ(e). δ is 1 % of the weighted mean
//! |data|. All free parameters are polished jointly (kd, every ks/kt channel, mx, my, r0, α of
//! every lobe; mx, my in ln; a tied my follows mx), each projected onto its range. The Jacobian is
//! analytic ([`Problem::normal_equations`]). Two stages: on every 4th pair, then on all pairs from there ([`polish`]).
//! Bounds are handled by projection plus an active set: a parameter on a bound whose descent
//! direction leaves the range is held there for the iteration. With the squared loss
//! ([`polish_squares`]) the same LM minimizes Ngan's L2 on its quadrature. Which result the fit
//! keeps is decided in `kurt::fit_judged` (the Eq. 3.7 error, or the user's metric).

use super::params::{Param, Space};
use super::samples::{LobeConst, PairSet, Samples};
use lustre_brdf::models::kurt::{Kurt, KurtLobe, LobeKind};
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
    loss: Loss,
    evaluations: Cell<usize>,
}

/// The loss of a pair's error e = data − p (weight a).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Loss {
    /// a·(√(e² + δ²) − δ): ≈ a|e|, the L1 of Eq. 3.7, smooth at 0.
    PseudoHuber(f64),
    /// a·e²: Ngan's L2 on its quadrature ([`super::samples::ngan_set`]).
    Squares,
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
        let loss = self.loss;
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
                        r[ch] = match loss {
                            Loss::PseudoHuber(delta) => {
                                let rho = (e * e + delta * delta).sqrt() - delta;
                                e.signum() * (set.weight[t] * rho).sqrt()
                            }
                            Loss::Squares => set.weight[t].sqrt() * e,
                        };
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

    /// JᵀJ and Jᵀr at `x` (residuals `r` there) with the analytic Jacobian J, accumulated pair
    /// by pair (J itself, 3N × n, is never stored). With e = data − p and q = √(e² + δ²), the
    /// residual sign(e)·√(a·ρ(e)) has d/de = √a·√(q + δ)/(2q) (finite at e = 0); p is linear in
    /// kd and ks, and [`LobeConst::eval_grad`] gives the lobe's shape derivatives; a coordinate
    /// on a log scale multiplies by its value. `None` when an entry is not finite.
    fn normal_equations(
        &self,
        x: &DVector<f64>,
        r: &DVector<f64>,
    ) -> Option<(DMatrix<f64>, DVector<f64>)> {
        self.evaluations.set(self.evaluations.get() + 1);
        let m = self.model(x);
        let n = self.slots.len();
        // d value / d coordinate per slot.
        let dv: Vec<f64> = self
            .slots
            .iter()
            .zip(x.iter())
            .map(|(s, &xi)| match s.param {
                Param::Free { log: true, .. } => s.param.value_at(xi.clamp(s.lo, s.hi)),
                _ => 1.0,
            })
            .collect();
        let (slots, ties, loss) = (&self.slots, &self.ties, self.loss);
        let nr = self.s.refl.len();
        // Per set: JᵀJ (row-major n × n, lower triangle) and Jᵀr summed over its pairs.
        let accumulate =
            |set: &PairSet, trans: bool, r: &[f64], kd: [f64; 3], lobes: &[KurtLobe]| {
                let kind = if trans {
                    LobeKind::Transmission
                } else {
                    LobeKind::Reflection
                };
                let consts: Vec<LobeConst> =
                    lobes.iter().map(|l| LobeConst::new(l, kind)).collect();
                let init = || {
                    (
                        vec![0.0; n * n],
                        vec![0.0; n],
                        vec![0.0; 3 * n],
                        vec![(0.0, [0.0; 4]); lobes.len()],
                    )
                };
                type Acc = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<(f64, [f64; 4])>);
                let step = |(mut a, mut g, mut row, mut grads): Acc, t: usize| -> Acc {
                    let mut p = kd.map(|k| k / PI * set.cos_o[t]);
                    for ((c, l), gr) in consts.iter().zip(lobes).zip(grads.iter_mut()) {
                        *gr = c.eval_grad(set, t);
                        for (pc, ks) in p.iter_mut().zip(l.ks.0) {
                            *pc += ks * gr.0;
                        }
                    }
                    let sw = set.weight[t].sqrt();
                    let drde: [f64; 3] = std::array::from_fn(|ch| match loss {
                        Loss::PseudoHuber(delta) => {
                            let e = set.data[ch][t] - p[ch];
                            let q = (e * e + delta * delta).sqrt();
                            sw * (q + delta).sqrt() / (2.0 * q)
                        }
                        Loss::Squares => sw,
                    });
                    row.fill(0.0);
                    for (k, (slot, dvk)) in slots.iter().zip(&dv).enumerate() {
                        match slot.target {
                            Target::Kd(c) if !trans => {
                                row[c * n + k] = -drde[c] * set.cos_o[t] / PI * dvk;
                            }
                            Target::Ks(tt, i, c) if tt == trans => {
                                row[c * n + k] = -drde[c] * grads[i].0 * dvk;
                            }
                            Target::Shape(tt, i, which) if tt == trans => {
                                let dg = &grads[i].1;
                                let d = if which == 0 && ties.contains(&(tt, i)) {
                                    dg[0] + dg[1]
                                } else {
                                    dg[which]
                                };
                                for ch in 0..3 {
                                    row[ch * n + k] = -drde[ch] * lobes[i].ks.0[ch] * d * dvk;
                                }
                            }
                            _ => {}
                        }
                    }
                    for ch in 0..3 {
                        let jr = &row[ch * n..(ch + 1) * n];
                        let rv = r[3 * t + ch];
                        for i in 0..n {
                            let ji = jr[i];
                            if ji == 0.0 {
                                continue;
                            }
                            g[i] += ji * rv;
                            for k in 0..=i {
                                a[i * n + k] += ji * jr[k];
                            }
                        }
                    }
                    (a, g, row, grads)
                };
                // Fixed chunks summed in order: the same sums whatever the threads do.
                let partial: Vec<(Vec<f64>, Vec<f64>)> = (0..set.len().div_ceil(PAIR_CHUNK))
                    .into_par_iter()
                    .map(|k| {
                        let pairs = k * PAIR_CHUNK..((k + 1) * PAIR_CHUNK).min(set.len());
                        let (a, g, _, _) = pairs.fold(init(), step);
                        (a, g)
                    })
                    .collect();
                let mut sum = (vec![0.0; n * n], vec![0.0; n]);
                for (b, h) in partial {
                    sum.0.iter_mut().zip(&b).for_each(|(u, v)| *u += v);
                    sum.1.iter_mut().zip(&h).for_each(|(u, v)| *u += v);
                }
                sum
            };
        let (ra, rg) = accumulate(
            &self.s.refl,
            false,
            &r.as_slice()[..3 * nr],
            m.kd.0,
            &m.reflection,
        );
        let (ta, tg) = accumulate(
            &self.s.trans,
            true,
            &r.as_slice()[3 * nr..],
            [0.0; 3],
            &m.transmission,
        );
        let mut a = DMatrix::zeros(n, n);
        for i in 0..n {
            for k in 0..=i {
                let v = ra[i * n + k] + ta[i * n + k];
                a[(i, k)] = v;
                a[(k, i)] = v;
            }
        }
        let g = DVector::from_fn(n, |i, _| rg[i] + tg[i]);
        (a.iter().chain(g.iter()).all(|v| v.is_finite())).then_some((a, g))
    }
}

/// Pairs per partial sum of [`Problem::normal_equations`].
const PAIR_CHUNK: usize = 512;

/// How [`marquardt`] ended.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stop {
    /// Relative reduction of ‖r‖², actual and predicted, below [`TOL`].
    Ftol,
    /// Scaled step below [`TOL`] times the scaled parameters.
    Xtol,
    /// Both of the above on the same step.
    Both,
    /// Zero projected gradient (every component zero or pointing out of its range at a bound).
    Gtol,
    /// No step lowers the error even with the largest damping (a minimum at machine precision).
    Precision,
    /// The iteration limit was reached; `fall`: the relative decrease of ‖r‖² over the last
    /// [`LIMIT_WINDOW`] iterations (how far from converged it stopped).
    Limit { iterations: usize, fall: f64 },
    /// The residuals or the Jacobian at the start are not finite.
    NonFinite,
}

/// Relative tolerances of [`marquardt`] (those of MINPACK's and the `levenberg-marquardt`
/// crate's defaults: √ε).
const TOL: f64 = 1.490_116_119_384_765_6e-8;

/// Iterations over which a polish stopped at its limit reports the error's decrease.
const LIMIT_WINDOW: usize = 10;

/// Levenberg-Marquardt with Marquardt's diagonal scaling, solved by the normal equations
/// (JᵀJ + λ·diag JᵀJ) δ = −Jᵀr with a Cholesky factorization, steps projected onto the
/// parameter ranges. JᵀJ and Jᵀr come from the analytic Jacobian, accumulated pair by pair
/// ([`Problem::normal_equations`]): one pass over the pairs per iteration, where a
/// forward-difference Jacobian took n + 1 and the pivoted QR of the 3N × n Jacobian (crate
/// `levenberg-marquardt`) took about 40 % of a 3-lobe fit. At most `max_iters` iterations (one
/// Jacobian each; an iteration tries damped steps until one lowers the error).
fn marquardt(p: &Problem, x0: DVector<f64>, max_iters: usize) -> (DVector<f64>, Stop) {
    let mut x = x0;
    p.project(&mut x);
    let Some(mut r) = p.residuals_at(&x) else {
        return (x, Stop::NonFinite);
    };
    let mut cost = r.norm_squared();
    let n = x.len();
    let (mut lambda, mut nu) = (1e-3, 2.0);
    // ‖r‖² at the start of every iteration.
    let mut history = Vec::with_capacity(max_iters);
    for _ in 0..max_iters {
        history.push(cost);
        let Some((mut a, mut g)) = p.normal_equations(&x, &r) else {
            return (x, Stop::NonFinite);
        };
        // Active set: a parameter on a bound whose descent direction −g leaves the range is held
        // there for this iteration (its row and column of JᵀJ cleared, its gradient zeroed), so
        // that the step of the others is the reduced Gauss-Newton step rather than a step
        // computed for a move the projection then cancels (which stalled 2- and 3-lobe polishes
        // with a lobe's α or r0 at 1 at the iteration limit).
        for (i, s) in p.slots.iter().enumerate() {
            if (x[i] <= s.lo && g[i] > 0.0) || (x[i] >= s.hi && g[i] < 0.0) {
                g[i] = 0.0;
                for k in 0..n {
                    if k != i {
                        a[(i, k)] = 0.0;
                        a[(k, i)] = 0.0;
                    }
                }
            }
        }
        if g.iter().all(|v| *v == 0.0) {
            return (x, Stop::Gtol);
        }
        let dmax = (0..n).map(|i| a[(i, i)]).fold(0.0, f64::max);
        let d: Vec<f64> = (0..n)
            .map(|i| a[(i, i)].max(1e-12 * dmax).max(f64::MIN_POSITIVE))
            .collect();
        let xnorm = (0..n).map(|i| d[i] * x[i] * x[i]).sum::<f64>().sqrt();
        loop {
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
    let before = history
        .len()
        .checked_sub(LIMIT_WINDOW)
        .and_then(|k| history.get(k))
        .or(history.first())
        .copied()
        .unwrap_or(cost);
    let fall = if before > 0.0 {
        (before - cost) / before
    } else {
        0.0
    };
    (
        x,
        Stop::Limit {
            iterations: max_iters,
            fall,
        },
    )
}

/// The polish's outcome.
pub(crate) struct Polished {
    /// The polished model (parameters clamped to their ranges).
    pub model: Kurt,
    /// Whether LM met one of its convergence criteria (or met them at machine precision).
    pub converged: bool,
    /// Passes over all pairs (residuals or Jacobian; a thinned pass counts its share).
    pub evaluations: usize,
    /// How LM ended, in words (its termination reason).
    pub reason: String,
}

/// How the polish ended, in words.
fn reason_words(t: Stop, n: usize, per_param: usize) -> String {
    match t {
        Stop::Ftol => "converged (relative reduction of the error below tolerance)".into(),
        Stop::Xtol => "converged (relative step below tolerance)".into(),
        Stop::Both => {
            "converged (relative reduction of the error and of the step below tolerance)".into()
        }
        Stop::Gtol => "converged (zero projected gradient)".into(),
        Stop::Precision => {
            "converged at machine precision (no step lowers the error at any damping)".into()
        }
        Stop::Limit { iterations, fall } => format!(
            "not converged: LM stopped at its iteration limit ({iterations} = {per_param}·(n+1), \
             n = {n}) while its squared error still fell by {fall:.2e} (relative) over the last \
             {LIMIT_WINDOW} iterations (tolerance per iteration {TOL:.1e})"
        ),
        Stop::NonFinite => "not converged: the residuals are not finite at the start".into(),
    }
}

/// Iteration limit of each polish stage per free parameter (plus one). The limit counts
/// iterations (Jacobians), as the `levenberg-marquardt` crate's patience of 15 counted its trial
/// points. Counting residual evaluations with the Jacobian's n each (50·(n+1) of them, ≈ 50
/// iterations) stopped 64 of 105 one-lobe polishes at the limit.
const MAX_ITERS_PER_PARAM: usize = 15;

/// Thinning of the first polish stage (every `POLISH_THIN`-th pair, see [`polish`]).
const POLISH_THIN: usize = 4;

/// Runs LM from `model` over the free parameters of `space`, in two stages: first on every
/// [`POLISH_THIN`]-th pair (weights scaled up, [`PairSet::every`]), where each residual and
/// Jacobian costs a quarter, then on the whole set from that result (the thinned optimum alone
/// was up to 12 % worse on the whole set: pink-felt, one lobe). The second stage's outcome is
/// the polish's. Each stage may use up to [`MAX_ITERS_PER_PARAM`]·(n + 1) iterations.
pub(crate) fn polish(s: &Samples, space: &Space, model: &Kurt) -> Polished {
    polish_limited(s, space, model, MAX_ITERS_PER_PARAM)
}

/// [`polish`] with `per_param`·(n + 1) iterations per stage.
fn polish_limited(s: &Samples, space: &Space, model: &Kurt, per_param: usize) -> Polished {
    let thin = s.every(POLISH_THIN);
    let first = polish_on(&thin, space, model, per_param);
    let mut out = polish_on(s, space, &first.model, per_param);
    // Passes over the whole set: the thinned ones count a quarter.
    out.evaluations += first.evaluations.div_ceil(POLISH_THIN);
    out
}

/// The least-squares problem of the free parameters of `space` from `model` on the pairs of
/// `s`, with its start vector; `None` when every parameter is fixed.
fn problem<'a>(
    s: &'a Samples,
    space: &Space,
    model: &Kurt,
    squares: bool,
) -> Option<(Problem<'a>, Vec<f64>)> {
    let (slots, x) = free_slots(space, model);
    if slots.is_empty() {
        return None;
    }
    let (mut num, mut den) = (0.0, 0.0);
    for set in [&s.refl, &s.trans] {
        for t in 0..set.len() {
            num += set.weight[t] * (set.data[0][t] + set.data[1][t] + set.data[2][t]) / 3.0;
            den += set.weight[t];
        }
    }
    let loss = if squares {
        Loss::Squares
    } else {
        Loss::PseudoHuber((0.01 * num / den.max(f64::MIN_POSITIVE)).max(1e-12))
    };
    let ties = [(false, &space.refl), (true, &space.trans)]
        .into_iter()
        .flat_map(|(t, v)| {
            v.iter()
                .enumerate()
                .filter(|(_, l)| l.tie_my)
                .map(move |(i, _)| (t, i))
        })
        .collect();
    let problem = Problem {
        s,
        base: model.clone(),
        slots,
        ties,
        loss,
        evaluations: Cell::new(0),
    };
    Some((problem, x))
}

/// One LM run from `model` over the free parameters of `space` on the pairs of `s`.
fn polish_on(s: &Samples, space: &Space, model: &Kurt, per_param: usize) -> Polished {
    polish_loss(s, space, model, per_param, false)
}

/// LM from `model` over the free parameters of `space` minimizing Σ a·(data − p)² on the pairs
/// of `s` (one stage; for Ngan's L2 on [`super::samples::ngan_set`]), at most
/// [`MAX_ITERS_PER_PARAM`]·(n + 1) iterations.
pub(crate) fn polish_squares(s: &Samples, space: &Space, model: &Kurt) -> Polished {
    polish_loss(s, space, model, MAX_ITERS_PER_PARAM, true)
}

/// One LM run with the pseudo-Huber loss or (`squares`) the squared error.
fn polish_loss(
    s: &Samples,
    space: &Space,
    model: &Kurt,
    per_param: usize,
    squares: bool,
) -> Polished {
    let Some((problem, x)) = problem(s, space, model, squares) else {
        return Polished {
            model: model.clone(),
            converged: true,
            evaluations: 0,
            reason: "nothing to polish (every parameter is fixed)".into(),
        };
    };
    let n = x.len();
    let (x, stop) = marquardt(&problem, DVector::from_vec(x), per_param * (n + 1));
    Polished {
        model: problem.model(&x),
        converged: !matches!(stop, Stop::Limit { .. } | Stop::NonFinite),
        evaluations: problem.evaluations.get(),
        reason: reason_words(stop, n, per_param),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kurt::{params, samples, KurtOptions};
    use lustre_brdf::Rgb;

    fn lobe(ks: [f64; 3], mx: f64, my: f64, r0: f64, alpha: f64) -> KurtLobe {
        KurtLobe::new(Rgb(ks), mx, my, r0, alpha).expect("lobe")
    }

    /// Data: one anisotropic reflection lobe and one transmission lobe; start: another model.
    fn case() -> (Samples, Kurt) {
        let data = Kurt::new(
            Rgb::new(0.2, 0.3, 0.4),
            vec![lobe([0.5, 0.4, 0.3], 0.08, 0.15, 0.3, 0.2)],
            vec![lobe([0.2, 0.25, 0.3], 0.2, 0.3, 0.5, 0.1)],
        )
        .expect("data");
        let start = Kurt::new(
            Rgb::new(0.25, 0.25, 0.3),
            vec![lobe([0.3, 0.5, 0.2], 0.1, 0.12, 0.5, 0.4)],
            vec![lobe([0.1, 0.3, 0.2], 0.15, 0.25, 0.3, 0.3)],
        )
        .expect("start");
        (samples::sample(&data, true).expect("samples"), start)
    }

    fn space(isotropic: bool) -> Space {
        let opts = KurtOptions {
            transmission_lobes: 1,
            ..KurtOptions::default()
        };
        params::build_space(&opts, true, isotropic).expect("space")
    }

    /// JᵀJ and Jᵀr of the analytic Jacobian equal those of central differences of the
    /// residuals, with my free and with my tied to mx, for the pseudo-Huber and the squared loss.
    #[test]
    fn normal_equations_match_finite_differences() {
        let (s, start) = case();
        for (isotropic, squares) in [(false, false), (true, false), (false, true), (true, true)] {
            let sp = space(isotropic);
            let (p, x) = problem(&s, &sp, &start, squares).expect("free parameters");
            let n = x.len();
            assert_eq!(n, if isotropic { 3 + 2 * 6 } else { 3 + 2 * 7 });
            let x = DVector::from_vec(x);
            let r = p.residuals_at(&x).expect("finite residuals");
            let (a, g) = p.normal_equations(&x, &r).expect("finite");
            let cols: Vec<DVector<f64>> = (0..n)
                .map(|k| {
                    let h = 1e-6 * x[k].abs().max(1e-2);
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[k] += h;
                    xm[k] -= h;
                    let rp = p.residuals_at(&xp).expect("finite");
                    let rm = p.residuals_at(&xm).expect("finite");
                    (rp - rm) / (2.0 * h)
                })
                .collect();
            let amax = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..n {
                let gi = cols[i].dot(&r);
                assert!(
                    (gi - g[i]).abs() <= 1e-5 * gmax,
                    "isotropic {isotropic}, squares {squares}, Jᵀr[{i}]: {} vs {gi}",
                    g[i]
                );
                for k in 0..n {
                    let aik = cols[i].dot(&cols[k]);
                    assert!(
                        (aik - a[(i, k)]).abs() <= 1e-5 * amax,
                        "isotropic {isotropic}, squares {squares}, JᵀJ[{i},{k}]: {} vs {aik}",
                        a[(i, k)]
                    );
                }
            }
        }
    }

    /// From a distant start the polish converges (a convergence criterion, not the limit)
    /// and recovers the data's model; with one iteration per parameter it stops at the limit
    /// and says how far the error still fell.
    #[test]
    fn polish_converges_or_says_why_not() {
        let (s, start) = case();
        let sp = space(false);
        let done = polish(&s, &sp, &start);
        assert!(done.converged, "{}", done.reason);
        assert!(done.reason.starts_with("converged"), "{}", done.reason);
        let l = &done.model.reflection[0];
        assert!(
            (l.mx - 0.08).abs() < 1e-3 && (l.my - 0.15).abs() < 1e-3,
            "{l:?}"
        );
        let far = Kurt::new(
            Rgb::new(0.05, 0.05, 0.05),
            vec![lobe([0.05, 0.05, 0.05], 0.6, 0.6, 0.9, 0.9)],
            vec![lobe([0.05, 0.05, 0.05], 0.6, 0.6, 0.9, 0.9)],
        )
        .expect("far start");
        let cut = polish_on(&s, &sp, &far, 1);
        assert!(!cut.converged);
        assert!(
            cut.reason
                .contains("iteration limit (18 = 1·(n+1), n = 17)"),
            "{}",
            cut.reason
        );
        assert!(cut.reason.contains("still fell by"), "{}", cut.reason);
    }
}
