//! Reflection probes (000 §4.4): the incident light of a curved glossy object, captured as a
//! cube map at the object's centre from the light-mapped scene with the object itself left out,
//! filtered into 002's Gaussian 6×6 pyramid, and looked up through bounding planes that correct
//! for the parallax between the centre and the shaded point (000 §4.4.1, Fig. 4.5–4.6). Room
//! probes ([`lustre_scene::ProbeSite`]) are the same captured at a point of the free space, with
//! the room's box as their planes; [`choose_probe`] says which probe a point without its own
//! reads. Probe rays look through transmitting surfaces ([`LitScene::hit`]).
//!
//! This is the CPU definition of the probe; the GPU capture renders the same cube.

use crate::integrator::BoundingPlane;
use crate::{Result, ShadeError};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_env::cube::{face_point, CubeMap, MAX_FACE_SIZE};
use lustre_env::pyramid::{CubePyramid, MipFilter};
use lustre_scene::Scene;
use lustre_trace::accel::Hit;
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::path_tracer::{PathScene, PathTracer};
use lustre_trace::setup::{axis_distances, mesh_prims, Surroundings, AXES};
use rayon::prelude::*;

/// The light-mapped scene as rays see it: the diffuse path scene's triangles (for intersection),
/// their light-mapped radiance, and which mesh each triangle came from.
pub struct LitScene<'a, 's> {
    /// The scene.
    pub scene: &'s Scene,
    /// Its triangles and materials ([`lustre_trace::bake::diffuse_path_scene`]).
    pub path_scene: &'a PathScene<'s>,
    /// The tracer over `path_scene`.
    pub tracer: &'a PathTracer<'a, 's>,
    /// The light-mapped radiance of every triangle.
    pub lit: &'a Lightmapped<'s>,
    /// Mesh index of every triangle, in the path scene's order.
    pub mesh_of: Vec<u32>,
    /// Per triangle: its material transmits ([`transmits`]); the rays of probes and view
    /// buffers pass through it (a window shows the sky behind it, not a black pane).
    pub see_through: Vec<bool>,
}

/// Whether material `m` of `scene` transmits light (glass, frosted or smooth): the objects that
/// get a see-through pass, and the surfaces probe and view-buffer rays pass through.
pub fn transmits(scene: &Scene, m: usize) -> bool {
    scene.materials.get(m).is_some_and(|mat| {
        mat.bsdf_at(&scene.textures, &[glam::Vec2::ZERO; 2])
            .is_ok_and(|b| b.flags().transmission)
    })
}

impl<'a, 's> LitScene<'a, 's> {
    /// Bundles the parts; the triangles of `path_scene` must be `scene`'s meshes in order (as
    /// [`lustre_trace::reference::path_scene`] lists them).
    pub fn new(
        scene: &'s Scene,
        path_scene: &'a PathScene<'s>,
        tracer: &'a PathTracer<'a, 's>,
        lit: &'a Lightmapped<'s>,
    ) -> Result<Self> {
        let mesh_of: Vec<u32> = scene
            .meshes
            .iter()
            .enumerate()
            .flat_map(|(k, m)| std::iter::repeat_n(k as u32, m.indices.len()))
            .collect();
        if mesh_of.len() != path_scene.geometry.positions.len() {
            return Err(ShadeError::Parameter(format!(
                "{}: {} triangles in the meshes but {} in the path scene",
                scene.source.display(),
                mesh_of.len(),
                path_scene.geometry.positions.len()
            )));
        }
        let glass: Vec<bool> = (0..scene.materials.len())
            .map(|m| transmits(scene, m))
            .collect();
        let see_through = path_scene
            .geometry
            .material
            .iter()
            .map(|&m| glass.get(m as usize).copied().unwrap_or(false))
            .collect();
        Ok(LitScene {
            scene,
            path_scene,
            tracer,
            lit,
            mesh_of,
            see_through,
        })
    }

    /// The first surface along o + t d that does not transmit, ignoring the triangles of mesh
    /// `skip`: what probes and view buffers see (glass is looked through; the camera's own rays
    /// see it and shade it with its see-through buffer).
    pub fn hit(&self, o: DVec3, d: DVec3, skip: Option<u32>) -> Option<Hit> {
        let m = skip.unwrap_or(u32::MAX);
        self.tracer
            .intersect_filtered(o, d, |p| self.see_through[p] || self.mesh_of[p] == m)
    }

