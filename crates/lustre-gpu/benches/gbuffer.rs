//! The light-mapped frame of the Modern Hall (glTF, its own camera): the raster G-buffer plus the
//! light-map shading on the adapter (lavapipe here; both passes submitted, ends when the queue
//! is idle, no readback; k = 1, one sample per pixel at its centre) against the CPU
//! (`render_lightmapped`, 1 jittered ray per pixel, rayon over all cores), at 640×360 and
//! 1680×1050 (000 Tables 4.1–4.2's size). `render_lightmapped` builds its BVH and light-map
//! tables per call; `cpu_prebuilt` is the same frame at pixel centres with them built once
//! (`trace_gbuffer` + `shade_gbuffer`), the CPU's per-frame cost. The light maps: a quick bake at 4 texels/m (the maps'
//! content does not change either time).
//!
//! `cargo bench -p lustre-gpu --bench gbuffer -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lustre_gpu::{GBufferTarget, GpuContext, LightmapFrameScene, LightmapRenderer, ShadeTarget};
use lustre_scene::lightmap::{build_atlas, AtlasOptions};
use lustre_scene::Scene;
use lustre_trace::bake::diffuse_path_scene;
use lustre_trace::bake::gbuffer::{shade_gbuffer, trace_gbuffer};
use lustre_trace::bake::render::{render_lightmapped, Lightmapped};
use lustre_trace::bake::{assemble, bake_tiles, BakeOptions, Denoiser};
use lustre_trace::path_tracer::PathTracer;
use lustre_trace::reference::path_camera;

fn fail<T, E: std::fmt::Display>(r: Result<T, E>) -> T {
    r.unwrap_or_else(|e| panic!("{e}"))
}

fn frame(c: &mut Criterion) {
    let path = lustre_env::shared_data_dir().join("scenes/modern_hall/gltf/staircase2.gltf");
    let mut scene = fail(Scene::load(&path));
    let (atlas, _) = fail(build_atlas(
        &mut scene,
        &AtlasOptions {
            texels_per_metre: 4.0,
            ..AtlasOptions::default()
        },
    ));
    let opts = BakeOptions {
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
        &opts,
        dir.path(),
        None,
        &|_, _| {},
    ));
    let pages = fail(assemble(&scene, &atlas, &opts, dir.path())).pages;
    let ctx = fail(GpuContext::new());
    let renderer = fail(LightmapRenderer::new(&ctx));
    let up = fail(LightmapFrameScene::upload(&ctx, &scene, &atlas, &pages));
    let (ps, bases, _) = fail(diffuse_path_scene(&scene));
    let lit = fail(Lightmapped::new(
        &scene,
        &atlas,
        &pages,
        &ps.geometry,
        bases,
    ));
    let pt = fail(PathTracer::new(&ps, Default::default()));
    let mut g = c.benchmark_group("lightmapped_frame_modern_hall");
    g.sample_size(10);
    for (w, h) in [(640u32, 360u32), (1680, 1050)] {
        let cam = fail(path_camera(&scene, None, w, h));
        let target = fail(GBufferTarget::new(&ctx, w, h));
        let out = fail(ShadeTarget::new(&ctx, w, h));
        let size = format!("{w}x{h}");
        g.bench_with_input(BenchmarkId::new("gpu", &size), &(), |b, _| {
            b.iter(|| fail(renderer.draw(&ctx, &up, &cam, 1, &target, &out)))
        });
        g.bench_with_input(BenchmarkId::new("gpu_gbuffer_only", &size), &(), |b, _| {
            b.iter(|| {
                fail(renderer.gbuffer.draw(&ctx, &up.geometry, &cam, &target));
                fail(ctx.wait())
            })
        });
        g.bench_with_input(BenchmarkId::new("cpu_1spp", &size), &(), |b, _| {
            b.iter(|| {
                fail(render_lightmapped(
                    &scene, &atlas, &pages, &cam, w as usize, h as usize, 1, 1,
                ))
            })
        });
        g.bench_with_input(BenchmarkId::new("cpu_prebuilt", &size), &(), |b, _| {
            b.iter(|| {
                let gb = fail(trace_gbuffer(
                    &pt,
                    &ps.geometry,
                    &cam,
                    w as usize,
                    h as usize,
                ));
                fail(shade_gbuffer(
                    &lit,
                    &ps.geometry,
                    ps.environment.as_ref(),
                    &cam,
                    &gb,
                    1,
                ))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, frame);
criterion_main!(benches);
