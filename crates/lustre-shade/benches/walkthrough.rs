//! The CPU walkthrough frame (`lustre_shade::frame`) on the built-in room, 320×180, one camera
//! ray per pixel, 2 rayon threads as on the development machine: regular sampling at 3, 8 and
//! 19 samples and Colbert–Křivánek at 19, each frame with its mirror and see-through passes;
//! and one probe capture (64² faces, 2×2 rays per texel, Gaussian pyramid, planes). The light
//! maps come from a small bake in the set-up (8 texels/m, 8 paths per texel): their quality does
//! not change the frame's cost. `cargo bench -p lustre-shade --bench walkthrough -- --noplot`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lustre_scene::lightmap::{build_atlas, AtlasOptions};
use lustre_shade::frame::{render_frame, FrameLight};
use lustre_shade::probe::{capture_probe, LitScene, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{assemble, bake_tiles, base_albedo, BakeOptions, BaseAlbedo, Transport};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("pool");
    let mut scene = lustre_scene::builtin::room().expect("built-in room");
    let aopts = AtlasOptions {
        texels_per_metre: 8.0,
        ..AtlasOptions::default()
    };
    let (atlas, _) = build_atlas(&mut scene, &aopts).expect("atlas");
    let dir = tempfile::tempdir().expect("tempdir");
    let opts = BakeOptions {
        spp: 8,
        bounces: 3,
        transport: Transport::Full,
        ..BakeOptions::default()
    };
    bake_tiles(&scene, &atlas, &opts, dir.path(), None, &|_, _| {}).expect("bake");
    let pages = assemble(&scene, &atlas, &opts, dir.path())
        .expect("assemble")
        .pages;
    let (ps, _) = path_scene(&scene).expect("path scene");
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = Lightmapped::new(&scene, &atlas, &pages, &ps.geometry, bases).expect("light maps");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(&scene, &ps, &pt, &lm).expect("lit scene");
    let popts = ProbeOptions {
        face_size: 64,
        ..ProbeOptions::default()
    };
    let probe_meshes: Vec<usize> = (0..scene.meshes.len())
        .filter(|&m| scene.meshes[m].hints.probe)
        .collect();
    let probes: Vec<_> = probe_meshes
        .iter()
        .map(|&m| capture_probe(&lit, m, &popts).expect("probe"))
        .collect();
    let (w, h) = (320usize, 180usize);
    let cam = path_camera(&scene, None, w as u32, h as u32).expect("camera");
    let light = FrameLight {
        probes: &probes,
        environment: None,
    };
    let mut g = c.benchmark_group("walkthrough");
    g.sample_size(10);
    g.throughput(Throughput::Elements((w * h) as u64));
    for (name, method, n) in [
        ("regular-3", (Method::Regular, 1), 3),
        ("regular-8", (Method::Regular, 1), 8),
        ("regular-19", (Method::Regular, 1), 19),
        ("ck-19", (Method::Ck, 1), 19),
    ] {
        let fopts = FrameRequest {
            method: method.0,
            samples: n,
            rays: 1,
            frames: method.1,
            seed: 1,
        };
        g.bench_function(name, |b| {
            b.iter(|| pool.install(|| black_box(render_frame(&lit, &light, &cam, w, h, &fopts))))
        });
    }
    g.throughput(Throughput::Elements(1));
    g.bench_function("probe-capture-64", |b| {
        b.iter(|| pool.install(|| black_box(capture_probe(&lit, probe_meshes[0], &popts))))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
