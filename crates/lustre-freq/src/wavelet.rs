//! Local bandwidth of an image from a 2D wavelet decomposition (004 §IV.3.1, Fig. IV.4–IV.5).
//!
//! The image (padded to powers of two: mirrored, periodic or with zeros beyond its edges,
//! [`Edges`]) is decomposed with Daubechies-4 wavelets, a 2D pyramid step per level (rows, then columns of
//! the current approximation). Detail level i (1 = finest) has coefficients spaced 2^i pixels
//! and a spectrum concentrated in [2^−(i+1), 2^−i] cycles per pixel (Fig. IV.4). For each pixel
//! and level, the largest |coefficient| among the three orientations whose support (4 taps,
//! 3·2^i pixels) covers the pixel, times 2^−i (the peak of a 2D orthonormal wavelet of that
//! level, so that the value is an amplitude in the image's units), is its wavelet amplitude at
//! that level; its square, the level's energy there. The pixel's significant level I_w is the finest level at which the
//! energy summed from the coarsest level reaches 95 % of the pixel's total (the "95th
//! percentile" of Fig. IV.5; amplitudes below 1e-9 of the image's largest |value| count as
//! rounding, not detail), and its bandwidth the upper edge of that level's band, 2^−I_w
//! cycles per pixel; a pixel without detail energy has bandwidth 0. As 004 notes, the estimate
//! is conservative: D4's bands overlap, so a sinusoid may be placed one octave above its band
//! (measured in the tests: within [f, 4f]).
//!
use crate::{FreqError, Result};

/// Daubechies-4 low-pass filter ((1 ± √3), (3 ± √3)) / (4√2).
const D4_LOW: [f64; 4] = [
    0.482_962_913_144_534_1,
    0.836_516_303_737_807_9,
    0.224_143_868_042_013_4,
    -0.129_409_522_551_260_4,
];

/// The high-pass filter of [`D4_LOW`] (quadrature mirror: g_k = (−1)^k h_{3−k}).
const D4_HIGH: [f64; 4] = [D4_LOW[3], -D4_LOW[2], D4_LOW[1], -D4_LOW[0]];

/// The share of a pixel's wavelet energy, summed from the coarsest level, that fixes its
/// significant level (Fig. IV.5's 95th percentile).
pub const ENERGY_PERCENTILE: f64 = 0.95;

/// One periodic D4 analysis step of `x` (even length ≥ 4): (approximation, detail), half
/// length each.
fn d4_step(x: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = x.len();
    let half = n / 2;
    let mut a = vec![0.0; half];
    let mut d = vec![0.0; half];
    for k in 0..half {
        for t in 0..4 {
            let v = x[(2 * k + t) % n];
            a[k] += D4_LOW[t] * v;
            d[k] += D4_HIGH[t] * v;
        }
    }
    (a, d)
}

/// What lies beyond an image's edges, per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edges {
    /// The image mirrored (no seam): a window onto a larger scene, a BRDF slice's θ axis.
    Reflect,
    /// Periodic in x (the φ axis of an equirect map or a BRDF slice), mirrored in y.
    WrapX,
    /// Periodic in both axes (a tiling texture).
    Wrap,
    /// Zeros (an area light: its border is an edge of its emission, §IV.3.1).
    Zero,
}

