//! The local angular bandwidth of a distant environment (004 §IV.3.1, "Distant illumination",
//! Fig. IV.6): the pixel bandwidth of the map's luminance ([`crate::wavelet::local_bandwidth`],
//! periodic in φ) times the largest number of pixels per radian of the equirect mapping at the
//! pixel, max(W / (2π sin θ), H / π) (the largest singular value of the Jacobian from angle to
//! image), in cycles per radian.

use crate::wavelet::{local_bandwidth, Edges};
use crate::Result;
use lustre_brdf::Rgb;
use lustre_env::EquirectMap;
use std::f64::consts::PI;

/// The local angular bandwidth (cycles per radian) of an equirect environment map's luminance:
/// [`local_bandwidth`] (periodic in φ) times max(W / (2π sin θ), H / π) pixels per radian.
pub fn angular_bandwidth(map: &EquirectMap) -> Result<Vec<f64>> {
    let (w, h) = (map.width, map.height);
    let lum: Vec<f64> = map
        .data
        .iter()
        .map(|p| Rgb(p.map(f64::from)).luminance())
        .collect();
    let mut out = local_bandwidth(&lum, w, h, Edges::WrapX)?;
    for y in 0..h {
        let theta = PI * (y as f64 + 0.5) / h as f64;
        let per_radian = (w as f64 / (2.0 * PI * theta.sin())).max(h as f64 / PI);
        for v in &mut out[y * w..(y + 1) * w] {
            *v *= per_radian;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn angular_bandwidth_of_bands_in_latitude() {
        // L = 1 + cos(k θ): k/(2π) cycles per radian along θ everywhere. At the equator the
        // mapping has H/π pixels per radian along θ and W/(2π) = H/π along φ.
        let (w, h) = (256, 128);
        let k = 24.0;
        let data: Vec<[f32; 3]> = (0..w * h)
            .map(|p| {
                let theta = PI * ((p / w) as f64 + 0.5) / h as f64;
                [(1.0 + (k * theta).cos()) as f32; 3]
            })
            .collect();
        let map = EquirectMap::new(w, h, data).expect("map");
        let b = angular_bandwidth(&map).expect("bandwidth");
        let want = k / (2.0 * PI);
        for y in [h / 2 - 8, h / 2, h / 2 + 8] {
            let v = b[y * w + 17];
            assert!(v >= want && v <= 4.0 * want, "row {y}: {v} vs {want}");
        }
    }
}
