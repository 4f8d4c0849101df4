//! A scene material as the record of the walkthrough's view-dependent pass, built as
//! `Material::bsdf_at` builds the CPU model ([`pack_material`]), and its per-pixel inputs
//! (textured parameters, normal map: [`pack_material_params`]).

use super::fitted::pack_fit;
use super::kinds::*;
use super::{
    lobe_flags, pack_conductor, pack_dielectric, pack_lambert, pack_pbr_metallic_roughness,
    pack_plastic, pack_rough_conductor, pack_rough_dielectric, pack_rough_plastic,
    pack_thin_dielectric, rough_plastic_table, GpuBsdf, FLAG_DELTA_ONLY, FLAG_DIFFUSE_ONLY,
    FLAG_NORMAL_MAPPED, FLAG_TEXTURED, FLAG_TWO_SIDED,
};
use crate::error::{invalid, Result};
use crate::passes::gbuffer::texture_slot;
use crate::passes::lightmap_shade::gpu_scalar;
use lustre_brdf::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use lustre_brdf::models::conductor::{ComplexIor, Conductor};
use lustre_brdf::models::dielectric::Dielectric;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::models::pbr_metallic_roughness::{PbrMetallicRoughness, PBR_ALPHA_MIN};
use lustre_brdf::models::plastic::Plastic;
use lustre_brdf::models::rough_conductor::RoughConductor;
use lustre_brdf::models::rough_dielectric::RoughDielectric;
use lustre_brdf::models::rough_plastic::{RoughPlastic, RoughPlasticCoating};
use lustre_brdf::models::thin_dielectric::ThinDielectric;
use lustre_brdf::rgb::Rgb;
use lustre_scene::material::{clamp_alpha, clamp_unit, TextureRef};
use lustre_scene::{Material, MaterialKind, Scene, TexturedRgb, TexturedScalar};
use lustre_shade::frame::thin_sheet;

/// No texture (a record word).
const NONE: u32 = u32::MAX;

