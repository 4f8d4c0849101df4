//! The view-dependent pass of the walkthrough frame (`frame_shade.wgsl`) on the adapter at
//! 1680×1050 (000 Tables 4.1–4.2's size), k = 1, for n = 3, 8 and 19 samples per pixel, regular
//! method: the built-in room (its gold sphere as a rough gold conductor, light maps baked small
//! and fast, probes captured on the CPU at 64², the floor's mirror buffer and the frosted
//! glass's see-through buffer rendered on the CPU at 840×525 and uploaded). One iteration = the
//! pass submitted and waited for (no readback), over a G-buffer and light-mapped image made
//! once. The glossy share of the screen is printed before the measurement.
//!
//! `cargo bench -p lustre-gpu --bench frame_shade -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lustre_brdf::rgb::Rgb;
use lustre_gpu::{
    FrameShadePass, FrameShadeScene, FrameShadeTarget, GBufferTarget, GpuContext,
    LightmapFrameScene, LightmapRenderer, ShadeTarget,
};
use lustre_scene::lightmap::{build_atlas, AtlasOptions};
use lustre_scene::material::{MicrofacetType, TexturedRgb, TexturedScalar};
use lustre_scene::{Material, MaterialKind};
use lustre_shade::frame::{FrameBuffers, FrameLight};
use lustre_shade::probe::{capture_probe, LitScene, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{assemble, bake_tiles, base_albedo, BakeOptions, BaseAlbedo, Denoiser};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};

fn fail<T, E: std::fmt::Display>(r: Result<T, E>) -> T {
    r.unwrap_or_else(|e| panic!("{e}"))
}

fn frame(c: &mut Criterion) {
    let mut scene = fail(lustre_scene::builtin::room());
    for m in &mut scene.materials {
        if let MaterialKind::Spec(_) = m.kind {
            *m = Material::new(
                m.name.clone(),
                MaterialKind::RoughConductor {
                    eta: Rgb::new(0.143, 0.374, 1.442),
                    k: Rgb::new(3.983, 2.385, 1.603),
                    specular: TexturedRgb::constant(Rgb::ONE),
                    alpha_u: TexturedScalar::constant(0.15),
                    alpha_v: TexturedScalar::constant(0.15),
                    distribution: MicrofacetType::Ggx,
                },
            );
        }
    }
    let (atlas, _) = fail(build_atlas(
        &mut scene,
        &AtlasOptions {
            texels_per_metre: 4.0,
            ..AtlasOptions::default()
        },
    ));
    let bake = BakeOptions {
        spp: 1,
        bounces: 2,
        seed: 5,
        denoiser: Denoiser::None,
        ..BakeOptions::default()
    };
    let dir = fail(tempfile::tempdir());
    fail(bake_tiles(
        &scene,
        &atlas,
        &bake,
        dir.path(),
        None,
        &|_, _| {},
    ));
    let pages = fail(assemble(&scene, &atlas, &bake, dir.path())).pages;
    let (ps, _) = fail(path_scene(&scene));
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = fail(Lightmapped::new(
        &scene,
        &atlas,
        &pages,
        &ps.geometry,
        bases,
    ));
    let pt = fail(PathTracer::new(&ps, PathOptions::default()));
    let lit = fail(LitScene::new(&scene, &ps, &pt, &lm));
    let popts = ProbeOptions {
        face_size: 64,
        supersample: 1,
        plane_rays: 32,
    };
    let probes: Vec<_> = (0..scene.meshes.len())
        .filter(|&m| scene.meshes[m].hints.probe)
        .map(|m| fail(capture_probe(&lit, m, &popts)))
        .collect();
    let light = FrameLight {
        probes: &probes,
        environment: None,
    };
    let (w, h) = (1680u32, 1050u32);
    let camera = fail(path_camera(&scene, None, w, h));
    let ctx = fail(GpuContext::new());
    let renderer = fail(LightmapRenderer::new(&ctx));
    let up = fail(LightmapFrameScene::upload(&ctx, &scene, &atlas, &pages));
    let target = fail(GBufferTarget::new(&ctx, w, h));
    let base = fail(ShadeTarget::new(&ctx, w, h));
    fail(renderer.draw(&ctx, &up, &camera, 1, &target, &base));
    let buffers = fail(FrameBuffers::render(&lit, &light, &camera, 840, 525));
    let gpu_scene = fail(FrameShadeScene::upload(&ctx, &lit, &light, &buffers));
    let pass = fail(FrameShadePass::new(&ctx));
    let out = fail(FrameShadeTarget::new(&ctx, w, h, 1));
    let mut g = c.benchmark_group(format!("frame_shade {w}x{h} ({})", ctx.describe()));
    g.sample_size(10);
    for n in [3u32, 8, 19] {
        let opts = FrameRequest {
            method: Method::Regular,
            samples: n,
            rays: 1,
            frames: 1,
            seed: 1,
        };
        fail(pass.shade(
            &ctx,
            &gpu_scene,
            &target,
            &base,
            &camera,
            1,
            (&opts, 0),
            &out,
        ));
        fail(ctx.wait());
        let stats = fail(out.stats(&ctx));
        eprintln!(
            "n = {n}: {} of {} pixels view-dependent ({:.0} %), {} lookups",
            stats.glossy_hits,
            w * h,
            100.0 * stats.glossy_hits as f64 / f64::from(w * h),
            stats.lookups
        );
        g.bench_with_input(BenchmarkId::new("regular", n), &n, |b, _| {
            b.iter(|| {
                fail(pass.shade(
                    &ctx,
                    &gpu_scene,
                    &target,
                    &base,
                    &camera,
                    1,
                    (&opts, 0),
                    &out,
                ));
                fail(ctx.wait());
            })
        });
    }
    g.finish();
}

criterion_group!(benches, frame);
criterion_main!(benches);
