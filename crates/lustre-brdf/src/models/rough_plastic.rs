//! Rough plastic, in Mitsuba 3's formulation (`roughplastic`): a rough dielectric coating (an
//! isotropic GGX or Beckmann microfacet reflection with Fresnel of η = int_ior/ext_ior) over a
//! Lambertian base seen through it,
//!
//! ```text
//! f(wi, wo) = s F(wo·h) D(h) G(wi, wo, h) / (4 cos θi cos θo)
//!           + ρ' T(cos θi) T(cos θo) / (π η²),
//! ρ' = ρ / (1 − Fdr)   (linear, default)   or   ρ / (1 − ρ Fdr)   (`nonlinear`),
//! ```
//!
//! with T(μ) the coating's external transmittance (the fraction of light arriving at cos θ = μ
//! that refracts through a microfacet and is not shadowed, single scattering: ∫ D_v(m) (1 − F)
//! G1(refracted, m) dm) and Fdr = 2∫ R_int(μ) μ dμ the coating's internal reflectance (R_int the
//! rough reflectance from inside, relative index 1/η). Like Mitsuba we tabulate T on 64 cosines
//! (linear interpolation) and integrate both with a Gauss-Legendre grid over the visible-normal
//! sampler (32² nodes for T, 64² for R_int; Mitsuba takes 32² and 128²). Sampling (Mitsuba's):
//! the coating with probability P_s = (1 − T(cos θo)) s / ((1 − T) s + T (1 − s)),
//! s = mean(specular)/(mean(diffuse) + mean(specular)), via visible normals; else the cosine-
//! weighted base. The Modern Hall uses it with GGX, α = 0.1 and 0.01, η = 1.5, `nonlinear`.

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{check_rgb, Error, Result};
use crate::frame::reflect;
use crate::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use crate::microfacet::fresnel::fresnel_dielectric;
use crate::models::dielectric::{refract, relative_ior};
use crate::models::glossy_diffuse::{self, GlossyDiffuse};
use crate::models::plastic::CoatedBase;
use crate::rgb::Rgb;
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::FRAC_1_PI;

/// Cosines at which the external transmittance is tabulated (Mitsuba's
/// `MI_ROUGH_TRANSMITTANCE_RES`).
const TABLE_RES: usize = 64;

/// A rough plastic. The tables depend only on (distribution, η): a textured material builds one
/// per (roughness, η) and varies the colours per hit with
/// [`RoughPlastic::with_reflectances`], which is cheap (the value is `Copy`, tables inline).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlastic {
    /// The coating's (isotropic) microfacet distribution.
    pub distribution: MicrofacetDistribution,
    /// Base albedo ρ.
    pub diffuse_reflectance: Rgb,
    /// Tint of the coating's reflection.
    pub specular_reflectance: Rgb,
    /// η = int_ior/ext_ior of the coating.
    pub eta: f64,
    /// Mitsuba's `nonlinear` flag.
    pub nonlinear: bool,
    external_transmittance: [f64; TABLE_RES],
    internal_reflectance: f64,
    specular_weight: f64,
}

/// ∫ over the visible normals m of `v` of g(m), by an n×n Gauss-Legendre grid on the sampler's
/// unit square (Mitsuba's `eval_reflectance`/`eval_transmittance` quadrature).
fn visible_normal_quadrature(
    d: &MicrofacetDistribution,
    v: DVec3,
    n: usize,
    g: impl Fn(DVec3) -> f64,
) -> f64 {
    let (x, w) = crate::numeric::gauss_legendre(n);
    let mut sum = 0.0;
    for (xa, wa) in x.iter().zip(&w) {
        for (xb, wb) in x.iter().zip(&w) {
            if let Some(m) = d.sample_visible(v, 0.5 * (xa + 1.0), 0.5 * (xb + 1.0)) {
                sum += 0.25 * wa * wb * g(m);
            }
        }
    }
    sum
}

