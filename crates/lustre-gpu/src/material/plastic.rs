//! The smooth plastic: [`KIND_PLASTIC`](super::kinds::KIND_PLASTIC). The record's
//! layout and the equations are in `plastic.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::plastic::Plastic`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRESNEL};
use lustre_brdf::models::plastic::Plastic;

/// `plastic.wgsl`: `plastic_{unpack, eval, pdf, sample}`, `plastic_textured`.
pub const MODULE: Module = Module {
    name: "plastic",
    source: Source::File(include_str!("plastic.wgsl")),
    deps: &[&RECORD, &PARAMS, &BSDF_SAMPLE, &FRESNEL],
};

/// `plastic.wgsl`'s parameters.
pub fn pack_plastic(m: &Plastic) -> Result<RecordParams> {
    let mut p = Params::new("plastic");
    let (dm, sm) = (m.diffuse_reflectance.mean(), m.specular_reflectance.mean());
    let weight = if dm + sm > 0.0 { sm / (dm + sm) } else { 0.5 };
    p.rgb(0, m.diffuse_reflectance, weight)?;
    p.rgb(1, m.specular_reflectance, f64::from(u8::from(m.nonlinear)))?;
    p.set(2, [m.eta, m.internal_reflectance(), 0.0, 0.0])?;
    Ok(p.p)
}
