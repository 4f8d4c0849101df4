//! The path tracer against exact answers: white furnace, a diffuse plane under a constant sky
//! (E = πL), a square area light (Lambert's polygon formula), BSDF-only / light-only / MIS
//! agreement, alpha masks, resumable accumulation and the two-halves noise estimate.

use glam::DVec3;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::SplitMix64;
use lustre_trace::path_tracer::{
    Accumulator, ConstantSurface, EnvLight, Geometry, PathCamera, PathOptions, PathScene,
    PathTracer, Surface,
};
use lustre_trace::sampling::Strategy;
use std::f64::consts::PI;

fn lambert(kd: f64, two_sided: bool) -> Box<dyn Surface> {
    Box::new(ConstantSurface {
        bsdf: Box::new(Lambert::new(Rgb::splat(kd)).unwrap()),
        two_sided,
    })
}

/// A quad (two triangles) with corners c, c+a, c+a+b, c+b; normal a × b.
fn quad(c: DVec3, a: DVec3, b: DVec3) -> [[DVec3; 3]; 2] {
    [[c, c + a, c + a + b], [c, c + a + b, c + b]]
}

fn push_quad(g: &mut Geometry, q: [[DVec3; 3]; 2], material: u32, emission: Rgb) {
    for t in q {
        g.positions.push(t);
        g.material.push(material);
        g.emission.push(emission);
    }
}

/// A closed box (inward and outward faces alike), for the furnace.
fn box_geometry(material: u32) -> Geometry {
    let mut g = Geometry::default();
    let (x, y, z) = (DVec3::X, DVec3::Y, DVec3::Z);
    let o = DVec3::splat(-1.0);
    for q in [
        quad(o, 2.0 * y, 2.0 * x),
        quad(o + 2.0 * y, 2.0 * z, 2.0 * x),
        quad(o, 2.0 * x, 2.0 * z),
        quad(o + 2.0 * x, 2.0 * y, 2.0 * z),
        quad(o, 2.0 * z, 2.0 * y),
        quad(o + 2.0 * z, 2.0 * x, 2.0 * y),
    ] {
        push_quad(&mut g, q, material, Rgb::ZERO);
    }
    g
}

/// Mean and standard error of channel 0 of `n` radiance estimates along (o, d).
fn estimate(pt: &PathTracer, o: DVec3, d: DVec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = SplitMix64::new(seed);
    let (mut s1, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let v = pt.radiance(o, d, &mut rng)[0];
        s1 += v;
        s2 += v * v;
    }
    let m = s1 / n as f64;
    let var = (s2 / n as f64 - m * m).max(0.0);
    (m, (var / n as f64).sqrt())
}

fn opts(max_depth: u32, strategy: Strategy) -> PathOptions {
    PathOptions {
        max_depth,
        rr_depth: 5,
        strategy,
    }
}

#[test]
fn white_furnace_concave_box() {
    // Every surface albedo 1 (two-sided Lambert) in a uniform L = 1 sky: radiance is 1 along
    // every ray, whatever the geometry. The box is seen from outside and from inside (where
    // only inter-reflection brings the light: the box is closed, so this checks paths of many
    // bounces and the roulette).
    let mut g = box_geometry(0);
    // Open the +z face so light gets in: drop its two triangles.
    g.positions.truncate(10);
    g.material.truncate(10);
    g.emission.truncate(10);
    let scene = PathScene {
        geometry: g,
        materials: vec![lambert(1.0, true)],
        environment: Some(EnvLight::constant(Rgb::ONE).unwrap()),
    };
    for st in [Strategy::Bsdf, Strategy::Light, Strategy::Mis] {
        let pt = PathTracer::new(&scene, opts(256, st)).unwrap();
        for (o, d) in [
            (DVec3::new(0.3, 0.2, 5.0), DVec3::new(-0.05, 0.0, -1.0)),
            (DVec3::new(3.0, 0.5, 0.2), DVec3::new(-1.0, 0.1, 0.0)),
        ] {
            let (m, e) = estimate(&pt, o, d.normalize(), 4000, 3);
            println!("furnace {st:?}: {m:.4} ± {e:.4}");
            assert!((m - 1.0).abs() < 4.0 * e + 0.01, "{st:?}: {m} ± {e}");
        }
    }
}

