//! Two-sided adapter (Mitsuba 3's `twosided` with one nested BSDF): seen from below, the surface
//! behaves as seen from above, i.e. both directions are mirrored through the surface plane
//! (z → −z) before the nested model is asked and the sampled direction is mirrored back. Lobe
//! flags are those of the nested model (reflection stays reflection).
//!
//! We provide a wrapper rather than a flag the integrator honours: a BSDF then means the same
//! thing in every integrator, the battery checks the wrapped model from both sides, and scenes
//! (Mitsuba's `twosided`, glTF `doubleSided`) map onto it directly. Like Mitsuba, the nested
//! model must not transmit (a transmissive model is already defined on both sides).

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample};
use crate::error::{Error, Result};
use crate::frame::mirror_z;
use crate::rgb::Rgb;
use glam::DVec3;

/// A reflection-only BSDF made two-sided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TwoSided<B> {
    inner: B,
}

impl<B: Bsdf> TwoSided<B> {
    /// Wraps `inner`; an error if it transmits.
    pub fn new(inner: B) -> Result<Self> {
        if inner.flags().transmission {
            return Err(Error::NotFound(format!(
                "twosided: the nested BSDF {} transmits light; only reflection models can be \
                 made two-sided",
                inner.name()
            )));
        }
        Ok(TwoSided { inner })
    }

    /// The nested model.
    pub fn inner(&self) -> &B {
        &self.inner
    }

    /// Both directions moved to the upper side when `wo` lies below.
    fn upper(wi: DVec3, wo: DVec3) -> (DVec3, DVec3) {
        if wo.z < 0.0 {
            (mirror_z(wi), mirror_z(wo))
        } else {
            (wi, wo)
        }
    }
}

impl<B: Bsdf + 'static> Bsdf for TwoSided<B> {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("twosided({})", self.inner.name())
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let (wi, wo) = Self::upper(wi, wo);
        self.inner.eval(wi, wo)
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z < 0.0 {
            self.inner.sample(mirror_z(wo), u1, u2).map(|s| BsdfSample {
                wi: mirror_z(s.wi),
                ..s
            })
        } else {
            self.inner.sample(wo, u1, u2)
        }
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (wi, wo) = Self::upper(wi, wo);
        self.inner.pdf(wi, wo)
    }

    fn flags(&self) -> BsdfFlags {
        self.inner.flags()
    }

    fn albedo(&self, wo: DVec3, n: usize) -> Rgb {
        self.inner
            .albedo(if wo.z < 0.0 { mirror_z(wo) } else { wo }, n)
    }
}
