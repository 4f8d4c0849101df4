//! The hierarchical brute-force search of one lobe (000 §3.4.1, Fig. 3.8) and the alternating
//! multi-lobe scheme with clamped residuals.

use super::params::{LobeSpace, Param};
use super::samples::{LobeConst, PairSet};
use lustre_brdf::models::kurt::{KurtLobe, LobeKind};
use lustre_brdf::Rgb;
use rayon::prelude::*;

/// Improvement, relative to the error without the lobe(s), below which a level (or an
/// alternation round) counts as settled.
const SETTLE_TOL: f64 = 1e-3;
/// Alternation rounds for more than one lobe (each round refits every lobe once).
pub(crate) const MAX_ROUNDS: usize = 3;

/// The outcome of a search.
#[derive(Clone, Debug)]
pub(crate) struct Found {
    /// The lobes found.
    pub lobes: Vec<KurtLobe>,
    /// Whether the last level of every final search and the alternation settled.
    pub settled: bool,
    /// Whether the alternation of several lobes settled (true for one lobe).
    pub alternation_settled: bool,
    /// The lobes of a one-lobe fit: the first search of the first round with the other lobes'
    /// ks set to zero (a second start for the polish, see `fit`).
    pub single: Vec<KurtLobe>,
    /// Lobe-shape evaluations over the pair set.
    pub evaluations: usize,
}

/// One dimension of the search: 0..4 the shape (mx, my, r0, α), 4..7 ks per channel.
/// A tied my is a placeholder (one value) and follows mx in [`lobe_at`].
fn dims(space: &LobeSpace) -> [Param; 7] {
    let s = space.shape;
    let k = space.ks;
    let my = if space.tie_my {
        Param::Fixed(0.0)
    } else {
        s[1]
    };
    [s[0], my, s[2], s[3], k[0], k[1], k[2]]
}

/// Values tried in one dimension: `grid` equidistant coordinates in the box, or the fixed value.
fn values(p: Param, bx: Option<(f64, f64)>, grid: usize, out: &mut Vec<f64>) {
    out.clear();
    match (p, bx) {
        (Param::Free { .. }, Some((lo, hi))) => {
            for k in 0..grid {
                out.push(lo + (hi - lo) * k as f64 / (grid - 1) as f64);
            }
        }
        (Param::Fixed(v), _) => out.push(v),
        (Param::Free { lo, .. }, None) => out.push(p.to_coord(lo)),
    }
}

/// A lobe from search coordinates (my = mx when tied).
fn lobe_at(p: &[Param; 7], x: &[f64; 7], tie_my: bool) -> KurtLobe {
    let v = |d: usize| p[d].value_at(x[d]);
    KurtLobe {
        ks: Rgb::new(v(4), v(5), v(6)),
        mx: v(0),
        my: if tie_my { v(0) } else { v(1) },
        r0: v(2),
        alpha: v(3),
    }
}