#[test]
fn diffuse_plane_under_a_constant_sky() {
    // One-sided plane z = 0 facing +z, kd = 0.6, sky L = (1, 2, 3): L_o = kd/π · E = kd L.
    let mut g = Geometry::default();
    push_quad(
        &mut g,
        quad(
            DVec3::new(-50.0, -50.0, 0.0),
            DVec3::new(100.0, 0.0, 0.0),
            DVec3::new(0.0, 100.0, 0.0),
        ),
        0,
        Rgb::ZERO,
    );
    let scene = PathScene {
        geometry: g,
        materials: vec![lambert(0.6, false)],
        environment: Some(EnvLight::constant(Rgb::new(1.0, 2.0, 3.0)).unwrap()),
    };
    for st in [Strategy::Bsdf, Strategy::Light, Strategy::Mis] {
        let pt = PathTracer::new(&scene, opts(8, st)).unwrap();
        let o = DVec3::new(0.1, 0.2, 1.0);
        let d = DVec3::new(0.3, -0.1, -1.0).normalize();
        let (m, e) = estimate(&pt, o, d, 2000, 5);
        println!("plane {st:?}: {m:.5} ± {e:.5}");
        // Cosine sampling is exact per sample (e = 0); light sampling is not.
        assert!((m - 0.6).abs() < 4.0 * e + 1e-9, "{st:?}: {m} ± {e}");
    }
    // The whole image through the camera, every pixel 0.6 · (1, 2, 3) (BSDF sampling: exact).
    let pt = PathTracer::new(&scene, opts(8, Strategy::Bsdf)).unwrap();
    let cam = PathCamera::look_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::Y, 40.0).unwrap();
    let mut acc = Accumulator::new(8, 6).unwrap();
    pt.render(&cam, &mut acc, 4, 1, &|_, _| {});
    for p in acc.image().data {
        for (c, want) in [0.6, 1.2, 1.8].iter().enumerate() {
            assert!((p[c] as f64 - want).abs() < 1e-5, "{p:?}");
        }
    }
}

/// Irradiance at the origin (normal +z) from a Lambertian polygon of radiance 1 (Lambert's
/// formula: E = ½ Σ θ_k n·(v_k × v_k+1)/|v_k × v_k+1|).
fn polygon_irradiance(v: &[DVec3]) -> f64 {
    let mut e = 0.0;
    for k in 0..v.len() {
        let a = v[k].normalize();
        let b = v[(k + 1) % v.len()].normalize();
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        e += theta * a.cross(b).normalize().z;
    }
    0.5 * e.abs()
}

#[test]
fn square_light_over_a_plane_matches_lamberts_formula() {
    // Emitter: a 1×1 square at height 1, facing down, radiance 5; floor kd = 0.5.
    let mut g = Geometry::default();
    push_quad(
        &mut g,
        quad(
            DVec3::new(-20.0, -20.0, 0.0),
            DVec3::new(40.0, 0.0, 0.0),
            DVec3::new(0.0, 40.0, 0.0),
        ),
        0,
        Rgb::ZERO,
    );
    let c = DVec3::new(0.2, -0.4, 1.0);
    let (a, b) = (DVec3::Y, DVec3::X); // a × b = −z: facing the floor
    push_quad(&mut g, quad(c, a, b), 0, Rgb::splat(5.0));
    let scene = PathScene {
        geometry: g,
        materials: vec![lambert(0.5, false)],
        environment: None,
    };
    let corners = [c, c + a, c + a + b, c + b];
    let exact = 0.5 / PI * 5.0 * polygon_irradiance(&corners);
    let o = DVec3::new(0.0, 0.0, 0.5);
    let d = DVec3::new(0.0, 0.0001, -1.0).normalize();
    let mut errs = vec![];
    for st in [Strategy::Bsdf, Strategy::Light, Strategy::Mis] {
        // max_depth 2: the floor point lit directly (the light's back side is black).
        let pt = PathTracer::new(&scene, opts(2, st)).unwrap();
        let (m, e) = estimate(&pt, o, d, 20_000, 9);
        println!("square light {st:?}: {m:.5} ± {e:.5}, exact {exact:.5}");
        assert!(
            (m - exact).abs() < 4.0 * e + 1e-4,
            "{st:?}: {m} ± {e} vs {exact}"
        );
        errs.push(e);
    }
    assert!(errs[2] < errs[0], "MIS {} vs BSDF {}", errs[2], errs[0]);
}

