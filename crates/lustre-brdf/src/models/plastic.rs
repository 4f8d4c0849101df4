//! Smooth plastic, in Mitsuba 3's formulation (`plastic`): a smooth dielectric coating of index
//! η = int_ior/ext_ior (a Dirac reflection of weight F(cos θo)·specular_reflectance) over a
//! Lambertian base seen through the coating,
//!
//! ```text
//! f_diffuse(wi, wo) = ρ' (1 − F(cos θi)) (1 − F(cos θo)) / (π η²),
//! ρ' = ρ / (1 − Fdr)           (default, linear)   or   ρ / (1 − ρ Fdr)    (`nonlinear`)
//! ```
//!
//! where Fdr = [`fresnel_diffuse_reflectance`](1/η) is the coating's hemispherical internal
//! reflectance (Mitsuba evaluates fitted approximations of it; we integrate it). The `nonlinear`
//! flag sums the internal bounces between coating and base properly (a darker, more saturated
//! base); the linear form is Mitsuba's default. With ρ = specular_reflectance = 1 and the linear
//! form the albedo is exactly 1 at every angle (η²(1 − Fdr(1/η)) = 1 − Fdr(η)).
//!
//! Sampling (Mitsuba's): the coating with probability P_s = F s / (F s + (1 − F)(1 − s)),
//! s = mean(specular)/(mean(diffuse) + mean(specular)), F = F(cos θo); otherwise the cosine-
//! weighted base. `eval`/`pdf` cover the base only (the coating is a delta lobe, see
//! [`crate::bsdf`]). One-sided.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Result};
use crate::microfacet::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance};
use crate::models::dielectric::relative_ior;
use crate::rgb::Rgb;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// A plastic's base seen through its coating, as the Lambertian a light map can hold. The base
/// lobe is f(wi, wo) = ρ' T(μi) T(μo) / (π η²) (T the coating's transmittance, 1 − F for a
/// smooth one); under uniform incident radiance L it reflects ρ' T(μo) T̄ L / η² towards μo,
/// T̄ = 2∫₀¹ T(μ) μ dμ, and, averaged over cosine-weighted outgoing directions, its albedo is
///
/// ```text
/// kd = ρ' T̄² / η² = scale · ρ / (1 − fdr · ρ),
/// ```
///
/// scale = T̄² / (η² (1 − Fdr)) and fdr = 0 for the linear ρ', scale = T̄² / η² and fdr = Fdr for
/// the nonlinear one (per channel). What kd leaves of f (a part that depends on μi and μo) is
/// the view-dependent rest. An uncoated base: scale 1, fdr 0 (kd = ρ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatedBase {
    /// The factor on ρ.
    pub scale: f64,
    /// The internal reflectance in the denominator (0: linear).
    pub fdr: f64,
}

impl CoatedBase {
    /// kd = ρ.
    pub const UNCOATED: CoatedBase = CoatedBase {
        scale: 1.0,
        fdr: 0.0,
    };

    /// The base of a coating of relative index `eta` with mean transmittance `mean_t` (T̄) and
    /// internal reflectance `fdr_int`, ρ' linear or `nonlinear`.
    pub fn new(mean_t: f64, eta: f64, fdr_int: f64, nonlinear: bool) -> Self {
        let s = mean_t * mean_t / (eta * eta);
        if nonlinear {
            CoatedBase {
                scale: s,
                fdr: fdr_int,
            }
        } else {
            CoatedBase {
                scale: s / (1.0 - fdr_int),
                fdr: 0.0,
            }
        }
    }

    /// kd of a base of albedo ρ (each channel in [0, 1]).
    pub fn kd(&self, rho: Rgb) -> Rgb {
        rho.map(|x| self.scale * x / (1.0 - self.fdr * x))
    }
}

