//! GlTF 2.0 metallic-roughness: [`KIND_PBR_METALLIC_ROUGHNESS`](super::kinds::KIND_PBR_METALLIC_ROUGHNESS). The record's
//! layout and the equations are in `pbr_metallic_roughness.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRAME, FRESNEL, GLOSSY_DIFFUSE, MICROFACET, SHEEN};
use lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness;

/// `pbr_metallic_roughness.wgsl`: `pbr_metallic_roughness_{unpack, eval, pdf, sample}`, `pbr_metallic_roughness_textured`.
pub const MODULE: Module = Module {
    name: "pbr_metallic_roughness",
    source: Source::File(include_str!("pbr_metallic_roughness.wgsl")),
    deps: &[
        &RECORD,
        &PARAMS,
        &BSDF_SAMPLE,
        &FRESNEL,
        &FRAME,
        &MICROFACET,
        &GLOSSY_DIFFUSE,
        &SHEEN,
    ],
};

/// `pbr_metallic_roughness.wgsl`'s parameters.
pub fn pack_pbr_metallic_roughness(m: &PbrMetallicRoughness) -> Result<RecordParams> {
    let mut p = Params::new("glTF metallic-roughness");
    p.rgb(0, m.base_color, m.metallic)?;
    p.set(1, [m.alpha_t(), 0.0, m.alpha_b(), m.anisotropy])?;
    let (c, sn) = m.rotation();
    let l = &m.layers;
    p.set(2, [c, sn, l.clearcoat, m.coat_alpha()])?;
    p.rgb(3, m.f0(), l.specular)?;
    p.rgb(4, l.sheen_color, l.sheen_roughness)?;
    Ok(p.p)
}
