//! Edge-aware denoising of a light-map page: the à-trous wavelet filter (Dammertz et al. 2010,
//! "Edge-avoiding À-Trous wavelet transform for fast global illumination filtering") with the
//! edge-stopping functions of SVGF (Schied et al. 2017): iteration i applies the 5×5 B3-spline
//! kernel h = (1, 4, 6, 4, 1)/16 ⊗ itself with taps 2^i texels apart, each tap q of texel p
//! weighted by
//!
//! w = h · exp(−|p_q − p_p|² / 2(σ_p·2^i·s_p)²) · max(0, n_p·n_q)^σ_n
//!       · exp(−|a_q − a_p|² / 2σ_a²) · exp(−|ℓ_q − ℓ_p| / (σ_ℓ √Var ℓ_p + ε)),
//!
//! (positions p, unit normals n, albedo a, luminance ℓ of the irradiance, s_p the texel's world
//! size); the variance is filtered with w² (SVGF Eq. 4 of §4.3). Taps off the page, uncovered
//! or of another chart get weight 0, so the filter never mixes charts whatever its footprint.
//! Last, each chart is scaled to the raw total irradiance of its texels, per channel (the
//! luminance edge stop darkens noisy pages: it cuts bright outliers off from their neighbours).
//! Irradiance does not depend on the receiver's albedo, so its weight only keeps bounce-light
//! differences between differently coloured surfaces of one chart apart; σ_a is loose by default.

use super::fill::PageBuffer;
use super::trace::{TexelRecord, NO_CHART};
use crate::{Result, TraceError};
use rayon::prelude::*;

/// The denoiser [`super::assemble`] runs. Open Image Denoise cannot be installed here; it
/// would be another variant, behind a cargo feature.
#[derive(Clone, Debug, PartialEq)]
pub enum Denoiser {
    /// No denoising (the raw Monte Carlo means).
    None,
    /// The edge-aware à-trous filter.
    ATrous(ATrousOptions),
}

/// Parameters of the à-trous filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ATrousOptions {
    /// Iterations (footprint 1 + 4·(2^iterations − 1) texels).
    pub iterations: u32,
    /// σ_p, in texels (scaled by the step).
    pub sigma_position: f64,
    /// σ_n, the normal exponent.
    pub sigma_normal: f64,
    /// σ_a, albedo difference.
    pub sigma_albedo: f64,
    /// σ_ℓ, in standard deviations of the luminance.
    pub sigma_luminance: f64,
}

impl Default for ATrousOptions {
    fn default() -> Self {
        ATrousOptions {
            iterations: 4,
            sigma_position: 2.0,
            sigma_normal: 64.0,
            sigma_albedo: 0.25,
            sigma_luminance: 4.0,
        }
    }
}

impl ATrousOptions {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        let ok = self.iterations <= 10
            && [
                self.sigma_position,
                self.sigma_normal,
                self.sigma_albedo,
                self.sigma_luminance,
            ]
            .iter()
            .all(|s| s.is_finite() && *s > 0.0);
        if ok {
            Ok(())
        } else {
            Err(TraceError::Parameter(format!(
                "à-trous parameters {self:?}: iterations ≤ 10, sigmas finite and > 0"
            )))
        }
    }
}

fn lum(e: [f32; 3]) -> f64 {
    0.2126 * f64::from(e[0]) + 0.7152 * f64::from(e[1]) + 0.0722 * f64::from(e[2])
}

