//! The Lambertian BRDF f = kd/π (000 Eq. 3.2's diffuse term), cosine-sampled.
//!
//! One-sided: zero unless both directions lie above the surface.

use crate::bsdf::{cosine_pdf, cosine_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Result};
use crate::rgb::Rgb;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// A perfectly diffuse reflector.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Lambert {
    /// Diffuse albedo kd per channel (finite, ≥ 0).
    pub kd: Rgb,
}

impl Lambert {
    /// A Lambertian BRDF; rejects negative or non-finite channels.
    pub fn new(kd: Rgb) -> Result<Self> {
        check_rgb("kd", kd, 0.0, crate::error::MAX_REFLECTANCE)?;
        Ok(Lambert { kd })
    }
}

impl Bsdf for Lambert {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        "Lambert".to_string()
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.kd / PI
        } else {
            Rgb::ZERO
        }
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        cosine_sample(self, wo, u1, u2, LobeFlags::DIFFUSE)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        cosine_pdf(wi, wo)
    }

    /// Reciprocal; energy conserving when kd ≤ 1 in every channel (the albedo is exactly kd).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, self.kd.max_component() <= 1.0)
            .with_lobes(LobeFlags::DIFFUSE_REFLECTION)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use crate::numeric::{integrate_sphere, SphereQuadrature};
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn albedo_is_kd_and_value_is_kd_over_pi() {
        let l = Lambert::new(Rgb::new(0.2, 0.5, 0.9)).expect("valid");
        // Panels split exactly at the horizon, so the rule sees a smooth integrand.
        let q = SphereQuadrature {
            theta_split: FRAC_PI_2,
            phi_points: 64,
            ..Default::default()
        };
        for wo in [DVec3::Z, spherical(1.2, 0.3), spherical(1.55, -2.0)] {
            for c in 0..3 {
                let a = integrate_sphere(|wi| l.eval(wi, wo)[c] * wi.z.max(0.0), DVec3::Z, &q);
                assert!((a - l.kd[c]).abs() < 1e-12, "{a}");
            }
            // Cosine sampling makes the estimator exact per sample: f cos/pdf = kd.
            let s = l.sample(wo, 0.3, 0.7).expect("upper wo samples");
            assert!((s.weight()[1] - 0.5).abs() < 1e-12);
        }
        assert!((l.eval(spherical(0.4, 1.0), DVec3::Z)[2] - 0.9 / PI).abs() < 1e-15);
        assert_eq!(l.eval(-DVec3::Z, DVec3::Z), Rgb::ZERO);
        assert!(l.sample(-DVec3::Z, 0.5, 0.5).is_none());
    }

    #[test]
    fn rejects_bad_kd() {
        assert!(Lambert::new(Rgb::new(-0.1, 0.0, 0.0)).is_err());
        assert!(Lambert::new(Rgb::new(0.1, f64::NAN, 0.0)).is_err());
        assert!(Lambert::new(Rgb::new(0.1, 0.1, f64::INFINITY)).is_err());
    }
}
