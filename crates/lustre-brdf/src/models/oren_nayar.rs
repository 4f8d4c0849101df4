//! The qualitative Oren-Nayar model (Oren & Nayar 1994) as written in 004 §III.4.4.4.2:
//!
//! f = ρ/π (A + B max(0, cos(φo − φi)) sin α tan β), α = max(θi, θo), β = min(θi, θo),
//! A = 1 − 0.5 σ²/(σ² + 0.33), B = 0.45 σ²/(σ² + 0.09), σ the facet slope deviation in radians.
//!
//! Evaluated without angles: cos(Δφ) sin α sin β = (ωi·ωo)_xy (the tangential dot product) and
//! cos β = max(cos θi, cos θo), so the term is B max(0, (ωi·ωo)_xy)/max(cos θi, cos θo) — finite
//! at grazing. Symmetric in ωi, ωo, hence reciprocal. σ = 0 is Lambert. Cosine-sampled.
//! One-sided: zero unless both directions lie above the surface.

use crate::bsdf::{cosine_pdf, cosine_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_range, check_rgb, Result};
use crate::rgb::Rgb;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Qualitative Oren-Nayar.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OrenNayar {
    /// Facet albedo ρ (finite, ≥ 0).
    pub rho: Rgb,
    /// Slope standard deviation σ in radians, in [0, π/2].
    pub sigma: f64,
}

impl OrenNayar {
    /// A validated model (ρ finite and ≥ 0, σ in [0, π/2]).
    pub fn new(rho: Rgb, sigma: f64) -> Result<Self> {
        check_rgb("rho", rho, 0.0, crate::error::MAX_REFLECTANCE)?;
        check_range("sigma", sigma, 0.0, FRAC_PI_2)?;
        Ok(OrenNayar { rho, sigma })
    }

    /// The coefficients (A, B).
    pub fn coefficients(&self) -> (f64, f64) {
        let s2 = self.sigma * self.sigma;
        (1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09))
    }

    /// The largest directional albedo over all incidences, ρ·(A + B/2) per channel.
    ///
    /// The albedo is ρ(A + B·K(θo)) with K(θo) = (1/π)∫ max(0, cos Δφ) sin α tan β cos θi dωi,
    /// which grows monotonically from 0 at normal incidence to 1/2 at grazing (K(π/2) = (1/π)·2·π/4;
    /// the monotonicity is measured in the tests). For small σ, B/2 ≈ 2.5σ² exceeds 1 − A ≈ 1.5σ²,
    /// so the qualitative model reflects more than ρ at grazing (at most 1.01518ρ, at σ ≈ 0.1985).
    pub fn max_albedo(&self) -> Rgb {
        let (a, b) = self.coefficients();
        self.rho * (a + 0.5 * b)
    }
}

impl Bsdf for OrenNayar {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("Oren-Nayar (σ = {})", self.sigma)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Rgb::ZERO;
        }
        let (a, b) = self.coefficients();
        let tangential = (wi.x * wo.x + wi.y * wo.y).max(0.0);
        self.rho / PI * (a + b * tangential / wi.z.max(wo.z))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        cosine_sample(self, wo, u1, u2, LobeFlags::DIFFUSE)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        cosine_pdf(wi, wo)
    }

    /// Reciprocal; energy conserving when [`OrenNayar::max_albedo`] ≤ 1 in every channel (not
    /// merely ρ ≤ 1: see there).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, self.max_albedo().max_component() <= 1.0)
            .with_lobes(LobeFlags::DIFFUSE_REFLECTION)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use crate::models::lambert::Lambert;

    #[test]
    fn sigma_zero_is_lambert() {
        let on = OrenNayar::new(Rgb::new(0.2, 0.4, 0.8), 0.0).expect("valid");
        let l = Lambert::new(Rgb::new(0.2, 0.4, 0.8)).expect("valid");
        for (wi, wo) in [
            (spherical(0.3, 0.0), spherical(1.2, 0.4)),
            (DVec3::Z, spherical(1.5, 2.0)),
        ] {
            assert!((on.eval(wi, wo) - l.eval(wi, wo)).max_component().abs() < 1e-15);
        }
    }

    #[test]
    fn known_value_by_angles() {
        // θi = 60°, θo = 30°, φi − φo = 40°: α = 60°, β = 30°.
        let on = OrenNayar::new(Rgb::ONE, 0.4).expect("valid");
        let (a, b) = (
            1.0 - 0.5 * 0.16 / (0.16 + 0.33),
            0.45 * 0.16 / (0.16 + 0.09),
        );
        let want = (a + b
            * 40f64.to_radians().cos()
            * 60f64.to_radians().sin()
            * 30f64.to_radians().tan())
            / PI;
        let got = on.eval(
            spherical(60f64.to_radians(), 0.5 + 40f64.to_radians()),
            spherical(30f64.to_radians(), 0.5),
        )[0];
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // Back-scattering exceeds forward scattering.
        let wo = spherical(1.0, 0.0);
        assert!(on.eval(wo, wo)[0] > on.eval(spherical(1.0, PI), wo)[0]);
    }

    #[test]
    fn grazing_albedo_exceeds_rho_for_moderate_sigma() {
        use crate::numeric::{integrate_sphere, SphereQuadrature};
        let q = SphereQuadrature {
            theta_split: FRAC_PI_2,
            phi_points: 256,
            ..Default::default()
        };
        let on = OrenNayar::new(Rgb::ONE, 0.2).expect("valid");
        assert!(!on.flags().energy_conserving);
        let wo = spherical(FRAC_PI_2 - 1e-7, 0.3);
        let a = integrate_sphere(|wi| on.eval(wi, wo)[0] * wi.z.max(0.0), DVec3::Z, &q);
        let bound = on.max_albedo()[0];
        assert!(a > 1.015 && (a - bound).abs() < 1e-5, "{a} vs {bound}");
        // Scaled below 1/max_albedo it is conserving again.
        let ok = OrenNayar::new(Rgb::splat(0.98), 0.2).expect("valid");
        assert!(ok.flags().energy_conserving);
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(OrenNayar::new(Rgb::ONE, -0.1).is_err());
        assert!(OrenNayar::new(Rgb::ONE, f64::NAN).is_err());
        assert!(OrenNayar::new(Rgb::ONE, 2.0).is_err());
        assert!(OrenNayar::new(Rgb::new(0.0, -0.2, 0.0), 0.1).is_err());
    }
}
