//! Textured quad emitters (004 §IV.5.3, Fig. IV.7, IV.21): a parallelogram that emits on the
//! side of edge_u × edge_v, its radiance a scale times a texture, shaded by sampling the light
//! directly (no BRDF importance sampling, no visibility, as 004), and its bandwidth propagated
//! to the pixel through the operators of Fig. IV.9.
//!
//! A scene's own emitters become such lights ([`scene_lights`]): each planar group of emissive
//! triangles, drawn into the texture of the smallest rectangle around it.
//!
//! The texture's spatial bandwidth (cycles per metre) comes from
//! `lustre_freq::spatial::area_light_bandwidth` (zero-padded: the light's border is an edge of
//! its emission). Seen from a point, a path leaves the light at angle θl to its normal, so its
//! spatial bandwidth across the ray is ν_s / cos θl (the projection P of Fig. IV.9); T_d then
//! shears it into the angular bandwidth d ν_s / cos θl that the surface receives (Eq. IV.5).

use crate::{AdaptiveError, Result};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_freq::spatial::area_light_bandwidth;

/// The texture of a light without one: constant, at a resolution fine enough for its edges'
/// bandwidth to show.
const PLAIN: usize = 16;

/// A textured parallelogram emitter.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// The corner at (u, v) = (0, 0).
    pub corner: DVec3,
    /// The edge to (1, 0).
    pub edge_u: DVec3,
    /// The edge to (0, 1).
    pub edge_v: DVec3,
    /// Radiance scale.
    pub radiance: Rgb,
    width: usize,
    height: usize,
    texels: Vec<[f32; 3]>,
    bandwidth: Vec<f64>,
    normal: DVec3,
    area: f64,
}

impl AreaLight {
    /// A light of `radiance` × `texture` (`(width, height, texels)`, row-major with row 0 at
    /// v = 0; `None`: constant). Errors, by name, on degenerate or non-finite edges, a negative
    /// or non-finite radiance, or a texture whose size does not match or that holds a negative
    /// or non-finite texel.
    pub fn new(
        corner: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
        radiance: Rgb,
        texture: Option<(usize, usize, Vec<[f32; 3]>)>,
    ) -> Result<Self> {
        let cross = edge_u.cross(edge_v);
        let area = cross.length();
        if !(corner.is_finite() && edge_u.is_finite() && edge_v.is_finite() && area > 1e-12) {
            return Err(AdaptiveError::Parameter(format!(
                "area light at {corner} with edges {edge_u} and {edge_v}: degenerate or not finite"
            )));
        }
        if !radiance.0.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(AdaptiveError::Parameter(format!(
                "area light radiance {:?} must be finite and ≥ 0",
                radiance.0
            )));
        }
        let (width, height, texels) =
            texture.unwrap_or_else(|| (PLAIN, PLAIN, vec![[1.0; 3]; PLAIN * PLAIN]));
        if width == 0 || height == 0 || texels.len() != width * height {
            return Err(AdaptiveError::Parameter(format!(
                "area light texture of {width} × {height} with {} texels",
                texels.len()
            )));
        }
        if let Some(k) = texels
            .iter()
            .position(|t| !t.iter().all(|c| c.is_finite() && *c >= 0.0))
        {
            return Err(AdaptiveError::Parameter(format!(
                "area light texel ({}, {}) is {:?} (must be finite and ≥ 0)",
                k % width,
                k / width,
                texels[k]
            )));
        }
        let bandwidth =
            area_light_bandwidth(&texels, width, height, (edge_u.length(), edge_v.length()))?;
        Ok(Self {
            corner,
            edge_u,
            edge_v,
            radiance,
            width,
            height,
            texels,
            bandwidth,
            normal: cross / area,
            area,
        })
    }

    /// The unit normal of the emitting side.
    pub fn normal(&self) -> DVec3 {
        self.normal
    }

    /// The area (m²).
    pub fn area(&self) -> f64 {
        self.area
    }

    /// The point at (u, v) ∈ [0, 1]².
    pub fn point(&self, u: f64, v: f64) -> DVec3 {
        self.corner + self.edge_u * u + self.edge_v * v
    }

    fn texel(&self, u: f64, v: f64) -> usize {
        let x = ((u * self.width as f64) as usize).min(self.width - 1);
        let y = ((v * self.height as f64) as usize).min(self.height - 1);
        y * self.width + x
    }

    /// The emitted radiance at (u, v) (nearest texel).
    pub fn emitted(&self, u: f64, v: f64) -> Rgb {
        let t = self.texels[self.texel(u, v)];
        Rgb([
            self.radiance.0[0] * f64::from(t[0]),
            self.radiance.0[1] * f64::from(t[1]),
            self.radiance.0[2] * f64::from(t[2]),
        ])
    }

    /// The texture: width, height and row-major texels (row 0 at v = 0).
    pub fn texture(&self) -> (usize, usize, &[[f32; 3]]) {
        (self.width, self.height, &self.texels)
    }

    /// The spatial bandwidth at (u, v) (cycles per metre, nearest texel).
    pub fn bandwidth_at(&self, u: f64, v: f64) -> f64 {
        self.bandwidth[self.texel(u, v)]
    }

    /// Sample (u, v) seen from `p`: the unit direction to it, its distance, and the cosine at
    /// the light (≤ 0 when `p` lies behind the emitting side).
    pub fn towards(&self, p: DVec3, u: f64, v: f64) -> (DVec3, f64, f64) {
        let d = self.point(u, v) - p;
        let dist = d.length();
        if dist <= 0.0 || !dist.is_finite() {
            return (DVec3::Z, 0.0, 0.0);
        }
        let w = d / dist;
        (w, dist, -w.dot(self.normal))
    }
}

