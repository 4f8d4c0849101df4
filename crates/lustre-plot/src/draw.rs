//! Shared drawing plumbing: one figure description rendered to PNG and SVG, atomic output,
//! text that is skipped when no font is available, and tick formatting.

use crate::{parent_dir, with_suffix, PlotError, PlotFiles, Result};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rayon::prelude::*;
use std::path::Path;

/// Backend errors flattened to text (they differ per backend type).
pub(crate) type DrawResult = std::result::Result<(), String>;

/// Converts any displayable backend error to the crate's drawing-error text.
pub(crate) fn de<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// A figure that can be drawn on any plotters backend.
pub(crate) trait Figure: Sync {
    /// Width and height in logical pixels (the PNG's size).
    fn size(&self) -> (u32, u32);
    /// PNGs are drawn at this many times the size and box-filtered down (anti-aliased lines).
    fn supersample(&self) -> u32 {
        1
    }
    /// Draws the figure in logical coordinates through `pen`.
    fn draw<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>) -> DrawResult;
}

/// A position in logical pixels, integer or not.
pub(crate) trait Point {
    /// The position as floating point.
    fn f(self) -> (f64, f64);
}

impl Point for (f64, f64) {
    fn f(self) -> (f64, f64) {
        self
    }
}

impl Point for (i32, i32) {
    fn f(self) -> (f64, f64) {
        (self.0 as f64, self.1 as f64)
    }
}

/// Line dash patterns, in logical pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Dash {
    /// A continuous line.
    Solid,
    /// Dashes of the first length separated by gaps of the second.
    Dashed(f64, f64),
}

/// Draws in logical (floating-point) coordinates scaled by `k` onto a drawing area, skipping
/// text when no font is available to the backend.
pub(crate) struct Pen<'a, DB: DrawingBackend> {
    /// The drawing area (device pixels).
    pub(crate) area: &'a DrawingArea<DB, Shift>,
    k: f64,
    text: bool,
}

impl<DB: DrawingBackend> Pen<'_, DB> {
    fn p(&self, (x, y): (f64, f64)) -> (i32, i32) {
        ((x * self.k).round() as i32, (y * self.k).round() as i32)
    }

    fn len(&self, v: f64) -> u32 {
        (v * self.k).round().max(1.0) as u32
    }

    /// A polyline of `width` logical pixels.
    pub(crate) fn path(
        &self,
        pts: &[(f64, f64)],
        color: RGBColor,
        width: f64,
        dash: Dash,
    ) -> DrawResult {
        let pts: Vec<(i32, i32)> = pts.iter().map(|&q| self.p(q)).collect();
        let style = color.stroke_width(self.len(width));
        match dash {
            // One element per segment: plotters joins thick polylines with miters, which shoot
            // far out of the panel where a sharp lobe turns back on itself (a narrow peak).
            Dash::Solid if width > 1.0 => pts.windows(2).try_for_each(|seg| {
                self.area
                    .draw(&PathElement::new(seg.to_vec(), style))
                    .map(|_| ())
            }),
            Dash::Solid => self.area.draw(&PathElement::new(pts, style)),
            Dash::Dashed(on, off) => self.area.draw(&DashedPathElement::new(
                pts,
                self.len(on) as i32,
                self.len(off) as i32,
                style,
            )),
        }
        .map_err(de)
    }

    /// A circle of radius `r` (logical pixels), filled or outlined.
    pub(crate) fn circle(
        &self,
        c: (f64, f64),
        r: f64,
        color: RGBColor,
        filled: bool,
    ) -> DrawResult {
        let style = if filled {
            color.filled()
        } else {
            color.stroke_width(self.len(1.0))
        };
        self.area
            .draw(&Circle::new(self.p(c), self.len(r), style))
            .map_err(de)
    }

    /// Text of `size` logical pixels with its anchor at `(h, v)`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn text(
        &self,
        s: &str,
        pos: impl Point,
        size: f64,
        color: RGBColor,
        h: HPos,
        v: VPos,
    ) -> DrawResult {
        if !self.text {
            return Ok(());
        }
        let style = TextStyle::from(("sans-serif", size * self.k).into_font())
            .color(&color)
            .pos(Pos::new(h, v));
        self.area
            .draw(&Text::new(s.to_string(), self.p(pos.f()), style))
            .map_err(de)
    }
}

/// Renders `fig` into a PNG at `path` atomically (temporary file beside it, then a rename).
/// Writes `{out_base}.png` and `{out_base}.svg` of one figure.
pub(crate) fn write_png_svg<F: Figure>(fig: &F, out_base: &Path) -> Result<PlotFiles> {
    let png = with_suffix(out_base, "png");
    let svg = with_suffix(out_base, "svg");
    write_png(fig, &png)?;
    write_svg(fig, &svg)?;
    Ok(PlotFiles {
        png,
        svg: Some(svg),
    })
}

