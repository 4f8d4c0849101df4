//! Plots of regular half-vector sample patterns (002 Fig. 4–5, 000 Fig. 4.17): the half vectors
//! of one lobe drawn in the disk around the lobe centre, with the border of the lobe where the
//! Beckmann exponential q(h) (002 Eq. 5) falls to ξ0 and the circle θ = θmax (002 Eq. 11).
//!
//! The disk is the azimuthal equidistant projection about +z: a half vector with polar angle θh
//! and azimuth φh is drawn at (θh cos φh, θh sin φh) in degrees, so equally spaced circles of
//! the concentric patterns appear equally spaced. x is the lobe's tangent, y its bitangent.
//! Samples are coloured by q(h) (1 at the centre, ξ0 at the border).

use crate::color::colormap;
use crate::draw::{fmt_deg, nice_ceil, write_png_svg, Dash, DrawResult, Figure, Pen};
use crate::{PlotError, PlotFiles, Result};
use lustre_brdf::DVec3;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use std::path::Path;

/// One panel: a pattern of half vectors for a lobe with roughness `mx`, `my` and threshold ξ0.
#[derive(Clone, Debug, PartialEq)]
pub struct PatternPanel {
    /// Panel title (e.g. "s1, nc = 3: 19 samples").
    pub title: String,
    /// Unit half vectors in the lobe frame (x = tangent), z > 0.
    pub h: Vec<DVec3>,
    /// Roughness along the tangent.
    pub mx: f64,
    /// Roughness along the bitangent.
    pub my: f64,
    /// The threshold whose q(h) = ξ0 curve is drawn (in (0, 1)).
    pub xi0: f64,
}

/// Options of [`pattern_plot`].
#[derive(Clone, Debug, PartialEq)]
pub struct PatternOptions {
    /// Figure title.
    pub title: String,
    /// Width of one panel in pixels (120 … 4000).
    pub panel_px: u32,
    /// Panels per row.
    pub columns: usize,
}

impl Default for PatternOptions {
    fn default() -> Self {
        PatternOptions {
            title: "Half-vector sample pattern".into(),
            panel_px: 420,
            columns: 3,
        }
    }
}

/// q(h) of 002 Eq. 5: exp(−tan²θh (cos²φh/mx² + sin²φh/my²)).
fn q(mx: f64, my: f64, h: DVec3) -> f64 {
    if h.z <= 0.0 {
        return 0.0;
    }
    let (ax, ay) = (h.x / (mx * h.z), h.y / (my * h.z));
    (-(ax * ax + ay * ay)).exp()
}

/// The disk position of a half vector in degrees: (θh cos φh, θh sin φh).
pub fn disk_position(h: DVec3) -> (f64, f64) {
    let rho = (h.x * h.x + h.y * h.y).sqrt();
    let theta = rho.atan2(h.z).to_degrees();
    if rho > 0.0 {
        (theta * h.x / rho, theta * h.y / rho)
    } else {
        (0.0, 0.0)
    }
}

/// The polar angle (degrees) of the border q = ξ0 at azimuth φ:
/// tan θ = √(−ln ξ0 / (cos²φ/mx² + sin²φ/my²)).
pub fn border_theta_deg(mx: f64, my: f64, xi0: f64, phi: f64) -> f64 {
    let (s, c) = phi.sin_cos();
    ((-xi0.ln()) / (c * c / (mx * mx) + s * s / (my * my)))
        .sqrt()
        .atan()
        .to_degrees()
}

/// θmax of 002 Eq. 11 in degrees.
fn theta_max_deg(p: &PatternPanel) -> f64 {
    ((-p.xi0.ln()).sqrt() * p.mx.max(p.my)).atan().to_degrees()
}

fn check(panels: &[PatternPanel], opts: &PatternOptions) -> Result<()> {
    if panels.is_empty() {
        return Err(PlotError::Input(
            "a pattern plot needs at least one panel".into(),
        ));
    }
    if opts.panel_px < 120 || opts.panel_px > 4000 || opts.columns == 0 {
        return Err(PlotError::Input(format!(
            "panel size {} px must lie in [120, 4000] and columns ({}) be at least 1",
            opts.panel_px, opts.columns
        )));
    }
    for p in panels {
        if !(p.mx.is_finite() && p.mx > 0.0 && p.my.is_finite() && p.my > 0.0) {
            return Err(PlotError::Input(format!(
                "panel '{}': roughness ({}, {}) must be finite and > 0",
                p.title, p.mx, p.my
            )));
        }
        if !(p.xi0 > 0.0 && p.xi0 < 1.0) {
            return Err(PlotError::Input(format!(
                "panel '{}': xi0 = {} must lie in (0, 1)",
                p.title, p.xi0
            )));
        }
        if p.h.iter().any(|h| !h.is_finite() || h.z <= 0.0) {
            return Err(PlotError::Input(format!(
                "panel '{}': half vectors must be finite with z > 0",
                p.title
            )));
        }
    }
    Ok(())
}

