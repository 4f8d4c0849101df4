//! The view-dependent part of the walkthrough frame on the GPU (issue 11 §4, §6, §7),
//! `frame_shade.wgsl`: a compute pass over the G-buffer the raster pass produced (read on the
//! GPU, no read-back between the passes) that adds, per G-buffer pixel, the material's rest
//! f − kd/π integrated against the pre-filtered incident light to the light-mapped image of
//! [`crate::LightmapShadePass`]. The CPU twin is
//! [`lustre_shade::frame::shade_gbuffer_view_dependent`] (per pixel
//! [`lustre_shade::frame::view_dependent`]).
//!
//! Materials are [`GpuBsdf`] records (144 bytes: kind, flags, two pad words, 32 floats of the
//! model's parameters), one binding-free WGSL module per model under `src/wgsl/`. Kind codes:
//! 0 none (no view-dependent part: a light-mapped Lambertian), [`KIND_ROUGH_CONDUCTOR`] 1,
//! [`KIND_ROUGH_PLASTIC`] 2, [`KIND_ROUGH_DIELECTRIC`] 3, [`KIND_CONDUCTOR`] 4,
//! [`KIND_THIN_DIELECTRIC`] 5 (also smooth glass, shaded as a thin sheet as the CPU frame does),
//! [`KIND_PBR_METALLIC_ROUGHNESS`] 6 (a transmissive rough one as kind 3, as the CPU builds it),
//! [`KIND_LAMBERT`] 7 (read only where the light map does not cover the pixel; a textured
//! Lambertian is kind 0), [`KIND_PLASTIC`] 8, [`KIND_DIELECTRIC`] 9 (smooth transmissive glTF
//! glass, built by the CPU as this interface);
//! 16–19 belong to the fitted models (gpu-fits), 20–27 to the analytic models only the adaptive
//! and bandwidth passes evaluate (`analytic`; this pass refuses them). Per pixel the pass reads the diffuse albedo kd
//! as `Lightmapped::albedo` does (textures included) from the light-map pass's records
//! (`material_albedo.wgsl`); a material's textured parameters at uv0 from its
//! [`pack_material_params`] record, resolved into the model's by `wgsl/textured.wgsl`
//! ([`FLAG_TEXTURED`]: diffuse and specular colours, roughness, the glTF base colour, metallic,
//! roughness and transmission); and tilts the shading frame by a normal map as the CPU's
//! `PathTracer::shading_point` does ([`FLAG_NORMAL_MAPPED`]; tangents from the mesh or ∂p/∂u).
//! Materials the pass cannot shade (fitted specs not on the GPU) are refused with a named error, so the caller falls back to the CPU frame.
//!
//! Incident light: every probe's pyramid and the environment's are concatenated into one
//! storage buffer with an offset table and read trilinearly and seamlessly as
//! `CubePyramid::sample` reads them (the texels beyond a face edge from a table built by
//! `lustre_env::cube::fetch_sources`), through the probe's bounding planes; view buffers
//! ([`GpuViewBuffer`]) are read with `ViewBuffer::{locate, level, sample}`'s arithmetic.
//! Methods: regular (Fibonacci lattice), Colbert–Křivánek (per G-buffer pixel SplitMix64
//! points, seeded as the CPU twin) and progressive refinement (frame f's R2 rotation, averaged
//! on the GPU across calls in the target's accumulation buffer; frame 0 resets it).

use crate::compute::{
    buffer_init, compute_pipeline, compute_pipelines, storage_entry, uniform_entry,
};
use crate::context::GpuContext;
use crate::cube_storage::ring_entries;
use crate::error::{invalid, scope_result, wgpu_error, Result};
use crate::fit_models::pack_fit;
use crate::gbuffer::{camera_uniform, map_read, texture_slot, GBufferTarget};
use crate::lightmap_shade::{gpu_scalar, shading_records, ShadeTarget};
use crate::probe_capture::GpuProbe;
use crate::pyramid::GpuPyramid;
use crate::view_buffer::GpuViewBuffer;
use crate::wgsl;
use glam::DVec3;
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
use lustre_scene::material::{Distribution, TextureRef};
use lustre_scene::{Material, MaterialKind, Scene, TexturedRgb, TexturedScalar};
use lustre_shade::frame::{
    thin_sheet, FrameBuffers, FrameLight, FrameMethod, FrameStats, FrameTables,
};
use lustre_shade::image::Image;
use lustre_shade::kernel::BoundingPlane;
use lustre_shade::mirror::ScreenTiles;
use lustre_shade::path::PathCamera;
use lustre_shade::probe::LitScene;
use std::sync::OnceLock;

/// No view-dependent part (a light-mapped Lambertian surface).
pub const KIND_NONE: u32 = 0;
/// `rough_conductor.wgsl`.
pub const KIND_ROUGH_CONDUCTOR: u32 = 1;
/// `rough_plastic.wgsl`.
pub const KIND_ROUGH_PLASTIC: u32 = 2;
/// `rough_dielectric.wgsl`.
pub const KIND_ROUGH_DIELECTRIC: u32 = 3;
/// `conductor.wgsl`.
pub const KIND_CONDUCTOR: u32 = 4;
/// `thin_dielectric.wgsl`.
pub const KIND_THIN_DIELECTRIC: u32 = 5;
/// `pbr_metallic_roughness.wgsl`.
pub const KIND_PBR_METALLIC_ROUGHNESS: u32 = 6;
/// `lambert.wgsl`.
pub const KIND_LAMBERT: u32 = 7;
/// `plastic.wgsl`.
pub const KIND_PLASTIC: u32 = 8;
/// `dielectric.wgsl`.
pub const KIND_DIELECTRIC: u32 = 9;
/// [`GpuBsdf::flags`]: only diffuse lobes (no view-dependent part where kd ≠ 0).
pub const FLAG_DIFFUSE_ONLY: u32 = 4;
/// [`GpuBsdf::flags`]: only Dirac lobes (summed exactly over their branches).
pub const FLAG_DELTA_ONLY: u32 = 1;
/// [`GpuBsdf::flags`]: a two-sided material (the frame is turned towards the viewer).
pub const FLAG_TWO_SIDED: u32 = 2;
/// [`GpuBsdf::flags`]: a BSDF parameter is textured: the pass reads the material's parameters
/// at the pixel's uv0 from its [`pack_material_params`] record and rewrites the model's
/// (`wgsl/textured.wgsl` `textured_bsdf`), as `Material::with_bsdf_at` builds the CPU model;
/// the record holds the clamped factors. Kinds 1–4 and 6–8 (a glTF record may turn into kind 3
/// or 9 per pixel: its transmission decides).
pub const FLAG_TEXTURED: u32 = 8;
/// [`GpuBsdf::flags`]: a normal-mapped material: the shading frame is tilted per pixel as the
/// CPU's `PathTracer::shading_point` tilts it (`wgsl/textured.wgsl` `mapped_normal`).
pub const FLAG_NORMAL_MAPPED: u32 = 16;
/// Entries of a rough plastic's transmittance table (`RoughPlastic::transmittance` at μ = i/63).
pub const ROUGH_PLASTIC_TABLE: usize = 64;

