//! The test battery every BSDF passes (in the manner of Mitsuba 3's BSDF tests): pdf normalization
//! by quadrature, chi-square agreement between `sample` and `pdf`, reciprocity, energy
//! conservation and finiteness. Public so that measured tables and fitted models can be checked by
//! the same code from any crate.

use crate::bsdf::Bsdf;
use crate::frame::{mirror_z, reflect};
use crate::numeric::{gamma_q, integrate_sphere, GaussRule, SphereQuadrature};
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

/// Directional albedo by quadrature, per channel (000 Eq. 2.6).
pub fn albedo_quadrature(bsdf: &dyn Bsdf, wo: DVec3, q: &SphereQuadrature) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let g = |wi: DVec3| bsdf.eval(wi, wo)[c] * wi.z.abs();
        *o = integrate_reflection(g, wo, q);
        if bsdf.flags().transmission {
            *o += integrate_transmission(g, wo, q);
        }
    }
    out
}

/// Fraction of `n` stratified samples for which `sample` succeeds (what ∫pdf must equal).
pub fn sample_success_fraction(bsdf: &dyn Bsdf, wo: DVec3, n: usize, seed: u64) -> f64 {
    let mut rng = SplitMix64::new(seed);
    let ok = (0..n)
        .filter(|_| bsdf.sample(wo, rng.next_f64(), rng.next_f64()).is_some())
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
    /// Fraction of samples that succeeded.
    pub sample_fraction: f64,
    /// Samples whose returned pdf disagrees with `pdf(wi, wo)` or whose value disagrees with `eval`.
    pub inconsistent: usize,
}

impl Chi2Result {
    /// Mitsuba's acceptance rule: p-value above the Šidák-corrected significance level and the
    /// sample fraction equal to the pdf integral.
    pub fn passed(&self, significance: f64, test_count: usize) -> bool {
        let alpha = 1.0 - (1.0 - significance).powf(1.0 / test_count as f64);
        self.p_value > alpha
            && (self.pdf_integral - self.sample_fraction).abs() < 1e-2
            && self.inconsistent == 0
    }
}

/// Chi-square goodness of fit between `sample` and `pdf` for one `wo`, on a (cos θ, φ) grid of
/// `res_theta × 2·res_theta` cells over the sphere (as Mitsuba 3's `ChiSquareTest`).
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
    for _ in 0..samples {
        if let Some(s) = bsdf.sample(wo, rng.next_f64(), rng.next_f64()) {
            if !(s.pdf > 0.0) || !s.pdf.is_finite() || !s.wi.is_finite() {
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
    // Expected counts: integrate the pdf over each cell with a Gauss rule in (cos θ, φ).
    let rule = GaussRule::new(6);
    let sub = 3; // sub-panels per cell edge
    let mut expected = vec![0.0f64; cells];
    for it in 0..res_theta {
        let z1 = 1.0 - 2.0 * it as f64 / res_theta as f64;
        let z0 = 1.0 - 2.0 * (it + 1) as f64 / res_theta as f64;
        for ip in 0..res_phi {
            let p0 = -PI + 2.0 * PI * ip as f64 / res_phi as f64;
            let p1 = p0 + 2.0 * PI / res_phi as f64;
            let v = rule.integrate(z0, z1, sub, |z| {
                let r = (1.0 - z * z).max(0.0).sqrt();
                rule.integrate(p0, p1, sub, |ph| {
                    bsdf.pdf(DVec3::new(r * ph.cos(), r * ph.sin(), z), wo)
                })
            });
            expected[it * res_phi + ip] = v * samples as f64;
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
    Chi2Result {
        statistic: stat,
        dof,
        p_value,
        pdf_integral,
        sample_fraction: ok as f64 / samples as f64,
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
