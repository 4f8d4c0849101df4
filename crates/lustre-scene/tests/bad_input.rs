//! Bad input of every kind gives a clear error (or a named warning), never a
//! panic: missing referenced files (named), NaN/Inf vertices, degenerate triangles (dropped and
//! counted), out-of-range indices, unknown XML plugins (named, with the line), malformed TOML,
//! unsupported required glTF extensions.

use lustre_scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

fn dir() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn xml(body: &str) -> String {
    format!("<?xml version=\"1.0\"?>\n<scene version=\"0.5.0\">\n{body}\n</scene>\n")
}

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

fn obj_shape(file: &str) -> String {
    format!("<shape type=\"obj\"><string name=\"filename\" value=\"{file}\"/></shape>")
}

#[test]
fn unknown_xml_plugin_is_named_with_its_line() {
    let d = dir();
    let p = write(
        d.path(),
        "s.xml",
        &xml("<bsdf type=\"diffuse\" id=\"a\"/>\n<bsdf type=\"velvet\" id=\"b\"/>"),
    );
    let e = Scene::load(&p).unwrap_err();
    match &e {
        SceneError::UnknownPlugin {
            line, kind, name, ..
        } => {
            assert_eq!((*line, kind.as_str(), name.as_str()), (4, "bsdf", "velvet"))
        }
        other => panic!("{other:?}"),
    }
    let msg = e.to_string();
    assert!(
        msg.contains("s.xml") && msg.contains("line 4") && msg.contains("velvet"),
        "{msg}"
    );
    // An unsupported shape, emitter and texture, and an unknown element.
    for (body, line, what) in [
        ("\n<shape type=\"ply\"/>", 4, "ply"),
        ("<emitter type=\"point\"/>", 3, "point"),
        (
            "<bsdf type=\"diffuse\">\n<texture name=\"reflectance\" type=\"checkerboard\"/></bsdf>",
            4,
            "checkerboard",
        ),
    ] {
        let p = write(d.path(), "u.xml", &xml(body));
        let msg = Scene::load(&p).unwrap_err().to_string();
        assert!(
            msg.contains(&format!("line {line}")) && msg.contains(what),
            "{msg}"
        );
    }
    let p = write(d.path(), "v.xml", &xml("<frobnicate/>"));
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("line 3") && msg.contains("frobnicate"),
        "{msg}"
    );
}

#[test]
fn malformed_xml_is_an_error() {
    let d = dir();
    for text in [
        "",
        "<scene version=\"0.5.0\">",
        "<notascene/>",
        "<scene/>",
        "\u{0}\u{1}",
    ] {
        let p = write(d.path(), "m.xml", text);
        let e = Scene::load(&p).unwrap_err();
        assert!(matches!(e, SceneError::Format { .. }), "{text:?}: {e:?}");
        assert!(e.to_string().contains("m.xml"));
    }
}

#[test]
fn missing_referenced_files_are_named() {
    let d = dir();
    let p = write(d.path(), "s.xml", &xml(&obj_shape("models/nope.obj")));
    match Scene::load(&p).unwrap_err() {
        SceneError::MissingFile { path, referenced } => {
            assert_eq!(path, p);
            assert!(referenced.ends_with("models/nope.obj"));
        }
        e => panic!("{e:?}"),
    }
    write(d.path(), "q.obj", QUAD);
    let tex = "<bsdf type=\"diffuse\"><texture name=\"reflectance\" type=\"bitmap\">\
               <string name=\"filename\" value=\"gone.png\"/></texture></bsdf>";
    let p = write(
        d.path(),
        "t.xml",
        &xml(&format!(
            "<shape type=\"obj\"><string name=\"filename\" value=\"q.obj\"/>{tex}</shape>"
        )),
    );
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("gone.png") && msg.contains("does not exist"),
        "{msg}"
    );
    // OBJ: a missing MTL library and a missing diffuse map.
    let p = write(d.path(), "m.obj", &format!("mtllib missing.mtl\n{QUAD}"));
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("missing.mtl"), "{msg}");
    write(
        d.path(),
        "k.mtl",
        "newmtl a\nKd 1 1 1\nmap_Kd nothere.png\n",
    );
    let p = write(
        d.path(),
        "k.obj",
        &format!("mtllib k.mtl\nusemtl a\n{QUAD}"),
    );
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("nothere.png"), "{msg}");
    // A scene file naming a missing geometry file and map.
    let p = write(
        d.path(),
        "s.toml",
        "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"absent.gltf\"\n",
    );
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("absent.gltf") && msg.contains("s.toml"),
        "{msg}"
    );
    let p = write(
        d.path(),
        "e.toml",
        "schema = \"lustre-scene\"\nversion = 1\n[environment]\nmap = \"sky.hdr\"\n",
    );
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("sky.hdr"), "{msg}");
    // An unknown extension.
    let p = write(d.path(), "x.fbx", "");
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("fbx"), "{msg}");
}

