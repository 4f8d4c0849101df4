//! AnalyticScene geometry: camera rays, ray–sphere / ray–plane intersections, tangent frames, render.

use glam::DVec3;
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::Rgb;
use lustre_shade::analytic_scene::{AnalyticScene, LookAtCamera, Plane, Sphere};
use lustre_shade::render::{render, render_with_progress};
use lustre_trace::sampling::ShadingFrame;
use proptest::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

fn material() -> Kurt {
    Kurt::new(
        Rgb::splat(0.5),
        vec![KurtLobe::new(Rgb::ONE, 0.1, 0.2, 1.0, 0.0).expect("lobe")],
        vec![],
    )
    .expect("kurt")
}

fn scene(spheres: Vec<Sphere>, planes: Vec<Plane>) -> AnalyticScene {
    AnalyticScene {
        camera: LookAtCamera {
            eye: DVec3::new(0.0, 0.0, 5.0),
            target: DVec3::ZERO,
            up: DVec3::Y,
            fov_y_deg: 40.0,
        },
        spheres,
        planes,
        materials: vec![material()],
    }
}

fn unit_sphere() -> Sphere {
    Sphere {
        center: DVec3::ZERO,
        radius: 1.0,
        material: 0,
        axis: DVec3::Y,
    }
}

fn assert_frame(f: &ShadingFrame) {
    for v in [f.t, f.b, f.n] {
        assert!((v.length() - 1.0).abs() < 1e-12, "not unit: {v:?}");
    }
    assert!(f.t.dot(f.n).abs() < 1e-12 && f.b.dot(f.n).abs() < 1e-12 && f.t.dot(f.b).abs() < 1e-12);
    assert!((f.n.cross(f.t) - f.b).length() < 1e-12, "b ≠ n × t: {f:?}");
}

#[test]
fn centre_pixel_looks_along_fwd_and_corners_are_symmetric() {
    let mut s = scene(vec![], vec![]);
    s.camera = LookAtCamera {
        eye: DVec3::new(1.0, 2.0, 3.0),
        target: DVec3::new(-2.0, 0.5, -1.0),
        up: DVec3::new(0.1, 1.0, 0.0),
        fov_y_deg: 50.0,
    };
    let (fwd, right, up) = s.camera.basis().expect("basis");
    let (w, h) = (7, 5);
    let (o, d) = s.primary(3, 2, w, h);
    assert_eq!(o, s.camera.eye);
    assert!((d - fwd).length() < 1e-14, "{d:?} vs {fwd:?}");
    // Opposite corners: mirrored right/up components, equal forward component.
    let (_, a) = s.primary(0, 0, w, h);
    let (_, b) = s.primary(w - 1, h - 1, w, h);
    assert!((a.dot(fwd) - b.dot(fwd)).abs() < 1e-14);
    assert!((a.dot(right) + b.dot(right)).abs() < 1e-14);
    assert!((a.dot(up) + b.dot(up)).abs() < 1e-14);
    // Top-left looks left and up; the exact slope of the contract formula.
    assert!(a.dot(right) < 0.0 && a.dot(up) > 0.0);
    let t = (25f64).to_radians().tan();
    let py = (1.0 - 1.0 / h as f64) * t;
    let px = (1.0 / w as f64 - 1.0) * t * w as f64 / h as f64;
    assert!((a.dot(up) / a.dot(fwd) - py).abs() < 1e-13);
    assert!((a.dot(right) / a.dot(fwd) - px).abs() < 1e-13);
}

