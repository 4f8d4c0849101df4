//! The automatic real-time set-up: which meshes get a mirror pass, which get an object probe
//! (and with it, for glass, a see-through pass), and where room probes with parallax boxes go —
//! decided from the geometry and the materials, written by `lustre bake` into the baked scene
//! file as ordinary hints (a hand-written hint always wins).
//!
//! The rules (the budgets in [`SetupOptions`]):
//!
//! - **Planar reflectors**: a mesh whose material has a view-dependent reflection (not
//!   diffuse-only, not transmissive), whose dominant plane ([`lustre_scene::Mesh::dominant_plane`],
//!   the mirror pass's own test) holds ≥ 99 % of its area, and whose area is at least 10⁻³ of
//!   the squared scene diagonal (or of the room box around the first camera where that is
//!   smaller: an interior on a vast site keeps its mirrors). Ranked by plane area × glossy albedo; the first
//!   `max_mirrors` get `planar_reflector`. Glass too, beside its object probe (which keeps
//!   its see-through pass), where its plane toward the first camera
//!   ([`lustre_scene::Mesh::plane_facing`]: a slab's near face) holds ≥ 50 % of the area facing
//!   it; the mirror pass takes that face.
//! - **Object probes**: every transmissive mesh (glass: its probe gives it a see-through pass),
//!   then every other curved (not planar) view-dependent mesh, ranked by area × glossy albedo;
//!   the first `max_object_probes` get `probe`. A mesh whose bounds' centre lies inside a solid,
//!   or (unless it transmits: its probe brings its see-through pass) nearer another surface than
//!   3 % of its bounds' diagonal (a fixture flush with a wall), is left to the room probes.
//! - **Room probes**: the scene's bounds are cut into cells (`grid` along the longest side);
//!   a cell is free space inside the scene when ≤ 25 % of 26 rays from its centre meet a back
//!   face, its nearest surface is at least half a cell away, and ≥ 75 % of the rays hit
//!   something (50 % in a scene without an environment); of those, the cells the cameras can
//!   walk to (neighbours with nothing between their centres, from the cameras' cells; all of
//!   them when no camera stands in one) are the free space. Probes are seeded at the cameras,
//!   then greedily at the uncovered free cell farthest from any surface; each probe's box is
//!   the median distance to the surroundings along ±x, ±y, ±z ([`axis_distances`]), the probe
//!   moved to the box's middle (up to three times, while that is free space), until `coverage` of the free cells lie in a box or
//!   `max_room_probes` are placed; a box that covers no new free cell is dropped. Where no box
//!   could be fitted (no free cell: a room on a vast site, whose cells outsize it), a probe
//!   stands at each camera that something surrounds (≥ 50 % of its rays hit, ≤ 25 % a back
//!   face) with the room's box around it; an open scene gets none. A scene without a
//!   view-dependent surface gets none. Where room boxes overlap, the frame blends the two
//!   that hold a point deepest (`lustre_shade::probe::choose_probe`).

use crate::path_tracer::PathTracer;
use glam::DVec3;
use lustre_scene::mesh::{GLASS_PLANE_SHARE, PLANAR_AREA_SHARE};
use lustre_scene::{MaterialKind, ObjectHints, ProbeSite, Scene, Vec2};
use std::fmt;
use std::ops::Range;

/// Budgets and resolution of the automatic set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetupOptions {
    /// Mirror passes (planar reflectors) at most.
    pub max_mirrors: usize,
    /// Object probes at most (each transmissive one also costs a see-through pass).
    pub max_object_probes: usize,
    /// Room probes at most.
    pub max_room_probes: usize,
    /// Cells along the scene's longest side in the free-space grid.
    pub grid: usize,
    /// Stop placing room probes once this fraction of the free cells is covered.
    pub coverage: f64,
}

impl Default for SetupOptions {
    fn default() -> Self {
        SetupOptions {
            max_mirrors: 4,
            max_object_probes: 12,
            max_room_probes: 8,
            grid: 24,
            coverage: 0.95,
        }
    }
}

