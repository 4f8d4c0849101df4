//! Triangle meshes in world space, and the analytic shapes (rectangle, disk, cube, sphere) that
//! the scene formats define, tessellated.
//!
//! Every mesh goes through [`Mesh::validated`]: non-finite positions, normals, tangents or UVs and
//! out-of-range indices are errors naming the mesh and the element; attribute arrays must have one
//! entry per vertex; degenerate triangles (a repeated index or zero area) are dropped and counted.
//! Texture coordinates follow glTF: v = 0 is the top row of an image (OBJ's v is flipped on read).

use crate::error::{Result, SceneError};
use glam::{DMat4, DVec3, Vec2, Vec3, Vec4};
use lustre_brdf::Rgb;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::path::Path;

/// Segments of a tessellated disk (a triangle fan of this many triangles).
pub const DISK_SEGMENTS: u32 = 64;
/// Longitudinal segments of a tessellated sphere.
pub const SPHERE_SEGMENTS: u32 = 64;
/// Latitudinal rings of a tessellated sphere.
pub const SPHERE_RINGS: u32 = 32;

/// Hints for the real-time renderer (probes, reflections, light maps); the path tracer ignores
/// them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectHints {
    /// Place a reflection probe at this object.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub probe: bool,
    /// Where the probe is captured (world space), as artists place reflection probes: at a
    /// point from which the object's surroundings are seen as its glossy surfaces see them
    /// (above a flight of stairs rather than in the space under it). `None`: the centre of the
    /// object's bounds (000 §4.4).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probe_centre: Option<[f64; 3]>,
    /// The object is a plane that should get a planar reflection.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub planar_reflector: bool,
    /// Shade the object as diffuse only (no glossy lobe in real time).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub diffuse_only: bool,
    /// Light-map density in texels per metre (world unit); `None`: the renderer's default.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lightmap_texels_per_metre: Option<f32>,
    /// The object's own glossy sample budget per pixel in the walkthrough frame (1 … 256);
    /// `None`: the frame's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub samples: Option<u32>,
    /// A solid glass slab's thickness (scene units): in the walkthrough frame what shows
    /// through it is displaced by the refraction offset of that thickness. `None`: a thin sheet.
    /// The automatic set-up writes it for solid glass slabs ([`Mesh::slab_thickness`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
}

/// Most triangles [`Mesh::slab_thickness`] pairs (it compares every pair).
pub const MAX_SLAB_TRIANGLES: usize = 4096;

/// Largest distance of a vertex from a mesh's plane, relative to the mesh's extent, for a
/// triangle to lie in the plane ([`Mesh::dominant_plane`]).
pub const PLANARITY_TOLERANCE: f64 = 1e-3;

/// Smallest share of a mesh's area that must lie in its dominant plane for it to be a planar
/// reflector. A floor mesh with a thin riser along one edge still counts (the riser's
/// triangles are shaded like any other glossy surface); a curved or folded mesh does not.
pub const PLANAR_AREA_SHARE: f64 = 0.99;

/// Smallest share of the area facing the eye that a transmissive mesh's plane toward it must
/// hold for a mirror pass ([`Mesh::plane_facing`]): a glass slab's two faces halve its area, so
/// the rule looks at the side the eye sees (the Modern Hall's balustrade: 81 %, 41 % of all).
pub const GLASS_PLANE_SHARE: f64 = 0.5;

/// The plane most of a mesh lies in ([`Mesh::dominant_plane`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPlane {
    /// A point on the plane (the area-weighted centroid of the triangles parallel to it).
    pub point: DVec3,
    /// The unit normal (the area-weighted mean of theirs).
    pub normal: DVec3,
    /// Per triangle (in the mesh's order): whether all its corners lie within
    /// [`PLANARITY_TOLERANCE`] × the mesh's extent of the plane.
    pub in_plane: Vec<bool>,
    /// The share of the mesh's area in the plane.
    pub area_share: f64,
    /// The share of the area of the triangles facing the eye in the plane
    /// ([`Mesh::plane_facing`]; `area_share` without an eye).
    pub facing_share: f64,
}

/// The largest per-object sample budget ([`ObjectHints::samples`]).
pub const MAX_OBJECT_SAMPLES: u32 = 256;

