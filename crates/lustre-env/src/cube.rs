//! Cube maps in Vulkan/wgpu face order and orientation, exact texel solid angles, seamless
//! bilinear lookup, and conversion to and from equirectangular maps.
//!
//! Faces 0..5 are +X, −X, +Y, −Y, +Z, −Z. For a direction r with major axis ma the face
//! coordinates are (Vulkan spec, "Cube Map Face Selection"):
//! +X: sc = −rz, tc = −ry; −X: sc = +rz, tc = −ry; +Y: sc = +rx, tc = +rz;
//! −Y: sc = +rx, tc = −rz; +Z: sc = +rx, tc = −ry; −Z: sc = −rx, tc = −ry;
//! s = ½(sc/|ma| + 1), t = ½(tc/|ma| + 1). Texel (i, j) of a face of size N has its centre at
//! s = (i + ½)/N, t = (j + ½)/N and is stored at `data[j*N + i]`.

use crate::equirect::EquirectMap;
use crate::error::{EnvError, Result};
use glam::DVec3;
use rayon::prelude::*;

/// Face index of +X.
pub const POS_X: usize = 0;
/// Face index of −X.
pub const NEG_X: usize = 1;
/// Face index of +Y.
pub const POS_Y: usize = 2;
/// Face index of −Y.
pub const NEG_Y: usize = 3;
/// Face index of +Z.
pub const POS_Z: usize = 4;
/// Face index of −Z.
pub const NEG_Z: usize = 5;

/// Largest accepted face size (texels per edge): 16384² · 6 texels is already 19 GB of f32 RGB.
pub const MAX_FACE_SIZE: usize = 16384;

/// A cube map: six square faces of `size × size` linear RGB texels (Vulkan face order).
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMap {
    /// Texels per face edge.
    pub size: usize,
    /// The faces +X, −X, +Y, −Y, +Z, −Z; texel (i, j) at `[j*size + i]`.
    pub faces: [Vec<[f32; 3]>; 6],
}

