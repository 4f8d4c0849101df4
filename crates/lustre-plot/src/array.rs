//! Transfer-probability plot arrays (000 Fig. 2.6 and 3.11): one disc per incident direction
//! (rows θi, columns φi), each a polar image of p(ωo|ωi) = f·|cos θo| over the outgoing
//! hemisphere with θo = 0° at the centre and 90° at the rim, the cube root of the intensity, the
//! light's azimuth at the top of every disc (red dot at the light's position) and the sample
//! rotated by φi. Transmissive BSDFs get a second array for the lower hemisphere; comparisons put
//! two BSDFs' arrays side by side on one shared scale.

use crate::color::{byte, colormap};
use crate::draw::{de, fmt_deg, fmt_value, nice_ceil, write_png, DrawResult, Figure, Pen};
use crate::{check_angle, clean, with_suffix, PlotError, PlotFiles, Result};
use lustre_brdf::frame::{deg, spherical};
use lustre_brdf::{Bsdf, DVec3, Rgb};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use rayon::prelude::*;
use std::path::Path;

/// Which hemisphere of outgoing directions a disc shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hemisphere {
    /// ωo above the surface (z > 0); the centre is the normal.
    Reflection,
    /// ωo below the surface (z < 0), seen through the surface from above; the centre is −z.
    Transmission,
}

/// How disc pixels are coloured.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ArrayColor {
    /// Each RGB channel scaled on the shared scale (grey for colourless materials, as in Fig. 2.6).
    #[default]
    Rgb,
    /// Luminance through the `inferno` colour map.
    Colormap,
}

/// Options of [`transfer_array`] and [`transfer_array_compare`].
#[derive(Clone, Debug, PartialEq)]
pub struct ArrayOptions {
    /// Row angles θi in degrees, each in [0, 90] (default 0, 5, 20, 35, 50, 65 as in Fig. 2.6).
    pub thetas_deg: Vec<f64>,
    /// Column angles φi in degrees (default 0 to 90 in steps of 15).
    pub phis_deg: Vec<f64>,
    /// Disc diameter in pixels, 16 to 1024 (default 96).
    pub disc_px: u32,
    /// Sub-pixels per axis averaged in each pixel, 1 to 8 (default 2).
    pub supersample: u32,
    /// Apply the cube root to the intensities (default true, as in the thesis).
    pub cube_root: bool,
    /// RGB or colour-mapped luminance.
    pub color: ArrayColor,
    /// Figure title; a descriptive default when `None`.
    pub title: Option<String>,
}

impl Default for ArrayOptions {
    fn default() -> Self {
        ArrayOptions {
            thetas_deg: vec![0.0, 5.0, 20.0, 35.0, 50.0, 65.0],
            phis_deg: (0..7).map(|k| 15.0 * k as f64).collect(),
            disc_px: 96,
            supersample: 2,
            cube_root: true,
            color: ArrayColor::Rgb,
            title: None,
        }
    }
}

/// One disc: `size`×`size` pixels, row-major from the top row; `None` outside the disc.
#[derive(Clone, Debug, PartialEq)]
pub struct Disc {
    /// Width and height in pixels.
    pub size: u32,
    /// The transfer probability p = f·|cos θo| per pixel (sub-pixel average, not cube-rooted).
    pub values: Vec<Option<Rgb>>,
}

impl Disc {
    /// The value at column `x`, row `y` (`None` outside the disc or the image).
    pub fn get(&self, x: u32, y: u32) -> Option<Rgb> {
        if x >= self.size || y >= self.size {
            return None;
        }
        self.values
            .get((y * self.size + x) as usize)
            .copied()
            .flatten()
    }

    /// The pixel (x, y) with the largest luminance.
    pub fn argmax(&self) -> Option<(u32, u32)> {
        let mut best: Option<(usize, f64)> = None;
        for (i, v) in self.values.iter().enumerate() {
            if let Some(v) = v {
                let l = v.luminance();
                if best.is_none_or(|(_, b)| l > b) {
                    best = Some((i, l));
                }
            }
        }
        best.map(|(i, _)| (i as u32 % self.size, i as u32 / self.size))
    }

    fn max(&self, color: ArrayColor) -> f64 {
        self.values
            .iter()
            .flatten()
            .map(|v| intensity(*v, color))
            .fold(0.0, f64::max)
    }
}

fn intensity(v: Rgb, color: ArrayColor) -> f64 {
    match color {
        ArrayColor::Rgb => v.max_component(),
        ArrayColor::Colormap => clean(v.luminance()),
    }
}

