//! Light-map unwrapping on the real scenes and analytic shapes: charts, pages, utilisation,
//! texel density, Sander stretch and time for each, with the page-resolution layout check.
//!
//! ```sh
//! cargo run --release -p lustre-scene --example unwrap_compare [-- --dump DIR]
//! cargo run --release -p lustre-scene --features uvunwrap-direct-solver --example unwrap_compare
//! ```
//!
//! `--dump DIR` also writes each input's light-mappable meshes (world space) as OBJ files with
//! the density and gutter in a comment, for `scripts/xatlas_compare.py`, which unwraps them with
//! xatlas (the Python bindings) into `DIR/NAME.xatlas.obj`; `--xatlas DIR` then measures those
//! with the same code (one more row per input).

use glam::{DMat4, DVec3, Vec3};
use lustre_scene::lightmap::{
    build_atlas, check_layout, measure_atlas, AtlasOptions, AtlasSource, LightmapAtlas, Unwrapper,
};
use lustre_scene::{mesh, Material, Rgb, Scene};
use std::io::Write;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    lustre_env::shared_data_dir()
}

fn shapes(name: &str, meshes: Vec<lustre_scene::Mesh>) -> Scene {
    let mut s = Scene::new(name);
    s.materials.push(Material::diffuse("white", Rgb([0.5; 3])));
    for m in meshes {
        s.push_mesh(Path::new(name), m).expect("valid shape");
    }
    s
}

fn dump_obj(scene: &Scene, dir: &Path, name: &str, density: f32, gutter: u32) {
    let path = dir.join(format!("{name}.obj"));
    let mut f = std::io::BufWriter::new(std::fs::File::create(&path).expect("create dump"));
    writeln!(f, "# texels_per_metre {density} gutter {gutter}").unwrap();
    let mut base = 1;
    for m in &scene.meshes {
        if m.emission.is_some() || m.indices.is_empty() {
            continue;
        }
        writeln!(f, "o {}", m.name.replace(char::is_whitespace, "_")).unwrap();
        for p in &m.positions {
            writeln!(f, "v {} {} {}", p.x, p.y, p.z).unwrap();
        }
        for t in &m.indices {
            writeln!(f, "f {} {} {}", t[0] + base, t[1] + base, t[2] + base).unwrap();
        }
        base += m.positions.len() as u32;
    }
}

