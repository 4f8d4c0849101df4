//! Timing of one SGD fit, one `metrics::evaluate` and Kurt fits with 1 and 3 lobes on an NBRDF
//! material (the fitting goal: an SGD fit ≤ 1 s wall with 2 threads; the times are wall times of
//! the whole fit on `RAYON_NUM_THREADS` threads, the default being all cores).

use criterion::{criterion_group, criterion_main, Criterion};
use lustre_fit::ct::{fit, CtDistribution, CtOptions};
use lustre_fit::kurt::{self, KurtOptions};
use lustre_fit::metrics::evaluate;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let data = match lustre_fit::data::load("nbrdf:gold-metallic-paint") {
        Ok(d) => d,
        Err(e) => {
            eprintln!("skipping the fit benchmarks: {e}");
            return;
        }
    };
    let d = data.bsdf.as_ref();
    let mut g = c.benchmark_group("ct");
    g.sample_size(10);
    g.bench_function("sgd_fit", |b| {
        b.iter(|| fit(black_box(d), CtDistribution::Sgd, &CtOptions::default()))
    });
    let Ok(model) = lustre_brdf::fits::sgd::load("gold-metallic-paint") else {
        return;
    };
    g.bench_function("evaluate", |b| {
        b.iter(|| evaluate(black_box(d), black_box(&model), false))
    });
    g.finish();
    let mut g = c.benchmark_group("kurt");
    g.sample_size(10);
    for lobes in [1, 3] {
        let opts = KurtOptions {
            lobes,
            ..KurtOptions::default()
        };
        g.bench_function(format!("fit_{lobes}_lobes"), |b| {
            b.iter(|| kurt::fit(black_box(d), false, &opts))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
