//! The bandwidth buffer of 004 §IV.4.1 (Fig. IV.11 b).
//!
//! Per surface pixel, from n_b directions ([`lustre_freq::pixel::predict`]):
//! - the image-space bandwidth b_p (Eq. IV.6–IV.7, cycles per pixel);
//! - the level ℓ_p = min(⌊log2(1 / (r b_p))⌋, L) at which it must be shaded, L = ⌊log2 min(W,
//!   H)⌋: with r = 2 (Nyquist's rate, the default) samples 2^ℓ pixels apart still resolve b_p;
//!   r = 1 is Eq. IV.11 as printed;
//! - the variance bound's sum S_p (Eq. IV.9, or Eq. IV.10 pre-convolved), which sets the
//!   sample count N_p = ⌈4π² S_p / V⌉ clamped to 1..=max; [`SampleRule::Relative`] divides
//!   it by the pixel's squared radiance first;
//! - the BRDF's largest bandwidth over the directions and the mirror direction (the
//!   pre-convolved lookup's level).
//!
//! Area lights (`light`) add n_b stratified points each: their paths join Eq. IV.6 with the
//! environment's (weighed by their shares of L_p), and their terms the variance sums.
//!
//! The paths' weights χ = L ρ need the BRDF's luminance ρ at each direction: on the CPU it is
//! read from the material's tabulated CDFs by default ([`BrdfWeights::Tabulated`]: the cell's
//! mean of f, a lookup, where a neural BRDF's `eval` is a network and took most of the pass),
//! or evaluated ([`BrdfWeights::Evaluated`], what the GPU pass does: `eval` is cheap there).
//!
//! V is chosen so that the mean N_p over the surface pixels is the requested mean (bisection):
//! 004 keeps the variance constant across the image; the mean sets its value.
//!
//! The level is min-filtered and the variance max-filtered over 2^k × 2^k blocks (the pyramids),
//! so a block's entry tells conservatively whether any pixel under it needs a finer level or
//! more samples.

use crate::gbuffer::Surfel;
use crate::gbuffer::{GBuffer, GPixel};
use crate::shading::{Lighting, ShadingContext};
use crate::{AdaptiveError, Result};
use glam::DVec3;
use lustre_brdf::sampling::hammersley;
use lustre_freq::brdf::BrdfBandwidth;
use lustre_freq::pixel::{
    incident_directions, predict_with, EnvironmentBandwidth, Incident, PixelPrediction,
    ShadingPoint,
};
use lustre_freq::transport::samples_for;
use lustre_freq::transport::{
    one_bounce, pixel_bandwidth, variance_sum, Bandwidth, Surface, VarianceTerm,
};
use rayon::prelude::*;
use std::f64::consts::PI;

/// The level stored for pixels that need no shading (the background).
pub const NO_LEVEL: u8 = u8::MAX;

/// The default n_b: 8 incident directions per pixel. 004 uses 16; on its five measured
/// materials' spheres and the line-up (256², royal_esplanade_1k, BENCHMARKS.md "Adaptive shading, fifth
/// part") n_b = 8 shaded 17–26 % fewer sphere pixels than 16 (1–11 % on the line-up) at the
/// same rate and N_p, within −0.06 … +2.25 dB of its PSNR (the prediction's max over the
/// directions grows with n_b, Fig. IV.17), and its pass took half the time; n_b = 4 lost up to
/// 2.8 dB.
pub const DEFAULT_N_B: usize = 8;

/// Where the bandwidth pass reads the BRDF's luminance ρ (the paths' weights χ = L ρ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrdfWeights {
    /// From the material's tabulated CDFs (`TabulatedSampler::brdf_luminance`: the cell's mean
    /// of f) when it has them and no texture varies it; `Bsdf::eval` otherwise.
    Tabulated,
    /// `Bsdf::eval` (the GPU pass's choice, `lustre_gpu::passes::bandwidth`).
    Evaluated,
}