/// A triangle mesh in world space with one material.
#[derive(Clone, Debug, PartialEq)]
pub struct Mesh {
    /// A name (the shape's id, the OBJ object, the glTF node/mesh), used by hints and overrides.
    pub name: String,
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit shading normals per vertex; `None`: use the geometric (face) normal.
    pub normals: Option<Vec<Vec3>>,
    /// Tangents per vertex (xyz unit, w = ±1 handedness of the bitangent), as in glTF.
    pub tangents: Option<Vec<Vec4>>,
    /// First texture-coordinate set (glTF convention: v = 0 at the top of an image).
    pub uv0: Option<Vec<Vec2>>,
    /// Second texture-coordinate set (light-map UVs, where the file has them).
    pub uv1: Option<Vec<Vec2>>,
    /// Triangles, counter-clockwise seen from the front.
    pub indices: Vec<[u32; 3]>,
    /// Index into [`crate::Scene::materials`].
    pub material: usize,
    /// Emitted radiance (W·sr⁻¹·m⁻², linear RGB) when the mesh is an area emitter, the same over
    /// its surface, from its front side only (the side its shading normals face, as Mitsuba's
    /// `area` emitters; modulated by the material's emission texture, if any).
    pub emission: Option<Rgb>,
    /// Real-time renderer hints.
    pub hints: ObjectHints,
}

impl Mesh {
    /// The thickness of a solid slab (a glass pane or shelf modelled with both faces): every
    /// triangle is paired with the nearest plane of an opposite-facing triangle (normals within
    /// cos 0.999 of opposite), the gaps' area-weighted median is the thickness. A slab when the
    /// paired triangles hold ≥ 75 % of the area and the thickness is under a tenth of the
    /// square root of the paired area (panes, not boxes). `None` otherwise, for a mesh with
    /// more than [`MAX_SLAB_TRIANGLES`] triangles (curved glass is no slab), or without area.
    pub fn slab_thickness(&self) -> Option<f64> {
        if self.indices.len() > MAX_SLAB_TRIANGLES {
            return None;
        }
        let p: Vec<DVec3> = self.positions.iter().map(|v| v.as_dvec3()).collect();
        // (unit normal, centroid, area) of each triangle with area.
        let tris: Vec<(DVec3, DVec3, f64)> = self
            .indices
            .iter()
            .filter_map(|t| {
                let [a, b, c] = t.map(|i| p.get(i as usize).copied().unwrap_or(DVec3::NAN));
                let x = (b - a).cross(c - a);
                let area = 0.5 * x.length();
                (area > 0.0 && area.is_finite())
                    .then(|| (x / (2.0 * area), (a + b + c) / 3.0, area))
            })
            .collect();
        let total: f64 = tris.iter().map(|t| t.2).sum();
        let mut gaps: Vec<(f64, f64)> = tris
            .iter()
            .filter_map(|&(n, c, a)| {
                tris.iter()
                    .filter(|o| o.0.dot(n) < -0.999)
                    .map(|o| (o.1 - c).dot(n).abs())
                    .filter(|g| *g > 0.0)
                    .min_by(f64::total_cmp)
                    .map(|g| (g, a))
            })
            .collect();
        let paired: f64 = gaps.iter().map(|g| g.1).sum();
        if total <= 0.0 || paired < 0.75 * total {
            return None;
        }
        gaps.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut acc = 0.0;
        let median = gaps.iter().find(|g| {
            acc += g.1;
            acc >= 0.5 * paired
        })?;
        (median.0 < 0.1 * paired.sqrt()).then_some(median.0)
    }

    /// The plane of the mesh's largest triangle, refined as the area-weighted mean normal and
    /// centroid of the triangles parallel to it (cos > 0.999), with the triangles within
    /// [`PLANARITY_TOLERANCE`] × the mesh's extent of it. `None` without a triangle of non-zero
    /// area. What the mirror pass reflects in, and what the automatic set-up calls planar
    /// (an area share ≥ [`PLANAR_AREA_SHARE`]).
    pub fn dominant_plane(&self) -> Option<MeshPlane> {
        self.plane_facing(None)
    }

