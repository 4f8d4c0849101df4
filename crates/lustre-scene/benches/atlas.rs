//! Light-map atlas generation (`build_atlas` with uvunwrap): a tessellated sphere and the Modern
//! Hall (glTF, 28,479 light-mappable triangles). Run one quickly with
//! `cargo bench -p lustre-scene --bench atlas -- --quick sphere`.

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Vec3;
use lustre_scene::lightmap::{build_atlas, AtlasOptions, Unwrapper};
use lustre_scene::{mesh, Material, Rgb, Scene};
use std::hint::black_box;
use std::path::Path;

fn atlas(c: &mut Criterion) {
    let mut g = c.benchmark_group("atlas");
    g.sample_size(10);
    let opts = |d: f32| AtlasOptions {
        texels_per_metre: d,
        gutter: 4,
        unwrapper: Unwrapper::Uvunwrap,
        ..AtlasOptions::default()
    };
    let mut sphere = Scene::new("sphere");
    sphere
        .materials
        .push(Material::diffuse("white", Rgb([0.5; 3])));
    sphere
        .push_mesh(
            Path::new("sphere"),
            mesh::sphere("sphere", Vec3::ZERO, 1.0, 0),
        )
        .expect("sphere");
    g.bench_function("sphere_64", |b| {
        b.iter(|| build_atlas(&mut black_box(sphere.clone()), &opts(64.0)).unwrap())
    });
    let hall = lustre_env::shared_data_dir().join("scenes/modern_hall/gltf/staircase2.gltf");
    let hall = Scene::load(&hall).expect("Modern Hall glTF");
    g.bench_function("modern_hall_32", |b| {
        b.iter(|| build_atlas(&mut black_box(hall.clone()), &opts(32.0)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, atlas);
criterion_main!(benches);
