//! The converged reference for real scenes: a unidirectional path tracer (Veach 1997 ch. 10;
//! pbrt-v4 §13.4 `PathIntegrator`, Mitsuba 3 `path`).
//!
//! At every vertex: next-event estimation toward one light — the environment (importance-sampled
//! by [`EnvSampler`]) or an emissive triangle (picked in proportion to its power, a point drawn
//! uniformly on its area) — and a continuation drawn from the [`Bsdf`]; both are weighted by the
//! power heuristic (β = 2) against the other technique's density, so a light reached by the
//! BSDF sample counts with the complementary weight. Delta lobes (weight 1, no NEE) come from
//! [`is_delta`]. Russian roulette after `rr_depth` bounces (survival = max throughput, ≤ 0.95).
//!
//! **Depth** follows Mitsuba: `max_depth` is the longest path in segments (1: only emitters
//! seen directly; 2: direct lighting).
//!
//! **Frames and normals.** The BSDF acts in the shading frame (interpolated normal, tangent
//! along ∂p/∂u). The geometric normal is turned to the shading normal's side. A direction whose
//! sides differ between the two normals is dropped (no light leaks through shading normals,
//! Veach §5.3). A two-sided material flips the frame to face the viewer. Emitters are one-sided
//! (front = the shading normal's side, as Mitsuba's `area`). A normal map (glTF tangent space:
//! T from the mesh's tangents or ∂p/∂u, B = w · N × T) replaces the shading normal
//! ([`mapped_normal`]); an emission texture multiplies the emitted radiance where it is seen
//! and where NEE samples it.
//!
//! **Pixels** are box-filtered (uniform jitter). Sample k of pixel (x, y) draws from
//! [`SplitMix64`] seeded by a hash of (seed, x, y, k), so a render continued with more samples
//! equals one rendered at once. Even and odd samples accumulate separately: their means are two
//! independent estimates whose difference measures the noise ([`Accumulator::noise_rms`]).

use crate::accel::{Accel, Hit};
use crate::image::Image;
use crate::sampling::{power_heuristic, ShadingFrame};
use crate::{Result, TraceError};
use glam::{DMat3, DVec3};
use lustre_brdf::bsdf::{Bsdf, BsdfSample};
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::SplitMix64;
use lustre_env::{Distribution1D, EnvSampler, EquirectMap};
use lustre_scene::Texture;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What the path tracer asks of a material at a hit.
pub trait Surface: Send + Sync {
    /// Calls `f` with the BSDF at texture coordinates `uv` (local frame, lustre-brdf
    /// conventions). A callback rather than a returned box: a textured material builds its
    /// BSDF on the stack at every hit, without allocating.
    fn with_bsdf(&self, uv: [f64; 2], f: &mut dyn FnMut(&dyn Bsdf));
    /// Whether the material has an alpha mask at all (lets rays skip the uv lookups).
    fn masked(&self) -> bool {
        false
    }
    /// Whether the surface exists at `uv` (alpha mask); only asked when [`Surface::masked`].
    fn opaque(&self, _uv: [f64; 2]) -> bool {
        true
    }
    /// Two-sided: the frame is flipped to face the viewer (Mitsuba's `twosided`).
    fn two_sided(&self) -> bool {
        false
    }
    /// Whether the material has a normal map (lets hits skip the lookup).
    fn normal_mapped(&self) -> bool {
        false
    }
    /// The tangent-space shading normal at `uv` (unit; +z = the interpolated normal, +x the
    /// tangent, +y the bitangent: glTF normal maps); only asked when
    /// [`Surface::normal_mapped`].
    fn normal_map(&self, _uv: [f64; 2]) -> Option<DVec3> {
        None
    }
    /// The textures that vary the surface's BSDF or its shading normal (its parameters' and
    /// normal map's images; not the emission's nor the alpha mask's): what frequency analysis
    /// adds to a hit's spatial bandwidth (004 §IV.3.1). None for an untextured surface.
    fn bsdf_textures(&self) -> Vec<&Texture> {
        vec![]
    }
    /// Whether the emitted radiance is textured.
    fn emission_textured(&self) -> bool {
        false
    }
    /// Factor of the triangle's emitted radiance at `uv` (a glTF emissive texture; 1 without
    /// one); only asked when [`Surface::emission_textured`].
    fn emission_factor(&self, _uv: [f64; 2]) -> Rgb {
        Rgb::ONE
    }
}

/// A material that is one BSDF everywhere.
#[derive(Debug)]
pub struct ConstantSurface {
    /// The BSDF.
    pub bsdf: Box<dyn Bsdf>,
    /// See [`Surface::two_sided`].
    pub two_sided: bool,
}

impl Surface for ConstantSurface {
    fn with_bsdf(&self, _uv: [f64; 2], f: &mut dyn FnMut(&dyn Bsdf)) {
        f(&*self.bsdf)
    }
    fn two_sided(&self) -> bool {
        self.two_sided
    }
}

/// True when the sample came from a delta (specular) lobe: its pdf is a discrete probability,
/// so it gets MIS weight 1 and the light it reaches is counted in full.
pub fn is_delta(s: &BsdfSample) -> bool {
    s.lobe.is_specular()
}

