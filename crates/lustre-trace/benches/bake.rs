//! Light-map baking speed on the Modern Hall (Mitsuba XML through lustre-scene), single thread:
//! irradiance paths ([`PathTracer::irradiance`], the bake's per-sample estimator, with the
//! materials made diffuse as the bake makes them) at 4 bounces, from the surface points the
//! camera sees (256 points), and the validity probes of those points. `cargo bench -p
//! lustre-trace --bench bake`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::DVec3;
use lustre_brdf::sampling::SplitMix64;
use lustre_trace::bake::diffuse_path_scene;
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::path_camera;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let path = lustre_env::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml");
    let scene = lustre_scene::Scene::load(&path).expect("Modern Hall");
    let (ps, _, _) = diffuse_path_scene(&scene).expect("diffuse scene");
    let pt = PathTracer::new(
        &ps,
        PathOptions {
            max_depth: 5,
            ..PathOptions::default()
        },
    )
    .expect("tracer");
    let (w, h) = (16usize, 16usize);
    let cam = path_camera(&scene, None, w as u32, h as u32).expect("camera");
    let points: Vec<(DVec3, DVec3)> = (0..w * h)
        .filter_map(|k| {
            let d = cam.direction((k % w) as f64 + 0.5, (k / w) as f64 + 0.5, w, h);
            let hit = pt.intersect(cam.origin, d)?;
            let t = &ps.geometry.positions[hit.prim];
            let mut n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            if n.dot(d) > 0.0 {
                n = -n;
            }
            Some((cam.origin + d * hit.t, n))
        })
        .collect();
    let mut g = c.benchmark_group("bake_modern_hall");
    g.sample_size(20);
    g.throughput(Throughput::Elements(points.len() as u64));
    g.bench_function("irradiance_path_4_bounces", |b| {
        let mut rng = SplitMix64::new(1);
        b.iter(|| {
            for &(p, n) in &points {
                black_box(pt.irradiance(p, n, n, &mut rng));
            }
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