/// The outgoing direction at disc position (u, v) ∈ [−1, 1]² (v up), or `None` outside the disc.
fn uv_direction(u: f64, v: f64, hemisphere: Hemisphere, phi_i_deg: f64) -> Option<DVec3> {
    let rho = (u * u + v * v).sqrt();
    if rho > 1.0 {
        return None;
    }
    let theta = rho * std::f64::consts::FRAC_PI_2;
    // Screen up is the light's azimuth φi; azimuth grows counter-clockwise seen from above.
    let phi = deg(phi_i_deg) + v.atan2(u) - std::f64::consts::FRAC_PI_2;
    let w = spherical(theta, phi);
    Some(match hemisphere {
        Hemisphere::Reflection => w,
        Hemisphere::Transmission => DVec3::new(w.x, w.y, -w.z),
    })
}

/// The outgoing direction at the centre of pixel (x, y) of a `size`-pixel disc for light azimuth
/// `phi_i_deg`: θo = 90°·(distance from the centre)/(disc radius), the light's azimuth at the top.
/// `None` outside the disc.
pub fn disc_direction(
    size: u32,
    x: u32,
    y: u32,
    hemisphere: Hemisphere,
    phi_i_deg: f64,
) -> Option<DVec3> {
    let s = size.max(1) as f64;
    let u = 2.0 * (x as f64 + 0.5) / s - 1.0;
    let v = 1.0 - 2.0 * (y as f64 + 0.5) / s;
    uv_direction(u, v, hemisphere, phi_i_deg)
}

/// The pixel (x, y) of a `size`-pixel disc that shows direction `w` (either hemisphere: the sign
/// of w.z is ignored), for light azimuth `phi_i_deg`. Inverse of [`disc_direction`].
pub fn direction_pixel(w: DVec3, size: u32, phi_i_deg: f64) -> (u32, u32) {
    let w = w.normalize_or(DVec3::Z);
    let rho = w.z.abs().clamp(0.0, 1.0).acos() / std::f64::consts::FRAC_PI_2;
    let a = w.y.atan2(w.x) - deg(phi_i_deg) + std::f64::consts::FRAC_PI_2;
    let (u, v) = (rho * a.cos(), rho * a.sin());
    let s = size.max(1) as f64;
    let px = |t: f64| ((t * s).floor() as i64).clamp(0, size.max(1) as i64 - 1) as u32;
    (px((u + 1.0) / 2.0), px((1.0 - v) / 2.0))
}

/// Computes one disc of p(ωo|ωi) = f·|cos θo| for light at (θi, φi), averaging
/// `supersample`² sub-pixels per pixel. Rows are computed in parallel.
pub fn transfer_disc(
    bsdf: &dyn Bsdf,
    theta_i_deg: f64,
    phi_i_deg: f64,
    hemisphere: Hemisphere,
    size: u32,
    supersample: u32,
) -> Disc {
    let size = size.max(1);
    let ss = supersample.clamp(1, 8);
    let wi = spherical(deg(theta_i_deg), deg(phi_i_deg));
    let s = size as f64;
    let values = (0..size)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..size).map(move |x| {
                disc_direction(size, x, y, hemisphere, phi_i_deg)?;
                let mut sum = Rgb::ZERO;
                let mut n = 0usize;
                for sy in 0..ss {
                    for sx in 0..ss {
                        let u = 2.0 * (x as f64 + (sx as f64 + 0.5) / ss as f64) / s - 1.0;
                        let v = 1.0 - 2.0 * (y as f64 + (sy as f64 + 0.5) / ss as f64) / s;
                        if let Some(wo) = uv_direction(u, v, hemisphere, phi_i_deg) {
                            sum += bsdf.eval(wi, wo).map(clean) * wo.z.abs();
                            n += 1;
                        }
                    }
                }
                Some(if n > 0 { sum / n as f64 } else { Rgb::ZERO })
            })
        })
        .collect();
    Disc { size, values }
}

/// True when `bsdf` declares transmission or scatters light below the surface for any of a
/// coarse set of probe configurations.
pub fn transmits(bsdf: &dyn Bsdf) -> bool {
    if bsdf.flags().transmission {
        return true;
    }
    [0.0, 30.0, 60.0, 85.0].iter().any(|&ti: &f64| {
        [0.0, 90.0, 200.0].iter().any(|&pi: &f64| {
            let wi = spherical(deg(ti), deg(pi));
            (0..8).any(|a| {
                (0..16).any(|b| {
                    let wo = spherical(deg(91.0 + 11.0 * a as f64), deg(22.5 * b as f64));
                    bsdf.eval(wi, wo).map(clean).max_component() > 0.0
                })
            })
        })
    })
}

