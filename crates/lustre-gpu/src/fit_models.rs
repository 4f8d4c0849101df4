//! The fitted models on the GPU: the 32-float layouts of the SGD, Beckmann and GGX
//! Cook-Torrance fits and of the Kurt model with reflection and transmission lobes, read by the
//! binding-free WGSL modules `sgd`, `cook_torrance` and `kurt` ([`crate::wgsl`]), whose
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
//! | 16 [`KIND_SGD`] | SGD Cook-Torrance | channel c at 10c: ρd, ρs, α, p, F0, F1, λ, ln c, k, θ0; [30], [31]: the bits of `pack2x16float`(α_proxy r, g) and (α_proxy b, 1) |
//! | 17 [`KIND_CT_BECKMANN`], 18 [`KIND_CT_GGX`] | Cook-Torrance | channel c at 5c: ρd, ρs, α, F0, F1; [15] flags (bit c: closed Smith G1, bit 3: GGX) |
//! | 19 [`KIND_KURT`] | Kurt | [0..3] kd, [3] nr + 8 nt, lobe i at 4 + 7i: ks (3), mx, my, r0, α |
//!
//! What does not fit is a named error ([`GpuError::Invalid`]): more than [`KURT_MAX_LOBES`]
//! Kurt lobes, an SGD channel with the numeric Smith G1 table or with a kap that is not
//! 1/(αΓ(1−p, α)) (the layout derives kap on the GPU; the published chrome is such a case), a
//! Fresnel other than (generalized) Schlick, mixed distributions, any other model.

use crate::error::{GpuError, Result};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::microfacet::fresnel::Fresnel;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::models::cook_torrance::{CookTorrance, CtChannel, G1Model};
use lustre_brdf::models::kurt::Kurt;
use lustre_brdf::rgb::Rgb;

/// The 32 floats of a `GpuBsdf` record.
pub type FitParams = [[f32; 4]; 8];

/// Kind code of an SGD Cook-Torrance fit (`wgsl/sgd.wgsl`).
pub const KIND_SGD: u32 = 16;
/// Kind code of a Beckmann Cook-Torrance fit (`wgsl/cook_torrance.wgsl`).
pub const KIND_CT_BECKMANN: u32 = 17;
/// Kind code of a GGX Cook-Torrance fit (`wgsl/cook_torrance.wgsl`).
pub const KIND_CT_GGX: u32 = 18;
/// Kind code of a Kurt model (`wgsl/kurt.wgsl`).
pub const KIND_KURT: u32 = 19;
/// Most Kurt lobes (reflection and transmission together) the layout holds: 4 + 7 × 4 = 32.
pub const KURT_MAX_LOBES: usize = 4;

/// Flag bit of the Cook-Torrance layout: the distribution is GGX.
const CT_FLAG_GGX: u32 = 8;
/// θ0 of an SGD channel without shadowing (G1 = 1 below θ0, and θ ≤ π/2 < 4).
const NO_SHADOWING_THETA0: f32 = 4.0;
/// Largest relative difference between an SGD channel's kap and 1/(αΓ(1−p, α)) that the
/// layout accepts (the published table prints six digits).
const KAP_TOLERANCE: f64 = 2e-5;

fn invalid(parameter: &str, message: String) -> GpuError {
    GpuError::Invalid {
        parameter: parameter.to_string(),
        message,
    }
}

fn to_params(f: &[f32; 32]) -> FitParams {
    std::array::from_fn(|i| [f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]])
}

/// The kind code and the 32 floats of `bsdf` when it is one of the fitted models: a
/// Cook-Torrance with the SGD, Beckmann or GGX distribution in every channel, or a Kurt model.
pub fn pack_fit(bsdf: &dyn Bsdf) -> Result<(u32, FitParams)> {
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
fn check_merging(name: &str, ch: &[CtChannel; 3], key: impl Fn(&Ndf) -> [f32; 2]) -> Result<()> {
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

/// The Beckmann or GGX Cook-Torrance layout (kinds 17, 18; module notes).
pub fn pack_cook_torrance(ct: &CookTorrance) -> Result<FitParams> {
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

/// The SGD Cook-Torrance layout (kind 16; module notes). Every channel must have an SGD whose
/// kap is 1/(αΓ(1−p, α)) and the Eq. V.3 shadowing approximation (or none).
pub fn pack_sgd(ct: &CookTorrance) -> Result<FitParams> {
    let name = ct.name();
    let ch = ct.channels();
    let mut f = [0f32; 32];
    let mut proxy = [0f32; 3];
    for (c, q) in ch.iter().enumerate() {
        let Ndf::Sgd(s) = q.ndf else {
            return Err(invalid(
                &name,
                format!(
                    "channel {c} has {} where channel 0 has an SGD",
                    q.ndf.name()
                ),
            ));
        };
        let normalized = s.kap() * s.alpha() * s.gamma0();
        if (normalized - 1.0).abs() > KAP_TOLERANCE {
            return Err(invalid(
                &name,
                format!(
                    "channel {c}: kap = {} is {normalized:.4} × 1/(αΓ(1−p, α)); the SGD layout \
                     (32 floats) derives kap on the GPU and holds only normalized distributions",
                    s.kap()
                ),
            ));
        }
        let (lambda, ln_c, k, theta0) = match q.g1 {
            G1Model::SgdApprox(a) => (a.lambda, a.ln_c(), a.k, a.theta0),
            G1Model::None => (0.0, -1e30, 1.0, f64::from(NO_SHADOWING_THETA0)),
            _ => {
                return Err(invalid(
                    &name,
                    format!(
                        "channel {c}: the numeric Smith G1 table does not fit the 32 floats; \
                         the Eq. V.3 approximation (g1 = [λ, c, k]) does"
                    ),
                ))
            }
        };
        let (f0, f1) = fresnel_params(&name, &q.fresnel)?;
        let v = [
            q.rho_d,
            q.rho_s,
            s.alpha(),
            s.p(),
            f0,
            f1,
            lambda,
            ln_c,
            k,
            theta0,
        ];
        f[10 * c..10 * c + 10].copy_from_slice(&v.map(|x| x as f32));
        let h = half::f16::from_f64(s.proxy_alpha());
        if h.to_f64() != s.proxy_alpha() {
            return Err(invalid(
                &name,
                format!(
                    "channel {c}: the proxy α {} is not a half-precision value",
                    s.proxy_alpha()
                ),
            ));
        }
        proxy[c] = h.to_f32();
    }
    let pack = |a: f32, b: f32| {
        let bits = u32::from(half::f16::from_f32(a).to_bits())
            | (u32::from(half::f16::from_f32(b).to_bits()) << 16);
        f32::from_bits(bits)
    };
    f[30] = pack(proxy[0], proxy[1]);
    f[31] = pack(proxy[2], 1.0);
    if !f[30].is_normal() {
        return Err(invalid(
            &name,
            format!(
                "the proxy α {} of channel 1 is below the f16 normal range (the packed word \
                 would be an f32 subnormal)",
                proxy[1]
            ),
        ));
    }
    check_merging(&name, ch, |n| match *n {
        Ndf::Sgd(s) => [s.alpha() as f32, s.p() as f32],
        _ => [f32::NAN, 0.0],
    })?;
    Ok(to_params(&f))
}

/// The Kurt layout (kind 19; module notes): at most [`KURT_MAX_LOBES`] lobes.
pub fn pack_kurt(k: &Kurt) -> Result<FitParams> {
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
