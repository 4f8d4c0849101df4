//! `lustre export material`: the glTF 2.0 files it writes pass the Khronos glTF Validator with no
//! error and load in three.js's GLTFLoader (node and tools/gltf's pinned packages: this test
//! fails without them), reload in lustre's own glTF reader with the fitted values; the Mitsuba
//! files evaluate alike in Mitsuba 3 and in lustre; bad requests are refused.

mod common;

use common::{fails, lustre, ok};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs the node script `tools/gltf/NAME` on `files` (the packages of tools/gltf, installed by
/// `npm ci` there); its standard output, one JSON line per file; panics when it fails.
fn node_tool(name: &str, files: &[&Path]) -> String {
    let tools = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/gltf");
    assert!(
        tools.join("node_modules/gltf-validator").is_dir()
            && tools.join("node_modules/three").is_dir(),
        "tools/gltf's packages are not installed: run `cd tools/gltf && npm ci`"
    );
    let o = Command::new("node")
        .arg(tools.join(name))
        .args(files)
        .output()
        .expect("node runs (apt-get install nodejs)");
    let report = String::from_utf8_lossy(&o.stdout).to_string();
    assert!(
        o.status.success(),
        "{name}: {report}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    report
}

/// The Khronos validator's report of `files`; panics when it finds an error. The warnings are
/// listed in the test's output.
fn validate(files: &[&Path]) -> String {
    let report = node_tool("validate.mjs", files);
    eprintln!("{report}");
    for line in report.lines() {
        assert!(line.contains("\"errors\":0"), "{line}");
    }
    report
}

/// three.js's GLTFLoader's view of `files` (one JSON value each); panics when one does not load.
fn three_load(files: &[&Path]) -> Vec<serde_json::Value> {
    node_tool("three_load.mjs", files)
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON"))
        .collect()
}

/// A number printed after `key` in `t`.
fn number_after(t: &str, key: &str) -> f64 {
    let rest = &t[t.find(key).unwrap_or_else(|| panic!("{key} in {t}")) + key.len()..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("{key} in {t}"))
}

#[test]
fn exported_materials_pass_the_khronos_validator_and_reload() {
    let dir = tempfile::tempdir().expect("dir");
    let rgl = lustre_brdf::shared_data_dir().join("measured/rgl");
    let bsdf: PathBuf = std::fs::read_dir(&rgl)
        .expect("rgl data")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .min()
        .expect("an RGL .bsdf file");
    let mut files = vec![];
    for (spec, name) in [
        ("sgd:nickel".to_string(), "nickel.glb"),
        ("nbrdf:gold-metallic-paint".to_string(), "gold.glb"),
        (bsdf.display().to_string(), "rgl.glb"),
    ] {
        let out = dir.path().join(name);
        let t = ok(lustre()
            .args(["export", "material", &spec, "--to", "gltf", "--out"])
            .arg(&out));
        // The glTF model's error beside lustre's own GGX fit of the same data.
        let gltf = number_after(&t, "Ngan L2 ");
        let ggx = number_after(&t, "GGX fit of the same data: Ngan L2 ");
        assert!(gltf.is_finite() && gltf >= 0.0 && ggx.is_finite(), "{t}");
        assert!(t.contains("wrote"), "{t}");
        // lustre's reader takes the file back: the sphere and its material, as printed.
        let scene = lustre_scene::Scene::load(&out).expect("reloads");
        assert_eq!(scene.triangle_count(), 3968);
        let colour = &t[t.find("base colour [").expect("colour") + 13..];
        let colour: Vec<f64> = colour[..colour.find(']').expect("]")]
            .split(", ")
            .map(|v| v.parse().expect("number"))
            .collect();
        match &scene.materials[0].kind {
            lustre_scene::MaterialKind::PbrMetallicRoughness {
                base_color,
                metallic,
                roughness,
                ..
            } => {
                for (got, printed) in base_color.factor.0.iter().zip(&colour) {
                    assert!((got - printed).abs() <= 5e-5, "{t}");
                }
                assert!((metallic.factor - number_after(&t, ", metallic ")).abs() <= 5e-5);
                assert!((roughness.factor - number_after(&t, ", roughness ")).abs() <= 5e-5);
            }
            other => panic!("{other:?}"),
        }
        files.push(out);
    }
    let refs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    validate(&refs);
    // three.js's loader reads each as a MeshStandardMaterial with the fitted factors (the
    // reload above checked them against the printed values) and the sphere's tangents.
    let mut layered = 0;
    for (v, out) in three_load(&refs).iter().zip(&files) {
        let scene = lustre_scene::Scene::load(out).expect("reloads");
        let (m, t) = (&v["materials"][0], v["triangles"].as_f64());
        assert_eq!(t, Some(3968.0), "{v}");
        assert_eq!(m["tangents"], true, "{v}");
        let lustre_scene::MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            layers,
            ..
        } = &scene.materials[0].kind
        else {
            panic!("{v}")
        };
        let close = |x: &serde_json::Value, y: f64| (x.as_f64().expect("number") - y).abs() < 1e-6;
        // The layers the fit chose: three.js reads the same factors as lustre (a physical
        // material where there is one).
        let core = *layers == Default::default();
        layered += usize::from(!core);
        let want = if core {
            "MeshStandardMaterial"
        } else {
            "MeshPhysicalMaterial"
        };
        assert_eq!(m["type"], want, "{v}");
        if !core {
            println!("{}: three.js {m}", out.display());
            assert!(close(&m["clearcoat"], layers.clearcoat), "{v}");
            assert!(close(&m["sheenRoughness"], layers.sheen_roughness), "{v}");
            assert!(close(&m["specularIntensity"], layers.specular), "{v}");
            if layers.has_clearcoat() {
                assert!(
                    close(&m["clearcoatRoughness"], layers.clearcoat_roughness),
                    "{v}"
                );
            }
            for c in 0..3 {
                assert!(close(&m["sheenColor"][c], layers.sheen_color.0[c]), "{v}");
                assert!(
                    close(&m["specularColor"][c], layers.specular_color.0[c]),
                    "{v}"
                );
            }
        }
        assert!(close(&m["metalness"], metallic.factor), "{v}");
        assert!(close(&m["roughness"], roughness.factor), "{v}");
        for c in 0..3 {
            assert!(close(&m["color"][c], base_color.factor.0[c]), "{v}");
        }
    }
    assert!(layered >= 1, "no exported material carries a glTF layer");

    // A bake's atlas (lightmap.glb) is glTF too: it passes the validator.
    let bake = dir.path().join("bake");
    ok(lustre()
        .arg("bake")
        .arg(lustre_brdf::shared_data_dir().join("scenes/cornell_box/cornell_box.obj"))
        .args(["--spp", "1", "--bounces", "1", "--texels-per-metre", "0.25"])
        .args(["--no-denoise", "--out"])
        .arg(&bake));
    validate(&[&bake.join("lightmap.glb")]);
    let atlas = three_load(&[&bake.join("lightmap.glb")]);
    assert_eq!(atlas[0]["meshes"].as_f64(), Some(7.0), "{atlas:?}");
}

#[test]
fn export_refuses_what_it_cannot_write() {
    let dir = tempfile::tempdir().expect("dir");
    for (spec, to, out, says) in [
        (
            "sgd:nickel",
            "gltf",
            "m.gltf",
            "a glTF (binary glTF) export is written as .glb",
        ),
        (
            "sgd:nickel",
            "mitsuba",
            "m.glb",
            "a Mitsuba (XML) export is written as .xml",
        ),
        (
            "nosuch-material",
            "gltf",
            "m.glb",
            "unknown material \"nosuch-material\"",
        ),
        ("sgd:nickel", "gltf", "nodir/m.glb", "no such folder"),
    ] {
        let t = fails(
            lustre()
                .args(["export", "material", spec, "--to", to, "--out"])
                .arg(dir.path().join(out)),
        );
        assert!(t.contains(says), "{t}");
    }
    // What the target model cannot carry is named, with what it costs.
    let t = ok(lustre()
        .args(["export", "material", "kurt-glass", "--out"])
        .arg(dir.path().join("glass.glb")));
    assert!(
        t.contains("kurt-glass transmits light; the exported material carries its reflection only"),
        "{t}"
    );
    assert!(t.contains("worse than lustre's GGX fit"), "{t}");
    // An anisotropic material exports with KHR_materials_anisotropy, fitted: three.js reads it
    // as a physical material with that strength and rotation, lustre renders it anisotropic.
    let brushed = dir.path().join("brushed.glb");
    let t = ok(lustre()
        .args(["export", "material", "kurt-demo", "--out"])
        .arg(&brushed));
    assert!(!t.contains("the exported model is isotropic"), "{t}");
    let strength = number_after(&t, "KHR_materials_anisotropy: strength ");
    let rotation = number_after(&t, ", rotation ");
    assert!(strength > 0.3, "{t}");
    // It fits the brushed metal better than lustre's own isotropic GGX fit.
    let gltf = number_after(&t, "  Ngan L2 ");
    let ggx = number_after(&t, "GGX fit of the same data: Ngan L2 ");
    assert!(gltf < ggx, "{t}");
    validate(&[&brushed]);
    let v = &three_load(&[&brushed])[0]["materials"][0];
    assert_eq!(v["type"], "MeshPhysicalMaterial", "{v}");
    assert!(
        (v["anisotropy"].as_f64().expect("anisotropy") - strength).abs() <= 5e-5,
        "{v}"
    );
    assert!((v["anisotropyRotation"].as_f64().expect("rotation") - rotation).abs() <= 5e-5);
    let scene = lustre_scene::Scene::load(&brushed).expect("reloads");
    let f = scene.materials[0]
        .bsdf_at(&scene.textures, &[glam::Vec2::ZERO; 2])
        .expect("bsdf");
    assert!(f.flags().anisotropic);
    // Mitsuba's rough conductor and plastic are isotropic: said so.
    let t = ok(lustre()
        .args([
            "export",
            "material",
            "kurt-demo",
            "--to",
            "mitsuba",
            "--out",
        ])
        .arg(dir.path().join("brushed.xml")));
    assert!(
        t.contains("kurt-demo is anisotropic; the exported model is isotropic"),
        "{t}"
    );
    // An existing file is replaced whole.
    let out = dir.path().join("m.glb");
    std::fs::write(&out, b"old").expect("write");
    ok(lustre()
        .args(["export", "material", "ggx(alpha=0.3)", "--out"])
        .arg(&out));
    let bytes = std::fs::read(&out).expect("read");
    assert!(bytes.starts_with(b"glTF"));
    assert_eq!(
        u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
        bytes.len()
    );
}

/// Direction pairs (wi, wo) over the upper hemisphere, the mirror configuration among them.
fn pairs() -> Vec<([f64; 3], [f64; 3])> {
    let dir = |t: f64, p: f64| {
        let (t, p) = (t.to_radians(), p.to_radians());
        [t.sin() * p.cos(), t.sin() * p.sin(), t.cos()]
    };
    let mut v = vec![];
    for ti in [5.0, 30.0, 55.0, 80.0] {
        for (to, po) in [(ti, 180.0), (20.0, 150.0), (45.0, 90.0), (70.0, 200.0)] {
            v.push((dir(ti, 0.0), dir(to, po)));
        }
    }
    v
}

/// Mitsuba 3's values of the BSDF in `xml` at `pairs` (tools/mitsuba/eval_bsdf.py; fails
/// without Mitsuba: `pip install mitsuba==3.9.1`).
fn mitsuba_eval(xml: &Path, pairs: &[([f64; 3], [f64; 3])]) -> Vec<[f64; 3]> {
    use std::io::Write;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/mitsuba/eval_bsdf.py");
    let mut child = Command::new("python3")
        .arg(&script)
        .arg(xml)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("python3 runs");
    let json = serde_json::to_string(&pairs.iter().map(|(a, b)| [a, b]).collect::<Vec<_>>())
        .expect("json");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(json.as_bytes())
        .expect("write");
    let o = child.wait_with_output().expect("runs");
    assert!(
        o.status.success(),
        "Mitsuba could not evaluate {}: {}",
        xml.display(),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("Mitsuba's values")
}

/// `a` and `b` agree within `rel` of the larger (and 1e-6 absolute); prints the largest
/// relative difference.
fn assert_close(what: &str, a: &[[f64; 3]], b: &[[f64; 3]], rel: f64) {
    let worst = a
        .iter()
        .zip(b)
        .flat_map(|(x, y)| {
            (0..3).map(move |c| (x[c] - y[c]).abs() / x[c].abs().max(y[c].abs()).max(1e-6))
        })
        .fold(0.0, f64::max);
    eprintln!("{what}: largest relative difference {worst:.2e}");
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            let tol = rel * x[c].abs().max(y[c].abs()) + 1e-6;
            assert!(
                (x[c] - y[c]).abs() <= tol,
                "{what}: pair {k} channel {c}: {} against {}",
                x[c],
                y[c]
            );
        }
    }
}

