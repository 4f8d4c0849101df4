//! The demanding evaluation map of 002 §8: tiny bright spots on a dim, smoothly varying
//! background, which exposes undersampling (missed or blotchy highlights) far more than natural
//! maps do.
//!
//! Construction (deterministic for a given seed, SplitMix64):
//! - background: `background · (1 + ½·(d·g))` per channel, with a random unit vector g, so the
//!   dim background varies smoothly by a factor 3 between opposite directions;
//! - `spots` spot centres uniformly distributed on the sphere; each has a full angular width
//!   w uniform in [`min_deg`, `max_deg`] and a peak-to-local-background ratio r log-uniform in
//!   [√max_ratio, max_ratio] (so the local ratios reach 1 : max_ratio, e.g. 1:3000), with a
//!   random mild tint (each channel × [0.8, 1]);
//! - spot profile: flat core out to 70 % of the radius w/2, then a cos² fall-off to 0 at w/2
//!   (a disc with a soft rim, so the spot stays a clear "tiny light" but has no hard edge).
//!
//! Texels take the mean of 2×2 sub-texel samples (the spots are only a few texels wide).

use crate::cube::{build_faces, face_point, CubeMap};
use crate::error::{EnvError, Result};
use glam::DVec3;

/// Parameters of [`spot_map`].
#[derive(Clone, Debug, PartialEq)]
pub struct SpotMapParams {
    /// Cube face size (texels per edge).
    pub size: usize,
    /// Number of spots.
    pub spots: usize,
    /// Smallest full angular spot width, degrees.
    pub min_deg: f64,
    /// Largest full angular spot width, degrees.
    pub max_deg: f64,
    /// Largest peak-to-local-background ratio (002 §8: up to 3000).
    pub max_ratio: f64,
    /// Mean background radiance (RGB).
    pub background: [f64; 3],
    /// Random seed.
    pub seed: u64,
}

impl Default for SpotMapParams {
    /// 256² faces, 24 spots 2–10° wide, ratios up to 3000, background 0.05 (002 §8 used
    /// 1024² faces; pass `size: 1024` for that).
    fn default() -> Self {
        Self {
            size: 256,
            spots: 24,
            min_deg: 2.0,
            max_deg: 10.0,
            max_ratio: 3000.0,
            background: [0.05, 0.05, 0.05],
            seed: 1,
        }
    }
}

