//! Textured and normal-mapped glossy materials in the GPU view-dependent pass
//! (`frame_shade.wgsl` with `wgsl/textured.wgsl`) against the CPU twin
//! `shade_gbuffer_view_dependent` on the GPU's own G-buffer: the built-in room with
//! (a) the first sphere a rough gold conductor whose αu and αv come from a roughness texture,
//! (b) the second a glTF metallic-roughness material with base colour and metallic-roughness
//! textures (G roughness, B metallic) and a normal map (the mesh's tangents),
//! (c) the floor a rough plastic with a textured diffuse reflectance, a textured roughness (its
//! coating's grid, `RoughPlasticCoating`) and a normal map (tangents from ∂p/∂u: the quad has
//! none), and (d) the third a glTF material with textured
//! transmission and roughness, so that its pixels are the glTF BRDF, a rough dielectric or a
//! smooth one. ≥ 90 dB for regular sampling and CK, and each textured material must matter: the
//! same frame with its textures replaced by their means (normal maps removed) differs clearly.
//! Fails (does not skip) without an adapter.

mod common;
use common::textures::{scalar, textured_gltf, textured_gold, textures, untextured};
use common::{ctx, quick_bake};
use lustre_brdf::rgb::Rgb;
use lustre_gpu::material::{pack_material, FLAG_NORMAL_MAPPED, FLAG_TEXTURED};
use lustre_gpu::{
    FrameShadePass, FrameShadeScene, FrameShadeTarget, GBufferTarget, GpuViewBuffer,
    LightmapFrameScene, LightmapRenderer, ShadeTarget,
};
use lustre_scene::material::{NormalMap, TextureRef, TexturedRgb, TexturedScalar};
use lustre_scene::{Material, MaterialKind, Scene};
use lustre_shade::frame::{shade_gbuffer_view_dependent, FrameBuffers, FrameLight};
use lustre_shade::probe::{capture_probe, LitScene, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::bake::gbuffer::VisibilityBuffer;
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{base_albedo, BaseAlbedo};
use lustre_trace::image::Image;
use lustre_trace::metrics::psnr;
use lustre_trace::path_tracer::{PathCamera, PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};

/// The room with the four textured materials (module docs).
fn textured_room() -> Scene {
    let mut scene = lustre_scene::builtin::room().expect("room");
    scene.textures = textures();
    let name = |k: usize, scene: &Scene| scene.materials[k].name.clone();
    // (a) The fitted sphere: a rough gold conductor, roughness textured.
    let gold = scene
        .materials
        .iter()
        .position(|m| matches!(m.kind, MaterialKind::Spec(_)))
        .expect("the fitted sphere");
    scene.materials[gold] = Material::new(name(gold, &scene), textured_gold());
    // (b) The anisotropic sphere: glTF metallic-roughness, textured and normal-mapped.
    let alu = material(&scene, "brushed-aluminium");
    let mut pbr = Material::new(name(alu, &scene), textured_gltf());
    pbr.normal_map = Some(NormalMap {
        texture: TextureRef {
            texture: 3,
            uv_set: 0,
        },
        scale: 1.0,
    });
    scene.materials[alu] = pbr;
    // (c) The floor: rough plastic, wood-textured diffuse reflectance, normal-mapped.
    let floor = material(&scene, "floor");
    if let MaterialKind::RoughPlastic { diffuse, alpha, .. } = &mut scene.materials[floor].kind {
        *diffuse = TexturedRgb::texture(TextureRef {
            texture: 4,
            uv_set: 0,
        });
        // A textured roughness: the coating's grid (RoughPlasticCoating), per pixel.
        *alpha = TexturedScalar {
            factor: 0.4,
            ..scalar(0, 1)
        };
    }
    scene.materials[floor].normal_map = Some(NormalMap {
        texture: TextureRef {
            texture: 3,
            uv_set: 0,
        },
        scale: 0.5,
    });
    // (d) The glass sphere: glTF with textured transmission and roughness.
    let glass = material(&scene, "frosted-glass");
    scene.materials[glass] = Material::new(
        name(glass, &scene),
        MaterialKind::PbrMetallicRoughness {
            base_color: TexturedRgb::constant(Rgb::new(0.9, 0.95, 1.0)),
            metallic: TexturedScalar::constant(0.0),
            roughness: scalar(5, 1),
            transmission: scalar(5, 0),
            ior: 1.5,
            anisotropy: 0.0,
            anisotropy_rotation: 0.0,
            layers: Default::default(),
        },
    );
    scene
}

fn material(scene: &Scene, name: &str) -> usize {
    scene
        .materials
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| panic!("no material {name}"))
}

/// The CPU twin of the view-dependent pass on `gb` for `scene` (its light maps `baked`'s).
#[allow(clippy::too_many_arguments)]
fn twin(
    scene: &Scene,
    baked: &common::Baked,
    light: &FrameLight,
    buffers: &FrameBuffers,
    camera: &PathCamera,
    gb: &VisibilityBuffer,
    opts: &FrameRequest,
) -> (Image, u64) {
    let (ps, _) = path_scene(scene).expect("path scene");
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = Lightmapped::new(scene, &baked.atlas, &baked.pages, &ps.geometry, bases)
        .expect("light maps");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(scene, &ps, &pt, &lm).expect("lit");
    let (img, stats) =
        shade_gbuffer_view_dependent(&lit, light, buffers, camera, gb, 1, opts).expect("twin");
    (img, stats.glossy_hits)
}