/// How N_p is set across the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleRule {
    /// The same N_p everywhere (the mean): spatial adaptivity only.
    Constant,
    /// N_p from the level a pixel is shaded at: N_0 (the mean) at level 0, N_0 · ⅔ · 2^k at
    /// level k ≥ 1 ([`coverage_samples`]). A pixel shaded at level k covers about 4^k image
    /// pixels through the up-sampling, each with its noise times the bilinear weights (whose
    /// squares average ⅔ · ⅔): its noise reaches the image with a weight a_k ≈ 4^k · 4/9. Under
    /// a fixed total Σ N_p, Σ a_k σ² / N_p is least at N_p ∝ √a_k σ; with σ alike this is
    /// N_p ∝ ⅔ · 2^k.
    Coverage,
    /// The bound itself (004: N_p ∝ S_p): pixels under bright light get the samples.
    Absolute,
    /// The bound relative to the pixel's squared radiance as its n_b directions estimate it
    /// (N_p ∝ S_p / L̂_p²): an equal relative error everywhere, which is what an image seen
    /// through a tone curve shows.
    Relative,
    /// N_p ∝ √S_p / L̂_p: the allocation that minimizes the summed squared relative error for a
    /// given total (Σ σ_p² / N_p under Σ N_p fixed has N_p ∝ σ_p), rather than equalizing it.
    RelativeMse,
}

/// How the buffer is filled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BufferOptions {
    /// Incident directions per pixel ([`DEFAULT_N_B`]; 004: 16).
    pub n_b: usize,
    /// The mean N_p over the surface pixels.
    pub mean_samples: f64,
    /// The largest N_p.
    pub max_samples: usize,
    /// Which variance bound (Eq. IV.9 direct, Eq. IV.10 pre-convolved).
    pub lighting: Lighting,
    /// What the target holds constant.
    pub scale: SampleRule,
    /// Samples per cycle of b_p: ℓ_p = ⌊log2(1 / (rate · b_p))⌋. 2 is Nyquist's rate; 1 is
    /// Eq. IV.11 as printed (⌊log2(1 / b_p)⌋, which relies on b_p's own over-estimate).
    pub rate: f64,
    /// Where the CPU's pass reads ρ.
    pub weights: BrdfWeights,
}

impl Default for BufferOptions {
    fn default() -> Self {
        Self {
            n_b: DEFAULT_N_B,
            mean_samples: 16.0,
            max_samples: 1024,
            lighting: Lighting::Direct,
            scale: SampleRule::Relative,
            rate: 2.0,
            weights: BrdfWeights::Tabulated,
        }
    }
}

/// The bandwidth buffer with its pyramids.
#[derive(Clone, Debug)]
pub struct BandwidthBuffer {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// b_p (cycles per pixel; 0 on the background).
    pub bandwidth: Vec<f64>,
    /// ℓ_p ([`NO_LEVEL`] on the background).
    pub level: Vec<u8>,
    /// S_p.
    pub variance: Vec<f64>,
    /// The BRDF's largest bandwidth (cycles per radian).
    pub brdf_max: Vec<f64>,
    /// The variance target V.
    pub target: f64,
    /// The largest N_p.
    pub max_samples: usize,
    /// N_p everywhere under [`SampleRule::Constant`]; N_0 under [`SampleRule::Coverage`].
    pub constant: Option<usize>,
    /// Whether N_p grows with the level ([`SampleRule::Coverage`]).
    pub coverage: bool,
    /// Levels 0..=L.
    pub levels: usize,
    /// Per level k, the min of ℓ over each 2^k block (row-major blocks).
    min_level: Vec<Vec<u8>>,
    /// Per level k, the max of S over each 2^k block.
    max_variance: Vec<Vec<f64>>,
}

