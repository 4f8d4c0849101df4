//! Planar reflectors (000 §4.5): the light-mapped scene rendered from the camera mirrored in the
//! reflector's plane into a buffer of radiance, positions and normals (§4.5.1, Fig. 4.26), its
//! MIP pyramid, and the projection of a lobe sample into the buffer by intersecting the sample
//! ray with the tangent plane of the mirror-direction hit, then once more with the tangent plane
//! of what the buffer shows there (§4.5.2, Fig. 4.28–4.31). Samples that leave the buffer (or
//! point below the plane) are not answered here: the caller falls back to a probe or the
//! environment.
//!
//! This is the CPU definition of the mirror pass; the GPU pass renders the same buffer.

use crate::probe::{transmits, LitScene};
use crate::{Result, ShadeError};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_scene::mesh::{MeshPlane, GLASS_PLANE_SHARE, PLANARITY_TOLERANCE, PLANAR_AREA_SHARE};
use lustre_trace::bake::gbuffer::{VisibilityBuffer, SKY};
use lustre_trace::path_tracer::PathCamera;
use rayon::prelude::*;

/// The plane of a planar reflector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReflectorPlane {
    /// A point on the plane (the area-weighted centroid of the in-plane triangles).
    pub point: DVec3,
    /// Unit normal, on the side of those triangles' face normals.
    pub normal: DVec3,
}

/// A reflector's plane and which of its triangles lie in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Reflector {
    /// The plane.
    pub plane: ReflectorPlane,
    /// Per triangle of the mesh (in its order): whether it lies in the plane.
    pub in_plane: Vec<bool>,
    /// The share of the mesh's area in the plane.
    pub area_share: f64,
}

impl ReflectorPlane {
    /// The plane of mesh `m` of `lit`'s scene seen from `eye`: the plane of its largest
    /// triangle, refined as the area-weighted mean normal and centroid of the triangles parallel
    /// to it (cos > 0.999), and the triangles within [`PLANARITY_TOLERANCE`] × the mesh's extent
    /// of it ([`lustre_scene::Mesh::dominant_plane`]); for glass, of its largest triangle facing
    /// `eye` ([`lustre_scene::Mesh::plane_facing`]: a slab's near face), so that its normal
    /// points to the eye's side. Errors (naming the mesh): no such mesh, no triangle of non-zero
    /// area, or less than [`PLANAR_AREA_SHARE`] of the area in the plane (for glass, less than
    /// [`GLASS_PLANE_SHARE`] of the area facing the eye): not planar.
    pub fn of_mesh(lit: &LitScene, m: usize, eye: DVec3) -> Result<Reflector> {
        let mesh = lit.scene.meshes.get(m).ok_or_else(|| {
            ShadeError::Parameter(format!(
                "{}: no mesh {m} to reflect in",
                lit.scene.source.display()
            ))
        })?;
        let glass = transmits(lit.scene, mesh.material);
        let MeshPlane {
            point,
            normal,
            in_plane,
            area_share,
            facing_share,
        } = if glass {
            mesh.plane_facing(Some(eye))
        } else {
            mesh.dominant_plane()
        }
        .ok_or_else(|| {
            ShadeError::Parameter(format!(
                "planar reflector {:?} has no triangle of non-zero area",
                mesh.name
            ))
        })?;
        let (share, need, of) = if glass {
            (facing_share, GLASS_PLANE_SHARE, "the area facing the eye")
        } else {
            (area_share, PLANAR_AREA_SHARE, "its area")
        };
        if share.is_nan() || share < need {
            return Err(ShadeError::Parameter(format!(
                "planar reflector {:?} is not planar: only {:.1} % of {of} lies in one plane (within {PLANARITY_TOLERANCE} of its extent)",
                mesh.name,
                100.0 * share
            )));
        }
        Ok(Reflector {
            plane: ReflectorPlane { point, normal },
            in_plane,
            area_share,
        })
    }

    /// `v` mirrored in the plane (a point).
    pub fn reflect_point(&self, v: DVec3) -> DVec3 {
        v - 2.0 * (v - self.point).dot(self.normal) * self.normal
    }

    /// `d` mirrored in the plane (a direction).
    pub fn reflect_dir(&self, d: DVec3) -> DVec3 {
        d - 2.0 * d.dot(self.normal) * self.normal
    }
}