/// Draws the transfer-probability array of `bsdf` (reflection, and transmission when
/// [`transmits`]) into `{out_base}.png`.
pub fn transfer_array(
    bsdf: &dyn Bsdf,
    label: &str,
    opts: &ArrayOptions,
    out_base: &Path,
) -> Result<PlotFiles> {
    render(&[(bsdf, label)], opts, out_base)
}

/// Draws the arrays of two BSDFs side by side (e.g. a measurement and its fit, Fig. 3.11) on one
/// shared intensity scale into `{out_base}.png`; the transmission arrays form a second row when
/// either BSDF transmits.
pub fn transfer_array_compare(
    a: (&dyn Bsdf, &str),
    b: (&dyn Bsdf, &str),
    opts: &ArrayOptions,
    out_base: &Path,
) -> Result<PlotFiles> {
    render(&[a, b], opts, out_base)
}

fn validate(opts: &ArrayOptions) -> Result<()> {
    if opts.thetas_deg.is_empty() || opts.phis_deg.is_empty() {
        return Err(PlotError::Input(
            "an array needs at least one θi and one φi".into(),
        ));
    }
    if opts.thetas_deg.len() > 64 || opts.phis_deg.len() > 64 {
        return Err(PlotError::Input("at most 64 rows and 64 columns".into()));
    }
    for &t in &opts.thetas_deg {
        check_angle("θi", t, 0.0, 90.0)?;
    }
    for &p in &opts.phis_deg {
        check_angle("φi", p, -360.0, 360.0)?;
    }
    if !(16..=1024).contains(&opts.disc_px) {
        return Err(PlotError::Input(format!(
            "disc size {} px must lie in [16, 1024]",
            opts.disc_px
        )));
    }
    if !(1..=8).contains(&opts.supersample) {
        return Err(PlotError::Input(format!(
            "supersample {} must lie in [1, 8]",
            opts.supersample
        )));
    }
    Ok(())
}

fn render(bsdfs: &[(&dyn Bsdf, &str)], opts: &ArrayOptions, out_base: &Path) -> Result<PlotFiles> {
    validate(opts)?;
    let hemispheres: Vec<Hemisphere> = if bsdfs.iter().any(|(b, _)| transmits(*b)) {
        vec![Hemisphere::Reflection, Hemisphere::Transmission]
    } else {
        vec![Hemisphere::Reflection]
    };
    let jobs: Vec<(usize, Hemisphere, f64, f64)> = hemispheres
        .iter()
        .flat_map(|&h| {
            (0..bsdfs.len()).flat_map(move |b| {
                opts.thetas_deg
                    .iter()
                    .flat_map(move |&t| opts.phis_deg.iter().map(move |&p| (b, h, t, p)))
            })
        })
        .collect();
    let discs: Vec<Disc> = jobs
        .par_iter()
        .map(|&(b, h, t, p)| transfer_disc(bsdfs[b].0, t, p, h, opts.disc_px, opts.supersample))
        .collect();
    let max = discs.iter().map(|d| d.max(opts.color)).fold(0.0, f64::max);
    let fig = ArrayFigure {
        labels: bsdfs.iter().map(|(_, l)| l.to_string()).collect(),
        hemispheres,
        discs,
        opts: opts.clone(),
        scale: nice_ceil(max),
    };
    let png = with_suffix(out_base, "png");
    write_png(&fig, &png)?;
    Ok(PlotFiles { png, svg: None })
}

const TITLE_H: i32 = 64;
const SUB_H: i32 = 30;
const HEAD_H: i32 = 22;
const ROW_W: i32 = 64;
const GAP: i32 = 12;
const BAR_W: i32 = 110;
const FOOT_H: i32 = 30;

/// A disc's top-left corner in the figure and its pixels.
type Tile = ((i32, i32), Vec<[u8; 3]>);

struct ArrayFigure {
    labels: Vec<String>,
    hemispheres: Vec<Hemisphere>,
    /// In job order: hemisphere, BSDF, θi, φi.
    discs: Vec<Disc>,
    opts: ArrayOptions,
    scale: f64,
}

impl ArrayFigure {
    fn cell(&self) -> i32 {
        self.opts.disc_px as i32 + GAP
    }

    fn section_size(&self) -> (i32, i32) {
        let c = self.cell();
        (
            ROW_W + self.opts.phis_deg.len() as i32 * c + GAP,
            SUB_H + HEAD_H + self.opts.thetas_deg.len() as i32 * c,
        )
    }

    fn display(&self, v: f64) -> f64 {
        let t = if self.scale > 0.0 {
            clean(v) / self.scale
        } else {
            0.0
        };
        if self.opts.cube_root {
            t.cbrt()
        } else {
            t
        }
    }

