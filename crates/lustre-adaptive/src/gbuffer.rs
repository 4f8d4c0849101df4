//! The geometry pass of 004 §IV.4 (Fig. IV.11 a): one camera ray through each pixel centre of a
//! `width × height` film, and per pixel the visible point's position, shading frame, distance to
//! the eye, material and texture coordinates, or the environment seen directly.
//!
//! The curvature c of Fig. IV.9 is estimated in screen space, as 004 does on the fly: the
//! largest |Δn| / |Δx| between the pixel and its four neighbours that lie on the same material
//! and at a depth within [`SAME_SURFACE`] of its own (a sphere of radius r reads 1/r).

use crate::{AdaptiveError, Result};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_trace::path_tracer::{PathCamera, PathScene, PathTracer};
use lustre_trace::sampling::ShadingFrame;
use rayon::prelude::*;

/// Neighbours whose depth differs by more than this fraction of the pixel's own are taken to
/// lie on another surface (for the curvature and for the bilateral up-sampling's parents).
pub const SAME_SURFACE: f64 = 0.05;

/// A visible surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surfel {
    /// World position.
    pub position: DVec3,
    /// Shading frame; its normal faces the eye on two-sided materials.
    pub frame: ShadingFrame,
    /// Unit direction to the eye.
    pub wo: DVec3,
    /// Distance to the eye (the depth of Fig. IV.12's g_z).
    pub depth: f64,
    /// Material index of the path scene.
    pub material: usize,
    /// Texture coordinates.
    pub uv: [f64; 2],
    /// Screen-space curvature (1/m).
    pub curvature: f64,
    /// Texture coordinates per metre along the surface, (u, v): per screen axis the smaller of
    /// the two one-sided differences to neighbours on the same surface (a UV seam on one side
    /// is skipped), the larger of the two axes. Scaled by a texture's size it gives the texels
    /// per metre that turn the texture's bandwidth into cycles per metre.
    pub uv_rate: [f64; 2],
}

/// What a pixel sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GPixel {
    /// A surface point.
    Surface(Surfel),
    /// The environment, seen directly (its radiance).
    Background(Rgb),
}

/// The G-buffer of one frame.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major pixels.
    pub pixels: Vec<GPixel>,
    /// The camera the buffer was rendered with.
    pub camera: PathCamera,
}

impl GBuffer {
    /// Renders the G-buffer of `tracer`'s scene through `camera`. Errors on a zero or absurd
    /// film size (above 16384 per side).
    pub fn render(
        tracer: &PathTracer,
        scene: &PathScene,
        camera: &PathCamera,
        width: usize,
        height: usize,
    ) -> Result<Self> {
        if width == 0 || height == 0 || width > 16384 || height > 16384 {
            return Err(AdaptiveError::Parameter(format!(
                "G-buffer of {width} × {height} pixels (each side must be 1..=16384)"
            )));
        }
        let mut pixels: Vec<GPixel> = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (x, y) = (k % width, k / width);
                let d = camera.direction(x as f64 + 0.5, y as f64 + 0.5, width, height);
                let o = camera.origin;
                match tracer.intersect(o, d) {
                    Some(h) => {
                        let (p, mut frame, uv) = tracer.shading_point(o, d, &h);
                        let material = scene.geometry.material[h.prim] as usize;
                        let wo = -d;
                        if frame.n.dot(wo) < 0.0 && scene.materials[material].two_sided() {
                            frame = ShadingFrame {
                                t: frame.t,
                                b: -frame.b,
                                n: -frame.n,
                            };
                        }
                        GPixel::Surface(Surfel {
                            position: p,
                            frame,
                            wo,
                            depth: (p - o).length(),
                            material,
                            uv,
                            curvature: 0.0,
                            uv_rate: [0.0; 2],
                        })
                    }
                    None => GPixel::Background(
                        scene
                            .environment
                            .as_ref()
                            .map_or(Rgb::ZERO, |env| env.eval(d)),
                    ),
                }
            })
            .collect();
        let curvature: Vec<f64> = (0..width * height)
            .into_par_iter()
            .map(|k| screen_curvature(&pixels, width, height, k))
            .collect();
        let uv_rate: Vec<[f64; 2]> = (0..width * height)
            .into_par_iter()
            .map(|k| screen_uv_rate(&pixels, width, height, k))
            .collect();
        for ((p, c), r) in pixels.iter_mut().zip(curvature).zip(uv_rate) {
            if let GPixel::Surface(s) = p {
                s.curvature = c;
                s.uv_rate = r;
            }
        }
        Ok(GBuffer {
            width,
            height,
            pixels,
            camera: *camera,
        })
    }

    /// The surface point at pixel (x, y), if any.
    pub fn surfel(&self, x: usize, y: usize) -> Option<&Surfel> {
        match &self.pixels[y * self.width + x] {
            GPixel::Surface(s) => Some(s),
            GPixel::Background(_) => None,
        }
    }

    /// Radians per pixel, max(f_x / W, f_y / H) of Eq. IV.7.
    pub fn radians_per_pixel(&self) -> f64 {
        let a = self.camera.tan_half_fov_y;
        let (w, h) = (self.width as f64, self.height as f64);
        let fy = 2.0 * a.atan();
        let fx = 2.0 * (a * w / h).atan();
        (fx / w).max(fy / h)
    }

    /// Surface pixels.
    pub fn surface_pixels(&self) -> usize {
        self.pixels
            .iter()
            .filter(|p| matches!(p, GPixel::Surface(_)))
            .count()
    }
}

