//! The scene's material layer: parameters that may be textured, evaluated at a hit into a
//! ready [`Bsdf`] from lustre-brdf.
//!
//! Textures belong here, not in the BSDF library: a [`Material`] holds constant factors and
//! optional texture references; [`Material::bsdf_at`] samples the textures at the hit's UVs and
//! builds the BSDF. Every material is checked once at load ([`Material::check`]), so a scene that
//! loads builds a BSDF at every hit (texel values are clamped into the models' valid ranges).

use crate::error::{Result, SceneError};
use crate::texture::Texture;
use glam::Vec2;
use lustre_brdf::microfacet::distribution::MicrofacetDistribution;
pub use lustre_brdf::microfacet::distribution::MicrofacetType;
use lustre_brdf::models::conductor::{ComplexIor, Conductor};
use lustre_brdf::models::dielectric::Dielectric;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::models::pbr_metallic_roughness::{PbrLayers, PbrMetallicRoughness, PBR_ALPHA_MIN};
use lustre_brdf::models::plastic::Plastic;
use lustre_brdf::models::rough_conductor::RoughConductor;
use lustre_brdf::models::rough_dielectric::RoughDielectric;
use lustre_brdf::models::rough_plastic::{RoughPlastic, RoughPlasticCoating};
use lustre_brdf::models::thin_dielectric::ThinDielectric;
use lustre_brdf::models::two_sided::TwoSided;
use lustre_brdf::{Bsdf, DVec3, Rgb};
use std::borrow::Cow;
use std::sync::{Arc, OnceLock};

/// A texture reference: which texture and which UV set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureRef {
    /// Index into [`crate::Scene::textures`].
    pub texture: usize,
    /// 0 for `uv0`, 1 for `uv1`.
    pub uv_set: u8,
}

/// An RGB parameter: `factor`, times the texture's RGB where there is one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturedRgb {
    /// Constant factor (the value when untextured).
    pub factor: Rgb,
    /// Optional texture multiplied in.
    pub texture: Option<TextureRef>,
}

/// A scalar parameter: `factor`, times one channel of the texture where there is one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturedScalar {
    /// Constant factor (the value when untextured).
    pub factor: f64,
    /// Optional texture multiplied in.
    pub texture: Option<TextureRef>,
    /// Channel of the texture (0 = R … 3 = A).
    pub channel: u8,
}

impl TexturedRgb {
    /// An untextured value.
    pub fn constant(c: Rgb) -> Self {
        TexturedRgb {
            factor: c,
            texture: None,
        }
    }

    /// A texture, unscaled.
    pub fn texture(t: TextureRef) -> Self {
        TexturedRgb {
            factor: Rgb::ONE,
            texture: Some(t),
        }
    }

    /// The value at a hit.
    pub fn at(&self, textures: &[Texture], uv: &[Vec2; 2]) -> Rgb {
        match self.texture.and_then(|t| lookup(textures, t, uv)) {
            Some(s) => Rgb::new(
                self.factor[0] * f64::from(s[0]),
                self.factor[1] * f64::from(s[1]),
                self.factor[2] * f64::from(s[2]),
            ),
            None => self.factor,
        }
    }
}

impl TexturedScalar {
    /// An untextured value.
    pub fn constant(v: f64) -> Self {
        TexturedScalar {
            factor: v,
            texture: None,
            channel: 0,
        }
    }

    /// The value at a hit.
    pub fn at(&self, textures: &[Texture], uv: &[Vec2; 2]) -> f64 {
        match self.texture.and_then(|t| lookup(textures, t, uv)) {
            Some(s) => self.factor * f64::from(s[usize::from(self.channel.min(3))]),
            None => self.factor,
        }
    }
}

fn lookup(textures: &[Texture], t: TextureRef, uv: &[Vec2; 2]) -> Option<[f32; 4]> {
    let tex = textures.get(t.texture)?;
    let p = uv[usize::from(t.uv_set.min(1))];
    Some(tex.sample(p.x, p.y))
}