/// Fraction of light arriving from `v` (outside) that refracts into a coating of index `eta`
/// through an unshadowed microfacet.
fn external_transmittance(d: &MicrofacetDistribution, v: DVec3, eta: f64, n: usize) -> f64 {
    visible_normal_quadrature(d, v, n, |m| {
        let f = fresnel_dielectric(v.dot(m), eta);
        let t = refract(v, m, f.cos_theta_t, f.eta_ti);
        if t.z * v.z >= 0.0 {
            return 0.0;
        }
        d.g1(t, m) * (1.0 - f.r)
    })
}

/// Fraction of light arriving from `v` that reflects off the interface of relative index `eta`
/// and leaves unshadowed.
fn rough_reflectance(d: &MicrofacetDistribution, v: DVec3, eta: f64, n: usize) -> f64 {
    visible_normal_quadrature(d, v, n, |m| {
        let r = reflect(v, m);
        if r.z <= 0.0 {
            return 0.0;
        }
        d.g1(r, m) * fresnel_dielectric(v.dot(m), eta).r
    })
}

impl RoughPlastic {
    /// A rough plastic: an isotropic `kind` distribution of roughness `alpha`, colours in
    /// [0, 1], indices as for [`relative_ior`]. Builds the transmittance table (≈ 0.3 M
    /// visible-normal samples).
    pub fn new(
        kind: MicrofacetType,
        alpha: f64,
        diffuse_reflectance: Rgb,
        specular_reflectance: Rgb,
        int_ior: f64,
        ext_ior: f64,
        nonlinear: bool,
    ) -> Result<Self> {
        check_rgb("diffuse_reflectance", diffuse_reflectance, 0.0, 1.0)?;
        check_rgb("specular_reflectance", specular_reflectance, 0.0, 1.0)?;
        let eta = relative_ior(int_ior, ext_ior)?;
        let distribution = MicrofacetDistribution::isotropic(kind, alpha)?;
        let mus: Vec<f64> = (0..TABLE_RES)
            .map(|i| (i as f64 / (TABLE_RES - 1) as f64).max(1e-6))
            .collect();
        let dir = |mu: f64| DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
        let mut table = [0.0; TABLE_RES];
        for (t, &mu) in table.iter_mut().zip(&mus) {
            *t = external_transmittance(&distribution, dir(mu), eta, 32);
        }
        // Mitsuba: mean over the same cosines of R_int(μ) μ, times 2.
        let internal_reflectance = 2.0
            * mus
                .iter()
                .map(|&mu| rough_reflectance(&distribution, dir(mu), 1.0 / eta, 64) * mu)
                .sum::<f64>()
            / TABLE_RES as f64;
        if internal_reflectance.is_nan() || internal_reflectance >= 1.0 {
            return Err(Error::param(
                "eta",
                eta,
                "the coating reflects all light internally",
            ));
        }
        let (d, s) = (diffuse_reflectance.mean(), specular_reflectance.mean());
        Ok(RoughPlastic {
            distribution,
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            external_transmittance: table,
            internal_reflectance,
            specular_weight: if d + s > 0.0 { s / (d + s) } else { 0.5 },
        })
    }

    /// The coating's transmittance table T(i/63), i = 0..64.
    pub fn transmittance_table(&self) -> &[f64; TABLE_RES] {
        &self.external_transmittance
    }

    /// The same coating (tables kept) with other colours in [0, 1]: what a texture lookup
    /// produces per shading point.
    pub fn with_reflectances(self, diffuse: Rgb, specular: Rgb) -> Result<Self> {
        check_rgb("diffuse_reflectance", diffuse, 0.0, 1.0)?;
        check_rgb("specular_reflectance", specular, 0.0, 1.0)?;
        let (d, s) = (diffuse.mean(), specular.mean());
        Ok(RoughPlastic {
            diffuse_reflectance: diffuse,
            specular_reflectance: specular,
            specular_weight: if d + s > 0.0 { s / (d + s) } else { 0.5 },
            ..self
        })
    }