#[test]
fn mitsuba_exports_evaluate_alike_in_mitsuba_and_in_lustre() {
    use lustre_brdf::bsdf::Bsdf;
    let dir = tempfile::tempdir().expect("dir");
    let pairs = pairs();
    let lustre_eval = |b: &dyn Bsdf| -> Vec<[f64; 3]> {
        pairs
            .iter()
            .map(|(wi, wo)| b.eval(glam::DVec3::from(*wi), glam::DVec3::from(*wo)).0)
            .collect()
    };
    // A measured paint (a conductor fits it better) and a plastic (the plastic fits it).
    for (spec, plugin) in [
        ("nbrdf:gold-metallic-paint", "roughconductor"),
        (
            "roughplastic(diffuse_r=0.6,diffuse_g=0.3,diffuse_b=0.1,alpha=0.2,distribution=ggx)",
            "roughplastic",
        ),
    ] {
        let xml = dir.path().join(format!("{plugin}.xml"));
        let t = ok(lustre()
            .args(["export", "material", spec, "--to", "mitsuba", "--out"])
            .arg(&xml));
        assert!(t.contains(&format!("Mitsuba 3 {plugin} fit of")), "{t}");
        let lustre_spec = t
            .lines()
            .find_map(|l| l.trim().strip_prefix("in lustre: "))
            .expect("the lustre spec");
        let model = lustre_brdf::catalog::resolve(lustre_spec).expect("resolves");
        let ours = lustre_eval(model.as_ref());
        // Mitsuba's own evaluation of the file: f32 arithmetic (1e-4 of the value); its rough
        // plastic interpolates a precomputed table of the rough interface's transmittance
        // (1e-3).
        let tol = if plugin == "roughplastic" { 1e-3 } else { 1e-4 };
        assert_close(spec, &mitsuba_eval(&xml, &pairs), &ours, tol);
        // lustre's Mitsuba reader takes the BSDF back as it was fitted.
        let text = std::fs::read_to_string(&xml).expect("xml");
        let (start, end) = (
            text.find("<bsdf").expect("bsdf"),
            text.find("</scene>").expect("scene"),
        );
        let id = &text[text.find(" id=\"").expect("id") + 5..];
        let id = &id[..id.find('"').expect("quote")];
        let scene_xml = dir.path().join("scene.xml");
        std::fs::write(
            &scene_xml,
            format!(
                "<scene version=\"3.0.0\">{}<shape type=\"rectangle\"><ref id=\"{id}\"/></shape>\
                 </scene>",
                &text[start..end]
            ),
        )
        .expect("write");
        let scene = lustre_scene::Scene::load(&scene_xml).expect("reloads");
        let back = scene.materials[0]
            .bsdf_at(&scene.textures, &[glam::Vec2::ZERO; 2])
            .expect("bsdf");
        assert_close(spec, &lustre_eval(back.as_ref()), &ours, 1e-12);
    }
    // An RGL measurement is exported as itself: Mitsuba's `measured` beside a copy of the file.
    let rgl = lustre_brdf::shared_data_dir().join("measured/rgl/paper_white_rgb.bsdf");
    let xml = dir.path().join("rgl/paper.xml");
    std::fs::create_dir_all(dir.path().join("rgl")).expect("mkdir");
    let t = ok(lustre()
        .args(["export", "material"])
        .arg(&rgl)
        .args(["--to", "mitsuba", "--out"])
        .arg(&xml));
    assert!(t.contains("Mitsuba 3 measured BSDF"), "{t}");
    assert_eq!(
        std::fs::read(dir.path().join("rgl/paper_white_rgb.bsdf")).expect("copy"),
        std::fs::read(&rgl).expect("source")
    );
    let theirs = mitsuba_eval(&xml, &pairs);
    let ours = lustre_eval(
        lustre_brdf::catalog::resolve(&rgl.display().to_string())
            .expect("rgl")
            .as_ref(),
    );
    // lustre's RGL reader against Mitsuba's `measured` plugin (f32 tables).
    assert_close("paper_white_rgb.bsdf", &theirs, &ours, 1e-4);
}