/// The scattering model of a material and its (possibly textured) parameters. Parameter meanings
/// and defaults follow Mitsuba's plugins of the same names; `alpha` is the microfacet roughness
/// (Mitsuba's `alpha`, not perceptual roughness).
#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// Lambertian reflector.
    Diffuse {
        /// Albedo.
        reflectance: TexturedRgb,
    },
    /// Smooth dielectric coating over a diffuse base.
    Plastic {
        /// Base albedo.
        diffuse: TexturedRgb,
        /// Scale of the specular reflection.
        specular: Rgb,
        /// Interior index of refraction.
        int_ior: f64,
        /// Exterior index of refraction.
        ext_ior: f64,
        /// Mitsuba's `nonlinear`: account for the colour shift of internal scattering.
        nonlinear: bool,
    },
    /// Rough dielectric coating over a diffuse base.
    RoughPlastic {
        /// Base albedo.
        diffuse: TexturedRgb,
        /// Scale of the specular reflection.
        specular: Rgb,
        /// Microfacet roughness.
        alpha: TexturedScalar,
        /// Microfacet distribution.
        distribution: MicrofacetType,
        /// Interior index of refraction.
        int_ior: f64,
        /// Exterior index of refraction.
        ext_ior: f64,
        /// Mitsuba's `nonlinear`.
        nonlinear: bool,
    },
    /// Smooth metal with a complex index of refraction (relative to the exterior medium).
    Conductor {
        /// Real part of the relative index, per channel.
        eta: Rgb,
        /// Imaginary part (absorption), per channel.
        k: Rgb,
        /// Scale of the reflection.
        specular: TexturedRgb,
    },
    /// Rough metal.
    RoughConductor {
        /// Real part of the relative index.
        eta: Rgb,
        /// Imaginary part.
        k: Rgb,
        /// Scale of the reflection.
        specular: TexturedRgb,
        /// Roughness along the tangent.
        alpha_u: TexturedScalar,
        /// Roughness along the bitangent.
        alpha_v: TexturedScalar,
        /// Microfacet distribution.
        distribution: MicrofacetType,
    },
    /// Smooth glass interface.
    Dielectric {
        /// Interior index of refraction.
        int_ior: f64,
        /// Exterior index of refraction.
        ext_ior: f64,
        /// Scale of the reflection.
        specular_reflectance: Rgb,
        /// Scale of the transmission.
        specular_transmittance: Rgb,
    },
    /// Rough glass interface.
    RoughDielectric {
        /// Interior index of refraction.
        int_ior: f64,
        /// Exterior index of refraction.
        ext_ior: f64,
        /// Microfacet roughness.
        alpha: TexturedScalar,
        /// Microfacet distribution.
        distribution: MicrofacetType,
        /// Scale of the reflection.
        specular_reflectance: Rgb,
        /// Scale of the transmission.
        specular_transmittance: Rgb,
    },
    /// A thin glass sheet (both interfaces, no refraction offset).
    ThinDielectric {
        /// Interior index of refraction.
        int_ior: f64,
        /// Exterior index of refraction.
        ext_ior: f64,
        /// Scale of the reflection.
        specular_reflectance: Rgb,
        /// Scale of the transmission.
        specular_transmittance: Rgb,
    },
    /// glTF 2.0 metallic-roughness (with KHR_materials_transmission / _ior / _anisotropy /
    /// _specular / _clearcoat / _sheen).
    PbrMetallicRoughness {
        /// Base colour (linear).
        base_color: TexturedRgb,
        /// Metalness in [0, 1] (glTF: the texture's B channel).
        metallic: TexturedScalar,
        /// Perceptual roughness in [0, 1] (glTF: the texture's G channel); alpha = roughness².
        roughness: TexturedScalar,
        /// Transmission weight in [0, 1] (KHR_materials_transmission, texture R channel).
        transmission: TexturedScalar,
        /// Index of refraction (KHR_materials_ior; 1.5 by default).
        ior: f64,
        /// Anisotropy strength in [0, 1] (KHR_materials_anisotropy; 0 = isotropic).
        anisotropy: f64,
        /// Rotation of the anisotropy direction from the tangent, radians.
        anisotropy_rotation: f64,
        /// KHR_materials_specular / _clearcoat / _sheen factors (their textures are not read).
        layers: PbrLayers,
    },
    /// Any lustre material specification (a fitted material JSON, `sgd:NAME`, an RGL `.bsdf`, a
    /// MERL `.binary`, `kurt(…)`, …), resolved through `lustre_brdf::catalog` at load.
    Spec(ResolvedSpec),
}