/// What the set-up chose, and what it left out.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Setup {
    /// Hints for meshes that had none, by mesh name (in mesh order).
    pub objects: Vec<(String, ObjectHints)>,
    /// Room probes (empty when the scene lists its own).
    pub probes: Vec<ProbeSite>,
    /// The report.
    pub report: SetupReport,
}

/// The counts behind the one-line report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SetupReport {
    /// Meshes given a mirror pass.
    pub mirrors: Vec<String>,
    /// Meshes given an object probe (transmissive ones get a see-through pass with it).
    pub object_probes: Vec<String>,
    /// Of those, the transmissive ones.
    pub see_through: usize,
    /// Meshes whose hand-written hints were kept.
    pub hand_written: usize,
    /// Room probes placed, or kept from the scene file (`hand_probes`).
    pub room_probes: usize,
    /// Whether the room probes are the scene file's own.
    pub hand_probes: bool,
    /// Free-space cells found, and the fraction inside a room probe's box.
    pub free_cells: usize,
    /// Fraction of `free_cells` covered.
    pub covered: f64,
    /// Whether the room probes stand at the cameras: no box could be fitted to free space.
    pub at_cameras: bool,
    /// Solid glass slabs given their thickness (the refraction offset), by name.
    pub slabs: Vec<(String, f64)>,
    /// Candidates over a budget or refused (a probe centre inside a solid or against a
    /// surface), by name.
    pub left_out: Vec<String>,
    /// Wall time, seconds.
    pub seconds: f64,
}

impl fmt::Display for SetupReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let list = |v: &[String]| {
            if v.is_empty() {
                String::new()
            } else if v.len() <= 4 {
                format!(" ({})", v.join(", "))
            } else {
                format!(" ({}, … {} more)", v[..3].join(", "), v.len() - 3)
            }
        };
        write!(
            f,
            "real-time set-up: {} mirror pass(es){}, {} object probe(s){} ({} see-through), ",
            self.mirrors.len(),
            list(&self.mirrors),
            self.object_probes.len(),
            list(&self.object_probes),
            self.see_through
        )?;
        if self.hand_probes {
            write!(f, "{} room probe(s) from the scene file", self.room_probes)?;
        } else if self.at_cameras {
            write!(
                f,
                "{} room probe(s) at the cameras ({} free cells: no room box fitted)",
                self.room_probes, self.free_cells
            )?;
        } else {
            write!(
                f,
                "{} room probe(s) covering {:.0} % of {} free cells",
                self.room_probes,
                100.0 * self.covered,
                self.free_cells
            )?;
        }
        if !self.slabs.is_empty() {
            let names: Vec<String> = self
                .slabs
                .iter()
                .map(|(n, t)| format!("{n} {t:.3}"))
                .collect();
            write!(
                f,
                "; {} glass slab(s) with their thickness{}",
                self.slabs.len(),
                list(&names)
            )?;
        }
        if self.hand_written > 0 {
            write!(
                f,
                "; {} mesh(es) keep hand-written hints",
                self.hand_written
            )?;
        }
        if !self.left_out.is_empty() {
            write!(
                f,
                "; left out {}{}",
                self.left_out.len(),
                list(&self.left_out)
            )?;
        }
        write!(f, "; {:.2} s", self.seconds)
    }
}

/// How a mesh's material looks to the set-up.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Appearance {
    /// Has a view-dependent part.
    view_dependent: bool,
    /// Transmits.
    transmissive: bool,
    /// Luminance of the albedo at normal incidence beyond the diffuse part.
    glossy: f64,
}

