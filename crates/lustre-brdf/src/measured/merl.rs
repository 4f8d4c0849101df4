//! The MERL isotropic BRDF table (Matusik et al. 2003, "A Data-Driven Reflectance Model").
//!
//! # File layout
//! Little-endian: three `i32` dimensions (90, 90, 180), then 90·90·180·3 `f64` values,
//! channel-major (all red values, then all green, then all blue). Within a channel the value of
//! bin (i, j, k) = (θh index, θd index, φd index) sits at `k + 180·(j + 90·i)`. A stored value
//! times the channel scale (1/1500, 1.15/1500, 1.66/1500) is the BRDF f_r in 1/sr. A file is
//! therefore exactly 12 + 90·90·180·3·8 = 34,992,012 bytes.
//!
//! # Indexing (as MERL's `BRDFRead.cpp`)
//! * θh (0..π/2) is sampled non-linearly: index coordinate u_h = sqrt(θh / (π/2)) · 90, i.e.
//!   sqrt(θh in degrees · 90); nearest index = ⌊u_h⌋ clamped to 0..=89.
//! * θd (0..π/2) linearly: u_d = θd / (π/2) · 90; nearest index = ⌊u_d⌋ clamped.
//! * φd: reciprocity (swapping wi and wo maps φd → φd + π) lets the table store only [0, π):
//!   φd < 0 is first folded to φd + π; u_φ = φd / π · 180; nearest index = ⌊u_φ⌋ clamped to
//!   0..=179.
//!
//! # Which point of a bin a stored value stands for: the lower edge
//! A stored value of bin (i, j, k) is the BRDF at the bin's *lower edge* ([`bin_node`]):
//! θh = (i/90)² · π/2, θd = j/90 · π/2, φd = k/180 · π. This is the convention of the real MERL
//! data as its users read it: the neural BRDFs of `nbrdf/merl_nbrdf.json` were trained on the
//! MERL tables with exactly these angles (asztr/Neural-BRDF, `binary_to_nbrdf/fastmerl.py`), and
//! `BRDFRead.cpp`'s lookup (⌊u⌋) maps a bin's lower edge to that bin. Evidence that the published
//! SGD fits use it too: `cargo run --release -p lustre-fit --example bin_convention` (results
//! in `docs/results/bin-convention.md`) measures, for all 100 materials, the published fits'
//! error against the tables under both conventions, and the parameter recovery from tables
//! made from the published parameters. [`BinConvention::Centre`] (the bin's centre,
//! (i + ½, j + ½, k + ½) in index coordinates, [`bin_center`]) is kept for that comparison.
//!
//! Trilinear interpolation ([`Interpolation::Trilinear`]) interpolates linearly in index
//! coordinates between the nodes of the table's convention; θ ends are clamped (the value at the
//! first/last node extends to the table's edge) and φd is periodic with period π (between the
//! last and the first bin the interpolation wraps around).
//!
//! # Missing bins
//! The measured MERL database marks unmeasured bins with negative values. By default they are
//! kept as missing ([`NegativeValues::Missing`]): they evaluate as 0, trilinear interpolation
//! renormalizes over the present corners, [`MerlTable::missing_count`] counts them and
//! [`MerlTable::coverage`] lets a fitter or an error metric mask them. A strict reader
//! ([`NegativeValues::Reject`], `--strict` on the command line) refuses such files.

use crate::bsdf::{cosine_pdf, cosine_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{write_atomic, Error, Result};
use crate::frame::{to_half_diff, HalfDiff};
use crate::rgb::Rgb;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;

/// Bins along θh.
/// The largest value a MERL table may hold (BRDF values in sr⁻¹): beyond it the table is read
/// as wrongly scaled, not as data. Models tabulated at grazing bins reach 10¹² (SGD nickel); the
/// albedo sums over a table stay finite far beyond 10³⁰.
pub const MAX_MEASURED_VALUE: f64 = 1e30;

pub const RES_THETA_H: usize = 90;
/// Bins along θd.
pub const RES_THETA_D: usize = 90;
/// Bins along φd (covering [0, π)).
pub const RES_PHI_D: usize = 180;
/// Bins per channel: 90·90·180 = 1,458,000.
pub const BINS: usize = RES_THETA_H * RES_THETA_D * RES_PHI_D;
/// Bytes of the header (three `i32`).
pub const HEADER_BYTES: usize = 12;
/// Exact size of a MERL `.binary` file: 34,992,012 bytes.
pub const FILE_BYTES: usize = HEADER_BYTES + 3 * BINS * 8;
/// Factors from stored values to f_r (1/sr), per RGB channel.
pub const CHANNEL_SCALE: [f64; 3] = [1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0];

/// How [`MerlTable`] evaluates between bins.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interpolation {
    /// The value of the bin that contains the angles (MERL's `BRDFRead.cpp` lookup).
    Nearest,
    /// Trilinear interpolation between bin centres in index space (the default).
    #[default]
    Trilinear,
}

