//! The walking camera: a position, a heading (yaw about +y) and a pitch, with the vertical field
//! of view; WASD / arrows move it in the horizontal plane (Q / E down and up), the mouse turns
//! it. Pure data, stepped with the frame's time.

use glam::DVec3;
use lustre_scene::{Camera, FovAxis};
use lustre_trace::path_tracer::PathCamera;

/// Largest pitch, degrees (looking straight up or down has no heading).
pub const MAX_PITCH_DEG: f64 = 89.0;

/// A first-person camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// Centre of projection.
    pub position: DVec3,
    /// Heading, radians: 0 looks along −z, positive turns towards +x.
    pub yaw: f64,
    /// Pitch, radians: positive looks up.
    pub pitch: f64,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f64,
}

/// Which ways the keys held push the camera (each −1, 0 or 1).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Movement {
    /// Forward (W, ↑) minus back (S, ↓).
    pub forward: f64,
    /// Right (D, →) minus left (A, ←).
    pub right: f64,
    /// Up (E) minus down (Q).
    pub up: f64,
}

impl FlyCamera {
    /// The camera of scene camera `c` on a film of `aspect` = width / height.
    pub fn from_camera(c: &Camera, aspect: f64) -> Self {
        let f = c.forward.normalize();
        FlyCamera {
            position: c.position,
            yaw: f.x.atan2(-f.z),
            pitch: f.y.clamp(-1.0, 1.0).asin(),
            fov_y_deg: c.fov_y_deg(aspect),
        }
        .clamped()
    }

    fn clamped(mut self) -> Self {
        let m = MAX_PITCH_DEG.to_radians();
        self.pitch = self.pitch.clamp(-m, m);
        self.yaw = self.yaw.rem_euclid(std::f64::consts::TAU);
        self
    }

    /// Unit viewing direction.
    pub fn forward(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        DVec3::new(cp * sy, sp, -cp * cy)
    }

    /// Unit direction of walking forward (the heading in the horizontal plane).
    fn heading(&self) -> DVec3 {
        let (sy, cy) = self.yaw.sin_cos();
        DVec3::new(sy, 0.0, -cy)
    }

    /// Moves by `speed` (units per second) × `dt` seconds along the keys held.
    pub fn walk(&mut self, m: Movement, speed: f64, dt: f64) {
        let right = self.heading().cross(DVec3::Y);
        let d = self.heading() * m.forward + right * m.right + DVec3::Y * m.up;
        if d.length_squared() > 0.0 && speed.is_finite() && dt.is_finite() {
            self.position += d.normalize() * speed * dt;
        }
    }

    /// Turns by a mouse motion of (dx, dy) pixels at `radians_per_pixel` (right and down
    /// positive, as the screen's axes).
    pub fn look(&mut self, dx: f64, dy: f64, radians_per_pixel: f64) {
        if dx.is_finite() && dy.is_finite() {
            self.yaw += dx * radians_per_pixel;
            self.pitch -= dy * radians_per_pixel;
            *self = self.clamped();
        }
    }

    /// The scene camera (vertical field of view, so any film shows the same vertical extent).
    pub fn to_camera(&self, name: &str) -> Camera {
        Camera {
            name: name.to_string(),
            position: self.position,
            forward: self.forward(),
            up: DVec3::Y,
            fov_deg: self.fov_y_deg,
            fov_axis: FovAxis::Y,
            aspect: None,
        }
    }

    /// The renderer's camera, as `lustre render` makes it from [`FlyCamera::to_camera`].
    pub fn path_camera(&self, w: u32, h: u32) -> Option<PathCamera> {
        lustre_trace::reference::film_camera(&self.to_camera("view"), w.max(1), h.max(1)).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_cameras_round_trip() {
        let c = Camera::look_at(
            "c",
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(4.0, 1.0, -2.0),
            DVec3::Y,
            60.0,
            FovAxis::X,
        )
        .unwrap();
        let f = FlyCamera::from_camera(&c, 16.0 / 9.0);
        assert!((f.forward() - c.forward).length() < 1e-12);
        assert!((f.fov_y_deg - c.fov_y_deg(16.0 / 9.0)).abs() < 1e-12);
        let back = f.to_camera("b");
        assert!((back.forward - c.forward).length() < 1e-12);
        // The same rays through the renderer's camera.
        let p = f.path_camera(320, 180).unwrap();
        let q = lustre_trace::reference::film_camera(&c, 320, 180).unwrap();
        assert!(
            (p.direction(10.5, 20.5, 320, 180) - q.direction(10.5, 20.5, 320, 180)).length() < 1e-9
        );
    }

    #[test]
    fn walking_and_looking() {
        let mut f = FlyCamera {
            position: DVec3::ZERO,
            yaw: 0.0,
            pitch: 0.3,
            fov_y_deg: 50.0,
        };
        // Forward walks along the heading, not up the pitch.
        f.walk(
            Movement {
                forward: 1.0,
                ..Default::default()
            },
            2.0,
            0.5,
        );
        assert!((f.position - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12);
        f.walk(
            Movement {
                right: 1.0,
                ..Default::default()
            },
            1.0,
            1.0,
        );
        assert!((f.position - DVec3::new(1.0, 0.0, -1.0)).length() < 1e-12);
        // Diagonals are not faster.
        let p = f.position;
        f.walk(
            Movement {
                forward: 1.0,
                right: 1.0,
                up: 0.0,
            },
            1.0,
            1.0,
        );
        assert!(((f.position - p).length() - 1.0).abs() < 1e-12);
        // Turning right by a quarter turn; pitch is clamped.
        f.look(100.0, 0.0, std::f64::consts::FRAC_PI_2 / 100.0);
        assert!((f.forward().x - 0.3f64.cos()).abs() < 1e-12);
        f.look(0.0, -1e6, 0.01);
        assert!((f.pitch.to_degrees() - MAX_PITCH_DEG).abs() < 1e-9);
        f.look(f64::NAN, 0.0, 0.01);
        assert!(f.forward().is_finite());
    }
}