/// Bakes `scene` quickly (full transport, 4 paths a texel, 8 texels per unit) into `out`.
fn quick_bake(scene: &Path, out: &Path) {
    ok(lustre()
        .arg("bake")
        .arg(scene)
        .args([
            "--transport",
            "full",
            "--spp",
            "4",
            "--texels-per-metre",
            "8",
            "--out",
        ])
        .arg(out));
}

/// Renders `scene` (camera `camera`) on the CPU at 96×54 into `out`; against `reference` when
/// given. The output.
fn cpu_frame(scene: &Path, camera: &str, out: &Path, reference: Option<&Path>) -> String {
    let mut c = lustre();
    c.arg("render")
        .arg(scene)
        .args([
            "--camera", camera, "--size", "96x54", "--device", "cpu", "--out",
        ])
        .arg(out);
    if let Some(r) = reference {
        c.arg("--compare-reference").arg(r);
    }
    ok(&mut c)
}

/// The glossy hits a frame's output printed.
fn glossy_hits(t: &str) -> f64 {
    number_after(t, "Regular with 16 samples: ")
}

/// The export and the baked scene it came from, read by lustre: the same meshes, hints, probes,
/// cameras, paths, film and environment, and materials that evaluate equal at every mesh's
/// first vertex (the textures travel as their original files, so exactly).
fn assert_reloads_unchanged(baked: &Path, glb: &Path) {
    let a = lustre_scene::Scene::load(baked).expect("baked scene");
    let b = lustre_scene::Scene::load(glb).expect("exported scene");
    assert_eq!(a.meshes.len(), b.meshes.len());
    let pairs: Vec<_> = pairs()
        .into_iter()
        .map(|(wi, wo)| (glam::DVec3::from(wi), glam::DVec3::from(wo)))
        .collect();
    let mut worst: f64 = 0.0;
    for (ma, mb) in a.meshes.iter().zip(&b.meshes) {
        assert_eq!(ma.name, mb.name);
        assert_eq!(ma.positions, mb.positions, "{}", ma.name);
        assert_eq!(ma.indices, mb.indices, "{}", ma.name);
        assert_eq!(ma.uv1, mb.uv1, "{}", ma.name);
        assert_eq!(ma.uv0.is_some(), mb.uv0.is_some(), "{}", ma.name);
        assert_eq!(ma.hints, mb.hints, "{}", ma.name);
        assert_eq!(ma.emission, mb.emission, "{}", ma.name);
        let (xa, xb) = (&a.materials[ma.material], &b.materials[mb.material]);
        assert_eq!(xa.name, xb.name);
        assert_eq!(xa.kind.name(), xb.kind.name(), "{}", xa.name);
        assert_eq!(xa.two_sided, xb.two_sided, "{}", xa.name);
        let uv = |m: &lustre_scene::Mesh| {
            [
                m.uv0.as_ref().map_or(glam::Vec2::ZERO, |u| u[0]),
                m.uv1.as_ref().map_or(glam::Vec2::ZERO, |u| u[0]),
            ]
        };
        let fa = xa.bsdf_at(&a.textures, &uv(ma)).expect("bsdf");
        let fb = xb.bsdf_at(&b.textures, &uv(mb)).expect("bsdf");
        for &(wi, wo) in &pairs {
            let (va, vb) = (fa.eval(wi, wo), fb.eval(wi, wo));
            for c in 0..3 {
                let d = (va.0[c] - vb.0[c]).abs() / (1e-3 + va.0[c].abs());
                worst = worst.max(d);
                // Within an 8-bit texture's quantisation.
                assert!(d <= 1.0 / 255.0, "{}: {va:?} vs {vb:?}", xa.name);
            }
        }
    }
    eprintln!("materials: largest relative difference {worst:.2e}");
    assert_eq!(a.probes, b.probes);
    assert_eq!(a.cameras, b.cameras);
    assert_eq!(a.camera_paths, b.camera_paths);
    assert_eq!(a.film, b.film);
    let (ea, eb) = (a.environment.as_ref(), b.environment.as_ref());
    assert_eq!(ea.is_some(), eb.is_some());
    if let (Some(ea), Some(eb)) = (ea, eb) {
        assert_eq!(ea.to_local, eb.to_local);
        assert_eq!(ea.intensity, eb.intensity);
        match (&ea.source, &eb.source) {
            // A Radiance .hdr's texels come back bit for bit from the embedded RGBE PNG.
            (
                lustre_scene::EnvironmentSource::Map { map: x, .. },
                lustre_scene::EnvironmentSource::Map { map: y, .. },
            ) => assert!(x == y, "the environment map changed"),
            (x, y) => assert_eq!(x, y),
        }
    }
    let lm = b.lightmap.as_ref().expect("the light map travels");
    assert_eq!(Some(&lm.atlas), a.lightmap.as_ref().map(|l| &l.atlas));
    assert!(!lm.embedded.is_empty() && lm.pages.is_empty());
}