fn appearance(scene: &Scene, material: usize) -> Appearance {
    let none = Appearance {
        view_dependent: false,
        transmissive: false,
        glossy: 0.0,
    };
    let Some(m) = scene.materials.get(material) else {
        return none;
    };
    let uv = [Vec2::ZERO; 2];
    let Ok(bsdf) = m.bsdf_at(&scene.textures, &uv) else {
        return none;
    };
    let flags = bsdf.flags();
    if flags.diffuse_only() {
        return none;
    }
    let total = bsdf.albedo(DVec3::Z, 256).luminance();
    let base = crate::bake::base_albedo(m);
    let diffuse = crate::bake::diffuse_albedo(m, &scene.textures, &uv, base).luminance();
    let glossy = if flags.transmission {
        1.0
    } else {
        (total - diffuse).max(0.0)
    };
    Appearance {
        view_dependent: true,
        transmissive: flags.transmission,
        glossy: if glossy.is_finite() { glossy } else { 0.0 },
    }
}

/// World bounds (low, high) of mesh `m` (`Mesh::bounds`), or of every mesh (`Scene::bounds`).
fn bounds(scene: &Scene, m: Option<usize>) -> Option<(DVec3, DVec3)> {
    let b = match m {
        Some(i) => scene.meshes[i].bounds(),
        None => scene.bounds(),
    };
    b.map(|(lo, hi)| (lo.as_dvec3(), hi.as_dvec3()))
}

/// The triangle range of each mesh in the path scene (meshes in order).
pub fn mesh_prims(scene: &Scene) -> Vec<Range<usize>> {
    let mut at = 0;
    scene
        .meshes
        .iter()
        .map(|m| {
            let r = at..at + m.indices.len();
            at = r.end;
            r
        })
        .collect()
}

/// What 26 rays (the cube's face, edge and corner directions) from `p` see, triangles `skip`
/// left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surroundings {
    /// Rays that hit a surface.
    pub hits: u32,
    /// Rays that hit the back of a one-sided surface.
    pub backs: u32,
    /// The nearest hit's distance (infinite when none).
    pub nearest: f64,
}

impl Surroundings {
    /// The rays cast.
    pub const RAYS: u32 = 26;

    /// Looks around `p` in `tracer`'s scene (`scene`'s meshes in order).
    pub fn at(tracer: &PathTracer, scene: &Scene, p: DVec3, skip: Option<Range<usize>>) -> Self {
        let g = &tracer.scene().geometry;
        let mut s = Surroundings {
            hits: 0,
            backs: 0,
            nearest: f64::INFINITY,
        };
        for x in -1i32..=1 {
            for y in -1i32..=1 {
                for z in -1i32..=1 {
                    if (x, y, z) == (0, 0, 0) {
                        continue;
                    }
                    let d = DVec3::new(f64::from(x), f64::from(y), f64::from(z)).normalize();
                    let hit = match &skip {
                        Some(r) => tracer.intersect_filtered(p, d, |q| r.contains(&q)),
                        None => tracer.intersect(p, d),
                    };
                    let Some(h) = hit else { continue };
                    s.hits += 1;
                    s.nearest = s.nearest.min(h.t);
                    let tri = &g.positions[h.prim];
                    let ng = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
                    let m = g.material[h.prim] as usize;
                    let two_sided = scene.materials.get(m).is_some_and(|m| m.two_sided);
                    if !two_sided && ng.dot(d) > 0.0 {
                        s.backs += 1;
                    }
                }
            }
        }
        s
    }

    /// The fraction of rays that hit a back face: near 1 inside a closed solid.
    pub fn inside_fraction(&self) -> f64 {
        f64::from(self.backs) / f64::from(Self::RAYS)
    }
}

