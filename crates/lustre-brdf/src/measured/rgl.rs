//! RGL tensor `.bsdf` files (Dupuy & Jakob 2018, "An adaptive parameterization for efficient
//! material acquisition and rendering", the EPFL RGL material database) and the measured BSDF
//! they describe.
//!
//! Ported from Mitsuba 3 (mitsuba-renderer/mitsuba3): the container format from
//! `src/core/tensor.cpp` (`TensorFile`), the BSDF from `src/bsdfs/measured.cpp` (`Measured`:
//! `eval`, `sample`, `pdf`, `theta2u`/`phi2u`/`u2theta`/`u2phi`, `elevation`, the isotropic and
//! reduction handling, the `jacobian` flag, the RGB branch) and the warps from
//! `include/mitsuba/core/distr_2d.h` (see [`super::rgl_warp`]). pbrt-v4 (mmp/pbrt-v4,
//! `src/pbrt/bxdfs.cpp`: `Tensor`, `MeasuredBRDF::Create`, `MeasuredBxDF`) reads the same files
//! with the same algorithm; its version check (1.0) and its clamping of negative RGB values are
//! used here.
//!
//! # File layout (little endian)
//! `"tensor_file\0"` (12 bytes), version (2 bytes: major 1, minor 0), field count (u32), then per
//! field: name length (u16), name, rank (u16), dtype (u8: 1 u8, 2 i8, 3 u16, 4 i16, 5 u32,
//! 6 i32, 7 u64, 8 i64, 9 f16, 10 f32, 11 f64), data offset (u64), shape (rank × u64). The data of
//! each field is a dense row-major array at its offset.
//!
//! # Conventions
//! Mitsuba's `si.wi` (the direction the tables are conditioned on, "θi, φi" in the file) is this
//! crate's `wo` (the viewer), and Mitsuba's sampled `wo` is this crate's `wi`. Mitsuba's `eval`
//! includes the cosine of the sampled direction; [`Bsdf::eval`] here divides it out, as pbrt-v4's
//! `MeasuredBxDF::f` does: f(wi, wo) = rgb(s) · D(m) / (4 σ(wo) cos θi), with s the VNDF-warp
//! preimage of the half vector m (the `rgb` table lives in the warped sample space) and the
//! factor D/(4σ) applied only when the file's `jacobian` flag is set.

use super::rgl_warp::Marginal2D;
use crate::bsdf::{Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{Error, Result};
use crate::rgb::Rgb;
use glam::DVec3;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// The magic bytes that open every tensor file.
pub const TENSOR_MAGIC: &[u8; 12] = b"tensor_file\0";

/// Fields whose values are densities or areas and must be non-negative.
const NON_NEGATIVE_FIELDS: [&str; 4] = ["ndf", "sigma", "vndf", "luminance"];

/// Element type of a tensor field (the numbering of Mitsuba's/pbrt's `Struct::Type`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TensorDtype {
    /// Unsigned 8-bit integer (code 1).
    UInt8,
    /// Signed 8-bit integer (code 2).
    Int8,
    /// Unsigned 16-bit integer (code 3).
    UInt16,
    /// Signed 16-bit integer (code 4).
    Int16,
    /// Unsigned 32-bit integer (code 5).
    UInt32,
    /// Signed 32-bit integer (code 6).
    Int32,
    /// Unsigned 64-bit integer (code 7).
    UInt64,
    /// Signed 64-bit integer (code 8).
    Int64,
    /// IEEE half precision (code 9).
    Float16,
    /// IEEE single precision (code 10).
    Float32,
    /// IEEE double precision (code 11).
    Float64,
}

impl TensorDtype {
    /// The dtype of a file code, or `None` for 0 (invalid) and unknown codes.
    pub fn from_code(code: u8) -> Option<Self> {
        use TensorDtype::*;
        Some(match code {
            1 => UInt8,
            2 => Int8,
            3 => UInt16,
            4 => Int16,
            5 => UInt32,
            6 => Int32,
            7 => UInt64,
            8 => Int64,
            9 => Float16,
            10 => Float32,
            11 => Float64,
            _ => return None,
        })
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        use TensorDtype::*;
        match self {
            UInt8 | Int8 => 1,
            UInt16 | Int16 | Float16 => 2,
            UInt32 | Int32 | Float32 => 4,
            UInt64 | Int64 | Float64 => 8,
        }
    }

