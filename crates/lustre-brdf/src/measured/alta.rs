//! ALTA data files (belcour/alta): `#` header lines, then one row per sample. Only the isotropic
//! 3D input parameterization `ISOTROPIC_TL_TV_PROJ_DPHI` with one output value is read, as in the
//! CEA retro-reflection measurements in `shared/data/measured/goniometric/`.
//!
//! # Meaning of the coordinates (ALTA `sources/core/params.h`, `params.cpp`)
//!
//! `params.h` documents ISOTROPIC_TL_TV_PROJ_DPHI as "3D Parametrization where the phi component
//! is projected. Coordinates are: [θl, θv cos(Δφ), θv sin(Δφ)]", and `params::to_cartesian`
//! builds the light L = (sin θl, 0, cos θl) (azimuth 0) and the view
//! V = (x/θv · sin θv, y/θv · sin θv, cos θv) with θv = √(x² + y²): (x, y) are the polar
//! coordinates (θv, Δφ = φv − φl) of the view direction, flattened onto a plane. x = −θl, y = 0
//! is the mirror direction and x = +θl, y = 0 the retro-reflection direction. ALTA's light is
//! our `wi`, its view our `wo`.
//!
//! # Output unit
//!
//! `params.h`: INV_STERADIAN: "Output values in inverse steradian (sr-1). This is the standard
//! definition for a BRDF." INV_STERADIAN_COSINE_FACTOR: "Output values in inverse steradian
//! (sr-1) weighted by the cosine factor of the output direction", i.e. value = f·cos θv (θv the
//! view, the outgoing direction). Supported: [`AltaUnit::InvSteradian`] and
//! [`AltaUnit::InvSteradianCosineFactor`]; ENERGY, RGB_COLOR, XYZ_COLOR and unknown or missing
//! `#PARAM_OUT` are errors unless the caller supplies the unit. (ALTA's own diffuse bootstrap in
//! `diffuse_function::bootstrap` divides cosine-weighted data by cos θv·cos θl; we follow the
//! documented definition, one cosine of the outgoing direction.)
//!
//! # Reconstruction
//!
//! The rows come in a few θl slices (15°, 30°, 60° in the CEA files), each a scattered set in the
//! (x, y) plane: a polar grid (θv every 3°, Δφ every 10°, with occluded holes) overlaid with
//! fine polar grids (1° rings, 5° azimuths) around the mirror and retro directions. Within a
//! slice the value is interpolated by inverse-distance weighting (Shepard, power 2) of the
//! [`NEIGHBOURS`] nearest samples in the (x, y) plane, found through a bucket grid; it reproduces
//! every sample exactly. Between slices it is linear in θl, clamped to the first and last
//! slice outside their range. f = value / max(cos θv, [`ALTA_COS_FLOOR`]) for cosine-weighted
//! data.

