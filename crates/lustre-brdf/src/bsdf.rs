//! The one interface every material model and measured table implements (after pbrt-v4's BxDF).
//!
//! Conventions: local shading frame (normal +z, tangent +x), `wi` towards the light, `wo` towards
//! the viewer, both unit vectors pointing away from the surface. `eval` returns the BSDF value
//! f(wi, wo) in 1/sr *without* the cosine factor. Pdfs are densities in solid angle over the whole
//! sphere of `wi`; a sampler may fail (for example when a reflected direction falls below the
//! horizon), so the pdf integrates to the probability that `sample` succeeds, which is at most 1.

use crate::rgb::Rgb;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, hammersley};
use glam::DVec3;

/// A direction drawn by [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled incident direction.
    pub wi: DVec3,
    /// f(wi, wo), the BSDF value (no cosine).
    pub value: Rgb,
    /// Solid-angle density of `wi` as returned by [`Bsdf::pdf`].
    pub pdf: f64,
}

impl BsdfSample {
    /// The Monte-Carlo weight f·|cos θi| / pdf.
    pub fn weight(&self) -> Rgb {
        if self.pdf > 0.0 {
            self.value * (self.wi.z.abs() / self.pdf)
        } else {
            Rgb::ZERO
        }
    }
}

/// What a model promises; the test battery checks each promise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BsdfFlags {
    /// f(wi, wo) = f(wo, wi) for every pair.
    pub reciprocal: bool,
    /// The directional albedo never exceeds 1 for the current parameters.
    pub energy_conserving: bool,
    /// Scatters into the lower hemisphere.
    pub transmission: bool,
    /// Depends on the azimuth of the configuration, not only on relative angles.
    pub anisotropic: bool,
}

impl BsdfFlags {
    /// Flags of an isotropic, reflection-only BSDF.
    pub fn isotropic_reflection(reciprocal: bool, energy_conserving: bool) -> Self {
        BsdfFlags {
            reciprocal,
            energy_conserving,
            transmission: false,
            anisotropic: false,
        }
    }
}

/// A bidirectional scattering distribution function in the local frame.
pub trait Bsdf: Send + Sync + std::fmt::Debug {
    /// A short human-readable name (model and material), used in plots and reports.
    fn name(&self) -> String;

    /// f(wi, wo) in 1/sr, no cosine factor.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb;

    /// Draws `wi` for the given `wo` from two uniform numbers in [0, 1).
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample>;

    /// The solid-angle density with which [`Bsdf::sample`] produces `wi`.
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64;

    /// The model's promises (reciprocity, energy conservation, transmission, anisotropy).
    fn flags(&self) -> BsdfFlags;

    /// Directional albedo a(wo) = ∫ f(wi, wo) |cos θi| dωi (000 Eq. 2.6), estimated with `n`
    /// Hammersley points pushed through the model's own importance sampler. Deterministic.
    fn albedo(&self, wo: DVec3, n: usize) -> Rgb {
        let n = n.max(1);
        let mut sum = Rgb::ZERO;
        for k in 0..n {
            let (u1, u2) = hammersley(k as u32, n as u32);
            if let Some(s) = self.sample(wo, u1, u2) {
                sum += s.weight();
            }
        }
        sum / n as f64
    }
}

impl<T: Bsdf + ?Sized> Bsdf for Box<T> {
    fn name(&self) -> String {
        (**self).name()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        (**self).eval(wi, wo)
    }
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        (**self).sample(wo, u1, u2)
    }
    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        (**self).pdf(wi, wo)
    }
    fn flags(&self) -> BsdfFlags {
        (**self).flags()
    }
    fn albedo(&self, wo: DVec3, n: usize) -> Rgb {
        (**self).albedo(wo, n)
    }
}