/// World-space triangles with per-corner shading normals and texture coordinates, a material
/// index and an emitted radiance per triangle. Empty `normals` / `uvs` / `emission` mean
/// geometric normals, uv = 0 and no emitters.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    /// Vertices, world space.
    pub positions: Vec<[DVec3; 3]>,
    /// Shading normals per corner (same length as `positions`, or empty).
    pub normals: Vec<[DVec3; 3]>,
    /// Texture coordinates per corner (same length as `positions`, or empty).
    pub uvs: Vec<[[f64; 2]; 3]>,
    /// Tangents per corner for normal maps (xyz, w = ±1 the bitangent's sign: glTF's
    /// B = w · N × T). Same length as `positions`, or empty; a zero tangent means "derive one
    /// from the uvs" (T = ∂p/∂u, w such that B points along −∂p/∂v, glTF's v runs down).
    pub tangents: Vec<[[f64; 4]; 3]>,
    /// Material index per triangle.
    pub material: Vec<u32>,
    /// Emitted radiance per triangle, front side (same length as `positions`, or empty).
    pub emission: Vec<Rgb>,
}

impl Geometry {
    /// ∂p/∂u and ∂p/∂v of triangle `prim` from its texture coordinates (pbrt-v4 Eq. 6.7):
    /// with e1 = p1 − p0, e2 = p2 − p0 and the uv differences (du1, dv1), (du2, dv2) of corners
    /// 1 and 2 from corner 0, det = du1 dv2 − dv1 du2 and
    /// ∂p/∂u = (dv2 e1 − dv1 e2)/det, ∂p/∂v = (du1 e2 − du2 e1)/det;
    /// (e1, 0) where the triangle has no uvs or they are degenerate (|det| ≤ 1e-12).
    pub fn surface_derivatives(&self, prim: usize) -> (DVec3, DVec3) {
        let t = &self.positions[prim];
        let e1 = t[1] - t[0];
        let e2 = t[2] - t[0];
        match self.uvs.get(prim) {
            Some(uvt) => {
                let (du1, dv1) = (uvt[1][0] - uvt[0][0], uvt[1][1] - uvt[0][1]);
                let (du2, dv2) = (uvt[2][0] - uvt[0][0], uvt[2][1] - uvt[0][1]);
                let det = du1 * dv2 - dv1 * du2;
                if det.abs() > 1e-12 {
                    ((e1 * dv2 - e2 * dv1) / det, (e2 * du1 - e1 * du2) / det)
                } else {
                    (e1, DVec3::ZERO)
                }
            }
            None => (e1, DVec3::ZERO),
        }
    }
}

/// An environment light: an equirect map (lustre's convention), a rotation taking map
/// directions to world directions, and a scale.
#[derive(Clone, Debug)]
pub struct EnvLight {
    map: EquirectMap,
    sampler: EnvSampler,
    to_world: DMat3,
    scale: f64,
}

impl EnvLight {
    /// The light of `map` rotated by `to_world` (a rotation matrix) and scaled by `scale` (≥ 0).
    /// Errors: a black map, a non-finite or negative scale, a matrix that is not a rotation.
    pub fn new(map: EquirectMap, to_world: DMat3, scale: f64) -> Result<Self> {
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(TraceError::Parameter(format!(
                "environment scale {scale} must be finite and ≥ 0"
            )));
        }
        let should_be_id = to_world.transpose() * to_world;
        if !(should_be_id - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .all(|v| v.abs() < 1e-6)
        {
            return Err(TraceError::Parameter(format!(
                "environment rotation {to_world:?} is not orthonormal"
            )));
        }
        let sampler = EnvSampler::new(&map)?;
        Ok(EnvLight {
            map,
            sampler,
            to_world,
            scale,
        })
    }

    /// A constant environment of radiance `l` (an 8×4 uniform map).
    pub fn constant(l: Rgb) -> Result<Self> {
        let px = [l[0] as f32, l[1] as f32, l[2] as f32];
        Self::new(EquirectMap::new(8, 4, vec![px; 32])?, DMat3::IDENTITY, 1.0)
    }

    /// Radiance arriving from world direction `d` (bilinear).
    pub fn eval(&self, d: DVec3) -> Rgb {
        Rgb(self.map.lookup_bilinear(self.to_world.transpose() * d)) * self.scale
    }

    /// The equirect map (map directions; see [`EnvLight::to_world`]).
    pub fn map(&self) -> &EquirectMap {
        &self.map
    }

    /// The rotation taking map directions to world directions.
    pub fn to_world(&self) -> DMat3 {
        self.to_world
    }

    /// The radiance scale.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The importance sampler (map directions).
    pub fn sampler(&self) -> &EnvSampler {
        &self.sampler
    }

    /// A world direction and its solid-angle density.
    pub fn sample(&self, u1: f64, u2: f64) -> (DVec3, f64) {
        let s = self.sampler.sample(u1, u2);
        (self.to_world * s.dir, s.pdf)
    }

