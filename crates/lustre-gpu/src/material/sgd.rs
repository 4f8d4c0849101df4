//! The SGD Cook-Torrance fits (Bagher et al.'s shifted gamma distribution with the Eq. V.3
//! shadowing approximation): [`KIND_SGD`](super::kinds::KIND_SGD), `sgd.wgsl` beside this file
//! (CPU twin: `lustre_brdf::models::cook_torrance::CookTorrance` with `Ndf::Sgd`).

use super::fitted::{check_merging, fresnel_params, invalid, to_params};
use super::RecordParams;
use crate::error::Result;
use crate::wgsl::{Module, Source};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::models::cook_torrance::{CookTorrance, G1Model};

/// `sgd.wgsl`: `sgd_{unpack, eval, pdf, sample}`, the f32 upper incomplete gamma.
pub const MODULE: Module = Module {
    name: "sgd",
    source: Source::File(include_str!("sgd.wgsl")),
    deps: &[&super::cook_torrance::MODULE],
};

/// θ0 of an SGD channel without shadowing (G1 = 1 below θ0, and θ ≤ π/2 < 4).
const NO_SHADOWING_THETA0: f32 = 4.0;
/// Largest relative difference between an SGD channel's kap and 1/(αΓ(1−p, α)) that the
/// layout accepts (the published table prints six digits).
const KAP_TOLERANCE: f64 = 2e-5;

/// The SGD Cook-Torrance layout ([`KIND_SGD`](super::kinds::KIND_SGD); the table in [`super::fitted`]). Every channel must have an SGD whose
/// kap is 1/(αΓ(1−p, α)) and the Eq. V.3 shadowing approximation (or none).
pub fn pack_sgd(ct: &CookTorrance) -> Result<RecordParams> {
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
