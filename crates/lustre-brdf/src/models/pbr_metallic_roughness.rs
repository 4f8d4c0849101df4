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
//! The layers of the ratified extensions ([`PbrLayers`]), in the specification's order:
//!
//! ```text
//! KHR_materials_ior, _specular (ior η, weight k, colour t):
//!   f0 = min(((η − 1)/(η + 1))² t, 1),  F = f0 + (1 − f0)(1 − |wo·h|)⁵          (per channel)
//!   dielectric = (1 − k max(F)) c/π + k F specular                             (fresnel_mix)
//! KHR_materials_sheen (colour s, roughness r_s; [`crate::models::sheen`]):
//!   f ← s D_charlie V_neubelt + f · min(1 − max(s) E(cos θo), 1 − max(s) E(cos θi))
//! KHR_materials_clearcoat (weight w, roughness r_c; GGX α_c = r_c², ior 1.5):
//!   f ← mix(f, D_c G_c / (4 cos θi cos θo), w (0.04 + 0.96 (1 − |wo·h|)⁵))
//! ```
//!
//! With the defaults (η = 1.5, k = 1, t = 1, no sheen, no coat) this is the core model above. The
//! coat's Fresnel is taken at wo·h, as `fresnel_mix` does, where the specification's
//! `fresnel_coat` takes it at the coat normal's n·wo: the same at the coat's highlight, and
//! reciprocal. The sheen albedo scaling is clamped at 0 (E exceeds 1 at grazing incidence for
//! the sharpest sheen).
//!
//! Sampling: with probability P_c the coat (GGX visible normals), else GGX visible normals of the
//! base lobe with probability P_s, else cosine-weighted (diffuse and sheen);
//! P_s = S / (S + D) with S = mix(k max F(cos θo), Schlick(mean(c), cos θo), metallic) and
//! D = (1 − metallic)(1 − k max F)·mean(c) + max(s)·E(cos θo); P_c = C / (C + (1 − C)) with
//! C = w (0.04 + 0.96 (1 − cos θo)⁵) — so a white dielectric sends ~F of its samples to the
//! specular lobe and a metal all of them.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_range, check_rgb, Result};
use crate::frame::reflect;
use crate::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use crate::models::glossy_diffuse::{self, GlossyDiffuse};
use crate::models::sheen::{charlie_d, neubelt_v, sheen_albedo, sheen_alpha};
use crate::rgb::Rgb;
use glam::DVec3;
use std::f64::consts::FRAC_1_PI;

/// Smallest α = roughness² used.
pub const PBR_ALPHA_MIN: f64 = 1e-3;

/// The layers of `KHR_materials_specular`, `_clearcoat` and `_sheen` (module notes; the
/// `KHR_materials_ior` η is the model's own, [`PbrMetallicRoughness::with_layers`]);
/// [`Default`] is the core model (no tint, no coat, no sheen).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PbrLayers {
    /// `specularFactor` k in [0, 1].
    pub specular: f64,
    /// `specularColorFactor` t (each channel ≥ 0; may exceed 1).
    pub specular_color: Rgb,
    /// `clearcoatFactor` w in [0, 1].
    pub clearcoat: f64,
    /// `clearcoatRoughnessFactor` in [0, 1] (α_c = r², clamped as the base's α).
    pub clearcoat_roughness: f64,
    /// `sheenColorFactor` in [0, 1] (0: no sheen).
    pub sheen_color: Rgb,
    /// `sheenRoughnessFactor` in [0, 1].
    pub sheen_roughness: f64,
}

impl Default for PbrLayers {
    fn default() -> Self {
        PbrLayers {
            specular: 1.0,
            specular_color: Rgb::ONE,
            clearcoat: 0.0,
            clearcoat_roughness: 0.0,
            sheen_color: Rgb::ZERO,
            sheen_roughness: 0.0,
        }
    }
}

impl PbrLayers {
    /// Checks each factor against its range (the error names the glTF factor).
    pub fn validate(&self) -> Result<()> {
        check_range("specularFactor", self.specular, 0.0, 1.0)?;
        check_rgb("specularColorFactor", self.specular_color, 0.0, 1e3)?;
        check_range("clearcoatFactor", self.clearcoat, 0.0, 1.0)?;
        check_range(
            "clearcoatRoughnessFactor",
            self.clearcoat_roughness,
            0.0,
            1.0,
        )?;
        check_rgb("sheenColorFactor", self.sheen_color, 0.0, 1.0)?;
        check_range("sheenRoughnessFactor", self.sheen_roughness, 0.0, 1.0)?;
        Ok(())
    }