    /// Density of [`EnvLight::sample`] at world direction `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        self.sampler.pdf(self.to_world.transpose() * d)
    }

    /// [`EnvLight::eval`] and [`EnvLight::pdf`] at world direction `d`, its map coordinates
    /// found once (the same values as the two calls).
    pub fn eval_and_pdf(&self, d: DVec3) -> (Rgb, f64) {
        let (u, v) = lustre_env::equirect::direction_uv(self.to_world.transpose() * d);
        (
            Rgb(self.map.bilinear_uv(u, v)) * self.scale,
            self.sampler.pdf_uv(u, v),
        )
    }
}

/// A pinhole camera: position and an orthonormal basis (forward, right, up), vertical field of
/// view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathCamera {
    /// Centre of projection.
    pub origin: DVec3,
    /// Unit view direction.
    pub forward: DVec3,
    /// Unit right vector (image +x).
    pub right: DVec3,
    /// Unit up vector (image −y).
    pub up: DVec3,
    /// tan(fov_y / 2).
    pub tan_half_fov_y: f64,
}

impl PathCamera {
    /// A camera at `eye` looking at `target` with the up hint `up` and vertical field of view
    /// `fov_y_deg`. Errors on a degenerate basis or a field of view outside (0, 180).
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3, fov_y_deg: f64) -> Result<Self> {
        let bad = || {
            TraceError::Parameter(format!(
                "camera eye {eye}, target {target}, up {up}, fov {fov_y_deg}° is degenerate"
            ))
        };
        if !(fov_y_deg > 0.0 && fov_y_deg < 180.0) {
            return Err(bad());
        }
        let forward = (target - eye).try_normalize().ok_or_else(bad)?;
        let right = forward.cross(up).try_normalize().ok_or_else(bad)?;
        Ok(PathCamera {
            origin: eye,
            forward,
            right,
            up: right.cross(forward),
            tan_half_fov_y: (fov_y_deg.to_radians() * 0.5).tan(),
        })
    }

    /// The unit ray direction through image position (x, y) in pixels (0..w, 0..h, y down).
    pub fn direction(&self, x: f64, y: f64, w: usize, h: usize) -> DVec3 {
        let (wf, hf) = (w as f64, h as f64);
        let a = self.tan_half_fov_y;
        let px = (2.0 * x / wf - 1.0) * a * wf / hf;
        let py = (1.0 - 2.0 * y / hf) * a;
        (self.forward + px * self.right + py * self.up).normalize()
    }
}

/// A scene as the path tracer sees it.
pub struct PathScene<'s> {
    /// Triangles.
    pub geometry: Geometry,
    /// Materials, indexed by `geometry.material`.
    pub materials: Vec<Box<dyn Surface + 's>>,
    /// The environment (black when `None`).
    pub environment: Option<EnvLight>,
}

/// Options of the path tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathOptions {
    /// Longest path in segments (Mitsuba's `max_depth`); ≥ 1.
    pub max_depth: u32,
    /// Bounces before Russian roulette starts (Mitsuba's `rr_depth`, default 5).
    pub rr_depth: u32,
    /// Which techniques run (all three estimate the same image; the single ones are for tests).
    pub strategy: crate::sampling::Strategy,
}

impl Default for PathOptions {
    fn default() -> Self {
        PathOptions {
            max_depth: 16,
            rr_depth: 5,
            strategy: crate::sampling::Strategy::Mis,
        }
    }
}

/// The path tracer over a [`PathScene`]: the BVH, the emitter distribution and the options.
pub struct PathTracer<'a, 's> {
    scene: &'a PathScene<'s>,
    accel: Accel,
    /// Emissive triangles and their selection distribution (by power = luminance · area).
    lights: Vec<usize>,
    light_dist: Option<Distribution1D>,
    /// Per triangle: its index in `lights`, or `usize::MAX`.
    light_index: Vec<usize>,
    /// Probability of choosing the environment for NEE.
    p_env: f64,
    opts: PathOptions,
    /// Per material: [`Surface::two_sided`] and [`Surface::masked`], asked once.
    two_sided: Vec<bool>,
    masked: Vec<bool>,
    any_masked: bool,
    /// Unit geometric normal per triangle (+z for a degenerate one).
    face_normal: Vec<DVec3>,
    /// Per material: [`Surface::normal_mapped`] and [`Surface::emission_textured`].
    normal_mapped: Vec<bool>,
    emission_textured: Vec<bool>,
}

/// Area of triangle t.
fn area(t: &[DVec3; 3]) -> f64 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length()
}

/// A scene point ready for shading.
struct Vertex {
    p: DVec3,
    /// Geometric normal on the shading normal's side.
    ng: DVec3,
    /// Shading frame (before any two-sided flip).
    frame: ShadingFrame,
    uv: [f64; 2],
    prim: usize,
    /// Interpolated shading normal (before any normal map; the emitters' front side).
    ns: DVec3,
}

