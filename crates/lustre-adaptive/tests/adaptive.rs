//! Adaptive shading (004 ch. IV) against exact and converged answers, on real data.

use lustre_adaptive::buffer::{
    coverage_samples, BandwidthBuffer, BrdfWeights, BufferOptions, SampleRule, NO_LEVEL,
};
use lustre_adaptive::gbuffer::{GBuffer, GPixel};
use lustre_adaptive::hierarchy::{box_downsample, render_adaptive, render_brute, NOT_SHADED};
use lustre_adaptive::light::{scene_lights, AreaLight};
use lustre_adaptive::shading::{Lighting, ShadingContext, ShadingOptions};
use lustre_brdf::rgb::Rgb;
use lustre_env::EquirectMap;
use lustre_scene::environment::{Environment, EnvironmentSource};
use lustre_scene::Scene;
use lustre_trace::baked::read_environment;
use lustre_trace::image::Image;
use lustre_trace::metrics::{psnr, rms};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{film_camera, path_scene};
use std::sync::Arc;

fn map_environment(map: EquirectMap) -> Environment {
    Environment {
        source: EnvironmentSource::Map {
            path: "test map".into(),
            map: Arc::new(map),
        },
        to_local: glam::DMat3::IDENTITY,
        intensity: 1.0,
    }
}

fn constant_map(v: f32) -> EquirectMap {
    EquirectMap::new(64, 32, vec![[v; 3]; 64 * 32]).expect("map")
}

fn royal() -> Environment {
    let path = lustre_env::shared_data_dir().join("envmaps/royal_esplanade_1k.hdr");
    read_environment(&path).expect("royal_esplanade_1k.hdr").0
}

/// Everything one frame needs.
struct Frame {
    scene: Scene,
    size: usize,
}

impl Frame {
    fn with<R>(
        &self,
        options: ShadingOptions,
        f: impl FnOnce(&GBuffer, &mut ShadingContext) -> R,
    ) -> R {
        let (ps, _) = path_scene(&self.scene).expect("path scene");
        let tracer = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
        let cam = film_camera(&self.scene.cameras[0], self.size as u32, self.size as u32)
            .expect("camera");
        let g = GBuffer::render(&tracer, &ps, &cam, self.size, self.size).expect("G-buffer");
        let mut ctx = ShadingContext::new(&ps, options, &|_, _| {}).expect("context");
        f(&g, &mut ctx)
    }
}

fn options(mean: f64, rule: SampleRule, lighting: Lighting) -> BufferOptions {
    BufferOptions {
        mean_samples: mean,
        scale: rule,
        lighting,
        ..Default::default()
    }
}

#[test]
fn a_white_furnace_gives_albedo_times_radiance_exactly_and_adaptive_shades_it_coarsely() {
    // A Lambertian sphere (kd 0.5) under a constant sky of radiance 2: every surface pixel is
    // 0.5 · 2 = 1 in expectation (the MIS estimator is not zero-variance: within 6 % per pixel
    // with 128 samples, 0.3 % over the image), and the image has no bandwidth, so the hierarchy
    // shades the coarse grid and up-samples the rest.
    let scene =
        lustre_scene::builtin::preview("lambert(kd=0.5)", Some(map_environment(constant_map(2.0))))
            .expect("scene");
    Frame { scene, size: 64 }.with(ShadingOptions::default(), |g, ctx| {
        let (brute, stats) = render_brute(g, ctx, 128, 1).expect("brute");
        assert_eq!(stats.shaded, g.surface_pixels());
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        let buffer = BandwidthBuffer::build(
            g,
            ctx,
            &env_bw,
            options(128.0, SampleRule::Constant, Lighting::Direct),
        )
        .expect("buffer");
        let adaptive = render_adaptive(g, ctx, &buffer, Lighting::Direct, 1).expect("adaptive");
        let mut sums = [0.0f64; 2];
        for (k, p) in g.pixels.iter().enumerate() {
            let (x, y) = (k % g.width, k / g.width);
            let expected = match p {
                GPixel::Surface(_) => 1.0,
                GPixel::Background(_) => 2.0,
            };
            let tolerance = if expected == 1.0 { 0.06 } else { 1e-6 };
            for (i, img) in [&brute, &adaptive.image].into_iter().enumerate() {
                for c in img.get(x, y) {
                    assert!(
                        (f64::from(c) - expected).abs() < tolerance,
                        "({x}, {y}): {c} vs {expected}"
                    );
                    if expected == 1.0 {
                        sums[i] += f64::from(c) / 3.0;
                    }
                }
            }
        }
        for s in sums {
            let mean = s / g.surface_pixels() as f64;
            assert!((mean - 1.0).abs() < 3e-3, "mean {mean}");
        }
        let surface = g.surface_pixels();
        assert!(
            adaptive.stats.shaded * 4 < surface,
            "shaded {} of {surface}",
            adaptive.stats.shaded
        );
        assert_eq!(adaptive.stats.shaded + adaptive.stats.upsampled, surface);
    });
}

