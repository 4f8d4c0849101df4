//! The walkthrough frame on the CPU (000 §4, Fig. 4.1): at every camera hit, the light-mapped
//! diffuse term kd·E/π (000 Eq. 4.1) plus the view-dependent rest of the material integrated
//! against pre-filtered incident light: the probe of the object hit (else the room probes whose
//! boxes hold the point, two blended by depth, else the nearest probe: [`choose_probe`]), looked up through its
//! bounding planes (000 §4.4.1), or the environment when the scene has no
//! probe. The rest of the material, f − kd/π, is integrated by pushing a regular point set
//! (a Fibonacci lattice) through the material's own sampling warp, each sample read at the MIP
//! level of its cell, the solid angle 1/(n·pdf) ([`footprint_level`], the level the truth
//! harness measured for the Kurt row lattice); `Ck` draws the same number of random points and
//! reads Colbert–Křivánek's level (with their +1 bias); `Progressive` rotates the lattice frame
//! after frame (Cranley–Patterson, R2 offsets) and reads the level of the accumulated count, so
//! it converges to the integral of the same incident light (000 §4.4.2).
//!
//! Planar reflectors (meshes hinted `planar_reflector`) read a mirror buffer rendered for the
//! frame's camera ([`crate::mirror`], 000 §4.5) instead: each sample is projected into it by the
//! two tangent-plane intersections and read at the level of its footprint there; samples that
//! leave the buffer fall back to the probe or the environment. The Fibonacci lattice pushed
//! through the warp puts every sample on its own ring around the lobe centre, denser where the
//! lobe is stronger: the multi-ring pattern of 000 §4.5.3 (Fig. 4.33b) taken to one sample per
//! ring.
//!
//! This is the CPU frame the GPU renderer mirrors and the fallback when there is no adapter.

use crate::integrator::{corrected_direction, pixel_seed, BoundingPlane};
use crate::mip::{ck_level_at, footprint_level, FOOTPRINT_LEVEL_BIAS};
use crate::mirror::{
    mirror_camera, render_mirror_with_gbuffer, render_see_through_with_gbuffer, MirrorBuffer,
    ScreenTiles, ViewBuffer,
};
use crate::probe::{choose_probe, transmits, LitScene, Probe, ProbeChoice};
use crate::request::{FrameRequest, Method, MAX_WALKTHROUGH_SAMPLES};
use crate::warp::{fibonacci_point, integrate_warp};
use crate::{Result, ShadeError};
use glam::DVec3;
use glam::Vec2;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::SplitMix64;
use lustre_env::pyramid::CubePyramid;
use lustre_scene::{Material, MaterialKind, Scene};
use lustre_trace::accel::Hit;
use lustre_trace::bake::gbuffer::{shade_gbuffer, VisibilityBuffer, SKY};
use lustre_trace::bake::render::camera_ray;
use lustre_trace::image::Image;
use lustre_trace::path_tracer::PathCamera;
use rayon::prelude::*;

/// One cube read: the pyramid, its bounding planes and the shading point relative to its
/// centre.
type CubeRead<'a> = (&'a CubePyramid, &'a [BoundingPlane], DVec3);

/// The pre-filtered incident light of a frame: the probes, and the environment's pyramid for
/// scenes without probes.
pub struct FrameLight<'p> {
    /// Captured probes.
    pub probes: &'p [Probe],
    /// The environment, when no probe exists (distant light, no parallax).
    pub environment: Option<&'p CubePyramid>,
}

/// Per-frame counts.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// Camera rays that hit a surface with a glossy part.
    pub glossy_hits: u64,
    /// Filtered lookups made.
    pub lookups: u64,
    /// Mirror buffers rendered (one per planar reflector).
    pub mirrors: usize,
    /// See-through buffers rendered (one per transmissive probe object).
    pub see_throughs: usize,
    /// Time of the mirror and see-through passes, seconds.
    pub mirror_seconds: f64,
}

/// The per-frame view buffers and per-mesh tables the view-dependent shading reads: the mirror
/// buffer of every planar reflector and the see-through buffer of every transmissive probe
/// object (rendered for one camera), which probe each mesh reads, and the thin-sheet stand-ins
/// of smooth glass.
pub struct FrameBuffers {
    /// Mirror buffers, one per planar reflector.
    pub mirrors: Vec<MirrorBuffer>,
    /// Per mesh: its mirror buffer.
    pub mirror_of_mesh: Vec<Option<usize>>,
    /// See-through buffers, one per transmissive probe object.
    pub see_throughs: Vec<ViewBuffer>,
    /// Per mesh: its see-through buffer.
    pub see_through_of_mesh: Vec<Option<usize>>,
    /// Per mesh: the probe captured for it.
    pub probe_of_mesh: Vec<Option<usize>>,
    /// Per scene material: the thin sheet a smooth dielectric is shaded as.
    pub thin: Vec<Option<Material>>,
    /// Per mesh: the index of its first triangle in the path scene.
    pub first_prim: Vec<usize>,
    /// Time of the mirror and see-through passes, seconds.
    pub seconds: f64,
}