#[test]
fn textured_and_normal_mapped_glossy_materials_match_their_cpu_twin() {
    let ctx = ctx();
    let baked = quick_bake(textured_room(), 4.0);
    let scene = &baked.scene;
    // Every textured material is on the GPU, flagged.
    let mut tables = vec![];
    for (name, flags) in [
        ("gold-paint", FLAG_TEXTURED),
        ("brushed-aluminium", FLAG_TEXTURED | FLAG_NORMAL_MAPPED),
        ("floor", FLAG_TEXTURED | FLAG_NORMAL_MAPPED),
        ("frosted-glass", FLAG_TEXTURED),
    ] {
        let b = pack_material(&scene.materials[material(scene, name)], &mut tables)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(b.flags & flags, flags, "{name}");
    }
    let (ps, _) = path_scene(scene).expect("path scene");
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = Lightmapped::new(scene, &baked.atlas, &baked.pages, &ps.geometry, bases)
        .expect("light maps");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(scene, &ps, &pt, &lm).expect("lit");
    let popts = ProbeOptions {
        face_size: 32,
        supersample: 1,
        plane_rays: 16,
    };
    let probes: Vec<_> = (0..scene.meshes.len())
        .filter(|&m| scene.meshes[m].hints.probe)
        .map(|m| capture_probe(&lit, m, &popts).expect("probe"))
        .collect();
    let light = FrameLight {
        probes: &probes,
        environment: None,
    };
    let (w, h) = (128usize, 80usize);
    let camera = path_camera(scene, None, w as u32, h as u32).expect("camera");
    let renderer = LightmapRenderer::new(&ctx).expect("passes");
    let up = LightmapFrameScene::upload(&ctx, scene, &baked.atlas, &baked.pages).expect("upload");
    let target = GBufferTarget::new(&ctx, w as u32, h as u32).expect("gbuffer");
    let base = ShadeTarget::new(&ctx, w as u32, h as u32).expect("target");
    renderer
        .draw(&ctx, &up, &camera, 1, &target, &base)
        .expect("draw");
    let gb = target.read_back(&ctx).expect("gbuffer readback");
    let mut buffers = FrameBuffers::render(&lit, &light, &camera, w, h).expect("buffers");
    for m in &mut buffers.mirrors {
        m.view = GpuViewBuffer::upload(&ctx, &m.view)
            .and_then(|g| g.read_back(&ctx))
            .expect("mirror round trip");
    }
    for v in &mut buffers.see_throughs {
        *v = GpuViewBuffer::upload(&ctx, v)
            .and_then(|g| g.read_back(&ctx))
            .expect("see-through round trip");
    }
    let gpu_scene = FrameShadeScene::upload(&ctx, &lit, &light, &buffers).expect("frame scene");
    let pass = FrameShadePass::new(&ctx).expect("compile");
    let out = FrameShadeTarget::new(&ctx, w as u32, h as u32, 1).expect("output");
    let samples = 8;
    let seed = 5;
    let mut regular = None;
    for (name, method) in [("regular", (Method::Regular, 1)), ("CK", (Method::Ck, 1))] {
        let opts = FrameRequest {
            method: method.0,
            samples,
            rays: 1,
            frames: method.1,
            seed,
        };
        let t0 = std::time::Instant::now();
        pass.shade(
            &ctx,
            &gpu_scene,
            &target,
            &base,
            &camera,
            1,
            (&opts, 0),
            &out,
        )
        .expect("shade");
        let gpu = out.read_back(&ctx).expect("readback");
        let seconds = t0.elapsed().as_secs_f64();
        let stats = out.stats(&ctx).expect("stats");
        let (cpu, cpu_stats) =
            shade_gbuffer_view_dependent(&lit, &light, &buffers, &camera, &gb, 1, &opts)
                .expect("cpu twin");
        let db = psnr(&gpu, &cpu, 1.0).expect("psnr");
        eprintln!(
            "textured room, {name}: GPU vs CPU twin {db:.1} dB ({w}×{h}, n = {samples}, \
             {seconds:.2} s with read-back); glossy pixels GPU {} CPU {}",
            stats.glossy_hits, cpu_stats.glossy_hits
        );
        assert!(db >= 90.0, "{name}: {db:.1} dB");
        assert_eq!(stats.glossy_hits, cpu_stats.glossy_hits, "{name}");
        assert!(cpu_stats.glossy_hits > (w * h / 4) as u64, "{name}");
        if method == (Method::Regular, 1) {
            regular = Some(gpu);
        }
    }
    // Each material's textures matter: its means instead (no normal map) change the frame.
    let gpu = regular.expect("the regular frame");
    let opts = FrameRequest {
        method: Method::Regular,
        samples,
        rays: 1,
        frames: 1,
        seed,
    };
    for name in ["gold-paint", "brushed-aluminium", "floor", "frosted-glass"] {
        let mut flat = scene.clone();
        let k = material(scene, name);
        flat.materials[k] = untextured(&scene.materials[k], &scene.textures);
        let (cpu, _) = twin(&flat, &baked, &light, &buffers, &camera, &gb, &opts);
        let db = psnr(&gpu, &cpu, 1.0).expect("psnr");
        eprintln!("{name} with its textures' means: {db:.1} dB from the textured GPU frame");
        assert!(
            db < 60.0,
            "{name}: the textures change nothing ({db:.1} dB)"
        );
    }
}
