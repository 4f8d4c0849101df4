//! The Ward-Dür BRDF (Dür 2006): Ward's lobe with the normalization 1/(cosθi cosθo) instead of
//! 1/√(cosθi cosθo), 004 §III.4.4.4 second equation:
//!
//! f = ρd/π + ρs · exp(−tan²θh (cos²φh/α² + sin²φh/β²)) / (4παβ cosθi cosθo).
//!
//! Reciprocal, but its albedo still exceeds 1 at grazing angles for some parameters (Neumann 1999;
//! measured in the tests). Sampling as in [`crate::models::ward`] (Walter 2005).

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample};
use crate::error::Result;
use crate::models::ward::{WardCore, WardKind};
use crate::rgb::Rgb;
use glam::DVec3;

/// The Ward-Dür anisotropic BRDF (α along the tangent +x, β along +y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WardDuer {
    core: WardCore,
}

impl WardDuer {
    /// A Ward-Dür BRDF: diffuse albedo `rho_d` (channels in [0, 1]), specular weight `rho_s`
    /// (in [0, 100]), roughness `alpha` along the tangent, `beta` along the bitangent ([1e-4, 10]).
    pub fn new(rho_d: Rgb, rho_s: Rgb, alpha: f64, beta: f64) -> Result<Self> {
        Ok(WardDuer {
            core: WardCore::new(WardKind::Duer, rho_d, rho_s, alpha, beta)?,
        })
    }

    /// The isotropic case α = β.
    pub fn isotropic(rho_d: Rgb, rho_s: Rgb, alpha: f64) -> Result<Self> {
        Self::new(rho_d, rho_s, alpha, alpha)
    }

    /// The specular lobe alone, without ρs (1/sr).
    pub fn specular_lobe(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.core.specular(wi, wo)
    }
}

impl Bsdf for WardDuer {
    fn name(&self) -> String {
        format!(
            "ward-duer(alpha={}, beta={})",
            self.core.alpha, self.core.beta
        )
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        self.core.eval(wi, wo)
    }
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        self.core.sample(wo, u1, u2)
    }
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.core.pdf(wi, wo)
    }
    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            reciprocal: true,
            energy_conserving: false,
            transmission: false,
            anisotropic: self.core.anisotropic(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use std::f64::consts::PI;

    #[test]
    fn known_value_and_ratio_to_ward() {
        // Away from the normal the two lobes differ by exactly √(cosθi cosθo).
        let d = WardDuer::new(Rgb::ZERO, Rgb::ONE, 0.2, 0.3).expect("valid");
        let w = crate::models::ward::Ward::new(Rgb::ZERO, Rgb::ONE, 0.2, 0.3).expect("valid");
        let wi = spherical(0.7, 0.4);
        let wo = spherical(0.9, -2.5);
        let r = w.specular_lobe(wi, wo) / d.specular_lobe(wi, wo);
        assert!((r - (wi.z * wo.z).sqrt()).abs() < 1e-12);
        let f = d.eval(DVec3::Z, DVec3::Z)[0];
        assert!((f - 1.0 / (4.0 * PI * 0.06)).abs() < 1e-12);
    }
}