impl FrameBuffers {
    /// Renders the mirror and see-through buffers of `lit` for `camera` at w×h (000 §4.5.1) and
    /// builds the per-mesh tables for the probes of `light`.
    pub fn render(
        lit: &LitScene,
        light: &FrameLight,
        camera: &PathCamera,
        w: usize,
        h: usize,
    ) -> Result<Self> {
        let meshes = &lit.scene.meshes;
        let probe_of_mesh: Vec<Option<usize>> = (0..meshes.len())
            .map(|m| light.probes.iter().position(|p| p.mesh == Some(m as u32)))
            .collect();
        let (reflectors, transmissive) = view_meshes(lit);
        let t_mirror = std::time::Instant::now();
        let mut mirror_of_mesh = vec![None; meshes.len()];
        let mut mirrors = vec![];
        let mut mirror_gbuffers = vec![];
        for &m in &reflectors {
            mirror_of_mesh[m] = Some(mirrors.len());
            let (mirror, gb) = render_mirror_with_gbuffer(lit, m, camera, w, h)?;
            mirrors.push(mirror);
            mirror_gbuffers.push(gb);
        }
        let mut buffers = FrameBuffers {
            mirrors,
            mirror_of_mesh,
            see_throughs: vec![],
            see_through_of_mesh: vec![None; meshes.len()],
            probe_of_mesh,
            thin: lit.scene.materials.iter().map(thin_sheet).collect(),
            first_prim: first_prims(lit),
            seconds: 0.0,
        };
        // The mirror layers: what each mirror buffer shows gains its view-dependent part as the
        // mirrored camera sees it (a gold sphere reflected in a floor is no longer black), read
        // from the probes only.
        for (i, (gb, &m)) in mirror_gbuffers.iter().zip(&reflectors).enumerate() {
            let cam = mirror_camera(camera, &buffers.mirrors[i].plane);
            let tiles = ScreenTiles::of_mesh(lit, m, camera, w, h);
            let (layer, _) = shade_mirror_layer(lit, light, &buffers, &cam, gb, &tiles)?;
            buffers.mirrors[i].view.set_radiance(&layer.data);
        }
        // The see-through pass: the camera's view without each transmissive probe object, its
        // layer's view-dependent part shaded over the mirror buffers and probes.
        let mut see_throughs = vec![];
        for &m in &transmissive {
            let (mut view, gb) = render_see_through_with_gbuffer(lit, m, camera, w, h)?;
            let tiles = ScreenTiles::of_mesh(lit, m, camera, w, h);
            let (layer, _) = shade_see_through_layer(lit, light, &buffers, camera, &gb, &tiles)?;
            view.set_radiance(&layer.data);
            see_throughs.push(view);
        }
        for (i, &m) in transmissive.iter().enumerate() {
            buffers.see_through_of_mesh[m] = Some(i);
        }
        buffers.see_throughs = see_throughs;
        buffers.seconds = t_mirror.elapsed().as_secs_f64();
        Ok(buffers)
    }

    /// The same probe table without view buffers: what a mirror layer reads
    /// ([`shade_mirror_layer`]).
    pub fn probes_only(&self) -> FrameBuffers {
        let n = self.probe_of_mesh.len();
        FrameBuffers {
            mirrors: vec![],
            mirror_of_mesh: vec![None; n],
            see_throughs: vec![],
            see_through_of_mesh: vec![None; n],
            probe_of_mesh: self.probe_of_mesh.clone(),
            thin: self.thin.clone(),
            first_prim: self.first_prim.clone(),
            seconds: 0.0,
        }
    }

    /// The per-mesh tables of these buffers (what a GPU pass needs besides the buffers).
    pub fn tables(&self) -> FrameTables {
        FrameTables {
            probe_of_mesh: self.probe_of_mesh.clone(),
            mirror_of_mesh: self.mirror_of_mesh.clone(),
            in_plane: self
                .mirrors
                .iter()
                .map(|m| m.reflector.in_plane.clone())
                .collect(),
            see_through_of_mesh: self.see_through_of_mesh.clone(),
            see_throughs: self.see_throughs.len(),
            first_prim: self.first_prim.clone(),
        }
    }

    /// The mirror buffer that answers triangle `prim` of mesh `mesh` (an in-plane triangle of a
    /// planar reflector).
    pub fn mirror_at(&self, mesh: usize, prim: usize) -> Option<&MirrorBuffer> {
        self.mirror_of_mesh[mesh]
            .map(|i| &self.mirrors[i])
            .filter(|m| m.reflector.in_plane[prim - self.first_prim[mesh]])
    }
}