/// The record of a scene material, built as `Material::bsdf_at` builds the CPU model (smooth
/// glass as the thin sheet the CPU frame shades). A rough plastic appends its transmittance
/// table to `tables`. Textured parameters are packed as their clamped factors and flagged
/// ([`FLAG_TEXTURED`]: read per pixel from the [`pack_material_params`] record), a normal map
/// is flagged ([`FLAG_NORMAL_MAPPED`]); a textured glTF material is packed as its BRDF with the
/// relative ior in p1.y, whatever its transmission factor (the pixel's transmission picks the
/// model); a rough plastic with a textured roughness appends its coating's grid
/// ([`RoughPlasticCoating`]: `COATING_ALPHAS` tables, then their Fdr). Errors (naming the
/// material): models not on the GPU in this build.
pub fn pack_material(m: &Material, tables: &mut Vec<f32>) -> Result<GpuBsdf> {
    let name = format!("material {:?}", m.name);
    let brdf = |e: lustre_brdf::Error| invalid(name.clone(), e.to_string());
    let refuse = |why: &str| invalid(name.clone(), format!("{why}: not on the GPU in this build"));
    let mut common = if m.two_sided { FLAG_TWO_SIDED } else { 0 };
    if m.normal_map.is_some() {
        common |= FLAG_NORMAL_MAPPED;
    }
    let record = |kind: u32, flags: u32, p: [[f32; 4]; 8]| GpuBsdf {
        kind,
        flags: flags | common,
        pad0: 0,
        pad1: 0,
        p,
    };
    let thin = thin_sheet(m);
    let kind = thin.as_ref().map_or(&m.kind, |t| &t.kind);
    // A parameter's clamped factor (the value everywhere when untextured) and whether it is
    // textured.
    let rgb = |t: &TexturedRgb| (t.factor.map(clamp_unit), t.texture.is_some());
    let alpha = |t: &TexturedScalar| (clamp_alpha(t.factor), t.texture.is_some());
    let flag = |textured: bool| if textured { FLAG_TEXTURED } else { 0 };
    match kind {
        MaterialKind::Diffuse { reflectance } => {
            let (c, tex) = rgb(reflectance);
            let l = Lambert::new(c).map_err(brdf)?;
            Ok(record(
                KIND_LAMBERT,
                FLAG_DIFFUSE_ONLY | flag(tex),
                pack_lambert(&l)?,
            ))
        }
        MaterialKind::RoughConductor {
            eta,
            k,
            specular,
            alpha_u,
            alpha_v,
            distribution,
        } => {
            let ((au, tu), (av, tv), (c, tc)) = (alpha(alpha_u), alpha(alpha_v), rgb(specular));
            let d = MicrofacetDistribution::new(*distribution, au, av).map_err(brdf)?;
            let ior = ComplexIor::new(*eta, *k).map_err(brdf)?;
            let c = RoughConductor::new(d, ior, c).map_err(brdf)?;
            Ok(record(
                KIND_ROUGH_CONDUCTOR,
                flag(tu || tv || tc),
                pack_rough_conductor(&c)?,
            ))
        }
        MaterialKind::RoughPlastic {
            diffuse,
            specular,
            alpha,
            distribution,
            int_ior,
            ext_ior,
            nonlinear,
        } => {
            let (rho, tex) = rgb(diffuse);
            if alpha.texture.is_some() {
                // The coating's grid (RoughPlasticCoating): per roughness its T table, then
                // the Fdr of every roughness; the pixel's α picks two rows (textured.wgsl).
                let coating =
                    RoughPlasticCoating::new(*distribution, *int_ior, *ext_ior, *nonlinear)
                        .map_err(brdf)?;
                let c = coating
                    .at(clamp_alpha(alpha.factor), rho, specular.map(clamp_unit))
                    .map_err(brdf)?;
                let offset = u32::try_from(tables.len()).unwrap_or(u32::MAX);
                let mut p = pack_rough_plastic(&c, offset)?;
                p[3][3] = 1.0;
                for g in &coating.grid {
                    tables.extend(rough_plastic_table(g));
                }
                tables.extend(coating.grid.iter().map(|g| g.internal_reflectance() as f32));
                return Ok(record(KIND_ROUGH_PLASTIC, FLAG_TEXTURED, p));
            }
            let c = RoughPlastic::new(
                *distribution,
                clamp_alpha(alpha.factor),
                rho,
                specular.map(clamp_unit),
                *int_ior,
                *ext_ior,
                *nonlinear,
            )
            .map_err(brdf)?;
            let offset = u32::try_from(tables.len()).unwrap_or(u32::MAX);
            let p = pack_rough_plastic(&c, offset)?;
            tables.extend(rough_plastic_table(&c));
            Ok(record(KIND_ROUGH_PLASTIC, flag(tex), p))
        }
        MaterialKind::RoughDielectric {
            int_ior,
            ext_ior,
            alpha: a,
            distribution,
            specular_reflectance,
            specular_transmittance,
        } => {
            let (av, tex) = alpha(a);
            let d = MicrofacetDistribution::isotropic(*distribution, av).map_err(brdf)?;
            let c = RoughDielectric::new(d, *int_ior, *ext_ior)
                .and_then(|c| {
                    c.with_tints(
                        specular_reflectance.map(clamp_unit),
                        specular_transmittance.map(clamp_unit),
                    )
                })
                .map_err(brdf)?;
            Ok(record(
                KIND_ROUGH_DIELECTRIC,
                flag(tex),
                pack_rough_dielectric(&c)?,
            ))
        }
        MaterialKind::Conductor { eta, k, specular } => {
            let (c, tex) = rgb(specular);
            let c = Conductor::new(*eta, *k, c).map_err(brdf)?;
            Ok(record(
                KIND_CONDUCTOR,
                FLAG_DELTA_ONLY | flag(tex),
                pack_conductor(&c)?,
            ))
        }
        MaterialKind::ThinDielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => {
            let c = ThinDielectric::new(*int_ior, *ext_ior)
                .and_then(|c| {
                    c.with_tints(
                        specular_reflectance.map(clamp_unit),
                        specular_transmittance.map(clamp_unit),
                    )
                })
                .map_err(brdf)?;
            Ok(record(
                KIND_THIN_DIELECTRIC,
                FLAG_DELTA_ONLY,
                pack_thin_dielectric(&c)?,
            ))
        }
        MaterialKind::Plastic {
            diffuse,
            specular,
            int_ior,
            ext_ior,
            nonlinear,
        } => {
            let (rho, tex) = rgb(diffuse);
            let c = Plastic::new(
                rho,
                specular.map(clamp_unit),
                *int_ior,
                *ext_ior,
                *nonlinear,
            )
            .map_err(brdf)?;
            Ok(record(KIND_PLASTIC, flag(tex), pack_plastic(&c)?))
        }
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
            let (c, tc) = rgb(base_color);
            let r = clamp_unit(roughness.factor);
            let pbr = |m: f64| {
                let b =
                    PbrMetallicRoughness::new(c, clamp_unit(m), r)?.with_layers(*ior, *layers)?;
                if *anisotropy > 0.0 {
                    b.with_anisotropy(clamp_unit(*anisotropy), *anisotropy_rotation)
                } else {
                    Ok(b)
                }
            };
            // The glass the CPU builds where the transmission is ≥ ½ (its relative ior also
            // rides in a textured record).
            let glass = || {
                Dielectric::new(*ior, 1.0)
                    .and_then(|g| g.with_tints(Rgb::ONE, c))
                    .map_err(brdf)
            };
            let textured = tc
                || metallic.texture.is_some()
                || roughness.texture.is_some()
                || transmission.texture.is_some();
            if textured {
                let b = pbr(metallic.factor).map_err(brdf)?;
                let mut p = pack_pbr_metallic_roughness(&b)?;
                let eta = if transmission.texture.is_some() || transmission.factor >= 0.5 {
                    glass()?.eta as f32
                } else {
                    0.0
                };
                if !eta.is_finite() {
                    return Err(invalid(
                        name.clone(),
                        format!("ior {ior} does not fit an f32"),
                    ));
                }
                p[1][1] = eta;
                return Ok(record(KIND_PBR_METALLIC_ROUGHNESS, FLAG_TEXTURED, p));
            }
            if transmission.factor >= 0.5 {
                let g = glass()?;
                let a = r * r;
                if a < PBR_ALPHA_MIN {
                    return Ok(record(
                        KIND_DIELECTRIC,
                        FLAG_DELTA_ONLY,
                        pack_dielectric(&g)?,
                    ));
                }
                let d = MicrofacetDistribution::isotropic(MicrofacetType::Ggx, a).map_err(brdf)?;
                let g = RoughDielectric::new(d, *ior, 1.0)
                    .and_then(|g| g.with_tints(Rgb::ONE, c))
                    .map_err(brdf)?;
                return Ok(record(KIND_ROUGH_DIELECTRIC, 0, pack_rough_dielectric(&g)?));
            }
            let b = pbr(metallic.factor).map_err(brdf)?;
            Ok(record(
                KIND_PBR_METALLIC_ROUGHNESS,
                0,
                pack_pbr_metallic_roughness(&b)?,
            ))
        }
        MaterialKind::Dielectric { .. } => Err(refuse("smooth glass without its thin sheet")),
        // The fitted models (SGD, Cook–Torrance, Kurt).
        MaterialKind::Spec(s) => {
            let (kind, p) = pack_fit(s.bsdf.as_ref())
                .map_err(|e| refuse(&format!("the spec {:?} ({e})", s.spec)))?;
            Ok(record(kind, lobe_flags(&s.bsdf.flags()), p))
        }
    }
}

