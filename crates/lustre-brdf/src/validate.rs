//! The test battery every BSDF passes (in the manner of Mitsuba 3's BSDF tests): pdf normalization
//! by quadrature, chi-square agreement between `sample` and `pdf`, reciprocity, energy
//! conservation and finiteness. Public so that measured tables and fitted models can be checked by
//! the same code from any crate.
//!
//! Delta (specular) lobes (see [`crate::bsdf`]) are checked apart: the chi-square and ∫pdf cover
//! the part with a density, and the frequency of each delta lobe must match the probability its
//! samples report.

use crate::bsdf::Bsdf;
use crate::frame::{mirror_z, reflect};
use crate::numeric::{gamma_q, integrate_sphere, SphereQuadrature};
use crate::sampling::{uniform_sphere, SplitMix64};
use glam::DVec3;
use std::f64::consts::PI;

/// ∫ g(wi) dωi over the upper hemisphere, parameterized by the half vector of (wi, wo) so that a
/// lobe around the mirror direction of `wo` is resolved however narrow it is.
pub fn integrate_reflection(g: impl Fn(DVec3) -> f64, wo: DVec3, q: &SphereQuadrature) -> f64 {
    integrate_sphere(
        |h| {
            let c = wo.dot(h);
            if c <= 0.0 || h.z <= 0.0 {
                return 0.0;
            }
            let wi = reflect(wo, h);
            if wi.z <= 0.0 {
                return 0.0;
            }
            g(wi) * 4.0 * c
        },
        DVec3::Z,
        q,
    )
}

/// ∫ g(wi) dωi over the lower hemisphere, parameterized by the half vector of the mirrored pair
/// (000 Eq. 3.5), resolving a transmission lobe around −wo.
pub fn integrate_transmission(g: impl Fn(DVec3) -> f64, wo: DVec3, q: &SphereQuadrature) -> f64 {
    integrate_reflection(|wi_mirrored| g(mirror_z(wi_mirrored)), wo, q)
}

/// ∫ pdf(wi, wo) dωi over the sphere (upper and, for transmissive models, lower hemisphere).
pub fn pdf_integral(bsdf: &dyn Bsdf, wo: DVec3, q: &SphereQuadrature) -> f64 {
    let mut s = integrate_reflection(|wi| bsdf.pdf(wi, wo), wo, q);
    if bsdf.flags().transmission {
        s += integrate_transmission(|wi| bsdf.pdf(wi, wo), wo, q);
    }
    s
}

/// Directional albedo per channel (000 Eq. 2.6): the part with a density by quadrature, plus
/// the delta lobes' part (if any) from [`DELTA_ALBEDO_SAMPLES`] Hammersley samples (exact up to
/// the stratification of the lobe choice, ~1/n).
pub fn albedo_quadrature(bsdf: &dyn Bsdf, wo: DVec3, q: &SphereQuadrature) -> [f64; 3] {
    let mut out = delta_albedo(bsdf, wo, DELTA_ALBEDO_SAMPLES);
    for (c, o) in out.iter_mut().enumerate() {
        let g = |wi: DVec3| bsdf.eval(wi, wo)[c] * wi.z.abs();
        *o += integrate_reflection(g, wo, q);
        if bsdf.flags().transmission {
            *o += integrate_transmission(g, wo, q);
        }
    }
    out
}

/// Hammersley samples [`albedo_quadrature`] spends on the delta lobes.
pub const DELTA_ALBEDO_SAMPLES: usize = 1 << 14;

/// The delta lobes' share of the directional albedo, per channel: the mean over `n` Hammersley
/// samples of the weight of the specular ones (zero for a BSDF without delta lobes).
pub fn delta_albedo(bsdf: &dyn Bsdf, wo: DVec3, n: usize) -> [f64; 3] {
    let mut out = [0.0; 3];
    if !bsdf.flags().has_delta() {
        return out;
    }
    for k in 0..n {
        let (u1, u2) = crate::sampling::hammersley(k as u32, n as u32);
        if let Some(s) = bsdf.sample(wo, u1, u2).filter(|s| s.is_delta()) {
            let w = s.weight();
            for (o, c) in out.iter_mut().zip(0..3) {
                *o += w[c] / n as f64;
            }
        }
    }
    out
}