/// Which buffer and probe each mesh reads, without the buffers themselves: the tables of
/// [`FrameBuffers`] ([`FrameBuffers::tables`]) or of view buffers rendered elsewhere (the GPU).
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTables {
    /// Per mesh: the probe captured for it.
    pub probe_of_mesh: Vec<Option<usize>>,
    /// Per mesh: its mirror buffer.
    pub mirror_of_mesh: Vec<Option<usize>>,
    /// Per mirror buffer: which of its reflector's triangles lie in the plane.
    pub in_plane: Vec<Vec<bool>>,
    /// Per mesh: its see-through buffer.
    pub see_through_of_mesh: Vec<Option<usize>>,
    /// See-through buffers.
    pub see_throughs: usize,
    /// Per mesh: the index of its first triangle in the path scene.
    pub first_prim: Vec<usize>,
}

impl FrameTables {
    /// The tables of `lit` for probes of meshes `probe_meshes` (`None`: a room probe) and
    /// mirrors of the reflectors `in_plane` ((mesh, in-plane triangles), in [`view_meshes`]'
    /// order).
    pub fn new(
        lit: &LitScene,
        probe_meshes: &[Option<u32>],
        in_plane: Vec<(usize, Vec<bool>)>,
    ) -> Self {
        let n = lit.scene.meshes.len();
        let mut mirror_of_mesh = vec![None; n];
        for (i, (m, _)) in in_plane.iter().enumerate() {
            mirror_of_mesh[*m] = Some(i);
        }
        let mut see_through_of_mesh = vec![None; n];
        let (_, transmissive) = view_meshes(lit);
        for (i, &m) in transmissive.iter().enumerate() {
            see_through_of_mesh[m] = Some(i);
        }
        FrameTables {
            probe_of_mesh: (0..n)
                .map(|m| probe_meshes.iter().position(|&p| p == Some(m as u32)))
                .collect(),
            mirror_of_mesh,
            in_plane: in_plane.into_iter().map(|(_, v)| v).collect(),
            see_through_of_mesh,
            see_throughs: transmissive.len(),
            first_prim: first_prims(lit),
        }
    }

    /// Mirror buffers.
    pub fn mirrors(&self) -> usize {
        self.in_plane.len()
    }

    /// The mirror buffer that answers triangle `prim` of mesh `mesh`.
    pub fn mirror_at(&self, mesh: usize, prim: usize) -> Option<usize> {
        self.mirror_of_mesh[mesh].filter(|&i| self.in_plane[i][prim - self.first_prim[mesh]])
    }
}

/// The meshes that get view buffers, in buffer order: the planar reflectors (a mirror buffer
/// each) and the transmissive probe objects (a see-through buffer each).
pub fn view_meshes(lit: &LitScene) -> (Vec<usize>, Vec<usize>) {
    let meshes = &lit.scene.meshes;
    let reflectors = (0..meshes.len())
        .filter(|&m| meshes[m].hints.planar_reflector)
        .collect();
    let transmissive = (0..meshes.len())
        .filter(|&m| meshes[m].hints.probe && transmits(lit.scene, meshes[m].material))
        .collect();
    (reflectors, transmissive)
}

/// Per mesh: the index of its first triangle in the path scene.
fn first_prims(lit: &LitScene) -> Vec<usize> {
    lustre_trace::setup::mesh_prims(lit.scene)
        .into_iter()
        .map(|r| r.start)
        .collect()
}

/// Smooth glass is shaded as a thin sheet (straight through, both interfaces' Fresnel): a pane
/// or a rail seen through, as the thin BTDF lobes of 000 §3.3.1.
pub fn thin_sheet(m: &Material) -> Option<Material> {
    match &m.kind {
        MaterialKind::Dielectric {
            int_ior,
            ext_ior,
            specular_reflectance,
            specular_transmittance,
        } => Some(Material::new(
            m.name.clone(),
            MaterialKind::ThinDielectric {
                int_ior: *int_ior,
                ext_ior: *ext_ior,
                specular_reflectance: *specular_reflectance,
                specular_transmittance: *specular_transmittance,
            },
        )),
        _ => None,
    }
}

/// A camera hit as the view-dependent shading sees it.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    /// Triangle (path-scene index).
    pub prim: usize,
    /// Barycentric weights.
    pub bary: [f64; 3],
    /// Direction of the camera ray (unit).
    pub d: DVec3,
}

/// The points of one pixel's glossy integral.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FramePoints {
    /// The regular set ([`fibonacci_point`]).
    Regular,
    /// Colbert–Křivánek: n random points drawn from `SplitMix64::new(seed)` ([`ck_point`]).
    Ck {
        /// The pixel's seed.
        seed: u64,
    },
    /// Progressive refinement: frames `0..frames` of the R2-rotated regular set, averaged.
    Progressive {
        /// The first frame.
        first: u32,
        /// Frames averaged.
        frames: u32,
    },
}

/// Point i of the Colbert–Křivánek set: two [`SplitMix64`] draws, each the top 24 bits of its
/// 64 (so that an f32 GPU twin draws the same points exactly).
pub fn ck_point(rng: &mut SplitMix64) -> (f64, f64) {
    let scale = 1.0 / 16_777_216.0;
    let a = (rng.next_u64() >> 40) as f64 * scale;
    let b = (rng.next_u64() >> 40) as f64 * scale;
    (a, b)
}

