//! The fuzz targets' seed corpus (fuzz/seeds/) is made of valid files: each one reads.

use lustre_scene::{gltf_io, mitsuba, scene_file};
use std::path::{Path, PathBuf};

fn seeds(target: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/seeds")
        .join(target);
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no seeds in {}", dir.display());
    v
}

#[test]
fn xml_seeds_read() {
    for p in seeds("scene_xml") {
        let text = std::fs::read_to_string(&p).unwrap();
        let s = mitsuba::from_str(Path::new("/nonexistent/fuzz.xml"), &text)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(
            s.triangle_count() > 0 && s.warnings.is_empty(),
            "{}: {:?}",
            p.display(),
            s.warnings
        );
    }
}

#[test]
fn gltf_seeds_read() {
    for p in seeds("gltf") {
        let s = gltf_io::from_slice(
            Path::new("/nonexistent/fuzz.gltf"),
            &std::fs::read(&p).unwrap(),
        )
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        if p.file_name().is_some_and(|n| n == "exported_scene.glb") {
            // What `lustre export scene` writes (the quad beside a floor, baked): the light map,
            // the sky, two cameras and a camera path come back from the extras.
            assert_eq!(s.triangle_count(), 4);
            let lm = s.lightmap.as_ref().expect("light map");
            assert_eq!(lm.embedded.len(), 1);
            assert!(lm.embedded[0].iter().flatten().any(|&v| v > 0.0));
            assert_eq!(s.cameras.len(), 2);
            assert_eq!(s.camera_paths.len(), 1);
            assert!(matches!(
                s.environment.as_ref().map(|e| &e.source),
                Some(lustre_scene::EnvironmentSource::Sky(_))
            ));
            assert_eq!((s.film.width, s.film.height), (64, 48));
            continue;
        }
        assert_eq!(s.triangle_count(), 2, "{}", p.display());
        assert_eq!(s.emitters().len(), 1);
        assert_eq!(s.cameras.len(), 1);
        let m = &s.materials[0];
        assert_eq!(m.alpha_mask.unwrap().cutoff, Some(0.3));
        assert_eq!(s.meshes[0].emission, Some(lustre_scene::Rgb::splat(2.0)));
        assert_eq!((s.film.width, s.film.height), (1080, 720));
        if p.file_name().is_some_and(|n| n == "layered_material.gltf") {
            // KHR_materials_specular / _clearcoat / _sheen, for the fuzzer to mutate.
            let lustre_scene::MaterialKind::PbrMetallicRoughness { layers, .. } = &m.kind else {
                panic!("{:?}", m.kind)
            };
            assert_eq!(layers.clearcoat, 0.9);
            assert_eq!(layers.sheen_roughness, 0.6);
            assert_eq!(layers.specular_color.0, [2.0, 1.0, 0.5]);
        }
    }
}

#[test]
fn toml_seeds_parse_and_round_trip() {
    for p in seeds("scene_toml") {
        let text = std::fs::read_to_string(&p).unwrap();
        let f = scene_file::parse(&p, &text).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert_eq!(scene_file::parse(&p, &f.to_toml().unwrap()).unwrap(), f);
    }
}
