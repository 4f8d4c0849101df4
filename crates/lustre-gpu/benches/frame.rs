//! Lavapipe (or GPU) frame times of the regular-sampling integrator at 1920×1080 for per-lobe sample
//! counts n = 3, 5, …, 19 (the shape of 000 Table 4.1): a screen full of specular pixels and a
//! screen half specular, half diffuse. `draw` = dispatch + wait, without upload or readback;
//! those are measured separately in the `transfer` group.
//!
//! The `scheme` group compares the two regular kernels per pixel at 480×270, a screen full of
//! one-lobe specular pixels: 002's stored pattern (Pdf002), ours, the per-pixel row lattice, and
//! the lattice with several taps in its long cells, at 14 and 17 lookups per lobe.
//!
//! Run one group quickly: `cargo bench -p lustre-gpu --bench frame -- --quick frame_full/7`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use glam::DVec3;
use lustre_gpu::{
    CameraBasis, CubeLevelRef, GpuContext, GpuEnvironment, GpuKurtMaterial, GpuLobe, GpuPlane,
    GpuRenderer, GpuScene, GpuSun, PackedScene, RenderTarget, LOBE_SCHEME_LATTICE,
    LOBE_SCHEME_TAP_LATTICE,
};
use std::f64::consts::PI;

const W: usize = 1920;
const H: usize = 1080;
const ENV_SIZE: usize = 256;

/// A smooth sky with a bright sun, every level evaluated at texel centres.
fn env_levels() -> Vec<(usize, Vec<Vec<[f32; 3]>>)> {
    let mut out = Vec::new();
    let mut n = ENV_SIZE;
    loop {
        let faces = (0..6)
            .map(|f| {
                (0..n * n)
                    .map(|k| {
                        let s = 2.0 * ((k % n) as f64 + 0.5) / n as f64 - 1.0;
                        let t = 2.0 * ((k / n) as f64 + 0.5) / n as f64 - 1.0;
                        let d = match f {
                            0 => DVec3::new(1.0, -t, -s),
                            1 => DVec3::new(-1.0, -t, s),
                            2 => DVec3::new(s, 1.0, t),
                            3 => DVec3::new(s, -1.0, -t),
                            4 => DVec3::new(s, -t, 1.0),
                            _ => DVec3::new(-s, -t, -1.0),
                        }
                        .normalize();
                        let sun = d.dot(DVec3::new(0.5, 0.7, 0.5).normalize()).max(0.0);
                        let v = 0.3 + 0.5 * d.y.max(0.0) + 20.0 * sun.powi(200);
                        [v as f32, (v * 0.9) as f32, (v * 0.8) as f32]
                    })
                    .collect()
            })
            .collect();
        out.push((n, faces));
        if n == 1 {
            return out;
        }
        n /= 2;
    }
}

/// A lobe with a centre sample and a ring of n − 1 half vectors at 0.6·θmax (000 §4.4.3 shape).
fn lobe(n: usize, samples: &mut Vec<[f32; 4]>) -> GpuLobe {
    let (mx, my, xi0) = (0.15f64, 0.15f64, 0.1f64);
    let theta = 0.6 * ((-xi0.ln()).sqrt() * mx).atan();
    let start = samples.len() as u32;
    samples.push([0.0, 0.0, 1.0, 0.0]);
    for k in 0..n - 1 {
        let phi = 2.0 * PI * k as f64 / (n - 1) as f64;
        let h = DVec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        );
        samples.push([h.x as f32, h.y as f32, h.z as f32, 0.0]);
    }
    // 002 Eq. 18: mean of D over the pattern.
    let d = |h: &[f32; 4]| {
        let (ax, ay) = (
            h[0] as f64 / (mx * h[2] as f64),
            h[1] as f64 / (my * h[2] as f64),
        );
        (-(ax * ax + ay * ay)).exp() / (PI * mx * my * (h[2] as f64).powi(4))
    };
    let pdf = samples[start as usize..].iter().map(d).sum::<f64>() / n as f64;
    GpuLobe {
        ks: [0.6, 0.6, 0.6],
        mx: mx as f32,
        my: my as f32,
        r0: 0.5,
        alpha: 0.0,
        xi0: xi0 as f32,
        pdf_constant: pdf as f32,
        sample_start: start,
        sample_count: n as u32,
        scheme: lustre_gpu::packed::LOBE_SCHEME_PATTERN,
    }
}