/// Hierarchical brute-force search of one lobe against `target` (per channel, ≥ 0) on `set`.
/// The shape (mx, my, r0, α) is searched on the product grid; for each shape every channel
/// picks its best ks on its own grid (the channels are independent given the shape, so the
/// cost is that of a 4-parameter search). Returns the lobe, whether the last level improved the
/// error by less than [`SETTLE_TOL`] times the error without the lobe, and the number of shape
/// evaluations.
///
/// With `start` (a refit in a later alternation round) the search begins where two levels of a
/// full search would: a box of half the full width centred on `start`, for `levels − 2` levels.
pub(crate) fn search_lobe(
    set: &PairSet,
    target: &[Vec<f64>; 3],
    kind: LobeKind,
    space: &LobeSpace,
    grid: usize,
    levels: usize,
    start: Option<&KurtLobe>,
) -> (KurtLobe, bool, usize) {
    let p = dims(space);
    let full: [Option<(f64, f64)>; 7] = std::array::from_fn(|d| p[d].coord_range());
    let mut boxes = full;
    let mut levels = levels;
    if let Some(l) = start {
        let v = [l.mx, l.my, l.r0, l.alpha, l.ks[0], l.ks[1], l.ks[2]];
        for d in 0..7 {
            if let Some((lo0, hi0)) = full[d] {
                let c = p[d].to_coord(v[d]).clamp(lo0, hi0);
                let hw = (hi0 - lo0) / 4.0;
                boxes[d] = Some(((c - hw).max(lo0), (c + hw).min(hi0)));
            }
        }
        levels = levels.saturating_sub(2).max(1);
    }
    let mut vals: [Vec<f64>; 7] = Default::default();
    let mut best: Option<(f64, [f64; 7])> = None;
    let mut prev_level_err = f64::INFINITY;
    let mut settled = false;
    let mut evaluations = 0usize;
    let n = set.len();
    // Σ a|target| per channel: the error without the lobe, also the scale of "settled".
    let abs_sum: [f64; 3] = std::array::from_fn(|c| {
        set.weight
            .iter()
            .zip(&target[c])
            .map(|(a, t)| a * t.abs())
            .sum()
    });
    let scale: f64 = abs_sum.iter().sum();
    for _level in 0..levels {
        for d in 0..7 {
            values(p[d], boxes[d], grid, &mut vals[d]);
        }
        let counts: [usize; 4] = std::array::from_fn(|d| vals[d].len());
        let total: usize = counts.iter().product();
        evaluations += total;
        let vals_ref = &vals;
        let level_best = (0..total)
            .into_par_iter()
            .map_init(
                || (vec![0.0; n], Vec::<usize>::with_capacity(n)),
                |(g, active), idx| {
                    let mut x = [0.0; 7];
                    let mut rest = idx;
                    for d in 0..4 {
                        x[d] = vals_ref[d][rest % counts[d]];
                        rest /= counts[d];
                    }
                    let lobe = lobe_at(&p, &x, space.tie_my);
                    let c = LobeConst::new(&lobe, kind);
                    let mut gmax = 0.0f64;
                    for (t, o) in g.iter_mut().enumerate() {
                        *o = c.eval(set, t);
                        gmax = gmax.max(*o);
                    }
                    // Pairs where the lobe is below 1e-12 of its peak add ks·g ≤ 1e-12·gmax to
                    // |t − ks·g|: they count as |t| (in `abs_sum`) and leave the ks loop.
                    let thr = gmax * 1e-12;
                    active.clear();
                    active.extend((0..n).filter(|&t| g[t] > thr));
                    let mut err = 0.0;
                    for ch in 0..3 {
                        let tc = &target[ch];
                        let inactive = abs_sum[ch]
                            - active
                                .iter()
                                .map(|&t| set.weight[t] * tc[t].abs())
                                .sum::<f64>();
                        let mut be = f64::INFINITY;
                        for &kc in &vals_ref[4 + ch] {
                            let ks = p[4 + ch].value_at(kc);
                            let e = inactive
                                + active
                                    .iter()
                                    .map(|&t| set.weight[t] * (tc[t] - ks * g[t]).abs())
                                    .sum::<f64>();
                            if e < be {
                                be = e;
                                x[4 + ch] = kc;
                            }
                        }
                        err += be;
                    }
                    (err, idx, x)
                },
            )
            .reduce(
                || (f64::INFINITY, usize::MAX, [0.0; 7]),
                |a, b| {
                    if b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)).is_lt() {
                        b
                    } else {
                        a
                    }
                },
            );
        let (err, _, x) = level_best;
        if best.is_none_or(|(e, _)| err < e) {
            best = Some((err, x));
        }
        let Some((best_err, bx)) = best else {
            break;
        };
        settled = prev_level_err.is_finite() && prev_level_err - best_err <= SETTLE_TOL * scale;
        prev_level_err = best_err;
        // Shrink every free box to ± one grid step around the best (Fig. 3.8).
        for d in 0..7 {
            if let (Some((lo, hi)), Some((lo0, hi0))) = (boxes[d], full[d]) {
                let step = (hi - lo) / (grid - 1) as f64;
                let (a, b) = ((bx[d] - step).max(lo0), (bx[d] + step).min(hi0));
                if a < b {
                    boxes[d] = Some((a, b));
                }
            }
        }
    }
    let x = best.map_or([0.0; 7], |b| b.1);
    (lobe_at(&p, &x, space.tie_my), settled, evaluations)
}

/// `ks·g` of a lobe at every pair, per channel.
fn contribution(set: &PairSet, lobe: &KurtLobe, kind: LobeKind) -> [Vec<f64>; 3] {
    let mut g = vec![0.0; set.len()];
    set.fill_lobe(lobe, kind, &mut g);
    std::array::from_fn(|c| g.iter().map(|v| v * lobe.ks[c]).collect())
}

