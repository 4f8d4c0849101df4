//! Format features: Mitsuba's two spellings, transforms, shapes, `$var` defaults, the envmap
//! convention; the lustre scene file's round trip and what it builds.

mod common;

use glam::{DVec3, Vec3};
use lustre_scene::scene_file::{
    self, CameraEntry, CameraPathEntry, EmitterEntry, EnvironmentEntry, GeometryEntry,
    KeyframeEntry, SceneFile, ShapeKind,
};
use lustre_scene::{EnvironmentSource, FovAxis, MaterialKind, ObjectHints, Rgb, Scene, Sky};
use std::path::Path;

fn load_xml(dir: &Path, body: &str, version: &str) -> Scene {
    let text = format!("<scene version=\"{version}\">\n{body}\n</scene>");
    let p = dir.join(format!("s{}.xml", version.replace('.', "_")));
    std::fs::write(&p, text).unwrap();
    Scene::load(&p).unwrap()
}

/// The same scene written with Mitsuba 0.5's and 3.x's property names reads the same.
#[test]
fn mitsuba_spellings_agree() {
    let d = tempfile::tempdir().unwrap();
    let v05 = r#"
<sensor type="perspective"><float name="fov" value="45"/><string name="fovAxis" value="y"/>
  <transform name="toWorld"><lookat origin="0, 1, 5" target="0, 1, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="320"/><integer name="height" value="240"/></film>
</sensor>
<bsdf type="roughplastic" id="p"><float name="alpha" value="0.2"/><float name="intIOR" value="1.6"/>
  <rgb name="diffuseReflectance" value="0.1, 0.2, 0.3"/></bsdf>
<shape type="rectangle"><transform name="toWorld"><scale x="2" y="3"/><rotate x="1" angle="-90"/>
  <translate y="0.5"/></transform><ref id="p"/></shape>
<shape type="sphere"><point name="center" x="0" y="2" z="0"/><float name="radius" value="0.5"/>
  <bsdf type="roughconductor"><float name="alphaU" value="0.1"/><float name="alphaV" value="0.3"/>
  <rgb name="eta" value="0.2"/><rgb name="k" value="3"/><string name="distribution" value="ggx"/></bsdf>
  <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#;
    let v3 = r#"
<sensor type="perspective"><float name="fov" value="45"/><string name="fov_axis" value="y"/>
  <transform name="to_world"><lookat origin="0, 1, 5" target="0, 1, 0" up="0, 1, 0"/></transform>
  <film type="hdrfilm"><integer name="width" value="320"/><integer name="height" value="240"/></film>
</sensor>
<bsdf type="roughplastic" id="p"><float name="alpha" value="0.2"/><float name="int_ior" value="1.6"/>
  <rgb name="diffuse_reflectance" value="0.1, 0.2, 0.3"/></bsdf>
<shape type="rectangle"><transform name="to_world"><scale value="2, 3, 1"/><rotate value="1, 0, 0" angle="-90"/>
  <translate value="0, 0.5, 0"/></transform><ref id="p"/></shape>
<shape type="sphere"><point name="center" value="0, 2, 0"/><float name="radius" value="0.5"/>
  <bsdf type="roughconductor"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.3"/>
  <rgb name="eta" value="0.2"/><rgb name="k" value="3"/><string name="distribution" value="ggx"/></bsdf>
  <emitter type="area"><rgb name="radiance" value="4"/></emitter></shape>
<emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#;
    let a = load_xml(d.path(), v05, "0.5.0");
    let b = load_xml(d.path(), v3, "3.0.0");
    assert_eq!(a.meshes, b.meshes);
    assert_eq!(a.materials, b.materials);
    assert_eq!(a.cameras, b.cameras);
    assert_eq!(a.environment, b.environment);
    assert_eq!(a.film, b.film);
    assert!(
        a.warnings.is_empty() && b.warnings.is_empty(),
        "{:?} {:?}",
        a.warnings,
        b.warnings
    );
    // The rectangle: scaled to 4 × 6, turned from z = 0 to the floor plane y = 0.5, facing up.
    let rect = &a.meshes[0];
    assert!((rect.area() - 24.0).abs() < 1e-5);
    assert!(rect.positions.iter().all(|p| (p.y - 0.5).abs() < 1e-6));
    let [p0, p1, p2] = rect.triangle(0);
    assert!((p1 - p0).cross(p2 - p0).y > 0.0);
    // The sphere emits and has the documented tessellation, outward-facing.
    let sphere = &a.meshes[1];
    assert_eq!(sphere.emission, Some(Rgb::splat(4.0)));
    assert_eq!(sphere.triangle_count(), 2 * 64 * 31);
    assert!((sphere.area() - std::f64::consts::PI).abs() < 0.01 * std::f64::consts::PI);
    for t in 0..sphere.triangle_count() {
        let [p, q, r] = sphere.triangle(t);
        let centroid = (p + q + r) / 3.0 - Vec3::new(0.0, 2.0, 0.0);
        assert!(
            (q - p).cross(r - p).dot(centroid) > 0.0,
            "triangle {t} faces inwards"
        );
    }
    match &a.materials[1].kind {
        MaterialKind::RoughConductor {
            alpha_u, alpha_v, ..
        } => {
            assert_eq!((alpha_u.factor, alpha_v.factor), (0.1, 0.3))
        }
        k => panic!("{k:?}"),
    }
    let cam = &a.cameras[0];
    assert_eq!((cam.fov_deg, cam.fov_axis), (45.0, FovAxis::Y));
    assert!((cam.forward - DVec3::NEG_Z).length() < 1e-12 && (cam.up - DVec3::Y).length() < 1e-12);
    assert_eq!(
        a.environment.as_ref().unwrap().radiance(DVec3::X),
        Rgb::splat(0.5)
    );
}

