//! The real scenes of ../shared/data: Modern Hall (Mitsuba XML and its glTF conversion) and the
//! Cornell box (OBJ/MTL). Counts, cameras, materials as the data README documents them,
//! emitters, textures.

mod common;

use glam::DVec3;
use lustre_scene::{FovAxis, MaterialKind, Scene};

/// README: 31,247 triangles, of which 2,432 in Mesh000 (2,327) and Mesh009 (105) have zero area
/// (repeated coordinates); they are dropped and counted.
const HALL_TRIANGLES: usize = 31_247;
const HALL_DEGENERATE: usize = 2_432;

/// Loaded once per test binary (building the rough-plastic coating tables dominates).
fn hall_xml() -> &'static Scene {
    static S: std::sync::OnceLock<Scene> = std::sync::OnceLock::new();
    S.get_or_init(|| Scene::load(&common::hall_xml()).expect("modern hall XML loads"))
}

fn hall_gltf() -> &'static Scene {
    static S: std::sync::OnceLock<Scene> = std::sync::OnceLock::new();
    S.get_or_init(|| Scene::load(&common::hall_gltf()).expect("modern hall glTF loads"))
}

#[test]
fn hall_xml_counts() {
    let s = hall_xml();
    assert_eq!(
        s.triangle_count() + s.stats.degenerate_triangles,
        HALL_TRIANGLES
    );
    assert_eq!(s.stats.degenerate_triangles, HALL_DEGENERATE);
    // 19 OBJ shapes, 5 disks, 8 rectangles.
    assert_eq!(s.meshes.len(), 32);
    // 8 named BSDFs + the emitters' black diffuse (shared by the 13 emitters).
    assert_eq!(s.materials.len(), 9);
    assert_eq!(s.emitters().len(), 13);
    assert_eq!(s.textures.len(), 3);
    assert_eq!((s.film.width, s.film.height), (1280, 720));
    assert!(s.environment.is_none());
    assert_eq!(s.warnings.len(), 2, "{:#?}", s.warnings);
    assert!(s.warnings.iter().all(|w| w.contains("degenerate")));
    // 5 disks of 64 triangles and 8 rectangles of 2.
    let analytic: usize = s
        .meshes
        .iter()
        .filter(|m| m.name.starts_with("disk@") || m.name.starts_with("rectangle@"))
        .map(|m| m.triangle_count())
        .sum();
    assert_eq!(analytic, 5 * 64 + 8 * 2);
}

#[test]
fn hall_xml_materials() {
    let s = hall_xml();
    let get = |n: &str| &s.materials[s.material_index(n).unwrap()];
    match &get("Wood").kind {
        MaterialKind::RoughPlastic {
            diffuse,
            alpha,
            distribution,
            int_ior,
            ext_ior,
            nonlinear,
            ..
        } => {
            assert!(diffuse.texture.is_some());
            assert_eq!(alpha.factor, 0.1);
            assert_eq!(*distribution, lustre_scene::MicrofacetType::Ggx);
            assert_eq!((*int_ior, *ext_ior, *nonlinear), (1.5, 1.0, true));
        }
        k => panic!("Wood is {k:?}"),
    }
    assert!(get("Wood").two_sided);
    match &get("Metal").kind {
        MaterialKind::RoughConductor {
            eta,
            k,
            alpha_u,
            alpha_v,
            ..
        } => {
            // eta and k relative to Mitsuba's air (1.000277).
            assert!((eta[0] - 1.65746 / 1.000277).abs() < 1e-9);
            assert!((k[2] - 4.837 / 1.000277).abs() < 1e-9);
            assert_eq!((alpha_u.factor, alpha_v.factor), (0.1, 0.1));
        }
        k => panic!("Metal is {k:?}"),
    }
    match &get("Glass").kind {
        MaterialKind::Dielectric {
            int_ior, ext_ior, ..
        } => {
            assert_eq!((*int_ior, *ext_ior), (1.5, 1.0))
        }
        k => panic!("Glass is {k:?}"),
    }
    assert!(!get("Glass").two_sided);
    match &get("Wall").kind {
        MaterialKind::Diffuse { reflectance } => {
            assert_eq!(reflectance.factor[1], 0.893289);
            assert!(reflectance.texture.is_none());
        }
        k => panic!("Wall is {k:?}"),
    }
}