#[test]
fn pre_convolved_shading_reads_the_map_itself_where_nothing_is_filtered() {
    // red-metallic-paint's BRDF bandwidth reaches the table's ceiling (20.4 cycles/rad) on
    // every pixel, so the pre-convolved level is 0 everywhere: the pre-convolved frame is the
    // direct one, pixel for pixel, with the same N_p (the constant rule).
    let scene =
        lustre_scene::builtin::preview("nbrdf:red-metallic-paint", Some(royal())).expect("scene");
    Frame { scene, size: 24 }.with(ShadingOptions::default(), |g, ctx| {
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        let o = |l| options(16.0, SampleRule::Constant, l);
        let b_pre =
            BandwidthBuffer::build(g, ctx, &env_bw, o(Lighting::Preconvolved)).expect("buffer");
        let b_direct =
            BandwidthBuffer::build(g, ctx, &env_bw, o(Lighting::Direct)).expect("buffer");
        let surface: Vec<usize> = (0..b_pre.level.len())
            .filter(|&k| b_pre.level[k] != u8::MAX)
            .collect();
        assert!(surface.len() > 100);
        assert!(surface
            .iter()
            .all(|&k| ctx.level_for(b_pre.brdf_max[k]) == 0.0));
        let pre = render_adaptive(g, ctx, &b_pre, Lighting::Preconvolved, 5).expect("pre");
        let direct = render_adaptive(g, ctx, &b_direct, Lighting::Direct, 5).expect("direct");
        assert_eq!(pre.shaded_level, direct.shaded_level);
        assert_eq!(pre.image.data, direct.image.data);
    });
}

#[test]
fn pre_convolved_shading_of_a_constant_sky_is_exact_too() {
    let scene = lustre_scene::builtin::preview(
        "nbrdf:gold-paint",
        Some(map_environment(constant_map(1.0))),
    )
    .expect("scene");
    Frame { scene, size: 32 }.with(ShadingOptions::default(), |g, ctx| {
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        let o = options(64.0, SampleRule::Constant, Lighting::Preconvolved);
        let buffer = BandwidthBuffer::build(g, ctx, &env_bw, o).expect("buffer");
        let pre = render_adaptive(g, ctx, &buffer, Lighting::Preconvolved, 3).expect("pre");
        let (direct, _) = render_brute(g, ctx, 64, 3).expect("brute");
        // A constant sky stays constant at every level, so the two agree to the pyramid's
        // float precision wherever the same pixels were shaded.
        let mut compared = 0;
        for (k, l) in pre.shaded_level.iter().enumerate() {
            if *l != u8::MAX {
                let (x, y) = (k % g.width, k / g.width);
                let (a, b) = (pre.image.get(x, y), direct.get(x, y));
                for c in 0..3 {
                    assert!(
                        (a[c] - b[c]).abs() <= 1e-4 * b[c].abs().max(1.0),
                        "({x}, {y})"
                    );
                }
                compared += 1;
            }
        }
        assert!(compared > 0);
    });
}