/// Draws the panels side by side (`opts.columns` per row) into `out_base.png` and
/// `out_base.svg`, on a shared angular scale.
pub fn pattern_plot(
    panels: &[PatternPanel],
    opts: &PatternOptions,
    out_base: &Path,
) -> Result<PlotFiles> {
    check(panels, opts)?;
    let extent = panels
        .iter()
        .flat_map(|p| {
            let border =
                (0..360).map(move |k| border_theta_deg(p.mx, p.my, p.xi0, (k as f64).to_radians()));
            let pts = p.h.iter().map(|&h| {
                let (x, y) = disk_position(h);
                (x * x + y * y).sqrt()
            });
            border.chain(pts).chain(std::iter::once(theta_max_deg(p)))
        })
        .fold(0.0f64, f64::max);
    let fig = PatternFigure {
        panels: panels.to_vec(),
        opts: opts.clone(),
        extent: nice_ceil(extent * 1.08).min(90.0),
    };
    write_png_svg(&fig, out_base)
}

const TITLE_H: f64 = 50.0;
const PANEL_TITLE_H: f64 = 34.0;
const LEGEND_H: f64 = 40.0;

struct PatternFigure {
    panels: Vec<PatternPanel>,
    opts: PatternOptions,
    /// The disk radius in degrees, shared by all panels.
    extent: f64,
}

impl PatternFigure {
    fn cols(&self) -> usize {
        self.opts.columns.min(self.panels.len())
    }

    fn rows(&self) -> usize {
        self.panels.len().div_ceil(self.cols())
    }

    fn panel_h(&self) -> f64 {
        self.opts.panel_px as f64 + PANEL_TITLE_H
    }

    fn draw_panel<DB: DrawingBackend>(
        &self,
        pen: &Pen<'_, DB>,
        p: &PatternPanel,
        x0: f64,
        y0: f64,
    ) -> DrawResult {
        let w = self.opts.panel_px as f64;
        let r = 0.5 * w - 34.0;
        let (cx, cy) = (x0 + 0.5 * w, y0 + PANEL_TITLE_H + 0.5 * w);
        let to_px = |x: f64, y: f64| (cx + x / self.extent * r, cy - y / self.extent * r);
        let grid = RGBColor(215, 215, 215);
        let label = RGBColor(90, 90, 90);
        pen.text(
            &p.title,
            (cx, y0 + 8.0),
            16.0,
            BLACK,
            HPos::Center,
            VPos::Top,
        )?;
        // Angle rings every quarter of the extent, labelled along +x.
        for k in 1..=4 {
            let rr = self.extent * k as f64 / 4.0;
            let pts: Vec<(f64, f64)> = (0..=360)
                .map(|a| {
                    let a = (a as f64).to_radians();
                    to_px(rr * a.cos(), rr * a.sin())
                })
                .collect();
            pen.path(&pts, if k == 4 { label } else { grid }, 1.0, Dash::Solid)?;
            let (lx, ly) = to_px(rr, 0.0);
            pen.text(
                &fmt_deg(rr),
                (lx - 2.0, ly + 4.0),
                11.0,
                label,
                HPos::Right,
                VPos::Top,
            )?;
        }
        pen.path(
            &[to_px(-self.extent, 0.0), to_px(self.extent, 0.0)],
            grid,
            1.0,
            Dash::Solid,
        )?;
        pen.path(
            &[to_px(0.0, -self.extent), to_px(0.0, self.extent)],
            grid,
            1.0,
            Dash::Solid,
        )?;
        let (ax, ay) = to_px(self.extent, 0.0);
        pen.text("x", (ax + 6.0, ay), 13.0, label, HPos::Left, VPos::Center)?;
        let (bx, by) = to_px(0.0, self.extent);
        pen.text("y", (bx, by - 4.0), 13.0, label, HPos::Center, VPos::Bottom)?;
        // θmax circle (002 Eq. 11) and the q = ξ0 border (the ξ0 ellipse).
        let tm = theta_max_deg(p);
        let circle: Vec<(f64, f64)> = (0..=360)
            .map(|a| {
                let a = (a as f64).to_radians();
                to_px(tm * a.cos(), tm * a.sin())
            })
            .collect();
        pen.path(
            &circle,
            RGBColor(120, 120, 120),
            1.0,
            Dash::Dashed(3.0, 4.0),
        )?;
        let border: Vec<(f64, f64)> = (0..=720)
            .map(|k| {
                let phi = (k as f64 / 2.0).to_radians();
                let t = border_theta_deg(p.mx, p.my, p.xi0, phi);
                to_px(t * phi.cos(), t * phi.sin())
            })
            .collect();
        pen.path(&border, RGBColor(214, 39, 40), 1.5, Dash::Dashed(7.0, 4.0))?;
        // Samples, coloured by q(h).
        for &h in &p.h {
            let (x, y) = disk_position(h);
            let t = (q(p.mx, p.my, h) - p.xi0) / (1.0 - p.xi0);
            let [cr, cg, cb] = colormap(0.15 + 0.75 * t);
            pen.circle(to_px(x, y), 5.0, RGBColor(cr, cg, cb), true)?;
            pen.circle(to_px(x, y), 5.0, BLACK, false)?;
        }
        Ok(())
    }
}

