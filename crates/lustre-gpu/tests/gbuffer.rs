//! The raster G-buffer and the light-mapped shading on the GPU against their CPU twins, on real
//! scenes (the Cornell box and the Modern Hall, light maps baked small and fast):
//! - visibility: the GPU's triangle ids against ray casting (`PathTracer::intersect`) at the
//!   pixel centres; only edge pixels may differ (raster rules vs the watertight ray test);
//! - shading: `lightmap_shade.wgsl` against `shade_gbuffer` on the GPU's own G-buffer
//!   (≥ 90 dB on lavapipe);
//! - the whole frame against the CPU frame at the same sample positions;
//! - k×k supersampling against the jittered, converged CPU image;
//! - bad input. Fails (does not skip) without an adapter.

mod common;
use common::{ctx, quick_bake, Baked};
use lustre_gpu::{LightmapFrameScene, LightmapRenderer};
use lustre_scene::Scene;
use lustre_trace::bake::diffuse_path_scene;
use lustre_trace::bake::gbuffer::{
    render_lightmapped_gbuffer, shade_gbuffer, VisibilityBuffer, SKY,
};
use lustre_trace::bake::render::{render_lightmapped, Lightmapped};
use lustre_trace::metrics::psnr;
use lustre_trace::path_tracer::PathCamera;
use lustre_trace::reference::path_camera;

/// A real scene with a small, quick bake (1 path per texel, 2 bounces, no denoiser).
fn baked(rel: &str, texels_per_metre: f32) -> Baked {
    let path = lustre_env::shared_data_dir().join(rel);
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    quick_bake(scene, texels_per_metre)
}

fn cornell() -> Baked {
    baked("scenes/cornell_box/cornell_box.obj", 0.1)
}

fn hall() -> Baked {
    baked("scenes/modern_hall/gltf/staircase2.gltf", 4.0)
}

fn camera(b: &Baked, w: usize, h: usize) -> PathCamera {
    path_camera(&b.scene, None, w as u32, h as u32).expect("camera")
}

/// (fraction of pixels whose ids agree, fraction of sky pixels, largest barycentric and relative
/// depth difference over agreeing surface pixels, 99th percentile of the barycentric one).
fn compare_visibility(gpu: &VisibilityBuffer, cpu: &VisibilityBuffer) -> (f64, f64, f64, f64, f64) {
    let agree = gpu.agreement(cpu).unwrap();
    let sky = cpu.prim.iter().filter(|&&p| p == SKY).count() as f64 / cpu.prim.len() as f64;
    let mut db = Vec::new();
    let mut dz = 0.0f64;
    for i in 0..gpu.prim.len() {
        if gpu.prim[i] == cpu.prim[i] && gpu.prim[i] != SKY {
            let d = (0..2)
                .map(|c| (f64::from(gpu.bary[i][c]) - f64::from(cpu.bary[i][c])).abs())
                .fold(0.0, f64::max);
            db.push(d);
            let z = (f64::from(gpu.depth[i]) / f64::from(cpu.depth[i]) - 1.0).abs();
            dz = dz.max(z);
        }
    }
    db.sort_by(f64::total_cmp);
    let p99 = db[(db.len() * 99) / 100];
    (agree, sky, db.last().copied().unwrap_or(0.0), p99, dz)
}

#[test]
fn gbuffer_ids_match_ray_casting_on_real_scenes() {
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let (w, h) = (160, 90);
    for (name, b) in [("Cornell box", cornell()), ("Modern Hall", hall())] {
        let cam = camera(&b, w, h);
        let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
        let (_, gpu) = r.render(&ctx, &up, &cam, w, h, 1).unwrap();
        let (_, cpu) =
            render_lightmapped_gbuffer(&b.scene, &b.atlas, &b.pages, &cam, w, h, 1).unwrap();
        let (agree, sky, bmax, b99, dz) = compare_visibility(&gpu, &cpu);
        eprintln!(
            "{name} {w}×{h}: ids agree on {:.3} % of pixels (sky {:.1} %); over agreeing pixels barycentrics differ ≤ {bmax:.2e} (99 %: {b99:.2e}), depth ≤ {dz:.2e} relative",
            100.0 * agree,
            100.0 * sky
        );
        assert!(agree >= 0.995, "{name}: {agree}");
        assert!(sky < 0.9, "{name}: the camera sees mostly sky");
        assert!(b99 < 1e-3 && dz < 1e-3, "{name}: {b99} {dz}");
        // Unit normals wherever there is a surface.
        for (p, n) in gpu.prim.iter().zip(&gpu.normal) {
            if *p != SKY {
                let l = n.iter().map(|v| v * v).sum::<f32>().sqrt();
                assert!((l - 1.0).abs() < 1e-3, "{name}: normal length {l}");
            }
        }
    }
}

