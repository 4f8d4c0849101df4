//! The G-buffer of a light-mapped frame and its shading on the CPU: the twins of lustre-gpu's
//! raster G-buffer pass and light-map shading pass.
//!
//! A G-buffer of (k·w)×(k·h) pixels holds, per pixel, what the camera ray through the pixel
//! centre sees: the triangle (index in [`super::diffuse_path_scene`]'s geometry, [`SKY`] for
//! none), its barycentric weights, the view depth and the shading normal. Shading a G-buffer
//! gives the w×h image: each pixel the box average of its k×k G-buffer pixels, each shaded by
//! [`Lightmapped::radiance`] (or the environment for [`SKY`]) along the ray through the
//! G-buffer pixel's centre, `camera.direction(X + ½, Y + ½, k·w, k·h)` — that is the sub-pixel
//! position ((i + ½)/k, (j + ½)/k) of the output pixel. k = 1 samples pixel centres.

use super::diffuse_path_scene;
use super::render::Lightmapped;
use crate::image::Image;
use crate::path_tracer::{EnvLight, Geometry, PathCamera, PathOptions, PathTracer};
use crate::{Result, TraceError};
use lustre_brdf::rgb::Rgb;
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::Scene;
use rayon::prelude::*;

/// The primitive id of a pixel where the camera sees no surface.
pub const SKY: u32 = u32::MAX;

/// Largest supersampling factor k (k×k G-buffer pixels per output pixel).
pub const MAX_SUPERSAMPLING: u32 = 8;

/// Per-pixel visibility of a frame (a visibility buffer: triangle, barycentrics, depth; the
/// walkthrough's G-buffer, from which every attribute is interpolated). lustre-adaptive's
/// `GBuffer` is the other kind: shaded surface points.
#[derive(Clone, Debug, PartialEq)]
pub struct VisibilityBuffer {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Triangle index per pixel (row-major), [`SKY`] where nothing is hit.
    pub prim: Vec<u32>,
    /// Barycentric weights (b1, b2) of corners 1 and 2 (b0 = 1 − b1 − b2); zero for sky.
    pub bary: Vec<[f32; 2]>,
    /// Depth along the camera's forward axis; zero for sky.
    pub depth: Vec<f32>,
    /// Unit shading normal (interpolated corner normals, else the geometric normal); zero for
    /// sky.
    pub normal: Vec<[f32; 3]>,
}

impl VisibilityBuffer {
    /// The fraction of pixels whose primitive ids agree with `other`'s. Errors on a size
    /// mismatch.
    pub fn agreement(&self, other: &VisibilityBuffer) -> Result<f64> {
        if (self.width, self.height) != (other.width, other.height) {
            return Err(TraceError::Parameter(format!(
                "G-buffers of {}×{} and {}×{} cannot be compared",
                self.width, self.height, other.width, other.height
            )));
        }
        let same = self
            .prim
            .iter()
            .zip(&other.prim)
            .filter(|(a, b)| a == b)
            .count();
        Ok(same as f64 / self.prim.len().max(1) as f64)
    }

    /// Checks the buffer lengths against the size.
    fn check(&self) -> Result<()> {
        let n = self.width * self.height;
        if n == 0
            || self.prim.len() != n
            || self.bary.len() != n
            || self.depth.len() != n
            || self.normal.len() != n
        {
            return Err(TraceError::Parameter(format!(
                "G-buffer of {}×{} pixels has {} ids, {} barycentrics, {} depths, {} normals",
                self.width,
                self.height,
                self.prim.len(),
                self.bary.len(),
                self.depth.len(),
                self.normal.len()
            )));
        }
        Ok(())
    }
}

/// Checks an output size and supersampling factor; returns the G-buffer size (k·w, k·h).
pub fn gbuffer_size(w: usize, h: usize, k: u32) -> Result<(usize, usize)> {
    if w == 0 || h == 0 {
        return Err(TraceError::Parameter(format!("image {w}×{h} is empty")));
    }
    if k == 0 || k > MAX_SUPERSAMPLING {
        return Err(TraceError::Parameter(format!(
            "supersampling {k}×{k} must be between 1 and {MAX_SUPERSAMPLING}"
        )));
    }
    let k = k as usize;
    match (w.checked_mul(k), h.checked_mul(k)) {
        (Some(a), Some(b)) if a <= 1 << 15 && b <= 1 << 15 => Ok((a, b)),
        _ => Err(TraceError::Parameter(format!(
            "image {w}×{h} at {k}×{k} supersampling exceeds 32768 pixels a side"
        ))),
    }
}