/// Point i of frame f of progressive refinement: the [`fibonacci_point`] shifted by frame f's
/// R2 offset modulo 1 (the second coordinate on the 2⁻²⁴ grid, so an f32 twin matches bits).
pub fn progressive_point(i: usize, n: usize, f: usize) -> (f64, f64) {
    let (u, v) = fibonacci_point(i, n);
    let (ou, ov) = r2_bits(f);
    let v24 = (v * 16_777_216.0) as u32;
    (
        (u + f64::from(ou) / 16_777_216.0).fract(),
        f64::from(v24.wrapping_add(ov) & 0xff_ffff) / 16_777_216.0,
    )
}

/// The thickness and relative index of refraction of mesh `mesh` as a solid slab: its
/// `thickness` hint (the automatic set-up writes it for solid glass) and its material's index
/// (interior / exterior for the dielectrics, glTF's `ior`, else 1.5). `None` without the hint.
pub fn slab_of(scene: &Scene, mesh: usize) -> Option<(f64, f64)> {
    let m = scene.meshes.get(mesh)?;
    let t = m.hints.thickness.filter(|t| *t > 0.0 && t.is_finite())?;
    let eta = match scene.materials.get(m.material).map(|x| &x.kind) {
        Some(
            MaterialKind::Dielectric {
                int_ior, ext_ior, ..
            }
            | MaterialKind::RoughDielectric {
                int_ior, ext_ior, ..
            }
            | MaterialKind::ThinDielectric {
                int_ior, ext_ior, ..
            },
        ) => *int_ior / *ext_ior,
        Some(MaterialKind::PbrMetallicRoughness { ior, .. }) => *ior,
        _ => 1.5,
    };
    (eta.is_finite() && eta > 0.0).then_some((t, eta))
}

/// The refraction offset of a solid slab (the see-through buffer of 000 §4.5 is a thin sheet's):
/// a ray along `wi` entering a slab of thickness `t` and relative index `eta` through a face
/// with normal `n` (either orientation) bends to sin θt = sin θi / η and leaves the far face
/// displaced within the faces' plane, from where the straight ray would have crossed, by
/// δ = t · w⊥ · (1 / (η cos θt) − 1 / cos θi), w⊥ = wi − (wi·n) n (the lateral shift
/// t sin θi (1 − cos θi / (η cos θt)) across the ray); continuing along `wi` from there, the
/// sample reads the see-through buffer from p + δ. Zero at grazing incidence, where no ray
/// enters, or for η ≤ 0.
pub fn slab_offset(t: f64, eta: f64, n: DVec3, wi: DVec3) -> DVec3 {
    let c = wi.dot(n).abs();
    let perp = wi - wi.dot(n) * n;
    let s2 = perp.length_squared() / (eta * eta);
    if !(c > 1e-6 && eta > 0.0 && s2 < 1.0) {
        return DVec3::ZERO;
    }
    perp * (t * (1.0 / (eta * (1.0 - s2).sqrt()) - 1.0 / c))
}

