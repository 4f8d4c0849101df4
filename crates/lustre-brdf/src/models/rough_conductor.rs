//! Rough conductor (Mitsuba 3's `roughconductor`): the microfacet BRDF of a metal,
//!
//! ```text
//! f(wi, wo) = F(wi·h) D(h) G1(wi, h) G1(wo, h) / (4 cos θi cos θo) · specular_reflectance
//! ```
//!
//! (Walter et al. 2007, Eq. 20) with an anisotropic GGX or Beckmann D, separable Smith G and the
//! complex Fresnel term of the RGB index η + ik. Sampling draws a visible normal of D from `wo`
//! ([`MicrofacetDistribution::sample_visible`]) and reflects `wo` about it:
//! pdf(wi) = D(h) G1(wo, h) / (4 cos θo). One-sided.

use crate::bsdf::{finish_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Result};
use crate::frame::reflect;
use crate::microfacet::distribution::MicrofacetDistribution;
use crate::models::conductor::ComplexIor;
use crate::rgb::Rgb;
use glam::DVec3;

/// A rough metal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    /// The microfacet distribution (type, αu, αv).
    pub distribution: MicrofacetDistribution,
    /// The metal's complex index.
    pub ior: ComplexIor,
    /// Tint multiplying the Fresnel term (Mitsuba's `specular_reflectance`).
    pub specular_reflectance: Rgb,
}

impl RoughConductor {
    /// A rough conductor; the tint must lie in [0, 1].
    pub fn new(
        distribution: MicrofacetDistribution,
        ior: ComplexIor,
        specular_reflectance: Rgb,
    ) -> Result<Self> {
        check_rgb("specular_reflectance", specular_reflectance, 0.0, 1.0)?;
        Ok(RoughConductor {
            distribution,
            ior,
            specular_reflectance,
        })
    }
}

impl Bsdf for RoughConductor {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!(
            "roughconductor({}, αu={}, αv={})",
            self.distribution.kind().name(),
            self.distribution.alpha_u(),
            self.distribution.alpha_v()
        )
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Rgb::ZERO;
        }
        let h = (wi + wo).normalize();
        let d = self.distribution.d(h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distribution.g(wi, wo, h);
        // Walter et al. 2007, Eq. 20.
        self.ior.fresnel(wi.dot(h)) * self.specular_reflectance * (d * g / (4.0 * wi.z * wo.z))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        let m = self.distribution.sample_visible(wo, u1, u2)?;
        let wi = reflect(wo, m);
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        finish_sample(wi, wo, self.pdf(wi, wo), LobeFlags::GLOSSY, || {
            self.eval(wi, wo)
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let h = (wi + wo).normalize();
        if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 {
            return 0.0;
        }
        // Visible-normal density divided by the reflection Jacobian 4 (wo·h).
        self.distribution.d(h) * self.distribution.g1(wo, h) / (4.0 * wo.z)
    }

    /// Reciprocal; energy conserving (single scattering loses energy, F ≤ 1, tint ≤ 1).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            anisotropic: self.distribution.is_anisotropic(),
            ..BsdfFlags::isotropic_reflection(true, true)
        }
    }
}