    /// True for the floating-point types.
    pub fn is_float(self) -> bool {
        matches!(
            self,
            TensorDtype::Float16 | TensorDtype::Float32 | TensorDtype::Float64
        )
    }

    /// A short name ("f32", "u8", ...).
    pub fn name(self) -> &'static str {
        use TensorDtype::*;
        match self {
            UInt8 => "u8",
            Int8 => "i8",
            UInt16 => "u16",
            Int16 => "i16",
            UInt32 => "u32",
            Int32 => "i32",
            UInt64 => "u64",
            Int64 => "i64",
            Float16 => "f16",
            Float32 => "f32",
            Float64 => "f64",
        }
    }
}

/// One named array of a tensor file.
#[derive(Clone, Debug, PartialEq)]
pub struct TensorField {
    /// The field's name.
    pub name: String,
    /// Element type.
    pub dtype: TensorDtype,
    /// Byte offset of the data in the file.
    pub offset: u64,
    /// Extent of each dimension (row-major, last fastest).
    pub shape: Vec<usize>,
    /// The raw little-endian data (`len() * dtype.size()` bytes).
    pub data: Vec<u8>,
}

impl TensorField {
    /// Number of elements (product of the shape).
    pub fn len(&self) -> usize {
        self.data.len() / self.dtype.size()
    }

    /// True when the field has no elements.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Every element converted to f64 (64-bit integers above 2^53 round).
    pub fn to_f64(&self) -> Vec<f64> {
        let s = self.dtype.size();
        self.data
            .chunks_exact(s)
            .map(|c| decode(self.dtype, c))
            .collect()
    }

    /// The data as text when it is a u8 field (the `description`), lossily decoded as UTF-8
    /// with trailing NULs removed.
    pub fn as_text(&self) -> Option<String> {
        (self.dtype == TensorDtype::UInt8).then(|| {
            String::from_utf8_lossy(&self.data)
                .trim_end_matches('\0')
                .to_string()
        })
    }
}

/// Decodes one little-endian element.
fn decode(dtype: TensorDtype, c: &[u8]) -> f64 {
    use TensorDtype::*;
    let a2 = |c: &[u8]| [c[0], c[1]];
    let a4 = |c: &[u8]| [c[0], c[1], c[2], c[3]];
    let a8 = |c: &[u8]| [c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]];
    match dtype {
        UInt8 => c[0] as f64,
        Int8 => c[0] as i8 as f64,
        UInt16 => u16::from_le_bytes(a2(c)) as f64,
        Int16 => i16::from_le_bytes(a2(c)) as f64,
        UInt32 => u32::from_le_bytes(a4(c)) as f64,
        Int32 => i32::from_le_bytes(a4(c)) as f64,
        UInt64 => u64::from_le_bytes(a8(c)) as f64,
        Int64 => i64::from_le_bytes(a8(c)) as f64,
        Float16 => half_to_f64(u16::from_le_bytes(a2(c))),
        Float32 => f32::from_le_bytes(a4(c)) as f64,
        Float64 => f64::from_le_bytes(a8(c)),
    }
}

/// IEEE 754 binary16 to f64.
fn half_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = ((h >> 10) & 0x1f) as i32;
    let man = (h & 0x3ff) as f64;
    sign * match exp {
        0 => man * 2f64.powi(-24),
        31 if man == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        e => (1.0 + man / 1024.0) * 2f64.powi(e - 15),
    }
}

/// A bounds-checked little-endian cursor over the header.
struct Cursor<'a> {
    b: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.b.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }
    fn u8(&mut self) -> Option<u8> {
        self.take(1).map(|s| s[0])
    }
    fn u16(&mut self) -> Option<u16> {
        self.take(2).map(|s| u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self) -> Option<u32> {
        self.take(4)
            .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8)
            .map(|s| u64::from_le_bytes([s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]]))
    }
    fn remaining(&self) -> usize {
        self.b.len().saturating_sub(self.pos)
    }
}

