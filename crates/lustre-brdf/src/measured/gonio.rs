//! Goniometric transfer-probability tables (000 §2.3, §3.2): for each measured incident direction
//! ωi (the light) a distribution p(ωo|ωi) = fs(ωi, ωo)·|cos θo| (000 Eq. 2.4) over the outgoing
//! sphere, reflection (θo ≤ 90°) and transmission (θo > 90°) hemispheres on one regular grid.
//!
//! # File format `lustre-gonio`, version 1
//!
//! A UTF-8 text file. Header lines start with `#` and come before the data:
//!
//! ```text
//! #lustre-gonio 1                      (first line: magic and version; required)
//! #units transfer_probability          (or `brdf`: values are fs in 1/sr; required unless the
//!                                       caller states the units)
//! #angles degrees                      (or `radians`; required)
//! #name frosted foil                   (optional, free text)
//! #theta_i 0 15 30 45 60 75            (axis lists, each strictly increasing)
//! #phi_i 0 90 180 270
//! #theta_o 0 5 10 ... 90 ... 180
//! #phi_o 0 10 20 ... 350
//! ## anything                          (comment)
//! theta_i phi_i theta_o phi_o value    (one row per grid point, in any order)
//! ```
//!
//! Axis ranges: θi ∈ [0°, 90°) (light above the surface), φi, φo ∈ [0°, 360°) (periodic),
//! θo ∈ [0°, 180°] where θo > 90° is the transmission hemisphere; an outgoing axis with nodes on
//! both sides of 90° must contain 90° itself, so that no interpolation cell mixes the two
//! hemispheres. A φi axis with a single entry declares an isotropic table: the distribution of
//! any other φi is the stored one rotated about the normal. Every grid point must appear exactly
//! once; values must be finite and non-negative. Unknown `#` keys and other versions are errors.
//!
//! Internally the table always holds transfer probabilities p; `brdf` files are converted with
//! p = f·|cos θo| when read.
//!
//! # Reconstruction (000 §3.2, Fig. 3.1 and 3.2)
//!
//! * [`Reconstruction::Quadrilinear`]: p is interpolated linearly in θi, φi, θo and φo.
//! * [`Reconstruction::HalfVector`]: with h the half vector of (ωi, ωo), each neighbouring measured
//!   incident direction ωi,k is looked up at ωo,k = ωi,k reflected about h, and the looked-up
//!   values are blended bilinearly in (θi, φi). For ωo in the transmission hemisphere the same is
//!   done with the mirrored vectors of 000 Eq. 3.5: ωo' = ωo mirrored by the surface plane,
//!   h' = half(ωi, ωo'), ωo,k' = reflect(ωi,k, h'), and the lookup at ωo,k' mirrored back.
//!   A lookup whose constructed direction leaves its hemisphere contributes zero.
//!
//! Both blend the transfer probability p itself, not f = p/|cos θo|: p is what was measured, it is
//! finite everywhere and vanishes towards the horizon, so no division by cos θo → 0 happens
//! inside the reconstruction; and every reconstructed p is then a convex combination of table
//! entries, which gives the rejection sampler a rigorous bound (the largest entry of the
//! neighbouring distributions). f is formed only in [`GonioBsdf`]'s `eval`, as
//! p / max(|cos θo|, [`COS_FLOOR`]). Near the specular peak the aligned lookups ωo,k sit at
//! θo,k ≈ θi,k, so blending p instead of f costs only the blend of cos θo,k versus cos θo (under
//! 1 % for a 15° incident grid at θi = 37.5°).
//!
//! Incident directions outside the θi axis range use the nearest θi node (clamped). A light
//! below the surface is handled by mirroring both directions (a two-sided thin sheet).

use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{write_atomic, Error, Result};
use crate::frame::{half_vector, mirror_z, phi, reflect, rotate_z, spherical};
use crate::numeric::SphereQuadrature;
use crate::rgb::Rgb;
use crate::sampling::{uniform_sphere, SplitMix64};
use crate::validate::{integrate_reflection, integrate_transmission};
use glam::DVec3;
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::Path;
use std::sync::Mutex;

/// The smallest |cos θo| by which a transfer probability is divided to give f.
pub const COS_FLOOR: f64 = 1e-3;

/// Candidates drawn by the rejection sampler before it gives up and returns `None`.
pub const MAX_REJECTION_CANDIDATES: usize = 1 << 22;

const TWO_PI: f64 = 2.0 * PI;

/// θ of a direction via atan2, accurate near both poles (acos loses half the digits there, which
/// would break the exactness of lookups at θo = 0° and 180° grid nodes).
fn theta(w: DVec3) -> f64 {
    (w.x * w.x + w.y * w.y).sqrt().atan2(w.z)
}