/// The distance from `centre` to its surroundings along ±x, −x, +y, −y, +z, −z (in that
/// order): `rays` rays in a 30° cone around each axis (a golden-angle spiral) measure the
/// distance projected on the axis, and the median is taken; `None` where fewer than half the
/// rays hit (open sky). Triangles `skip` are left out.
pub fn axis_distances(
    tracer: &PathTracer,
    centre: DVec3,
    skip: Option<Range<usize>>,
    rays: u32,
) -> [Option<f64>; 6] {
    let cos_max = 30f64.to_radians().cos();
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    AXES.map(|axis| {
        let (t, b) = axis.any_orthonormal_pair();
        let mut dist: Vec<f64> = (0..rays)
            .filter_map(|k| {
                let u = (f64::from(k) + 0.5) / f64::from(rays);
                let cos = 1.0 - u * (1.0 - cos_max);
                let sin = (1.0 - cos * cos).max(0.0).sqrt();
                let phi = f64::from(k) * golden;
                let d = axis * cos + (t * phi.cos() + b * phi.sin()) * sin;
                let hit = match &skip {
                    Some(r) => tracer.intersect_filtered(centre, d, |q| r.contains(&q)),
                    None => tracer.intersect(centre, d),
                };
                hit.map(|h| h.t * cos)
            })
            .collect();
        if rays == 0 || dist.len() * 2 < rays as usize {
            return None;
        }
        dist.sort_by(f64::total_cmp);
        let median = dist[dist.len() / 2];
        (median > 0.0 && median.is_finite()).then_some(median)
    })
}

/// The six axes of [`axis_distances`].
pub const AXES: [DVec3; 6] = [
    DVec3::X,
    DVec3::NEG_X,
    DVec3::Y,
    DVec3::NEG_Y,
    DVec3::Z,
    DVec3::NEG_Z,
];

/// Rays per axis that measure a room probe's box.
const BOX_RAYS: u32 = 64;

/// The parallax box around `p` (low, high): [`axis_distances`], clamped to `scene_box` where
/// a direction is open.
fn room_box(tracer: &PathTracer, p: DVec3, scene_box: (DVec3, DVec3)) -> (DVec3, DVec3) {
    let d = axis_distances(tracer, p, None, BOX_RAYS);
    let hi = DVec3::new(
        d[0].map_or(scene_box.1.x, |t| p.x + t),
        d[2].map_or(scene_box.1.y, |t| p.y + t),
        d[4].map_or(scene_box.1.z, |t| p.z + t),
    );
    let lo = DVec3::new(
        d[1].map_or(scene_box.0.x, |t| p.x - t),
        d[3].map_or(scene_box.0.y, |t| p.y - t),
        d[5].map_or(scene_box.0.z, |t| p.z - t),
    );
    (lo.min(p), hi.max(p))
}

fn inside(b: &(DVec3, DVec3), p: DVec3) -> bool {
    b.0.cmple(p).all() && p.cmple(b.1).all()
}

/// Whether `h` says anything about reflections (a probe, a mirror, diffuse-only, a sample
/// budget): such a mesh is hand-set and the set-up leaves it alone. A light-map density alone
/// is not.
pub fn has_realtime_hints(h: &ObjectHints) -> bool {
    h.probe
        || h.planar_reflector
        || h.diffuse_only
        || h.probe_centre.is_some()
        || h.samples.is_some()
}