/// Errors, saying why, when nothing lights `scene` for adaptive shading: no environment (or a
/// black one, radiance scale 0) and none of `lights`. A check callers can make before building
/// the materials' tables ([`crate::shading::ShadingContext::check_lit`] makes it after).
pub fn check_lit(scene: &lustre_trace::path_tracer::PathScene, lights: &[AreaLight]) -> Result<()> {
    let env_lit = scene.environment.as_ref().is_some_and(|e| e.scale() > 0.0);
    if env_lit || !lights.is_empty() {
        Ok(())
    } else {
        Err(AdaptiveError::Parameter(
            "nothing lights the scene: it has no environment and no planar emitter (adaptive \
             shading lights by the environment and by area lights, 004 ch. IV)"
                .into(),
        ))
    }
}

/// Texels along the longer side of a scene emitter's light ([`scene_lights`]).
const EMITTER_TEXELS: usize = 32;
/// Coverage sub-samples per texel and axis when an emitter is drawn into its light's texture.
const EMITTER_SUBSAMPLES: usize = 4;
/// Largest |sin| between an emitter triangle's normal and its emitter's plane normal, and the
/// largest distance of a vertex from that plane as a fraction of the emitter's size, for the
/// emitter to count as planar.
const PLANAR_TOLERANCE: f64 = 1e-3;