/// The face a direction falls on and its face coordinates (s, t) in [0, 1].
/// A zero or non-finite direction gives face +X at its centre.
pub fn face_coords(d: DVec3) -> (usize, f64, f64) {
    let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
    if !(ax.is_finite() && ay.is_finite() && az.is_finite())
        || (ax == 0.0 && ay == 0.0 && az == 0.0)
    {
        return (POS_X, 0.5, 0.5);
    }
    // Ties resolve towards x, then y (as the Vulkan rule "largest magnitude, first in order").
    let (face, sc, tc, ma) = if ax >= ay && ax >= az {
        if d.x > 0.0 {
            (POS_X, -d.z, -d.y, ax)
        } else {
            (NEG_X, d.z, -d.y, ax)
        }
    } else if ay >= az {
        if d.y > 0.0 {
            (POS_Y, d.x, d.z, ay)
        } else {
            (NEG_Y, d.x, -d.z, ay)
        }
    } else if d.z > 0.0 {
        (POS_Z, d.x, -d.y, az)
    } else {
        (NEG_Z, -d.x, -d.y, az)
    };
    (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

/// The (unnormalised) direction of face coordinates (sc, tc) ∈ [−1, 1]² (or beyond, on the
/// extended face plane) of `face`: the inverse of [`face_coords`] up to length.
pub fn face_point(face: usize, sc: f64, tc: f64) -> DVec3 {
    match face {
        POS_X => DVec3::new(1.0, -tc, -sc),
        NEG_X => DVec3::new(-1.0, -tc, sc),
        POS_Y => DVec3::new(sc, 1.0, tc),
        NEG_Y => DVec3::new(sc, -1.0, -tc),
        POS_Z => DVec3::new(sc, -tc, 1.0),
        _ => DVec3::new(-sc, -tc, -1.0),
    }
}

/// ∫∫ dx dy / (1 + x² + y²)^{3/2} from (0, 0) to (x, y): the solid angle subtended by the
/// rectangle [0, x] × [0, y] of a face plane at unit distance.
fn area_element(x: f64, y: f64) -> f64 {
    (x * y).atan2((x * x + y * y + 1.0).sqrt())
}

/// Exact solid angle of the face rectangle [x0, x1] × [y0, y1] (face-plane coordinates in
/// [−1, 1]).
pub fn rect_solid_angle(x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    area_element(x1, y1) - area_element(x0, y1) - area_element(x1, y0) + area_element(x0, y0)
}

/// The exact solid angles of all texels of a face of size `size`, `[j*size + i]` (the same on
/// every face), from the (size+1)² corner values of the area element.
pub fn solid_angle_table(size: usize) -> Vec<f64> {
    let n = size as f64;
    let x = |k: usize| 2.0 * k as f64 / n - 1.0;
    let m = size + 1;
    let mut f = vec![0.0f64; m * m];
    for b in 0..m {
        for a in 0..m {
            f[b * m + a] = area_element(x(a), x(b));
        }
    }
    let mut out = Vec::with_capacity(size * size);
    for j in 0..size {
        for i in 0..size {
            let k = j * m + i;
            out.push(f[k + m + 1] - f[k + m] - f[k + 1] + f[k]);
        }
    }
    out
}

/// Checks a face size.
fn check_size(size: usize) -> Result<()> {
    if size == 0 || size > MAX_FACE_SIZE {
        return Err(EnvError::Parameter(format!(
            "cube face size {size} is outside 1..={MAX_FACE_SIZE}"
        )));
    }
    Ok(())
}

/// The neighbour texel that a tap (i, j) lying outside face `face` (in exactly one coordinate,
/// by k ≥ 1 texels, k ≤ size) reads: the cube is unfolded about the shared edge, so the tap is
/// the (k−1)-th texel row/column from that edge on the neighbouring face, at the same position
/// along the edge. Returns (face, i, j).
fn wrap_edge(size: usize, face: usize, i: i64, j: i64) -> (usize, usize, usize) {
    let n = size as f64;
    let nn = size as i64;
    let (k, sc, tc) = if i < 0 || i >= nn {
        let k = if i < 0 { -i } else { i - nn + 1 };
        let sc = if i < 0 { -1.0 } else { 1.0 };
        (k, sc, 2.0 * (j as f64 + 0.5) / n - 1.0)
    } else {
        let k = if j < 0 { -j } else { j - nn + 1 };
        let tc = if j < 0 { -1.0 } else { 1.0 };
        (k, 2.0 * (i as f64 + 0.5) / n - 1.0, tc)
    };
    // The neighbour: the face of a point just beyond the edge.
    let beyond = face_point(
        face,
        if sc.abs() == 1.0 { sc * 1.5 } else { sc },
        if tc.abs() == 1.0 { tc * 1.5 } else { tc },
    );
    let (nface, _, _) = face_coords(beyond);
    // The edge point (texel centre along the edge) in the neighbour's coordinates.
    let e = face_point(face, sc, tc);
    let (s2, t2) = project_on(nface, e);
    let k = (k - 1).clamp(0, nn - 1) as usize;
    let along = |c: f64| ((c * n).floor() as i64).clamp(0, nn - 1) as usize;
    // The edge coordinate is the one at 0 or 1; the other is a texel centre.
    let ds = s2.min(1.0 - s2).abs();
    let dt = t2.min(1.0 - t2).abs();
    if ds < dt {
        let ii = if s2 < 0.5 { k } else { size - 1 - k };
        (nface, ii, along(t2))
    } else {
        let jj = if t2 < 0.5 { k } else { size - 1 - k };
        (nface, along(s2), jj)
    }
}

/// The texels [`CubeMap::fetch`] reads for tap (i, j) of `face` on faces of `size` texels (i, j
/// within `size` texels of the face): (face, i, j) of each, and how many (1 on the face or
/// beyond one edge; 3 beyond a corner, to be averaged). The GPU pyramid builder uploads these
/// as a table so that both read the same texels.
pub fn fetch_sources(
    size: usize,
    face: usize,
    i: i64,
    j: i64,
) -> ([(usize, usize, usize); 3], usize) {
    let nn = size as i64;
    let out_i = i < 0 || i >= nn;
    let out_j = j < 0 || j >= nn;
    match (out_i, out_j) {
        (false, false) => ([(face, i as usize, j as usize); 3], 1),
        (true, false) | (false, true) => ([wrap_edge(size, face, i, j); 3], 1),
        (true, true) => {
            let ci = i.clamp(0, nn - 1);
            let cj = j.clamp(0, nn - 1);
            (
                [
                    (face, ci as usize, cj as usize),
                    wrap_edge(size, face, i, cj),
                    wrap_edge(size, face, ci, j),
                ],
                3,
            )
        }
    }
}

/// Face coordinates (s, t) of direction `d` on a given face (which need not be its major face;
/// `d` must have a non-zero component along the face's axis).
fn project_on(face: usize, d: DVec3) -> (f64, f64) {
    let (sc, tc, ma) = match face {
        POS_X => (-d.z, -d.y, d.x.abs()),
        NEG_X => (d.z, -d.y, d.x.abs()),
        POS_Y => (d.x, d.z, d.y.abs()),
        NEG_Y => (d.x, -d.z, d.y.abs()),
        POS_Z => (d.x, -d.y, d.z.abs()),
        _ => (-d.x, -d.y, d.z.abs()),
    };
    (0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

impl CubeMap {
    /// A cube map from six faces of `size²` texels each.
    pub fn new(size: usize, faces: [Vec<[f32; 3]>; 6]) -> Result<Self> {
        check_size(size)?;
        for (f, data) in faces.iter().enumerate() {
            if data.len() != size * size {
                return Err(EnvError::Parameter(format!(
                    "cube face {f} has {} texels, expected {size}² = {}",
                    data.len(),
                    size * size
                )));
            }
        }
        Ok(Self { size, faces })
    }

    /// A cube map with `f(direction)` evaluated at every texel centre (rayon-parallel).
    pub fn from_fn(size: usize, f: impl Fn(DVec3) -> [f64; 3] + Sync) -> Result<Self> {
        check_size(size)?;
        let faces = build_faces(size, |face, i, j| {
            let v = f(Self::texel_dir(size, face, i, j));
            [v[0] as f32, v[1] as f32, v[2] as f32]
        });
        Ok(Self { size, faces })
    }

    /// Unit direction of the centre of texel (i, j) of `face` on a cube of face size `size`.
    pub fn texel_dir(size: usize, face: usize, i: usize, j: usize) -> DVec3 {
        let n = size as f64;
        let sc = 2.0 * (i as f64 + 0.5) / n - 1.0;
        let tc = 2.0 * (j as f64 + 0.5) / n - 1.0;
        face_point(face, sc, tc).normalize()
    }

    /// Exact solid angle (sr) of texel (i, j) of a face of size `size` (the same on every
    /// face): the integral of dA·cos/r² over the texel's square on the unit-distance face plane.
    pub fn texel_solid_angle(size: usize, i: usize, j: usize) -> f64 {
        let n = size as f64;
        let x0 = 2.0 * i as f64 / n - 1.0;
        let y0 = 2.0 * j as f64 / n - 1.0;
        rect_solid_angle(x0, x0 + 2.0 / n, y0, y0 + 2.0 / n)
    }

    /// Texel (i, j) of `face`, where (i, j) may lie up to `size` texels outside the face: such a
    /// tap reads the neighbouring face (the cube unfolded about the shared edge), and a tap
    /// outside in both coordinates (beyond a corner, where no texel exists) is the average of
    /// the three texels meeting there, as Vulkan's seamless cube filtering does.
    pub fn fetch(&self, face: usize, i: i64, j: i64) -> [f64; 3] {
        let (src, n) = fetch_sources(self.size, face, i, j);
        let mut acc = [0.0f64; 3];
        for &(f, a, b) in &src[..n] {
            let v = self.faces[f][b * self.size + a];
            for c in 0..3 {
                acc[c] += f64::from(v[c]);
            }
        }
        if n == 1 {
            acc
        } else {
            acc.map(|v| v / n as f64)
        }
    }

    /// Seamless bilinear lookup in direction `d` (need not be normalised): taps that fall off
    /// the face read the neighbouring face, corner taps average the three texels that meet
    /// (Vulkan's cube filtering).
    pub fn bilinear(&self, d: DVec3) -> [f64; 3] {
        let (face, s, t) = face_coords(d);
        let n = self.size as f64;
        let u = s * n - 0.5;
        let v = t * n - 0.5;
        let i0 = u.floor();
        let j0 = v.floor();
        let fu = u - i0;
        let fv = v - j0;
        let (i0, j0) = (i0 as i64, j0 as i64);
        let a = self.fetch(face, i0, j0);
        let b = self.fetch(face, i0 + 1, j0);
        let c = self.fetch(face, i0, j0 + 1);
        let e = self.fetch(face, i0 + 1, j0 + 1);
        std::array::from_fn(|k| {
            (1.0 - fv) * ((1.0 - fu) * a[k] + fu * b[k]) + fv * ((1.0 - fu) * c[k] + fu * e[k])
        })
    }

    /// ∫ L dω over the sphere (per channel), with exact texel solid angles.
    pub fn integral(&self) -> [f64; 3] {
        let n = self.size;
        let omega = solid_angle_table(n);
        let mut acc = [0.0f64; 3];
        for j in 0..n {
            for i in 0..n {
                let w = omega[j * n + i];
                for face in &self.faces {
                    let v = face[j * n + i];
                    for c in 0..3 {
                        acc[c] += w * v[c] as f64;
                    }
                }
            }
        }
        acc
    }

    /// Area-correct resampling of an equirectangular map onto a cube of face size `size`: each
    /// cube texel is the solid-angle-weighted mean of S×S bilinear lookups of the map at the
    /// centres of its sub-texels (weights = the exact sub-texel solid angles), with S chosen so
    /// that the sub-samples are at most about a sixth of a map texel apart (S ∈ [4, 16]). So
    /// ∫L dω is preserved to the accuracy of the bilinear reconstruction.
    pub fn from_equirect(map: &EquirectMap, size: usize) -> Result<Self> {
        check_size(size)?;
        // Cube texel edge ≈ 2/N rad at the face centre; map texel π/H rad.
        let ratio = (2.0 / size as f64) / (std::f64::consts::PI / map.height as f64);
        let ss = ((6.0 * ratio).ceil() as usize).clamp(4, 16);
        let n = size as f64;
        let sub = 2.0 / (n * ss as f64);
        let faces = build_faces(size, |face, i, j| {
            let x0 = 2.0 * i as f64 / n - 1.0;
            let y0 = 2.0 * j as f64 / n - 1.0;
            // F at the (S+1)² sub-texel corners: a sub-texel's solid angle is the
            // inclusion–exclusion of F over its four corners.
            let mut corners = vec![0.0f64; (ss + 1) * (ss + 1)];
            for b in 0..=ss {
                for a in 0..=ss {
                    corners[b * (ss + 1) + a] =
                        area_element(x0 + a as f64 * sub, y0 + b as f64 * sub);
                }
            }
            let mut acc = [0.0f64; 3];
            let mut wsum = 0.0;
            for b in 0..ss {
                let ya = y0 + b as f64 * sub;
                for a in 0..ss {
                    let xa = x0 + a as f64 * sub;
                    let k = b * (ss + 1) + a;
                    let w = corners[k + ss + 2] - corners[k + ss + 1] - corners[k + 1] + corners[k];
                    let d = face_point(face, xa + 0.5 * sub, ya + 0.5 * sub);
                    let v = map.lookup_bilinear(d);
                    for c in 0..3 {
                        acc[c] += w * v[c];
                    }
                    wsum += w;
                }
            }
            std::array::from_fn(|c| (acc[c] / wsum) as f32)
        });
        Ok(Self { size, faces })
    }

    /// Resamples the cube map onto an equirectangular map of the given width (height =
    /// width/2) with seamless bilinear lookups at the pixel centres.
    pub fn to_equirect(&self, width: usize) -> Result<EquirectMap> {
        if width < 2 || !width.is_multiple_of(2) {
            return Err(EnvError::Parameter(format!(
                "equirect width {width} must be even and at least 2"
            )));
        }
        let height = width / 2;
        let data: Vec<[f32; 3]> = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % width, k / width);
                let d = EquirectMap::pixel_dir(width, height, i, j);
                let v = self.bilinear(d);
                [v[0] as f32, v[1] as f32, v[2] as f32]
            })
            .collect();
        EquirectMap::new(width, height, data)
    }
}

/// Six faces with `f(face, i, j)` at every texel (rayon over faces × rows).
pub(crate) fn build_faces(
    size: usize,
    f: impl Fn(usize, usize, usize) -> [f32; 3] + Sync,
) -> [Vec<[f32; 3]>; 6] {
    let all: Vec<[f32; 3]> = (0..6 * size * size)
        .into_par_iter()
        .with_min_len(256)
        .map(|k| {
            let face = k / (size * size);
            let r = k % (size * size);
            f(face, r % size, r / size)
        })
        .collect();
    let per = size * size;
    std::array::from_fn(|face| all[face * per..(face + 1) * per].to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn solid_angles_sum_to_4pi() {
        for n in [1usize, 2, 3, 8, 64, 257] {
            let mut s = 0.0;
            for j in 0..n {
                for i in 0..n {
                    s += CubeMap::texel_solid_angle(n, i, j);
                }
            }
            let err = (6.0 * s - 4.0 * PI).abs();
            assert!(err < 1e-9, "n = {n}: 6·Σ = {}, error {err:e}", 6.0 * s);
        }
        let t = solid_angle_table(33);
        assert!((6.0 * t.iter().sum::<f64>() - 4.0 * PI).abs() < 1e-9);
        assert!((t[5 * 33 + 7] - CubeMap::texel_solid_angle(33, 7, 5)).abs() < 1e-15);
        // One face is 4π/6; the centre texel of a large face is ≈ (2/N)².
        let n = 1001;
        let c = CubeMap::texel_solid_angle(n, 500, 500);
        assert!((c / (2.0 / n as f64).powi(2) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn texel_dirs_round_trip_to_their_texel() {
        let n = 7;
        for face in 0..6 {
            for j in 0..n {
                for i in 0..n {
                    let d = CubeMap::texel_dir(n, face, i, j);
                    assert!((d.length() - 1.0).abs() < 1e-12);
                    let (f, s, t) = face_coords(d);
                    assert_eq!(f, face);
                    assert!((s - (i as f64 + 0.5) / n as f64).abs() < 1e-12);
                    assert!((t - (j as f64 + 0.5) / n as f64).abs() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn vulkan_face_orientation() {
        // Spot checks against the Vulkan table: +X at s=0 is towards +z, t=0 towards +y.
        let (f, s, t) = face_coords(DVec3::new(1.0, 0.5, 0.5));
        assert_eq!((f, s, t), (POS_X, 0.25, 0.25));
        let (f, s, t) = face_coords(DVec3::new(0.5, 1.0, 0.5));
        assert_eq!((f, s, t), (POS_Y, 0.75, 0.75));
        let (f, s, t) = face_coords(DVec3::new(0.5, -1.0, 0.5));
        assert_eq!((f, s, t), (NEG_Y, 0.75, 0.25));
        let (f, s, t) = face_coords(DVec3::new(0.5, 0.5, -1.0));
        assert_eq!((f, s, t), (NEG_Z, 0.25, 0.25));
        let (f, s, t) = face_coords(DVec3::new(-1.0, 0.5, 0.5));
        assert_eq!((f, s, t), (NEG_X, 0.75, 0.25));
        let (f, s, t) = face_coords(DVec3::new(0.5, 0.5, 1.0));
        assert_eq!((f, s, t), (POS_Z, 0.75, 0.25));
    }

    #[test]
    fn edge_wrap_reads_the_geometric_neighbour() {
        // Every out-of-face tap (one coordinate out by k ≤ 2) maps to the texel whose centre
        // is nearest to the tap's extended-plane direction rotated onto the neighbour face.
        let n = 6;
        for face in 0..6 {
            for along in 0..n as i64 {
                for k in 1..=2i64 {
                    for (i, j) in [
                        (-k, along),
                        (n as i64 - 1 + k, along),
                        (along, -k),
                        (along, n as i64 - 1 + k),
                    ] {
                        let (f2, a, b) = wrap_edge(n, face, i, j);
                        assert_ne!(f2, face);
                        // The neighbour texel is adjacent (across the edge) to the tap's
                        // along-edge texel on the own face: their centres are (k−½ + ½)
                        // texel widths apart in arc, roughly k·2/N rad.
                        let own = CubeMap::texel_dir(
                            n,
                            face,
                            i.clamp(0, n as i64 - 1) as usize,
                            j.clamp(0, n as i64 - 1) as usize,
                        );
                        let other = CubeMap::texel_dir(n, f2, a, b);
                        let ang = own.dot(other).clamp(-1.0, 1.0).acos();
                        let expect = k as f64 * (2.0 / n as f64) * 0.8;
                        assert!(
                            ang < expect * 1.5 && ang > expect * 0.4,
                            "face {face} tap ({i},{j}) → face {f2} ({a},{b}): {ang} rad"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn bilinear_reproduces_constant_and_is_continuous_across_seams() {
        let c = CubeMap::from_fn(8, |_| [2.0, 3.0, 4.0]).unwrap();
        for d in [
            DVec3::X,
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(-0.3, 1.0, 1.0),
        ] {
            assert_eq!(c.bilinear(d), [2.0, 3.0, 4.0]);
        }
        // A linear function of direction: the lookup just on each side of an edge agrees.
        let a = DVec3::new(0.3, -0.5, 0.7);
        let m = CubeMap::from_fn(16, |d| {
            let v = 1.0 + d.dot(a);
            [v, v, v]
        })
        .unwrap();
        for (p, q) in [
            (
                DVec3::new(1.0, 0.3, 1.0 - 1e-9),
                DVec3::new(1.0 - 1e-9, 0.3, 1.0),
            ),
            (
                DVec3::new(0.2, 1.0, -1.0 + 1e-9),
                DVec3::new(0.2, 1.0 - 1e-9, -1.0),
            ),
            (
                DVec3::new(-1.0, -1.0 + 1e-9, 0.4),
                DVec3::new(-1.0 + 1e-9, -1.0, 0.4),
            ),
        ] {
            let (x, y) = (m.bilinear(p)[0], m.bilinear(q)[0]);
            assert!((x - y).abs() < 1e-6, "{x} vs {y}");
        }
    }

    #[test]
    fn equirect_round_trip_of_a_smooth_map() {
        let a = DVec3::new(0.2, 0.6, -0.3);
        let f = |d: DVec3| 1.0 + d.dot(a) + 0.3 * d.x * d.z;
        let (w, h) = (128, 64);
        let data = (0..w * h)
            .map(|k| [f(EquirectMap::pixel_dir(w, h, k % w, k / w)) as f32; 3])
            .collect();
        let m = EquirectMap::new(w, h, data).unwrap();
        let cube = CubeMap::from_equirect(&m, 32).unwrap();
        let back = cube.to_equirect(w).unwrap();
        let mut worst: f64 = 0.0;
        for (k, v) in back.data.iter().enumerate() {
            let exact = f(EquirectMap::pixel_dir(w, h, k % w, k / w));
            worst = worst.max((v[0] as f64 - exact).abs());
        }
        assert!(worst < 5e-3, "round trip max error {worst}");
        let (i0, i1) = (m.integral()[0], cube.integral()[0]);
        assert!((i0 - i1).abs() < 1e-4 * i0, "{i0} vs {i1}");
        assert!(cube.to_equirect(3).is_err());
        assert!(cube.to_equirect(0).is_err());
    }

    proptest::proptest! {
        /// Lookups in any direction (zero, huge, denormal components) are finite and inside
        /// the range of the texels.
        #[test]
        fn lookups_are_finite_and_bounded(x in -1e6f64..1e6, y in -1e6f64..1e6, z in -1e-300f64..1e6) {
            let m = CubeMap::from_fn(4, |d| [2.0 + d.x, 2.0 + d.y, 2.0 + d.z]).unwrap();
            for d in [DVec3::new(x, y, z), DVec3::ZERO, DVec3::new(x, 0.0, 0.0)] {
                let v = m.bilinear(d);
                proptest::prop_assert!(v.iter().all(|c| c.is_finite() && *c >= 0.9 && *c <= 3.1), "{:?}", v);
            }
        }
    }

    #[test]
    fn rejects_bad_sizes() {
        assert!(CubeMap::new(0, Default::default()).is_err());
        let faces: [Vec<[f32; 3]>; 6] = std::array::from_fn(|_| vec![[0.0; 3]; 4]);
        assert!(CubeMap::new(3, faces.clone()).is_err());
        assert!(CubeMap::new(2, faces).is_ok());
        assert!(CubeMap::from_fn(0, |_| [0.0; 3]).is_err());
    }
}