/// What the values of a table file are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GonioUnits {
    /// p(ωo|ωi) = fs·|cos θo| (000 Eq. 2.4), the thesis's measured quantity.
    TransferProbability,
    /// fs in 1/sr.
    Brdf,
}

impl GonioUnits {
    fn keyword(self) -> &'static str {
        match self {
            GonioUnits::TransferProbability => "transfer_probability",
            GonioUnits::Brdf => "brdf",
        }
    }
}

/// How non-measured directions are reconstructed (000 §3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reconstruction {
    /// Linear interpolation over (θi, φi, θo, φo) of p (Fig. 3.1).
    Quadrilinear,
    /// Lookups at directions reflected about the half vector, blended in (θi, φi) (Fig. 3.2).
    HalfVector,
}

/// The four axes of a table, in radians.
#[derive(Clone, Debug, PartialEq)]
pub struct GonioAxes {
    /// Incident polar angles, strictly increasing in [0, π/2).
    pub theta_i: Vec<f64>,
    /// Incident azimuths, strictly increasing in [0, 2π); one entry means isotropic.
    pub phi_i: Vec<f64>,
    /// Outgoing polar angles, strictly increasing in [0, π] (> π/2: transmission).
    pub theta_o: Vec<f64>,
    /// Outgoing azimuths, strictly increasing in [0, 2π).
    pub phi_o: Vec<f64>,
}

impl GonioAxes {
    /// Axes from lists in degrees, validated.
    pub fn from_degrees(
        theta_i: &[f64],
        phi_i: &[f64],
        theta_o: &[f64],
        phi_o: &[f64],
    ) -> Result<Self> {
        let r = |v: &[f64]| v.iter().map(|d| d.to_radians()).collect::<Vec<_>>();
        let a = GonioAxes {
            theta_i: r(theta_i),
            phi_i: r(phi_i),
            theta_o: r(theta_o),
            phi_o: r(phi_o),
        };
        a.validate(Path::new("<axes>"))?;
        Ok(a)
    }

    /// Evenly spaced axes: θi = 0, Δθi, … below 90°; φi every Δφi; θo = 0 … 180° (or 90° when
    /// `transmission` is false) every Δθo; φo every Δφo. Steps in degrees.
    pub fn regular_degrees(
        d_theta_i: f64,
        d_phi_i: f64,
        d_theta_o: f64,
        d_phi_o: f64,
        transmission: bool,
    ) -> Result<Self> {
        let steps = |step: f64, end: f64, inclusive: bool| -> Result<Vec<f64>> {
            if !step.is_finite() || step <= 0.0 {
                return Err(Error::param(
                    "step",
                    step,
                    "axis steps must be positive degrees",
                ));
            }
            let n = (end / step + 1e-9).floor() as usize;
            let mut v: Vec<f64> = (0..=n).map(|k| k as f64 * step).collect();
            if !inclusive {
                v.retain(|&x| x < end - 1e-9);
            }
            Ok(v)
        };
        let to_end = if transmission { 180.0 } else { 90.0 };
        Self::from_degrees(
            &steps(d_theta_i, 90.0, false)?,
            &steps(d_phi_i, 360.0, false)?,
            &steps(d_theta_o, to_end, true)?,
            &steps(d_phi_o, 360.0, false)?,
        )
    }

    /// Number of grid points.
    pub fn len(&self) -> usize {
        self.theta_i.len() * self.phi_i.len() * self.theta_o.len() * self.phi_o.len()
    }

    /// True when some axis is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn validate(&self, path: &Path) -> Result<()> {
        let check = |name: &str, v: &[f64], lo: f64, hi: f64, hi_inclusive: bool| -> Result<()> {
            if v.is_empty() {
                return Err(Error::format(path, format!("axis {name} is empty")));
            }
            for (k, &x) in v.iter().enumerate() {
                let inside =
                    x.is_finite() && x >= lo && (x < hi || (hi_inclusive && x <= hi + 1e-12));
                if !inside {
                    return Err(Error::format(
                        path,
                        format!(
                            "axis {name}: entry {k} = {:.6}° lies outside [{:.0}°, {:.0}°{}",
                            x.to_degrees(),
                            lo.to_degrees(),
                            hi.to_degrees(),
                            if hi_inclusive { "]" } else { ")" }
                        ),
                    ));
                }
                if k > 0 && x <= v[k - 1] {
                    return Err(Error::format(
                        path,
                        format!("axis {name} is not strictly increasing at entry {k}"),
                    ));
                }
            }
            Ok(())
        };
        check("theta_i", &self.theta_i, 0.0, FRAC_PI_2, false)?;
        check("phi_i", &self.phi_i, 0.0, TWO_PI, false)?;
        check("theta_o", &self.theta_o, 0.0, PI, true)?;
        check("phi_o", &self.phi_o, 0.0, TWO_PI, false)?;
        let below = self.theta_o.iter().any(|&t| t < FRAC_PI_2 - 1e-12);
        let above = self.theta_o.iter().any(|&t| t > FRAC_PI_2 + 1e-12);
        let has_90 = self.theta_o.iter().any(|&t| (t - FRAC_PI_2).abs() <= 1e-12);
        if below && above && !has_90 {
            return Err(Error::format(
                path,
                "axis theta_o spans both hemispheres but lacks the horizon node 90°",
            ));
        }
        Ok(())
    }
}

