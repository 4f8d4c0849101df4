//! The Lafortune (1997) generalized cosine-lobe BRDF, 004 §III.4.4.4:
//!
//! f(u, v) = ρd/π + Σ_j ρs_j · max(0, Cx ux vx + Cy uy vy + Cz uz vz)^n_j
//!
//! (u = wi, v = wo in the local frame). Each lobe may be anisotropic (Cx ≠ Cy) and point anywhere:
//! Cx = Cy = −Cz gives a Phong lobe about the mirror direction, Cx = Cy > 0 a retro-reflective lobe.
//!
//! Two lobe normalizations are supported ([`LobeNorm`]):
//! * [`LobeNorm::Raw`]: Lafortune's own form above; the magnitude of C carries the lobe strength.
//! * [`LobeNorm::Peak`]: ρs (n + 2)/(2π) · max(0, C·(u∘v) / max_k |C_k|)^n, so that the lobe's
//!   largest value over all pairs is ρs (n + 2)/(2π) (the bilinear form's maximum over unit
//!   vectors is max_k |C_k|) and its albedo about the normal is ≈ ρs. This is how the published
//!   one-lobe fits of Ngan et al. 2005 (unit C, ks ~ 0.1, n up to 16600) must be evaluated; see
//!   [`crate::fits::lafortune`] for the evidence.
//!
//! Importance sampling: for fixed v the lobe is (|C∘v| ŵ·u)^n with ŵ = (Cx vx, Cy vy, Cz vz)/|C∘v|,
//! a cosine power about ŵ scaled by |C∘v|^n; it is drawn with [`cosine_power`] about ŵ (samples
//! below the horizon fail). Lobes and the diffuse term (cosine sampling) are mixed with weights
//! equal to their approximate albedo.

use crate::bsdf::{
    diffuse_mixture_pdf, finish_sample, sample_diffuse_mixture, Bsdf, BsdfFlags, BsdfSample,
    LobeFlags,
};
use crate::error::{check_range, check_rgb, Error, Result};
use crate::models::ward::COS_MIN;
use crate::rgb::Rgb;
use crate::sampling::{cosine_power, cosine_power_pdf, to_world};
use glam::DVec3;
use std::f64::consts::PI;

/// How a lobe's coefficient scales its cosine power.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeNorm {
    /// ρs · max(0, C·(u∘v))^n (Lafortune et al. 1997, Eq. 4).
    Raw,
    /// ρs · (n + 2)/(2π) · max(0, C·(u∘v)/max_k|C_k|)^n (the convention of Ngan et al. 2005's
    /// published fits, see [`crate::fits::lafortune`]).
    Peak,
}

/// One generalized cosine lobe.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LafortuneLobe {
    /// (Cx, Cy, Cz).
    pub c: DVec3,
    /// The exponent n.
    pub n: f64,
    /// ρs per channel.
    pub rho: Rgb,
    /// How ρs scales the lobe.
    pub norm: LobeNorm,
}

impl LafortuneLobe {
    /// A lobe in Lafortune's raw form, ρs·max(0, C·(u∘v))^n.
    pub fn raw(c: DVec3, n: f64, rho: Rgb) -> Self {
        LafortuneLobe {
            c,
            n,
            rho,
            norm: LobeNorm::Raw,
        }
    }

    /// An isotropic peak-normalized lobe (Cx = Cy = `cxy`, Cz = `cz`), as in Ngan et al. 2005.
    pub fn ngan(cxy: f64, cz: f64, n: f64, ks: Rgb) -> Self {
        LafortuneLobe {
            c: DVec3::new(cxy, cxy, cz),
            n,
            rho: ks,
            norm: LobeNorm::Peak,
        }
    }

    fn validate(&self) -> Result<()> {
        check_range("lobe.Cx", self.c.x, -1e3, 1e3)?;
        check_range("lobe.Cy", self.c.y, -1e3, 1e3)?;
        check_range("lobe.Cz", self.c.z, -1e3, 1e3)?;
        check_range("lobe.n", self.n, 0.0, 1e6)?;
        check_rgb("lobe.rho", self.rho, 0.0, 1e3)?;
        let cmax = self.c.abs().max_element();
        match self.norm {
            LobeNorm::Peak if cmax == 0.0 => Err(Error::param(
                "lobe.C",
                0.0,
                "a peak-normalized lobe needs a non-zero C",
            )),
            LobeNorm::Raw if cmax > 1.0 && self.n * cmax.ln() > 600.0 => Err(Error::param(
                "lobe.n",
                self.n,
                format!("max|C|^n = {cmax}^n overflows: reduce n or |C|"),
            )),
            _ => Ok(()),
        }
    }

    /// (scale K, divisor m) with lobe = ρ·K·(C·(u∘v)/m)^n.
    pub fn scale(&self) -> (f64, f64) {
        match self.norm {
            LobeNorm::Raw => (1.0, 1.0),
            LobeNorm::Peak => ((self.n + 2.0) / (2.0 * PI), self.c.abs().max_element()),
        }
    }

    /// The lobe's value (per unit ρ) for the pair (u, v).
    fn value(&self, u: DVec3, v: DVec3) -> f64 {
        let d = self.c.x * u.x * v.x + self.c.y * u.y * v.y + self.c.z * u.z * v.z;
        if d <= 0.0 {
            return 0.0;
        }
        let (k, m) = self.scale();
        k * (d / m).powf(self.n)
    }

    /// Lobe axis ŵ for `v` and ln of the lobe's value on that axis (per unit ρ).
    fn axis(&self, v: DVec3) -> Option<(DVec3, f64)> {
        let a = self.c * v;
        let la = a.length();
        if !la.is_finite() || la <= 0.0 {
            return None;
        }
        let (k, m) = self.scale();
        Some((a / la, k.ln() + self.n * (la / m).ln()))
    }
}

