//! The smooth conductor: [`KIND_CONDUCTOR`](super::kinds::KIND_CONDUCTOR). The record's
//! layout and the equations are in `conductor.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::conductor::Conductor`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRESNEL};
use lustre_brdf::models::conductor::Conductor;

/// `conductor.wgsl`: `conductor_{unpack, eval, pdf, sample}`, `conductor_textured`.
pub const MODULE: Module = Module {
    name: "conductor",
    source: Source::File(include_str!("conductor.wgsl")),
    deps: &[&RECORD, &PARAMS, &BSDF_SAMPLE, &FRESNEL],
};

/// `conductor.wgsl`'s parameters.
pub fn pack_conductor(m: &Conductor) -> Result<RecordParams> {
    let mut p = Params::new("conductor");
    p.rgb(0, m.ior.eta, 0.0)?;
    p.rgb(1, m.ior.k, 0.0)?;
    p.rgb(2, m.specular_reflectance, 0.0)?;
    Ok(p.p)
}