/// One surface pixel's prediction: the bandwidth pass's output (the CPU's
/// [`predict_pixels`], or the GPU's twin).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelEstimate {
    /// ν, the variance sums and L̂ (lustre-freq's prediction).
    pub prediction: PixelPrediction,
    /// The BRDF's largest bandwidth over the n_b directions and the mirror direction (cycles
    /// per radian).
    pub brdf_max: f64,
}

/// The bandwidth pass on the CPU: per pixel of `g`, its prediction from `n_b` directions
/// (`None` on the background), ρ read as `weights` says. The scene's directions are turned into
/// the map's frame first.
pub fn predict_pixels(
    g: &GBuffer,
    ctx: &ShadingContext,
    env: &EnvironmentBandwidth,
    n_b: usize,
    weights: BrdfWeights,
) -> Result<Vec<Option<PixelEstimate>>> {
    let to_local = ctx.env.to_world().transpose();
    let dirs = incident_directions(n_b);
    g.pixels
        .par_iter()
        .map(|p| -> Result<Option<PixelEstimate>> {
            let GPixel::Surface(s) = p else {
                return Ok(None);
            };
            let f = &s.frame;
            let point = ShadingPoint {
                frame: (to_local * f.t, to_local * f.b, to_local * f.n),
                wo: to_local * s.wo,
                eye_distance: s.depth,
                curvature: s.curvature,
                texture: ctx.texture_bandwidth(s),
            };
            let tables = &ctx.materials[s.material];
            let table = match (weights, &tables.sampler) {
                (BrdfWeights::Tabulated, Some(t)) if tables.textures.is_empty() => Some(t),
                _ => None,
            };
            // The tables seen from ωo, found once per pixel (ωo as predict_with finds it).
            let (t, b, n) = point.frame;
            let wo_l = DVec3::new(point.wo.dot(t), point.wo.dot(b), point.wo.dot(n));
            let view = table.map(|t| t.luminance_view(wo_l));
            let mut pred = None;
            ctx.scene.materials[s.material].with_bsdf(s.uv, &mut |b| {
                let rho = |wi: &Incident, wo: DVec3| match &view {
                    Some(v) => v.at_polar(wi.dir.z, wi.theta, wi.phi),
                    None => b.eval(wi.dir, wo).luminance(),
                };
                pred = Some(
                    predict_with(&point, env, &rho, &tables.bandwidth, &dirs).map(
                        |(p, dirs_max)| {
                            let lit = light_paths(ctx, s, &rho, &tables.bandwidth, n_b);
                            let (p, light_max) = merge(p, &lit);
                            (p, dirs_max.max(light_max))
                        },
                    ),
                );
            });
            let (prediction, dirs_max) = pred.ok_or_else(|| {
                AdaptiveError::Parameter(format!("material {} gave no BSDF", s.material))
            })??;
            let wo = DVec3::new(s.wo.dot(f.t), s.wo.dot(f.b), s.wo.dot(f.n));
            let mirror = DVec3::new(-wo.x, -wo.y, wo.z);
            let brdf_max = tables.bandwidth.at(mirror, wo).max(dirs_max);
            Ok(Some(PixelEstimate {
                prediction,
                brdf_max,
            }))
        })
        .collect()
}

/// One path from an area light through the pixel: its share of L_p, its 2D bandwidth at the
/// eye, and its variance term.
struct LightPath {
    contribution: f64,
    bandwidth: Bandwidth,
    term: VarianceTerm,
}