#[test]
fn hall_gltf_counts() {
    let s = hall_gltf();
    assert_eq!(
        s.triangle_count() + s.stats.degenerate_triangles,
        HALL_TRIANGLES
    );
    assert_eq!(s.stats.degenerate_triangles, HALL_DEGENERATE);
    assert_eq!(s.meshes.len(), 32);
    assert_eq!(s.materials.len(), 12);
    assert_eq!(s.emitters().len(), 13);
    assert_eq!(s.textures.len(), 3);
    assert_eq!((s.film.width, s.film.height), (1280, 720));
}

/// The glTF conversion has the XML's geometry: same bounds, same emitter power (Σ L·A per
/// channel), and the ceiling disks emit downwards in both.
#[test]
fn hall_gltf_matches_xml_geometry() {
    let (x, g) = (hall_xml(), hall_gltf());
    let (xb, gb) = (x.bounds().unwrap(), g.bounds().unwrap());
    assert!((xb.0 - gb.0).abs().max_element() < 1e-4 && (xb.1 - gb.1).abs().max_element() < 1e-4);
    let power = |s: &Scene| -> [f64; 3] {
        let mut p = [0.0; 3];
        for m in s.meshes.iter() {
            if let Some(e) = m.emission {
                for c in 0..3 {
                    p[c] += e[c] * m.area();
                }
            }
        }
        p
    };
    let (px, pg) = (power(x), power(g));
    for c in 0..3 {
        assert!((px[c] - pg[c]).abs() < 1e-4 * px[c], "{px:?} vs {pg:?}");
    }
    for s in [x, g] {
        // Emitters at the ceiling (y ≈ 5.61) face down.
        let mut ceiling = 0;
        for m in s.meshes.iter().filter(|m| m.emission.is_some()) {
            let [a, b, c] = m.triangle(0);
            if (a.y - 5.61029).abs() < 1e-3 && m.triangle_count() == 64 {
                let n = (b - a).cross(c - a);
                assert!(n.y < 0.0, "{}: normal {n:?}", m.name);
                ceiling += 1;
            }
        }
        // The XML's disks; the glTF's disks are the same tessellation.
        assert_eq!(ceiling, 5);
    }
}

/// The camera of the XML and of the glTF conversion agree (README: fov 70° along x, film
/// 1280×720; glTF yfov 0.7504 rad at aspect 16:9).
#[test]
fn hall_camera_matches_between_xml_and_gltf() {
    let (x, g) = (hall_xml(), hall_gltf());
    let (cx, cg) = (x.camera(None).unwrap(), g.camera(None).unwrap());
    assert_eq!((cx.fov_deg, cx.fov_axis), (70.0, FovAxis::X));
    assert_eq!(cg.fov_axis, FovAxis::Y);
    assert!((cx.position - DVec3::new(6.91182, 1.65163, 2.55414)).length() < 1e-9);
    assert!((cx.position - cg.position).length() < 1e-6);
    assert!((cx.forward - cg.forward).length() < 1e-6);
    assert!((cx.up - cg.up).length() < 1e-6);
    let aspect = 1280.0 / 720.0;
    assert!((cx.fov_y_deg(aspect) - cg.fov_y_deg(aspect)).abs() < 1e-5);
    assert!((cg.fov_y_deg(aspect) - 0.7504158558301225f64.to_degrees()).abs() < 1e-5);
    // On the reference's square film the XML camera spans 70° both ways.
    assert!((cx.fov_y_deg(1.0) - 70.0).abs() < 1e-12);
    // Centre ray = forward; the right edge at 35° from it.
    let d = cx.ray_direction(512.0, 512.0, 1024, 1024);
    assert!((d - cx.forward).length() < 1e-12);
    let e = cx.ray_direction(1024.0, 512.0, 1024, 1024);
    assert!((e.dot(cx.forward).acos().to_degrees() - 35.0).abs() < 1e-9);
}