/// The view-dependent radiance at camera hit `hit` of `lit` (000 Eq. 4.4): the material's rest
/// f − kd/π (kd the light-mapped albedo) integrated with `n` samples of `points`, each read from
/// the mirror buffer of an in-plane reflector triangle, the see-through buffer of a
/// transmissive probe object (unless `see_through` is false: a see-through layer's own
/// shading), the probe of the object (else [`choose_probe`]'s, through its bounding planes) or
/// the environment's pyramid. Returns the radiance (zero where nothing is view-dependent), the
/// lookups made and whether the hit has a view-dependent part.
pub fn view_dependent(
    lit: &LitScene,
    light: &FrameLight,
    buffers: &FrameBuffers,
    hit: &SurfaceHit,
    n: usize,
    points: FramePoints,
    see_through: bool,
) -> (Rgb, u64, bool) {
    let ps = lit.path_scene;
    let g = &ps.geometry;
    let d = hit.d;
    let mesh = lit.mesh_of[hit.prim] as usize;
    if lit.scene.meshes[mesh].hints.diffuse_only {
        return (Rgb::ZERO, 0, false);
    }
    let k = g.material[hit.prim] as usize;
    let surface = &ps.materials[k];
    let kd = lit.lit.albedo(g, hit.prim, hit.bary, d);
    let h = Hit {
        prim: hit.prim,
        bary: hit.bary,
        t: 1.0,
    };
    let (p, frame, uv) = lit.tracer.shading_point(DVec3::ZERO, d, &h);
    let wo = -d;
    let frame = if surface.two_sided() && wo.dot(frame.n) < 0.0 {
        frame.flipped()
    } else {
        frame
    };
    let wo_local = frame.to_local(wo);
    // The incident light: this object's probe, else the room probes whose boxes hold the point
    // (the two deepest blended), else the nearest probe, else the environment.
    let choice = match buffers.probe_of_mesh[mesh] {
        Some(i) => Some(ProbeChoice {
            probe: i,
            blend: None,
        }),
        None => choose_probe(
            light
                .probes
                .iter()
                .map(|q| (q.centre, &q.planes[..], q.mesh.is_none())),
            p,
        ),
    };
    let cube = |i: usize| -> CubeRead<'_> {
        let pr = &light.probes[i];
        (&pr.pyramid, &pr.planes[..], p - pr.centre)
    };
    let env_light: Option<(CubeRead, Option<(CubeRead, f64)>)> = match choice {
        Some(c) => Some((cube(c.probe), c.blend.map(|(j, w)| (cube(j), w)))),
        None => light
            .environment
            .map(|env| ((env, &[][..], DVec3::ZERO), None)),
    };
    // The mirror buffer, for the reflector's in-plane triangles.
    let mirror = buffers.mirror_at(mesh, hit.prim);
    let see_through = buffers.see_through_of_mesh[mesh]
        .filter(|_| see_through)
        .map(|i| &buffers.see_throughs[i]);
    if env_light.is_none() && mirror.is_none() && see_through.is_none() {
        return (Rgb::ZERO, 0, false);
    }
    // A solid slab's thickness and relative index: what shows through it is read from the
    // point its refraction offset moves the sample to.
    let slab = see_through.and_then(|_| slab_of(lit.scene, mesh));
    // A view buffer's filtered radiance for a sample from `o` along `wi` (None when it leaves
    // it).
    let read_view =
        |v: &ViewBuffer, o: DVec3, wi: DVec3, pdf: Option<f64>, total: usize, ck: bool| {
            let ((x, y), found) = v.locate(o, wi)?;
            let lod = pdf.map_or(0.0, |pd| {
                let bias = if ck { 1.0 } else { FOOTPRINT_LEVEL_BIAS };
                v.level(o, wi, found, 1.0 / (total as f64 * pd), bias)
            });
            Some(v.sample(x, y, lod))
        };
    // The filtered radiance of a sample along `wi` drawn with density `pdf` (None: Dirac) out
    // of `total`; `ck` picks Colbert–Křivánek's level instead of the footprint's.
    let fetch = |wi: DVec3, pdf: Option<f64>, total: usize, ck: bool| -> Rgb {
        if let Some(m) = mirror {
            if let Some(c) = read_view(&m.view, p, wi, pdf, total, ck) {
                return c;
            }
        }
        if let Some(v) = see_through {
            if wi.dot(frame.n) * wo.dot(frame.n) < 0.0 {
                let o = slab.map_or(p, |(t, eta)| p + slab_offset(t, eta, frame.n, wi));
                if let Some(c) = read_view(v, o, wi, pdf, total, ck) {
                    return c;
                }
            }
        }
        let read_cube = |(pyramid, planes, rel): CubeRead| -> Rgb {
            let face = pyramid.base_size();
            let lod = pdf.map_or(0.0, |pd| {
                if ck {
                    ck_level_at(pd, total, face, wi)
                } else {
                    footprint_level(1.0 / (total as f64 * pd), wi, face)
                }
            });
            let dir = if planes.is_empty() {
                wi
            } else {
                corrected_direction(planes, rel, wi)
            };
            Rgb(pyramid.sample(dir, lod))
        };
        match env_light {
            Some((first, None)) => read_cube(first),
            Some((first, Some((second, w)))) => {
                read_cube(first) * (1.0 - w) + read_cube(second) * w
            }
            None => ps.environment.as_ref().map_or(Rgb::ZERO, |e| e.eval(wi)),
        }
    };
    let mut glossy = Rgb::ZERO;
    let mut lookups = 0u64;
    let with_bsdf = |f: &mut dyn FnMut(&dyn Bsdf)| match &buffers.thin[k] {
        Some(m) => {
            let uv2 = [Vec2::new(uv[0] as f32, uv[1] as f32); 2];
            if m.with_bsdf_at(&lit.scene.textures, &uv2, &mut *f).is_err() {
                surface.with_bsdf(uv, f);
            }
        }
        None => surface.with_bsdf(uv, f),
    };
    let mut is_view_dependent = true;
    with_bsdf(&mut |bsdf| {
        // A Lambertian surface the light map covers has no view-dependent part left.
        if bsdf.flags().diffuse_only() && kd != Rgb::ZERO {
            is_view_dependent = false;
            return;
        }
        let to_world = |v: DVec3| frame.to_world(v);
        match points {
            FramePoints::Regular => {
                let (c, k) = integrate_warp(
                    bsdf,
                    kd,
                    to_world,
                    wo_local,
                    n,
                    |i| fibonacci_point(i, n),
                    |wi, pdf| fetch(wi, pdf, n, false),
                );
                glossy = c;
                lookups = k as u64;
            }
            FramePoints::Ck { seed } => {
                let mut rng = SplitMix64::new(seed);
                let pts: Vec<(f64, f64)> = (0..n).map(|_| ck_point(&mut rng)).collect();
                let (c, k) = integrate_warp(
                    bsdf,
                    kd,
                    to_world,
                    wo_local,
                    n,
                    |i| pts[i],
                    |wi, pdf| fetch(wi, pdf, n, true),
                );
                glossy = c;
                lookups = k as u64;
            }
            FramePoints::Progressive { first, frames } => {
                // Frame f: the set rotated by an R2 offset; the level of the accumulated count
                // (f + 1)·n, so the filtering shrinks as frames accumulate.
                let mut acc = Rgb::ZERO;
                for f in first as usize..(first + frames) as usize {
                    let total = n * (f + 1);
                    let (c, k) = integrate_warp(
                        bsdf,
                        kd,
                        to_world,
                        wo_local,
                        n,
                        |i| progressive_point(i, n, f),
                        |wi, pdf| fetch(wi, pdf, total, false),
                    );
                    acc += c;
                    lookups += k as u64;
                }
                glossy = acc * (1.0 / f64::from(frames.max(1)));
            }
        }
    });
    if !glossy.is_finite() {
        glossy = Rgb::ZERO;
    }
    (glossy.map(|c| c.max(0.0)), lookups, is_view_dependent)
}