/// Fraction of `n` random samples for which `sample` succeeds on a lobe with a density (what
/// ∫pdf must equal; specular samples are not counted).
pub fn sample_success_fraction(bsdf: &dyn Bsdf, wo: DVec3, n: usize, seed: u64) -> f64 {
    let mut rng = SplitMix64::new(seed);
    let ok = (0..n)
        .filter(|_| {
            bsdf.sample(wo, rng.next_f64(), rng.next_f64())
                .is_some_and(|s| !s.is_delta())
        })
        .count();
    ok as f64 / n as f64
}

/// Result of [`chi2_test`].
#[derive(Clone, Debug)]
pub struct Chi2Result {
    /// The chi-square statistic after pooling sparse cells.
    pub statistic: f64,
    /// Degrees of freedom.
    pub dof: usize,
    /// Probability of a statistic at least this large if `sample` follows `pdf`.
    pub p_value: f64,
    /// ∫ pdf over the sphere, from the cell integrals.
    pub pdf_integral: f64,
    /// Fraction of samples that succeeded on a lobe with a density.
    pub sample_fraction: f64,
    /// Fraction of samples that came from a delta lobe.
    pub delta_fraction: f64,
    /// Over the delta lobes (grouped by their flags): the largest |observed frequency − mean
    /// reported probability| in binomial standard deviations (0 without delta samples).
    pub delta_sigma: f64,
    /// Samples whose returned pdf disagrees with `pdf(wi, wo)` or whose value disagrees with
    /// `eval`, and delta samples with a probability outside (0, 1] or a non-finite value.
    pub inconsistent: usize,
}

impl Chi2Result {
    /// Mitsuba's acceptance rule: p-value above the Šidák-corrected significance level and the
    /// sample fraction equal to the pdf integral.
    pub fn passed(&self, significance: f64, test_count: usize) -> bool {
        let alpha = 1.0 - (1.0 - significance).powf(1.0 / test_count as f64);
        self.p_value > alpha
            && (self.pdf_integral - self.sample_fraction).abs() < 1e-2
            && self.delta_sigma < 5.0
            && self.inconsistent == 0
    }
}

/// Error accepted per rectangle in [`CellCubature`], as a fraction of the Poisson standard
/// deviation √E of the rectangle's expected count E: the errors of a cell's (at least 16)
/// rectangles then stay a small fraction of the cell's own deviation.
const POISSON_TOL: f64 = 0.03;

/// Gauss points per rectangle edge in [`CellCubature`].
const CUBATURE_NODES: usize = 5;

/// Adaptive cubature of `pdf(·, wo)` over a (θ, φ) rectangle of the sphere, for the expected
/// counts of [`chi2_test`]. A fixed rule misses lobes narrower than its node spacing (a Phong lobe
/// with n = 5000, RGL `cg_sunflower` at 600/sr, a Kurt lobe with m = 0.01): their cell integrals
/// then miss ∫pdf by percents (Phong n = 5000 at θo = 0.05: 1.13) and fail a correct sampler.
///
/// Each cell starts as `INITIAL × INITIAL` rectangles in (θ, φ) (θ rather than cos θ, so that a
/// lobe at the pole keeps its angular width); a rectangle's `CUBATURE_NODES²`-point Gauss estimate
/// is compared with the sum of those of its four quarters, and it is split where they disagree by
/// more than the tolerance (in probability: [`CellCubature::tol`] spread over the sphere by area,
/// or `POISSON_TOL` of the Poisson deviation of its expected count), down to `MAX_DEPTH` halvings.
/// A lobe so narrow that no node of a rectangle sees it would pass that test unnoticed, so
/// rectangles near the directions where BSDF lobes peak (the mirror direction of `wo`, `−wo`,
/// `wo`, the normal, and their reflections through the surface) are split regardless until they
/// are `MIN_ANGLE` across.
struct CellCubature<'a> {
    bsdf: &'a dyn Bsdf,
    wo: DVec3,
    x: [f64; CUBATURE_NODES],
    w: [f64; CUBATURE_NODES],
    seeds: [DVec3; 6],
    /// Allowed error per unit (θ, φ) area.
    tol_density: f64,
    samples: f64,
}