/// A smooth plastic.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic {
    /// Base albedo ρ (Mitsuba's `diffuse_reflectance`).
    pub diffuse_reflectance: Rgb,
    /// Tint of the coating's reflection.
    pub specular_reflectance: Rgb,
    /// η = int_ior/ext_ior of the coating.
    pub eta: f64,
    /// Mitsuba's `nonlinear` flag (see the module notes).
    pub nonlinear: bool,
    fdr_int: f64,
    specular_weight: f64,
}

impl Plastic {
    /// A smooth plastic; colours in [0, 1], indices as for [`relative_ior`].
    pub fn new(
        diffuse_reflectance: Rgb,
        specular_reflectance: Rgb,
        int_ior: f64,
        ext_ior: f64,
        nonlinear: bool,
    ) -> Result<Self> {
        check_rgb("diffuse_reflectance", diffuse_reflectance, 0.0, 1.0)?;
        check_rgb("specular_reflectance", specular_reflectance, 0.0, 1.0)?;
        let eta = relative_ior(int_ior, ext_ior)?;
        let (d, s) = (diffuse_reflectance.mean(), specular_reflectance.mean());
        Ok(Plastic {
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
            specular_weight: if d + s > 0.0 { s / (d + s) } else { 0.5 },
        })
    }

    /// The same coating with other colours in [0, 1] (cheap: Fdr is kept), for textures.
    pub fn with_reflectances(self, diffuse: Rgb, specular: Rgb) -> Result<Self> {
        check_rgb("diffuse_reflectance", diffuse, 0.0, 1.0)?;
        check_rgb("specular_reflectance", specular, 0.0, 1.0)?;
        let (d, s) = (diffuse.mean(), specular.mean());
        Ok(Plastic {
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            specular_weight: if d + s > 0.0 { s / (d + s) } else { 0.5 },
            ..self
        })
    }

    /// The coating's internal diffuse reflectance Fdr(1/η).
    pub fn internal_reflectance(&self) -> f64 {
        self.fdr_int
    }

    /// The base as a Lambertian ([`CoatedBase`]), T(μ) = 1 − F(μ): T̄ = 1 − Fdr(η).
    pub fn coated_base(&self) -> CoatedBase {
        CoatedBase::new(
            1.0 - fresnel_diffuse_reflectance(self.eta),
            self.eta,
            self.fdr_int,
            self.nonlinear,
        )
    }

    fn prob_specular(&self, f_o: f64) -> f64 {
        let ps = f_o * self.specular_weight;
        let pd = (1.0 - f_o) * (1.0 - self.specular_weight);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }

    fn base(&self) -> Rgb {
        let d = self.diffuse_reflectance;
        if self.nonlinear {
            d.map(|x| x / (1.0 - x * self.fdr_int))
        } else {
            d / (1.0 - self.fdr_int)
        }
    }
}

impl Bsdf for Plastic {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("plastic(η={})", self.eta)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Rgb::ZERO;
        }
        let f_i = fresnel_dielectric(wi.z, self.eta).r;
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        self.base() * (FRAC_1_PI / (self.eta * self.eta) * (1.0 - f_i) * (1.0 - f_o))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        let ps = self.prob_specular(f_o);
        if u1 < ps {
            let wi = DVec3::new(-wo.x, -wo.y, wo.z);
            return BsdfSample::delta(
                wi,
                self.specular_reflectance * (f_o / ps),
                ps,
                LobeFlags::SPECULAR_REFLECTION,
                1.0,
            );
        }
        let u1 = ((u1 - ps) / (1.0 - ps)).clamp(0.0, 1.0 - f64::EPSILON);
        let wi = cosine_hemisphere(u1, u2);
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wi, wo);
        (pdf > 0.0)
            .then(|| BsdfSample::new(wi, self.eval(wi, wo), pdf, LobeFlags::DIFFUSE_REFLECTION))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).r;
        (1.0 - self.prob_specular(f_o)) * cosine_hemisphere_pdf(wi)
    }

    /// Reciprocal; energy conserving (colours ≤ 1; exactly 1 for white, see the module notes).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, true)
            .with_lobes(LobeFlags::SPECULAR_REFLECTION | LobeFlags::DIFFUSE_REFLECTION)
    }
}
