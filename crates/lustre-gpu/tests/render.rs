//! Renders of hand-built packed scenes whose pixels are known by hand: cube-map face order and
//! orientation (contract conventions), the diffuse term and one lobe under a constant environment.
//! They fail (not skip) without an adapter.

use glam::DVec3;
use lustre_gpu::{
    CameraBasis, CubeLevelRef, GpuContext, GpuEnvironment, GpuError, GpuKurtMaterial, GpuLobe,
    GpuRenderer, GpuSphere, GpuSun, PackedScene,
};

fn context() -> GpuContext {
    match GpuContext::new() {
        Ok(c) => c,
        Err(e) => panic!("the GPU tests need an adapter (CI installs lavapipe): {e}"),
    }
}

/// A pyramid whose every level stores `f(face, s, t)` at texel centres, and a constant
/// irradiance map.
fn environment(
    ctx: &GpuContext,
    size: usize,
    f: impl Fn(usize, f32, f32) -> [f32; 3],
    irradiance: [f32; 3],
) -> GpuEnvironment {
    let mut levels = Vec::new();
    let mut n = size;
    loop {
        let faces: Vec<Vec<[f32; 3]>> = (0..6)
            .map(|face| {
                (0..n * n)
                    .map(|k| {
                        let (i, j) = (k % n, k / n);
                        f(
                            face,
                            (i as f32 + 0.5) / n as f32,
                            (j as f32 + 0.5) / n as f32,
                        )
                    })
                    .collect()
            })
            .collect();
        levels.push((n, faces));
        if n == 1 {
            break;
        }
        n /= 2;
    }
    let refs: Vec<CubeLevelRef> = levels
        .iter()
        .map(|(n, faces)| CubeLevelRef {
            size: *n,
            faces: std::array::from_fn(|k| faces[k].as_slice()),
        })
        .collect();
    let irr = vec![irradiance];
    let irr_ref = CubeLevelRef {
        size: 1,
        faces: std::array::from_fn(|_| irr.as_slice()),
    };
    match GpuEnvironment::from_levels(ctx, &refs, irr_ref) {
        Ok(e) => e,
        Err(e) => panic!("upload: {e}"),
    }
}

fn empty_scene(eye: DVec3, target: DVec3, up: DVec3) -> PackedScene {
    PackedScene {
        camera: CameraBasis::new(eye, target, up, 40.0),
        spheres: vec![],
        planes: vec![],
        materials: vec![],
        lobes: vec![],
        samples: vec![],
        suns: vec![],
    }
}

/// The background of a 1×1 image looks along the camera axis: level 0 at (s, t) of the face the
/// contract assigns. Each face stores (s, t, face/8), which bilinear filtering reproduces exactly
/// inside the face.
#[test]
fn background_follows_vulkan_face_order_and_orientation() {
    let ctx = context();
    let renderer = GpuRenderer::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let env = environment(&ctx, 16, |face, s, t| [s, t, face as f32 / 8.0], [0.0; 3]);
    // (direction, face, sc, tc, |ma|) by the contract's table.
    let (a, b) = (0.3, -0.2);
    let cases = [
        (DVec3::new(1.0, a, b), 0, -b, -a),
        (DVec3::new(-1.0, a, b), 1, b, -a),
        (DVec3::new(a, 1.0, b), 2, a, b),
        (DVec3::new(a, -1.0, b), 3, a, -b),
        (DVec3::new(a, b, 1.0), 4, a, -b),
        (DVec3::new(a, b, -1.0), 5, -a, -b),
    ];
    for (d, face, sc, tc) in cases {
        let up = if face == 2 || face == 3 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let scene = empty_scene(DVec3::ZERO, d, up);
        let px = renderer
            .render_packed(&scene, &env, 1, 1)
            .unwrap_or_else(|e| panic!("{e}"))[0];
        let want = [
            0.5 * (sc as f32 + 1.0),
            0.5 * (tc as f32 + 1.0),
            face as f32 / 8.0,
        ];
        for c in 0..3 {
            assert!(
                (px[c] - want[c]).abs() < 3e-3,
                "face {face}: got {px:?}, want {want:?}"
            );
        }
    }
}

