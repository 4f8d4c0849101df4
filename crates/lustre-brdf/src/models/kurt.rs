//! The Kurt, Szirmay-Kalos & Křivánek (2010) BRDF with Luksch's transmission lobes (000 §3.3).
//!
//! f(ωi, ωo) = kd/π + Σ ks·f_rlobe(ωi, ωo) + Σ kt·f_tlobe(ωi, ωo)            (000 Eq. 3.6)
//!
//! f_rlobe = F(ωo·h) D(h) / (4 (ωo·h) ((ωi·n)(ωo·n))^α)                         (000 Eq. 3.4)
//! D(h)    = exp(−tan²θh (cos²φh/mx² + sin²φh/my²)) / (π mx my cos⁴θh)         (000 Eq. 3.3)
//! F(u)    = r0 + (1 − r0)(1 − u)⁵                                             (000 Eq. 2.9)
//!
//! A transmission lobe (000 Eq. 3.5) is a reflection lobe evaluated with the transmitted direction
//! mirrored through the surface plane (z → −z), with the Fresnel factor 1 − F. Its peak therefore
//! lies at ωi = −ωo: the thin-surface model ignores refraction.
//!
//! **Both sides.** The surface is thin and two-sided: when `wo` lies below the surface (z < 0) both
//! directions are mirrored through the surface plane and the configuration is evaluated as if `wo`
//! were above. The diffuse term and the reflection lobes then act in the lower hemisphere and the
//! transmission lobes carry light from the upper one. Because every lobe is symmetric in its two
//! arguments, f(wi, wo) = f(wo, wi) holds for all pairs, across hemispheres included. Directions
//! exactly in the surface plane (z = 0) scatter nothing.
//!
//! **Sampling** (000 §4.4.2): a component (diffuse, each reflection lobe, each transmission lobe) is
//! picked with probability proportional to the luminance of kd, ks or kt; the diffuse term is
//! cosine-sampled, a lobe draws h by Eq. 4.5–4.7 and reflects ωo about it (Eq. 4.8), mirrored
//! through the plane for a transmission lobe. The lobe density is Eq. 4.9,
//! p(ωi) = D(h) cos θh / (4 ωo·h), and the model's pdf is the mixture over the components.
//!
//! **Energy.** For α = 0 a lobe with F ≡ 1 and unit ks has the albedo
//! A(ωo) = ∫ D(h) (ωi·n) dωh over the h that reflect ωo into the upper hemisphere; the tests in
//! `tests/kurt_battery.rs` measure it by quadrature over roughness and incidence (see
//! [`Kurt::flags`] for the resulting promise).

use crate::bsdf::{finish_sample, sample_diffuse_mixture, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_range, check_rgb, Result};
use crate::frame::{half_vector, mirror_z, reflect};
use crate::rgb::Rgb;
use crate::sampling::cosine_hemisphere_pdf;
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Smallest accepted roughness mx, my.
pub const MIN_ROUGHNESS: f64 = 1e-6;
/// Largest accepted roughness mx, my.
pub const MAX_ROUGHNESS: f64 = 1e3;

/// One specular lobe: reflection (ks) or transmission (where `ks` plays kt).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct KurtLobe {
    /// Lobe weight ks (kt for a transmission lobe), per channel, ≥ 0.
    pub ks: Rgb,
    /// Roughness along the tangent x, in [`MIN_ROUGHNESS`, `MAX_ROUGHNESS`].
    pub mx: f64,
    /// Roughness along the bitangent y, in [`MIN_ROUGHNESS`, `MAX_ROUGHNESS`].
    pub my: f64,
    /// Schlick reflectance at normal incidence, in [0, 1].
    pub r0: f64,
    /// Shadowing/masking exponent α, in [0, 1].
    pub alpha: f64,
}

impl KurtLobe {
    /// A validated lobe: mx, my finite in [`MIN_ROUGHNESS`, `MAX_ROUGHNESS`], r0 and α in
    /// [0, 1], ks finite and ≥ 0 in every channel.
    pub fn new(ks: Rgb, mx: f64, my: f64, r0: f64, alpha: f64) -> Result<Self> {
        let lobe = KurtLobe {
            ks,
            mx,
            my,
            r0,
            alpha,
        };
        lobe.validate()?;
        Ok(lobe)
    }

