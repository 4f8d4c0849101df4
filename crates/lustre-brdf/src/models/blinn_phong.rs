//! The Blinn-Phong BRDF as written in 004 §III.4.4.4.1:
//!
//! f(L, V) = ρd/π + ρs (n + 2)/(2π) (H·N)ⁿ.
//!
//! The factor (n + 2)/(2π) normalizes the lobe over the *half vector* with an extra cos θh, not
//! over ωi: at normal incidence the specular albedo tends to 4ρs as n grows (ωi turns twice as
//! fast as h, dωi = 4 (ωo·h) dωh), so the model is **not** energy conserving in general. The flag
//! promises energy conservation only when ρs = 0 and ρd ≤ 1; the tests demonstrate the violation.
//! One-sided: zero unless both directions lie above the surface.
//!
//! Sampling mixes cosine sampling (luminance of ρd) with h ∝ cosⁿθh reflected about ωo (luminance
//! of ρs), p(ωi) = (n + 1)/(2π) cosⁿθh / (4 ωo·h).

use crate::bsdf::{
    diffuse_mixture_pdf, finish_sample, sample_diffuse_mixture, Bsdf, BsdfFlags, BsdfSample,
    LobeFlags,
};
use crate::error::Result;
use crate::frame::{half_vector, reflect};
use crate::models::phong::{both_above, check_params, weights};
use crate::rgb::Rgb;
use crate::sampling::{cosine_power, cosine_power_pdf};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Blinn-Phong with the (n + 2)/(2π) factor of 004.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlinnPhong {
    /// Diffuse albedo ρd (finite, ≥ 0).
    pub rho_d: Rgb,
    /// Specular coefficient ρs (finite, ≥ 0).
    pub rho_s: Rgb,
    /// Exponent n in [0, [`MAX_EXPONENT`](crate::models::phong::MAX_EXPONENT)].
    pub n: f64,
}

impl BlinnPhong {
    /// A validated model (channels finite and ≥ 0, n in [0, [`MAX_EXPONENT`](crate::models::phong::MAX_EXPONENT)]).
    pub fn new(rho_d: Rgb, rho_s: Rgb, n: f64) -> Result<Self> {
        check_params(rho_d, rho_s, n)?;
        Ok(BlinnPhong { rho_d, rho_s, n })
    }
}

impl Bsdf for BlinnPhong {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("Blinn-Phong (n = {})", self.n)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !both_above(wi, wo) {
            return Rgb::ZERO;
        }
        let Some(h) = half_vector(wi, wo) else {
            return self.rho_d / PI;
        };
        let lobe = (self.n + 2.0) / (2.0 * PI) * h.z.max(0.0).powf(self.n);
        self.rho_d / PI + self.rho_s * lobe
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let (wi, kind) =
            sample_diffuse_mixture(&weights(self.rho_d, self.rho_s), u1, u2, |_, u1, u2| {
                let h = cosine_power(u1, u2, self.n);
                (wo.dot(h) > 0.0).then(|| reflect(wo, h))
            })?;
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        finish_sample(wi, wo, self.pdf(wi, wo), kind, || self.eval(wi, wo))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !both_above(wi, wo) {
            return 0.0;
        }
        diffuse_mixture_pdf(
            &weights(self.rho_d, self.rho_s),
            wi,
            |_| match half_vector(wi, wo) {
                Some(h) if wo.dot(h) > 0.0 => cosine_power_pdf(h.z, self.n) / (4.0 * wo.dot(h)),
                _ => 0.0,
            },
        )
    }

    /// Reciprocal; energy conserving only when ρs = 0 and ρd ≤ 1 (see the module notes).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(
            true,
            self.rho_s.max_component() == 0.0 && self.rho_d.max_component() <= 1.0,
        )
        .with_lobes(LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use crate::numeric::SphereQuadrature;
    use crate::validate::albedo_quadrature;

    #[test]
    fn known_values() {
        let b = BlinnPhong::new(Rgb::splat(0.1), Rgb::splat(0.5), 30.0).expect("valid");
        let wo = spherical(0.6, 0.2);
        // Mirror configuration: H = N.
        let wi = DVec3::new(-wo.x, -wo.y, wo.z);
        assert!((b.eval(wi, wo)[0] - (0.1 / PI + 0.5 * 32.0 / (2.0 * PI))).abs() < 1e-12);
        // ωi = ωo at θ = 0.6: H = ωo, H·N = cos 0.6.
        let want = 0.1 / PI + 0.5 * 32.0 / (2.0 * PI) * 0.6f64.cos().powf(30.0);
        assert!((b.eval(wo, wo)[1] - want).abs() < 1e-12);
    }

    #[test]
    fn violates_energy_conservation_for_bright_sharp_lobes() {
        // ρs = 0.95, n = 1000: the normal-incidence albedo is close to 4ρs, far above 1.
        let b = BlinnPhong::new(Rgb::ZERO, Rgb::splat(0.95), 1000.0).expect("valid");
        assert!(!b.flags().energy_conserving);
        let q = SphereQuadrature {
            phi_points: 64,
            uniform_panels: 24,
            ..Default::default()
        };
        let a = albedo_quadrature(&b, DVec3::Z, &q)[0];
        // Asymptotically 4ρs (n+2)/(n+1+…): check it is above 3.7.
        assert!(a > 3.7 && a < 4.0 * 0.95, "{a}");
        assert!(
            !BlinnPhong::new(Rgb::ZERO, Rgb::splat(0.01), 2.0)
                .expect("valid")
                .flags()
                .energy_conserving
        );
        assert!(
            BlinnPhong::new(Rgb::splat(0.9), Rgb::ZERO, 2.0)
                .expect("valid")
                .flags()
                .energy_conserving
        );
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(BlinnPhong::new(Rgb::ZERO, Rgb::ONE, -0.5).is_err());
        assert!(BlinnPhong::new(Rgb::ZERO, Rgb::ONE, f64::INFINITY).is_err());
        assert!(BlinnPhong::new(Rgb::new(-1.0, 0.0, 0.0), Rgb::ONE, 1.0).is_err());
    }
}
