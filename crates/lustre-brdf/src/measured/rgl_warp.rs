//! A bilinear 2-D distribution on the unit square whose table may depend on extra parameters,
//! interpolated multilinearly between the parameter nodes: a port to f64 of Mitsuba 3's
//! `Marginal2D<Float, Dimension, Continuous = true>` (mitsuba-renderer/mitsuba3,
//! `include/mitsuba/core/distr_2d.h`: constructor, `eval`, `sample_continuous`,
//! `invert_continuous`, `sample_segment`, `invert_segment`, and `Distribution2D::
//! interpolate_weights`). pbrt-v4's `PiecewiseLinear2D` (mmp/pbrt-v4, `src/pbrt/util/sampling.h`)
//! is the same algorithm.
//!
//! The table of one slice has `h` rows of `w` values (x fastest); the density is the bilinear
//! interpolant of the table over the unit square, with `w - 1` by `h - 1` patches. Sampling
//! inverts the continuous marginal CDF in y, then the conditional CDF in x, both exactly (the
//! CDF of a linear segment is a quadratic), so [`Marginal2D::sample`] produces exactly the
//! density [`Marginal2D::eval`] reports, and [`Marginal2D::invert`] is its inverse.
//!
//! One deliberate numerical difference from Mitsuba: the quadratic of `sample_segment` is
//! solved in the cancellation-free form t = 2s / (v0 + sqrt(v0² + 2s(v1 − v0))) for every
//! segment, where Mitsuba switches to the constant-density formula when |v0 − v1| < 1e-4 (v0 + v1)
//! (an f32 precaution that leaves a ~1e-4 mismatch between `sample` and `invert`).

/// A (possibly conditional) bilinear distribution on [0, 1]² (Mitsuba's `Marginal2D`).
#[derive(Clone, Debug)]
pub struct Marginal2D {
    w: usize,
    h: usize,
    /// Node values of each conditioning parameter (outermost first, as in the table layout).
    params: Vec<Vec<f64>>,
    /// Slice stride of each parameter (0 for a parameter with a single node).
    strides: Vec<usize>,
    /// Density values, one `w × h` slice per parameter node combination.
    data: Vec<f64>,
    /// Marginal CDF in y: `h - 1` entries per slice (empty when sampling is disabled).
    marg_cdf: Vec<f64>,
    /// Conditional CDFs in x: `h × (w - 1)` entries per slice (empty when sampling is disabled).
    cond_cdf: Vec<f64>,
    normalized: bool,
}

/// The up to 2^D slices (and their weights) that a parameter vector interpolates between.
struct Corners {
    n: usize,
    slice: [usize; 8],
    weight: [f64; 8],
}

/// The most conditioning parameters supported (Mitsuba instantiates 0, 2 and 3).
pub const MAX_PARAMS: usize = 3;

impl Marginal2D {
    /// Builds the distribution from `data`, laid out as `N0 × … × N(D−1) × h × w` (row-major,
    /// `w` fastest) where `Nk = params[k].len()`.
    ///
    /// With `normalize`, each slice is scaled to integrate to 1 over the unit square (a pdf);
    /// without it the values are kept as they are (an interpolant). `enable_sampling` builds the
    /// CDFs needed by [`Marginal2D::sample`] and [`Marginal2D::invert`]; as in Mitsuba it requires
    /// `normalize`. Errors (in words, for the caller to wrap with the file and field) on
    /// resolutions below 2, a table of the wrong length, non-finite or negative densities,
    /// parameters that are not finite and strictly increasing, and slices with no mass.
    pub fn new(
        data: &[f64],
        w: usize,
        h: usize,
        params: Vec<Vec<f64>>,
        normalize: bool,
        enable_sampling: bool,
    ) -> Result<Self, String> {
        if w < 2 || h < 2 {
            return Err(format!(
                "table resolution {w} x {h}: both must be at least 2"
            ));
        }
        if params.len() > MAX_PARAMS {
            return Err(format!(
                "{} conditioning parameters (at most {MAX_PARAMS})",
                params.len()
            ));
        }
        if enable_sampling && !normalize {
            return Err("sampling requires a normalized distribution".into());
        }
        let mut slices = 1usize;
        let mut strides = vec![0; params.len()];
        for (k, p) in params.iter().enumerate().rev() {
            if p.is_empty() {
                return Err(format!("parameter {k} has no nodes"));
            }
            if p.iter().any(|v| !v.is_finite()) {
                return Err(format!("parameter {k} has a non-finite node"));
            }
            if p.windows(2).any(|q| q[1] <= q[0]) {
                return Err(format!("parameter {k} nodes are not strictly increasing"));
            }
            strides[k] = if p.len() > 1 { slices } else { 0 };
            slices = slices
                .checked_mul(p.len())
                .ok_or_else(|| "parameter resolution overflows".to_string())?;
        }
        let n_data = w
            .checked_mul(h)
            .ok_or_else(|| "table size overflows".to_string())?;
        let expected = n_data
            .checked_mul(slices)
            .ok_or_else(|| "table size overflows".to_string())?;
        if data.len() != expected {
            return Err(format!(
                "table has {} values, expected {expected}",
                data.len()
            ));
        }
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(format!("value {i} is not finite ({})", data[i]));
        }
        if normalize {
            if let Some(i) = data.iter().position(|&v| v < 0.0) {
                return Err(format!("density value {i} is negative ({})", data[i]));
            }
        }

