//! Fresnel terms of the microfacet models: Schlick (004 §III.4.4.4.2), the generalized Schlick of
//! the SGD fits (004 Eq. V.5) and Lazányi's metal approximation (004 §III.4.4.4.2); and the exact
//! unpolarized Fresnel equations of a dielectric interface ([`fresnel_dielectric`]) and of a
//! conductor with a complex index ([`fresnel_conductor`]), as the physically based models
//! (conductor, dielectric, plastic) use them.

use crate::error::{check_range, Result};

/// A Fresnel reflectance as a function of cos θ_d = i·h.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// F = 1 (no Fresnel effect).
    One,
    /// Schlick: F = F0 + (1 − F0)(1 − cos θ)⁵.
    Schlick {
        /// Reflectance at normal incidence.
        f0: f64,
    },
    /// 004 Eq. V.5: F = F0 + (1 − F0)(1 − cos θ)⁵ − F1 cos θ. The published fits store values of
    /// F0 above 1 and negative F1; they are taken as they are.
    GeneralizedSchlick {
        /// F0.
        f0: f64,
        /// F1, the slope of the linear term.
        f1: f64,
    },
    /// Lazányi & Szirmay-Kalos (2005): F = ((n−1)² + 4n(1−cos θ)⁵ + k²)/((n+1)² + k²).
    Lazanyi {
        /// Real part of the refractive index.
        n: f64,
        /// Extinction coefficient.
        k: f64,
    },
}

impl Fresnel {
    /// Schlick with a validated F0 (finite, ≥ 0).
    pub fn schlick(f0: f64) -> Result<Fresnel> {
        Ok(Fresnel::Schlick {
            f0: check_range("f0", f0, 0.0, f64::MAX)?,
        })
    }

    /// Eq. V.5 with finite F0, F1 (any sign, as in the published table).
    pub fn generalized_schlick(f0: f64, f1: f64) -> Result<Fresnel> {
        Ok(Fresnel::GeneralizedSchlick {
            f0: check_range("f0", f0, -f64::MAX, f64::MAX)?,
            f1: check_range("f1", f1, -f64::MAX, f64::MAX)?,
        })
    }

    /// Lazányi with n > 0 and k ≥ 0.
    pub fn lazanyi(n: f64, k: f64) -> Result<Fresnel> {
        Ok(Fresnel::Lazanyi {
            n: check_range("n", n, 1e-6, 1e6)?,
            k: check_range("k", k, 0.0, 1e6)?,
        })
    }

    /// F(cos θ_d); the argument is clamped to [0, 1].
    #[inline]
    pub fn eval(&self, cos_theta_d: f64) -> f64 {
        let c = if cos_theta_d > 0.0 {
            cos_theta_d.min(1.0)
        } else {
            0.0
        };
        let m = 1.0 - c;
        let m5 = (m * m) * (m * m) * m;
        match *self {
            Fresnel::One => 1.0,
            Fresnel::Schlick { f0 } => f0 + (1.0 - f0) * m5,
            Fresnel::GeneralizedSchlick { f0, f1 } => f0 + (1.0 - f0) * m5 - f1 * c,
            Fresnel::Lazanyi { n, k } => {
                let k2 = k * k;
                ((n - 1.0) * (n - 1.0) + 4.0 * n * m5 + k2) / ((n + 1.0) * (n + 1.0) + k2)
            }
        }
    }

    /// (F0, F1) of the same F in the generalized Schlick form (004 Eq. V.5): Schlick is F1 = 0,
    /// one is F0 = 1, F1 = 0; `None` for Lazányi, which has no such form.
    pub fn generalized_schlick_form(&self) -> Option<(f64, f64)> {
        match *self {
            Fresnel::GeneralizedSchlick { f0, f1 } => Some((f0, f1)),
            Fresnel::Schlick { f0 } => Some((f0, 0.0)),
            Fresnel::One => Some((1.0, 0.0)),
            Fresnel::Lazanyi { .. } => None,
        }
    }