/// A parsed tensor file: every field with its name, dtype, shape and data.
#[derive(Clone, Debug)]
pub struct RglTensorFile {
    path: PathBuf,
    version: (u8, u8),
    fields: Vec<TensorField>,
}

impl RglTensorFile {
    /// Reads and parses a file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = crate::error::read_file(path)?;
        Self::parse(path, &bytes)
    }

    /// Parses the bytes of a tensor file; `path` only names the file in error messages. Checks
    /// the magic, the version (1.0, as pbrt-v4), the field table (names unique and non-empty
    /// UTF-8, known dtypes, shapes whose byte size neither overflows nor leaves the file, data
    /// regions that do not overlap), that every floating-point value is finite, and that the
    /// density fields (`ndf`, `sigma`, `vndf`, `luminance`) are non-negative. Never panics; no
    /// allocation is sized by the header before it is checked against the byte length.
    pub fn parse(path: impl AsRef<Path>, bytes: &[u8]) -> Result<Self> {
        let path = path.as_ref();
        let err = |p: String| Error::format(path, p);
        let mut c = Cursor { b: bytes, pos: 0 };
        let too_short = || {
            Error::format(
                path,
                format!(
                    "{} bytes: too short for a tensor file header (18 bytes)",
                    bytes.len()
                ),
            )
        };
        let magic = c.take(12).ok_or_else(too_short)?;
        if magic != TENSOR_MAGIC {
            return Err(err(format!(
                "not a tensor file: expected magic \"tensor_file\\0\", found {:?}",
                String::from_utf8_lossy(magic)
            )));
        }
        let version = c.take(2).ok_or_else(too_short)?;
        if version != [1, 0] {
            return Err(err(format!(
                "unknown tensor file version {}.{} (only 1.0 is supported)",
                version[0], version[1]
            )));
        }
        let n_fields = c.u32().ok_or_else(too_short)? as usize;
        // Each field entry takes at least 13 header bytes (name length, rank, dtype, offset).
        if n_fields > c.remaining() / 13 {
            return Err(err(format!(
                "header declares {n_fields} fields but only {} bytes follow",
                c.remaining()
            )));
        }
        let mut fields: Vec<TensorField> = Vec::with_capacity(n_fields);
        let mut names = std::collections::HashSet::with_capacity(n_fields);
        let mut ranges: Vec<(usize, usize, usize)> = Vec::with_capacity(n_fields);
        for k in 0..n_fields {
            let trunc =
                |what: &str| Error::format(path, format!("header truncated in field {k} ({what})"));
            let name_len = c.u16().ok_or_else(|| trunc("name length"))? as usize;
            let name = c.take(name_len).ok_or_else(|| trunc("name"))?;
            let name = std::str::from_utf8(name)
                .map_err(|_| err(format!("field {k}: name is not valid UTF-8")))?
                .to_string();
            if name.is_empty() {
                return Err(err(format!("field {k} has an empty name")));
            }
            if !names.insert(name.clone()) {
                return Err(err(format!("field \"{name}\" appears twice")));
            }
            let ndim = c.u16().ok_or_else(|| trunc("rank"))? as usize;
            let code = c.u8().ok_or_else(|| trunc("dtype"))?;
            let dtype = TensorDtype::from_code(code)
                .ok_or_else(|| err(format!("field \"{name}\": unknown dtype code {code}")))?;
            let offset = c.u64().ok_or_else(|| trunc("offset"))?;
            if ndim > c.remaining() / 8 {
                return Err(trunc("shape"));
            }
            let mut shape = Vec::with_capacity(ndim);
            let mut count: u64 = 1;
            for _ in 0..ndim {
                let d = c.u64().ok_or_else(|| trunc("shape"))?;
                count = count.checked_mul(d).ok_or_else(|| {
                    err(format!(
                        "field \"{name}\": shape {shape:?}x{d}... overflows"
                    ))
                })?;
                shape.push(d);
            }
            let size = count.checked_mul(dtype.size() as u64).ok_or_else(|| {
                err(format!(
                    "field \"{name}\": shape {shape:?} is too large (size overflows)"
                ))
            })?;
            let end = offset
                .checked_add(size)
                .filter(|&e| e <= bytes.len() as u64)
                .ok_or_else(|| {
                    err(format!(
                        "field \"{name}\": data of {size} bytes at offset {offset} lies beyond \
                         the end of the file ({} bytes)",
                        bytes.len()
                    ))
                })?;
            // Both fit in the file length, so the conversions are lossless.
            let (start, end) = (offset as usize, end as usize);
            let shape: Vec<usize> = shape.into_iter().map(|d| d as usize).collect();
            ranges.push((start, end, k));
            fields.push(TensorField {
                name,
                dtype,
                offset,
                shape,
                data: Vec::new(),
            });
        }
        // Field data must not overlap (which also bounds the copies below by the file length).
        ranges.sort_unstable();
        for pair in ranges.windows(2) {
            let ((_, e0, a), (s1, _, b)) = (pair[0], pair[1]);
            if s1 < e0 {
                return Err(err(format!(
                    "fields \"{}\" and \"{}\" overlap in the file",
                    fields[a].name, fields[b].name
                )));
            }
        }
        for &(start, end, k) in &ranges {
            let f = &mut fields[k];
            f.data = bytes[start..end].to_vec();
            if f.dtype.is_float() {
                let nn = NON_NEGATIVE_FIELDS.contains(&f.name.as_str());
                let s = f.dtype.size();
                for (i, ch) in f.data.chunks_exact(s).enumerate() {
                    let v = decode(f.dtype, ch);
                    if !v.is_finite() {
                        return Err(err(format!("field \"{}\": value {i} is {v}", f.name)));
                    }
                    if nn && v < 0.0 {
                        return Err(err(format!(
                            "field \"{}\": value {i} is negative ({v}) in a density table",
                            f.name
                        )));
                    }
                }
            }
        }
        Ok(RglTensorFile {
            path: path.to_path_buf(),
            version: (version[0], version[1]),
            fields,
        })
    }

    /// The path given to [`RglTensorFile::parse`] or [`RglTensorFile::read`].
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// File format version (major, minor).
    pub fn version(&self) -> (u8, u8) {
        self.version
    }

    /// All fields in file order.
    pub fn fields(&self) -> &[TensorField] {
        &self.fields
    }

    /// The field of that name, if present.
    pub fn field(&self, name: &str) -> Option<&TensorField> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// The field of that name with the given dtype and rank, or an error naming file and field.
    fn require(&self, name: &str, dtype: TensorDtype, ndim: usize) -> Result<&TensorField> {
        let f = self.field(name).ok_or_else(|| {
            Error::format(
                &self.path,
                format!("RGL BSDF: required field \"{name}\" is missing"),
            )
        })?;
        if f.dtype != dtype || f.shape.len() != ndim {
            return Err(Error::format(
                &self.path,
                format!(
                    "RGL BSDF: field \"{name}\" is {} with shape {:?}, expected {} with {ndim} \
                     dimensions",
                    f.dtype.name(),
                    f.shape,
                    dtype.name()
                ),
            ));
        }
        Ok(f)
    }
}