/// What a reader does with negative stored values (the MERL database's mark for unmeasured bins).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NegativeValues {
    /// Fail with a count of the negative values (strict reading).
    Reject,
    /// Keep them as missing bins (the default): they evaluate as 0, are reported by
    /// [`MerlTable::is_missing`] and masked through [`MerlTable::coverage`].
    #[default]
    Missing,
}

/// Which point of its bin a stored value stands for (see the module notes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BinConvention {
    /// The bin's lower edge: θh = (i/90)²·π/2, θd = j/90·π/2, φd = k/180·π (the default; the
    /// convention of the MERL data's users and of the neural BRDFs trained on it).
    #[default]
    LowerEdge,
    /// The bin's centre: (i + ½, j + ½, k + ½) in index coordinates.
    Centre,
}

impl BinConvention {
    /// The index-coordinate offset of the node within its bin: 0 or ½.
    #[inline]
    pub fn offset(self) -> f64 {
        match self {
            BinConvention::LowerEdge => 0.0,
            BinConvention::Centre => 0.5,
        }
    }

    /// `lower-edge` or `centre`.
    pub fn name(self) -> &'static str {
        match self {
            BinConvention::LowerEdge => "lower-edge",
            BinConvention::Centre => "centre",
        }
    }
}

/// The bin (i, j, k) = (θh, θd, φd indices) that contains the given angles, as `BRDFRead.cpp`
/// computes it (see the module docs). Never panics; out-of-range and NaN angles are clamped.
pub fn nearest_bin(theta_h: f64, theta_d: f64, phi_d: f64) -> (usize, usize, usize) {
    (
        theta_h_index(theta_h),
        theta_d_index(theta_d),
        phi_d_index(phi_d),
    )
}

/// θh index: ⌊sqrt(θh/(π/2) · 90 · 90)⌋ clamped to 0..=89.
fn theta_h_index(theta_h: f64) -> usize {
    if theta_h.is_nan() || theta_h <= 0.0 {
        return 0;
    }
    let u = (theta_h / FRAC_PI_2 * (RES_THETA_H * RES_THETA_H) as f64).sqrt();
    (u as usize).min(RES_THETA_H - 1)
}

/// θd index: ⌊θd/(π/2) · 90⌋ clamped to 0..=89.
fn theta_d_index(theta_d: f64) -> usize {
    if theta_d.is_nan() || theta_d <= 0.0 {
        return 0;
    }
    ((theta_d / FRAC_PI_2 * RES_THETA_D as f64) as usize).min(RES_THETA_D - 1)
}

/// φd index: fold φd < 0 to φd + π, then ⌊φd/π · 180⌋ clamped to 0..=179.
fn phi_d_index(phi_d: f64) -> usize {
    let p = if phi_d < 0.0 { phi_d + PI } else { phi_d };
    if p.is_nan() || p <= 0.0 {
        return 0;
    }
    ((p / PI * RES_PHI_D as f64) as usize).min(RES_PHI_D - 1)
}

/// The centre of bin (i, j, k): θh = ((i+½)/90)²·π/2, θd = (j+½)/90·π/2, φd = (k+½)/180·π,
/// φh = 0. Indices beyond the table are not checked (the formula simply extends).
pub fn bin_center(i: usize, j: usize, k: usize) -> HalfDiff {
    let uh = (i as f64 + 0.5) / RES_THETA_H as f64;
    HalfDiff {
        theta_h: uh * uh * FRAC_PI_2,
        phi_h: 0.0,
        theta_d: (j as f64 + 0.5) / RES_THETA_D as f64 * FRAC_PI_2,
        phi_d: (k as f64 + 0.5) / RES_PHI_D as f64 * PI,
    }
}

/// The point a stored value of bin (i, j, k) stands for under `convention`, with φh = 0:
/// θh = ((i + o)/90)²·π/2, θd = (j + o)/90·π/2, φd = (k + o)/180·π, o = [`BinConvention::offset`].
pub fn bin_node_with(convention: BinConvention, i: usize, j: usize, k: usize) -> HalfDiff {
    let o = convention.offset();
    let uh = (i as f64 + o) / RES_THETA_H as f64;
    HalfDiff {
        theta_h: uh * uh * FRAC_PI_2,
        phi_h: 0.0,
        theta_d: (j as f64 + o) / RES_THETA_D as f64 * FRAC_PI_2,
        phi_d: (k as f64 + o) / RES_PHI_D as f64 * PI,
    }
}