/// A lustre material specification and the BSDF it resolved to (shared by every hit).
#[derive(Clone, Debug)]
pub struct ResolvedSpec {
    /// The specification as written (relative paths resolved against the scene file's folder).
    pub spec: String,
    /// The resolved BSDF, with [`ResolvedSpec::edits`] applied.
    pub bsdf: Arc<dyn Bsdf>,
    /// Edits of a fitted model's parameters (`model.…` fields of
    /// [`crate::material_edit`]) made since the specification resolved, in order: (field,
    /// value).
    pub edits: Vec<(String, String)>,
}

impl ResolvedSpec {
    /// Resolves `spec` through `lustre_brdf::catalog::resolve`; errors name `material`.
    pub fn resolve(material: &str, spec: &str) -> Result<ResolvedSpec> {
        let bsdf = lustre_brdf::catalog::resolve(spec)
            .map_err(|e| SceneError::material(material, format!("spec {spec:?}: {e}")))?;
        Ok(ResolvedSpec {
            spec: spec.to_string(),
            bsdf: Arc::from(bsdf),
            edits: vec![],
        })
    }
}

/// Two resolved specs are equal when their specifications and edits are.
impl PartialEq for ResolvedSpec {
    fn eq(&self, other: &Self) -> bool {
        self.spec == other.spec && self.edits == other.edits
    }
}

impl MaterialKind {
    /// The kind's name in Mitsuba's spelling (`diffuse`, `roughplastic`, …; `pbr`, `spec`).
    pub fn name(&self) -> &'static str {
        match self {
            MaterialKind::Diffuse { .. } => "diffuse",
            MaterialKind::Plastic { .. } => "plastic",
            MaterialKind::RoughPlastic { .. } => "roughplastic",
            MaterialKind::Conductor { .. } => "conductor",
            MaterialKind::RoughConductor { .. } => "roughconductor",
            MaterialKind::Dielectric { .. } => "dielectric",
            MaterialKind::RoughDielectric { .. } => "roughdielectric",
            MaterialKind::ThinDielectric { .. } => "thindielectric",
            MaterialKind::PbrMetallicRoughness { .. } => "pbr",
            MaterialKind::Spec(_) => "spec",
        }
    }
}

/// Alpha masking: a surface point is present with probability (or when above `cutoff`) `opacity`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaMask {
    /// Opacity in [0, 1].
    pub opacity: TexturedScalar,
    /// glTF `MASK`: opaque where opacity ≥ cutoff, absent elsewhere. `None`: Mitsuba's `mask`,
    /// stochastic (present with probability = opacity).
    pub cutoff: Option<f32>,
}

/// A tangent-space normal map (glTF convention: RGB in [0, 1] → [−1, 1], +y up in the texture).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalMap {
    /// The texture (linear).
    pub texture: TextureRef,
    /// glTF `normalTexture.scale` (scales x and y).
    pub scale: f32,
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name (the Mitsuba id, the MTL or glTF material name); material overrides match it.
    pub name: String,
    /// Scattering model and parameters.
    pub kind: MaterialKind,
    /// Scatter on both sides alike (Mitsuba `twosided`, glTF `doubleSided`): the BSDF is applied
    /// with the normal flipped towards the viewer.
    pub two_sided: bool,
    /// Alpha masking (cut-outs).
    pub alpha_mask: Option<AlphaMask>,
    /// Normal map.
    pub normal_map: Option<NormalMap>,
    /// Emission texture (sRGB-decoded) that multiplies the mesh's emitted radiance (glTF).
    pub emission_texture: Option<TextureRef>,
    /// Prepared models (see [`Material::bsdf_at`]); filled on first use.
    cache: BsdfCache,
}

