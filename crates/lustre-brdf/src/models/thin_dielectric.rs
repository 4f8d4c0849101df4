//! Thin dielectric sheet (Mitsuba 3's `thindielectric`): a pane of glass of negligible
//! thickness. Light is reflected with R' = R + T²R/(1 − R²) = 2R/(1 + R) (the series of internal
//! reflections r + t r t + t r³ t + …, R = Fresnel at |cos θo|) and otherwise passes straight
//! through (wi = −wo: the two refractions cancel), with no radiance scaling (η = 1 on both
//! sides). Both lobes are Dirac; the same from either side.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Result};
use crate::microfacet::fresnel::fresnel_dielectric;
use crate::models::dielectric::relative_ior;
use crate::rgb::Rgb;
use glam::DVec3;

/// A thin glass sheet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric {
    /// η = int_ior/ext_ior of the sheet's material.
    pub eta: f64,
    /// Tint of the reflection.
    pub specular_reflectance: Rgb,
    /// Tint of the transmission.
    pub specular_transmittance: Rgb,
}

impl ThinDielectric {
    /// An untinted sheet of index `int_ior` in a medium of index `ext_ior`.
    pub fn new(int_ior: f64, ext_ior: f64) -> Result<Self> {
        Ok(ThinDielectric {
            eta: relative_ior(int_ior, ext_ior)?,
            specular_reflectance: Rgb::ONE,
            specular_transmittance: Rgb::ONE,
        })
    }

    /// The same sheet with tints in [0, 1].
    pub fn with_tints(self, reflectance: Rgb, transmittance: Rgb) -> Result<Self> {
        check_rgb("specular_reflectance", reflectance, 0.0, 1.0)?;
        check_rgb("specular_transmittance", transmittance, 0.0, 1.0)?;
        Ok(ThinDielectric {
            specular_reflectance: reflectance,
            specular_transmittance: transmittance,
            ..self
        })
    }

    /// The sheet's total reflectance 2R/(1 + R) at |cos θ|.
    pub fn reflectance(&self, cos_theta: f64) -> f64 {
        let r = fresnel_dielectric(cos_theta.abs(), self.eta).r;
        if r < 1.0 {
            2.0 * r / (1.0 + r)
        } else {
            1.0
        }
    }
}

impl Bsdf for ThinDielectric {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("thindielectric(η={})", self.eta)
    }

    fn eval(&self, _wi: DVec3, _wo: DVec3) -> Rgb {
        Rgb::ZERO
    }

    fn sample(&self, wo: DVec3, u1: f64, _u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        if u1 < r {
            let wi = DVec3::new(-wo.x, -wo.y, wo.z);
            BsdfSample::delta(
                wi,
                self.specular_reflectance,
                r,
                LobeFlags::SPECULAR_REFLECTION,
                1.0,
            )
        } else {
            BsdfSample::delta(
                -wo,
                self.specular_transmittance,
                1.0 - r,
                LobeFlags::SPECULAR_TRANSMISSION,
                1.0,
            )
        }
    }

    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }

    /// Reciprocal (no radiance scaling, no density); energy conserving (R' + T' = 1).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, true)
            .with_lobes(LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION)
    }
}