/// The measured NDF table on its own grid: D(θ, φ) in 1/sr at θ = `theta[j]`, φ = `phi[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct NdfGrid {
    /// θ nodes (radians), θ = (j / (n − 1))² π/2 (the file's u ↦ θ map).
    pub theta: Vec<f64>,
    /// φ nodes (radians) in [−π, π]; relative to φ of `wo` in isotropic files.
    pub phi: Vec<f64>,
    /// D values, row-major `[phi][theta]`.
    pub values: Vec<f64>,
}

/// A measured BSDF from an RGL tensor file (Mitsuba 3's `measured` plugin, RGB variant).
#[derive(Clone, Debug)]
pub struct RglBsdf {
    name: String,
    description: String,
    theta_i: Vec<f64>,
    phi_i: Vec<f64>,
    ndf: Marginal2D,
    sigma: Marginal2D,
    vndf: Marginal2D,
    luminance: Marginal2D,
    rgb: Marginal2D,
    isotropic: bool,
    jacobian: bool,
    reduction: u32,
}

/// Mitsuba `measured.cpp` `u2theta`: u ∈ [0, 1] ↦ θ = u² π/2.
#[inline]
pub fn u2theta(u: f64) -> f64 {
    u * u * (PI / 2.0)
}

/// Mitsuba `measured.cpp` `u2phi`: u ∈ [0, 1] ↦ φ = (2u − 1) π.
#[inline]
pub fn u2phi(u: f64) -> f64 {
    (2.0 * u - 1.0) * PI
}

