//! Evaluation scenes: a pinhole camera, spheres and square planes carrying Kurt materials.
//!
//! The formulas are part of the shared contract (the GPU renderer mirrors them in WGSL):
//!
//! - **LookAtCamera.** For pixel (x, y) of a W×H image: fwd = normalize(target − eye),
//!   right = normalize(fwd × up), up' = right × fwd, a = tan(fov_y/2),
//!   px = (2(x+½)/W − 1)·a·W/H, py = (1 − 2(y+½)/H)·a, dir = normalize(fwd + px·right + py·up').
//! - **Sphere frame.** n = (p − c)/r, t = normalize(axis × n); where |axis × n| < 1e-6 (at the
//!   poles) t = normalize(x̂ × n), and where that is degenerate too, t = ẑ. b = n × t.
//! - **Plane frame.** n = normal, t = the tangent made orthogonal to n (Gram–Schmidt), b = n × t;
//!   the plane is the square |(p − point)·t| ≤ half_size, |(p − point)·b| ≤ half_size.
//! - **Facing.** The Kurt surface is thin and two-sided, so a hit seen from the back side is shaded
//!   with n flipped towards the viewer (t kept, b = n × t recomputed): `frame.n · wo ≥ 0` always.
//!
//! Intersections take the nearest hit with ray parameter t > [`T_MIN`]; rays starting inside a
//! sphere hit its far side, hits behind the origin are ignored, a ray parallel to a plane misses it,
//! and a ray grazing a sphere (discriminant ≥ 0) hits it once.

use crate::{Result, ShadeError};
use glam::DVec3;
use lustre_brdf::models::kurt::Kurt;
use lustre_trace::sampling::ShadingFrame;

/// Smallest accepted ray parameter of a hit (world units; rays have unit direction).
pub const T_MIN: f64 = 1e-9;

/// A pinhole camera (vertical field of view in degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LookAtCamera {
    /// Centre of projection.
    pub eye: DVec3,
    /// The point the camera looks at (centre pixel direction).
    pub target: DVec3,
    /// The up hint (need not be orthogonal to the view direction, must not be parallel to it).
    pub up: DVec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub fov_y_deg: f64,
}

/// A sphere; `axis` orients the anisotropic tangent (t = normalize(axis × n), along the latitude
/// circles around the axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius, > 0.
    pub radius: f64,
    /// Index into [`AnalyticScene::materials`].
    pub material: usize,
    /// Tangent axis (unit length expected; see the module docs for the degenerate case).
    pub axis: DVec3,
}

/// A square of side 2·half_size centred at `point`, in the plane through `point` with `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Centre of the square.
    pub point: DVec3,
    /// Plane normal (unit length expected).
    pub normal: DVec3,
    /// The anisotropic tangent direction (made orthogonal to `normal`); the square's edges run
    /// along it and along normal × tangent.
    pub tangent: DVec3,
    /// Half the side of the square (may be infinite for an unbounded plane).
    pub half_size: f64,
    /// Index into [`AnalyticScene::materials`].
    pub material: usize,
}

/// LookAtCamera, geometry and the Kurt materials the geometry refers to.
#[derive(Clone, Debug, PartialEq)]
pub struct AnalyticScene {
    /// The viewpoint.
    pub camera: LookAtCamera,
    /// Spheres.
    pub spheres: Vec<Sphere>,
    /// Square planes.
    pub planes: Vec<Plane>,
    /// Materials, indexed by `Sphere::material` and `Plane::material`.
    pub materials: Vec<Kurt>,
}

/// A ray–surface hit, ready for shading.
#[derive(Clone, Copy, Debug)]
pub struct AnalyticHit {
    /// World position.
    pub position: DVec3,
    /// Orthonormal shading frame (b = n × t), n facing the viewer.
    pub frame: ShadingFrame,
    /// Unit direction to the viewer (−ray direction).
    pub wo: DVec3,
    /// Index into [`AnalyticScene::materials`].
    pub material: usize,
}

impl LookAtCamera {
    /// The camera basis (fwd, right, up') of the contract, or `None` when it is degenerate (eye at
    /// the target, up parallel to the view direction, non-finite values).
    pub fn basis(&self) -> Option<(DVec3, DVec3, DVec3)> {
        let fwd = (self.target - self.eye).try_normalize()?;
        let right = fwd.cross(self.up).try_normalize()?;
        Some((fwd, right, right.cross(fwd)))
    }
}

impl Sphere {
    /// The shading frame at a point `p` on the sphere (outward normal), per the module docs.
    pub fn frame_at(&self, p: DVec3) -> ShadingFrame {
        let n = ((p - self.center) / self.radius).normalize();
        let mut t = self.axis.cross(n);
        if t.length() < 1e-6 {
            t = DVec3::X.cross(n);
            if t.length() < 1e-6 {
                t = DVec3::Z;
            }
        }
        let t = t.normalize();
        ShadingFrame {
            t,
            b: n.cross(t),
            n,
        }
    }

    /// The nearest ray parameter t > [`T_MIN`] where the ray o + t·d (d unit) meets the sphere.
    ///
    /// The discriminant is formed as r² − |f − (f·d)d|² (f = o − c), which keeps its precision
    /// for distant spheres, and the roots as q = −f·d ± √disc, t = c/q (the stable pair).
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<f64> {
        let f = o - self.center;
        let b = f.dot(d);
        let perp = f - b * d;
        let r2 = self.radius * self.radius;
        let disc = r2 - perp.length_squared();
        if disc.is_nan() || disc < 0.0 {
            return None;
        }
        let c = f.length_squared() - r2;
        let q = -b - b.signum() * disc.sqrt();
        let (t0, t1) = if q == 0.0 {
            (0.0, 0.0)
        } else {
            let (a, z) = (c / q, q);
            (a.min(z), a.max(z))
        };
        if t0 > T_MIN {
            Some(t0)
        } else if t1 > T_MIN {
            Some(t1)
        } else {
            None
        }
    }
}

