//! Cube-map MIP pyramids with the filters of 002 §3 (Table 1): the standard 2×2 box and
//! pyramids of Gaussians (Burt & Adelson) with 4×4 and 6×6 kernels.
//!
//! Level l+1 texel (i, j) sits over the 2×2 parent block (2i..2i+1, 2j..2j+1) of level l. The
//! kernels are separable binomials centred on that block (the centre lies between parent
//! texels, so even-length kernels are symmetric about it):
//! - `Box2`: weights (1, 1)/2 per axis over parent offsets 2i, 2i+1 (the block itself);
//! - `Gauss4`: weights (1, 3, 3, 1)/8 per axis over 2i−1 .. 2i+2 (one texel of margin around
//!   the block on each side; σ = √3/2 parent texels);
//! - `Gauss6`: weights (1, 5, 10, 10, 5, 1)/32 per axis over 2i−2 .. 2i+3 (two texels of margin;
//!   σ = √5/2 parent texels).
//!
//! Taps that fall off the face read the neighbouring face through [`CubeMap::fetch`] (the cube
//! unfolded about the shared edge; beyond a corner the average of the three texels meeting
//! there), so the filtering is seamless.
//!
//! Each tap's kernel weight is multiplied by the exact solid angle of the tapped texel and the
//! sum is normalised (a solid-angle-weighted mean rather than a plain image filter): cube
//! texels near a face corner subtend up to 3√3 ≈ 5.2 times less solid angle than those at the
//! centre, and with plain weights a bright source near a corner would gain or lose energy at
//! coarse levels (≈ 10 % at 1×1 on the shared maps). With the weighting, `Box2` preserves
//! ∫L dω exactly from level to level (a child texel is exactly the union of its four parents),
//! the Gaussians to about 1e-3, and a constant map stays constant (to the last f32 bit).
//!
//! Power-of-two base sizes are the intended case. Other sizes work (level sizes are
//! max(1, N >> l), as on a GPU), but for an odd parent size the last parent row and column lie
//! outside every child's 2×2 block and only enter through the Gaussian margins.

use crate::cube::{build_faces, face_coords, solid_angle_table, CubeMap};
use crate::error::Result;
use glam::DVec3;

/// The down-sampling filter of a pyramid (002 §3, Table 1). The default is `Gauss6`, the
/// filter of 002's evaluation (§8).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MipFilter {
    /// Standard MIP mapping: mean of the 2×2 parent block.
    Box2,
    /// Pyramid of Gaussians, 4×4 binomial (1,3,3,1)/8 per axis.
    Gauss4,
    /// Pyramid of Gaussians, 6×6 binomial (1,5,10,10,5,1)/32 per axis.
    #[default]
    Gauss6,
}

impl MipFilter {
    /// The 1-D kernel weights and the offset of the first tap relative to 2i.
    pub fn kernel(self) -> (&'static [f64], i64) {
        match self {
            MipFilter::Box2 => (&[0.5, 0.5], 0),
            MipFilter::Gauss4 => (&[0.125, 0.375, 0.375, 0.125], -1),
            MipFilter::Gauss6 => (
                &[
                    1.0 / 32.0,
                    5.0 / 32.0,
                    10.0 / 32.0,
                    10.0 / 32.0,
                    5.0 / 32.0,
                    1.0 / 32.0,
                ],
                -2,
            ),
        }
    }
}

/// A MIP pyramid of cube maps: level 0 is the base, level l has face size max(1, N >> l),
/// down to 1×1.
#[derive(Clone, Debug, PartialEq)]
pub struct CubePyramid {
    /// The levels, finest first.
    pub levels: Vec<CubeMap>,
    /// The filter the levels were built with.
    pub filter: MipFilter,
}

