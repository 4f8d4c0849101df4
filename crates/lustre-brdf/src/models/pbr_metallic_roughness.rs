//! The glTF 2.0 metallic-roughness BRDF (glTF 2.0 specification, Appendix B):
//!
//! ```text
//! α = roughness²,  D = GGX(α),  V = G1(wi) G1(wo) / (4 |cos θi| |cos θo|)   (separable Smith)
//! specular   = V D
//! metal      = specular · (c + (1 − c)(1 − |wo·h|)⁵)                  (Schlick, F0 = base colour)
//! dielectric = mix(c/π, specular, 0.04 + 0.96 (1 − |wo·h|)⁵)          (fresnel_mix, ior 1.5)
//! f          = mix(dielectric, metal, metallic)
//! ```
//!
//! α is clamped below at 1e-3 (roughness 0.0316): the specification's perfectly smooth limit is
//! a Dirac lobe, which real-time engines also clamp away (Filament's minimum α ≈ 2e-3).
//!
//! `KHR_materials_anisotropy` (strength s, rotation ρ): the GGX lobe becomes anisotropic with
//! α_t = mix(α, 1, s²) along the anisotropy direction t = (cos ρ, sin ρ, 0) of the tangent frame
//! and α_b = α across it; the model is evaluated, sampled and its density taken in the frame
//! (t, z × t, z), so everything else (Fresnel, the diffuse lobe, P_s) is unchanged.
//!
//! Sampling: GGX visible normals (specular) with probability P_s, else cosine-weighted (diffuse);
//! P_s = S / (S + (1 − metallic)(1 − F)·mean(c)) with F = 0.04 + 0.96(1 − cos θo)⁵ and
//! S = mix(F, Schlick(mean(c), cos θo), metallic), so a white dielectric sends ~F of its samples to
//! the specular lobe and a metal all of them.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_range, check_rgb, Result};
use crate::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use crate::models::glossy_diffuse::{self, GlossyDiffuse};
use crate::rgb::Rgb;
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// Smallest α = roughness² used.
pub const PBR_ALPHA_MIN: f64 = 1e-3;

/// The glTF metallic-roughness material (per-texel values are the scene layer's business).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PbrMetallicRoughness {
    /// Base colour c (linear).
    pub base_color: Rgb,
    /// Metalness in [0, 1].
    pub metallic: f64,
    /// Perceptual roughness in [0, 1].
    pub roughness: f64,
    /// `KHR_materials_anisotropy` strength in [0, 1] (0: isotropic).
    pub anisotropy: f64,
    /// Rotation of the anisotropy direction from the tangent, radians.
    pub anisotropy_rotation: f64,
    /// (cos ρ, sin ρ).
    rotation: (f64, f64),
    distribution: MicrofacetDistribution,
}

