//! Hierarchical shading (004 §IV.4.2, Fig. IV.11 c–d, Fig. IV.12) and the brute-force renderer
//! it is compared with.
//!
//! Level k's grid is the pixels whose coordinates are multiples of 2^k. From the coarsest level
//! L down to 0, each pixel of level k's grid that no coarser grid holds is either
//! - **up-sampled** from its parents, the corners of the level-(k+1) cell around it, when the
//!   min-filtered level of the blocks under those parents is ≥ k + 1 (every pixel there may be
//!   sampled 2^(k+1) apart) and the parents carry weight: w_i = g_z(z − z_i) g_a(p − p_i) α_i
//!   with α_i the bilinear weights, g_z a Gaussian of the relative depth difference
//!   (σ = [`crate::gbuffer::SAME_SURFACE`]), parents on another material weighing 0, and g_a the
//!   anisotropic screen-space Gaussian exp(−vᵀMv), M = R_φᵀ diag(1, 1 / cos²θx) R_φ, v in units of
//!   the parents' spacing, φ the angle of the screen-projected normal, θx the angle between the
//!   normal and the view direction;
//! - or **shaded**, with the G-buffer's finest values at that pixel and the N_p of the
//!   max-filtered variance of its level-k block.
//!
//! Every pixel of the coarsest grid is shaded. The background is the environment, seen directly.

use crate::buffer::BandwidthBuffer;
use crate::gbuffer::{GBuffer, GPixel, Surfel, SAME_SURFACE};
use crate::shading::{pixel_seed, Lighting, ShadingContext};
use crate::{AdaptiveError, Result};
use lustre_brdf::rgb::Rgb;
use lustre_trace::image::Image;
use rayon::prelude::*;

/// Marks a pixel in [`AdaptiveFrame::shaded_level`] that was up-sampled (or is background).
pub const NOT_SHADED: u8 = crate::buffer::NO_LEVEL;

/// Parents whose summed weight falls below this share of their bilinear weights do not carry
/// the pixel: it is shaded.
pub const MIN_WEIGHT: f64 = 0.05;

/// What the adaptive renderer did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HierarchyStats {
    /// Surface pixels shaded.
    pub shaded: usize,
    /// Surface pixels up-sampled.
    pub upsampled: usize,
    /// Shading samples taken in all.
    pub samples: u64,
    /// Per level (index k): pixels shaded and up-sampled there.
    pub per_level: Vec<(usize, usize)>,
}

/// An adaptive frame.
#[derive(Clone, Debug)]
pub struct AdaptiveFrame {
    /// The image.
    pub image: Image,
    /// Per pixel: the level at which it was shaded, or [`NOT_SHADED`].
    pub shaded_level: Vec<u8>,
    /// Per pixel: the samples it was shaded with (0 when up-sampled).
    pub samples: Vec<u32>,
    /// Counts.
    pub stats: HierarchyStats,
}

/// Renders `g` hierarchically with the buffer's levels and sample counts.
pub fn render_adaptive(
    g: &GBuffer,
    ctx: &ShadingContext,
    buffer: &BandwidthBuffer,
    lighting: Lighting,
    seed: u64,
) -> Result<AdaptiveFrame> {
    check_sizes(g, buffer)?;
    let (w, h) = (g.width, g.height);
    let mut values: Vec<Option<Rgb>> = vec![None; w * h];
    let mut shaded_level = vec![NOT_SHADED; w * h];
    let mut samples = vec![0u32; w * h];
    let mut stats = HierarchyStats {
        per_level: vec![(0, 0); buffer.levels],
        ..Default::default()
    };
    let top = buffer.levels - 1;
    let lod = |k: usize| -> Option<f64> {
        (lighting == Lighting::Preconvolved)
            .then(|| ctx.preconvolved_lod(buffer.brdf_max[k]))
            .flatten()
    };
    let (right, up) = (g.camera.right, g.camera.up);
    for level in (0..=top).rev() {
        let step = 1usize << level;
        let parent = step << 1;
        let points: Vec<usize> = (0..h)
            .step_by(step)
            .flat_map(|y| (0..w).step_by(step).map(move |x| y * w + x))
            .filter(|&k| {
                let (x, y) = (k % w, k / w);
                level == top || x % parent != 0 || y % parent != 0
            })
            .filter(|&k| matches!(g.pixels[k], GPixel::Surface(_)))
            .collect();
        let done: Vec<(usize, Rgb, bool, u32)> = points
            .par_iter()
            .map(|&k| {
                let (x, y) = (k % w, k / w);
                let GPixel::Surface(s) = &g.pixels[k] else {
                    unreachable!("filtered to surface pixels")
                };
                if level < top {
                    if let Some(v) = upsample(g, buffer, &values, s, x, y, level, right, up) {
                        return (k, v, false, 0);
                    }
                }
                let n = buffer.samples(level, x, y);
                let v = ctx.shade(s, n, lod(k), pixel_seed(seed, k));
                (k, v, true, n as u32)
            })
            .collect();
        for (k, v, shaded, n) in done {
            values[k] = Some(v);
            if shaded {
                shaded_level[k] = level as u8;
                samples[k] = n;
                stats.shaded += 1;
                stats.samples += n as u64;
                stats.per_level[level].0 += 1;
            } else {
                stats.upsampled += 1;
                stats.per_level[level].1 += 1;
            }
        }
    }
    let data = g
        .pixels
        .iter()
        .zip(&values)
        .map(|(p, v)| match p {
            GPixel::Background(l) => l.to_f32(),
            GPixel::Surface(_) => v.unwrap_or(Rgb::ZERO).to_f32(),
        })
        .collect();
    Ok(AdaptiveFrame {
        image: Image::from_data(w, h, data)?,
        shaded_level,
        samples,
        stats,
    })
}

