//! Equirectangular (latitude–longitude) maps.
//!
//! Pixel (i, j), row 0 at the top (+y); u = (i+½)/W, v = (j+½)/H. A direction d maps to
//! φ = atan2(d.x, −d.z), u = ½ + φ/(2π), θ = acos(d.y), v = θ/π; the inverse is
//! d = (sinθ sinφ, cosθ, −sinθ cosφ) with φ = 2π(u − ½).

use crate::error::{EnvError, Result};
use glam::DVec3;
use std::f64::consts::PI;

/// Largest accepted equirect width (the height is half of it).
pub const MAX_WIDTH: usize = 1 << 16;

/// An equirectangular map, width = 2·height, row-major, row 0 at the top, linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub struct EquirectMap {
    /// Width in pixels (= 2·height).
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels, `data[j*width + i]`.
    pub data: Vec<[f32; 3]>,
}

impl EquirectMap {
    /// A map from its pixels; checks width = 2·height, non-zero size and the data length.
    pub fn new(width: usize, height: usize, data: Vec<[f32; 3]>) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(EnvError::Parameter(format!(
                "equirect map size {width}×{height} is empty"
            )));
        }
        if width != 2 * height {
            return Err(EnvError::Parameter(format!(
                "equirect map size {width}×{height} is not 2:1 (width must be twice the height)"
            )));
        }
        if width > MAX_WIDTH {
            return Err(EnvError::Parameter(format!(
                "equirect map width {width} exceeds {MAX_WIDTH}"
            )));
        }
        if data.len() != width * height {
            return Err(EnvError::Parameter(format!(
                "equirect map {width}×{height} needs {} pixels, got {}",
                width * height,
                data.len()
            )));
        }
        Ok(Self {
            width,
            height,
            data,
        })
    }

    /// Unit direction of the centre of pixel (i, j) of a `width × height` map.
    pub fn pixel_dir(width: usize, height: usize, i: usize, j: usize) -> DVec3 {
        let u = (i as f64 + 0.5) / width as f64;
        let v = (j as f64 + 0.5) / height as f64;
        let phi = 2.0 * PI * (u - 0.5);
        let theta = PI * v;
        DVec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        )
    }

    /// Exact solid angle of a pixel in row j: (2π/W)·(cos θ₀ − cos θ₁).
    pub fn row_solid_angle(&self, j: usize) -> f64 {
        let h = self.height as f64;
        let t0 = PI * j as f64 / h;
        let t1 = PI * (j as f64 + 1.0) / h;
        2.0 * PI / self.width as f64 * (t0.cos() - t1.cos())
    }

    /// ∫ L dω over the sphere (per channel) with exact pixel solid angles.
    pub fn integral(&self) -> [f64; 3] {
        let mut acc = [0.0f64; 3];
        for j in 0..self.height {
            let w = self.row_solid_angle(j);
            let mut row = [0.0f64; 3];
            for v in &self.data[j * self.width..(j + 1) * self.width] {
                for c in 0..3 {
                    row[c] += v[c] as f64;
                }
            }
            for c in 0..3 {
                acc[c] += w * row[c];
            }
        }
        acc
    }

    /// Bilinear lookup in direction `d` (need not be normalised): wraps around in φ, clamps at
    /// the poles. A zero or non-finite direction reads the top-centre pixel row.
    pub fn lookup_bilinear(&self, d: DVec3) -> [f64; 3] {
        let (u, v) = direction_uv(d);
        self.bilinear_uv(u, v)
    }

    /// [`EquirectMap::lookup_bilinear`] at map coordinates (u, v) ∈ [0, 1]² of
    /// [`direction_uv`].
    pub fn bilinear_uv(&self, u: f64, v: f64) -> [f64; 3] {
        let taps = self.bilinear_taps(u, v);
        std::array::from_fn(|k| {
            let t = |i: usize| self.data[taps.texels[i]][k] as f64;
            let [w00, w10, w01, w11] = taps.weights;
            (w00 * t(0) + w10 * t(1)) + (w01 * t(2) + w11 * t(3))
        })
    }

    /// The four texels [`EquirectMap::bilinear_uv`] reads at (u, v) and their weights: a
    /// lookup of another per-texel quantity of the map (its luminance, its bandwidth) at the
    /// same place.
    pub fn bilinear_taps(&self, u: f64, v: f64) -> BilinearTaps {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = u * w as f64 - 0.5;
        let y = (v * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let x0 = x.floor();
        let y0 = y.floor();
        let fx = x - x0;
        let fy = y - y0;
        // Columns wrap around (no division for the columns next to [0, w), which are all a
        // direction's uv can give).
        let xi = |k: i64| {
            if (0..w).contains(&k) {
                k as usize
            } else if (-w..0).contains(&k) {
                (k + w) as usize
            } else {
                k.rem_euclid(w) as usize
            }
        };
        let (x0, y0) = (x0 as i64, y0 as i64);
        let y1 = (y0 + 1).min(h - 1) as usize;
        let y0 = y0 as usize;
        let (xa, xb) = (xi(x0), xi(x0 + 1));
        let row = self.width;
        BilinearTaps {
            texels: [y0 * row + xa, y0 * row + xb, y1 * row + xa, y1 * row + xb],
            weights: [
                (1.0 - fy) * (1.0 - fx),
                (1.0 - fy) * fx,
                fy * (1.0 - fx),
                fy * fx,
            ],
        }
    }
}