/// The camera mirrored in `plane`: origin and axes reflected, so that pixel (x, y) of the mirror
/// camera looks along the reflection of the real camera's ray through (x, y).
pub fn mirror_camera(camera: &PathCamera, plane: &ReflectorPlane) -> PathCamera {
    PathCamera {
        origin: plane.reflect_point(camera.origin),
        forward: plane.reflect_dir(camera.forward),
        right: plane.reflect_dir(camera.right),
        up: plane.reflect_dir(camera.up),
        tan_half_fov_y: camera.tan_half_fov_y,
    }
}

/// Image position (x, y) in pixels (0..w, 0..h) where `camera` sees the point `p`, the inverse
/// of [`PathCamera::direction`]; `None` behind the camera.
pub fn project(camera: &PathCamera, w: usize, h: usize, p: DVec3) -> Option<(f64, f64)> {
    project_dir(camera, w, h, p - camera.origin)
}

/// Image position of the direction `v` from the camera (a point at infinity along `v`).
pub fn project_dir(camera: &PathCamera, w: usize, h: usize, v: DVec3) -> Option<(f64, f64)> {
    let z = v.dot(camera.forward);
    if z.is_nan() || z <= 1e-12 {
        return None;
    }
    let a = camera.tan_half_fov_y;
    let (wf, hf) = (w as f64, h as f64);
    let px = v.dot(camera.right) / z;
    let py = v.dot(camera.up) / z;
    let x = (px / (a * wf / hf) + 1.0) * 0.5 * wf;
    let y = (1.0 - py / a) * 0.5 * hf;
    (x.is_finite() && y.is_finite()).then_some((x, y))
}

/// Where a sample found its radiance in a mirror buffer: the image position and, unless at
/// infinity, the point and the normal of its tangent plane.
pub type Located = ((f64, f64), Option<(DVec3, DVec3)>);

/// One texel of the mirror buffer: what the mirror camera sees beyond the plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirrorTexel {
    /// Light-mapped radiance towards the mirror camera (or the environment).
    pub radiance: Rgb,
    /// World position of the surface seen; `None` for the environment (a point at infinity).
    pub position: Option<DVec3>,
    /// Unit geometric normal of the surface seen (zero for the environment).
    pub normal: DVec3,
}

/// A view of the light-mapped scene with one object left out, as a buffer of radiance,
/// positions and normals with the radiance's MIP pyramid (2×2 box means, level l of size
/// ⌈w/2^l⌉ × ⌈h/2^l⌉): the mirror camera's view beyond a reflector ([`render_mirror`]), or the
/// camera's own view behind a transmissive object ([`render_see_through`]).
#[derive(Clone, Debug)]
pub struct ViewBuffer {
    /// The mesh left out.
    pub mesh: u32,
    /// The camera the buffer was rendered from.
    pub camera: PathCamera,
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Level-0 texels, row-major.
    pub texels: Vec<MirrorTexel>,
    /// Radiance levels: (width, height, texels), finest first (level 0 = the texels').
    pub levels: Vec<(usize, usize, Vec<Rgb>)>,
    /// For a mirror buffer: the reflector's plane; samples below it are not answered.
    pub front: Option<ReflectorPlane>,
}

impl ViewBuffer {
    /// Replaces the level-0 radiance (row-major, w·h values) and rebuilds the MIP levels.
    /// Values beyond the texels are ignored; missing ones leave their texels as they were.
    pub fn set_radiance(&mut self, level0: &[[f32; 3]]) {
        for (t, c) in self.texels.iter_mut().zip(level0) {
            t.radiance = Rgb(c.map(f64::from));
        }
        let radiance = self.texels.iter().map(|t| t.radiance).collect();
        self.levels = box_levels(self.width, self.height, radiance);
    }
}

/// The mirror buffer of one reflector for one view (000 §4.5.1): the frame's resolution.
#[derive(Clone, Debug)]
pub struct MirrorBuffer {
    /// The reflector's plane and in-plane triangles.
    pub reflector: Reflector,
    /// Its plane.
    pub plane: ReflectorPlane,
    /// What the mirrored camera sees beyond the plane.
    pub view: ViewBuffer,
}

/// Renders the mirror buffer of reflector `mesh` for `camera` at w×h: one ray per texel centre
/// from the mirrored camera, starting where it crosses the plane (the plane itself and what lies
/// behind it left out), shaded with the light-mapped scene (diffuse only, as 000 §4.5.1; the
/// frame then adds its view-dependent part, [`crate::frame::shade_mirror_layer`]).
pub fn render_mirror(
    lit: &LitScene,
    mesh: usize,
    camera: &PathCamera,
    w: usize,
    h: usize,
) -> Result<MirrorBuffer> {
    Ok(render_mirror_with_gbuffer(lit, mesh, camera, w, h)?.0)
}