    /// Radiance arriving at `o` from direction `d` (towards −`d`): the light-mapped surface
    /// first hit, ignoring the triangles of mesh `skip`, or the environment.
    pub fn radiance(&self, o: DVec3, d: DVec3, skip: Option<u32>) -> Rgb {
        match self.hit(o, d, skip) {
            Some(h) => self
                .lit
                .radiance(&self.path_scene.geometry, h.prim, h.bary, d),
            None => self
                .path_scene
                .environment
                .as_ref()
                .map_or(Rgb::ZERO, |e| e.eval(d)),
        }
    }

    /// Distance from `o` along `d` to the first surface, ignoring mesh `skip`.
    pub fn distance(&self, o: DVec3, d: DVec3, skip: Option<u32>) -> Option<f64> {
        self.hit(o, d, skip).map(|h| h.t)
    }

    /// World bounds of mesh `m` (min, max).
    pub fn mesh_bounds(&self, m: usize) -> Option<(DVec3, DVec3)> {
        let mesh = self.scene.meshes.get(m)?;
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in &mesh.positions {
            let p = p.as_dvec3();
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
    }
}

/// How a probe is captured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeOptions {
    /// Cube face size in texels (level 0).
    pub face_size: usize,
    /// Rays per texel edge: s² stratified rays per texel, box-filtered.
    pub supersample: u32,
    /// Rays per axis direction used to place the automatic bounding planes.
    pub plane_rays: u32,
}

impl Default for ProbeOptions {
    fn default() -> Self {
        ProbeOptions {
            face_size: 128,
            supersample: 2,
            plane_rays: 64,
        }
    }
}

impl ProbeOptions {
    /// Errors on a face size of 0 or beyond [`MAX_FACE_SIZE`], a supersampling of 0 or above
    /// 16, or no plane rays.
    pub fn validate(&self) -> Result<()> {
        if self.face_size == 0 || self.face_size > MAX_FACE_SIZE {
            return Err(ShadeError::Parameter(format!(
                "probe face size {} is outside 1..={MAX_FACE_SIZE}",
                self.face_size
            )));
        }
        if !(1..=16).contains(&self.supersample) {
            return Err(ShadeError::Parameter(format!(
                "probe supersampling {} is outside 1..=16",
                self.supersample
            )));
        }
        if self.plane_rays == 0 {
            return Err(ShadeError::Parameter("probe plane rays must be > 0".into()));
        }
        Ok(())
    }
}

/// A captured probe: its projection centre, the bounding planes (in coordinates relative to the
/// centre, as [`crate::integrator::Lookup`] takes them) and the filtered pyramid.
#[derive(Clone, Debug)]
pub struct Probe {
    /// The object's mesh name, or the room probe's name.
    pub name: String,
    /// The object's mesh index; `None` for a room probe.
    pub mesh: Option<u32>,
    /// The projection centre (world space).
    pub centre: DVec3,
    /// Bounding planes relative to `centre`.
    pub planes: Vec<BoundingPlane>,
    /// The captured light, Gaussian 6×6 pyramid (002 §3).
    pub pyramid: CubePyramid,
}