/// A goniometric table of transfer probabilities p(ωo|ωi) on a regular (θi, φi, θo, φo) grid.
#[derive(Clone, Debug, PartialEq)]
pub struct GonioTable {
    /// A name for reports (the `#name` header, or the file stem).
    pub name: String,
    axes: GonioAxes,
    /// p at grid point ((ti·nφi + pi)·nθo + to)·nφo + po.
    values: Vec<f64>,
    /// Largest p of each incident distribution.
    dist_max: Vec<f64>,
}

/// Index of `x` in `axis` (exact up to rounding), by binary search.
fn axis_index(axis: &[f64], x: f64) -> Option<usize> {
    let tol = 1e-9 * x.abs().max(1.0);
    let k = axis.partition_point(|&a| a < x - tol);
    (k < axis.len() && (axis[k] - x).abs() <= tol).then_some(k)
}

/// Linear weights on a clamped axis: (i0, i1, t) with value = (1−t)·a[i0] + t·a[i1].
fn clamped_cell(axis: &[f64], x: f64) -> (usize, usize, f64) {
    let n = axis.len();
    if n == 1 || x <= axis[0] {
        return (0, 0, 0.0);
    }
    if x >= axis[n - 1] {
        return (n - 1, n - 1, 0.0);
    }
    let k = axis.partition_point(|&a| a <= x).clamp(1, n - 1);
    let (a, b) = (axis[k - 1], axis[k]);
    (k - 1, k, ((x - a) / (b - a)).clamp(0.0, 1.0))
}

/// Linear weights on a periodic axis in [0, 2π).
fn periodic_cell(axis: &[f64], x: f64) -> (usize, usize, f64) {
    let n = axis.len();
    let x = x.rem_euclid(TWO_PI);
    if n == 1 {
        return (0, 0, 0.0);
    }
    if x < axis[0] || x >= axis[n - 1] {
        // The wrap-around cell from the last node to the first + 2π.
        let a = axis[n - 1];
        let b = axis[0] + TWO_PI;
        let xx = if x < axis[0] { x + TWO_PI } else { x };
        return (n - 1, 0, ((xx - a) / (b - a)).clamp(0.0, 1.0));
    }
    let k = axis.partition_point(|&a| a <= x).clamp(1, n - 1);
    let (a, b) = (axis[k - 1], axis[k]);
    (k - 1, k, ((x - a) / (b - a)).clamp(0.0, 1.0))
}

fn parse_number(path: &Path, line_no: usize, tok: &str, what: &str) -> Result<f64> {
    let v: f64 = tok.parse().map_err(|_| {
        Error::format(
            path,
            format!("line {line_no}: {what} {tok:?} is not a number"),
        )
    })?;
    if !v.is_finite() {
        return Err(Error::format(
            path,
            format!("line {line_no}: {what} is not finite ({tok})"),
        ));
    }
    Ok(v)
}

impl GonioTable {
    /// A table from axes and p values in grid order (see the struct docs), validated.
    pub fn from_values(name: impl Into<String>, axes: GonioAxes, values: Vec<f64>) -> Result<Self> {
        let path = Path::new("<memory>");
        axes.validate(path)?;
        if values.len() != axes.len() {
            return Err(Error::format(
                path,
                format!(
                    "{} values for a grid of {} points",
                    values.len(),
                    axes.len()
                ),
            ));
        }
        if let Some(k) = values.iter().position(|v| !v.is_finite() || *v < 0.0) {
            return Err(Error::format(
                path,
                format!("value {k} is {} (must be finite and ≥ 0)", values[k]),
            ));
        }
        let per = axes.theta_o.len() * axes.phi_o.len();
        let dist_max = values
            .chunks(per)
            .map(|c| c.iter().cloned().fold(0.0, f64::max))
            .collect();
        Ok(GonioTable {
            name: name.into(),
            axes,
            values,
            dist_max,
        })
    }

