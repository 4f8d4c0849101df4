//! The whole walkthrough frame on the GPU (`GpuWalkthrough`: probes captured and filtered on the
//! GPU, mirror and see-through passes, G-buffer, light-map shading, the view-dependent pass)
//! against the chain of its CPU twins fed with the GPU's own intermediates (the read-back
//! G-buffer, probes and view buffers): ≥ 90 dB on lavapipe for every method, on the built-in
//! room with its real materials (the SGD fit of MERL gold-metallic-paint, anisotropic brushed
//! aluminium, frosted glass, the glossy floor as the planar reflector). Also the agreement of
//! the GPU frame with the CPU's ray-cast frame, and the named refusal of a material the GPU
//! cannot shade. Fails without an adapter.

use lustre_brdf::rgb::Rgb;
use lustre_gpu::{GpuContext, GpuFrameOptions, GpuWalkthrough, LightmapFrameScene};
use lustre_scene::lightmap::{build_atlas, AtlasOptions, LightmapAtlas};
use lustre_scene::{Material, MaterialKind, ResolvedSpec, Scene};
use lustre_shade::bake::render::Lightmapped;
use lustre_shade::bake::{assemble, bake_tiles, spec_albedo, BakeOptions, Denoiser};
use lustre_shade::frame::{
    render_frame, shade_gbuffer_view_dependent, FrameBuffers, FrameLight, FrameMethod,
    FrameOptions, GBufferViewOptions,
};
use lustre_shade::metrics::psnr;
use lustre_shade::mirror::MirrorBuffer;
use lustre_shade::path::{PathOptions, PathTracer};
use lustre_shade::probe::{LitScene, ProbeOptions};
use lustre_shade::reference::{path_camera, path_scene};

fn ctx() -> GpuContext {
    GpuContext::new().unwrap_or_else(|e| panic!("{e}"))
}

/// The room's light maps from a quick bake (4 texels/m, 1 path per texel, 2 bounces).
fn baked(scene: &mut Scene) -> (LightmapAtlas, Vec<Vec<[f32; 3]>>) {
    let (atlas, _) = build_atlas(
        scene,
        &AtlasOptions {
            texels_per_metre: 4.0,
            ..AtlasOptions::default()
        },
    )
    .expect("atlas");
    let bake = BakeOptions {
        spp: 1,
        bounces: 2,
        seed: 5,
        denoiser: Denoiser::None,
        ..BakeOptions::default()
    };
    let dir = tempfile::tempdir().expect("tempdir");
    bake_tiles(scene, &atlas, &bake, dir.path(), None, &|_, _| {}).expect("bake");
    let pages = assemble(scene, &atlas, &bake, dir.path())
        .expect("assemble")
        .pages;
    (atlas, pages)
}

const PROBES: ProbeOptions = ProbeOptions {
    face_size: 32,
    supersample: 1,
    plane_rays: 16,
};