/// The G-buffer by ray casting ([`PathTracer::intersect`]) at the centres of a `gw`×`gh`
/// grid: the CPU twin of the raster pass.
pub fn trace_gbuffer(
    pt: &PathTracer,
    g: &Geometry,
    camera: &PathCamera,
    gw: usize,
    gh: usize,
) -> Result<VisibilityBuffer> {
    if gw == 0 || gh == 0 {
        return Err(TraceError::Parameter(format!(
            "G-buffer {gw}×{gh} is empty"
        )));
    }
    let px: Vec<(u32, [f32; 2], f32, [f32; 3])> = (0..gw * gh)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % gw, i / gw);
            let d = camera.direction(x as f64 + 0.5, y as f64 + 0.5, gw, gh);
            match pt.intersect(camera.origin, d) {
                Some(hit) => {
                    let b = hit.bary;
                    let tri = &g.positions[hit.prim];
                    let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                    let ns = g
                        .normals
                        .get(hit.prim)
                        .map_or(ng, |n| n[0] * b[0] + n[1] * b[1] + n[2] * b[2])
                        .normalize_or_zero();
                    (
                        hit.prim as u32,
                        [b[1] as f32, b[2] as f32],
                        (hit.t * d.dot(camera.forward)) as f32,
                        ns.as_vec3().to_array(),
                    )
                }
                None => (SKY, [0.0; 2], 0.0, [0.0; 3]),
            }
        })
        .collect();
    Ok(VisibilityBuffer {
        width: gw,
        height: gh,
        prim: px.iter().map(|p| p.0).collect(),
        bary: px.iter().map(|p| p.1).collect(),
        depth: px.iter().map(|p| p.2).collect(),
        normal: px.iter().map(|p| p.3).collect(),
    })
}

/// Shades the (k·w)×(k·h) G-buffer `gb` of triangles of `g` seen from `camera` into the w×h
/// image (module docs): the CPU twin of the GPU light-map shading pass. Errors: a G-buffer
/// whose size is not a multiple of `k`, mis-sized buffers, a primitive id beyond `g`.
pub fn shade_gbuffer(
    lit: &Lightmapped,
    g: &Geometry,
    environment: Option<&EnvLight>,
    camera: &PathCamera,
    gb: &VisibilityBuffer,
    k: u32,
) -> Result<Image> {
    gb.check()?;
    let ku = k as usize;
    if k == 0
        || k > MAX_SUPERSAMPLING
        || !gb.width.is_multiple_of(ku)
        || !gb.height.is_multiple_of(ku)
    {
        return Err(TraceError::Parameter(format!(
            "G-buffer {}×{} is not {k}×{k} supersampled (k between 1 and {MAX_SUPERSAMPLING})",
            gb.width, gb.height
        )));
    }
    if let Some(p) = gb
        .prim
        .iter()
        .find(|&&p| p != SKY && p as usize >= g.positions.len())
    {
        return Err(TraceError::Parameter(format!(
            "G-buffer names triangle {p}, the scene has {}",
            g.positions.len()
        )));
    }
    let (w, h) = (gb.width / ku, gb.height / ku);
    let data: Vec<[f32; 3]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = Rgb::ZERO;
            for j in 0..ku {
                for s in 0..ku {
                    let (gx, gy) = (x * ku + s, y * ku + j);
                    let gi = gy * gb.width + gx;
                    let d = camera.direction(gx as f64 + 0.5, gy as f64 + 0.5, gb.width, gb.height);
                    let c = match gb.prim[gi] {
                        SKY => environment.map_or(Rgb::ZERO, |e| e.eval(d)),
                        p => {
                            let [b1, b2] = gb.bary[gi].map(f64::from);
                            lit.radiance(g, p as usize, [1.0 - b1 - b2, b1, b2], d)
                        }
                    };
                    if c.is_finite() {
                        sum += c;
                    }
                }
            }
            (sum / (ku * ku) as f64).0.map(|c| c as f32)
        })
        .collect();
    Image::from_data(w, h, data)
}

/// The whole light-mapped frame on the CPU at the G-buffer's sample positions: ray-cast
/// G-buffer ([`trace_gbuffer`]) then [`shade_gbuffer`]; `render_lightmapped` with the pixel's
/// k×k sub-pixel centres instead of jittered samples.
#[allow(clippy::too_many_arguments)]
pub fn render_lightmapped_gbuffer(
    scene: &Scene,
    atlas: &LightmapAtlas,
    pages: &[Vec<[f32; 3]>],
    camera: &PathCamera,
    w: usize,
    h: usize,
    k: u32,
) -> Result<(Image, VisibilityBuffer)> {
    let (gw, gh) = gbuffer_size(w, h, k)?;
    let (ps, bases, _) = diffuse_path_scene(scene)?;
    let lit = Lightmapped::new(scene, atlas, pages, &ps.geometry, bases)?;
    let pt = PathTracer::new(&ps, PathOptions::default())?;
    let gb = trace_gbuffer(&pt, &ps.geometry, camera, gw, gh)?;
    let img = shade_gbuffer(&lit, &ps.geometry, ps.environment.as_ref(), camera, &gb, k)?;
    Ok((img, gb))
}