/// Four texels of a bilinear lookup ([`EquirectMap::bilinear_taps`]): their indices in the
/// map's row-major data and their weights (summing to 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BilinearTaps {
    /// (x0, y0), (x1, y0), (x0, y1), (x1, y1).
    pub texels: [usize; 4],
    /// Their bilinear weights.
    pub weights: [f64; 4],
}

/// The map coordinates (u, v) ∈ [0, 1]² of direction `d` (need not be normalised; +y up, u = ½ at
/// −z): u = ½ + atan2(x, −z) / 2π, v = acos(y) / π. A zero or non-finite direction gives +y.
pub fn direction_uv(d: DVec3) -> (f64, f64) {
    let len = d.length();
    let d = if len.is_finite() && len > 0.0 {
        d / len
    } else {
        DVec3::Y
    };
    let phi = d.x.atan2(-d.z);
    (0.5 + phi / (2.0 * PI), d.y.clamp(-1.0, 1.0).acos() / PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_shapes() {
        assert!(EquirectMap::new(0, 0, vec![]).is_err());
        assert!(EquirectMap::new(3, 2, vec![[0.0; 3]; 6]).is_err());
        assert!(EquirectMap::new(4, 2, vec![[0.0; 3]; 7]).is_err());
        assert!(EquirectMap::new(4, 2, vec![[0.0; 3]; 8]).is_ok());
    }

    #[test]
    fn pixel_solid_angles_sum_to_4pi_and_directions_round_trip() {
        let m = EquirectMap::new(64, 32, vec![[1.0; 3]; 64 * 32]).unwrap();
        let s = m.integral();
        assert!((s[0] - 4.0 * PI).abs() < 1e-9, "{s:?}");
        // Conventions: +y is row 0, −z is u = ½, +x is u = ¾.
        let d = EquirectMap::pixel_dir(64, 32, 32, 16);
        assert!(d.z < -0.99);
        let d = EquirectMap::pixel_dir(64, 32, 48, 16);
        assert!(d.x > 0.99);
        assert!(EquirectMap::pixel_dir(64, 32, 5, 0).y > 0.99);
        // A lookup at a pixel centre returns that pixel.
        let data: Vec<[f32; 3]> = (0..64 * 32).map(|k| [k as f32, 0.0, 0.0]).collect();
        let m = EquirectMap::new(64, 32, data).unwrap();
        for (i, j) in [(0, 3), (63, 10), (17, 31), (40, 0)] {
            let v = m.lookup_bilinear(EquirectMap::pixel_dir(64, 32, i, j));
            assert!((v[0] - (j * 64 + i) as f64).abs() < 1e-6, "{i},{j}: {v:?}");
        }
    }
}
