//! The ABC microfacet BRDF of Löw et al. 2012, exactly as evaluated for the published MERL fits
//! (`fits/merl_abc_fits_low2012.csv`: kD rgb, A rgb, B, C, ior). 004 §III.4.4.4 only mentions it
//! ("a condensed version of the ABC model as the distribution in the Cook-Torrance BRDF").
//!
//! Transcribed from `djb::abc::eval`, `abc::ndf`, `abc::gaf` and `fresnel::unpolarized` in
//! jdupuy/dj_brdf, file `dj_brdf.h` (public domain), with i = wi (towards the light) and o = wo:
//!
//! f = kD/π + F(i·h) · D(h) · G / (π cosθi cosθo),
//! D = A / (1 + B (1 − cosθh))^C          (per channel A, shared B and C; unnormalized),
//! G = min(1, 2 (n·h)(n·i)/(h·i), 2 (n·h)(n·o)/(h·o))   (Cook-Torrance V-groove),
//! F = exact unpolarized dielectric Fresnel with index `ior` at c = clamp(i·h, 0, 1):
//!     g = √(η² + c² − 1), F = ½ (g−c)²/(g+c)² · (1 + (c(g+c) − 1)²/(c(g−c) + 1)²).
//!
//! Note the 1/(π cos cos) (not 1/(4 cos cos)): the fits absorb the constant in A. 1 − cosθh is
//! computed as sin²θh/(1 + cosθh) so that B up to 10⁷ keeps its precision near the peak.
//!
//! Sampling: the specular half vector is drawn with density ∝ (1 + B(1 − cosθh))^(−C) in
//! (cosθh, φh), inverted in closed form in t = 1 − cosθh:
//! F(t) = ((1 + Bt)^(1−C) − 1)/((1 + B)^(1−C) − 1) (ln(1 + Bt)/ln(1 + B) when C = 1), so
//! p(h) = (1 + Bt)^(−C)/(2πZ), Z = ∫₀¹ (1 + Bt)^(−C) dt, and wi has p(h)/(4 h·o). The diffuse term
//! is cosine sampled; weights mean(kD) : 8·mean(A)·Z·F(1) (≈ the specular albedo at normal incidence).

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

/// The ABC BRDF (isotropic).
#[derive(Clone, Debug, PartialEq)]
pub struct Abc {
    kd: Rgb,
    a: Rgb,
    b: f64,
    c: f64,
    ior: f64,
    /// Z = ∫₀¹ (1 + Bt)^(−C) dt.
    z: f64,
    label: String,
}

/// 1 − cosθ of a unit vector, accurate near the pole.
fn one_minus_cos(h: DVec3) -> f64 {
    if h.z > 0.0 {
        (h.x * h.x + h.y * h.y) / (1.0 + h.z)
    } else {
        1.0 - h.z
    }
}

/// dj_brdf's `unpolarized__eval`: the Fresnel reflectance of a dielectric of index `ior` > 1.
pub fn fresnel_unpolarized(cos_theta_d: f64, ior: f64) -> f64 {
    let c = cos_theta_d.clamp(0.0, 1.0);
    let g = (ior * ior + c * c - 1.0).max(0.0).sqrt();
    let tmp1 = c * (g + c) - 1.0;
    let tmp2 = c * (g - c) + 1.0;
    let tmp3 = (tmp1 * tmp1) / (tmp2 * tmp2);
    let tmp4 = ((g - c) * (g - c)) / ((g + c) * (g + c));
    0.5 * tmp4 * (1.0 + tmp3)
}

impl Abc {
    /// An ABC BRDF: diffuse `kd` (channels in [0, 1]), peak `a` (in [0, 10⁷]), `b` in [10⁻⁶, 10¹⁰],
    /// `c` in [10⁻⁴, 100] and index of refraction `ior` in (1, 10⁴].
    pub fn new(kd: Rgb, a: Rgb, b: f64, c: f64, ior: f64) -> Result<Self> {
        check_rgb("kD", kd, 0.0, 1.0)?;
        check_rgb("A", a, 0.0, 1e7)?;
        check_range("B", b, 1e-6, 1e10)?;
        check_range("C", c, 1e-4, 100.0)?;
        check_range("ior", ior, 1.0 + 1e-9, 1e4)?;
        let z = Self::z_integral(b, c);
        Ok(Abc {
            kd,
            a,
            b,
            c,
            ior,
            z,
            label: String::new(),
        })
    }

    /// The same BRDF with a material name shown by [`Bsdf::name`].
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = label.into();
        self
    }

    /// (kD, A, B, C, ior).
    pub fn params(&self) -> (Rgb, Rgb, f64, f64, f64) {
        (self.kd, self.a, self.b, self.c, self.ior)
    }

    fn z_integral(b: f64, c: f64) -> f64 {
        let l = b.ln_1p();
        let s = 1.0 - c;
        if (s * l).abs() < 1e-9 {
            l / b
        } else {
            (s * l).exp_m1() / (b * s)
        }
    }

    /// Inverse of the CDF of t = 1 − cosθh.
    fn t_of_u(&self, u: f64) -> f64 {
        let l = self.b.ln_1p();
        let s = 1.0 - self.c;
        let t = if (s * l).abs() < 1e-9 {
            (u * l).exp_m1() / self.b
        } else {
            ((u * (s * l).exp_m1()).ln_1p() / s).exp_m1() / self.b
        };
        t.clamp(0.0, 1.0)
    }

    /// The NDF shape (1 + Bt)^(−C).
    fn shape(&self, t: f64) -> f64 {
        (-self.c * (self.b * t).ln_1p()).exp()
    }

    fn weights(&self) -> [f64; 2] {
        let ws = 8.0 * self.a.mean() * self.z * fresnel_unpolarized(1.0, self.ior);
        [self.kd.mean(), if ws.is_finite() { ws } else { 0.0 }]
    }

    fn spec_pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match half_vector(wi, wo) {
            Some(h) if h.z > 0.0 && h.dot(wo) > 0.0 => {
                self.shape(one_minus_cos(h)) / (2.0 * PI * self.z) / (4.0 * h.dot(wo))
            }
            _ => 0.0,
        }
    }
}