/// Captures the cube map seen from `centre` with mesh `skip` left out: each texel the box-filtered
/// mean of s×s stratified rays through its face square (rayon-parallel).
pub fn capture_cube(
    lit: &LitScene,
    centre: DVec3,
    skip: Option<u32>,
    opts: &ProbeOptions,
) -> Result<CubeMap> {
    opts.validate()?;
    if !centre.is_finite() {
        return Err(ShadeError::Parameter(format!(
            "probe centre {centre} is not finite"
        )));
    }
    let n = opts.face_size;
    let s = opts.supersample as usize;
    let inv = 1.0 / (s * s) as f64;
    let faces: Vec<Vec<[f32; 3]>> = (0..6)
        .map(|face| {
            (0..n * n)
                .into_par_iter()
                .map(|k| {
                    let (i, j) = (k % n, k / n);
                    let mut sum = Rgb::ZERO;
                    for a in 0..s {
                        for b in 0..s {
                            let sc =
                                2.0 * (i as f64 + (a as f64 + 0.5) / s as f64) / n as f64 - 1.0;
                            let tc =
                                2.0 * (j as f64 + (b as f64 + 0.5) / s as f64) / n as f64 - 1.0;
                            let d = face_point(face, sc, tc).normalize();
                            let l = lit.radiance(centre, d, skip);
                            if l.is_finite() {
                                sum += l;
                            }
                        }
                    }
                    (sum * inv).0.map(|c| c as f32)
                })
                .collect()
        })
        .collect();
    let faces: [Vec<[f32; 3]>; 6] = faces
        .try_into()
        .map_err(|_| ShadeError::Parameter("cube capture lost a face".into()))?;
    Ok(CubeMap::new(n, faces)?)
}

/// The automatic bounding planes of a probe at `centre` (000 §4.4.1 lets the user place them; a
/// room's walls are what they model): along each of ±x, ±y, ±z, a plane perpendicular to the
/// axis at the median distance to the surroundings measured by `rays` rays in a 30° cone
/// ([`lustre_trace::setup::axis_distances`]); a direction where fewer than half the rays hit
/// (open sky) gets no plane. Planes are relative to `centre`; the triangles of mesh `skip` are
/// left out.
pub fn auto_planes(
    lit: &LitScene,
    centre: DVec3,
    skip: Option<u32>,
    rays: u32,
) -> Result<Vec<BoundingPlane>> {
    let skip = skip.and_then(|m| mesh_prims(lit.scene).get(m as usize).cloned());
    let dist = axis_distances(lit.tracer, centre, skip, rays);
    let mut planes = vec![];
    for (axis, d) in AXES.iter().zip(dist) {
        if let Some(t) = d {
            planes.push(BoundingPlane::new(*axis * t, -*axis)?);
        }
    }
    Ok(planes)
}

/// The bounding planes of a box (world corners `lo`, `hi`) relative to `centre`, normals
/// inwards: the parallax box of a room probe.
pub fn box_planes(centre: DVec3, lo: DVec3, hi: DVec3) -> Result<Vec<BoundingPlane>> {
    let mut planes = vec![];
    for axis in AXES {
        let corner = if axis.max_element() > 0.0 { hi } else { lo };
        let t = (corner - centre).dot(axis);
        planes.push(BoundingPlane::new(axis * t, -axis)?);
    }
    Ok(planes)
}

/// Captures the probe of mesh `mesh` at the centre of its bounds: the cube with the object left
/// out, its Gaussian 6×6 pyramid, and [`auto_planes`]. Errors: no such mesh, or a centre inside
/// another object's solid (more than half the axis rays hit back faces — a probe inside a wall).
pub fn capture_probe(lit: &LitScene, mesh: usize, opts: &ProbeOptions) -> Result<Probe> {
    let (name, centre) = probe_placement(lit, mesh)?;
    let skip = Some(mesh as u32);
    let cube = capture_cube(lit, centre, skip, opts)?;
    let pyramid = CubePyramid::build(cube, MipFilter::Gauss6)?;
    let planes = auto_planes(lit, centre, skip, opts.plane_rays)?;
    Ok(Probe {
        name,
        mesh: Some(mesh as u32),
        centre,
        planes,
        pyramid,
    })
}

/// Where room probe `index` of the scene ([`lustre_scene::Scene::probes`]) is captured, and its
/// bounding planes: its parallax box, else [`auto_planes`] from its centre. Errors: no such
/// probe, a centre inside a solid.
pub fn room_placement(
    lit: &LitScene,
    index: usize,
    plane_rays: u32,
) -> Result<(String, DVec3, Vec<BoundingPlane>)> {
    let site = lit.scene.probes.get(index).ok_or_else(|| {
        ShadeError::Parameter(format!(
            "{}: no room probe {index} (the scene lists {})",
            lit.scene.source.display(),
            lit.scene.probes.len()
        ))
    })?;
    let centre = DVec3::from_array(site.centre);
    let backs = Surroundings::at(lit.tracer, lit.scene, centre, None).inside_fraction();
    if backs > 0.5 {
        return Err(ShadeError::Parameter(format!(
            "{}: room probe {:?} at {centre} is inside a solid ({:.0} % of its rays hit back faces)",
            lit.scene.source.display(),
            site.name,
            backs * 100.0
        )));
    }
    let planes = match site.parallax_box() {
        Some((lo, hi)) => box_planes(centre, DVec3::from_array(lo), DVec3::from_array(hi))?,
        None => auto_planes(lit, centre, None, plane_rays)?,
    };
    Ok((site.name.clone(), centre, planes))
}