        let (scale_x, scale_y) = (0.5 / (w - 1) as f64, 0.5 / (h - 1) as f64);
        let n_marg = h - 1;
        let n_cond = h * (w - 1);
        let mut out = Vec::with_capacity(expected);
        let mut marg_cdf = Vec::new();
        let mut cond_cdf = Vec::new();
        if enable_sampling {
            marg_cdf.reserve(slices * n_marg);
            cond_cdf.reserve(slices * n_cond);
        }
        let mut row_sum = vec![0.0; h];
        for (s, slice) in data.chunks_exact(n_data).enumerate() {
            // Continuous conditional CDFs: running integral of each row's linear interpolant.
            let cond_start = cond_cdf.len();
            for (y, row) in slice.chunks_exact(w).enumerate() {
                let mut acc = 0.0;
                for x in 0..w - 1 {
                    acc += scale_x * (row[x] + row[x + 1]);
                    if enable_sampling {
                        cond_cdf.push(acc);
                    }
                }
                row_sum[y] = acc;
            }
            // Marginal CDF: running integral of the (linear in y) row integrals.
            let marg_start = marg_cdf.len();
            let mut acc = 0.0;
            for y in 0..h - 1 {
                acc += scale_y * (row_sum[y] + row_sum[y + 1]);
                if enable_sampling {
                    marg_cdf.push(acc);
                }
            }
            let norm = if normalize {
                if !acc.is_finite() || acc <= 0.0 {
                    return Err(format!("slice {s} has no mass (integral {acc})"));
                }
                1.0 / acc
            } else {
                1.0
            };
            if enable_sampling {
                cond_cdf[cond_start..].iter_mut().for_each(|v| *v *= norm);
                marg_cdf[marg_start..].iter_mut().for_each(|v| *v *= norm);
            }
            out.extend(slice.iter().map(|v| v * norm));
        }
        Ok(Marginal2D {
            w,
            h,
            params,
            strides,
            data: out,
            marg_cdf,
            cond_cdf,
            normalized: normalize,
        })
    }

    /// Table resolution (w, h): values per row and rows.
    pub fn size(&self) -> (usize, usize) {
        (self.w, self.h)
    }

    /// The node values of each conditioning parameter (outermost first).
    pub fn params(&self) -> &[Vec<f64>] {
        &self.params
    }

    /// The slice stride of each parameter (0 for a parameter with a single node).
    pub fn strides(&self) -> &[usize] {
        &self.strides
    }

    /// Every slice's (normalized, if requested) values, `w × h` per slice.
    pub fn data(&self) -> &[f64] {
        &self.data
    }

    /// The marginal CDFs in y, `h − 1` per slice (empty without sampling).
    pub fn marginal_cdf(&self) -> &[f64] {
        &self.marg_cdf
    }

    /// The conditional CDFs in x, `h × (w − 1)` per slice (empty without sampling).
    pub fn conditional_cdf(&self) -> &[f64] {
        &self.cond_cdf
    }

    /// Whether each slice was normalized to a density.
    pub fn is_normalized(&self) -> bool {
        self.normalized
    }

    /// The (normalized, if requested) table values of the slice at parameter node indices `idx`.
    pub fn slice(&self, idx: &[usize]) -> Option<&[f64]> {
        if idx.len() != self.params.len() {
            return None;
        }
        let mut s = 0;
        let mut stride = 1;
        for (k, p) in self.params.iter().enumerate().rev() {
            if idx[k] >= p.len() {
                return None;
            }
            s += idx[k] * stride;
            stride *= p.len();
        }
        let n = self.w * self.h;
        self.data.get(s * n..(s + 1) * n)
    }

    /// Mitsuba's `interpolate_weights`: for each parameter the node interval containing it
    /// (clamped to the ends) and linear weights, expanded into the slices to blend.
    fn corners(&self, param: &[f64]) -> Corners {
        let mut c = Corners {
            n: 1,
            slice: [0; 8],
            weight: [0.0; 8],
        };
        c.weight[0] = 1.0;
        for (k, nodes) in self.params.iter().enumerate() {
            if nodes.len() == 1 {
                continue;
            }
            let x = param.get(k).copied().unwrap_or(0.0);
            // find_interval: the last i in [0, n-2] with nodes[i] < x.
            let i = nodes
                .partition_point(|&v| v < x)
                .saturating_sub(1)
                .min(nodes.len() - 2);
            let (p0, p1) = (nodes[i], nodes[i + 1]);
            let mut t = ((x - p0) / (p1 - p0)).clamp(0.0, 1.0);
            if !t.is_finite() {
                t = 0.0;
            }
            let n = c.n;
            for j in 0..n {
                let (s, wgt) = (c.slice[j], c.weight[j]);
                c.slice[j] = s + self.strides[k] * i;
                c.weight[j] = wgt * (1.0 - t);
                c.slice[n + j] = s + self.strides[k] * (i + 1);
                c.weight[n + j] = wgt * t;
            }
            c.n = 2 * n;
        }
        c
    }

    /// Parameter-interpolated entry `idx` of a table with `per_slice` entries per slice.
    #[inline]
    fn lookup(table: &[f64], per_slice: usize, c: &Corners, idx: usize) -> f64 {
        let mut v = 0.0;
        for j in 0..c.n {
            if c.weight[j] != 0.0 {
                v += c.weight[j]
                    * table
                        .get(c.slice[j] * per_slice + idx)
                        .copied()
                        .unwrap_or(0.0);
            }
        }
        v
    }

    /// Patch index and position inside it for a point of the unit square.
    #[inline]
    fn locate(&self, pos: (f64, f64)) -> ((usize, usize), (f64, f64)) {
        let sx = pos.0.clamp(0.0, 1.0) * (self.w - 1) as f64;
        let sy = pos.1.clamp(0.0, 1.0) * (self.h - 1) as f64;
        // `as usize` saturates (NaN → 0), so no index can leave the table.
        let ix = (sx as usize).min(self.w - 2);
        let iy = (sy as usize).min(self.h - 2);
        ((ix, iy), (sx - ix as f64, sy - iy as f64))
    }

    /// The four corner values of patch (ix, iy).
    #[inline]
    fn patch(&self, c: &Corners, ix: usize, iy: usize) -> [f64; 4] {
        let n = self.w * self.h;
        let o = iy * self.w + ix;
        [
            Self::lookup(&self.data, n, c, o),
            Self::lookup(&self.data, n, c, o + 1),
            Self::lookup(&self.data, n, c, o + self.w),
            Self::lookup(&self.data, n, c, o + self.w + 1),
        ]
    }

    /// The bilinear interpolant at `pos` (Mitsuba `Marginal2D::eval`): the density when the
    /// distribution is normalized, the interpolated table value otherwise.
    pub fn eval(&self, pos: (f64, f64), param: &[f64]) -> f64 {
        let c = self.corners(param);
        let ((ix, iy), (fx, fy)) = self.locate(pos);
        let [v00, v10, v01, v11] = self.patch(&c, ix, iy);
        lerp(lerp(v00, v10, fx), lerp(v01, v11, fx), fy)
    }

    /// Warps a uniform point of [0, 1]² to the distribution (Mitsuba `sample_continuous`):
    /// returns the point and its density. Returns `None` when sampling was not enabled.
    pub fn sample(&self, u: (f64, f64), param: &[f64]) -> Option<((f64, f64), f64)> {
        if self.marg_cdf.is_empty() {
            return None;
        }
        let (w, h) = (self.w, self.h);
        let n_cond = h * (w - 1);
        let n_marg = h - 1;
        let c = self.corners(param);
        let lo = f64::EPSILON;
        let (mut sx, mut sy) = (u.0.clamp(lo, 1.0 - lo), u.1.clamp(lo, 1.0 - lo));
        if !sx.is_finite() || !sy.is_finite() {
            sx = 0.5;
            sy = 0.5;
        }
        let marg = |i: usize| Self::lookup(&self.marg_cdf, n_marg, &c, i);
        if !self.normalized {
            sy *= marg(n_marg - 1);
        }
        // Row: first index in [0, n_marg - 1] whose CDF is not below sy.
        let row = search(n_marg - 1, |i| marg(i) < sy);
        if row > 0 {
            sy -= marg(row - 1);
        }
        let off = row * (w - 1);
        let r0 = Self::lookup(&self.cond_cdf, n_cond, &c, off + (w - 1) - 1);
        let r1 = Self::lookup(&self.cond_cdf, n_cond, &c, off + 2 * (w - 1) - 1);
        let ty = sample_segment(sy, (h - 1) as f64, r0, r1);
        sx *= lerp(r0, r1, ty);
        let cond = |i: usize| {
            let v0 = Self::lookup(&self.cond_cdf, n_cond, &c, off + i);
            let v1 = Self::lookup(&self.cond_cdf, n_cond, &c, off + (w - 1) + i);
            lerp(v0, v1, ty)
        };
        // Column: as Mitsuba, but searched in [0, w - 2] so that roundoff past the row total
        // stays inside the last patch.
        let col = search(w - 2, |i| cond(i) < sx);
        if col > 0 {
            sx -= cond(col - 1);
        }
        let [v00, v10, v01, v11] = self.patch(&c, col, row);
        let (c0, c1) = (lerp(v00, v01, ty), lerp(v10, v11, ty));
        let tx = sample_segment(sx, (w - 1) as f64, c0, c1);
        let p = (
            (col as f64 + tx) / (w - 1) as f64,
            (row as f64 + ty) / (h - 1) as f64,
        );
        Some((p, lerp(c0, c1, tx)))
    }

    /// The inverse of [`Marginal2D::sample`] (Mitsuba `invert_continuous`): maps a point of the
    /// unit square back to the uniform variates, with the density at the point. Returns `None`
    /// when sampling was not enabled.
    pub fn invert(&self, pos: (f64, f64), param: &[f64]) -> Option<((f64, f64), f64)> {
        if self.marg_cdf.is_empty() {
            return None;
        }
        let (w, h) = (self.w, self.h);
        let n_cond = h * (w - 1);
        let n_marg = h - 1;
        let c = self.corners(param);
        let ((ix, iy), (fx, fy)) = self.locate(pos);
        let [v00, v10, v01, v11] = self.patch(&c, ix, iy);
        let (c0, c1) = (lerp(v00, v01, fy), lerp(v10, v11, fy));
        let pdf = lerp(c0, c1, fx);
        let mut sx = invert_segment(fx, 1.0 / (w - 1) as f64, c0, c1);
        let off = iy * (w - 1);
        if ix > 0 {
            let v0 = Self::lookup(&self.cond_cdf, n_cond, &c, off + ix - 1);
            let v1 = Self::lookup(&self.cond_cdf, n_cond, &c, off + (w - 1) + ix - 1);
            sx += lerp(v0, v1, fy);
        }
        let r0 = Self::lookup(&self.cond_cdf, n_cond, &c, off + (w - 1) - 1);
        let r1 = Self::lookup(&self.cond_cdf, n_cond, &c, off + 2 * (w - 1) - 1);
        let row_total = lerp(r0, r1, fy);
        sx = if row_total > 0.0 { sx / row_total } else { 0.0 };
        let mut sy = invert_segment(fy, 1.0 / (h - 1) as f64, r0, r1);
        if iy > 0 {
            sy += Self::lookup(&self.marg_cdf, n_marg, &c, iy - 1);
        }
        if !self.normalized {
            let total = Self::lookup(&self.marg_cdf, n_marg, &c, n_marg - 1);
            sy = if total > 0.0 { sy / total } else { 0.0 };
        }
        Some(((sx.clamp(0.0, 1.0), sy.clamp(0.0, 1.0)), pdf))
    }
}

