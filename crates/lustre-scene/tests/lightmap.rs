//! Light-map UV atlases: TEXCOORD_1 kept when valid and rejected when overlapping or outside
//! [0, 1]; generated atlases inside [0, 1], without overlap, charts a gutter apart at page
//! resolution, at the requested density; page-size limit; skipped meshes; bad options; the
//! atlas .glb and the scene file's `[lightmap]` section.

mod common;

use glam::{DMat4, DVec3, Vec2, Vec3};
use lustre_brdf::Rgb;
use lustre_scene::lightmap::{
    build_atlas, check_layout, find_overlapping_triangles, read_atlas_glb, validate_uv1,
    write_atlas_glb, AtlasOptions, AtlasReport, SkipReason, Unwrapper,
};
use lustre_scene::scene_file::{self, SceneFile};
use lustre_scene::{mesh, AtlasSource, LightmapAtlas, Material, Mesh, Scene};
use std::path::Path;

/// A scene of `meshes` with one diffuse material.
fn scene_of(meshes: Vec<Mesh>) -> Scene {
    let mut s = Scene::new("test.toml");
    s.materials.push(Material::diffuse("white", Rgb([0.5; 3])));
    for m in meshes {
        s.push_mesh(Path::new("test.toml"), m).unwrap();
    }
    s
}

/// A unit square at height `y` (normal +y) with `uv1` = the square [u0, u0 + size]² .
fn quad(name: &str, y: f32, u0: Vec2, size: f32) -> Mesh {
    let p = vec![
        Vec3::new(0.0, y, 0.0),
        Vec3::new(0.0, y, 1.0),
        Vec3::new(1.0, y, 1.0),
        Vec3::new(1.0, y, 0.0),
    ];
    let mut m = Mesh::new(name, p, vec![[0, 1, 2], [0, 2, 3]], 0);
    m.uv1 = Some(vec![
        u0,
        u0 + Vec2::new(0.0, size),
        u0 + Vec2::new(size, size),
        u0 + Vec2::new(size, 0.0),
    ]);
    m
}

/// A sphere and a cube of radius / half side 1 m, apart.
fn sphere_and_cube() -> Scene {
    let mut cube = mesh::cube("cube", 0);
    cube.transform(&DMat4::from_translation(DVec3::new(3.0, 0.0, 0.0)));
    scene_of(vec![mesh::sphere("sphere", Vec3::ZERO, 1.0, 0), cube])
}

fn cornell() -> Scene {
    Scene::load(&common::cornell()).expect("Cornell box loads")
}

/// The Cornell box is in units of ≈ 5.5 mm (walls 556 units): densities per unit are small.
const CORNELL_DENSITY: f32 = 0.25;

fn options(texels_per_metre: f32, gutter: u32) -> AtlasOptions {
    AtlasOptions {
        texels_per_metre,
        gutter,
        ..AtlasOptions::default()
    }
}

/// Area-weighted texel density of mesh `i` (texels per unit): √(UV area in texels / area).
fn density(scene: &Scene, atlas: &LightmapAtlas, i: usize) -> f64 {
    let m = &scene.meshes[i];
    let uv1 = m.uv1.as_ref().expect("uv1");
    let (w, h) = (f64::from(atlas.width), f64::from(atlas.height));
    let mut uv_area = 0.0;
    for tri in &m.indices {
        let [a, b, c] = tri.map(|v| uv1[v as usize].as_dvec2() * glam::DVec2::new(w, h));
        uv_area += 0.5 * (b - a).perp_dot(c - a).abs();
    }
    (uv_area / m.area()).sqrt()
}

/// Every check a generated atlas must pass: every light-mapped triangle's uv1 in [0, 1], no two
/// triangles overlapping, no texel shared by two charts and none within the gutter of another
/// chart (conservative rasterisation at page resolution), triangles unchanged in 3D and in
/// order, attributes carried along the split, and the mesh page in range.
fn assert_valid_generated(before: &Scene, after: &Scene, atlas: &LightmapAtlas) {
    assert!(matches!(atlas.source, AtlasSource::Generated { .. }));
    assert_eq!(atlas.mesh_page.len(), after.meshes.len());
    let check = check_layout(after, atlas);
    assert!(check.is_clean(), "{check:?}");
    assert!(check.covered_texels > 0);
    assert_eq!(find_overlapping_triangles(after, atlas), None);
    for (i, (b, a)) in before.meshes.iter().zip(&after.meshes).enumerate() {
        let Some(page) = atlas.mesh_page[i] else {
            continue;
        };
        assert!(page < atlas.pages);
        assert_eq!(a.triangle_count(), b.triangle_count(), "{}", a.name);
        let uv1 = a.uv1.as_ref().expect("uv1 set");
        assert_eq!(uv1.len(), a.positions.len());
        for t in 0..a.triangle_count() {
            assert_eq!(a.triangle(t), b.triangle(t), "{} triangle {t}", a.name);
            for (&va, &vb) in a.indices[t].iter().zip(&b.indices[t]) {
                let (va, vb) = (va as usize, vb as usize);
                if let (Some(na), Some(nb)) = (&a.normals, &b.normals) {
                    assert_eq!(na[va], nb[vb]);
                }
                if let (Some(ua), Some(ub)) = (&a.uv0, &b.uv0) {
                    assert_eq!(ua[va], ub[vb]);
                }
                let q = uv1[va];
                assert!((0.0..=1.0).contains(&q.x) && (0.0..=1.0).contains(&q.y));
            }
        }
    }
}

