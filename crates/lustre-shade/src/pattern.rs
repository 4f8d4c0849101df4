//! Regular sample patterns of half vectors for one Kurt (anisotropic Beckmann) lobe.
//!
//! - [`concentric`], [`concentric_for_budget`]: 002 §5 (Eq. 11–13): equally spaced concentric
//!   circles around the lobe centre out to θmax, anisotropic rejection of samples with q < ξ0 and
//!   the half-offset alternative per circle; the pattern closest to a sample budget.
//! - [`thesis`]: 000 §4.4.3 (Eq. 4.10–4.13): one centre sample plus a ring at ξ1 = 0.6 for
//!   isotropic-ish lobes, samples equally spaced along the major axis for strongly anisotropic
//!   lobes (the switch at [`THESIS_SWITCH_RATIO`]).
//! - [`multi_ring`]: 000 §4.5.3: centre plus several rings of a few samples each.
//!
//! Half vectors are unit vectors in the lobe's local frame (x = tangent, z = normal), z > 0.
//! Every pattern stores its PDF constant, 002 Eq. 18: the mean of the Beckmann D (002 Eq. 4)
//! over its half vectors.

use std::f64::consts::PI;

use glam::DVec3;
use lustre_brdf::models::kurt::beckmann_d;

use crate::error::{Result, ShadeError};

/// The two circle spacings of 002 Eq. 12.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spacing {
    /// s1 = θmax / (nc + 1): a sample at the pole, then circles at s1, 2 s1, …; 6 samples on
    /// the first circle.
    S1,
    /// s2 = θmax / (nc + 2): the first circle (4 samples) at half a spacing around the pole,
    /// then circles one spacing apart.
    S2,
}

/// Which generator produced a [`Pattern`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PatternKind {
    /// 002 §5 concentric circles.
    Concentric {
        /// The circle spacing (002 Eq. 12).
        spacing: Spacing,
        /// nc, the number of circles (for [`Spacing::S1`] the pole sample counts as the first).
        circles: usize,
    },
    /// 000 §4.4.3: centre sample plus one ring at ξ1 = 0.6.
    ThesisRing,
    /// 000 §4.4.3: samples equally spaced along the major axis (strong anisotropy).
    ThesisLinear,
    /// 000 §4.5.3: centre sample plus several rings.
    MultiRing {
        /// Number of rings around the centre sample.
        rings: usize,
    },
    /// Ours ([`row_lattice`]): `budget` equal-mass cells of the slope-space Gaussian laid out
    /// per pixel in rows across the lobe's image in ωi, so that every cell is about round there.
    RowLattice {
        /// Samples (= filtered lookups) per lobe.
        budget: usize,
    },
    /// Ours with anisotropic footprints ([`tap_lattice`]): the row lattice whose cells that are
    /// long in ωi are read by up to [`LATTICE_MAX_TAPS`] taps along their long axis, with fewer
    /// cells so that the taps fit the budget.
    TapLattice {
        /// Filtered lookups (taps) per lobe.
        budget: usize,
    },
}

/// A regular pattern of half vectors for one lobe.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    /// The generator and its parameters.
    pub kind: PatternKind,
    /// Unit half vectors in the lobe's local frame (x = tangent), z > 0.
    pub h: Vec<DVec3>,
    /// 002 Eq. 18: mean of `beckmann_d(mx, my, h_i)` over the pattern.
    pub pdf_constant: f64,
    /// Lobe roughness along the tangent.
    pub mx: f64,
    /// Lobe roughness along the bitangent.
    pub my: f64,
    /// The density threshold: ξ0 of 002 §5 for concentric patterns, ξ1border
    /// ([`THESIS_XI_BORDER`]) for the thesis patterns.
    pub xi0: f64,
}

/// ξ1border of 000 Eq. 4.10: the lobe border of the thesis patterns (empirically 0.01).
pub const THESIS_XI_BORDER: f64 = 0.01;

/// ξ1 of the ring of the thesis pattern (000 §4.4.3: "radius = 0.6", i.e. 40 % off-centre).
pub const THESIS_RING_XI1: f64 = 0.6;

/// The switch of 000 §4.4.3: the linear pattern along the major axis is used when
/// max(mx, my) / min(mx, my) is at least this ratio. The thesis leaves the threshold open
/// (its example of the linear pattern has mx = 0.01, my = 0.14); 4 is our choice.
pub const THESIS_SWITCH_RATIO: f64 = 4.0;

