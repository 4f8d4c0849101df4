//! Image comparison: RMS of linear values, PSNR and CIE76 ΔE of display values, and a
//! false-colour difference image (002 Fig. 9 style).

use crate::error::{Result, TraceError};
use crate::image::{display_value, srgb_eotf, Image};

/// D65 reference white (CIE 1931 2°), Y = 1.
pub const D65_WHITE: [f64; 3] = [0.950_47, 1.0, 1.088_83];

/// Rec. 709 / sRGB luminance weights of linear RGB.
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

fn check_same(a: &Image, b: &Image) -> Result<()> {
    if a.width != b.width || a.height != b.height || a.data.len() != b.data.len() {
        return Err(TraceError::Parameter(format!(
            "metrics: images differ in size ({}x{} vs {}x{})",
            a.width, a.height, b.width, b.height
        )));
    }
    Ok(())
}

/// Root-mean-square difference of the linear values over all pixels and channels.
pub fn rms(a: &Image, b: &Image) -> Result<f64> {
    check_same(a, b)?;
    let sum: f64 = a
        .data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] as f64 - q[c] as f64).powi(2)))
        .sum();
    Ok((sum / (3 * a.data.len()) as f64).sqrt())
}

/// Mean squared difference of the display values (exposure, clamp, sRGB OETF; unquantized).
fn display_mse(a: &Image, b: &Image, exposure: f64) -> f64 {
    let sum: f64 = a
        .data
        .iter()
        .zip(&b.data)
        .flat_map(|(p, q)| {
            (0..3).map(move |c| {
                (display_value(p[c] as f64, exposure) - display_value(q[c] as f64, exposure))
                    .powi(2)
            })
        })
        .sum();
    sum / (3 * a.data.len()) as f64
}

/// Peak signal-to-noise ratio in dB of the display values with peak 1:
/// 10 · log10(1 / MSE). Identical display values give `f64::INFINITY`.
pub fn psnr(a: &Image, b: &Image, exposure: f64) -> Result<f64> {
    check_same(a, b)?;
    let mse = display_mse(a, b, exposure);
    Ok(if mse > 0.0 {
        -10.0 * mse.log10()
    } else {
        f64::INFINITY
    })
}

/// CIE L*a*b* (D65) of an sRGB display colour with channels in [0, 1]: sRGB EOTF, the sRGB →
/// XYZ matrix (IEC 61966-2-1), then CIE 1976 L*a*b* relative to [`D65_WHITE`].
pub fn srgb_to_lab(rgb: [f64; 3]) -> [f64; 3] {
    let [r, g, b] = rgb.map(srgb_eotf);
    let x = 0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b;
    let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175 * b;
    let z = 0.019_333_9 * r + 0.119_192 * g + 0.950_304_1 * b;
    let f = |t: f64| {
        const D: f64 = 6.0 / 29.0;
        if t > D * D * D {
            t.cbrt()
        } else {
            t / (3.0 * D * D) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (
        f(x / D65_WHITE[0]),
        f(y / D65_WHITE[1]),
        f(z / D65_WHITE[2]),
    );
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Mean CIE76 ΔE (Euclidean distance in L*a*b*, D65) between the display values of the two
/// images (exposure, clamp, sRGB OETF, then [`srgb_to_lab`]). sRGB white vs black is 100.
pub fn delta_e(a: &Image, b: &Image, exposure: f64) -> Result<f64> {
    check_same(a, b)?;
    let lab = |p: &[f32; 3]| srgb_to_lab(p.map(|c| display_value(c as f64, exposure)));
    let sum: f64 = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| {
            let (la, lb) = (lab(p), lab(q));
            ((la[0] - lb[0]).powi(2) + (la[1] - lb[1]).powi(2) + (la[2] - lb[2]).powi(2)).sqrt()
        })
        .sum();
    Ok(sum / a.data.len() as f64)
}

/// The colour ramp of [`false_colour`] at t ∈ [0, 1], as sRGB display values: blue (0) → cyan
/// (¼) → green (½) → yellow (¾) → red (1), piecewise linear.
pub fn ramp(t: f64) -> [f64; 3] {
    const STOPS: [[f64; 3]; 5] = [
        [0.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
    ];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) } * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let (p, q) = (STOPS[i], STOPS[i + 1]);
    [0, 1, 2].map(|c| p[c] + f * (q[c] - p[c]))
}

/// A false-colour image of the absolute luminance difference |Y(a) − Y(b)| of the linear
/// values (Rec. 709 weights), scaled by `max_abs` (t = |ΔY| / max_abs, clamped to 1) and mapped
/// through [`ramp`] (002 Fig. 9 style). The pixels are stored linear, so that
/// [`Image::write_png`] with exposure 1 shows the ramp colours exactly.
pub fn false_colour(a: &Image, b: &Image, max_abs: f64) -> Result<Image> {
    check_same(a, b)?;
    if !(max_abs.is_finite() && max_abs > 0.0) {
        return Err(TraceError::Parameter(format!(
            "false colour: max_abs = {max_abs} must be finite and > 0"
        )));
    }
    let lum = |p: &[f32; 3]| (0..3).map(|c| LUMINANCE[c] * p[c] as f64).sum::<f64>();
    let data = a
        .data
        .iter()
        .zip(&b.data)
        .map(|(p, q)| {
            let t = (lum(p) - lum(q)).abs() / max_abs;
            ramp(t).map(|c| srgb_eotf(c) as f32)
        })
        .collect();
    Image::from_data(a.width, a.height, data)
}