    /// T(μ), linearly interpolated in the table.
    pub fn transmittance(&self, mu: f64) -> f64 {
        let x = mu.clamp(0.0, 1.0) * (TABLE_RES - 1) as f64;
        let i = (x as usize).min(TABLE_RES - 2);
        let t = x - i as f64;
        let tab = &self.external_transmittance;
        tab[i] * (1.0 - t) + tab[i + 1] * t
    }

    /// The coating's internal reflectance Fdr.
    pub fn internal_reflectance(&self) -> f64 {
        self.internal_reflectance
    }

    /// T̄ = 2∫₀¹ T(μ) μ dμ of the interpolated table (exact for its piecewise-linear T).
    pub fn mean_transmittance(&self) -> f64 {
        let tab = &self.external_transmittance;
        let h = 1.0 / (TABLE_RES - 1) as f64;
        let mut sum = 0.0;
        for i in 0..TABLE_RES - 1 {
            let (a, b) = (i as f64 * h, (i + 1) as f64 * h);
            let slope = (tab[i + 1] - tab[i]) / h;
            // ∫ₐᵇ (T_a + slope (μ − a)) μ dμ
            sum += tab[i] * (b * b - a * a) / 2.0
                + slope * ((b * b * b - a * a * a) / 3.0 - a * (b * b - a * a) / 2.0);
        }
        2.0 * sum
    }

    /// The base as a Lambertian ([`CoatedBase`]).
    pub fn coated_base(&self) -> CoatedBase {
        CoatedBase::new(
            self.mean_transmittance(),
            self.eta,
            self.internal_reflectance,
            self.nonlinear,
        )
    }
}

impl GlossyDiffuse for RoughPlastic {
    fn distribution(&self) -> &MicrofacetDistribution {
        &self.distribution
    }

    fn prob_specular(&self, wo: DVec3) -> f64 {
        let t = self.transmittance(wo.z);
        let ps = (1.0 - t) * self.specular_weight;
        let pd = t * (1.0 - self.specular_weight);
        if ps + pd > 0.0 {
            ps / (ps + pd)
        } else {
            0.0
        }
    }
}

impl Bsdf for RoughPlastic {
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn name(&self) -> String {
        format!(
            "roughplastic({}, α={}, η={}{})",
            self.distribution.kind().name(),
            self.distribution.alpha_u(),
            self.eta,
            if self.nonlinear { ", nonlinear" } else { "" }
        )
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return Rgb::ZERO;
        }
        let h = (wi + wo).normalize();
        let d = self.distribution.d(h);
        let spec = if d > 0.0 {
            let f = fresnel_dielectric(wo.dot(h), self.eta).r;
            f * d * self.distribution.g(wi, wo, h) / (4.0 * wi.z * wo.z)
        } else {
            0.0
        };
        let fdr = self.internal_reflectance;
        let base = if self.nonlinear {
            self.diffuse_reflectance.map(|x| x / (1.0 - x * fdr))
        } else {
            self.diffuse_reflectance / (1.0 - fdr)
        };
        let t = self.transmittance(wi.z) * self.transmittance(wo.z);
        self.specular_reflectance * spec + base * (FRAC_1_PI / (self.eta * self.eta) * t)
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        glossy_diffuse::sample(self, wo, u1, u2)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        glossy_diffuse::pdf(self, wi, wo)
    }

    /// Reciprocal (T(cos θi) T(cos θo) and the coating are symmetric); energy conserving for
    /// colours ≤ 1 (measured in the tests: the white linear albedo stays below 1).
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, true)
            .with_lobes(LobeFlags::GLOSSY_REFLECTION | LobeFlags::DIFFUSE_REFLECTION)
    }
}

/// Roughnesses of a [`RoughPlasticCoating`]: `COATING_ALPHAS` values from
/// [`COATING_ALPHA_MIN`] to 1, evenly spaced in log α.
pub const COATING_ALPHAS: usize = 65;
/// The smallest roughness of a [`RoughPlasticCoating`] (lustre-scene's clamp of α).
pub const COATING_ALPHA_MIN: f64 = 1e-4;