impl Material {
    /// A material with defaults (one-sided, no mask, no normal map, no emission texture).
    pub fn new(name: impl Into<String>, kind: MaterialKind) -> Self {
        Material {
            name: name.into(),
            kind,
            two_sided: false,
            alpha_mask: None,
            normal_map: None,
            emission_texture: None,
            cache: BsdfCache::default(),
        }
    }

    /// Replaces the scattering model (an edit), dropping the models prepared for the old one.
    pub fn set_kind(&mut self, kind: MaterialKind) {
        self.kind = kind;
        self.cache = BsdfCache::default();
    }

    /// A Lambertian material of constant albedo.
    pub fn diffuse(name: impl Into<String>, reflectance: Rgb) -> Self {
        Material::new(
            name,
            MaterialKind::Diffuse {
                reflectance: TexturedRgb::constant(reflectance),
            },
        )
    }

    /// Opacity at a hit (1 without a mask). With a cutoff the answer is 0 or 1.
    pub fn alpha_at(&self, textures: &[Texture], uv: &[Vec2; 2]) -> f64 {
        match &self.alpha_mask {
            None => 1.0,
            Some(m) => {
                let a = m.opacity.at(textures, uv).clamp(0.0, 1.0);
                match m.cutoff {
                    Some(c) => {
                        if a >= f64::from(c) {
                            1.0
                        } else {
                            0.0
                        }
                    }
                    None => a,
                }
            }
        }
    }

    /// The tangent-space shading normal from the normal map at a hit (unit, +z = geometric
    /// normal); `None` without a normal map.
    pub fn normal_map_at(&self, textures: &[Texture], uv: &[Vec2; 2]) -> Option<DVec3> {
        let m = self.normal_map?;
        let t = lookup(textures, m.texture, uv)?;
        let x = f64::from((2.0 * t[0] - 1.0) * m.scale);
        let y = f64::from((2.0 * t[1] - 1.0) * m.scale);
        let z = f64::from(2.0 * t[2] - 1.0).max(1e-4);
        Some(DVec3::new(x, y, z).normalize())
    }

    /// The emission texture's factor at a hit (1 without one).
    pub fn emission_at(&self, textures: &[Texture], uv: &[Vec2; 2]) -> Rgb {
        match self.emission_texture.and_then(|t| lookup(textures, t, uv)) {
            Some(s) => Rgb::new(f64::from(s[0]), f64::from(s[1]), f64::from(s[2])),
            None => Rgb::ONE,
        }
    }

    /// Checks that the material builds a BSDF (at uv = 0 and with every texture at its extreme
    /// values clamped), that texture references are in range, and names the problem otherwise.
    pub fn check(&self, textures: &[Texture]) -> Result<()> {
        let refs = self.texture_refs();
        if let Some(r) = refs.iter().find(|r| r.texture >= textures.len()) {
            return Err(SceneError::material(
                &self.name,
                format!(
                    "texture index {} out of range ({} textures)",
                    r.texture,
                    textures.len()
                ),
            ));
        }
        self.bsdf_at(textures, &[Vec2::ZERO; 2]).map(|_| ())
    }

    /// Every texture this material refers to.
    pub fn texture_refs(&self) -> Vec<TextureRef> {
        let mut m = self.clone();
        let mut out = Vec::new();
        m.for_each_texture_ref(|t| out.push(*t));
        out
    }