/// The scene's own emitters as area lights (004 §IV.5.3 takes textured quads): its emissive
/// triangles grouped by shared vertices; each group, which must be planar and emit on one side,
/// becomes the smallest rectangle around it (over the group's edge directions) whose texture
/// is the group drawn into it — the triangles' radiance (times the material's emission texture,
/// if any) where they cover a texel, 0 outside, coverage-weighted — scaled so that each colour
/// channel's ∫ L dA equals the triangles' own. A disk becomes its square with the disk drawn
/// in it; a rectangle, itself. No emissive triangle: no light. Errors, naming the group, on
/// one that is not planar or emits on both sides.
pub fn scene_lights(scene: &lustre_trace::path_tracer::PathScene) -> Result<Vec<AreaLight>> {
    let g = &scene.geometry;
    let emissive: Vec<usize> = (0..g.positions.len())
        .filter(|&i| g.emission.get(i).is_some_and(|e| e.max_component() > 0.0))
        .collect();
    // Union–find over the emissive triangles: two that share a vertex (positions equal to
    // 1e-9 of the scene's scale) belong to one emitter.
    let scale = emissive
        .iter()
        .flat_map(|&i| g.positions[i])
        .map(|p| p.abs().max_element())
        .fold(1.0f64, f64::max);
    let key = |p: DVec3| {
        let q = p / (scale * 1e-9);
        (q.x.round() as i64, q.y.round() as i64, q.z.round() as i64)
    };
    let mut parent: Vec<usize> = (0..emissive.len()).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut first_at = std::collections::HashMap::new();
    for (k, &i) in emissive.iter().enumerate() {
        for p in g.positions[i] {
            let other = *first_at.entry(key(p)).or_insert(k);
            let (a, b) = (find(&mut parent, k), find(&mut parent, other));
            parent[a] = b;
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for (k, &tri) in emissive.iter().enumerate() {
        let root = find(&mut parent, k);
        groups.entry(root).or_default().push(tri);
    }
    groups
        .into_values()
        .map(|tris| emitter_light(scene, &tris))
        .collect()
}

/// One planar emitter (triangles `tris` of `scene`) as a textured rectangle.
fn emitter_light(
    scene: &lustre_trace::path_tracer::PathScene,
    tris: &[usize],
) -> Result<AreaLight> {
    let g = &scene.geometry;
    let centroid = tris
        .iter()
        .flat_map(|&i| g.positions[i])
        .fold(DVec3::ZERO, |a, p| a + p)
        / (3 * tris.len()) as f64;
    let name = || format!("emitter of {} triangles around {centroid:.3}", tris.len());
    // The emitting side: the shading normals where the scene has them (the path tracer's
    // `emitted` looks at them), else the winding's.
    let facing = |i: usize| -> (DVec3, DVec3, f64) {
        let [a, b, c] = g.positions[i];
        let cross = (b - a).cross(c - a);
        let area = 0.5 * cross.length();
        let ng = cross.normalize_or_zero();
        let side = match g.normals.get(i) {
            Some(ns) => ns[0] + ns[1] + ns[2],
            None => ng,
        };
        let ng = if ng.dot(side) < 0.0 { -ng } else { ng };
        (ng, side, area)
    };
    let total_area: f64 = tris.iter().map(|&i| facing(i).2).sum();
    let size = tris
        .iter()
        .flat_map(|&i| g.positions[i])
        .map(|p| (p - centroid).length())
        .fold(0.0f64, f64::max);
    if !(total_area > 0.0 && total_area.is_finite() && size > 0.0 && size.is_finite()) {
        return Err(AdaptiveError::Parameter(format!(
            "{}: degenerate (no area, or not finite)",
            name()
        )));
    }
    // The area-weighted normal (zero for a closed surface, which the test below refuses).
    let n = tris
        .iter()
        .map(|&i| {
            let (ng, _, area) = facing(i);
            ng * area
        })
        .fold(DVec3::ZERO, |a, v| a + v)
        .normalize_or_zero();
    for &i in tris {
        let (ng, side, area) = facing(i);
        let off_plane = g.positions[i]
            .iter()
            .map(|p| (*p - centroid).dot(n).abs())
            .fold(0.0f64, f64::max);
        if area > 0.0
            && (n == DVec3::ZERO
                || ng.cross(n).length() > PLANAR_TOLERANCE
                || side.dot(n) <= 0.0
                || off_plane > PLANAR_TOLERANCE * size)
        {
            return Err(AdaptiveError::Parameter(format!(
                "{}: not planar or not emitting on one side (triangle {i}); adaptive shading \
                 takes planar emitters (004 §IV.5.3)",
                name()
            )));
        }
    }
    // The rectangle: over the group's edge directions, the one whose bounding box in the
    // plane is smallest.
    let points: Vec<DVec3> = tris.iter().flat_map(|&i| g.positions[i]).collect();
    let mut best: Option<(f64, DVec3, [f64; 4])> = None;
    for &i in tris.iter().take(64) {
        let [a, b, c] = g.positions[i];
        for e in [b - a, c - b, a - c] {
            let u = (e - n * e.dot(n)).normalize_or_zero();
            if u == DVec3::ZERO {
                continue;
            }
            let v = n.cross(u);
            let mut bb = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
            for p in &points {
                let (x, y) = ((*p - centroid).dot(u), (*p - centroid).dot(v));
                bb = [bb[0].min(x), bb[1].min(y), bb[2].max(x), bb[3].max(y)];
            }
            let area = (bb[2] - bb[0]) * (bb[3] - bb[1]);
            if best.as_ref().is_none_or(|(a, _, _)| area < *a) {
                best = Some((area, u, bb));
            }
        }
    }
    let (_, u, bb) = best
        .ok_or_else(|| AdaptiveError::Parameter(format!("{}: no edge to orient it by", name())))?;
    let v = n.cross(u);
    let (lu, lv) = (bb[2] - bb[0], bb[3] - bb[1]);
    if !(lu > 0.0 && lv > 0.0) {
        return Err(AdaptiveError::Parameter(format!("{}: no area", name())));
    }
    let corner = centroid + u * bb[0] + v * bb[1];
    let (edge_u, edge_v) = (u * lu, v * lv);
    let (w, h) = if lu >= lv {
        let h = ((EMITTER_TEXELS as f64 * lv / lu).round() as usize).clamp(4, EMITTER_TEXELS);
        (EMITTER_TEXELS, h)
    } else {
        let w = ((EMITTER_TEXELS as f64 * lu / lv).round() as usize).clamp(4, EMITTER_TEXELS);
        (w, EMITTER_TEXELS)
    };
    // Each triangle drawn into the sub-sample grid (a sub-sample already covered keeps its
    // first triangle, so shared edges count once).
    let s = EMITTER_SUBSAMPLES;
    let (sw, sh) = (w * s, h * s);
    let mut sub: Vec<Option<Rgb>> = vec![None; sw * sh];
    let mut exact = [0.0f64; 3];
    for &i in tris {
        let k = g.material[i] as usize;
        let textured = scene
            .materials
            .get(k)
            .is_some_and(|m| m.emission_textured());
        let e = g.emission[i];
        let [a, b, c] = g.positions[i];
        let to_plane = |p: DVec3| ((p - corner).dot(u) / lu, (p - corner).dot(v) / lv);
        let (pa, pb, pc) = (to_plane(a), to_plane(b), to_plane(c));
        let det = (pb.0 - pa.0) * (pc.1 - pa.1) - (pc.0 - pa.0) * (pb.1 - pa.1);
        if det.abs() < 1e-300 {
            continue;
        }
        let area = 0.5 * (b - a).cross(c - a).length();
        let uvs = g.uvs.get(i);
        // ∫ L dA of the triangle itself (its texture's mean over it by the same sub-samples
        // where textured: filled in below).
        let mut tri_sum = [0.0f64; 3];
        let mut tri_count = 0usize;
        let x0 = ((pa.0.min(pb.0).min(pc.0) * sw as f64).floor().max(0.0)) as usize;
        let x1 = ((pa.0.max(pb.0).max(pc.0) * sw as f64).ceil() as usize).min(sw);
        let y0 = ((pa.1.min(pb.1).min(pc.1) * sh as f64).floor().max(0.0)) as usize;
        let y1 = ((pa.1.max(pb.1).max(pc.1) * sh as f64).ceil() as usize).min(sh);
        for y in y0..y1 {
            for x in x0..x1 {
                let p = ((x as f64 + 0.5) / sw as f64, (y as f64 + 0.5) / sh as f64);
                let l1 = ((pb.0 - p.0) * (pc.1 - p.1) - (pc.0 - p.0) * (pb.1 - p.1)) / det;
                let l2 = ((pc.0 - p.0) * (pa.1 - p.1) - (pa.0 - p.0) * (pc.1 - p.1)) / det;
                let l3 = 1.0 - l1 - l2;
                if l1 < 0.0 || l2 < 0.0 || l3 < 0.0 {
                    continue;
                }
                let radiance = match (textured, uvs) {
                    (true, Some(t)) => {
                        let uv = [
                            l1 * t[0][0] + l2 * t[1][0] + l3 * t[2][0],
                            l1 * t[0][1] + l2 * t[1][1] + l3 * t[2][1],
                        ];
                        e * scene.materials[k].emission_factor(uv)
                    }
                    _ => e,
                };
                for (acc, c) in tri_sum.iter_mut().zip(radiance.0) {
                    *acc += c;
                }
                tri_count += 1;
                let cell = &mut sub[y * sw + x];
                if cell.is_none() {
                    *cell = Some(radiance);
                }
            }
        }
        // The triangle's ∫ L dA: its area times its radiance (averaged over its sub-samples
        // where textured; a triangle smaller than a sub-sample counts by its own radiance).
        let mean = if tri_count > 0 && textured {
            tri_sum.map(|s| s / tri_count as f64)
        } else {
            e.0
        };
        for (acc, m) in exact.iter_mut().zip(mean) {
            *acc += area * m;
        }
    }
    let mut texels = vec![[0.0f32; 3]; w * h];
    let mut drawn = [0.0f64; 3];
    for y in 0..sh {
        for x in 0..sw {
            if let Some(r) = sub[y * sw + x] {
                let t = &mut texels[(y / s) * w + x / s];
                for c in 0..3 {
                    t[c] += (r.0[c] / (s * s) as f64) as f32;
                    drawn[c] += r.0[c];
                }
            }
        }
    }
    // ∫ L dA as drawn: Σ sub-samples × (area of a sub-sample).
    let sub_area = lu * lv / (sw * sh) as f64;
    let radiance = Rgb(std::array::from_fn(|c| {
        let d = drawn[c] * sub_area;
        if d > 0.0 {
            exact[c] / d
        } else {
            0.0
        }
    }));
    AreaLight::new(corner, edge_u, edge_v, radiance, Some((w, h, texels)))
}