#[test]
fn mitsuba_defaults_and_variables() {
    let d = tempfile::tempdir().unwrap();
    let body = r#"<default name="alb" value="0.25"/>
<shape type="cube"><bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="$alb, $alb, 0.5"/></bsdf></bsdf></shape>
<shape type="disk"><bsdf type="dielectric"><string name="intIOR" value="water"/></bsdf></shape>
<shape type="disk"><bsdf type="bumpmap"><texture type="bitmap"><string name="filename" value="x.png"/></texture>
  <bsdf type="diffuse"/></bsdf></shape>"#;
    let s = load_xml(d.path(), body, "0.5.0");
    assert_eq!(s.meshes[0].triangle_count(), 12);
    assert!((s.meshes[0].area() - 24.0).abs() < 1e-5);
    let m = &s.materials[s.meshes[0].material];
    assert!(m.two_sided);
    assert_eq!(
        m.kind,
        MaterialKind::Diffuse {
            reflectance: lustre_scene::TexturedRgb::constant(Rgb::new(0.25, 0.25, 0.5))
        }
    );
    match &s.materials[s.meshes[1].material].kind {
        MaterialKind::Dielectric {
            int_ior, ext_ior, ..
        } => {
            assert_eq!((*int_ior, *ext_ior), (1.333, 1.000277))
        }
        k => panic!("{k:?}"),
    }
    // The bumpmap is read through with a warning naming it (its texture is not opened).
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("bumpmap ignored") && s.warnings[0].contains("line 5"));
    // A property that is not used is a named warning.
    let s = load_xml(
        d.path(),
        "<shape type=\"disk\"><bsdf type=\"diffuse\"><float name=\"sheen\" value=\"1\"/></bsdf></shape>",
        "3.0.0",
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("\"sheen\" ignored")),
        "{:?}",
        s.warnings
    );
}