impl<'a> CellCubature<'a> {
    const INITIAL: usize = 4;
    const MAX_DEPTH: usize = 6;
    const MIN_ANGLE: f64 = 2e-3;

    fn new(bsdf: &'a dyn Bsdf, wo: DVec3, samples: usize) -> Self {
        let (xs, ws) = crate::numeric::gauss_legendre(CUBATURE_NODES);
        let mut x = [0.0; CUBATURE_NODES];
        let mut w = [0.0; CUBATURE_NODES];
        x.copy_from_slice(&xs);
        w.copy_from_slice(&ws);
        let r = DVec3::new(-wo.x, -wo.y, wo.z);
        let seeds = [r, mirror_z(r), wo, mirror_z(wo), DVec3::Z, -DVec3::Z];
        CellCubature {
            bsdf,
            wo,
            x,
            w,
            seeds: seeds.map(|s| s.try_normalize().unwrap_or(DVec3::Z)),
            tol_density: Self::tol(samples) / (2.0 * PI * PI),
            samples: samples.max(1) as f64,
        }
    }

    /// Absolute error budget over the sphere, in probability: half a count in all, so that no
    /// cell's expected count is off by more than a small fraction of its standard deviation
    /// (the error estimates are pessimistic, the accepted refined sums far better).
    fn tol(samples: usize) -> f64 {
        0.5 / samples.max(1) as f64
    }

    fn density(&self, t: f64, p: f64) -> f64 {
        let (st, ct) = t.sin_cos();
        let (sp, cp) = p.sin_cos();
        self.bsdf.pdf(DVec3::new(st * cp, st * sp, ct), self.wo) * st.abs()
    }

    /// Tensor Gauss estimate over [t0, t1] × [p0, p1].
    fn rect(&self, t0: f64, t1: f64, p0: f64, p1: f64) -> f64 {
        let (tc, th) = (0.5 * (t0 + t1), 0.5 * (t1 - t0));
        let (pc, ph) = (0.5 * (p0 + p1), 0.5 * (p1 - p0));
        let mut s = 0.0;
        for (xt, wt) in self.x.iter().zip(&self.w) {
            let t = tc + th * xt;
            let mut row = 0.0;
            for (xp, wp) in self.x.iter().zip(&self.w) {
                row += wp * self.density(t, pc + ph * xp);
            }
            s += wt * row;
        }
        s * th * ph
    }

    /// Whether a rectangle lies within twice its half-diagonal of a lobe direction and is
    /// still wider than `MIN_ANGLE`.
    fn near_seed(&self, t0: f64, t1: f64, p0: f64, p1: f64) -> bool {
        let s_max = if t0 <= 0.5 * PI && t1 >= 0.5 * PI {
            1.0
        } else {
            t0.sin().max(t1.sin())
        };
        let half_diag = 0.5 * (t1 - t0).hypot(s_max * (p1 - p0));
        if half_diag < Self::MIN_ANGLE {
            return false;
        }
        let c = crate::frame::spherical(0.5 * (t0 + t1), 0.5 * (p0 + p1));
        let reach = (2.0 * half_diag).min(PI).cos();
        self.seeds.iter().any(|s| s.dot(c) >= reach)
    }

    fn refine(&self, t0: f64, t1: f64, p0: f64, p1: f64, whole: f64, depth: usize) -> f64 {
        let (tm, pm) = (0.5 * (t0 + t1), 0.5 * (p0 + p1));
        let quarters = [
            (t0, tm, p0, pm),
            (t0, tm, pm, p1),
            (tm, t1, p0, pm),
            (tm, t1, pm, p1),
        ];
        let parts = quarters.map(|(a, b, c, d)| self.rect(a, b, c, d));
        let sum: f64 = parts.iter().sum();
        if depth >= Self::MAX_DEPTH {
            return sum;
        }
        let tol = (self.tol_density * (t1 - t0) * (p1 - p0))
            .max(POISSON_TOL * (sum.abs() / self.samples).sqrt());
        if (sum - whole).abs() <= tol && !self.near_seed(t0, t1, p0, p1) {
            return sum;
        }
        quarters
            .iter()
            .zip(parts)
            .map(|(&(a, b, c, d), v)| self.refine(a, b, c, d, v, depth + 1))
            .sum()
    }