/// The point a stored value of bin (i, j, k) stands for in this crate's convention (the lower
/// edge, [`BinConvention::LowerEdge`]).
pub fn bin_node(i: usize, j: usize, k: usize) -> HalfDiff {
    bin_node_with(BinConvention::default(), i, j, k)
}

/// Folds φd into [0, π) (reciprocity: swapping wi and wo maps φd to φd ± π).
#[inline]
pub fn fold_phi_d(phi_d: f64) -> f64 {
    let p = phi_d.rem_euclid(PI);
    // rem_euclid of a tiny negative number rounds up to π itself.
    if p >= PI {
        0.0
    } else {
        p
    }
}

/// The MERL angles of a reflection pair: [`to_half_diff`] with φd folded into [0, π) by
/// [`fold_phi_d`]; `None` when either direction is at or below the surface or they are opposite.
pub fn merl_angles(wi: DVec3, wo: DVec3) -> Option<HalfDiff> {
    if wi.z <= 0.0 || wo.z <= 0.0 {
        return None;
    }
    let hd = to_half_diff(wi, wo)?;
    Some(HalfDiff {
        phi_d: fold_phi_d(hd.phi_d),
        ..hd
    })
}

/// Offset of bin (i, j, k) within one channel: `k + 180·(j + 90·i)`.
#[inline]
pub fn bin_offset(i: usize, j: usize, k: usize) -> usize {
    k + RES_PHI_D * (j + RES_THETA_D * i)
}

/// Two neighbouring indices and the weight of the second along a clamped axis: `x` is the index
/// coordinate minus the node offset (so nodes sit at integers).
#[inline]
fn clamped_axis(x: f64, n: usize) -> (usize, usize, f64) {
    if x.is_nan() || x <= 0.0 {
        return (0, 0, 0.0);
    }
    let last = (n - 1) as f64;
    if x >= last {
        return (n - 1, n - 1, 0.0);
    }
    let i0 = x.floor();
    let i = i0 as usize;
    (i, i + 1, x - i0)
}

/// The same along the periodic φd axis (period π, `RES_PHI_D` bins), nodes at `offset`.
#[inline]
fn periodic_axis(phi_d: f64, offset: f64) -> (usize, usize, f64) {
    let p = phi_d.rem_euclid(PI);
    let x = p / PI * RES_PHI_D as f64 - offset;
    if !x.is_finite() {
        return (0, 0, 0.0);
    }
    let f = x.floor();
    let t = (x - f).clamp(0.0, 1.0);
    let n = RES_PHI_D as i64;
    let i0 = (f as i64).rem_euclid(n) as usize;
    (i0, (i0 + 1) % RES_PHI_D, t)
}

/// A MERL isotropic BRDF table (90 × 90 × 180 bins, RGB, f64).
#[derive(Clone)]
pub struct MerlTable {
    name: String,
    /// Stored (unscaled) values, channel-major, `3 · BINS`; missing values hold 0.
    values: Vec<f64>,
    /// Per stored value: missing? Empty when nothing is missing.
    missing: Vec<bool>,
    missing_count: usize,
    interpolation: Interpolation,
    convention: BinConvention,
}

/// Which direction pairs of a MERL table were measured: the bins whose three channels are all
/// present ([`MerlTable::coverage`]). Plain data, cheap to share with a fitter.
#[derive(Clone, Debug)]
pub struct MerlCoverage {
    /// Per bin (`bin_offset` order): all three channels present.
    present: Vec<bool>,
    masked_bins: usize,
}

impl MerlCoverage {
    /// Whether the bin containing the pair (the `BRDFRead.cpp` lookup) was measured; pairs at or
    /// below the horizon count as covered (they are not measured by any table).
    pub fn covers(&self, wi: DVec3, wo: DVec3) -> bool {
        match merl_angles(wi, wo) {
            Some(hd) => {
                let (i, j, k) = nearest_bin(hd.theta_h, hd.theta_d, hd.phi_d);
                self.present[bin_offset(i, j, k)]
            }
            None => true,
        }
    }

    /// Bins with at least one missing channel.
    pub fn masked_bins(&self) -> usize {
        self.masked_bins
    }
}

impl std::fmt::Debug for MerlTable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MerlTable")
            .field("name", &self.name)
            .field("missing_count", &self.missing_count)
            .field("interpolation", &self.interpolation)
            .field("convention", &self.convention)
            .finish_non_exhaustive()
    }
}