    /// Calls `f` on every texture reference (to renumber textures when scenes are merged).
    pub fn for_each_texture_ref(&mut self, mut f: impl FnMut(&mut TextureRef)) {
        let rgb = |t: &mut TexturedRgb, f: &mut dyn FnMut(&mut TextureRef)| {
            if let Some(r) = &mut t.texture {
                f(r)
            }
        };
        let sc = |t: &mut TexturedScalar, f: &mut dyn FnMut(&mut TextureRef)| {
            if let Some(r) = &mut t.texture {
                f(r)
            }
        };
        match &mut self.kind {
            MaterialKind::Diffuse { reflectance } => rgb(reflectance, &mut f),
            MaterialKind::Plastic { diffuse, .. } => rgb(diffuse, &mut f),
            MaterialKind::RoughPlastic { diffuse, alpha, .. } => {
                rgb(diffuse, &mut f);
                sc(alpha, &mut f);
            }
            MaterialKind::Conductor { specular, .. } => rgb(specular, &mut f),
            MaterialKind::RoughConductor {
                specular,
                alpha_u,
                alpha_v,
                ..
            } => {
                rgb(specular, &mut f);
                sc(alpha_u, &mut f);
                sc(alpha_v, &mut f);
            }
            MaterialKind::RoughDielectric { alpha, .. } => sc(alpha, &mut f),
            MaterialKind::PbrMetallicRoughness {
                base_color,
                metallic,
                roughness,
                transmission,
                ..
            } => {
                rgb(base_color, &mut f);
                sc(metallic, &mut f);
                sc(roughness, &mut f);
                sc(transmission, &mut f);
            }
            MaterialKind::Dielectric { .. }
            | MaterialKind::ThinDielectric { .. }
            | MaterialKind::Spec(_) => {}
        }
        if let Some(m) = &mut self.alpha_mask {
            sc(&mut m.opacity, &mut f);
        }
        if let Some(n) = &mut self.normal_map {
            f(&mut n.texture);
        }
        if let Some(t) = &mut self.emission_texture {
            f(t);
        }
    }

    /// Evaluates the textures at a hit (`uv[0]`, `uv[1]`: the hit's two UV sets, zero where the
    /// mesh has none) and returns the BSDF there, in the local shading frame (+z the normal).
    ///
    /// Models (lustre-brdf): `Diffuse` → Lambert; `Plastic`/`RoughPlastic` → Mitsuba's
    /// formulations; `Conductor`/`RoughConductor` → complex-Fresnel metals (anisotropic when
    /// αu ≠ αv); `Dielectric`/`RoughDielectric`/`ThinDielectric`; `PbrMetallicRoughness` →
    /// the glTF BRDF, or, with transmission ≥ ½, a (rough) dielectric of the material's ior
    /// tinted by the base colour (roughness² as α; the glTF model has no transmission lobe);
    /// `Spec` → the resolved catalog BSDF. Reflection-only models of a two-sided material are
    /// wrapped in `TwoSided` (transmissive models are two-sided by nature). Texel values are
    /// clamped to the models' ranges (colours to [0, 1], α to [1e-4, 1]).
    ///
    /// Cost: a material without textured BSDF parameters is built once and shared (an `Arc`);
    /// a textured (rough) plastic copies a prototype built once (its coating tables cost
    /// ≈ 0.3 M samples) with `with_reflectances`; the other models are cheap to build.
    /// [`Material::with_bsdf_at`] is the same without the box (nothing allocated per hit).
    pub fn bsdf_at(&self, textures: &[Texture], uv: &[Vec2; 2]) -> Result<Box<dyn Bsdf>> {
        self.build_into(textures, uv, Boxed)
    }

    /// [`Material::bsdf_at`] without allocating: the BSDF at the hit is built on the stack (or
    /// borrowed from the material's cache) and handed to `f`. The path tracer's per-hit call.
    pub fn with_bsdf_at<R>(
        &self,
        textures: &[Texture],
        uv: &[Vec2; 2],
        f: impl FnOnce(&dyn Bsdf) -> R,
    ) -> Result<R> {
        self.build_into(textures, uv, Call(f))
    }

    fn build_into<S: BsdfSink>(
        &self,
        textures: &[Texture],
        uv: &[Vec2; 2],
        sink: S,
    ) -> Result<S::Out> {
        let err = |e: lustre_brdf::Error| SceneError::material(&self.name, e.to_string());
        let textured = self.kind_is_textured();
        if !textured {
            if let Some(Prepared::Whole(key, two_sided, b)) = self.cache.0.get() {
                if *key == self.kind && *two_sided == self.two_sided {
                    return Ok(sink.shared(b));
                }
            }
            let arc: Arc<dyn Bsdf> = Arc::from(self.build(textures, uv, Boxed).map_err(err)?);
            let _ = self.cache.0.set(Prepared::Whole(
                self.kind.clone(),
                self.two_sided,
                arc.clone(),
            ));
            return Ok(sink.shared(&arc));
        }
        self.build(textures, uv, sink).map_err(err)
    }

