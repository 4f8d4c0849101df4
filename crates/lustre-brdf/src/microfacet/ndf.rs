//! Isotropic microfacet normal distributions in the P22 form of 004 §III.4.4.4.2 (Eq. III.2,
//! Table III.2) and the Shifted Gamma Distribution of 004 §V.3.2.
//!
//! # Normalization (read this before changing a constant)
//!
//! 004 writes both `∫₀^∞ P22(x) dx = 1/π` (below Eq. III.3) and `D(θ) = P22(tan²θ)/(π cos⁴θ)`
//! (§V.3.2); with both, `∫ D(h)(h·n) dω = 1/π`, which is wrong (the test
//! `004_normalization_is_inconsistent` proves it numerically). We use, as the published SGD table
//! does,
//!
//! ```text
//! ∫₀^∞ P22(x) dx = 1,   x = tan²θ,   D(θ) = χ+(θ) P22(tan²θ) / (π cos⁴θ),
//! ```
//!
//! so that `D(h) cosθ_h dω = P22(x) dx dφ / (2π)` and `∫ D(h)(h·n) dω = 1`. Table III.2 is thus
//! rescaled by π: Beckmann `e^{−x/α²}/α²`, exponential `e^{−√x/α}/(2α²)`, GGX `α²/(α²+x)²`, and
//! SGD `kap e^{−A} A^{−p}` with `A = α + x/α`, `kap = 1/(α Γ(1−p, α))` (Eq. V.2 rewritten; the
//! paper's `α^{p−1}/Γ(1−p,α) · e^{−(α²+x)/α}/(α²+x)^p` is the same function).
//!
//! # Sampling
//!
//! `sample_h` draws a microfacet normal with φ = 2π u1 and x = tan²θ from u2 (004 Eq. III.3 and
//! the separable CDF below it). Beckmann, GGX and exponential are sampled exactly
//! (`pdf_h = D(h) cosθ_h`). The SGD CDF `1 − Γ(1−p, α + x/α)/Γ(1−p, α)` (§V.3.5) has no closed
//! inverse, so, as the paper does, we sample a GGX proxy and the BSDF weight f·cos/pdf carries the
//! ratio. The paper uses the proxy GGX with the SGD's own α, which for small α puts the proxy's
//! median tan²θ (= α²) far from the SGD's; we instead pick the proxy α so that both have the same
//! median of tan²θ (GGX's median x is α_ggx²), computed once at construction and rounded to the
//! nearest half-precision value (the GPU layout of `lustre_gpu::fit_models` carries it so).

use crate::error::{check_range, Error, Result};
use crate::numeric::upper_gamma;
use glam::DVec3;
use std::f64::consts::PI;

/// Smallest and largest α accepted by the constructors.
pub const ALPHA_RANGE: (f64, f64) = (1e-6, 10.0);
/// Range of the SGD exponent p accepted by [`Ndf::sgd`].
pub const SGD_P_RANGE: (f64, f64) = (-2.0, 3.0);

/// The shifted gamma distribution (004 §V.3.2) with its precomputed constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sgd {
    alpha: f64,
    p: f64,
    kap: f64,
    ln_kap: f64,
    gamma0: f64,
    proxy_alpha: f64,
}

impl Sgd {
    /// α (the paper's roughness; the distribution in x = tan²θ spans roughly [α², α]).
    pub fn alpha(&self) -> f64 {
        self.alpha
    }
    /// The exponent p.
    pub fn p(&self) -> f64 {
        self.p
    }
    /// The factor kap in `P22 = kap e^{−A} A^{−p}` (equal to 1/(αΓ(1−p, α)) unless built by
    /// [`Ndf::sgd_with_kap`]).
    pub fn kap(&self) -> f64 {
        self.kap
    }
    /// Γ(1−p, α), the normalizer of the CDF.
    pub fn gamma0(&self) -> f64 {
        self.gamma0
    }
    /// α of the GGX proxy used for importance sampling (same median of tan²θ).
    pub fn proxy_alpha(&self) -> f64 {
        self.proxy_alpha
    }
    /// P22(x) = kap e^{−A} A^{−p}, A = α + x/α.
    #[inline]
    fn p22(&self, x: f64) -> f64 {
        let a = self.alpha + x / self.alpha;
        (self.ln_kap - a - self.p * a.ln()).exp()
    }
    /// CDF of the (normalized) SGD in x: 1 − Γ(1−p, α + x/α)/Γ(1−p, α) (004 §V.3.5).
    fn cdf_x(&self, x: f64) -> f64 {
        if x.is_nan() || x <= 0.0 {
            return 0.0;
        }
        (1.0 - upper_gamma(1.0 - self.p, self.alpha + x / self.alpha) / self.gamma0).clamp(0.0, 1.0)
    }
}

