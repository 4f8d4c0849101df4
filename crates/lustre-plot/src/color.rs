//! Colours: the curve palette and the luminance colour map.

use plotters::style::RGBColor;

/// Curve colours for overlaid BSDFs: blue, red, green, orange, purple, grey (the first two stay
/// distinguishable for red-green colour-blind readers).
pub(crate) const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 100, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(90, 90, 90),
];

/// Channel colours for RGB curves.
pub(crate) const CHANNEL: [RGBColor; 3] = [
    RGBColor(220, 30, 30),
    RGBColor(20, 150, 40),
    RGBColor(30, 70, 220),
];

/// Samples of matplotlib's `inferno` colour map (CC0, van der Walt and Smith) at t = k/8.
const INFERNO: [[f64; 3]; 9] = [
    [0.0, 0.0, 4.0],
    [31.0, 12.0, 72.0],
    [85.0, 15.0, 109.0],
    [136.0, 34.0, 106.0],
    [186.0, 54.0, 85.0],
    [227.0, 89.0, 51.0],
    [249.0, 140.0, 10.0],
    [249.0, 201.0, 50.0],
    [252.0, 255.0, 164.0],
];

/// The colour map at `t` in [0, 1] (clamped), as 8-bit RGB.
pub(crate) fn colormap(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (INFERNO.len() - 1) as f64;
    let i = (x.floor() as usize).min(INFERNO.len() - 2);
    let f = x - i as f64;
    let (a, b) = (INFERNO[i], INFERNO[i + 1]);
    [0, 1, 2].map(|c| (a[c] + (b[c] - a[c]) * f).round().clamp(0.0, 255.0) as u8)
}

/// A value in [0, 1] (clamped) as a byte.
pub(crate) fn byte(t: f64) -> u8 {
    if t.is_finite() {
        (t.clamp(0.0, 1.0) * 255.0).round() as u8
    } else {
        0
    }
}
