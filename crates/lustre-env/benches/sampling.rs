//! Importance sampling of a real map: 4,096 directions drawn from royal_esplanade_1k's sampler
//! (`EnvSampler::sample`, the shading estimators' environment samples), their densities, and
//! the light with the density at a direction (the estimator's per-sample reads).
//! `cargo bench -p lustre-env --bench sampling -- --noplot`

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use lustre_env::equirect::direction_uv;
use lustre_env::{read_map, shared_data_dir, EnvSampler};
use std::hint::black_box;

fn sampling(c: &mut Criterion) {
    let path = shared_data_dir().join("envmaps/royal_esplanade_1k.hdr");
    let map = read_map(&path).expect("royal_esplanade_1k.hdr").map;
    let sampler = EnvSampler::new(&map).expect("sampler");
    let n = 4096u32;
    // A Hammersley set: the points the estimators draw.
    let points: Vec<(f64, f64)> = (0..n)
        .map(|k| {
            (
                (k as f64 + 0.5) / n as f64,
                k.reverse_bits() as f64 / 2f64.powi(32),
            )
        })
        .collect();
    let mut g = c.benchmark_group("env_sampling_royal_esplanade_1k");
    g.throughput(Throughput::Elements(n as u64));
    g.bench_function("sample", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u1, u2) in &points {
                acc += sampler.sample(black_box(u1), black_box(u2)).pdf;
            }
            acc
        })
    });
    let dirs: Vec<_> = points
        .iter()
        .map(|&(u1, u2)| sampler.sample(u1, u2).dir)
        .collect();
    g.bench_function("pdf", |b| {
        b.iter(|| dirs.iter().map(|&d| sampler.pdf(black_box(d))).sum::<f64>())
    });
    // What a shading sample reads at its direction: the light and the sampler's density, with
    // the map coordinates found twice (two calls) or once (`pdf_uv`).
    g.bench_function("light_then_pdf", |b| {
        b.iter(|| {
            dirs.iter()
                .map(|&d| {
                    let d = black_box(d);
                    map.lookup_bilinear(d)[0] + sampler.pdf(d)
                })
                .sum::<f64>()
        })
    });
    g.bench_function("light_and_pdf_one_uv", |b| {
        b.iter(|| {
            dirs.iter()
                .map(|&d| {
                    let (u, v) = direction_uv(black_box(d));
                    map.bilinear_uv(u, v)[0] + sampler.pdf_uv(u, v)
                })
                .sum::<f64>()
        })
    });
    g.finish();
}

criterion_group!(benches, sampling);
criterion_main!(benches);