/// [`render_mirror`] and the G-buffer of the mirrored camera's view (what a layer of its
/// view-dependent part is shaded from).
pub fn render_mirror_with_gbuffer(
    lit: &LitScene,
    mesh: usize,
    camera: &PathCamera,
    w: usize,
    h: usize,
) -> Result<(MirrorBuffer, VisibilityBuffer)> {
    let reflector = ReflectorPlane::of_mesh(lit, mesh, camera.origin)?;
    let plane = reflector.plane;
    let cam = mirror_camera(camera, &plane);
    let (mut view, gb) = render_view(lit, mesh, &cam, w, h, |d| {
        // Start on the plane: what lies between the mirrored eye and the plane is behind the
        // reflector in the real view.
        let denom = d.dot(plane.normal);
        if denom.abs() > 1e-12 {
            ((plane.point - cam.origin).dot(plane.normal) / denom).max(0.0)
        } else {
            0.0
        }
    })?;
    view.front = Some(plane);
    Ok((
        MirrorBuffer {
            reflector,
            plane,
            view,
        },
        gb,
    ))
}

/// Renders what `camera` sees at w×h with mesh `mesh` left out: the light arriving through a
/// transmissive object (a glass rail, a window pane), read by its transmitted samples as the
/// mirror buffer is read by reflected ones.
pub fn render_see_through(
    lit: &LitScene,
    mesh: usize,
    camera: &PathCamera,
    w: usize,
    h: usize,
) -> Result<ViewBuffer> {
    render_see_through_with_gbuffer(lit, mesh, camera, w, h).map(|(v, _)| v)
}

/// [`render_see_through`] and the G-buffer of its rays (the triangle and barycentrics each
/// texel shows; the geometric normal in `normal`), which the see-through layer's
/// view-dependent shading reads ([`crate::frame::shade_see_through_layer`]).
pub fn render_see_through_with_gbuffer(
    lit: &LitScene,
    mesh: usize,
    camera: &PathCamera,
    w: usize,
    h: usize,
) -> Result<(ViewBuffer, VisibilityBuffer)> {
    if mesh >= lit.scene.meshes.len() {
        return Err(ShadeError::Parameter(format!(
            "{}: no mesh {mesh} to see through",
            lit.scene.source.display()
        )));
    }
    render_view(lit, mesh, camera, w, h, |_| 0.0)
}

/// Which tiles of a w×h view a mesh covers, widened by a margin (where a see-through layer is
/// shaded, [`crate::frame::shade_see_through_layer`]): the view in tiles of
/// [`SCREEN_TILE`]² pixels, a tile covered when a triangle of the mesh, projected, comes within
/// [`SCREEN_TILE_MARGIN`] of the larger side of the tile (a conservative 2-D overlap test: the
/// box axes and the triangle's edge normals). Every tile is covered when a vertex lies on or
/// behind the camera's plane, none when the mesh is missing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScreenTiles {
    /// Tiles per row.
    pub cols: usize,
    /// Tile rows.
    pub rows: usize,
    /// Per tile (row-major): covered.
    pub covered: Vec<bool>,
}

/// Side of a [`ScreenTiles`] tile, pixels.
pub const SCREEN_TILE: usize = 8;

/// The widening of [`ScreenTiles`], as a share of the view's larger side: room for the MIP
/// footprints of rough transmission around the object's own pixels.
pub const SCREEN_TILE_MARGIN: f64 = 1.0 / 32.0;

impl ScreenTiles {
    /// Every tile of a w×h view covered.
    pub fn all(w: usize, h: usize) -> Self {
        let (cols, rows) = (w.div_ceil(SCREEN_TILE), h.div_ceil(SCREEN_TILE));
        ScreenTiles {
            cols,
            rows,
            covered: vec![true; cols * rows],
        }
    }

