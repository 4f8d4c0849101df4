//! Lobes in the plane of incidence (004 Fig. V.11, 000 Fig. 3.12): for each θi one polar panel
//! whose radius in direction θo is p = f·|cos θo| (or f), optionally cube-rooted, with several
//! BSDFs overlaid for comparison. The lower half-plane (transmission) is drawn when any BSDF
//! scatters into it.

use crate::color::{CHANNEL, PALETTE};
use crate::draw::{fmt_deg, fmt_value, nice_ceil, write_png_svg, Dash, DrawResult, Figure, Pen};
use crate::{check_angle, clean, PlotError, PlotFiles, Result};
use lustre_brdf::frame::{deg, spherical};
use lustre_brdf::{Bsdf, DVec3, Rgb};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use rayon::prelude::*;
use std::path::Path;

/// The radial quantity of a lobe plot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Quantity {
    /// The transfer probability p(ωo|ωi) = f·|cos θo| (000 §2.3, what goniometers record).
    #[default]
    TransferProbability,
    /// The BSDF value f in 1/sr.
    Bsdf,
}

/// Which colour channels are plotted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Channels {
    /// Rec. 709 luminance, one curve per BSDF.
    #[default]
    Luminance,
    /// One curve per RGB channel and BSDF (BSDFs told apart by dash style).
    Rgb,
}

impl Channels {
    /// How many curves each BSDF gets.
    pub fn count(self) -> usize {
        match self {
            Channels::Luminance => 1,
            Channels::Rgb => 3,
        }
    }
}

/// Options of [`polar_plot`].
#[derive(Clone, Debug, PartialEq)]
pub struct PolarOptions {
    /// Radial quantity (default f·|cos θo|).
    pub quantity: Quantity,
    /// Plot the cube root of the quantity (004 Fig. V.11, 000 Fig. 3.12); ring labels keep the
    /// quantity's own values.
    pub cube_root: bool,
    /// Luminance or RGB curves.
    pub channels: Channels,
    /// Azimuth φi of the plane of incidence, degrees (the plane contains the normal and the
    /// direction of azimuth φi).
    pub phi_i_deg: f64,
    /// Samples over the full circle of outgoing directions (at least 8; default 720, 0.5°).
    pub samples: usize,
    /// Width of one panel in pixels (default 440).
    pub panel_px: u32,
    /// Figure title; a descriptive default when `None`.
    pub title: Option<String>,
}

impl Default for PolarOptions {
    fn default() -> Self {
        PolarOptions {
            quantity: Quantity::TransferProbability,
            cube_root: false,
            channels: Channels::Luminance,
            phi_i_deg: 0.0,
            samples: 720,
            panel_px: 440,
            title: None,
        }
    }
}

/// One outgoing direction of a lobe curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolarSample {
    /// Signed angle from the normal in the plane of incidence, degrees in [−180, 180]: positive
    /// on the mirror side (away from the light), |angle| > 90 below the surface (transmission).
    pub angle_deg: f64,
    /// The outgoing direction ωo in the local frame.
    pub wo: DVec3,
    /// The plotted quantity before any cube root (negative or non-finite values set to 0).
    pub value: Rgb,
}

impl PolarSample {
    /// The quantity in curve `c` (0 for luminance; 0, 1, 2 for R, G, B).
    pub fn channel(&self, channels: Channels, c: usize) -> f64 {
        match channels {
            Channels::Luminance => clean(self.value.luminance()),
            Channels::Rgb => self.value[c.min(2)],
        }
    }

    /// The curve point at radius `r` in the plot plane: x to the mirror side, y along the normal.
    pub fn point(&self, r: f64) -> (f64, f64) {
        let a = deg(self.angle_deg);
        (r * a.sin(), r * a.cos())
    }
}

