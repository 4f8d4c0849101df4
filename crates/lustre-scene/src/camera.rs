//! Pinhole cameras as world transforms, and camera paths (keyframes in time).
//!
//! A camera looks along `forward` with `up` up and right = forward × up (right-handed, +y up as in
//! the rest of lustre). The field of view keeps Mitsuba's meaning: an angle along one axis of the
//! film ([`FovAxis`]), so the same camera renders the same horizontal extent at any aspect when
//! the axis is x. [`Camera::fov_y_deg`] gives the vertical angle for a film aspect.

use glam::{DMat4, DQuat, DVec3};
use serde::{Deserialize, Serialize};

/// Which film axis the field of view spans (Mitsuba's `fovAxis`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FovAxis {
    /// Horizontal (Mitsuba's default).
    #[default]
    X,
    /// Vertical (glTF's `yfov`).
    Y,
    /// The film diagonal.
    Diagonal,
    /// The smaller of the two axes.
    Smaller,
    /// The larger of the two axes.
    Larger,
}

/// A pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Name (`default` when the file gives none).
    pub name: String,
    /// Centre of projection (world).
    pub position: DVec3,
    /// Unit viewing direction (the centre pixel's ray).
    pub forward: DVec3,
    /// Unit up direction, orthogonal to `forward`.
    pub up: DVec3,
    /// Full field of view in degrees along `fov_axis`, in (0, 180).
    pub fov_deg: f64,
    /// The film axis `fov_deg` spans.
    pub fov_axis: FovAxis,
    /// Aspect ratio (width / height) the camera was made for, where the file says (glTF
    /// `aspectRatio`); the film decides otherwise.
    pub aspect: Option<f64>,
}

impl Camera {
    /// A camera at `position` looking at `target` with `up` as the up hint (made orthogonal).
    /// Returns `None` when the view direction is zero or parallel to `up`, or a value is not
    /// finite.
    pub fn look_at(
        name: impl Into<String>,
        position: DVec3,
        target: DVec3,
        up: DVec3,
        fov_deg: f64,
        fov_axis: FovAxis,
    ) -> Option<Camera> {
        let forward = (target - position).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(position.is_finite() && fov_deg > 0.0 && fov_deg < 180.0) {
            return None;
        }
        Some(Camera {
            name: name.into(),
            position,
            forward,
            up,
            fov_deg,
            fov_axis,
            aspect: None,
        })
    }

    /// Unit right direction, forward × up.
    pub fn right(&self) -> DVec3 {
        self.forward.cross(self.up)
    }

    /// Camera-to-world matrix in the glTF/OpenGL convention (camera looks down −z, +y up,
    /// +x right).
    pub fn to_world(&self) -> DMat4 {
        DMat4::from_cols(
            self.right().extend(0.0),
            self.up.extend(0.0),
            (-self.forward).extend(0.0),
            self.position.extend(1.0),
        )
    }

    /// The vertical field of view in degrees for a film of `aspect` = width / height.
    pub fn fov_y_deg(&self, aspect: f64) -> f64 {
        let t = (self.fov_deg.to_radians() * 0.5).tan();
        let ty = match self.fov_axis {
            FovAxis::X => t / aspect,
            FovAxis::Y => t,
            FovAxis::Diagonal => t / (1.0 + aspect * aspect).sqrt(),
            FovAxis::Smaller => {
                if aspect >= 1.0 {
                    t
                } else {
                    t / aspect
                }
            }
            FovAxis::Larger => {
                if aspect >= 1.0 {
                    t / aspect
                } else {
                    t
                }
            }
        };
        2.0 * ty.atan().to_degrees()
    }

    /// The world-space unit ray direction through film point (x, y) in pixels of a W×H film
    /// (y down, pixel centres at half-integers).
    pub fn ray_direction(&self, x: f64, y: f64, width: u32, height: u32) -> DVec3 {
        let aspect = f64::from(width) / f64::from(height);
        let ty = (self.fov_y_deg(aspect).to_radians() * 0.5).tan();
        let px = (2.0 * x / f64::from(width) - 1.0) * ty * aspect;
        let py = (1.0 - 2.0 * y / f64::from(height)) * ty;
        (self.forward + px * self.right() + py * self.up).normalize()
    }
}

/// One keyframe of a camera path.
#[derive(Clone, Debug, PartialEq)]
pub struct Keyframe {
    /// Time in seconds from the start of the path.
    pub time: f64,
    /// The camera at that time.
    pub camera: Camera,
}

/// A camera path: keyframes with strictly increasing times, interpolated linearly in position and
/// field of view and spherically in orientation.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    /// Name.
    pub name: String,
    /// Keyframes (at least one), by increasing time.
    pub keyframes: Vec<Keyframe>,
    /// Start again after the last keyframe.
    pub looped: bool,
}