impl MerlTable {
    /// Reads a MERL `.binary` file, keeping negative values as missing bins
    /// ([`NegativeValues::Missing`]). The table is named after the file stem.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        Self::read_with(path, NegativeValues::Missing)
    }

    /// Reads a MERL `.binary` file with the given treatment of negative values.
    pub fn read_with(path: impl AsRef<Path>, negative: NegativeValues) -> Result<Self> {
        let path = path.as_ref();
        let bytes = crate::error::read_file(path)?;
        Self::parse_with(path, &bytes, negative)
    }

    /// Parses the bytes of a MERL `.binary` file (`path` is used in messages and for the name),
    /// keeping negative values as missing bins. Never panics.
    pub fn parse(path: impl AsRef<Path>, bytes: &[u8]) -> Result<Self> {
        Self::parse_with(path, bytes, NegativeValues::Missing)
    }

    /// Parses the bytes of a MERL `.binary` file with the given treatment of negative values.
    /// Checks, in order: header present, dims (90, 90, 180), exact size, finiteness, signs, and
    /// that some measured value is positive (an all-zero table is refused).
    pub fn parse_with(
        path: impl AsRef<Path>,
        bytes: &[u8],
        negative: NegativeValues,
    ) -> Result<Self> {
        let path = path.as_ref();
        let fail = |problem: String| Error::format(path, problem);
        if bytes.len() < HEADER_BYTES {
            return Err(fail(format!(
                "file is {} bytes, too short for the 12-byte MERL header (a MERL table is {FILE_BYTES} bytes)",
                bytes.len()
            )));
        }
        let dim = |k: usize| {
            let mut b = [0u8; 4];
            b.copy_from_slice(&bytes[4 * k..4 * k + 4]);
            i32::from_le_bytes(b)
        };
        let dims = (dim(0), dim(1), dim(2));
        if dims != (RES_THETA_H as i32, RES_THETA_D as i32, RES_PHI_D as i32) {
            return Err(fail(format!(
                "wrong dims in header: ({}, {}, {}), expected (90, 90, 180)",
                dims.0, dims.1, dims.2
            )));
        }
        if bytes.len() < FILE_BYTES {
            return Err(fail(format!(
                "truncated by {} bytes: file is {} bytes, a 90x90x180 MERL table is {FILE_BYTES}",
                FILE_BYTES - bytes.len(),
                bytes.len()
            )));
        }
        if bytes.len() > FILE_BYTES {
            return Err(fail(format!(
                "{} trailing bytes after the table: file is {} bytes, a 90x90x180 MERL table is {FILE_BYTES}",
                bytes.len() - FILE_BYTES,
                bytes.len()
            )));
        }
        let mut values = Vec::with_capacity(3 * BINS);
        for chunk in bytes[HEADER_BYTES..].chunks_exact(8) {
            let mut b = [0u8; 8];
            b.copy_from_slice(chunk);
            values.push(f64::from_le_bytes(b));
        }
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let table = Self::from_stored_named(path, name, values, negative)?;
        if table.values.iter().all(|v| *v == 0.0) {
            let what = if table.missing_count == 3 * BINS {
                "every value is negative (unmeasured): the table holds no measurement"
            } else {
                "every measured value is zero: the table holds no reflectance"
            };
            return Err(fail(what.into()));
        }
        Ok(table)
    }

    /// A table from stored (unscaled) values, channel-major, `3 · BINS` of them, rejecting
    /// negative values. Errors (naming `<memory>`) on a wrong length or non-finite values.
    pub fn from_stored(name: impl Into<String>, values: Vec<f64>) -> Result<Self> {
        Self::from_stored_named(
            Path::new("<memory>"),
            name.into(),
            values,
            NegativeValues::Reject,
        )
    }

    fn from_stored_named(
        path: &Path,
        name: String,
        mut values: Vec<f64>,
        negative: NegativeValues,
    ) -> Result<Self> {
        if values.len() != 3 * BINS {
            return Err(Error::format(
                path,
                format!(
                    "{} stored values, a 90x90x180 RGB table has {}",
                    values.len(),
                    3 * BINS
                ),
            ));
        }
        let describe = |n: usize| {
            let (c, b) = (n / BINS, n % BINS);
            let (i, rest) = (b / (RES_THETA_D * RES_PHI_D), b % (RES_THETA_D * RES_PHI_D));
            format!(
                "channel {c}, bin ({i}, {}, {})",
                rest / RES_PHI_D,
                rest % RES_PHI_D
            )
        };
        let bad: Vec<usize> = values
            .iter()
            .enumerate()
            .filter(|(_, v)| !v.is_finite())
            .map(|(n, _)| n)
            .collect();
        if let Some(&first) = bad.first() {
            return Err(Error::format(
                path,
                format!(
                    "{} non-finite values (NaN or Inf); the first at {} is {}",
                    bad.len(),
                    describe(first),
                    values[first]
                ),
            ));
        }
        let huge: Vec<usize> = values
            .iter()
            .enumerate()
            .filter(|(_, v)| **v > MAX_MEASURED_VALUE)
            .map(|(n, _)| n)
            .collect();
        if let Some(&first) = huge.first() {
            return Err(Error::format(
                path,
                format!(
                    "{} values above {} (a table scaled wrongly?); the first at {} is {}",
                    huge.len(),
                    crate::error::plain_number(MAX_MEASURED_VALUE),
                    describe(first),
                    crate::error::plain_number(values[first])
                ),
            ));
        }
        let negatives = values.iter().filter(|v| **v < 0.0).count();
        let mut missing = Vec::new();
        if negatives > 0 {
            match negative {
                NegativeValues::Reject => {
                    let first = values.iter().position(|v| *v < 0.0).unwrap_or(0);
                    return Err(Error::format(
                        path,
                        format!(
                            "{negatives} negative values (the first at {} is {}); the MERL database \
                             marks unmeasured bins negative, and a strict reading (--strict) refuses \
                             them: read without --strict to mask them as unmeasured",
                            describe(first),
                            values[first]
                        ),
                    ));
                }
                NegativeValues::Missing => {
                    missing = values.iter().map(|v| *v < 0.0).collect();
                    for v in values.iter_mut().filter(|v| **v < 0.0) {
                        *v = 0.0;
                    }
                }
            }
        }
        Ok(MerlTable {
            name,
            values,
            missing,
            missing_count: negatives,
            interpolation: Interpolation::default(),
            convention: BinConvention::default(),
        })
    }

    /// A table from stored values the caller guarantees to be `3 · BINS` finite, non-negative
    /// numbers (the neural synthesis, whose outputs are finite and clamped at 0 by construction).
    pub(crate) fn from_valid_stored(name: String, values: Vec<f64>) -> Self {
        debug_assert!(
            values.len() == 3 * BINS && values.iter().all(|v| v.is_finite() && *v >= 0.0)
        );
        MerlTable {
            name,
            values,
            missing: Vec::new(),
            missing_count: 0,
            interpolation: Interpolation::default(),
            convention: BinConvention::default(),
        }
    }

    /// The material name (file stem, or the name given at construction).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Renames the table.
    pub fn with_name(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// How [`Bsdf::eval`] and [`MerlTable::eval_half_diff`] interpolate.
    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }

    /// Sets the interpolation used by [`Bsdf::eval`].
    pub fn set_interpolation(&mut self, interpolation: Interpolation) {
        self.interpolation = interpolation;
    }

    /// The same table with another interpolation.
    pub fn with_interpolation(mut self, interpolation: Interpolation) -> Self {
        self.interpolation = interpolation;
        self
    }

    /// Which point of a bin a stored value stands for (default [`BinConvention::LowerEdge`]).
    pub fn convention(&self) -> BinConvention {
        self.convention
    }

    /// The same table read with another bin convention.
    pub fn with_convention(mut self, convention: BinConvention) -> Self {
        self.convention = convention;
        self
    }

    /// The stored (unscaled) values, channel-major, `3 · BINS`; missing values read 0.
    pub fn stored_values(&self) -> &[f64] {
        &self.values
    }

    /// The stored (unscaled) value of channel `c` at bin (i, j, k). Panics on out-of-range indices.
    pub fn stored(&self, c: usize, i: usize, j: usize, k: usize) -> f64 {
        self.values[c * BINS + bin_offset(i, j, k)]
    }

    /// f_r (1/sr) of bin (i, j, k), missing channels as 0. Panics on out-of-range indices.
    pub fn bin_value(&self, i: usize, j: usize, k: usize) -> Rgb {
        let o = bin_offset(i, j, k);
        Rgb::new(
            self.values[o] * CHANNEL_SCALE[0],
            self.values[BINS + o] * CHANNEL_SCALE[1],
            self.values[2 * BINS + o] * CHANNEL_SCALE[2],
        )
    }

    /// Number of missing stored values (over all three channels).
    pub fn missing_count(&self) -> usize {
        self.missing_count
    }

    /// Whether channel `c` of bin (i, j, k) is missing. Panics on out-of-range indices.
    pub fn is_missing(&self, c: usize, i: usize, j: usize, k: usize) -> bool {
        let n = c * BINS + bin_offset(i, j, k);
        assert!(n < 3 * BINS, "MERL bin index out of range");
        !self.missing.is_empty() && self.missing[n]
    }

    /// Which bins were measured in all three channels, or `None` when nothing is missing.
    pub fn coverage(&self) -> Option<MerlCoverage> {
        if self.missing.is_empty() {
            return None;
        }
        let present: Vec<bool> = (0..BINS)
            .map(|b| !(self.missing[b] || self.missing[BINS + b] || self.missing[2 * BINS + b]))
            .collect();
        let masked_bins = present.iter().filter(|p| !**p).count();
        Some(MerlCoverage {
            present,
            masked_bins,
        })
    }

    /// The missing mask (channel-major like the values), or `None` when nothing is missing.
    pub fn missing_mask(&self) -> Option<&[bool]> {
        (!self.missing.is_empty()).then_some(self.missing.as_slice())
    }

    /// f_r at the bin containing (θh, θd, φd) (`BRDFRead.cpp` lookup).
    pub fn lookup_nearest(&self, theta_h: f64, theta_d: f64, phi_d: f64) -> Rgb {
        let (i, j, k) = nearest_bin(theta_h, theta_d, phi_d);
        self.bin_value(i, j, k)
    }

    /// f_r trilinearly interpolated between the nodes of the table's [`BinConvention`] in index
    /// space (θ ends clamped, φd periodic with period π). Missing corners are left out and the
    /// weights of the present ones renormalized; with no present weighted corner the channel
    /// is 0.
    pub fn lookup_trilinear(&self, theta_h: f64, theta_d: f64, phi_d: f64) -> Rgb {
        let o = self.convention.offset();
        let uh = if theta_h > 0.0 {
            (theta_h / FRAC_PI_2).sqrt() * RES_THETA_H as f64
        } else {
            0.0
        };
        let (h0, h1, th) = clamped_axis(uh - o, RES_THETA_H);
        let (d0, d1, td) = clamped_axis(theta_d / FRAC_PI_2 * RES_THETA_D as f64 - o, RES_THETA_D);
        let (p0, p1, tp) = periodic_axis(phi_d, o);
        let mut offsets = [0usize; 8];
        let mut weights = [0.0f64; 8];
        let mut n = 0;
        for (i, wi) in [(h0, 1.0 - th), (h1, th)] {
            for (j, wj) in [(d0, 1.0 - td), (d1, td)] {
                for (k, wk) in [(p0, 1.0 - tp), (p1, tp)] {
                    offsets[n] = bin_offset(i, j, k);
                    weights[n] = wi * wj * wk;
                    n += 1;
                }
            }
        }
        let mut out = [0.0; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let base = c * BINS;
            let mut sum = 0.0;
            let mut wsum = 0.0;
            for (off, w) in offsets.iter().zip(weights) {
                if self.missing.is_empty() || !self.missing[base + off] {
                    sum += w * self.values[base + off];
                    wsum += w;
                }
            }
            if self.missing.is_empty() {
                *o = sum * CHANNEL_SCALE[c];
            } else if wsum > 0.0 {
                *o = sum / wsum * CHANNEL_SCALE[c];
            }
        }
        Rgb(out)
    }

    /// f_r at half/difference angles (φh ignored) with the table's interpolation setting.
    pub fn eval_half_diff(&self, hd: &HalfDiff) -> Rgb {
        match self.interpolation {
            Interpolation::Nearest => self.lookup_nearest(hd.theta_h, hd.theta_d, hd.phi_d),
            Interpolation::Trilinear => self.lookup_trilinear(hd.theta_h, hd.theta_d, hd.phi_d),
        }
    }

    /// The file bytes (header and values); missing values are written as −1 (MERL's mark).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(FILE_BYTES);
        for d in [RES_THETA_H, RES_THETA_D, RES_PHI_D] {
            out.extend_from_slice(&(d as i32).to_le_bytes());
        }
        for (n, v) in self.values.iter().enumerate() {
            let v = if !self.missing.is_empty() && self.missing[n] {
                -1.0
            } else {
                *v
            };
            out.extend_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// Writes the table as a MERL `.binary` file, atomically.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        write_atomic(path.as_ref(), &self.to_bytes())
    }
}