/// The glossy samples of triangle `prim`: its object's own budget
/// (`ObjectHints::samples`, clamped to 1..=[`MAX_WALKTHROUGH_SAMPLES`]) or the frame's `n`.
pub fn object_samples(lit: &LitScene, prim: usize, n: usize) -> usize {
    lit.mesh_of
        .get(prim)
        .and_then(|&m| lit.scene.meshes.get(m as usize))
        .and_then(|m| m.hints.samples)
        .map_or(n, |s| {
            (s as usize).clamp(1, MAX_WALKTHROUGH_SAMPLES as usize)
        })
}

/// The request validated ([`FrameRequest::validate`]) and of a walkthrough method (regular, CK,
/// progressive).
pub fn walkthrough_request(req: &FrameRequest) -> Result<()> {
    req.validate()?;
    if !req.method.walkthrough() {
        return Err(ShadeError::Parameter(format!(
            "the {} method is not one of the walkthrough's (regular, ck, progressive)",
            req.method.name()
        )));
    }
    Ok(())
}

/// Renders a w×h frame of `lit` at `camera` with the incident light `light`.
pub fn render_frame(
    lit: &LitScene,
    light: &FrameLight,
    camera: &PathCamera,
    w: usize,
    h: usize,
    req: &FrameRequest,
) -> Result<(Image, FrameStats)> {
    walkthrough_request(req)?;
    if w == 0 || h == 0 {
        return Err(ShadeError::Parameter(format!("image {w}×{h} is empty")));
    }
    let buffers = FrameBuffers::render(lit, light, camera, w, h)?;
    let ps = lit.path_scene;
    let g = &ps.geometry;
    let n = req.samples as usize;
    let shade = |o: DVec3, d: DVec3, rng: &mut SplitMix64| -> (Rgb, u64, bool) {
        let Some(hit) = lit.tracer.intersect(o, d) else {
            return (
                ps.environment.as_ref().map_or(Rgb::ZERO, |e| e.eval(d)),
                0,
                false,
            );
        };
        let l = lit.lit.radiance(g, hit.prim, hit.bary, d);
        let points = match req.method {
            Method::Ck => FramePoints::Ck {
                seed: rng.next_u64(),
            },
            Method::Progressive => FramePoints::Progressive {
                first: 0,
                frames: req.frames,
            },
            _ => FramePoints::Regular,
        };
        let surface = SurfaceHit {
            prim: hit.prim,
            bary: hit.bary,
            d,
        };
        let n = object_samples(lit, hit.prim, n);
        let (glossy, lookups, vd) = view_dependent(lit, light, &buffers, &surface, n, points, true);
        (l + glossy, lookups, vd)
    };
    let seed = req.seed;
    let spp = req.rays;
    let rows: Vec<([f32; 3], u64, u64)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = Rgb::ZERO;
            let (mut hits, mut lookups) = (0u64, 0u64);
            for k in 0..spp {
                let (d, mut rng) = camera_ray(camera, seed, (x, y), (w, h), k);
                let (c, n, glossy) = shade(camera.origin, d, &mut rng);
                if c.is_finite() {
                    sum += c;
                }
                hits += u64::from(glossy);
                lookups += n;
            }
            ((sum / f64::from(spp)).0.map(|c| c as f32), hits, lookups)
        })
        .collect();
    let mut stats = FrameStats {
        mirrors: buffers.mirrors.len(),
        see_throughs: buffers.see_throughs.len(),
        mirror_seconds: buffers.seconds,
        ..FrameStats::default()
    };
    let data = rows
        .into_iter()
        .map(|(c, hits, n)| {
            stats.glossy_hits += hits;
            stats.lookups += n;
            c
        })
        .collect();
    Ok((Image::from_data(w, h, data)?, stats))
}