impl Plane {
    /// The shading frame of the plane (normal side), per the module docs.
    pub fn frame(&self) -> ShadingFrame {
        let n = self.normal.normalize();
        let mut t = self.tangent - n * n.dot(self.tangent);
        if t.length() < 1e-6 {
            t = DVec3::X.cross(n);
            if t.length() < 1e-6 {
                t = DVec3::Z;
            }
        }
        let t = t.normalize();
        ShadingFrame {
            t,
            b: n.cross(t),
            n,
        }
    }

    /// The ray parameter t > [`T_MIN`] where the ray o + t·d meets the square, if it does.
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<f64> {
        let fr = self.frame();
        let denom = d.dot(fr.n);
        if denom.is_nan() || denom.abs() <= 1e-12 {
            return None;
        }
        let t = (self.point - o).dot(fr.n) / denom;
        if !(t > T_MIN && t.is_finite()) {
            return None;
        }
        let q = o + t * d - self.point;
        (q.dot(fr.t).abs() <= self.half_size && q.dot(fr.b).abs() <= self.half_size).then_some(t)
    }
}

impl AnalyticScene {
    /// Checks the scene: a usable camera, finite geometry, positive radii and sizes, non-zero
    /// normals and material indices in range. Names the offending item.
    pub fn validate(&self) -> Result<()> {
        let c = &self.camera;
        let finite = |v: DVec3| v.is_finite();
        if !(finite(c.eye) && finite(c.target) && finite(c.up)) || c.basis().is_none() {
            return Err(ShadeError::Parameter(format!(
                "camera: eye {:?}, target {:?}, up {:?} do not define a view (eye = target or up parallel to the view)",
                c.eye, c.target, c.up
            )));
        }
        if !(c.fov_y_deg > 0.0 && c.fov_y_deg < 180.0) {
            return Err(ShadeError::Parameter(format!(
                "camera: fov_y_deg = {} must lie in (0, 180)",
                c.fov_y_deg
            )));
        }
        let nm = self.materials.len();
        for (i, s) in self.spheres.iter().enumerate() {
            if !(finite(s.center) && finite(s.axis) && s.radius > 0.0 && s.radius.is_finite()) {
                return Err(ShadeError::Parameter(format!(
                    "sphere {i}: centre {:?}, radius {}, axis {:?} (radius must be finite and > 0)",
                    s.center, s.radius, s.axis
                )));
            }
            if s.material >= nm {
                return Err(ShadeError::Parameter(format!(
                    "sphere {i}: material {} out of range ({nm} materials)",
                    s.material
                )));
            }
        }
        for (i, p) in self.planes.iter().enumerate() {
            let ok = finite(p.point)
                && finite(p.tangent)
                && p.normal.try_normalize().is_some()
                && p.half_size > 0.0;
            if !ok {
                return Err(ShadeError::Parameter(format!(
                    "plane {i}: point {:?}, normal {:?}, tangent {:?}, half_size {} (normal non-zero, half_size > 0)",
                    p.point, p.normal, p.tangent, p.half_size
                )));
            }
            if p.material >= nm {
                return Err(ShadeError::Parameter(format!(
                    "plane {i}: material {} out of range ({nm} materials)",
                    p.material
                )));
            }
        }
        Ok(())
    }

    /// The primary ray (origin, unit direction) through the centre of pixel (x, y) of a w×h
    /// image, by the contract's camera formula. A degenerate camera (see [`AnalyticScene::validate`])
    /// gives a NaN direction, which [`AnalyticScene::intersect`] treats as a miss.
    pub fn primary(&self, x: usize, y: usize, w: usize, h: usize) -> (DVec3, DVec3) {
        let c = &self.camera;
        let Some((fwd, right, up)) = c.basis() else {
            return (c.eye, DVec3::NAN);
        };
        let a = (c.fov_y_deg.to_radians() * 0.5).tan();
        let (wf, hf) = (w as f64, h as f64);
        let px = (2.0 * (x as f64 + 0.5) / wf - 1.0) * a * wf / hf;
        let py = (1.0 - 2.0 * (y as f64 + 0.5) / hf) * a;
        (c.eye, (fwd + px * right + py * up).normalize())
    }

    /// The nearest hit of the ray o + t·d (t > [`T_MIN`]), with the shading frame facing the
    /// viewer. `d` need not be normalized; a zero or non-finite ray misses.
    pub fn intersect(&self, o: DVec3, d: DVec3) -> Option<AnalyticHit> {
        let d = d.try_normalize()?;
        if !o.is_finite() {
            return None;
        }
        let mut best: Option<(f64, ShadingFrame, usize)> = None;
        let closer = |t: f64, best: &Option<(f64, ShadingFrame, usize)>| match best {
            Some((bt, _, _)) => t < *bt,
            None => true,
        };
        for s in &self.spheres {
            if let Some(t) = s.intersect(o, d) {
                if closer(t, &best) {
                    best = Some((t, s.frame_at(o + t * d), s.material));
                }
            }
        }
        for p in &self.planes {
            if let Some(t) = p.intersect(o, d) {
                if closer(t, &best) {
                    best = Some((t, p.frame(), p.material));
                }
            }
        }
        let (t, mut frame, material) = best?;
        let wo = -d;
        if frame.n.dot(wo) < 0.0 {
            frame.n = -frame.n;
            frame.b = frame.n.cross(frame.t);
        }
        Some(AnalyticHit {
            position: o + t * d,
            frame,
            wo,
            material,
        })
    }
}