/// Captures room probe `index`: the cube at its centre (nothing left out), its Gaussian 6×6
/// pyramid and [`room_placement`]'s planes.
pub fn capture_room_probe(lit: &LitScene, index: usize, opts: &ProbeOptions) -> Result<Probe> {
    opts.validate()?;
    let (name, centre, planes) = room_placement(lit, index, opts.plane_rays)?;
    let cube = capture_cube(lit, centre, None, opts)?;
    let pyramid = CubePyramid::build(cube, MipFilter::Gauss6)?;
    Ok(Probe {
        name,
        mesh: None,
        centre,
        planes,
        pyramid,
    })
}

/// Every probe of the scene, in the order the renderers list them: the object probes (meshes
/// hinted `probe`, in mesh order), then the room probes. `each(name, seconds)` after each.
pub fn capture_probes(
    lit: &LitScene,
    opts: &ProbeOptions,
    each: &mut dyn FnMut(&Probe, f64),
) -> Result<Vec<Probe>> {
    let mut probes = vec![];
    for (m, mesh) in lit.scene.meshes.iter().enumerate() {
        if mesh.hints.probe {
            let t = std::time::Instant::now();
            let p = capture_probe(lit, m, opts)?;
            each(&p, t.elapsed().as_secs_f64());
            probes.push(p);
        }
    }
    for i in 0..lit.scene.probes.len() {
        let t = std::time::Instant::now();
        let p = capture_room_probe(lit, i, opts)?;
        each(&p, t.elapsed().as_secs_f64());
        probes.push(p);
    }
    Ok(probes)
}

/// Whether a scene has probes (object or room).
pub fn has_probes(scene: &Scene) -> bool {
    !scene.probes.is_empty() || scene.meshes.iter().any(|m| m.hints.probe)
}

/// Whether `rel` (relative to a probe's centre) lies beyond bounding plane `b`, by more than
/// 10⁻³ of the plane's distance from the centre: a floor on its room box's lower face is inside
/// (in f64 here as in f32 on the GPU).
pub fn outside_plane(b: &BoundingPlane, rel: DVec3) -> bool {
    (rel - b.point).dot(b.normal) < -1e-3 * b.point.length()
}

/// How far `rel` (relative to a probe's centre) lies inside its bounding planes: the least
/// signed distance to one of them (negative outside one; +∞ without planes).
pub fn plane_depth(planes: &[BoundingPlane], rel: DVec3) -> f64 {
    planes
        .iter()
        .map(|b| (rel - b.point).dot(b.normal))
        .fold(f64::INFINITY, f64::min)
}

/// The probe(s) a point reads ([`choose_probe`]): `probe`, or where two room boxes hold the
/// point, `probe` with weight 1 − w and `blend = Some((other, w))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeChoice {
    /// The probe read (with weight 1 − w when blended).
    pub probe: usize,
    /// The second room probe and its weight w ∈ [0, ½].
    pub blend: Option<(usize, f64)>,
}