/// One material of the view-dependent pass (144 bytes, `frame_shade.wgsl`'s `GpuBsdf`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBsdf {
    /// Model code (module docs).
    pub kind: u32,
    /// [`FLAG_DELTA_ONLY`] | [`FLAG_TWO_SIDED`] | [`FLAG_DIFFUSE_ONLY`] | [`FLAG_TEXTURED`] |
    /// [`FLAG_NORMAL_MAPPED`].
    pub flags: u32,
    /// Zero.
    pub pad0: u32,
    /// Zero.
    pub pad1: u32,
    /// The model's parameters, in its module's layout.
    pub p: [[f32; 4]; 8],
}

/// The parameters of a record, each checked finite (named in the error).
pub(crate) struct Params {
    pub(crate) p: [[f32; 4]; 8],
    model: &'static str,
}

impl Params {
    pub(crate) fn new(model: &'static str) -> Self {
        Params {
            p: [[0.0; 4]; 8],
            model,
        }
    }

    pub(crate) fn set(&mut self, row: usize, v: [f64; 4]) -> Result<()> {
        for (k, x) in v.iter().enumerate() {
            let y = *x as f32;
            if !y.is_finite() {
                return Err(invalid(
                    self.model,
                    format!("parameter p{row}[{k}] = {x} does not fit an f32"),
                ));
            }
            self.p[row][k] = y;
        }
        Ok(())
    }

    pub(crate) fn rgb(&mut self, row: usize, c: Rgb, w: f64) -> Result<()> {
        self.set(row, [c[0], c[1], c[2], w])
    }
}

fn distribution_code(d: &MicrofacetDistribution) -> f64 {
    match d.kind() {
        MicrofacetType::Beckmann => 0.0,
        MicrofacetType::Ggx => 1.0,
    }
}

/// `rough_conductor.wgsl`'s parameters.
pub fn pack_rough_conductor(m: &RoughConductor) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("rough conductor");
    let d = &m.distribution;
    p.set(0, [d.alpha_u(), d.alpha_v(), distribution_code(d), 0.0])?;
    p.rgb(1, m.ior.eta, 0.0)?;
    p.rgb(2, m.ior.k, 0.0)?;
    p.rgb(3, m.specular_reflectance, 0.0)?;
    Ok(p.p)
}

/// `rough_plastic.wgsl`'s parameters; its transmittance table ([`rough_plastic_table`])
/// starts at entry `table` of the pass's table buffer (p3 = (table, table, 0, 0): one row, no
/// blend; a textured roughness sets p3.w = 1 and the pixel picks two rows of the coating's
/// grid, `wgsl/textured.wgsl`). Errors: an anisotropic coating, a table
/// offset beyond f32's exact integers.
pub fn pack_rough_plastic(m: &RoughPlastic, table: u32) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("rough plastic");
    let d = &m.distribution;
    if d.alpha_u() != d.alpha_v() {
        return Err(invalid(
            "rough plastic",
            "an anisotropic coating is not on the GPU",
        ));
    }
    if table >= 1 << 24 {
        return Err(invalid(
            "rough plastic",
            format!("table offset {table} is not exact in f32"),
        ));
    }
    let (dm, sm) = (m.diffuse_reflectance.mean(), m.specular_reflectance.mean());
    let weight = if dm + sm > 0.0 { sm / (dm + sm) } else { 0.5 };
    p.set(
        0,
        [
            d.alpha_u(),
            distribution_code(d),
            m.eta,
            m.internal_reflectance(),
        ],
    )?;
    p.rgb(1, m.diffuse_reflectance, weight)?;
    p.rgb(2, m.specular_reflectance, f64::from(u8::from(m.nonlinear)))?;
    p.set(3, [f64::from(table), f64::from(table), 0.0, 0.0])?;
    Ok(p.p)
}

/// The rough plastic's external transmittance T(i/63), i = 0..64 (its own table's entries).
pub fn rough_plastic_table(m: &RoughPlastic) -> [f32; ROUGH_PLASTIC_TABLE] {
    let last = (ROUGH_PLASTIC_TABLE - 1) as f64;
    std::array::from_fn(|i| m.transmittance(i as f64 / last) as f32)
}

/// `rough_dielectric.wgsl`'s parameters.
pub fn pack_rough_dielectric(m: &RoughDielectric) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("rough dielectric");
    let d = &m.distribution;
    p.set(0, [d.alpha_u(), d.alpha_v(), distribution_code(d), m.eta])?;
    p.rgb(1, m.specular_reflectance, 0.0)?;
    p.rgb(2, m.specular_transmittance, 0.0)?;
    Ok(p.p)
}

/// `conductor.wgsl`'s parameters.
pub fn pack_conductor(m: &Conductor) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("conductor");
    p.rgb(0, m.ior.eta, 0.0)?;
    p.rgb(1, m.ior.k, 0.0)?;
    p.rgb(2, m.specular_reflectance, 0.0)?;
    Ok(p.p)
}

/// `thin_dielectric.wgsl`'s parameters.
pub fn pack_thin_dielectric(m: &ThinDielectric) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("thin dielectric");
    p.set(0, [m.eta, 0.0, 0.0, 0.0])?;
    p.rgb(1, m.specular_reflectance, 0.0)?;
    p.rgb(2, m.specular_transmittance, 0.0)?;
    Ok(p.p)
}

/// `pbr_metallic_roughness.wgsl`'s parameters.
pub fn pack_pbr_metallic_roughness(m: &PbrMetallicRoughness) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("glTF metallic-roughness");
    p.rgb(0, m.base_color, m.metallic)?;
    p.set(1, [m.alpha(), 0.0, 0.0, 0.0])?;
    Ok(p.p)
}

/// `lambert.wgsl`'s parameters.
pub fn pack_lambert(m: &Lambert) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("Lambert");
    p.rgb(0, m.kd, 0.0)?;
    Ok(p.p)
}

