//! Light-mapped diffuse shading on the CPU (000 §4.3, Eq. 4.1): the image the real-time
//! renderer draws from the baked maps, without its glossy part. Per pixel, jittered camera rays
//! (the path tracer's box filter and sample seeds); at the first hit, the emitted radiance (front
//! side) plus kd·E/π, with kd the material's [`super::diffuse_albedo`] at the hit and E read
//! bilinearly from the hit's light-map page at its uv1 (texel centres at ((x+½)/W, (y+½)/H),
//! clamped at the page border); meshes without a light map are black; rays that miss see the
//! environment. Comparing this image with the path tracer's image of the diffuse scene
//! ([`super::diffuse_path_scene`]) measures the whole bake.

use super::raster::Raster;
use super::{diffuse_albedo, diffuse_path_scene, BaseAlbedo};
use crate::image::Image;
use crate::path_tracer::{Geometry, PathCamera, PathOptions, PathTracer};
use crate::{Result, TraceError};
use glam::{DVec3, Vec2};
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::SplitMix64;
use lustre_scene::lightmap::{LightmapAtlas, SceneLightmap};
use lustre_scene::Scene;
use rayon::prelude::*;
use std::f64::consts::PI;

/// Bilinear lookup of `page` (W×H texels) at texel-unit coordinates (u·W, v·H).
pub fn bilinear(page: &[[f32; 3]], w: u32, h: u32, x: f64, y: f64) -> Rgb {
    let fx = (x - 0.5).clamp(0.0, f64::from(w - 1));
    let fy = (y - 0.5).clamp(0.0, f64::from(h - 1));
    let (x0, y0) = (fx.floor() as u32, fy.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (tx, ty) = (fx - f64::from(x0), fy - f64::from(y0));
    let at = |x: u32, y: u32| Rgb(page[(y * w + x) as usize].map(f64::from));
    (at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx) * (1.0 - ty)
        + (at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx) * ty
}

/// The light-mapped diffuse radiance of a scene's surfaces (000 Eq. 4.1): what a camera ray,
/// a probe capture or a mirror pass sees where it hits the scene. Built once per set of pages and
/// shared by every ray; plain data, no tracer (the caller intersects with its own).
pub struct Lightmapped<'a> {
    scene: &'a Scene,
    atlas: &'a LightmapAtlas,
    pages: &'a [Vec<[f32; 3]>],
    raster: Raster,
    mapped: Vec<u32>,
    bases: Vec<BaseAlbedo>,
}

impl<'a> Lightmapped<'a> {
    /// Checks that `pages` fit `atlas` and maps every triangle of `geometry` (the triangles of
    /// [`super::diffuse_path_scene`], in its order) to its light-map triangle. `bases` are the
    /// per-material [`BaseAlbedo`]s that [`super::diffuse_path_scene`] returns.
    pub fn new(
        scene: &'a Scene,
        atlas: &'a LightmapAtlas,
        pages: &'a [Vec<[f32; 3]>],
        geometry: &Geometry,
        bases: Vec<BaseAlbedo>,
    ) -> Result<Self> {
        let n = (atlas.width * atlas.height) as usize;
        if pages.len() != atlas.pages as usize || pages.iter().any(|p| p.len() != n) {
            return Err(TraceError::Parameter(format!(
                "{} light-map pages do not fit an atlas of {} pages of {}×{}",
                pages.len(),
                atlas.pages,
                atlas.width,
                atlas.height
            )));
        }
        let raster = Raster::new(scene, atlas, atlas.width.max(atlas.height))?;
        let mut mapped = vec![u32::MAX; geometry.positions.len()];
        for (k, t) in raster.triangles.iter().enumerate() {
            if let Some(m) = mapped.get_mut(t.prim as usize) {
                *m = k as u32;
            }
        }
        Ok(Lightmapped {
            scene,
            atlas,
            pages,
            raster,
            mapped,
            bases,
        })
    }