    /// [`Mesh::dominant_plane`] seen from `eye`: the plane of the largest triangle whose front
    /// faces it (of all triangles when `None`, or when none faces it), with the share of the
    /// facing triangles' area in it — a glass slab's face toward the eye, not its far face.
    pub fn plane_facing(&self, eye: Option<DVec3>) -> Option<MeshPlane> {
        let p: Vec<DVec3> = self.positions.iter().map(|v| v.as_dvec3()).collect();
        let tris: Vec<[DVec3; 3]> = self
            .indices
            .iter()
            .map(|t| t.map(|i| p.get(i as usize).copied().unwrap_or(DVec3::NAN)))
            .collect();
        let cross: Vec<DVec3> = tris
            .iter()
            .map(|[a, b, c]| (*b - *a).cross(*c - *a))
            .collect();
        let largest_of = |facing: bool| {
            cross
                .iter()
                .zip(&tris)
                .filter(|(c, t)| {
                    c.is_finite()
                        && (!facing
                            || eye.is_some_and(|e| (e - (t[0] + t[1] + t[2]) / 3.0).dot(**c) > 0.0))
                })
                .map(|(c, _)| *c)
                .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()))
                .and_then(|c| c.try_normalize())
        };
        let largest = largest_of(eye.is_some()).or_else(|| largest_of(false))?;
        let (mut n, mut c, mut a_par) = (DVec3::ZERO, DVec3::ZERO, 0.0);
        for (t, x) in tris.iter().zip(&cross) {
            let a = x.length();
            if a > 0.0 && x.dot(largest) > 0.999 * a {
                n += *x;
                c += (t[0] + t[1] + t[2]) / 3.0 * a;
                a_par += a;
            }
        }
        let normal = n.try_normalize()?;
        let point = c / a_par;
        let (lo, hi) = p.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let tol = PLANARITY_TOLERANCE * (hi - lo).length().max(1e-12);
        let in_plane: Vec<bool> = tris
            .iter()
            .map(|t| t.iter().all(|v| (*v - point).dot(normal).abs() <= tol))
            .collect();
        let total: f64 = cross
            .iter()
            .map(|x| x.length())
            .filter(|a| a.is_finite())
            .sum();
        let inside: f64 = cross
            .iter()
            .zip(&in_plane)
            .filter(|(_, &k)| k)
            .map(|(x, _)| x.length())
            .sum();
        let faces = |t: &[DVec3; 3], x: &DVec3| {
            eye.is_none_or(|e| (e - (t[0] + t[1] + t[2]) / 3.0).dot(*x) > 0.0)
        };
        let facing: f64 = tris
            .iter()
            .zip(&cross)
            .filter(|(t, x)| x.is_finite() && faces(t, x))
            .map(|(_, x)| x.length())
            .sum();
        let facing_inside: f64 = tris
            .iter()
            .zip(&cross)
            .zip(&in_plane)
            .filter(|((t, x), &k)| k && x.is_finite() && faces(t, x))
            .map(|((_, x), _)| x.length())
            .sum();
        Some(MeshPlane {
            point,
            normal,
            in_plane,
            area_share: inside / total.max(1e-300),
            facing_share: facing_inside / facing.max(1e-300),
        })
    }

    /// A mesh with positions and triangles only (no normals, UVs or emission).
    pub fn new(
        name: impl Into<String>,
        positions: Vec<Vec3>,
        indices: Vec<[u32; 3]>,
        material: usize,
    ) -> Self {
        Mesh {
            name: name.into(),
            positions,
            normals: None,
            tangents: None,
            uv0: None,
            uv1: None,
            indices,
            material,
            emission: None,
            hints: ObjectHints::default(),
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The corners of triangle `t`.
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// A UV sphere (48 × 24 quads) with unit normals, uv0 (u along the longitude) and tangents
    /// along the longitude (the brushing direction of an anisotropic material).
    pub fn uv_sphere(name: &str, centre: Vec3, radius: f32, material: usize) -> Mesh {
        let (nu, nv) = (48u32, 24u32);
        let (mut p, mut n, mut uv, mut t) = (vec![], vec![], vec![], vec![]);
        for j in 0..=nv {
            let th = PI * f64::from(j) / f64::from(nv);
            for i in 0..=nu {
                let ph = 2.0 * PI * f64::from(i) / f64::from(nu);
                let d = DVec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
                p.push(centre + d.as_vec3() * radius);
                n.push(d.as_vec3());
                uv.push(Vec2::new(i as f32 / nu as f32, j as f32 / nv as f32));
                let tan = DVec3::new(-ph.sin(), 0.0, ph.cos());
                t.push(Vec4::new(tan.x as f32, 0.0, tan.z as f32, 1.0));
            }
        }
        let at = |i: u32, j: u32| j * (nu + 1) + i;
        let mut idx = vec![];
        for j in 0..nv {
            for i in 0..nu {
                idx.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                idx.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let mut m = Mesh::new(name, p, idx, material);
        m.normals = Some(n);
        m.uv0 = Some(uv);
        m.tangents = Some(t);
        m
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.indices.len())
            .map(|t| {
                let [a, b, c] = self.triangle(t);
                0.5 * f64::from((b - a).cross(c - a).length())
            })
            .sum()
    }

    /// Axis-aligned bounds (min, max); `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut it = self.positions.iter();
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
    }

    /// Checks the mesh and drops its degenerate triangles; returns it with the number dropped.
    /// `path` names the file in errors. Errors: a non-finite position, normal, tangent or UV
    /// (naming the vertex), an attribute array whose length differs from the positions', an index
    /// out of range (naming the triangle), a material index ≥ `material_count`.
    pub fn validated(mut self, path: &Path, material_count: usize) -> Result<(Mesh, usize)> {
        let err = |problem: String| SceneError::geometry(path, &self.name, problem);
        let n = self.positions.len();
        if n > u32::MAX as usize {
            return Err(err(format!("{n} vertices exceed the 32-bit index range")));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(err(format!(
                "vertex {i} has a non-finite position {:?}",
                self.positions[i]
            )));
        }
        let check_len = |what: &str, len: Option<usize>| -> Result<()> {
            match len {
                Some(l) if l != n => Err(err(format!(
                    "{l} {what} for {n} vertices (one per vertex expected)"
                ))),
                _ => Ok(()),
            }
        };
        check_len("normals", self.normals.as_ref().map(Vec::len))?;
        check_len("tangents", self.tangents.as_ref().map(Vec::len))?;
        check_len("uv0 coordinates", self.uv0.as_ref().map(Vec::len))?;
        check_len("uv1 coordinates", self.uv1.as_ref().map(Vec::len))?;
        if let Some(i) = self.normals.iter().flatten().position(|v| !v.is_finite()) {
            return Err(err(format!("normal {i} is not finite")));
        }
        if let Some(i) = self.tangents.iter().flatten().position(|v| !v.is_finite()) {
            return Err(err(format!("tangent {i} is not finite")));
        }
        for (set, uvs) in [("uv0", &self.uv0), ("uv1", &self.uv1)] {
            if let Some(i) = uvs.iter().flatten().position(|v| !v.is_finite()) {
                return Err(err(format!("{set} coordinate {i} is not finite")));
            }
        }
        if self.material >= material_count {
            return Err(err(format!(
                "material index {} out of range ({material_count} materials)",
                self.material
            )));
        }
        if let Some(e) = self.emission {
            if !e.is_finite() || e.min_component() < 0.0 {
                return Err(err(format!(
                    "emitted radiance {:?} is negative or not finite",
                    e.0
                )));
            }
        }
        if let Some((t, tri)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, tri)| tri.iter().any(|&i| i as usize >= n))
        {
            return Err(err(format!(
                "triangle {t} has index {tri:?} out of range ({n} vertices)"
            )));
        }
        // Unit normals: renormalise; a zero normal falls back to none for the whole mesh.
        if let Some(normals) = &mut self.normals {
            if normals.iter().any(|v| v.length_squared() == 0.0) {
                self.normals = None;
            } else {
                for v in normals.iter_mut() {
                    *v = v.normalize();
                }
            }
        }
        let before = self.indices.len();
        let positions = &self.positions;
        self.indices.retain(|&[a, b, c]| {
            if a == b || b == c || a == c {
                return false;
            }
            let (pa, pb, pc) = (
                positions[a as usize],
                positions[b as usize],
                positions[c as usize],
            );
            let cross = (pb - pa).cross(pc - pa);
            cross.length_squared() > 0.0 && cross.is_finite()
        });
        let dropped = before - self.indices.len();
        Ok((self, dropped))
    }

    /// Applies an affine transform to positions, normals (inverse transpose) and tangents.
    /// A transform with a negative determinant flips the winding to keep faces front-facing.
    pub fn transform(&mut self, m: &DMat4) {
        let normal_m = m.inverse().transpose();
        for p in &mut self.positions {
            *p = m.transform_point3(p.as_dvec3()).as_vec3();
        }
        if let Some(normals) = &mut self.normals {
            for v in normals.iter_mut() {
                *v = normal_m
                    .transform_vector3(v.as_dvec3())
                    .normalize_or_zero()
                    .as_vec3();
            }
        }
        if let Some(tangents) = &mut self.tangents {
            for t in tangents.iter_mut() {
                let d = m
                    .transform_vector3(t.truncate().as_dvec3())
                    .normalize_or_zero()
                    .as_vec3();
                *t = d.extend(t.w);
            }
        }
        if m.determinant() < 0.0 {
            for tri in &mut self.indices {
                tri.swap(1, 2);
            }
        }
    }
}