impl Bsdf for Abc {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        if self.label.is_empty() {
            format!("abc(B={}, C={}, ior={})", self.b, self.c, self.ior)
        } else {
            format!("abc({})", self.label)
        }
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let (ci, co) = (wi.z, wo.z);
        if ci < COS_MIN || co < COS_MIN {
            return Rgb::ZERO;
        }
        let diffuse = self.kd * (1.0 / PI);
        let Some(h) = half_vector(wi, wo) else {
            return diffuse;
        };
        let hi = h.dot(wi);
        if hi <= 0.0 || h.z <= 0.0 {
            return diffuse;
        }
        let f = fresnel_unpolarized(hi, self.ior);
        // abc::gaf: h·i = h·o for a reflection pair.
        let g = 1f64
            .min(2.0 * h.z * ci / hi)
            .min(2.0 * h.z * co / h.dot(wo));
        let d = self.shape(one_minus_cos(h));
        diffuse + self.a * (f * d * g / (PI * ci * co))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z < COS_MIN {
            return None;
        }
        let (wi, kind) = sample_diffuse_mixture(&self.weights(), u1, u2, |_, u1, u2| {
            let t = self.t_of_u(u1);
            let ct = 1.0 - t;
            let st = (t * (2.0 - t)).max(0.0).sqrt();
            let (sp, cp) = (2.0 * PI * u2).sin_cos();
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
        diffuse_mixture_pdf(&self.weights(), wi, |_| self.spec_pdf(wi, wo))
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, false)
            .with_lobes(LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    #[test]
    fn fresnel_limits() {
        // Normal incidence: ((η−1)/(η+1))²; grazing: 1.
        let f0 = fresnel_unpolarized(1.0, 1.5);
        assert!((f0 - 0.04).abs() < 1e-12, "{f0}");
        assert!((fresnel_unpolarized(0.0, 1.5) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn known_value_by_hand() {
        let m = Abc::new(
            Rgb::splat(0.2),
            Rgb::new(50.0, 40.0, 30.0),
            1000.0,
            0.8,
            2.0,
        )
        .expect("valid");
        let (wi, wo) = (spherical(0.3, 0.0), spherical(0.5, PI));
        let h = (wi + wo).normalize();
        let d = 50.0 / (1.0 + 1000.0 * (1.0 - h.z)).powf(0.8);
        let g = 1f64
            .min(2.0 * h.z * wi.z / wi.dot(h))
            .min(2.0 * h.z * wo.z / wo.dot(h));
        let c = wi.dot(h);
        let gg = (4.0 + c * c - 1.0f64).sqrt();
        let f = 0.5 * (gg - c).powi(2) / (gg + c).powi(2)
            * (1.0 + (c * (gg + c) - 1.0).powi(2) / (c * (gg - c) + 1.0).powi(2));
        let want = 0.2 / PI + f * d * g / (PI * wi.z * wo.z);
        let got = m.eval(wi, wo)[0];
        assert!((got - want).abs() < 1e-10 * want, "{got} vs {want}");
    }

    #[test]
    fn z_integral_and_inverse_cdf() {
        for &(b, c) in &[(10.0, 0.5), (1e5, 1.0), (3e6, 0.08), (50.0, 2.6)] {
            let m = Abc::new(Rgb::ZERO, Rgb::ONE, b, c, 1.5).expect("valid");
            let rule = crate::numeric::GaussRule::new(20);
            let edges: Vec<f64> = (0..=60)
                .map(|k| if k == 0 { 0.0 } else { 1e-9 * 1.5f64.powi(k) })
                .filter(|&t| t <= 1.0)
                .chain(std::iter::once(1.0))
                .collect();
            let z = rule.integrate_panels(&edges, |t| m.shape(t));
            assert!((z - m.z).abs() < 1e-8 * z, "B={b} C={c}: {z} vs {}", m.z);
            for &u in &[0.1, 0.5, 0.9] {
                let t = m.t_of_u(u);
                let cdf = rule
                    .integrate_panels(&edges.iter().map(|&e| e.min(t)).collect::<Vec<_>>(), |s| {
                        m.shape(s)
                    })
                    / z;
                assert!((cdf - u).abs() < 1e-7, "B={b} C={c} u={u}: {cdf}");
            }
        }
    }

    #[test]
    fn rejects_absurd_parameters() {
        assert!(Abc::new(Rgb::ZERO, Rgb::ONE, 10.0, 1.0, 1.0).is_err());
        assert!(Abc::new(Rgb::ZERO, Rgb::splat(-1.0), 10.0, 1.0, 1.5).is_err());
        assert!(Abc::new(Rgb::ZERO, Rgb::ONE, f64::NAN, 1.0, 1.5).is_err());
        assert!(Abc::new(Rgb::ZERO, Rgb::ONE, 10.0, 0.0, 1.5).is_err());
    }
}
