//! CPU shading throughput: `shade_regular` at budgets 14/17/30 per lobe with 002's printed
//! patterns (`shade_regular`) and with ours, the row lattice (`shade_lattice`), the lattice with
//! two suns split off (`shade_lattice_sun`: the same budget, two of it sun evaluations), `shade_ck`, and
//! the reference per sample. Each iteration shades 64 pixel configurations (throughput in elements
//! = calls, or samples for the reference).

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::DVec3;
use lustre_brdf::models::kurt::{Kurt, KurtLobe};
use lustre_brdf::rgb::Rgb;
use lustre_env::{irradiance_map, CubeMap, CubePyramid, MipFilter, Sun};
use lustre_shade::integrator::{
    plan_lattice, plan_lattice_sun, plan_regular, plan_tap_lattice, shade_ck, shade_reference,
    shade_regular, FilteredEnvironment, Weighting,
};
use lustre_trace::sampling::ShadingFrame;
use std::hint::black_box;

const PIXELS: usize = 64;

fn setup() -> (CubePyramid, CubeMap, Kurt, Vec<(ShadingFrame, DVec3)>) {
    let base = CubeMap::from_fn(128, |d| {
        let s = (8.0 * d.x).sin() * (5.0 * d.z).cos();
        [1.0 + 0.5 * s, 1.0 + 0.3 * d.y, 0.8 + 0.2 * d.z]
    })
    .expect("cube map");
    let pyramid = CubePyramid::build(base, MipFilter::Gauss6).expect("pyramid");
    let irradiance = irradiance_map(&pyramid, 16).expect("irradiance");
    let lobe = KurtLobe::new(Rgb::new(0.8, 0.7, 0.6), 0.12, 0.25, 0.9, 0.0).expect("lobe");
    let kurt = Kurt::new(Rgb::splat(0.1), vec![lobe], vec![]).expect("material");
    let pixels = (0..PIXELS)
        .map(|i| {
            let a = i as f64 * 0.7;
            let n = DVec3::new(a.sin(), 1.0, a.cos() * 0.5).normalize();
            let f = ShadingFrame::new(n, DVec3::X);
            let th = 0.1 + 1.2 * (i as f64 / PIXELS as f64);
            let wo = f.to_world(DVec3::new(th.sin() * a.cos(), th.sin() * a.sin(), th.cos()));
            (f, wo)
        })
        .collect();
    (pyramid, irradiance, kurt, pixels)
}

fn bench(c: &mut Criterion) {
    let (pyramid, irradiance, kurt, pixels) = setup();
    let env = FilteredEnvironment {
        pyramid: &pyramid,
        irradiance: &irradiance,
    };
    let mut g = c.benchmark_group("shade_regular");
    g.throughput(Throughput::Elements(PIXELS as u64));
    for budget in [14, 17, 30] {
        let plan = plan_regular(&kurt, budget, 0.01).expect("plan");
        g.bench_with_input(BenchmarkId::from_parameter(budget), &plan, |b, plan| {
            b.iter(|| {
                for (f, wo) in &pixels {
                    black_box(shade_regular(f, *wo, plan, &env, Weighting::Pdf002));
                }
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("shade_lattice");
    g.throughput(Throughput::Elements(PIXELS as u64));
    for budget in [14, 17, 30] {
        let plan = plan_lattice(&kurt, budget).expect("plan");
        g.bench_with_input(BenchmarkId::from_parameter(budget), &plan, |b, plan| {
            b.iter(|| {
                for (f, wo) in &pixels {
                    black_box(shade_regular(f, *wo, plan, &env, Weighting::Pdf002));
                }
            })
        });
    }
    g.finish();
    let suns = [
        Sun {
            direction: DVec3::new(0.3, 0.9, 0.2).normalize(),
            irradiance: [4.0, 3.8, 3.5],
            spread: 0.005,
        },
        Sun {
            direction: DVec3::new(-0.6, 0.3, 0.7).normalize(),
            irradiance: [1.0, 1.0, 1.2],
            spread: 0.005,
        },
    ];
    let mut g = c.benchmark_group("shade_lattice_sun");
    g.throughput(Throughput::Elements(PIXELS as u64));
    for budget in [14, 17, 30] {
        let plan = plan_lattice_sun(&kurt, budget, &suns).expect("plan");
        g.bench_with_input(BenchmarkId::from_parameter(budget), &plan, |b, plan| {
            b.iter(|| {
                for (f, wo) in &pixels {
                    black_box(shade_regular(f, *wo, plan, &env, Weighting::Pdf002));
                }
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("shade_tap_lattice");
    g.throughput(Throughput::Elements(PIXELS as u64));
    for budget in [14, 17, 30] {
        let plan = plan_tap_lattice(&kurt, budget).expect("plan");
        g.bench_with_input(BenchmarkId::from_parameter(budget), &plan, |b, plan| {
            b.iter(|| {
                for (f, wo) in &pixels {
                    black_box(shade_regular(f, *wo, plan, &env, Weighting::Pdf002));
                }
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("shade_ck");
    g.throughput(Throughput::Elements(PIXELS as u64));
    for n in [16, 32] {
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, &n| {
            b.iter(|| {
                for (f, wo) in &pixels {
                    black_box(shade_ck(f, *wo, &kurt, n, &env));
                }
            })
        });
    }
    g.finish();
    let mut g = c.benchmark_group("reference");
    let samples = 256;
    g.throughput(Throughput::Elements((PIXELS * samples) as u64));
    g.bench_function("per_sample", |b| {
        b.iter(|| {
            for (i, (f, wo)) in pixels.iter().enumerate() {
                black_box(shade_reference(f, *wo, &kurt, &env, samples, i as u64));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