/// Denoises the known texels of `page` (whose guides are `recs`, variance per texel `var`, the
/// luminance variance of the mean) in place.
pub fn atrous(page: &mut PageBuffer, recs: &[TexelRecord], var: &[f64], o: &ATrousOptions) {
    let (w, h) = (page.width as i64, page.height as i64);
    let n = (w * h) as usize;
    let pos = |i: usize| glam::Vec3::from_array(recs[i].position);
    let active = |i: usize| page.known[i] && recs[i].chart != NO_CHART;
    // World size of a texel: distance to the nearest active right/down neighbour of its chart.
    let size: Vec<f64> = (0..n)
        .map(|i| {
            let (x, y) = ((i as i64) % w, (i as i64) / w);
            let mut s = f64::INFINITY;
            for (dx, dy) in [(1, 0), (0, 1), (-1, 0), (0, -1)] {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w || ny >= h {
                    continue;
                }
                let j = (ny * w + nx) as usize;
                if active(i) && active(j) && recs[j].chart == recs[i].chart {
                    let d = f64::from(pos(i).distance(pos(j)));
                    if d > 0.0 {
                        s = s.min(d);
                    }
                }
            }
            if s.is_finite() {
                s
            } else {
                0.0
            }
        })
        .collect();
    let mean_l = {
        let (s, c) = (0..n)
            .filter(|&i| active(i))
            .fold((0.0, 0usize), |(s, c), i| (s + lum(page.e[i]), c + 1));
        if c > 0 {
            s / c as f64
        } else {
            0.0
        }
    };
    let eps = 1e-3 * mean_l + 1e-12;
    let kernel = [1.0 / 16.0, 1.0 / 4.0, 3.0 / 8.0, 1.0 / 4.0, 1.0 / 16.0];
    let mut e = page.e.clone();
    let mut v = var.to_vec();
    for it in 0..o.iterations {
        let step = 1i64 << it;
        let next: Vec<([f32; 3], f64)> = (0..n)
            .into_par_iter()
            .map(|i| {
                if !active(i) {
                    return (e[i], v[i]);
                }
                let (x, y) = ((i as i64) % w, (i as i64) / w);
                let (rp, np) = (&recs[i], glam::Vec3::from_array(recs[i].normal));
                let lp = lum(e[i]);
                let sp = o.sigma_position * step as f64 * size[i].max(1e-12);
                let sl = o.sigma_luminance * v[i].max(0.0).sqrt() + eps;
                let (mut sum, mut wsum, mut vsum) = ([0.0f64; 3], 0.0, 0.0);
                for (ky, hy) in kernel.iter().enumerate() {
                    for (kx, hx) in kernel.iter().enumerate() {
                        let (nx, ny) = (x + (kx as i64 - 2) * step, y + (ky as i64 - 2) * step);
                        if nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let j = (ny * w + nx) as usize;
                        if !active(j) || recs[j].chart != rp.chart {
                            continue;
                        }
                        let rq = &recs[j];
                        let dp = f64::from(pos(i).distance_squared(pos(j)));
                        let wn = f64::from(np.dot(glam::Vec3::from_array(rq.normal)).max(0.0))
                            .powf(o.sigma_normal);
                        let da: f64 = (0..3)
                            .map(|c| (f64::from(rq.albedo[c]) - f64::from(rp.albedo[c])).powi(2))
                            .sum();
                        let wgt = hx
                            * hy
                            * (-dp / (2.0 * sp * sp)).exp()
                            * wn
                            * (-da / (2.0 * o.sigma_albedo * o.sigma_albedo)).exp()
                            * (-(lum(e[j]) - lp).abs() / sl).exp();
                        if wgt.is_nan() || wgt <= 0.0 {
                            continue;
                        }
                        for c in 0..3 {
                            sum[c] += wgt * f64::from(e[j][c]);
                        }
                        wsum += wgt;
                        vsum += wgt * wgt * v[j];
                    }
                }
                if wsum > 0.0 {
                    (sum.map(|s| (s / wsum) as f32), vsum / (wsum * wsum))
                } else {
                    (e[i], v[i])
                }
            })
            .collect();
        for (i, (ei, vi)) in next.into_iter().enumerate() {
            e[i] = ei;
            v[i] = vi;
        }
    }
    // Each chart keeps the raw page's total irradiance (per channel): the luminance edge stop
    // cuts bright outliers off from their neighbours and so darkens a noisy page (−3.8 % in
    // the mean of the Modern Hall at 16 spp without this). A scale keeps zeros at zero.
    let charts = recs
        .iter()
        .filter(|r| r.chart != NO_CHART)
        .map(|r| r.chart as usize + 1)
        .max()
        .unwrap_or(0);
    let mut raw_sum = vec![[0.0f64; 3]; charts];
    let mut den_sum = vec![[0.0f64; 3]; charts];
    for i in (0..n).filter(|&i| active(i)) {
        let c = recs[i].chart as usize;
        for k in 0..3 {
            raw_sum[c][k] += f64::from(page.e[i][k]);
            den_sum[c][k] += f64::from(e[i][k]);
        }
    }
    for i in (0..n).filter(|&i| active(i)) {
        let c = recs[i].chart as usize;
        for k in 0..3 {
            if den_sum[c][k] > 0.0 {
                e[i][k] = (f64::from(e[i][k]) * raw_sum[c][k] / den_sum[c][k]) as f32;
            }
        }
    }
    page.e = e;
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_brdf::sampling::SplitMix64;

    /// A flat 32×16 page: chart 0 on the left half, chart 1 on the right, positions on the
    /// plane y = 0 with texel size 0.1, normal +y, grey albedo.
    fn page(values: impl Fn(u32, u32) -> f32) -> (PageBuffer, Vec<TexelRecord>) {
        let (w, h) = (32u32, 16u32);
        let mut recs = vec![];
        let mut e = vec![];
        for y in 0..h {
            for x in 0..w {
                let v = values(x, y);
                recs.push(TexelRecord {
                    e: [v; 3],
                    var: [0.01; 3],
                    valid: 16,
                    chart: u32::from(x >= 16),
                    position: [0.1 * x as f32, 0.0, 0.1 * y as f32],
                    normal: [0.0, 1.0, 0.0],
                    albedo: [0.5; 3],
                });
                e.push([v; 3]);
            }
        }
        let n = recs.len();
        (
            PageBuffer {
                width: w,
                height: h,
                e,
                chart: recs.iter().map(|r| r.chart).collect(),
                known: vec![true; n],
            },
            recs,
        )
    }

    #[test]
    fn charts_are_never_mixed() {
        let (mut p, recs) = page(|x, _| if x < 16 { 1.0 } else { 1.2 });
        let var = vec![0.01; recs.len()];
        atrous(&mut p, &recs, &var, &ATrousOptions::default());
        for (k, e) in p.e.iter().enumerate() {
            let want = if k % 32 < 16 { 1.0 } else { 1.2 };
            assert_eq!(*e, [want; 3], "texel {k}");
        }
    }

    #[test]
    fn noise_is_reduced_without_bias() {
        let mut rng = SplitMix64::new(5);
        let noise: Vec<f32> = (0..32 * 16)
            .map(|_| (0.1 * 3f64.sqrt() * (2.0 * rng.next_f64() - 1.0)) as f32)
            .collect();
        let (mut p, recs) = page(|x, y| 1.0 + noise[(y * 32 + x) as usize]);
        let var = vec![0.01; recs.len()];
        let rms = |e: &[[f32; 3]]| {
            (e.iter()
                .map(|v| (f64::from(v[0]) - 1.0).powi(2))
                .sum::<f64>()
                / e.len() as f64)
                .sqrt()
        };
        let mean = |e: &[[f32; 3]]| e.iter().map(|v| f64::from(v[0])).sum::<f64>() / 512.0;
        let (before, m0) = (rms(&p.e), mean(&p.e));
        atrous(&mut p, &recs, &var, &ATrousOptions::default());
        let (after, m1) = (rms(&p.e), mean(&p.e));
        assert!(after < before / 4.0, "RMS error {before} → {after}");
        assert!((m1 - m0).abs() < 0.01, "mean {m0} → {m1}");
    }

    #[test]
    fn fireflies_are_spread_and_every_chart_keeps_its_energy() {
        // 1 texel in 20 holds a path 20× brighter (its variance says so): the edge stop alone
        // would cut it off from its neighbours and darken each chart.
        let bright = |x: u32, y: u32| (x * 7 + y * 13).is_multiple_of(20);
        let (mut p, recs) = page(|x, y| if bright(x, y) { 20.0 } else { 1.0 });
        let var: Vec<f64> = (0..32 * 16)
            .map(|i| if bright(i % 32, i / 32) { 25.0 } else { 0.01 })
            .collect();
        let chart_mean = |e: &[[f32; 3]], c: u32| {
            let v: Vec<f64> = (0..512)
                .filter(|&i| u32::from(i % 32 >= 16) == c)
                .map(|i| f64::from(e[i as usize][1]))
                .collect();
            v.iter().sum::<f64>() / v.len() as f64
        };
        let before = [chart_mean(&p.e, 0), chart_mean(&p.e, 1)];
        atrous(&mut p, &recs, &var, &ATrousOptions::default());
        for c in 0..2 {
            let after = chart_mean(&p.e, c);
            assert!(
                (after / before[c as usize] - 1.0).abs() < 1e-5,
                "chart {c}: mean {} → {after}",
                before[c as usize]
            );
        }
        let max = p.e.iter().map(|v| v[1]).fold(0.0f32, f32::max);
        assert!(max < 15.0, "a firefly kept {max} of 20");
    }
}