#[test]
fn non_finite_vertices_are_rejected() {
    let d = dir();
    for (bad, what) in [
        ("v nan 0 0", "NaN"),
        ("v 0 inf 0", "inf"),
        ("v 0 0 -inf", "-inf"),
    ] {
        let text = format!("v 0 0 0\nv 1 0 0\n{bad}\nf 1 2 3\n");
        write(d.path(), "n.obj", &text);
        for p in [
            d.path().join("n.obj"),
            write(d.path(), "n.xml", &xml(&obj_shape("n.obj"))),
        ] {
            let e = Scene::load(&p).unwrap_err();
            let msg = e.to_string();
            assert!(matches!(e, SceneError::Geometry { .. }), "{what}: {e:?}");
            assert!(
                msg.contains("vertex 2") && msg.contains("non-finite"),
                "{msg}"
            );
            assert!(msg.contains("n.obj"), "{msg}");
        }
    }
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let d = dir();
    // Triangle 2 repeats a corner's coordinates, triangle 3 is collinear.
    let text = "o thing\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 2 0 0\n\
                f 1 2 3\nf 1 2 4\nf 1 2 5\n";
    let p = write(d.path(), "g.obj", text);
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.triangle_count(), 1);
    assert_eq!(s.stats.degenerate_triangles, 2);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("thing") && s.warnings[0].contains("2 degenerate"));
}

#[test]
fn out_of_range_indices_are_rejected() {
    let d = dir();
    let p = write(d.path(), "o.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("o.obj"), "{msg}");
    // Through the mesh check itself (as glTF indices go).
    let mut m = lustre_scene::Mesh::new(
        "m",
        vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        vec![[0, 1, 2], [0, 1, 3]],
        0,
    );
    let e = m
        .clone()
        .validated(Path::new("x"), 1)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("triangle 1") && e.contains("out of range"),
        "{e}"
    );
    m.indices.pop();
    m.uv0 = Some(vec![glam::Vec2::ZERO; 2]);
    let e = m
        .clone()
        .validated(Path::new("x"), 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("2 uv0 coordinates for 3 vertices"), "{e}");
    m.uv0 = None;
    let e = m.validated(Path::new("x"), 0).unwrap_err().to_string();
    assert!(e.contains("material index 0 out of range"), "{e}");
}

/// A minimal glTF (one triangle, external .bin) with a POSITION accessor and u16 indices.
fn gltf_triangle(d: &Path, positions: [[f32; 3]; 3], indices: [u16; 3], extra: &str) -> PathBuf {
    let mut bin = Vec::new();
    for p in positions.iter().flatten() {
        bin.extend_from_slice(&p.to_le_bytes());
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    bin.extend_from_slice(&[0, 0]);
    std::fs::write(d.join("t.bin"), &bin).unwrap();
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},{extra}"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"uri":"t.bin","byteLength":{len}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                     {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        len = bin.len()
    );
    write(d, "t.gltf", &json)
}

const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