#[test]
fn sphere_hits_in_front_inside_grazing_and_misses_behind() {
    let sp = unit_sphere();
    let z = DVec3::new(0.0, 0.0, 5.0);
    assert!((sp.intersect(z, -DVec3::Z).expect("front") - 4.0).abs() < 1e-12);
    // From inside: the far side.
    assert!((sp.intersect(DVec3::ZERO, DVec3::X).expect("inside") - 1.0).abs() < 1e-12);
    assert!(
        (sp.intersect(DVec3::new(0.5, 0.0, 0.0), -DVec3::X)
            .expect("inside")
            - 1.5)
            .abs()
            < 1e-12
    );
    // Behind the origin: miss.
    assert!(sp.intersect(z, DVec3::Z).is_none());
    // Grazing: tangent ray hits once at t = 5, a hair outside misses.
    let t = sp
        .intersect(DVec3::new(1.0, 0.0, 5.0), -DVec3::Z)
        .expect("grazing");
    assert!((t - 5.0).abs() < 1e-6);
    assert!(sp
        .intersect(DVec3::new(1.0 + 1e-9, 0.0, 5.0), -DVec3::Z)
        .is_none());
    // Distant sphere: the stable formula keeps the near root exact.
    let far = Sphere {
        center: DVec3::new(0.0, 0.0, -1e7),
        ..sp
    };
    let t = far.intersect(DVec3::ZERO, -DVec3::Z).expect("far");
    assert!((t - (1e7 - 1.0)).abs() < 1e-8, "{t}");
    // Small sphere far away, off-centre ray: hit point lies on the sphere.
    let small = Sphere {
        center: DVec3::new(3.0, -2.0, -500.0),
        radius: 0.01,
        ..sp
    };
    let d = (small.center + DVec3::new(0.007, 0.0, 0.0)).normalize();
    let t = small.intersect(DVec3::ZERO, d).expect("small");
    assert!(((t * d - small.center).length() - 0.01).abs() < 1e-9);
}

#[test]
fn scene_hit_frame_faces_the_viewer_and_nearest_wins() {
    let s = scene(
        vec![
            unit_sphere(),
            Sphere {
                center: DVec3::new(0.0, 0.0, -3.0),
                ..unit_sphere()
            },
        ],
        vec![Plane {
            point: DVec3::new(0.0, 0.0, -10.0),
            normal: DVec3::Z,
            tangent: DVec3::X,
            half_size: 100.0,
            material: 0,
        }],
    );
    s.validate().expect("valid");
    let hit = s
        .intersect(DVec3::new(0.0, 0.0, 5.0), -DVec3::Z)
        .expect("hit");
    assert!((hit.position - DVec3::Z).length() < 1e-12);
    assert!((hit.frame.n - DVec3::Z).length() < 1e-12);
    assert!((hit.wo - DVec3::Z).length() < 1e-12);
    assert_frame(&hit.frame);
    // Tangent along latitude circles around +y: at +z it is axis × n = y × z = +x.
    assert!((hit.frame.t - DVec3::X).length() < 1e-12);
    // From inside the first sphere: its far wall, seen from the back, n flipped to the viewer.
    let hit = s.intersect(DVec3::ZERO, -DVec3::Z).expect("inside");
    assert!((hit.position + DVec3::Z).length() < 1e-12);
    assert!(hit.frame.n.dot(hit.wo) > 0.99);
    assert_frame(&hit.frame);
    // Plane seen from behind: n flipped, still b = n × t.
    let hit = s
        .intersect(DVec3::new(5.0, 0.0, -20.0), DVec3::Z)
        .expect("plane back");
    assert!((hit.position.z + 10.0).abs() < 1e-12);
    assert!((hit.frame.n + DVec3::Z).length() < 1e-12);
    assert_frame(&hit.frame);
    // Parallel to the plane and outside the square: misses.
    assert!(s
        .intersect(DVec3::new(0.0, 50.0, -10.0), DVec3::X)
        .is_none());
    assert!(s
        .intersect(DVec3::new(150.0, 0.0, 0.0), -DVec3::Z)
        .is_none());
    // Degenerate rays miss.
    assert!(s.intersect(DVec3::ZERO, DVec3::ZERO).is_none());
    assert!(s.intersect(DVec3::ZERO, DVec3::NAN).is_none());
}

#[test]
fn pole_frames_fall_back() {
    // n ∥ axis: t = normalize(x̂ × n); axis = x̂ at n = ±x̂: t = ẑ.
    let sp = unit_sphere();
    for p in [DVec3::Y, -DVec3::Y] {
        let f = sp.frame_at(p);
        assert_frame(&f);
        assert!((f.t - DVec3::X.cross(p)).length() < 1e-12);
    }
    let sx = Sphere {
        axis: DVec3::X,
        ..sp
    };
    for p in [DVec3::X, -DVec3::X] {
        let f = sx.frame_at(p);
        assert_frame(&f);
        assert!((f.t - DVec3::Z).length() < 1e-12);
    }
    // A plane whose tangent is parallel to its normal still gets a frame.
    let pl = Plane {
        point: DVec3::ZERO,
        normal: DVec3::Y,
        tangent: DVec3::Y,
        half_size: 1.0,
        material: 0,
    };
    assert_frame(&pl.frame());
}