#[test]
fn on_a_measured_paint_under_a_real_sky_adaptive_beats_brute_force_at_equal_samples() {
    // gold-paint's neural BRDF under royal_esplanade_1k: the reference is brute force with
    // 2 × 256 samples (its own noise is estimated from its halves and must be far below the
    // errors judged); adaptive shading with a constant N_p of 32 at the shaded pixels must
    // reach a higher PSNR than brute force with 32 at every pixel, with under 60 % of the
    // samples (measured: 34.62 vs 33.46 dB with 104,032 vs 195,840 samples).
    let scene = lustre_scene::builtin::preview("nbrdf:gold-paint", Some(royal())).expect("scene");
    Frame { scene, size: 96 }.with(ShadingOptions::default(), |g, ctx| {
        let (r1, _) = render_brute(g, ctx, 256, 11).expect("ref 1");
        let (r2, _) = render_brute(g, ctx, 256, 12).expect("ref 2");
        let reference = Image::from_data(
            g.width,
            g.height,
            r1.data
                .iter()
                .zip(&r2.data)
                .map(|(a, b)| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])])
                .collect(),
        )
        .expect("reference");
        let exposure = 0.5 / reference.mean();
        let (brute, bstats) = render_brute(g, ctx, 32, 5).expect("brute");
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        let buffer = BandwidthBuffer::build(
            g,
            ctx,
            &env_bw,
            options(32.0, SampleRule::Constant, Lighting::Direct),
        )
        .expect("buffer");
        let adaptive = render_adaptive(g, ctx, &buffer, Lighting::Direct, 5).expect("adaptive");
        let p_brute = psnr(&reference, &brute, exposure).expect("psnr");
        let p_adaptive = psnr(&reference, &adaptive.image, exposure).expect("psnr");
        let ref_noise = rms(&r1, &r2).expect("rms") / 2.0;
        let err_adaptive = rms(&reference, &adaptive.image).expect("rms");
        eprintln!(
            "brute 32: {p_brute:.2} dB, {} samples; adaptive: {p_adaptive:.2} dB, {} samples, {} of {} pixels shaded; reference noise {ref_noise:.2e} vs adaptive error {err_adaptive:.2e}",
            bstats.samples,
            adaptive.stats.samples,
            adaptive.stats.shaded,
            g.surface_pixels()
        );
        assert!(ref_noise < 0.3 * err_adaptive, "the reference is too noisy");
        assert!(p_adaptive > p_brute, "{p_adaptive} ≤ {p_brute}");
        assert!(10 * adaptive.stats.samples < 6 * bstats.samples);
        // ρ read from the tables (the default) against ρ evaluated: the same levels on nearly
        // every pixel, and an image as close to the reference.
        let evaluated = BandwidthBuffer::build(
            g,
            ctx,
            &env_bw,
            BufferOptions {
                weights: BrdfWeights::Evaluated,
                ..options(32.0, SampleRule::Constant, Lighting::Direct)
            },
        )
        .expect("buffer");
        let same = buffer
            .level
            .iter()
            .zip(&evaluated.level)
            .filter(|(a, b)| a == b)
            .count() as f64
            / buffer.level.len() as f64;
        let by_eval = render_adaptive(g, ctx, &evaluated, Lighting::Direct, 5).expect("adaptive");
        let p_eval = psnr(&reference, &by_eval.image, exposure).expect("psnr");
        eprintln!(
            "ρ evaluated: {p_eval:.2} dB, {} pixels shaded; levels equal on {:.2} % of pixels",
            by_eval.stats.shaded,
            100.0 * same
        );
        assert!(same > 0.97, "levels equal on {same}");
        assert!((p_adaptive - p_eval).abs() < 0.3, "{p_adaptive} vs {p_eval}");
        // N_p by the level's coverage (N_0 = 16 at level 0, round(16 · ⅔ · 2^k) at level k):
        // every shaded pixel has its level's count. (On this sphere it does not beat the
        // constant rule at equal samples: 33.92 dB with 98,892 samples at N_0 22 against
        // 34.66 dB with 101,024; BENCHMARKS.md "Adaptive shading, ninth part".)
        let fp_buffer = BandwidthBuffer::build(
            g,
            ctx,
            &env_bw,
            options(16.0, SampleRule::Coverage, Lighting::Direct),
        )
        .expect("buffer");
        let fp = render_adaptive(g, ctx, &fp_buffer, Lighting::Direct, 5).expect("adaptive");
        let mut counted = 0u64;
        for (k, &l) in fp.shaded_level.iter().enumerate() {
            if l != NOT_SHADED {
                let n = coverage_samples(16, l as usize, fp_buffer.max_samples);
                assert_eq!(fp.samples[k] as usize, n, "pixel {k} at level {l}");
                counted += n as u64;
            }
        }
        assert_eq!(counted, fp.stats.samples);
        assert_eq!(fp.shaded_level, adaptive.shaded_level, "the rule moves no level");
        assert!(fp.stats.per_level.iter().filter(|l| l.0 > 0).count() >= 3);
    });
}