/// Mitsuba's envmap reads u = atan2(d.x, −d.z)/2π, lustre's equirect half a turn further: the
/// converted environment returns, for world direction +x, the texel lustre stores at −x.
#[test]
fn mitsuba_envmap_is_converted_to_lustre_convention() {
    let d = tempfile::tempdir().unwrap();
    let map = common::data().join("envmaps/venice_sunset_1k.hdr");
    let body = format!(
        // A sphere for it to light: a scene with no geometry is refused.
        "<shape type=\"sphere\"/><emitter type=\"envmap\"><string name=\"filename\" value=\"{}\"/><float name=\"scale\" value=\"2\"/></emitter>",
        map.display()
    );
    let s = load_xml(d.path(), &body, "0.5.0");
    let env = s.environment.unwrap();
    let EnvironmentSource::Map { map: m, .. } = &env.source else {
        panic!()
    };
    for (world, stored) in [
        (DVec3::X, DVec3::NEG_X),
        (DVec3::NEG_Z, DVec3::Z),
        (DVec3::new(0.3, 0.5, 0.8), DVec3::new(-0.3, 0.5, -0.8)),
    ] {
        let got = env.radiance(world);
        let want = Rgb(m.lookup_bilinear(stored)) * 2.0;
        assert!(
            (got - want).max_component().abs() < 1e-9 * want.max_component().max(1.0),
            "{world}"
        );
    }
    // The world-oriented equirect of a constant environment is constant.
    let c = lustre_scene::Environment::constant(Rgb::splat(0.7));
    let e = c.to_world_equirect(16);
    assert_eq!((e.width, e.height), (16, 8));
    assert!(e.data.iter().all(|p| *p == [0.7f32; 3]));
}

fn full_file() -> SceneFile {
    let mut f = SceneFile::new();
    f.film = Some(lustre_scene::Film {
        width: 640,
        height: 360,
    });
    f.geometry.push(GeometryEntry {
        file: "mitsuba/scene.xml".into(),
        transform: None,
    });
    f.environment = Some(EnvironmentEntry {
        map: None,
        constant: None,
        sky: Some(Sky::default()),
        rotation_deg: 30.0,
        intensity: 0.5,
    });
    f.cameras.push(CameraEntry {
        name: "stairs".into(),
        position: [0.0, 1.5, 0.0],
        look_at: Some([-3.0, 1.0, 0.0]),
        forward: None,
        up: [0.0, 1.0, 0.0],
        fov_deg: 60.0,
        fov_axis: FovAxis::Y,
    });
    f.camera_paths.push(CameraPathEntry {
        name: "walk".into(),
        looped: true,
        keyframes: vec![
            KeyframeEntry {
                time: 0.0,
                camera: "default".into(),
            },
            KeyframeEntry {
                time: 4.0,
                camera: "stairs".into(),
            },
        ],
    });
    f.materials.insert("Wood".into(), "sgd:pink-fabric".into());
    f.materials.insert("Wall".into(), "lambert(kd=0.7)".into());
    f.material_params
        .insert("Wall.spec.kd".into(), "0.6".into());
    f.emitters.push(EmitterEntry {
        object: None,
        shape: Some(ShapeKind::Rectangle),
        transform: Some([
            0.5, 0.0, 0.0, -2.0, 0.0, 0.0, -0.5, 5.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ]),
        radiance: [3.0, 3.0, 3.0],
    });
    f.emitters.push(EmitterEntry {
        object: Some("Mesh018".into()),
        shape: None,
        transform: None,
        radiance: [0.1, 0.2, 0.3],
    });
    f.objects.insert(
        "Mesh011".into(),
        ObjectHints {
            planar_reflector: true,
            lightmap_texels_per_metre: Some(64.0),
            ..Default::default()
        },
    );
    f.objects.insert(
        "Mesh018".into(),
        ObjectHints {
            probe: true,
            probe_centre: Some([0.5, 2.25, -1.0]),
            diffuse_only: true,
            ..Default::default()
        },
    );
    f.probes.push(lustre_scene::ProbeSite {
        name: "hall".into(),
        centre: [0.0, 2.0, 0.0],
        box_min: Some([-5.0, 0.0, -4.0]),
        box_max: Some([5.0, 6.0, 4.0]),
    });
    f.probes.push(lustre_scene::ProbeSite {
        name: "landing".into(),
        centre: [-1.8, 5.2, -1.5],
        box_min: None,
        box_max: None,
    });
    f
}

