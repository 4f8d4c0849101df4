//! Ray casting against triangle meshes: a compressed wide BVH (CWBVH, Ylitie et al. 2017) built
//! by `obvhs` (PLOC + reinsertion), with our watertight ray–triangle test (Woop, Benthin & Wald
//! 2013, "Watertight Ray/Triangle Intersection", JCGT 2(1)), closest hit and any-hit shadow
//! rays, and a callback that can reject a hit (alpha masks).
//!
//! Vertices are stored in f32 (as the BVH's bounds); the test runs in f32 with the paper's
//! fallback to f64 when an edge function is exactly zero, so a ray through a shared edge or
//! vertex hits at least one of the triangles that meet there.

use crate::{Result, TraceError};
use glam::{DVec3, Vec3A};
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::PlocBuilder;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

/// A ray hit: the triangle (index into the input), the distance along the (unit or not)
/// direction, and the barycentric weights of the triangle's three vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the triangle in the slice given to [`Accel::new`].
    pub prim: usize,
    /// Ray parameter: the hit point is origin + t · direction.
    pub t: f64,
    /// Barycentric weights (b0, b1, b2) of v0, v1, v2; they sum to 1.
    pub bary: [f64; 3],
}

/// A ray prepared for the watertight test: the axis permutation and shear constants of Woop et
/// al. 2013 §3 (kz = the dominant axis of the direction; kx, ky the others, swapped to keep the
/// winding when d[kz] < 0), folded into three row vectors so that the sheared coordinates of a
/// vertex are dot products: x = v·rx = v[kx] − sx·v[kz], y = v·ry = v[ky] − sy·v[kz],
/// z = v·rz = sz·v[kz]. The other entries are exact zeros, so each dot product rounds exactly
/// like the paper's scalar code (watertightness is kept).
#[derive(Clone, Copy, Debug)]
struct WoopRay {
    o: Vec3A,
    rx: Vec3A,
    ry: Vec3A,
    rz: Vec3A,
    /// False when the direction is zero or not finite (the ray hits nothing).
    valid: bool,
}

impl WoopRay {
    fn new(o: DVec3, d: DVec3) -> Self {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let (sx, sy, sz) = (
            (d[kx] / d[kz]) as f32,
            (d[ky] / d[kz]) as f32,
            (1.0 / d[kz]) as f32,
        );
        let mut rx = [0.0f32; 3];
        let mut ry = [0.0f32; 3];
        let mut rz = [0.0f32; 3];
        rx[kx] = 1.0;
        rx[kz] = -sx;
        ry[ky] = 1.0;
        ry[kz] = -sy;
        rz[kz] = sz;
        WoopRay {
            o: to3a(o),
            rx: Vec3A::from_array(rx),
            ry: Vec3A::from_array(ry),
            rz: Vec3A::from_array(rz),
            valid: sx.is_finite() && sy.is_finite() && sz.is_finite() && o.is_finite(),
        }
    }

    /// The watertight test against (a, b, c): Some((t, [b0, b1, b2])) for tmin < t < tmax.
    #[inline]
    fn intersect(&self, tri: &Triangle, tmin: f32, tmax: f32) -> Option<(f32, [f32; 3])> {
        let a = tri.v0 - self.o;
        let b = tri.v1 - self.o;
        let c = tri.v2 - self.o;
        // Shear and scale (Eq. 3–4 of the paper's Fig. 2 code).
        let (ax, ay) = (a.dot(self.rx), a.dot(self.ry));
        let (bx, by) = (b.dot(self.rx), b.dot(self.ry));
        let (cx, cy) = (c.dot(self.rx), c.dot(self.ry));
        // Scaled barycentrics (2D edge functions).
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // Fall back to double precision at exact zeros (the paper's §3.3).
            let (cxd, cyd, bxd, byd, axd, ayd) = (
                cx as f64, cy as f64, bx as f64, by as f64, ax as f64, ay as f64,
            );
            u = (cxd * byd - cyd * bxd) as f32;
            v = (axd * cyd - ayd * cxd) as f32;
            w = (bxd * ayd - byd * axd) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = a.dot(self.rz);
        let bz = b.dot(self.rz);
        let cz = c.dot(self.rz);
        let t_scaled = u * az + v * bz + w * cz;
        // Depth test without division: t = T / det must lie in (tmin, tmax).
        if det > 0.0 {
            if t_scaled <= tmin * det || t_scaled >= tmax * det {
                return None;
            }
        } else if t_scaled >= tmin * det || t_scaled <= tmax * det {
            return None;
        }
        let inv = 1.0 / det;
        Some((t_scaled * inv, [u * inv, v * inv, w * inv]))
    }
}

/// The acceleration structure of a triangle soup.
pub struct Accel {
    bvh: Option<CwBvh>,
    /// Triangles in the BVH's leaf order (`tris[i]` is input triangle `prims[i]`), so that a
    /// leaf reads consecutive triangles without the index indirection.
    tris: Vec<Triangle>,
    prims: Vec<u32>,
    /// Number of input triangles.
    len: usize,
}

