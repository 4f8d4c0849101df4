//! Heat maps of non-negative per-pixel quantities (004 Fig. IV.6 and IV.8: local bandwidth),
//! on a log scale: the inferno colour map over the octaves between the 1st and the 99.9th
//! percentile of the positive values; zeros are black.

use crate::color::colormap;
use crate::draw::{de, write_png, DrawResult, Figure, Pen};
use crate::{PlotError, Result};
use plotters::prelude::*;
use std::path::Path;

/// The value range a heat map spans (the colour map's ends).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeatScale {
    /// The value at the dark end (the 1st percentile of the positive values).
    pub low: f64,
    /// The value at the bright end (the 99.9th percentile).
    pub high: f64,
}

struct HeatFigure {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl Figure for HeatFigure {
    fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    fn draw<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>) -> DrawResult {
        let bitmap =
            BitMapElement::<(i32, i32)>::with_ref((0, 0), (self.width, self.height), &self.rgb)
                .ok_or_else(|| "raster size mismatch".to_string())?;
        pen.area.draw(&bitmap).map_err(de)
    }
}

/// Writes `values` (`width × height`, row-major, finite and ≥ 0) as a log-scale heat map PNG at
/// `path` (atomically) and returns the scale used. Errors on a size mismatch, a zero size, or a
/// negative or non-finite value (named with its pixel).
pub fn heat_map(values: &[f64], width: usize, height: usize, path: &Path) -> Result<HeatScale> {
    if width == 0 || height == 0 || width * height != values.len() || width > 16384 {
        return Err(PlotError::Input(format!(
            "heat map of {width}×{height} pixels from {} values",
            values.len()
        )));
    }
    if let Some(k) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        return Err(PlotError::Input(format!(
            "heat map: value {} at pixel ({}, {}) is not finite and ≥ 0",
            values[k],
            k % width,
            k / width
        )));
    }
    let (rgb, scale) = heat_rgb(values);
    let fig = HeatFigure {
        width: width as u32,
        height: height as u32,
        rgb,
    };
    write_png(&fig, path)?;
    Ok(scale)
}

/// The colours of a heat map of `values` (8-bit RGB, one triple per value) and its scale: the
/// inferno colour map over the octaves between the 1st and the 99.9th percentile of the
/// positive values; zero, negative and non-finite values are black, and positive values that
/// span no range (a constant map) take the colour map's middle. What [`heat_map`] draws,
/// for a caller that shows it itself (the viewer's buffer views).
pub fn heat_rgb(values: &[f64]) -> (Vec<u8>, HeatScale) {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    let mut sorted: Vec<f64> = values.iter().copied().filter(|v| positive(*v)).collect();
    sorted.sort_by(f64::total_cmp);
    let scale = if sorted.is_empty() {
        HeatScale {
            low: 0.0,
            high: 0.0,
        }
    } else {
        let pick = |p: f64| sorted[((sorted.len() - 1) as f64 * p) as usize];
        HeatScale {
            low: pick(0.01),
            high: pick(0.999),
        }
    };
    let span = (scale.high / scale.low).log2();
    // Positive values that span no range (a constant map, e.g. a constant sample count) draw at
    // the colour map's middle, not at its dark end, where they would look like zeros.
    let flat = span.is_nan() || span <= 1e-9;
    let rgb = values
        .iter()
        .flat_map(|&v| {
            if !positive(v) {
                [0, 0, 0]
            } else if flat {
                colormap(0.5)
            } else {
                colormap((v / scale.low).log2() / span)
            }
        })
        .collect();
    (rgb, scale)
}