#[test]
fn scene_file_round_trip() {
    let d = tempfile::tempdir().unwrap();
    let f = full_file();
    let p = d.path().join("a.toml");
    scene_file::write(&p, &f).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    let back = scene_file::parse(&p, &text).unwrap();
    assert_eq!(back, f);
    // And again: the written text is stable.
    assert_eq!(back.to_toml().unwrap(), text);
    // A probe centre that is not finite, or without a probe, is refused by name.
    for (probe, centre, says) in [
        (
            true,
            [0.0, f64::INFINITY, 0.0],
            "objects.Mesh018.probe_centre",
        ),
        (false, [0.0, 1.0, 0.0], "probe_centre without probe"),
    ] {
        let mut bad = f.clone();
        let h = bad.objects.get_mut("Mesh018").unwrap();
        h.probe = probe;
        h.probe_centre = Some(centre);
        let e = bad.validate().unwrap_err();
        assert!(e.contains(says), "{e}");
    }
    // Room probes: a name given twice, a box without its other corner, a centre outside its
    // box, each refused by name.
    let mut twice = f.clone();
    twice.probes[1].name = "hall".into();
    assert!(twice
        .validate()
        .unwrap_err()
        .contains("\"hall\" is given twice"));
    let mut half = f.clone();
    half.probes[0].box_max = None;
    assert!(half.validate().unwrap_err().contains("go together"));
    let mut out = f.clone();
    out.probes[0].centre = [0.0, 7.0, 0.0];
    assert!(out.validate().unwrap_err().contains("outside its box"));
    // An invalid file is not written.
    let mut bad = f.clone();
    bad.cameras[0].fov_deg = f64::NAN;
    let q = d.path().join("b.toml");
    assert!(scene_file::write(&q, &bad)
        .unwrap_err()
        .to_string()
        .contains("fov_deg"));
    assert!(!q.exists());
}

/// A scene file over the Modern Hall: overrides, cameras, paths, emitters and hints land where
/// they should.
#[test]
fn scene_file_builds_the_modern_hall() {
    let hall = common::data().join("scenes/modern_hall");
    let p = hall.join("lustre-test.toml");
    let f = full_file();
    let s = scene_file::build(&p, &f).unwrap();
    let xml = Scene::load(&common::hall_xml()).unwrap();
    assert_eq!(s.triangle_count(), xml.triangle_count() + 2);
    assert_eq!(s.emitters().len(), xml.emitters().len() + 2);
    assert_eq!((s.film.width, s.film.height), (640, 360));
    let wood = &s.materials[s.material_index("Wood").unwrap()];
    match &wood.kind {
        MaterialKind::Spec(r) => assert_eq!(r.spec, "sgd:pink-fabric"),
        k => panic!("{k:?}"),
    }
    assert!(
        wood.two_sided,
        "the override keeps the Mitsuba twosided flag"
    );
    // [material_params] apply after the overrides: the Wall's lambert(kd=0.7) at kd 0.6.
    let wall = &s.materials[s.material_index("Wall").unwrap()];
    match &wall.kind {
        MaterialKind::Spec(r) => assert_eq!(r.spec, "lambert(kd=0.6)"),
        k => panic!("{k:?}"),
    }
    let mut bad = f.clone();
    bad.material_params
        .insert("Nope.alpha".into(), "0.1".into());
    let e = scene_file::build(&p, &bad).unwrap_err().to_string();
    assert!(e.contains("material_params") && e.contains("Nope"), "{e}");
    let brdf = wood.bsdf_at(&s.textures, &[glam::Vec2::ZERO; 2]).unwrap();
    assert!(brdf.eval(DVec3::Z, DVec3::Z).max_component() > 0.0);
    let m011 = s.meshes.iter().find(|m| m.name == "Mesh011").unwrap();
    assert!(m011.hints.planar_reflector && m011.hints.lightmap_texels_per_metre == Some(64.0));
    let m018 = s.meshes.iter().find(|m| m.name == "Mesh018").unwrap();
    assert!(m018.hints.probe && m018.hints.diffuse_only);
    let names: Vec<&str> = s.probes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["hall", "landing"], "the room probes");
    assert_eq!(m018.emission, Some(Rgb::new(0.1, 0.2, 0.3)));
    // The added rectangle: 1 × 1 m at y = 5 facing down.
    let added = s.meshes.last().unwrap();
    assert!((added.area() - 1.0).abs() < 1e-6);
    let [a, b, c] = added.triangle(0);
    assert!((b - a).cross(c - a).y < 0.0 && (a.y - 5.0).abs() < 1e-6);
    // Cameras: the XML's, then the file's; the path runs between them.
    assert_eq!(s.cameras.len(), 2);
    let path = &s.camera_paths[0];
    let start = path.at(0.0).unwrap();
    // Looped: time 4 wraps to 0, so the end is read from the keyframe.
    assert!((path.at(4.0).unwrap().position - start.position).length() < 1e-12);
    let end = path.keyframes[1].camera.clone();
    assert!((start.position - s.cameras[0].position).length() < 1e-12);
    assert!((end.position - DVec3::new(0.0, 1.5, 0.0)).length() < 1e-12);
    let mid = path.at(2.0).unwrap();
    assert!((mid.position - (start.position + end.position) / 2.0).length() < 1e-9);
    assert!((mid.forward.length() - 1.0).abs() < 1e-9 && mid.forward.dot(mid.up).abs() < 1e-9);
    // Looped: time 6 is time 2.
    assert!((path.at(6.0).unwrap().position - mid.position).length() < 1e-9);
    // The sky, rotated and scaled.
    let env = s.environment.as_ref().unwrap();
    assert_eq!(env.radiance(DVec3::Y), Rgb(Sky::default().zenith) * 0.5);
    assert_eq!(env.radiance(DVec3::NEG_Y), Rgb(Sky::default().ground) * 0.5);
}