    fn value_at(&self, t: f64) -> f64 {
        if self.opts.cube_root {
            self.scale * t.powi(3)
        } else {
            self.scale * t
        }
    }

    fn pixel(&self, v: Rgb) -> [u8; 3] {
        match self.opts.color {
            ArrayColor::Rgb => [0, 1, 2].map(|c| byte(self.display(v[c]))),
            ArrayColor::Colormap => colormap(self.display(v.luminance())),
        }
    }

    /// Top-left corner of disc (θ row, φ col) of section (hemisphere h, BSDF b).
    fn disc_origin(&self, h: usize, b: usize, row: usize, col: usize) -> (i32, i32) {
        let (sw, sh) = self.section_size();
        let c = self.cell();
        (
            b as i32 * sw + ROW_W + col as i32 * c + GAP / 2,
            TITLE_H + h as i32 * sh + SUB_H + HEAD_H + row as i32 * c + GAP / 2,
        )
    }

    /// The raster of all discs on a white background, rows computed in parallel.
    fn raster(&self) -> Vec<u8> {
        let (w, h) = self.size();
        let (w, h) = (w as usize, h as usize);
        let mut buf = vec![255u8; w * h * 3];
        let (nt, np, nb) = (
            self.opts.thetas_deg.len(),
            self.opts.phis_deg.len(),
            self.labels.len(),
        );
        let d = self.opts.disc_px as usize;
        // Each disc's pixels, then copied row by row into the image.
        let tiles: Vec<Tile> = self
            .discs
            .par_iter()
            .enumerate()
            .map(|(i, disc)| {
                let (hb, rest) = (i / (nb * nt * np), i % (nb * nt * np));
                let (b, rest) = (rest / (nt * np), rest % (nt * np));
                let origin = self.disc_origin(hb, b, rest / np, rest % np);
                let px = disc
                    .values
                    .iter()
                    .map(|v| v.map_or([255, 255, 255], |v| self.pixel(v)))
                    .collect();
                (origin, px)
            })
            .collect();
        for ((x0, y0), px) in tiles {
            for (k, rgb) in px.iter().enumerate() {
                let (x, y) = (x0 as usize + k % d, y0 as usize + k / d);
                if x < w && y < h {
                    buf[3 * (y * w + x)..3 * (y * w + x) + 3].copy_from_slice(rgb);
                }
            }
        }
        // The colour bar.
        let (bx, by, bh) = self.bar_geometry();
        for y in by..by + bh {
            let t = 1.0 - (y - by) as f64 / (bh - 1).max(1) as f64;
            let rgb = match self.opts.color {
                ArrayColor::Rgb => [byte(t); 3],
                ArrayColor::Colormap => colormap(t),
            };
            for x in bx..bx + 18 {
                let (x, y) = (x as usize, y as usize);
                if x < w && y < h {
                    buf[3 * (y * w + x)..3 * (y * w + x) + 3].copy_from_slice(&rgb);
                }
            }
        }
        buf
    }

    fn bar_geometry(&self) -> (i32, i32, i32) {
        let (sw, sh) = self.section_size();
        let top = TITLE_H + SUB_H + HEAD_H;
        let bottom = TITLE_H + self.hemispheres.len() as i32 * sh - GAP;
        (
            self.labels.len() as i32 * sw + 16,
            top,
            (bottom - top).max(40),
        )
    }

    fn title(&self) -> String {
        if let Some(t) = &self.opts.title {
            return t.clone();
        }
        let what = if self.labels.len() > 1 {
            format!("{} vs {}", self.labels[0], self.labels[1..].join(" vs "))
        } else {
            self.labels.first().cloned().unwrap_or_default()
        };
        let root = if self.opts.cube_root {
            "cube root of "
        } else {
            ""
        };
        format!("Transfer probability, {root}p(ωo|ωi) = f·|cos θo|: {what}")
    }
}

impl Figure for ArrayFigure {
    fn size(&self) -> (u32, u32) {
        let (sw, sh) = self.section_size();
        let w = self.labels.len() as i32 * sw + BAR_W;
        let h = TITLE_H + self.hemispheres.len() as i32 * sh + FOOT_H;
        (w.max(640) as u32, h as u32)
    }