/// A diffuse term plus any number of generalized cosine lobes.
#[derive(Clone, Debug, PartialEq)]
pub struct Lafortune {
    rho_d: Rgb,
    lobes: Vec<LafortuneLobe>,
    label: String,
}

impl Lafortune {
    /// A Lafortune BRDF with diffuse albedo `rho_d` (channels in [0, 1]) and `lobes` (C components
    /// in [−1000, 1000], n in [0, 10⁶], ρs in [0, 1000]).
    pub fn new(rho_d: Rgb, lobes: Vec<LafortuneLobe>) -> Result<Self> {
        check_rgb("rho_d", rho_d, 0.0, 1.0)?;
        for l in &lobes {
            l.validate()?;
        }
        Ok(Lafortune {
            rho_d,
            lobes,
            label: String::new(),
        })
    }

    /// The same BRDF with a material name shown by [`Bsdf::name`].
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = label.into();
        self
    }

    /// The diffuse albedo ρd.
    pub fn rho_d(&self) -> Rgb {
        self.rho_d
    }

    /// The lobes.
    pub fn lobes(&self) -> &[LafortuneLobe] {
        &self.lobes
    }

    /// Mixture weights for `wo`: diffuse first, then one per lobe (approximate albedos).
    fn weights(&self, wo: DVec3) -> Vec<f64> {
        let mut w = Vec::with_capacity(self.lobes.len() + 1);
        w.push(self.rho_d.mean());
        for l in &self.lobes {
            let wl = match l.axis(wo) {
                Some((axis, ln_peak)) => {
                    // Peak · (solid angle 2π/(n+1)) · projected cosine of the axis.
                    let ln = ln_peak + (2.0 * PI / (l.n + 1.0)).ln();
                    l.rho.mean() * ln.min(300.0).exp() * axis.z.max(0.05)
                }
                None => 0.0,
            };
            w.push(if wl.is_finite() { wl } else { 0.0 });
        }
        w
    }
}

impl Bsdf for Lafortune {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        if self.label.is_empty() {
            format!("lafortune({} lobes)", self.lobes.len())
        } else {
            format!("lafortune({})", self.label)
        }
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z < COS_MIN || wo.z < COS_MIN {
            return Rgb::ZERO;
        }
        let mut f = self.rho_d * (1.0 / PI);
        for l in &self.lobes {
            f += l.rho * l.value(wi, wo);
        }
        f
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if wo.z < COS_MIN {
            return None;
        }
        let (wi, kind) = sample_diffuse_mixture(&self.weights(wo), u1, u2, |k, u1, u2| {
            let l = &self.lobes[k - 1];
            let (axis, _) = l.axis(wo)?;
            Some(to_world(cosine_power(u1, u2, l.n), axis))
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
        diffuse_mixture_pdf(&self.weights(wo), wi, |k| {
            let l = &self.lobes[k - 1];
            l.axis(wo)
                .map_or(0.0, |(axis, _)| cosine_power_pdf(axis.dot(wi), l.n))
        })
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            reciprocal: true,
            energy_conserving: false,
            transmission: false,
            anisotropic: self.lobes.iter().any(|l| l.c.x != l.c.y),
            lobes: LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    #[test]
    fn raw_lobe_by_hand() {
        let l = LafortuneLobe::raw(DVec3::new(-0.9, -0.7, 0.8), 3.0, Rgb::splat(2.0));
        let m = Lafortune::new(Rgb::splat(0.3), vec![l]).expect("valid");
        let u = spherical(0.4, 0.2);
        let v = spherical(0.5, 0.2 + PI);
        let d = -0.9 * u.x * v.x - 0.7 * u.y * v.y + 0.8 * u.z * v.z;
        let want = 0.3 / PI + 2.0 * d.powi(3);
        assert!((m.eval(u, v)[0] - want).abs() < 1e-12);
        assert!(m.flags().anisotropic);
    }

    #[test]
    fn peak_lobe_by_hand() {
        // Phong-like lobe at the mirror direction: value ks (n+2)/(2π).
        let l = LafortuneLobe::ngan(-0.577, 0.577, 500.0, Rgb::splat(0.1));
        let m = Lafortune::new(Rgb::ZERO, vec![l]).expect("valid");
        let v = spherical(0.5, 1.0);
        let u = spherical(0.5, 1.0 + PI);
        let f = m.eval(u, v)[0];
        assert!((f - 0.1 * 502.0 / (2.0 * PI)).abs() < 1e-9, "{f}");
    }

    #[test]
    fn rejects_absurd_parameters() {
        let ok = LafortuneLobe::raw(DVec3::new(-1.0, -1.0, 1.0), 10.0, Rgb::ONE);
        assert!(Lafortune::new(Rgb::splat(1.5), vec![ok]).is_err());
        let bad = LafortuneLobe { n: -1.0, ..ok };
        assert!(Lafortune::new(Rgb::ZERO, vec![bad]).is_err());
        let bad = LafortuneLobe {
            c: DVec3::new(f64::NAN, 0.0, 1.0),
            ..ok
        };
        assert!(Lafortune::new(Rgb::ZERO, vec![bad]).is_err());
        let bad = LafortuneLobe::ngan(0.0, 0.0, 10.0, Rgb::ONE);
        assert!(Lafortune::new(Rgb::ZERO, vec![bad]).is_err());
        let bad = LafortuneLobe::raw(DVec3::new(-1.5, -1.5, 1.5), 5000.0, Rgb::ONE);
        assert!(Lafortune::new(Rgb::ZERO, vec![bad]).is_err());
    }
}