use crate::bsdf::{cosine_pdf, cosine_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{Error, Result};
use crate::frame::{phi, theta};
use crate::rgb::Rgb;
use glam::DVec3;
use std::f64::consts::FRAC_PI_2;
use std::path::{Path, PathBuf};

/// Samples blended by the inverse-distance interpolation within a slice.
pub const NEIGHBOURS: usize = 6;

/// The smallest cos θv that cosine-weighted values are divided by: cos 87°, the last ring below
/// grazing in the CEA files (their 90° ring has cos θv = 0).
pub const ALTA_COS_FLOOR: f64 = 0.052_335_956_242_943_835;

/// The bucket size of a slice's search grid in the (x, y) plane, radians.
pub const ALTA_CELL: f64 = 0.05;
/// The grid covers [−ALTA_HALF_EXTENT, ALTA_HALF_EXTENT]² (every (x, y) of a view above the
/// surface: θv < π/2).
pub const ALTA_HALF_EXTENT: f64 = FRAC_PI_2 + 1e-6;
const CELL: f64 = ALTA_CELL;
const HALF_EXTENT: f64 = ALTA_HALF_EXTENT;

/// Cells per axis of a slice's search grid.
pub fn alta_grid_cells() -> usize {
    ((2.0 * HALF_EXTENT) / CELL).ceil() as usize
}

/// The most candidates a leaf of [`AltaCandidates`] holds unless it is at [`ALTA_MAX_DEPTH`].
pub const ALTA_LEAF_CANDIDATES: usize = 32;
/// How many times a grid cell of [`AltaCandidates`] may be split into 4 × 4 children.
pub const ALTA_MAX_DEPTH: usize = 3;
/// The `count` of a split node of [`AltaCandidates`] (its `first` is its first child).
pub const ALTA_SPLIT: u32 = u32::MAX;

/// One θl slice laid out for a search without rings (the GPU twin's, `lustre_gpu`'s
/// `measured::pack_alta`): nodes covering the (x, y) plane, each listing every sample that can
/// be among the [`NEIGHBOURS`] nearest of a point inside it. With c a node's centre, h its half
/// diagonal and d₆ the distance from c to its 6th nearest sample, a point q of the node
/// (|q − c| ≤ h) has its 6 nearest within d₆ + h of q, so within d₆ + 2h of c: the node lists
/// the samples within d₆ + 2h (+ 10⁻⁴ rad, for a query's rounding) of its centre. The first
/// [`alta_grid_cells`]² nodes are the search grid's cells (row-major, [`ALTA_CELL`] from
/// −[`ALTA_HALF_EXTENT`]); a node whose list would exceed [`ALTA_LEAF_CANDIDATES`] (where the
/// measurement is dense, around the mirror and retro directions) is split into 4 × 4 children
/// (row-major, consecutive), at most [`ALTA_MAX_DEPTH`] times. Nodes outside the disc of the
/// views above the surface (radius π/2) list none.
#[derive(Clone, Debug, PartialEq)]
pub struct AltaCandidates {
    /// The slice's θl (radians).
    pub theta_l: f64,
    /// Per node, (first, count): its candidates `points[first .. first + count]`, or, with
    /// count [`ALTA_SPLIT`], its 16 children `nodes[first .. first + 16]`.
    pub nodes: Vec<[u32; 2]>,
    /// The candidates (x, y, value in the file's unit), leaf after leaf.
    pub points: Vec<[f64; 3]>,
}

impl AltaCandidates {
    /// The candidates of the leaf holding (x, y) (clamped to the grid), walked down as
    /// `alta_eval` walks it.
    pub fn leaf(&self, x: f64, y: f64) -> &[[f64; 3]] {
        let n = alta_grid_cells();
        let cell = |v: f64| (((v + HALF_EXTENT) / CELL).floor().max(0.0) as usize).min(n - 1);
        let (cx, cy) = (cell(x), cell(y));
        let mut node = self.nodes[cy * n + cx];
        let mut x0 = -HALF_EXTENT + cx as f64 * CELL;
        let mut y0 = -HALF_EXTENT + cy as f64 * CELL;
        let mut size = CELL;
        while node[1] == ALTA_SPLIT {
            size /= 4.0;
            let sub = |v: f64, o: f64| (((v - o) / size).floor().max(0.0) as usize).min(3);
            let (sx, sy) = (sub(x, x0), sub(y, y0));
            x0 += sx as f64 * size;
            y0 += sy as f64 * size;
            node = self.nodes[node[0] as usize + 4 * sy + sx];
        }
        &self.points[node[0] as usize..(node[0] + node[1]) as usize]
    }
}

/// What an ALTA table's values are (`#PARAM_OUT`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AltaUnit {
    /// `INV_STERADIAN`: the BRDF f in 1/sr.
    InvSteradian,
    /// `INV_STERADIAN_COSINE_FACTOR`: f·cos θv (cosine of the outgoing/view direction).
    InvSteradianCosineFactor,
}

impl AltaUnit {
    /// The ALTA name of the unit.
    pub fn alta_name(self) -> &'static str {
        match self {
            AltaUnit::InvSteradian => "INV_STERADIAN",
            AltaUnit::InvSteradianCosineFactor => "INV_STERADIAN_COSINE_FACTOR",
        }
    }
}