/// The largest gutter (≤ 32) at which `atlas`'s layout is clean, or `None` if even 0 is not.
fn achieved_gutter(scene: &Scene, atlas: &LightmapAtlas) -> Option<u32> {
    let clean = |g: u32| {
        check_layout(
            scene,
            &LightmapAtlas {
                gutter: g,
                ..atlas.clone()
            },
        )
        .is_clean()
    };
    if !clean(0) {
        return None;
    }
    let (mut lo, mut hi) = (0, 33);
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if clean(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// The row of an xatlas result written by scripts/xatlas_compare.py.
fn xatlas_row(path: &Path, name: &str, density: f32, gutter: u32) -> Result<String, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let header: Vec<&str> = text
        .lines()
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let field = |k: &str| -> Result<f64, String> {
        let i = header
            .iter()
            .position(|h| *h == k)
            .ok_or(format!("no {k} in the header"))?;
        header
            .get(i + 1)
            .and_then(|v| v.parse().ok())
            .ok_or(format!("bad {k}"))
    };
    let (w, h, pages, charts, time) = (
        field("width")? as u32,
        field("height")? as u32,
        field("atlases")? as u32,
        field("charts")? as u32,
        field("time_s")?,
    );
    let mut s = Scene::load(path).map_err(|e| e.to_string())?;
    for m in &mut s.meshes {
        m.uv1 = m.uv0.take();
    }
    let atlas = LightmapAtlas {
        width: w,
        height: h,
        pages: pages.max(1),
        mesh_page: vec![Some(0); s.meshes.len()],
        gutter,
        texels_per_metre: density,
        source: AtlasSource::Generated {
            unwrapper: "xatlas".into(),
        },
    };
    let m = measure_atlas(&s, &atlas);
    let achieved = achieved_gutter(&s, &atlas);
    Ok(format!(
        "| {name} | xatlas (python 0.0.11) | {} | {charts} | {} × {w}×{h} | {:.1} % | {:.3} | {:.3} | {:.2} | {} | {time:.2} s |",
        s.triangle_count(),
        pages.max(1),
        100.0 * m.utilisation,
        m.density_ratio,
        m.stretch_l2,
        m.stretch_max,
        achieved.map_or("overlap".into(), |g| format!("{g}")),
    ))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .map(PathBuf::from)
    };
    let dump = arg("--dump");
    let xatlas = arg("--xatlas");
    if let Some(d) = &dump {
        std::fs::create_dir_all(d).expect("dump folder");
    }
    let load = |p: PathBuf| Scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let mut cube = mesh::cube("cube", 0);
    cube.transform(&DMat4::from_translation(DVec3::new(3.0, 0.0, 0.0)));
    // (name, scene, texels per unit, gutter)
    let cases: Vec<(&str, Scene, f32, u32)> = vec![
        (
            "cornell_box",
            load(data().join("scenes/cornell_box/cornell_box.obj")),
            0.25,
            4,
        ),
        (
            "sphere",
            shapes("sphere", vec![mesh::sphere("sphere", Vec3::ZERO, 1.0, 0)]),
            64.0,
            4,
        ),
        ("cube", shapes("cube", vec![cube]), 64.0, 4),
        (
            "modern_hall_gltf",
            load(data().join("scenes/modern_hall/gltf/staircase2.gltf")),
            32.0,
            4,
        ),
        (
            "modern_hall_xml",
            load(data().join("scenes/modern_hall/mitsuba/scene.xml")),
            32.0,
            4,
        ),
    ];
    println!(
        "uvunwrap 0.3.0, direct solver: {}, threads: {}",
        cfg!(feature = "uvunwrap-direct-solver"),
        std::env::var("RAYON_NUM_THREADS").unwrap_or_else(|_| "all".into())
    );
    println!(
        "| input | unwrapper | light-mapped triangles | charts | pages × size | utilisation | density ratio | stretch L2 | stretch max | gutter achieved | time |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (name, scene, density, gutter) in cases {
        if let Some(d) = &dump {
            dump_obj(&scene, d, name, density, gutter);
        }
        let mut s = scene.clone();
        let opts = AtlasOptions {
            texels_per_metre: density,
            gutter,
            unwrapper: Unwrapper::Uvunwrap,
            ..AtlasOptions::default()
        };
        println!("| **{name}** ({density} texels/unit, gutter {gutter}) | | | | | | | | | | |");
        let (atlas, r) = match build_atlas(&mut s, &opts) {
            Ok(x) => x,
            Err(e) => {
                println!("| {name} | uvunwrap | error: {e} |");
                continue;
            }
        };
        println!(
            "| {name} | uvunwrap 0.3.0 | {} ({} meshes, {} skipped) | {} | {} × {}×{} | {:.1} % | {:.3} | {:.3} | {:.2} | {} | {:.2} s |",
            r.triangles,
            r.meshes,
            r.skipped_meshes,
            r.charts,
            r.pages,
            r.width,
            r.height,
            100.0 * r.utilisation,
            r.density_ratio,
            r.stretch_l2,
            r.stretch_max,
            achieved_gutter(&s, &atlas).map_or("overlap".into(), |g| format!("{g}")),
            r.time_s
        );
        if let Some(dir) = &xatlas {
            let path = dir.join(format!("{name}.xatlas.obj"));
            match xatlas_row(&path, name, density, gutter) {
                Ok(row) => println!("{row}"),
                Err(e) => println!("| {name} | xatlas | {e} |"),
            }
        }
    }
}