/// A lobe sampled over the whole circle of outgoing directions in the plane of incidence.
#[derive(Clone, Debug, PartialEq)]
pub struct PolarCurve {
    /// Incidence angle θi, degrees.
    pub theta_i_deg: f64,
    /// Azimuth of the plane of incidence, degrees.
    pub phi_i_deg: f64,
    /// The incident (light) direction ωi.
    pub wi: DVec3,
    /// Samples from −180° to 180° inclusive.
    pub samples: Vec<PolarSample>,
}

impl PolarCurve {
    /// True when some sample below the surface is non-zero.
    pub fn transmits(&self) -> bool {
        self.samples
            .iter()
            .any(|s| s.wo.z < -1e-9 && s.value.max_component() > 0.0)
    }

    /// The largest value over the samples and the curves of `channels`.
    pub fn max(&self, channels: Channels) -> f64 {
        self.samples
            .iter()
            .flat_map(|s| (0..channels.count()).map(move |c| s.channel(channels, c)))
            .fold(0.0, f64::max)
    }
}

/// The most incidence angles (one panel each) and materials (one curve each) of a polar plot.
pub const MAX_PANELS: usize = 16;

/// Samples `bsdf` in the plane of incidence for light at (θi, φi = `opts.phi_i_deg`).
///
/// The light direction is ωi = (θi, φi); the outgoing direction at signed angle ψ is
/// ωo = −sin ψ·(cos φi, sin φi, 0) + cos ψ·z, so ψ = θi is the mirror direction and ψ = −θi the
/// light itself.
pub fn polar_curve(bsdf: &dyn Bsdf, theta_i_deg: f64, opts: &PolarOptions) -> PolarCurve {
    let phi = deg(opts.phi_i_deg);
    let wi = spherical(deg(theta_i_deg), phi);
    let d = DVec3::new(phi.cos(), phi.sin(), 0.0);
    let n = opts.samples.max(8);
    let samples = (0..=n)
        .map(|k| {
            let angle_deg = -180.0 + 360.0 * k as f64 / n as f64;
            let a = deg(angle_deg);
            let wo = (-a.sin() * d + a.cos() * DVec3::Z).normalize();
            let f = bsdf.eval(wi, wo).map(clean);
            let value = match opts.quantity {
                Quantity::TransferProbability => f * wo.z.abs(),
                Quantity::Bsdf => f,
            };
            PolarSample {
                angle_deg,
                wo,
                value,
            }
        })
        .collect();
    PolarCurve {
        theta_i_deg,
        phi_i_deg: opts.phi_i_deg,
        wi,
        samples,
    }
}

/// Draws one polar panel per θi with every BSDF of `bsdfs` overlaid (labelled in the legend) and
/// writes `{out_base}.png` and `{out_base}.svg`. All panels share one radial scale.
///
/// Errors: no BSDF or no angle, θi outside [0°, 90°], φi not finite, a zero panel size, or a
/// file that cannot be written.
pub fn polar_plot(
    bsdfs: &[(&dyn Bsdf, &str)],
    thetas_deg: &[f64],
    opts: &PolarOptions,
    out_base: &Path,
) -> Result<PlotFiles> {
    if bsdfs.is_empty() || thetas_deg.is_empty() {
        return Err(PlotError::Input(
            "a polar plot needs at least one BSDF and one θi".into(),
        ));
    }
    if thetas_deg.len() > MAX_PANELS || bsdfs.len() > MAX_PANELS {
        return Err(PlotError::Input(format!(
            "a polar plot takes at most {MAX_PANELS} θi and {MAX_PANELS} materials (got {} and {})",
            thetas_deg.len(),
            bsdfs.len()
        )));
    }
    for &t in thetas_deg {
        check_angle("θi", t, 0.0, 90.0)?;
    }
    check_angle("φi", opts.phi_i_deg, -360.0, 360.0)?;
    if opts.panel_px < 120 || opts.panel_px > 4000 {
        return Err(PlotError::Input(format!(
            "panel size {} px must lie in [120, 4000]",
            opts.panel_px
        )));
    }
    let curves: Vec<Vec<PolarCurve>> = thetas_deg
        .par_iter()
        .map(|&t| {
            bsdfs
                .iter()
                .map(|(b, _)| polar_curve(*b, t, opts))
                .collect()
        })
        .collect();
    let fig = PolarFigure::new(
        curves,
        bsdfs.iter().map(|(_, l)| l.to_string()).collect(),
        opts.clone(),
    );
    write_png_svg(&fig, out_base)
}