    /// Hands `b` to the sink, wrapped in `TwoSided` for a two-sided reflection-only material.
    fn emit<S: BsdfSink, B: Bsdf + 'static>(&self, sink: S, b: B) -> lustre_brdf::Result<S::Out> {
        if self.two_sided && !b.flags().transmission {
            Ok(sink.take(TwoSided::new(b)?))
        } else {
            Ok(sink.take(b))
        }
    }

    /// Whether a BSDF parameter (not the mask, normal map or emission) is textured.
    fn kind_is_textured(&self) -> bool {
        let r = |t: &TexturedRgb| t.texture.is_some();
        let s = |t: &TexturedScalar| t.texture.is_some();
        match &self.kind {
            MaterialKind::Diffuse { reflectance } => r(reflectance),
            MaterialKind::Plastic { diffuse, .. } => r(diffuse),
            MaterialKind::RoughPlastic { diffuse, alpha, .. } => r(diffuse) || s(alpha),
            MaterialKind::Conductor { specular, .. } => r(specular),
            MaterialKind::RoughConductor {
                specular,
                alpha_u,
                alpha_v,
                ..
            } => r(specular) || s(alpha_u) || s(alpha_v),
            MaterialKind::RoughDielectric { alpha, .. } => s(alpha),
            MaterialKind::PbrMetallicRoughness {
                base_color,
                metallic,
                roughness,
                transmission,
                ..
            } => r(base_color) || s(metallic) || s(roughness) || s(transmission),
            MaterialKind::Dielectric { .. }
            | MaterialKind::ThinDielectric { .. }
            | MaterialKind::Spec(_) => false,
        }
    }

    /// A (rough) plastic's prototype, built once per material with the base colour at the
    /// texture's mean; hits copy it and set the base colour.
    fn coat_prototype(&self, textures: &[Texture]) -> lustre_brdf::Result<Cow<'_, Prepared>> {
        if let Some(p @ (Prepared::Plastic(key, _) | Prepared::RoughPlastic(key, _))) =
            self.cache.0.get()
        {
            if *key == self.kind {
                return Ok(Cow::Borrowed(p));
            }
        }
        let mean = |t: &TexturedRgb| -> Rgb {
            let m = t
                .texture
                .and_then(|r| textures.get(r.texture))
                .map_or([1.0; 4], |t| t.mean());
            Rgb::new(t.factor[0] * m[0], t.factor[1] * m[1], t.factor[2] * m[2]).map(clamp_unit)
        };
        let p = match &self.kind {
            MaterialKind::Plastic {
                diffuse,
                specular,
                int_ior,
                ext_ior,
                nonlinear,
            } => Prepared::Plastic(
                self.kind.clone(),
                Plastic::new(
                    mean(diffuse),
                    specular.map(clamp_unit),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                )?,
            ),
            MaterialKind::RoughPlastic {
                diffuse,
                specular,
                alpha,
                distribution,
                int_ior,
                ext_ior,
                nonlinear,
            } => Prepared::RoughPlastic(
                self.kind.clone(),
                Box::new(RoughPlastic::new(
                    *distribution,
                    clamp_alpha(alpha.factor),
                    mean(diffuse),
                    specular.map(clamp_unit),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                )?),
            ),
            _ => {
                return Err(lustre_brdf::Error::NotFound(
                    "not a plastic material".to_string(),
                ))
            }
        };
        // A cache holding a model of another kind (the kind was edited) is not overwritten;
        // the fresh prototype is then used by value.
        Ok(match self.cache.0.set(p) {
            Ok(()) => Cow::Borrowed(self.cache.0.get().ok_or_else(mismatch)?),
            Err(p) => Cow::Owned(p),
        })
    }

    /// A rough plastic's coating grid (its roughness is textured), built once per material.
    fn coating(&self) -> lustre_brdf::Result<Cow<'_, Prepared>> {
        if let Some(p @ Prepared::Coating(key, _)) = self.cache.0.get() {
            if *key == self.kind {
                return Ok(Cow::Borrowed(p));
            }
        }
        let MaterialKind::RoughPlastic {
            distribution,
            int_ior,
            ext_ior,
            nonlinear,
            ..
        } = &self.kind
        else {
            return Err(lustre_brdf::Error::NotFound(
                "not a rough plastic material".to_string(),
            ));
        };
        let p = Prepared::Coating(
            self.kind.clone(),
            Box::new(RoughPlasticCoating::new(
                *distribution,
                *int_ior,
                *ext_ior,
                *nonlinear,
            )?),
        );
        Ok(match self.cache.0.set(p) {
            Ok(()) => Cow::Borrowed(self.cache.0.get().ok_or_else(mismatch)?),
            Err(p) => Cow::Owned(p),
        })
    }

    /// Builds the BSDF at a hit and hands it to `sink` (two-sided wrapping included).
    fn build<S: BsdfSink>(
        &self,
        textures: &[Texture],
        uv: &[Vec2; 2],
        sink: S,
    ) -> lustre_brdf::Result<S::Out> {
        let rgb = |t: &TexturedRgb| t.at(textures, uv).map(clamp_unit);
        let alpha = |t: &TexturedScalar| clamp_alpha(t.at(textures, uv));
        match &self.kind {
            MaterialKind::Diffuse { reflectance } => {
                self.emit(sink, Lambert::new(rgb(reflectance))?)
            }
            MaterialKind::Plastic {
                diffuse, specular, ..
            } => match &*self.coat_prototype(textures)? {
                Prepared::Plastic(_, p) => self.emit(
                    sink,
                    p.with_reflectances(rgb(diffuse), specular.map(clamp_unit))?,
                ),
                _ => Err(mismatch()),
            },
            MaterialKind::RoughPlastic {
                diffuse,
                specular,
                alpha: a,
                ..
            } if a.texture.is_none() => match &*self.coat_prototype(textures)? {
                Prepared::RoughPlastic(_, p) => self.emit(
                    sink,
                    p.with_reflectances(rgb(diffuse), specular.map(clamp_unit))?,
                ),
                _ => Err(mismatch()),
            },
            MaterialKind::RoughPlastic {
                diffuse,
                specular,
                alpha: a,
                ..
            } => match &*self.coating()? {
                Prepared::Coating(_, c) => self.emit(
                    sink,
                    c.at(alpha(a), rgb(diffuse), specular.map(clamp_unit))?,
                ),
                _ => Err(mismatch()),
            },
            MaterialKind::Conductor { eta, k, specular } => {
                self.emit(sink, Conductor::new(*eta, *k, rgb(specular))?)
            }
            MaterialKind::RoughConductor {
                eta,
                k,
                specular,
                alpha_u,
                alpha_v,
                distribution,
            } => self.emit(
                sink,
                RoughConductor::new(
                    MicrofacetDistribution::new(*distribution, alpha(alpha_u), alpha(alpha_v))?,
                    ComplexIor::new(*eta, *k)?,
                    rgb(specular),
                )?,
            ),
            MaterialKind::Dielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => self.emit(
                sink,
                Dielectric::new(*int_ior, *ext_ior)?.with_tints(
                    specular_reflectance.map(clamp_unit),
                    specular_transmittance.map(clamp_unit),
                )?,
            ),
            MaterialKind::RoughDielectric {
                int_ior,
                ext_ior,
                alpha: a,
                distribution,
                specular_reflectance,
                specular_transmittance,
            } => self.emit(
                sink,
                RoughDielectric::new(
                    MicrofacetDistribution::isotropic(*distribution, alpha(a))?,
                    *int_ior,
                    *ext_ior,
                )?
                .with_tints(
                    specular_reflectance.map(clamp_unit),
                    specular_transmittance.map(clamp_unit),
                )?,
            ),
            MaterialKind::ThinDielectric {
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => self.emit(
                sink,
                ThinDielectric::new(*int_ior, *ext_ior)?.with_tints(
                    specular_reflectance.map(clamp_unit),
                    specular_transmittance.map(clamp_unit),
                )?,
            ),
            MaterialKind::PbrMetallicRoughness {
                base_color,
                metallic,
                roughness,
                transmission,
                ior,
                anisotropy,
                anisotropy_rotation,
                layers,
            } => {
                let c = rgb(base_color);
                let r = clamp_unit(roughness.at(textures, uv));
                if transmission.at(textures, uv) >= 0.5 {
                    let a = r * r;
                    if a < PBR_ALPHA_MIN {
                        self.emit(sink, Dielectric::new(*ior, 1.0)?.with_tints(Rgb::ONE, c)?)
                    } else {
                        self.emit(
                            sink,
                            RoughDielectric::new(
                                MicrofacetDistribution::isotropic(MicrofacetType::Ggx, a)?,
                                *ior,
                                1.0,
                            )?
                            .with_tints(Rgb::ONE, c)?,
                        )
                    }
                } else {
                    let m = PbrMetallicRoughness::new(c, clamp_unit(metallic.at(textures, uv)), r)?
                        .with_layers(*ior, *layers)?;
                    let m = if *anisotropy > 0.0 {
                        m.with_anisotropy(clamp_unit(*anisotropy), *anisotropy_rotation)?
                    } else {
                        m
                    };
                    self.emit(sink, m)
                }
            }
            MaterialKind::Spec(r) => self.emit(sink, r.bsdf.clone()),
        }
    }
}