/// The shading normal of a tangent-space normal `n_ts` (+z = `ns`) with tangent `t` and
/// bitangent sign `sign` (glTF: B = sign · N × T, T made orthogonal to N first), and the
/// tangent to build the frame with. A degenerate tangent or result keeps `ns`.
pub fn mapped_normal(ns: DVec3, t: DVec3, sign: f64, n_ts: DVec3) -> (DVec3, DVec3) {
    let Some(t) = (t - ns * ns.dot(t)).try_normalize() else {
        return (ns, t);
    };
    let b = ns.cross(t) * sign;
    match (t * n_ts.x + b * n_ts.y + ns * n_ts.z).try_normalize() {
        Some(n) => (n, t),
        None => (ns, t),
    }
}

/// A small offset that moves a spawned ray off its surface (scaled with the coordinates).
pub(crate) fn offset(p: DVec3, ng: DVec3, w: DVec3) -> DVec3 {
    let eps = 2e-5 * (1.0 + p.abs().max_element());
    if w.dot(ng) >= 0.0 {
        p + ng * eps
    } else {
        p - ng * eps
    }
}

impl<'a, 's> PathTracer<'a, 's> {
    /// The scene it traces.
    pub fn scene(&self) -> &'a PathScene<'s> {
        self.scene
    }

    /// Builds the BVH and the emitter distribution. Errors: mismatched array lengths, a
    /// material index out of range, a non-finite vertex, `max_depth` = 0.
    pub fn new(scene: &'a PathScene<'s>, opts: PathOptions) -> Result<Self> {
        let g = &scene.geometry;
        let n = g.positions.len();
        for (name, len) in [
            ("normals", g.normals.len()),
            ("uvs", g.uvs.len()),
            ("tangents", g.tangents.len()),
            ("emission", g.emission.len()),
        ] {
            if len != 0 && len != n {
                return Err(TraceError::Parameter(format!(
                    "geometry: {len} {name} for {n} triangles"
                )));
            }
        }
        if g.material.len() != n {
            return Err(TraceError::Parameter(format!(
                "geometry: {} material indices for {n} triangles",
                g.material.len()
            )));
        }
        if let Some(k) = g
            .material
            .iter()
            .position(|&m| m as usize >= scene.materials.len())
        {
            return Err(TraceError::Parameter(format!(
                "triangle {k} uses material {} of {}",
                g.material[k],
                scene.materials.len()
            )));
        }
        if opts.max_depth == 0 {
            return Err(TraceError::Parameter("max_depth must be ≥ 1".into()));
        }
        let accel = Accel::new(&g.positions)?;
        let mut lights = vec![];
        let mut power = vec![];
        let mut light_index = vec![usize::MAX; if g.emission.is_empty() { 0 } else { n }];
        for (k, e) in g.emission.iter().enumerate() {
            let p = e.mean() * area(&g.positions[k]);
            if e.is_finite() && p > 0.0 {
                light_index[k] = lights.len();
                lights.push(k);
                power.push(p);
            }
        }
        let light_dist = (!lights.is_empty()).then(|| Distribution1D::new(power));
        let p_env = match (&scene.environment, &light_dist) {
            (Some(_), Some(_)) => 0.5,
            (Some(_), None) => 1.0,
            _ => 0.0,
        };
        let two_sided: Vec<bool> = scene.materials.iter().map(|m| m.two_sided()).collect();
        let masked: Vec<bool> = scene.materials.iter().map(|m| m.masked()).collect();
        Ok(PathTracer {
            scene,
            accel,
            lights,
            light_dist,
            light_index,
            p_env,
            opts,
            two_sided,
            any_masked: masked.iter().any(|&m| m),
            masked,
            normal_mapped: scene.materials.iter().map(|m| m.normal_mapped()).collect(),
            emission_textured: scene
                .materials
                .iter()
                .map(|m| m.emission_textured())
                .collect(),
            face_normal: g
                .positions
                .iter()
                .map(|t| {
                    (t[1] - t[0])
                        .cross(t[2] - t[0])
                        .try_normalize()
                        .unwrap_or(DVec3::Z)
                })
                .collect(),
        })
    }

    /// The BVH (for benchmarks and ray queries).
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// uv at barycentrics `b` of triangle `prim`.
    fn uv_at(&self, prim: usize, b: [f64; 3]) -> [f64; 2] {
        match self.scene.geometry.uvs.get(prim) {
            Some(t) => [0, 1].map(|c| b[0] * t[0][c] + b[1] * t[1][c] + b[2] * t[2][c]),
            None => [0.0; 2],
        }
    }

    /// The alpha test of hit candidates.
    fn accept(&self, prim: usize, b: [f64; 3]) -> bool {
        let k = self.scene.geometry.material[prim] as usize;
        !self.masked[k] || self.scene.materials[k].opaque(self.uv_at(prim, b))
    }

    /// The closest surface along o + t d, t > 0 (alpha-masked hits skipped).
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<Hit> {
        if self.any_masked {
            self.accel
                .intersect(o, d, 0.0, f64::INFINITY, |p, b| self.accept(p, b))
        } else {
            self.accel.intersect(o, d, 0.0, f64::INFINITY, |_, _| true)
        }
    }