/// Largest number of circles [`concentric_for_budget`] tries.
pub const MAX_CIRCLES: usize = 64;

/// The smallest lobe roughness a pattern takes (as a GGX material's α).
pub const MIN_ROUGHNESS: f64 = 1e-6;
/// The largest lobe roughness a pattern takes (as a GGX material's α).
pub const MAX_ROUGHNESS: f64 = 10.0;

fn check_roughness(mx: f64, my: f64) -> Result<()> {
    for (name, m) in [("mx", mx), ("my", my)] {
        if !(m.is_finite() && (MIN_ROUGHNESS..=MAX_ROUGHNESS).contains(&m)) {
            return Err(ShadeError::Parameter(format!(
                "pattern roughness {name} = {} must lie in [{MIN_ROUGHNESS:e}, {MAX_ROUGHNESS}]",
                lustre_brdf::error::plain_number(m)
            )));
        }
    }
    Ok(())
}

fn check_xi0(xi0: f64) -> Result<()> {
    if !(xi0 > 0.0 && xi0 < 1.0) {
        return Err(ShadeError::Parameter(format!(
            "pattern threshold xi0 = {} must lie in (0, 1)",
            lustre_brdf::error::plain_number(xi0)
        )));
    }
    Ok(())
}

/// The unit vector with polar angle `theta` from +z and azimuth `phi` from +x.
fn spherical(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// q(h) of 002 Eq. 5: exp(−tan²θh (cos²φh / mx² + sin²φh / my²)), 1 at the pole.
pub fn q(mx: f64, my: f64, h: DVec3) -> f64 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let (ax, ay) = (h.x / (mx * h.z), h.y / (my * h.z));
    (-(ax * ax + ay * ay)).exp()
}

/// θmax of 002 Eq. 11: arctan(√(−ln ξ0) · max(mx, my)), where the isotropic Beckmann density
/// with the larger roughness has fallen to ξ0 (q(θmax) = ξ0).
pub fn theta_max(mx: f64, my: f64, xi0: f64) -> f64 {
    ((-xi0.ln()).sqrt() * mx.max(my)).atan()
}

/// The circle spacing of 002 Eq. 12 for `circles` circles.
pub fn spacing_angle(theta_max: f64, circles: usize, spacing: Spacing) -> f64 {
    match spacing {
        Spacing::S1 => theta_max / (circles as f64 + 1.0),
        Spacing::S2 => theta_max / (circles as f64 + 2.0),
    }
}

/// Number of samples on a circle at polar angle `theta` for circle spacing `s` (002 Eq. 13):
/// the circumference 2π sin θ divided by the spacing, rounded to the nearest even number,
/// n = 2⌊π sin θ / s + ½⌋ (at least 2).
///
/// This is Eq. 13, n_i = 2⌊n0 sin θi / (2 sin θ0) + ½⌋, with the unrounded first-circle count
/// n0 = 2π sin θ0 / s (≈ 6 at θ0 = s for s1, ≈ π → 4 at θ0 = s/2 for s2). Using the rounded
/// n0 = 4 for s2 would give 4 + 12 + 20 = 36 samples for nc = 3, while 002 Fig. 4 states 30
/// (= 4 + 10 + 16), which this form reproduces (and 19 = 1 + 6 + 12 for s1).
pub fn ring_count(theta: f64, s: f64) -> usize {
    let n = (PI * theta.sin() / s + 0.5).floor();
    if n.is_finite() && n >= 1.0 {
        2 * n as usize
    } else {
        2
    }
}

/// Mean of the Beckmann D over the half vectors (002 Eq. 18).
fn pdf_constant(mx: f64, my: f64, h: &[DVec3]) -> f64 {
    if h.is_empty() {
        return 0.0;
    }
    h.iter().map(|&v| beckmann_d(mx, my, v)).sum::<f64>() / h.len() as f64
}

/// The samples of one circle at polar angle `theta` with `n` samples starting at azimuth
/// `offset · 2π/n`, with those below the threshold rejected; and the sum of q of those kept.
fn circle(mx: f64, my: f64, xi0: f64, theta: f64, n: usize, offset: f64) -> (Vec<DVec3>, f64) {
    let mut kept = Vec::with_capacity(n);
    let mut sum = 0.0;
    for k in 0..n {
        let h = spherical(theta, 2.0 * PI * (k as f64 + offset) / n as f64);
        let qh = q(mx, my, h);
        if qh >= xi0 {
            kept.push(h);
            sum += qh;
        }
    }
    (kept, sum)
}