/// Decides the set-up of `scene` (ray cast with `tracer`, built over
/// [`crate::reference::path_scene`] or the diffuse path scene of the same scene). Meshes whose
/// hints say anything about reflections ([`has_realtime_hints`]) keep them and count against the budgets; room probes are placed
/// only when the scene lists none.
pub fn auto_setup(scene: &Scene, tracer: &PathTracer, opts: &SetupOptions) -> Setup {
    let t0 = std::time::Instant::now();
    let mut report = SetupReport::default();
    let Some(scene_box) = bounds(scene, None) else {
        report.seconds = t0.elapsed().as_secs_f64();
        return Setup {
            report,
            ..Setup::default()
        };
    };
    // The scale planar reflectors are measured against: the scene's diagonal, or the room
    // around the first camera where that is smaller (an interior on a vast site).
    let diag = scene
        .cameras
        .first()
        .map(|c| c.position)
        .filter(|p| inside(&scene_box, *p))
        .map(|p| {
            let b = room_box(tracer, p, scene_box);
            (b.1 - b.0).length()
        })
        .unwrap_or(f64::INFINITY)
        .min((scene_box.1 - scene_box.0).length())
        .max(1e-9);
    let prims = mesh_prims(scene);
    let mut hints: Vec<Option<ObjectHints>> = vec![None; scene.meshes.len()];
    let hand: Vec<bool> = scene
        .meshes
        .iter()
        .map(|m| has_realtime_hints(&m.hints))
        .collect();
    report.hand_written = hand.iter().filter(|&&h| h).count();
    let mut mirrors_used = scene
        .meshes
        .iter()
        .filter(|m| m.hints.planar_reflector)
        .count();
    let mut probes_used = scene.meshes.iter().filter(|m| m.hints.probe).count();
    let per_material: Vec<Appearance> = (0..scene.materials.len())
        .map(|k| appearance(scene, k))
        .collect();
    let none = Appearance {
        view_dependent: false,
        transmissive: false,
        glossy: 0.0,
    };
    let looks: Vec<Appearance> = scene
        .meshes
        .iter()
        .map(|m| per_material.get(m.material).copied().unwrap_or(none))
        .collect();
    let any_view_dependent = looks.iter().any(|a| a.view_dependent);
    // Candidates: (score, mesh, planar).
    let eye = scene.cameras.first().map(|c| c.position);
    let mut mirror_cands = vec![];
    let mut probe_cands = vec![];
    for (m, look) in looks.iter().enumerate() {
        if hand[m] || !look.view_dependent || scene.meshes[m].emission.is_some() {
            continue;
        }
        let area = scene.meshes[m].area();
        let share = scene.meshes[m]
            .dominant_plane()
            .map_or(0.0, |p| p.area_share);
        let planar = area > 0.0 && share >= PLANAR_AREA_SHARE;
        let plane = share * area;
        if planar && !look.transmissive && plane >= 1e-3 * diag * diag {
            mirror_cands.push((plane * look.glossy, m));
        } else if look.transmissive {
            probe_cands.push((f64::INFINITY, area, m));
            // Planar glass (a pane, or a slab's face toward the first camera) reflects through
            // a mirror pass too; its probe keeps the see-through pass.
            if let Some(p) = scene.meshes[m].plane_facing(eye) {
                let plane = p.area_share * area;
                if p.facing_share >= GLASS_PLANE_SHARE && plane >= 1e-3 * diag * diag {
                    mirror_cands.push((plane * look.glossy, m));
                }
            }
        } else if !planar {
            probe_cands.push((area * look.glossy, area, m));
        }
    }
    mirror_cands.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, m) in mirror_cands {
        let name = scene.meshes[m].name.clone();
        if mirrors_used < opts.max_mirrors {
            mirrors_used += 1;
            hints[m]
                .get_or_insert_with(ObjectHints::default)
                .planar_reflector = true;
            report.mirrors.push(name);
        } else {
            report.left_out.push(name);
        }
    }
    probe_cands.sort_by(|a, b| b.0.total_cmp(&a.0).then(b.1.total_cmp(&a.1)));
    for (_, _, m) in probe_cands {
        let name = scene.meshes[m].name.clone();
        if probes_used >= opts.max_object_probes {
            report.left_out.push(name);
            continue;
        }
        let Some((lo, hi)) = bounds(scene, Some(m)) else {
            continue;
        };
        let around = Surroundings::at(tracer, scene, 0.5 * (lo + hi), Some(prims[m].clone()));
        if around.inside_fraction() > 0.5 {
            report
                .left_out
                .push(format!("{name} (centre inside a solid)"));
            continue;
        }
        // A centre against another surface (an object on a wall, fixtures spread along one)
        // would see half its cube through that surface: the room probes serve it.
        if !looks[m].transmissive && around.nearest < 0.03 * (hi - lo).length() {
            report
                .left_out
                .push(format!("{name} (centre against a surface)"));
            continue;
        }
        probes_used += 1;
        hints[m].get_or_insert_with(ObjectHints::default).probe = true;
        if looks[m].transmissive {
            report.see_through += 1;
        }
        report.object_probes.push(name);
    }
    // Solid glass (not a thin sheet) modelled with both faces: its thickness, for the
    // refraction offset of what shows through it (hand-hinted meshes too, unless they give one).
    for (m, mesh) in scene.meshes.iter().enumerate() {
        let solid = matches!(
            scene.materials.get(mesh.material).map(|x| &x.kind),
            Some(MaterialKind::Dielectric { .. } | MaterialKind::RoughDielectric { .. })
        );
        if !solid || mesh.hints.thickness.is_some() {
            continue;
        }
        if let Some(t) = mesh.slab_thickness() {
            hints[m].get_or_insert_with(ObjectHints::default).thickness = Some(t);
            report.slabs.push((mesh.name.clone(), t));
        }
    }
    let probes = if !scene.probes.is_empty() {
        report.hand_probes = true;
        report.room_probes = scene.probes.len();
        vec![]
    } else if any_view_dependent {
        let sites = room_probes(scene, tracer, scene_box, opts, &mut report);
        report.room_probes = sites.len();
        sites
    } else {
        vec![]
    };
    let mut objects = vec![];
    for (m, h) in hints.into_iter().enumerate() {
        if let Some(h) = h {
            let name = &scene.meshes[m].name;
            if !objects
                .iter()
                .any(|(n, _): &(String, ObjectHints)| n == name)
            {
                objects.push((name.clone(), h));
            }
        }
    }
    report.seconds = t0.elapsed().as_secs_f64();
    Setup {
        objects,
        probes,
        report,
    }
}