    /// The closest surface along o + t d, t > 0, skipping alpha-masked hits and the triangles
    /// for which `skip(prim)` holds (a probe capture leaves its own object out).
    pub fn intersect_filtered(
        &self,
        o: DVec3,
        d: DVec3,
        skip: impl Fn(usize) -> bool,
    ) -> Option<Hit> {
        self.accel.intersect(o, d, 0.0, f64::INFINITY, |p, b| {
            !skip(p) && (!self.any_masked || self.accept(p, b))
        })
    }

    /// Whether anything opaque lies on o + t d for 0 < t < tmax.
    pub fn occluded(&self, o: DVec3, d: DVec3, tmax: f64) -> bool {
        if self.any_masked {
            self.accel
                .occluded(o, d, 0.0, tmax, |p, b| self.accept(p, b))
        } else {
            self.accel.occluded(o, d, 0.0, tmax, |_, _| true)
        }
    }

    /// The unit geometric normal (turned to the shading normal's side) and the unit shading
    /// normal of triangle `prim` at barycentrics `b`.
    pub(crate) fn normals(&self, prim: usize, b: [f64; 3]) -> (DVec3, DVec3) {
        let g = &self.scene.geometry;
        let ng = self.face_normal[prim];
        let ns = g
            .normals
            .get(prim)
            .and_then(|n| (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).try_normalize())
            .unwrap_or(ng);
        (if ns.dot(ng) < 0.0 { -ng } else { ng }, ns)
    }

    /// The shading point of hit `h` of the ray o + t d: position, shading frame (normal map
    /// applied, tangent along ∂p/∂u) and texture coordinates, as the path tracer shades it.
    pub fn shading_point(&self, o: DVec3, d: DVec3, h: &Hit) -> (DVec3, ShadingFrame, [f64; 2]) {
        let v = self.vertex(o, d, h);
        (v.p, v.frame, v.uv)
    }

    fn vertex(&self, o: DVec3, d: DVec3, h: &Hit) -> Vertex {
        let g = &self.scene.geometry;
        let t = &g.positions[h.prim];
        let b = h.bary;
        let p = t[0] * b[0] + t[1] * b[1] + t[2] * b[2];
        let p = if p.is_finite() { p } else { o + d * h.t };
        let (ng, ns) = self.normals(h.prim, b);
        let uv = self.uv_at(h.prim, b);
        let (dpdu, dpdv) = g.surface_derivatives(h.prim);
        let k = g.material[h.prim] as usize;
        let frame = match self.normal_mapped[k]
            .then(|| self.scene.materials[k].normal_map(uv))
            .flatten()
        {
            Some(n_ts) => {
                let (t, sign) = match g.tangents.get(h.prim) {
                    Some(tc) if tc[0][3] != 0.0 => {
                        let t = DVec3::new(
                            b[0] * tc[0][0] + b[1] * tc[1][0] + b[2] * tc[2][0],
                            b[0] * tc[0][1] + b[1] * tc[1][1] + b[2] * tc[2][1],
                            b[0] * tc[0][2] + b[1] * tc[1][2] + b[2] * tc[2][2],
                        );
                        (t, tc[0][3].signum())
                    }
                    _ => (
                        dpdu,
                        if ns.cross(dpdu).dot(dpdv) > 0.0 {
                            -1.0
                        } else {
                            1.0
                        },
                    ),
                };
                let (n, t) = mapped_normal(ns, t, sign, n_ts);
                ShadingFrame::new(n, t)
            }
            None => ShadingFrame::new(ns, dpdu),
        };
        Vertex {
            p,
            ng,
            frame,
            uv,
            prim: h.prim,
            ns,
        }
    }

    /// Emitted radiance of triangle `prim` (shading normal `ns`, texture coordinates `uv`)
    /// toward `wo` (front side only), times the material's emission texture.
    fn emitted(&self, prim: usize, ns: DVec3, uv: [f64; 2], wo: DVec3) -> Rgb {
        match self.scene.geometry.emission.get(prim) {
            Some(e) if wo.dot(ns) > 0.0 => {
                let k = self.scene.geometry.material[prim] as usize;
                if self.emission_textured[k] {
                    *e * self.scene.materials[k].emission_factor(uv)
                } else {
                    *e
                }
            }
            _ => Rgb::ZERO,
        }
    }

    /// Solid-angle density of NEE choosing emissive triangle `prim` at the point seen from
    /// `from` at `to` with (unit) normal `n`.
    fn area_light_pdf(&self, prim: usize, from: DVec3, to: DVec3, n: DVec3) -> f64 {
        let (Some(dist), Some(&li)) = (&self.light_dist, self.light_index.get(prim)) else {
            return 0.0;
        };
        if li == usize::MAX {
            return 0.0;
        }
        let d = to - from;
        let dist2 = d.length_squared();
        let cos_l = (d.normalize_or_zero().dot(n)).abs();
        if cos_l <= 0.0 {
            return 0.0;
        }
        (1.0 - self.p_env) * dist.probability(li) / area(&self.scene.geometry.positions[prim])
            * dist2
            / cos_l
    }