impl Bsdf for MerlTable {
    fn name(&self) -> String {
        format!("MERL {}", self.name)
    }

    /// Looks the pair up through its Rusinkiewicz angles; 0 unless both lie above the surface.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        merl_angles(wi, wo).map_or(Rgb::ZERO, |hd| self.eval_half_diff(&hd))
    }

    /// Cosine-weighted hemisphere sampling; fails when `wo` is below the surface.
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        cosine_sample(self, wo, u1, u2, LobeFlags::GLOSSY)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        cosine_pdf(wi, wo)
    }

    /// Reciprocal (the φd fold) and isotropic; measured data promise no energy bound.
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, false)
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

/// A table of any BSDF: f_r at every bin's node of `convention` (φh = 0; 0 where a direction is
/// at or below the horizon), read back with the same convention. Errors when a value is not
/// finite or negative (e.g. a model with a negative Fresnel term).
pub fn table_from_bsdf(
    name: impl Into<String>,
    bsdf: &dyn Bsdf,
    convention: BinConvention,
    progress: impl Fn(u64) + Sync,
) -> Result<MerlTable> {
    let values = fill_bins(
        |i, j, k| {
            let (wi, wo) = crate::frame::from_half_diff(&bin_node_with(convention, i, j, k));
            if wi.z <= 0.0 || wo.z <= 0.0 {
                Rgb::ZERO
            } else {
                bsdf.eval(wi, wo)
            }
        },
        progress,
    );
    let name = name.into();
    if let Some(v) = values.iter().find(|v| !v.is_finite() || **v < 0.0) {
        return Err(Error::NotFound(format!(
            "{}: the model evaluates to {v:e} (stored value) at some bin: a MERL table holds \
             finite non-negative reflectance",
            bsdf.name()
        )));
    }
    Ok(MerlTable::from_stored(name, values)?.with_convention(convention))
}

