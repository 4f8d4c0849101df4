//! The anisotropic Phong BRDF of Ashikhmin & Shirley 2000 (004 §III.4.4.4 names it and refers to
//! the paper for the formulas, transcribed here). With k1 = wi, k2 = wo, h their normalized half
//! vector, u = +x (tangent), v = +y:
//!
//! specular  ρs = √((nu+1)(nv+1))/(8π) · (n·h)^((nu (h·u)² + nv (h·v)²)/(1 − (h·n)²))
//!                / ((h·k) max(n·k1, n·k2)) · F(k·h),   F(c) = Rs + (1 − Rs)(1 − c)⁵ (Schlick)
//! diffuse   ρd = 28Rd/(23π) (1 − Rs)(1 − (1 − n·k1/2)⁵)(1 − (1 − n·k2/2)⁵).
//!
//! Sampling (paper §4): φh = atan(√((nu+1)/(nv+1)) tan(πξ/2)) in the first quadrant, mirrored to
//! the other three; cosθh = ξ2^(1/(nu cos²φh + nv sin²φh + 1)); density of h
//! √((nu+1)(nv+1))/(2π) (n·h)^(nu cos²φh + nv sin²φh), of wi that over 4(k·h). Mixed with cosine
//! sampling for the diffuse term, weights mean(Rs) : mean(Rd)(1 − mean(Rs)).

use crate::bsdf::{
    diffuse_mixture_pdf, finish_sample, sample_diffuse_mixture, Bsdf, BsdfFlags, BsdfSample,
    LobeFlags,
};
use crate::error::{check_range, check_rgb, Result};
use crate::frame::{half_vector, reflect};
use crate::models::ward::COS_MIN;
use crate::rgb::Rgb;
use glam::DVec3;
use std::f64::consts::PI;

/// The Ashikhmin-Shirley anisotropic Phong BRDF (exponent `nu` along the tangent +x, `nv` along
/// +y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AshikhminShirley {
    nu: f64,
    nv: f64,
    rs: Rgb,
    rd: Rgb,
}

impl AshikhminShirley {
    /// A BRDF with Phong exponents `nu`, `nv` (each in [0, 10⁶]), specular reflectance at normal
    /// incidence `rs` and diffuse reflectance `rd` (channels in [0, 1]).
    pub fn new(nu: f64, nv: f64, rs: Rgb, rd: Rgb) -> Result<Self> {
        check_range("nu", nu, 0.0, 1e6)?;
        check_range("nv", nv, 0.0, 1e6)?;
        check_rgb("Rs", rs, 0.0, 1.0)?;
        check_rgb("Rd", rd, 0.0, 1.0)?;
        Ok(AshikhminShirley { nu, nv, rs, rd })
    }

    /// (nu, nv, Rs, Rd).
    pub fn params(&self) -> (f64, f64, Rgb, Rgb) {
        (self.nu, self.nv, self.rs, self.rd)
    }

    /// The exponent nu cos²φh + nv sin²φh of a unit half vector.
    fn exponent(&self, h: DVec3) -> f64 {
        let s2 = h.x * h.x + h.y * h.y;
        if s2 > 0.0 {
            (self.nu * h.x * h.x + self.nv * h.y * h.y) / s2
        } else {
            0.5 * (self.nu + self.nv)
        }
    }

    /// Density of the half vector h (solid angle of h).
    fn h_pdf(&self, h: DVec3) -> f64 {
        if h.z <= 0.0 {
            return 0.0;
        }
        ((self.nu + 1.0) * (self.nv + 1.0)).sqrt() / (2.0 * PI) * h.z.powf(self.exponent(h))
    }

    fn weights(&self) -> [f64; 2] {
        let rs = self.rs.mean();
        [self.rd.mean() * (1.0 - rs), rs]
    }
}

