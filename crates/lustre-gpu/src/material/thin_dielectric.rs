//! The thin dielectric sheet: [`KIND_THIN_DIELECTRIC`](super::kinds::KIND_THIN_DIELECTRIC). The record's
//! layout and the equations are in `thin_dielectric.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::thin_dielectric::ThinDielectric`.

use super::kinds::RECORD;
use super::{Params, RecordParams};
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRESNEL};
use lustre_brdf::models::thin_dielectric::ThinDielectric;

/// `thin_dielectric.wgsl`: `thin_dielectric_{unpack, eval, pdf, sample}`.
pub const MODULE: Module = Module {
    name: "thin_dielectric",
    source: Source::File(include_str!("thin_dielectric.wgsl")),
    deps: &[&RECORD, &BSDF_SAMPLE, &FRESNEL],
};

/// `thin_dielectric.wgsl`'s parameters.
pub fn pack_thin_dielectric(m: &ThinDielectric) -> Result<RecordParams> {
    let mut p = Params::new("thin dielectric");
    p.set(0, [m.eta, 0.0, 0.0, 0.0])?;
    p.rgb(1, m.specular_reflectance, 0.0)?;
    p.rgb(2, m.specular_transmittance, 0.0)?;
    Ok(p.p)
}