/// An isotropic microfacet distribution, D(θ) = P22(tan²θ)/(π cos⁴θ) (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ndf {
    /// Beckmann, P22 = e^{−x/α²}/α² (α: RMS slope·√2 convention of Table III.2).
    Beckmann {
        /// Roughness α.
        alpha: f64,
    },
    /// Trowbridge-Reitz / GGX, P22 = α²/(α²+x)².
    Ggx {
        /// Roughness α.
        alpha: f64,
    },
    /// Exponential, P22 = e^{−√x/α}/(2α²).
    Exponential {
        /// Roughness α.
        alpha: f64,
    },
    /// Shifted gamma distribution (004 Eq. V.2); build with [`Ndf::sgd`].
    Sgd(Sgd),
}

fn check_alpha(alpha: f64) -> Result<f64> {
    check_range("alpha", alpha, ALPHA_RANGE.0, ALPHA_RANGE.1)
}

impl Ndf {
    /// A Beckmann distribution; α must lie in [`ALPHA_RANGE`].
    pub fn beckmann(alpha: f64) -> Result<Ndf> {
        Ok(Ndf::Beckmann {
            alpha: check_alpha(alpha)?,
        })
    }

    /// A GGX distribution; α must lie in [`ALPHA_RANGE`].
    pub fn ggx(alpha: f64) -> Result<Ndf> {
        Ok(Ndf::Ggx {
            alpha: check_alpha(alpha)?,
        })
    }

    /// An exponential distribution; α must lie in [`ALPHA_RANGE`].
    pub fn exponential(alpha: f64) -> Result<Ndf> {
        Ok(Ndf::Exponential {
            alpha: check_alpha(alpha)?,
        })
    }

    /// A normalized SGD: α in [`ALPHA_RANGE`], p in [`SGD_P_RANGE`], kap = 1/(αΓ(1−p, α)).
    pub fn sgd(alpha: f64, p: f64) -> Result<Ndf> {
        let alpha = check_alpha(alpha)?;
        let p = check_range("p", p, SGD_P_RANGE.0, SGD_P_RANGE.1)?;
        let gamma0 = upper_gamma(1.0 - p, alpha);
        if !(gamma0.is_finite() && gamma0 > 0.0) {
            return Err(Error::param(
                "p",
                p,
                format!("Γ(1−p, α) = {gamma0} for α = {alpha}"),
            ));
        }
        Self::sgd_with_kap(alpha, p, 1.0 / (alpha * gamma0))
    }

    /// An SGD with a given kap (the published table stores kap, and for a few materials, e.g.
    /// chrome, it is not 1/(αΓ(1−p, α)); then D is not normalized). kap must be finite and > 0.
    pub fn sgd_with_kap(alpha: f64, p: f64, kap: f64) -> Result<Ndf> {
        let alpha = check_alpha(alpha)?;
        let p = check_range("p", p, SGD_P_RANGE.0, SGD_P_RANGE.1)?;
        let kap = check_range("kap", kap, f64::MIN_POSITIVE, f64::MAX)?;
        let gamma0 = upper_gamma(1.0 - p, alpha);
        if !(gamma0.is_finite() && gamma0 > 0.0) {
            return Err(Error::param(
                "p",
                p,
                format!("Γ(1−p, α) = {gamma0} for α = {alpha}"),
            ));
        }
        let mut s = Sgd {
            alpha,
            p,
            kap,
            ln_kap: kap.ln(),
            gamma0,
            proxy_alpha: alpha,
        };
        s.proxy_alpha = half_precision(sgd_median_x(&s).sqrt());
        Ok(Ndf::Sgd(s))
    }

