//! The Beckmann and GGX Cook-Torrance fits: [`KIND_CT_BECKMANN`](super::kinds::KIND_CT_BECKMANN)
//! and [`KIND_CT_GGX`](super::kinds::KIND_CT_GGX), `cook_torrance.wgsl` beside this file (CPU twin:
//! `lustre_brdf::models::cook_torrance::CookTorrance` with the closed-form Smith G1).

use super::fitted::{check_merging, fresnel_params, invalid, to_params};
use super::RecordParams;
use crate::error::Result;
use crate::wgsl::{Module, Source, BSDF_SAMPLE, FRAME, MICROFACET, MIXTURE, TYPES};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::models::cook_torrance::{CookTorrance, G1Model};

/// `cook_torrance.wgsl`: `cook_torrance_{unpack, eval, pdf, sample}`.
pub const MODULE: Module = Module {
    name: "cook_torrance",
    source: Source::File(include_str!("cook_torrance.wgsl")),
    deps: &[&TYPES, &FRAME, &MICROFACET, &MIXTURE, &BSDF_SAMPLE],
};

/// Flag bit of the Cook-Torrance layout: the distribution is GGX.
const CT_FLAG_GGX: u32 = 8;

/// The Beckmann or GGX Cook-Torrance layout ([`KIND_CT_BECKMANN`](super::kinds::KIND_CT_BECKMANN), [`KIND_CT_GGX`](super::kinds::KIND_CT_GGX); the table in [`super::fitted`]).
pub fn pack_cook_torrance(ct: &CookTorrance) -> Result<RecordParams> {
    let name = ct.name();
    let ch = ct.channels();
    let ggx = matches!(ch[0].ndf, Ndf::Ggx { .. });
    let mut f = [0f32; 32];
    let mut flags = if ggx { CT_FLAG_GGX } else { 0 };
    for (c, q) in ch.iter().enumerate() {
        let alpha = match (q.ndf, ggx) {
            (Ndf::Ggx { alpha }, true) | (Ndf::Beckmann { alpha }, false) => alpha,
            _ => {
                return Err(invalid(
                    &name,
                    format!(
                        "channel {c} has {} where channel 0 has {}: one distribution for all",
                        q.ndf.name(),
                        ch[0].ndf.name()
                    ),
                ))
            }
        };
        match q.g1 {
            G1Model::Closed => flags |= 1 << c,
            G1Model::None => {}
            _ => {
                return Err(invalid(
                    &name,
                    format!("channel {c}: only the closed-form Smith G1 or none fits the layout"),
                ))
            }
        }
        let (f0, f1) = fresnel_params(&name, &q.fresnel)?;
        f[5 * c..5 * c + 5].copy_from_slice(&[q.rho_d, q.rho_s, alpha, f0, f1].map(|v| v as f32));
    }
    f[15] = flags as f32;
    check_merging(&name, ch, |n| match *n {
        Ndf::Beckmann { alpha } | Ndf::Ggx { alpha } => [alpha as f32, 0.0],
        _ => [f32::NAN, 0.0],
    })?;
    Ok(to_params(&f))
}