/// One θl slice: scattered (x, y, value) samples and a bucket grid over them.
#[derive(Clone, Debug)]
struct Slice {
    theta_l: f64,
    pts: Vec<[f64; 3]>,
    /// Per bucket: start offset into `order` (CSR), `n_cells² + 1` entries.
    starts: Vec<usize>,
    order: Vec<usize>,
    n_cells: usize,
}

impl Slice {
    fn new(theta_l: f64, pts: Vec<[f64; 3]>) -> Self {
        let n_cells = alta_grid_cells();
        let cell_of = |x: f64, y: f64| -> usize {
            let cx = (((x + HALF_EXTENT) / CELL) as usize).min(n_cells - 1);
            let cy = (((y + HALF_EXTENT) / CELL) as usize).min(n_cells - 1);
            cy * n_cells + cx
        };
        let mut counts = vec![0usize; n_cells * n_cells + 1];
        for p in &pts {
            counts[cell_of(p[0], p[1]) + 1] += 1;
        }
        for k in 1..counts.len() {
            counts[k] += counts[k - 1];
        }
        let starts = counts.clone();
        let mut fill = counts;
        let mut order = vec![0usize; pts.len()];
        for (i, p) in pts.iter().enumerate() {
            let c = cell_of(p[0], p[1]);
            order[fill[c]] = i;
            fill[c] += 1;
        }
        Slice {
            theta_l,
            pts,
            starts,
            order,
            n_cells,
        }
    }

    /// The slice's [`AltaCandidates`].
    fn candidates(&self) -> AltaCandidates {
        let n = self.n_cells;
        let mut nodes: Vec<[u32; 2]> = vec![[0, 0]; n * n];
        let mut points: Vec<[f64; 3]> = Vec::new();
        // (node, corner, size, depth), breadth first.
        let mut queue: std::collections::VecDeque<(usize, [f64; 2], f64, usize)> = (0..n * n)
            .map(|k| {
                let corner = [
                    -HALF_EXTENT + (k % n) as f64 * CELL,
                    -HALF_EXTENT + (k / n) as f64 * CELL,
                ];
                (k, corner, CELL, 0)
            })
            .collect();
        let mut d2: Vec<f64> = Vec::with_capacity(self.pts.len());
        let mut sorted: Vec<f64> = Vec::with_capacity(self.pts.len());
        while let Some((k, corner, size, depth)) = queue.pop_front() {
            let h = size * std::f64::consts::SQRT_2 / 2.0;
            let c = [corner[0] + size / 2.0, corner[1] + size / 2.0];
            if (c[0] * c[0] + c[1] * c[1]).sqrt() - h > FRAC_PI_2 || self.pts.is_empty() {
                continue;
            }
            d2.clear();
            d2.extend(
                self.pts
                    .iter()
                    .map(|p| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)),
            );
            sorted.clear();
            sorted.extend_from_slice(&d2);
            let m = NEIGHBOURS.min(sorted.len());
            sorted.select_nth_unstable_by(m - 1, f64::total_cmp);
            let reach = sorted[m - 1].sqrt() + 2.0 * h + 1e-4;
            let within = d2.iter().filter(|&&d| d <= reach * reach).count();
            if within > ALTA_LEAF_CANDIDATES && depth < ALTA_MAX_DEPTH {
                let first = nodes.len();
                nodes[k] = [first as u32, ALTA_SPLIT];
                nodes.extend(std::iter::repeat_n([0, 0], 16));
                let s = size / 4.0;
                for j in 0..16 {
                    let child = [
                        corner[0] + (j % 4) as f64 * s,
                        corner[1] + (j / 4) as f64 * s,
                    ];
                    queue.push_back((first + j, child, s, depth + 1));
                }
                continue;
            }
            nodes[k] = [points.len() as u32, within as u32];
            points.extend(
                self.pts
                    .iter()
                    .zip(&d2)
                    .filter(|(_, &d)| d <= reach * reach)
                    .map(|(p, _)| *p),
            );
        }
        AltaCandidates {
            theta_l: self.theta_l,
            nodes,
            points,
        }
    }

    /// Shepard interpolation of the `NEIGHBOURS` nearest samples to (x, y).
    fn value(&self, x: f64, y: f64) -> f64 {
        let n = self.n_cells as isize;
        let cx = (((x + HALF_EXTENT) / CELL).floor() as isize).clamp(0, n - 1);
        let cy = (((y + HALF_EXTENT) / CELL).floor() as isize).clamp(0, n - 1);
        let mut best: Vec<(f64, f64)> = Vec::with_capacity(NEIGHBOURS + 1); // (d², value)
        for r in 0..n {
            // Every point outside rings 0..r is at least (r)·CELL − (offset in cell) away; a
            // safe lower bound is (r − 1)·CELL.
            if best.len() == NEIGHBOURS {
                let lim = ((r - 1).max(0) as f64) * CELL;
                if best[NEIGHBOURS - 1].0 <= lim * lim {
                    break;
                }
            }
            for iy in (cy - r)..=(cy + r) {
                for ix in (cx - r)..=(cx + r) {
                    if (iy - cy).abs() != r && (ix - cx).abs() != r {
                        continue; // interior of the ring, already visited
                    }
                    if ix < 0 || iy < 0 || ix >= n || iy >= n {
                        continue;
                    }
                    let c = (iy * n + ix) as usize;
                    for &i in &self.order[self.starts[c]..self.starts[c + 1]] {
                        let p = self.pts[i];
                        let d2 = (p[0] - x).powi(2) + (p[1] - y).powi(2);
                        if best.len() < NEIGHBOURS || d2 < best[best.len() - 1].0 {
                            let at = best.partition_point(|b| b.0 <= d2);
                            best.insert(at, (d2, p[2]));
                            best.truncate(NEIGHBOURS);
                        }
                    }
                }
            }
        }
        match best.first() {
            None => 0.0,
            Some(&(d2, v)) if d2 < 1e-24 => v,
            Some(_) => {
                let (mut num, mut den) = (0.0, 0.0);
                for &(d2, v) in &best {
                    num += v / d2;
                    den += 1.0 / d2;
                }
                num / den
            }
        }
    }
}