/// Options of the concentric patterns ([`concentric_with`], [`concentric_for_budget_opts`]).
/// The default reproduces 002 §5 as printed (and [`concentric`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ConcentricOptions {
    /// `None`: rings at the printed radii, the outermost at (nc − 1)/(nc + 1)·θmax (s1) or
    /// (nc − ½)/(nc + 2)·θmax (s2), i.e. only ≈ θmax/2 for nc = 3. `Some(r)`: every ring radius
    /// scaled by one factor so that the outermost ring lies at r·θmax (the ring sample counts
    /// stay those of the printed radii). The rejection q ≥ ξ0 is applied at the scaled radii
    /// (with a relative tolerance of 1e-9, so a ring exactly at θmax is kept): for r > 1 the
    /// rings beyond θmax are dropped even for isotropic lobes, so [`concentric_for_budget_opts`]
    /// then picks more circles and the kept rings fill the disc out to θmax more coarsely.
    /// Measured on the 002 §8 spot map (`examples/regular_study.rs`), r = 1 to 1.5 cuts the RMS
    /// error of 14–30-sample patterns by about 2–5× at the 002 Eq. 16 level, without MIP bias.
    pub reach: Option<f64>,
}

/// The concentric pattern of 002 §5 with `circles` circles (nc) and the given spacing.
///
/// θmax from Eq. 11, spacing s from Eq. 12. [`Spacing::S1`]: a sample at the pole and circles at
/// θ = i·s, i = 1 … nc − 1 (the pole counts as the first of the nc circles), 6 samples on the
/// first. [`Spacing::S2`]: circles at θ = (i + ½)·s, i = 0 … nc − 1, 4 samples on the first.
/// The other circles get [`ring_count`] samples (Eq. 13, even). Samples are equally spaced in
/// φ starting at φ = 0. For anisotropic lobes samples with q(h) < ξ0 are rejected, and the
/// same circle rotated by half a sample is tried too: the variant with the larger sum of q over
/// the kept samples is taken. With nc = 3 and ξ0 = 0.1 an isotropic lobe gets 19 (s1) and 30
/// (s2) samples, as in 002 Fig. 4. Patterns are symmetric under x → −x and y → −y.
pub fn concentric(mx: f64, my: f64, circles: usize, spacing: Spacing, xi0: f64) -> Result<Pattern> {
    concentric_with(mx, my, circles, spacing, xi0, ConcentricOptions::default())
}

/// [`concentric`] with [`ConcentricOptions`] (ring radii scaled to reach a chosen fraction of
/// θmax). Errors as [`concentric`], and for a reach that is not finite and > 0 or that would
/// put the outermost ring at or beyond 90°.
pub fn concentric_with(
    mx: f64,
    my: f64,
    circles: usize,
    spacing: Spacing,
    xi0: f64,
    opts: ConcentricOptions,
) -> Result<Pattern> {
    check_roughness(mx, my)?;
    check_xi0(xi0)?;
    if circles == 0 {
        return Err(ShadeError::Parameter(
            "pattern: the number of circles must be at least 1".into(),
        ));
    }
    let tmax = theta_max(mx, my, xi0);
    let s = spacing_angle(tmax, circles, spacing);
    // With a reach, rings may sit exactly on the border q = ξ0: keep them despite rounding.
    let threshold = if opts.reach.is_some() {
        xi0 * (1.0 - 1e-9)
    } else {
        xi0
    };
    let scale = match opts.reach {
        None => 1.0,
        Some(r) => {
            if !(r.is_finite() && r > 0.0 && r * tmax < 0.5 * PI) {
                return Err(ShadeError::Parameter(format!(
                    "pattern: reach {r} must be finite, > 0 and keep reach·θmax ({tmax} rad) below 90°"
                )));
            }
            let outer = match spacing {
                Spacing::S1 => (circles as f64 - 1.0) * s,
                Spacing::S2 => (circles as f64 - 0.5) * s,
            };
            if outer > 0.0 {
                r * tmax / outer
            } else {
                1.0
            }
        }
    };
    let mut h = Vec::new();
    for i in 0..circles {
        let (theta, n) = match spacing {
            Spacing::S1 if i == 0 => {
                h.push(DVec3::Z);
                continue;
            }
            Spacing::S1 => {
                let theta = i as f64 * s;
                (theta, if i == 1 { 6 } else { ring_count(theta, s) })
            }
            Spacing::S2 => {
                let theta = (i as f64 + 0.5) * s;
                (theta, if i == 0 { 4 } else { ring_count(theta, s) })
            }
        };
        let (base, q_base) = circle(mx, my, threshold, scale * theta, n, 0.0);
        let (half, q_half) = circle(mx, my, threshold, scale * theta, n, 0.5);
        // Ties (isotropic lobes) keep the unrotated circle.
        if q_half > q_base * (1.0 + 1e-12) {
            h.extend(half);
        } else {
            h.extend(base);
        }
    }
    Ok(Pattern {
        kind: PatternKind::Concentric { spacing, circles },
        pdf_constant: pdf_constant(mx, my, &h),
        h,
        mx,
        my,
        xi0,
    })
}