impl CameraPath {
    /// Duration (time of the last keyframe).
    pub fn duration(&self) -> f64 {
        self.keyframes.last().map_or(0.0, |k| k.time)
    }

    /// The camera at time `t` (clamped to the path, or wrapped when looped); `None` for a path
    /// without keyframes.
    pub fn at(&self, t: f64) -> Option<Camera> {
        let first = self.keyframes.first()?;
        let last = self.keyframes.last()?;
        let mut t = if t.is_finite() { t } else { first.time };
        let span = last.time - first.time;
        if self.looped && span > 0.0 {
            t = first.time + (t - first.time).rem_euclid(span);
        }
        if t <= first.time {
            return Some(first.camera.clone());
        }
        if t >= last.time {
            return Some(last.camera.clone());
        }
        let i = self.keyframes.iter().position(|k| k.time > t)?;
        let (a, b) = (&self.keyframes[i - 1], &self.keyframes[i]);
        let s = (t - a.time) / (b.time - a.time);
        let qa = orientation(&a.camera);
        let qb = orientation(&b.camera);
        let q = qa.slerp(qb, s);
        let mut c = a.camera.clone();
        c.position = a.camera.position.lerp(b.camera.position, s);
        c.forward = q * DVec3::NEG_Z;
        c.up = q * DVec3::Y;
        c.fov_deg = a.camera.fov_deg + (b.camera.fov_deg - a.camera.fov_deg) * s;
        Some(c)
    }
}

fn orientation(c: &Camera) -> DQuat {
    DQuat::from_mat3(&glam::DMat3::from_cols(c.right(), c.up, -c.forward))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(axis: FovAxis) -> Camera {
        Camera::look_at("c", DVec3::ZERO, DVec3::NEG_Z, DVec3::Y, 60.0, axis).unwrap()
    }

    #[test]
    fn fov_axes() {
        let t = |deg: f64| (deg.to_radians() / 2.0).tan();
        let y = |c: &Camera, a: f64| t(c.fov_y_deg(a));
        assert!((cam(FovAxis::Y).fov_y_deg(2.0) - 60.0).abs() < 1e-12);
        assert!((y(&cam(FovAxis::X), 2.0) - t(60.0) / 2.0).abs() < 1e-12);
        assert!((y(&cam(FovAxis::Diagonal), 1.0) - t(60.0) / 2f64.sqrt()).abs() < 1e-12);
        assert!((cam(FovAxis::Smaller).fov_y_deg(2.0) - 60.0).abs() < 1e-12);
        assert!((y(&cam(FovAxis::Smaller), 0.5) - 2.0 * t(60.0)).abs() < 1e-12);
        assert!((y(&cam(FovAxis::Larger), 2.0) - t(60.0) / 2.0).abs() < 1e-12);
    }

    #[test]
    fn frame_and_rays() {
        let c = cam(FovAxis::Y);
        assert!((c.right() - DVec3::X).length() < 1e-12);
        let m = c.to_world();
        assert!((m.transform_vector3(DVec3::NEG_Z) - c.forward).length() < 1e-12);
        // The top-left pixel corner looks up and to the left.
        let d = c.ray_direction(0.0, 0.0, 200, 100);
        assert!(d.x < 0.0 && d.y > 0.0);
        assert!((d.y / -d.z - t30()).abs() < 1e-12);
        assert!(Camera::look_at("c", DVec3::ZERO, DVec3::Y, DVec3::Y, 60.0, FovAxis::Y).is_none());
        assert!(Camera::look_at("c", DVec3::ZERO, DVec3::X, DVec3::Y, 180.0, FovAxis::Y).is_none());
    }

    fn t30() -> f64 {
        30f64.to_radians().tan()
    }

    #[test]
    fn paths_interpolate_and_clamp() {
        let a = cam(FovAxis::Y);
        let mut b = Camera::look_at(
            "b",
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(3.0, 0.0, 0.0),
            DVec3::Y,
            40.0,
            FovAxis::Y,
        )
        .unwrap();
        b.name = "b".into();
        let p = CameraPath {
            name: "p".into(),
            keyframes: vec![
                Keyframe {
                    time: 1.0,
                    camera: a.clone(),
                },
                Keyframe {
                    time: 3.0,
                    camera: b.clone(),
                },
            ],
            looped: false,
        };
        assert_eq!(p.at(0.0).unwrap(), a);
        assert_eq!(p.at(5.0).unwrap(), b);
        let m = p.at(2.0).unwrap();
        assert!((m.position - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
        assert!((m.fov_deg - 50.0).abs() < 1e-12);
        // Halfway between looking down −z and +x: 45° between them.
        let half = DVec3::new(1.0, 0.0, -1.0).normalize();
        assert!((m.forward - half).length() < 1e-9, "{}", m.forward);
        assert!(CameraPath {
            name: "e".into(),
            keyframes: vec![],
            looped: true
        }
        .at(1.0)
        .is_none());
    }
}