/// Where [`Material::build`] delivers the BSDF it built: boxed ([`Material::bsdf_at`]) or lent to
/// a closure on the stack ([`Material::with_bsdf_at`]).
trait BsdfSink {
    type Out;
    /// A model built for this hit.
    fn take<B: Bsdf + 'static>(self, b: B) -> Self::Out;
    /// The material's cached model (untextured materials).
    fn shared(self, b: &Arc<dyn Bsdf>) -> Self::Out;
}

/// Boxes the model.
struct Boxed;

impl BsdfSink for Boxed {
    type Out = Box<dyn Bsdf>;
    fn take<B: Bsdf + 'static>(self, b: B) -> Box<dyn Bsdf> {
        Box::new(b)
    }
    fn shared(self, b: &Arc<dyn Bsdf>) -> Box<dyn Bsdf> {
        Box::new(b.clone())
    }
}

/// Lends the model to a closure.
struct Call<F>(F);

impl<R, F: FnOnce(&dyn Bsdf) -> R> BsdfSink for Call<F> {
    type Out = R;
    fn take<B: Bsdf + 'static>(self, b: B) -> R {
        (self.0)(&b)
    }
    fn shared(self, b: &Arc<dyn Bsdf>) -> R {
        (self.0)(&**b)
    }
}