/// Places the room probes (module notes).
fn room_probes(
    scene: &Scene,
    tracer: &PathTracer,
    scene_box: (DVec3, DVec3),
    opts: &SetupOptions,
    report: &mut SetupReport,
) -> Vec<ProbeSite> {
    use rayon::prelude::*;
    let ext = scene_box.1 - scene_box.0;
    let cell = ext.max_element() / opts.grid.max(1) as f64;
    if !(cell > 0.0 && cell.is_finite()) {
        return vec![];
    }
    let n = (ext / cell).ceil().max(DVec3::ONE).as_uvec3();
    let (nx, ny, nz) = (n.x as usize, n.y as usize, n.z as usize);
    let min_hits = if scene.environment.is_some() {
        0.75
    } else {
        0.5
    };
    let centre_of = |k: usize| {
        let (x, y, z) = (k % nx, (k / nx) % ny, k / (nx * ny));
        scene_box.0 + (DVec3::new(x as f64, y as f64, z as f64) + 0.5) * cell
    };
    // Per cell: its clearance when it is free space inside the scene.
    let clearance: Vec<Option<f64>> = (0..nx * ny * nz)
        .into_par_iter()
        .map(|k| {
            let s = Surroundings::at(tracer, scene, centre_of(k), None);
            let ok = f64::from(s.backs) <= 0.25 * f64::from(Surroundings::RAYS)
                && f64::from(s.hits) >= min_hits * f64::from(Surroundings::RAYS)
                && s.nearest >= 0.5 * cell;
            ok.then_some(s.nearest)
        })
        .collect();
    // The free space the cameras are in: free cells joined to a camera's cell through free
    // neighbours with nothing between their centres (all free cells when no camera is in one).
    let cameras: Vec<DVec3> = scene
        .cameras
        .iter()
        .chain(
            scene
                .camera_paths
                .iter()
                .flat_map(|p| p.keyframes.iter().map(|k| &k.camera)),
        )
        .map(|c| c.position)
        .filter(|p| inside(&scene_box, *p))
        .collect();
    let cell_of = |p: DVec3| {
        let q = ((p - scene_box.0) / cell)
            .floor()
            .max(DVec3::ZERO)
            .as_uvec3();
        let (x, y, z) = (
            (q.x as usize).min(nx - 1),
            (q.y as usize).min(ny - 1),
            (q.z as usize).min(nz - 1),
        );
        x + nx * (y + ny * z)
    };
    let mut reached = vec![false; clearance.len()];
    let mut queue: std::collections::VecDeque<usize> = cameras
        .iter()
        .map(|&p| cell_of(p))
        .filter(|&k| clearance[k].is_some())
        .collect();
    for &k in &queue {
        reached[k] = true;
    }
    while let Some(k) = queue.pop_front() {
        let (x, y, z) = (k % nx, (k / nx) % ny, k / (nx * ny));
        let mut next = vec![];
        if x > 0 {
            next.push(k - 1)
        }
        if x + 1 < nx {
            next.push(k + 1)
        }
        if y > 0 {
            next.push(k - nx)
        }
        if y + 1 < ny {
            next.push(k + nx)
        }
        if z > 0 {
            next.push(k - nx * ny)
        }
        if z + 1 < nz {
            next.push(k + nx * ny)
        }
        for j in next {
            if reached[j] || clearance[j].is_none() {
                continue;
            }
            let (a, b) = (centre_of(k), centre_of(j));
            if !tracer.occluded(a, (b - a) / cell, cell) {
                reached[j] = true;
                queue.push_back(j);
            }
        }
    }
    let any_reached = reached.iter().any(|&r| r);
    let free: Vec<(DVec3, f64)> = clearance
        .iter()
        .enumerate()
        .filter(|(k, c)| c.is_some() && (!any_reached || reached[*k]))
        .map(|(k, c)| (centre_of(k), c.unwrap_or(0.0)))
        .collect();
    report.free_cells = free.len();
    if free.is_empty() {
        return camera_probes(tracer, scene, &cameras, scene_box, opts, report);
    }
    let mut seeds = cameras.clone();
    seeds.dedup_by(|a, b| a.distance(*b) < cell);
    let mut boxes: Vec<(DVec3, (DVec3, DVec3))> = vec![];
    let mut refused = vec![false; free.len()];
    let covered =
        |boxes: &[(DVec3, (DVec3, DVec3))], p: DVec3| boxes.iter().any(|b| inside(&b.1, p));
    let mut seeds = seeds.into_iter();
    while boxes.len() < opts.max_room_probes {
        let count = free.iter().filter(|f| covered(&boxes, f.0)).count();
        if count as f64 >= opts.coverage * free.len() as f64 {
            break;
        }
        // The next seed: a camera not yet inside a box, else the uncovered free cell farthest
        // from any surface.
        let seed = seeds.by_ref().find(|p| !covered(&boxes, *p)).or_else(|| {
            free.iter()
                .enumerate()
                .filter(|(i, f)| !refused[*i] && !covered(&boxes, f.0))
                .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
                .map(|(i, f)| {
                    refused[i] = true;
                    f.0
                })
        });
        let Some(seed) = seed else { break };
        // Move the probe to its box's middle while that is free space and the box still holds
        // the seed (three times at most: seen from the middle the box is the room's, seen from
        // a corner it is shorter).
        let mut centre = seed;
        let mut b = room_box(tracer, seed, scene_box);
        for _ in 0..3 {
            let mid = 0.5 * (b.0 + b.1);
            let s = Surroundings::at(tracer, scene, mid, None);
            if mid.distance(centre) < 0.25 * cell
                || s.inside_fraction() > 0.25
                || s.nearest < 0.5 * cell
            {
                break;
            }
            let moved = room_box(tracer, mid, scene_box);
            if !inside(&moved, seed) {
                break;
            }
            centre = mid;
            b = moved;
        }
        // A box thinner than a cell on some axis, or one that covers no free cell not covered
        // already, adds nothing.
        let adds = free
            .iter()
            .filter(|f| inside(&b, f.0) && !covered(&boxes, f.0))
            .count();
        if (b.1 - b.0).min_element() < cell || adds == 0 {
            continue;
        }
        boxes.push((centre, b));
    }
    if boxes.is_empty() {
        return camera_probes(tracer, scene, &cameras, scene_box, opts, report);
    }
    let count = free.iter().filter(|f| covered(&boxes, f.0)).count();
    report.covered = count as f64 / free.len() as f64;
    sites(&boxes)
}