/// The probe cube maps beside an exported glb are the probes lustre's renderer captures for the
/// baked scene (the same capture, face for face, texel for texel within the .hdr's RGBE
/// precision), listed in probes.json with their centres and bounding planes.
fn assert_probes_written(baked: &Path, glb: &Path, printed: &str) {
    use lustre_shade::probe::{capture_probes, LitScene, ProbeOptions};
    let b = lustre_trace::baked::BakedScene::load(baked).expect("baked");
    let (ps, _) = lustre_trace::reference::path_scene(&b.scene).expect("path scene");
    let bases = b
        .scene
        .materials
        .iter()
        .map(lustre_trace::bake::base_albedo)
        .collect();
    let lm = lustre_trace::bake::render::Lightmapped::new(
        &b.scene,
        &b.atlas,
        &b.pages,
        &ps.geometry,
        bases,
    )
    .expect("light maps");
    let pt = lustre_trace::path_tracer::PathTracer::new(&ps, Default::default()).expect("tracer");
    let lit = LitScene::new(&b.scene, &ps, &pt, &lm).expect("lit");
    let probes = capture_probes(&lit, &ProbeOptions::default(), &mut |_, _| {}).expect("probes");
    assert!(!probes.is_empty());
    assert!(
        printed.contains(&format!("probes: {} cube map(s) of 6 × 128²", probes.len())),
        "{printed}"
    );
    let dir = PathBuf::from(format!("{}.probes", glb.display()));
    let index: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("probes.json")).expect("json"))
            .expect("JSON");
    let list = index["probes"].as_array().expect("probes");
    assert_eq!(list.len(), probes.len());
    let mut worst: f64 = 0.0;
    for (p, entry) in probes.iter().zip(list) {
        assert_eq!(entry["name"], p.name.as_str());
        assert_eq!(entry["centre"].as_array().map(Vec::len), Some(3));
        for (i, c) in p.centre.to_array().iter().enumerate() {
            assert_eq!(entry["centre"][i].as_f64(), Some(*c));
        }
        assert_eq!(
            entry["planes"].as_array().map(Vec::len),
            Some(p.planes.len())
        );
        let cube = &p.pyramid.levels[0];
        for (f, face) in cube.faces.iter().enumerate() {
            let file = dir.join(entry["faces"][f].as_str().expect("face file"));
            let img = image::open(&file).expect("face").into_rgb32f();
            assert_eq!(
                (img.width() as usize, img.height() as usize),
                (cube.size, cube.size)
            );
            for (got, want) in img.pixels().zip(face) {
                let m = want.iter().fold(0f32, |a, &b| a.max(b));
                for c in 0..3 {
                    let d = f64::from((got.0[c] - want[c]).abs() / m.max(1e-6));
                    worst = worst.max(d);
                    assert!(d <= 1.0 / 128.0, "{}: {got:?} vs {want:?}", file.display());
                }
            }
        }
    }
    eprintln!(
        "{} probes: largest texel difference {worst:.2e} of the texel's largest channel",
        probes.len()
    );
}