fn schlick5(cos: f64) -> f64 {
    let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

impl PbrMetallicRoughness {
    /// A material with base colour in [0, 1], metallic and roughness in [0, 1].
    pub fn new(base_color: Rgb, metallic: f64, roughness: f64) -> Result<Self> {
        check_rgb("base_color", base_color, 0.0, 1.0)?;
        check_range("metallic", metallic, 0.0, 1.0)?;
        check_range("roughness", roughness, 0.0, 1.0)?;
        let alpha = (roughness * roughness).max(PBR_ALPHA_MIN);
        Ok(PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            rotation: (1.0, 0.0),
            distribution: MicrofacetDistribution::isotropic(MicrofacetType::Ggx, alpha)?,
        })
    }

    /// The same material with `KHR_materials_anisotropy`: strength in [0, 1], rotation (radians,
    /// finite) of the anisotropy direction from the tangent.
    pub fn with_anisotropy(self, strength: f64, rotation: f64) -> Result<Self> {
        check_range("anisotropy", strength, 0.0, 1.0)?;
        check_range("anisotropy_rotation", rotation, -f64::MAX, f64::MAX)?;
        let alpha = self.alpha_b();
        let alpha_t = alpha + (1.0 - alpha) * strength * strength;
        Ok(PbrMetallicRoughness {
            anisotropy: strength,
            anisotropy_rotation: rotation,
            rotation: (rotation.cos(), rotation.sin()),
            distribution: MicrofacetDistribution::new(MicrofacetType::Ggx, alpha_t, alpha)?,
            ..self
        })
    }

    /// α = max(roughness², 1e-3) (isotropic; α_b with anisotropy).
    pub fn alpha(&self) -> f64 {
        self.alpha_b()
    }

    /// α_b = max(roughness², 1e-3): the roughness across the anisotropy direction.
    pub fn alpha_b(&self) -> f64 {
        self.distribution.alpha_v()
    }

    /// α_t = mix(α, 1, strength²): the roughness along the anisotropy direction.
    pub fn alpha_t(&self) -> f64 {
        self.distribution.alpha_u()
    }

    /// (cos ρ, sin ρ) of the anisotropy rotation ρ.
    pub fn rotation(&self) -> (f64, f64) {
        self.rotation
    }

    /// `v` in the anisotropy frame (t, z × t, z).
    fn aniso_frame(&self, v: DVec3) -> DVec3 {
        let (c, s) = self.rotation;
        DVec3::new(c * v.x + s * v.y, -s * v.x + c * v.y, v.z)
    }

    /// `v` back from the anisotropy frame.
    fn shading_frame(&self, v: DVec3) -> DVec3 {
        let (c, s) = self.rotation;
        DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
    }

    /// f in the anisotropy frame.
    fn eval_aniso(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Rgb::ZERO;
        }
        let h = (wi + wo).normalize();
        let (d, denom) = (self.distribution.d(h), 4.0 * wi.z * wo.z);
        let spec = if d > 0.0 && denom > 0.0 {
            d * self.distribution.g(wi, wo, h) / denom
        } else {
            0.0
        };
        let w = schlick5(wo.dot(h));
        let c = self.base_color;
        let metal = c.map(|x| spec * (x + (1.0 - x) * w));
        let f = 0.04 + 0.96 * w;
        let dielectric = c * (FRAC_1_PI * (1.0 - f)) + Rgb::splat(spec * f);
        dielectric * (1.0 - self.metallic) + metal * self.metallic
    }
}

impl GlossyDiffuse for PbrMetallicRoughness {
    fn distribution(&self) -> &MicrofacetDistribution {
        &self.distribution
    }

    fn prob_specular(&self, wo: DVec3) -> f64 {
        let c = self.base_color.mean();
        let w = schlick5(wo.z);
        let f_d = 0.04 + 0.96 * w;
        let f_m = c + (1.0 - c) * w;
        let s = f_d + (f_m - f_d) * self.metallic;
        let d = (1.0 - self.metallic) * (1.0 - f_d) * c;
        if s + d > 0.0 {
            s / (s + d)
        } else {
            1.0
        }
    }
}

impl Bsdf for PbrMetallicRoughness {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        if self.anisotropy > 0.0 {
            format!(
                "pbr(metallic={}, roughness={}, anisotropy={}, rotation={})",
                self.metallic, self.roughness, self.anisotropy, self.anisotropy_rotation
            )
        } else {
            format!(
                "pbr(metallic={}, roughness={})",
                self.metallic, self.roughness
            )
        }
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        self.eval_aniso(self.aniso_frame(wi), self.aniso_frame(wo))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        let wo = self.aniso_frame(wo);
        let (wi, lobe, pdf) = glossy_diffuse::sample_direction(self, wo, u1, u2)?;
        Some(BsdfSample::new(
            self.shading_frame(wi),
            self.eval_aniso(wi, wo),
            pdf,
            lobe,
        ))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        glossy_diffuse::pdf(self, self.aniso_frame(wi), self.aniso_frame(wo))
    }

    /// Reciprocal. Energy conserving only as a pure metal (a rough conductor with F ≤ 1): the
    /// dielectric mix (1 − F(wo·h)) c/π + F·specular reflects up to 1.116 with a white base at
    /// roughness 0.5 at grazing incidence (measured in `tests/physical_battery.rs`).
    fn flags(&self) -> BsdfFlags {
        let lobes = if self.metallic < 1.0 {
            LobeFlags::GLOSSY_REFLECTION | LobeFlags::DIFFUSE_REFLECTION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        };
        BsdfFlags {
            anisotropic: self.distribution.is_anisotropic(),
            ..BsdfFlags::isotropic_reflection(true, self.metallic == 1.0)
        }
        .with_lobes(lobes)
    }
}