/// Vec4s per material of the [`pack_material_params`] records.
pub const MATERIAL_PARAMS: usize = 5;

/// The per-pixel inputs of a material's record (`frame_shade.wgsl` reads them where the record
/// is flagged [`FLAG_TEXTURED`] or [`FLAG_NORMAL_MAPPED`]): its textured parameters as
/// `material_albedo.wgsl` reads them — rgb: (factor rgb, texture slot bits, −1 none), then
/// three scalars as `scalar_at` reads them (factor, slot bits, uv set bits, channel bits) —
/// and the normal map (scale, slot bits, 0, 0). Which parameter is which follows the kind
/// (`wgsl/textured.wgsl`): rgb = a Lambert's or plastic's diffuse reflectance, a conductor's
/// specular colour, the glTF base colour; scalars = a rough conductor's αu, αv, a rough
/// dielectric's α, the glTF metallic, roughness, transmission. Every texture is read at uv0
/// (the CPU's view-dependent shading reads both uv sets at uv0). Textures get slots in
/// `slots`. Errors: a texture beyond the scene's (named).
pub fn pack_material_params(
    scene: &Scene,
    m: &Material,
    slots: &mut Vec<usize>,
) -> Result<[[f32; 4]; MATERIAL_PARAMS]> {
    let slot = |t: Option<TextureRef>, slots: &mut Vec<usize>| -> Result<u32> {
        Ok(match t {
            Some(r) => texture_slot(scene, &m.name, r.texture, slots)? as u32,
            None => NONE,
        })
    };
    let mut out = [[0.0f32; 4]; MATERIAL_PARAMS];
    let none = TexturedScalar::constant(0.0);
    let (rgb, scalars): (Option<&TexturedRgb>, [&TexturedScalar; 3]) = match &m.kind {
        MaterialKind::Diffuse { reflectance } => (Some(reflectance), [&none; 3]),
        MaterialKind::Plastic { diffuse, .. } => (Some(diffuse), [&none; 3]),
        MaterialKind::RoughPlastic { diffuse, alpha, .. } => (Some(diffuse), [alpha, &none, &none]),
        MaterialKind::Conductor { specular, .. } => (Some(specular), [&none; 3]),
        MaterialKind::RoughConductor {
            specular,
            alpha_u,
            alpha_v,
            ..
        } => (Some(specular), [alpha_u, alpha_v, &none]),
        MaterialKind::RoughDielectric { alpha, .. } => (None, [alpha, &none, &none]),
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ..
        } => (Some(base_color), [metallic, roughness, transmission]),
        MaterialKind::Dielectric { .. }
        | MaterialKind::ThinDielectric { .. }
        | MaterialKind::Spec(_) => (None, [&none; 3]),
    };
    if let Some(c) = rgb {
        let f = c.factor.0.map(|v| v as f32);
        out[0] = [f[0], f[1], f[2], f32::from_bits(slot(c.texture, slots)?)];
    } else {
        out[0][3] = f32::from_bits(NONE);
    }
    for (row, s) in out[1..4].iter_mut().zip(scalars) {
        *row = gpu_scalar(scene, &m.name, s, slots)?;
    }
    out[4] = match m.normal_map {
        Some(n) => [
            n.scale,
            f32::from_bits(slot(Some(n.texture), slots)?),
            0.0,
            0.0,
        ],
        None => [0.0, f32::from_bits(NONE), 0.0, 0.0],
    };
    Ok(out)
}