#[test]
fn gltf_bad_input() {
    let d = dir();
    let p = gltf_triangle(d.path(), TRI, [0, 1, 2], "");
    let s = Scene::load(&p).unwrap();
    assert_eq!(s.triangle_count(), 1);
    // Index out of range.
    let p = gltf_triangle(d.path(), TRI, [0, 1, 5], "");
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("out of range") && msg.contains("t.gltf"),
        "{msg}"
    );
    // NaN and infinite positions.
    for bad in [f32::NAN, f32::INFINITY] {
        let p = gltf_triangle(
            d.path(),
            [[0.0; 3], [1.0, bad, 0.0], [0.0, 1.0, 0.0]],
            [0, 1, 2],
            "",
        );
        let msg = Scene::load(&p).unwrap_err().to_string();
        assert!(
            msg.contains("vertex 1") && msg.contains("non-finite"),
            "{msg}"
        );
    }
    // A degenerate triangle, the only one: no geometry, with the reason.
    let p = gltf_triangle(d.path(), TRI, [0, 1, 1], "");
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("no geometry") && msg.contains("1 degenerate triangle(s) dropped"),
        "{msg}"
    );
    // A required extension we do not support.
    let p = gltf_triangle(
        d.path(),
        TRI,
        [0, 1, 2],
        r#""extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],"#,
    );
    match Scene::load(&p).unwrap_err() {
        SceneError::UnsupportedExtension { extension, .. } => {
            assert_eq!(extension, "KHR_draco_mesh_compression")
        }
        e => panic!("{e:?}"),
    }
    // A used-only extension we do not read is a named warning.
    let p = gltf_triangle(
        d.path(),
        TRI,
        [0, 1, 2],
        r#""extensionsUsed":["KHR_texture_transform"],"#,
    );
    let s = Scene::load(&p).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("KHR_texture_transform")),
        "{:?}",
        s.warnings
    );
    // Missing buffer file.
    std::fs::remove_file(d.path().join("t.bin")).unwrap();
    match Scene::load(&p).unwrap_err() {
        SceneError::MissingFile { referenced, .. } => assert!(referenced.ends_with("t.bin")),
        e => panic!("{e:?}"),
    }
    // A buffer shorter than its accessors claim, and not JSON at all.
    let p = gltf_triangle(d.path(), TRI, [0, 1, 2], "");
    std::fs::write(d.path().join("t.bin"), [0u8; 8]).unwrap();
    assert!(Scene::load(&p).is_err());
    let p = write(d.path(), "j.gltf", "{ not json");
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("j.gltf"), "{msg}");
}

fn toml_err(text: &str) -> String {
    let d = dir();
    let p = write(d.path(), "s.toml", text);
    Scene::load(&p).unwrap_err().to_string()
}

