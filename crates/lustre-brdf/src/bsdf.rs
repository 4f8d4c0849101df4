//! The one interface every material model and measured table implements (after pbrt-v4's BxDF).
//!
//! Conventions: local shading frame (normal +z, tangent +x), `wi` towards the light, `wo` towards
//! the viewer, both unit vectors pointing away from the surface. `eval` returns the BSDF value
//! f(wi, wo) in 1/sr *without* the cosine factor. Pdfs are densities in solid angle over the whole
//! sphere of `wi`; a sampler may fail (for example when a reflected direction falls below the
//! horizon), so the pdf integrates to the probability that `sample` succeeds, which is at most 1.
//!
//! # Delta (specular) lobes
//!
//! A Dirac lobe (smooth mirror, smooth glass, the coat of a smooth plastic) has no density. As in
//! Mitsuba 3 and pbrt-v4:
//! - `eval(wi, wo)` and `pdf(wi, wo)` return 0 for every given pair: a direction chosen by any
//!   other means hits a Dirac lobe with probability zero;
//! - `sample` returns the lobe's direction with `lobe` containing [`LobeFlags::SPECULAR`],
//!   `pdf` = the discrete probability of having picked that lobe (in (0, 1]), and `value` such
//!   that [`BsdfSample::weight`] = value·|cos θi|/pdf is the throughput of the sample
//!   (for a mirror of reflectance F picked with probability P: value = F/|cos θi|, pdf = P).
//! - an integrator must not apply MIS to a specular sample (its pdf is a probability, not a
//!   density); [`BsdfFlags::has_delta`] says whether this can happen at all.
//!
//! The integral of `pdf` over the sphere plus the total probability of the delta lobes equals
//! the probability that `sample` succeeds (the battery in [`crate::validate`] checks both parts).
//!
//! `sample` takes two uniform numbers. A model that picks a lobe before drawing a direction
//! picks it with the first number and rescales it (pbrt's trick); one whose choice depends on the
//! drawn direction (the rough dielectric: reflect or refract by F(wo·m)) splits the second number
//! into two with [`crate::sampling::split_uniform`].
//!
//! # Refraction
//!
//! Transmissive models scale radiance by 1/η² across the interface (pbrt-v4's
//! `TransportMode::Radiance`, Mitsuba's radiance mode): f of a refraction carries 1/η² with
//! η = η(wi side)/η(wo side), so the albedo seen from the denser side can exceed 1.
//! [`BsdfSample::eta`] reports that η so that an integrator can undo the factor for Russian
//! roulette (pbrt's `etaScale`), and "energy conserving" means the energy flux ratio
//! (weight·η², summed) never exceeds 1.

use crate::rgb::Rgb;
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, hammersley};
use glam::DVec3;
use std::ops::{BitAnd, BitOr, BitOrAssign};

/// The kind of lobe a sample came from, or the union of the lobes a BSDF has: a bit set of
/// REFLECTION/TRANSMISSION × DIFFUSE/GLOSSY/SPECULAR (pbrt-v4's `BxDFFlags`, Mitsuba 3's
/// `BSDFFlags` without the polarization and side bits).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct LobeFlags(u8);

impl LobeFlags {
    /// No lobe.
    pub const NONE: LobeFlags = LobeFlags(0);
    /// Scatters into the hemisphere of `wo`.
    pub const REFLECTION: LobeFlags = LobeFlags(1);
    /// Scatters into the opposite hemisphere.
    pub const TRANSMISSION: LobeFlags = LobeFlags(2);
    /// A lobe as wide as the hemisphere (Lambert-like).
    pub const DIFFUSE: LobeFlags = LobeFlags(4);
    /// A lobe with a density but concentrated (microfacet, Phong, measured).
    pub const GLOSSY: LobeFlags = LobeFlags(8);
    /// A Dirac lobe (see the module notes on delta lobes).
    pub const SPECULAR: LobeFlags = LobeFlags(16);
    /// Diffuse reflection.
    pub const DIFFUSE_REFLECTION: LobeFlags = LobeFlags(1 | 4);
    /// Glossy reflection.
    pub const GLOSSY_REFLECTION: LobeFlags = LobeFlags(1 | 8);
    /// Specular (Dirac) reflection.
    pub const SPECULAR_REFLECTION: LobeFlags = LobeFlags(1 | 16);
    /// Diffuse transmission.
    pub const DIFFUSE_TRANSMISSION: LobeFlags = LobeFlags(2 | 4);
    /// Glossy transmission.
    pub const GLOSSY_TRANSMISSION: LobeFlags = LobeFlags(2 | 8);
    /// Specular (Dirac) transmission, including straight pass-through (thin dielectric).
    pub const SPECULAR_TRANSMISSION: LobeFlags = LobeFlags(2 | 16);

    /// The raw bits.
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// Whether every bit of `other` is set.
    pub const fn contains(self, other: LobeFlags) -> bool {
        self.0 & other.0 == other.0
    }