    /// A short name such as `sgd(α=0.01, p=0.5)`.
    pub fn name(&self) -> String {
        match self {
            Ndf::Beckmann { alpha } => format!("beckmann(α={alpha})"),
            Ndf::Ggx { alpha } => format!("ggx(α={alpha})"),
            Ndf::Exponential { alpha } => format!("exponential(α={alpha})"),
            Ndf::Sgd(s) => format!("sgd(α={}, p={})", s.alpha, s.p),
        }
    }

    /// P22(x), x = tan²θ, normalized to ∫₀^∞ P22 dx = 1 (Table III.2 × π, Eq. V.2).
    #[inline]
    pub fn p22(&self, x: f64) -> f64 {
        if x.is_nan() || x < 0.0 {
            return 0.0;
        }
        match *self {
            Ndf::Beckmann { alpha } => {
                let a2 = alpha * alpha;
                (-x / a2).exp() / a2
            }
            Ndf::Ggx { alpha } => {
                let a2 = alpha * alpha;
                let d = a2 + x;
                a2 / (d * d)
            }
            Ndf::Exponential { alpha } => (-x.sqrt() / alpha).exp() / (2.0 * alpha * alpha),
            Ndf::Sgd(ref s) => s.p22(x),
        }
    }

    /// D(θ_h) = χ+ P22(tan²θ_h)/(π cos⁴θ_h) (Eq. III.2 with the normalization above).
    #[inline]
    pub fn d(&self, cos_theta_h: f64) -> f64 {
        let c = cos_theta_h;
        if c.is_nan() || c <= 0.0 {
            return 0.0;
        }
        let c = c.min(1.0);
        let c2 = c * c;
        let s2 = (1.0 - c2).max(0.0);
        if let Ndf::Ggx { alpha } = *self {
            // α²/(π(α²c² + s²)²): finite at grazing.
            let a2 = alpha * alpha;
            let d = a2 * c2 + s2;
            return a2 / (PI * d * d);
        }
        if c < 1e-100 {
            return 0.0;
        }
        self.p22(s2 / c2) / (PI * c2 * c2)
    }

    /// CDF of x = tan²θ_h under D(h)cosθ_h dω: ∫₀^x P22. For SGD, the normalized CDF of §V.3.5.
    pub fn cdf_x(&self, x: f64) -> f64 {
        if x.is_nan() || x <= 0.0 {
            return 0.0;
        }
        match *self {
            Ndf::Beckmann { alpha } => -(-x / (alpha * alpha)).exp_m1(),
            Ndf::Ggx { alpha } => x / (alpha * alpha + x),
            Ndf::Exponential { alpha } => {
                let u = x.sqrt() / alpha;
                if u < 1e-4 {
                    // 1 − (1+u)e^{−u} = u²/2 − u³/3 + u⁴/8 …
                    u * u * (0.5 - u / 3.0 + u * u / 8.0)
                } else {
                    1.0 - (1.0 + u) * (-u).exp()
                }
            }
            Ndf::Sgd(ref s) => s.cdf_x(x),
        }
    }

    /// Characteristic scales (x_lo, x_hi) of tan²θ: P22 is flat below x_lo and its tail beyond
    /// x_hi carries negligible mass (< e^{−50}; for GGX's power tail, x_hi = 1e20 α²). Used to
    /// place quadrature panels.
    pub fn x_range(&self) -> (f64, f64) {
        match *self {
            Ndf::Beckmann { alpha } => (alpha * alpha, 70.0 * alpha * alpha),
            Ndf::Ggx { alpha } => (alpha * alpha, 1e20 * alpha * alpha),
            Ndf::Exponential { alpha } => (alpha * alpha, 6400.0 * alpha * alpha),
            Ndf::Sgd(ref s) => {
                let a = s.alpha;
                (a * a, a * (a + 80.0 + 10.0 * s.p.abs()))
            }
        }
    }

