//! Bitmap textures in linear floating point, with bilinear lookup and wrapping.
//!
//! Colour textures (base colour, diffuse reflectance, emission) are decoded from sRGB to linear on
//! read; data textures (roughness, metallic, normal maps, opacity) are kept as stored. Texel (0, 0)
//! is the top-left of the image; uv (0, 0) is its top-left corner (the glTF convention).

use crate::error::{read_referenced, Result, SceneError};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Largest accepted texture side.
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// How a texture's stored values are interpreted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ColorSpace {
    /// sRGB-encoded colour: decoded to linear on load (alpha stays linear).
    Srgb,
    /// Linear data stored as is.
    Linear,
}

/// A decoded texture: `channels` f32 per texel, row-major, row 0 at the top, linear.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// The file it came from (or a name for embedded images).
    pub source: PathBuf,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Channels per texel: 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA).
    pub channels: u8,
    /// How the stored values were decoded.
    pub color_space: ColorSpace,
    /// Texels, `data[(y*width + x)*channels + c]`.
    pub data: Vec<f32>,
}

/// The sRGB transfer function inverse (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Texture {
    /// A texture from texels; checks the size and the data length.
    pub fn new(
        source: impl Into<PathBuf>,
        width: u32,
        height: u32,
        channels: u8,
        color_space: ColorSpace,
        data: Vec<f32>,
    ) -> Result<Texture> {
        let source = source.into();
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
            return Err(SceneError::format(
                &source,
                format!("texture size {width}×{height} outside 1..={MAX_TEXTURE_SIDE}"),
            ));
        }
        if !(1..=4).contains(&channels) {
            return Err(SceneError::format(
                &source,
                format!("{channels} channels (1 to 4 expected)"),
            ));
        }
        let expected = width as usize * height as usize * channels as usize;
        if data.len() != expected {
            return Err(SceneError::format(
                &source,
                format!("{} values for {width}×{height}×{channels}", data.len()),
            ));
        }
        Ok(Texture {
            source,
            width,
            height,
            channels,
            color_space,
            data,
        })
    }

    /// Decodes an image file (PNG, JPEG, HDR, EXR) from memory; `source` names it in messages.
    pub fn decode(source: &Path, bytes: &[u8], color_space: ColorSpace) -> Result<Texture> {
        let img = image::load_from_memory(bytes)
            .map_err(|e| SceneError::format(source, format!("cannot decode image: {e}")))?;
        let (width, height) = (img.width(), img.height());
        if width == 0 || height == 0 || width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
            return Err(SceneError::format(
                source,
                format!("image size {width}×{height} outside 1..={MAX_TEXTURE_SIDE}"),
            ));
        }
        let float_source = matches!(
            img.color(),
            image::ColorType::Rgb32F | image::ColorType::Rgba32F
        );
        let (channels, mut data): (u8, Vec<f32>) = match img.color().channel_count() {
            1 => (1, img.to_luma32f().into_raw()),
            2 => (2, img.to_luma_alpha32f().into_raw()),
            3 => (3, img.to_rgb32f().into_raw()),
            _ => (4, img.to_rgba32f().into_raw()),
        };
        // Float images (HDR, EXR) are linear already.
        if color_space == ColorSpace::Srgb && !float_source {
            let colour_channels = if channels == 2 || channels == 4 {
                channels - 1
            } else {
                channels
            };
            for texel in data.chunks_mut(channels as usize) {
                for c in texel.iter_mut().take(colour_channels as usize) {
                    *c = srgb_to_linear(*c);
                }
            }
        }
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(SceneError::format(
                source,
                format!("texel value {i} is not finite"),
            ));
        }
        Texture::new(source, width, height, channels, color_space, data)
    }

    /// Reads and decodes the image file at `path`; `referrer` is the scene file naming it.
    pub fn read(referrer: &Path, path: &Path, color_space: ColorSpace) -> Result<Texture> {
        let bytes = read_referenced(referrer, path)?;
        Texture::decode(path, &bytes, color_space)
    }

    /// Texel (x, y) as RGBA: grey expands to RGB, a missing alpha is 1.
    pub fn texel(&self, x: u32, y: u32) -> [f32; 4] {
        let i = (y as usize * self.width as usize + x as usize) * self.channels as usize;
        let t = &self.data[i..i + self.channels as usize];
        match self.channels {
            1 => [t[0], t[0], t[0], 1.0],
            2 => [t[0], t[0], t[0], t[1]],
            3 => [t[0], t[1], t[2], 1.0],
            _ => [t[0], t[1], t[2], t[3]],
        }
    }

    /// Bilinear lookup at (u, v) with wrapping (repeat) in both directions, RGBA. Texel centres
    /// lie at ((x+½)/W, (y+½)/H). Non-finite coordinates read texel (0, 0).
    pub fn sample(&self, u: f32, v: f32) -> [f32; 4] {
        let (u, v) = if u.is_finite() && v.is_finite() {
            (u, v)
        } else {
            (0.0, 0.0)
        };
        let (w, h) = (self.width as f32, self.height as f32);
        let x = u * w - 0.5;
        let y = v * h - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // Repeat; the common in-range case without the integer division of `rem_euclid`.
        let wrap = |i: f32, n: u32| -> u32 {
            if i >= 0.0 && i < n as f32 {
                i as u32
            } else {
                (i as i64).rem_euclid(i64::from(n)) as u32
            }
        };
        let (xa, xb) = (wrap(x0, self.width), wrap(x0 + 1.0, self.width));
        let (ya, yb) = (wrap(y0, self.height), wrap(y0 + 1.0, self.height));
        let (t00, t10, t01, t11) = (
            self.texel(xa, ya),
            self.texel(xb, ya),
            self.texel(xa, yb),
            self.texel(xb, yb),
        );
        let mut out = [0.0f32; 4];
        for c in 0..4 {
            let top = t00[c] + (t10[c] - t00[c]) * fx;
            let bottom = t01[c] + (t11[c] - t01[c]) * fx;
            out[c] = top + (bottom - top) * fy;
        }
        out
    }

    /// Mean RGBA over all texels.
    pub fn mean(&self) -> [f64; 4] {
        let mut acc = [0.0f64; 4];
        for y in 0..self.height {
            for x in 0..self.width {
                let t = self.texel(x, y);
                for c in 0..4 {
                    acc[c] += f64::from(t[c]);
                }
            }
        }
        let n = f64::from(self.width) * f64::from(self.height);
        acc.map(|a| a / n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // 2×2: (0,0)=0 (1,0)=1 / (0,1)=2 (1,1)=3, grey.
        Texture::new("t", 2, 2, 1, ColorSpace::Linear, vec![0.0, 1.0, 2.0, 3.0]).unwrap()
    }

    #[test]
    fn bilinear_hits_texel_centres_and_wraps() {
        let t = checker();
        assert_eq!(t.sample(0.25, 0.25)[0], 0.0);
        assert_eq!(t.sample(0.75, 0.25)[0], 1.0);
        assert_eq!(t.sample(0.25, 0.75)[0], 2.0);
        assert_eq!(t.sample(0.5, 0.25)[0], 0.5);
        assert_eq!(t.sample(0.5, 0.5)[0], 1.5);
        // Between the last and the first column: wraps.
        assert_eq!(t.sample(0.0, 0.25)[0], 0.5);
        assert_eq!(t.sample(1.25, -0.75)[0], t.sample(0.25, 0.25)[0]);
        assert_eq!(t.sample(f32::NAN, 0.3), t.sample(0.0, 0.0));
        assert_eq!(t.sample(0.25, 0.25)[3], 1.0);
    }

    #[test]
    fn srgb_decoding() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_to_linear(0.5) - 0.214_041).abs() < 1e-5);
        assert!((srgb_to_linear(0.04) - 0.04 / 12.92).abs() < 1e-9);
    }

    #[test]
    fn bad_sizes_and_bytes_are_errors() {
        assert!(Texture::new("t", 0, 2, 1, ColorSpace::Linear, vec![]).is_err());
        assert!(Texture::new("t", 2, 2, 5, ColorSpace::Linear, vec![0.0; 20]).is_err());
        assert!(Texture::new("t", 2, 2, 1, ColorSpace::Linear, vec![0.0; 3]).is_err());
        let e = Texture::decode(Path::new("x.png"), b"not an image", ColorSpace::Srgb).unwrap_err();
        assert!(e.to_string().contains("x.png"));
    }
}
