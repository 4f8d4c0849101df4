//! The rough conductor (a rough metal): [`KIND_ROUGH_CONDUCTOR`](super::kinds::KIND_ROUGH_CONDUCTOR). The record's
//! layout and the equations are in `rough_conductor.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::rough_conductor::RoughConductor`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{distribution_code, Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRAME, FRESNEL, MICROFACET};
use lustre_brdf::models::rough_conductor::RoughConductor;

/// `rough_conductor.wgsl`: `rough_conductor_{unpack, eval, pdf, sample}`, `rough_conductor_textured`.
pub const MODULE: Module = Module {
    name: "rough_conductor",
    source: Source::File(include_str!("rough_conductor.wgsl")),
    deps: &[
        &RECORD,
        &PARAMS,
        &BSDF_SAMPLE,
        &FRESNEL,
        &FRAME,
        &MICROFACET,
    ],
};

/// `rough_conductor.wgsl`'s parameters.
pub fn pack_rough_conductor(m: &RoughConductor) -> Result<RecordParams> {
    let mut p = Params::new("rough conductor");
    let d = &m.distribution;
    p.set(0, [d.alpha_u(), d.alpha_v(), distribution_code(d), 0.0])?;
    p.rgb(1, m.ior.eta, 0.0)?;
    p.rgb(2, m.ior.k, 0.0)?;
    p.rgb(3, m.specular_reflectance, 0.0)?;
    Ok(p.p)
}