    /// Draws a microfacet normal (upper hemisphere) with φ = 2πu1 and tan²θ from u2: exactly
    /// from D(h)cosθ_h for Beckmann, GGX and exponential; from the GGX proxy for SGD.
    pub fn sample_h(&self, u1: f64, u2: f64) -> DVec3 {
        let u2 = u2.clamp(0.0, 1.0 - f64::EPSILON);
        let x = match *self {
            Ndf::Beckmann { alpha } => -alpha * alpha * (-u2).ln_1p(),
            Ndf::Ggx { alpha } => alpha * alpha * u2 / (1.0 - u2),
            Ndf::Exponential { alpha } => {
                let u = invert_exponential_cdf(u2);
                alpha * alpha * u * u
            }
            Ndf::Sgd(ref s) => s.proxy_alpha * s.proxy_alpha * u2 / (1.0 - u2),
        };
        let cos_t = 1.0 / (1.0 + x).sqrt();
        let sin_t = (x / (1.0 + x)).sqrt();
        let phi = 2.0 * PI * u1;
        DVec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
    }

    /// Solid-angle density of [`Ndf::sample_h`]: D(h)cosθ_h, or the GGX proxy's for SGD.
    #[inline]
    pub fn pdf_h(&self, h: DVec3) -> f64 {
        if h.z.is_nan() || h.z <= 0.0 {
            return 0.0;
        }
        match *self {
            Ndf::Sgd(ref s) => {
                Ndf::Ggx {
                    alpha: s.proxy_alpha,
                }
                .d(h.z)
                    * h.z
            }
            _ => self.d(h.z) * h.z,
        }
    }
}

/// The proxy α as the nearest IEEE half-precision value (at least the smallest positive one),
/// so that the GPU's 32-float SGD layout carries the sampler exactly (`lustre_gpu::fit_models`);
/// the relative change (< 5e-4 for α ≥ 6.1e-5) does not matter to importance sampling.
fn half_precision(x: f64) -> f64 {
    half::f16::from_f64(x)
        .to_f64()
        .max(half::f16::MIN_POSITIVE_SUBNORMAL.to_f64())
}

/// Solves 1 − (1+u)e^{−u} = xi for u ≥ 0 (exponential distribution CDF with u = √x/α) by
/// Newton's method on ln(1+u) − u = ln(1−xi), safeguarded by bisection.
fn invert_exponential_cdf(xi: f64) -> f64 {
    if xi.is_nan() || xi <= 0.0 {
        return 0.0;
    }
    let lnq = (-xi).ln_1p(); // ln(1 − xi) ≤ 0
    let big_l = -lnq;
    let (mut lo, mut hi) = (0.0f64, 2.0 * big_l + 2.0);
    // h(u) = ln(1+u) − u − ln q, decreasing from −ln q ≥ 0 at u = 0.
    let h = |u: f64| u.ln_1p() - u - lnq;
    let mut u = if xi < 0.5 {
        (2.0 * xi).sqrt()
    } else {
        big_l + (1.0 + big_l).ln()
    };
    u = u.clamp(lo, hi);
    for _ in 0..100 {
        let hu = h(u);
        if hu > 0.0 {
            lo = u;
        } else {
            hi = u;
        }
        let dh = -u / (1.0 + u);
        let mut next = if dh < 0.0 {
            u - hu / dh
        } else {
            0.5 * (lo + hi)
        };
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - u).abs() <= 1e-15 * u.max(1e-300) {
            return next;
        }
        u = next;
    }
    u
}