/// glTF materials map as the data README says: diffuse → roughness 1, (rough)plastic →
/// roughness = √α, conductor → metallic 1, dielectric → transmission 1 and ior 1.5, emitters
/// → emission = radiance; all double-sided.
#[test]
fn hall_gltf_materials_map_as_documented() {
    let (x, g) = (hall_xml(), hall_gltf());
    for m in &g.materials {
        assert!(m.two_sided, "{}", m.name);
        let MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ior,
            ..
        } = &m.kind
        else {
            panic!("{} is {:?}", m.name, m.kind);
        };
        let Some(xi) = x.material_index(&m.name) else {
            assert!(m.name.starts_with("Emitter"), "{}", m.name);
            assert_eq!(base_color.factor, lustre_scene::Rgb::ZERO);
            continue;
        };
        match &x.materials[xi].kind {
            MaterialKind::Diffuse { reflectance } => {
                assert_eq!((metallic.factor, roughness.factor), (0.0, 1.0));
                assert_eq!(reflectance.texture.is_some(), base_color.texture.is_some());
                if reflectance.texture.is_none() {
                    assert!((reflectance.factor[0] - base_color.factor[0]).abs() < 1e-6);
                }
            }
            MaterialKind::RoughPlastic { alpha, .. } => {
                assert_eq!(metallic.factor, 0.0);
                assert!((roughness.factor - alpha.factor.sqrt()).abs() < 1e-6);
                assert!(base_color.texture.is_some());
            }
            MaterialKind::RoughConductor { .. } => assert_eq!(metallic.factor, 1.0),
            MaterialKind::Dielectric { int_ior, .. } => {
                assert_eq!(transmission.factor, 1.0);
                assert!((ior - int_ior).abs() < 1e-6);
            }
            k => panic!("unexpected XML material {k:?}"),
        }
    }
}

/// The three JPEG textures decode (sRGB → linear) to sane sizes and means, and the XML and the
/// glTF read the same pixels.
#[test]
fn hall_textures_load() {
    let (x, g) = (hall_xml(), hall_gltf());
    for t in &x.textures {
        assert!(t.width >= 256 && t.height >= 256, "{:?}", t.source);
        assert_eq!(t.channels, 3);
        let mean = t.mean();
        let luminance = 0.2126 * mean[0] + 0.7152 * mean[1] + 0.0722 * mean[2];
        assert!(
            luminance > 0.02 && luminance < 0.9,
            "{:?}: {mean:?}",
            t.source
        );
        assert_eq!(t.color_space, lustre_scene::ColorSpace::Srgb);
        // The same bytes read as data: the colour texture is their sRGB decoding.
        let raw =
            lustre_scene::Texture::read(&t.source, &t.source, lustre_scene::ColorSpace::Linear)
                .unwrap();
        for (a, b) in raw.data.iter().zip(&t.data).step_by(997) {
            assert!((lustre_scene::texture::srgb_to_linear(*a) - b).abs() < 1e-6);
        }
        let name = t.source.file_name().unwrap();
        let other = g
            .textures
            .iter()
            .find(|o| o.source.file_name() == Some(name))
            .unwrap();
        assert_eq!(other.data, t.data);
    }
}