#[test]
fn validate_names_the_problem() {
    let mut s = scene(vec![unit_sphere()], vec![]);
    s.spheres[0].material = 3;
    let e = s.validate().expect_err("bad material").to_string();
    assert!(e.contains("sphere 0") && e.contains("material 3"), "{e}");
    s.spheres[0].material = 0;
    s.spheres[0].radius = -1.0;
    assert!(s
        .validate()
        .expect_err("radius")
        .to_string()
        .contains("radius"));
    s.spheres[0].radius = 1.0;
    s.camera.target = s.camera.eye;
    assert!(s
        .validate()
        .expect_err("camera")
        .to_string()
        .contains("camera"));
    s.camera.target = DVec3::ZERO;
    s.camera.fov_y_deg = 180.0;
    assert!(s.validate().expect_err("fov").to_string().contains("fov"));
}

#[test]
fn render_tiny_scene() {
    let s = scene(vec![unit_sphere()], vec![]);
    let (w, h) = (33, 21);
    let rows = AtomicUsize::new(0);
    let img = render_with_progress(
        &s,
        w,
        h,
        |hit| Rgb::splat(hit.frame.n.dot(hit.wo)),
        |_| Rgb::new(0.0, 0.0, 7.0),
        &|r| {
            rows.fetch_max(r, Ordering::Relaxed);
        },
    );
    assert_eq!(rows.load(Ordering::Relaxed), h);
    assert_eq!((img.width, img.height, img.data.len()), (w, h, w * h));
    // Centre: head-on, n·wo = 1; corners: background.
    assert!((img.get(16, 10)[0] - 1.0).abs() < 1e-6);
    assert_eq!(img.get(0, 0), [0.0, 0.0, 7.0]);
    assert_eq!(img.get(w - 1, h - 1), [0.0, 0.0, 7.0]);
    // Coverage: the sphere subtends asin(1/5) ≈ 11.54° against a 20° half-field; the hit fraction
    // of the image is close to the projected disc's area share.
    let hits = img.data.iter().filter(|p| p[2] != 7.0).count();
    let r_px = (1.0f64 / 24f64.sqrt()) / 20f64.to_radians().tan() * h as f64 / 2.0;
    let expect = std::f64::consts::PI * r_px * r_px;
    assert!(
        (hits as f64 - expect).abs() < 0.15 * expect,
        "{hits} vs {expect}"
    );
    // Left–right symmetric.
    for y in 0..h {
        for x in 0..w {
            assert!((img.get(x, y)[0] - img.get(w - 1 - x, y)[0]).abs() < 1e-6);
        }
    }
    // Empty image.
    let e = render(&s, 0, 0, |_| Rgb::ZERO, |_| Rgb::ZERO);
    assert!(e.data.is_empty());
}

proptest! {
    #[test]
    fn frames_are_orthonormal_everywhere(
        theta in 0.0f64..std::f64::consts::PI,
        phi in 0.0f64..std::f64::consts::TAU,
        ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in -1.0f64..1.0,
    ) {
        let axis = DVec3::new(ax, ay, az).try_normalize().unwrap_or(DVec3::Y);
        let sp = Sphere { center: DVec3::new(1.0, -2.0, 0.5), radius: 0.7, material: 0, axis };
        let n = DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
        let f = sp.frame_at(sp.center + 0.7 * n);
        prop_assert!((f.n - n).length() < 1e-12);
        assert_frame(&f);
        // AnalyticHit from a random outside point towards the sphere point: consistent and facing.
        let s = scene(vec![sp], vec![]);
        let o = sp.center + 3.0 * n + DVec3::new(0.1, 0.2, -0.1);
        if let Some(hit) = s.intersect(o, sp.center - o) {
            prop_assert!(hit.frame.n.dot(hit.wo) >= 0.0);
            prop_assert!(((hit.position - sp.center).length() - 0.7).abs() < 1e-12);
            assert_frame(&hit.frame);
        }
    }
}