/// Median of tan²θ under the normalized SGD: solves Γ(1−p, α + x/α) = Γ(1−p, α)/2 by bisection
/// in log x.
fn sgd_median_x(s: &Sgd) -> f64 {
    let target = 0.5 * s.gamma0;
    let g = |x: f64| upper_gamma(1.0 - s.p, s.alpha + x / s.alpha);
    let mut hi = s.alpha * s.alpha;
    let mut n = 0;
    while g(hi) > target && n < 200 {
        hi *= 4.0;
        n += 1;
    }
    let mut lo = hi / 4.0;
    n = 0;
    while g(lo) < target && n < 400 {
        lo /= 4.0;
        n += 1;
    }
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if g(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi / lo - 1.0 < 1e-13 {
            break;
        }
    }
    (lo * hi).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::{integrate_sphere, GaussRule, SphereQuadrature};
    use crate::sampling::SplitMix64;

    fn fine() -> SphereQuadrature {
        SphereQuadrature {
            points_per_panel: 16,
            phi_points: 4, // D is isotropic about +z
            theta_min: 1e-7,
            theta_split: 0.3,
            uniform_panels: 64,
        }
    }

    fn all_params() -> Vec<Ndf> {
        let mut v = Vec::new();
        for &a in &[0.01, 0.03, 0.1, 0.3, 0.6, 1.0] {
            v.push(Ndf::beckmann(a).unwrap());
            v.push(Ndf::ggx(a).unwrap());
            v.push(Ndf::exponential(a).unwrap());
        }
        for &a in &[1e-4, 1e-3, 0.01, 0.05, 0.3] {
            for &p in &[0.0, 0.3, 0.7, 1.0, 1.5] {
                v.push(Ndf::sgd(a, p).unwrap());
            }
        }
        v
    }

    /// ∫₀^∞ P22 dx by log-spaced Gauss panels.
    fn p22_integral(ndf: &Ndf) -> f64 {
        let (lo, hi) = ndf.x_range();
        let rule = GaussRule::new(12);
        let (a, b) = ((lo * 1e-12).ln(), hi.ln());
        let panels = ((b - a) / 0.5).ceil() as usize;
        let head = lo * 1e-12 * ndf.p22(0.0); // P22 is flat below x_lo
        head + rule.integrate(a, b, panels, |v| {
            let x = v.exp();
            ndf.p22(x) * x
        })
    }

    #[test]
    fn d_cos_integrates_to_one() {
        // GGX's power tail (D cos ~ 1/π at grazing) converges in θ; the rest is resolved by the
        // geometric panels down to 1e-7 rad.
        let mut worst = 0.0f64;
        for ndf in all_params() {
            let v = integrate_sphere(|h| ndf.d(h.z) * h.z.max(0.0), DVec3::Z, &fine());
            worst = worst.max((v - 1.0).abs());
            assert!((v - 1.0).abs() < 1e-6, "{}: ∫D cos = {v}", ndf.name());
            let px = p22_integral(&ndf);
            assert!((px - 1.0).abs() < 1e-8, "{}: ∫P22 = {px}", ndf.name());
        }
        println!("worst |∫D cos dω − 1| = {worst:.3e}");
    }

    #[test]
    fn normalization_004_is_inconsistent() {
        // 004 asks for ∫P22 dx = 1/π *and* D = P22/(π cos⁴θ). Take the SGD's P22 scaled so that
        // its integral is 1/π: then ∫D cos dω = 1/π, not 1. So one of the two must go; we keep
        // D = P22/(π cos⁴) and ∫P22 = 1 (what the published kap = 1/(αΓ(1−p,α)) means).
        for ndf in [Ndf::sgd(0.05, 0.5).unwrap(), Ndf::beckmann(0.2).unwrap()] {
            let p22_paper = |x: f64| ndf.p22(x) / PI;
            assert!((p22_integral(&ndf) / PI - 1.0 / PI).abs() < 1e-9);
            let v = integrate_sphere(
                |h| {
                    if h.z <= 0.0 {
                        return 0.0;
                    }
                    let c2 = h.z * h.z;
                    p22_paper((1.0 - c2) / c2) / (PI * c2 * c2) * h.z
                },
                DVec3::Z,
                &fine(),
            );
            assert!((v - 1.0 / PI).abs() < 1e-7, "{v}");
            assert!((v - 1.0).abs() > 0.6);
        }
        // And the paper's written form of the SGD P22 is ours (it integrates to 1, not 1/π).
        let (a, p) = (0.02f64, 0.8f64);
        let ndf = Ndf::sgd(a, p).unwrap();
        for &x in &[0.0, 1e-4, 0.01, 0.3] {
            let paper = a.powf(p - 1.0) / upper_gamma(1.0 - p, a) * (-(a * a + x) / a).exp()
                / (a * a + x).powf(p);
            assert!((paper - ndf.p22(x)).abs() < 1e-10 * paper, "{x}");
        }
    }

    #[test]
    fn known_values() {
        let b = Ndf::beckmann(0.5).unwrap();
        // D(0) = 1/(π α²).
        assert!((b.d(1.0) - 1.0 / (PI * 0.25)).abs() < 1e-12);
        let c = 0.8f64;
        let t2 = (1.0 - c * c) / (c * c);
        let want = (-t2 / 0.25).exp() / (PI * 0.25 * c.powi(4));
        assert!((b.d(c) - want).abs() < 1e-12 * want);
        let g = Ndf::ggx(0.3).unwrap();
        let want = 0.09 / (PI * c.powi(4) * (0.09 + t2).powi(2));
        assert!((g.d(c) - want).abs() < 1e-12 * want);
        // GGX at grazing: 1/(π α²)·α⁴/α⁴ … = α²/π·1/s⁴ with s = 1.
        assert!((g.d(1e-300) - 0.09 / PI).abs() < 1e-12);
        // SGD with p = 0 is Beckmann with α_B² = α.
        let s = Ndf::sgd(0.04, 0.0).unwrap();
        let bb = Ndf::beckmann(0.2).unwrap();
        for &c in &[1.0, 0.99, 0.9, 0.5] {
            assert!((s.d(c) - bb.d(c)).abs() < 1e-10 * bb.d(c), "{c}");
        }
        assert_eq!(b.d(0.0), 0.0);
        assert_eq!(b.d(-0.3), 0.0);
    }

    #[test]
    fn constructors_validate() {
        assert!(Ndf::beckmann(0.0).is_err());
        assert!(Ndf::ggx(-1.0).is_err());
        assert!(Ndf::exponential(f64::NAN).is_err());
        assert!(Ndf::sgd(f64::INFINITY, 0.5).is_err());
        assert!(Ndf::sgd(0.1, f64::NAN).is_err());
        assert!(Ndf::sgd(0.1, 10.0).is_err());
        assert!(Ndf::sgd_with_kap(0.1, 0.5, 0.0).is_err());
        assert!(Ndf::sgd(1e-4, 1.5).is_ok());
    }

    #[test]
    fn sgd_proxy_matches_median() {
        for &(a, p) in &[(1e-4, 1.5), (0.01, 0.5), (0.3, 0.0), (0.05, 1.2)] {
            let Ndf::Sgd(s) = Ndf::sgd(a, p).unwrap() else {
                unreachable!()
            };
            let x = s.proxy_alpha() * s.proxy_alpha();
            let ndf = Ndf::Sgd(s);
            // Exact up to the half-precision rounding of α_proxy (relative 4.9e-4).
            assert!(
                (ndf.cdf_x(x) - 0.5).abs() < 1e-3,
                "{a} {p}: {}",
                ndf.cdf_x(x)
            );
            // GGX's median is α²: half of the proxy's samples fall below it.
            assert!((Ndf::ggx(s.proxy_alpha()).unwrap().cdf_x(x) - 0.5).abs() < 1e-12);
        }
    }

    /// Chi-square of cdf(x) of the samples against uniformity, 64 bins.
    fn chi2_uniform(values: &[f64]) -> f64 {
        let bins = 64;
        let mut h = vec![0.0f64; bins];
        for &v in values {
            h[((v * bins as f64) as usize).min(bins - 1)] += 1.0;
        }
        let e = values.len() as f64 / bins as f64;
        h.iter().map(|o| (o - e) * (o - e) / e).sum()
    }

    #[test]
    fn samplers_follow_their_cdf() {
        // 63 dof: the 1e-4 quantile of chi2(63) is about 117.
        let mut rng = SplitMix64::new(7);
        for ndf in all_params() {
            let n = 20_000;
            let mut xs = Vec::with_capacity(n);
            let mut phis = Vec::with_capacity(n);
            let cdf_ref = match ndf {
                Ndf::Sgd(s) => Ndf::Ggx {
                    alpha: s.proxy_alpha(),
                },
                o => o,
            };
            for _ in 0..n {
                let h = ndf.sample_h(rng.next_f64(), rng.next_f64());
                assert!((h.length() - 1.0).abs() < 1e-12 && h.z > 0.0);
                let x = (h.x * h.x + h.y * h.y) / (h.z * h.z);
                xs.push(cdf_ref.cdf_x(x));
                phis.push((h.y.atan2(h.x) + PI) / (2.0 * PI));
                // Sampled density agrees with pdf_h.
                let want = cdf_ref.d(h.z) * h.z;
                assert!((ndf.pdf_h(h) - want).abs() <= 1e-12 * want);
            }
            let c = chi2_uniform(&xs);
            assert!(c < 117.0, "{}: chi2 of x = {c}", ndf.name());
            let c = chi2_uniform(&phis);
            assert!(c < 117.0, "{}: chi2 of φ = {c}", ndf.name());
        }
    }

    #[test]
    fn pdf_h_integrates_to_one() {
        for ndf in [
            Ndf::sgd(1e-3, 1.2).unwrap(),
            Ndf::exponential(0.05).unwrap(),
        ] {
            let v = integrate_sphere(|h| ndf.pdf_h(h), DVec3::Z, &fine());
            assert!((v - 1.0).abs() < 1e-6, "{}: {v}", ndf.name());
        }
    }

    #[test]
    fn exponential_inverse_cdf() {
        let e = Ndf::exponential(1.0).unwrap();
        for &xi in &[1e-12, 1e-6, 0.01, 0.3, 0.5, 0.9, 0.999_999, 1.0 - 1e-15] {
            let u = invert_exponential_cdf(xi);
            let back = e.cdf_x(u * u);
            assert!((back - xi).abs() < 1e-12 * xi.max(1e-3), "{xi}: {back}");
        }
    }

    /// E[w²] of the importance weight w = P22_sgd/P22_ggx under the GGX proxy (1 is perfect).
    fn weight_second_moment(ndf: &Ndf, proxy_alpha: f64) -> f64 {
        let g = Ndf::Ggx { alpha: proxy_alpha };
        let (lo, hi) = ndf.x_range();
        let rule = GaussRule::new(12);
        let (a, b) = ((lo.min(proxy_alpha * proxy_alpha) * 1e-12).ln(), hi.ln());
        let panels = ((b - a) / 0.5).ceil() as usize;
        rule.integrate(a, b, panels, |v| {
            let x = v.exp();
            let p = ndf.p22(x);
            p * p / g.p22(x) * x
        })
    }

    #[test]
    fn median_proxy_beats_same_alpha_proxy() {
        // Published (α, p) of MERL materials (green channel): alum-bronze, aventurnine, brass,
        // gold-paint, pvc, teflon.
        let mats = [
            (0.0300126, 0.450056),
            (0.000856166, 0.504525),
            (2.5847e-4, 0.4016),
            (0.10807, 0.6376),
            (0.017668, 0.7306),
            (0.66217, 1.1413),
        ];
        for (a, p) in mats {
            let ndf = Ndf::sgd(a, p).unwrap();
            let Ndf::Sgd(s) = ndf else { unreachable!() };
            let ours = weight_second_moment(&ndf, s.proxy_alpha());
            let paper = weight_second_moment(&ndf, a);
            println!("SGD α={a} p={p}: proxy α {:.4e}; E[w²] median proxy {ours:.3}, paper's (α_ggx = α) {paper:.3}", s.proxy_alpha());
            assert!(ours.is_finite() && ours >= 1.0 - 1e-6);
            assert!(ours < paper, "α={a} p={p}");
        }
    }
}