    /// The dielectric's f0 = min(((η − 1)/(η + 1))² t, 1) per channel at ior η.
    pub fn f0(&self, ior: f64) -> Rgb {
        let r = (ior - 1.0) / (ior + 1.0);
        self.specular_color.map(|t| (r * r * t).min(1.0))
    }

    /// Whether `KHR_materials_specular` differs from the core model (k ≠ 1 or t ≠ 1).
    pub fn has_specular(&self) -> bool {
        self.specular != 1.0 || self.specular_color != Rgb::ONE
    }

    /// Whether the layers add a sheen lobe.
    pub fn has_sheen(&self) -> bool {
        self.sheen_color.max_component() > 0.0
    }

    /// Whether the layers add a clearcoat.
    pub fn has_clearcoat(&self) -> bool {
        self.clearcoat > 0.0
    }
}

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
    /// `KHR_materials_ior`'s η of the dielectric (1.5 by default).
    pub ior: f64,
    /// The extensions' layers.
    pub layers: PbrLayers,
    /// (cos ρ, sin ρ).
    rotation: (f64, f64),
    distribution: MicrofacetDistribution,
    /// The dielectric's f0 ([`PbrLayers::f0`]).
    f0: Rgb,
    /// The coat's GGX distribution (α_c = max(r_c², 1e-3)).
    coat: MicrofacetDistribution,
    /// The sheen's Charlie α.
    sheen_alpha: f64,
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
            ior: 1.5,
            layers: PbrLayers::default(),
            rotation: (1.0, 0.0),
            distribution: MicrofacetDistribution::isotropic(MicrofacetType::Ggx, alpha)?,
            f0: PbrLayers::default().f0(1.5),
            coat: MicrofacetDistribution::isotropic(MicrofacetType::Ggx, PBR_ALPHA_MIN)?,
            sheen_alpha: sheen_alpha(0.0),
        })
    }

    /// The same material with the dielectric's ior η ≥ 1 and the extensions' layers (module
    /// notes), each checked.
    pub fn with_layers(self, ior: f64, layers: PbrLayers) -> Result<Self> {
        check_range("ior", ior, 1.0, 1e3)?;
        layers.validate()?;
        let r = layers.clearcoat_roughness;
        Ok(PbrMetallicRoughness {
            ior,
            layers,
            f0: layers.f0(ior),
            coat: MicrofacetDistribution::isotropic(
                MicrofacetType::Ggx,
                (r * r).max(PBR_ALPHA_MIN),
            )?,
            sheen_alpha: sheen_alpha(layers.sheen_roughness),
            ..self
        })
    }

    /// The dielectric's f0 per channel.
    pub fn f0(&self) -> Rgb {
        self.f0
    }

    /// α_c of the coat.
    pub fn coat_alpha(&self) -> f64 {
        self.coat.alpha_u()
    }

    /// The sheen's Charlie α.
    pub fn sheen_alpha(&self) -> f64 {
        self.sheen_alpha
    }

    /// The coat's choice probability P_c at cos θo.
    fn prob_coat(&self, cos_o: f64) -> f64 {
        if !self.layers.has_clearcoat() {
            return 0.0;
        }
        self.layers.clearcoat * (0.04 + 0.96 * schlick5(cos_o))
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
        let k = self.layers.specular;
        let f = self.f0.map(|f0| f0 + (1.0 - f0) * w);
        let dielectric = c * (FRAC_1_PI * (1.0 - k * f.max_component())) + f * (k * spec);
        let mut out = dielectric * (1.0 - self.metallic) + metal * self.metallic;
        let l = &self.layers;
        if l.has_sheen() {
            let s = l.sheen_color.max_component();
            let r = l.sheen_roughness;
            let scale = (1.0 - s * sheen_albedo(wo.z, r))
                .min(1.0 - s * sheen_albedo(wi.z, r))
                .max(0.0);
            let sheen = charlie_d(self.sheen_alpha, h.z) * neubelt_v(wi.z, wo.z);
            out = l.sheen_color * sheen + out * scale;
        }
        if l.has_clearcoat() {
            let (d, denom) = (self.coat.d(h), 4.0 * wi.z * wo.z);
            let coat = if d > 0.0 && denom > 0.0 {
                d * self.coat.g(wi, wo, h) / denom
            } else {
                0.0
            };
            let fc = l.clearcoat * (0.04 + 0.96 * w);
            out = out * (1.0 - fc) + Rgb::splat(coat * fc);
        }
        out
    }
}

