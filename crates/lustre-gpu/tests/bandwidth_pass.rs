//! The bandwidth pass (`bandwidth_pass.wgsl`) against its CPU twin
//! (`lustre_adaptive::buffer::predict_pixels`) on 004's line-up of measured paints (neural
//! BRDFs) under royal_esplanade_1k, and the buffers assembled from both. GPU tests fail (never
//! skip) without an adapter.

use lustre_adaptive::buffer::{
    predict_pixels, BandwidthBuffer, BrdfWeights, BufferOptions, SampleRule,
};
use lustre_gpu::material::measured::MeasuredBrdf;
use lustre_gpu::passes::bandwidth::{
    BandwidthPass, BandwidthPixel, BandwidthScene, DIRECTIONS_PER_DISPATCH,
};

mod common;
use common::{ctx, line_up};

/// Relative differences |g − c| / max(|c|, floor) over the pixels: RMS, worst, and the share
/// above `outlier`.
fn compare(pairs: &[(f64, f64)], floor: f64, outlier: f64) -> (f64, f64, f64) {
    let d: Vec<f64> = pairs
        .iter()
        .map(|(c, g)| (g - c).abs() / c.abs().max(floor))
        .collect();
    let rms = (d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt();
    let worst = d.iter().cloned().fold(0.0, f64::max);
    let share = d.iter().filter(|v| **v > outlier).count() as f64 / d.len() as f64;
    (rms, worst, share)
}

#[test]
fn the_gpu_bandwidth_pass_matches_its_cpu_twin_on_the_line_up() {
    let scene = line_up::scene(
        [
            "nbrdf:color-changing-paint3",
            "nbrdf:red-metallic-paint",
            "nbrdf:gold-paint",
        ],
        "nbrdf:white-marble",
    );
    let (w, h) = (96, 64);
    line_up::with_frame(&scene, (w, h), |_, g, shading| {
        let env_bw = shading.environment_bandwidth().expect("env bandwidth");
        let n_b = 16;
        let cpu = predict_pixels(&g, &shading, &env_bw, n_b, BrdfWeights::Evaluated).expect("cpu");
        let gpu_ctx = ctx();
        let scene_gpu =
            BandwidthScene::from_context(&gpu_ctx, &shading, &env_bw, None).expect("upload");
        let mut pass = BandwidthPass::new(&gpu_ctx).expect("pass");
        let (gpu, timing) = pass
            .predict(&gpu_ctx, &scene_gpu, &g, &shading, n_b as u32)
            .expect("gpu");
        eprintln!("{}", gpu_ctx.describe());
        eprintln!(
            "bandwidth pass, {w}×{h}, n_b {n_b}: wall {:.2} ms, GPU {:?} ms",
            timing.wall_ms, timing.gpu_ms
        );
        assert_eq!(cpu.len(), gpu.len());
        let mut fields: [Vec<(f64, f64)>; 6] = Default::default();
        let mut surface = 0;
        for (c, gp) in cpu.iter().zip(&gpu) {
            match (c, gp) {
                (None, None) => {}
                (Some(c), Some(gp)) => {
                    surface += 1;
                    let (a, b) = (&c.prediction, &gp.prediction);
                    fields[0].push((a.bandwidth.angular, b.bandwidth.angular));
                    fields[1].push((a.variance, b.variance));
                    fields[2].push((a.variance_preconvolved, b.variance_preconvolved));
                    fields[3].push((a.radiance, b.radiance));
                    fields[4].push((c.brdf_max, gp.brdf_max));
                    fields[5].push((a.weight, b.weight));
                }
                _ => panic!("the CPU and the GPU disagree on which pixels are surfaces"),
            }
        }
        assert!(surface > w * h / 3, "{surface} surface pixels");
        let names = [
            "angular bandwidth",
            "variance sum",
            "pre-convolved variance sum",
            "radiance",
            "BRDF max bandwidth",
            "path weight Σλ",
        ];
        let stats: Vec<(f64, f64, f64)> = names
            .iter()
            .zip(&fields)
            .map(|(name, pairs)| {
                let scale = pairs.iter().map(|(c, _)| c.abs()).fold(0.0, f64::max);
                let (rms, worst, share) = compare(pairs, 1e-3 * scale, 1e-2);
                eprintln!(
                    "{name}: relative RMS {rms:.2e}, worst {worst:.2e}, {:.2} % of pixels off by > 1 %",
                    100.0 * share
                );
                (rms, worst, share)
            })
            .collect();
        for (name, (rms, _, share)) in names.iter().zip(stats) {
            // f32 against f64: a direction on a cell edge of the BRDF's bandwidth table or of the
            // map's bandwidth may land in the neighbouring cell; such pixels stay rare.
            assert!(
                share < 0.01,
                "{name}: {:.2} % of pixels off by > 1 %",
                100.0 * share
            );
            assert!(rms < 5e-3, "{name}: relative RMS {rms}");
        }
        // The buffers assembled from both agree on the level of nearly every pixel.
        let o = BufferOptions {
            scale: SampleRule::Constant,
            ..Default::default()
        };
        let a = BandwidthBuffer::assemble(&g, &cpu, o).expect("cpu buffer");
        let b = BandwidthBuffer::assemble(&g, &gpu, o).expect("gpu buffer");
        let differ = a.level.iter().zip(&b.level).filter(|(x, y)| x != y).count();
        eprintln!("levels differ on {differ} of {} pixels", w * h);
        assert!(differ * 100 < surface, "{differ} levels differ");
        // A textured area light above the line-up (a 2 × 2 checkerboard): its paths join the
        // prediction on both.
        let mut lit = shading;
        let tex: Vec<[f32; 3]> = (0..4)
            .map(|k| if k == 0 || k == 3 { [1.0; 3] } else { [0.2; 3] })
            .collect();
        lit.lights.push(
            lustre_adaptive::light::AreaLight::new(
                glam::DVec3::new(-1.5, 4.0, -1.0),
                glam::DVec3::X * 3.0,
                glam::DVec3::Z * 2.0,
                lustre_brdf::rgb::Rgb([40.0; 3]),
                Some((2, 2, tex)),
            )
            .expect("light"),
        );
        let cpu_lit = predict_pixels(&g, &lit, &env_bw, n_b, BrdfWeights::Evaluated).expect("cpu");
        let scene_lit =
            BandwidthScene::from_context(&gpu_ctx, &lit, &env_bw, None).expect("upload");
        let (gpu_lit, _) = pass
            .predict(&gpu_ctx, &scene_lit, &g, &lit, n_b as u32)
            .expect("gpu");
        let mut lit_fields: [Vec<(f64, f64)>; 3] = Default::default();
        let mut raised = 0;
        for ((c, gp), unlit) in cpu_lit.iter().zip(&gpu_lit).zip(&cpu) {
            if let (Some(c), Some(gp), Some(u)) = (c, gp, unlit) {
                lit_fields[0].push((
                    c.prediction.bandwidth.angular,
                    gp.prediction.bandwidth.angular,
                ));
                lit_fields[1].push((c.prediction.variance, gp.prediction.variance));
                lit_fields[2].push((c.prediction.radiance, gp.prediction.radiance));
                if c.prediction.radiance > 1.05 * u.prediction.radiance {
                    raised += 1;
                }
            }
        }
        eprintln!(
            "with the area light, {raised} of {surface} pixels receive more than 5 % more light"
        );
        assert!(
            raised * 4 > surface,
            "{raised} pixels lit by the area light"
        );
        for (name, pairs) in ["angular bandwidth", "variance sum", "radiance"]
            .iter()
            .zip(&lit_fields)
        {
            let scale = pairs.iter().map(|(c, _)| c.abs()).fold(0.0, f64::max);
            let (rms, worst, share) = compare(pairs, 1e-3 * scale, 1e-2);
            eprintln!(
                "with the area light, {name}: relative RMS {rms:.2e}, worst {worst:.2e}, {:.2} % of pixels off by > 1 %",
                100.0 * share
            );
            assert!(share < 0.01, "{name}: {:.2} % off by > 1 %", 100.0 * share);
            assert!(rms < 5e-3, "{name}: relative RMS {rms}");
        }
        // n_b = 1024 with the light: 2048 paths a pixel, taken over 16 dispatches
        // (DIRECTIONS_PER_DISPATCH; in one, lavapipe's loop limit dropped paths).
        let many = 1024;
        assert_eq!(2 * many, 16 * DIRECTIONS_PER_DISPATCH as usize);
        let cpu_many =
            predict_pixels(&g, &lit, &env_bw, many, BrdfWeights::Evaluated).expect("cpu");
        let (gpu_many, _) = pass
            .predict(&gpu_ctx, &scene_lit, &g, &lit, many as u32)
            .expect("gpu");
        let mut many_fields: [Vec<(f64, f64)>; 4] = Default::default();
        for (c, gp) in cpu_many.iter().zip(&gpu_many) {
            if let (Some(c), Some(gp)) = (c, gp) {
                let (a, b) = (&c.prediction, &gp.prediction);
                many_fields[0].push((a.bandwidth.angular, b.bandwidth.angular));
                many_fields[1].push((a.variance, b.variance));
                many_fields[2].push((a.radiance, b.radiance));
                many_fields[3].push((c.brdf_max, gp.brdf_max));
            }
        }
        for (name, pairs) in ["angular bandwidth", "variance sum", "radiance", "BRDF max"]
            .iter()
            .zip(&many_fields)
        {
            let scale = pairs.iter().map(|(c, _)| c.abs()).fold(0.0, f64::max);
            let (rms, worst, share) = compare(pairs, 1e-3 * scale, 1e-2);
            eprintln!(
                "n_b {many} with the area light, {name}: relative RMS {rms:.2e}, worst {worst:.2e}, {:.2} % of pixels off by > 1 %",
                100.0 * share
            );
            assert!(share < 0.01, "{name}: {:.2} % off by > 1 %", 100.0 * share);
            assert!(rms < 5e-3, "{name}: relative RMS {rms}");
        }
    })
}

#[test]
fn the_pass_names_bad_input() {
    let gpu_ctx = ctx();
    let map = lustre_env::EquirectMap::new(8, 4, vec![[1.0; 3]; 32]).expect("map");
    let net = lustre_brdf::measured::nbrdf::NbrdfSet::read(
        lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json"),
    )
    .expect("merl_nbrdf.json")
    .material("gold-paint")
    .expect("gold-paint");
    let bw = lustre_freq::brdf::brdf_bandwidth(
        &net,
        lustre_freq::brdf::BrdfBandwidthOptions {
            incident: 4,
            slice: 16,
            out: 4,
        },
    )
    .expect("bandwidth");
    match BandwidthScene::new(
        &gpu_ctx,
        &map,
        &[0.0; 31],
        &[(MeasuredBrdf::Nbrdf(&net), &bw)],
    ) {
        Err(e) => assert!(e.to_string().contains("31 values for a 8 × 4 map"), "{e}"),
        Ok(_) => panic!("31 bandwidth values for 32 texels were accepted"),
    }
    let scene = BandwidthScene::new(
        &gpu_ctx,
        &map,
        &[0.0; 32],
        &[(MeasuredBrdf::Nbrdf(&net), &bw)],
    )
    .expect("scene");
    let mut pass = BandwidthPass::new(&gpu_ctx).expect("pass");
    let px = BandwidthPixel {
        position: glam::DVec3::ZERO,
        frame: (glam::DVec3::X, glam::DVec3::Y, glam::DVec3::Z),
        wo: glam::DVec3::Z,
        depth: 1.0,
        curvature: 0.0,
        texture: 0.0,
        material: 1,
        uv: [0.5, 0.5],
    };
    let e = pass
        .run(&gpu_ctx, &scene, &[Some(px)], 16)
        .expect_err("material 1 of 1");
    assert!(e.to_string().contains("material 1 of 1"), "{e}");
    let e = pass.run(&gpu_ctx, &scene, &[None], 0).expect_err("n_b 0");
    assert!(e.to_string().contains("n_b"), "{e}");
    // A degenerate pixel (zero normal, NaN curvature) predicts zeros, not NaN.
    let bad = BandwidthPixel {
        frame: (glam::DVec3::ZERO, glam::DVec3::ZERO, glam::DVec3::ZERO),
        curvature: f64::NAN,
        material: 0,
        ..px
    };
    let (out, _) = pass
        .run(
            &gpu_ctx,
            &scene,
            &[Some(bad), Some(BandwidthPixel { material: 0, ..px })],
            16,
        )
        .expect("run");
    assert_eq!(out[0], Default::default());
    assert!(out[1].radiance > 0.0 && out[1].variance.is_finite());
}

#[test]
fn the_textures_bandwidth_reaches_the_gpu_pass_as_the_cpus() {
    // The line-up's pixels with a texture bandwidth of 0.5–12.5 cycles per metre each (set
    // here on measured materials, as `predict` would from `ShadingContext::texture_bandwidth`
    // for textured ones), against `lustre_freq::pixel::predict`.
    let scene = line_up::scene(
        [
            "nbrdf:color-changing-paint3",
            "nbrdf:red-metallic-paint",
            "nbrdf:gold-paint",
        ],
        "nbrdf:white-marble",
    );
    line_up::with_frame(&scene, (48, 32), |_, g, shading| {
        let env_bw = shading.environment_bandwidth().expect("env bandwidth");
        let n_b = 16;
        let gpu_ctx = ctx();
        let scene_gpu =
            BandwidthScene::from_context(&gpu_ctx, &shading, &env_bw, None).expect("upload");
        let mut pass = BandwidthPass::new(&gpu_ctx).expect("pass");
        let texture = |k: usize| 0.5 + 2.0 * (k % 7) as f64;
        let pixels: Vec<Option<BandwidthPixel>> = BandwidthPass::pixels(&g, &shading)
            .into_iter()
            .enumerate()
            .map(|(k, p)| {
                p.map(|p| BandwidthPixel {
                    texture: texture(k),
                    ..p
                })
            })
            .collect();
        let (gpu, _) = pass
            .run(&gpu_ctx, &scene_gpu, &pixels, n_b as u32)
            .expect("gpu");
        let (mut with, mut raised) = (vec![], 0);
        for (k, (p, gp)) in pixels.iter().zip(&gpu).enumerate() {
            let (Some(p), lustre_adaptive::gbuffer::GPixel::Surface(s)) = (p, &g.pixels[k]) else {
                continue;
            };
            let point = |texture: f64| lustre_freq::pixel::ShadingPoint {
                frame: p.frame,
                wo: p.wo,
                eye_distance: p.depth,
                curvature: p.curvature,
                texture,
            };
            let mut cpu = None;
            shading.scene.materials[s.material].with_bsdf(s.uv, &mut |b| {
                let tables = &shading.materials[s.material];
                let with = lustre_freq::pixel::predict(
                    &point(p.texture),
                    &env_bw,
                    b,
                    &tables.bandwidth,
                    n_b,
                );
                let without =
                    lustre_freq::pixel::predict(&point(0.0), &env_bw, b, &tables.bandwidth, n_b);
                cpu = Some((with.expect("cpu"), without.expect("cpu")));
            });
            let (c, plain) = cpu.expect("a BSDF");
            with.push((c.bandwidth.angular, f64::from(gp.bandwidth[1])));
            if c.bandwidth.angular > 1.05 * plain.bandwidth.angular {
                raised += 1;
            }
        }
        let scale = with.iter().map(|(c, _)| c.abs()).fold(0.0, f64::max);
        let (rms, worst, share) = compare(&with, 1e-3 * scale, 1e-2);
        eprintln!(
            "with textures, angular bandwidth at the eye: relative RMS {rms:.2e}, worst \
             {worst:.2e}, {:.2} % of {} pixels off by > 1 %; the texture raised it by > 5 % on \
             {raised}",
            100.0 * share,
            with.len()
        );
        assert!(raised * 2 > with.len(), "{raised} of {} raised", with.len());
        assert!(share < 0.01 && rms < 5e-3, "rms {rms}, {share}");
    })
}

#[test]
fn analytic_specs_in_the_bandwidth_pass_match_the_cpu() {
    // Analytic models that need no side table (their scene uploads an empty BRDF table, which
    // the pass must still bind), against `predict_pixels`.
    let scene = line_up::scene(
        [
            "lambert(kd=0.5)",
            "ward(kd=0.1, ks=0.4, ax=0.15)",
            "phong(kd=0.2, ks=0.5, n=10)",
        ],
        "oren-nayar(kd=0.6, sigma=0.5)",
    );
    line_up::with_frame(&scene, (48, 32), |_, g, shading| {
        let env_bw = shading.environment_bandwidth().expect("env bandwidth");
        let n_b = 16;
        let cpu = predict_pixels(&g, &shading, &env_bw, n_b, BrdfWeights::Evaluated).expect("cpu");
        let gpu_ctx = ctx();
        let scene_gpu = BandwidthScene::from_context(&gpu_ctx, &shading, &env_bw, Some(&scene))
            .expect("upload");
        let mut pass = BandwidthPass::new(&gpu_ctx).expect("pass");
        let (gpu, _) = pass
            .predict(&gpu_ctx, &scene_gpu, &g, &shading, n_b as u32)
            .expect("an empty BRDF table is bound");
        let mut fields: [Vec<(f64, f64)>; 3] = Default::default();
        for (c, gp) in cpu.iter().zip(&gpu) {
            if let (Some(c), Some(gp)) = (c, gp) {
                let (a, b) = (&c.prediction, &gp.prediction);
                fields[0].push((a.bandwidth.angular, b.bandwidth.angular));
                fields[1].push((a.variance, b.variance));
                fields[2].push((a.radiance, b.radiance));
            }
        }
        for (name, pairs) in ["angular bandwidth", "variance sum", "radiance"]
            .iter()
            .zip(&fields)
        {
            let scale = pairs.iter().map(|(c, _)| c.abs()).fold(0.0, f64::max);
            let (rms, worst, share) = compare(pairs, 1e-3 * scale, 1e-2);
            eprintln!(
                "analytic specs, {name}: relative RMS {rms:.2e}, worst {worst:.2e}, {:.2} % of \
                 {} pixels off by > 1 %",
                100.0 * share,
                pairs.len()
            );
            assert!(share < 0.01 && rms < 5e-3, "{name}: rms {rms}, {share}");
        }
    })
}
