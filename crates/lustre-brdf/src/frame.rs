//! Directions in the local shading frame: normal +z, tangent +x (the anisotropy axis), bitangent +y.
//!
//! `wi` points towards the light, `wo` towards the viewer; both point away from the surface.

use glam::DVec3;
use std::f64::consts::PI;

/// cos θ of a local direction.
#[inline]
pub fn cos_theta(w: DVec3) -> f64 {
    w.z
}

/// θ of a local direction, in [0, π].
#[inline]
pub fn theta(w: DVec3) -> f64 {
    w.z.clamp(-1.0, 1.0).acos()
}

/// φ of a local direction, in (−π, π].
#[inline]
pub fn phi(w: DVec3) -> f64 {
    w.y.atan2(w.x)
}

/// The unit vector of spherical angles (θ, φ).
#[inline]
pub fn spherical(theta: f64, phi: f64) -> DVec3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    DVec3::new(st * cp, st * sp, ct)
}

/// Mirror reflection of `w` about the unit vector `n` (both pointing away from the surface).
#[inline]
pub fn reflect(w: DVec3, n: DVec3) -> DVec3 {
    2.0 * w.dot(n) * n - w
}

/// Mirror image through the surface plane (z → −z): the primed vectors of 000 Eq. 3.5.
#[inline]
pub fn mirror_z(w: DVec3) -> DVec3 {
    DVec3::new(w.x, w.y, -w.z)
}

/// The normalized half vector of two directions, or `None` when they are opposite.
#[inline]
pub fn half_vector(wi: DVec3, wo: DVec3) -> Option<DVec3> {
    let h = wi + wo;
    let l2 = h.length_squared();
    (l2 > 1e-24).then(|| h / l2.sqrt())
}

/// Rusinkiewicz (1998) half/difference angles of an isotropic configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfDiff {
    /// θ_h, angle between the half vector and the normal.
    pub theta_h: f64,
    /// φ_h, azimuth of the half vector.
    pub phi_h: f64,
    /// θ_d, angle between `wi` and the half vector.
    pub theta_d: f64,
    /// φ_d, azimuth of `wi` in the frame where the half vector is the pole.
    pub phi_d: f64,
}

/// Converts a reflection pair to half/difference angles (Rusinkiewicz 1998).
pub fn to_half_diff(wi: DVec3, wo: DVec3) -> Option<HalfDiff> {
    let h = half_vector(wi, wo)?;
    let theta_h = theta(h);
    let phi_h = phi(h);
    // Rotate wi by -φ_h about z, then by -θ_h about y: the difference vector.
    let d = rotate_y(rotate_z(wi, -phi_h), -theta_h);
    Some(HalfDiff {
        theta_h,
        phi_h,
        theta_d: theta(d),
        phi_d: phi(d),
    })
}

/// Converts half/difference angles back to (wi, wo).
pub fn from_half_diff(hd: &HalfDiff) -> (DVec3, DVec3) {
    let d = spherical(hd.theta_d, hd.phi_d);
    let wi = rotate_z(rotate_y(d, hd.theta_h), hd.phi_h);
    let h = spherical(hd.theta_h, hd.phi_h);
    (wi, reflect(wi, h))
}

/// Rotation about z by `a`.
#[inline]
pub fn rotate_z(v: DVec3, a: f64) -> DVec3 {
    let (s, c) = a.sin_cos();
    DVec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

/// Rotation about y by `a`.
#[inline]
pub fn rotate_y(v: DVec3, a: f64) -> DVec3 {
    let (s, c) = a.sin_cos();
    DVec3::new(c * v.x + s * v.z, v.y, -s * v.x + c * v.z)
}

/// An orthonormal basis (t, b, n) around a unit vector `n` (Duff et al. 2017).
pub fn basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Degrees to radians.
#[inline]
pub fn deg(d: f64) -> f64 {
    d * PI / 180.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_diff_round_trip() {
        for &(ti, pi, to, po) in &[
            (0.3, 0.1, 0.9, 2.5),
            (1.2, -2.0, 0.2, 0.4),
            (0.01, 0.0, 1.5, 3.0),
        ] {
            let wi = spherical(ti, pi);
            let wo = spherical(to, po);
            let hd = to_half_diff(wi, wo).expect("not opposite");
            let (a, b) = from_half_diff(&hd);
            assert!(
                (a - wi).length() < 1e-12 && (b - wo).length() < 1e-12,
                "{hd:?}"
            );
        }
    }

    #[test]
    fn basis_is_orthonormal() {
        for n in [DVec3::Z, -DVec3::Z, DVec3::new(0.3, -0.4, 0.5).normalize()] {
            let (t, b) = basis(n);
            assert!(t.dot(b).abs() < 1e-12 && t.dot(n).abs() < 1e-12 && b.dot(n).abs() < 1e-12);
            assert!((t.cross(b) - n).length() < 1e-12);
        }
    }
}
