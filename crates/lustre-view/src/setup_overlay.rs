//! The real-time set-up drawn over the frame: the room probes' parallax boxes, the object
//! probes' and the planar reflectors' bounds, as wireframes projected with the frame's camera
//! (what `lustre_trace::setup` or the scene's hints chose; "show set-up" in the side panel).

use glam::DVec3;
use lustre_scene::Scene;
use lustre_trace::path_tracer::PathCamera;

/// What a box of the overlay stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OverlayKind {
    /// A room probe's parallax box.
    RoomProbe,
    /// An object probe's object (its bounds).
    ObjectProbe,
    /// A planar reflector (its bounds, flat along its normal).
    Reflector,
}

/// A named world-space box.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlayBox {
    /// The probe's or the mesh's name.
    pub name: String,
    /// What it is.
    pub kind: OverlayKind,
    /// Low corner.
    pub lo: DVec3,
    /// High corner.
    pub hi: DVec3,
}

/// The boxes of a scene's set-up.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SetupOverlay {
    /// Room probes, then object probes and reflectors in mesh order.
    pub boxes: Vec<OverlayBox>,
}

impl SetupOverlay {
    /// The set-up of `scene` as it will be rendered: its room probes (their boxes, or a small
    /// cube at the centre of one without) and the meshes hinted `probe` or `planar_reflector`.
    pub fn of(scene: &Scene) -> Self {
        let mut boxes = vec![];
        for p in &scene.probes {
            let c = DVec3::from_array(p.centre);
            let (lo, hi) = match p.parallax_box() {
                Some((lo, hi)) => (DVec3::from_array(lo), DVec3::from_array(hi)),
                None => (c - 0.05, c + 0.05),
            };
            boxes.push(OverlayBox {
                name: p.name.clone(),
                kind: OverlayKind::RoomProbe,
                lo,
                hi,
            });
        }
        for m in &scene.meshes {
            let kind = match (m.hints.planar_reflector, m.hints.probe) {
                (true, _) => OverlayKind::Reflector,
                (false, true) => OverlayKind::ObjectProbe,
                _ => continue,
            };
            if let Some((lo, hi)) = m.bounds() {
                boxes.push(OverlayBox {
                    name: m.name.clone(),
                    kind,
                    lo: lo.as_dvec3(),
                    hi: hi.as_dvec3(),
                });
            }
        }
        SetupOverlay { boxes }
    }

    /// The boxes' edges on a w×h image of `camera` (pixels, x right, y down), each clipped to
    /// the space in front of the camera; edges wholly behind it are left out.
    pub fn segments(
        &self,
        camera: &PathCamera,
        w: f64,
        h: f64,
    ) -> Vec<([f64; 2], [f64; 2], OverlayKind)> {
        let near = 1e-3;
        let aspect = w / h.max(1e-9);
        let tan_y = camera.tan_half_fov_y;
        let tan_x = tan_y * aspect;
        // Camera space: (right, up, forward).
        let to_cam = |p: DVec3| {
            let d = p - camera.origin;
            DVec3::new(d.dot(camera.right), d.dot(camera.up), d.dot(camera.forward))
        };
        let to_px = |c: DVec3| {
            [
                (0.5 + 0.5 * c.x / (c.z * tan_x)) * w,
                (0.5 - 0.5 * c.y / (c.z * tan_y)) * h,
            ]
        };
        let mut out = vec![];
        for b in &self.boxes {
            let corner = |i: usize| {
                DVec3::new(
                    if i & 1 == 0 { b.lo.x } else { b.hi.x },
                    if i & 2 == 0 { b.lo.y } else { b.hi.y },
                    if i & 4 == 0 { b.lo.z } else { b.hi.z },
                )
            };
            for i in 0..8usize {
                for bit in [1usize, 2, 4] {
                    if i & bit != 0 {
                        continue;
                    }
                    let (mut a, mut c) = (to_cam(corner(i)), to_cam(corner(i | bit)));
                    if a.z < near && c.z < near {
                        continue;
                    }
                    // Clip the edge to z ≥ near.
                    if a.z < near {
                        a = a + (c - a) * ((near - a.z) / (c.z - a.z));
                    } else if c.z < near {
                        c = c + (a - c) * ((near - c.z) / (a.z - c.z));
                    }
                    out.push((to_px(a), to_px(c), b.kind));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_ahead_projects_onto_the_image_and_one_behind_does_not() {
        let cam = PathCamera::look_at(DVec3::ZERO, DVec3::NEG_Z, DVec3::Y, 90.0).unwrap();
        let overlay = SetupOverlay {
            boxes: vec![
                OverlayBox {
                    name: "ahead".into(),
                    kind: OverlayKind::RoomProbe,
                    lo: DVec3::new(-1.0, -1.0, -4.0),
                    hi: DVec3::new(1.0, 1.0, -2.0),
                },
                OverlayBox {
                    name: "behind".into(),
                    kind: OverlayKind::Reflector,
                    lo: DVec3::new(-1.0, -1.0, 2.0),
                    hi: DVec3::new(1.0, 1.0, 4.0),
                },
            ],
        };
        let segs = overlay.segments(&cam, 200.0, 100.0);
        assert_eq!(segs.len(), 12, "the box ahead's 12 edges only");
        assert!(segs.iter().all(|s| s.2 == OverlayKind::RoomProbe));
        // The near face's corner (1, 1, −2): x = ½ + ½·(1/2)/(tan 45°·2), y = ½ − ½·(1/2)/1.
        let hit = segs.iter().flat_map(|(a, b, _)| [a, b]).any(|p| {
            (p[0] - (0.5 + 0.125) * 200.0).abs() < 1e-9 && (p[1] - 0.25 * 100.0).abs() < 1e-9
        });
        assert!(hit, "{segs:?}");
        for (a, b, _) in &segs {
            for p in [a, b] {
                assert!(
                    p[0] >= 0.0 && p[0] <= 200.0 && p[1] >= 0.0 && p[1] <= 100.0,
                    "{p:?}"
                );
            }
        }
    }

    #[test]
    fn the_overlay_lists_room_probes_then_hinted_meshes() {
        let mut scene = lustre_scene::builtin::room().unwrap();
        scene.probes.push(lustre_scene::ProbeSite {
            name: "room-1".into(),
            centre: [0.0, 1.0, 0.0],
            box_min: Some([-2.0, 0.0, -2.0]),
            box_max: Some([2.0, 2.5, 2.0]),
        });
        let o = SetupOverlay::of(&scene);
        assert_eq!(o.boxes[0].kind, OverlayKind::RoomProbe);
        let reflectors = o
            .boxes
            .iter()
            .filter(|b| b.kind == OverlayKind::Reflector)
            .count();
        let probes = o
            .boxes
            .iter()
            .filter(|b| b.kind == OverlayKind::ObjectProbe)
            .count();
        assert_eq!(
            reflectors,
            scene
                .meshes
                .iter()
                .filter(|m| m.hints.planar_reflector)
                .count()
        );
        assert!(reflectors >= 1 && probes >= 1, "{o:?}");
    }
}