    /// Checks the ranges documented on [`KurtLobe::new`].
    pub fn validate(&self) -> Result<()> {
        check_rgb("ks", self.ks, 0.0, crate::error::MAX_REFLECTANCE)?;
        check_range("mx", self.mx, MIN_ROUGHNESS, MAX_ROUGHNESS)?;
        check_range("my", self.my, MIN_ROUGHNESS, MAX_ROUGHNESS)?;
        check_range("r0", self.r0, 0.0, 1.0)?;
        check_range("alpha", self.alpha, 0.0, 1.0)?;
        Ok(())
    }
}

/// Which Fresnel factor a lobe carries: F for reflection, 1 − F for transmission (000 Eq. 3.5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    /// A reflection lobe, Fresnel F.
    Reflection,
    /// A transmission lobe, Fresnel 1 − F.
    Transmission,
}

/// Schlick's Fresnel approximation F(u) = r0 + (1 − r0)(1 − u)⁵ (000 Eq. 2.9).
#[inline]
pub fn schlick(r0: f64, u: f64) -> f64 {
    let m = (1.0 - u).clamp(0.0, 1.0);
    let m2 = m * m;
    r0 + (1.0 - r0) * m2 * m2 * m
}

/// The anisotropic normalized Beckmann distribution D(h) of 000 Eq. 3.3 (φh measured from the
/// tangent x); zero for h at or below the horizon. ∫ D(h) cos θh dωh = 1.
#[inline]
pub fn beckmann_d(mx: f64, my: f64, h: DVec3) -> f64 {
    if h.z.is_nan() || h.z <= 0.0 {
        return 0.0;
    }
    // tan²θh cos²φh = hx²/hz², tan²θh sin²φh = hy²/hz².
    let (ax, ay) = (h.x / (mx * h.z), h.y / (my * h.z));
    let e = -(ax * ax + ay * ay);
    if e.is_nan() || e <= -740.0 {
        return 0.0;
    }
    // In logarithms, so that neither cos⁴θh nor mx·my under- or overflows.
    (e - PI.ln() - mx.ln() - my.ln() - 4.0 * h.z.ln()).exp()
}

/// f_lobe of 000 Eq. 3.4 (or Eq. 3.5 with 1 − F), times the lobe's ks, in the reflection geometry:
/// `wi` and `wo` both in the upper hemisphere (for a transmission lobe `wi` is the mirrored
/// transmitted direction). Zero when either is not above the surface.
#[inline]
pub fn lobe_eval(lobe: &KurtLobe, kind: LobeKind, wi: DVec3, wo: DVec3) -> Rgb {
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return Rgb::ZERO;
    }
    let Some(h) = half_vector(wi, wo) else {
        return Rgb::ZERO;
    };
    let u = wo.dot(h);
    if u.is_nan() || u <= 0.0 {
        return Rgb::ZERO;
    }
    let f = schlick(lobe.r0, u);
    let fresnel = match kind {
        LobeKind::Reflection => f,
        LobeKind::Transmission => 1.0 - f,
    };
    let d = beckmann_d(lobe.mx, lobe.my, h);
    let shadow = if lobe.alpha == 0.0 {
        1.0
    } else {
        (wi.z * wo.z).powf(lobe.alpha)
    };
    lobe.ks * (fresnel * d / (4.0 * u * shadow))
}

/// Draws a half vector h with density D(h) cos θh (000 Eq. 4.5–4.7) from u1, u2 in [0, 1).
/// Eq. 4.5's arctan is taken with the quadrant of 2πu2 (atan2), so φh covers the full circle.
#[inline]
pub fn lobe_sample_h(lobe: &KurtLobe, u1: f64, u2: f64) -> DVec3 {
    let phi0 = 2.0 * PI * u2;
    let phi = (lobe.my * phi0.sin()).atan2(lobe.mx * phi0.cos());
    let (sp, cp) = phi.sin_cos();
    // ξ1 = 1 − u1 ∈ (0, 1]; kept away from 0 so that the logarithm is finite.
    let xi1 = (1.0 - u1).clamp(f64::MIN_POSITIVE, 1.0);
    let a = cp * cp / (lobe.mx * lobe.mx) + sp * sp / (lobe.my * lobe.my);
    let t2 = -xi1.ln() / a; // tan²θh, Eq. 4.6
    let ct = 1.0 / (1.0 + t2).sqrt();
    let st = (t2 / (1.0 + t2)).sqrt();
    DVec3::new(st * cp, st * sp, ct) // Eq. 4.7
}