/// Mean over the texels and channels of an EXR light-map page.
fn page_mean(exr: &Path) -> f64 {
    let img = image::open(exr).expect("page").into_rgb32f();
    let n = img.as_raw().len();
    img.as_raw().iter().map(|&v| f64::from(v)).sum::<f64>() / n as f64
}

/// three.js (GLTFLoader and a MOZ_lightmap plugin) in headless Chromium on `glb`: its report.
fn three_page(glb: &Path, png: &Path) -> serde_json::Value {
    let report = node_tool("three_page.mjs", &[glb, png]);
    eprintln!("{report}");
    serde_json::from_str(report.trim()).expect("JSON")
}

#[test]
fn a_baked_hall_exports_to_a_glb_that_validates_reloads_and_opens_in_three_js() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    // The Modern Hall from its own XML (the automatic real-time set-up decides its hints).
    let hall = lustre_brdf::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml");
    quick_bake(&hall, &d.join("bake"));
    let baked = d.join("bake/scene.toml");
    let glb = d.join("hall.glb");
    let t = ok(lustre()
        .args(["export", "scene"])
        .arg(&baked)
        .arg("--out")
        .arg(&glb));
    assert!(
        t.contains("32 meshes") && t.contains("through MOZ_lightmap") && t.contains("wrote"),
        "{t}"
    );
    // Materials glTF cannot say are named with what the glTF one leaves out.
    assert!(
        t.contains("Glass (dielectric): solid glass as glTF's thin-walled transmission"),
        "{t}"
    );
    validate(&[&glb]);
    assert_reloads_unchanged(&baked, &glb);
    assert_probes_written(&baked, &glb, &t);
    // The frames agree: the scene's camera, from the bake and from the export.
    let a = cpu_frame(&baked, "default", &d.join("a"), None);
    let b = cpu_frame(&glb, "default", &d.join("b"), Some(&d.join("a/frame.exr")));
    let psnr = number_after(&b, "PSNR ");
    eprintln!("Hall, baked vs exported: {psnr} dB");
    assert!(psnr >= 45.0, "{b}");
    assert_eq!(glossy_hits(&a), glossy_hits(&b), "{a}\n{b}");
    // three.js shows the light map: its page decodes to the baked irradiance, and the frame is
    // several times brighter with it than without.
    let r = three_page(&glb, &d.join("three.png"));
    let with = &r["with"];
    assert_eq!(with["meshes"].as_f64(), Some(32.0), "{r}");
    assert!(with["lightmapped"].as_f64().unwrap_or(0.0) >= 10.0, "{r}");
    assert_eq!(with["pages"][0]["encoding"], "rgbe", "{r}");
    let three_mean = with["pages"][0]["meanIrradiance"].as_f64().expect("mean");
    let baked_mean = page_mean(&d.join("bake/lightmap_000.exr"));
    assert!(
        (three_mean / baked_mean - 1.0).abs() <= 0.005,
        "three.js page mean {three_mean}, baked {baked_mean}"
    );
    let (lit, unlit) = (
        with["frameMean"].as_f64().expect("frame"),
        r["without"]["frameMean"].as_f64().expect("frame"),
    );
    assert!(lit >= 2.0 * unlit && lit > 0.05, "{r}");
    assert!(r["console"].as_array().is_some_and(Vec::is_empty), "{r}");
    assert!(
        std::fs::metadata(d.join("three.png"))
            .expect("capture")
            .len()
            > 1000
    );
}