    /// An upper bound of F over cos θ ∈ [0, 1] (exact for One, Schlick and Lazányi; for Eq. V.5
    /// the maximum over 4097 points plus the Lipschitz margin (|F1| + 5|1 − F0|)·h/2, so a
    /// guaranteed bound).
    pub fn max_value(&self) -> f64 {
        match *self {
            Fresnel::One => 1.0,
            Fresnel::Schlick { f0 } => f0.max(1.0),
            // The numerator is largest at cos θ = 0, where F = 1.
            Fresnel::Lazanyi { .. } => 1.0,
            Fresnel::GeneralizedSchlick { f0, f1 } => {
                let n = 4096;
                let h = 1.0 / n as f64;
                let m = (0..=n)
                    .map(|i| self.eval(i as f64 * h))
                    .fold(f64::MIN, f64::max);
                m + (f1.abs() + 5.0 * (1.0 - f0).abs()) * h * 0.5
            }
        }
    }
}

/// The unpolarized Fresnel reflectance of a dielectric interface and the refracted cosine
/// (Mitsuba 3's `fresnel`; Born & Wolf Eq. 1.5.21–22 averaged over both polarizations).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricFresnel {
    /// Reflectance R in [0, 1] (1 under total internal reflection).
    pub r: f64,
    /// Cosine of the refracted direction, with the sign opposite to `cos_theta_i` (0 under total
    /// internal reflection).
    pub cos_theta_t: f64,
    /// Relative index along the direction of travel: η(transmitted side)/η(incident side).
    pub eta_it: f64,
    /// Its reciprocal, the factor applied to the tangential components when refracting.
    pub eta_ti: f64,
}