/// The probe(s) a point `p` of a mesh without its own probe reads, among `probes` (centre,
/// planes relative to it, whether it is a room probe): the room probes whose planes enclose `p`,
/// else an object probe whose planes enclose it, else any (the nearest centre within the first
/// of these groups that has one: 000 §4.4 reads the nearest probe; a room's box makes it the
/// room's, and an object probe, captured for its own object, serves others only where no room
/// holds them). Where room boxes overlap, the two that hold `p` deepest are blended, each
/// weighted by its depth d (the distance from `p` to its nearest face): w = d₂ / (d₁ + d₂), so a
/// reflection fades from one room's probe to the next across their overlap instead of jumping
/// (Unity's and Godot's probe blending; the same rule in `frame_shade.wgsl`).
pub fn choose_probe<'p>(
    probes: impl IntoIterator<Item = (DVec3, &'p [BoundingPlane], bool)>,
    p: DVec3,
) -> Option<ProbeChoice> {
    let mut best: Option<(u8, f64, usize)> = None;
    // The two room boxes holding p deepest: (−depth, squared distance, index).
    let mut rooms: [Option<(f64, f64, usize)>; 2] = [None, None];
    for (i, (centre, planes, room)) in probes.into_iter().enumerate() {
        let rel = p - centre;
        let inside = !planes.iter().any(|b| outside_plane(b, rel));
        let rank = match (inside, room) {
            (true, true) => 0u8,
            (true, false) => 1,
            (false, _) => 2,
        };
        let d2 = rel.length_squared();
        if best.is_none_or(|(r, d, _)| (rank, d2) < (r, d)) {
            best = Some((rank, d2, i));
        }
        if rank == 0 {
            let key = (-plane_depth(planes, rel).max(0.0), d2, i);
            if rooms[0].is_none_or(|r| (key.0, key.1) < (r.0, r.1)) {
                rooms = [Some(key), rooms[0]];
            } else if rooms[1].is_none_or(|r| (key.0, key.1) < (r.0, r.1)) {
                rooms[1] = Some(key);
            }
        }
    }
    match rooms {
        [Some((a, _, i)), Some((b, _, j))] if a + b < 0.0 => Some(ProbeChoice {
            probe: i,
            blend: Some((j, b / (a + b))),
        }),
        [Some((_, _, i)), _] => Some(ProbeChoice {
            probe: i,
            blend: None,
        }),
        _ => best.map(|b| ProbeChoice {
            probe: b.2,
            blend: None,
        }),
    }
}

