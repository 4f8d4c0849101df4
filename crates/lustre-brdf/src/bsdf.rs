//! The one interface every material model and measured table implements (after pbrt-v4's BxDF).
//!
//! Conventions: local shading frame (normal +z, tangent +x), `wi` towards the light, `wo` towards
//! the viewer, both unit vectors pointing away from the surface. `eval` returns the BSDF value
//! f(wi, wo) in 1/sr *without* the cosine factor. Pdfs are densities in solid angle over the whole
//! sphere of `wi`; a sampler may fail (for example when a reflected direction falls below the
//! horizon), so the pdf integrates to the probability that `sample` succeeds, which is at most 1.

use crate::rgb::Rgb;
use crate::sampling::hammersley;
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