/// The up-sampled value of pixel (x, y) at `level`, or `None` when it must be shaded.
#[allow(clippy::too_many_arguments)]
fn upsample(
    g: &GBuffer,
    buffer: &BandwidthBuffer,
    values: &[Option<Rgb>],
    s: &Surfel,
    x: usize,
    y: usize,
    level: usize,
    right: glam::DVec3,
    up: glam::DVec3,
) -> Option<Rgb> {
    let w = g.width;
    let p = 2usize << level;
    let (x0, y0) = (x / p * p, y / p * p);
    let ax = (x - x0) as f64 / p as f64;
    let ay = (y - y0) as f64 / p as f64;
    // The screen-projected normal (image y down) and cos θx of the anisotropic Gaussian.
    let n = s.frame.n;
    let proj = glam::DVec2::new(n.dot(right), -n.dot(up));
    let along = proj.try_normalize();
    let cos_x = n.dot(s.wo).abs().max(0.05);
    let mut sum = Rgb::ZERO;
    let mut weight = 0.0;
    for (cx, cy, alpha) in [
        (x0, y0, (1.0 - ax) * (1.0 - ay)),
        (x0 + p, y0, ax * (1.0 - ay)),
        (x0, y0 + p, (1.0 - ax) * ay),
        (x0 + p, y0 + p, ax * ay),
    ] {
        if alpha == 0.0 {
            continue;
        }
        if cx >= w || cy >= g.height {
            return None;
        }
        if buffer.min_level(level + 1, cx, cy) < (level + 1) as u8 {
            return None;
        }
        let GPixel::Surface(q) = &g.pixels[cy * w + cx] else {
            continue;
        };
        let Some(c) = values[cy * w + cx] else {
            continue;
        };
        if q.material != s.material {
            continue;
        }
        let dz = (s.depth - q.depth) / (SAME_SURFACE * s.depth);
        let v = glam::DVec2::new(
            (x as f64 - cx as f64) / p as f64,
            (y as f64 - cy as f64) / p as f64,
        );
        let quad = match along {
            Some(a) => {
                let par = v.dot(a);
                let perp = v.perp_dot(a);
                perp * perp + par * par / (cos_x * cos_x)
            }
            None => v.length_squared(),
        };
        let wgt = (-dz * dz).exp() * (-quad).exp() * alpha;
        sum += c * wgt;
        weight += wgt;
    }
    (weight >= MIN_WEIGHT).then(|| sum * (1.0 / weight))
}

/// Counts of a brute-force frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BruteStats {
    /// Surface pixels shaded (all of them).
    pub shaded: usize,
    /// Shading samples taken.
    pub samples: u64,
}

/// Brute force: every surface pixel shaded with `n` samples, the environment at full
/// resolution (the same estimator as [`render_adaptive`]'s shading).
pub fn render_brute(
    g: &GBuffer,
    ctx: &ShadingContext,
    n: usize,
    seed: u64,
) -> Result<(Image, BruteStats)> {
    if n == 0 {
        return Err(AdaptiveError::Parameter(
            "brute-force shading with 0 samples per pixel".into(),
        ));
    }
    let data: Vec<[f32; 3]> = g
        .pixels
        .par_iter()
        .enumerate()
        .map(|(k, p)| match p {
            GPixel::Background(l) => l.to_f32(),
            GPixel::Surface(s) => ctx.shade(s, n, None, pixel_seed(seed, k)).to_f32(),
        })
        .collect();
    let shaded = g.surface_pixels();
    Ok((
        Image::from_data(g.width, g.height, data)?,
        BruteStats {
            shaded,
            samples: (shaded * n) as u64,
        },
    ))
}

fn check_sizes(g: &GBuffer, b: &BandwidthBuffer) -> Result<()> {
    if g.width != b.width || g.height != b.height {
        return Err(AdaptiveError::Parameter(format!(
            "G-buffer of {} × {} with a bandwidth buffer of {} × {}",
            g.width, g.height, b.width, b.height
        )));
    }
    Ok(())
}

/// The mean of each k × k block of `img` (a supersampled frame resolved to its pixels; 004
/// §IV.5.3's adaptive multi-sample anti-aliasing shades the sub-pixels hierarchically, then
/// resolves them). Errors when k is 0 or does not divide the size.
pub fn box_downsample(img: &Image, k: usize) -> Result<Image> {
    if k == 0 || !img.width.is_multiple_of(k) || !img.height.is_multiple_of(k) {
        return Err(AdaptiveError::Parameter(format!(
            "resolving a {} × {} frame by {k} × {k} blocks",
            img.width, img.height
        )));
    }
    let (w, h) = (img.width / k, img.height / k);
    let scale = 1.0 / (k * k) as f64;
    let data = (0..w * h)
        .map(|p| {
            let (x, y) = (p % w, p / w);
            let mut s = [0.0f64; 3];
            for dy in 0..k {
                for dx in 0..k {
                    let v = img.get(x * k + dx, y * k + dy);
                    for c in 0..3 {
                        s[c] += f64::from(v[c]);
                    }
                }
            }
            s.map(|c| (c * scale) as f32)
        })
        .collect();
    Ok(Image::from_data(w, h, data)?)
}