#[test]
fn malformed_and_invalid_toml() {
    let head = "schema = \"lustre-scene\"\nversion = 1\n";
    let msg = toml_err("schema = \"lustre-scene\"\nversion = \n");
    assert!(
        msg.contains("malformed TOML") && msg.contains("line 2"),
        "{msg}"
    );
    let msg = toml_err("version = 1\n");
    assert!(msg.contains("no schema"), "{msg}");
    let msg = toml_err("schema = \"lustre-material\"\nversion = 1\n");
    assert!(msg.contains("not a lustre scene file"), "{msg}");
    let msg = toml_err("schema = \"lustre-scene\"\nversion = 7\n");
    assert!(msg.contains("version 7 is not supported"), "{msg}");
    let msg = toml_err(&format!("{head}colour = 3\n"));
    assert!(msg.contains("colour"), "{msg}");
    let msg = toml_err(&format!("{head}[environment]\nconstant = [1, 1, 1]\nsky = {{ zenith = [1,1,1], horizon = [1,1,1], ground = [0,0,0] }}\n"));
    assert!(msg.contains("exactly one of map, constant, sky"), "{msg}");
    let msg = toml_err(&format!("{head}[environment]\nconstant = [1, -1, 1]\n"));
    assert!(msg.contains("≥ 0"), "{msg}");
    let msg = toml_err(&format!(
        "{head}[[camera]]\nname = \"a\"\nposition = [0,0,0]\nlook_at = [0,0,-1]\nfov_deg = 190\n"
    ));
    assert!(msg.contains("fov_deg"), "{msg}");
    let msg = toml_err(&format!(
        "{head}[[camera]]\nname = \"a\"\nposition = [0,0,0]\nlook_at = [0,1,0]\nfov_deg = 60\n"
    ));
    assert!(msg.contains("parallel"), "{msg}");
    let msg = toml_err(&format!("{head}[[camera_path]]\nname = \"p\"\nkeyframes = [{{ time = 1.0, camera = \"a\" }}, {{ time = 1.0, camera = \"a\" }}]\n"));
    assert!(msg.contains("strictly increasing"), "{msg}");
    let msg = toml_err(&format!("{head}[[camera_path]]\nname = \"p\"\nkeyframes = [{{ time = 1.0, camera = \"nobody\" }}]\n"));
    assert!(msg.contains("no camera named \"nobody\""), "{msg}");
    let msg = toml_err(&format!(
        "{head}[materials]\nNotThere = \"lambert(kd=0.5)\"\n"
    ));
    assert!(msg.contains("no material named \"NotThere\""), "{msg}");
    let msg = toml_err(&format!("{head}[objects.Ghost]\nprobe = true\n"));
    assert!(msg.contains("no mesh named \"Ghost\""), "{msg}");
    let msg = toml_err(&format!("{head}[objects.Ghost]\nprobe = 3\n"));
    assert!(msg.contains("invalid scene file"), "{msg}");
    let msg = toml_err(&format!("{head}[[emitter]]\nradiance = [1, 1, 1]\n"));
    assert!(msg.contains("exactly one of object, shape"), "{msg}");
    let msg = toml_err(&format!("{head}film = {{ width = 0, height = 10 }}\n"));
    assert!(msg.contains("film"), "{msg}");
}

#[test]
fn deeply_nested_bsdfs_are_an_error() {
    let d = dir();
    let body = format!(
        "<bsdf type=\"diffuse\" id=\"x\"/><shape type=\"disk\">{}<bsdf type=\"diffuse\"/>{}</shape>",
        "<bsdf type=\"twosided\">".repeat(40),
        "</bsdf>".repeat(40)
    );
    let p = write(d.path(), "deep.xml", &xml(&body));
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(msg.contains("nested more than 16 deep"), "{msg}");
}

/// Found by the gltf fuzz target: gltf-json's validation panics on a POSITION accessor index
/// out of range; the reader checks that reference first.
#[test]
fn gltf_attribute_naming_a_missing_accessor_is_an_error() {
    let d = dir();
    let p = gltf_triangle(d.path(), TRI, [0, 1, 2], "");
    let text = std::fs::read_to_string(&p)
        .unwrap()
        .replace("\"POSITION\":0", "\"POSITION\":9");
    let p = write(d.path(), "bad.gltf", &text);
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("POSITION names accessor 9, but the file has 2 accessor(s)"),
        "{msg}"
    );
}

/// A glTF of another major version, and a .glb without the GLB magic: named, not parsed as
/// something else.
#[test]
fn gltf_of_another_version_and_glb_without_magic_are_errors() {
    let d = dir();
    let p = gltf_triangle(d.path(), TRI, [0, 1, 2], "");
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("\"version\":\"2.0\""), "{text}");
    let p = write(
        d.path(),
        "v3.gltf",
        &text.replace("\"version\":\"2.0\"", "\"version\":\"3.0\""),
    );
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("glTF version \"3.0\": lustre reads glTF 2.x files only"),
        "{msg}"
    );
    let p = write(d.path(), "text.glb", &text);
    let msg = Scene::load(&p).unwrap_err().to_string();
    assert!(
        msg.contains("text.glb") && msg.contains("not a binary glTF (GLB)"),
        "{msg}"
    );
}

