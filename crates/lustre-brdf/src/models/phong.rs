//! The Phong BRDF with Lewis' normalization (004 §III.4.4.4.1, Lewis 1994):
//!
//! f(L, V) = ρd/π + ρs (n + 2)/(2π) max(0, V·R)ⁿ, R the mirror of L about the normal.
//!
//! V·R = ωo·reflect(ωi) = ωi·reflect(ωo), so the model is reciprocal. At normal incidence the
//! specular albedo is exactly ρs and it decreases towards grazing (Lewis 1994), so ρd + ρs ≤ 1
//! conserves energy. One-sided: zero unless both directions lie above the surface.
//!
//! Sampling mixes cosine sampling (weight: luminance of ρd) with a cosⁿ lobe about the mirror
//! direction of ωo (weight: luminance of ρs); samples below the horizon fail.

use crate::bsdf::{
    diffuse_mixture_pdf, finish_sample, sample_diffuse_mixture, Bsdf, BsdfFlags, BsdfSample,
    LobeFlags,
};
use crate::error::{check_range, check_rgb, Result};
use crate::rgb::Rgb;
use crate::sampling::{cosine_power, cosine_power_pdf, to_world};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Largest accepted Phong exponent.
pub const MAX_EXPONENT: f64 = 1e7;

/// Validates the parameters shared by [`Phong`] and [`crate::models::blinn_phong::BlinnPhong`]:
/// ρd and ρs finite and ≥ 0, n in [0, [`MAX_EXPONENT`]].
pub(crate) fn check_params(rho_d: Rgb, rho_s: Rgb, n: f64) -> Result<()> {
    check_rgb("rho_d", rho_d, 0.0, crate::error::MAX_REFLECTANCE)?;
    check_rgb("rho_s", rho_s, 0.0, crate::error::MAX_REFLECTANCE)?;
    check_range("n", n, 0.0, MAX_EXPONENT)?;
    Ok(())
}

/// Diffuse and specular sampling weights (luminances of ρd and ρs).
pub(crate) fn weights(rho_d: Rgb, rho_s: Rgb) -> [f64; 2] {
    [rho_d.luminance(), rho_s.luminance()]
}

/// Whether `wi` and `wo` both lie strictly above the surface (false for NaN).
pub(crate) fn both_above(wi: DVec3, wo: DVec3) -> bool {
    wi.z > 0.0 && wo.z > 0.0
}

/// Mirror of a local direction about the normal.
#[inline]
fn mirror(w: DVec3) -> DVec3 {
    DVec3::new(-w.x, -w.y, w.z)
}

/// Lewis-normalized Phong.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Phong {
    /// Diffuse albedo ρd (finite, ≥ 0).
    pub rho_d: Rgb,
    /// Specular albedo ρs at normal incidence (finite, ≥ 0).
    pub rho_s: Rgb,
    /// Exponent n in [0, [`MAX_EXPONENT`]].
    pub n: f64,
}

impl Phong {
    /// A validated model (channels finite and ≥ 0, n in [0, [`MAX_EXPONENT`]]).
    pub fn new(rho_d: Rgb, rho_s: Rgb, n: f64) -> Result<Self> {
        check_params(rho_d, rho_s, n)?;
        Ok(Phong { rho_d, rho_s, n })
    }
}

impl Bsdf for Phong {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("Phong (Lewis, n = {})", self.n)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !both_above(wi, wo) {
            return Rgb::ZERO;
        }
        let c = wo.dot(mirror(wi));
        let lobe = if c > 0.0 {
            (self.n + 2.0) / (2.0 * PI) * c.powf(self.n)
        } else {
            0.0
        };
        self.rho_d / PI + self.rho_s * lobe
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z.is_nan() || wo.z <= 0.0 {
            return None;
        }
        let (wi, kind) =
            sample_diffuse_mixture(&weights(self.rho_d, self.rho_s), u1, u2, |_, u1, u2| {
                Some(to_world(cosine_power(u1, u2, self.n), mirror(wo)).normalize())
            })?;
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        finish_sample(wi, wo, self.pdf(wi, wo), kind, || self.eval(wi, wo))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if !both_above(wi, wo) {
            return 0.0;
        }
        diffuse_mixture_pdf(&weights(self.rho_d, self.rho_s), wi, |_| {
            cosine_power_pdf(wi.dot(mirror(wo)), self.n)
        })
    }

    /// Reciprocal; energy conserving when ρd + ρs ≤ 1 in every channel.
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, (self.rho_d + self.rho_s).max_component() <= 1.0)
            .with_lobes(LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;
    use crate::numeric::{integrate_sphere, SphereQuadrature};
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn known_values() {
        let p = Phong::new(Rgb::splat(0.3), Rgb::splat(0.6), 40.0).expect("valid");
        // Peak: ωi = mirror of ωo gives V·R = 1.
        let wo = spherical(0.7, 1.1);
        let peak = p.eval(mirror(wo), wo)[0];
        assert!((peak - (0.3 / PI + 0.6 * 42.0 / (2.0 * PI))).abs() < 1e-12);
        // 20° off the mirror direction in the plane of incidence: V·R = cos 20°.
        let wi = spherical(0.7 + 20f64.to_radians(), 1.1 + PI);
        let want = 0.3 / PI + 0.6 * 42.0 / (2.0 * PI) * 20f64.to_radians().cos().powf(40.0);
        assert!((p.eval(wi, wo)[1] - want).abs() < 1e-12);
        // Albedo at normal incidence is ρd + ρs exactly.
        // Panels split exactly at the horizon, so the rule sees a smooth integrand.
        let q = SphereQuadrature {
            theta_split: FRAC_PI_2,
            phi_points: 64,
            ..Default::default()
        };
        let a = integrate_sphere(|wi| p.eval(wi, DVec3::Z)[2] * wi.z.max(0.0), DVec3::Z, &q);
        assert!((a - 0.9).abs() < 1e-12, "{a}");
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Phong::new(Rgb::ZERO, Rgb::ONE, -1.0).is_err());
        assert!(Phong::new(Rgb::ZERO, Rgb::ONE, f64::NAN).is_err());
        assert!(Phong::new(Rgb::ZERO, Rgb::new(0.0, -1.0, 0.0), 5.0).is_err());
        assert!(Phong::new(Rgb::splat(f64::INFINITY), Rgb::ONE, 5.0).is_err());
    }
}