    /// Radiance arriving at `o` along unit direction `d` (the path tracer proper).
    pub fn radiance(&self, o: DVec3, d: DVec3, rng: &mut SplitMix64) -> Rgb {
        let st = PathState {
            l: Rgb::ZERO,
            beta: Rgb::ONE,
            prev_pdf: 0.0,
            prev_delta: true,
            prev_p: o,
            eta_scale: 1.0,
        };
        self.trace(o, d, 0, st, rng)
    }

    /// Irradiance E = ∫ L(p, ω) cos θ dω (the path tracer's units) on the side of `ns` at the
    /// surface point `p` with geometric normal `ng`: π times the radiance a white Lambertian
    /// surface at `p` would reflect (Lo = E/π, 000 Eq. 4.1 with kd = 1), estimated by the same
    /// next-event estimation, MIS and continuation as [`PathTracer::radiance`] from a first
    /// vertex at `p` (depth 1, as if a camera ray had reached it; `max_depth` = 2 is direct
    /// light only). `ng` is turned to `ns`'s side; ray origins are offset along it.
    pub fn irradiance(&self, p: DVec3, ng: DVec3, ns: DVec3, rng: &mut SplitMix64) -> Rgb {
        let ng = if ng.dot(ns) < 0.0 { -ng } else { ng };
        let frame = ShadingFrame::new(ns, ns.any_orthonormal_vector());
        let v = Vertex {
            p,
            ng,
            frame,
            uv: [0.0; 2],
            prim: usize::MAX,
            ns,
        };
        let mut st = PathState {
            l: Rgb::ZERO,
            beta: Rgb::ONE,
            prev_pdf: 0.0,
            prev_delta: true,
            prev_p: p,
            eta_scale: 1.0,
        };
        if self.opts.max_depth < 2 {
            return Rgb::ZERO;
        }
        let white = lustre_brdf::models::lambert::Lambert { kd: Rgb::ONE };
        let next = self.scatter(&white, &v, frame, ng, ns, 1, &mut st, rng);
        let l = match next {
            Some((o, d)) => self.trace(o, d, 1, st, rng),
            None => st.l,
        };
        l * std::f64::consts::PI
    }

    /// Follows the path from the ray o + t·d after `depth` segments with state `st`; the
    /// radiance gathered.
    fn trace(
        &self,
        o: DVec3,
        d: DVec3,
        depth: u32,
        mut st: PathState,
        rng: &mut SplitMix64,
    ) -> Rgb {
        use crate::sampling::Strategy;
        let strategy = self.opts.strategy;
        let use_bsdf_hits = strategy != Strategy::Light;
        let mis = strategy == Strategy::Mis;
        let (mut o, mut d) = (o, d);
        let mut depth = depth; // segments so far
        loop {
            depth += 1;
            let hit = self.intersect(o, d);
            let Some(h) = hit else {
                if let Some(env) = &self.scene.environment {
                    let le = env.eval(d);
                    let w = if st.prev_delta {
                        1.0
                    } else if !use_bsdf_hits {
                        0.0
                    } else if mis {
                        power_heuristic(st.prev_pdf, self.p_env * env.pdf(d))
                    } else {
                        1.0
                    };
                    st.l += st.beta * le * w;
                }
                break;
            };
            let v = self.vertex(o, d, &h);
            let wo = -d;
            let le = self.emitted(v.prim, v.ns, v.uv, wo);
            if le != Rgb::ZERO {
                let w = if st.prev_delta {
                    1.0
                } else if !use_bsdf_hits {
                    0.0
                } else if mis {
                    power_heuristic(
                        st.prev_pdf,
                        self.area_light_pdf(v.prim, st.prev_p, v.p, v.ng),
                    )
                } else {
                    1.0
                };
                st.l += st.beta * le * w;
            }
            if depth >= self.opts.max_depth {
                break;
            }
            let mat = &self.scene.materials[self.scene.geometry.material[v.prim] as usize];
            let (frame, ng) = if self.two_sided[self.scene.geometry.material[v.prim] as usize]
                && wo.dot(v.ng) < 0.0
            {
                (v.frame.flipped(), -v.ng)
            } else {
                (v.frame, v.ng)
            };
            let mut next = None;
            mat.with_bsdf(v.uv, &mut |bsdf| {
                next = self.scatter(bsdf, &v, frame, ng, wo, depth, &mut st, rng);
            });
            let Some((o2, d2)) = next else {
                break;
            };
            o = o2;
            d = d2;
        }
        st.l
    }

