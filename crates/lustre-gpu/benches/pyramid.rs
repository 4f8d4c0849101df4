//! Cube-map pyramid builds on the adapter (lavapipe here) against the CPU (`CubePyramid::build`,
//! rayon over all cores): Gauss 6×6, all levels down to 1×1, from bases of 256², 512² and 1024²
//! faces (002 Table 1: 5.97 ms for 1024² on a Quadro 6000). The GPU time includes the upload of
//! the base and the small per-level tables, and ends when the queue is idle; no readback.
//!
//! `cargo bench -p lustre-gpu --bench pyramid -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lustre_env::{CubeMap, CubePyramid, MipFilter};
use lustre_gpu::{GpuContext, GpuPyramidBuilder};

/// A sky with a small bright sun (the map the pyramid is for: a high dynamic range).
fn base(n: usize) -> CubeMap {
    let sun = glam::DVec3::new(0.3, 0.8, -0.5).normalize();
    CubeMap::from_fn(n, |d| {
        let d = d.normalize();
        let s = if d.dot(sun) > 0.9995 { 5000.0 } else { 0.0 };
        [0.3 + s, 0.5 + s, 0.9 * (0.5 + 0.5 * d.y) + s]
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

fn pyramid(c: &mut Criterion) {
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let builder = GpuPyramidBuilder::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let mut g = c.benchmark_group("pyramid_gauss6");
    g.sample_size(10);
    for n in [256, 512, 1024] {
        let b = base(n);
        g.bench_with_input(BenchmarkId::new("gpu", n), &b, |bench, b| {
            bench.iter(|| {
                builder
                    .build(&ctx, b, MipFilter::Gauss6)
                    .unwrap_or_else(|e| panic!("{e}"))
            })
        });
        g.bench_with_input(BenchmarkId::new("cpu", n), &b, |bench, b| {
            bench.iter(|| {
                CubePyramid::build(b.clone(), MipFilter::Gauss6).unwrap_or_else(|e| panic!("{e}"))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, pyramid);
criterion_main!(benches);
