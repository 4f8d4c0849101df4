//! The rough plastic (a rough dielectric coating over a diffuse base; its transmittance table read through the pass's `bsdf_table`): [`KIND_ROUGH_PLASTIC`](super::kinds::KIND_ROUGH_PLASTIC). The record's
//! layout and the equations are in `rough_plastic.wgsl`'s header; the CPU twin is
//! `lustre_brdf::models::rough_plastic::RoughPlastic`.

use super::kinds::RECORD;
use super::textured::PARAMS;
use super::{distribution_code, Params, RecordParams};
use crate::error::{invalid, Result};
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRAME, FRESNEL, GLOSSY_DIFFUSE, MICROFACET};
use lustre_brdf::models::rough_plastic::RoughPlastic;

/// `rough_plastic.wgsl`: `rough_plastic_{unpack, eval, pdf, sample}`, `rough_plastic_textured`.
pub const MODULE: Module = Module {
    name: "rough_plastic",
    source: Source::File(include_str!("rough_plastic.wgsl")),
    deps: &[
        &RECORD,
        &PARAMS,
        &BSDF_SAMPLE,
        &FRESNEL,
        &FRAME,
        &MICROFACET,
        &GLOSSY_DIFFUSE,
    ],
};

/// `rough_plastic.wgsl`'s parameters; its transmittance table ([`rough_plastic_table`])
/// starts at entry `table` of the pass's table buffer (p3 = (table, table, 0, 0): one row, no
/// blend; a textured roughness sets p3.w = 1 and the pixel picks two rows of the coating's
/// grid, `wgsl/textured.wgsl`). Errors: an anisotropic coating, a table
/// offset beyond f32's exact integers.
pub fn pack_rough_plastic(m: &RoughPlastic, table: u32) -> Result<RecordParams> {
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

/// Entries of a rough plastic's transmittance table (`RoughPlastic::transmittance` at μ = i/63).
pub const ROUGH_PLASTIC_TABLE: usize = 64;

/// The rough plastic's external transmittance T(i/63), i = 0..64 (its own table's entries).
pub fn rough_plastic_table(m: &RoughPlastic) -> [f32; ROUGH_PLASTIC_TABLE] {
    let last = (ROUGH_PLASTIC_TABLE - 1) as f64;
    std::array::from_fn(|i| m.transmittance(i as f64 / last) as f32)
}