/// Mitsuba `measured.cpp` `theta2u`: the inverse of [`u2theta`].
#[inline]
pub fn theta2u(theta: f64) -> f64 {
    (theta * (2.0 / PI)).max(0.0).sqrt()
}

/// Mitsuba `measured.cpp` `phi2u`: the inverse of [`u2phi`].
#[inline]
pub fn phi2u(phi: f64) -> f64 {
    (phi + PI) * (0.5 / PI)
}

/// Mitsuba's `elevation`: θ of a unit vector, accurate near the pole.
#[inline]
fn elevation(d: DVec3) -> f64 {
    let dist = (d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0)).sqrt();
    2.0 * (0.5 * dist).clamp(-1.0, 1.0).asin()
}

/// drjit's `mulsign_neg(a, b)`: −a when b's sign bit is clear, a when it is set.
#[inline]
fn mulsign_neg(a: f64, b: f64) -> f64 {
    if b.is_sign_negative() {
        a
    } else {
        -a
    }
}

/// What eval and pdf share: the folded pair in the table's coordinates.
struct Config {
    theta_i: f64,
    phi_i: f64,
    u_wi: (f64, f64),
    u_m: (f64, f64),
    m: DVec3,
    v: DVec3,
}

impl RglBsdf {
    /// Reads an RGL `.bsdf` file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        Self::from_tensor(&RglTensorFile::read(path)?)
    }

    /// Parses the bytes of an RGL `.bsdf` file (`path` names it in messages). Never panics.
    pub fn parse(path: impl AsRef<Path>, bytes: &[u8]) -> Result<Self> {
        Self::from_tensor(&RglTensorFile::parse(path, bytes)?)
    }

    /// Builds the BSDF from a parsed tensor, checking the field structure exactly as Mitsuba's
    /// `Measured` constructor does (RGB branch). Files with `spectra`/`wavelengths` instead of
    /// `rgb` are refused with an error saying so (spectral-to-RGB conversion is not done here).
    pub fn from_tensor(t: &RglTensorFile) -> Result<Self> {
        use TensorDtype::{Float32, UInt8};
        let path = t.path();
        let bad = |p: String| Error::format(path, format!("RGL BSDF: {p}"));
        if t.field("rgb").is_none() && t.field("spectra").is_some() {
            let n = t
                .field("wavelengths")
                .and_then(|f| f.shape.first().copied())
                .unwrap_or(0);
            return Err(bad(format!(
                "spectral measurement (field \"spectra\", {n} wavelengths) without an \"rgb\" \
                 field: only the RGB files (*_rgb.bsdf) of the RGL database are supported"
            )));
        }
        let description = t
            .require("description", UInt8, 1)?
            .as_text()
            .unwrap_or_default();
        let theta_i_f = t.require("theta_i", Float32, 1)?;
        let phi_i_f = t.require("phi_i", Float32, 1)?;
        let ndf_f = t.require("ndf", Float32, 2)?;
        let sigma_f = t.require("sigma", Float32, 2)?;
        let vndf_f = t.require("vndf", Float32, 4)?;
        let lum_f = t.require("luminance", Float32, 4)?;
        let rgb_f = t.require("rgb", Float32, 5)?;
        let jac_f = t.require("jacobian", UInt8, 1)?;
        let (n_theta, n_phi) = (theta_i_f.shape[0], phi_i_f.shape[0]);
        let (vs, ls, rs) = (&vndf_f.shape, &lum_f.shape, &rgb_f.shape);
        let shape_ok = vs[0] == n_phi
            && vs[1] == n_theta
            && ls[0] == n_phi
            && ls[1] == n_theta
            && ls[2] == ls[3]
            && rs[0] == n_phi
            && rs[1] == n_theta
            && rs[2] == 3
            && rs[3] == rs[4]
            && ls[2] == rs[3]
            && ls[3] == rs[4]
            && jac_f.shape[0] == 1;
        if !shape_ok {
            return Err(bad(format!(
                "inconsistent shapes: theta_i [{n_theta}], phi_i [{n_phi}], vndf {vs:?}, \
                 luminance {ls:?}, rgb {rs:?}, jacobian {:?} (expected vndf [phi_i, theta_i, h, \
                 w], luminance [phi_i, theta_i, n, n], rgb [phi_i, theta_i, 3, n, n], jacobian [1])",
                jac_f.shape
            )));
        }
        let theta_i = theta_i_f.to_f64();
        let phi_i = phi_i_f.to_f64();
        let isotropic = n_phi <= 2;
        let jacobian = jac_f.data.first().copied().unwrap_or(0) != 0;
        let reduction = if isotropic {
            1
        } else {
            let span = phi_i[n_phi - 1] - phi_i[0];
            let r = (2.0 * PI / span).round();
            if !(r == 1.0 || r == 2.0 || r == 4.0) {
                return Err(bad(format!(
                    "phi_i spans {span} rad: symmetry reduction {r} is not 1, 2 or 4"
                )));
            }
            r as u32
        };
        let build = |f: &TensorField, w: usize, h: usize, params: Vec<Vec<f64>>, norm: bool| {
            Marginal2D::new(&f.to_f64(), w, h, params, norm, norm)
                .map_err(|e| bad(format!("field \"{}\": {e}", f.name)))
        };
        let ndf = build(ndf_f, ndf_f.shape[1], ndf_f.shape[0], vec![], false)?;
        let sigma = build(sigma_f, sigma_f.shape[1], sigma_f.shape[0], vec![], false)?;
        let pp = vec![phi_i.clone(), theta_i.clone()];
        let vndf = build(vndf_f, vs[3], vs[2], pp.clone(), true)?;
        let luminance = build(lum_f, ls[3], ls[2], pp, true)?;
        let rgb = build(
            rgb_f,
            rs[4],
            rs[3],
            vec![phi_i.clone(), theta_i.clone(), vec![0.0, 1.0, 2.0]],
            false,
        )?;
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        Ok(RglBsdf {
            name: format!("RGL measured ({stem})"),
            description,
            theta_i,
            phi_i,
            ndf,
            sigma,
            vndf,
            luminance,
            rgb,
            isotropic,
            jacobian,
            reduction,
        })
    }

    /// The file's `description` text.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// True when the file has at most two φi nodes (Mitsuba's isotropy test).
    pub fn is_isotropic(&self) -> bool {
        self.isotropic
    }

    /// The file's `jacobian` flag: the rgb table is multiplied by D(m)/(4σ(wo)) when set.
    pub fn jacobian(&self) -> bool {
        self.jacobian
    }

    /// Symmetry reduction of an anisotropic file (φi covers 2π/reduction); 1 when isotropic.
    pub fn reduction(&self) -> u32 {
        self.reduction
    }

    /// The tables: the NDF, σ, the VNDF, the luminance and the RGB values (Mitsuba's
    /// `Measured` fields, in that order).
    pub fn tables(&self) -> [&Marginal2D; 5] {
        [
            &self.ndf,
            &self.sigma,
            &self.vndf,
            &self.luminance,
            &self.rgb,
        ]
    }

    /// The θi nodes of the tables (radians).
    pub fn theta_i(&self) -> &[f64] {
        &self.theta_i
    }

    /// The φi nodes of the tables (radians).
    pub fn phi_i(&self) -> &[f64] {
        &self.phi_i
    }

    /// The measured microfacet NDF D(θh, φh) in 1/sr (bilinear in the file's (√(2θ/π), φ)
    /// parameterization). In isotropic files φh is relative to φ of `wo` and D does not depend
    /// on it. Normalized as ∫ D(h) cos θh dωh = 1 (checked by the tests).
    pub fn ndf(&self, theta_h: f64, phi_h: f64) -> f64 {
        let u = phi2u(phi_h);
        self.ndf.eval((theta2u(theta_h), u - u.floor()), &[])
    }

    /// The projected microfacet area σ(θ, φ) = ∫ D(h) max(0, ω·h) dωh of a direction ω,
    /// from the file's `sigma` table (1 at normal incidence).
    pub fn sigma(&self, theta: f64, phi: f64) -> f64 {
        let u = phi2u(phi);
        self.sigma.eval((theta2u(theta), u - u.floor()), &[])
    }

    /// The NDF table at its nodes.
    pub fn ndf_grid(&self) -> NdfGrid {
        let (w, h) = self.ndf.size();
        let node = |k: usize, n: usize| k as f64 / (n - 1) as f64;
        NdfGrid {
            theta: (0..w).map(|j| u2theta(node(j, w))).collect(),
            phi: (0..h).map(|i| u2phi(node(i, h))).collect(),
            values: self.ndf.slice(&[]).map(<[f64]>::to_vec).unwrap_or_default(),
        }
    }

    /// Folds the pair by the file's symmetry (Mitsuba's `mulsign_neg` reduction) and computes
    /// the table coordinates. `v` is the conditioning direction (this crate's `wo`), `l` the
    /// other one. Both must be strictly above the surface.
    fn config(&self, l: DVec3, v: DVec3) -> Option<(Config, (f64, f64))> {
        if !(l.is_finite() && v.is_finite()) || l.z <= 0.0 || v.z <= 0.0 {
            return None;
        }
        let (sx, sy) = self.fold_signs(v);
        let fold = |d: DVec3| DVec3::new(mulsign_neg(d.x, sx), mulsign_neg(d.y, sy), d.z);
        let (v, l) = (fold(v), fold(l));
        let m = (v + l).try_normalize()?;
        let theta_i = elevation(v);
        let phi_i = v.y.atan2(v.x);
        let theta_m = elevation(m);
        let phi_m = m.y.atan2(m.x);
        let u_wi = (theta2u(theta_i), phi2u(phi_i));
        let uy = phi2u(if self.isotropic { phi_m - phi_i } else { phi_m });
        let u_m = (theta2u(theta_m), uy - uy.floor());
        Some((
            Config {
                theta_i,
                phi_i,
                u_wi,
                u_m,
                m,
                v,
            },
            (sx, sy),
        ))
    }

    /// The signs Mitsuba folds by: (−1, −1) (no change) unless the file is reduced.
    fn fold_signs(&self, v: DVec3) -> (f64, f64) {
        if self.reduction >= 2 {
            let sy = v.y;
            let sx = if self.reduction == 4 { v.x } else { sy };
            (sx, sy)
        } else {
            (-1.0, -1.0)
        }
    }

    /// f·cos θl as Mitsuba's `eval` returns it, per channel, with negative (out-of-gamut) RGB
    /// values clamped to 0 as pbrt-v4 does.
    fn eval_cos(&self, c: &Config) -> Rgb {
        let params = [c.phi_i, c.theta_i];
        let Some((s, _)) = self.vndf.invert(c.u_m, &params) else {
            return Rgb::ZERO;
        };
        let mut spec = Rgb::ZERO;
        for ch in 0..3 {
            spec[ch] = self.rgb.eval(s, &[c.phi_i, c.theta_i, ch as f64]).max(0.0);
        }
        if self.jacobian {
            let sigma = self.sigma.eval(c.u_wi, &[]);
            if sigma.is_nan() || sigma <= 0.0 {
                return Rgb::ZERO;
            }
            spec *= self.ndf.eval(c.u_m, &[]) / (4.0 * sigma);
        }
        spec
    }

    /// Mitsuba's `pdf` for a configuration.
    fn pdf_config(&self, c: &Config) -> f64 {
        let params = [c.phi_i, c.theta_i];
        let Some((s, vndf_pdf)) = self.vndf.invert(c.u_m, &params) else {
            return 0.0;
        };
        let lum_pdf = self.luminance.eval(s, &params);
        let sin_m = (c.m.x * c.m.x + c.m.y * c.m.y).sqrt();
        // dω_l = 4 (v·m) dω_m and dω_m = 2π² u_x sin θm du (θ = u_x² π/2, φ = (2u_y − 1)π).
        // Mitsuba clamps the first factor at 1e-6 (an f32 guard); that makes pdf() smaller than
        // the true density of sample() for θm < ~1e-5, where a Hammersley point at u = 0 then
        // gets a weight of 1e4. In f64 the exact Jacobian is used instead.
        let jac = 2.0 * PI * PI * c.u_m.0 * sin_m * 4.0 * c.v.dot(c.m);
        let p = vndf_pdf * lum_pdf / jac;
        if p.is_finite() && p > 0.0 {
            p
        } else {
            0.0
        }
    }
}