/// The fuzz seed's quad (its material opaque) with material extensions `ext` added and listed
/// as used, read.
fn quad_with(ext: serde_json::Value) -> lustre_scene::Result<lustre_scene::Scene> {
    let seed =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/gltf/quad_embedded.gltf");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&seed).expect("seed")).expect("JSON");
    doc["materials"][0]["extensions"]["KHR_materials_transmission"]["transmissionFactor"] =
        serde_json::json!(0.0);
    for (k, v) in ext.as_object().expect("object") {
        doc["materials"][0]["extensions"][k] = v.clone();
        doc["extensionsUsed"]
            .as_array_mut()
            .expect("list")
            .push(serde_json::json!(k));
    }
    lustre_scene::gltf_io::from_slice(
        Path::new("/nonexistent/quad.gltf"),
        doc.to_string().as_bytes(),
    )
}

/// `KHR_materials_anisotropy` is read and rendered: the material's BSDF is the glTF model with
/// α_t = mix(α, 1, s²) along the rotated tangent, not the isotropic one.
#[test]
fn gltf_anisotropy_is_read_and_rendered() {
    use lustre_brdf::models::pbr_metallic_roughness::PbrMetallicRoughness;
    use lustre_brdf::Bsdf;
    let scene = quad_with(serde_json::json!({
        "KHR_materials_anisotropy": { "anisotropyStrength": 0.7, "anisotropyRotation": 0.4 },
    }))
    .expect("reads");
    let f = scene.materials[0]
        .bsdf_at(&scene.textures, &[glam::Vec2::ZERO; 2])
        .expect("bsdf");
    assert!(f.flags().anisotropic);
    // KHR_materials_ior sets the dielectric's F0 too.
    let lustre_scene::MaterialKind::PbrMetallicRoughness { ior, .. } = &scene.materials[0].kind
    else {
        panic!("{:?}", scene.materials[0].kind)
    };
    let c = lustre_scene::Rgb([0.8f32, 0.2, 0.2].map(f64::from));
    let core = PbrMetallicRoughness::new(c, f64::from(0.1f32), f64::from(0.4f32))
        .and_then(|m| m.with_layers(*ior, Default::default()))
        .expect("model");
    let want = core.with_anisotropy(0.7, 0.4).expect("model");
    let iso = core;
    let wo = glam::DVec3::new(0.3, 0.2, 0.93).normalize();
    let mut differs = false;
    for k in 0..16 {
        let phi = k as f64 * std::f64::consts::TAU / 16.0;
        let wi = glam::DVec3::new(0.5 * phi.cos(), 0.5 * phi.sin(), 0.866).normalize();
        let (got, w) = (f.eval(wi, wo), want.eval(wi, wo));
        for ch in 0..3 {
            assert!(
                (got.0[ch] - w.0[ch]).abs() <= 1e-12 * (1.0 + w.0[ch]),
                "{got:?} {w:?}"
            );
        }
        differs |= (iso.eval(wi, wo).0[0] - got.0[0]).abs() > 1e-3 * got.0[0];
    }
    assert!(differs, "the anisotropic lobe is not the isotropic one");
}