#[test]
fn buffers_hold_no_nan_on_black_or_degenerate_input_and_bad_parameters_are_named() {
    // A black sky lights nothing: the scene is either refused by name or, taken as one without
    // an environment, nothing lights it (no emitter either), which the context says.
    let black = lustre_scene::builtin::preview(
        "nbrdf:blue-rubber",
        Some(map_environment(constant_map(0.0))),
    )
    .expect("scene");
    match path_scene(&black) {
        Err(e) => assert!(e.to_string().contains("black"), "{e}"),
        Ok((ps, _)) => {
            let ctx = ShadingContext::new(&ps, ShadingOptions::default(), &|_, _| {})
                .expect("a context without light");
            assert!(!ctx.lit_by_environment());
            let e = ctx.check_lit().expect_err("nothing lights it");
            assert!(e.to_string().contains("nothing lights the scene"), "{e}");
        }
    }
    // A sky that is black but for one texel, and every sample rule: finite everywhere.
    let mut texels = vec![[0.0f32; 3]; 64 * 32];
    texels[10 * 64 + 20] = [1e4, 1e4, 1e4];
    let scene = lustre_scene::builtin::preview(
        "nbrdf:white-marble",
        Some(map_environment(
            EquirectMap::new(64, 32, texels).expect("map"),
        )),
    )
    .expect("scene");
    Frame { scene, size: 24 }.with(ShadingOptions::default(), |g, ctx| {
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        for rule in [
            SampleRule::Constant,
            SampleRule::Absolute,
            SampleRule::Relative,
            SampleRule::RelativeMse,
        ] {
            for lighting in [Lighting::Direct, Lighting::Preconvolved] {
                for mean in [1.0, 7.5, 1024.0] {
                    let b = BandwidthBuffer::build(g, ctx, &env_bw, options(mean, rule, lighting))
                        .expect("buffer");
                    assert!(b
                        .bandwidth
                        .iter()
                        .chain(&b.variance)
                        .chain(&b.brdf_max)
                        .all(|v| v.is_finite() && *v >= 0.0));
                    assert!(b.target.is_finite() && b.target > 0.0);
                    for (k, l) in b.level.iter().enumerate() {
                        let surface = matches!(g.pixels[k], GPixel::Surface(_));
                        assert_eq!(*l == NO_LEVEL, !surface);
                        assert!(!surface || (*l as usize) < b.levels);
                    }
                    let f = render_adaptive(g, ctx, &b, lighting, 1).expect("adaptive");
                    assert!(f.image.data.iter().flatten().all(|c| c.is_finite()));
                    assert!(f.samples.iter().all(|n| *n as usize <= b.max_samples));
                }
            }
        }
        for bad in [
            BufferOptions {
                n_b: 0,
                ..Default::default()
            },
            BufferOptions {
                mean_samples: 0.5,
                ..Default::default()
            },
            BufferOptions {
                mean_samples: f64::NAN,
                ..Default::default()
            },
            BufferOptions {
                max_samples: 0,
                ..Default::default()
            },
            BufferOptions {
                rate: 0.0,
                ..Default::default()
            },
        ] {
            let e = BandwidthBuffer::build(g, ctx, &env_bw, bad).expect_err("absurd options");
            assert!(e.to_string().contains("bandwidth buffer"), "{e}");
        }
        assert!(render_brute(g, ctx, 0, 1).is_err());
    });
    // Degenerate G-buffer values: a zero normal and a NaN curvature predict nothing, no NaN.
    let scene = lustre_scene::builtin::preview("nbrdf:gold-paint", Some(royal())).expect("scene");
    Frame { scene, size: 16 }.with(ShadingOptions::default(), |g, ctx| {
        let mut g = g.clone();
        for p in g.pixels.iter_mut() {
            if let GPixel::Surface(s) = p {
                s.curvature = f64::NAN;
                s.frame.n = glam::DVec3::ZERO;
            }
        }
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        let b = BandwidthBuffer::build(&g, ctx, &env_bw, BufferOptions::default()).expect("buffer");
        assert!(b.bandwidth.iter().chain(&b.variance).all(|v| v.is_finite()));
        let f = render_adaptive(&g, ctx, &b, Lighting::Direct, 1).expect("adaptive");
        assert!(f.image.data.iter().flatten().all(|c| c.is_finite()));
    });
}

#[test]
fn coverage_counts_are_two_thirds_of_two_to_the_level_rounded() {
    for (n0, k, max, n) in [
        (16, 0, 1024, 16),
        (16, 1, 1024, 21),
        (16, 2, 1024, 43),
        (1, 1, 1024, 1),
        (1, 2, 1024, 3),
        (3, 1, 1024, 4),
        (5, 3, 1024, 27),
        (0, 0, 1024, 1),
        (1000, 4, 1024, 1024),
        (7, 200, 4096, 4096),
        (5, 2, 0, 1),
    ] {
        assert_eq!(coverage_samples(n0, k, max), n, "N_0 {n0}, level {k}");
    }
}

#[test]
fn supersampled_frames_resolve_by_their_blocks() {
    let img = Image::from_data(4, 2, (0..8).map(|k| [k as f32, 1.0, 2.0]).collect()).expect("img");
    let r = box_downsample(&img, 2).expect("resolve");
    assert_eq!((r.width, r.height), (2, 1));
    assert_eq!(r.get(0, 0), [(0.0 + 1.0 + 4.0 + 5.0) / 4.0, 1.0, 2.0]);
    assert_eq!(r.get(1, 0), [(2.0 + 3.0 + 6.0 + 7.0) / 4.0, 1.0, 2.0]);
    assert!(box_downsample(&img, 3).is_err());
    assert!(box_downsample(&img, 0).is_err());
}