/// One down-sampling step (parent size ≥ 2): the next level from `parent` with `filter`
/// (rayon-parallel). Each tap's kernel weight is multiplied by the tap texel's exact solid
/// angle and the sum normalised, so the child is a solid-angle-weighted mean.
fn downsample(parent: &CubeMap, filter: MipFilter) -> CubeMap {
    let size = (parent.size / 2).max(1);
    let (w, off) = filter.kernel();
    let np = parent.size as i64;
    // Texel solid angles of the parent (the same table on every face).
    let omega = solid_angle_table(parent.size);
    // A tap k texels beyond an edge reads the (k−1)-th texel from the edge of the neighbour,
    // whose solid angle (symmetric under the face's flips and transposition) is that of the
    // mirrored index.
    let mirror = |i: i64| -> usize {
        let m = if i < 0 {
            -i - 1
        } else if i >= np {
            i - np
        } else {
            i
        };
        m.clamp(0, np - 1) as usize
    };
    let faces = build_faces(size, |face, i, j| {
        let mut acc = [0.0f64; 3];
        let mut wsum = 0.0;
        let (bi, bj) = (2 * i as i64 + off, 2 * j as i64 + off);
        let len = w.len() as i64;
        let inside = bi >= 0 && bj >= 0 && bi + len <= np && bj + len <= np;
        for (b, wb) in w.iter().enumerate() {
            if inside {
                // Fast path: the whole footprint lies on this face.
                let start = (bj as usize + b) * parent.size + bi as usize;
                let texels = &parent.faces[face][start..start + w.len()];
                let omegas = &omega[start..start + w.len()];
                for ((v, wa), om) in texels.iter().zip(w).zip(omegas) {
                    let k = wa * wb * om;
                    wsum += k;
                    for c in 0..3 {
                        acc[c] += k * v[c] as f64;
                    }
                }
            } else {
                let jj = bj + b as i64;
                for (a, wa) in w.iter().enumerate() {
                    let ii = bi + a as i64;
                    let v = parent.fetch(face, ii, jj);
                    let k = wa * wb * omega[mirror(jj) * parent.size + mirror(ii)];
                    wsum += k;
                    for c in 0..3 {
                        acc[c] += k * v[c];
                    }
                }
            }
        }
        std::array::from_fn(|c| (acc[c] / wsum) as f32)
    });
    CubeMap { size, faces }
}

impl CubePyramid {
    /// Builds all levels down to 1×1 from `base` with `filter`, seam-correct and
    /// rayon-parallel (see the module documentation for the kernels).
    pub fn build(base: CubeMap, filter: MipFilter) -> Result<Self> {
        let base = CubeMap::new(base.size, base.faces)?;
        let mut levels = vec![base];
        while let Some(last) = levels.last() {
            if last.size == 1 {
                break;
            }
            let next = downsample(last, filter);
            levels.push(next);
        }
        Ok(Self { levels, filter })
    }

    /// Face size of level 0.
    pub fn base_size(&self) -> usize {
        self.levels[0].size
    }