    /// Whether any bit of `other` is set.
    pub const fn intersects(self, other: LobeFlags) -> bool {
        self.0 & other.0 != 0
    }

    /// Whether no bit is set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Has a Dirac component.
    pub const fn is_specular(self) -> bool {
        self.intersects(Self::SPECULAR)
    }

    /// Has a diffuse component.
    pub const fn is_diffuse(self) -> bool {
        self.intersects(Self::DIFFUSE)
    }

    /// Has a glossy component.
    pub const fn is_glossy(self) -> bool {
        self.intersects(Self::GLOSSY)
    }

    /// Has a reflection component.
    pub const fn is_reflection(self) -> bool {
        self.intersects(Self::REFLECTION)
    }

    /// Has a transmission component.
    pub const fn is_transmission(self) -> bool {
        self.intersects(Self::TRANSMISSION)
    }

    /// Has a component with a density (diffuse or glossy), i.e. `eval`/`pdf` can be non-zero.
    pub const fn is_non_delta(self) -> bool {
        self.intersects(LobeFlags(4 | 8))
    }

    /// REFLECTION when `wi` and `wo` lie on the same side of the surface, else TRANSMISSION.
    pub fn side(wi: DVec3, wo: DVec3) -> LobeFlags {
        if wi.z * wo.z >= 0.0 {
            Self::REFLECTION
        } else {
            Self::TRANSMISSION
        }
    }
}

impl BitOr for LobeFlags {
    type Output = LobeFlags;
    fn bitor(self, o: LobeFlags) -> LobeFlags {
        LobeFlags(self.0 | o.0)
    }
}

impl BitOrAssign for LobeFlags {
    fn bitor_assign(&mut self, o: LobeFlags) {
        self.0 |= o.0;
    }
}

impl BitAnd for LobeFlags {
    type Output = LobeFlags;
    fn bitand(self, o: LobeFlags) -> LobeFlags {
        LobeFlags(self.0 & o.0)
    }
}

impl std::fmt::Debug for LobeFlags {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names = [
            "REFLECTION",
            "TRANSMISSION",
            "DIFFUSE",
            "GLOSSY",
            "SPECULAR",
        ];
        let set: Vec<&str> = names
            .iter()
            .enumerate()
            .filter(|(i, _)| self.0 & (1 << i) != 0)
            .map(|(_, n)| *n)
            .collect();
        if set.is_empty() {
            write!(f, "LobeFlags(NONE)")
        } else {
            write!(f, "LobeFlags({})", set.join("|"))
        }
    }
}

/// A direction drawn by [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The sampled incident direction.
    pub wi: DVec3,
    /// f(wi, wo), the BSDF value (no cosine).
    pub value: Rgb,
    /// Solid-angle density of `wi` as returned by [`Bsdf::pdf`]; for a specular lobe the
    /// discrete probability of having picked it (module notes).
    pub pdf: f64,
    /// The lobe the sample came from (side × diffuse/glossy/specular).
    pub lobe: LobeFlags,
    /// η(wi side)/η(wo side) for a refraction (the radiance of the sample carries 1/η²),
    /// 1 otherwise.
    pub eta: f64,
}

impl BsdfSample {
    /// A non-refracted sample (η = 1).
    pub fn new(wi: DVec3, value: Rgb, pdf: f64, lobe: LobeFlags) -> Self {
        BsdfSample {
            wi,
            value,
            pdf,
            lobe,
            eta: 1.0,
        }
    }

    /// A specular (Dirac) sample picked with probability `prob` whose throughput is `weight`:
    /// value = weight·prob/|cos θi| (module notes). `None` for a direction in the surface plane
    /// or a probability outside (0, 1].
    pub fn delta(wi: DVec3, weight: Rgb, prob: f64, lobe: LobeFlags, eta: f64) -> Option<Self> {
        let c = wi.z.abs();
        if !(c > 0.0 && prob > 0.0 && prob <= 1.0 && wi.is_finite()) {
            return None;
        }
        Some(BsdfSample {
            wi,
            value: weight * (prob / c),
            pdf: prob,
            lobe: lobe | LobeFlags::SPECULAR,
            eta,
        })
    }

    /// Whether the sample came from a Dirac lobe.
    pub fn is_delta(&self) -> bool {
        self.lobe.is_specular()
    }

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
    /// The directional albedo never exceeds 1 for the current parameters (for refraction: the
    /// energy flux ratio, the radiance factor 1/η² removed; see the module notes).
    pub energy_conserving: bool,
    /// Scatters into the lower hemisphere (`lobes` has TRANSMISSION).
    pub transmission: bool,
    /// Depends on the azimuth of the configuration, not only on relative angles.
    pub anisotropic: bool,
    /// The union of the lobes `sample` can return.
    pub lobes: LobeFlags,
}