/// A square filling the view; `half`: its right half is a second, purely diffuse square.
fn scene(n: usize, half: bool) -> PackedScene {
    let mut samples = Vec::new();
    let lobes = vec![lobe(n, &mut samples)];
    let specular = GpuKurtMaterial {
        kd: [0.1, 0.1, 0.1],
        lobe_start: 0,
        reflection: 1,
        transmission: 0,
        sun_start: 0,
        sun_count: 0,
    };
    let diffuse = GpuKurtMaterial {
        reflection: 0,
        ..specular
    };
    let square = |x: f32, half_size: f32, material: u32| GpuPlane {
        point: [x, 0.0, 0.0],
        half_size,
        normal: [0.0, 0.0, 1.0],
        material,
        tangent: [1.0, 0.0, 0.0],
        pad: 0,
    };
    let planes = if half {
        vec![square(-2.0, 2.0, 0), square(2.0, 2.0, 1)]
    } else {
        vec![square(0.0, 4.0, 0)]
    };
    PackedScene {
        // Looking slightly down at the square from 2 units: the view is filled with it.
        camera: CameraBasis::new(
            DVec3::new(0.0, -0.5, 2.0),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::Y,
            60.0,
        ),
        spheres: vec![],
        planes,
        materials: vec![specular, diffuse],
        lobes,
        samples,
        suns: vec![],
    }
}

fn bench(c: &mut Criterion) {
    let ctx = match GpuContext::new() {
        Ok(ctx) => ctx,
        Err(e) => panic!("{e}"),
    };
    eprintln!("adapter: {}", ctx.describe());
    let renderer = GpuRenderer::new(&ctx).unwrap_or_else(|e| panic!("{e}"));
    let levels = env_levels();
    let refs: Vec<CubeLevelRef> = levels
        .iter()
        .map(|(n, f)| CubeLevelRef {
            size: *n,
            faces: std::array::from_fn(|k| f[k].as_slice()),
        })
        .collect();
    let irr = refs[refs.len() - 3];
    let env = GpuEnvironment::from_levels(&ctx, &refs, irr).unwrap_or_else(|e| panic!("{e}"));
    let target = RenderTarget::new(&ctx, W, H).unwrap_or_else(|e| panic!("{e}"));
    for (name, half) in [("frame_full", false), ("frame_half", true)] {
        let mut g = c.benchmark_group(name);
        g.sample_size(10);
        for n in (3..=19).step_by(2) {
            let gs = GpuScene::upload(&ctx, &scene(n, half)).unwrap_or_else(|e| panic!("{e}"));
            let bindings = renderer
                .bind(&gs, &env, &target)
                .unwrap_or_else(|e| panic!("{e}"));
            g.bench_with_input(BenchmarkId::from_parameter(n), &bindings, |b, bindings| {
                b.iter(|| renderer.draw(bindings).unwrap_or_else(|e| panic!("{e}")))
            });
        }
        g.finish();
    }
    let small = RenderTarget::new(&ctx, 480, 270).unwrap_or_else(|e| panic!("{e}"));
    let mut g = c.benchmark_group("scheme");
    g.sample_size(10);
    for n in [14, 17] {
        for (name, scheme) in [
            ("pattern", None),
            ("lattice", Some(LOBE_SCHEME_LATTICE)),
            ("taps", Some(LOBE_SCHEME_TAP_LATTICE)),
            ("lattice+sun", Some(LOBE_SCHEME_LATTICE)),
        ] {
            let mut packed = scene(n, false);
            if let Some(scheme) = scheme {
                packed.lobes[0].scheme = scheme;
                packed.lobes[0].sample_count = n as u32;
            }
            if name == "lattice+sun" {
                // integrator::plan_lattice_sun with two suns: n − 2 cells and two exact evaluations.
                packed.lobes[0].sample_count = n as u32 - 2;
                packed.materials[0].sun_count = 2;
                packed.suns = vec![
                    GpuSun {
                        direction: [0.3, 0.9, 0.3],
                        spread: 0.01,
                        irradiance: [4.0, 3.8, 3.5],
                        pad1: 0.0,
                    },
                    GpuSun {
                        direction: [-0.6, 0.3, 0.74],
                        spread: 0.06,
                        irradiance: [1.0, 1.0, 1.2],
                        pad1: 0.0,
                    },
                ];
            }
            let gs = GpuScene::upload(&ctx, &packed).unwrap_or_else(|e| panic!("{e}"));
            let bindings = renderer
                .bind(&gs, &env, &small)
                .unwrap_or_else(|e| panic!("{e}"));
            g.bench_with_input(BenchmarkId::new(name, n), &bindings, |b, bindings| {
                b.iter(|| renderer.draw(bindings).unwrap_or_else(|e| panic!("{e}")))
            });
        }
    }
    g.finish();
    let mut g = c.benchmark_group("transfer");
    g.sample_size(10);
    g.bench_function("readback_1080p", |b| {
        b.iter(|| target.read_back(&ctx).unwrap_or_else(|e| panic!("{e}")))
    });
    g.bench_function("upload_env_256", |b| {
        b.iter(|| {
            let e = GpuEnvironment::from_levels(&ctx, &refs, irr).unwrap_or_else(|e| panic!("{e}"));
            ctx.wait().unwrap_or_else(|e| panic!("{e}"));
            e
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