    /// Tabulates p(ωo|ωi) = `p(wi, wo)` at every grid point (wi = light, wo = viewer).
    pub fn from_fn(
        name: impl Into<String>,
        axes: GonioAxes,
        p: impl Fn(DVec3, DVec3) -> f64,
    ) -> Result<Self> {
        let mut values = Vec::with_capacity(axes.len());
        for &ti in &axes.theta_i {
            for &pi in &axes.phi_i {
                let wi = spherical(ti, pi);
                for &to in &axes.theta_o {
                    for &po in &axes.phi_o {
                        values.push(p(wi, spherical(to, po)));
                    }
                }
            }
        }
        Self::from_values(name, axes, values)
    }

    /// Tabulates a BSDF: p = mean over channels of f(wi, wo) times |cos θo|.
    pub fn tabulate(bsdf: &dyn Bsdf, axes: GonioAxes) -> Result<Self> {
        Self::from_fn(bsdf.name(), axes, |wi, wo| {
            bsdf.eval(wi, wo).mean() * wo.z.abs()
        })
    }

    /// The axes (radians).
    pub fn axes(&self) -> &GonioAxes {
        &self.axes
    }

    /// p at grid indices (θi, φi, θo, φo), or `None` outside the grid.
    pub fn value(&self, ti: usize, pi: usize, to: usize, po: usize) -> Option<f64> {
        let a = &self.axes;
        if ti >= a.theta_i.len()
            || pi >= a.phi_i.len()
            || to >= a.theta_o.len()
            || po >= a.phi_o.len()
        {
            return None;
        }
        self.values.get(self.index(ti, pi, to, po)).copied()
    }

    fn index(&self, ti: usize, pi: usize, to: usize, po: usize) -> usize {
        let a = &self.axes;
        ((ti * a.phi_i.len() + pi) * a.theta_o.len() + to) * a.phi_o.len() + po
    }

    /// Whether the table has a transmission hemisphere (θo > 90°).
    pub fn has_transmission(&self) -> bool {
        self.axes.theta_o.iter().any(|&t| t > FRAC_PI_2 + 1e-12)
    }

    /// Reads a table file; `units` overrides (or supplies) the `#units` header.
    pub fn read(path: &Path, units: Option<GonioUnits>) -> Result<Self> {
        let bytes = crate::error::read_file(path)?;
        Self::parse(path, &bytes, units)
    }

