//! The rough dielectric (glossy reflection and transmission): [`KIND_ROUGH_DIELECTRIC`](super::kinds::KIND_ROUGH_DIELECTRIC). The record's
//! layout and the equations are in `rough_dielectric.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::rough_dielectric::RoughDielectric`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{distribution_code, Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRAME, FRESNEL, MICROFACET};
use lustre_brdf::models::rough_dielectric::RoughDielectric;

/// `rough_dielectric.wgsl`: `rough_dielectric_{unpack, eval, pdf, sample}`, `rough_dielectric_textured`.
pub const MODULE: Module = Module {
    name: "rough_dielectric",
    source: Source::File(include_str!("rough_dielectric.wgsl")),
    deps: &[
        &RECORD,
        &PARAMS,
        &BSDF_SAMPLE,
        &FRESNEL,
        &FRAME,
        &MICROFACET,
    ],
};

/// `rough_dielectric.wgsl`'s parameters.
pub fn pack_rough_dielectric(m: &RoughDielectric) -> Result<RecordParams> {
    let mut p = Params::new("rough dielectric");
    let d = &m.distribution;
    p.set(0, [d.alpha_u(), d.alpha_v(), distribution_code(d), m.eta])?;
    p.rgb(1, m.specular_reflectance, 0.0)?;
    p.rgb(2, m.specular_transmittance, 0.0)?;
    Ok(p.p)
}