#[test]
fn gpu_shading_matches_the_cpu_twin_on_its_gbuffer() {
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let (w, h) = (160, 90);
    for (name, b) in [("Cornell box", cornell()), ("Modern Hall", hall())] {
        let cam = camera(&b, w, h);
        let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
        let (ps, bases, _) = diffuse_path_scene(&b.scene).unwrap();
        let lit = Lightmapped::new(&b.scene, &b.atlas, &b.pages, &ps.geometry, bases).unwrap();
        for k in [1, 2] {
            let (img, gb) = r.render(&ctx, &up, &cam, w, h, k).unwrap();
            let cpu =
                shade_gbuffer(&lit, &ps.geometry, ps.environment.as_ref(), &cam, &gb, k).unwrap();
            let db = psnr(&img, &cpu, 1.0).unwrap();
            let mean = cpu.mean();
            let max_rel = img
                .data
                .iter()
                .zip(&cpu.data)
                .flat_map(|(a, c)| (0..3).map(move |i| (a[i] - c[i]).abs() / c[i].abs().max(1e-3)))
                .fold(0.0f32, f32::max);
            eprintln!(
                "{name} {w}×{h} k={k}: GPU shading vs CPU twin {db:.1} dB, largest relative difference {max_rel:.2e} (mean {mean:.4}), {}",
                ctx.describe()
            );
            assert!(mean > 1e-3, "{name}: black frame");
            assert!(db >= 90.0, "{name} k={k}: {db} dB");
        }
    }
}

#[test]
fn gpu_frame_matches_the_cpu_frame_at_pixel_centres() {
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let (w, h) = (160, 90);
    for (name, b) in [("Cornell box", cornell()), ("Modern Hall", hall())] {
        let cam = camera(&b, w, h);
        let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
        let (img, _) = r.render(&ctx, &up, &cam, w, h, 1).unwrap();
        let (cpu, _) =
            render_lightmapped_gbuffer(&b.scene, &b.atlas, &b.pages, &cam, w, h, 1).unwrap();
        let db = psnr(&img, &cpu, 1.0).unwrap();
        eprintln!("{name} {w}×{h}: GPU frame vs CPU frame at pixel centres {db:.1} dB");
        assert!(db >= 40.0, "{name}: {db} dB");
    }
}

#[test]
fn supersampling_approaches_the_converged_jittered_frame() {
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let (w, h) = (80, 45);
    let b = cornell();
    let cam = camera(&b, w, h);
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let converged = render_lightmapped(&b.scene, &b.atlas, &b.pages, &cam, w, h, 256, 3).unwrap();
    let mut last = 0.0;
    for k in [1, 2, 4] {
        let (img, _) = r.render(&ctx, &up, &cam, w, h, k).unwrap();
        let (cpu, _) =
            render_lightmapped_gbuffer(&b.scene, &b.atlas, &b.pages, &cam, w, h, k).unwrap();
        let db = psnr(&img, &converged, 1.0).unwrap();
        let twin = psnr(&img, &cpu, 1.0).unwrap();
        eprintln!("Cornell box {w}×{h} k={k}: vs 256 jittered spp {db:.1} dB; vs the CPU twin at the same sub-pixels {twin:.1} dB");
        assert!(db > last + 1.0, "k={k}: {db} dB after {last} dB");
        last = db;
    }
}