/// The solid-angle density of `wi` produced by reflecting `wo` about [`lobe_sample_h`]'s h,
/// p = D(h) cos θh / (4 ωo·h) (000 Eq. 4.9), in the reflection geometry (both upper hemisphere).
#[inline]
pub fn lobe_pdf(lobe: &KurtLobe, wi: DVec3, wo: DVec3) -> f64 {
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return 0.0;
    }
    let Some(h) = half_vector(wi, wo) else {
        return 0.0;
    };
    let u = wo.dot(h);
    if u.is_nan() || u <= 0.0 {
        return 0.0;
    }
    beckmann_d(lobe.mx, lobe.my, h) * h.z / (4.0 * u)
}

/// The Kurt BSDF: a Lambertian term plus any number of reflection and transmission lobes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Kurt {
    /// Diffuse coefficient kd (reflection only), per channel, ≥ 0.
    pub kd: Rgb,
    /// Reflection lobes (000 Eq. 3.4).
    pub reflection: Vec<KurtLobe>,
    /// Transmission lobes (000 Eq. 3.5); their `ks` is kt.
    pub transmission: Vec<KurtLobe>,
}

impl Kurt {
    /// A validated model: kd finite and ≥ 0, every lobe valid ([`KurtLobe::validate`]).
    pub fn new(kd: Rgb, reflection: Vec<KurtLobe>, transmission: Vec<KurtLobe>) -> Result<Self> {
        let k = Kurt {
            kd,
            reflection,
            transmission,
        };
        k.validate()?;
        Ok(k)
    }

    /// Checks kd and every lobe.
    pub fn validate(&self) -> Result<()> {
        check_rgb("kd", self.kd, 0.0, crate::error::MAX_REFLECTANCE)?;
        self.reflection
            .iter()
            .chain(&self.transmission)
            .try_for_each(KurtLobe::validate)
    }

    /// Component selection weights: luminance of kd, of each ks, then of each kt.
    fn weights(&self) -> impl Iterator<Item = f64> + '_ {
        std::iter::once(self.kd.luminance()).chain(
            self.reflection
                .iter()
                .chain(&self.transmission)
                .map(|l| l.ks.luminance()),
        )
    }

    /// Maps a pair to the side where `wo` is above the surface (the thin two-sided convention).
    #[inline]
    fn to_upper(wi: DVec3, wo: DVec3) -> (DVec3, DVec3) {
        if wo.z < 0.0 {
            (mirror_z(wi), mirror_z(wo))
        } else {
            (wi, wo)
        }
    }
}

impl Bsdf for Kurt {
    fn name(&self) -> String {
        format!(
            "Kurt ({} reflection, {} transmission lobes)",
            self.reflection.len(),
            self.transmission.len()
        )
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let (wi, wo) = Self::to_upper(wi, wo);
        if wo.z.is_nan() || wo.z <= 0.0 {
            return Rgb::ZERO;
        }
        if wi.z > 0.0 {
            let mut f = self.kd / PI;
            for l in &self.reflection {
                f += lobe_eval(l, LobeKind::Reflection, wi, wo);
            }
            f
        } else if wi.z < 0.0 {
            let wm = mirror_z(wi);
            let mut f = Rgb::ZERO;
            for l in &self.transmission {
                f += lobe_eval(l, LobeKind::Transmission, wm, wo);
            }
            f
        } else {
            Rgb::ZERO
        }
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        let flip = wo.z < 0.0;
        let wo_u = if flip { mirror_z(wo) } else { wo };
        if wo_u.z.is_nan() || wo_u.z <= 0.0 {
            return None;
        }
        let weights: Vec<f64> = self.weights().collect();
        let nr = self.reflection.len();
        let (wi_u, kind) = sample_diffuse_mixture(&weights, u1, u2, |idx, u1, u2| {
            let (lobe, transmit) = if idx <= nr {
                (&self.reflection[idx - 1], false)
            } else {
                (&self.transmission[idx - 1 - nr], true)
            };
            let h = lobe_sample_h(lobe, u1, u2);
            if wo_u.dot(h).is_nan() || wo_u.dot(h) <= 0.0 {
                return None;
            }
            let r = reflect(wo_u, h); // Eq. 4.8
            if r.z.is_nan() || r.z <= 0.0 {
                return None;
            }
            Some(if transmit { mirror_z(r) } else { r })
        })?;
        let wi = if flip { mirror_z(wi_u) } else { wi_u };
        finish_sample(wi, wo, self.pdf(wi, wo), kind, || self.eval(wi, wo))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (wi, wo) = Self::to_upper(wi, wo);
        if wo.z.is_nan() || wo.z <= 0.0 {
            return 0.0;
        }
        let total: f64 = self.weights().sum();
        if total.is_nan() || total <= 0.0 {
            return 0.0;
        }
        let p = if wi.z > 0.0 {
            let mut p = self.kd.luminance() * cosine_hemisphere_pdf(wi);
            for l in &self.reflection {
                let w = l.ks.luminance();
                if w > 0.0 {
                    p += w * lobe_pdf(l, wi, wo);
                }
            }
            p
        } else if wi.z < 0.0 {
            let wm = mirror_z(wi);
            let mut p = 0.0;
            for l in &self.transmission {
                let w = l.ks.luminance();
                if w > 0.0 {
                    p += w * lobe_pdf(l, wm, wo);
                }
            }
            p
        } else {
            0.0
        };
        p / total
    }