/// A sphere seen head-on under a constant environment L and irradiance E, with one lobe whose
/// pattern is the single half vector n: wi = wo = n, f = ks·r0·D(n)/4, the Pdf002 weight is
/// pdf_constant/4 = D(n)/4, so the pixel is kd·E + ks·r0·L (reflection) or + kt·(1 − r0)·L
/// (transmission, light from −n).
#[test]
fn diffuse_and_single_sample_lobe_match_hand_values() {
    let ctx = context();
    let renderer = GpuRenderer::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let l = [1.5, 0.5, 2.0];
    let e = [2.0, 1.0, 0.5];
    let env = environment(&ctx, 8, |_, _, _| l, e);
    let (mx, my, r0) = (0.2f32, 0.3f32, 0.25f32);
    let d_n = 1.0 / (std::f32::consts::PI * mx * my);
    let kd = [0.5, 0.25, 1.0];
    let ks = [0.4, 0.8, 0.2];
    for transmission in [false, true] {
        let scene = PackedScene {
            camera: CameraBasis::new(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, 30.0),
            spheres: vec![GpuSphere {
                center: [0.0; 3],
                radius: 1.0,
                axis: [0.0, 1.0, 0.0],
                material: 0,
            }],
            planes: vec![],
            materials: vec![GpuKurtMaterial {
                kd,
                lobe_start: 0,
                reflection: u32::from(!transmission),
                transmission: u32::from(transmission),
                sun_start: 0,
                sun_count: 0,
            }],
            lobes: vec![GpuLobe {
                ks,
                mx,
                my,
                r0,
                alpha: 0.0,
                xi0: 0.1,
                pdf_constant: d_n,
                sample_start: 0,
                sample_count: 1,
                scheme: lustre_gpu::packed::LOBE_SCHEME_PATTERN,
            }],
            samples: vec![[0.0, 0.0, 1.0, 0.0]],
            suns: vec![],
        };
        let px = renderer
            .render_packed(&scene, &env, 1, 1)
            .unwrap_or_else(|e| panic!("{e}"))[0];
        let fr = if transmission { 1.0 - r0 } else { r0 };
        for c in 0..3 {
            let want = kd[c] * e[c] + ks[c] * fr * l[c];
            assert!(
                (px[c] - want).abs() < 2e-3 * want.max(1.0),
                "transmission {transmission}, channel {c}: got {}, want {want}",
                px[c]
            );
        }
    }
}

/// Out-of-range indices (spheres, sun ranges), a NaN sun and a degenerate camera are errors
/// naming the input, not panics.
#[test]
fn invalid_scenes_are_reported() {
    let ctx = context();
    let renderer = GpuRenderer::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let env = environment(&ctx, 4, |_, _, _| [1.0; 3], [1.0; 3]);
    let mut scene = empty_scene(DVec3::ZERO, DVec3::Z, DVec3::Y);
    scene.spheres.push(GpuSphere {
        center: [0.0, 0.0, 3.0],
        radius: 1.0,
        axis: [0.0, 1.0, 0.0],
        material: 2,
    });
    match renderer.render_packed(&scene, &env, 4, 4) {
        Err(GpuError::Invalid { parameter, .. }) => assert_eq!(parameter, "sphere 0"),
        other => panic!("expected an invalid-sphere error, got {other:?}"),
    }
    let scene = empty_scene(DVec3::ZERO, DVec3::ZERO, DVec3::Y);
    match renderer.render_packed(&scene, &env, 4, 4) {
        Err(GpuError::Invalid { parameter, .. }) => assert_eq!(parameter, "camera"),
        other => panic!("expected a camera error, got {other:?}"),
    }
    let scene = empty_scene(DVec3::ZERO, DVec3::Z, DVec3::Y);
    assert!(matches!(
        renderer.render_packed(&scene, &env, 0, 4),
        Err(GpuError::Invalid { .. })
    ));
    // A material whose sun range runs past the sun array, and a sun with a NaN irradiance.
    let mut scene = empty_scene(DVec3::ZERO, DVec3::Z, DVec3::Y);
    scene.materials.push(GpuKurtMaterial {
        kd: [0.5; 3],
        lobe_start: 0,
        reflection: 0,
        transmission: 0,
        sun_start: 0,
        sun_count: 1,
    });
    match renderer.render_packed(&scene, &env, 4, 4) {
        Err(GpuError::Invalid { parameter, .. }) => assert_eq!(parameter, "material 0"),
        other => panic!("expected an invalid-material error, got {other:?}"),
    }
    scene.suns.push(GpuSun {
        direction: [0.0, 1.0, 0.0],
        spread: 0.0,
        irradiance: [f32::NAN, 1.0, 1.0],
        pad1: 0.0,
    });
    match renderer.render_packed(&scene, &env, 4, 4) {
        Err(GpuError::Invalid { parameter, .. }) => assert_eq!(parameter, "sun 0"),
        other => panic!("expected an invalid-sun error, got {other:?}"),
    }
    // A sun's spread widens the lobes: a negative or NaN one is refused too.
    for spread in [-0.1, f32::NAN] {
        scene.suns[0] = GpuSun {
            direction: [0.0, 1.0, 0.0],
            spread,
            irradiance: [1.0, 1.0, 1.0],
            pad1: 0.0,
        };
        match renderer.render_packed(&scene, &env, 4, 4) {
            Err(GpuError::Invalid { parameter, .. }) => assert_eq!(parameter, "sun 0"),
            other => panic!("expected an invalid-sun error for spread {spread}, got {other:?}"),
        }
    }
}