/// `KHR_materials_specular`, `_clearcoat` and `_sheen` are read and rendered (the material's
/// BSDF is the layered glTF model); their textures are named in warnings; a factor out of range
/// or of the wrong type is refused naming it.
#[test]
fn gltf_specular_clearcoat_and_sheen_are_read_and_rendered() {
    use lustre_brdf::models::pbr_metallic_roughness::{PbrLayers, PbrMetallicRoughness};
    use lustre_brdf::Bsdf;
    let scene = quad_with(serde_json::json!({
        "KHR_materials_specular": { "specularFactor": 0.5, "specularColorFactor": [2.0, 1.0, 0.5] },
        "KHR_materials_clearcoat": { "clearcoatFactor": 0.9, "clearcoatRoughnessFactor": 0.1,
                                     "clearcoatTexture": { "index": 0 } },
        "KHR_materials_sheen": { "sheenColorFactor": [0.3, 0.2, 0.1], "sheenRoughnessFactor": 0.6 },
    }))
    .expect("reads");
    let layers = PbrLayers {
        specular: 0.5,
        specular_color: lustre_scene::Rgb([2.0, 1.0, 0.5]),
        clearcoat: 0.9,
        clearcoat_roughness: 0.1,
        sheen_color: lustre_scene::Rgb([0.3, 0.2, 0.1]),
        sheen_roughness: 0.6,
    };
    let lustre_scene::MaterialKind::PbrMetallicRoughness {
        layers: got, ior, ..
    } = &scene.materials[0].kind
    else {
        panic!("{:?}", scene.materials[0].kind)
    };
    assert_eq!(*got, layers);
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("clearcoatTexture ignored")),
        "{:?}",
        scene.warnings
    );
    let f = scene.materials[0]
        .bsdf_at(&scene.textures, &[glam::Vec2::ZERO; 2])
        .expect("bsdf");
    let c = lustre_scene::Rgb([0.8f32, 0.2, 0.2].map(f64::from));
    let want = PbrMetallicRoughness::new(c, f64::from(0.1f32), f64::from(0.4f32))
        .and_then(|m| m.with_layers(*ior, layers))
        .expect("model");
    let core = PbrMetallicRoughness::new(c, f64::from(0.1f32), f64::from(0.4f32))
        .and_then(|m| m.with_layers(*ior, PbrLayers::default()))
        .expect("model");
    let wo = glam::DVec3::new(0.3, 0.2, 0.93).normalize();
    for k in 0..16 {
        let phi = k as f64 * std::f64::consts::TAU / 16.0;
        let wi = glam::DVec3::new(0.9 * phi.cos(), 0.9 * phi.sin(), 0.436).normalize();
        let (got, w) = (f.eval(wi, wo), want.eval(wi, wo));
        for ch in 0..3 {
            assert!(
                (got.0[ch] - w.0[ch]).abs() <= 1e-12 * (1.0 + w.0[ch]),
                "{got:?} {w:?}"
            );
        }
        assert!((core.eval(wi, wo).0[0] - got.0[0]).abs() > 1e-3 * got.0[0]);
    }
    for (ext, what) in [
        (
            serde_json::json!({ "KHR_materials_clearcoat": { "clearcoatFactor": 1.5 } }),
            "clearcoatFactor",
        ),
        (
            serde_json::json!({ "KHR_materials_sheen": { "sheenColorFactor": [0.1, 0.2] } }),
            "sheenColorFactor",
        ),
        (
            serde_json::json!({ "KHR_materials_specular": { "specularFactor": "x" } }),
            "specularFactor",
        ),
        (
            serde_json::json!({ "KHR_materials_specular": { "specularColorFactor": [-1.0, 1.0, 1.0] } }),
            "specularColorFactor",
        ),
    ] {
        let e = quad_with(ext).expect_err("refused").to_string();
        assert!(e.contains(what), "{e}");
    }
}