/// SplitMix64: a tiny, good-enough deterministic generator.
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniformly distributed unit vector.
    fn unit(&mut self) -> DVec3 {
        let z = 2.0 * self.next_f64() - 1.0;
        let phi = 2.0 * std::f64::consts::PI * self.next_f64();
        let r = (1.0 - z * z).max(0.0).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// One spot: centre, angular radius (rad) and its cosine, peak ratio and tint.
#[derive(Clone, Debug)]
struct Spot {
    centre: DVec3,
    radius: f64,
    cos_radius: f64,
    ratio: f64,
    tint: [f64; 3],
}

/// Profile of a spot at angle `a` from its centre (1 in the core, 0 beyond the radius).
fn profile(a: f64, radius: f64) -> f64 {
    let core = 0.7 * radius;
    if a <= core {
        1.0
    } else if a >= radius {
        0.0
    } else {
        let x = (a - core) / (radius - core);
        (0.5 * std::f64::consts::PI * x).cos().powi(2)
    }
}

/// The spot map of 002 §8 (see the module documentation for the construction).
pub fn spot_map(p: &SpotMapParams) -> Result<CubeMap> {
    let bad = |what: &str| Err(EnvError::Parameter(format!("spot map: {what}")));
    if p.size == 0 || p.size > 4096 {
        return bad(&format!("face size {} is outside 1..=4096", p.size));
    }
    if p.spots > 10_000 {
        return bad(&format!("{} spots is more than 10000", p.spots));
    }
    if !(p.min_deg > 0.0 && p.min_deg <= p.max_deg && p.max_deg <= 90.0) {
        return bad(&format!(
            "spot widths {}..{}° must satisfy 0 < min ≤ max ≤ 90",
            p.min_deg, p.max_deg
        ));
    }
    if !(p.max_ratio.is_finite() && p.max_ratio >= 1.0) {
        return bad(&format!("max_ratio {} must be finite and ≥ 1", p.max_ratio));
    }
    if p.background.iter().any(|b| !(b.is_finite() && *b > 0.0)) {
        return bad(&format!(
            "background {:?} must be finite and positive",
            p.background
        ));
    }
    let mut rng = SplitMix(p.seed);
    let g = rng.unit();
    let lo = p.max_ratio.sqrt().ln();
    let hi = p.max_ratio.ln();
    let spots: Vec<Spot> = (0..p.spots)
        .map(|_| {
            let centre = rng.unit();
            let w = p.min_deg + (p.max_deg - p.min_deg) * rng.next_f64();
            let ratio = (lo + (hi - lo) * rng.next_f64()).exp();
            let tint = [
                0.8 + 0.2 * rng.next_f64(),
                0.8 + 0.2 * rng.next_f64(),
                0.8 + 0.2 * rng.next_f64(),
            ];
            let radius = 0.5 * w.to_radians();
            Spot {
                centre,
                radius,
                cos_radius: radius.cos(),
                ratio,
                tint,
            }
        })
        .collect();
    let eval = |d: DVec3| -> [f64; 3] {
        let b = 1.0 + 0.5 * d.dot(g);
        let mut v = [b; 3];
        for s in &spots {
            let cosine = d.dot(s.centre);
            if cosine <= s.cos_radius {
                continue;
            }
            let a = cosine.clamp(-1.0, 1.0).acos();
            if a < s.radius {
                let k = profile(a, s.radius) * s.ratio * b;
                for (vc, tc) in v.iter_mut().zip(s.tint) {
                    *vc += k * tc;
                }
            }
        }
        std::array::from_fn(|c| v[c] * p.background[c])
    };
    let n = p.size as f64;
    let faces = build_faces(p.size, |face, i, j| {
        let mut acc = [0.0f64; 3];
        for (a, b) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
            let sc = 2.0 * (i as f64 + a) / n - 1.0;
            let tc = 2.0 * (j as f64 + b) / n - 1.0;
            let v = eval(face_point(face, sc, tc).normalize());
            for c in 0..3 {
                acc[c] += 0.25 * v[c];
            }
        }
        [acc[0] as f32, acc[1] as f32, acc[2] as f32]
    });
    CubeMap::new(p.size, faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spots_are_bright_tiny_and_on_a_dim_background() {
        let p = SpotMapParams {
            size: 128,
            ..Default::default()
        };
        let m = spot_map(&p).unwrap();
        assert_eq!(m, spot_map(&p).unwrap(), "deterministic for a seed");
        let all: Vec<f64> = m.faces.iter().flatten().map(|v| v[1] as f64).collect();
        let min = all.iter().cloned().fold(f64::INFINITY, f64::min);
        let max = all.iter().cloned().fold(0.0, f64::max);
        // Background between 0.5 and 1.5 × 0.05; the brightest spot ≥ √3000 ≈ 55 × local.
        assert!(min >= 0.05 * 0.5 * 0.99, "{min}");
        let bright = all.iter().filter(|v| **v > 0.05 * 1.6).count();
        let frac = bright as f64 / all.len() as f64;
        eprintln!(
            "spot map: min {min:.4}, max {max:.1}, ratio {:.0}, spot area {:.2}%",
            max / min,
            100.0 * frac
        );
        assert!(
            max / (0.05 * 1.5) > 50.0 && max < 0.05 * 1.5 * 3001.0,
            "{max}"
        );
        // 24 spots of ≤ 10° cover at most 24·(1 − cos 5°)/2 ≈ 4.6 % of the sphere.
        assert!(frac > 0.0 && frac < 0.046, "{frac}");
        // Another seed gives another map.
        let q = spot_map(&SpotMapParams {
            seed: 2,
            ..p.clone()
        })
        .unwrap();
        assert_ne!(m, q);
    }

    #[test]
    fn rejects_bad_parameters() {
        let ok = SpotMapParams {
            size: 8,
            ..Default::default()
        };
        assert!(spot_map(&ok).is_ok());
        for bad in [
            SpotMapParams {
                size: 0,
                ..ok.clone()
            },
            SpotMapParams {
                min_deg: 0.0,
                ..ok.clone()
            },
            SpotMapParams {
                min_deg: 11.0,
                ..ok.clone()
            },
            SpotMapParams {
                max_ratio: f64::NAN,
                ..ok.clone()
            },
            SpotMapParams {
                background: [0.0, 1.0, 1.0],
                ..ok.clone()
            },
        ] {
            assert!(spot_map(&bad).is_err(), "{bad:?}");
        }
    }
}