/// The form factor from a point to a parallel a × b rectangle with a corner above it at height c
/// (Howell's catalog, B-3): 1/2π [A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²))].
fn corner_form_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

/// A Lambertian floor (kd 0.5) under a constant sky of 0.1 and a 2 × 2 m light of radiance 3
/// facing down 2 m above the point the camera's centre pixel sees.
fn lit_floor(texture: Option<(usize, usize, Vec<[f32; 3]>)>) -> (Scene, AreaLight) {
    let mut scene =
        lustre_scene::builtin::preview("lambert(kd=0.5)", Some(map_environment(constant_map(0.1))))
            .expect("scene");
    let mut floor = lustre_scene::mesh::rectangle("floor", 0);
    floor.transform(
        &(glam::DMat4::from_scale(glam::DVec3::new(6.0, 1.0, 6.0))
            * glam::DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2)),
    );
    scene.meshes = vec![floor];
    scene.cameras = vec![lustre_scene::camera::Camera::look_at(
        "default",
        glam::DVec3::new(0.0, 4.0, 3.0),
        glam::DVec3::ZERO,
        glam::DVec3::Y,
        40.0,
        lustre_scene::camera::FovAxis::Y,
    )
    .expect("camera")];
    let light = AreaLight::new(
        glam::DVec3::new(-1.0, 2.0, -1.0),
        glam::DVec3::new(2.0, 0.0, 0.0),
        glam::DVec3::new(0.0, 0.0, 2.0),
        Rgb::splat(3.0),
        texture,
    )
    .expect("light");
    (scene, light)
}

#[test]
fn an_area_light_over_a_lambertian_floor_gives_the_form_factor_and_its_texture_raises_the_bandwidth(
) {
    let (scene, light) = lit_floor(None);
    assert!(light.normal().y < -0.999, "the light faces down");
    // 33² pixels: the centre of pixel (16, 16) is the image's centre, which sees the origin.
    let frame = Frame { scene, size: 33 };
    let expected = 0.5 * 0.1 + 0.5 * 3.0 * 4.0 * corner_form_factor(1.0, 1.0, 2.0);
    let plain = frame.with(ShadingOptions::default(), |g, ctx| {
        ctx.lights = vec![light.clone()];
        let s = g.surfel(16, 16).expect("the floor");
        assert!(s.position.length() < 1e-9, "{}", s.position);
        let (b, brute, _) = lit_floor_agrees(g, ctx, expected, "area light");
        ctx.lights.clear();
        let unlit = render_brute(g, ctx, 64, 1).expect("unlit").0;
        assert!(
            brute.mean() > 2.0 * unlit.mean(),
            "the light adds to the floor"
        );
        mean_bandwidth(&b)
    });
    // A checkerboard of 8 × 8 squares on the same light: more spatial bandwidth reaches the
    // floor below it.
    let checker: Vec<[f32; 3]> = (0..64 * 64)
        .map(|k| {
            let (x, y) = (k % 64 / 8, k / 64 / 8);
            [((x + y) % 2) as f32 * 2.0; 3]
        })
        .collect();
    let (scene, light) = lit_floor(Some((64, 64, checker)));
    let textured = Frame { scene, size: 33 }.with(ShadingOptions::default(), |g, ctx| {
        ctx.lights = vec![light.clone()];
        let env_bw = ctx.environment_bandwidth().expect("bandwidth");
        let o = options(16.0, SampleRule::Constant, Lighting::Direct);
        mean_bandwidth(&BandwidthBuffer::build(g, ctx, &env_bw, o).expect("buffer"))
    });
    eprintln!("mean b_p: textured light {textured:.4}, plain {plain:.4} cycles per pixel");
    assert!(
        textured > 1.5 * plain,
        "textured {textured} vs plain {plain}"
    );
    // Bad lights are refused by name.
    for (u, v, r) in [
        (glam::DVec3::X, glam::DVec3::X, 1.0),
        (glam::DVec3::X, glam::DVec3::Z, -1.0),
        (glam::DVec3::X, glam::DVec3::new(0.0, f64::NAN, 1.0), 1.0),
    ] {
        assert!(AreaLight::new(glam::DVec3::ZERO, u, v, Rgb::splat(r), None).is_err());
    }
    let e = AreaLight::new(
        glam::DVec3::ZERO,
        glam::DVec3::X,
        glam::DVec3::Z,
        Rgb::ONE,
        Some((2, 2, vec![[1.0; 3], [f32::NAN; 3], [1.0; 3], [1.0; 3]])),
    )
    .expect_err("a NaN texel");
    assert!(e.to_string().contains("texel (1, 0)"), "{e}");
}