/// Where no room box could be fitted to free space (a room too open for the free-space test,
/// too small for its cells), a probe at each camera that something surrounds (at least half
/// of its rays hit a surface, at most a quarter a back face), with the box of the room around
/// it: the glossy surfaces then read what the cameras' surroundings show, never the bare
/// environment through the walls. An open scene (most of a camera's rays escape) gets none.
fn camera_probes(
    tracer: &PathTracer,
    scene: &Scene,
    cameras: &[DVec3],
    scene_box: (DVec3, DVec3),
    opts: &SetupOptions,
    report: &mut SetupReport,
) -> Vec<ProbeSite> {
    let mut boxes: Vec<(DVec3, (DVec3, DVec3))> = vec![];
    for &p in cameras {
        if boxes.len() >= opts.max_room_probes || boxes.iter().any(|b| inside(&b.1, p)) {
            continue;
        }
        let s = Surroundings::at(tracer, scene, p, None);
        let rays = f64::from(Surroundings::RAYS);
        if f64::from(s.backs) > 0.25 * rays || f64::from(s.hits) < 0.5 * rays {
            continue;
        }
        boxes.push((p, room_box(tracer, p, scene_box)));
    }
    report.at_cameras = !boxes.is_empty();
    report.covered = 0.0;
    sites(&boxes)
}