#[test]
fn alpha_masked_surface_lets_light_through() {
    #[derive(Debug)]
    struct Holes;
    impl Surface for Holes {
        fn with_bsdf(&self, _uv: [f64; 2], f: &mut dyn FnMut(&dyn lustre_brdf::bsdf::Bsdf)) {
            f(&Lambert::new(Rgb::ZERO).unwrap())
        }
        fn masked(&self) -> bool {
            true
        }
        fn opaque(&self, _uv: [f64; 2]) -> bool {
            false
        }
    }
    // A black occluder that is fully masked out above the lit plane: the plane looks as if
    // the occluder were absent.
    let mut g = Geometry::default();
    push_quad(
        &mut g,
        quad(
            DVec3::new(-50.0, -50.0, 0.0),
            DVec3::new(100.0, 0.0, 0.0),
            DVec3::new(0.0, 100.0, 0.0),
        ),
        0,
        Rgb::ZERO,
    );
    push_quad(
        &mut g,
        quad(
            DVec3::new(-50.0, -50.0, 0.5),
            DVec3::new(100.0, 0.0, 0.0),
            DVec3::new(0.0, 100.0, 0.0),
        ),
        1,
        Rgb::ZERO,
    );
    let scene = PathScene {
        geometry: g,
        materials: vec![lambert(0.5, false), Box::new(Holes)],
        environment: Some(EnvLight::constant(Rgb::ONE).unwrap()),
    };
    let pt = PathTracer::new(&scene, PathOptions::default()).unwrap();
    let (m, e) = estimate(&pt, DVec3::new(0.0, 0.0, 2.0), -DVec3::Z, 2000, 2);
    assert!((m - 0.5).abs() < 4.0 * e + 1e-6, "{m} ± {e}");
}

#[test]
fn resumed_accumulation_equals_one_run_and_noise_estimate_is_honest() {
    let mut g = Geometry::default();
    push_quad(
        &mut g,
        quad(
            DVec3::new(-50.0, -50.0, 0.0),
            DVec3::new(100.0, 0.0, 0.0),
            DVec3::new(0.0, 100.0, 0.0),
        ),
        0,
        Rgb::ZERO,
    );
    // A sky with a bright half: noisy enough to measure.
    let mut data = vec![[0.2f32; 3]; 64 * 32];
    for (k, p) in data.iter_mut().enumerate() {
        if (k % 64) < 8 && (k / 64) < 12 {
            *p = [30.0; 3];
        }
    }
    let map = lustre_env::EquirectMap::new(64, 32, data).unwrap();
    let env = EnvLight::new(map, glam::DMat3::from_rotation_x(PI / 2.0), 1.0).unwrap();
    let scene = PathScene {
        geometry: g,
        materials: vec![lambert(0.5, false)],
        environment: Some(env),
    };
    let pt = PathTracer::new(&scene, opts(4, Strategy::Bsdf)).unwrap();
    let cam = PathCamera::look_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::Y, 30.0).unwrap();
    let (w, h) = (12, 10);
    let mut once = Accumulator::new(w, h).unwrap();
    pt.render(&cam, &mut once, 8, 42, &|_, _| {});
    let mut twice = Accumulator::new(w, h).unwrap();
    pt.render(&cam, &mut twice, 4, 42, &|_, _| {});
    // Through the files' precision (f32 half means) and back.
    let (a, b) = twice.halves();
    let mut twice = Accumulator::from_halves(&a, &b, twice.spp).unwrap();
    pt.render(&cam, &mut twice, 4, 42, &|_, _| {});
    for (p, q) in once.image().data.iter().zip(&twice.image().data) {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-5 * p[c].abs().max(1.0),
                "{p:?} {q:?}"
            );
        }
    }
    // Noise estimate vs the true error against a converged image (every pixel sees the same
    // flat plane lit by the same sky: the exact answer is one constant, the converged mean).
    let mut conv = Accumulator::new(w, h).unwrap();
    pt.render(&cam, &mut conv, 2048, 7, &|_, _| {});
    let truth_value: f64 =
        conv.image().data.iter().map(|p| p[0] as f64).sum::<f64>() / (w * h) as f64;
    let mut small = Accumulator::new(w, h).unwrap();
    pt.render(&cam, &mut small, 16, 99, &|_, _| {});
    let est = small.noise_rms().unwrap();
    let img = small.image();
    let truth = lustre_trace::image::Image {
        width: w,
        height: h,
        data: img
            .data
            .iter()
            .map(|_| {
                let v = truth_value as f32;
                [v, v, v]
            })
            .collect(),
    };
    let actual = lustre_trace::metrics::rms(&img, &truth).unwrap();
    println!("noise estimate {est:.4}, actual error {actual:.4}");
    assert!(
        est > 0.5 * actual && est < 2.0 * actual,
        "{est} vs {actual}"
    );
}

