//! Spatial bandwidth of area-light sources and textures (004 §IV.3.1, "Local light sources
//! (spatial)" and "Texture (spatial)", Fig. IV.7): the local bandwidth of the image's luminance
//! ([`local_bandwidth`]), zero-padded for an area light (its border is an edge of its emission)
//! and periodic for a tiling texture, in cycles per metre.

use crate::wavelet::{local_bandwidth, Edges};
use crate::{FreqError, Result};
use lustre_brdf::Rgb;

fn luminance(texels: &[[f32; 3]]) -> Vec<f64> {
    texels
        .iter()
        .map(|p| Rgb(p.map(f64::from)).luminance())
        .collect()
}

/// The spatial bandwidth (cycles per metre) of a `width × height` emission image spread over a
/// `size` = (x, y) metre quad: the pixel bandwidth times max(width / x, height / y) pixels per
/// metre. Errors on a size that is not positive and finite, or a bad image (see
/// [`local_bandwidth`]).
pub fn area_light_bandwidth(
    texels: &[[f32; 3]],
    width: usize,
    height: usize,
    size: (f64, f64),
) -> Result<Vec<f64>> {
    if !(size.0 > 0.0 && size.1 > 0.0 && size.0.is_finite() && size.1.is_finite()) {
        return Err(FreqError::Parameter(format!(
            "area light of {} × {} m: both sides must be positive and finite",
            size.0, size.1
        )));
    }
    let per_metre = (width as f64 / size.0).max(height as f64 / size.1);
    let mut b = local_bandwidth(&luminance(texels), width, height, Edges::Zero)?;
    b.iter_mut().for_each(|v| *v *= per_metre);
    Ok(b)
}

/// The spatial bandwidth of a tiling texture in cycles per texel (periodic in both axes); a
/// renderer scales it by the texels per metre of the surface's UV mapping at a point.
pub fn texture_bandwidth(texels: &[[f32; 3]], width: usize, height: usize) -> Result<Vec<f64>> {
    local_bandwidth(&luminance(texels), width, height, Edges::Wrap)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_textured_area_light_and_a_tiling_texture() {
        // A 0.5 × 0.5 m light of 32² texels with a 4-texel checker in its left half.
        let n = 32;
        let texels: Vec<[f32; 3]> = (0..n * n)
            .map(|k| {
                let (x, y) = (k % n, k / n);
                let v = if x < n / 2 && (x / 4 + y / 4) % 2 == 0 {
                    0.2
                } else {
                    1.0
                };
                [v; 3]
            })
            .collect();
        let b = area_light_bandwidth(&texels, n, n, (0.5, 0.5)).expect("light");
        // 64 texels per metre; inside the checker, its band (period 8 texels) or above; in the
        // plain right half away from the checker and the border, less.
        let (checker, plain) = (b[(n / 2) * n + 6], b[(n / 2) * n + 3 * n / 4]);
        assert!(checker >= 64.0 / 8.0, "{checker}");
        assert!(plain < checker, "{plain} vs {checker}");
        // As a texture the border adds nothing: the plain region's bandwidth can only fall.
        let t = texture_bandwidth(&texels, n, n).expect("texture");
        assert!(t.iter().all(|v| v.is_finite() && *v >= 0.0 && *v <= 0.5));
        assert!(64.0 * t[(n / 2) * n + 3 * n / 4] <= plain);
        assert!(area_light_bandwidth(&texels, n, n, (0.0, 1.0)).is_err());
        assert!(area_light_bandwidth(&texels, n, n, (f64::NAN, 1.0)).is_err());
    }
}
