//! Regular sampling for any BSDF: a fixed regular point set in [0, 1)² pushed through the
//! model's own sampling warp ([`Bsdf::sample`]), each sample read from the pyramid at the MIP
//! level of its solid angle, weighted by f |cos θi| / p.
//!
//! The seeds (000 §4, 002) place regular patterns in the half-vector space of Kurt lobes only.
//! Every model `lustre fit` writes (SGD / Beckmann / GGX Cook-Torrance) and every analytic
//! material already has an inverse-CDF-like warp from [0, 1)² to directions, so the same idea
//! carries over: take n points that cover [0, 1)² evenly, map them through the warp, and each
//! sample stands for the solid angle Ω = 1/(n p(ωi)) around it (002 Eq. 12's cell, here from
//! the warp's own density). The estimate is the plain importance-sampling sum
//! (1/n) Σ L(ωi; level(Ω)) f |cos θi| / p (000 Eq. 4.4) with pre-filtered lookups.
//!
//! The point set ([`fibonacci_point`]): the Fibonacci lattice xᵢ = (i + ½)/n,
//! yᵢ = frac(½ + i/φ) (φ the golden ratio) for any n. The first coordinate is exactly stratified
//! in n strata, so a model that picks its lobe with u1 (the diffuse/glossy mixtures) gives each
//! lobe its share of the budget to within one sample, and the rescaled u1 stays stratified
//! inside the lobe; the second is the golden-ratio sequence, the 1-D sequence of lowest
//! discrepancy, so every pair of points differs in both coordinates. Through a radial/azimuthal
//! warp it is the sunflower (Vogel) spiral, the most even n-point covering of a disc, for any
//! n, where a √n × √n grid needs a square n and Hammersley stratifies only at powers of two.
//! Measured against the exact integral (`examples/warp_study.rs`, BENCHMARKS.md): Hammersley
//! read at the same levels is better at n = 8 (a (0, 3, 2)-net) for 6 of 9 materials, the
//! Fibonacci lattice at 13 and 19 for 6 of 9; both beat random points and CK.
//!
//! Levels ([`LevelRule`]): [`mip::footprint_level`] of Ω (the row lattice's rule, direction-
//! dependent texel size, bias −½), or Colbert–Křivánek's [`mip::ck_level`] (mean texel size,
//! bias +1). Dirac samples (smooth conductors, dielectrics, coats) are read at level 0.
//!
//! [`shade_regular_warp`] is ours (Fibonacci points, footprint levels); [`shade_ck_warp`] is
//! Colbert & Křivánek (2007) for any BSDF (Hammersley points, their level), the baseline of
//! 002 and GPU Gems 3 ch. 20; [`shade_warp`] takes any point set and level rule, so that a
//! comparison can change one thing at a time.
//!
//! Sides: as [`crate::integrator::shade_reference`] (and unlike the Kurt integrators, which face the
//! frame towards the viewer) the BSDF receives ωo in the given frame and decides the side
//! itself, as [`crate::truth::truth`] does.

use crate::integrator::{incident, FilteredEnvironment, Lookup};
use crate::mip;
use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::{hammersley, SplitMix64};
use lustre_trace::sampling::ShadingFrame;
use std::f64::consts::PI;

/// 1/φ = (√5 − 1)/2, the golden-ratio step of [`fibonacci_point`], rounded to 24 bits
/// (round(2²⁴/φ)).
const INV_GOLDEN_24: u32 = 10_368_890;

/// Point i of the n-point Fibonacci lattice in [0, 1)²: ((i + ½)/n, frac(½ + i/φ)), the second
/// coordinate computed on the 2⁻²⁴ grid ((2²³ + i·round(2²⁴/φ)) mod 2²⁴ / 2²⁴), so that an f32
/// GPU twin reproduces it bit for bit (the rough dielectric splits its bits).
#[inline]
pub fn fibonacci_point(i: usize, n: usize) -> (f64, f64) {
    let v = (i as u32)
        .wrapping_mul(INV_GOLDEN_24)
        .wrapping_add(0x80_0000)
        & 0xff_ffff;
    (
        (i as f64 + 0.5) / n.max(1) as f64,
        f64::from(v) / 16_777_216.0,
    )
}

/// The points pushed through the warp.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointSet {
    /// [`fibonacci_point`]: the regular set of [`shade_regular_warp`].
    Fibonacci,
    /// The n-point Hammersley set ([`hammersley`]), Colbert & Křivánek's choice.
    Hammersley,
    /// Independent uniform points from [`SplitMix64`]`(seed)`.
    Random(u64),
}

