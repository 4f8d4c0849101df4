//! Per-call cost of `eval` (RGB) and `sample` for every model and measured format.
//!
//! Run: `cargo bench -p lustre-brdf --bench bsdf`. Each benchmark walks a fixed pool of 1024
//! direction pairs (seeded), so the reported time per element is the time of one RGB call.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use lustre_brdf::catalog;
use lustre_brdf::sampling::{cosine_hemisphere, SplitMix64};
use lustre_brdf::DVec3;
use std::hint::black_box;

/// The materials measured: analytic models by spec, published fits, measured tables.
const SPECS: &[&str] = &[
    "lambert(kd=0.5)",
    "oren-nayar(kd=0.5, sigma=0.3)",
    "phong(kd=0.2, ks=0.5, n=50)",
    "blinn-phong(kd=0.2, ks=0.5, n=50)",
    "ward(kd=0.2, ks=0.2, ax=0.1, ay=0.2)",
    "ward-duer(kd=0.2, ks=0.2, ax=0.1, ay=0.2)",
    "ward-gmd(kd=0.2, ks=0.2, ax=0.1, ay=0.2)",
    "ashikhmin-shirley(rd=0.3, rs=0.4, nu=100, nv=500)",
    "kurt(kd=0.1, ks=0.8, mx=0.1, my=0.2, r0=0.9, alpha=0.2)",
    "kurt-demo",
    "beckmann(rho_d=0.1, rho_s=0.5, alpha=0.1, f0=0.9)",
    "ggx(rho_d=0.1, rho_s=0.5, alpha=0.1, f0=0.9)",
    "sgd:gold-metallic-paint",
    "sgd-numeric:gold-metallic-paint",
    "abc:gold-metallic-paint",
    "lafortune:gold-metallic-paint",
    "nbrdf:gold-metallic-paint",
    "conductor(material=Au)",
    "roughconductor(material=Au, alpha=0.1, distribution=ggx)",
    "roughconductor(material=Cu, alpha_u=0.05, alpha_v=0.3, distribution=beckmann)",
    "dielectric(int_ior=1.5, ext_ior=1)",
    "roughdielectric(int_ior=1.5, ext_ior=1, alpha=0.1, distribution=ggx)",
    "roughdielectric(int_ior=1.5, ext_ior=1, alpha=0.1, distribution=beckmann)",
    "thindielectric(int_ior=1.5, ext_ior=1)",
    "plastic(diffuse=0.5, int_ior=1.5, ext_ior=1)",
    "roughplastic(diffuse=0.5, alpha=0.1, distribution=ggx, int_ior=1.5, ext_ior=1, nonlinear=1)",
    "pbr(base_color=0.8, metallic=0.5, roughness=0.4)",
    "twosided:roughconductor(material=Al, alpha=0.1, distribution=ggx)",
];

fn pairs(n: usize) -> Vec<(DVec3, DVec3)> {
    let mut rng = SplitMix64::new(7);
    (0..n)
        .map(|_| {
            let wi = cosine_hemisphere(rng.next_f64(), rng.next_f64());
            let wo = cosine_hemisphere(rng.next_f64(), rng.next_f64());
            (wi, wo)
        })
        .collect()
}

fn bench_models(c: &mut Criterion) {
    let pool = pairs(1024);
    let mut eval = c.benchmark_group("eval");
    eval.throughput(Throughput::Elements(pool.len() as u64));
    let mut materials = Vec::new();
    for spec in SPECS {
        match catalog::resolve(spec) {
            Ok(b) => materials.push((spec.to_string(), b)),
            Err(e) => eprintln!("skipping {spec}: {e}"),
        }
    }
    let rgl = lustre_brdf::shared_data_dir().join("measured/rgl/paper_white_rgb.bsdf");
    if let Ok(b) = catalog::resolve(&rgl.to_string_lossy()) {
        materials.push(("rgl:paper_white".to_string(), b));
    }
    for (name, b) in &materials {
        eval.bench_with_input(BenchmarkId::from_parameter(name), b, |bch, b| {
            bch.iter(|| {
                let mut acc = 0.0;
                for (wi, wo) in &pool {
                    acc += b.eval(black_box(*wi), black_box(*wo))[0];
                }
                acc
            })
        });
    }
    eval.finish();
    let mut sample = c.benchmark_group("sample");
    sample.throughput(Throughput::Elements(pool.len() as u64));
    let mut rng = SplitMix64::new(11);
    let us: Vec<(f64, f64)> = (0..pool.len())
        .map(|_| (rng.next_f64(), rng.next_f64()))
        .collect();
    for (name, b) in &materials {
        sample.bench_with_input(BenchmarkId::from_parameter(name), b, |bch, b| {
            bch.iter(|| {
                let mut acc = 0.0;
                for ((_, wo), (u1, u2)) in pool.iter().zip(&us) {
                    if let Some(s) = b.sample(black_box(*wo), *u1, *u2) {
                        acc += s.pdf;
                    }
                }
                acc
            })
        });
    }
    sample.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = bench_models
}
criterion_main!(benches);