#[test]
fn bad_input_is_a_clear_error() {
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let b = cornell();
    // Pages of the wrong size and the wrong count.
    let mut small = b.pages.clone();
    let half = small[0].len() / 2;
    small[0].truncate(half);
    let mut more = b.pages.clone();
    more.push(b.pages[0].clone());
    for pages in [small, more, Vec::new()] {
        let e = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &pages)
            .unwrap_err()
            .to_string();
        assert!(e.contains("light-map pages do not fit"), "{e}");
    }
    // An atlas that names the wrong number of meshes.
    let mut atlas = b.atlas.clone();
    atlas.mesh_page.pop();
    let e = LightmapFrameScene::upload(&ctx, &b.scene, &atlas, &b.pages)
        .unwrap_err()
        .to_string();
    assert!(e.contains("meshes"), "{e}");
    // An empty scene.
    let mut empty = Scene::new("empty");
    empty.environment = Some(lustre_scene::Environment::constant(
        lustre_brdf::rgb::Rgb::new(1.0, 1.0, 1.0),
    ));
    let e = LightmapFrameScene::upload(&ctx, &empty, &b.atlas, &b.pages)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no triangles"), "{e}");
    // Zero-size targets and absurd supersampling.
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let cam = camera(&b, 16, 16);
    for (w, h, k) in [(0, 16, 1), (16, 0, 1), (16, 16, 0), (16, 16, 99)] {
        let e = r.render(&ctx, &up, &cam, w, h, k).unwrap_err().to_string();
        assert!(e.contains("image size"), "{w}×{h} k={k}: {e}");
    }
    assert!(lustre_gpu::GBufferTarget::new(&ctx, 0, 4).is_err());
    assert!(lustre_gpu::ShadeTarget::new(&ctx, 4, 0).is_err());
    // Targets beyond the device's storage limit say both sizes in plain units and what to
    // lower (16384² at 4×4 samples: 64 GB, more than any device's binding).
    let limit = ctx.device.limits().max_storage_buffer_binding_size;
    let e = match lustre_gpu::FrameShadeTarget::new(&ctx, 16384, 16384, 4) {
        Ok(_) => panic!("a 64 GB target was made"),
        Err(e) => e.to_string(),
    };
    assert!(
        e.contains("16384×16384 at 4×4 samples a pixel needs a storage buffer of 64 GB")
            && e.contains(&format!(
                "more than this GPU's {}",
                lustre_brdf::budget::bytes(limit)
            ))
            && e.contains("a smaller image or fewer camera rays"),
        "{e}"
    );
    let side = 1 << 14;
    if u64::from(side) * u64::from(side) * 16 > limit {
        let e = match lustre_gpu::ShadeTarget::new(&ctx, side, side) {
            Ok(_) => panic!("a target beyond the limit was made"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("needs a storage buffer of 4.0 GB"), "{e}");
    }
}

/// Sky pixels: the equirect lookup of a real map, rotated and scaled, against `EnvLight::eval`.
/// The Cornell box is open at the front; the light maps of the unlit-by-sky bake serve (the
/// parity does not depend on what the maps hold).
#[test]
fn sky_pixels_match_the_environment_lookup() {
    use lustre_scene::{Environment, EnvironmentSource};
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let mut b = cornell();
    let path = lustre_env::shared_data_dir().join("envmaps/venice_sunset_1k.hdr");
    let map = lustre_env::read_map(&path).expect("map").map;
    b.scene.environment = Some(Environment {
        source: EnvironmentSource::Map {
            path,
            map: std::sync::Arc::new(map),
        },
        to_local: glam::DMat3::from_rotation_y(0.7) * glam::DMat3::from_rotation_x(0.2),
        intensity: 0.5,
    });
    let (w, h) = (160, 90);
    let cam = camera(&b, w, h);
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let (ps, bases, _) = diffuse_path_scene(&b.scene).unwrap();
    assert!(ps.environment.is_some());
    let lit = Lightmapped::new(&b.scene, &b.atlas, &b.pages, &ps.geometry, bases).unwrap();
    let (img, gb) = r.render(&ctx, &up, &cam, w, h, 1).unwrap();
    let sky = gb.prim.iter().filter(|&&p| p == SKY).count();
    let cpu = shade_gbuffer(&lit, &ps.geometry, ps.environment.as_ref(), &cam, &gb, 1).unwrap();
    let db = psnr(&img, &cpu, 1.0).unwrap();
    // The sky pixels alone.
    let mut sky_img = cpu.clone();
    let mut sky_cpu = cpu.clone();
    for (i, &p) in gb.prim.iter().enumerate() {
        if p != SKY {
            sky_img.data[i] = [0.0; 3];
            sky_cpu.data[i] = [0.0; 3];
        } else {
            sky_img.data[i] = img.data[i];
        }
    }
    let db_sky = psnr(&sky_img, &sky_cpu, 1.0).unwrap();
    let sky_mean = sky_cpu.mean() * (w * h) as f64 / sky as f64;
    eprintln!(
        "Cornell box under a rotated venice_sunset_1k: {sky} sky pixels (mean {sky_mean:.3}), frame {db:.1} dB, sky pixels {db_sky:.1} dB"
    );
    assert!(sky > w * h / 10, "{sky} sky pixels");
    assert!(sky_mean > 0.01, "black sky");
    assert!(db >= 90.0 && db_sky >= 90.0, "{db} {db_sky}");
}

/// The index of the scene texture whose file name contains `name`.
fn texture_index(scene: &lustre_scene::Scene, name: &str) -> usize {
    scene
        .textures
        .iter()
        .position(|t| t.source.to_string_lossy().contains(name))
        .unwrap_or_else(|| panic!("no texture {name}"))
}