#[test]
fn a_sunroom_exports_with_its_sky_cameras_and_camera_path() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    let sunroom = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sunroom/scene.xml");
    let scene = d.join("scene.toml");
    std::fs::write(
        &scene,
        format!(
            r#"schema = "lustre-scene"
version = 1
film = {{ width = 320, height = 180 }}

[[geometry]]
file = {:?}

[[camera]]
name = "corner"
position = [2.0, 1.4, 1.8]
look_at = [-1.0, 0.8, -1.0]
up = [0.0, 1.0, 0.0]
fov_deg = 60.0
fov_axis = "y"

[[camera_path]]
name = "walk"
looped = false
keyframes = [{{ time = 0.0, camera = "corner" }}, {{ time = 3.0, camera = "default" }}]
"#,
            sunroom.display().to_string()
        ),
    )
    .expect("write");
    quick_bake(&scene, &d.join("bake"));
    let baked = d.join("bake/scene.toml");
    let glb = d.join("sunroom.glb");
    // An existing file is replaced whole.
    std::fs::write(&glb, b"old").expect("write");
    let t = ok(lustre()
        .args(["export", "scene"])
        .arg(&baked)
        .arg("--out")
        .arg(&glb));
    assert!(
        t.contains("2 cameras, 1 camera paths as animations")
            && t.contains("environment map: embedded"),
        "{t}"
    );
    let names: Vec<_> = std::fs::read_dir(d)
        .expect("dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .collect();
    assert!(!names.iter().any(|n| n.contains(".tmp")), "{names:?}");
    validate(&[&glb]);
    assert_reloads_unchanged(&baked, &glb);
    for camera in ["default", "corner"] {
        let a = cpu_frame(&baked, camera, &d.join(format!("a-{camera}")), None);
        let b = cpu_frame(
            &glb,
            camera,
            &d.join(format!("b-{camera}")),
            Some(&d.join(format!("a-{camera}/frame.exr"))),
        );
        let psnr = number_after(&b, "PSNR ");
        eprintln!("sunroom {camera}, baked vs exported: {psnr} dB");
        assert!(psnr >= 45.0, "{b}");
        assert_eq!(glossy_hits(&a), glossy_hits(&b), "{a}\n{b}");
    }
    // three.js plays the path as an animation of its camera node.
    let r = three_page(&glb, &d.join("three.png"));
    let anim = &r["with"]["animations"][0];
    assert_eq!(anim["name"], "walk", "{r}");
    assert_eq!(anim["duration"].as_f64(), Some(3.0), "{r}");
    assert_eq!(anim["tracks"].as_f64(), Some(2.0), "{r}");
    assert_eq!(r["with"]["lightmapped"].as_f64(), Some(17.0), "{r}");
}

