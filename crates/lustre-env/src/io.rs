//! Readers for Radiance `.hdr` (RGBE) and OpenEXR environment maps.
//!
//! Every reader returns a [`LoadedMap`]: the equirect map with non-finite texels (NaN, ±Inf)
//! and negative channel values replaced by 0, and the counts of texels so sanitized. Errors
//! name the file and the problem; no byte sequence makes a reader panic.

use crate::equirect::{EquirectMap, MAX_WIDTH};
use crate::error::{EnvError, Result};
use std::io::Cursor;
use std::path::{Path, PathBuf};

/// An environment map as read from a file, with the counts of sanitized texels.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedMap {
    /// The map (non-finite and negative channel values replaced by 0).
    pub map: EquirectMap,
    /// Number of texels that had a NaN or infinite channel (set to 0).
    pub nonfinite: usize,
    /// Number of texels that had a negative channel (set to 0).
    pub negative: usize,
}

impl LoadedMap {
    /// The warning every command prints for a map whose texels were sanitized (`None` when
    /// none was): `FILE: N non-finite and M negative texels were set to 0`.
    pub fn sanitized_warning(&self, path: &Path) -> Option<String> {
        (self.nonfinite + self.negative > 0).then(|| {
            format!(
                "{}: {} non-finite and {} negative texels were set to 0",
                path.display(),
                self.nonfinite,
                self.negative
            )
        })
    }
}

/// The Radiance magic (`#?RADIANCE` or `#?RGBE`, both start with `#?`).
const HDR_MAGIC: &[u8] = b"#?";
/// The OpenEXR magic number 20000630 (little endian).
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
/// The smallest map height a file may have: a 2×1 or 4×2 image is no environment.
pub const MIN_FILE_HEIGHT: usize = 4;

/// The directory of the shared data (`LUSTRE_DATA`, else `../shared/data` next to the
/// repository), where the test environment maps live under `envmaps/`.
pub fn shared_data_dir() -> PathBuf {
    if let Some(p) = std::env::var_os("LUSTRE_DATA") {
        return p.into();
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data")
}

fn format_err(path: &Path, problem: impl Into<String>) -> EnvError {
    EnvError::Format {
        path: path.to_path_buf(),
        problem: problem.into(),
    }
}

/// The width and height an environment map's header declares, read from its first bytes only
/// (at most 1 MB), so that a job can count the map's memory before it decodes it. The file is
/// checked as [`read_map`] checks it (a regular file of at most 4 GB); a header this cannot
/// read is an error, as it would be for [`read_map`].
pub fn map_size(path: &Path) -> Result<(usize, usize)> {
    use std::io::Read;
    let io = |source| EnvError::Io {
        path: path.to_path_buf(),
        source,
    };
    lustre_brdf::error::check_input(path).map_err(io)?;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(1 << 20).read_to_end(&mut head))
        .map_err(io)?;
    if head.starts_with(&EXR_MAGIC) {
        let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(&head), false)
            .map_err(|e| format_err(path, format!("bad OpenEXR header: {e}")))?;
        // The largest layer: an upper bound of the one the reader takes.
        meta.headers
            .iter()
            .map(|h| (h.layer_size.width(), h.layer_size.height()))
            .max_by_key(|&(w, h)| w.saturating_mul(h))
            .ok_or_else(|| format_err(path, "an OpenEXR file without a layer"))
    } else if head.starts_with(HDR_MAGIC) {
        let decoder = image::codecs::hdr::HdrDecoder::new(Cursor::new(&head))
            .map_err(|e| format_err(path, format!("bad Radiance header: {e}")))?;
        let meta = decoder.metadata();
        Ok((meta.width as usize, meta.height as usize))
    } else {
        Err(not_a_map(path, &head))
    }
}