    /// The tiles of a w×h view from `camera` that mesh `mesh` of `lit` covers (type docs).
    pub fn of_mesh(lit: &LitScene, mesh: usize, camera: &PathCamera, w: usize, h: usize) -> Self {
        let mut t = Self::all(w, h);
        t.covered.fill(false);
        let Some(m) = lit.scene.meshes.get(mesh) else {
            return t;
        };
        let (wf, hf) = (w as f64, h as f64);
        let a = camera.tan_half_fov_y;
        let mut px = Vec::with_capacity(m.positions.len());
        for v in &m.positions {
            let rel = v.as_dvec3() - camera.origin;
            let z = rel.dot(camera.forward);
            if z.is_nan() || z <= 1e-9 * rel.length() {
                return Self::all(w, h);
            }
            // The inverse of PathCamera::direction.
            let x = (rel.dot(camera.right) / z / (a * wf / hf) + 1.0) * 0.5 * wf;
            let y = (1.0 - rel.dot(camera.up) / z / a) * 0.5 * hf;
            if !(x.is_finite() && y.is_finite()) {
                return Self::all(w, h);
            }
            px.push([x, y]);
        }
        let margin = wf.max(hf) * SCREEN_TILE_MARGIN;
        let size = SCREEN_TILE as f64;
        for tri in &m.indices {
            let Some(p) = tri
                .iter()
                .map(|&i| px.get(i as usize).copied())
                .collect::<Option<Vec<[f64; 2]>>>()
            else {
                continue;
            };
            let lo = [0, 1].map(|k| p.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min));
            let hi = [0, 1].map(|k| p.iter().map(|q| q[k]).fold(f64::NEG_INFINITY, f64::max));
            let tile = |v: f64, n: usize| ((v / size).floor().max(0.0) as usize).min(n - 1);
            if hi[0] + margin < 0.0
                || hi[1] + margin < 0.0
                || lo[0] - margin > wf
                || lo[1] - margin > hf
            {
                continue;
            }
            let (c0, c1) = (tile(lo[0] - margin, t.cols), tile(hi[0] + margin, t.cols));
            let (r0, r1) = (tile(lo[1] - margin, t.rows), tile(hi[1] + margin, t.rows));
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let bx = [c as f64 * size - margin, (c + 1) as f64 * size + margin];
                    let by = [r as f64 * size - margin, (r + 1) as f64 * size + margin];
                    if !t.covered[r * t.cols + c] && triangle_meets_box(&p, bx, by) {
                        t.covered[r * t.cols + c] = true;
                    }
                }
            }
        }
        t
    }

    /// Whether pixel (x, y) lies in a covered tile.
    pub fn covers(&self, x: usize, y: usize) -> bool {
        let (c, r) = (x / SCREEN_TILE, y / SCREEN_TILE);
        c < self.cols && r < self.rows && self.covered[r * self.cols + c]
    }
}

/// Whether 2-D triangle `p` overlaps the box [bx0, bx1] × [by0, by1] (separating axes: the box's
/// and the triangle's edge normals; the caller has checked the box axes' bounds).
fn triangle_meets_box(p: &[[f64; 2]], bx: [f64; 2], by: [f64; 2]) -> bool {
    let corners = [
        [bx[0], by[0]],
        [bx[1], by[0]],
        [bx[1], by[1]],
        [bx[0], by[1]],
    ];
    let lo = [0, 1].map(|k| p.iter().map(|q| q[k]).fold(f64::INFINITY, f64::min));
    let hi = [0, 1].map(|k| p.iter().map(|q| q[k]).fold(f64::NEG_INFINITY, f64::max));
    if hi[0] < bx[0] || lo[0] > bx[1] || hi[1] < by[0] || lo[1] > by[1] {
        return false;
    }
    for i in 0..3 {
        let (a, b) = (p[i], p[(i + 1) % 3]);
        let n = [b[1] - a[1], a[0] - b[0]];
        let dot = |q: [f64; 2]| n[0] * q[0] + n[1] * q[1];
        let tri: Vec<f64> = p.iter().map(|&q| dot(q)).collect();
        let (tlo, thi) = tri
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let (blo, bhi) = corners
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &c| {
                (l.min(dot(c)), h.max(dot(c)))
            });
        if thi < blo || tlo > bhi {
            return false;
        }
    }
    true
}