impl std::fmt::Debug for Accel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Accel")
            .field("triangles", &self.tris.len())
            .finish()
    }
}

fn to3a(p: DVec3) -> Vec3A {
    Vec3A::new(p.x as f32, p.y as f32, p.z as f32)
}

/// A compressed wide BVH of `triangles` with obvhs's medium-quality parameters: the steps of
/// obvhs's `build_cwbvh_from_tris` (PLOC, reinsertion, conversion to CWBVH) without its build
/// timer, std's `Instant`, which panics in a browser (wasm32).
fn build_cwbvh(triangles: &[Triangle]) -> CwBvh {
    let config = BvhBuildParams::medium_build();
    let mut bvh2 = PlocBuilder::with_capacity(triangles.len()).build(
        config.ploc_search_distance,
        triangles,
        (0..triangles.len() as u32).collect::<Vec<_>>(),
        config.sort_precision,
        config.search_depth_threshold,
    );
    bvh2.uses_spatial_splits = config.pre_split;
    ReinsertionOptimizer::default().run(&mut bvh2, config.reinsertion_batch_ratio, None);
    bvh2_to_cwbvh(&bvh2, config.max_prims_per_leaf.clamp(1, 3), true, false)
}

impl Accel {
    /// Builds the BVH over `triangles` (world-space vertices). Errors on a non-finite vertex
    /// (naming the triangle). An empty soup is valid: every ray misses.
    pub fn new(triangles: &[[DVec3; 3]]) -> Result<Self> {
        let mut tris = Vec::with_capacity(triangles.len());
        for (k, t) in triangles.iter().enumerate() {
            if !t.iter().all(|p| p.is_finite()) {
                return Err(TraceError::Parameter(format!(
                    "triangle {k} has a non-finite vertex: {t:?}"
                )));
            }
            tris.push(Triangle {
                v0: to3a(t[0]),
                v1: to3a(t[1]),
                v2: to3a(t[2]),
            });
        }
        let bvh = (!tris.is_empty()).then(|| build_cwbvh(&tris));
        let prims = bvh
            .as_ref()
            .map_or_else(Vec::new, |b| b.primitive_indices.clone());
        let tris = prims.iter().map(|&k| tris[k as usize]).collect();
        Ok(Accel {
            bvh,
            tris,
            prims,
            len: triangles.len(),
        })
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True without triangles.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The closest hit of the ray o + t·d with tmin < t < tmax that `accept` (given the
    /// triangle and barycentrics) keeps; `accept` is how alpha masks reject hits.
    pub fn intersect(
        &self,
        o: DVec3,
        d: DVec3,
        tmin: f64,
        tmax: f64,
        mut accept: impl FnMut(usize, [f64; 3]) -> bool,
    ) -> Option<Hit> {
        let bvh = self.bvh.as_ref()?;
        let wr = WoopRay::new(o, d);
        if !wr.valid {
            return None;
        }
        let ray = bvh_ray(o, d, tmin, tmax);
        let mut rh = RayHit::none();
        let mut best: Option<Hit> = None;
        let (tris, prims) = (&self.tris, &self.prims);
        bvh.ray_traverse(ray, &mut rh, |r, id| {
            let prim = prims[id] as usize;
            match wr.intersect(&tris[id], r.tmin, r.tmax) {
                Some((t, b)) => {
                    let bary = b.map(|x| x as f64);
                    if accept(prim, bary) {
                        best = Some(Hit {
                            prim,
                            t: t as f64,
                            bary,
                        });
                        t
                    } else {
                        f32::INFINITY
                    }
                }
                None => f32::INFINITY,
            }
        });
        best
    }

    /// True when something `accept` keeps lies on the ray with tmin < t < tmax (any hit;
    /// shadow rays).
    pub fn occluded(
        &self,
        o: DVec3,
        d: DVec3,
        tmin: f64,
        tmax: f64,
        mut accept: impl FnMut(usize, [f64; 3]) -> bool,
    ) -> bool {
        let Some(bvh) = self.bvh.as_ref() else {
            return false;
        };
        let wr = WoopRay::new(o, d);
        if !wr.valid {
            return false;
        }
        let ray = bvh_ray(o, d, tmin, tmax);
        let (tris, prims) = (&self.tris, &self.prims);
        !bvh.ray_traverse_miss(ray, |r, id| {
            let prim = prims[id] as usize;
            match wr.intersect(&tris[id], r.tmin, r.tmax) {
                Some((t, b)) if accept(prim, b.map(|x| x as f64)) => t,
                _ => f32::INFINITY,
            }
        })
    }
}

/// The BVH's ray. Negative zeros in the direction become +0: obvhs picks the traversal octant
/// from `x < 0` but inverts −0 to −1/ε, and the two disagree on an axis-parallel ray (measured:
/// a ray along −z missed every triangle).
fn bvh_ray(o: DVec3, d: DVec3, tmin: f64, tmax: f64) -> Ray {
    let d = d + DVec3::ZERO;
    Ray::new(to3a(o), to3a(d), tmin as f32, tmax as f32)
}