    /// One path vertex with its BSDF: next-event estimation (added to `st.l`) and the
    /// continuation (throughput, MIS state and roulette in `st`); the next ray, or `None` when
    /// the path ends.
    #[allow(clippy::too_many_arguments)]
    fn scatter(
        &self,
        bsdf: &dyn Bsdf,
        v: &Vertex,
        frame: ShadingFrame,
        ng: DVec3,
        wo: DVec3,
        depth: u32,
        st: &mut PathState,
        rng: &mut SplitMix64,
    ) -> Option<(DVec3, DVec3)> {
        use crate::sampling::Strategy;
        let use_nee = self.opts.strategy != Strategy::Bsdf;
        let mis = self.opts.strategy == Strategy::Mis;
        let wo_l = frame.to_local(wo);
        // Same side of both normals, or the direction is dropped.
        let consistent = |w: DVec3, wl: DVec3| (w.dot(ng) > 0.0) == (wl.z > 0.0);
        // Next-event estimation (pointless on a BSDF made only of Dirac lobes).
        let lobes = bsdf.flags().lobes;
        let only_delta = lobes.is_specular() && !lobes.is_non_delta();
        if use_nee && !only_delta {
            if let Some((wi, pdf_l, le, tmax)) = self.sample_light(v.p, rng) {
                let wi_l = frame.to_local(wi);
                if consistent(wi, wi_l) {
                    let f = bsdf.eval(wi_l, wo_l);
                    if f != Rgb::ZERO && !self.occluded(offset(v.p, ng, wi), wi, tmax) {
                        let w = if mis {
                            power_heuristic(pdf_l, bsdf.pdf(wi_l, wo_l))
                        } else {
                            1.0
                        };
                        let c = st.beta * f * le * (wi_l.z.abs() / pdf_l * w);
                        if c.is_finite() {
                            st.l += c;
                        }
                    }
                }
            }
        }
        // Continue the path.
        let (u1, u2) = (rng.next_f64(), rng.next_f64());
        let s = bsdf.sample(wo_l, u1, u2)?;
        let wi = frame.to_world(s.wi);
        if !consistent(wi, s.wi) {
            return None;
        }
        let wt = s.weight();
        if !wt.is_finite() || wt == Rgb::ZERO {
            return None;
        }
        st.beta = st.beta * wt;
        // Refraction scaled radiance by 1/η²; roulette looks at the flux (pbrt's etaScale).
        if s.lobe.is_transmission() {
            st.eta_scale *= s.eta * s.eta;
        }
        st.prev_delta = is_delta(&s);
        st.prev_pdf = s.pdf;
        st.prev_p = v.p;
        // With light sampling only, paths continue for indirect light but emitters they
        // reach are not counted (NEE counted them).
        if depth >= self.opts.rr_depth {
            let q = (st.beta.max_component() * st.eta_scale).min(0.95);
            if rng.next_f64() >= q {
                return None;
            }
            st.beta *= 1.0 / q;
        }
        Some((offset(v.p, ng, wi), wi))
    }

    /// Draws a light for NEE at point `p`: (unit direction, solid-angle pdf including the
    /// light choice, radiance, shadow-ray tmax along the direction).
    fn sample_light(&self, p: DVec3, rng: &mut SplitMix64) -> Option<(DVec3, f64, Rgb, f64)> {
        let u0 = rng.next_f64();
        let (u1, u2) = (rng.next_f64(), rng.next_f64());
        if u0 < self.p_env {
            let env = self.scene.environment.as_ref()?;
            let (wi, pdf) = env.sample(u1, u2);
            let pdf = pdf * self.p_env;
            return (pdf > 0.0).then(|| (wi, pdf, env.eval(wi), f64::INFINITY));
        }
        let dist = self.light_dist.as_ref()?;
        let (k, _) = dist.sample((u0 - self.p_env) / (1.0 - self.p_env));
        let prim = self.lights[k];
        let t = &self.scene.geometry.positions[prim];
        // Uniform point on the triangle (pbrt-v4 Eq. A.12).
        let su = u1.sqrt();
        let b = [1.0 - su, u2 * su, (1.0 - u2) * su];
        let q = t[0] * b[0] + t[1] * b[1] + t[2] * b[2];
        let (ng, ns) = self.normals(prim, b);
        let to = q - p;
        let dist2 = to.length_squared();
        let wi = to.try_normalize()?;
        let le = self.emitted(prim, ns, self.uv_at(prim, b), -wi);
        if le == Rgb::ZERO {
            return None;
        }
        let pdf = self.area_light_pdf(prim, p, q, ng);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        // Stop the shadow ray just short of the light (relative, in units of the distance).
        let tmax = dist2.sqrt() * (1.0 - 1e-4);
        Some((wi, pdf, le, tmax))
    }
}

/// The state a path carries from vertex to vertex.
struct PathState {
    /// Radiance gathered so far.
    l: Rgb,
    /// Throughput.
    beta: Rgb,
    /// Density of the last BSDF sample (solid angle) and whether it was a delta lobe.
    prev_pdf: f64,
    prev_delta: bool,
    /// The last scattering point (for the area-light density of an emitter hit by chance).
    prev_p: DVec3,
    /// Product of η² over refractions (pbrt's etaScale).
    eta_scale: f64,
}

/// Two independent half-images (even / odd samples) of a progressive render.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulator {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Samples per pixel so far.
    pub spp: u32,
    even: Vec<[f64; 3]>,
    odd: Vec<[f64; 3]>,
}