const TITLE_H: i32 = 58;
const LEGEND_H: i32 = 44;
const PANEL_TITLE_H: i32 = 30;

struct PolarFigure {
    curves: Vec<Vec<PolarCurve>>,
    labels: Vec<String>,
    opts: PolarOptions,
    transmission: bool,
    /// Outer ring value (the quantity, not its cube root).
    vmax: f64,
    cols: usize,
    rows: usize,
}

impl PolarFigure {
    fn new(curves: Vec<Vec<PolarCurve>>, labels: Vec<String>, opts: PolarOptions) -> Self {
        let transmission = curves.iter().flatten().any(PolarCurve::transmits);
        let vmax = nice_ceil(
            curves
                .iter()
                .flatten()
                .map(|c| c.max(opts.channels))
                .fold(0.0, f64::max),
        );
        let n = curves.len();
        let cols = match n {
            0..=3 => n.max(1),
            4 => 2,
            5..=6 => 3,
            _ => 4,
        };
        let rows = n.div_ceil(cols);
        PolarFigure {
            curves,
            labels,
            opts,
            transmission,
            vmax,
            cols,
            rows,
        }
    }

    fn radius(&self) -> i32 {
        (self.opts.panel_px as f64 * 0.36) as i32
    }

    fn panel_h(&self) -> i32 {
        let r = self.radius();
        if self.transmission {
            PANEL_TITLE_H + 2 * r + 60
        } else {
            PANEL_TITLE_H + r + 62
        }
    }

    /// The plotted radius fraction (0..1 of the outer ring) of a quantity value.
    fn frac(&self, v: f64) -> f64 {
        if self.opts.cube_root {
            (v / self.vmax).cbrt()
        } else {
            v / self.vmax
        }
    }

    /// The quantity value at a radius fraction.
    fn value_at(&self, frac: f64) -> f64 {
        if self.opts.cube_root {
            self.vmax * frac.powi(3)
        } else {
            self.vmax * frac
        }
    }

    fn title(&self) -> String {
        if let Some(t) = &self.opts.title {
            return t.clone();
        }
        let q = match self.opts.quantity {
            Quantity::TransferProbability => "Transfer probability f·|cos θo|",
            Quantity::Bsdf => "BSDF f (1/sr)",
        };
        let root = if self.opts.cube_root {
            ", cube root"
        } else {
            ""
        };
        let ch = match self.opts.channels {
            Channels::Luminance => "luminance",
            Channels::Rgb => "RGB",
        };
        format!(
            "{q} in the plane of incidence (φi = {}){root}, {ch}",
            fmt_deg(self.opts.phi_i_deg)
        )
    }