/// Alpha masks: the Modern Hall with holes cut in its wallpaper (opacity = the tiles texture's
/// red channel, glTF cutoff 0.5) and in its floor (the wood texture's green channel, no cutoff:
/// the ray test's ½). The raster pass must discard what `PathTracer::intersect` skips.
#[test]
fn alpha_masked_holes_match_ray_casting() {
    use lustre_scene::material::{AlphaMask, TextureRef, TexturedScalar};
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let mut b = hall();
    let (w, h) = (160, 90);
    let cam = camera(&b, w, h);
    let plain = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let (_, before) = r.render(&ctx, &plain, &cam, w, h, 1).unwrap();
    let tex = |name: &str| texture_index(&b.scene, name);
    let (tiles, wood) = (tex("Tiles"), tex("wood5"));
    for (material, texture, channel, cutoff) in [
        ("Wallpaper", tiles, 0, Some(0.5)),
        ("FloorTiles", wood, 1, None),
    ] {
        let m = b
            .scene
            .materials
            .iter_mut()
            .find(|m| m.name == material)
            .unwrap_or_else(|| panic!("no material {material}"));
        m.alpha_mask = Some(AlphaMask {
            opacity: TexturedScalar {
                factor: 1.0,
                texture: Some(TextureRef { texture, uv_set: 0 }),
                channel,
            },
            cutoff,
        });
    }
    let masked = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let (_, gpu) = r.render(&ctx, &masked, &cam, w, h, 1).unwrap();
    let (_, cpu) = render_lightmapped_gbuffer(&b.scene, &b.atlas, &b.pages, &cam, w, h, 1).unwrap();
    let changed = 1.0 - gpu.agreement(&before).unwrap();
    let (agree, _, _, b99, dz) = compare_visibility(&gpu, &cpu);
    eprintln!(
        "Modern Hall {w}×{h} with alpha-masked wallpaper and floor: {:.1} % of pixels see through a hole; ids agree with ray casting on {:.3} %",
        100.0 * changed,
        100.0 * agree
    );
    assert!(changed > 0.02, "the masks cut nothing visible: {changed}");
    assert!(agree >= 0.995, "{agree}");
    assert!(b99 < 1e-3 && dz < 1e-3, "{b99} {dz}");
}

/// glTF materials whose metallic and transmission are textured (k per pixel): the Modern Hall's
/// wallpaper made metallic where the tiles texture is red and transmissive where the wood
/// texture is blue. GPU shading against the CPU twin, and the image must change.
#[test]
fn textured_metallic_and_transmission_match_the_cpu_twin() {
    use lustre_scene::material::{MaterialKind, TextureRef, TexturedRgb, TexturedScalar};
    let ctx = ctx();
    let r = LightmapRenderer::new(&ctx).unwrap();
    let mut b = hall();
    let (w, h) = (160, 90);
    let cam = camera(&b, w, h);
    let plain = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let (before, _) = r.render(&ctx, &plain, &cam, w, h, 1).unwrap();
    let tex = |name: &str| texture_index(&b.scene, name);
    let (tiles, wood, paper) = (tex("Tiles"), tex("wood5"), tex("Wallpaper"));
    let scalar = |texture, channel, factor| TexturedScalar {
        factor,
        texture: Some(TextureRef { texture, uv_set: 0 }),
        channel,
    };
    let m = b
        .scene
        .materials
        .iter_mut()
        .find(|m| m.name == "Wallpaper")
        .expect("Wallpaper");
    m.kind = MaterialKind::PbrMetallicRoughness {
        base_color: TexturedRgb {
            factor: lustre_brdf::rgb::Rgb::new(1.0, 0.9, 0.8),
            texture: Some(TextureRef {
                texture: paper,
                uv_set: 0,
            }),
        },
        metallic: scalar(tiles, 0, 1.0),
        roughness: TexturedScalar::constant(0.5),
        transmission: scalar(wood, 2, 1.5),
        ior: 1.5,
        anisotropy: 0.0,
        anisotropy_rotation: 0.0,
        layers: Default::default(),
    };
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let (ps, bases, _) = diffuse_path_scene(&b.scene).unwrap();
    let lit = Lightmapped::new(&b.scene, &b.atlas, &b.pages, &ps.geometry, bases).unwrap();
    let (img, gb) = r.render(&ctx, &up, &cam, w, h, 1).unwrap();
    let cpu = shade_gbuffer(&lit, &ps.geometry, ps.environment.as_ref(), &cam, &gb, 1).unwrap();
    let db = psnr(&img, &cpu, 1.0).unwrap();
    let change = psnr(&img, &before, 1.0).unwrap();
    eprintln!(
        "Modern Hall {w}×{h}, wallpaper with textured metallic and transmission: GPU vs CPU twin {db:.1} dB; vs the plain hall {change:.1} dB"
    );
    assert!(
        change < 40.0,
        "the textured scalars changed nothing: {change} dB"
    );
    assert!(db >= 90.0, "{db} dB");
}
