//! The Lambertian reflector: [`KIND_LAMBERT`](super::kinds::KIND_LAMBERT). The record's
//! layout and the equations are in `lambert.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::lambert::Lambert`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRESNEL};
use lustre_brdf::models::lambert::Lambert;

/// `lambert.wgsl`: `lambert_{unpack, eval, pdf, sample}`, `lambert_textured`.
pub const MODULE: Module = Module {
    name: "lambert",
    source: Source::File(include_str!("lambert.wgsl")),
    deps: &[&RECORD, &PARAMS, &BSDF_SAMPLE, &FRESNEL],
};

/// `lambert.wgsl`'s parameters.
pub fn pack_lambert(m: &Lambert) -> Result<RecordParams> {
    let mut p = Params::new("Lambert");
    p.rgb(0, m.kd, 0.0)?;
    Ok(p.p)
}