/// The room probes of `boxes` (centre, box), named room-1, room-2, …
fn sites(boxes: &[(DVec3, (DVec3, DVec3))]) -> Vec<ProbeSite> {
    let r = |v: f64| (v * 1e4).round() / 1e4;
    boxes
        .iter()
        .enumerate()
        .map(|(i, (c, (lo, hi)))| ProbeSite {
            name: format!("room-{}", i + 1),
            centre: c.to_array().map(r),
            box_min: Some(lo.to_array().map(r)),
            box_max: Some(hi.to_array().map(r)),
        })
        .map(|mut s| {
            // Rounding must keep the centre inside its box.
            for k in 0..3 {
                if let (Some(lo), Some(hi)) = (s.box_min.as_mut(), s.box_max.as_mut()) {
                    lo[k] = lo[k].min(s.centre[k]);
                    hi[k] = hi[k].max(s.centre[k]);
                }
            }
            s
        })
        .collect()
}

/// Applies `setup` to `scene` in memory: the hints to the meshes that had none (keeping their
/// light-map densities), the room probes
/// when the scene lists none.
pub fn apply(scene: &mut Scene, setup: &Setup) {
    for (name, h) in &setup.objects {
        for m in scene.meshes.iter_mut().filter(|m| &m.name == name) {
            let thickness = m.hints.thickness.or(h.thickness);
            if !has_realtime_hints(&m.hints) {
                m.hints = ObjectHints {
                    lightmap_texels_per_metre: m.hints.lightmap_texels_per_metre,
                    ..*h
                };
            }
            m.hints.thickness = thickness;
        }
    }
    if scene.probes.is_empty() {
        scene.probes = setup.probes.clone();
    }
}

/// Removes every real-time hint and room probe of `scene` (keeping light-map densities), for
/// a set-up decided from scratch.
pub fn clear_hints(scene: &mut Scene) {
    for m in &mut scene.meshes {
        m.hints = ObjectHints {
            lightmap_texels_per_metre: m.hints.lightmap_texels_per_metre,
            ..ObjectHints::default()
        };
    }
    scene.probes.clear();
}
