//! Smooth conductor (Mitsuba 3's `conductor`): a Dirac mirror lobe weighted by the complex
//! Fresnel reflectance of a metal with RGB index η + ik ([`fresnel_conductor`]) and an optional
//! `specular_reflectance` tint. One-sided: black seen from below (wrap it in
//! [`crate::models::two_sided::TwoSided`] for a two-sided surface).
//!
//! Delta convention (see [`crate::bsdf`]): `eval` = `pdf` = 0; `sample` returns the mirror
//! direction with probability 1 and throughput F(cos θo)·tint.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Error, Result};
use crate::microfacet::fresnel::fresnel_conductor;
use crate::models::conductor_presets::conductor_preset;
use crate::rgb::Rgb;
use glam::DVec3;

/// Complex index of refraction per RGB channel, relative to the outside medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ComplexIor {
    /// Real part η (≥ 0).
    pub eta: Rgb,
    /// Extinction coefficient k (≥ 0).
    pub k: Rgb,
}

impl ComplexIor {
    /// Validated η, k: finite, ≥ 0, and not both zero in a channel.
    pub fn new(eta: Rgb, k: Rgb) -> Result<Self> {
        check_rgb("eta", eta, 0.0, 1e6)?;
        check_rgb("k", k, 0.0, 1e6)?;
        for c in 0..3 {
            if eta[c] == 0.0 && k[c] == 0.0 {
                return Err(Error::param("eta", 0.0, "η and k cannot both be 0"));
            }
        }
        Ok(ComplexIor { eta, k })
    }

    /// One of Mitsuba's named materials (see [`conductor_preset`]), e.g. `Au`, or `none`.
    pub fn preset(name: &str) -> Result<Self> {
        let (eta, k) = conductor_preset(name).ok_or_else(|| {
            Error::NotFound(format!(
                "unknown conductor material {name:?} (Mitsuba's names: Ag, Al, Au, Cr, Cu, Hg, \
                 W, …, or none for a perfect mirror)"
            ))
        })?;
        Ok(ComplexIor { eta, k })
    }

    /// Fresnel reflectance per channel at cos θ (incidence from outside).
    pub fn fresnel(&self, cos_theta: f64) -> Rgb {
        Rgb::new(
            fresnel_conductor(cos_theta, self.eta[0], self.k[0]),
            fresnel_conductor(cos_theta, self.eta[1], self.k[1]),
            fresnel_conductor(cos_theta, self.eta[2], self.k[2]),
        )
    }
}

/// A perfectly smooth metal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    /// The metal's complex index.
    pub ior: ComplexIor,
    /// Tint multiplying the Fresnel term (Mitsuba's `specular_reflectance`; 1 for physical
    /// realism).
    pub specular_reflectance: Rgb,
}

impl Conductor {
    /// A smooth conductor with index η + ik and a tint in [0, 1].
    pub fn new(eta: Rgb, k: Rgb, specular_reflectance: Rgb) -> Result<Self> {
        check_rgb("specular_reflectance", specular_reflectance, 0.0, 1.0)?;
        Ok(Conductor {
            ior: ComplexIor::new(eta, k)?,
            specular_reflectance,
        })
    }

    /// A smooth conductor of one of Mitsuba's named materials, untinted.
    pub fn preset(name: &str) -> Result<Self> {
        Ok(Conductor {
            ior: ComplexIor::preset(name)?,
            specular_reflectance: Rgb::ONE,
        })
    }
}

impl Bsdf for Conductor {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        "conductor".to_string()
    }

    fn eval(&self, _wi: DVec3, _wo: DVec3) -> Rgb {
        Rgb::ZERO
    }

    fn sample(&self, wo: DVec3, _u1: f64, _u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let wi = DVec3::new(-wo.x, -wo.y, wo.z);
        let weight = self.ior.fresnel(wo.z) * self.specular_reflectance;
        BsdfSample::delta(wi, weight, 1.0, LobeFlags::SPECULAR_REFLECTION, 1.0)
    }

    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }

    /// Reciprocal (trivially: no density), energy conserving (F ≤ 1, tint ≤ 1), a delta lobe.
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, true).with_lobes(LobeFlags::SPECULAR_REFLECTION)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    #[test]
    fn mirror_with_complex_fresnel() {
        let c = Conductor::preset("Au").unwrap();
        let wo = spherical(0.7, 1.1);
        let s = c.sample(wo, 0.3, 0.9).expect("upper wo");
        assert!(s.is_delta() && s.lobe == LobeFlags::SPECULAR_REFLECTION && s.pdf == 1.0);
        assert!((s.wi - spherical(0.7, 1.1 + std::f64::consts::PI)).length() < 1e-12);
        let f = c.ior.fresnel(wo.z);
        for ch in 0..3 {
            assert!((s.weight()[ch] - f[ch]).abs() < 1e-12);
        }
        // Mitsuba's albedo of gold at normal incidence from its RGB index.
        let (n, k) = (c.ior.eta[0], c.ior.k[0]);
        let r0 = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        let a = c.albedo(DVec3::Z, 16);
        assert!((a[0] - r0).abs() < 1e-12, "{a:?} vs {r0}");
        assert_eq!(c.eval(s.wi, wo), Rgb::ZERO);
        assert_eq!(c.pdf(s.wi, wo), 0.0);
        assert!(c.sample(-wo, 0.3, 0.3).is_none(), "one-sided");
        let mirror = Conductor::preset("none").unwrap();
        assert_eq!(mirror.albedo(spherical(1.4, 0.0), 4), Rgb::ONE);
        assert!(c.flags().has_delta() && c.flags().delta_only() && !c.flags().diffuse_only());
        assert!(Conductor::new(Rgb::ZERO, Rgb::ZERO, Rgb::ONE).is_err());
        assert!(Conductor::new(Rgb::ONE, Rgb::splat(f64::NAN), Rgb::ONE).is_err());
        assert!(Conductor::preset("Unobtainium").is_err());
    }
}