/// The largest concentric pattern (either spacing, nc = 1 … [`MAX_CIRCLES`]) with at most
/// `budget` samples, so that a method compared at a budget never exceeds it. 002 §5 (last
/// paragraph) takes the pattern *closest* to the budget, which may be larger (a budget of 17
/// for the mx 0.2 / my 0.075 lobe with reach 1 planned 20 samples); ties go to s1. The pole
/// pattern (nc = 1 of s1, one sample) always fits.
pub fn concentric_for_budget(mx: f64, my: f64, budget: usize, xi0: f64) -> Result<Pattern> {
    concentric_for_budget_opts(mx, my, budget, xi0, ConcentricOptions::default())
}

/// [`concentric_for_budget`] with [`ConcentricOptions`].
pub fn concentric_for_budget_opts(
    mx: f64,
    my: f64,
    budget: usize,
    xi0: f64,
    opts: ConcentricOptions,
) -> Result<Pattern> {
    let s1 = budget_search(mx, my, budget, xi0, Spacing::S1, opts)?;
    let s2 = budget_search(mx, my, budget, xi0, Spacing::S2, opts)?;
    let fits = |p: &Pattern| p.h.len() <= budget;
    Ok(match (fits(&s1), fits(&s2)) {
        (true, true) if s2.h.len() > s1.h.len() => s2,
        (false, true) => s2,
        _ => s1,
    })
}

/// The largest concentric pattern with the given spacing (nc = 1 … [`MAX_CIRCLES`]) with at
/// most `budget` samples (ties go to fewer circles); when even nc = 1 exceeds the budget (s2
/// puts 4 samples on its first circle), that smallest pattern.
pub fn concentric_for_budget_with(
    mx: f64,
    my: f64,
    budget: usize,
    xi0: f64,
    spacing: Spacing,
) -> Result<Pattern> {
    budget_search(mx, my, budget, xi0, spacing, ConcentricOptions::default())
}

/// [`concentric_for_budget_with`] with [`ConcentricOptions`].
fn budget_search(
    mx: f64,
    my: f64,
    budget: usize,
    xi0: f64,
    spacing: Spacing,
    opts: ConcentricOptions,
) -> Result<Pattern> {
    check_roughness(mx, my)?;
    check_xi0(xi0)?;
    if budget == 0 {
        return Err(ShadeError::Parameter(
            "pattern: the sample budget must be at least 1".into(),
        ));
    }
    let mut best = concentric_with(mx, my, 1, spacing, xi0, opts)?;
    for circles in 2..=MAX_CIRCLES {
        if best.h.len() > budget {
            break;
        }
        let p = concentric_with(mx, my, circles, spacing, xi0, opts)?;
        if p.h.len() > budget {
            break;
        }
        if p.h.len() > best.h.len() {
            best = p;
        }
    }
    Ok(best)
}

/// θthresh of 000 Eq. 4.10 at azimuth φh: arctan √(−ln ξ1border / (cos²φh/mx² + sin²φh/my²)).
pub fn theta_thresh(mx: f64, my: f64, phi: f64) -> f64 {
    let (sp, cp) = phi.sin_cos();
    let a = cp * cp / (mx * mx) + sp * sp / (my * my);
    ((-THESIS_XI_BORDER.ln()) / a).sqrt().atan()
}

