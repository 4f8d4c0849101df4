//! Rendering a [`AnalyticScene`] into an [`Image`]: one primary ray through each pixel centre, rows in
//! parallel (rayon). Pixels that hit are shaded by a caller-supplied integrator, missed pixels by a
//! background function (usually `env.pyramid.sample(dir, 0.0)`).

use crate::analytic_scene::{AnalyticHit, AnalyticScene};
use glam::DVec3;
use lustre_brdf::Rgb;
use lustre_trace::image::Image;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Renders `scene` at w×h: `shade` for pixels whose primary ray hits a surface, `background`
/// (given the unit ray direction) for the others. Row-parallel; no progress reporting.
/// A zero width or height gives an empty image.
pub fn render(
    scene: &AnalyticScene,
    w: usize,
    h: usize,
    shade: impl Fn(&AnalyticHit) -> Rgb + Sync,
    background: impl Fn(DVec3) -> Rgb + Sync,
) -> Image {
    render_with_progress(scene, w, h, shade, background, &|_| {})
}

/// [`render`] that calls `progress(rows_done)` each time a row is finished (from worker threads;
/// the counts arrive in increasing order per call but calls may interleave). Command-line tools
/// drive a progress bar with it.
pub fn render_with_progress(
    scene: &AnalyticScene,
    w: usize,
    h: usize,
    shade: impl Fn(&AnalyticHit) -> Rgb + Sync,
    background: impl Fn(DVec3) -> Rgb + Sync,
    progress: &(dyn Fn(usize) + Sync),
) -> Image {
    let mut data = vec![[0.0f32; 3]; w * h];
    let done = AtomicUsize::new(0);
    if w > 0 {
        data.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, px) in row.iter_mut().enumerate() {
                let (o, d) = scene.primary(x, y, w, h);
                let c = match scene.intersect(o, d) {
                    Some(hit) => shade(&hit),
                    None => background(d),
                };
                *px = [c[0] as f32, c[1] as f32, c[2] as f32];
            }
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
        });
    }
    Image {
        width: w,
        height: h,
        data,
    }
}