impl PbrMetallicRoughness {
    /// The density in the anisotropy frame: P_c · coat + (1 − P_c) · the base mixture.
    fn pdf_aniso(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let base = glossy_diffuse::pdf(self, wi, wo);
        let pc = self.prob_coat(wo.z);
        if pc <= 0.0 {
            return base;
        }
        let h = (wi + wo).normalize();
        let coat = self.coat.d(h) * self.coat.g1(wo, h) / (4.0 * wo.z);
        pc * coat + (1.0 - pc) * base
    }
}

impl GlossyDiffuse for PbrMetallicRoughness {
    fn distribution(&self) -> &MicrofacetDistribution {
        &self.distribution
    }

    fn prob_specular(&self, wo: DVec3) -> f64 {
        let c = self.base_color.mean();
        let w = schlick5(wo.z);
        let k = self.layers.specular;
        let f_d = k * self.f0.map(|f0| f0 + (1.0 - f0) * w).max_component();
        let f_m = c + (1.0 - c) * w;
        let s = f_d + (f_m - f_d) * self.metallic;
        let mut d = (1.0 - self.metallic) * (1.0 - f_d) * c;
        if self.layers.has_sheen() {
            let sheen = self.layers.sheen_color.max_component();
            d += sheen * sheen_albedo(wo.z, self.layers.sheen_roughness);
        }
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
        let mut s = format!(
            "pbr(metallic={}, roughness={}",
            self.metallic, self.roughness
        );
        if self.anisotropy > 0.0 {
            s += &format!(
                ", anisotropy={}, rotation={}",
                self.anisotropy, self.anisotropy_rotation
            );
        }
        let l = &self.layers;
        if self.ior != 1.5 || l.has_specular() {
            s += &format!(
                ", ior={}, specular={}, specular_color={:?}",
                self.ior, l.specular, l.specular_color.0
            );
        }
        if l.has_clearcoat() {
            s += &format!(
                ", clearcoat={}, clearcoat_roughness={}",
                l.clearcoat, l.clearcoat_roughness
            );
        }
        if l.has_sheen() {
            s += &format!(
                ", sheen={:?}, sheen_roughness={}",
                l.sheen_color.0, l.sheen_roughness
            );
        }
        s + ")"
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        self.eval_aniso(self.aniso_frame(wi), self.aniso_frame(wo))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let wo = self.aniso_frame(wo);
        let pc = self.prob_coat(wo.z);
        let (wi, lobe, pdf) = if u1 < pc {
            let u1 = (u1 / pc).clamp(0.0, 1.0 - f64::EPSILON);
            let h = self.coat.sample_visible(wo, u1, u2)?;
            let wi = reflect(wo, h);
            (wi, LobeFlags::GLOSSY_REFLECTION, self.pdf_aniso(wi, wo))
        } else {
            let u1 = ((u1 - pc) / (1.0 - pc)).clamp(0.0, 1.0 - f64::EPSILON);
            let (wi, lobe, base) = glossy_diffuse::sample_direction(self, wo, u1, u2)?;
            // Without a coat the mixture's own density is the model's.
            let pdf = if pc > 0.0 {
                self.pdf_aniso(wi, wo)
            } else {
                base
            };
            (wi, lobe, pdf)
        };
        (pdf > 0.0 && pdf.is_finite())
            .then(|| BsdfSample::new(self.shading_frame(wi), self.eval_aniso(wi, wo), pdf, lobe))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.pdf_aniso(self.aniso_frame(wi), self.aniso_frame(wo))
    }

    /// Reciprocal. Energy conserving only as a pure metal without sheen (a rough conductor with
    /// F ≤ 1, coated or not): the dielectric mix (1 − F(wo·h)) c/π + F·specular reflects up to
    /// 1.116 with a white base at roughness 0.5 at grazing incidence (measured in
    /// `tests/physical_battery.rs`), and the Charlie sheen's albedo exceeds 1 at grazing
    /// incidence (E(0) ≈ 5.7 at r = 0.07 by the quadrature of [`crate::models::sheen`]).
    fn flags(&self) -> BsdfFlags {
        let lobes = if self.metallic < 1.0 || self.layers.has_sheen() {
            LobeFlags::GLOSSY_REFLECTION | LobeFlags::DIFFUSE_REFLECTION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        };
        BsdfFlags {
            anisotropic: self.distribution.is_anisotropic(),
            ..BsdfFlags::isotropic_reflection(
                true,
                self.metallic == 1.0 && !self.layers.has_sheen(),
            )
        }
        .with_lobes(lobes)
    }
}