/// The paths from every area light through `s` (n_b stratified points per light, their
/// bandwidth through Fig. IV.9's operators from the light's surface; `light::AreaLight`).
fn light_paths(
    ctx: &ShadingContext,
    s: &Surfel,
    rho: &dyn Fn(&Incident, DVec3) -> f64,
    brdf: &BrdfBandwidth,
    n_b: usize,
) -> Vec<LightPath> {
    let f = &s.frame;
    let local = |d: DVec3| DVec3::new(d.dot(f.t), d.dot(f.b), d.dot(f.n));
    let wo = local(s.wo);
    let mut out = vec![];
    if wo.z <= 0.0 || !(s.curvature.is_finite() && s.depth.is_finite()) {
        return out;
    }
    for light in &ctx.lights {
        for k in 0..n_b {
            let (u, v) = hammersley(k as u32, n_b as u32);
            let v = (v + 0.5 / n_b as f64).fract();
            let (w, dist, cos_l) = light.towards(s.position, u, v);
            let wi = local(w);
            if cos_l <= 0.0 || wi.z <= 0.0 {
                continue;
            }
            let g = cos_l * light.area() / (dist * dist * n_b as f64);
            let chi = light.emitted(u, v).luminance() * rho(&Incident::new(wi), wo);
            let nu_s = light.bandwidth_at(u, v) / cos_l.max(1e-6);
            let nu_brdf = brdf.at(wi, wo);
            let surface = Surface {
                cos_i: wi.z,
                cos_x: wo.z.max(1e-6),
                curvature: s.curvature,
                texture: ctx.texture_bandwidth(s),
                brdf: nu_brdf,
            };
            let contribution = chi * wi.z * g;
            out.push(LightPath {
                contribution,
                bandwidth: one_bounce(Bandwidth::new(nu_s, 0.0), dist, &surface, s.depth),
                term: VarianceTerm {
                    light: dist * nu_s,
                    brdf: nu_brdf,
                    // On the environment's scale, where L̂ = π / n_b Σ χ_i.
                    chi: contribution * n_b as f64 / PI,
                },
            });
        }
    }
    out
}

/// The environment's prediction merged with the area lights' paths: Eq. IV.6 over all paths,
/// the environment's weighing as much as its L̂ and each light path as much as its share of
/// L_p; the variance sums and L̂ add up. Also the BRDF's largest bandwidth over the lights'
/// directions (0 without lights).
fn merge(env: PixelPrediction, lights: &[LightPath]) -> (PixelPrediction, f64) {
    if lights.is_empty() {
        return (env, 0.0);
    }
    let mut paths = vec![(env.radiance, env.bandwidth)];
    paths.extend(lights.iter().map(|p| (p.contribution, p.bandwidth)));
    let terms: Vec<VarianceTerm> = lights.iter().map(|p| p.term).collect();
    let light_sum: f64 = lights.iter().map(|p| p.contribution.max(0.0)).sum();
    let brdf_max = lights.iter().map(|p| p.term.brdf).fold(0.0, f64::max);
    (
        PixelPrediction {
            bandwidth: pixel_bandwidth(&paths),
            variance: env.variance + variance_sum(&terms, false),
            variance_preconvolved: env.variance_preconvolved + variance_sum(&terms, true),
            radiance: env.radiance + light_sum,
            weight: env.radiance + light_sum,
        },
        brdf_max,
    )
}

impl BandwidthBuffer {
    /// Fills the buffer of `g` on the CPU (`env`: the bandwidth of the scene's environment
    /// map): [`predict_pixels`], then [`BandwidthBuffer::assemble`].
    pub fn build(
        g: &GBuffer,
        ctx: &ShadingContext,
        env: &EnvironmentBandwidth,
        options: BufferOptions,
    ) -> Result<Self> {
        check(&options)?;
        let estimates = predict_pixels(g, ctx, env, options.n_b, options.weights)?;
        Self::assemble(g, &estimates, options)
    }