    /// Parses a table from memory; `path` names it in messages. `units`, when given, says what
    /// the values are and takes precedence over the file's `#units` header; without it a
    /// missing or unknown `#units` is an error.
    pub fn parse(path: &Path, bytes: &[u8], units: Option<GonioUnits>) -> Result<Self> {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| Error::format(path, format!("not UTF-8 text ({e})")))?;
        let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
        match lines.next() {
            Some((_, l)) if l.split_whitespace().next() == Some("#lustre-gonio") => {
                let v = l.split_whitespace().nth(1);
                if v != Some("1") {
                    return Err(Error::format(
                        path,
                        format!(
                            "unsupported lustre-gonio version {:?} (this reader knows 1)",
                            v.unwrap_or("")
                        ),
                    ));
                }
            }
            _ => return Err(Error::format(path, "first line must be `#lustre-gonio 1`")),
        }
        let mut file_units: Option<std::result::Result<GonioUnits, String>> = None;
        let mut degrees: Option<bool> = None;
        let mut name: Option<String> = None;
        let mut ax: [Option<Vec<f64>>; 4] = [None, None, None, None];
        const AXES: [&str; 4] = ["#theta_i", "#phi_i", "#theta_o", "#phi_o"];
        let mut data_lines: Vec<(usize, &str)> = Vec::new();
        for (no, line) in lines {
            if line.is_empty() || line.starts_with("##") {
                continue;
            }
            if line.starts_with('#') {
                if !data_lines.is_empty() {
                    return Err(Error::format(
                        path,
                        format!("line {no}: header line after the data rows"),
                    ));
                }
                let mut toks = line.split_whitespace();
                let key = toks.next().unwrap_or("");
                match key {
                    "#units" => {
                        let u = toks.next().unwrap_or("");
                        file_units = Some(match u {
                            "transfer_probability" => Ok(GonioUnits::TransferProbability),
                            "brdf" => Ok(GonioUnits::Brdf),
                            other => Err(other.to_string()),
                        });
                    }
                    "#angles" => {
                        degrees = Some(match toks.next().unwrap_or("") {
                            "degrees" => true,
                            "radians" => false,
                            other => {
                                return Err(Error::format(
                                    path,
                                    format!(
                                        "line {no}: unknown #angles {other:?} (degrees or radians)"
                                    ),
                                ))
                            }
                        })
                    }
                    "#name" => name = Some(line["#name".len()..].trim().to_string()),
                    k if AXES.contains(&k) => {
                        let i = AXES.iter().position(|a| *a == k).unwrap_or(0);
                        if ax[i].is_some() {
                            return Err(Error::format(path, format!("line {no}: {k} given twice")));
                        }
                        let v = toks
                            .map(|t| parse_number(path, no, t, &k[1..]))
                            .collect::<Result<Vec<f64>>>()?;
                        ax[i] = Some(v);
                    }
                    other => {
                        return Err(Error::format(
                            path,
                            format!("line {no}: unknown header {other:?}"),
                        ))
                    }
                }
                continue;
            }
            data_lines.push((no, line));
        }
        let units = match (units, file_units) {
            (Some(u), _) => u,
            (None, Some(Ok(u))) => u,
            (None, Some(Err(u))) => {
                return Err(Error::format(
                    path,
                    format!("unknown #units {u:?} (known: transfer_probability, brdf); state the units to read it"),
                ))
            }
            (None, None) => {
                return Err(Error::format(
                    path,
                    "missing #units header (transfer_probability or brdf); state the units to read it",
                ))
            }
        };
        let degrees = degrees
            .ok_or_else(|| Error::format(path, "missing #angles header (degrees or radians)"))?;
        let scale = if degrees { PI / 180.0 } else { 1.0 };
        let mut got: Vec<Vec<f64>> = Vec::with_capacity(4);
        for (i, a) in ax.into_iter().enumerate() {
            let a = a.ok_or_else(|| Error::format(path, format!("missing {} header", AXES[i])))?;
            got.push(a.into_iter().map(|x| x * scale).collect());
        }
        let axes = GonioAxes {
            phi_o: got.pop().unwrap_or_default(),
            theta_o: got.pop().unwrap_or_default(),
            phi_i: got.pop().unwrap_or_default(),
            theta_i: got.pop().unwrap_or_default(),
        };
        axes.validate(path)?;
        let total = axes
            .theta_i
            .len()
            .checked_mul(axes.phi_i.len())
            .and_then(|n| n.checked_mul(axes.theta_o.len()))
            .and_then(|n| n.checked_mul(axes.phi_o.len()))
            .ok_or_else(|| Error::format(path, "grid size overflows"))?;
        if data_lines.len() != total {
            return Err(Error::format(
                path,
                format!(
                    "incomplete grid: {} data rows for {} grid points ({}×{}×{}×{})",
                    data_lines.len(),
                    total,
                    axes.theta_i.len(),
                    axes.phi_i.len(),
                    axes.theta_o.len(),
                    axes.phi_o.len()
                ),
            ));
        }
        let mut values = vec![f64::NAN; total];
        let table = GonioTable {
            name: String::new(),
            axes,
            values: Vec::new(),
            dist_max: Vec::new(),
        };
        for (no, line) in data_lines {
            let toks: Vec<&str> = line.split_whitespace().collect();
            if toks.len() != 5 {
                return Err(Error::format(
                    path,
                    format!(
                        "line {no}: {} fields, expected 5 (theta_i phi_i theta_o phi_o value)",
                        toks.len()
                    ),
                ));
            }
            const WHAT: [&str; 5] = ["theta_i", "phi_i", "theta_o", "phi_o", "value"];
            let mut f = [0.0; 5];
            for k in 0..5 {
                f[k] = parse_number(path, no, toks[k], WHAT[k])?;
            }
            let a = &table.axes;
            let mut idx = [0usize; 4];
            for (k, axis) in [&a.theta_i, &a.phi_i, &a.theta_o, &a.phi_o]
                .into_iter()
                .enumerate()
            {
                idx[k] = axis_index(axis, f[k] * scale).ok_or_else(|| {
                    Error::format(
                        path,
                        format!(
                            "line {no}: {} = {} is not on the {} axis",
                            WHAT[k], toks[k], WHAT[k]
                        ),
                    )
                })?;
            }
            let v = f[4];
            if v < 0.0 {
                return Err(Error::format(
                    path,
                    format!("line {no}: negative value {v}"),
                ));
            }
            let p = match units {
                GonioUnits::TransferProbability => v,
                GonioUnits::Brdf => v * a.theta_o[idx[2]].cos().abs(),
            };
            let i = table.index(idx[0], idx[1], idx[2], idx[3]);
            if !values[i].is_nan() {
                return Err(Error::format(
                    path,
                    format!("line {no}: grid point given twice"),
                ));
            }
            values[i] = p;
        }
        if let Some(i) = values.iter().position(|v| v.is_nan()) {
            // Unreachable when the row count matches and no point repeats, kept as a guard.
            return Err(Error::format(
                path,
                format!("incomplete grid: grid point {i} has no row"),
            ));
        }
        let name = name.unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default()
        });
        Self::from_values(name, table.axes, values).map_err(|e| match e {
            Error::Format { problem, .. } => Error::format(path, problem),
            other => other,
        })
    }

    /// The file text (radians, transfer probabilities, shortest round-trip numbers).
    pub fn to_text(&self) -> String {
        use std::fmt::Write;
        let a = &self.axes;
        let mut s = String::with_capacity(self.values.len() * 48 + 256);
        let _ = writeln!(
            s,
            "#lustre-gonio 1\n#units {}\n#angles radians",
            GonioUnits::TransferProbability.keyword()
        );
        if !self.name.is_empty() {
            let _ = writeln!(s, "#name {}", self.name.replace('\n', " "));
        }
        for (k, axis) in [
            ("theta_i", &a.theta_i),
            ("phi_i", &a.phi_i),
            ("theta_o", &a.theta_o),
            ("phi_o", &a.phi_o),
        ] {
            s.push('#');
            s.push_str(k);
            for x in axis.iter() {
                let _ = write!(s, " {x}");
            }
            s.push('\n');
        }
        for (ti, &t_i) in a.theta_i.iter().enumerate() {
            for (pi, &p_i) in a.phi_i.iter().enumerate() {
                for (to, &t_o) in a.theta_o.iter().enumerate() {
                    for (po, &p_o) in a.phi_o.iter().enumerate() {
                        let v = self.values[self.index(ti, pi, to, po)];
                        let _ = writeln!(s, "{t_i} {p_i} {t_o} {p_o} {v}");
                    }
                }
            }
        }
        s
    }

    /// Writes the table atomically in the `lustre-gonio 1` format.
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomic(path, self.to_text().as_bytes())
    }

    /// Bilinear lookup of p in the measured distribution (ti, pi) at outgoing direction `wo`.
    fn lookup(&self, ti: usize, pi: usize, wo: DVec3) -> f64 {
        let a = &self.axes;
        let (t0, t1, wt) = clamped_cell(&a.theta_o, theta(wo));
        let (p0, p1, wp) = periodic_cell(&a.phi_o, phi(wo));
        let v = |to: usize, po: usize| self.values[self.index(ti, pi, to, po)];
        (1.0 - wt) * ((1.0 - wp) * v(t0, p0) + wp * v(t0, p1))
            + wt * ((1.0 - wp) * v(t1, p0) + wp * v(t1, p1))
    }

    /// The neighbouring measured incident directions of `wi` (upper hemisphere) with their
    /// bilinear weights, and the rotation that maps the query into the table's frame (non-zero
    /// only for isotropic tables).
    fn incident_neighbours(&self, wi: DVec3) -> ([(usize, usize, f64); 4], f64) {
        let a = &self.axes;
        let (t0, t1, wt) = clamped_cell(&a.theta_i, theta(wi));
        let (rot, (p0, p1, wp)) = if a.phi_i.len() == 1 {
            (a.phi_i[0] - phi(wi), (0, 0, 0.0))
        } else {
            (0.0, periodic_cell(&a.phi_i, phi(wi)))
        };
        (
            [
                (t0, p0, (1.0 - wt) * (1.0 - wp)),
                (t0, p1, (1.0 - wt) * wp),
                (t1, p0, wt * (1.0 - wp)),
                (t1, p1, wt * wp),
            ],
            rot,
        )
    }

    /// The reconstructed transfer probability p(ωo|ωi) for a light direction `wi` with
    /// wi.z ≥ 0 (the caller mirrors lower-hemisphere lights) and any viewer direction `wo`.
    pub fn transfer_probability(&self, wi: DVec3, wo: DVec3, recon: Reconstruction) -> f64 {
        let (nb, rot) = self.incident_neighbours(wi);
        let (wi, wo) = if rot != 0.0 {
            (rotate_z(wi, rot), rotate_z(wo, rot))
        } else {
            (wi, wo)
        };
        let a = &self.axes;
        let transmitted = wo.z < 0.0;
        // Transmission: reflect in the mirrored configuration (000 Eq. 3.5).
        let wo_m = if transmitted { mirror_z(wo) } else { wo };
        let h = match recon {
            Reconstruction::HalfVector => half_vector(wi, wo_m),
            Reconstruction::Quadrilinear => None,
        };
        let mut p = 0.0;
        for &(ti, pi, w) in &nb {
            if w <= 0.0 {
                continue;
            }
            let look = match h {
                None => wo,
                Some(h) => {
                    let wik = spherical(a.theta_i[ti], a.phi_i[pi]);
                    let wok = reflect(wik, h);
                    if wok.z < 0.0 {
                        continue; // the constructed direction left its hemisphere
                    }
                    if transmitted {
                        mirror_z(wok)
                    } else {
                        wok
                    }
                }
            };
            p += w * self.lookup(ti, pi, look);
        }
        p
    }

    /// A rigorous upper bound of p(·|ωi) over all ωo for either reconstruction: both are convex
    /// combinations of the entries of the neighbouring distributions.
    pub fn max_transfer_probability(&self, wi: DVec3) -> f64 {
        let (nb, _) = self.incident_neighbours(wi);
        let n_pi = self.axes.phi_i.len();
        nb.iter()
            .filter(|(_, _, w)| *w > 0.0)
            .map(|&(ti, pi, _)| self.dist_max[ti * n_pi + pi])
            .fold(0.0, f64::max)
    }

    /// Reflectivity r(ωi) = ∫ over the upper hemisphere of p(ωo|ωi) dωo (000 Eq. 2.7), by
    /// quadrature refined around the mirror direction.
    pub fn reflectivity(&self, wi: DVec3, recon: Reconstruction) -> f64 {
        let wi = upper(wi);
        integrate_reflection(
            |wo| self.transfer_probability(wi, wo, recon),
            wi,
            &quadrature(),
        )
    }

    /// Transmissivity t(ωi) = ∫ over the lower hemisphere of p(ωo|ωi) dωo (000 Eq. 2.8), by
    /// quadrature refined around −ωi. Zero for tables without a transmission hemisphere.
    pub fn transmissivity(&self, wi: DVec3, recon: Reconstruction) -> f64 {
        if !self.has_transmission() {
            return 0.0;
        }
        let wi = upper(wi);
        integrate_transmission(
            |wo| self.transfer_probability(wi, wo, recon),
            wi,
            &quadrature(),
        )
    }

    /// Probability that a photon from ωi is absorbed, 1 − (r + t) (000 Eq. 3.1).
    pub fn absorption(&self, wi: DVec3, recon: Reconstruction) -> f64 {
        1.0 - (self.reflectivity(wi, recon) + self.transmissivity(wi, recon))
    }
}