    /// Reciprocal always. Energy conserving is promised when every lobe has α = 0 and
    /// kd + Σks + Σkt ≤ 1 in every channel: the single-lobe albedo with F ≡ 1 stays at or below 1
    /// for every roughness and incidence measured (see `tests/kurt_battery.rs`), and F + (1 − F)
    /// = 1 bounds a reflection/transmission pair. Anisotropic when some lobe has mx ≠ my.
    fn flags(&self) -> BsdfFlags {
        let lobes = || self.reflection.iter().chain(&self.transmission);
        let sum = lobes().fold(self.kd, |acc, l| acc + l.ks);
        BsdfFlags {
            reciprocal: true,
            energy_conserving: lobes().all(|l| l.alpha == 0.0) && sum.max_component() <= 1.0,
            transmission: !self.transmission.is_empty(),
            anisotropic: lobes().any(|l| l.mx != l.my),
            lobes: {
                let mut l = LobeFlags::NONE;
                if self.kd.max_component() > 0.0 {
                    l |= LobeFlags::DIFFUSE_REFLECTION;
                }
                if !self.reflection.is_empty() {
                    l |= LobeFlags::GLOSSY_REFLECTION;
                }
                if !self.transmission.is_empty() {
                    l |= LobeFlags::GLOSSY_TRANSMISSION;
                }
                l
            },
        }
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::spherical;

    fn lobe(ks: f64, mx: f64, my: f64, r0: f64, alpha: f64) -> KurtLobe {
        KurtLobe::new(Rgb::splat(ks), mx, my, r0, alpha).expect("valid lobe")
    }

    #[test]
    fn rejects_absurd_parameters() {
        assert!(KurtLobe::new(Rgb::ONE, 0.0, 0.1, 0.5, 0.0).is_err());
        assert!(KurtLobe::new(Rgb::ONE, -0.1, 0.1, 0.5, 0.0).is_err());
        assert!(KurtLobe::new(Rgb::ONE, f64::NAN, 0.1, 0.5, 0.0).is_err());
        assert!(KurtLobe::new(Rgb::ONE, 0.1, f64::INFINITY, 0.5, 0.0).is_err());
        assert!(KurtLobe::new(Rgb::ONE, 0.1, 0.1, 1.5, 0.0).is_err());
        assert!(KurtLobe::new(Rgb::ONE, 0.1, 0.1, 0.5, -0.1).is_err());
        assert!(KurtLobe::new(Rgb::ONE, 0.1, 0.1, 0.5, 1.1).is_err());
        assert!(KurtLobe::new(Rgb::new(1.0, -0.1, 0.0), 0.1, 0.1, 0.5, 0.0).is_err());
        let mut bad = lobe(1.0, 0.1, 0.1, 0.5, 0.0);
        bad.r0 = f64::NAN;
        assert!(Kurt::new(Rgb::ZERO, vec![], vec![bad]).is_err());
        assert!(Kurt::new(Rgb::new(f64::NAN, 0.0, 0.0), vec![], vec![]).is_err());
        assert!(Kurt::new(Rgb::splat(0.5), vec![lobe(0.5, 0.1, 0.2, 0.1, 0.3)], vec![]).is_ok());
    }

    #[test]
    fn normal_incidence_peak_by_hand() {
        // ωi = ωo = n: h = n, θh = 0, F(1) = r0, D = 1/(π mx my): f = kd/π + ks r0/(4π mx my).
        let (kd, ks, mx, my, r0) = (0.2, 0.7, 0.1, 0.3, 0.04);
        let k = Kurt::new(Rgb::splat(kd), vec![lobe(ks, mx, my, r0, 0.6)], vec![]).expect("ok");
        let f = k.eval(DVec3::Z, DVec3::Z)[0];
        let want = kd / PI + ks * r0 / (4.0 * PI * mx * my);
        assert!((f - want).abs() < 1e-12 * want, "{f} vs {want}");
    }

    #[test]
    fn off_peak_value_by_hand() {
        // wo at θ = 30° towards +x, wi at θ = 50° towards −x: h lies in the xz plane at
        // θh = 10° towards −x, so φh = π and only mx matters; written out longhand.
        let l = lobe(1.0, 0.2, 0.4, 0.3, 0.5);
        let wo = spherical(30f64.to_radians(), 0.0);
        let wi = spherical(50f64.to_radians(), PI);
        let th: f64 = (-10f64).to_radians(); // h = (sin θh, 0, cos θh) with θh = −10°
        let u = (40f64).to_radians().cos(); // ωo·h: angle 30° + 10°
        let d = (-(th.tan().powi(2)) / (0.2f64 * 0.2)).exp() / (PI * 0.2 * 0.4 * th.cos().powi(4));
        let fr = 0.3 + 0.7 * (1.0 - u).powi(5);
        let want =
            fr * d / (4.0 * u * (50f64.to_radians().cos() * 30f64.to_radians().cos()).powf(0.5));
        let got = lobe_eval(&l, LobeKind::Reflection, wi, wo)[1];
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
        // The transmission lobe at the mirrored pair carries 1 − F instead.
        let k = Kurt::new(Rgb::ZERO, vec![], vec![l]).expect("ok");
        let gt = k.eval(mirror_z(wi), wo)[2];
        let want_t = (1.0 - fr) * d
            / (4.0 * u * (50f64.to_radians().cos() * 30f64.to_radians().cos()).powf(0.5));
        assert!((gt - want_t).abs() < 1e-12 * want_t, "{gt} vs {want_t}");
    }

    #[test]
    fn transmission_peak_is_straight_through() {
        // The transmission lobe peaks at ωi = −ωo (no refraction, 000 Fig. 3.5).
        let k = Kurt::new(Rgb::ZERO, vec![], vec![lobe(1.0, 0.1, 0.1, 0.0, 0.0)]).expect("ok");
        let wo = spherical(0.6, 0.4);
        let peak = k.eval(-wo, wo)[0];
        for t in [0.55, 0.65, 0.5] {
            let wi = -spherical(t, 0.4);
            assert!(k.eval(wi, wo)[0] < peak);
        }
        // By hand: the mirrored pair is the mirror configuration, h = n, ωo·h = cos θo, so
        // f = kt (1 − F(cos θo)) / (π mx my · 4 cos θo).
        let c = wo.z;
        let want = (1.0 - (1.0 - c).powi(5)) / (PI * 0.01 * 4.0 * c);
        assert!((peak - want).abs() < 1e-12 * want, "{peak} vs {want}");
        // Nothing in the reflection hemisphere.
        assert_eq!(k.eval(reflect(wo, DVec3::Z), wo), Rgb::ZERO);
    }

    #[test]
    fn sampled_half_vector_quadrants() {
        // φh follows the quadrant of 2πu2 (Eq. 4.5 taken with atan2).
        let l = lobe(1.0, 0.2, 0.5, 0.0, 0.0);
        for (u2, sx, sy) in [
            (0.1, 1.0, 1.0),
            (0.35, -1.0, 1.0),
            (0.6, -1.0, -1.0),
            (0.9, 1.0, -1.0),
        ] {
            let h = lobe_sample_h(&l, 0.5, u2);
            assert!(h.x * sx > 0.0 && h.y * sy > 0.0, "u2={u2}: {h}");
            assert!((h.length() - 1.0).abs() < 1e-12);
        }
    }
}