/// An ALTA table in `ISOTROPIC_TL_TV_PROJ_DPHI`, evaluated as an isotropic BRDF.
#[derive(Clone, Debug)]
pub struct AltaTable {
    /// The file the table came from.
    pub path: PathBuf,
    /// `#SAMPLE` (or the file stem).
    pub name: String,
    unit: AltaUnit,
    slices: Vec<Slice>,
    rows: usize,
    /// [`AltaTable::candidates`], built on first use (0.3 s a table) and kept: a scene
    /// uploads its tables to the GPU once per pass.
    candidates: std::sync::OnceLock<Vec<AltaCandidates>>,
}

impl AltaTable {
    /// Reads an ALTA file; `unit_override`, when given, replaces (or supplies) `#PARAM_OUT`.
    pub fn read(path: &Path, unit_override: Option<AltaUnit>) -> Result<Self> {
        let bytes = crate::error::read_file(path)?;
        Self::parse(path, &bytes, unit_override)
    }

    /// Parses an ALTA file from memory; `path` names it in messages.
    pub fn parse(path: &Path, bytes: &[u8], unit_override: Option<AltaUnit>) -> Result<Self> {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| Error::format(path, format!("not UTF-8 text ({e})")))?;
        let mut dim: Option<(usize, usize)> = None;
        let mut param_in: Option<String> = None;
        let mut param_out: Option<String> = None;
        let mut name: Option<String> = None;
        let mut rows: Vec<[f64; 4]> = Vec::new();
        for (i, raw) in text.lines().enumerate() {
            let no = i + 1;
            let line = raw.trim();
            if line.is_empty() {
                continue;
            }
            if let Some(h) = line.strip_prefix('#') {
                let mut toks = h.split_whitespace();
                match toks.next().unwrap_or("") {
                    "DIM" => {
                        let mut num = || -> Option<usize> { toks.next()?.parse().ok() };
                        match (num(), num()) {
                            (Some(a), Some(b)) => dim = Some((a, b)),
                            _ => {
                                return Err(Error::format(
                                    path,
                                    format!("line {no}: bad #DIM {h:?}"),
                                ))
                            }
                        }
                    }
                    "PARAM_IN" => param_in = toks.next().map(str::to_string),
                    "PARAM_OUT" => param_out = toks.next().map(str::to_string),
                    "SAMPLE" => {
                        let rest = h.trim_start().strip_prefix("SAMPLE").unwrap_or("");
                        name = Some(rest.trim().trim_matches('"').to_string());
                    }
                    "VS" if toks.next() != Some("0") => {
                        return Err(Error::format(
                            path,
                            format!(
                                "line {no}: vertical segments ({h}) are not supported; only #VS 0"
                            ),
                        ));
                    }
                    // #VS 0 and other `#` lines (#ORIGIN, #URL, #CMD, comments) carry no data.
                    _ => {}
                }
                continue;
            }
            // A data row: check the header first.
            if rows.is_empty() {
                match param_in.as_deref() {
                    Some("ISOTROPIC_TL_TV_PROJ_DPHI") => {}
                    Some(other) => {
                        return Err(Error::format(
                            path,
                            format!("unsupported #PARAM_IN {other}; this reader knows ISOTROPIC_TL_TV_PROJ_DPHI"),
                        ))
                    }
                    None => return Err(Error::format(path, "missing #PARAM_IN before the data")),
                }
                match dim {
                    Some((3, 1)) => {}
                    Some((a, b)) => {
                        return Err(Error::format(
                            path,
                            format!("#DIM {a} {b}: ISOTROPIC_TL_TV_PROJ_DPHI with one output needs #DIM 3 1"),
                        ))
                    }
                    None => return Err(Error::format(path, "missing #DIM before the data")),
                }
            }
            let toks: Vec<&str> = line.split_whitespace().collect();
            if toks.len() != 4 {
                return Err(Error::format(
                    path,
                    format!(
                        "line {no}: {} fields, #DIM 3 1 needs 4 (theta_l x y value)",
                        toks.len()
                    ),
                ));
            }
            let mut r = [0.0; 4];
            for k in 0..4 {
                r[k] = toks[k].parse::<f64>().map_err(|_| {
                    Error::format(path, format!("line {no}: {:?} is not a number", toks[k]))
                })?;
                if !r[k].is_finite() {
                    return Err(Error::format(
                        path,
                        format!("line {no}: field {} is not finite ({})", k + 1, toks[k]),
                    ));
                }
            }
            if !(0.0..=FRAC_PI_2 + 1e-9).contains(&r[0]) {
                return Err(Error::format(
                    path,
                    format!("line {no}: theta_l = {} outside [0, π/2]", r[0]),
                ));
            }
            if r[1].hypot(r[2]) > FRAC_PI_2 + 1e-6 {
                return Err(Error::format(
                    path,
                    format!("line {no}: view angle √(x²+y²) exceeds π/2"),
                ));
            }
            if r[3] < 0.0 {
                return Err(Error::format(
                    path,
                    format!("line {no}: negative value {}", r[3]),
                ));
            }
            rows.push(r);
        }
        if rows.is_empty() {
            return Err(Error::format(path, "no data rows"));
        }
        let unit = match (unit_override, param_out.as_deref()) {
            (Some(u), _) => u,
            (None, Some("INV_STERADIAN")) => AltaUnit::InvSteradian,
            (None, Some("INV_STERADIAN_COSINE_FACTOR")) => AltaUnit::InvSteradianCosineFactor,
            (None, Some(other)) => {
                return Err(Error::format(
                    path,
                    format!(
                        "unsupported #PARAM_OUT {other} (supported: INV_STERADIAN, INV_STERADIAN_COSINE_FACTOR); supply the unit to read it"
                    ),
                ))
            }
            (None, None) => {
                return Err(Error::format(
                    path,
                    "missing #PARAM_OUT: the unit of the values is unknown (supported: INV_STERADIAN, INV_STERADIAN_COSINE_FACTOR); supply the unit to read it",
                ))
            }
        };
        let n_rows = rows.len();
        rows.sort_by(|a, b| a[0].total_cmp(&b[0]));
        let mut slices = Vec::new();
        let mut start = 0;
        while start < rows.len() {
            let t = rows[start][0];
            let mut end = start;
            while end < rows.len() && (rows[end][0] - t).abs() <= 1e-9 {
                end += 1;
            }
            let pts = rows[start..end]
                .iter()
                .map(|r| [r[1], r[2], r[3]])
                .collect();
            slices.push(Slice::new(t, pts));
            start = end;
        }
        let name = name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        Ok(AltaTable {
            path: path.to_path_buf(),
            name,
            unit,
            slices,
            rows: n_rows,
            candidates: std::sync::OnceLock::new(),
        })
    }

    /// The unit of the values.
    pub fn unit(&self) -> AltaUnit {
        self.unit
    }

    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.rows
    }

    /// True when the table has no rows (never, for a parsed table).
    pub fn is_empty(&self) -> bool {
        self.rows == 0
    }

    /// Each slice's [`AltaCandidates`], θl increasing (built once per table).
    pub fn candidates(&self) -> &[AltaCandidates] {
        self.candidates
            .get_or_init(|| self.slices.iter().map(Slice::candidates).collect())
    }

    /// The θl of the slices, increasing (radians).
    pub fn theta_l_slices(&self) -> Vec<f64> {
        self.slices.iter().map(|s| s.theta_l).collect()
    }

    /// The interpolated raw value (in the file's unit) at ALTA coordinates (θl, x, y).
    pub fn value(&self, theta_l: f64, x: f64, y: f64) -> f64 {
        let s = &self.slices;
        let k = s.partition_point(|sl| sl.theta_l <= theta_l);
        if k == 0 {
            return s[0].value(x, y);
        }
        if k == s.len() {
            return s[k - 1].value(x, y);
        }
        let (a, b) = (&s[k - 1], &s[k]);
        let t = (theta_l - a.theta_l) / (b.theta_l - a.theta_l);
        if t <= 0.0 {
            return a.value(x, y);
        }
        (1.0 - t) * a.value(x, y) + t * b.value(x, y)
    }

    /// ALTA coordinates (θl, θv cos Δφ, θv sin Δφ) of a light `wi` and viewer `wo`.
    pub fn coordinates(wi: DVec3, wo: DVec3) -> [f64; 3] {
        let tv = theta(wo);
        let dphi = phi(wo) - phi(wi);
        [theta(wi), tv * dphi.cos(), tv * dphi.sin()]
    }

    /// The BRDF f(wi, wo) in 1/sr; zero when either direction is below the surface.
    pub fn brdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let [tl, x, y] = Self::coordinates(wi, wo);
        let v = self.value(tl, x, y);
        match self.unit {
            AltaUnit::InvSteradian => v,
            AltaUnit::InvSteradianCosineFactor => v / wo.z.max(ALTA_COS_FLOOR),
        }
    }
}