    /// Number of levels (log2(N) + 1 for a power-of-two base).
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Trilinear, seamless lookup as Vulkan's `textureSampleLevel`: `lod` is clamped to
    /// [0, levels − 1] (NaN reads level 0), and the result is the lerp between the bilinear
    /// lookups of levels ⌊lod⌋ and ⌈lod⌉.
    pub fn sample(&self, d: DVec3, lod: f64) -> [f64; 3] {
        let max = (self.levels.len() - 1) as f64;
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, max)
        };
        let l0 = lod.floor();
        let f = lod - l0;
        let l0 = l0 as usize;
        let a = self.levels[l0].bilinear(d);
        if f == 0.0 {
            return a;
        }
        let b = self.levels[(l0 + 1).min(self.levels.len() - 1)].bilinear(d);
        std::array::from_fn(|c| (1.0 - f) * a[c] + f * b[c])
    }

    /// Nearest-texel lookup on one level (no filtering): the texel containing `d`.
    pub fn texel(&self, d: DVec3, level: usize) -> [f64; 3] {
        let m = &self.levels[level.min(self.levels.len() - 1)];
        let (face, s, t) = face_coords(d);
        let n = m.size as f64;
        let i = ((s * n).floor() as i64).clamp(0, m.size as i64 - 1);
        let j = ((t * n).floor() as i64).clamp(0, m.size as i64 - 1);
        m.fetch(face, i, j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cube::face_point;

    const FILTERS: [MipFilter; 3] = [MipFilter::Box2, MipFilter::Gauss4, MipFilter::Gauss6];

    #[test]
    fn kernels_sum_to_one_and_are_centred_on_the_block() {
        for f in FILTERS {
            let (w, off) = f.kernel();
            assert_eq!(w.iter().sum::<f64>(), 1.0);
            // Centre of mass at 2i + ½ (between the two parent texels of the block).
            let c: f64 = w
                .iter()
                .enumerate()
                .map(|(k, x)| x * (k as i64 + off) as f64)
                .sum();
            assert_eq!(c, 0.5);
        }
    }

    #[test]
    fn constant_map_stays_exactly_constant() {
        for f in FILTERS {
            let base = CubeMap::from_fn(16, |_| [0.7, 1.3, 1e4]).unwrap();
            let p = CubePyramid::build(base, f).unwrap();
            assert_eq!(p.levels.len(), 5);
            for (l, m) in p.levels.iter().enumerate() {
                assert_eq!(m.size, 16 >> l);
                for face in &m.faces {
                    for v in face {
                        assert_eq!(*v, [0.7f32, 1.3, 1e4], "{f:?} level {l}");
                    }
                }
            }
            assert_eq!(
                p.sample(DVec3::new(0.3, -1.0, 0.2), 2.7),
                [0.7f32 as f64, 1.3f32 as f64, 1e4]
            );
        }
    }

    /// L = 1 + d·a is smooth; every level must stay smooth across every cube edge: the jump
    /// between the two texels facing each other across an edge must be no larger than the
    /// jumps between neighbouring texels inside the faces (plus a small slack).
    #[test]
    fn smooth_function_stays_smooth_across_every_edge_at_every_level() {
        let a = DVec3::new(0.31, -0.52, 0.77);
        for f in FILTERS {
            let base = CubeMap::from_fn(32, |d| {
                let v = 1.0 + d.dot(a);
                [v, v, v]
            })
            .unwrap();
            let p = CubePyramid::build(base, f).unwrap();
            for (l, m) in p.levels.iter().enumerate() {
                let n = m.size as i64;
                if n < 2 {
                    continue;
                }
                // Largest step between in-face neighbours.
                let mut inner: f64 = 0.0;
                for face in 0..6 {
                    for j in 0..n {
                        for i in 0..n - 1 {
                            let d = (m.fetch(face, i + 1, j)[0] - m.fetch(face, i, j)[0]).abs();
                            let e = (m.fetch(face, j, i + 1)[0] - m.fetch(face, j, i)[0]).abs();
                            inner = inner.max(d).max(e);
                        }
                    }
                }
                // Steps across each edge: the border texel vs the tap just outside it.
                let mut across: f64 = 0.0;
                for face in 0..6 {
                    for k in 0..n {
                        for (i, j, di, dj) in [
                            (0, k, -1, 0),
                            (n - 1, k, 1, 0),
                            (k, 0, 0, -1),
                            (k, n - 1, 0, 1),
                        ] {
                            let d =
                                (m.fetch(face, i + di, j + dj)[0] - m.fetch(face, i, j)[0]).abs();
                            across = across.max(d);
                        }
                    }
                }
                // At 2×2 every texel touches a cube corner and the footprints wrap around
                // half the cube, so only a looser bound is meaningful there.
                let slack = if n == 2 { 1.6 } else { 1.3 };
                assert!(
                    across <= slack * inner + 1e-6,
                    "{f:?} level {l} (N = {n}): across-edge step {across} vs in-face {inner}"
                );
                // And the level approximates the smooth function (filtering a linear function
                // is exact up to the cube's curvature).
                let mut err: f64 = 0.0;
                for face in 0..6 {
                    for j in 0..n as usize {
                        for i in 0..n as usize {
                            let d = CubeMap::texel_dir(m.size, face, i, j);
                            err = err.max(
                                (m.faces[face][j * m.size + i][0] as f64 - 1.0 - d.dot(a)).abs(),
                            );
                        }
                    }
                }
                eprintln!(
                    "{f:?} N = {n}: max error {err:.2e}, across {across:.2e}, inner {inner:.2e}"
                );
                assert!(
                    n < 8 || err < 0.25 / n as f64 + 0.02,
                    "{f:?} level {l}: max error {err}"
                );
            }
        }
    }

    #[test]
    fn sample_is_trilinear_and_clamped() {
        let base = CubeMap::from_fn(8, |d| [d.x + 2.0, 1.0, 1.0]).unwrap();
        let p = CubePyramid::build(base, MipFilter::Gauss4).unwrap();
        let d = face_point(0, 0.3, -0.2);
        let (a, b) = (p.sample(d, 1.0)[0], p.sample(d, 2.0)[0]);
        assert!((p.sample(d, 1.25)[0] - (0.75 * a + 0.25 * b)).abs() < 1e-12);
        assert_eq!(p.sample(d, -3.0), p.sample(d, 0.0));
        assert_eq!(p.sample(d, 99.0), p.sample(d, 3.0));
        assert_eq!(p.sample(d, f64::NAN), p.sample(d, 0.0));
        assert_eq!(p.base_size(), 8);
        assert_eq!(p.level_count(), 4);
    }
}