#[test]
fn valid_texcoord1_is_used_as_is() {
    let scene = scene_of(vec![
        quad("a", 0.0, Vec2::new(0.05, 0.05), 0.4),
        quad("b", 1.0, Vec2::new(0.55, 0.55), 0.4),
    ]);
    let mut s = scene.clone();
    let (atlas, report) = build_atlas(&mut s, &options(32.0, 2)).unwrap();
    assert_eq!(atlas.source, AtlasSource::Texcoord1);
    assert_eq!(report.texcoord1_rejected, None);
    assert_eq!(s.meshes, scene.meshes, "vertices and uv1 untouched");
    assert_eq!(atlas.mesh_page, vec![Some(0), Some(0)]);
    assert_eq!(report.charts, 2);
    // Two 1 m² quads at 32 texels/m on 0.32 of the page: a page of √(2·32²/0.32) ≈ 80 texels.
    assert_eq!((atlas.width, atlas.height), (80, 80));
    assert!((report.density_ratio - 1.0).abs() < 0.02, "{report:?}");
    assert!((report.stretch_l2 - 1.0).abs() < 1e-6);
    assert!(check_layout(&s, &atlas).is_clean());
}

#[test]
fn overlapping_or_outside_texcoord1_is_detected_and_regenerated() {
    let overlapping = scene_of(vec![
        quad("a", 0.0, Vec2::new(0.1, 0.1), 0.5),
        quad("b", 1.0, Vec2::new(0.3, 0.3), 0.5),
    ]);
    let outside = scene_of(vec![
        quad("a", 0.0, Vec2::new(0.1, 0.1), 0.3),
        quad("b", 1.0, Vec2::new(0.8, 0.8), 0.3),
    ]);
    // Two charts 3 texels apart on a 100-texel page: too close for a 4-texel gutter.
    let close = scene_of(vec![
        quad("a", 0.0, Vec2::new(0.105, 0.105), 0.3),
        quad("b", 1.0, Vec2::new(0.435, 0.105), 0.3),
    ]);
    for (scene, what) in [
        (&overlapping, "overlap"),
        (&outside, "outside [0, 1]"),
        (&close, "gutter"),
    ] {
        let err = validate_uv1(scene, &[0, 1], 100, 100, 4).unwrap_err();
        assert!(err.contains(what), "{err}");
        let mut s = scene.clone();
        let (atlas, report) = build_atlas(&mut s, &options(32.0, 4)).unwrap();
        assert!(
            report.texcoord1_rejected.as_deref().unwrap().contains(what),
            "{report:?}"
        );
        assert_valid_generated(scene, &s, &atlas);
        let mut s = scene.clone();
        let only = AtlasOptions {
            unwrapper: Unwrapper::Texcoord1,
            ..options(32.0, 4)
        };
        let err = build_atlas(&mut s, &only).unwrap_err().to_string();
        assert!(err.contains("TEXCOORD_1") && err.contains(what), "{err}");
    }
    assert!(validate_uv1(&close, &[0, 1], 100, 100, 2).is_ok());
}

