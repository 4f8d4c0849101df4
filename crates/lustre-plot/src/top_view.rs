//! A top view (x right, z down) of a scene's real-time set-up: every mesh's bounds in grey, the
//! planar reflectors in magenta, the object probes in yellow, the room probes' parallax boxes in
//! dashed cyan with their centres, the cameras in black.

use crate::draw::{write_png_svg, Dash, DrawResult, Figure, Pen};
use crate::{PlotError, PlotFiles, Result};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use std::path::Path;

/// What an item of the top view is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TopKind {
    /// A mesh without a set-up role (its bounds).
    Mesh,
    /// A planar reflector (its bounds).
    Reflector,
    /// An object probe's object (its bounds).
    ObjectProbe,
    /// A room probe's parallax box; `at` is its centre.
    RoomProbe,
    /// A camera; `at` is its position, `hi` − `lo` its forward direction's x–z part.
    Camera,
}

/// One rectangle (x–z bounds) of the top view.
#[derive(Clone, Debug, PartialEq)]
pub struct TopItem {
    /// What it is.
    pub kind: TopKind,
    /// Its name (drawn for reflectors, object and room probes).
    pub label: String,
    /// Low corner (x, z).
    pub lo: [f64; 2],
    /// High corner (x, z).
    pub hi: [f64; 2],
    /// A point (x, z): a room probe's centre, a camera's position.
    pub at: [f64; 2],
}

struct TopFigure<'a> {
    items: &'a [TopItem],
    lo: [f64; 2],
    scale: f64,
    size: (u32, u32),
}

const PAD: f64 = 24.0;

impl Figure for TopFigure<'_> {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn supersample(&self) -> u32 {
        2
    }

    fn draw<DB: DrawingBackend>(&self, pen: &Pen<'_, DB>) -> DrawResult {
        let p = |v: [f64; 2]| {
            (
                PAD + (v[0] - self.lo[0]) * self.scale,
                PAD + (v[1] - self.lo[1]) * self.scale,
            )
        };
        let rect = |a: [f64; 2], b: [f64; 2]| {
            let (x0, z0) = p(a);
            let (x1, z1) = p(b);
            vec![(x0, z0), (x1, z0), (x1, z1), (x0, z1), (x0, z0)]
        };
        // Meshes first, the set-up over them.
        for pass in 0..2 {
            for it in self.items {
                let (colour, width, dash) = match (pass, it.kind) {
                    (0, TopKind::Mesh) => (RGBColor(185, 185, 185), 0.6, Dash::Solid),
                    (1, TopKind::Reflector) => (RGBColor(230, 40, 200), 2.0, Dash::Solid),
                    (1, TopKind::ObjectProbe) => (RGBColor(200, 160, 0), 2.0, Dash::Solid),
                    (1, TopKind::RoomProbe) => (RGBColor(0, 170, 220), 2.0, Dash::Dashed(8.0, 4.0)),
                    (1, TopKind::Camera) => {
                        let c = p(it.at);
                        let d = [it.hi[0] - it.lo[0], it.hi[1] - it.lo[1]];
                        let len = (d[0] * d[0] + d[1] * d[1]).sqrt().max(1e-12);
                        let tip = (c.0 + 24.0 * d[0] / len, c.1 + 24.0 * d[1] / len);
                        pen.circle(c, 4.0, BLACK, true)?;
                        pen.path(&[c, tip], BLACK, 1.5, Dash::Solid)?;
                        continue;
                    }
                    _ => continue,
                };
                pen.path(&rect(it.lo, it.hi), colour, width, dash)?;
                if it.kind != TopKind::Mesh {
                    let at = if it.kind == TopKind::RoomProbe {
                        pen.circle(p(it.at), 4.0, colour, true)?;
                        p(it.at)
                    } else {
                        p(it.lo)
                    };
                    pen.text(
                        &it.label,
                        (at.0 + 5.0, at.1 - 3.0),
                        11.0,
                        colour,
                        HPos::Left,
                        VPos::Bottom,
                    )?;
                }
            }
        }
        Ok(())
    }
}

/// Draws `items` into `{out_base}.png` and `{out_base}.svg`, `width` pixels across the x extent
/// (or the z extent when it is larger). Errors: no items, a non-finite coordinate, a width
/// outside 64..=4096, the files.
pub fn top_view(items: &[TopItem], width: u32, out_base: &Path) -> Result<PlotFiles> {
    if items.is_empty() {
        return Err(PlotError::Input("a top view of nothing".into()));
    }
    if !(64..=4096).contains(&width) {
        return Err(PlotError::Input(format!(
            "top view width {width} is outside 64..=4096"
        )));
    }
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for it in items {
        for v in [it.lo, it.hi, it.at] {
            if !v.iter().all(|c| c.is_finite()) {
                return Err(PlotError::Input(format!(
                    "top view item {:?} has a non-finite coordinate",
                    it.label
                )));
            }
        }
        for v in [it.lo, it.hi] {
            for k in 0..2 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
    }
    let ext = [(hi[0] - lo[0]).max(1e-9), (hi[1] - lo[1]).max(1e-9)];
    let scale = f64::from(width) / ext[0].max(ext[1]);
    let size = (
        (ext[0] * scale + 2.0 * PAD).ceil() as u32,
        (ext[1] * scale + 2.0 * PAD).ceil() as u32,
    );
    write_png_svg(
        &TopFigure {
            items,
            lo,
            scale,
            size,
        },
        out_base,
    )
}