    /// The light-map page of triangle `prim` and its corners' uv1 in texel units (u·W, v·H),
    /// `None` for triangles without a light map (the data a GPU twin of [`Self::radiance`]
    /// uploads).
    pub fn lightmap_triangle(&self, prim: usize) -> Option<(u32, [[f64; 2]; 3])> {
        let k = *self.mapped.get(prim)?;
        let t = self.raster.triangles.get(k as usize)?;
        Some((t.page, t.uv))
    }

    /// Radiance leaving triangle `prim` of `g` at barycentrics `bary` towards −`d` (`d` the
    /// incoming ray's direction): its emission (front side) plus kd·E/π, E read bilinearly from
    /// its page at uv1 (texel centres at ((x+½)/W, (y+½)/H), clamped at the page border). Black
    /// for back faces of one-sided materials and for triangles without a light map.
    pub fn radiance(&self, g: &Geometry, prim: usize, bary: [f64; 3], d: DVec3) -> Rgb {
        let (l, kd, e) = self.parts(g, prim, bary, d);
        l + kd * e * (1.0 / PI)
    }

    /// The atlas the pages fill.
    pub fn atlas(&self) -> &LightmapAtlas {
        self.atlas
    }

    /// The per-material [`BaseAlbedo`]s (as given to [`Lightmapped::new`]).
    pub fn bases(&self) -> &[BaseAlbedo] {
        &self.bases
    }

    /// The diffuse albedo kd that [`Lightmapped::radiance`] applies at this hit (zero where it
    /// adds no light-mapped term): the part of the material a glossy pass must leave out.
    pub fn albedo(&self, g: &Geometry, prim: usize, bary: [f64; 3], d: DVec3) -> Rgb {
        self.parts(g, prim, bary, d).1
    }

    /// (emission, kd, E) at a hit.
    fn parts(&self, g: &Geometry, prim: usize, bary: [f64; 3], d: DVec3) -> (Rgb, Rgb, Rgb) {
        let b = bary;
        let tri = &g.positions[prim];
        let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let ns = g
            .normals
            .get(prim)
            .map_or(ng, |nn| nn[0] * b[0] + nn[1] * b[1] + nn[2] * b[2]);
        let front = ns.dot(-d) > 0.0;
        let l = match g.emission.get(prim) {
            Some(e) if front => *e,
            _ => Rgb::ZERO,
        };
        let k = self.mapped.get(prim).copied().unwrap_or(u32::MAX);
        if k == u32::MAX {
            return (l, Rgb::ZERO, Rgb::ZERO);
        }
        let (atlas, t) = (self.atlas, &self.raster.triangles[k as usize]);
        let m = g.material[prim] as usize;
        let material = &self.scene.materials[m];
        if !(front || material.two_sided) {
            return (l, Rgb::ZERO, Rgb::ZERO);
        }
        let uv1 = [0, 1].map(|c| b[0] * t.uv[0][c] + b[1] * t.uv[1][c] + b[2] * t.uv[2][c]);
        let e = bilinear(
            &self.pages[t.page as usize],
            atlas.width,
            atlas.height,
            uv1[0],
            uv1[1],
        );
        let uv0 = g.uvs.get(prim).map_or([0.0; 2], |u| {
            [0, 1].map(|c| b[0] * u[0][c] + b[1] * u[1][c] + b[2] * u[2][c])
        });
        let kd = diffuse_albedo(
            material,
            &self.scene.textures,
            &[
                Vec2::new(uv0[0] as f32, uv0[1] as f32),
                Vec2::new(
                    (uv1[0] / f64::from(atlas.width)) as f32,
                    (uv1[1] / f64::from(atlas.height)) as f32,
                ),
            ],
            self.bases[m],
        );
        (l, kd, e)
    }
}

/// Camera ray `k` of pixel (x, y) of a w×h image: jittered uniformly in the pixel by a stream
/// seeded from `seed`, the pixel index and `k` — the sample positions every light-mapped frame
/// shares. Returns the direction and the stream, for the pixel's further random numbers.
pub fn camera_ray(
    camera: &PathCamera,
    seed: u64,
    (x, y): (usize, usize),
    (w, h): (usize, usize),
    k: u32,
) -> (DVec3, SplitMix64) {
    let i = (y * w + x) as u64;
    let mut rng = SplitMix64::new(
        seed ^ i.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ u64::from(k).wrapping_mul(0xC2B2_AE3D_27D4_EB4F),
    );
    let (jx, jy) = (rng.next_f64(), rng.next_f64());
    (camera.direction(x as f64 + jx, y as f64 + jy, w, h), rng)
}