/// Texture coordinates of the two triangles of [`quad`]: u along a, v along b.
const QUAD_UVS: [[[f64; 2]; 3]; 2] = [
    [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]],
    [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
];

/// A black emitter material whose emission texture is 0.25 where u < ½ and 1 elsewhere.
#[derive(Debug)]
struct HalfDimmed;

impl Surface for HalfDimmed {
    fn with_bsdf(&self, _uv: [f64; 2], f: &mut dyn FnMut(&dyn lustre_brdf::bsdf::Bsdf)) {
        f(&Lambert::new(Rgb::ZERO).unwrap())
    }
    fn emission_textured(&self) -> bool {
        true
    }
    fn emission_factor(&self, uv: [f64; 2]) -> Rgb {
        Rgb::splat(if uv[0] < 0.5 { 0.25 } else { 1.0 })
    }
}

#[test]
fn emission_texture_scales_emitted_radiance_seen_and_sampled() {
    // Emitter: the square x, y ∈ [−1, 1] at height 1 facing down, radiance 4, u along +x, its
    // left half (x < 0) dimmed to 0.25 by the texture. Floor: Lambert 0.5 at z = 0.
    let mut g = Geometry::default();
    let emitter = quad(
        DVec3::new(-1.0, 1.0, 1.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, -2.0, 0.0),
    );
    push_quad(&mut g, emitter, 0, Rgb::splat(4.0));
    g.uvs.extend(QUAD_UVS);
    let floor = quad(
        DVec3::new(-50.0, -50.0, 0.0),
        DVec3::new(100.0, 0.0, 0.0),
        DVec3::new(0.0, 100.0, 0.0),
    );
    push_quad(&mut g, floor, 1, Rgb::ZERO);
    g.uvs.extend([[[0.0; 2]; 3]; 2]);
    let scene = PathScene {
        geometry: g,
        materials: vec![Box::new(HalfDimmed), lambert(0.5, false)],
        environment: None,
    };
    // Seen directly (max depth 1): exactly 4 × the texel.
    let pt = PathTracer::new(&scene, opts(1, Strategy::Mis)).unwrap();
    let mut rng = SplitMix64::new(1);
    let up = DVec3::Z;
    for (x, want) in [(-0.5, 1.0), (0.5, 4.0)] {
        let l = pt.radiance(DVec3::new(x, 0.2, 0.5), up, &mut rng);
        assert!((l[0] - want).abs() < 1e-12, "x = {x}: {l:?} vs {want}");
    }
    // On the floor below (direct light, max depth 2): L = ρ/π · Σ L_half · E_half(Lambert's
    // formula), by light sampling, BSDF sampling and MIS alike.
    let x = DVec3::new(0.3, -0.2, 0.0);
    let half = |x0: f64, x1: f64| {
        polygon_irradiance(&[
            DVec3::new(x0, -1.0, 1.0) - x,
            DVec3::new(x1, -1.0, 1.0) - x,
            DVec3::new(x1, 1.0, 1.0) - x,
            DVec3::new(x0, 1.0, 1.0) - x,
        ])
    };
    let exact = 0.5 / PI * (1.0 * half(-1.0, 0.0) + 4.0 * half(0.0, 1.0));
    for st in [Strategy::Light, Strategy::Bsdf, Strategy::Mis] {
        let pt = PathTracer::new(&scene, opts(2, st)).unwrap();
        let (m, e) = estimate(&pt, x + DVec3::Z * 0.5, -DVec3::Z, 40_000, 7);
        assert!(
            (m - exact).abs() < 4.0 * e + 1e-4,
            "{st:?}: {m} ± {e} vs {exact}"
        );
    }
}