/// On a floor frame whose centre pixel (16, 16) sees the origin: `shade` there (1,024 samples)
/// gives `expected` within 0.2 %, and adaptive shading's frame mean (N_p 16) is brute force's
/// (64 samples) within 1 %. Returns the buffer, brute force's frame and the pixels shaded.
fn lit_floor_agrees(
    g: &GBuffer,
    ctx: &ShadingContext,
    expected: f64,
    what: &str,
) -> (BandwidthBuffer, Image, usize) {
    let s = g.surfel(16, 16).expect("the floor");
    let v = ctx.shade(s, 1024, None, 3).luminance();
    eprintln!("{what}: {v:.5} vs the form factor's {expected:.5}");
    assert!(
        (v - expected).abs() < 2e-3 * expected,
        "{what}: {v} vs {expected}"
    );
    let env_bw = ctx.environment_bandwidth().expect("bandwidth");
    let o = options(16.0, SampleRule::Constant, Lighting::Direct);
    let b = BandwidthBuffer::build(g, ctx, &env_bw, o).expect("buffer");
    let (brute, _) = render_brute(g, ctx, 64, 1).expect("brute");
    let f = render_adaptive(g, ctx, &b, Lighting::Direct, 1).expect("adaptive");
    let ratio = f.image.mean() / brute.mean();
    eprintln!(
        "{what}: adaptive / brute mean {ratio:.5}, {} of {} pixels shaded",
        f.stats.shaded,
        g.surface_pixels()
    );
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "{what}: adaptive / brute mean {ratio}"
    );
    (b, brute, f.stats.shaded)
}

fn mean_bandwidth(b: &BandwidthBuffer) -> f64 {
    let v: Vec<f64> = b
        .bandwidth
        .iter()
        .zip(&b.level)
        .filter(|(_, l)| **l != NO_LEVEL)
        .map(|(v, _)| *v)
        .collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The floor of [`lit_floor`] (12 × 12 m, uv over [0, 1]²) under its constant sky alone, its
/// material a Lambertian of reflectance `reflectance`, textured by `texture` (64² texels).
fn floor_of(reflectance: lustre_scene::TexturedRgb, texture: Option<Vec<f32>>) -> Scene {
    let (mut scene, _) = lit_floor(None);
    scene.materials[0] =
        lustre_scene::Material::new("floor", lustre_scene::MaterialKind::Diffuse { reflectance });
    if let Some(data) = texture {
        scene.textures.push(
            lustre_scene::Texture::new(
                "checker",
                64,
                64,
                3,
                lustre_scene::ColorSpace::Linear,
                data,
            )
            .expect("texture"),
        );
    }
    scene
}

#[test]
fn a_textured_material_adds_its_texture_bandwidth_at_the_rate_of_its_uv_mapping() {
    // A checkerboard of 8 × 8-texel squares, reflectance 0.2 / 0.8, against its mean, 0.5.
    let checker: Vec<f32> = (0..64 * 64)
        .flat_map(|k| {
            let (x, y) = (k % 64 / 8, k / 64 / 8);
            [if (x + y) % 2 == 0 { 0.2 } else { 0.8 }; 3]
        })
        .collect();
    let textured = floor_of(
        lustre_scene::TexturedRgb::texture(lustre_scene::TextureRef {
            texture: 0,
            uv_set: 0,
        }),
        Some(checker),
    );
    let plain = floor_of(lustre_scene::TexturedRgb::constant(Rgb::splat(0.5)), None);
    let run = |scene: Scene| {
        Frame { scene, size: 33 }.with(ShadingOptions::default(), |g, ctx| {
            let s = g.surfel(16, 16).expect("the floor");
            let t = ctx.texture_bandwidth(s);
            let env_bw = ctx.environment_bandwidth().expect("bandwidth");
            let o = options(16.0, SampleRule::Constant, Lighting::Direct);
            let b = BandwidthBuffer::build(g, ctx, &env_bw, o).expect("buffer");
            assert!(b.bandwidth.iter().all(|v| v.is_finite()));
            // Eq. IV.6–IV.7 at the centre pixel, which sees the origin from 5 m at cos θ = 0.8:
            // t cycles per metre on the floor are t · d / cos θ cycles per radian at the eye.
            let expected = t * s.depth / s.wo.dot(s.frame.n) * g.radians_per_pixel();
            (
                s.uv_rate,
                t,
                mean_bandwidth(&b),
                b.bandwidth[16 * 33 + 16],
                expected,
            )
        })
    };
    let (rate, t, textured_bp, centre, expected) = run(textured);
    let (plain_rate, plain_t, plain_bp, _, _) = run(plain);
    // The floor is 12 m across its uv square: 1/12 uv per metre along both axes.
    for r in rate {
        assert!(
            (r - 1.0 / 12.0).abs() < 0.02 / 12.0,
            "uv per metre {rate:?}"
        );
    }
    assert_eq!(rate, plain_rate);
    // 64 texels per 12 m, the checker's bandwidth per texel: cycles per metre > 0; none
    // untextured.
    assert_eq!(plain_t, 0.0);
    assert!(t > 0.0 && t.is_finite(), "{t}");
    eprintln!(
        "texture bandwidth at the centre {t:.3} cycles per metre; b_p there {centre:.4} \
         cycles per pixel (t · d / cos θ per pixel: {expected:.4}); mean b_p textured \
         {textured_bp:.4}, plain {plain_bp:.4}"
    );
    // Under a constant sky a plain Lambertian floor has nothing to resolve; the texture alone
    // sets b_p.
    assert!(plain_bp < 1e-9, "plain {plain_bp}");
    assert!(
        (centre - expected).abs() < 0.05 * expected,
        "b_p {centre} at the centre vs {expected}"
    );
}

/// `mesh` (in the plane z = 0, facing +z) turned to face down, 2 m above the origin.
fn facing_down_at_2m(mut mesh: lustre_scene::mesh::Mesh) -> lustre_scene::mesh::Mesh {
    mesh.transform(
        &(glam::DMat4::from_translation(glam::DVec3::new(0.0, 2.0, 0.0))
            * glam::DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2)),
    );
    mesh
}

