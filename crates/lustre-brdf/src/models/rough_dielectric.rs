//! Rough dielectric interface (Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces"; Mitsuba 3's `roughdielectric`), η = int_ior/ext_ior, anisotropic GGX or Beckmann.
//!
//! With η_o the index on the side of `wo`, η_i that of `wi`, and η = η_i/η_o:
//!
//! ```text
//! reflection   f = F(wo·h) D(h) G(wi, wo, h) / (4 |cos θi| |cos θo|),    h = ±(wi + wo)/‖·‖
//! refraction   f = (1/η²) (1 − F(wo·h)) D(h) G |wi·h| |wo·h| η² / (|cos θi| |cos θo| (wo·h + η wi·h)²),
//!              h = ±(wo + η wi)/‖·‖                                      (Walter Eqs. 16, 21)
//! ```
//!
//! h oriented towards the macro-surface normal. The leading 1/η² is the radiance scaling across
//! the interface (Walter's "missing term", applied in radiance mode as Mitsuba and pbrt-v4 do; see
//! [`crate::bsdf`]): it makes f non-reciprocal, f(wi, wo) η_o² = f(wo, wi) η_i², and the albedo
//! seen from the denser side exceed 1; [`BsdfSample::eta`] carries η so the flux can be recovered.
//!
//! Sampling: a visible normal m of D from ±wo (the side of `wo`), then reflection with
//! probability F(wo·m), refraction otherwise, so that
//! pdf = D_v(m) · (F or 1 − F) · |∂h/∂wi| with |∂h/∂wi| = 1/(4|wi·h|) (reflection) or
//! η²|wi·h|/(wo·h + η wi·h)² (refraction) (Walter Eqs. 14, 17).

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Result};
use crate::frame::reflect;
use crate::microfacet::distribution::MicrofacetDistribution;
use crate::microfacet::fresnel::fresnel_dielectric;
use crate::models::dielectric::{refract, relative_ior};
use crate::rgb::Rgb;
use crate::sampling::split_uniform;
use glam::DVec3;

/// A rough glass interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    /// The microfacet distribution (type, αu, αv).
    pub distribution: MicrofacetDistribution,
    /// η = int_ior/ext_ior.
    pub eta: f64,
    /// Tint of the reflection.
    pub specular_reflectance: Rgb,
    /// Tint of the refraction.
    pub specular_transmittance: Rgb,
}

/// The generalized half vector of a pair and the pair's geometry.
struct Config {
    h: DVec3,
    reflect: bool,
    /// η_i/η_o (1 for reflection).
    eta: f64,
}

impl RoughDielectric {
    /// An untinted rough interface between `int_ior` (below) and `ext_ior` (above).
    pub fn new(distribution: MicrofacetDistribution, int_ior: f64, ext_ior: f64) -> Result<Self> {
        Ok(RoughDielectric {
            distribution,
            eta: relative_ior(int_ior, ext_ior)?,
            specular_reflectance: Rgb::ONE,
            specular_transmittance: Rgb::ONE,
        })
    }

    /// The same interface with tints in [0, 1].
    pub fn with_tints(self, reflectance: Rgb, transmittance: Rgb) -> Result<Self> {
        check_rgb("specular_reflectance", reflectance, 0.0, 1.0)?;
        check_rgb("specular_transmittance", transmittance, 0.0, 1.0)?;
        Ok(RoughDielectric {
            specular_reflectance: reflectance,
            specular_transmittance: transmittance,
            ..self
        })
    }

    fn config(&self, wi: DVec3, wo: DVec3) -> Option<Config> {
        if wo.z == 0.0 || wi.z == 0.0 || wo.z.is_nan() || wi.z.is_nan() {
            return None;
        }
        let reflect = wi.z * wo.z > 0.0;
        let eta = if reflect {
            1.0
        } else if wo.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let h = (wo + wi * eta).try_normalize()?;
        let h = if h.z < 0.0 { -h } else { h };
        // Micro- and macro-surface must agree on the side of both directions.
        if wo.dot(h) * wo.z <= 0.0 || wi.dot(h) * wi.z <= 0.0 {
            return None;
        }
        Some(Config { h, reflect, eta })
    }
}

impl Bsdf for RoughDielectric {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!(
            "roughdielectric({}, αu={}, αv={}, η={})",
            self.distribution.kind().name(),
            self.distribution.alpha_u(),
            self.distribution.alpha_v(),
            self.eta
        )
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let Some(c) = self.config(wi, wo) else {
            return Rgb::ZERO;
        };
        let d = self.distribution.d(c.h);
        if d == 0.0 {
            return Rgb::ZERO;
        }
        let g = self.distribution.g(wi, wo, c.h);
        let (oh, ih) = (wo.dot(c.h), wi.dot(c.h));
        let f = fresnel_dielectric(oh, self.eta).r;
        let (ci, co) = (wi.z.abs(), wo.z.abs());
        if c.reflect {
            // Walter Eq. 20.
            self.specular_reflectance * (f * d * g / (4.0 * ci * co))
        } else {
            // Walter Eq. 21 times the radiance scaling 1/η².
            let denom = oh + c.eta * ih;
            let v = (1.0 - f) * d * g * (ih * oh).abs() / (ci * co * denom * denom);
            self.specular_transmittance * v.abs()
        }
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z == 0.0 {
            return None;
        }
        let s = wo.z.signum();
        // Three numbers from two: u2's bits, de-interleaved, give the azimuth of m and the lobe.
        let (u2, u) = split_uniform(u2);
        let m = self.distribution.sample_visible(wo * s, u1, u2)?;
        let fr = fresnel_dielectric(wo.dot(m), self.eta);
        let (wi, lobe, eta) = if u < fr.r {
            (reflect(wo, m), LobeFlags::GLOSSY_REFLECTION, 1.0)
        } else {
            let wi = refract(wo, m, fr.cos_theta_t, fr.eta_ti);
            (wi, LobeFlags::GLOSSY_TRANSMISSION, fr.eta_it)
        };
        let wi = wi.try_normalize()?;
        let same = wi.z * wo.z > 0.0;
        if same != lobe.is_reflection() || wi.z == 0.0 {
            return None;
        }
        let pdf = self.pdf(wi, wo);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            value: self.eval(wi, wo),
            pdf,
            lobe,
            eta,
        })
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(c) = self.config(wi, wo) else {
            return 0.0;
        };
        let (oh, ih) = (wo.dot(c.h), wi.dot(c.h));
        let jacobian = if c.reflect {
            1.0 / (4.0 * ih.abs())
        } else {
            let denom = oh + c.eta * ih;
            c.eta * c.eta * ih.abs() / (denom * denom)
        };
        let s = wo.z.signum();
        let f = fresnel_dielectric(oh, self.eta).r;
        let choice = if c.reflect { f } else { 1.0 - f };
        self.distribution.pdf_visible(wo * s, c.h) * choice * jacobian
    }

    /// Not reciprocal (radiance scaling); energy conserving in flux (tints ≤ 1, single
    /// scattering loses energy).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            anisotropic: self.distribution.is_anisotropic(),
            ..BsdfFlags::isotropic_reflection(false, true)
                .with_lobes(LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION)
        }
    }
}