impl Accumulator {
    /// An empty w×h accumulator; errors on a zero size.
    pub fn new(width: usize, height: usize) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(TraceError::Parameter(format!(
                "image size {width}×{height} is empty"
            )));
        }
        Ok(Accumulator {
            width,
            height,
            spp: 0,
            even: vec![[0.0; 3]; width * height],
            odd: vec![[0.0; 3]; width * height],
        })
    }

    /// Even samples taken so far.
    fn n_even(&self) -> u32 {
        self.spp.div_ceil(2)
    }

    /// Odd samples taken so far.
    fn n_odd(&self) -> u32 {
        self.spp / 2
    }

    /// Restores an accumulator from its two half means (as written by a previous run) and the
    /// sample count; errors when the sizes differ or `spp` < 2.
    pub fn from_halves(even: &Image, odd: &Image, spp: u32) -> Result<Self> {
        if even.width != odd.width || even.height != odd.height || spp < 2 {
            return Err(TraceError::Parameter(format!(
                "resume: halves {}×{} and {}×{} with {spp} samples do not fit together",
                even.width, even.height, odd.width, odd.height
            )));
        }
        let mut a = Accumulator::new(even.width, even.height)?;
        a.spp = spp;
        let (ne, no) = (a.n_even() as f64, a.n_odd() as f64);
        a.even = even.data.iter().map(|p| p.map(|c| c as f64 * ne)).collect();
        a.odd = odd.data.iter().map(|p| p.map(|c| c as f64 * no)).collect();
        Ok(a)
    }

    fn image_of(&self, f: impl Fn(usize) -> [f64; 3]) -> Image {
        Image {
            width: self.width,
            height: self.height,
            data: (0..self.width * self.height)
                .map(|k| f(k).map(|c| c as f32))
                .collect(),
        }
    }

    /// The mean of all samples.
    pub fn image(&self) -> Image {
        let n = self.spp.max(1) as f64;
        self.image_of(|k| [0, 1, 2].map(|c| (self.even[k][c] + self.odd[k][c]) / n))
    }

    /// The means of the even and of the odd samples.
    pub fn halves(&self) -> (Image, Image) {
        let (ne, no) = (self.n_even().max(1) as f64, self.n_odd().max(1) as f64);
        (
            self.image_of(|k| self.even[k].map(|c| c / ne)),
            self.image_of(|k| self.odd[k].map(|c| c / no)),
        )
    }

    /// Estimated RMS noise of [`Accumulator::image`] (linear, all channels): RMS(even − odd)/2,
    /// exact in expectation for an even sample count. `None` below 2 samples.
    pub fn noise_rms(&self) -> Option<f64> {
        if self.spp < 2 {
            return None;
        }
        let (a, b) = self.halves();
        crate::metrics::rms(&a, &b).ok().map(|r| r / 2.0)
    }
}

/// The seed of sample `k` of pixel (x, y).
fn sample_seed(seed: u64, x: usize, y: usize, k: u32) -> u64 {
    let mut g = SplitMix64::new(
        seed ^ (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (k as u64).wrapping_mul(0x1656_67B1_9E37_79F9),
    );
    g.next_u64()
}

/// One pixel's index and the sums of its even and odd samples in a pass.
type PixelSums = (usize, [f64; 3], [f64; 3]);

/// Side of the square tiles rendered in parallel.
pub const TILE: usize = 16;

impl PathTracer<'_, '_> {
    /// Adds `samples` samples per pixel to `acc` through `camera`, tiles in parallel;
    /// `progress(tiles_done, tiles)` after each tile.
    pub fn render(
        &self,
        camera: &PathCamera,
        acc: &mut Accumulator,
        samples: u32,
        seed: u64,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) {
        let (w, h) = (acc.width, acc.height);
        let (tx, ty) = (w.div_ceil(TILE), h.div_ceil(TILE));
        let n_tiles = tx * ty;
        let first = acc.spp;
        let done = AtomicUsize::new(0);
        let tiles: Vec<Vec<PixelSums>> = (0..n_tiles)
            .into_par_iter()
            .map(|t| {
                let (x0, y0) = ((t % tx) * TILE, (t / tx) * TILE);
                let mut out = vec![];
                for y in y0..(y0 + TILE).min(h) {
                    for x in x0..(x0 + TILE).min(w) {
                        let (mut even, mut odd) = ([0.0; 3], [0.0; 3]);
                        for k in first..first + samples {
                            let mut rng = SplitMix64::new(sample_seed(seed, x, y, k));
                            let (jx, jy) = (rng.next_f64(), rng.next_f64());
                            let d = camera.direction(x as f64 + jx, y as f64 + jy, w, h);
                            let c = self.radiance(camera.origin, d, &mut rng);
                            let c = if c.is_finite() { c } else { Rgb::ZERO };
                            let dst = if k % 2 == 0 { &mut even } else { &mut odd };
                            for ch in 0..3 {
                                dst[ch] += c[ch];
                            }
                        }
                        out.push((y * w + x, even, odd));
                    }
                }
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, n_tiles);
                out
            })
            .collect();
        for tile in tiles {
            for (k, e, o) in tile {
                for c in 0..3 {
                    acc.even[k][c] += e[c];
                    acc.odd[k][c] += o[c];
                }
            }
        }
        acc.spp += samples;
    }
}