#[test]
fn cornell_box_obj() {
    let s = Scene::load(&common::cornell()).unwrap();
    assert_eq!(s.triangle_count(), 36);
    assert_eq!(s.stats.degenerate_triangles, 0);
    assert_eq!(s.materials.len(), 5);
    let emitters = s.emitters();
    assert_eq!(emitters.len(), 1);
    let light = &s.meshes[emitters[0]];
    assert_eq!(light.name, "light");
    assert_eq!(light.emission, Some(lustre_scene::Rgb::splat(20.0)));
    // The light is 130 × 105 mm and faces down into the box.
    assert!((light.area() - 130.0 * 105.0).abs() < 1.0);
    let [a, b, c] = light.triangle(0);
    assert!((b - a).cross(c - a).y < 0.0);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("Ka"));
    let red = &s.materials[s.material_index("red").unwrap()];
    assert_eq!(
        red.kind,
        MaterialKind::Diffuse {
            reflectance: lustre_scene::TexturedRgb::constant(lustre_scene::Rgb::new(1.0, 0.0, 0.0))
        }
    );
}

/// Every Modern Hall material builds its BSDF at a hit; textures change the base colour there,
/// two-sided materials answer from below, the glass transmits, and the textured rough plastic
/// (a prototype cloned per hit) evaluates exactly as a fresh lustre-brdf model.
#[test]
fn hall_materials_build_bsdfs() {
    use lustre_brdf::microfacet::distribution::MicrofacetType;
    use lustre_brdf::models::rough_plastic::RoughPlastic;
    let s = hall_xml();
    let up = DVec3::new(0.3, 0.2, 0.9).normalize();
    let view = DVec3::new(-0.4, 0.1, 0.9).normalize();
    let below = DVec3::new(view.x, view.y, -view.z);
    let uv_a = [glam::Vec2::new(0.1, 0.2), glam::Vec2::ZERO];
    let uv_b = [glam::Vec2::new(0.6, 0.7), glam::Vec2::ZERO];
    for m in &s.materials {
        let b = m.bsdf_at(&s.textures, &uv_a).unwrap();
        let flags = b.flags();
        let f = b.eval(up, view);
        assert!(f.is_finite(), "{}", m.name);
        if m.name == "Glass" {
            assert!(flags.transmission);
            continue;
        }
        if m.name.starts_with("twosided@") {
            assert_eq!(f, lustre_scene::Rgb::ZERO, "the emitters' black diffuse");
            continue;
        }
        assert!(f.max_component() > 0.0, "{}: {f:?}", m.name);
        assert!(m.two_sided);
        let g = b.eval(DVec3::new(up.x, up.y, -up.z), below);
        assert!(
            (g - f).max_component().abs() < 1e-12,
            "{}: two-sided",
            m.name
        );
    }
    let wood = &s.materials[s.material_index("Wood").unwrap()];
    let (fa, fb) = (
        wood.bsdf_at(&s.textures, &uv_a).unwrap().eval(up, view),
        wood.bsdf_at(&s.textures, &uv_b).unwrap().eval(up, view),
    );
    assert!(
        (fa - fb).max_component().abs() > 1e-4,
        "texture varies: {fa:?} {fb:?}"
    );
    let rho = match &wood.kind {
        MaterialKind::RoughPlastic { diffuse, .. } => diffuse.at(&s.textures, &uv_b),
        k => panic!("{k:?}"),
    };
    let fresh = RoughPlastic::new(
        MicrofacetType::Ggx,
        0.1,
        rho,
        lustre_scene::Rgb::ONE,
        1.5,
        1.0,
        true,
    )
    .unwrap();
    use lustre_brdf::Bsdf;
    let want = fresh.eval(up, view);
    assert!(
        (fb - want).max_component().abs() < 1e-12 * want.max_component(),
        "{fb:?} vs {want:?}"
    );
    // The glTF glass becomes a smooth dielectric (transmission 1, roughness 0).
    let g = hall_gltf();
    let glass = &g.materials[g.material_index("Glass").unwrap()];
    let b = glass.bsdf_at(&g.textures, &uv_a).unwrap();
    assert!(
        b.flags().transmission && b.name().to_lowercase().contains("dielectric"),
        "{}",
        b.name()
    );
    for m in &g.materials {
        assert!(m
            .bsdf_at(&g.textures, &uv_b)
            .unwrap()
            .eval(up, view)
            .is_finite());
    }
}