    fn draw<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>) -> DrawResult {
        let area = pen.area;
        let (w, h) = self.size();
        let buf = self.raster();
        let bitmap = BitMapElement::<(i32, i32)>::with_ref((0, 0), (w, h), &buf)
            .ok_or_else(|| "raster size mismatch".to_string())?;
        area.draw(&bitmap).map_err(de)?;
        let grey = RGBColor(90, 90, 90);
        pen.text(
            &self.title(),
            (w as i32 / 2, 12),
            20.0,
            BLACK,
            HPos::Center,
            VPos::Top,
        )?;
        let mapping = if self.opts.color == ArrayColor::Colormap {
            "luminance, inferno colour map"
        } else {
            "RGB"
        };
        pen.text(&format!("rows θi, columns φi; θo = 0° at the centre, 90° at the rim; light azimuth up; {mapping}"),
            (w as i32 / 2, 38),
            14.0,
            grey,
            HPos::Center,
            VPos::Top,
        )?;
        let (sw, sh) = self.section_size();
        let d = self.opts.disc_px as i32;
        let rad = d as f64 / 2.0;
        let dot = (d / 30).max(2);
        for (hi, hemi) in self.hemispheres.iter().enumerate() {
            for (b, label) in self.labels.iter().enumerate() {
                let (sx, sy) = (b as i32 * sw, TITLE_H + hi as i32 * sh);
                let hname = match hemi {
                    Hemisphere::Reflection => "reflection (upper hemisphere)",
                    Hemisphere::Transmission => "transmission (lower hemisphere, seen from above)",
                };
                pen.text(
                    &format!("{label} — {hname}"),
                    (sx + sw / 2, sy + 6),
                    17.0,
                    BLACK,
                    HPos::Center,
                    VPos::Top,
                )?;
                for (col, &phi) in self.opts.phis_deg.iter().enumerate() {
                    let (x0, _) = self.disc_origin(hi, b, 0, col);
                    let s = format!("φi = {}", fmt_deg(phi));
                    pen.text(
                        &s,
                        (x0 + d / 2, sy + SUB_H + HEAD_H / 2),
                        13.0,
                        grey,
                        HPos::Center,
                        VPos::Center,
                    )?;
                }
                for (row, &theta) in self.opts.thetas_deg.iter().enumerate() {
                    let (_, y0) = self.disc_origin(hi, b, row, 0);
                    let s = format!("θi = {}", fmt_deg(theta));
                    pen.text(
                        &s,
                        (sx + ROW_W - 4, y0 + d / 2),
                        13.0,
                        grey,
                        HPos::Right,
                        VPos::Center,
                    )?;
                    for (col, &phi) in self.opts.phis_deg.iter().enumerate() {
                        let (x0, y0) = self.disc_origin(hi, b, row, col);
                        let c = (x0 as f64 + rad, y0 as f64 + rad);
                        let ipt = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
                        area.draw(&Circle::new(
                            ipt(c.0, c.1),
                            d / 2,
                            RGBColor(150, 150, 150).stroke_width(1),
                        ))
                        .map_err(de)?;
                        // Light position: azimuth up, radius θi/90°.
                        let lr = rad * theta / 90.0;
                        area.draw(&Circle::new(ipt(c.0, c.1 - lr), dot, RED.filled()))
                            .map_err(de)?;
                        // Tangent (+x) direction: a green tick outside the rim.
                        let a = deg(90.0 - phi);
                        let tick = |k: f64| ipt(c.0 + k * rad * a.cos(), c.1 - k * rad * a.sin());
                        area.draw(&PathElement::new(
                            vec![tick(1.03), tick(1.2)],
                            RGBColor(0, 170, 0).stroke_width(2),
                        ))
                        .map_err(de)?;
                    }
                }
            }
        }
        // Colour bar ticks with the quantity's own values.
        let (bx, by, bh) = self.bar_geometry();
        area.draw(&Rectangle::new(
            [(bx, by), (bx + 18, by + bh)],
            grey.stroke_width(1),
        ))
        .map_err(de)?;
        pen.text(
            "p",
            (bx + 9, by - 6),
            15.0,
            BLACK,
            HPos::Center,
            VPos::Bottom,
        )?;
        for k in 0..=4 {
            let tk = k as f64 / 4.0;
            let y = by + ((1.0 - tk) * (bh - 1) as f64).round() as i32;
            area.draw(&PathElement::new(
                vec![(bx + 18, y), (bx + 23, y)],
                grey.stroke_width(1),
            ))
            .map_err(de)?;
            pen.text(
                &fmt_value(self.value_at(tk)),
                (bx + 26, y),
                12.0,
                BLACK,
                HPos::Left,
                VPos::Center,
            )?;
        }
        pen.text("red dot: light position; green tick: tangent (+x) direction; one shared intensity scale",
            (w as i32 / 2, h as i32 - FOOT_H / 2),
            13.0,
            grey,
            HPos::Center,
            VPos::Center,
        )
    }
}
