//! The fitted models on the GPU: which of the kinds [`super::sgd`], [`super::cook_torrance`]
//! and [`super::kurt`] a fitted model is, and their shared checks. The 32-float layouts of the
//! SGD, Beckmann and GGX Cook-Torrance fits and of the Kurt model with reflection and
//! transmission lobes are read by the binding-free WGSL modules `sgd`, `cook_torrance` and
//! `kurt` beside those files, whose
//! `<model>_{unpack, eval, pdf, sample}` are the twins of the CPU's `Bsdf::{eval, pdf, sample}`
//! (`tests/fit_models.rs` measures how close).
//!
//! A material record of the view-dependent pass is `GpuBsdf { kind, flags, pad0, pad1,
//! p: array<vec4<f32>, 8> }`; [`pack_fit`] gives its `kind` and `p` for whatever a
//! `MaterialKind::Spec` resolves to (a `lustre-material` JSON, a published fit such as
//! `sgd:gold-metallic-paint`, `kurt(…)`, `beckmann(…)`, `ggx(…)`, the `kurt-*` built-ins), and
//! [`fit_kd`] its diffuse albedo kd (the part the light map holds: f contains kd/π on the
//! reflection side). Layouts (floats, `p[i][j]` is float 4i + j):
//!
//! | kind | model | layout |
//! |---|---|---|
//! | [`KIND_SGD`] | SGD Cook-Torrance | channel c at 10c: ρd, ρs, α, p, F0, F1, λ, ln c, k, θ0; [30], [31]: the bits of `pack2x16float`(α_proxy r, g) and (α_proxy b, 1) |
//! | [`KIND_CT_BECKMANN`], [`KIND_CT_GGX`] | Cook-Torrance | channel c at 5c: ρd, ρs, α, F0, F1; [15] flags (bit c: closed Smith G1, bit 3: GGX) |
//! | [`KIND_KURT`] | Kurt | [0..3] kd, [3] nr + 8 nt, lobe i at 4 + 7i: ks (3), mx, my, r0, α |
//!
//! What does not fit is a named error ([`GpuError::Invalid`]): more than [`KURT_MAX_LOBES`](super::kurt::KURT_MAX_LOBES)
//! Kurt lobes, an SGD channel with the numeric Smith G1 table or with a kap that is not
//! 1/(αΓ(1−p, α)) (the layout derives kap on the GPU; the published chrome is such a case), a
//! Fresnel other than (generalized) Schlick, mixed distributions, any other model.

use super::cook_torrance::pack_cook_torrance;
use super::kinds::{KIND_CT_BECKMANN, KIND_CT_GGX, KIND_KURT, KIND_SGD};
use super::kurt::pack_kurt;
use super::sgd::pack_sgd;
use super::RecordParams;
use crate::error::{GpuError, Result};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::microfacet::fresnel::Fresnel;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::models::cook_torrance::{CookTorrance, CtChannel};
use lustre_brdf::models::kurt::Kurt;
use lustre_brdf::rgb::Rgb;

pub(crate) fn invalid(parameter: &str, message: String) -> GpuError {
    GpuError::Invalid {
        parameter: parameter.to_string(),
        message,
    }
}

pub(crate) fn to_params(f: &[f32; 32]) -> RecordParams {
    std::array::from_fn(|i| [f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]])
}

/// The kind code and the 32 floats of `bsdf` when it is one of the fitted models: a
/// Cook-Torrance with the SGD, Beckmann or GGX distribution in every channel, or a Kurt model.
pub fn pack_fit(bsdf: &dyn Bsdf) -> Result<(u32, RecordParams)> {
    let any = bsdf.as_any();
    if let Some(ct) = any.and_then(|a| a.downcast_ref::<CookTorrance>()) {
        return match ct.channels()[0].ndf {
            Ndf::Sgd(_) => Ok((KIND_SGD, pack_sgd(ct)?)),
            Ndf::Beckmann { .. } => Ok((KIND_CT_BECKMANN, pack_cook_torrance(ct)?)),
            Ndf::Ggx { .. } => Ok((KIND_CT_GGX, pack_cook_torrance(ct)?)),
            Ndf::Exponential { .. } => Err(invalid(
                &bsdf.name(),
                "the exponential distribution has no GPU layout (SGD, Beckmann, GGX do)".into(),
            )),
        };
    }
    if let Some(k) = any.and_then(|a| a.downcast_ref::<Kurt>()) {
        return Ok((KIND_KURT, pack_kurt(k)?));
    }
    Err(invalid(
        &bsdf.name(),
        "not a fitted model with a GPU layout (SGD, Beckmann or GGX Cook-Torrance, Kurt)".into(),
    ))
}

/// The diffuse albedo kd of a fitted model (ρd per channel, Kurt's kd): its f holds kd/π on
/// the reflection side, the part a light map already accounts for.
pub fn fit_kd(bsdf: &dyn Bsdf) -> Result<Rgb> {
    let any = bsdf.as_any();
    if let Some(ct) = any.and_then(|a| a.downcast_ref::<CookTorrance>()) {
        let c = ct.channels();
        return Ok(Rgb::new(c[0].rho_d, c[1].rho_d, c[2].rho_d));
    }
    if let Some(k) = any.and_then(|a| a.downcast_ref::<Kurt>()) {
        return Ok(k.kd);
    }
    Err(invalid(
        &bsdf.name(),
        "not a fitted model with a GPU layout (SGD, Beckmann or GGX Cook-Torrance, Kurt)".into(),
    ))
}

/// (F0, F1) of the generalized Schlick form of a channel's Fresnel (Schlick: F1 = 0; one:
/// F0 = 1, F1 = 0).
pub(crate) fn fresnel_params(name: &str, f: &Fresnel) -> Result<(f64, f64)> {
    f.generalized_schlick_form().ok_or_else(|| {
        invalid(
            name,
            "the Lazányi Fresnel has no GPU layout (generalized Schlick, Schlick and one do)"
                .into(),
        )
    })
}

/// The channel index each channel's sampling lobe merges into on the GPU (the first channel
/// with f32-equal distribution parameters), checked against the CPU's rule (equal NDFs).
pub(crate) fn check_merging(
    name: &str,
    ch: &[CtChannel; 3],
    key: impl Fn(&Ndf) -> [f32; 2],
) -> Result<()> {
    for c in 1..3 {
        for e in 0..c {
            let gpu = key(&ch[c].ndf) == key(&ch[e].ndf);
            let cpu = ch[c].ndf == ch[e].ndf;
            if gpu != cpu {
                return Err(invalid(
                    name,
                    format!(
                        "channels {e} and {c} have distributions that are {} on the CPU but \
                         {} in f32",
                        if cpu { "equal" } else { "different" },
                        if gpu { "equal" } else { "different" }
                    ),
                ));
            }
            if gpu {
                break;
            }
        }
    }
    Ok(())
}