/// Reads an environment map, `.hdr` or `.exr`, chosen by the file's magic bytes.
pub fn read_map(path: &Path) -> Result<LoadedMap> {
    let bytes = lustre_brdf::error::read_input(path).map_err(|source| EnvError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.starts_with(&EXR_MAGIC) {
        parse_exr(path, &bytes)
    } else if bytes.starts_with(HDR_MAGIC) {
        parse_hdr(path, &bytes)
    } else {
        Err(not_a_map(path, &bytes))
    }
}

/// The error of a file that starts with neither map's magic number.
fn not_a_map(path: &Path, bytes: &[u8]) -> EnvError {
    if bytes.is_empty() {
        format_err(path, "empty file")
    } else {
        format_err(
            path,
            "not an environment map: neither the Radiance '#?' nor the OpenEXR magic number",
        )
    }
}

/// Checks a decoded map's shape and sanitizes its texels.
fn finish(path: &Path, width: usize, height: usize, mut data: Vec<[f32; 3]>) -> Result<LoadedMap> {
    if width == 0 || height == 0 {
        return Err(format_err(
            path,
            format!("image has zero size ({width}×{height})"),
        ));
    }
    if width != 2 * height {
        return Err(format_err(
            path,
            format!("{width}×{height} is not an equirectangular map (width must be 2 × height)"),
        ));
    }
    let mut nonfinite = 0;
    let mut negative = 0;
    for px in &mut data {
        if px.iter().any(|v| !v.is_finite()) {
            nonfinite += 1;
            for v in px.iter_mut() {
                if !v.is_finite() {
                    *v = 0.0;
                }
            }
        }
        if px.iter().any(|v| *v < 0.0) {
            negative += 1;
            for v in px.iter_mut() {
                if *v < 0.0 {
                    *v = 0.0;
                }
            }
        }
    }
    if height < MIN_FILE_HEIGHT {
        return Err(format_err(
            path,
            format!(
                "a {width}×{height} map is too small to be an environment (at least \
                 {}×{MIN_FILE_HEIGHT} pixels)",
                2 * MIN_FILE_HEIGHT
            ),
        ));
    }
    let map = EquirectMap::new(width, height, data).map_err(|e| format_err(path, e.to_string()))?;
    Ok(LoadedMap {
        map,
        nonfinite,
        negative,
    })
}

/// Parses a Radiance `.hdr` (RGBE, run-length encoded or flat) held in `bytes`; `path` names
/// the file in errors.
pub fn parse_hdr(path: &Path, bytes: &[u8]) -> Result<LoadedMap> {
    if bytes.is_empty() {
        return Err(format_err(path, "empty file"));
    }
    if !bytes.starts_with(HDR_MAGIC) {
        return Err(format_err(path, "not a Radiance .hdr file (no '#?' magic)"));
    }
    let decoder = image::codecs::hdr::HdrDecoder::new(Cursor::new(bytes))
        .map_err(|e| format_err(path, format!("bad Radiance header: {e}")))?;
    let meta = decoder.metadata();
    let (w, h) = (meta.width as usize, meta.height as usize);
    if w == 0 || h == 0 {
        return Err(format_err(path, format!("image has zero size ({w}×{h})")));
    }
    if w != 2 * h {
        return Err(format_err(
            path,
            format!("{w}×{h} is not an equirectangular map (width must be 2 × height)"),
        ));
    }
    if w > MAX_WIDTH {
        return Err(format_err(path, format!("width {w} exceeds {MAX_WIDTH}")));
    }
    // Each RLE scanline needs at least a few bytes per 32 pixels: refuse headers that promise
    // far more pixels than the file could hold before allocating for them.
    if (w * h) / 128 > bytes.len() {
        return Err(format_err(
            path,
            format!(
                "truncated: {w}×{h} pixels cannot fit in {} bytes",
                bytes.len()
            ),
        ));
    }
    let img = image::DynamicImage::from_decoder(decoder)
        .map_err(|e| format_err(path, format!("cannot decode Radiance pixels: {e}")))?;
    let rgb = img.into_rgb32f();
    let data: Vec<[f32; 3]> = rgb.pixels().map(|p| p.0).collect();
    finish(path, w, h, data)
}

/// Parses an OpenEXR file held in `bytes` (first layer with R, G, B channels, largest
/// resolution level); `path` names the file in errors. A compression the decoder does not
/// handle is a `Format` error naming it.
pub fn parse_exr(path: &Path, bytes: &[u8]) -> Result<LoadedMap> {
    use exr::prelude::*;
    if bytes.is_empty() {
        return Err(format_err(path, "empty file"));
    }
    if !bytes.starts_with(&EXR_MAGIC) {
        return Err(format_err(path, "not an OpenEXR file (bad magic number)"));
    }
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| format_err(path, format!("bad OpenEXR header: {e}")))?;
    let header = meta
        .headers
        .iter()
        .find(|h| {
            !h.deep
                && ["R", "G", "B"]
                    .iter()
                    .all(|c| h.channels.list.iter().any(|ch| ch.name.eq(c)))
        })
        .ok_or_else(|| format_err(path, "no flat layer with R, G and B channels"))?;
    let compression = header.compression;
    let (w, h) = (header.layer_size.width(), header.layer_size.height());
    if w == 0 || h == 0 {
        return Err(format_err(path, format!("image has zero size ({w}×{h})")));
    }
    if w != 2 * h {
        return Err(format_err(
            path,
            format!("{w}×{h} is not an equirectangular map (width must be 2 × height)"),
        ));
    }
    // Refuse headers that promise far more pixels than the file could hold, before the reader
    // allocates for them: real ZIP/PIZ/DWA maps hold ≥ 0.4 byte per pixel (DWAB, measured on
    // the shared studio maps), so 1/32 byte per pixel leaves a wide margin.
    if w > MAX_WIDTH || w.saturating_mul(h) / 32 > bytes.len() {
        return Err(format_err(
            path,
            format!(
                "{w}×{h} pixels are implausible for a {} byte file",
                bytes.len()
            ),
        ));
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .specific_channels()
        .required("R")
        .required("G")
        .required("B")
        .collect_pixels(
            |res, _| vec![[0.0f32; 3]; res.width() * res.height()],
            move |px: &mut Vec<[f32; 3]>, pos, (r, g, b): (f32, f32, f32)| {
                if let Some(v) = px.get_mut(pos.y() * w + pos.x()) {
                    *v = [r, g, b];
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| {
            let name = format!("{compression:?}");
            format_err(
                path,
                format!(
                    "cannot decode OpenEXR pixels ({} compression): {e}",
                    name.to_uppercase()
                ),
            )
        })?;
    let size = image.layer_data.size;
    if size.width() != w || size.height() != h {
        return Err(format_err(path, "layer size differs from its header"));
    }
    finish(path, w, h, image.layer_data.channel_data.pixels)
}