/// Prepared models of a material; the key is the kind they were built for (a changed kind is
/// rebuilt, never served stale).
#[derive(Clone, Debug)]
enum Prepared {
    Whole(MaterialKind, bool, Arc<dyn Bsdf>),
    Plastic(MaterialKind, Plastic),
    RoughPlastic(MaterialKind, Box<RoughPlastic>),
    /// A rough plastic with a textured roughness: its coating's grid.
    Coating(MaterialKind, Box<RoughPlasticCoating>),
}

/// The per-material cache of prepared models.
#[derive(Clone, Debug, Default)]
struct BsdfCache(OnceLock<Prepared>);

/// A cache never makes two materials differ.
impl PartialEq for BsdfCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// A colour channel or weight as the models take it: NaN → 0, else clamped to [0, 1] (also the
/// GPU records' clamp, `lustre_gpu::material`).
pub fn clamp_unit(x: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(0.0, 1.0)
    }
}

/// A microfacet roughness as the models take it: NaN → 1, else clamped to [10⁻⁴, 1] (also the
/// GPU records' clamp, `lustre_gpu::material`).
pub fn clamp_alpha(a: f64) -> f64 {
    if a.is_nan() {
        1.0
    } else {
        a.clamp(1e-4, 1.0)
    }
}

fn mismatch() -> lustre_brdf::Error {
    lustre_brdf::Error::NotFound("prepared model does not match the material kind".into())
}