/// A perfect mirror (two-sided off) whose normal map is the constant tangent-space normal
/// `n_ts`.
#[derive(Debug)]
struct MappedMirror {
    n_ts: DVec3,
}

impl Surface for MappedMirror {
    fn with_bsdf(&self, _uv: [f64; 2], f: &mut dyn FnMut(&dyn lustre_brdf::bsdf::Bsdf)) {
        f(&lustre_brdf::models::conductor::Conductor::preset("none").unwrap())
    }
    fn normal_mapped(&self) -> bool {
        true
    }
    fn normal_map(&self, _uv: [f64; 2]) -> Option<DVec3> {
        Some(self.n_ts)
    }
}

#[test]
fn normal_map_turns_the_mirror_reflection() {
    // A mirror floor at z = 0 (uvs: u along +x, v along +y) seen straight down. Emitter A
    // (radiance 1) lies straight above; emitter B (radiance 3) where the reflection goes when
    // the normal is tilted by 30° towards +x (60° from the vertical), emitter C (radiance 5)
    // where it goes for the same tilt towards −y. Generated tangent frame: T = ∂p/∂u = +x,
    // B = −∂p/∂v = −y (glTF's v runs down the image), so n_ts = (sin 30°, 0, cos 30°) turns
    // the normal towards +x and (0, sin 30°, cos 30°) towards −y. An explicit tangent +x with
    // w = +1 has B = N × T = +y (the reflection then misses everything); w = −1 gives −y.
    let (s30, c30) = (0.5f64, 0.75f64.sqrt());
    let build = |n_ts: DVec3, tangent: Option<[f64; 4]>| {
        let mut g = Geometry::default();
        let floor = quad(
            DVec3::new(-50.0, -50.0, 0.0),
            DVec3::new(100.0, 0.0, 0.0),
            DVec3::new(0.0, 100.0, 0.0),
        );
        push_quad(&mut g, floor, 0, Rgb::ZERO);
        // Emitter A: a 1×1 square at height 2 above the origin, facing down.
        push_quad(
            &mut g,
            quad(
                DVec3::new(-0.5, 0.5, 2.0),
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(0.0, -1.0, 0.0),
            ),
            1,
            Rgb::ONE,
        );
        // Emitters B and C: 1×1 squares facing the origin at distance 2.
        for (dir, side, l) in [
            (DVec3::new(c30, 0.0, s30), DVec3::Y, 3.0),
            (DVec3::new(0.0, -c30, s30), DVec3::X, 5.0),
        ] {
            let b = dir.cross(side);
            push_quad(
                &mut g,
                quad(dir * 2.0 - 0.5 * side - 0.5 * b, b, side),
                1,
                Rgb::splat(l),
            );
        }
        g.uvs.extend(QUAD_UVS);
        g.uvs.extend([[[0.0; 2]; 3]; 6]);
        if let Some(t) = tangent {
            g.tangents.extend([[t; 3]; 2]);
            g.tangents.extend([[[0.0; 4]; 3]; 6]);
        }
        PathScene {
            geometry: g,
            materials: vec![Box::new(MappedMirror { n_ts }), lambert(0.0, true)],
            environment: None,
        }
    };
    let look = |n_ts: DVec3, tangent: Option<[f64; 4]>| {
        let scene = build(n_ts, tangent);
        let pt = PathTracer::new(&scene, opts(2, Strategy::Bsdf)).unwrap();
        pt.radiance(
            DVec3::new(0.0, 0.0, 1.0),
            -DVec3::Z,
            &mut SplitMix64::new(3),
        )[0]
    };
    let (to_x, to_y) = (DVec3::new(s30, 0.0, c30), DVec3::new(0.0, s30, c30));
    let close = |a: f64, b: f64| (a - b).abs() < 1e-6 * b.max(1.0);
    assert!(close(look(DVec3::Z, None), 1.0), "flat map");
    assert!(close(look(to_x, None), 3.0), "{}", look(to_x, None));
    assert!(close(look(to_y, None), 5.0), "{}", look(to_y, None));
    let (w_pos, w_neg) = (Some([1.0, 0.0, 0.0, 1.0]), Some([1.0, 0.0, 0.0, -1.0]));
    assert!(close(look(to_x, w_pos), 3.0));
    assert_eq!(look(to_y, w_pos), 0.0);
    assert!(close(look(to_y, w_neg), 5.0));
}
