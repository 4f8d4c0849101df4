//! Pyramid build times for 256² / 512² / 1024² faces × each filter (002 Table 1 measures the
//! same on a GPU: 0.18–5.97 ms). Run one group quickly with
//! `cargo bench -p lustre-env --bench pyramid -- --quick 256`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use lustre_env::{CubeMap, CubePyramid, MipFilter};
use std::hint::black_box;

fn pyramid(c: &mut Criterion) {
    let mut g = c.benchmark_group("pyramid");
    g.sample_size(10);
    for size in [256usize, 512, 1024] {
        let base = CubeMap::from_fn(size, |d| [1.0 + d.x, 1.0 + d.y * d.y, 2.0 + d.z]).unwrap();
        for filter in [MipFilter::Box2, MipFilter::Gauss4, MipFilter::Gauss6] {
            g.bench_with_input(
                BenchmarkId::new(format!("{filter:?}"), size),
                &base,
                |b, base| b.iter(|| CubePyramid::build(black_box(base.clone()), filter).unwrap()),
            );
        }
    }
    g.finish();
}

criterion_group!(benches, pyramid);
criterion_main!(benches);