/// A Lambertian floor (kd 0.5) lit only by `emitter` (a mesh of radiance 3), no environment.
fn floor_under(emitter: lustre_scene::mesh::Mesh) -> Scene {
    let (mut scene, _) = lit_floor(None);
    scene.environment = None;
    let mut e = emitter;
    e.emission = Some(Rgb::splat(3.0));
    scene.meshes.push(e);
    scene
}

#[test]
fn a_scenes_own_planar_emitters_light_it_as_area_lights() {
    // A 2 × 2 m rectangle emitter 2 m above the origin, facing down, and no environment: the
    // floor's radiance at the origin is ρ L_e F (the form factor of its four 1 × 1 quarters).
    let rect = facing_down_at_2m(lustre_scene::mesh::rectangle("panel", 0));
    let frame = Frame {
        scene: floor_under(rect),
        size: 33,
    };
    frame.with(ShadingOptions::default(), |g, ctx| {
        assert!(!ctx.lit_by_environment());
        assert!(ctx.check_lit().is_err(), "no light yet");
        ctx.lights = scene_lights(ctx.scene).expect("lights");
        assert_eq!(ctx.lights.len(), 1);
        let l = &ctx.lights[0];
        // The rectangle itself: its own area, facing down, every texel covered alike.
        assert!((l.area() - 4.0).abs() < 1e-5, "area {}", l.area());
        assert!(l.normal().y < -0.999_999, "normal {}", l.normal());
        let (_, _, texels) = l.texture();
        assert!(texels.iter().all(|t| (t[0] - texels[0][0]).abs() < 1e-6));
        let expected = 0.5 * 3.0 * 4.0 * corner_form_factor(1.0, 1.0, 2.0);
        let (_, _, shaded) = lit_floor_agrees(g, ctx, expected, "rectangle emitter");
        assert!(shaded < g.surface_pixels());
    });
    // A disk emitter of radius 1 (Mitsuba's 64-triangle fan) at the same height: drawn into a
    // square light; on its axis the irradiance form factor of a disk, R² / (R² + h²).
    let disk = facing_down_at_2m(lustre_scene::mesh::disk("lamp", 0));
    let frame = Frame {
        scene: floor_under(disk),
        size: 33,
    };
    frame.with(ShadingOptions::default(), |g, ctx| {
        ctx.lights = scene_lights(ctx.scene).expect("lights");
        assert_eq!(ctx.lights.len(), 1);
        let l = &ctx.lights[0];
        // Its power is the fan's: Σ texels × texel area × radiance = L_e × fan area.
        let (w, h, texels) = l.texture();
        let fan = 32.0 * (2.0 * std::f64::consts::PI / 64.0).sin();
        let power: f64 = texels.iter().map(|t| f64::from(t[1])).sum::<f64>() * l.area()
            / (w * h) as f64
            * l.radiance.0[1];
        assert!(
            (power - 3.0 * fan).abs() < 1e-6 * fan,
            "{power} vs {}",
            3.0 * fan
        );
        assert!(
            (l.area() - 4.0).abs() < 0.01,
            "square of side 2: {}",
            l.area()
        );
        let expected = 0.5 * 3.0 * 1.0 / (1.0 + 4.0);
        let s = g.surfel(16, 16).expect("the floor");
        let v = ctx.shade(s, 1024, None, 3).luminance();
        eprintln!("disk emitter: {v:.5} vs the disk's form factor {expected:.5}");
        assert!((v - expected).abs() < 5e-3 * expected, "{v} vs {expected}");
    });
    // Two emitters that share no vertex are two lights; a cube is refused by name.
    let mut a = lustre_scene::mesh::rectangle("a", 0);
    a.transform(&glam::DMat4::from_translation(glam::DVec3::new(
        -3.0, 2.0, 0.0,
    )));
    let mut scene = floor_under(a);
    let mut b = lustre_scene::mesh::disk("b", 0);
    b.transform(&glam::DMat4::from_translation(glam::DVec3::new(
        3.0, 2.0, 0.0,
    )));
    b.emission = Some(Rgb::splat(1.0));
    scene.meshes.push(b);
    let (ps, _) = path_scene(&scene).expect("path scene");
    assert_eq!(scene_lights(&ps).expect("two lights").len(), 2);
    let mut cube = lustre_scene::mesh::cube("box", 0);
    cube.transform(&glam::DMat4::from_translation(glam::DVec3::new(
        0.0, 3.0, 0.0,
    )));
    let boxed = floor_under(cube);
    let (ps, _) = path_scene(&boxed).expect("path scene");
    let e = scene_lights(&ps).expect_err("a cube emitter");
    assert!(e.to_string().contains("not planar"), "{e}");
}