/// How a sample's solid angle Ω = 1/(n p) becomes a MIP level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelRule {
    /// [`mip::footprint_level`]`(Ω, ωi, N)`: ½ log2(Ω / Ωp(ωi)) − ½.
    Footprint,
    /// [`mip::ck_level`]`(p, n, N)`: ½ log2(Ω / Ω̄p) + 1 (Colbert & Křivánek 2007).
    Ck,
}

/// The radiance towards `wo_local` of `bsdf` minus a Lambertian part `kd`/π (zero: the whole
/// BSDF; the walkthrough frame passes the light-mapped albedo, whose light the light map holds), from `n` points pushed through the BSDF's sampling warp; `points(i)` gives the i-th
/// point in [0, 1)², `light(wi_world, pdf)` the filtered incident radiance of a sample drawn
/// with density `pdf` (`None` for a Dirac sample, read unfiltered). Returns the radiance and
/// the lookups made (at most `n`).
pub fn integrate_warp(
    bsdf: &dyn Bsdf,
    kd: Rgb,
    to_world: impl Fn(DVec3) -> DVec3,
    wo_local: DVec3,
    n: usize,
    points: impl Fn(usize) -> (f64, f64),
    light: impl Fn(DVec3, Option<f64>) -> Rgb,
) -> (Rgb, usize) {
    let mut sum = Rgb::ZERO;
    let mut lookups = 0;
    if bsdf.flags().delta_only() && n >= 2 {
        // Only Dirac lobes (a mirror, a glass sheet): the integral is a sum over the branches,
        // found at the two ends of the lobe-selection coordinate and weighted by their
        // probabilities (value·|cos| = weight·probability) — exact, with at most 2 lookups.
        let mut seen: Vec<DVec3> = vec![];
        for u1 in [1e-9, 1.0 - 1e-9] {
            let Some(s) = bsdf.sample(wo_local, u1, 0.5) else {
                continue;
            };
            if !s.wi.is_finite() || seen.iter().any(|w| w.distance_squared(s.wi) < 1e-18) {
                continue;
            }
            seen.push(s.wi);
            lookups += 1;
            sum += light(to_world(s.wi), None) * (s.value * s.wi.z.abs());
        }
        return (sum, lookups);
    }
    for i in 0..n {
        let (u1, u2) = points(i);
        let Some(s) = bsdf.sample(wo_local, u1, u2) else {
            continue;
        };
        if s.pdf.is_nan() || s.pdf <= 0.0 || !s.wi.is_finite() {
            continue;
        }
        let wi = to_world(s.wi);
        let weight = if s.is_delta() {
            s.weight()
        } else {
            // f − kd/π on the reflection side: the light map already holds the diffuse part.
            let reflect = s.wi.z * wo_local.z > 0.0;
            let f = if reflect {
                s.value - kd * (1.0 / PI)
            } else {
                s.value
            };
            f * (s.wi.z.abs() / s.pdf)
        };
        if !weight.is_finite() || weight == Rgb::ZERO {
            continue;
        }
        let pdf = (!s.is_delta()).then_some(s.pdf);
        lookups += 1;
        sum += light(wi, pdf) * weight;
    }
    (sum * (1.0 / n as f64), lookups)
}

/// The filtered estimate of the light reflected and transmitted towards the world direction
/// `wo` at a point with shading frame `f`: `n` points of `points` pushed through
/// `bsdf.sample(ωo, u1, u2)`, each lit by `env` (through the optional bounding-plane `lookup`)
/// at the level `levels` gives its solid angle 1/(n p), weighted by f |cos θi| / p
/// ([`lustre_brdf::bsdf::BsdfSample::weight`]); Dirac samples at level 0. Failed samples count
/// as zero. Returns the radiance and the number of pyramid lookups made. `n = 0` gives black.
#[allow(clippy::too_many_arguments)]
pub fn shade_warp(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
    n: usize,
    points: PointSet,
    levels: LevelRule,
) -> (Rgb, usize) {
    if n == 0 {
        return (Rgb::ZERO, 0);
    }
    let wo_l = f.to_local(wo);
    let face = env.pyramid.base_size();
    let nu = n.min(u32::MAX as usize) as u32;
    let random: Vec<(f64, f64)> = match points {
        PointSet::Random(seed) => {
            let mut g = SplitMix64::new(seed);
            (0..n).map(|_| (g.next_f64(), g.next_f64())).collect()
        }
        _ => vec![],
    };
    integrate_warp(
        bsdf,
        Rgb::ZERO,
        |v| f.to_world(v),
        wo_l,
        n,
        |i| match points {
            PointSet::Random(_) => random[i],
            PointSet::Hammersley => hammersley(i as u32, nu),
            PointSet::Fibonacci => fibonacci_point(i, n),
        },
        |wi, pdf| {
            let level = pdf.map_or(0.0, |p| match levels {
                LevelRule::Footprint => mip::footprint_level(1.0 / (n as f64 * p), wi, face),
                LevelRule::Ck => mip::ck_level(p, n, face),
            });
            incident(env, lookup, wi, level)
        },
    )
}

