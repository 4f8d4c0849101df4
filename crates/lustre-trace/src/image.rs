//! Float RGB images (linear radiance) and their display encoding; PNG (sRGB, 8 bit) and
//! OpenEXR (32-bit float) output, both written atomically.

use std::io::Cursor;
use std::path::Path;

use crate::error::{Result, TraceError};

/// A float RGB image, row-major, row 0 at the top, linear radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width · height` pixels, pixel (x, y) at `data[y * width + x]`.
    pub data: Vec<[f32; 3]>,
}

/// The sRGB opto-electronic transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_oetf(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse of [`srgb_oetf`]: display value in [0, 1] to linear.
pub fn srgb_eotf(v: f64) -> f64 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// The display value of a linear channel: `v · exposure` clamped to [0, 1] (NaN → 0), then
/// [`srgb_oetf`].
pub fn display_value(v: f64, exposure: f64) -> f64 {
    let x = v * exposure;
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    srgb_oetf(x)
}

/// Encodes interleaved 8-bit RGB as PNG and writes it atomically.
fn write_png_bytes(path: &Path, width: usize, height: usize, rgb: Vec<u8>) -> Result<()> {
    let bytes = encode_png(path, width, height, rgb)?;
    lustre_brdf::error::write_atomic(path, &bytes)?;
    Ok(())
}

/// An 8-bit RGB PNG file's bytes (`path` names it in errors).
fn encode_png(path: &Path, width: usize, height: usize, rgb: Vec<u8>) -> Result<Vec<u8>> {
    let buf = image::RgbImage::from_raw(width as u32, height as u32, rgb)
        .ok_or_else(|| encode_error(path, "PNG", "buffer size mismatch"))?;
    let mut bytes = Vec::new();
    buf.write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
        .map_err(|e| encode_error(path, "PNG", e))?;
    Ok(bytes)
}

fn encode_error(path: &Path, what: &str, e: impl std::fmt::Display) -> TraceError {
    TraceError::Io {
        path: path.to_path_buf(),
        source: std::io::Error::other(format!("{what} encoding failed: {e}")),
    }
}

impl Image {
    /// A black image; an error when a side is zero or the pixel count overflows.
    pub fn new(width: usize, height: usize) -> Result<Self> {
        let n = Self::check_size(width, height)?;
        Ok(Image {
            width,
            height,
            data: vec![[0.0; 3]; n],
        })
    }

    /// An image from its pixels; an error when `data.len() != width · height` or a side is 0.
    pub fn from_data(width: usize, height: usize, data: Vec<[f32; 3]>) -> Result<Self> {
        let n = Self::check_size(width, height)?;
        if data.len() != n {
            return Err(TraceError::Parameter(format!(
                "image: {width}x{height} needs {n} pixels, got {}",
                data.len()
            )));
        }
        Ok(Image {
            width,
            height,
            data,
        })
    }

    fn check_size(width: usize, height: usize) -> Result<usize> {
        if width == 0 || height == 0 {
            return Err(TraceError::Parameter(format!(
                "image: size {width}x{height} must be non-zero"
            )));
        }
        width
            .checked_mul(height)
            .filter(|&n| n <= u32::MAX as usize)
            .ok_or_else(|| TraceError::Parameter(format!("image: size {width}x{height} too large")))
    }

