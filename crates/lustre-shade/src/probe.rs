//! Reflection probes (000 §4.4): the incident light of a curved glossy object, captured as a
//! cube map at the object's centre from the light-mapped scene with the object itself left out,
//! filtered into 002's Gaussian 6×6 pyramid, and looked up through bounding planes that correct
//! for the parallax between the centre and the shaded point (000 §4.4.1, Fig. 4.5–4.6).
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
        Ok(LitScene {
            scene,
            path_scene,
            tracer,
            lit,
            mesh_of,
        })
    }

    /// The first surface along o + t d, ignoring the triangles of mesh `skip`.
    pub fn hit(&self, o: DVec3, d: DVec3, skip: Option<u32>) -> Option<Hit> {
        match skip {
            Some(m) => self
                .tracer
                .intersect_filtered(o, d, |p| self.mesh_of[p] == m),
            None => self.tracer.intersect(o, d),
        }
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
    /// The object's mesh name.
    pub name: String,
    /// The object's mesh index.
    pub mesh: u32,
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
/// room's walls are what they model): along each of ±x, ±y, ±z, `rays` rays in a 30° cone
/// around the axis (a fixed golden-angle spiral) measure the distance to the surroundings
/// projected on the axis, and a plane perpendicular to the axis is placed at the median. A
/// direction where fewer than half the rays hit (open sky) gets no plane. Planes are relative to
/// `centre`.
pub fn auto_planes(
    lit: &LitScene,
    centre: DVec3,
    skip: Option<u32>,
    rays: u32,
) -> Result<Vec<BoundingPlane>> {
    let axes = [
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ];
    let cos_max = 30f64.to_radians().cos();
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let mut planes = vec![];
    for axis in axes {
        let (t, b) = axis.any_orthonormal_pair();
        let mut dist: Vec<f64> = (0..rays)
            .filter_map(|k| {
                let u = (k as f64 + 0.5) / rays as f64;
                let cos = 1.0 - u * (1.0 - cos_max);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = k as f64 * golden;
                let d = axis * cos + (t * phi.cos() + b * phi.sin()) * sin;
                lit.distance(centre, d, skip).map(|s| s * cos)
            })
            .collect();
        if dist.len() * 2 < rays as usize {
            continue;
        }
        dist.sort_by(f64::total_cmp);
        let median = dist[dist.len() / 2];
        if median > 0.0 && median.is_finite() {
            planes.push(BoundingPlane::new(axis * median, -axis)?);
        }
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
        mesh: mesh as u32,
        centre,
        planes,
        pyramid,
    })
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
    let skip = Some(mesh as u32);
    let backs = inside_fraction(lit, centre, skip);
    if backs > 0.5 {
        return Err(ShadeError::Parameter(format!(
            "{}: the probe of {name:?} at {centre} is inside a solid ({:.0} % of its rays hit back faces)",
            lit.scene.source.display(),
            backs * 100.0
        )));
    }
    Ok((name, centre))
}

/// The fraction of 26 rays (the cube's face, edge and corner directions) from `p` that hit a
/// back face of a one-sided geometric surface: near 1 inside a closed solid.
fn inside_fraction(lit: &LitScene, p: DVec3, skip: Option<u32>) -> f64 {
    let g = &lit.path_scene.geometry;
    let mut backs = 0;
    let mut total = 0;
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) == (0, 0, 0) {
                    continue;
                }
                let d = DVec3::new(x as f64, y as f64, z as f64).normalize();
                total += 1;
                if let Some(h) = lit.hit(p, d, skip) {
                    let tri = &g.positions[h.prim];
                    let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                    let m = g.material[h.prim] as usize;
                    let two_sided = lit.scene.materials.get(m).is_some_and(|m| m.two_sided);
                    if !two_sided && ng.dot(d) > 0.0 {
                        backs += 1;
                    }
                }
            }
        }
    }
    f64::from(backs) / f64::from(total)
}