#[test]
fn the_gpu_frame_matches_its_cpu_twins_and_the_ray_cast_frame() {
    let ctx = ctx();
    let mut scene = lustre_scene::builtin::room().expect("room");
    let (atlas, pages) = baked(&mut scene);
    let (ps, _) = path_scene(&scene).expect("path scene");
    let spec: Vec<Rgb> = scene.materials.iter().map(spec_albedo).collect();
    let lm = Lightmapped::new(&scene, &atlas, &pages, &ps.geometry, spec).expect("light maps");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(&scene, &ps, &pt, &lm).expect("lit");
    let up = LightmapFrameScene::upload(&ctx, &scene, &atlas, &pages).expect("upload");
    let walk = GpuWalkthrough::new(&ctx, &lit, up, &PROBES, None).expect("walkthrough");
    assert_eq!(walk.probes.len(), 3, "the three spheres");
    assert_eq!(walk.capture_ms.len(), 3);
    // The probes as the CPU twins read them: the GPU's, read back.
    let probes: Vec<_> = walk
        .probes
        .iter()
        .map(|p| p.read_back(&ctx).expect("probe read-back"))
        .collect();
    let light = FrameLight {
        probes: &probes,
        environment: None,
    };
    let (w, h) = (80usize, 48usize);
    let camera = path_camera(&scene, None, w as u32, h as u32).expect("camera");
    for (name, method, k) in [
        ("regular", FrameMethod::Regular, 1),
        ("regular, 2×2 supersampled", FrameMethod::Regular, 2),
        ("CK", FrameMethod::Ck, 1),
        (
            "progressive (3 frames)",
            FrameMethod::Progressive { frames: 3 },
            1,
        ),
    ] {
        let samples = 8;
        let frame = walk
            .render(
                &ctx,
                &lit,
                &camera,
                (w, h),
                &GpuFrameOptions {
                    samples,
                    method,
                    supersampling: k,
                    seed: 3,
                },
            )
            .expect("GPU frame");
        assert_eq!((frame.stats.mirrors, frame.stats.see_throughs), (1, 1));
        // The CPU twins on the GPU's intermediates.
        let gb = frame.gbuffer.read_back(&ctx).expect("G-buffer read-back");
        let views: Vec<_> = frame
            .views
            .iter()
            .map(|v| v.read_back(&ctx).expect("view read-back"))
            .collect();
        let (mirror_views, see_throughs) = views.split_at(frame.reflectors.len());
        let t = &frame.tables;
        let buffers = FrameBuffers {
            mirrors: frame
                .reflectors
                .iter()
                .zip(mirror_views)
                .map(|(r, v)| MirrorBuffer {
                    reflector: r.clone(),
                    plane: r.plane,
                    view: v.clone(),
                })
                .collect(),
            mirror_of_mesh: t.mirror_of_mesh.clone(),
            see_throughs: see_throughs.to_vec(),
            see_through_of_mesh: t.see_through_of_mesh.clone(),
            probe_of_mesh: t.probe_of_mesh.clone(),
            thin: scene
                .materials
                .iter()
                .map(lustre_shade::frame::thin_sheet)
                .collect(),
            first_prim: t.first_prim.clone(),
            seconds: 0.0,
        };
        let (twin, twin_stats) = shade_gbuffer_view_dependent(
            &lit,
            &light,
            &buffers,
            &camera,
            &gb,
            k,
            &GBufferViewOptions {
                samples: samples as usize,
                method,
                seed: 3,
            },
        )
        .expect("CPU twin");
        let db = psnr(&frame.image, &twin, 1.0).expect("psnr");
        println!(
            "{name}: GPU frame vs its CPU twins {db:.1} dB; glossy pixels {} / {}; GPU times \
             {:?}",
            frame.stats.glossy_hits, twin_stats.glossy_hits, frame.times
        );
        assert!(db >= 90.0, "{name}: {db:.1} dB");
        if !matches!(method, FrameMethod::Progressive { .. }) {
            assert_eq!(frame.stats.glossy_hits, twin_stats.glossy_hits, "{name}");
        }
    }
    // The same frame ray-cast on the CPU (its own probes and buffers, jittered camera rays):
    // only the sampling of the pixels and the probes' rays differ.
    let cpu_probes: Vec<_> = (0..scene.meshes.len())
        .filter(|&m| scene.meshes[m].hints.probe)
        .map(|m| lustre_shade::probe::capture_probe(&lit, m, &PROBES).expect("probe"))
        .collect();
    let cpu_light = FrameLight {
        probes: &cpu_probes,
        environment: None,
    };
    let gpu = walk
        .render(
            &ctx,
            &lit,
            &camera,
            (w, h),
            &GpuFrameOptions {
                samples: 8,
                method: FrameMethod::Regular,
                supersampling: 4,
                seed: 3,
            },
        )
        .expect("GPU frame");
    let (cpu, _) = render_frame(
        &lit,
        &cpu_light,
        &camera,
        w,
        h,
        &FrameOptions {
            samples: 8,
            method: FrameMethod::Regular,
            spp: 16,
            seed: 3,
        },
    )
    .expect("CPU frame");
    let db = psnr(&gpu.image, &cpu, 1.0).expect("psnr");
    println!("GPU frame (4×4 G-buffer) vs the CPU ray-cast frame (16 rays/pixel): {db:.1} dB");
    assert!(db >= 30.0, "{db:.1} dB");
}

#[test]
fn a_material_the_gpu_cannot_shade_is_refused_by_name() {
    let ctx = ctx();
    let mut scene = lustre_scene::builtin::room().expect("room");
    // The published SGD fit of chrome: its normalisation is not reproduced in f32.
    let chrome = scene
        .materials
        .iter()
        .position(|m| matches!(m.kind, MaterialKind::Spec(_)))
        .expect("the fitted sphere");
    scene.materials[chrome] = Material::new(
        "chrome",
        MaterialKind::Spec(ResolvedSpec::resolve("chrome", "sgd:chrome").expect("spec")),
    );
    let (atlas, pages) = baked(&mut scene);
    let (ps, _) = path_scene(&scene).expect("path scene");
    let spec: Vec<Rgb> = scene.materials.iter().map(spec_albedo).collect();
    let lm = Lightmapped::new(&scene, &atlas, &pages, &ps.geometry, spec).expect("light maps");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(&scene, &ps, &pt, &lm).expect("lit");
    let up = LightmapFrameScene::upload(&ctx, &scene, &atlas, &pages).expect("upload");
    let err = GpuWalkthrough::new(&ctx, &lit, up, &PROBES, None)
        .expect_err("chrome is refused")
        .to_string();
    assert!(
        err.contains("chrome") && err.contains("gold-paint") && err.contains("not on the GPU"),
        "{err}"
    );
}