/// The half vector of the thesis' uniformity-preserving mapping (000 Eq. 4.12–4.13):
/// φh = arctan(my/mx · tan 2πξ2) (quadrant-correct), θh = (1 − ξ1) · θthresh(φh).
pub fn thesis_h(mx: f64, my: f64, xi1: f64, xi2: f64) -> DVec3 {
    let phi0 = 2.0 * PI * xi2;
    let phi = (my * phi0.sin()).atan2(mx * phi0.cos());
    spherical((1.0 - xi1) * theta_thresh(mx, my, phi), phi)
}

fn thesis_pattern(kind: PatternKind, mx: f64, my: f64, h: Vec<DVec3>) -> Pattern {
    Pattern {
        kind,
        pdf_constant: pdf_constant(mx, my, &h),
        h,
        mx,
        my,
        xi0: THESIS_XI_BORDER,
    }
}

/// The thesis pattern of 000 §4.4.3 with `budget` samples.
///
/// If max(mx, my)/min(mx, my) ≥ [`THESIS_SWITCH_RATIO`]: `budget` samples equally spaced along
/// the major axis, sample k at signed ξ-distance t = 1 − (2k+1)/n from the centre (the thesis'
/// ξ1 = (2k+1)/n on one side, 2 − (2k+1)/n on the other; ξ2 = 0.25/0.75 for my > mx, 0/0.5
/// for mx > my). Otherwise one sample at the centre (ξ1 = 1) and `budget − 1` on the ring
/// ξ1 = 0.6, ξ2 = k/(budget − 1).
pub fn thesis(mx: f64, my: f64, budget: usize) -> Result<Pattern> {
    check_roughness(mx, my)?;
    if budget == 0 {
        return Err(ShadeError::Parameter(
            "pattern: the sample budget must be at least 1".into(),
        ));
    }
    if mx.max(my) / mx.min(my) >= THESIS_SWITCH_RATIO {
        // Major axis: ξ2 = 0.25 (φ = 90°) for my > mx, ξ2 = 0 (φ = 0°) for mx > my.
        let xi2 = if my > mx { 0.25 } else { 0.0 };
        let h = (0..budget)
            .map(|k| {
                let t = 1.0 - (2 * k + 1) as f64 / budget as f64;
                if t >= 0.0 {
                    thesis_h(mx, my, 1.0 - t, xi2)
                } else {
                    thesis_h(mx, my, 1.0 + t, xi2 + 0.5)
                }
            })
            .collect();
        return Ok(thesis_pattern(PatternKind::ThesisLinear, mx, my, h));
    }
    let ring = budget - 1;
    let mut h = vec![DVec3::Z];
    h.extend((0..ring).map(|k| thesis_h(mx, my, THESIS_RING_XI1, k as f64 / ring as f64)));
    Ok(thesis_pattern(PatternKind::ThesisRing, mx, my, h))
}

/// The multi-ring pattern of 000 §4.5.3: one centre sample plus `rings` rings of `per_ring`
/// samples (e.g. 3 × 3 for a budget of 10).
///
/// The thesis gives no radii: ring j = 1 … rings lies at 1 − ξ1 = 0.8 · j / (rings + 1) (so one
/// ring is the thesis ring at ξ1 = 0.6 and several rings spread evenly inside twice its
/// radius), and ring j is rotated by (j − 1)/rings of a sample step, so that all rings together
/// cover `rings · per_ring` distinct azimuths. Mapped with 000 Eq. 4.12–4.13.
pub fn multi_ring(mx: f64, my: f64, rings: usize, per_ring: usize) -> Result<Pattern> {
    check_roughness(mx, my)?;
    if rings == 0 || per_ring == 0 {
        return Err(ShadeError::Parameter(format!(
            "pattern: multi-ring needs rings >= 1 and per_ring >= 1 (got {rings}, {per_ring})"
        )));
    }
    let mut h = vec![DVec3::Z];
    for j in 1..=rings {
        let r = 0.8 * j as f64 / (rings as f64 + 1.0);
        let offset = (j - 1) as f64 / rings as f64;
        h.extend(
            (0..per_ring).map(|k| thesis_h(mx, my, 1.0 - r, (k as f64 + offset) / per_ring as f64)),
        );
    }
    Ok(thesis_pattern(PatternKind::MultiRing { rings }, mx, my, h))
}