/// Mitsuba's `rectangle`: the square [−1, 1]² in the plane z = 0, normal +z, uv (0,0) at (−1,−1)
/// … (1,1) at (1,1) (v flipped to the glTF convention), two triangles.
pub fn rectangle(name: &str, material: usize) -> Mesh {
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let uv = vec![
        Vec2::new(0.0, 1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(0.0, 0.0),
    ];
    let mut m = Mesh::new(name, positions, vec![[0, 1, 2], [0, 2, 3]], material);
    m.normals = Some(vec![Vec3::Z; 4]);
    m.uv0 = Some(uv);
    m
}

/// Mitsuba's `disk`: the unit disk in the plane z = 0, normal +z, as a fan of [`DISK_SEGMENTS`]
/// triangles around the centre.
pub fn disk(name: &str, material: usize) -> Mesh {
    let n = DISK_SEGMENTS;
    let mut positions = vec![Vec3::ZERO];
    let mut uv = vec![Vec2::new(0.5, 0.5)];
    for k in 0..n {
        let phi = 2.0 * std::f64::consts::PI * f64::from(k) / f64::from(n);
        let (s, c) = phi.sin_cos();
        positions.push(Vec3::new(c as f32, s as f32, 0.0));
        uv.push(Vec2::new(0.5 + 0.5 * c as f32, 0.5 - 0.5 * s as f32));
    }
    let indices = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
    let mut m = Mesh::new(name, positions, indices, material);
    m.normals = Some(vec![Vec3::Z; (n + 1) as usize]);
    m.uv0 = Some(uv);
    m
}

/// Mitsuba's `cube`: [−1, 1]³, 24 vertices with face normals, 12 triangles.
pub fn cube(name: &str, material: usize) -> Mesh {
    let mut positions = Vec::with_capacity(24);
    let mut normals = Vec::with_capacity(24);
    let mut uv = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut nrm = Vec3::ZERO;
            nrm[axis] = sign;
            // Two tangent axes forming a right-handed frame with the normal.
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u32;
            for (s, t) in [(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let mut p = nrm;
                p[a] = s;
                p[b] = t * sign;
                positions.push(p);
                normals.push(nrm);
                uv.push(Vec2::new(0.5 + 0.5 * s, 0.5 - 0.5 * t));
            }
            indices.push([base, base + 1, base + 2]);
            indices.push([base, base + 2, base + 3]);
        }
    }
    let mut m = Mesh::new(name, positions, indices, material);
    m.normals = Some(normals);
    m.uv0 = Some(uv);
    m
}