#[inline]
fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// drjit's `binary_search(0, end, pred)`: the first index in [0, end] where `pred` is false
/// (`end` when it holds everywhere below; `pred(end)` is never evaluated).
fn search(end: usize, pred: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (0usize, end);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if pred(mid) {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Mitsuba's `sample_segment`: the position t ∈ [0, 1] in a segment of width 1/`inv_width`
/// with linear density v0 → v1 at which the integral from 0 equals `s`, i.e. the root of
/// (v1 − v0) t²/2 + v0 t = s·inv_width, in cancellation-free form.
#[inline]
fn sample_segment(s: f64, inv_width: f64, v0: f64, v1: f64) -> f64 {
    let s = s * inv_width;
    let disc = (v0 * v0 + 2.0 * s * (v1 - v0)).max(0.0);
    let denom = v0 + disc.sqrt();
    if denom > 0.0 {
        (2.0 * s / denom).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// Mitsuba's `invert_segment`: the integral of the linear density v0 → v1 over [0, t] of a
/// segment of the given width.
#[inline]
fn invert_segment(t: f64, width: f64, v0: f64, v1: f64) -> f64 {
    t * lerp(v0, v1, 0.5 * t) * width
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> Marginal2D {
        // 3 x 2 table, one parameter with two nodes.
        let data = [1.0, 2.0, 4.0, 0.5, 1.0, 3.0, 2.0, 2.0, 2.0, 0.0, 1.0, 5.0];
        Marginal2D::new(&data, 3, 2, vec![vec![0.0, 1.0]], true, true).expect("valid table")
    }

    #[test]
    fn sample_inverts_and_reports_eval() {
        let m = table();
        for &p in &[0.0, 0.3, 1.0] {
            for k in 0..50 {
                let (u1, u2) = crate::sampling::hammersley(k, 50);
                let (x, pdf) = m.sample((u1, u2), &[p]).expect("sampling enabled");
                assert!((pdf - m.eval(x, &[p])).abs() < 1e-12, "{pdf}");
                let (u, pdf2) = m.invert(x, &[p]).expect("sampling enabled");
                assert!(
                    (u.0 - u1).abs() < 1e-10 && (u.1 - u2).abs() < 1e-10,
                    "{u:?} vs {u1} {u2}"
                );
                assert!((pdf - pdf2).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn density_integrates_to_one() {
        let m = table();
        let rule = crate::numeric::GaussRule::new(4);
        for &p in &[0.0, 0.6, 1.0] {
            // Panels aligned with the patches: the bilinear interpolant is integrated exactly.
            let v = rule.integrate(0.0, 1.0, 1, |y| {
                rule.integrate(0.0, 1.0, 2, |x| m.eval((x, y), &[p]))
            });
            assert!((v - 1.0).abs() < 1e-12, "{v}");
        }
    }

    #[test]
    fn rejects_bad_tables() {
        assert!(Marginal2D::new(&[1.0; 4], 1, 4, vec![], true, true).is_err());
        assert!(Marginal2D::new(&[1.0; 3], 2, 2, vec![], true, true).is_err());
        assert!(Marginal2D::new(&[0.0; 4], 2, 2, vec![], true, true).is_err());
        assert!(Marginal2D::new(&[1.0, -1.0, 1.0, 1.0], 2, 2, vec![], true, true).is_err());
        assert!(Marginal2D::new(&[1.0; 8], 2, 2, vec![vec![1.0, 1.0]], true, true).is_err());
        assert!(Marginal2D::new(&[f64::NAN; 4], 2, 2, vec![], false, false).is_err());
    }
}