/// The row lattice of [`row_lattice`]: `budget` half vectors laid out per pixel (they depend on
/// the view), so the stored pattern holds no half vectors; `integrator::shade_regular` builds them
/// with [`lattice_rows`], [`row_length`] and [`gauss_quantile`].
pub fn row_lattice(mx: f64, my: f64, budget: usize) -> Result<Pattern> {
    check_roughness(mx, my)?;
    if budget == 0 {
        return Err(ShadeError::Parameter(
            "pattern: the sample budget must be at least 1".into(),
        ));
    }
    Ok(Pattern {
        kind: PatternKind::RowLattice { budget },
        h: vec![],
        pdf_constant: 0.0,
        mx,
        my,
        xi0: ROW_LATTICE_XI0,
    })
}

/// The row lattice with anisotropic footprints (`integrator::plan_tap_lattice`): like
/// [`row_lattice`], per pixel, at most `budget` lookups in all; `integrator::shade_regular` gives a
/// cell that is long in ωi up to [`LATTICE_MAX_TAPS`] taps along its long axis.
pub fn tap_lattice(mx: f64, my: f64, budget: usize) -> Result<Pattern> {
    let p = row_lattice(mx, my, budget)?;
    Ok(Pattern {
        kind: PatternKind::TapLattice { budget },
        ..p
    })
}

/// The most taps one cell of a [`tap_lattice`] takes (measured on six truth-harness cases,
/// BENCHMARKS.md (regular sampling vs the exact integral): 3 and 4 within 0.2 points of each other, 2 worse on the 0.08 / 0.3
/// lobe).
pub const LATTICE_MAX_TAPS: usize = 3;

/// The `xi0` stored with a [`PatternKind::RowLattice`] pattern: unused by the estimator (the
/// lattice covers the whole lobe by equal-mass cells), kept inside (0, 1) for the GPU records.
pub const ROW_LATTICE_XI0: f64 = 0.5;

/// The quantile of the slope-space Gaussian marginal, density e^{−x²}/√π: x = erfinv(2u − 1),
/// by Giles' single-precision polynomial ("Approximating the erfinv function", GPU Computing
/// Gems, 2011; relative error < 4e-7 on (−1, 1)), the same polynomial as `shade.wgsl`. `u` is
/// clamped to [1e-7, 1 − 1e-7].
pub fn gauss_quantile(u: f64) -> f64 {
    let x = (2.0 * u.clamp(1e-7, 1.0 - 1e-7) - 1.0).clamp(-1.0, 1.0);
    lustre_brdf::numeric::erfinv_giles(x)
}

/// The number of rows of a [`row_lattice`] of `budget` samples for a lobe whose image in ωi
/// space is `ratio` (≥ 1) times longer along its major axis than along its minor one:
/// k = round(√(budget / ratio)) clamped to 1 ..= budget, so that with about budget/k samples
/// per row the cells are about as long as wide (round) in ωi space.
pub fn lattice_rows(budget: usize, ratio: f64) -> usize {
    let r = if ratio.is_finite() && ratio >= 1.0 {
        ratio
    } else if ratio.is_nan() {
        1.0
    } else {
        ratio.max(1.0)
    };
    let k = (budget as f64 / r).sqrt().round();
    if k.is_finite() {
        (k as usize).clamp(1, budget.max(1))
    } else {
        1
    }
}

/// The number of samples in row `j` of `rows` rows sharing `budget` samples: ⌊budget/rows⌋,
/// plus one for the budget mod rows rows nearest the centre (order c, c−1, c+1, c−2, … from
/// the centre row c = (rows−1)/2, or from the lower central row for an even count). The rows
/// sum to `budget` exactly.
pub fn row_length(budget: usize, rows: usize, j: usize) -> usize {
    let rows = rows.max(1);
    let base = budget / rows;
    let extra = budget % rows;
    let rank = if rows % 2 == 1 {
        let c = (rows - 1) / 2;
        if j == c {
            0
        } else if j < c {
            2 * (c - j) - 1
        } else {
            2 * (j - c)
        }
    } else {
        let c0 = rows / 2 - 1;
        if j <= c0 {
            2 * (c0 - j)
        } else {
            2 * (j - c0 - 1) + 1
        }
    };
    base + usize::from(rank < extra)
}