/// Σ over the lights of ∫ L dA per channel (texels × texel area × radiance scale).
fn light_power(lights: &[AreaLight]) -> [f64; 3] {
    let mut p = [0.0; 3];
    for l in lights {
        let (w, h, texels) = l.texture();
        for (c, acc) in p.iter_mut().enumerate() {
            *acc += texels.iter().map(|t| f64::from(t[c])).sum::<f64>() * l.area() / (w * h) as f64
                * l.radiance.0[c];
        }
    }
    p
}

/// Σ over the emissive triangles of area × radiance per channel.
fn emitted_power(ps: &lustre_trace::path_tracer::PathScene) -> [f64; 3] {
    let g = &ps.geometry;
    let mut p = [0.0; 3];
    for (i, e) in g.emission.iter().enumerate() {
        let [a, b, c] = g.positions[i];
        let area = 0.5 * (b - a).cross(c - a).length();
        for (acc, v) in p.iter_mut().zip(e.0) {
            *acc += area * v;
        }
    }
    p
}

#[test]
fn the_modern_halls_emitters_and_the_cornell_boxs_panel_become_area_lights() {
    // The Hall (Bitterli's staircase2): 13 emitters, 5 disk lamps of radius 0.1049 m on the
    // ceiling facing down, 8 rectangles; the lights keep the triangles' power.
    let hall = Scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/modern_hall.toml"),
    )
    .expect("the Hall");
    let (ps, _) = path_scene(&hall).expect("path scene");
    let lights = scene_lights(&ps).expect("lights");
    assert_eq!(lights.len(), 13);
    let lamps = lights
        .iter()
        .filter(|l| l.normal().y < -0.999 && (l.edge_u.length() - 2.0 * 0.104916).abs() < 2e-3)
        .count();
    assert_eq!(lamps, 5, "the ceiling lamps");
    let (drawn, exact) = (light_power(&lights), emitted_power(&ps));
    eprintln!("the Hall's emitters: power of the lights {drawn:.5?}, of the triangles {exact:.5?}");
    for c in 0..3 {
        assert!(
            (drawn[c] / exact[c] - 1.0).abs() < 1e-6,
            "{drawn:?} vs {exact:?}"
        );
    }
    // The Cornell box's ceiling panel: one light, the panel's own area, facing down.
    let cornell =
        Scene::load(&lustre_env::shared_data_dir().join("scenes/cornell_box/cornell_box.obj"))
            .expect("the Cornell box");
    let (ps, _) = path_scene(&cornell).expect("path scene");
    let lights = scene_lights(&ps).expect("lights");
    assert_eq!(lights.len(), 1);
    let (drawn, exact) = (light_power(&lights), emitted_power(&ps));
    eprintln!(
        "Cornell panel: {:.5} m² facing {:.3}, power {drawn:.5?} vs the triangles' {exact:.5?}",
        lights[0].area(),
        lights[0].normal()
    );
    assert!((drawn[0] / exact[0] - 1.0).abs() < 1e-6);
    assert!(lights[0].normal().y < -0.999);
}