/// The light-mapped G-buffer shading ([`shade_gbuffer`]) plus the view-dependent part
/// ([`view_dependent`]) of every G-buffer pixel, k×k G-buffer pixels box-averaged into each of
/// the w×h output pixels: the CPU twin of lustre-gpu's view-dependent pass. The rays are the
/// G-buffer pixel centres' (as [`shade_gbuffer`]); CK seeds pixel (x, y) of the G-buffer with
/// [`pixel_seed`]`(x, y, seed)`; `frame` is the progressive frame shaded (frames `0..=frame`
/// averaged when `accumulate`, else frame `frame` alone). Errors as [`shade_gbuffer`], and on
/// a request [`walkthrough_request`] refuses.
pub fn shade_gbuffer_view_dependent(
    lit: &LitScene,
    light: &FrameLight,
    buffers: &FrameBuffers,
    camera: &PathCamera,
    gb: &VisibilityBuffer,
    k: u32,
    req: &FrameRequest,
) -> Result<(Image, FrameStats)> {
    shade_gbuffer_region(lit, light, buffers, camera, gb, k, req, None, true)
}

/// Glossy samples per texel of a see-through layer ([`shade_see_through_layer`]).
pub const SEE_THROUGH_SAMPLES: usize = 8;

/// The see-through layer (the Modern Hall's glass rail): what a transmissive probe
/// object's see-through buffer shows, light-mapped plus its own view-dependent part. A surface
/// seen through glass is seen from the same camera, so the frame's mirror buffers and probes
/// answer its samples as they answer the surfaces seen directly; see-through buffers are not
/// read (no glass behind glass: what shows there is light-mapped). The light-mapped shading of
/// the w×h G-buffer `gb` (k = 1, the see-through buffer's rays) plus the view-dependent part
/// with [`SEE_THROUGH_SAMPLES`] regular samples, only for the pixels in the covered `tiles`
/// ([`ScreenTiles::of_mesh`]: where the object's samples read; light-mapped only
/// elsewhere). The layer belongs to the camera, like the mirror buffers: the same for every
/// method and progressive frame. The CPU twin of lustre-gpu's see-through layer pass.
pub fn shade_see_through_layer(
    lit: &LitScene,
    light: &FrameLight,
    buffers: &FrameBuffers,
    camera: &PathCamera,
    gb: &VisibilityBuffer,
    tiles: &ScreenTiles,
) -> Result<(Image, FrameStats)> {
    let req = layer_request();
    shade_gbuffer_region(lit, light, buffers, camera, gb, 1, &req, Some(tiles), false)
}

/// What a view buffer's layer is shaded with ([`shade_see_through_layer`],
/// [`shade_mirror_layer`]): [`SEE_THROUGH_SAMPLES`] regular samples, one ray, one frame.
pub fn layer_request() -> FrameRequest {
    FrameRequest {
        method: Method::Regular,
        samples: SEE_THROUGH_SAMPLES as u32,
        rays: 1,
        frames: 1,
        seed: 0,
    }
}

/// The mirror layer (000 §4.5.1 shades mirror buffers diffuse only): what a mirror buffer
/// shows, light-mapped plus its own view-dependent part as the mirrored camera `camera` sees it
/// in the covered `tiles` (the reflector's screen rectangle as the real camera sees it, widened:
/// mirror pixel (x, y) is the reflection of the real camera's pixel (x, y)), from its w×h
/// G-buffer `gb` with [`SEE_THROUGH_SAMPLES`] regular samples, read from the probes
/// of `buffers` (its view buffers are not read: they belong to the real camera). The CPU twin of
/// lustre-gpu's mirror layer pass.
pub fn shade_mirror_layer(
    lit: &LitScene,
    light: &FrameLight,
    buffers: &FrameBuffers,
    camera: &PathCamera,
    gb: &VisibilityBuffer,
    tiles: &ScreenTiles,
) -> Result<(Image, FrameStats)> {
    let req = layer_request();
    let plain = buffers.probes_only();
    shade_gbuffer_region(lit, light, &plain, camera, gb, 1, &req, Some(tiles), false)
}

