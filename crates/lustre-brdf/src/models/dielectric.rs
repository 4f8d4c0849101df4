//! Smooth dielectric interface (Mitsuba 3's `dielectric`): Dirac reflection and refraction with
//! the exact Fresnel reflectance ([`fresnel_dielectric`]), η = int_ior/ext_ior (the normal +z
//! points to the exterior; `wo` below the surface means the viewer is inside).
//!
//! `sample` picks reflection with probability R and refraction with 1 − R (so each sample's
//! throughput is the tint alone, times 1/η² for refraction). Radiance scaling: a refracted sample
//! carries 1/η_it² with η_it = η(wi side)/η(wo side), reported in [`BsdfSample::eta`]; the energy
//! flux R + T = 1 exactly (`weight·η²` summed over both lobes). `eval` = `pdf` = 0.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_range, check_rgb, Error, Result};
use crate::microfacet::fresnel::fresnel_dielectric;
use crate::rgb::Rgb;
use glam::DVec3;

/// Mitsuba 3's named indices of refraction (`ior.h`, from Hecht's "Optics", at ~589 nm), by
/// their lower-case names.
const IOR_PRESETS: &[(&str, f64)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// The index of refraction of one of Mitsuba's named media (`bk7`, `air`, `water`,
/// `polypropylene`, …; case-insensitive as in Mitsuba), or `None`.
pub fn ior_preset(name: &str) -> Option<f64> {
    let lower = name.to_ascii_lowercase();
    IOR_PRESETS.iter().find(|p| p.0 == lower).map(|p| p.1)
}

/// Mitsuba's default interior index of `dielectric`, `thindielectric` and `roughdielectric`
/// (`bk7`).
pub const DEFAULT_GLASS_IOR: f64 = 1.5046;
/// Mitsuba's default interior index of `plastic` and `roughplastic` (`polypropylene`).
pub const DEFAULT_PLASTIC_IOR: f64 = 1.49;
/// Mitsuba's default exterior index (`air`).
pub const DEFAULT_EXT_IOR: f64 = 1.000277;

/// Relative index η = int_ior/ext_ior from the two absolute indices (each finite, in (0, 100]);
/// errors when they are equal (Mitsuba's rule: the interface would be invisible).
pub fn relative_ior(int_ior: f64, ext_ior: f64) -> Result<f64> {
    let i = check_range("int_ior", int_ior, 1e-3, 100.0)?;
    let e = check_range("ext_ior", ext_ior, 1e-3, 100.0)?;
    if i == e {
        return Err(Error::param(
            "int_ior",
            i,
            "the interior and exterior indices must differ",
        ));
    }
    Ok(i / e)
}

/// Refracts `w` through a microfacet (or the macro-surface) with normal `m`, given the Fresnel
/// record's cos θt and η_ti (Mitsuba's `refract`).
#[inline]
pub fn refract(w: DVec3, m: DVec3, cos_theta_t: f64, eta_ti: f64) -> DVec3 {
    m * (w.dot(m) * eta_ti + cos_theta_t) - w * eta_ti
}

/// A smooth glass (or water, …) interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// η = int_ior/ext_ior.
    pub eta: f64,
    /// Tint of the reflection (Mitsuba's `specular_reflectance`).
    pub specular_reflectance: Rgb,
    /// Tint of the refraction (Mitsuba's `specular_transmittance`).
    pub specular_transmittance: Rgb,
}

impl Dielectric {
    /// An untinted interface between media of indices `int_ior` (below) and `ext_ior` (above).
    pub fn new(int_ior: f64, ext_ior: f64) -> Result<Self> {
        Ok(Dielectric {
            eta: relative_ior(int_ior, ext_ior)?,
            specular_reflectance: Rgb::ONE,
            specular_transmittance: Rgb::ONE,
        })
    }

    /// The same interface with tints in [0, 1].
    pub fn with_tints(self, reflectance: Rgb, transmittance: Rgb) -> Result<Self> {
        check_rgb("specular_reflectance", reflectance, 0.0, 1.0)?;
        check_rgb("specular_transmittance", transmittance, 0.0, 1.0)?;
        Ok(Dielectric {
            specular_reflectance: reflectance,
            specular_transmittance: transmittance,
            ..self
        })
    }
}

impl Bsdf for Dielectric {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("dielectric(η={})", self.eta)
    }

    fn eval(&self, _wi: DVec3, _wo: DVec3) -> Rgb {
        Rgb::ZERO
    }

    fn sample(&self, wo: DVec3, u1: f64, _u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z == 0.0 {
            return None;
        }
        let f = fresnel_dielectric(wo.z, self.eta);
        if u1 < f.r {
            let wi = DVec3::new(-wo.x, -wo.y, wo.z);
            BsdfSample::delta(
                wi,
                self.specular_reflectance,
                f.r,
                LobeFlags::SPECULAR_REFLECTION,
                1.0,
            )
        } else {
            let wi = refract(wo, DVec3::Z, f.cos_theta_t, f.eta_ti).normalize();
            // Radiance scaling 1/η_it² (solid-angle compression across the interface).
            let weight = self.specular_transmittance * (f.eta_ti * f.eta_ti);
            BsdfSample::delta(
                wi,
                weight,
                1.0 - f.r,
                LobeFlags::SPECULAR_TRANSMISSION,
                f.eta_it,
            )
        }
    }

    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }

    /// Not reciprocal in radiance form (the 1/η² factor depends on the direction of travel);
    /// energy conserving in flux (R + T = 1, tints ≤ 1).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(false, true)
            .with_lobes(LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION)
    }
}