/// The local bandwidth (cycles per pixel, in [0, ½]) of a `width × height` single-channel
/// image `values` (row-major), with `edges` beyond its borders. Errors on a zero size, a length
/// mismatch or a non-finite value.
pub fn local_bandwidth(
    values: &[f64],
    width: usize,
    height: usize,
    edges: Edges,
) -> Result<Vec<f64>> {
    if width == 0 || height == 0 || values.len() != width * height {
        return Err(FreqError::Parameter(format!(
            "local bandwidth: a {width}×{height} image needs {} values, got {}",
            width * height,
            values.len()
        )));
    }
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(FreqError::Parameter(format!(
            "local bandwidth: value {} at pixel ({}, {}) is not finite",
            values[k],
            k % width,
            k / width
        )));
    }
    // Pad to powers of two (at least 4): a periodic axis by wrapping (to the next power of
    // two), any other to twice its size, mirrored or with zeros (so the periodic transform sees
    // no seam between the two ends).
    let (wrap_x, wrap_y) = match edges {
        Edges::WrapX => (true, false),
        Edges::Wrap => (true, true),
        Edges::Reflect | Edges::Zero => (false, false),
    };
    let size = |n: usize, wrap: bool| if wrap { n } else { 2 * n }.next_power_of_two().max(4);
    let (pw, ph) = (size(width, wrap_x), size(height, wrap_y));
    // The source index of padded index i along an axis of n, or None for a zero.
    let source = |i: usize, n: usize, wrap: bool| -> Option<usize> {
        if wrap {
            return Some(i % n);
        }
        let i = i % (2 * n);
        if i < n {
            Some(i)
        } else if edges == Edges::Zero {
            None
        } else {
            Some(2 * n - 1 - i)
        }
    };
    let mut img = vec![0.0; pw * ph];
    for y in 0..ph {
        let Some(sy) = source(y, height, wrap_y) else {
            continue;
        };
        for x in 0..pw {
            if let Some(sx) = source(x, width, wrap_x) {
                img[y * pw + x] = values[sy * width + sx];
            }
        }
    }
    // The 2D pyramid: per level, the three detail bands' |coefficients|, max over orientation.
    let mut levels: Vec<(usize, usize, Vec<f64>)> = vec![];
    let (mut w, mut h) = (pw, ph);
    let mut approx = img;
    while w >= 4 && h >= 4 {
        let (hw, hh) = (w / 2, h / 2);
        // Rows.
        let mut lo = vec![0.0; hw * h];
        let mut hi = vec![0.0; hw * h];
        for y in 0..h {
            let (a, d) = d4_step(&approx[y * w..(y + 1) * w]);
            lo[y * hw..(y + 1) * hw].copy_from_slice(&a);
            hi[y * hw..(y + 1) * hw].copy_from_slice(&d);
        }
        // Columns of both halves.
        let mut next = vec![0.0; hw * hh];
        let mut detail = vec![0.0f64; hw * hh];
        let mut column = vec![0.0; h];
        for x in 0..hw {
            for (band, src) in [(0, &lo), (1, &hi)] {
                for y in 0..h {
                    column[y] = src[y * hw + x];
                }
                let (a, d) = d4_step(&column);
                for y in 0..hh {
                    let i = y * hw + x;
                    if band == 0 {
                        next[i] = a[y];
                        detail[i] = detail[i].max(d[y].abs());
                    } else {
                        detail[i] = detail[i].max(a[y].abs()).max(d[y].abs());
                    }
                }
            }
        }
        levels.push((hw, hh, detail));
        approx = next;
        w = hw;
        h = hh;
    }
    // Amplitudes below 1e-9 of the image's largest |value| are rounding (the high-pass taps
    // of a constant sum to ~1e-17, not 0).
    let floor = 1e-9 * values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut out = vec![0.0; width * height];
    let mut energy = vec![0.0; levels.len()];
    for y in 0..height {
        for x in 0..width {
            for (i, (lw, lh, detail)) in levels.iter().enumerate() {
                // Coefficients j of level i + 1 cover pixels 2^(i+1) j … 2^(i+1) (j + 3) − 1
                // (periodic): j from ⌊x/2^(i+1)⌋ − 2 to ⌊x/2^(i+1)⌋.
                let s = i + 1;
                let (cx, cy) = (x >> s, y >> s);
                let mut m = 0.0f64;
                for dy in 0..3 {
                    let jy = (cy + lh - dy) % lh;
                    for dx in 0..3 {
                        let jx = (cx + lw - dx) % lw;
                        m = m.max(detail[jy * lw + jx]);
                    }
                }
                // A 2D orthonormal wavelet of level s peaks at 2^−s: the coefficient's
                // amplitude in the image.
                let amplitude = m * 0.5f64.powi(s as i32);
                energy[i] = if amplitude > floor {
                    amplitude * amplitude
                } else {
                    0.0
                };
            }
            let total: f64 = energy.iter().sum();
            if total <= 0.0 {
                continue;
            }
            // From the coarsest level down, the first at which 95 % is reached.
            let mut acc = 0.0;
            let mut significant = 1;
            for i in (0..energy.len()).rev() {
                acc += energy[i];
                if acc >= ENERGY_PERCENTILE * total {
                    significant = i + 1;
                    break;
                }
            }
            out[y * width + x] = 0.5f64.powi(significant as i32);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn d4_filters_are_orthonormal() {
        let dot = |a: &[f64; 4], b: &[f64; 4]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        assert!((dot(&D4_LOW, &D4_LOW) - 1.0).abs() < 1e-12);
        assert!((dot(&D4_HIGH, &D4_HIGH) - 1.0).abs() < 1e-12);
        assert!(dot(&D4_LOW, &D4_HIGH).abs() < 1e-12);
        // Two vanishing moments: the high-pass filter kills constants and ramps.
        assert!(D4_HIGH.iter().sum::<f64>().abs() < 1e-12);
        let ramp: f64 = D4_HIGH.iter().enumerate().map(|(k, g)| k as f64 * g).sum();
        assert!(ramp.abs() < 1e-12);
    }

    #[test]
    fn a_constant_image_has_no_bandwidth() {
        let b = local_bandwidth(&vec![3.5; 40 * 24], 40, 24, Edges::Reflect).expect("bandwidth");
        assert!(b.iter().all(|&v| v == 0.0));
    }

    #[test]
    fn a_sinusoid_is_found_in_its_band() {
        // cos(2π f x) with f = 3/64 cycles per pixel lies in level 4's band [1/32, 1/16]; D4's
        // leakage into the next finer band may put the estimate one octave higher (1/8), never
        // below f.
        for f in [3.0 / 64.0, 3.0 / 16.0] {
            let (w, h) = (128, 32);
            let img: Vec<f64> = (0..w * h)
                .map(|k| (2.0 * PI * f * (k % w) as f64).cos())
                .collect();
            let b = local_bandwidth(&img, w, h, Edges::WrapX).expect("bandwidth");
            for &v in &b {
                assert!(v >= f && v <= 4.0 * f, "f {f}: estimate {v}");
            }
        }
    }

    #[test]
    fn the_estimate_is_local() {
        // Left half smooth, right half a checkerboard at the Nyquist rate.
        let (w, h) = (128, 64);
        let img: Vec<f64> = (0..w * h)
            .map(|k| {
                let (x, y) = (k % w, k / w);
                if x < w / 2 {
                    1.0
                } else {
                    ((x + y) % 2) as f64
                }
            })
            .collect();
        let b = local_bandwidth(&img, w, h, Edges::Reflect).expect("bandwidth");
        for y in 0..h {
            // Far from the edge only the coarsest levels' support reaches across it.
            assert!(
                b[y * w + 8] <= 1.0 / 32.0,
                "left, row {y}: {}",
                b[y * w + 8]
            );
            assert_eq!(b[y * w + w - 8], 0.5, "right, row {y}");
        }
    }

    #[test]
    fn bad_images_are_refused() {
        assert!(local_bandwidth(&[1.0; 5], 2, 2, Edges::Reflect).is_err());
        assert!(local_bandwidth(&[], 0, 0, Edges::Reflect).is_err());
        let e = local_bandwidth(&[1.0, f64::NAN, 1.0, 1.0], 2, 2, Edges::Reflect).expect_err("NaN");
        assert!(e.to_string().contains("(1, 0)"), "{e}");
    }

    #[test]
    fn a_uniform_area_light_has_bandwidth_at_its_border_only() {
        // 004 Fig. IV.7 (a, b): a solid white square, zero-padded.
        let n = 64;
        let b = local_bandwidth(&vec![1.0; n * n], n, n, Edges::Zero).expect("bandwidth");
        let at = |x: usize, y: usize| b[y * n + x];
        assert!(
            at(0, n / 2) >= 0.25 && at(n - 1, n / 2) >= 0.25,
            "{}",
            at(0, n / 2)
        );
        assert!(
            at(n / 2, n / 2) < at(0, n / 2) / 4.0,
            "{}",
            at(n / 2, n / 2)
        );
        // The same image tiling (a texture) or mirrored has none.
        for edges in [Edges::Wrap, Edges::Reflect] {
            let b = local_bandwidth(&vec![1.0; n * n], n, n, edges).expect("bandwidth");
            assert!(b.iter().all(|&v| v == 0.0), "{edges:?}");
        }
    }
}