pub(crate) fn write_png<F: Figure>(fig: &F, path: &Path) -> Result<()> {
    // Checked before drawing: a missing folder is named before any work.
    let dir = parent_dir(path);
    drop(temp_in(&dir, ".png")?);
    let draw_err = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    let text = crate::font::font_available();
    let (w, h) = fig.size();
    let k = fig.supersample().clamp(1, 4);
    // Supersampled figures are drawn into a k-times larger buffer first.
    let small = if k > 1 {
        let (bw, bh) = (w * k, h * k);
        let mut big = vec![255u8; 3 * bw as usize * bh as usize];
        {
            let area = BitMapBackend::with_buffer(&mut big, (bw, bh)).into_drawing_area();
            fig.draw(&Pen {
                area: &area,
                k: k as f64,
                text,
            })
            .map_err(draw_err)?;
            area.present().map_err(de).map_err(draw_err)?;
        }
        Some(downsample(&big, w as usize, h as usize, k as usize))
    } else {
        None
    };
    let mut rgb = vec![255u8; 3 * w as usize * h as usize];
    {
        let area = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
        area.fill(&WHITE).map_err(de).map_err(draw_err)?;
        match &small {
            Some(buf) => {
                let bitmap = BitMapElement::<(i32, i32)>::with_ref((0, 0), (w, h), buf)
                    .ok_or_else(|| draw_err("raster size mismatch".into()))?;
                area.draw(&bitmap).map_err(de).map_err(draw_err)?;
            }
            None => fig
                .draw(&Pen {
                    area: &area,
                    k: 1.0,
                    text,
                })
                .map_err(draw_err)?,
        }
        area.present().map_err(de).map_err(draw_err)?;
    }
    // Encoded in memory and written as one atomic file, so a write error is the operating
    // system's, naming the file.
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &rgb,
        w,
        h,
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| draw_err(format!("encoding the PNG: {e}")))?;
    write_bytes_atomic(path, &png)
}

/// Box-filters an RGB image of (w·k)×(h·k) pixels down to w×h.
fn downsample(big: &[u8], w: usize, h: usize, k: usize) -> Vec<u8> {
    let bw = w * k;
    let mut out = vec![0u8; 3 * w * h];
    out.par_chunks_mut(3 * w).enumerate().for_each(|(y, row)| {
        for x in 0..w {
            for c in 0..3 {
                let mut sum = 0u32;
                for dy in 0..k {
                    for dx in 0..k {
                        sum += big[3 * ((y * k + dy) * bw + x * k + dx) + c] as u32;
                    }
                }
                row[3 * x + c] = ((sum + (k * k) as u32 / 2) / (k * k) as u32) as u8;
            }
        }
    });
    out
}

/// Renders `fig` into an SVG at `path` atomically. SVG text needs no font file.
pub(crate) fn write_svg<F: Figure>(fig: &F, path: &Path) -> Result<()> {
    let draw_err = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    let mut svg = String::new();
    {
        let area = SVGBackend::with_string(&mut svg, fig.size()).into_drawing_area();
        area.fill(&WHITE).map_err(de).map_err(draw_err)?;
        fig.draw(&Pen {
            area: &area,
            k: 1.0,
            text: true,
        })
        .map_err(draw_err)?;
        area.present().map_err(de).map_err(draw_err)?;
    }
    write_bytes_atomic(path, svg.as_bytes())
}

/// Temporary files named `.lustre-plot-*`, readable by others once renamed (mode 0644 less the
/// umask on Unix, like a plainly created file; tempfile's default is 0600).
fn builder() -> tempfile::Builder<'static, 'static> {
    let mut b = tempfile::Builder::new();
    b.prefix(".lustre-plot-");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o644));
    }
    b
}

/// A temporary file in `dir`; errors name `dir` (the folder the user gave), not the hidden file.
fn temp_in(dir: &Path, suffix: &str) -> Result<tempfile::NamedTempFile> {
    let io = |source| PlotError::Io {
        path: dir.to_path_buf(),
        source,
    };
    if !dir.is_dir() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::NotFound,
            "no such folder (the output's folder must exist)",
        )));
    }
    builder()
        .suffix(suffix)
        .tempfile_in(dir)
        .map_err(|e| io(std::io::Error::from(e.kind())))
}

/// Writes bytes atomically: a temporary file in the same folder, then a rename.
pub(crate) fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let dir = parent_dir(path);
    let io = |p: &Path, source| PlotError::Io {
        path: p.to_path_buf(),
        source,
    };
    let mut tmp = temp_in(&dir, "")?;
    tmp.as_file_mut()
        .write_all(bytes)
        .map_err(|e| io(path, e))?;
    tmp.as_file().sync_all().map_err(|e| io(path, e))?;
    tmp.persist(path).map_err(|e| io(path, e.error))?;
    Ok(())
}

/// Formats a tick value with two significant digits (at least the integer part).
pub(crate) fn fmt_value(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e4).contains(&a) {
        return format!("{v:.1e}");
    }
    let decimals = (1 - a.log10().floor() as i32).clamp(0, 6) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Rounds `v` > 0 up to two significant digits (a tidy outer ring / colour-bar end).
pub(crate) fn nice_ceil(v: f64) -> f64 {
    if v.is_nan() || v <= 0.0 || v.is_infinite() {
        return 1.0;
    }
    let p = 10f64.powf(v.log10().floor() - 1.0);
    (v / p).ceil() * p
}

/// Formats an angle in degrees, dropping a zero fraction.
pub(crate) fn fmt_deg(d: f64) -> String {
    if (d - d.round()).abs() < 1e-9 {
        format!("{}°", d.round() as i64)
    } else {
        format!("{d:.1}°")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_formatting() {
        assert_eq!(fmt_value(0.0), "0");
        assert_eq!(fmt_value(0.0781), "0.078");
        assert_eq!(fmt_value(2.0), "2");
        assert_eq!(fmt_value(2.11), "2.1");
        assert_eq!(fmt_value(125.0), "125");
        assert_eq!(fmt_value(1.5e-5), "1.5e-5");
        assert!((nice_ceil(0.01234) - 0.013).abs() < 1e-12);
        assert_eq!(fmt_deg(30.0), "30°");
        assert_eq!(fmt_deg(7.5), "7.5°");
    }
}
