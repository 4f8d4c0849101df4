//! A glossy microfacet lobe beside a cosine-weighted diffuse lobe: the sampling and density
//! that rough plastic and the glTF metallic-roughness model share (each with its own choice
//! probability). GPU twin: lustre-gpu's `wgsl/glossy_diffuse.wgsl`.
//!
//! ```text
//! sample: with probability P_s(wo)  wi = wo reflected about a visible normal m ~ D_v(m),
//!         else                      wi ~ cos θi / π
//!         (the first uniform number picks the lobe and is rescaled for it, pbrt's trick)
//! pdf(wi, wo) = P_s · D(h) G1(wo, h) / (4 cos θo) + (1 − P_s) cos θi / π,   h = (wi + wo)/|wi + wo|
//! ```
//!
//! (the visible-normal density D_v(h) = G1(wo, h) (wo·h) D(h) / cos θo times the reflection's
//! Jacobian 1/(4 wo·h)); 0 unless both directions lie above the surface.

use crate::bsdf::{Bsdf, BsdfSample, LobeFlags};
use crate::frame::reflect;
use crate::microfacet::distribution::MicrofacetDistribution;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf};
use glam::DVec3;

/// A model made of this mixture: its glossy lobe's distribution and the probability of
/// sampling that lobe.
pub(crate) trait GlossyDiffuse: Bsdf {
    /// The glossy lobe's microfacet distribution.
    fn distribution(&self) -> &MicrofacetDistribution;
    /// P_s(wo): the probability of sampling the glossy lobe.
    fn prob_specular(&self, wo: DVec3) -> f64;
}

/// [`Bsdf::sample`] of the mixture: the glossy lobe (reflection about a visible normal) with
/// probability P_s(wo), else the cosine lobe; the direction, its density [`pdf`] and the model's
/// value. `None` below the horizon or where the density is not positive and finite.
pub(crate) fn sample<M: GlossyDiffuse>(m: &M, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
    let (wi, kind, pdf) = sample_direction(m, wo, u1, u2)?;
    Some(BsdfSample::new(wi, m.eval(wi, wo), pdf, kind))
}

/// [`sample`] without the model's value: the direction, its lobe and its density, for a model
/// that evaluates in another frame (the glTF material's rotated anisotropy).
pub(crate) fn sample_direction<M: GlossyDiffuse>(
    m: &M,
    wo: DVec3,
    u1: f64,
    u2: f64,
) -> Option<(DVec3, LobeFlags, f64)> {
    if wo.z.is_nan() || wo.z <= 0.0 {
        return None;
    }
    let ps = m.prob_specular(wo);
    let (wi, kind) = if u1 < ps {
        let u1 = (u1 / ps).clamp(0.0, 1.0 - f64::EPSILON);
        let h = m.distribution().sample_visible(wo, u1, u2)?;
        (reflect(wo, h), LobeFlags::GLOSSY_REFLECTION)
    } else {
        let u1 = ((u1 - ps) / (1.0 - ps)).clamp(0.0, 1.0 - f64::EPSILON);
        (cosine_hemisphere(u1, u2), LobeFlags::DIFFUSE_REFLECTION)
    };
    // 0 where wi is not above the surface: no sample.
    let pdf = pdf(m, wi, wo);
    (pdf > 0.0 && pdf.is_finite()).then_some((wi, kind, pdf))
}

/// [`Bsdf::pdf`] of the mixture: P_s · D(h) G1(wo, h) / (4 cos θo) + (1 − P_s) cos θi / π.
pub(crate) fn pdf<M: GlossyDiffuse>(m: &M, wi: DVec3, wo: DVec3) -> f64 {
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return 0.0;
    }
    let ps = m.prob_specular(wo);
    let d = m.distribution();
    let h = (wi + wo).normalize();
    let spec = d.d(h) * d.g1(wo, h) / (4.0 * wo.z);
    ps * spec + (1.0 - ps) * cosine_hemisphere_pdf(wi)
}
