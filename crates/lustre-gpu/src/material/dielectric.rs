//! The smooth dielectric interface: [`KIND_DIELECTRIC`](super::kinds::KIND_DIELECTRIC). The record's
//! layout and the equations are in `dielectric.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::dielectric::Dielectric`.

use super::kinds::RECORD;
use super::{Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRESNEL};
use lustre_brdf::models::dielectric::Dielectric;

/// `dielectric.wgsl`: `dielectric_{unpack, eval, pdf, sample}`.
pub const MODULE: Module = Module {
    name: "dielectric",
    source: Source::File(include_str!("dielectric.wgsl")),
    deps: &[&RECORD, &BSDF_SAMPLE, &FRESNEL],
};

/// `dielectric.wgsl`'s parameters.
pub fn pack_dielectric(m: &Dielectric) -> Result<RecordParams> {
    let mut p = Params::new("dielectric");
    p.set(0, [m.eta, 0.0, 0.0, 0.0])?;
    p.rgb(1, m.specular_reflectance, 0.0)?;
    p.rgb(2, m.specular_transmittance, 0.0)?;
    Ok(p.p)
}