impl BsdfFlags {
    /// Flags of an isotropic, reflection-only BSDF with a glossy lobe (and possibly a diffuse
    /// one: add it with [`BsdfFlags::with_lobes`]).
    pub fn isotropic_reflection(reciprocal: bool, energy_conserving: bool) -> Self {
        BsdfFlags {
            reciprocal,
            energy_conserving,
            transmission: false,
            anisotropic: false,
            lobes: LobeFlags::GLOSSY_REFLECTION,
        }
    }

    /// The same promises with the given lobes (`transmission` follows them).
    pub fn with_lobes(self, lobes: LobeFlags) -> Self {
        BsdfFlags {
            lobes,
            transmission: lobes.is_transmission(),
            ..self
        }
    }

    /// Some lobe is a Dirac delta: `sample` may return specular samples, and light sampling
    /// cannot find those paths.
    pub fn has_delta(&self) -> bool {
        self.lobes.is_specular()
    }

    /// Some lobe has a density (`eval`/`pdf` can be non-zero): light sampling and MIS apply.
    pub fn has_non_delta(&self) -> bool {
        self.lobes.is_non_delta()
    }

    /// Only Dirac lobes: `eval` and `pdf` are zero everywhere, so light sampling is useless.
    pub fn delta_only(&self) -> bool {
        self.has_delta() && !self.has_non_delta()
    }

    /// Only diffuse lobes (a Lambert-like surface: view-independent shading applies).
    pub fn diffuse_only(&self) -> bool {
        self.lobes.is_diffuse()
            && !self
                .lobes
                .intersects(LobeFlags::GLOSSY | LobeFlags::SPECULAR)
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

    /// The concrete model behind a `dyn Bsdf`, for code that handles particular models (the
    /// GPU's fitted-model layouts downcast the Cook-Torrance and Kurt models); `None` for a
    /// model that does not offer it.
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        None
    }

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

/// Boxed, shared and borrowed BSDFs are BSDFs (a scene hands out `Box<dyn Bsdf>` built per
/// hit, shared `Arc`s of resolved specs, or borrows of constant materials).
macro_rules! forward_bsdf {
    ($($ptr:ty),*) => {$(
        impl<T: Bsdf + ?Sized> Bsdf for $ptr {
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
            fn as_any(&self) -> Option<&dyn std::any::Any> {
                (**self).as_any()
            }
            fn albedo(&self, wo: DVec3, n: usize) -> Rgb {
                (**self).albedo(wo, n)
            }
        }
    )*};
}
forward_bsdf!(Box<T>, std::sync::Arc<T>, &T);

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
/// positive and finite. `kind` is DIFFUSE or GLOSSY; the side (reflection or transmission)
/// follows from `wi` and `wo`. `value` is only evaluated when the sample is kept.
pub fn finish_sample(
    wi: DVec3,
    wo: DVec3,
    pdf: f64,
    kind: LobeFlags,
    value: impl FnOnce() -> Rgb,
) -> Option<BsdfSample> {
    if !pdf.is_finite() || pdf <= 0.0 {
        return None;
    }
    Some(BsdfSample::new(
        wi,
        value(),
        pdf,
        kind | LobeFlags::side(wi, wo),
    ))
}

/// Cosine-weighted hemisphere sampling for a BSDF whose pdf is [`cosine_pdf`]: `None` unless
/// `wo` and the drawn `wi` both lie above the surface; value and density come from the BSDF's
/// own `eval` and `pdf`. `kind` (DIFFUSE or GLOSSY) is the kind of the BSDF's lobe, reported
/// with REFLECTION on the sample.
pub fn cosine_sample<B: Bsdf + ?Sized>(
    bsdf: &B,
    wo: DVec3,
    u1: f64,
    u2: f64,
    kind: LobeFlags,
) -> Option<BsdfSample> {
    if wo.z.is_nan() || wo.z <= 0.0 {
        return None;
    }
    let wi = cosine_hemisphere(u1, u2);
    if wi.z.is_nan() || wi.z <= 0.0 {
        return None;
    }
    Some(BsdfSample::new(
        wi,
        bsdf.eval(wi, wo),
        bsdf.pdf(wi, wo),
        kind | LobeFlags::REFLECTION,
    ))
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
/// Returns the direction and the kind of the picked component (DIFFUSE for 0, else GLOSSY).
/// `None` when all weights are zero or the lobe sampler fails.
pub fn sample_diffuse_mixture(
    weights: &[f64],
    u1: f64,
    u2: f64,
    lobe: impl FnOnce(usize, f64, f64) -> Option<DVec3>,
) -> Option<(DVec3, LobeFlags)> {
    let (k, u1) = select_component(weights, u1)?;
    if k == 0 {
        Some((cosine_hemisphere(u1, u2), LobeFlags::DIFFUSE))
    } else {
        lobe(k, u1, u2).map(|w| (w, LobeFlags::GLOSSY))
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