/// One ray per texel centre of `cam`, from `start(d)` along it, mesh `mesh` left out; the view
/// buffer and the G-buffer of the rays.
fn render_view(
    lit: &LitScene,
    mesh: usize,
    cam: &PathCamera,
    w: usize,
    h: usize,
    start: impl Fn(DVec3) -> f64 + Sync,
) -> Result<(ViewBuffer, VisibilityBuffer)> {
    if w == 0 || h == 0 {
        return Err(ShadeError::Parameter(format!(
            "view buffer {w}×{h} is empty"
        )));
    }
    let g = &lit.path_scene.geometry;
    let rays: Vec<(MirrorTexel, u32, [f32; 2], f32)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let d = cam.direction(x as f64 + 0.5, y as f64 + 0.5, w, h);
            let o = cam.origin + d * start(d);
            match lit.hit(o, d, Some(mesh as u32)) {
                Some(hh) => {
                    let tri = &g.positions[hh.prim];
                    let ng = (tri[1] - tri[0])
                        .cross(tri[2] - tri[0])
                        .try_normalize()
                        .unwrap_or(DVec3::ZERO);
                    let q = o + d * hh.t;
                    (
                        MirrorTexel {
                            radiance: lit.lit.radiance(g, hh.prim, hh.bary, d),
                            position: Some(q),
                            normal: ng,
                        },
                        hh.prim as u32,
                        [hh.bary[1] as f32, hh.bary[2] as f32],
                        (q - cam.origin).dot(cam.forward) as f32,
                    )
                }
                None => (
                    MirrorTexel {
                        radiance: lit
                            .path_scene
                            .environment
                            .as_ref()
                            .map_or(Rgb::ZERO, |e| e.eval(d)),
                        position: None,
                        normal: DVec3::ZERO,
                    },
                    SKY,
                    [0.0; 2],
                    0.0,
                ),
            }
        })
        .collect();
    let gb = VisibilityBuffer {
        width: w,
        height: h,
        prim: rays.iter().map(|r| r.1).collect(),
        bary: rays.iter().map(|r| r.2).collect(),
        depth: rays.iter().map(|r| r.3).collect(),
        normal: rays
            .iter()
            .map(|r| r.0.normal.as_vec3().to_array())
            .collect(),
    };
    let texels: Vec<MirrorTexel> = rays.into_iter().map(|r| r.0).collect();
    let levels = box_levels(w, h, texels.iter().map(|t| t.radiance).collect());
    Ok((
        ViewBuffer {
            mesh: mesh as u32,
            camera: *cam,
            width: w,
            height: h,
            texels,
            levels,
            front: None,
        },
        gb,
    ))
}

/// The radiance MIP pyramid of a view buffer from its w×h level 0 (row-major): 2×2 box means of
/// the texels that exist (odd sizes keep the last row/column's 2 or 1), level l of size
/// ⌈w/2^l⌉ × ⌈h/2^l⌉, down to 1×1; finest first.
pub fn box_levels(w: usize, h: usize, level0: Vec<Rgb>) -> Vec<(usize, usize, Vec<Rgb>)> {
    let mut levels = vec![(w, h, level0)];
    while let Some((lw, lh, data)) = levels.last() {
        if *lw == 1 && *lh == 1 {
            break;
        }
        let (nw, nh) = (lw.div_ceil(2), lh.div_ceil(2));
        let mut next = vec![Rgb::ZERO; nw * nh];
        for y in 0..nh {
            for x in 0..nw {
                let mut sum = Rgb::ZERO;
                let mut k = 0.0;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = (2 * x + dx, 2 * y + dy);
                    if sx < *lw && sy < *lh {
                        sum += data[sy * lw + sx];
                        k += 1.0;
                    }
                }
                next[y * nw + x] = sum * (1.0 / k);
            }
        }
        levels.push((nw, nh, next));
    }
    levels
}

impl ViewBuffer {
    /// The texel nearest to image position (x, y), `None` outside the buffer.
    pub fn texel_at(&self, x: f64, y: f64) -> Option<&MirrorTexel> {
        if !(x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64) {
            return None;
        }
        self.texels.get(y as usize * self.width + x as usize)
    }

    /// Where the sample ray from `p` (on the reflector) along `wi` finds its radiance in the
    /// buffer (000 §4.5.2): intersected with the tangent plane of the surface the mirror camera
    /// sees at `p`'s own position, projected into the mirror camera, then intersected with the
    /// tangent plane of what the buffer shows there and projected again (the additional
    /// intersection step, Fig. 4.31). A sample towards the environment, or whose plane it does
    /// not meet, is projected as a direction. Returns the image position and the point found
    /// with the normal of its tangent plane (`None` at infinity); `None` when the position
    /// leaves the buffer or `wi` points below the plane.
    pub fn locate(&self, p: DVec3, wi: DVec3) -> Option<Located> {
        if self.front.is_some_and(|f| wi.dot(f.normal) <= 0.0) {
            return None;
        }
        let (w, h) = (self.width, self.height);
        let (x0, y0) = project(&self.camera, w, h, p)?;
        let first = self.texel_at(x0, y0)?;
        let step = |t: &MirrorTexel| -> Option<Located> {
            let hit = t
                .position
                .and_then(|q| ray_plane(p, wi, q, t.normal).map(|pi| (pi, t.normal)));
            match hit {
                Some((pi, n)) => Some((project(&self.camera, w, h, pi)?, Some((pi, n)))),
                None => Some((project_dir(&self.camera, w, h, wi)?, None)),
            }
        };
        let ((x1, y1), _) = step(first)?;
        let second = self.texel_at(x1, y1)?;
        let ((x2, y2), pi) = step(second)?;
        self.texel_at(x2, y2)?;
        Some(((x2, y2), pi))
    }