/// Builds a table from a function of bin (i, j, k) giving f_r (1/sr), evaluated in parallel;
/// errors when a value is not finite or negative.
pub fn table_from_fn(
    name: impl Into<String>,
    f: impl Fn(usize, usize, usize) -> Rgb + Sync,
) -> Result<MerlTable> {
    MerlTable::from_stored(name, fill_bins(f, |_| {}))
}

/// Stored values (f_r divided by the channel scales, channel-major) of every bin, evaluated in
/// parallel with rayon one (θh, θd) row of 180 φd bins at a time; `progress(n)` is called with
/// the number of bins just finished (the calls add up to [`BINS`]).
pub(crate) fn fill_bins(
    f: impl Fn(usize, usize, usize) -> Rgb + Sync,
    progress: impl Fn(u64) + Sync,
) -> Vec<f64> {
    use rayon::prelude::*;
    let mut values = vec![0.0; 3 * BINS];
    let (r, gb) = values.split_at_mut(BINS);
    let (g, b) = gb.split_at_mut(BINS);
    let row = RES_PHI_D;
    r.par_chunks_mut(row)
        .zip(g.par_chunks_mut(row))
        .zip(b.par_chunks_mut(row))
        .enumerate()
        .for_each(|(ij, ((r, g), b))| {
            let (i, j) = (ij / RES_THETA_D, ij % RES_THETA_D);
            for k in 0..RES_PHI_D {
                let v = f(i, j, k);
                r[k] = v[0] / CHANNEL_SCALE[0];
                g[k] = v[1] / CHANNEL_SCALE[1];
                b[k] = v[2] / CHANNEL_SCALE[2];
            }
            progress(row as u64);
        });
    values
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::deg;

    #[test]
    fn nearest_indices_by_hand() {
        // θh = 0 → 0; θh just below 90° → 89; θh = 1° → ⌊sqrt(90)⌋ = 9; θh = 10° → ⌊30⌋ = 30.
        assert_eq!(theta_h_index(0.0), 0);
        assert_eq!(theta_h_index(deg(89.999)), 89);
        assert_eq!(theta_h_index(deg(90.0)), 89);
        assert_eq!(theta_h_index(deg(1.0)), 9);
        assert_eq!(theta_h_index(deg(10.0) + 1e-12), 30);
        assert_eq!(theta_h_index(deg(40.0)), 60);
        assert_eq!(theta_h_index(-0.1), 0);
        assert_eq!(theta_h_index(f64::NAN), 0);
        // θd linear: 45.5° → 45, 89.99° → 89, 90° clamped.
        assert_eq!(theta_d_index(deg(45.5)), 45);
        assert_eq!(theta_d_index(deg(89.99)), 89);
        assert_eq!(theta_d_index(deg(90.0)), 89);
        // φd: 10.5° → 10; −10.5° folds to 169.5° → 169; −0.2° → 179.8° → 179; π → clamp 179.
        assert_eq!(phi_d_index(deg(10.5)), 10);
        assert_eq!(phi_d_index(deg(-10.5)), 169);
        assert_eq!(phi_d_index(deg(-0.2)), 179);
        assert_eq!(phi_d_index(PI), 179);
        assert_eq!(phi_d_index(-PI), 0);
        assert_eq!(nearest_bin(deg(1.0), deg(45.5), deg(-10.5)), (9, 45, 169));
    }

    /// A table of absurdly large (finite) values is refused, not read into ∞ albedos.
    #[test]
    fn absurdly_large_values_are_refused() {
        let mut values = vec![0.5; 3 * BINS];
        values[7] = 1e300;
        let e = MerlTable::from_stored("huge", values)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("1 values above 1e30") && e.contains("is 1e300"),
            "{e}"
        );
    }

    #[test]
    fn bin_centres_map_back_to_their_bins() {
        for i in 0..RES_THETA_H {
            for j in [0, 17, 89] {
                for k in [0, 90, 179] {
                    let c = bin_center(i, j, k);
                    assert_eq!(nearest_bin(c.theta_h, c.theta_d, c.phi_d), (i, j, k));
                }
            }
        }
        // The documented degrees: θh of bin 9 = 9.5²/90 degrees.
        assert!((bin_center(9, 0, 0).theta_h - deg(9.5 * 9.5 / 90.0)).abs() < 1e-15);
        assert!((bin_center(0, 3, 0).theta_d - deg(3.5)).abs() < 1e-15);
        assert!((bin_center(0, 0, 7).phi_d - deg(7.5)).abs() < 1e-15);
    }

    #[test]
    fn lower_edges_are_the_fastmerl_angles() {
        // asztr/Neural-BRDF fastmerl.py: θh = (i/90)²·π/2, θd = i/90·π/2, φd = i/180·π.
        for (i, j, k) in [(0, 0, 0), (9, 45, 90), (89, 89, 179)] {
            let n = bin_node(i, j, k);
            let u = i as f64 / 90.0;
            assert!((n.theta_h - u * u * FRAC_PI_2).abs() < 1e-15);
            assert!((n.theta_d - j as f64 / 90.0 * FRAC_PI_2).abs() < 1e-15);
            assert!((n.phi_d - k as f64 / 180.0 * PI).abs() < 1e-15);
            // A node lies in its own bin (BRDFRead.cpp's lookup), up to rounding at the edge.
            let e = bin_node_with(BinConvention::LowerEdge, i, j, k);
            let nudge = 1e-9;
            assert_eq!(
                nearest_bin(e.theta_h + nudge, e.theta_d + nudge, e.phi_d + nudge),
                (i, j, k)
            );
        }
        assert_eq!(
            bin_node_with(BinConvention::Centre, 3, 4, 5),
            bin_center(3, 4, 5)
        );
    }

    #[test]
    fn axes_clamp_and_wrap() {
        assert_eq!(clamped_axis(-0.3, 90), (0, 0, 0.0));
        assert_eq!(clamped_axis(89.2, 90), (89, 89, 0.0));
        let (a, b, t) = clamped_axis(3.25, 90);
        assert_eq!((a, b), (3, 4));
        assert!((t - 0.25).abs() < 1e-15);
        // Centres: φd = 0 sits half-way between the centres of bins 179 and 0.
        let (a, b, t) = periodic_axis(0.0, 0.5);
        assert_eq!((a, b), (179, 0));
        assert!((t - 0.5).abs() < 1e-12);
        let (a, b, t) = periodic_axis(-deg(0.25), 0.5);
        assert_eq!((a, b), (179, 0));
        assert!((t - 0.25).abs() < 1e-9);
        assert_eq!(periodic_axis(f64::NAN, 0.5), (0, 0, 0.0));
        // Lower edges: φd = 0 is bin 0's node; −0.5° lies between the nodes of 179 and 0.
        let (a, _, t) = periodic_axis(0.0, 0.0);
        assert_eq!((a, t), (0, 0.0));
        let (a, b, t) = periodic_axis(-deg(0.5), 0.0);
        assert_eq!((a, b), (179, 0));
        assert!((t - 0.5).abs() < 1e-9);
    }

    #[test]
    fn fold_is_into_half_open_range() {
        assert_eq!(fold_phi_d(PI), 0.0);
        assert!((fold_phi_d(-0.5) - (PI - 0.5)).abs() < 1e-15);
        assert!((fold_phi_d(0.5) - 0.5).abs() < 1e-15);
        let p = fold_phi_d(-1e-300);
        assert!((0.0..PI).contains(&p));
    }
}