/// Renders `scene` at `camera` (w×h, `spp` jittered samples per pixel, seeded by `seed`)
/// shaded from the light maps `pages` of `atlas` (as [`super::assemble`] returns them).
#[allow(clippy::too_many_arguments)]
pub fn render_lightmapped(
    scene: &Scene,
    atlas: &LightmapAtlas,
    pages: &[Vec<[f32; 3]>],
    camera: &PathCamera,
    w: usize,
    h: usize,
    spp: u32,
    seed: u64,
) -> Result<Image> {
    if w == 0 || h == 0 || spp == 0 {
        return Err(TraceError::Parameter(format!(
            "image {w}×{h} at {spp} spp is empty"
        )));
    }
    let (ps, bases, _) = diffuse_path_scene(scene)?;
    let lit = Lightmapped::new(scene, atlas, pages, &ps.geometry, bases)?;
    let pt = PathTracer::new(&ps, PathOptions::default())?;
    let shade = |o: DVec3, d: DVec3| -> Rgb {
        match pt.intersect(o, d) {
            Some(hit) => lit.radiance(&ps.geometry, hit.prim, hit.bary, d),
            None => ps.environment.as_ref().map_or(Rgb::ZERO, |e| e.eval(d)),
        }
    };
    let data: Vec<[f32; 3]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = Rgb::ZERO;
            for k in 0..spp {
                let (d, _) = camera_ray(camera, seed, (x, y), (w, h), k);
                let c = shade(camera.origin, d);
                if c.is_finite() {
                    sum += c;
                }
            }
            (sum / f64::from(spp)).0.map(|c| c as f32)
        })
        .collect();
    Image::from_data(w, h, data)
}

/// Reads the baked pages a scene file's `[lightmap]` names (OpenEXR, as `lustre bake` writes
/// them). Errors name the file: unreadable, or not the atlas's page size; no pages at all (the
/// atlas has not been baked).
pub fn read_pages(lightmap: &SceneLightmap) -> Result<Vec<Vec<[f32; 3]>>> {
    let atlas = &lightmap.atlas;
    if !lightmap.embedded.is_empty() {
        let texels = atlas.width as usize * atlas.height as usize;
        if lightmap.embedded.len() != atlas.pages as usize
            || lightmap.embedded.iter().any(|p| p.len() != texels)
        {
            return Err(TraceError::Parameter(format!(
                "{}: {} embedded light-map pages for an atlas of {} pages of {}×{} texels",
                lightmap.atlas_file.display(),
                lightmap.embedded.len(),
                atlas.pages,
                atlas.width,
                atlas.height
            )));
        }
        return Ok(lightmap.embedded.clone());
    }
    if lightmap.pages.is_empty() {
        return Err(TraceError::Parameter(format!(
            "the light-map atlas {} has no baked pages (run `lustre bake`)",
            lightmap.atlas_file.display()
        )));
    }
    if lightmap.pages.len() != atlas.pages as usize {
        return Err(TraceError::Parameter(format!(
            "{} light-map page files for an atlas of {} pages ({})",
            lightmap.pages.len(),
            atlas.pages,
            lightmap.atlas_file.display()
        )));
    }
    lightmap
        .pages
        .iter()
        .map(|p| {
            let img = Image::read_exr(p)?;
            if img.width != atlas.width as usize || img.height != atlas.height as usize {
                return Err(TraceError::Parameter(format!(
                    "{}: light-map page is {}×{}, the atlas's pages are {}×{}",
                    p.display(),
                    img.width,
                    img.height,
                    atlas.width,
                    atlas.height
                )));
            }
            if img.data.iter().flatten().any(|c| !c.is_finite()) {
                return Err(TraceError::Parameter(format!(
                    "{}: light-map page has NaN or infinite texels",
                    p.display()
                )));
            }
            Ok(img.data)
        })
        .collect()
}