impl Bsdf for RglBsdf {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        let Some((c, _)) = self.config(wi, wo) else {
            return Rgb::ZERO;
        };
        let f = self.eval_cos(&c) / wi.z;
        if f.is_finite() {
            f
        } else {
            Rgb::ZERO
        }
    }

    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        if !wo.is_finite() || wo.z <= 0.0 {
            return None;
        }
        let (sx, sy) = self.fold_signs(wo);
        let v = DVec3::new(mulsign_neg(wo.x, sx), mulsign_neg(wo.y, sy), wo.z);
        let theta_i = elevation(v);
        let phi_i = v.y.atan2(v.x);
        let params = [phi_i, theta_i];
        // Luminance warp first, then the VNDF warp (MI_SAMPLE_LUMINANCE = 1).
        let (s, _) = self.luminance.sample((u2, u1), &params)?;
        let (u_m, _) = self.vndf.sample(s, &params)?;
        let mut phi_m = u2phi(u_m.1);
        if self.isotropic {
            phi_m += phi_i;
        }
        let m = crate::frame::spherical(u2theta(u_m.0), phi_m);
        let l = 2.0 * m.dot(v) * m - v;
        let wi = DVec3::new(mulsign_neg(l.x, sx), mulsign_neg(l.y, sy), l.z);
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        // Value and density through eval/pdf, so that they are exactly what those report.
        let pdf = self.pdf(wi, wo);
        (pdf > 0.0)
            .then(|| BsdfSample::new(wi, self.eval(wi, wo), pdf, LobeFlags::GLOSSY_REFLECTION))
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        match self.config(wi, wo) {
            Some((c, _)) => self.pdf_config(&c),
            None => 0.0,
        }
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }

    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            // Measured data is not reciprocal in general; energy conservation is not
            // guaranteed by the tables (the tests measure the albedo instead).
            reciprocal: false,
            energy_conserving: false,
            transmission: false,
            anisotropic: !self.isotropic,
            lobes: LobeFlags::GLOSSY_REFLECTION,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn u_maps_invert() {
        for &t in &[0.0, 0.1, 0.7, PI / 2.0] {
            assert!((u2theta(theta2u(t)) - t).abs() < 1e-14);
        }
        for &p in &[-PI, -1.0, 0.0, 2.0, PI] {
            assert!((u2phi(phi2u(p)) - p).abs() < 1e-14);
        }
        assert!((elevation(DVec3::new(0.6, 0.0, 0.8)) - 0.8f64.acos()).abs() < 1e-14);
    }

    #[test]
    fn half_floats_decode() {
        assert_eq!(half_to_f64(0x3c00), 1.0);
        assert_eq!(half_to_f64(0xc000), -2.0);
        assert_eq!(half_to_f64(0x0001), 2f64.powi(-24));
        assert!(half_to_f64(0x7c00).is_infinite() && half_to_f64(0x7e00).is_nan());
    }

    #[test]
    fn mulsign_neg_matches_drjit() {
        assert_eq!(mulsign_neg(2.0, 1.0), -2.0);
        assert_eq!(mulsign_neg(2.0, 0.0), -2.0);
        assert_eq!(mulsign_neg(2.0, -0.0), 2.0);
        assert_eq!(mulsign_neg(-2.0, -3.0), -2.0);
    }
}