fn upper(w: DVec3) -> DVec3 {
    if w.z < 0.0 {
        mirror_z(w)
    } else {
        w
    }
}

/// The quadrature of the reflectivity and pdf normalization integrals.
fn quadrature() -> SphereQuadrature {
    SphereQuadrature {
        points_per_panel: 8,
        phi_points: 128,
        theta_min: 1e-3,
        theta_split: 0.2,
        uniform_panels: 24,
    }
}

/// A goniometric table with a reconstruction, as a [`Bsdf`]: f(wi, wo) = p(wo|wi) / |cos θo|
/// (000 Eq. 2.4) with wi the light (the table's incident axis) and wo the viewer.
///
/// Sampling is the rejection procedure of 000 §3.2. [`GonioBsdf::sample_outgoing`] draws ωo for a
/// photon from ωi; [`Bsdf::sample`] runs the same procedure from the viewer side (the table
/// entered with ωi := wo, the drawn direction returned as wi), which for a reciprocal table is
/// exactly importance sampling of f·|cos θi|. The density of the procedure is
/// p(·|ω)/∫p(·|ω) dω, with the integral computed by quadrature and cached per direction.
#[derive(Debug)]
pub struct GonioBsdf {
    table: GonioTable,
    recon: Reconstruction,
    /// (bound M, normalization Z) per entering direction, keyed by its bits.
    cache: Mutex<HashMap<[u64; 3], (f64, f64)>>,
}