/// [`shade_gbuffer_view_dependent`] with the view-dependent part only in the output pixels of
/// the covered `tiles` (all when `None`) and see-through buffers read only when `see_through`.
#[allow(clippy::too_many_arguments)]
fn shade_gbuffer_region(
    lit: &LitScene,
    light: &FrameLight,
    buffers: &FrameBuffers,
    camera: &PathCamera,
    gb: &VisibilityBuffer,
    k: u32,
    req: &FrameRequest,
    tiles: Option<&ScreenTiles>,
    see_through: bool,
) -> Result<(Image, FrameStats)> {
    let ps = lit.path_scene;
    let g = &ps.geometry;
    let base = shade_gbuffer(lit.lit, g, ps.environment.as_ref(), camera, gb, k)?;
    walkthrough_request(req)?;
    let n = req.samples as usize;
    let ku = k as usize;
    let (w, h) = (base.width, base.height);
    let rows: Vec<([f32; 3], u64, u64)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let mut sum = Rgb::ZERO;
            let (mut hits, mut lookups) = (0u64, 0u64);
            if tiles.is_some_and(|t| !t.covers(x, y)) {
                return ([0.0; 3], 0, 0);
            }
            for j in 0..ku {
                for s in 0..ku {
                    let (gx, gy) = (x * ku + s, y * ku + j);
                    let gi = gy * gb.width + gx;
                    let prim = gb.prim[gi];
                    if prim == SKY {
                        continue;
                    }
                    let d = camera.direction(gx as f64 + 0.5, gy as f64 + 0.5, gb.width, gb.height);
                    let [b1, b2] = gb.bary[gi].map(f64::from);
                    let hit = SurfaceHit {
                        prim: prim as usize,
                        bary: [1.0 - b1 - b2, b1, b2],
                        d,
                    };
                    let points = match req.method {
                        Method::Ck => FramePoints::Ck {
                            seed: pixel_seed(gx, gy, req.seed),
                        },
                        Method::Progressive => FramePoints::Progressive {
                            first: 0,
                            frames: req.frames,
                        },
                        _ => FramePoints::Regular,
                    };
                    let (c, l, vd) = view_dependent(
                        lit,
                        light,
                        buffers,
                        &hit,
                        object_samples(lit, prim as usize, n),
                        points,
                        see_through,
                    );
                    sum += c;
                    hits += u64::from(vd);
                    lookups += l;
                }
            }
            let c = (sum / (ku * ku) as f64).0.map(|c| c as f32);
            (c, hits, lookups)
        })
        .collect();
    let mut stats = FrameStats {
        mirrors: buffers.mirrors.len(),
        see_throughs: buffers.see_throughs.len(),
        mirror_seconds: buffers.seconds,
        ..FrameStats::default()
    };
    let data = rows
        .into_iter()
        .zip(&base.data)
        .map(|((c, hits, n), b)| {
            stats.glossy_hits += hits;
            stats.lookups += n;
            std::array::from_fn(|ch| b[ch] + c[ch])
        })
        .collect();
    Ok((Image::from_data(w, h, data)?, stats))
}

/// The f-th point of the R2 sequence (Roberts 2018), the per-frame rotation of the set, on the
/// 2⁻²⁴ grid: (f·a1, f·a2) mod 1 with a1, a2 = 1/g, 1/g² (g the plastic number) rounded to
/// 24 bits.
pub fn r2_bits(f: usize) -> (u32, u32) {
    const A1: u32 = 12_664_746;
    const A2: u32 = 9_560_334;
    let f = f as u32;
    (
        f.wrapping_mul(A1) & 0xff_ffff,
        f.wrapping_mul(A2) & 0xff_ffff,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slab_offset_is_where_the_refracted_ray_leaves() {
        // A slab between z = 0 and z = −t, entered at the origin: Snell's law traced through
        // it, and the straight ray along wi that meets the same exit point starts at δ.
        let t = 0.04;
        for eta in [1.33, 1.5, 2.4] {
            for deg in [0.0f64, 10.0, 30.0, 45.0, 60.0, 80.0, 89.0] {
                let th = deg.to_radians();
                let phi = 0.7f64;
                let wi = DVec3::new(th.sin() * phi.cos(), th.sin() * phi.sin(), -th.cos());
                let perp_t = DVec3::new(wi.x, wi.y, 0.0) / eta;
                let wt = DVec3::new(perp_t.x, perp_t.y, -(1.0 - perp_t.length_squared()).sqrt());
                let exit = wt * (t / -wt.z);
                let expect = exit - wi * (t / -wi.z);
                for n in [DVec3::Z, -DVec3::Z] {
                    let d = slab_offset(t, eta, n, wi);
                    assert!(
                        (d - expect).length() < 1e-12,
                        "η {eta} θ {deg}°: {d} vs {expect}"
                    );
                    assert!(d.z.abs() < 1e-15, "in the faces' plane");
                }
                // The lateral shift across the ray: t sin θ (1 − cos θ / (η cos θt)).
                let ct = (1.0 - (th.sin() / eta).powi(2)).sqrt();
                let lateral = t * th.sin() * (1.0 - th.cos() / (eta * ct));
                let got = slab_offset(t, eta, DVec3::Z, wi);
                let across = (got - wi * got.dot(wi)).length();
                assert!((across - lateral).abs() < 1e-12, "{across} vs {lateral}");
            }
        }
        // Grazing, or no slab: no offset.
        assert_eq!(slab_offset(t, 1.5, DVec3::Z, DVec3::X), DVec3::ZERO);
        assert_eq!(slab_offset(t, 0.0, DVec3::Z, -DVec3::Z), DVec3::ZERO);
    }
}
