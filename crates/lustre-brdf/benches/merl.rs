//! MERL synthesis: one full 90×90×180 table from a neural BRDF (1,458,000 network evaluations,
//! rayon over all cores), and single lookups in a table.
//!
//! Run: `cargo bench -p lustre-brdf --bench merl`.

use criterion::{criterion_group, criterion_main, Criterion};
use lustre_brdf::measured::merl::MerlTable;
use lustre_brdf::measured::nbrdf::{synthesize_merl, NbrdfSet};
use std::hint::black_box;

fn bench_merl(c: &mut Criterion) {
    let path = lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json");
    let set = NbrdfSet::read(&path).expect("the MERL NBRDF set in ../shared/data");
    let net = set
        .material("gold-metallic-paint")
        .expect("gold-metallic-paint");
    let mut g = c.benchmark_group("merl");
    g.sample_size(10);
    g.bench_function("synth gold-metallic-paint (1.458M bins)", |b| {
        b.iter(|| synthesize_merl(black_box(&net), |_| {}))
    });
    let table: MerlTable = synthesize_merl(&net, |_| {});
    g.bench_function("lookup trilinear", |b| {
        b.iter(|| table.lookup_trilinear(black_box(0.1), black_box(0.7), black_box(1.3)))
    });
    g.bench_function("lookup nearest", |b| {
        b.iter(|| table.lookup_nearest(black_box(0.1), black_box(0.7), black_box(1.3)))
    });
    g.finish();
}

criterion_group!(benches, bench_merl);
criterion_main!(benches);