    fn draw_panel<DB: DrawingBackend>(
        &self,
        pen: &Pen<'_, DB>,
        curves: &[PolarCurve],
        x0: i32,
        y0: i32,
    ) -> DrawResult {
        let p = self.opts.panel_px as f64;
        let rf = self.radius() as f64;
        let cx = x0 as f64 + p / 2.0;
        let cy = (y0 + PANEL_TITLE_H + 26 + self.radius()) as f64;
        let to_px = |x: f64, y: f64| (cx + x, cy - y);
        let grid = RGBColor(215, 215, 215);
        let label = RGBColor(90, 90, 90);
        let theta_i = curves.first().map_or(0.0, |c| c.theta_i_deg);
        let (lo, hi): (i32, i32) = if self.transmission {
            (-180, 180)
        } else {
            (-90, 90)
        };

        // Rings with their values along the surface line.
        for k in 1..=4 {
            let fr = k as f64 / 4.0;
            let pts: Vec<(f64, f64)> = (2 * lo..=2 * hi)
                .map(|a| {
                    let a = deg(a as f64 / 2.0);
                    to_px(fr * rf * a.sin(), fr * rf * a.cos())
                })
                .collect();
            let color = if k == 4 {
                RGBColor(150, 150, 150)
            } else {
                grid
            };
            pen.path(&pts, color, 1.0, Dash::Solid)?;
            let (lx, ly) = to_px(fr * rf, 0.0);
            let v = fmt_value(self.value_at(fr));
            pen.text(
                &v,
                (lx - 2.0, ly + 5.0),
                12.0,
                label,
                HPos::Right,
                VPos::Top,
            )?;
        }
        // Spokes every 15°, labels every 30° (θo measured from +z).
        for a in (lo..=hi).step_by(15) {
            let ar = deg(a as f64);
            let inner = if a % 30 == 0 { 0.0 } else { 0.25 };
            let p0 = to_px(inner * rf * ar.sin(), inner * rf * ar.cos());
            let p1 = to_px(rf * ar.sin(), rf * ar.cos());
            pen.path(&[p0, p1], grid, 1.0, Dash::Solid)?;
            if a % 30 == 0 && a.abs() != 90 && a != -180 {
                let lp = to_px((rf + 14.0) * ar.sin(), (rf + 14.0) * ar.cos());
                let s = if a == 0 {
                    "θo = 0°".to_string()
                } else {
                    fmt_deg(a.abs() as f64)
                };
                pen.text(&s, lp, 12.0, label, HPos::Center, VPos::Center)?;
            }
        }
        // The surface.
        let dark = RGBColor(60, 60, 60);
        pen.path(
            &[(cx - rf - 10.0, cy), (cx + rf + 10.0, cy)],
            dark,
            2.0,
            Dash::Solid,
        )?;
        pen.text(
            "90°",
            (cx - rf - 12.0, cy),
            12.0,
            label,
            HPos::Right,
            VPos::Center,
        )?;
        pen.text(
            "90°",
            (cx + rf + 12.0, cy),
            12.0,
            label,
            HPos::Left,
            VPos::Center,
        )?;
        // Light direction (orange ray, red dot at the rim) and mirror direction (dashed).
        let ti = deg(theta_i);
        let light = to_px(-rf * ti.sin(), rf * ti.cos());
        let mirror = to_px(rf * ti.sin(), rf * ti.cos());
        pen.path(&[(cx, cy), light], RGBColor(255, 160, 0), 2.0, Dash::Solid)?;
        pen.path(
            &[(cx, cy), mirror],
            RGBColor(120, 120, 120),
            1.0,
            Dash::Dashed(6.0, 5.0),
        )?;
        pen.circle(light, 6.0, RED, true)?;

        // The lobes.
        for (b, c) in curves.iter().enumerate() {
            // Colourless lobes draw one grey curve instead of three coinciding ones.
            let grey = self.opts.channels == Channels::Rgb
                && c.samples.iter().all(|s| {
                    let v = s.value;
                    (v[0] - v[1]).abs().max((v[1] - v[2]).abs()) <= 1e-6 * self.vmax
                });
            let count = if grey { 1 } else { self.opts.channels.count() };
            for ch in 0..count {
                let pts: Vec<(f64, f64)> = c
                    .samples
                    .iter()
                    .filter(|s| self.transmission || s.angle_deg.abs() <= 90.0)
                    .map(|s| {
                        let (x, y) =
                            s.point(self.frac(s.channel(self.opts.channels, ch)).min(1.5) * rf);
                        to_px(x, y)
                    })
                    .collect();
                self.draw_curve(pen, &pts, b, ch, grey)?;
            }
        }
        let title = format!("θi = {}", fmt_deg(theta_i));
        pen.text(
            &title,
            (cx, y0 as f64 + 6.0),
            19.0,
            BLACK,
            HPos::Center,
            VPos::Top,
        )
    }