/// The generated-atlas checks and the density on the Cornell box, a sphere and a cube.
#[test]
fn generated_atlases_are_valid_at_the_requested_density() {
    for (scene, d, gutter) in [
        (cornell(), CORNELL_DENSITY, 4),
        (sphere_and_cube(), 64.0, 2),
        (sphere_and_cube(), 20.0, 5),
    ] {
        let mut s = scene.clone();
        let (atlas, report) = build_atlas(
            &mut s,
            &AtlasOptions {
                unwrapper: Unwrapper::Uvunwrap,
                ..options(d, gutter)
            },
        )
        .unwrap();
        assert_valid_generated(&scene, &s, &atlas);
        assert_eq!(atlas.gutter, gutter);
        assert_eq!(report.pages, 1);
        // Area-weighted density within 5 % of the requested one, mesh by mesh.
        for (i, page) in atlas.mesh_page.iter().enumerate() {
            if page.is_some() {
                let r = density(&s, &atlas, i) / f64::from(d);
                assert!(
                    (r - 1.0).abs() < 0.05,
                    "{}: density ratio {r}",
                    s.meshes[i].name
                );
            }
        }
        assert!((report.density_ratio - 1.0).abs() < 0.05, "{report:?}");
        assert!(
            report.stretch_l2 >= 1.0 && report.stretch_l2 < 1.2,
            "{report:?}"
        );
        assert!(
            report.utilisation > 0.2 && report.utilisation <= 1.0,
            "{report:?}"
        );
        assert!(report.charts as usize >= report.meshes);
        assert!(report.vertices.1 >= report.vertices.0);
    }
}

#[test]
fn a_mesh_density_hint_overrides_the_atlas_density() {
    let mut scene = sphere_and_cube();
    scene.meshes[1].hints.lightmap_texels_per_metre = Some(40.0);
    let (atlas, _) = build_atlas(&mut scene, &options(10.0, 2)).unwrap();
    let (sphere, cube) = (density(&scene, &atlas, 0), density(&scene, &atlas, 1));
    assert!((sphere / 10.0 - 1.0).abs() < 0.05, "{sphere}");
    assert!((cube / 40.0 - 1.0).abs() < 0.05, "{cube}");
}

/// A density whose atlas exceeds the page limit spreads over several pages, each mesh on one;
/// a mesh that alone exceeds a page is an error naming it.
#[test]
fn page_size_limit_spreads_over_pages_or_names_the_mesh() {
    let meshes: Vec<Mesh> = (0..6)
        .map(|i| {
            let mut m = mesh::cube(&format!("cube{i}"), 0);
            m.transform(&DMat4::from_translation(DVec3::new(
                3.0 * i as f64,
                0.0,
                0.0,
            )));
            m
        })
        .collect();
    let scene = scene_of(meshes);
    let mut s = scene.clone();
    let opts = AtlasOptions {
        max_page_size: 64,
        ..options(8.0, 2)
    };
    // Each cube: 24 m² · 64 = 1536 texels (six 16-texel faces); six cubes need more than one
    // 64² page.
    let (atlas, report) = build_atlas(&mut s, &opts).unwrap();
    assert!(atlas.pages > 1, "{report:?}");
    assert_eq!((atlas.width, atlas.height), (64, 64));
    assert_valid_generated(&scene, &s, &atlas);
    // A 10 m square at 8 texels/m is 80 texels wide.
    let mut big = mesh::rectangle("big floor", 0);
    big.transform(&DMat4::from_scale(DVec3::splat(5.0)));
    let mut s = scene_of(vec![mesh::cube("small", 0), big]);
    let err = build_atlas(&mut s, &opts).unwrap_err().to_string();
    assert!(err.contains("big floor") && err.contains("64"), "{err}");
}

#[test]
fn emitters_and_meshes_without_area_are_skipped_and_counted() {
    let mut lamp = mesh::rectangle("lamp", 0);
    lamp.emission = Some(Rgb([10.0; 3]));
    let flat = Mesh::new(
        "flat",
        vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
        vec![[0, 1, 2]],
        0,
    );
    let mut s = scene_of(vec![mesh::cube("box", 0), lamp, flat]);
    assert_eq!(
        s.meshes[2].triangle_count(),
        0,
        "the collinear triangle is dropped"
    );
    let (atlas, report) = build_atlas(&mut s, &options(16.0, 2)).unwrap();
    assert_eq!(atlas.mesh_page, vec![Some(0), None, None]);
    assert_eq!(report.skipped_meshes, 2);
    let reasons: Vec<_> = report
        .skipped
        .iter()
        .map(|k| (k.name.as_str(), k.reason))
        .collect();
    assert_eq!(
        reasons,
        vec![("lamp", SkipReason::Emitter), ("flat", SkipReason::NoArea)]
    );
    // Nothing left to light-map: a clear error.
    let mut lamp_only = scene_of(vec![mesh::rectangle("lamp", 0)]);
    lamp_only.meshes[0].emission = Some(Rgb([1.0; 3]));
    let err = build_atlas(&mut lamp_only, &options(16.0, 2))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no mesh to light-map"), "{err}");
}

