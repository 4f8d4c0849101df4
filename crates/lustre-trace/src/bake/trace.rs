//! One texel's irradiance: sample points, the validity test, one path per valid point.

use super::raster::{texel_seed, Raster};
use super::{diffuse_albedo, BakeOptions, PROBES, PROBE_BACKFACE_LIMIT};
use crate::path_tracer::{offset, PathScene, PathTracer};
use glam::{DVec3, Vec2};
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::{cosine_hemisphere, to_world, SplitMix64};
use lustre_scene::Scene;

/// Chart id of a texel no triangle covers.
pub const NO_CHART: u32 = u32::MAX;

/// What a bake stores per texel (the payload of a tile file, 17 little-endian 32-bit words).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexelRecord {
    /// Mean irradiance over the valid samples (0 when none).
    pub e: [f32; 3],
    /// Variance of that mean, per channel (sample variance / valid count; 0 below 2 samples).
    pub var: [f32; 3],
    /// Valid samples.
    pub valid: u32,
    /// The texel's chart, [`NO_CHART`] when uncovered.
    pub chart: u32,
    /// Mean world position of the samples (valid ones when there are any).
    pub position: [f32; 3],
    /// Mean shading normal (unit), same samples.
    pub normal: [f32; 3],
    /// Mean diffuse albedo, same samples.
    pub albedo: [f32; 3],
}

impl TexelRecord {
    /// Covered by a chart.
    pub fn covered(&self) -> bool {
        self.chart != NO_CHART
    }
}

/// Per-triangle data of the path tracer's geometry the baker reads.
pub struct TexelBaker<'a, 's> {
    pub(crate) scene: &'s Scene,
    pub(crate) ps: &'a PathScene<'s>,
    pub(crate) pt: &'a PathTracer<'a, 's>,
    pub(crate) raster: &'a Raster,
    pub(crate) bases: &'a [super::BaseAlbedo],
    pub(crate) opts: &'a BakeOptions,
}

/// A sample point on the surface.
#[derive(Clone, Copy, Debug)]
struct Point {
    p: DVec3,
    ng: DVec3,
    ns: DVec3,
    albedo: Rgb,
    /// Distance in texels from the texel centre.
    centre_dist2: f64,
}

/// Counters of a texel's samples.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexelCounts {
    /// Samples taken.
    pub samples: u64,
    /// Samples found invalid (inside or behind geometry).
    pub invalid: u64,
}

impl TexelBaker<'_, '_> {
    /// Geometric normal of triangle `prim` turned to its shading normal's side at `b`, and the
    /// unit shading normal (the path tracer's own).
    fn normals(&self, prim: usize, b: [f64; 3]) -> (DVec3, DVec3) {
        self.pt.normals(prim, b)
    }

    fn point(&self, tri: u32, b: [f64; 3], uv: [f64; 2], x: u32, y: u32) -> Point {
        let t = &self.raster.triangles[tri as usize];
        let prim = t.prim as usize;
        let g = &self.ps.geometry;
        let c = &g.positions[prim];
        let p = c[0] * b[0] + c[1] * b[1] + c[2] * b[2];
        let (ng, ns) = self.normals(prim, b);
        let uv0 = g.uvs.get(prim).map_or([0.0; 2], |u| {
            [0, 1].map(|k| b[0] * u[0][k] + b[1] * u[1][k] + b[2] * u[2][k])
        });
        let uv1 = [0, 1].map(|k| {
            let s = [f64::from(self.raster.width), f64::from(self.raster.height)][k];
            (b[0] * t.uv[0][k] + b[1] * t.uv[1][k] + b[2] * t.uv[2][k]) / s
        });
        let m = g.material[prim] as usize;
        let albedo = diffuse_albedo(
            &self.scene.materials[m],
            &self.scene.textures,
            &[
                Vec2::new(uv0[0] as f32, uv0[1] as f32),
                Vec2::new(uv1[0] as f32, uv1[1] as f32),
            ],
            self.bases[m],
        );
        let (dx, dy) = (uv[0] - f64::from(x) - 0.5, uv[1] - f64::from(y) - 0.5);
        Point {
            p,
            ng,
            ns,
            albedo,
            centre_dist2: dx * dx + dy * dy,
        }
    }

    /// Whether the front of a hit triangle faces away from a ray along `d` (a back face of
    /// a one-sided material).
    fn back_face(&self, prim: usize, bary: [f64; 3], d: DVec3) -> bool {
        let m = self.ps.geometry.material[prim] as usize;
        if self.ps.materials[m].two_sided() {
            return false;
        }
        let (ng, _) = self.normals(prim, bary);
        ng.dot(d) > 0.0
    }