#[test]
fn scene_export_refuses_what_it_cannot_write() {
    let dir = tempfile::tempdir().expect("dir");
    let sunroom = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sunroom/scene.xml");
    // Not baked: refused, with the command that bakes it.
    let t = fails(
        lustre()
            .args(["export", "scene"])
            .arg(&sunroom)
            .arg("--out")
            .arg(dir.path().join("s.glb")),
    );
    assert!(t.contains("lustre bake"), "{t}");
    // A scene is one binary glTF.
    let t = fails(
        lustre()
            .args(["export", "scene"])
            .arg(&sunroom)
            .arg("--out")
            .arg(dir.path().join("s.gltf")),
    );
    assert!(t.contains("name it .glb"), "{t}");
    // An absurd probe size is refused before anything is written.
    let t = fails(
        lustre()
            .args(["export", "scene"])
            .arg(&sunroom)
            .args(["--probe-size", "0", "--out"])
            .arg(dir.path().join("s.glb")),
    );
    assert!(t.contains("probe face size 0"), "{t}");
    assert!(!dir.path().join("s.glb").exists() && !dir.path().join("s.gltf").exists());
}

/// An EXR's width, height and RGB values.
fn exr(path: &Path) -> (usize, usize, Vec<f64>) {
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    (w, h, img.into_raw().into_iter().map(f64::from).collect())
}

/// A Gaussian blur of σ pixels (edges clamped), which takes Monte-Carlo noise out of a
/// comparison of two renderers.
fn blur(w: usize, h: usize, a: &[f64], sigma: f64) -> Vec<f64> {
    let r = (3.0 * sigma) as isize;
    let k: Vec<f64> = (-r..=r)
        .map(|i| (-0.5 * (i as f64 / sigma).powi(2)).exp())
        .collect();
    let sum: f64 = k.iter().sum();
    let pass = |a: &[f64], dx: isize, dy: isize| -> Vec<f64> {
        let mut o = vec![0.0; a.len()];
        for y in 0..h as isize {
            for x in 0..w as isize {
                for c in 0..3 {
                    o[(y as usize * w + x as usize) * 3 + c] = k
                        .iter()
                        .enumerate()
                        .map(|(i, kk)| {
                            let d = i as isize - r;
                            let xx = (x + d * dx).clamp(0, w as isize - 1) as usize;
                            let yy = (y + d * dy).clamp(0, h as isize - 1) as usize;
                            kk * a[(yy * w + xx) * 3 + c]
                        })
                        .sum::<f64>()
                        / sum;
                }
            }
        }
        o
    };
    pass(&pass(a, 1, 0), 0, 1)
}