impl Figure for PatternFigure {
    fn size(&self) -> (u32, u32) {
        let w = (self.cols() as u32 * self.opts.panel_px).max(560);
        let h = TITLE_H + self.rows() as f64 * self.panel_h() + LEGEND_H;
        (w, h.round() as u32)
    }

    fn supersample(&self) -> u32 {
        2
    }

    fn draw<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>) -> DrawResult {
        let (w, h) = self.size();
        let (w, h) = (w as f64, h as f64);
        pen.text(
            &self.opts.title,
            (w / 2.0, 12.0),
            20.0,
            BLACK,
            HPos::Center,
            VPos::Top,
        )?;
        let x_off = (w - (self.cols() as u32 * self.opts.panel_px) as f64) / 2.0;
        for (i, p) in self.panels.iter().enumerate() {
            let (row, col) = (i / self.cols(), i % self.cols());
            let x0 = x_off + col as f64 * self.opts.panel_px as f64;
            let y0 = TITLE_H + row as f64 * self.panel_h();
            self.draw_panel(pen, p, x0, y0)?;
        }
        // Legend.
        let y = h - LEGEND_H / 2.0;
        let x = w / 2.0 - 260.0;
        let [cr, cg, cb] = colormap(0.9);
        pen.circle((x, y), 5.0, RGBColor(cr, cg, cb), true)?;
        pen.circle((x, y), 5.0, BLACK, false)?;
        pen.text(
            "half vector (colour: q(h))",
            (x + 12.0, y),
            13.0,
            BLACK,
            HPos::Left,
            VPos::Center,
        )?;
        let x = x + 210.0;
        pen.path(
            &[(x, y), (x + 30.0, y)],
            RGBColor(214, 39, 40),
            1.5,
            Dash::Dashed(7.0, 4.0),
        )?;
        pen.text(
            "q = ξ0",
            (x + 36.0, y),
            13.0,
            BLACK,
            HPos::Left,
            VPos::Center,
        )?;
        let x = x + 110.0;
        pen.path(
            &[(x, y), (x + 30.0, y)],
            RGBColor(120, 120, 120),
            1.0,
            Dash::Dashed(3.0, 4.0),
        )?;
        pen.text("θmax", (x + 36.0, y), 13.0, BLACK, HPos::Left, VPos::Center)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ring(n: usize, theta: f64) -> Vec<DVec3> {
        (0..n)
            .map(|k| {
                let phi = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                )
            })
            .collect()
    }

    #[test]
    fn disk_and_border_geometry() {
        let t = 20f64.to_radians();
        let (x, y) = disk_position(DVec3::new(0.0, t.sin(), t.cos()));
        assert!(x.abs() < 1e-12 && (y - 20.0).abs() < 1e-12);
        assert_eq!(disk_position(DVec3::Z), (0.0, 0.0));
        // Along x the border is θmax of the x roughness: arctan(√(ln 10) · 0.2) = 16.88°.
        let b = border_theta_deg(0.2, 0.075, 0.1, 0.0);
        assert!((b - (10f64.ln().sqrt() * 0.2).atan().to_degrees()).abs() < 1e-12);
        assert!((b - 16.882).abs() < 1e-3);
        // q at the border is ξ0.
        let bt = border_theta_deg(0.2, 0.075, 0.1, 1.0).to_radians();
        let h = DVec3::new(bt.sin() * 1f64.cos(), bt.sin() * 1f64.sin(), bt.cos());
        assert!((q(0.2, 0.075, h) - 0.1).abs() < 1e-12);
    }

    #[test]
    fn writes_png_and_svg_and_rejects_bad_input() {
        let dir = tempfile::tempdir().unwrap();
        let mut h = vec![DVec3::Z];
        h.extend(ring(6, 0.05));
        let panel = PatternPanel {
            title: "test".into(),
            h,
            mx: 0.2,
            my: 0.075,
            xi0: 0.1,
        };
        let files = pattern_plot(
            &[panel.clone(), panel.clone()],
            &PatternOptions::default(),
            &dir.path().join("pat"),
        )
        .unwrap();
        assert!(std::fs::metadata(&files.png).unwrap().len() > 1000);
        let svg = std::fs::read_to_string(files.svg.unwrap()).unwrap();
        assert!(svg.contains("<circle"));
        let opts = PatternOptions::default();
        assert!(pattern_plot(&[], &opts, &dir.path().join("x")).is_err());
        let mut bad = panel.clone();
        bad.xi0 = 1.0;
        assert!(pattern_plot(&[bad], &opts, &dir.path().join("x")).is_err());
        let mut bad = panel;
        bad.h.push(DVec3::new(0.0, 0.0, -1.0));
        assert!(pattern_plot(&[bad], &opts, &dir.path().join("x")).is_err());
    }
}