/// `plastic.wgsl`'s parameters.
pub fn pack_plastic(m: &Plastic) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("plastic");
    let (dm, sm) = (m.diffuse_reflectance.mean(), m.specular_reflectance.mean());
    let weight = if dm + sm > 0.0 { sm / (dm + sm) } else { 0.5 };
    p.rgb(0, m.diffuse_reflectance, weight)?;
    p.rgb(1, m.specular_reflectance, f64::from(u8::from(m.nonlinear)))?;
    p.set(2, [m.eta, m.internal_reflectance(), 0.0, 0.0])?;
    Ok(p.p)
}

/// `dielectric.wgsl`'s parameters.
pub fn pack_dielectric(m: &Dielectric) -> Result<[[f32; 4]; 8]> {
    let mut p = Params::new("dielectric");
    p.set(0, [m.eta, 0.0, 0.0, 0.0])?;
    p.rgb(1, m.specular_reflectance, 0.0)?;
    p.rgb(2, m.specular_transmittance, 0.0)?;
    Ok(p.p)
}

/// lustre-scene's clamps of colours and roughness (`Material::bsdf_at`).
fn unit(x: f64) -> f64 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(0.0, 1.0)
    }
}

fn clamp_alpha(a: f64) -> f64 {
    if a.is_nan() {
        1.0
    } else {
        a.clamp(1e-4, 1.0)
    }
}

fn microfacet(d: Distribution) -> MicrofacetType {
    match d {
        Distribution::Beckmann => MicrofacetType::Beckmann,
        Distribution::Ggx => MicrofacetType::Ggx,
    }
}