impl GonioBsdf {
    /// Wraps a table with a reconstruction.
    pub fn new(table: GonioTable, recon: Reconstruction) -> Self {
        GonioBsdf {
            table,
            recon,
            cache: Mutex::new(HashMap::new()),
        }
    }

    /// The table.
    pub fn table(&self) -> &GonioTable {
        &self.table
    }

    /// The reconstruction.
    pub fn reconstruction(&self) -> Reconstruction {
        self.recon
    }

    /// (M, Z) for an entering direction in the upper hemisphere: the bound and ∫p.
    fn bound_and_norm(&self, wi: DVec3) -> (f64, f64) {
        let key = [wi.x.to_bits(), wi.y.to_bits(), wi.z.to_bits()];
        if let Ok(c) = self.cache.lock() {
            if let Some(v) = c.get(&key) {
                return *v;
            }
        }
        let m = self.table.max_transfer_probability(wi);
        let z = if m > 0.0 {
            self.table.reflectivity(wi, self.recon) + self.table.transmissivity(wi, self.recon)
        } else {
            0.0
        };
        if let Ok(mut c) = self.cache.lock() {
            if c.len() > 1 << 16 {
                c.clear();
            }
            c.insert(key, (m, z));
        }
        (m, z)
    }

    /// p(ωo|ωi) for any light direction (a light below the surface mirrors both directions).
    pub fn transfer_probability(&self, wi: DVec3, wo: DVec3) -> f64 {
        if wi.z < 0.0 {
            self.table
                .transfer_probability(mirror_z(wi), mirror_z(wo), self.recon)
        } else {
            self.table.transfer_probability(wi, wo, self.recon)
        }
    }