/// A sphere of `radius` at `center`, tessellated with [`SPHERE_SEGMENTS`] × [`SPHERE_RINGS`]
/// (latitude–longitude grid, smooth normals; 2·64·31 = 3,968 triangles after the poles' degenerate
/// ones are dropped).
pub fn sphere(name: &str, center: Vec3, radius: f32, material: usize) -> Mesh {
    let (nu, nv) = (SPHERE_SEGMENTS, SPHERE_RINGS);
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uv = Vec::new();
    for j in 0..=nv {
        let theta = std::f64::consts::PI * f64::from(j) / f64::from(nv);
        for i in 0..=nu {
            let phi = 2.0 * std::f64::consts::PI * f64::from(i) / f64::from(nu);
            let d = Vec3::new(
                (theta.sin() * phi.cos()) as f32,
                (theta.sin() * phi.sin()) as f32,
                theta.cos() as f32,
            );
            positions.push(center + radius * d);
            normals.push(d);
            uv.push(Vec2::new(i as f32 / nu as f32, j as f32 / nv as f32));
        }
    }
    let row = nu + 1;
    let mut indices = Vec::new();
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (
                j * row + i,
                j * row + i + 1,
                (j + 1) * row + i + 1,
                (j + 1) * row + i,
            );
            if j != 0 {
                indices.push([a, d, b]);
            }
            if j + 1 != nv {
                indices.push([b, d, c]);
            }
        }
    }
    let mut m = Mesh::new(name, positions, indices, material);
    m.normals = Some(normals);
    m.uv0 = Some(uv);
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_give_their_thickness_and_other_shapes_none() {
        // A 2 × 1.5 pane 4 cm thick (the unit cube scaled), turned about y.
        let mut pane = cube("pane", 0);
        pane.transform(
            &(DMat4::from_rotation_y(0.6) * DMat4::from_scale(DVec3::new(1.0, 0.75, 0.02))),
        );
        let t = pane.slab_thickness().expect("a slab");
        assert!((t - 0.04).abs() < 1e-5, "{t}");
        // A box as thick as it is wide, a sphere, a single sheet: no slab.
        assert_eq!(cube("box", 0).slab_thickness(), None);
        assert_eq!(sphere("ball", Vec3::ZERO, 1.0, 0).slab_thickness(), None);
        assert_eq!(rectangle("sheet", 0).slab_thickness(), None);
    }

    #[test]
    fn a_slabs_plane_is_its_face_toward_the_eye() {
        // A 2 × 1.5 pane 4 cm thick, faces at z = ±0.02 (areas 3; edges 0.06 at x = ±1, 0.08 at
        // y = ±0.75): 6.28 in all.
        let mut pane = cube("pane", 0);
        pane.transform(&DMat4::from_scale(DVec3::new(1.0, 0.75, 0.02)));
        for (eye, z) in [
            (DVec3::new(3.0, 0.2, 5.0), 0.02f64),
            (DVec3::new(-3.0, 0.1, -5.0), -0.02),
        ] {
            let p = pane.plane_facing(Some(eye)).expect("a plane");
            assert!((p.normal.z - z.signum()).abs() < 1e-9, "{eye}: {p:?}");
            assert!((p.point.z - z).abs() < 1e-6, "{eye}: {p:?}");
            // One face of the slab's 6.28: under half of it, most of what the eye sees (the
            // face and the edge at x = ±1 turned to it).
            let total = 2.0 * (3.0 + 0.06 + 0.08);
            assert!(
                (p.area_share - 3.0 / total).abs() < 1e-4,
                "{}",
                p.area_share
            );
            let facing = 3.0 + 0.06;
            assert!(
                (p.facing_share - 3.0 / facing).abs() < 1e-4,
                "{}",
                p.facing_share
            );
            assert!(p.facing_share >= GLASS_PLANE_SHARE);
        }
        // Without an eye: the dominant plane, its facing share the area share.
        let d = pane.dominant_plane().expect("a plane");
        assert_eq!(d.facing_share, d.area_share);
        // A closed box: no face holds half of what an eye sees from a corner.
        let p = cube("box", 0)
            .plane_facing(Some(DVec3::splat(5.0)))
            .expect("a plane");
        assert!(p.facing_share < GLASS_PLANE_SHARE, "{}", p.facing_share);
    }

    #[test]
    fn shapes_have_their_areas_and_face_outwards() {
        let pi = std::f64::consts::PI;
        assert!((rectangle("r", 0).area() - 4.0).abs() < 1e-6);
        let d = disk("d", 0);
        assert_eq!(d.triangle_count(), DISK_SEGMENTS as usize);
        let inscribed =
            0.5 * f64::from(DISK_SEGMENTS) * (2.0 * pi / f64::from(DISK_SEGMENTS)).sin();
        assert!((d.area() - inscribed).abs() < 1e-5);
        let c = cube("c", 0);
        assert!((c.area() - 24.0).abs() < 1e-5);
        for (m, centre) in [(c, Vec3::ZERO), (sphere("s", Vec3::ONE, 2.0, 0), Vec3::ONE)] {
            let (m, dropped) = m.validated(Path::new("x"), 1).unwrap();
            assert_eq!(dropped, 0);
            for t in 0..m.triangle_count() {
                let [a, b, c] = m.triangle(t);
                let n = (b - a).cross(c - a);
                assert!(
                    n.dot((a + b + c) / 3.0 - centre) > 0.0,
                    "{} triangle {t}",
                    m.name
                );
            }
        }
        for m in [rectangle("r", 0), disk("d", 0)] {
            let [a, b, c] = m.triangle(0);
            assert!((b - a).cross(c - a).z > 0.0);
        }
    }

    #[test]
    fn transform_keeps_orientation_under_reflection() {
        let mut m = rectangle("r", 0);
        m.transform(&DMat4::from_scale(glam::DVec3::new(1.0, 1.0, -1.0)));
        let [a, b, c] = m.triangle(0);
        let n = (b - a).cross(c - a);
        assert!(n.z < 0.0 && m.normals.as_ref().unwrap()[0].z < 0.0);
    }
}