    /// Whether at least [`PROBE_BACKFACE_LIMIT`] of [`PROBES`] cosine-distributed probe rays
    /// from `q` hit a back face.
    fn buried(&self, q: &Point, rng: &mut SplitMix64) -> bool {
        let mut back = 0;
        for j in 0..PROBES {
            // Stratified in azimuth so that the probes spread out.
            let u1 = (f64::from(j) + rng.next_f64()) / f64::from(PROBES);
            let u2 = rng.next_f64();
            let d = to_world(cosine_hemisphere(u2, u1), q.ng);
            let o = offset(q.p, q.ng, d);
            if let Some(h) = self.pt.intersect(o, d) {
                if self.back_face(h.prim, h.bary, d) {
                    back += 1;
                    if back >= PROBE_BACKFACE_LIMIT {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Bakes texel (x, y) of `page`.
    pub fn texel(&self, page: u32, x: u32, y: u32) -> (TexelRecord, TexelCounts) {
        let Some((chart, tris)) = self.raster.texel(page, x, y) else {
            return (
                TexelRecord {
                    chart: NO_CHART,
                    ..TexelRecord::default()
                },
                TexelCounts::default(),
            );
        };
        let spp = self.opts.spp;
        let mut rngs = Vec::with_capacity(spp as usize);
        let mut points = Vec::with_capacity(spp as usize);
        for k in 0..spp {
            let mut rng = SplitMix64::new(texel_seed(self.opts.seed, page, x, y, k));
            let s = self.raster.sample(x, y, &tris, k, spp, &mut rng);
            let pt = s.map(|s| self.point(s.tri, s.bary, s.uv, x, y));
            let valid = pt.is_some_and(|q| !self.buried(&q, &mut rng));
            points.push((pt, valid));
            rngs.push(rng);
        }
        // The reference sample: the valid one nearest the texel centre; samples it cannot see
        // (a wall thinner than the texel between them) are invalid.
        let reference = points
            .iter()
            .enumerate()
            .filter_map(|(k, (p, v))| p.filter(|_| *v).map(|p| (k, p)))
            .min_by(|a, b| a.1.centre_dist2.total_cmp(&b.1.centre_dist2));
        if let Some((r, rp)) = reference {
            let lift = |q: &Point| {
                let ts = self.raster.triangles[tris[0] as usize].texel_size;
                q.p + q.ng * (0.05 * ts).max(1e-4 * (1.0 + q.p.abs().max_element()))
            };
            let a = lift(&rp);
            for (k, (p, v)) in points.iter_mut().enumerate() {
                if k == r || !*v {
                    continue;
                }
                let Some(q) = p else { continue };
                let b = lift(q);
                let Some(d) = (b - a).try_normalize() else {
                    continue;
                };
                if self.pt.occluded(a, d, (b - a).length()) {
                    *v = false;
                }
            }
        }
        let mut sum = [0.0f64; 3];
        let mut sum2 = [0.0f64; 3];
        let mut valid = 0u32;
        let (mut pos, mut nrm, mut alb) = (DVec3::ZERO, DVec3::ZERO, Rgb::ZERO);
        let (mut pos_all, mut nrm_all, mut alb_all) = (DVec3::ZERO, DVec3::ZERO, Rgb::ZERO);
        let mut n_all = 0u32;
        let mut counts = TexelCounts {
            samples: u64::from(spp),
            invalid: 0,
        };
        for ((p, v), rng) in points.iter().zip(rngs.iter_mut()) {
            let Some(q) = p else {
                counts.invalid += 1;
                continue;
            };
            pos_all += q.p;
            nrm_all += q.ns;
            alb_all += q.albedo;
            n_all += 1;
            if !*v {
                counts.invalid += 1;
                continue;
            }
            let e = self.pt.irradiance(q.p, q.ng, q.ns, rng);
            let e = if e.is_finite() { e } else { Rgb::ZERO };
            for c in 0..3 {
                sum[c] += e[c];
                sum2[c] += e[c] * e[c];
            }
            pos += q.p;
            nrm += q.ns;
            alb += q.albedo;
            valid += 1;
        }
        let (pos, nrm, alb, n) = if valid > 0 {
            (pos, nrm, alb, valid)
        } else {
            (pos_all, nrm_all, alb_all, n_all.max(1))
        };
        let nf = f64::from(n);
        let mut rec = TexelRecord {
            valid,
            chart,
            position: (pos / nf).as_vec3().to_array(),
            normal: nrm.normalize_or(DVec3::Z).as_vec3().to_array(),
            albedo: (alb / nf).0.map(|c| c as f32),
            ..TexelRecord::default()
        };
        if valid > 0 {
            let v = f64::from(valid);
            for c in 0..3 {
                let mean = sum[c] / v;
                rec.e[c] = mean as f32;
                if valid > 1 {
                    let s2 = ((sum2[c] - v * mean * mean) / (v - 1.0)).max(0.0);
                    rec.var[c] = (s2 / v) as f32;
                }
            }
        }
        (rec, counts)
    }
}