    /// The buffer from the pixels' predictions (one per pixel of `g`, `None` on the
    /// background): levels (Eq. IV.7, IV.11), sample counts, pyramids.
    pub fn assemble(
        g: &GBuffer,
        estimates: &[Option<PixelEstimate>],
        options: BufferOptions,
    ) -> Result<Self> {
        check(&options)?;
        let (w, h) = (g.width, g.height);
        if estimates.len() != w * h {
            return Err(AdaptiveError::Parameter(format!(
                "bandwidth buffer of {w} × {h} pixels from {} predictions",
                estimates.len()
            )));
        }
        let levels = (w.min(h).ilog2() as usize) + 1;
        let top = (levels - 1) as f64;
        let rad_per_pixel = g.radians_per_pixel();
        let clean = |v: f64| if v.is_finite() { v.max(0.0) } else { 0.0 };
        let per_pixel: Vec<(f64, u8, f64, f64)> = estimates
            .iter()
            .map(|e| {
                let Some(e) = e else {
                    return (0.0, NO_LEVEL, 0.0, 0.0);
                };
                let pred = &e.prediction;
                let b_p = pred.bandwidth.angular * rad_per_pixel;
                let level = if b_p > 0.0 && b_p.is_finite() {
                    (1.0 / (options.rate * b_p)).log2().floor().clamp(0.0, top)
                } else {
                    top
                } as u8;
                let bound = match options.lighting {
                    Lighting::Direct => pred.variance,
                    Lighting::Preconvolved => pred.variance_preconvolved,
                };
                let variance = match options.scale {
                    SampleRule::Absolute | SampleRule::Constant | SampleRule::Coverage => bound,
                    SampleRule::Relative if pred.radiance > 0.0 => {
                        bound / (pred.radiance * pred.radiance)
                    }
                    SampleRule::RelativeMse if pred.radiance > 0.0 => bound.sqrt() / pred.radiance,
                    SampleRule::Relative | SampleRule::RelativeMse => 0.0,
                };
                (clean(b_p), level, clean(variance), clean(e.brdf_max))
            })
            .collect();
        let bandwidth: Vec<f64> = per_pixel.iter().map(|v| v.0).collect();
        let level: Vec<u8> = per_pixel.iter().map(|v| v.1).collect();
        let variance: Vec<f64> = per_pixel.iter().map(|v| v.2).collect();
        let brdf_max: Vec<f64> = per_pixel.iter().map(|v| v.3).collect();
        // A constant N_p (or N_0) needs no target (1 stands in).
        let constant = matches!(options.scale, SampleRule::Constant | SampleRule::Coverage)
            .then(|| (options.mean_samples.round() as usize).clamp(1, options.max_samples));
        let coverage = options.scale == SampleRule::Coverage;
        let target = match constant {
            Some(_) => 1.0,
            None => {
                let surface: Vec<f64> = level
                    .iter()
                    .zip(&variance)
                    .filter(|(l, _)| **l != NO_LEVEL)
                    .map(|(_, v)| *v)
                    .collect();
                target_for_mean(&surface, options.mean_samples, options.max_samples)?
            }
        };
        let mut min_level = vec![level.clone()];
        let mut max_variance = vec![variance.clone()];
        for k in 1..levels {
            let (pw, ph) = (w.div_ceil(1 << (k - 1)), h.div_ceil(1 << (k - 1)));
            let (bw, bh) = (w.div_ceil(1 << k), h.div_ceil(1 << k));
            let prev_l = &min_level[k - 1];
            let prev_v = &max_variance[k - 1];
            let mut l = vec![NO_LEVEL; bw * bh];
            let mut v = vec![0.0f64; bw * bh];
            for by in 0..bh {
                for bx in 0..bw {
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (x, y) = (2 * bx + dx, 2 * by + dy);
                        if x < pw && y < ph {
                            l[by * bw + bx] = l[by * bw + bx].min(prev_l[y * pw + x]);
                            v[by * bw + bx] = v[by * bw + bx].max(prev_v[y * pw + x]);
                        }
                    }
                }
            }
            min_level.push(l);
            max_variance.push(v);
        }
        Ok(Self {
            width: w,
            height: h,
            bandwidth,
            level,
            variance,
            brdf_max,
            target,
            max_samples: options.max_samples,
            constant,
            coverage,
            levels,
            min_level,
            max_variance,
        })
    }

    /// The min of ℓ over the level-`k` block holding pixel (x, y).
    pub fn min_level(&self, k: usize, x: usize, y: usize) -> u8 {
        let bw = self.width.div_ceil(1 << k);
        self.min_level[k][(y >> k) * bw + (x >> k)]
    }

    /// N_p for the level-`k` block holding pixel (x, y) (its max-filtered variance).
    pub fn samples(&self, k: usize, x: usize, y: usize) -> usize {
        if let Some(n) = self.constant {
            return if self.coverage {
                coverage_samples(n, k, self.max_samples)
            } else {
                n
            };
        }
        let bw = self.width.div_ceil(1 << k);
        let v = self.max_variance[k][(y >> k) * bw + (x >> k)];
        samples_for(v, self.target, self.max_samples).unwrap_or(self.max_samples)
    }
}