/// `(mean ratio, relative RMS)` of `img` against `reference` after a `sigma`-pixel blur.
fn against(img: &Path, reference: &Path, sigma: f64) -> (f64, f64) {
    let (w, h, a) = exr(img);
    let (w2, h2, b) = exr(reference);
    assert_eq!((w, h), (w2, h2));
    let (a, b) = if sigma > 0.0 {
        (blur(w, h, &a, sigma), blur(w, h, &b, sigma))
    } else {
        (a, b)
    };
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let rms = (a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt();
    (mean(&a) / mean(&b), rms / mean(&b))
}

/// Mitsuba 3 (pip, scalar_rgb) renders `scene` at `size` and `spp` into `out`.
fn mitsuba_render(scene: &Path, out: &Path, size: &str, spp: u32) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/mitsuba/render_scene.py");
    let o = Command::new("python3")
        .arg(script)
        .arg(scene)
        .arg(out)
        .args(["--size", size, "--spp", &spp.to_string()])
        .output()
        .expect("python3 runs");
    let t = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        o.status.success(),
        "Mitsuba 3 (pip install mitsuba==3.9.1): {t}"
    );
    eprintln!("{t}");
}

/// `lustre reference` of `scene` at `size` and `spp` into `out`.
fn reference(scene: &Path, out: &Path, size: &str, spp: u32) {
    ok(lustre()
        .arg("reference")
        .arg(scene)
        .args(["--size", size, "--spp", &spp.to_string(), "--out"])
        .arg(out));
}

#[test]
fn scenes_exported_to_mitsuba_render_alike_in_mitsuba_and_in_lustre() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    let hall = lustre_brdf::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml");
    let sunroom = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sunroom/scene.xml");
    for (name, scene, spp) in [("hall", &hall, 1024), ("sunroom", &sunroom, 512)] {
        let out = d.join(name);
        let t = ok(lustre()
            .args(["export", "scene"])
            .arg(scene)
            .args(["--to", "mitsuba", "--out"])
            .arg(&out));
        assert!(t.contains("wrote") && t.contains("OBJ"), "{t}");
        let xml = out.join("scene.xml");
        // lustre reads the folder back as the same scene: its reference is the original's,
        // sample for sample.
        reference(scene, &d.join(format!("{name}-a.exr")), "64x36", 16);
        reference(&xml, &d.join(format!("{name}-b.exr")), "64x36", 16);
        let (ratio, rms) = against(
            &d.join(format!("{name}-b.exr")),
            &d.join(format!("{name}-a.exr")),
            0.0,
        );
        assert!(
            (ratio - 1.0).abs() <= 1e-5 && rms <= 1e-4,
            "{name}: {ratio} {rms}"
        );
        // Mitsuba renders the folder as it is, as lustre's path tracer renders the original:
        // within 2 % after a 2-pixel blur, the mean within 1 %.
        mitsuba_render(&xml, &d.join(format!("{name}-mitsuba.exr")), "96x54", spp);
        reference(scene, &d.join(format!("{name}-lustre.exr")), "96x54", spp);
        let (ratio, rms) = against(
            &d.join(format!("{name}-mitsuba.exr")),
            &d.join(format!("{name}-lustre.exr")),
            2.0,
        );
        eprintln!(
            "{name}: Mitsuba 3 of the export against lustre reference of the original, \
             {spp} spp, 2-px blur: mean ratio {ratio:.4}, relative RMS {:.2} %",
            100.0 * rms
        );
        assert!((ratio - 1.0).abs() <= 0.01 && rms <= 0.02, "{name}");
    }
    // lustre's own materials (a published fit, an RGL measurement) become a fitted Mitsuba
    // model and Mitsuba's `measured` BSDF (the file copied), and Mitsuba loads the folder.
    let rgl: PathBuf = std::fs::read_dir(lustre_brdf::shared_data_dir().join("measured/rgl"))
        .expect("rgl data")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "bsdf"))
        .min()
        .expect("an RGL .bsdf file");
    let toml = d.join("specs.toml");
    std::fs::write(
        &toml,
        format!(
            "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = {:?}\n[materials]\n\
             Oak = \"sgd:nickel\"\nWalnut = {:?}\n",
            sunroom.display().to_string(),
            rgl.display().to_string()
        ),
    )
    .expect("write");
    let out = d.join("specs");
    let t = ok(lustre()
        .args(["export", "scene"])
        .arg(&toml)
        .args(["--to", "mitsuba", "--out"])
        .arg(&out));
    assert!(
        t.contains(
            "Oak (sgd:nickel): sgd:nickel as Mitsuba's roughconductor fitted to it: Ngan L2"
        ),
        "{t}"
    );
    assert!(
        t.contains("as Mitsuba's measured BSDF (no fit, no loss)"),
        "{t}"
    );
    let copied = out.join("textures").join(rgl.file_name().expect("name"));
    assert_eq!(std::fs::read(&copied).ok(), std::fs::read(&rgl).ok());
    mitsuba_render(&out.join("scene.xml"), &d.join("specs.exr"), "32x18", 4);
    // The folder is a folder.
    let file = d.join("file");
    std::fs::write(&file, b"x").expect("write");
    let t = fails(
        lustre()
            .args(["export", "scene"])
            .arg(&hall)
            .args(["--to", "mitsuba", "--out"])
            .arg(&file),
    );
    assert!(t.contains("a Mitsuba scene is a folder"), "{t}");
}