#[test]
fn glb_header_shorter_than_itself_is_an_error() {
    // Found by the `gltf` fuzz target: a declared length under 12 bytes made gltf 1.4.1 subtract
    // with overflow (a panic in builds with overflow checks).
    let mut bytes = b"glTF".to_vec();
    bytes.extend_from_slice(&2u32.to_le_bytes());
    bytes.extend_from_slice(&0u32.to_le_bytes());
    bytes.extend_from_slice(b"\x00\x06\x11\x00JSON{}");
    let e = lustre_scene::gltf_io::from_slice(Path::new("short.glb"), &bytes)
        .unwrap_err()
        .to_string();
    assert!(e.contains("short.glb") && e.contains("less than"), "{e}");
    let e = lustre_scene::gltf_io::from_slice(Path::new("tiny.glb"), b"glTF\x02\0")
        .unwrap_err()
        .to_string();
    assert!(e.contains("tiny.glb") && e.contains("truncated"), "{e}");
}

#[test]
fn gltf_accessor_with_count_zero_is_an_error() {
    // Found by the `gltf` fuzz target: count 0 made gltf 1.4.1 compute `count − 1` and overflow.
    let d = dir();
    let p = gltf_triangle(
        d.path(),
        [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [0, 1, 2],
        "",
    );
    let text = std::fs::read_to_string(&p).unwrap();
    let bad = text.replacen("\"count\":3", "\"count\":0", 1);
    assert_ne!(bad, text, "the fixture has a count of 3");
    std::fs::write(&p, bad).unwrap();
    let e = Scene::load(&p).unwrap_err().to_string();
    assert!(e.contains("count 0"), "{e}");
}

/// `glb` with its JSON chunk replaced by `json` (padded with spaces), the lengths updated.
fn glb_with_json(glb: &[u8], json: &serde_json::Value) -> Vec<u8> {
    let len = |at: usize| u32::from_le_bytes([glb[at], glb[at + 1], glb[at + 2], glb[at + 3]]);
    let json_len = len(12) as usize;
    let rest = &glb[20 + json_len..];
    let mut text = json.to_string().into_bytes();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + text.len() + rest.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(rest);
    out
}

/// An exported scene whose embedded images lost their mimeType (the specification requires it;
/// the gltf crate panicked reading them, found by the `gltf` fuzz target) is an error naming
/// the image, and broken lustre extras are errors naming the file, never panics.
#[test]
fn exported_scene_bad_input() {
    let seed =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/gltf/exported_scene.glb");
    let glb = std::fs::read(&seed).unwrap();
    let json_len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    let doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let at = Path::new("/nonexistent/x.glb");
    assert!(lustre_scene::gltf_io::from_slice(at, &glb_with_json(&glb, &doc)).is_ok());
    let mut no_mime = doc.clone();
    for image in no_mime["images"].as_array_mut().unwrap() {
        image.as_object_mut().unwrap().remove("mimeType");
    }
    let e = lustre_scene::gltf_io::from_slice(at, &glb_with_json(&glb, &no_mime)).unwrap_err();
    assert!(
        e.to_string()
            .contains("image 0 is in a bufferView but has no mimeType"),
        "{e}"
    );
    let mut no_source = doc.clone();
    no_source["images"][0]
        .as_object_mut()
        .unwrap()
        .remove("bufferView");
    let e = lustre_scene::gltf_io::from_slice(at, &glb_with_json(&glb, &no_source)).unwrap_err();
    assert!(
        e.to_string()
            .contains("image 0 has neither a uri nor a bufferView"),
        "{e}"
    );
    for (pointer, value, says) in [
        (
            "/asset/extras/lustre_scene/version",
            serde_json::json!(2),
            "version",
        ),
        (
            "/asset/extras/lustre_scene/camera_paths/0/keyframes",
            serde_json::json!([]),
            "camera path",
        ),
        (
            "/asset/extras/lustre_scene/environment/source",
            serde_json::json!({}),
            "environment",
        ),
        (
            "/materials/0/extras/lustre_material/kind",
            serde_json::json!("velvet"),
            "velvet",
        ),
    ] {
        let mut bad = doc.clone();
        *bad.pointer_mut(pointer)
            .unwrap_or_else(|| panic!("{pointer}")) = value;
        let e = lustre_scene::gltf_io::from_slice(at, &glb_with_json(&glb, &bad)).unwrap_err();
        assert!(
            e.to_string().contains(says) && e.to_string().contains("x.glb"),
            "{pointer}: {e}"
        );
    }
}