    /// The pixel at column `x`, row `y` (row 0 at the top). Panics when out of range.
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the image"
        );
        self.data[y * self.width + x]
    }

    /// Sets the pixel at column `x`, row `y`. Panics when out of range.
    pub fn set(&mut self, x: usize, y: usize, v: [f32; 3]) {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside the image"
        );
        self.data[y * self.width + x] = v;
    }

    /// Display values in [0, 1] per pixel ([`display_value`]: exposure, clamp, sRGB OETF).
    pub fn to_display(&self, exposure: f64) -> Vec<[f64; 3]> {
        self.data
            .iter()
            .map(|p| p.map(|c| display_value(c as f64, exposure)))
            .collect()
    }

    /// Interleaved 8-bit sRGB (R, G, B per pixel, row 0 first): [`display_value`] rounded to
    /// the nearest of 0 … 255.
    pub fn to_srgb8(&self, exposure: f64) -> Vec<u8> {
        self.data
            .iter()
            .flat_map(|p| p.map(|c| (display_value(c as f64, exposure) * 255.0).round() as u8))
            .collect()
    }

    /// Interleaved 8-bit sRGB like [`Image::to_srgb8`] with triangular dither of ±1 step (the
    /// sum of two uniform hashes of pixel, channel and `seed`): smooth gradients do not band.
    pub fn to_srgb8_dithered(&self, exposure: f64, seed: u64) -> Vec<u8> {
        let unit = |k: u64| {
            let mut z = k.wrapping_add(0x9E37_79B9_7F4A_7C15);
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        self.data
            .iter()
            .enumerate()
            .flat_map(|(i, p)| {
                (0..3).map(move |c| {
                    let k = seed ^ ((i as u64 * 3 + c as u64) << 1);
                    let d = unit(k) + unit(k ^ 1) - 1.0;
                    let v = display_value(f64::from(p[c]), exposure) * 255.0 + d;
                    v.round().clamp(0.0, 255.0) as u8
                })
            })
            .collect()
    }

    /// Writes an 8-bit sRGB PNG ([`Image::to_srgb8_dithered`]) atomically.
    pub fn write_png_dithered(&self, path: &Path, exposure: f64, seed: u64) -> Result<()> {
        let bytes = self.encode_png_dithered(exposure, seed)?;
        lustre_brdf::error::write_atomic(path, &bytes)?;
        Ok(())
    }

    /// The PNG file [`Image::write_png_dithered`] writes, in memory.
    pub fn encode_png_dithered(&self, exposure: f64, seed: u64) -> Result<Vec<u8>> {
        encode_png(
            Path::new("(in memory)"),
            self.width,
            self.height,
            self.to_srgb8_dithered(exposure, seed),
        )
    }

    /// Writes an 8-bit sRGB PNG ([`Image::to_srgb8`]) atomically.
    pub fn write_png(&self, path: &Path, exposure: f64) -> Result<()> {
        write_png_bytes(path, self.width, self.height, self.to_srgb8(exposure))
    }

    /// Reads an image file (OpenEXR, or anything the `image` crate reads) as linear RGB.
    pub fn read_exr(path: &Path) -> Result<Image> {
        lustre_brdf::error::check_input(path).map_err(|e| TraceError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let img = image::open(path)
            .map_err(|e| TraceError::Parameter(format!("cannot read {}: {e}", path.display())))?;
        let rgb = img.to_rgb32f();
        let (w, h) = (rgb.width() as usize, rgb.height() as usize);
        Image::from_data(w, h, rgb.pixels().map(|p| p.0).collect())
    }

    /// Mean of the linear values over all pixels and channels (0 for an empty image).
    pub fn mean(&self) -> f64 {
        let s: f64 = self
            .data
            .iter()
            .map(|p| p.iter().map(|&c| f64::from(c)).sum::<f64>())
            .sum();
        s / (3 * self.data.len()).max(1) as f64
    }

    /// The per-pixel mean of two images of the same size (e.g. a reference from two independent
    /// halves). Errors when the sizes differ.
    pub fn average(&self, other: &Image) -> Result<Image> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(TraceError::Parameter(format!(
                "averaging a {} × {} image with a {} × {} one",
                self.width, self.height, other.width, other.height
            )));
        }
        let data = self
            .data
            .iter()
            .zip(&other.data)
            .map(|(p, q)| std::array::from_fn(|c| 0.5 * (p[c] + q[c])))
            .collect();
        Image::from_data(self.width, self.height, data)
    }

    /// Writes the linear values as a 32-bit float RGB OpenEXR file atomically.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        let raw: Vec<f32> = self.data.iter().flatten().copied().collect();
        let buf = image::Rgb32FImage::from_raw(self.width as u32, self.height as u32, raw)
            .ok_or_else(|| encode_error(path, "EXR", "buffer size mismatch"))?;
        let mut bytes = Vec::new();
        image::DynamicImage::ImageRgb32F(buf)
            .write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::OpenExr)
            .map_err(|e| encode_error(path, "EXR", e))?;
        lustre_brdf::error::write_atomic(path, &bytes)?;
        Ok(())
    }
}
