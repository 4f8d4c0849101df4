//! Levenberg-Marquardt polish of the brute-force result (crate `levenberg-marquardt`).
//!
//! LM minimizes a sum of squares; the L1 metric of Eq. 3.7 is approximated by the
//! pseudo-Huber loss ρ(e) = √(e² + δ²) − δ (≈ |e| for |e| ≫ δ, smooth at 0) with
//! residuals r = sign(e)·√(a·ρ(e)), so that Σ r² = Σ a·ρ(e). δ is 1 % of the weighted mean
//! |data|. All free parameters are polished jointly (kd, every ks/kt channel, mx, my, r0, α of
//! every lobe; mx, my in ln; a tied my follows mx), each clamped to its range. The Jacobian is taken by forward
//! differences. The polished model is kept only when it lowers the true Eq. 3.7 error.

use super::params::{Param, Space};
use super::samples::{LobeConst, PairSet, Samples};
use lustre_brdf::models::kurt::{Kurt, LobeKind};
use nalgebra::{storage::Owned, DMatrix, DVector, Dyn};
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
    x: DVector<f64>,
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

impl levenberg_marquardt::LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
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
        let r = self.residuals_of(&self.model(&self.x));
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let r0 = self.residuals_of(&self.model(&self.x));
        let mut j = DMatrix::zeros(r0.len(), self.x.len());
        for (k, s) in self.slots.iter().enumerate() {
            let xk = self.x[k].clamp(s.lo, s.hi);
            let h = 1e-6 * xk.abs().max(1e-3);
            // Forward difference, backward at the upper end of the range.
            let step = if xk + h <= s.hi { h } else { -h };
            let mut x = self.x.clone();
            x[k] = xk + step;
            let r = self.residuals_of(&self.model(&x));
            j.set_column(k, &((r - &r0) / step));
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
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

/// LM's termination reason in words.
fn reason_words(t: &levenberg_marquardt::TerminationReason) -> String {
    use levenberg_marquardt::TerminationReason as T;
    match t {
        T::Converged { ftol, xtol } => format!(
            "converged ({})",
            match (ftol, xtol) {
                (true, true) => "relative reduction of the error and of the step below tolerance",
                (true, false) => "relative reduction of the error below tolerance",
                _ => "relative step below tolerance",
            }
        ),
        T::ResidualsZero => "converged (zero residuals)".into(),
        T::Orthogonal => "converged (gradient orthogonal to the residuals, gtol)".into(),
        T::NoImprovementPossible(what) => {
            format!("converged at machine precision ({what} tolerance cannot be met)")
        }
        T::LostPatience => "not converged: LM stopped at its evaluation limit (15·(n+1))".into(),
        T::NoParameters => "nothing to polish (no free parameter)".into(),
        T::NoResiduals => "nothing to polish (no sample)".into(),
        T::WrongDimensions(w) => format!("not run: wrong dimensions ({w})"),
        T::Numerical(w) => format!("not converged: numerical failure in LM ({w})"),
        T::User(w) => format!("not converged: {w}"),
    }
}

/// Runs LM from `model` over the free parameters of `space`.
pub(crate) fn polish(s: &Samples, space: &Space, model: &Kurt) -> Polished {
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
    let problem = Problem {
        s,
        base: model.clone(),
        slots,
        ties,
        x: DVector::from_vec(x),
        delta,
        evaluations: Cell::new(0),
    };
    let (problem, report) = levenberg_marquardt::LevenbergMarquardt::new()
        .with_patience(15)
        .minimize(problem);
    Polished {
        model: problem.model(&problem.x),
        // NoImprovementPossible: the tolerances were met at machine precision, not above it.
        converged: report.termination.was_successful()
            || matches!(
                report.termination,
                levenberg_marquardt::TerminationReason::NoImprovementPossible(_)
            ),
        evaluations: problem.evaluations.get(),
        reason: reason_words(&report.termination),
    }
}