/// Picks one of several components with probabilities proportional to `weights` using `u`,
/// and returns its index together with `u` rescaled to [0, 1) for reuse (pbrt's trick).
/// Returns `None` when all weights are zero.
pub fn select_component(weights: &[f64], u: f64) -> Option<(usize, f64)> {
    let total: f64 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let target = u * total;
    let mut acc = 0.0;
    for (i, &w) in weights.iter().enumerate() {
        if w <= 0.0 {
            continue;
        }
        if target < acc + w || i == weights.len() - 1 {
            let r = ((target - acc) / w).clamp(0.0, 1.0 - f64::EPSILON);
            return Some((i, r));
        }
        acc += w;
    }
    // Rounding left `target` past the last positive weight.
    let last = weights.iter().rposition(|&w| w > 0.0)?;
    Some((last, 1.0 - f64::EPSILON))
}

/// Builds a [`BsdfSample`] for `wi` from its density and value, or `None` unless `pdf` is
/// positive and finite. `value` is only evaluated when the sample is kept.
pub fn finish_sample(wi: DVec3, pdf: f64, value: impl FnOnce() -> Rgb) -> Option<BsdfSample> {
    if !pdf.is_finite() || pdf <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi,
        value: value(),
        pdf,
    })
}

/// Cosine-weighted hemisphere sampling for a BSDF whose pdf is [`cosine_pdf`]: `None` unless
/// `wo` and the drawn `wi` both lie above the surface; value and density come from the BSDF's
/// own `eval` and `pdf`.
pub fn cosine_sample<B: Bsdf + ?Sized>(
    bsdf: &B,
    wo: DVec3,
    u1: f64,
    u2: f64,
) -> Option<BsdfSample> {
    if wo.z.is_nan() || wo.z <= 0.0 {
        return None;
    }
    let wi = cosine_hemisphere(u1, u2);
    if wi.z.is_nan() || wi.z <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi,
        value: bsdf.eval(wi, wo),
        pdf: bsdf.pdf(wi, wo),
    })
}

/// The density of [`cosine_sample`]: cos θi / π for `wo` above the surface, else 0.
pub fn cosine_pdf(wi: DVec3, wo: DVec3) -> f64 {
    if wo.z > 0.0 {
        cosine_hemisphere_pdf(wi)
    } else {
        0.0
    }
}

/// Draws `wi` from a mixture whose component 0 is the cosine-weighted hemisphere and whose
/// component k ≥ 1 is drawn by `lobe(k, u1, u2)`. The component is picked with
/// [`select_component`]`(weights, u1)`, whose rescaled `u1` then feeds the chosen warp.
/// `None` when all weights are zero or the lobe sampler fails.
pub fn sample_diffuse_mixture(
    weights: &[f64],
    u1: f64,
    u2: f64,
    lobe: impl FnOnce(usize, f64, f64) -> Option<DVec3>,
) -> Option<DVec3> {
    let (k, u1) = select_component(weights, u1)?;
    if k == 0 {
        Some(cosine_hemisphere(u1, u2))
    } else {
        lobe(k, u1, u2)
    }
}

/// The density of [`sample_diffuse_mixture`]:
/// (w₀ cos θi/π + Σ_{k≥1, wₖ>0} wₖ lobe_pdf(k)) / Σ wₖ, or 0 when the weights sum to no
/// positive number.
pub fn diffuse_mixture_pdf(weights: &[f64], wi: DVec3, lobe_pdf: impl Fn(usize) -> f64) -> f64 {
    let total: f64 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return 0.0;
    }
    let mut p = weights[0] * cosine_hemisphere_pdf(wi);
    for (k, &w) in weights.iter().enumerate().skip(1) {
        if w > 0.0 {
            p += w * lobe_pdf(k);
        }
    }
    p / total
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn component_selection_is_proportional() {
        let w = [1.0, 0.0, 3.0];
        assert_eq!(select_component(&w, 0.1).map(|x| x.0), Some(0));
        assert_eq!(select_component(&w, 0.3).map(|x| x.0), Some(2));
        let (_, r) = select_component(&w, 0.625).expect("positive weights");
        assert!((r - 0.5).abs() < 1e-12);
        assert!(select_component(&[0.0, 0.0], 0.5).is_none());
    }
}