    /// ∫ pdf dω over the cell θ ∈ [t0, t1], φ ∈ [p0, p1].
    fn cell(&self, t0: f64, t1: f64, p0: f64, p1: f64) -> f64 {
        let n = Self::INITIAL;
        let mut total = 0.0;
        for i in 0..n {
            let a = t0 + (t1 - t0) * i as f64 / n as f64;
            let b = t0 + (t1 - t0) * (i + 1) as f64 / n as f64;
            for j in 0..n {
                let c = p0 + (p1 - p0) * j as f64 / n as f64;
                let d = p0 + (p1 - p0) * (j + 1) as f64 / n as f64;
                total += self.refine(a, b, c, d, self.rect(a, b, c, d), 0);
            }
        }
        total
    }
}

/// Chi-square goodness of fit between `sample` and `pdf` for one `wo`, on a (cos θ, φ) grid of
/// `res_theta × 2·res_theta` cells over the sphere (as Mitsuba 3's `ChiSquareTest`): samples are
/// binned, the expected count of each cell is the adaptive cubature of the pdf over it (accurate
/// for lobes down to a few milliradians wide), cells expecting fewer than 5 samples are pooled,
/// and `pdf_integral` (the sum of the cell integrals) is reported for comparison with the
/// fraction of samples that succeeded.
pub fn chi2_test(
    bsdf: &dyn Bsdf,
    wo: DVec3,
    res_theta: usize,
    samples: usize,
    seed: u64,
) -> Chi2Result {
    let res_phi = 2 * res_theta;
    let cells = res_theta * res_phi;
    let cell_of = |w: DVec3| -> usize {
        let ct = ((1.0 - w.z.clamp(-1.0, 1.0)) * 0.5 * res_theta as f64) as usize;
        let ph = (w.y.atan2(w.x) + PI) / (2.0 * PI) * res_phi as f64;
        ct.min(res_theta - 1) * res_phi + (ph as usize).min(res_phi - 1)
    };
    let mut hist = vec![0.0f64; cells];
    let mut rng = SplitMix64::new(seed);
    let mut ok = 0usize;
    let mut inconsistent = 0usize;
    // Delta samples per lobe flags: (count, sum of reported probabilities).
    let mut delta: Vec<(crate::bsdf::LobeFlags, usize, f64)> = Vec::new();
    for _ in 0..samples {
        if let Some(s) = bsdf.sample(wo, rng.next_f64(), rng.next_f64()) {
            if s.is_delta() {
                if !(s.pdf > 0.0 && s.pdf <= 1.0 && s.value.is_finite() && s.wi.is_finite()) {
                    inconsistent += 1;
                    continue;
                }
                match delta.iter_mut().find(|d| d.0 == s.lobe) {
                    Some(d) => {
                        d.1 += 1;
                        d.2 += s.pdf;
                    }
                    None => delta.push((s.lobe, 1, s.pdf)),
                }
                continue;
            }
            if s.pdf.is_nan() || s.pdf <= 0.0 || !s.pdf.is_finite() || !s.wi.is_finite() {
                inconsistent += 1;
                continue;
            }
            ok += 1;
            hist[cell_of(s.wi)] += 1.0;
            // The pdf and value a sample reports must be those of pdf() and eval().
            let p = bsdf.pdf(s.wi, wo);
            let f = bsdf.eval(s.wi, wo);
            let rel = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs()) + 1e-12;
            if !rel(p, s.pdf) || !(0..3).all(|c| rel(f[c], s.value[c])) {
                inconsistent += 1;
            }
        }
    }
    // Expected counts: adaptive cubature of the pdf over each cell (see `CellCubature`).
    let cubature = CellCubature::new(bsdf, wo, samples);
    let mut expected = vec![0.0f64; cells];
    for it in 0..res_theta {
        let z1 = 1.0 - 2.0 * it as f64 / res_theta as f64;
        let z0 = 1.0 - 2.0 * (it + 1) as f64 / res_theta as f64;
        let (t0, t1) = (z1.clamp(-1.0, 1.0).acos(), z0.clamp(-1.0, 1.0).acos());
        for ip in 0..res_phi {
            let p0 = -PI + 2.0 * PI * ip as f64 / res_phi as f64;
            let p1 = p0 + 2.0 * PI / res_phi as f64;
            expected[it * res_phi + ip] = cubature.cell(t0, t1, p0, p1) * samples as f64;
        }
    }
    let pdf_integral = expected.iter().sum::<f64>() / samples as f64;
    // Pool cells with expected count < 5 (sorted ascending), as Mitsuba does.
    let mut order: Vec<usize> = (0..cells).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut pool_e, mut pool_o, mut stat, mut dof) = (0.0, 0.0, 0.0, 0usize);
    for &i in &order {
        if expected[i] == 0.0 {
            if hist[i] > 0.0 {
                // Samples where the pdf is zero: a certain failure.
                stat = f64::INFINITY;
            }
            continue;
        }
        if expected[i] < 5.0 {
            pool_e += expected[i];
            pool_o += hist[i];
            if pool_e >= 5.0 {
                stat += (pool_o - pool_e).powi(2) / pool_e;
                dof += 1;
                pool_e = 0.0;
                pool_o = 0.0;
            }
            continue;
        }
        stat += (hist[i] - expected[i]).powi(2) / expected[i];
        dof += 1;
    }
    if pool_e > 0.0 {
        stat += (pool_o - pool_e).powi(2) / pool_e;
        dof += 1;
    }
    let dof = dof.saturating_sub(1).max(1);
    let p_value = if stat.is_finite() {
        gamma_q(dof as f64 / 2.0, stat / 2.0)
    } else {
        0.0
    };
    let n = samples as f64;
    let delta_sigma = delta
        .iter()
        .map(|&(_, count, sum_p)| {
            let p = sum_p / count as f64;
            let sd = (p * (1.0 - p) / n).sqrt().max(1.0 / n);
            (count as f64 / n - p).abs() / sd
        })
        .fold(0.0, f64::max);
    Chi2Result {
        statistic: stat,
        dof,
        p_value,
        pdf_integral,
        sample_fraction: ok as f64 / n,
        delta_fraction: delta.iter().map(|d| d.1).sum::<usize>() as f64 / n,
        delta_sigma,
        inconsistent,
    }
}