/// The coating of a rough plastic whose roughness varies over its surface (a textured α): the
/// transmittance table T(μ) and internal reflectance Fdr of [`RoughPlastic::new`] at
/// [`COATING_ALPHAS`] roughnesses log-spaced over [[`COATING_ALPHA_MIN`], 1], built once per
/// material; a shading point's coating is interpolated linearly in log α
/// ([`RoughPlasticCoating::at`]). T and Fdr vary slowly with α (tests/coating.rs: T within
/// 1.4·10⁻³ of the exact table between grid points, Fdr within 4·10⁻⁴, the BRDF within 0.2 %),
/// and a per-point table would cost ≈ 0.3 M microfacet integrals per hit.
#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlasticCoating {
    /// The coatings at the grid's roughnesses (colours: ρ = 0.5, R_s = 1).
    pub grid: Vec<RoughPlastic>,
}

impl RoughPlasticCoating {
    /// The grid of coatings of an isotropic `kind` distribution and indices as for
    /// [`relative_ior`]. Errors as [`RoughPlastic::new`].
    pub fn new(kind: MicrofacetType, int_ior: f64, ext_ior: f64, nonlinear: bool) -> Result<Self> {
        let grid = (0..COATING_ALPHAS)
            .into_par_iter()
            .map(|i| {
                RoughPlastic::new(
                    kind,
                    Self::alpha_of(i),
                    Rgb::splat(0.5),
                    Rgb::ONE,
                    int_ior,
                    ext_ior,
                    nonlinear,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(RoughPlasticCoating { grid })
    }

    /// Roughness i of the grid.
    pub fn alpha_of(i: usize) -> f64 {
        let step = -COATING_ALPHA_MIN.log2() / (COATING_ALPHAS - 1) as f64;
        (COATING_ALPHA_MIN.log2() + step * i as f64).exp2()
    }

    /// Where roughness `alpha` falls in the grid: (i, t), the coating (1 − t)·grid[i] +
    /// t·grid[i + 1]; α clamped to the grid's range (NaN: 1).
    pub fn position(alpha: f64) -> (usize, f64) {
        let a = Self::clamp(alpha);
        let x = (a / COATING_ALPHA_MIN).log2() * (COATING_ALPHAS - 1) as f64
            / -COATING_ALPHA_MIN.log2();
        let i = (x.max(0.0) as usize).min(COATING_ALPHAS - 2);
        (i, (x - i as f64).clamp(0.0, 1.0))
    }

    /// α clamped to the grid's range; NaN: 1.
    pub fn clamp(alpha: f64) -> f64 {
        if alpha.is_nan() {
            1.0
        } else {
            alpha.clamp(COATING_ALPHA_MIN, 1.0)
        }
    }

    /// The rough plastic of roughness `alpha` ([`RoughPlasticCoating::clamp`]ed; its
    /// distribution exact, its T table and Fdr interpolated between the two nearest grid
    /// roughnesses) with colours in [0, 1].
    pub fn at(&self, alpha: f64, diffuse: Rgb, specular: Rgb) -> Result<RoughPlastic> {
        let (i, t) = Self::position(alpha);
        let (a, b) = (&self.grid[i], &self.grid[i + 1]);
        let distribution =
            MicrofacetDistribution::isotropic(a.distribution.kind(), Self::clamp(alpha))?;
        let mut table = [0.0; TABLE_RES];
        for (k, v) in table.iter_mut().enumerate() {
            *v = a.external_transmittance[k] * (1.0 - t) + b.external_transmittance[k] * t;
        }
        let internal_reflectance = a.internal_reflectance * (1.0 - t) + b.internal_reflectance * t;
        RoughPlastic {
            distribution,
            external_transmittance: table,
            internal_reflectance,
            ..*a
        }
        .with_reflectances(diffuse, specular)
    }
}