/// Whether `q` lies on the same surface as `p` (same material, depth within [`SAME_SURFACE`]).
pub fn same_surface(p: &Surfel, q: &Surfel) -> bool {
    p.material == q.material && (p.depth - q.depth).abs() <= SAME_SURFACE * p.depth
}

/// [`Surfel::uv_rate`] at pixel `k` (0 for the background and isolated pixels).
fn screen_uv_rate(pixels: &[GPixel], w: usize, h: usize, k: usize) -> [f64; 2] {
    let GPixel::Surface(p) = &pixels[k] else {
        return [0.0; 2];
    };
    let (x, y) = (k % w, k / w);
    // |Δu| / |Δx| and |Δv| / |Δx| to neighbour `q` on the same surface.
    let rate = |q: Option<usize>| -> Option<[f64; 2]> {
        let GPixel::Surface(q) = &pixels[q?] else {
            return None;
        };
        let dx = (q.position - p.position).length();
        if !(same_surface(p, q) && dx > 0.0) {
            return None;
        }
        let r = [
            (q.uv[0] - p.uv[0]).abs() / dx,
            (q.uv[1] - p.uv[1]).abs() / dx,
        ];
        r.iter().all(|v| v.is_finite()).then_some(r)
    };
    let axes = [
        ((x > 0).then(|| k - 1), (x + 1 < w).then_some(k + 1)),
        ((y > 0).then(|| k - w), (y + 1 < h).then_some(k + w)),
    ];
    let mut out = [0.0f64; 2];
    for (a, b) in axes {
        let side = match (rate(a), rate(b)) {
            (Some(a), Some(b)) => [a[0].min(b[0]), a[1].min(b[1])],
            (Some(r), None) | (None, Some(r)) => r,
            (None, None) => continue,
        };
        out = [out[0].max(side[0]), out[1].max(side[1])];
    }
    out
}

/// The screen-space curvature at pixel `k` (0 for the background and isolated pixels).
fn screen_curvature(pixels: &[GPixel], w: usize, h: usize, k: usize) -> f64 {
    let GPixel::Surface(p) = &pixels[k] else {
        return 0.0;
    };
    let (x, y) = (k % w, k / w);
    let mut c: f64 = 0.0;
    let neighbours = [
        (x > 0).then(|| k - 1),
        (x + 1 < w).then_some(k + 1),
        (y > 0).then(|| k - w),
        (y + 1 < h).then_some(k + w),
    ];
    for q in neighbours.into_iter().flatten() {
        if let GPixel::Surface(q) = &pixels[q] {
            let dx = (q.position - p.position).length();
            if same_surface(p, q) && dx > 0.0 {
                let v = (q.frame.n - p.frame.n).length() / dx;
                if v.is_finite() {
                    c = c.max(v);
                }
            }
        }
    }
    c
}