/// Fresnel equations for an interface of relative index `eta` = η_inside/η_outside (the normal
/// +z points outside); `cos_theta_i` < 0 means the incident direction lies inside.
pub fn fresnel_dielectric(cos_theta_i: f64, eta: f64) -> DielectricFresnel {
    let outside = cos_theta_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    // Snell: sin²θt = sin²θi / η_it².
    let cos_t2 = 1.0 - (1.0 - cos_theta_i * cos_theta_i) * eta_ti * eta_ti;
    let ci = cos_theta_i.abs();
    let ct = cos_t2.max(0.0).sqrt();
    let r = if eta == 1.0 {
        0.0
    } else if ci == 0.0 || cos_t2 <= 0.0 {
        1.0
    } else {
        let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
        let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    DielectricFresnel {
        r: r.clamp(0.0, 1.0),
        cos_theta_t: if cos_t2 <= 0.0 {
            0.0
        } else if outside {
            -ct
        } else {
            ct
        },
        eta_it,
        eta_ti,
    }
}

/// Unpolarized reflectance of a conductor with complex relative index η + ik, for incidence from
/// outside (`cos_theta_i` in [0, 1]; Mitsuba 3's `fresnel_conductor`, after Moeller's "Optics").
/// With η = 0, k = 1 it is 1 at every angle (Mitsuba's `none` material, a perfect mirror).
pub fn fresnel_conductor(cos_theta_i: f64, eta: f64, k: f64) -> f64 {
    let c = cos_theta_i.clamp(0.0, 1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let t1 = eta * eta - k * k - s2;
    let a2pb2 = (t1 * t1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
    let a = (0.5 * (a2pb2 + t1)).max(0.0).sqrt();
    let term1 = a2pb2 + c2;
    let term2 = 2.0 * c * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + s4;
    let term4 = term2 * s2;
    let rp = rs * (term3 - term4) / (term3 + term4);
    let f = 0.5 * (rs + rp);
    if f.is_finite() {
        f.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// Hemispherical average 2∫₀¹ R(μ) μ dμ of the dielectric reflectance for light arriving from
/// the side where the relative index is `eta` (η_other/η_this; η < 1: from inside a denser medium,
/// total internal reflection included). Mitsuba uses fitted approximations (Egan & Hilgeman, d'Eon
/// & Irving) for this "diffuse Fresnel reflectance"; we integrate: the total internal reflection
/// cone exactly, the rest by 64-point Gauss-Legendre in s with μ = μc + (1 − μc)s², which removes
/// the square-root edge at the critical cosine μc.
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    // Incident from the outside of an interface of relative index `eta`.
    let mu_c = if eta < 1.0 {
        (1.0 - eta * eta).max(0.0).sqrt()
    } else {
        0.0
    };
    let (x, w) = crate::numeric::gauss_legendre(64);
    let mut sum = mu_c * mu_c; // R = 1 on [0, μc]: 2∫ μ dμ = μc²
    for (xi, wi) in x.iter().zip(&w) {
        let s = 0.5 * (xi + 1.0);
        let mu = mu_c + (1.0 - mu_c) * s * s;
        let jac = 2.0 * (1.0 - mu_c) * s * 0.5;
        sum += wi * jac * 2.0 * mu * fresnel_dielectric(mu, eta).r;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_known_values() {
        let f = Fresnel::schlick(0.04).unwrap();
        assert_eq!(f.eval(1.0), 0.04);
        assert_eq!(f.eval(0.0), 1.0);
        // cos 60° = 0.5: 0.04 + 0.96/32.
        assert!((f.eval(0.5) - (0.04 + 0.96 / 32.0)).abs() < 1e-15);
        // Clamped arguments.
        assert_eq!(f.eval(-0.3), 1.0);
        assert_eq!(f.eval(1.7), 0.04);
        assert_eq!(Fresnel::One.eval(0.3), 1.0);
    }

    #[test]
    fn generalized_reduces_to_schlick() {
        let g = Fresnel::generalized_schlick(0.3, 0.0).unwrap();
        let s = Fresnel::schlick(0.3).unwrap();
        for i in 0..=20 {
            let c = i as f64 / 20.0;
            assert_eq!(g.eval(c), s.eval(c));
        }
        // With F1: F(1) = F0 − F1, F(0) = 1.
        let g = Fresnel::generalized_schlick(0.8, 0.2).unwrap();
        assert!((g.eval(1.0) - 0.6).abs() < 1e-15);
        assert_eq!(g.eval(0.0), 1.0);
        // Hand value at c = 0.3: 0.8 + 0.2·0.7⁵ − 0.06.
        assert!((g.eval(0.3) - (0.8 + 0.2 * 0.7f64.powi(5) - 0.06)).abs() < 1e-15);
    }

    #[test]
    fn lazanyi_with_k0_is_schlick() {
        for &n in &[1.2, 1.5, 2.4, 0.6] {
            let l = Fresnel::lazanyi(n, 0.0).unwrap();
            let f0 = ((n - 1.0) / (n + 1.0)).powi(2);
            let s = Fresnel::schlick(f0).unwrap();
            for i in 0..=20 {
                let c = i as f64 / 20.0;
                assert!((l.eval(c) - s.eval(c)).abs() < 1e-14, "n={n} c={c}");
            }
        }
        // Gold-like n = 0.2, k = 3.4: at normal incidence ((0.8)² + k²)/((1.2)² + k²).
        let l = Fresnel::lazanyi(0.2, 3.4).unwrap();
        let want = (0.64 + 11.56) / (1.44 + 11.56);
        assert!((l.eval(1.0) - want).abs() < 1e-14);
        assert!((l.eval(0.0) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn dielectric_and_conductor_known_values() {
        // Normal incidence: ((η−1)/(η+1))², from either side; grazing: 1.
        let f = fresnel_dielectric(1.0, 1.5);
        assert!((f.r - 0.04).abs() < 1e-15 && (f.cos_theta_t + 1.0).abs() < 1e-15);
        assert!((fresnel_dielectric(-1.0, 1.5).r - 0.04).abs() < 1e-15);
        assert_eq!(fresnel_dielectric(0.0, 1.5).r, 1.0);
        // Brewster angle tan θB = η: the p amplitude vanishes, R = a_s²/2.
        let cb = (1.0f64 / (1.0 + 1.5 * 1.5)).sqrt();
        let f = fresnel_dielectric(cb, 1.5);
        let ct = -f.cos_theta_t;
        let a_s = (cb - 1.5 * ct) / (cb + 1.5 * ct);
        assert!((f.r - 0.5 * a_s * a_s).abs() < 1e-15);
        // Snell: η sinθt = sinθi.
        let ci: f64 = 0.6;
        let f = fresnel_dielectric(ci, 1.33);
        let (si, st) = ((1.0 - ci * ci).sqrt(), (1.0 - f.cos_theta_t.powi(2)).sqrt());
        assert!((1.33 * st - si).abs() < 1e-14);
        // Total internal reflection from inside beyond the critical angle (sin θc = 1/1.5).
        assert_eq!(fresnel_dielectric(-0.5, 1.5).r, 1.0);
        assert!(fresnel_dielectric(-0.9, 1.5).r < 1.0);
        // Conductor: k = 0 reduces to the dielectric, normal incidence ((η−1)² + k²)/((η+1)² + k²).
        for &c in &[0.05, 0.3, 0.7, 1.0] {
            let d = fresnel_dielectric(c, 1.7).r;
            assert!((fresnel_conductor(c, 1.7, 0.0) - d).abs() < 1e-12, "c={c}");
        }
        let (n, k) = (0.143036, 3.982997);
        let want = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
        assert!((fresnel_conductor(1.0, n, k) - want).abs() < 1e-14);
        assert!((fresnel_conductor(0.0, n, k) - 1.0).abs() < 1e-12);
        for i in 0..=20 {
            assert_eq!(fresnel_conductor(i as f64 / 20.0, 0.0, 1.0), 1.0);
        }
    }

    #[test]
    fn diffuse_reflectance_matches_mitsubas_fits_and_reciprocity() {
        // Mitsuba 3's fits (d'Eon & Irving for η ≥ 1, Egan & Hilgeman for η < 1; 0.1 % accurate
        // for η in [1, 2]).
        for &eta in &[1.33f64, 1.5, 1.8] {
            let inv = 1.0 / eta;
            let fit_ext = 0.919317 - 3.4793 * inv + 6.75335 * inv.powi(2) - 7.80989 * inv.powi(3)
                + 4.98554 * inv.powi(4)
                - 1.36881 * inv.powi(5);
            let e = 1.0 / eta;
            let fit_int = 0.0636 / e + e * (e * -1.4399 + 0.7099) + 0.6681;
            let ext = fresnel_diffuse_reflectance(eta);
            let int = fresnel_diffuse_reflectance(1.0 / eta);
            assert!(
                (ext - fit_ext).abs() < 2e-3 * fit_ext,
                "η={eta}: {ext} vs {fit_ext}"
            );
            assert!(
                (int - fit_int).abs() < 5e-3 * fit_int,
                "η={eta}: {int} vs {fit_int}"
            );
            // Energy balance of a smooth interface: η²(1 − Fdr_int) = 1 − Fdr_ext.
            assert!(
                ((eta * eta) * (1.0 - int) - (1.0 - ext)).abs() < 1e-10,
                "η={eta}"
            );
        }
    }

    #[test]
    fn max_value_bounds_the_curve() {
        for f in [
            Fresnel::One,
            Fresnel::schlick(0.5).unwrap(),
            Fresnel::generalized_schlick(6.05524, 5.05524).unwrap(),
            Fresnel::generalized_schlick(0.0300766, -0.713784).unwrap(),
            Fresnel::lazanyi(0.2, 3.4).unwrap(),
        ] {
            let m = f.max_value();
            for i in 0..=10_000 {
                assert!(f.eval(i as f64 / 10_000.0) <= m + 1e-15, "{f:?}");
            }
            assert!(m < 1.0 + f.eval(1.0).abs() + 8.0);
        }
        assert!(Fresnel::schlick(-0.1).is_err());
        assert!(Fresnel::lazanyi(0.0, 1.0).is_err());
        assert!(Fresnel::generalized_schlick(f64::NAN, 0.0).is_err());
    }
}
