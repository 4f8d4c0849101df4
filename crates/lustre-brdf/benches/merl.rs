//! MERL synthesis: one full 90×90×180 table from a neural BRDF (1,458,000 network evaluations,
//! rayon over all cores), single lookups in a table, and tabulated-CDF importance sampling
//! (004 §IV.4.3): building the tables of a MERL table and of its neural BRDF (32 view bins ×
//! 64 × 64 cells, 2² points per cell, rayon over the view bins), one sample and one pdf.
//!
//! Run: `cargo bench -p lustre-brdf --bench merl`.

use criterion::{criterion_group, criterion_main, Criterion};
use lustre_brdf::measured::merl::MerlTable;
use lustre_brdf::measured::nbrdf::{synthesize_merl, NbrdfSet};
use lustre_brdf::tabulated::{Tabulated, TabulatedOptions};
use lustre_brdf::{Bsdf, DVec3};
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
    let o = TabulatedOptions::default();
    g.bench_function("tabulate the MERL table (32 × 64 × 64 cells)", |b| {
        b.iter(|| Tabulated::new(black_box(&table), o).expect("tabulate"))
    });
    g.bench_function("tabulate the neural BRDF (32 × 64 × 64 cells)", |b| {
        b.iter(|| Tabulated::new(black_box(&net), o).expect("tabulate"))
    });
    let t = Tabulated::new(&table, o).expect("tabulate");
    let wo = DVec3::new(0.5, 0.2, 0.84).normalize();
    g.bench_function("tabulated sample", |b| {
        b.iter(|| t.sample(black_box(wo), black_box(0.37), black_box(0.71)))
    });
    let wi = DVec3::new(-0.4, -0.1, 0.91).normalize();
    g.bench_function("tabulated pdf", |b| {
        b.iter(|| t.pdf(black_box(wi), black_box(wo)))
    });
    g.finish();
}

criterion_group!(benches, bench_merl);
criterion_main!(benches);
