//! Shared drawing plumbing: one figure description rendered to PNG and SVG, atomic output,
//! text that is skipped when no font is available, and tick formatting.

use crate::{parent_dir, PlotError, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Backend errors flattened to text (they differ per backend type).
pub(crate) type DrawResult = std::result::Result<(), String>;

/// Converts any displayable backend error to the crate's drawing-error text.
pub(crate) fn de<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// A figure that can be drawn on any plotters backend.
pub(crate) trait Figure: Sync {
    /// Width and height in pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the figure. `text` is false when text must be skipped (PNG without a font).
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>, text: &Texter) -> DrawResult;
}

/// Draws text only when a font is available to the backend.
pub(crate) struct Texter {
    enabled: bool,
}

impl Texter {
    /// Draws `s` at `pos` with its anchor at `(h, v)`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn text<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        s: &str,
        pos: (i32, i32),
        size: f64,
        color: RGBColor,
        h: HPos,
        v: VPos,
    ) -> DrawResult {
        if !self.enabled {
            return Ok(());
        }
        let style = TextStyle::from(("sans-serif", size).into_font())
            .color(&color)
            .pos(Pos::new(h, v));
        area.draw(&Text::new(s.to_string(), pos, style)).map_err(de)
    }
}

/// Renders `fig` into a PNG at `path` atomically (temporary file beside it, then a rename).
pub(crate) fn write_png<F: Figure>(fig: &F, path: &Path) -> Result<()> {
    let dir = parent_dir(path);
    let tmp = builder()
        .suffix(".png")
        .tempfile_in(&dir)
        .map_err(|source| PlotError::Io {
            path: dir.clone(),
            source,
        })?;
    let draw_err = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    {
        let backend = BitMapBackend::new(tmp.path(), fig.size());
        let area = backend.into_drawing_area();
        area.fill(&WHITE).map_err(de).map_err(draw_err)?;
        fig.draw(
            &area,
            &Texter {
                enabled: crate::font::font_available(),
            },
        )
        .map_err(draw_err)?;
        area.present().map_err(de).map_err(draw_err)?;
    }
    // The encoder wrote through its own handle; flushing the inode through ours makes the rename
    // publish complete data.
    tmp.as_file().sync_all().map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    tmp.persist(path).map_err(|e| PlotError::Io {
        path: path.to_path_buf(),
        source: e.error,
    })?;
    Ok(())
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
        fig.draw(&area, &Texter { enabled: true })
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

/// Writes bytes atomically: a temporary file in the same folder, then a rename.
pub(crate) fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    use std::io::Write;
    let dir = parent_dir(path);
    let io = |p: &Path, source| PlotError::Io {
        path: p.to_path_buf(),
        source,
    };
    let mut tmp = builder().tempfile_in(&dir).map_err(|e| io(&dir, e))?;
    tmp.write_all(bytes).map_err(|e| io(path, e))?;
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