/// Where the probe of mesh `mesh` is captured: its name and the mesh's `probe_centre` hint, else
/// the centre of its bounds (what [`capture_probe`] and the GPU capture share). Errors: no such
/// mesh, or a centre inside another object's solid (more than half the axis rays hit back faces
/// — a probe inside a wall).
pub fn probe_placement(lit: &LitScene, mesh: usize) -> Result<(String, DVec3)> {
    let (lo, hi) = lit.mesh_bounds(mesh).ok_or_else(|| {
        ShadeError::Parameter(format!(
            "{}: no mesh {mesh} (or it has no finite vertices) to place a probe at",
            lit.scene.source.display()
        ))
    })?;
    let name = lit.scene.meshes[mesh].name.clone();
    let centre = match lit.scene.meshes[mesh].hints.probe_centre {
        Some([x, y, z]) => DVec3::new(x, y, z),
        None => 0.5 * (lo + hi),
    };
    let skip = mesh_prims(lit.scene).get(mesh).cloned();
    let backs = Surroundings::at(lit.tracer, lit.scene, centre, skip).inside_fraction();
    if backs > 0.5 {
        return Err(ShadeError::Parameter(format!(
            "{}: the probe of {name:?} at {centre} is inside a solid ({:.0} % of its rays hit back faces)",
            lit.scene.source.display(),
            backs * 100.0
        )));
    }
    Ok((name, centre))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The probe read with the larger weight.
    fn pick<'p>(
        probes: impl IntoIterator<Item = (DVec3, &'p [BoundingPlane], bool)>,
        p: DVec3,
    ) -> Option<usize> {
        choose_probe(probes, p).map(|c| c.probe)
    }

    #[test]
    fn a_box_that_holds_the_point_wins_over_a_nearer_centre() {
        // A room box [0, 4]³ probed at its middle; a small object probe just outside it, whose
        // centre is nearer to the point.
        let room_c = DVec3::splat(2.0);
        let room = box_planes(room_c, DVec3::ZERO, DVec3::splat(4.0)).unwrap();
        assert_eq!(room.len(), 6);
        let obj_c = DVec3::new(4.6, 3.5, 3.5);
        let obj = box_planes(obj_c, DVec3::new(4.2, 3.0, 3.0), DVec3::new(5.0, 4.0, 4.0)).unwrap();
        let probes = [(room_c, &room[..], true), (obj_c, &obj[..], false)];
        let p = DVec3::new(3.9, 3.5, 3.5);
        assert!(obj_c.distance(p) < room_c.distance(p));
        assert_eq!(
            choose_probe(probes, p),
            Some(ProbeChoice {
                probe: 0,
                blend: None
            })
        );
        // Inside a room and an object probe's planes: the room, though the object's is nearer;
        // inside an object probe's planes only: that one before a nearer probe outside; inside
        // neither: the nearer centre.
        let obj_in_room = box_planes(obj_c, DVec3::ZERO, DVec3::splat(5.0)).unwrap();
        let mixed = [(room_c, &room[..], true), (obj_c, &obj_in_room[..], false)];
        assert_eq!(pick(mixed, DVec3::new(3.9, 3.5, 3.5)), Some(0));
        let away = DVec3::new(4.5, 3.6, 3.6);
        let near_c = DVec3::new(4.6, 3.6, 3.6);
        let elsewhere = box_planes(near_c, DVec3::splat(6.0), DVec3::splat(7.0)).unwrap();
        let mixed = [
            (near_c, &elsewhere[..], true),
            (obj_c, &obj_in_room[..], false),
        ];
        assert_eq!(pick(mixed, away), Some(1));
        let far = DVec3::new(9.0, 3.5, 3.5);
        assert_eq!(pick(probes, far), Some(1));
        // Planes point inwards, at the box's faces relative to the centre.
        for b in &room {
            assert!((b.point.length() - 2.0).abs() < 1e-12);
            assert!((b.normal + b.point / 2.0).length() < 1e-12);
        }
        assert_eq!(choose_probe(std::iter::empty(), p), None);
    }

    #[test]
    fn overlapping_room_boxes_blend_by_depth() {
        // Rooms [0, 4]³ and [3, 7] × [0, 4]²: the point crosses their overlap along x.
        let a = box_planes(DVec3::splat(2.0), DVec3::ZERO, DVec3::splat(4.0)).unwrap();
        let b_lo = DVec3::new(3.0, 0.0, 0.0);
        let b_hi = DVec3::new(7.0, 4.0, 4.0);
        let b_c = 0.5 * (b_lo + b_hi);
        let b = box_planes(b_c, b_lo, b_hi).unwrap();
        let rooms = [(DVec3::splat(2.0), &a[..], true), (b_c, &b[..], true)];
        // The weight of room b at x along y = z = 2.
        let w_b = |x: f64| {
            let c = choose_probe(rooms, DVec3::new(x, 2.0, 2.0)).unwrap();
            match c.blend {
                None => f64::from(u8::from(c.probe == 1)),
                Some((j, w)) => {
                    assert!((0.0..=0.5).contains(&w), "{w}");
                    if j == 1 {
                        w
                    } else {
                        1.0 - w
                    }
                }
            }
        };
        // Outside the overlap one room alone; inside, d_a = 4 − x and d_b = x − 3.
        assert_eq!(w_b(2.5), 0.0);
        assert_eq!(w_b(5.0), 1.0);
        for x in [3.1, 3.25, 3.5, 3.75, 3.9] {
            let expect = (x - 3.0) / ((4.0 - x) + (x - 3.0));
            assert!(
                (w_b(x) - expect).abs() < 1e-12,
                "x {x}: {} vs {expect}",
                w_b(x)
            );
        }
        // Continuous across both faces of the overlap and where the deeper box changes.
        for x0 in [3.0, 3.5, 4.0] {
            assert!(
                (w_b(x0 - 1e-9) - w_b(x0 + 1e-9)).abs() < 1e-6,
                "jump at x = {x0}"
            );
        }
        // plane_depth: inside positive, outside negative, no planes unbounded.
        assert!(
            (plane_depth(&a, DVec3::new(1.0, 2.0, 2.0) - DVec3::splat(2.0)) - 1.0).abs() < 1e-12
        );
        assert!(plane_depth(&a, DVec3::new(5.0, 2.0, 2.0) - DVec3::splat(2.0)) < 0.0);
        assert_eq!(plane_depth(&[], DVec3::ONE), f64::INFINITY);
    }
}