#[test]
fn absurd_options_are_clear_errors() {
    let scene = sphere_and_cube();
    let bad = [
        (options(0.0, 2), "texels_per_metre"),
        (options(-3.0, 2), "texels_per_metre"),
        (options(f32::NAN, 2), "texels_per_metre"),
        (options(f32::INFINITY, 2), "texels_per_metre"),
        (options(16.0, 1000), "gutter"),
        (
            AtlasOptions {
                max_page_size: 0,
                ..options(16.0, 2)
            },
            "max_page_size",
        ),
        // 1e6 texels per metre over 34 m²: thousands of 8192² pages.
        (options(1.0e6, 2), "pages"),
    ];
    for (opts, what) in bad {
        let mut s = scene.clone();
        let err = build_atlas(&mut s, &opts).unwrap_err().to_string();
        assert!(err.contains(what) && err.contains("test.toml"), "{err}");
        assert_eq!(s.meshes, scene.meshes, "nothing changed on error");
    }
    let mut s = scene.clone();
    s.meshes[1].hints.lightmap_texels_per_metre = Some(f32::NAN);
    let err = build_atlas(&mut s, &options(16.0, 2))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("cube") && err.contains("lightmap_texels_per_metre"),
        "{err}"
    );
}

/// Built once: the Cornell box's generated atlas (its light is an emitter: skipped).
fn cornell_atlas() -> &'static (Scene, LightmapAtlas, AtlasReport) {
    static A: std::sync::OnceLock<(Scene, LightmapAtlas, AtlasReport)> = std::sync::OnceLock::new();
    A.get_or_init(|| {
        let mut s = cornell();
        let (atlas, report) = build_atlas(&mut s, &options(CORNELL_DENSITY, 4)).unwrap();
        (s, atlas, report)
    })
}

#[test]
fn atlas_glb_round_trips_through_gltf_and_our_reader() {
    let (scene, atlas, report) = cornell_atlas();
    assert_eq!(report.skipped_meshes, 1, "{report:?}");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lightmap.glb");
    write_atlas_glb(scene, atlas, &path).unwrap();
    let lit: Vec<&Mesh> = scene
        .meshes
        .iter()
        .zip(&atlas.mesh_page)
        .filter(|(_, p)| p.is_some())
        .map(|(m, _)| m)
        .collect();
    // The gltf crate.
    let (doc, buffers, _) = gltf::import(&path).expect("gltf reads the atlas");
    let nodes: Vec<_> = doc.nodes().collect();
    assert_eq!(nodes.len(), lit.len());
    for (node, m) in nodes.iter().zip(&lit) {
        assert_eq!(node.name(), Some(m.name.as_str()));
        let mesh = node.mesh().unwrap();
        assert_eq!(mesh.name(), Some(m.name.as_str()));
        let prim = mesh.primitives().next().unwrap();
        let r = prim.reader(|b| Some(&buffers[b.index()]));
        let uv1: Vec<Vec2> = r
            .read_tex_coords(1)
            .unwrap()
            .into_f32()
            .map(Vec2::from_array)
            .collect();
        assert_eq!(&uv1, m.uv1.as_ref().unwrap());
        let pos: Vec<Vec3> = r.read_positions().unwrap().map(Vec3::from_array).collect();
        assert_eq!(pos, m.positions);
        let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
        assert_eq!(idx, m.indices.iter().flatten().copied().collect::<Vec<_>>());
    }
    // The page in the extras.
    let bytes = std::fs::read(&path).unwrap();
    let glb = gltf::Glb::from_slice(&bytes).unwrap();
    let json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    assert_eq!(json["nodes"][0]["extras"]["lightmap_page"], 0);
    // Our reader.
    let back = Scene::load(&path).unwrap();
    assert_eq!(back.meshes.len(), lit.len());
    for (b, m) in back.meshes.iter().zip(&lit) {
        assert_eq!(b.name, m.name);
        assert_eq!(b.uv1, m.uv1);
        assert_eq!(b.positions, m.positions);
        assert_eq!(b.indices, m.indices);
    }
    // And back onto the freshly loaded scene: the same meshes and atlas.
    let mut fresh = cornell();
    let read = read_atlas_glb(&path, &mut fresh).unwrap();
    assert_eq!(&read, atlas);
    assert_eq!(&fresh.meshes, &scene.meshes);
}