/// N_p at level `k` under [`SampleRule::Coverage`] from N_0 = `n0`: N_0 at level 0,
/// round(N_0 · ⅔ · 2^k) at k ≥ 1, clamped to 1..=`max` (a `max` of 0 counts as 1).
pub fn coverage_samples(n0: usize, k: usize, max: usize) -> usize {
    let max = max.max(1);
    if k == 0 {
        return n0.clamp(1, max);
    }
    // round(n0 · 2^(k+1) / 3) in integers (no tie: 3 divides neither n0 · 2^(k+1) ± ½).
    let m = (n0 as u128) << (k + 1).min(64);
    ((m + 1) / 3).clamp(1, max as u128) as usize
}

/// Levels as a map to draw: ℓ + 1, and 0 for [`NO_LEVEL`] (the background; in a frame's
/// `shaded_level`, also the up-sampled pixels, `hierarchy::NOT_SHADED` being the same value).
pub fn level_map(levels: &[u8]) -> Vec<f64> {
    levels
        .iter()
        .map(|l| {
            if *l == NO_LEVEL {
                0.0
            } else {
                f64::from(*l) + 1.0
            }
        })
        .collect()
}

fn check(options: &BufferOptions) -> Result<()> {
    if options.n_b == 0
        || options.max_samples == 0
        || !(options.mean_samples >= 1.0 && options.mean_samples.is_finite())
        || !(options.rate > 0.0 && options.rate <= 64.0)
    {
        return Err(AdaptiveError::Parameter(format!(
            "bandwidth buffer with n_b = {}, mean samples {}, max samples {} and rate {} (n_b ≥ 1, 1 ≤ mean, max ≥ 1, 0 < rate ≤ 64)",
            options.n_b, options.mean_samples, options.max_samples, options.rate
        )));
    }
    Ok(())
}

/// The variance target V whose N_p (clamped to 1..=max) average `mean` over `sums`: bisection
/// on log V. With every sum 0, any V gives N_p = 1 (1 is returned).
pub fn target_for_mean(sums: &[f64], mean: f64, max: usize) -> Result<f64> {
    let hi_sum = sums.iter().cloned().fold(0.0f64, f64::max);
    let lo_sum = sums
        .iter()
        .cloned()
        .filter(|v| *v > 0.0)
        .fold(f64::INFINITY, f64::min);
    if sums.is_empty() || hi_sum <= 0.0 {
        return Ok(1.0);
    }
    let mean_at = |t: f64| -> Result<f64> {
        let mut s = 0usize;
        for v in sums {
            s += samples_for(*v, t, max)?;
        }
        Ok(s as f64 / sums.len() as f64)
    };
    // At V ≥ 4π² max S every N_p is 1; at V ≤ 4π² min S / max every positive one is max.
    let mut hi = (4.0 * PI * PI * hi_sum).ln() + 1.0;
    let mut lo = (4.0 * PI * PI * lo_sum / max as f64).ln() - 1.0;
    if mean_at(lo.exp())? <= mean {
        return Ok(lo.exp());
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if mean_at(mid.exp())? > mean {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(hi.exp())
}
