//! Adaptive shading's stages on a gold-paint sphere (its neural BRDF) under royal_esplanade_1k,
//! 128² pixels, rayon on every core: the CPU bandwidth pass with ρ from the sampling tables
//! (the default) and evaluated, the hierarchical shading of a frame at rate 1 with N_p = 64,
//! and brute force at 16 samples per pixel. `cargo bench -p lustre-adaptive --bench adaptive`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lustre_adaptive::buffer::{BandwidthBuffer, BrdfWeights, BufferOptions, SampleRule};
use lustre_adaptive::gbuffer::GBuffer;
use lustre_adaptive::hierarchy::{render_adaptive, render_brute};
use lustre_adaptive::shading::{Lighting, ShadingContext, ShadingOptions};
use lustre_trace::baked::read_environment;
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{film_camera, path_scene};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let size = 128;
    let map = lustre_env::shared_data_dir().join("envmaps/royal_esplanade_1k.hdr");
    let env = read_environment(&map).expect("royal_esplanade_1k").0;
    let scene = lustre_scene::builtin::preview("nbrdf:gold-paint", Some(env)).expect("scene");
    let (ps, _) = path_scene(&scene).expect("path scene");
    let tracer = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let cam = film_camera(&scene.cameras[0], size as u32, size as u32).expect("camera");
    let g = GBuffer::render(&tracer, &ps, &cam, size, size).expect("G-buffer");
    let ctx = ShadingContext::new(&ps, ShadingOptions::default(), &|_, _| {}).expect("tables");
    let env_bw = ctx.environment_bandwidth().expect("environment bandwidth");
    let options = |weights| BufferOptions {
        mean_samples: 64.0,
        scale: SampleRule::Constant,
        rate: 1.0,
        weights,
        ..Default::default()
    };
    let mut grp = c.benchmark_group("adaptive_gold_paint_128");
    grp.sample_size(10);
    grp.throughput(Throughput::Elements(g.surface_pixels() as u64));
    for (name, w) in [
        ("bandwidth_pass_tabulated", BrdfWeights::Tabulated),
        ("bandwidth_pass_evaluated", BrdfWeights::Evaluated),
    ] {
        grp.bench_function(name, |b| {
            b.iter(|| {
                black_box(BandwidthBuffer::build(&g, &ctx, &env_bw, options(w)).expect("buffer"))
            })
        });
    }
    let buffer =
        BandwidthBuffer::build(&g, &ctx, &env_bw, options(BrdfWeights::Tabulated)).expect("buffer");
    grp.bench_function("hierarchical_shading_rate1_np64", |b| {
        b.iter(|| {
            black_box(render_adaptive(&g, &ctx, &buffer, Lighting::Direct, 7).expect("frame"))
        })
    });
    grp.bench_function("brute_16", |b| {
        b.iter(|| black_box(render_brute(&g, &ctx, 16, 7).expect("brute")))
    });
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