/// Isotropic, reflection only; sampled by cosine-weighted hemisphere sampling of wi.
impl Bsdf for AltaTable {
    fn name(&self) -> String {
        format!("ALTA {}", self.name)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        Rgb::splat(self.brdf(wi, wo))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        cosine_sample(self, wo, u1, u2, LobeFlags::GLOSSY)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        cosine_pdf(wi, wo)
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(false, false)
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::SplitMix64;

    /// `n` samples uniform in radius and angle over the views' disc, random values.
    fn disc_samples(rng: &mut SplitMix64, n: usize) -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| {
                let (r, a) = (
                    rng.next_f64() * FRAC_PI_2,
                    rng.next_f64() * std::f64::consts::TAU,
                );
                [r * a.cos(), r * a.sin(), rng.next_f64()]
            })
            .collect()
    }

    /// Shepard's weighting of the `NEIGHBOURS` nearest of `pts` to (x, y), by sorting them all.
    fn shepard_by_sorting(pts: &[[f64; 3]], x: f64, y: f64) -> f64 {
        let mut d: Vec<(f64, f64)> = pts
            .iter()
            .map(|p| ((p[0] - x).powi(2) + (p[1] - y).powi(2), p[2]))
            .collect();
        assert!(d.len() >= NEIGHBOURS, "({x}, {y}): {} candidates", d.len());
        d.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (num, den) = d[..NEIGHBOURS]
            .iter()
            .fold((0.0, 0.0), |(n, w), &(d2, v)| (n + v / d2, w + 1.0 / d2));
        num / den
    }

    /// The bucket search finds the same neighbours as a brute-force scan.
    #[test]
    fn bucket_search_matches_brute_force() {
        let mut rng = SplitMix64::new(2);
        let mut pts = disc_samples(&mut rng, 500);
        // A dense cluster, as around the retro direction.
        for k in 0..200 {
            let a = k as f64 * 0.1;
            pts.push([0.3 + 0.01 * a.cos(), 0.01 * a.sin(), rng.next_f64()]);
        }
        let s = Slice::new(0.3, pts.clone());
        for _ in 0..300 {
            let (r, a) = (
                rng.next_f64() * FRAC_PI_2,
                rng.next_f64() * std::f64::consts::TAU,
            );
            let (x, y) = (r * a.cos(), r * a.sin());
            let (v, want) = (s.value(x, y), shepard_by_sorting(&pts, x, y));
            assert!((v - want).abs() < 1e-12, "({x}, {y}): {v} vs {want}");
        }
        assert_eq!(s.value(pts[3][0], pts[3][1]), pts[3][2]);
    }

    /// Shepard's interpolation over a leaf's candidates alone gives the ring search's value, at
    /// points spread over the views' disc, cell corners included, and around a dense cluster
    /// (which splits its cells).
    #[test]
    fn leaf_candidates_hold_the_nearest_samples() {
        let mut rng = SplitMix64::new(9);
        let mut pts = disc_samples(&mut rng, 400);
        // 1° rings of 72 points around (−0.4, 0), as the CEA files' fine grids.
        for ring in 1..6 {
            for k in 0..72 {
                let (r, a) = (ring as f64 * 0.01745, k as f64 * 5f64.to_radians());
                pts.push([-0.4 + r * a.cos(), r * a.sin(), rng.next_f64()]);
            }
        }
        let s = Slice::new(0.5, pts);
        let c = s.candidates();
        let n = alta_grid_cells();
        assert!(c.nodes.len() > n * n, "no cell was split");
        let mut checked = 0;
        for k in 0..30_000 {
            let (x, y) = match k % 3 {
                // A cell corner.
                0 => (
                    -HALF_EXTENT + (rng.next_f64() * n as f64).floor() * CELL,
                    -HALF_EXTENT + (rng.next_f64() * n as f64).floor() * CELL,
                ),
                // In the cluster.
                1 => (
                    -0.4 + 0.2 * (rng.next_f64() - 0.5),
                    0.2 * (rng.next_f64() - 0.5),
                ),
                _ => (
                    (2.0 * rng.next_f64() - 1.0) * FRAC_PI_2,
                    (2.0 * rng.next_f64() - 1.0) * FRAC_PI_2,
                ),
            };
            if x * x + y * y >= FRAC_PI_2 * FRAC_PI_2 {
                continue;
            }
            let (v, want) = (s.value(x, y), shepard_by_sorting(c.leaf(x, y), x, y));
            assert!((v - want).abs() < 1e-12, "({x}, {y}): {v} vs {want}");
            checked += 1;
        }
        assert!(checked > 20_000, "{checked}");
        // The leaves stay short; the longest lie at the rings' centre, where ring 1's 72 points
        // are all equally near.
        let leaves: Vec<usize> = (c.nodes.iter())
            .filter(|e| e[1] != ALTA_SPLIT && e[1] > 0)
            .map(|e| e[1] as usize)
            .collect();
        let longest = leaves.iter().copied().max().unwrap_or(0);
        let mean = leaves.iter().sum::<usize>() as f64 / leaves.len() as f64;
        assert!(
            longest <= 80 && mean < 24.0,
            "leaves: longest {longest}, mean {mean}"
        );
    }
}
