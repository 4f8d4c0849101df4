//! Diffuse irradiance maps: E(n)/π = (1/π) ∫ L(ω) max(0, n·ω) dω, stored so that a Lambertian
//! surface shades as `kd · lookup(n)` (002 §4: the diffuse part from a pre-convolved map).
//!
//! Brute-force cosine convolution: the source is the finest pyramid level whose faces are at
//! most [`SOURCE_SIZE`]² (the pyramid's filter has already averaged the finer detail), every
//! source texel weighted by its exact solid angle (see [`CubeMap::texel_solid_angle`]) and
//! the clamped cosine at its centre.

use crate::cube::{build_faces, solid_angle_table, CubeMap};
use crate::error::{EnvError, Result};
use crate::pyramid::CubePyramid;
use glam::DVec3;
use std::f64::consts::PI;

/// Largest source face size used for the convolution.
pub const SOURCE_SIZE: usize = 32;

/// The irradiance map of `src` with faces of `size²` texels, each storing E(n)/π for the
/// texel-centre normal n (rayon-parallel).
pub fn irradiance_map(src: &CubePyramid, size: usize) -> Result<CubeMap> {
    if size == 0 || size > 256 {
        return Err(EnvError::Parameter(format!(
            "irradiance map face size {size} is outside 1..=256"
        )));
    }
    let level = src
        .levels
        .iter()
        .find(|m| m.size <= SOURCE_SIZE)
        .unwrap_or(&src.levels[src.levels.len() - 1]);
    let n = level.size;
    // Source texels: direction, radiance × solid angle / π.
    let mut texels: Vec<(DVec3, [f64; 3])> = Vec::with_capacity(6 * n * n);
    let omega = solid_angle_table(n);
    for (face, data) in level.faces.iter().enumerate() {
        for j in 0..n {
            for i in 0..n {
                let w = omega[j * n + i] / PI;
                let v = data[j * n + i];
                texels.push((
                    CubeMap::texel_dir(n, face, i, j),
                    [w * v[0] as f64, w * v[1] as f64, w * v[2] as f64],
                ));
            }
        }
    }
    let faces = build_faces(size, |face, i, j| {
        let normal = CubeMap::texel_dir(size, face, i, j);
        let mut acc = [0.0f64; 3];
        for (d, lw) in &texels {
            let c = normal.dot(*d);
            if c > 0.0 {
                for k in 0..3 {
                    acc[k] += c * lw[k];
                }
            }
        }
        [acc[0] as f32, acc[1] as f32, acc[2] as f32]
    });
    CubeMap::new(size, faces)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pyramid::MipFilter;

    #[test]
    fn constant_radiance_gives_one() {
        let p = CubePyramid::build(
            CubeMap::from_fn(64, |_| [1.0, 2.0, 0.5]).unwrap(),
            MipFilter::Box2,
        )
        .unwrap();
        let e = irradiance_map(&p, 8).unwrap();
        let mut worst: f64 = 0.0;
        for face in &e.faces {
            for v in face {
                worst = worst
                    .max((v[0] as f64 - 1.0).abs())
                    .max((v[1] as f64 - 2.0).abs() / 2.0);
                assert!((v[2] as f64 - 0.5).abs() < 5e-3);
            }
        }
        eprintln!("constant L: max relative error {worst:e}");
        assert!(worst < 5e-3, "{worst}");
    }

    /// L = max(d.y, 0): (1/π)∫ max(ω_y, 0) max(n·ω, 0) dω = (2/(3π))·((π − α) cos α + sin α),
    /// α = angle between n and +y (the correlation of two clamped cosines).
    #[test]
    fn clamped_cosine_sky_matches_closed_form() {
        let p = CubePyramid::build(
            CubeMap::from_fn(32, |d| [d.y.max(0.0); 3]).unwrap(),
            MipFilter::Box2,
        )
        .unwrap();
        let e = irradiance_map(&p, 8).unwrap();
        let mut worst: f64 = 0.0;
        for face in 0..6 {
            for j in 0..8 {
                for i in 0..8 {
                    let n = CubeMap::texel_dir(8, face, i, j);
                    let a = n.y.clamp(-1.0, 1.0).acos();
                    let exact = 2.0 / (3.0 * PI) * ((PI - a) * a.cos() + a.sin());
                    let got = e.faces[face][j * 8 + i][0] as f64;
                    worst = worst.max((got - exact).abs());
                }
            }
        }
        eprintln!("max(d.y, 0) sky: max absolute error {worst:e} (E/π ≤ 2/3)");
        assert!(worst < 5e-3, "{worst}");
        // Bilinear between texel centres (≈ 0.34 rad from the pole) of a concave function.
        assert!((e.bilinear(DVec3::Y)[0] - 2.0 / 3.0).abs() < 0.02);
        assert!(e.bilinear(-DVec3::Y)[0].abs() < 5e-3);
    }

    #[test]
    fn rejects_bad_size() {
        let p = CubePyramid::build(CubeMap::from_fn(4, |_| [1.0; 3]).unwrap(), MipFilter::Box2)
            .unwrap();
        assert!(irradiance_map(&p, 0).is_err());
    }
}