/// [`FLAG_DIFFUSE_ONLY`] or [`FLAG_DELTA_ONLY`] as a model's lobes are.
pub(crate) fn lobe_flags(f: &lustre_brdf::bsdf::BsdfFlags) -> u32 {
    if f.diffuse_only() {
        FLAG_DIFFUSE_ONLY
    } else if f.delta_only() {
        FLAG_DELTA_ONLY
    } else {
        0
    }
}

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
    let rgb = |t: &TexturedRgb| (t.factor.map(unit), t.texture.is_some());
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
            let d = MicrofacetDistribution::new(microfacet(*distribution), au, av).map_err(brdf)?;
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
                let coating = RoughPlasticCoating::new(
                    microfacet(*distribution),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                )
                .map_err(brdf)?;
                let c = coating
                    .at(clamp_alpha(alpha.factor), rho, specular.map(unit))
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
                microfacet(*distribution),
                clamp_alpha(alpha.factor),
                rho,
                specular.map(unit),
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
            let d =
                MicrofacetDistribution::isotropic(microfacet(*distribution), av).map_err(brdf)?;
            let c = RoughDielectric::new(d, *int_ior, *ext_ior)
                .and_then(|c| {
                    c.with_tints(
                        specular_reflectance.map(unit),
                        specular_transmittance.map(unit),
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
                        specular_reflectance.map(unit),
                        specular_transmittance.map(unit),
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
            let c = Plastic::new(rho, specular.map(unit), *int_ior, *ext_ior, *nonlinear)
                .map_err(brdf)?;
            Ok(record(KIND_PLASTIC, flag(tex), pack_plastic(&c)?))
        }
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ior,
            ..
        } => {
            let (c, tc) = rgb(base_color);
            let r = unit(roughness.factor);
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
                let b = PbrMetallicRoughness::new(c, unit(metallic.factor), r).map_err(brdf)?;
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
            let b = PbrMetallicRoughness::new(c, unit(metallic.factor), r).map_err(brdf)?;
            Ok(record(
                KIND_PBR_METALLIC_ROUGHNESS,
                0,
                pack_pbr_metallic_roughness(&b)?,
            ))
        }
        MaterialKind::Dielectric { .. } => Err(refuse("smooth glass without its thin sheet")),
        // The fitted models (SGD, Cook–Torrance, Kurt: kinds 16–19).
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

/// Everything the pass reads besides the G-buffer: per-triangle records, materials with their
/// per-pixel parameter records ([`pack_material_params`]) and tangents, the cube maps, the view
/// buffers, and what the per-pixel diffuse albedo kd is read from (the light-map pass's
/// triangle and material records and textures, [`crate::lightmap_shade`]).
#[derive(Debug)]
pub struct FrameShadeScene {
    tris: wgpu::Buffer,
    bsdfs: wgpu::Buffer,
    tables: wgpu::Buffer,
    cube_texels: wgpu::Buffer,
    cube_levels: wgpu::Buffer,
    cubes: wgpu::Buffer,
    planes: wgpu::Buffer,
    ring: wgpu::Buffer,
    view_radiance: wgpu::Buffer,
    view_geometry: wgpu::Buffer,
    views: wgpu::Buffer,
    params: wgpu::Buffer,
    tangents: wgpu::Buffer,
    albedo_tris: wgpu::Buffer,
    albedo_mats: wgpu::Buffer,
    texels: wgpu::Buffer,
    texture_info: wgpu::Buffer,
    /// Per view buffer: its first texel in `view_radiance`.
    view_offsets: Vec<u32>,
    page: [u32; 2],
    probes: u32,
    environment: u32,
    /// The largest of the objects' own sample budgets (0: none has one).
    own_samples: u32,
    /// The scene's view-dependent materials, as packed.
    pub materials: Vec<GpuBsdf>,
}

const NONE: u32 = u32::MAX;

/// ∂p/∂u and ∂p/∂v of triangle `t` with texture coordinates `uv` (pbrt-v4 Eq. 6.7), as the CPU's
/// `PathTracer::shading_point` takes them: (e1, 0) where the uvs are missing or degenerate.
fn surface_derivatives(t: &[DVec3; 3], uv: Option<&[[f64; 2]; 3]>) -> (DVec3, DVec3) {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    match uv {
        Some(uvt) => {
            let (du1, dv1) = (uvt[1][0] - uvt[0][0], uvt[1][1] - uvt[0][1]);
            let (du2, dv2) = (uvt[2][0] - uvt[0][0], uvt[2][1] - uvt[0][1]);
            let det = du1 * dv2 - dv1 * du2;
            if det.abs() > 1e-12 {
                ((e1 * dv2 - e2 * dv1) / det, (e2 * du1 - e1 * du2) / det)
            } else {
                (e1, DVec3::ZERO)
            }
        }
        None => (e1, DVec3::ZERO),
    }
}

/// A storage buffer of `data`, one zero element when it is empty (bindings are never empty).
fn storage<T: bytemuck::Pod + bytemuck::Zeroable>(
    ctx: &GpuContext,
    label: &str,
    data: &[T],
) -> wgpu::Buffer {
    let zero = [T::zeroed()];
    let data = if data.is_empty() { &zero[..] } else { data };
    buffer_init(
        ctx,
        label,
        bytemuck::cast_slice(data),
        wgpu::BufferUsages::STORAGE,
    )
}

/// Concatenates GPU buffers into one (on the GPU), returning it and each part's offset in
/// elements of `elem` bytes.
fn concat(
    ctx: &GpuContext,
    label: &str,
    parts: &[&wgpu::Buffer],
    elem: u64,
) -> (wgpu::Buffer, Vec<u32>) {
    let total: u64 = parts.iter().map(|b| b.size()).sum();
    let out = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: total.max(elem),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    let mut offsets = Vec::with_capacity(parts.len());
    let mut at = 0;
    for b in parts {
        offsets.push((at / elem) as u32);
        enc.copy_buffer_to_buffer(b, 0, &out, at, b.size());
        at += b.size();
    }
    ctx.queue.submit([enc.finish()]);
    (out, offsets)
}

impl FrameShadeScene {
    /// Uploads the CPU frame's incident light (`light`'s probes, else its environment) and
    /// view buffers (`buffers`) and builds the per-triangle records of `lit`.
    pub fn upload(
        ctx: &GpuContext,
        lit: &LitScene,
        light: &FrameLight,
        buffers: &FrameBuffers,
    ) -> Result<Self> {
        let probes = light
            .probes
            .iter()
            .map(|p| {
                Ok(GpuProbe {
                    name: p.name.clone(),
                    mesh: p.mesh,
                    pyramid: GpuPyramid::upload(ctx, &p.pyramid)?,
                    centre: p.centre,
                    planes: p.planes.clone(),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let environment = match (light.probes.is_empty(), light.environment) {
            (true, Some(e)) => Some(GpuPyramid::upload(ctx, e)?),
            _ => None,
        };
        let views = buffers
            .mirrors
            .iter()
            .map(|m| &m.view)
            .chain(&buffers.see_throughs)
            .map(|v| GpuViewBuffer::upload(ctx, v))
            .collect::<Result<Vec<_>>>()?;
        Self::new(
            ctx,
            lit,
            &buffers.tables(),
            &probes,
            environment.as_ref(),
            &views,
        )
    }

    /// The pass's inputs from GPU-resident probes (one per `lit` probe object, in the order of
    /// `links.probe_of_mesh`), the environment's pyramid (read when there is no probe) and
    /// view buffers (`links`' mirrors then see-throughs, in order). Errors: a material the
    /// pass cannot shade ([`pack_material`]), too many probes or views.
    pub fn new(
        ctx: &GpuContext,
        lit: &LitScene,
        links: &FrameTables,
        probes: &[GpuProbe],
        environment: Option<&GpuPyramid>,
        views: &[GpuViewBuffer],
    ) -> Result<Self> {
        let scene = lit.scene;
        let g = &lit.path_scene.geometry;
        if views.len() != links.mirrors() + links.see_throughs {
            return Err(invalid(
                "view buffers",
                format!(
                    "{} given, the frame has {} mirrors and {} see-through buffers",
                    views.len(),
                    links.mirrors(),
                    links.see_throughs
                ),
            ));
        }
        // Materials, packed only where a triangle of a shaded mesh uses them.
        let mut used = vec![false; scene.materials.len()];
        for (prim, &m) in lit.mesh_of.iter().enumerate() {
            if !scene.meshes[m as usize].hints.diffuse_only {
                if let Some(u) = used.get_mut(g.material[prim] as usize) {
                    *u = true;
                }
            }
        }
        let mut tables = vec![];
        let mut materials = vec![GpuBsdf::zeroed_record(); scene.materials.len()];
        let mut params = vec![[0.0f32; 4]; MATERIAL_PARAMS * scene.materials.len().max(1)];
        let mut slots = vec![];
        for (k, m) in scene.materials.iter().enumerate() {
            if used[k] {
                materials[k] = pack_material(m, &mut tables)?;
                params[MATERIAL_PARAMS * k..MATERIAL_PARAMS * (k + 1)]
                    .copy_from_slice(&pack_material_params(scene, m, &mut slots)?);
            }
        }
        // kd per pixel (`Lightmapped::albedo`): the light-map pass's records, their textures
        // after the parameters'.
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        let albedo = shading_records(scene, lit.lit, g, lit.lit.spec(), slots, limit)?;
        let atlas = lit.lit.atlas();
        // Per triangle: 7 vec4 (frame_shade.wgsl `shade_point`); per triangle of a
        // normal-mapped material, 4 vec4 in `tangents`.
        let bits = |u: u32| f32::from_bits(u);
        let v4 = |v: DVec3, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
        let mut tris: Vec<[f32; 4]> = Vec::with_capacity(g.positions.len() * 7);
        let mut own_samples = 0;
        let mut tangents: Vec<[f32; 4]> = vec![];
        for (prim, t) in g.positions.iter().enumerate() {
            let mesh = lit.mesh_of[prim] as usize;
            let k = g.material[prim];
            let material = if scene.meshes[mesh].hints.diffuse_only {
                NONE
            } else {
                k
            };
            let normals = g.normals.get(prim);
            let nz = [DVec3::ZERO; 3];
            let n = normals.unwrap_or(&nz);
            let (dpdu, dpdv) = surface_derivatives(t, g.uvs.get(prim));
            // A normal-mapped material's tangent block (`mapped_normal`'s inputs): the corners'
            // tangents (xyz, w: the bitangent's sign; w = 0: derive T from ∂p/∂u), ∂p/∂v.
            let mapped = material != NONE
                && materials
                    .get(k as usize)
                    .is_some_and(|b| b.flags & FLAG_NORMAL_MAPPED != 0);
            let tangent_block = if mapped {
                let at = u32::try_from(tangents.len()).unwrap_or(NONE);
                let tc = g.tangents.get(prim).copied().unwrap_or([[0.0; 4]; 3]);
                let sign = if tc[0][3] != 0.0 {
                    tc[0][3].signum()
                } else {
                    0.0
                };
                for c in tc {
                    tangents.push([c[0] as f32, c[1] as f32, c[2] as f32, sign as f32]);
                }
                tangents.push(v4(dpdv, 0.0));
                at
            } else {
                NONE
            };
            let probe = links.probe_of_mesh[mesh].map_or(NONE, |i| i as u32);
            let mirror = links.mirror_at(mesh, prim).map_or(NONE, |i| i as u32);
            let see =
                links.see_through_of_mesh[mesh].map_or(NONE, |i| (links.mirrors() + i) as u32);
            // The object's own sample budget (0: the frame's).
            let samples = scene.meshes[mesh]
                .hints
                .samples
                .map_or(0, |s| s.clamp(1, lustre_shade::frame::MAX_SAMPLES as u32));
            own_samples = own_samples.max(samples);
            tris.extend([
                v4(t[0], bits(material)),
                v4(t[1], bits(samples)),
                v4(t[2], bits(u32::from(normals.is_some()))),
                v4(n[0], bits(probe)),
                v4(n[1], bits(mirror)),
                v4(n[2], bits(see)),
                v4(dpdu, bits(tangent_block)),
            ]);
        }
        // Cube maps: the probes, then the environment when there is no probe.
        let mut pyramids: Vec<(&GpuPyramid, DVec3, &[BoundingPlane])> = probes
            .iter()
            .map(|p| (&p.pyramid, p.centre, &p.planes[..]))
            .collect();
        let env_index = match environment {
            Some(e) if probes.is_empty() => {
                pyramids.push((e, DVec3::ZERO, &[]));
                0
            }
            _ => NONE,
        };
        let level_buffers: Vec<&wgpu::Buffer> = pyramids
            .iter()
            .flat_map(|(p, _, _)| p.levels.iter())
            .collect();
        let (cube_texels, offsets) = concat(ctx, "frame cube texels", &level_buffers, 16);
        let mut cube_levels: Vec<[u32; 4]> = vec![];
        let mut cubes: Vec<[f32; 4]> = vec![];
        let mut planes: Vec<[f32; 4]> = vec![];
        let mut ring = vec![];
        for (p, centre, pl) in &pyramids {
            let first = cube_levels.len() as u32;
            for &n in &p.sizes {
                let texel = offsets[cube_levels.len()];
                cube_levels.push([texel, n as u32, ring.len() as u32, 0]);
                ring_entries(n, texel, &mut ring);
            }
            cubes.push(v4(*centre, bits(first)));
            cubes.push([
                bits(p.sizes.len() as u32),
                bits((planes.len() / 2) as u32),
                bits(pl.len() as u32),
                0.0,
            ]);
            for b in *pl {
                planes.push(v4(b.point, 0.0));
                planes.push(v4(b.normal, 0.0));
            }
        }
        // View buffers.
        let radiance: Vec<&wgpu::Buffer> = views.iter().map(|v| &v.radiance).collect();
        let geometry: Vec<&wgpu::Buffer> = views.iter().map(|v| &v.geometry).collect();
        let (view_radiance, r_off) = concat(ctx, "frame view radiance", &radiance, 16);
        let (view_geometry, g_off) = concat(ctx, "frame view geometry", &geometry, 16);
        let mut view_records: Vec<[f32; 4]> = vec![];
        for (i, v) in views.iter().enumerate() {
            let c = &v.camera;
            let front = v.front;
            view_records.extend([
                v4(c.origin, c.tan_half_fov_y as f32),
                v4(c.forward, 0.0),
                v4(c.right, 0.0),
                v4(c.up, 0.0),
                [
                    bits(v.width as u32),
                    bits(v.height as u32),
                    bits(v.level_sizes.len() as u32),
                    bits(r_off[i]),
                ],
                [bits(g_off[i]), bits(u32::from(front.is_some())), 0.0, 0.0],
                v4(front.map_or(DVec3::ZERO, |f| f.point), 0.0),
                v4(front.map_or(DVec3::ZERO, |f| f.normal), 0.0),
            ]);
        }
        Ok(FrameShadeScene {
            tris: storage(ctx, "frame triangles", &tris),
            bsdfs: storage(ctx, "frame materials", &materials),
            tables: storage(ctx, "frame material tables", &tables),
            cube_texels,
            cube_levels: storage(ctx, "frame cube levels", &cube_levels),
            cubes: storage(ctx, "frame cubes", &cubes),
            planes: storage(ctx, "frame planes", &planes),
            ring: storage(ctx, "frame cube rings", &ring),
            view_radiance,
            view_geometry,
            views: storage(ctx, "frame views", &view_records),
            params: storage(ctx, "frame material parameters", &params),
            tangents: storage(ctx, "frame tangents", &tangents),
            albedo_tris: storage(ctx, "frame albedo triangles", &albedo.tris),
            albedo_mats: storage(ctx, "frame albedo materials", &albedo.mats),
            texels: storage(ctx, "frame texels", &albedo.texels),
            texture_info: storage(ctx, "frame textures", &albedo.info),
            view_offsets: r_off,
            page: [atlas.width, atlas.height],
            probes: probes.len() as u32,
            environment: env_index,
            own_samples,
            materials,
        })
    }
}

impl FrameShadeScene {
    /// Copies view buffer `index`'s radiance (every level) into the pass's concatenation,
    /// after `view` was shaded again (a see-through layer). Submitted, not waited for.
    /// Errors: no such view, a buffer of another size.
    pub fn refresh_view(&self, ctx: &GpuContext, index: usize, view: &GpuViewBuffer) -> Result<()> {
        let at = self.view_offsets.get(index).copied().ok_or_else(|| {
            invalid(
                "view buffer",
                format!("no view {index} among {}", self.view_offsets.len()),
            )
        })?;
        let start = u64::from(at) * 16;
        let end = self
            .view_offsets
            .get(index + 1)
            .map_or(self.view_radiance.size(), |&o| u64::from(o) * 16);
        if view.radiance.size() != end - start {
            return Err(invalid(
                "view buffer",
                format!(
                    "view {index} holds {} bytes, the frame's copy {}",
                    view.radiance.size(),
                    end - start
                ),
            ));
        }
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view refresh"),
            });
        enc.copy_buffer_to_buffer(&view.radiance, 0, &self.view_radiance, start, end - start);
        ctx.queue.submit([enc.finish()]);
        Ok(())
    }
}

impl GpuBsdf {
    /// Kind 0 (no view-dependent part), no flags.
    pub fn zeroed_record() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

/// The WGSL source of the pass: the modules it imports, then `frame_shade.wgsl`.
pub fn frame_shade_wgsl() -> &'static str {
    static SRC: OnceLock<String> = OnceLock::new();
    SRC.get_or_init(|| {
        wgsl::compose(
            &[
                &wgsl::BSDF,
                &wgsl::MIP,
                &wgsl::PLANES,
                &wgsl::QMC,
                &wgsl::WARP,
                &wgsl::TEXTURED,
                &wgsl::CUBE_STORAGE,
            ],
            &[
                include_str!("texture_sample.wgsl"),
                include_str!("material_albedo.wgsl"),
                include_str!("frame_shade.wgsl"),
            ]
            .concat(),
        )
    })
}

/// One case of [`evaluate_models`]: record `record` at ωo, evaluated at ωi and sampled at u.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelCase {
    /// Index into the records.
    pub record: u32,
    /// ωo (local frame).
    pub wo: [f32; 3],
    /// ωi (local frame) of eval and pdf.
    pub wi: [f32; 3],
    /// The sample's (u1, u2).
    pub u: [f32; 2],
}

/// What [`evaluate_models`] returns per case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelResult {
    /// f(ωi, ωo).
    pub eval: [f32; 3],
    /// pdf(ωi, ωo).
    pub pdf: f32,
    /// The sampled direction.
    pub sample_wi: [f32; 3],
    /// Its pdf (0: no sample, the CPU's `None`).
    pub sample_pdf: f32,
    /// Its value.
    pub sample_value: [f32; 3],
    /// Whether it came from a Dirac lobe.
    pub delta: bool,
}

/// Runs `bsdf.wgsl`'s sample / eval / pdf of `records` (with their `tables`) on `cases` on
/// the GPU: the twins the parity tests hold against lustre-brdf.
pub fn evaluate_models(
    ctx: &GpuContext,
    records: &[GpuBsdf],
    tables: &[f32],
    cases: &[ModelCase],
) -> Result<Vec<ModelResult>> {
    static SRC: OnceLock<String> = OnceLock::new();
    let src = SRC.get_or_init(|| wgsl::compose(&[&wgsl::BSDF], include_str!("bsdf_models.wgsl")));
    if let Some(c) = cases.iter().find(|c| c.record as usize >= records.len()) {
        return Err(invalid(
            "model case",
            format!("record {} of {}", c.record, records.len()),
        ));
    }
    let (pipeline, layout) = compute_pipeline(
        ctx,
        "bsdf_models.wgsl",
        "compiling bsdf_models.wgsl",
        src,
        &[
            storage_entry(0, true),
            storage_entry(1, true),
            storage_entry(2, true),
            storage_entry(3, false),
        ],
    )?;
    let input: Vec<[f32; 4]> = cases
        .iter()
        .flat_map(|c| {
            [
                [c.wo[0], c.wo[1], c.wo[2], f32::from_bits(c.record)],
                [c.wi[0], c.wi[1], c.wi[2], 0.0],
                [c.u[0], c.u[1], 0.0, 0.0],
            ]
        })
        .collect();
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
    let out_bytes = (input.len().max(1) * 16) as u64;
    let results = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("model results"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("model results readback"),
        size: out_bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let (r, t, c) = (
        storage(ctx, "model records", records),
        storage(ctx, "model tables", tables),
        storage(ctx, "model cases", &input),
    );
    let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("bsdf_models.wgsl"),
        layout: &layout,
        entries: &[buf(0, &r), buf(1, &t), buf(2, &c), buf(3, &results)],
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("model cases"),
        });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("model cases"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((cases.len() as u32).div_ceil(64).max(1), 1, 1);
    }
    enc.copy_buffer_to_buffer(&results, 0, &staging, 0, out_bytes);
    ctx.queue.submit([enc.finish()]);
    let bytes = map_read(ctx, &staging, "model cases", scope)?;
    let v: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    Ok(cases
        .iter()
        .enumerate()
        .map(|(i, _)| {
            let (a, b, c) = (v[3 * i], v[3 * i + 1], v[3 * i + 2]);
            ModelResult {
                eval: [a[0], a[1], a[2]],
                pdf: a[3],
                sample_wi: [b[0], b[1], b[2]],
                sample_pdf: b[3],
                sample_value: [c[0], c[1], c[2]],
                delta: c[3] > 0.5,
            }
        })
        .collect())
}