#[test]
fn scene_file_lightmap_section_round_trips_and_mismatches_are_named() {
    let (scene, atlas, _) = cornell_atlas();
    let dir = tempfile::tempdir().unwrap();
    write_atlas_glb(scene, atlas, &dir.path().join("lightmap.glb")).unwrap();
    let pages: Vec<String> = (0..atlas.pages)
        .map(|p| format!("lightmap_{p:03}.exr"))
        .collect();
    for p in &pages {
        std::fs::write(dir.path().join(p), b"page").unwrap();
    }
    let cornell_path = common::cornell();
    let file = SceneFile::for_geometry(cornell_path.to_str().unwrap()).with_lightmap(
        "lightmap.glb",
        pages.clone(),
        atlas,
    );
    let toml_path = dir.path().join("scene.toml");
    scene_file::write(&toml_path, &file).unwrap();
    let text = std::fs::read_to_string(&toml_path).unwrap();
    assert!(
        text.contains("[lightmap]") && text.contains("lightmap.glb"),
        "{text}"
    );
    assert_eq!(scene_file::parse(&toml_path, &text).unwrap(), file);
    let loaded = Scene::load(&toml_path).unwrap();
    assert_eq!(loaded.meshes, scene.meshes);
    let lm = loaded.lightmap.as_ref().expect("lightmap");
    assert_eq!(&lm.atlas, atlas);
    assert_eq!(lm.atlas_file, dir.path().join("lightmap.glb"));
    assert_eq!(
        lm.pages,
        pages.iter().map(|p| dir.path().join(p)).collect::<Vec<_>>()
    );

    // A missing page is named.
    std::fs::remove_file(dir.path().join(&pages[0])).unwrap();
    let err = Scene::load(&toml_path).unwrap_err().to_string();
    assert!(err.contains(&pages[0]), "{err}");

    // An atlas made for another scene: other mesh count; a renamed mesh; other geometry.
    let cases: Vec<(Scene, LightmapAtlas, &str)> = vec![
        {
            let mut s = sphere_and_cube();
            let (a, _) = build_atlas(&mut s, &options(8.0, 2)).unwrap();
            (s, a, "meshes")
        },
        {
            let mut s = scene.clone();
            s.meshes[0].name = "not the floor".into();
            (s, atlas.clone(), "another scene")
        },
        {
            let mut s = scene.clone();
            s.meshes[0].indices.pop();
            (s, atlas.clone(), "triangles")
        },
    ];
    for (other, other_atlas, what) in cases {
        let glb = dir.path().join("other.glb");
        write_atlas_glb(&other, &other_atlas, &glb).unwrap();
        let file = SceneFile::for_geometry(cornell_path.to_str().unwrap()).with_lightmap(
            "other.glb",
            vec![],
            &other_atlas,
        );
        scene_file::write(&toml_path, &file).unwrap();
        let err = Scene::load(&toml_path).unwrap_err().to_string();
        assert!(err.contains("other.glb") && err.contains(what), "{err}");
    }

    // A density that disagrees with the atlas, and a wrong page count.
    let mut file = SceneFile::for_geometry(cornell_path.to_str().unwrap()).with_lightmap(
        "lightmap.glb",
        vec![],
        atlas,
    );
    file.lightmap.as_mut().unwrap().texels_per_metre = Some(CORNELL_DENSITY * 2.0);
    scene_file::write(&toml_path, &file).unwrap();
    let err = Scene::load(&toml_path).unwrap_err().to_string();
    assert!(
        err.contains("lightmap.glb") && err.contains("texels per metre"),
        "{err}"
    );
    file.lightmap.as_mut().unwrap().texels_per_metre = None;
    file.lightmap.as_mut().unwrap().pages = vec!["a.exr".into(), "b.exr".into()];
    scene_file::write(&toml_path, &file).unwrap();
    let err = Scene::load(&toml_path).unwrap_err().to_string();
    assert!(err.contains("pages"), "{err}");
}

#[test]
fn lightmap_section_is_validated() {
    let bad = [
        ("atlas = \"\"", "lightmap.atlas"),
        (
            "atlas = \"a.glb\"\npages = [\"p.exr\", \"p.exr\"]",
            "pages[1]",
        ),
        (
            "atlas = \"a.glb\"\ntexels_per_metre = -1.0",
            "texels_per_metre",
        ),
        ("atlas = \"a.glb\"\ncolour = 3", "unknown field"),
    ];
    for (section, what) in bad {
        let text = format!("schema = \"lustre-scene\"\nversion = 1\n[lightmap]\n{section}\n");
        let err = scene_file::parse(Path::new("s.toml"), &text)
            .unwrap_err()
            .to_string();
        assert!(err.contains(what) && err.contains("s.toml"), "{err}");
    }
}