impl Bsdf for AshikhminShirley {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!("ashikhmin-shirley(nu={}, nv={})", self.nu, self.nv)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let (ci, co) = (wi.z, wo.z);
        if ci < COS_MIN || co < COS_MIN {
            return Rgb::ZERO;
        }
        let p5 = |x: f64| 1.0 - (1.0 - 0.5 * x).powi(5);
        let diffuse = self
            .rd
            .zip(self.rs, |rd, rs| 28.0 * rd / (23.0 * PI) * (1.0 - rs))
            * (p5(ci) * p5(co));
        let Some(h) = half_vector(wi, wo) else {
            return diffuse;
        };
        let kh = h.dot(wi).clamp(0.0, 1.0);
        if kh <= 0.0 {
            return diffuse;
        }
        let lobe = ((self.nu + 1.0) * (self.nv + 1.0)).sqrt() / (8.0 * PI)
            * h.z.powf(self.exponent(h))
            / (kh * ci.max(co));
        let m5 = (1.0 - kh).powi(5);
        diffuse + self.rs.map(|rs| lobe * (rs + (1.0 - rs) * m5))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z < COS_MIN {
            return None;
        }
        let (wi, kind) = sample_diffuse_mixture(&self.weights(), u1, u2, |_, u1, u2| {
            // Quadrant from the first uniform, then the paper's first-quadrant φ.
            let q = ((u1 * 4.0) as usize).min(3);
            let r = u1 * 4.0 - q as f64;
            let p = (((self.nu + 1.0) / (self.nv + 1.0)).sqrt() * (0.5 * PI * r).tan()).atan();
            let phi = match q {
                0 => p,
                1 => PI - p,
                2 => PI + p,
                _ => 2.0 * PI - p,
            };
            let (sp, cp) = phi.sin_cos();
            let e = self.nu * cp * cp + self.nv * sp * sp;
            let ct = (1.0 - u2).powf(1.0 / (e + 1.0));
            let st = (1.0 - ct * ct).max(0.0).sqrt();
            let h = DVec3::new(st * cp, st * sp, ct);
            (h.dot(wo) > 0.0).then(|| reflect(wo, h))
        })?;
        if wi.z < COS_MIN {
            return None;
        }
        finish_sample(wi, wo, self.pdf(wi, wo), kind, || self.eval(wi, wo))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z < COS_MIN || wo.z < COS_MIN {
            return 0.0;
        }
        diffuse_mixture_pdf(&self.weights(), wi, |_| match half_vector(wi, wo) {
            Some(h) if h.dot(wo) > 0.0 => self.h_pdf(h) / (4.0 * h.dot(wo)),
            _ => 0.0,
        })
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            reciprocal: true,
            energy_conserving: false,
            transmission: false,
            anisotropic: self.nu != self.nv,
            lobes: LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    #[test]
    fn known_value_by_hand() {
        let m =
            AshikhminShirley::new(100.0, 10.0, Rgb::splat(0.05), Rgb::splat(0.5)).expect("valid");
        // Normal incidence both ways: h = n, exponent irrelevant, F = Rs, (h·k) = 1.
        let f = m.eval(DVec3::Z, DVec3::Z)[0];
        let p5 = 1.0 - 0.5f64.powi(5);
        let want = 28.0 * 0.5 / (23.0 * PI) * 0.95 * p5 * p5
            + (101.0f64 * 11.0).sqrt() / (8.0 * PI) * 0.05;
        assert!((f - want).abs() < 1e-12, "{f} vs {want}");
        // A general pair, computed from the paper's formula in angles.
        let (wi, wo) = (spherical(0.3, 0.2), spherical(0.5, 2.9));
        let h = (wi + wo).normalize();
        let (th, ph) = (h.z.acos(), h.y.atan2(h.x));
        let e = 100.0 * ph.cos().powi(2) + 10.0 * ph.sin().powi(2);
        let kh = wi.dot(h);
        let fr = 0.05 + 0.95 * (1.0 - kh).powi(5);
        let spec =
            (101.0f64 * 11.0).sqrt() / (8.0 * PI) * th.cos().powf(e) / (kh * wi.z.max(wo.z)) * fr;
        let diff = 28.0 * 0.5 / (23.0 * PI)
            * 0.95
            * (1.0 - (1.0 - wi.z / 2.0).powi(5))
            * (1.0 - (1.0 - wo.z / 2.0).powi(5));
        let got = m.eval(wi, wo)[2];
        assert!(
            (got - spec - diff).abs() < 1e-12 * got,
            "{got} vs {}",
            spec + diff
        );
    }

    #[test]
    fn rejects_absurd_parameters() {
        assert!(AshikhminShirley::new(-1.0, 1.0, Rgb::ZERO, Rgb::ZERO).is_err());
        assert!(AshikhminShirley::new(1.0, f64::NAN, Rgb::ZERO, Rgb::ZERO).is_err());
        assert!(AshikhminShirley::new(1.0, 1.0, Rgb::splat(1.2), Rgb::ZERO).is_err());
    }
}