/// The output of the pass: the frame (light-mapped + view-dependent), the progressive
/// accumulation and the view-dependent sums of a frame's sample dispatches (per G-buffer pixel)
/// and the counts.
#[derive(Debug)]
pub struct FrameShadeTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    out: wgpu::Buffer,
    accum: wgpu::Buffer,
    partial: wgpu::Buffer,
    counts: wgpu::Buffer,
}

impl FrameShadeTarget {
    /// An output of `w`×`h` pixels of a G-buffer supersampled k×k. Errors: a zero size, a
    /// buffer beyond the device's limit.
    pub fn new(ctx: &GpuContext, w: u32, h: u32, k: u32) -> Result<Self> {
        let bytes = u64::from(w) * u64::from(h) * 16;
        let accum = bytes * u64::from(k) * u64::from(k);
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        if w == 0 || h == 0 || k == 0 || accum > limit {
            return Err(invalid(
                "image size",
                format!("{w}×{h} at {k}×{k} must be non-empty and fit {limit} bytes of storage"),
            ));
        }
        let buffer = |label: &str, size: u64| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Ok(FrameShadeTarget {
            width: w,
            height: h,
            out: buffer("frame output", bytes),
            accum: buffer("frame accumulation", accum),
            partial: buffer("frame sample sums", accum),
            counts: buffer("frame counts", 8),
        })
    }