/// Ours: regular in-lobe sampling for any BSDF, `budget` [`fibonacci_point`]s through the
/// model's warp, footprint levels ([`shade_warp`] with [`PointSet::Fibonacci`],
/// [`LevelRule::Footprint`]). Returns the radiance and the lookups made (≤ `budget`).
pub fn shade_regular_warp(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
    budget: usize,
) -> (Rgb, usize) {
    shade_warp(
        f,
        wo,
        bsdf,
        env,
        lookup,
        budget,
        PointSet::Fibonacci,
        LevelRule::Footprint,
    )
}

/// Colbert & Křivánek (2007) filtered importance sampling for any BSDF: `n` Hammersley points
/// through the model's warp, their MIP level ([`shade_warp`] with [`PointSet::Hammersley`],
/// [`LevelRule::Ck`]); for Kurt materials [`crate::integrator::shade_ck_with`] is the per-lobe
/// form.
pub fn shade_ck_warp(
    f: &ShadingFrame,
    wo: DVec3,
    bsdf: &dyn Bsdf,
    env: &FilteredEnvironment,
    lookup: Option<&Lookup>,
    n: usize,
) -> (Rgb, usize) {
    shade_warp(
        f,
        wo,
        bsdf,
        env,
        lookup,
        n,
        PointSet::Hammersley,
        LevelRule::Ck,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::catalog::resolve;
    use lustre_env::{irradiance_map, CubeMap, CubePyramid, MipFilter};

    #[test]
    fn fibonacci_points_are_stratified_and_distinct() {
        for n in [1, 2, 5, 8, 13, 19, 64] {
            let pts: Vec<_> = (0..n).map(|i| fibonacci_point(i, n)).collect();
            for (i, &(x, y)) in pts.iter().enumerate() {
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
                // x in stratum i, y in a stratum of its own.
                assert_eq!((x * n as f64) as usize, i);
                for &(_, y2) in &pts[i + 1..] {
                    assert!((y - y2).abs() > 0.1 / n as f64, "n = {n}: {y} vs {y2}");
                }
            }
        }
    }

    /// A constant environment of radiance 1: every method returns the directional albedo of
    /// the BSDF, which for a Lambertian surface is kd for any point set (weight = kd per
    /// sample), and for a mirror the Fresnel reflectance at level 0.
    #[test]
    fn constant_environment_gives_the_albedo() {
        let base = CubeMap::from_fn(16, |_| [1.0, 1.0, 1.0]).expect("map");
        let pyramid = CubePyramid::build(base, MipFilter::Gauss6).expect("pyramid");
        let irradiance = irradiance_map(&pyramid, 4).expect("irradiance");
        let env = FilteredEnvironment {
            pyramid: &pyramid,
            irradiance: &irradiance,
        };
        let frame = ShadingFrame::new(DVec3::new(0.2, 1.0, -0.3), DVec3::X);
        let wo = frame.to_world(DVec3::new(0.3, -0.2, 0.9).normalize());
        let lambert = resolve("lambert(kd=0.4)").expect("lambert");
        let mirror = resolve("conductor(material=none)").expect("mirror");
        for points in [
            PointSet::Fibonacci,
            PointSet::Hammersley,
            PointSet::Random(3),
        ] {
            for levels in [LevelRule::Footprint, LevelRule::Ck] {
                let (c, k) = shade_warp(&frame, wo, &*lambert, &env, None, 11, points, levels);
                assert_eq!(k, 11);
                for ch in 0..3 {
                    assert!((c[ch] - 0.4).abs() < 1e-5, "{points:?} {levels:?}: {c:?}");
                }
                // A Dirac-only BSDF is summed over its branches: one lookup for a mirror.
                let (m, k) = shade_warp(&frame, wo, &*mirror, &env, None, 5, points, levels);
                assert_eq!(k, 1);
                assert!((m[0] - 1.0).abs() < 1e-5, "{m:?}");
            }
        }
        assert_eq!(
            shade_regular_warp(&frame, wo, &*lambert, &env, None, 0),
            (Rgb::ZERO, 0)
        );
    }
}