    /// Density over the sphere of the §3.2 sampler's ωo for a photon from ωi: p(ωo|ωi)/∫p.
    pub fn pdf_outgoing(&self, wi: DVec3, wo: DVec3) -> f64 {
        let (wi, wo) = if wi.z < 0.0 {
            (mirror_z(wi), mirror_z(wo))
        } else {
            (wi, wo)
        };
        let (_, z) = self.bound_and_norm(wi);
        if z > 0.0 {
            self.table.transfer_probability(wi, wo, self.recon) / z
        } else {
            0.0
        }
    }

    /// The rejection sampler of 000 §3.2 for a photon arriving from ωi: maxPDF = a bound of
    /// p(·|ωi), x uniform in [0, maxPDF), candidates ωo uniform over the sphere until
    /// x < p(ωo|ωi) (a fresh x per candidate). Returns ωo and its density
    /// [`GonioBsdf::pdf_outgoing`], or `None` for a fully absorbing direction (or after
    /// [`MAX_REJECTION_CANDIDATES`] candidates).
    pub fn sample_outgoing(&self, wi: DVec3, rng: &mut SplitMix64) -> Option<(DVec3, f64)> {
        let flip = wi.z < 0.0;
        let wi_u = upper(wi);
        let (m, z) = self.bound_and_norm(wi_u);
        if m.is_nan() || z.is_nan() || m <= 0.0 || z <= 0.0 {
            return None;
        }
        for _ in 0..MAX_REJECTION_CANDIDATES {
            let wo = uniform_sphere(rng.next_f64(), rng.next_f64());
            let x = rng.next_f64() * m;
            let p = self.table.transfer_probability(wi_u, wo, self.recon);
            if x < p {
                let wo = if flip { mirror_z(wo) } else { wo };
                return Some((wo, p / z));
            }
        }
        None
    }
}

impl Bsdf for GonioBsdf {
    fn name(&self) -> String {
        format!("gonio table {} ({:?})", self.table.name, self.recon)
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let p = self.transfer_probability(wi, wo);
        Rgb::splat(p / wo.z.abs().max(COS_FLOOR))
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        // The procedure needs an unbounded stream of numbers: derive it from (u1, u2).
        let mut rng =
            SplitMix64::new(u1.to_bits() ^ u2.to_bits().rotate_left(29) ^ 0x5DEE_CE66_D1CE_4E5B);
        let (wi, _) = self.sample_outgoing(wo, &mut rng)?;
        Some(BsdfSample::new(
            wi,
            self.eval(wi, wo),
            self.pdf(wi, wo),
            LobeFlags::GLOSSY | LobeFlags::side(wi, wo),
        ))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        self.pdf_outgoing(wo, wi)
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            reciprocal: false,
            energy_conserving: false,
            transmission: self.table.has_transmission(),
            anisotropic: self.table.axes.phi_i.len() > 1,
            lobes: if self.table.has_transmission() {
                LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION
            } else {
                LobeFlags::GLOSSY_REFLECTION
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_cells_wrap() {
        let axis = [0.0, 1.0, 2.0];
        let (a, b, t) = periodic_cell(&axis, 2.5);
        assert_eq!((a, b), (2, 0));
        assert!((t - 0.5 / (TWO_PI - 2.0)).abs() < 1e-12);
        assert_eq!(periodic_cell(&axis, 1.0), (1, 2, 0.0));
        assert_eq!(clamped_cell(&axis, 5.0), (2, 2, 0.0));
        assert_eq!(axis_index(&axis, 1.0 + 1e-12), Some(1));
        assert_eq!(axis_index(&axis, 1.5), None);
    }
}