    fn read(&self, ctx: &GpuContext, b: &wgpu::Buffer) -> Result<Vec<u8>> {
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame readback"),
            size: b.size(),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame readback"),
            });
        enc.copy_buffer_to_buffer(b, 0, &staging, 0, b.size());
        ctx.queue.submit([enc.finish()]);
        map_read(ctx, &staging, "frame readback", scope)
    }

    /// Copies the frame to the host.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Image> {
        let bytes = self.read(ctx, &self.out)?;
        let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        Image::from_data(
            self.width as usize,
            self.height as usize,
            px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        )
        .map_err(|e| wgpu_error("frame readback", e))
    }

    /// The counts of the last call (one progressive frame): G-buffer pixels with a
    /// view-dependent part, lookups.
    pub fn stats(&self, ctx: &GpuContext) -> Result<FrameStats> {
        let bytes = self.read(ctx, &self.counts)?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(FrameStats {
            glossy_hits: u64::from(c[0]),
            lookups: u64::from(c[1]),
            ..FrameStats::default()
        })
    }
}

/// Options of one call of [`FrameShadePass::shade`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameShadeOptions {
    /// Samples per G-buffer pixel (1..=`lustre_shade::frame::MAX_SAMPLES`).
    pub samples: u32,
    /// Regular or CK; `Progressive` shades frame `frame` and averages it into the target's
    /// accumulation (frame 0 resets it: a camera move).
    pub method: FrameMethod,
    /// The progressive frame index.
    pub frame: u32,
    /// Seed of the CK points.
    pub seed: u64,
}

