//! Rays per second of the BVH on the Modern Hall (Mitsuba XML through lustre-scene): closest-hit
//! camera rays (256×256, coherent) and the incoherent rays of a diffuse bounce (cosine-sampled
//! about the normal at each camera hit), single thread. `cargo bench -p lustre-trace --bench accel`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::DVec3;
use lustre_brdf::sampling::{cosine_hemisphere, SplitMix64};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};
use lustre_trace::sampling::ShadingFrame;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let path = lustre_env::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml");
    let scene = lustre_scene::Scene::load(&path).expect("Modern Hall");
    let (ps, _) = path_scene(&scene).expect("path scene");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let (w, h) = (256usize, 256usize);
    let cam = path_camera(&scene, None, w as u32, h as u32).expect("camera");
    let primary: Vec<(DVec3, DVec3)> = (0..w * h)
        .map(|k| {
            let d = cam.direction((k % w) as f64 + 0.5, (k / w) as f64 + 0.5, w, h);
            (cam.origin, d)
        })
        .collect();
    let mut rng = SplitMix64::new(5);
    let bounce: Vec<(DVec3, DVec3)> = primary
        .iter()
        .filter_map(|&(o, d)| {
            let hit = pt.intersect(o, d)?;
            let t = &ps.geometry.positions[hit.prim];
            let mut n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            if n.dot(d) > 0.0 {
                n = -n;
            }
            let p = o + d * hit.t + n * 1e-4;
            let f = ShadingFrame::new(n, DVec3::X);
            let wi = f.to_world(cosine_hemisphere(rng.next_f64(), rng.next_f64()));
            Some((p, wi))
        })
        .collect();
    println!(
        "Modern Hall: {} triangles, {} camera rays, {} bounce rays",
        ps.geometry.positions.len(),
        primary.len(),
        bounce.len()
    );
    let mut g = c.benchmark_group("modern_hall_rays");
    g.sample_size(10);
    for (name, rays) in [("camera", &primary), ("diffuse_bounce", &bounce)] {
        g.throughput(Throughput::Elements(rays.len() as u64));
        g.bench_function(format!("{name}_closest_hit"), |b| {
            b.iter(|| {
                let mut n = 0usize;
                for &(o, d) in rays.iter() {
                    n += pt.intersect(o, d).is_some() as usize;
                }
                black_box(n)
            })
        });
        g.bench_function(format!("{name}_any_hit"), |b| {
            b.iter(|| {
                let mut n = 0usize;
                for &(o, d) in rays.iter() {
                    n += pt.occluded(o, d, f64::INFINITY) as usize;
                }
                black_box(n)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