    /// Trilinear lookup of the radiance at image position (x, y) (level-0 pixels) and MIP level
    /// `lod` (clamped to the pyramid).
    pub fn sample(&self, x: f64, y: f64, lod: f64) -> Rgb {
        let top = (self.levels.len() - 1) as f64;
        let lod = if lod.is_nan() {
            0.0
        } else {
            lod.clamp(0.0, top)
        };
        let l0 = lod.floor() as usize;
        let l1 = (l0 + 1).min(self.levels.len() - 1);
        let f = lod - l0 as f64;
        let a = self.bilinear(l0, x, y);
        if f == 0.0 {
            a
        } else {
            a * (1.0 - f) + self.bilinear(l1, x, y) * f
        }
    }

    fn bilinear(&self, level: usize, x: f64, y: f64) -> Rgb {
        let (lw, lh, data) = &self.levels[level];
        let s = (1u64 << level) as f64;
        let fx = (x / s - 0.5).clamp(0.0, (*lw - 1) as f64);
        let fy = (y / s - 0.5).clamp(0.0, (*lh - 1) as f64);
        let (x0, y0) = (fx.floor() as usize, fy.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(lw - 1), (y0 + 1).min(lh - 1));
        let (tx, ty) = (fx - x0 as f64, fy - y0 as f64);
        let at = |x: usize, y: usize| data[y * lw + x];
        (at(x0, y0) * (1.0 - tx) + at(x1, y0) * tx) * (1.0 - ty)
            + (at(x0, y1) * (1.0 - tx) + at(x1, y1) * tx) * ty
    }

    /// The MIP level of a sample of solid angle `omega` (sr) from `p` along `wi` that the buffer
    /// answers at `found` (a point and its tangent plane's normal, from [`MirrorBuffer::locate`];
    /// 000 §4.5.3 per sample): the cone of that solid angle around `wi` cut with the tangent
    /// plane, the patch projected into the buffer (finite differences of two edge rays), ½ log2
    /// of its area in texels, plus `bias`, clamped to the pyramid. At infinity the cone's
    /// directions are projected.
    pub fn level(
        &self,
        p: DVec3,
        wi: DVec3,
        found: Option<(DVec3, DVec3)>,
        omega: f64,
        bias: f64,
    ) -> f64 {
        let (w, h) = (self.width, self.height);
        let (t, b) = wi.any_orthonormal_pair();
        let e = omega.max(0.0).sqrt();
        let (wu, wv) = (wi + t * e, wi + b * e);
        let pts = match found {
            Some((q, n)) => (
                project(&self.camera, w, h, q),
                ray_plane(p, wu, q, n).and_then(|x| project(&self.camera, w, h, x)),
                ray_plane(p, wv, q, n).and_then(|x| project(&self.camera, w, h, x)),
            ),
            None => (
                project_dir(&self.camera, w, h, wi),
                project_dir(&self.camera, w, h, wu),
                project_dir(&self.camera, w, h, wv),
            ),
        };
        let top = (self.levels.len() - 1) as f64;
        let (Some(c), Some(u), Some(v)) = pts else {
            return top;
        };
        let area = ((u.0 - c.0) * (v.1 - c.1) - (u.1 - c.1) * (v.0 - c.0)).abs();
        if !(area > 0.0 && area.is_finite()) {
            return 0.0;
        }
        (0.5 * area.log2() + bias).clamp(0.0, top)
    }
}

/// Where the ray p + s·d (s > 0) meets the plane through `q` with normal `n`.
fn ray_plane(p: DVec3, d: DVec3, q: DVec3, n: DVec3) -> Option<DVec3> {
    let denom = d.dot(n);
    if denom.is_nan() || denom.abs() < 1e-12 {
        return None;
    }
    let s = (q - p).dot(n) / denom;
    (s > 0.0 && s.is_finite()).then(|| p + d * s)
}