    /// The dash pattern of the `b`-th BSDF's curves.
    fn dash(b: usize) -> Dash {
        match b % 3 {
            0 => Dash::Solid,
            1 => Dash::Dashed(9.0, 5.0),
            _ => Dash::Dashed(2.0, 4.0),
        }
    }

    /// Draws a curve of BSDF `b`, channel `ch` in its style (`grey`: one curve for all channels).
    fn draw_curve<DB: DrawingBackend>(
        &self,
        pen: &Pen<'_, DB>,
        pts: &[(f64, f64)],
        b: usize,
        ch: usize,
        grey: bool,
    ) -> DrawResult {
        let (color, dash) = match self.opts.channels {
            Channels::Luminance => (PALETTE[b % PALETTE.len()], b),
            Channels::Rgb if grey => (RGBColor(70, 70, 70), b),
            Channels::Rgb => (CHANNEL[ch], b),
        };
        // The first BSDF (the reference, e.g. a measurement) is solid and the others dashed, so
        // that overlaid curves stay visible where they coincide.
        pen.path(pts, color, 2.0, Self::dash(dash))
    }

    fn draw_legend<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>, y: i32) -> DrawResult {
        let y = y as f64;
        let grey = RGBColor(90, 90, 90);
        let mut x = 20.0;
        for (b, label) in self.labels.iter().enumerate() {
            let pts = [(x, y), (x + 34.0, y)];
            match self.opts.channels {
                Channels::Luminance => self.draw_curve(pen, &pts, b, 0, false)?,
                // A black sample of the dash style.
                Channels::Rgb => pen.path(&pts, BLACK, 2.0, Self::dash(b))?,
            }
            pen.text(label, (x + 42.0, y), 16.0, BLACK, HPos::Left, VPos::Center)?;
            x += 70.0 + 8.0 * label.chars().count() as f64;
        }
        if self.opts.channels == Channels::Rgb {
            let note = "(curve colour = R, G, B channel; grey where all coincide)";
            pen.text(note, (x, y), 14.0, grey, HPos::Left, VPos::Center)?;
            x += 370.0;
        }
        pen.circle((x + 6.0, y), 6.0, RED, true)?;
        pen.text(
            "light ωi",
            (x + 18.0, y),
            14.0,
            grey,
            HPos::Left,
            VPos::Center,
        )?;
        let x = x + 90.0;
        pen.path(
            &[(x, y), (x + 30.0, y)],
            RGBColor(120, 120, 120),
            1.0,
            Dash::Dashed(6.0, 5.0),
        )?;
        pen.text(
            "mirror direction",
            (x + 38.0, y),
            14.0,
            grey,
            HPos::Left,
            VPos::Center,
        )
    }
}

impl Figure for PolarFigure {
    fn size(&self) -> (u32, u32) {
        let w = self.cols as u32 * self.opts.panel_px;
        let legend_w = self
            .labels
            .iter()
            .map(|l| 70 + 8 * l.chars().count() as u32)
            .sum::<u32>()
            + if self.opts.channels == Channels::Rgb {
                790
            } else {
                420
            };
        let h = TITLE_H + self.rows as i32 * self.panel_h() + LEGEND_H;
        (w.max(legend_w).max(520), h as u32)
    }

    fn supersample(&self) -> u32 {
        2
    }

    fn draw<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>) -> DrawResult {
        let (w, h) = self.size();
        let x_off = (w as i32 - self.cols as i32 * self.opts.panel_px as i32) / 2;
        pen.text(
            &self.title(),
            (w as i32 / 2, 14),
            21.0,
            BLACK,
            HPos::Center,
            VPos::Top,
        )?;
        for (i, curves) in self.curves.iter().enumerate() {
            let (row, col) = (i / self.cols, i % self.cols);
            let x0 = x_off + col as i32 * self.opts.panel_px as i32;
            let y0 = TITLE_H + row as i32 * self.panel_h();
            self.draw_panel(pen, curves, x0, y0)?;
        }
        self.draw_legend(pen, h as i32 - LEGEND_H / 2 - 4)
    }
}
