//! What the path tracer shares with lustre-shade's CPU kernels: the orthonormal shading frame
//! ([`ShadingFrame`]), the choice of sampling techniques ([`Strategy`]) and their multiple
//! importance sampling weight ([`power_heuristic`]).

use glam::DVec3;
use lustre_brdf::frame::basis;

/// An orthonormal shading frame in world space: tangent `t`, bitangent `b = n × t`, normal `n`.
/// Local coordinates of a world vector w are (w·t, w·b, w·n), the lustre-brdf convention
/// (normal +z, tangent +x).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingFrame {
    /// Tangent (the anisotropy axis, local +x).
    pub t: DVec3,
    /// Bitangent, n × t (local +y).
    pub b: DVec3,
    /// Normal (local +z).
    pub n: DVec3,
}

impl ShadingFrame {
    /// The frame with normal `n` (normalized) and the tangent `t_hint` made orthogonal to it by
    /// Gram–Schmidt. When `t_hint` is (nearly) parallel to `n`, zero or not finite, a tangent is
    /// chosen by `lustre_brdf::frame::basis`; a zero or non-finite `n` is replaced by +y.
    pub fn new(n: DVec3, t_hint: DVec3) -> Self {
        let n = n.try_normalize().unwrap_or(DVec3::Y);
        let t_perp = t_hint - n * n.dot(t_hint);
        let t = if t_hint.is_finite() && t_perp.length() > 1e-9 * t_hint.length() {
            t_perp.normalize()
        } else {
            basis(n).0
        };
        ShadingFrame {
            t,
            b: n.cross(t),
            n,
        }
    }

    /// World → local: (w·t, w·b, w·n).
    #[inline]
    pub fn to_local(&self, w: DVec3) -> DVec3 {
        DVec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }

    /// Local → world: t·x + b·y + n·z.
    #[inline]
    pub fn to_world(&self, w: DVec3) -> DVec3 {
        self.t * w.x + self.b * w.y + self.n * w.z
    }

    /// The frame of the other side: (t, −b, −n), still right-handed with b = n × t.
    #[inline]
    pub fn flipped(&self) -> Self {
        ShadingFrame {
            t: self.t,
            b: -self.b,
            n: -self.n,
        }
    }
}

/// Which directions an estimator draws: lustre-shade's `integrator::shade_reference_mis` and the
/// path tracer ([`PathOptions::strategy`](crate::path_tracer::PathOptions::strategy)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Strategy {
    /// BSDF importance sampling only (the estimator of lustre-shade's `integrator::shade_reference`).
    Bsdf,
    /// Environment importance sampling only (next-event estimation; misses what the sampler
    /// cannot reach, e.g. delta lobes).
    Light,
    /// One BSDF and one environment sample per iteration, combined by the power heuristic
    /// (Veach 1997, Eq. 9.13, β = 2).
    Mis,
}

/// The power heuristic weight of a technique with density `a` against one with `b` (β = 2).
#[inline]
pub fn power_heuristic(a: f64, b: f64) -> f64 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_round_trips() {
        for (n, t) in [
            (DVec3::Y, DVec3::X),
            (DVec3::new(0.3, -0.5, 0.8), DVec3::new(1.0, 2.0, 0.0)),
            (DVec3::Z, DVec3::Z),    // degenerate hint
            (DVec3::X, DVec3::ZERO), // zero hint
            (DVec3::ZERO, DVec3::X), // zero normal → +y
            (DVec3::new(0.0, 0.0, -2.0), DVec3::new(f64::NAN, 0.0, 0.0)),
        ] {
            let f = ShadingFrame::new(n, t);
            assert!((f.t.length() - 1.0).abs() < 1e-12, "{f:?}");
            assert!((f.n.length() - 1.0).abs() < 1e-12, "{f:?}");
            assert!(f.t.dot(f.n).abs() < 1e-12, "{f:?}");
            assert!((f.b - f.n.cross(f.t)).length() < 1e-12, "{f:?}");
            let w = DVec3::new(0.2, -0.7, 0.4);
            assert!((f.to_world(f.to_local(w)) - w).length() < 1e-12);
            let g = f.flipped();
            assert!((g.b - g.n.cross(g.t)).length() < 1e-12);
        }
        let f = ShadingFrame::new(DVec3::Y, DVec3::new(1.0, 5.0, 0.0));
        assert!((f.t - DVec3::X).length() < 1e-12);
        assert!((f.b - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
    }
}
