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
            distribution: MicrofacetDistribution::isotropic(MicrofacetType::Ggx, alpha)?,
        })
    }

    /// α = max(roughness², 1e-3).
    pub fn alpha(&self) -> f64 {
        self.distribution.alpha_u()
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
        format!(
            "pbr(metallic={}, roughness={})",
            self.metallic, self.roughness
        )
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
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

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        glossy_diffuse::sample(self, wo, u1, u2)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        glossy_diffuse::pdf(self, wi, wo)
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
        BsdfFlags::isotropic_reflection(true, self.metallic == 1.0).with_lobes(lobes)
    }
}
