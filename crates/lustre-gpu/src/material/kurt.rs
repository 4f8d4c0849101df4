//! The Kurt model with Luksch's transmission lobes as a whole BSDF: [`KIND_KURT`](super::kinds::KIND_KURT),
//! `kurt.wgsl` beside this file (CPU twin: `lustre_brdf::models::kurt::Kurt`).

use super::fitted::{invalid, to_params};
use super::RecordParams;
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRAME, LOBE, MIXTURE, TYPES};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::models::kurt::Kurt;

/// `kurt.wgsl`: `kurt_{unpack, eval, pdf, sample}`.
pub const MODULE: Module = Module {
    name: "kurt",
    source: Source::File(include_str!("kurt.wgsl")),
    deps: &[&TYPES, &FRAME, &LOBE, &MIXTURE, &BSDF_SAMPLE],
};

/// Most Kurt lobes (reflection and transmission together) the layout holds: 4 + 7 × 4 = 32.
pub const KURT_MAX_LOBES: usize = 4;

/// The Kurt layout ([`KIND_KURT`](super::kinds::KIND_KURT); the table in [`super::fitted`]): at most [`KURT_MAX_LOBES`] lobes.
pub fn pack_kurt(k: &Kurt) -> Result<RecordParams> {
    let (nr, nt) = (k.reflection.len(), k.transmission.len());
    if nr + nt > KURT_MAX_LOBES {
        return Err(invalid(
            &k.name(),
            format!(
                "{nr} reflection and {nt} transmission lobes: the Kurt layout (32 floats) holds \
                 {KURT_MAX_LOBES} lobes in all"
            ),
        ));
    }
    let mut f = [0f32; 32];
    f[..3].copy_from_slice(&k.kd.0.map(|v| v as f32));
    f[3] = (nr + 8 * nt) as f32;
    for (i, l) in k.reflection.iter().chain(&k.transmission).enumerate() {
        let v = [l.ks[0], l.ks[1], l.ks[2], l.mx, l.my, l.r0, l.alpha];
        f[4 + 7 * i..11 + 7 * i].copy_from_slice(&v.map(|x| x as f32));
    }
    Ok(to_params(&f))
}