/// Largest relative reciprocity violation |f(wi,wo) − f(wo,wi)| / max over `n` random pairs
/// (pairs in the same hemisphere, and across hemispheres for transmissive models).
pub fn reciprocity_error(bsdf: &dyn Bsdf, n: usize, seed: u64) -> f64 {
    let mut rng = SplitMix64::new(seed);
    let mut worst = 0.0f64;
    for _ in 0..n {
        let mut a = uniform_sphere(rng.next_f64(), rng.next_f64());
        let mut b = uniform_sphere(rng.next_f64(), rng.next_f64());
        a.z = a.z.abs().max(1e-3);
        b.z = b.z.abs().max(1e-3);
        let (a, mut b) = (a.normalize(), b.normalize());
        if bsdf.flags().transmission && rng.next_f64() < 0.5 {
            b = mirror_z(b);
        }
        let f1 = bsdf.eval(a, b);
        let f2 = bsdf.eval(b, a);
        for c in 0..3 {
            let m = f1[c].abs().max(f2[c].abs());
            if m > 1e-300 {
                worst = worst.max((f1[c] - f2[c]).abs() / m);
            }
        }
    }
    worst
}

/// Outgoing directions the battery tests at: θo from near-normal to grazing, several azimuths.
pub fn test_directions() -> Vec<DVec3> {
    [
        (0.05, 0.3),
        (0.5, 1.0),
        (1.0, -2.0),
        (1.3, 2.5),
        (1.52, 0.7),
    ]
    .iter()
    .map(|&(t, p)| crate::frame::spherical(t, p))
    .collect()
}