/// Σ_c Σ_t a_t |base − Σ lobes|: the group's share of the Eq. 3.7 error (times 3).
fn group_error(set: &PairSet, base: &[Vec<f64>; 3], contrib: &[[Vec<f64>; 3]]) -> f64 {
    (0..3)
        .map(|c| {
            (0..set.len())
                .map(|t| {
                    let m: f64 = contrib.iter().map(|k| k[c][t]).sum();
                    set.weight[t] * (base[c][t] - m).abs()
                })
                .sum::<f64>()
        })
        .sum()
}

/// Fits `spaces.len()` lobes of one kind to `base` (the data minus the diffuse term) on `set`:
/// one lobe at a time against the residual of the others with negative values clamped to zero
/// (000 §3.4.1, multiple lobes), alternating rounds until the group error stops improving by
/// [`SETTLE_TOL`] or [`MAX_ROUNDS`] rounds (later rounds start each lobe's search around its
/// previous value, see [`search_lobe`]). The best round is kept.
pub(crate) fn fit_group(
    set: &PairSet,
    base: &[Vec<f64>; 3],
    kind: LobeKind,
    spaces: &[LobeSpace],
    grid: usize,
    levels: usize,
) -> Found {
    let l = spaces.len();
    if l == 0 || set.len() == 0 {
        return Found {
            lobes: spaces.iter().map(zero_lobe).collect(),
            settled: true,
            alternation_settled: true,
            single: spaces.iter().map(zero_lobe).collect(),
            evaluations: 0,
        };
    }
    let n = set.len();
    let mut lobes: Vec<KurtLobe> = Vec::with_capacity(l);
    let mut contrib: Vec<[Vec<f64>; 3]> = Vec::with_capacity(l);
    let mut evaluations = 0;
    let mut best: Option<(f64, Vec<KurtLobe>, bool)> = None;
    let mut alternation_settled = l == 1;
    let rounds = if l == 1 { 1 } else { MAX_ROUNDS };
    let mut single: Vec<KurtLobe> = spaces.iter().map(zero_lobe).collect();
    let scale = group_error(set, base, &[]);
    for round in 0..rounds {
        let mut searches_settled = true;
        for k in 0..l {
            let target: [Vec<f64>; 3] = std::array::from_fn(|c| {
                (0..n)
                    .map(|t| {
                        let others: f64 = contrib
                            .iter()
                            .enumerate()
                            .filter(|&(j, _)| j != k)
                            .map(|(_, v)| v[c][t])
                            .sum();
                        (base[c][t] - others).max(0.0)
                    })
                    .collect()
            });
            let start = (round > 0).then(|| lobes[k]);
            let (lobe, settled, ev) =
                search_lobe(set, &target, kind, &spaces[k], grid, levels, start.as_ref());
            evaluations += ev;
            searches_settled &= settled;
            if round == 0 && k == 0 {
                single[0] = lobe;
            }
            let ck = contribution(set, &lobe, kind);
            if k < lobes.len() {
                lobes[k] = lobe;
                contrib[k] = ck;
            } else {
                lobes.push(lobe);
                contrib.push(ck);
            }
        }
        let err = group_error(set, base, &contrib);
        match &best {
            Some((e, _, _)) if round > 0 => {
                let improved = *e - err;
                if err < *e {
                    best = Some((err, lobes.clone(), searches_settled));
                }
                if improved <= SETTLE_TOL * scale {
                    alternation_settled = true;
                    break;
                }
            }
            _ => best = Some((err, lobes.clone(), searches_settled)),
        }
    }
    let (_, lobes, searches_settled) = best.unwrap_or((0.0, lobes, false));
    Found {
        lobes,
        settled: searches_settled && alternation_settled,
        alternation_settled,
        single,
        evaluations,
    }
}

/// A lobe with zero weight (for a group without pairs, or a placeholder beside a one-lobe fit):
/// fixed values where given (a fixed ks included), otherwise ks = 0 and the lower end of each
/// shape range.
fn zero_lobe(s: &LobeSpace) -> KurtLobe {
    let v = |p: Param| match p {
        Param::Fixed(v) => v,
        Param::Free { lo, .. } => lo,
    };
    let ks = |p: Param| match p {
        Param::Fixed(v) => v,
        Param::Free { .. } => 0.0,
    };
    KurtLobe {
        ks: Rgb::new(ks(s.ks[0]), ks(s.ks[1]), ks(s.ks[2])),
        mx: v(s.shape[0]),
        my: v(s.shape[1]),
        r0: v(s.shape[2]),
        alpha: v(s.shape[3]),
    }
}