/// The light-mapped image a run adds to: the first w·h RGBA f32 texels of a buffer.
struct Lit<'a> {
    buffer: &'a wgpu::Buffer,
    width: u32,
    height: u32,
}

/// Samples per G-buffer pixel in one dispatch of the pass's sampling entry point. llvmpipe
/// (lavapipe) ends all loops of an invocation silently once they have run 65,535 iterations
/// together (`LP_MAX_TGSI_LOOP_ITERATIONS`); one output pixel of 4×4 G-buffer pixels at 256
/// samples each came out at 24.5 dB against the CPU twin, 64 samples at 129 dB. A frame's
/// sampling is dispatched ⌈n/64⌉ times, one thread per G-buffer pixel, each adding its share.
pub const SAMPLES_PER_DISPATCH: u32 = 64;

/// The compiled pass: the sampling entry point (per G-buffer pixel) and the resolve (per
/// output pixel).
#[derive(Debug)]
pub struct FrameShadePass {
    samples: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

fn texture_entry(binding: u32, sample_type: wgpu::TextureSampleType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn buf(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: b.as_entire_binding(),
    }
}

impl FrameShadePass {
    /// Compiles `frame_shade.wgsl` with its modules.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let mut entries = vec![
            uniform_entry(0),
            texture_entry(1, wgpu::TextureSampleType::Uint),
            texture_entry(2, wgpu::TextureSampleType::Float { filterable: false }),
        ];
        entries.extend((3..15).map(|b| storage_entry(b, true)));
        entries.extend((15..18).map(|b| storage_entry(b, false)));
        entries.extend((18..25).map(|b| storage_entry(b, true)));
        entries.push(storage_entry(25, false));
        let ([samples, resolve], layout) = compute_pipelines(
            ctx,
            "frame_shade.wgsl",
            "compiling frame_shade.wgsl",
            frame_shade_wgsl(),
            &entries,
            ["samples_main", "main"],
        )?;
        Ok(FrameShadePass {
            samples,
            resolve,
            layout,
        })
    }

    /// Shades the (k·w)×(k·h) `gbuffer` seen from `camera`: `lightmapped` (the w×h light-map
    /// shading of the same G-buffer) plus the view-dependent part, into `out` (submitted, not
    /// waited for). Errors: mismatched sizes, a sample count outside 1..=MAX_SAMPLES.
    #[allow(clippy::too_many_arguments)]
    pub fn shade(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        lightmapped: &ShadeTarget,
        camera: &PathCamera,
        k: u32,
        opts: &FrameShadeOptions,
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let lit = Lit {
            buffer: lightmapped.buffer(),
            width: lightmapped.width,
            height: lightmapped.height,
        };
        self.dispatch(ctx, scene, gbuffer, lit, camera, k, opts, (None, true), out)
    }

    /// The see-through layer of view buffer `view` (index `index` of `scene`'s views, a
    /// see-through buffer), as `lustre_shade::frame::shade_see_through_layer`: its light-mapped
    /// level 0 plus the view-dependent part of the pixels in the covered `tiles` of its
    /// w×h G-buffer `gbuffer` with `SEE_THROUGH_SAMPLES` regular samples, see-through buffers
    /// not read, written into `out` (w×h at k = 1) and copied over the view's level 0; the
    /// caller rebuilds its MIP levels ([`crate::GpuViewPass::build_levels`]) and the scene's
    /// copy ([`FrameShadeScene::refresh_view`]). Submitted, not waited for. Errors: sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn shade_see_through_layer(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        view: &GpuViewBuffer,
        camera: &PathCamera,
        tiles: &ScreenTiles,
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let (w, h) = (view.width as u32, view.height as u32);
        if (out.width, out.height) != (w, h) {
            return Err(invalid(
                "see-through layer",
                format!(
                    "a {}×{} output for a {w}×{h} view buffer",
                    out.width, out.height
                ),
            ));
        }
        let lit = Lit {
            buffer: &view.radiance,
            width: w,
            height: h,
        };
        let opts = FrameShadeOptions {
            samples: lustre_shade::frame::SEE_THROUGH_SAMPLES as u32,
            method: FrameMethod::Regular,
            frame: 0,
            seed: 0,
        };
        self.dispatch(
            ctx,
            scene,
            gbuffer,
            lit,
            camera,
            1,
            &opts,
            (Some(tiles), false),
            out,
        )?;
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("see-through layer"),
            });
        enc.copy_buffer_to_buffer(&out.out, 0, &view.radiance, 0, out.out.size());
        ctx.queue.submit([enc.finish()]);
        Ok(())
    }

    /// One run of the pass: the tiles shaded (all: `None`) and whether see-through buffers are
    /// read.
    #[allow(clippy::too_many_arguments)]
    fn dispatch(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        lightmapped: Lit,
        camera: &PathCamera,
        k: u32,
        opts: &FrameShadeOptions,
        (tiles, see_through): (Option<&ScreenTiles>, bool),
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let max = lustre_shade::frame::MAX_SAMPLES as u32;
        if opts.samples == 0 || opts.samples > max {
            return Err(invalid(
                "samples",
                format!("{} is outside 1..={max}", opts.samples),
            ));
        }
        if k == 0
            || gbuffer.width != out.width * k
            || gbuffer.height != out.height * k
            || (lightmapped.width, lightmapped.height) != (out.width, out.height)
        {
            return Err(invalid(
                "supersampling",
                format!(
                    "a {}×{} G-buffer, a {}×{} light-mapped image and a {}×{} output do not \
                     agree at {k}×{k}",
                    gbuffer.width,
                    gbuffer.height,
                    lightmapped.width,
                    lightmapped.height,
                    out.width,
                    out.height
                ),
            ));
        }
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let cam = camera_uniform(camera, gbuffer.width, gbuffer.height, 0.0);
        let mut u: Vec<[u32; 4]> = cam.iter().map(|v| v.map(f32::to_bits)).collect();
        let method = match opts.method {
            FrameMethod::Regular => 0,
            FrameMethod::Ck => 1,
            FrameMethod::Progressive { .. } => 2,
        };
        u.push([gbuffer.width, gbuffer.height, k, opts.samples]);
        u.push([method, opts.frame, scene.probes, scene.page[0]]);
        u.push([
            opts.seed as u32,
            (opts.seed >> 32) as u32,
            scene.environment,
            scene.page[1],
        ]);
        let (mask, tile_u) = match tiles {
            Some(t) => {
                let (cols, rows) = (u32::try_from(t.cols), u32::try_from(t.rows));
                let (Ok(cols), Ok(rows)) = (cols, rows) else {
                    return Err(invalid("screen tiles", format!("{}×{}", t.cols, t.rows)));
                };
                let bits: Vec<u32> = t.covered.iter().map(|&c| u32::from(c)).collect();
                (storage(ctx, "frame tile mask", &bits), [cols, rows, 1, 0])
            }
            None => (storage(ctx, "frame tile mask", &[0u32]), [0, 0, 0, 0]),
        };
        u.push(tile_u);
        u.push([u32::from(!see_through), 0, 0, 0]);
        // The largest n of a pixel: the frame's, or an object's own budget.
        let n = opts.samples.max(scene.own_samples);
        let chunks: Vec<u32> = (0..n).step_by(SAMPLES_PER_DISPATCH as usize).collect();
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let (prim, bary) = (view(&gbuffer.prim), view(&gbuffer.bary_depth));
        let binds: Vec<wgpu::BindGroup> = chunks
            .iter()
            .map(|&first| {
                let mut u = u.clone();
                u.push([first, first + SAMPLES_PER_DISPATCH, 0, 0]);
                let uniform = buffer_init(
                    ctx,
                    "frame uniform",
                    bytemuck::cast_slice(&u),
                    wgpu::BufferUsages::UNIFORM,
                );
                self.bind_group(
                    ctx,
                    scene,
                    (&uniform, &mask),
                    (&prim, &bary),
                    &lightmapped,
                    out,
                )
            })
            .collect();
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame shading"),
            });
        enc.clear_buffer(&out.counts, 0, None);
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("frame shading"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.samples);
            for bind in &binds {
                pass.set_bind_group(0, bind, &[]);
                pass.dispatch_workgroups(gbuffer.width.div_ceil(8), gbuffer.height.div_ceil(8), 1);
            }
            pass.set_pipeline(&self.resolve);
            pass.dispatch_workgroups(out.width.div_ceil(8), out.height.div_ceil(8), 1);
        }
        ctx.queue.submit([enc.finish()]);
        scope_result(scope, "frame shading")
    }

    /// The bind group of one dispatch: its uniform block and the tile mask, the G-buffer's
    /// primitive and barycentric textures, the light-mapped image, the output.
    fn bind_group(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        (uniform, mask): (&wgpu::Buffer, &wgpu::Buffer),
        (prim, bary): (&wgpu::TextureView, &wgpu::TextureView),
        lightmapped: &Lit,
        out: &FrameShadeTarget,
    ) -> wgpu::BindGroup {
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame_shade.wgsl"),
            layout: &self.layout,
            entries: &[
                buf(0, uniform),
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(prim),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(bary),
                },
                buf(3, &scene.tris),
                buf(4, &scene.bsdfs),
                buf(5, &scene.tables),
                buf(6, &scene.cube_texels),
                buf(7, &scene.cube_levels),
                buf(8, &scene.cubes),
                buf(9, &scene.planes),
                buf(10, &scene.ring),
                buf(11, &scene.view_radiance),
                buf(12, &scene.view_geometry),
                buf(13, &scene.views),
                wgpu::BindGroupEntry {
                    binding: 14,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: lightmapped.buffer,
                        offset: 0,
                        size: wgpu::BufferSize::new(
                            u64::from(lightmapped.width) * u64::from(lightmapped.height) * 16,
                        ),
                    }),
                },
                buf(15, &out.accum),
                buf(16, &out.out),
                buf(17, &out.counts),
                buf(18, &scene.albedo_tris),
                buf(19, &scene.albedo_mats),
                buf(20, &scene.texels),
                buf(21, &scene.texture_info),
                buf(22, &scene.params),
                buf(23, &scene.tangents),
                buf(24, mask),
                buf(25, &out.partial),
            ],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use wgpu::naga;

    /// The pass and the model-evaluation kernel parse and validate without an adapter; the
    /// uniform block and the material record have the sizes the Rust side writes.
    #[test]
    fn wgsl_parses_and_validates_with_naga() {
        let models = wgsl::compose(&[&wgsl::BSDF], include_str!("bsdf_models.wgsl"));
        for (src, types) in [
            (
                frame_shade_wgsl(),
                &[("Params", 11 * 16), ("GpuBsdf", 144)][..],
            ),
            (models.as_str(), &[("GpuBsdf", 144)][..]),
        ] {
            let m = naga::front::wgsl::parse_str(src)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)));
            let mut v = naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            );
            if let Err(e) = v.validate(&m) {
                panic!("{}", e.emit_to_string(src));
            }
            assert!(m.entry_points.iter().any(|p| p.name == "main"));
            if src == frame_shade_wgsl() {
                assert!(m.entry_points.iter().any(|p| p.name == "samples_main"));
            }
            for (name, bytes) in types {
                let size = m
                    .types
                    .iter()
                    .find(|(_, t)| t.name.as_deref() == Some(*name))
                    .map(|(_, t)| t.inner.size(m.to_ctx()))
                    .unwrap_or_else(|| panic!("no struct {name}"));
                assert_eq!(size, *bytes, "{name}");
            }
        }
        assert_eq!(std::mem::size_of::<GpuBsdf>(), 144);
    }

    /// The WGSL's copies of the coating grid's and the screen tiles' constants are lustre-brdf's
    /// and lustre-shade's.
    #[test]
    fn coating_constants_match() {
        use lustre_brdf::models::rough_plastic::{COATING_ALPHAS, COATING_ALPHA_MIN};
        let src = frame_shade_wgsl();
        assert!(src.contains(&format!("const COATING_ALPHAS: u32 = {COATING_ALPHAS}u;")));
        assert_eq!(COATING_ALPHA_MIN, 1e-4);
        assert!(src.contains("const COATING_ALPHA_MIN: f32 = 1e-4;"));
        let tile = lustre_shade::mirror::SCREEN_TILE;
        assert!(src.contains(&format!("const SCREEN_TILE: u32 = {tile}u;")));
    }

    /// Every parameter must fit an f32: a named error otherwise.
    #[test]
    fn parameters_beyond_f32_are_named() {
        let t = ThinDielectric::new(1.5, 1.0).expect("thin");
        assert!(pack_thin_dielectric(&t).is_ok());
        let huge = ThinDielectric { eta: 1e300, ..t };
        let err = pack_thin_dielectric(&huge).unwrap_err().to_string();
        assert!(
            err.contains("thin dielectric") && err.contains("f32"),
            "{err}"
        );
    }
}
