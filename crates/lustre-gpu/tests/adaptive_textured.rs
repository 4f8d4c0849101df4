//! Textured and normal-mapped scene materials in the GPU bandwidth and adaptive passes
//! (`measured::material_eval_source`'s `material_prepare`: a record's textured parameters read
//! at the pixel's uv through `wgsl/textured.wgsl`; the shading frame, normal map included, the
//! G-buffer's) against their CPU twins on the line-up (004 Fig. IV.13) under royal_esplanade:
//! (a) the left sphere a rough gold conductor whose αu and αv come from a roughness texture,
//! (b) the middle one a glTF metallic-roughness material with base colour and
//! metallic-roughness textures and a normal map, (c) the right one a measured gold-paint, and
//! (d) the floor a rough plastic with a wood-textured diffuse reflectance, a textured roughness
//! (its coating's grid) and a normal map. Each texture must matter: the CPU frame with the
//! textures replaced by their means and without normal maps differs clearly. Fails (does not
//! skip) without an adapter.

mod common;
use common::textures::{scalar, textured_gltf, textured_gold, textures, untextured};
use common::{ctx, line_up};
use lustre_adaptive::buffer::{predict_pixels, BandwidthBuffer, BrdfWeights, BufferOptions};
use lustre_adaptive::gbuffer::{GBuffer, GPixel};
use lustre_adaptive::hierarchy::render_adaptive;
use lustre_adaptive::shading::Lighting;
use lustre_brdf::rgb::Rgb;
use lustre_gpu::passes::adaptive::{AdaptivePass, AdaptiveScene};
use lustre_gpu::passes::bandwidth::{BandwidthPass, BandwidthScene};
use lustre_scene::material::{MicrofacetType, NormalMap, TextureRef, TexturedRgb, TexturedScalar};
use lustre_scene::{Material, MaterialKind, Scene};
use lustre_trace::image::Image;

/// Texture `texture` read at uv0.
fn uv0(texture: usize) -> TextureRef {
    TextureRef { texture, uv_set: 0 }
}

/// The line-up with the textured materials of the module docs.
fn textured_line_up() -> Scene {
    let mut scene = line_up::scene(
        ["nbrdf:gold-paint", "nbrdf:gold-paint", "nbrdf:gold-paint"],
        "nbrdf:white-marble",
    );
    // 0 roughness (G), 1 base colour, 2 metallic-roughness (G, B), 3 normal map, 4 wood.
    scene.textures = textures();
    let normal_map = |scale: f32| NormalMap {
        texture: uv0(3),
        scale,
    };
    scene.materials[0] = Material::new("textured gold", textured_gold());
    let mut pbr = Material::new("textured glTF", textured_gltf());
    pbr.normal_map = Some(normal_map(1.0));
    scene.materials[1] = pbr;
    let mut floor = Material::new(
        "wood floor",
        MaterialKind::RoughPlastic {
            diffuse: TexturedRgb::texture(uv0(4)),
            specular: Rgb::ONE,
            alpha: TexturedScalar {
                factor: 0.6,
                ..scalar(0, 1)
            },
            distribution: MicrofacetType::Ggx,
            int_ior: 1.5,
            ext_ior: 1.0,
            nonlinear: false,
        },
    );
    floor.normal_map = Some(normal_map(0.5));
    scene.materials[3] = floor;
    scene
}

/// Relative RMS of `b` against `a` over `g`'s surface pixels of material `m` (all surface
/// pixels when `None`), and the share of those pixels off by more than 1 % of the frame's
/// largest value.
fn difference(g: &GBuffer, a: &Image, b: &Image, m: Option<usize>) -> (f64, f64) {
    let (mut se, mut ss, mut n, mut over) = (0.0, 0.0, 0usize, 0usize);
    let peak = a
        .data
        .iter()
        .flatten()
        .fold(0.0f32, |p, v| p.max(*v))
        .max(1e-6);
    for (k, p) in g.pixels.iter().enumerate() {
        let GPixel::Surface(s) = p else { continue };
        if m.is_some_and(|m| m != s.material) {
            continue;
        }
        let (x, y) = (a.data[k], b.data[k]);
        let mut worst = 0.0f32;
        for c in 0..3 {
            let d = f64::from(x[c] - y[c]);
            se += d * d;
            ss += f64::from(x[c]) * f64::from(x[c]);
            worst = worst.max((x[c] - y[c]).abs());
        }
        n += 1;
        if worst > 0.01 * peak {
            over += 1;
        }
    }
    assert!(n > 0, "no pixel of material {m:?}");
    ((se / ss.max(1e-30)).sqrt(), over as f64 / n as f64)
}

#[test]
fn textured_and_normal_mapped_materials_are_shaded_on_the_gpu_as_on_the_cpu() {
    let gpu_ctx = ctx();
    let scene = textured_line_up();
    let (w, h) = (72, 48);
    // Each material's textures matter: the CPU frame without them differs on its pixels.
    let frame = |scene: &Scene| {
        line_up::with_frame(scene, (w, h), |_, g, shading| {
            let env_bw = shading.environment_bandwidth().expect("env bandwidth");
            let buffer = BandwidthBuffer::build(&g, &shading, &env_bw, BufferOptions::default())
                .expect("buffer");
            let img = render_adaptive(&g, &shading, &buffer, Lighting::Direct, 11)
                .expect("cpu")
                .image;
            (g, img)
        })
    };
    let (g, textured) = frame(&scene);
    let mut plain = scene.clone();
    for m in [0, 1, 3] {
        plain.materials[m] = untextured(&scene.materials[m], &scene.textures);
    }
    let (_, without) = frame(&plain);
    for (m, name) in [(0, "gold"), (1, "glTF"), (3, "floor")] {
        let (rms, _) = difference(&g, &textured, &without, Some(m));
        eprintln!("{name}: its textures change the CPU frame by {rms:.3} (relative RMS)");
        assert!(rms > 0.05, "{name}: the textures barely matter ({rms})");
    }

    line_up::with_frame(&scene, (w, h), |_, g, shading| {
        let env_bw = shading.environment_bandwidth().expect("env bandwidth");
        // The bandwidth pass against the CPU's evaluated weights (a textured material's ρ at
        // the pixel, as the GPU evaluates it).
        let n_b = 16;
        let cpu = predict_pixels(&g, &shading, &env_bw, n_b, BrdfWeights::Evaluated).expect("cpu");
        let bw_scene = BandwidthScene::from_context(&gpu_ctx, &shading, &env_bw, Some(&scene))
            .expect("the bandwidth pass takes textured materials");
        let mut bw_pass = BandwidthPass::new(&gpu_ctx).expect("pass");
        let (gpu, _) = bw_pass
            .predict(&gpu_ctx, &bw_scene, &g, &shading, n_b as u32)
            .expect("predict");
        let (mut se, mut ss, mut n, mut off) = (0.0, 0.0, 0usize, 0usize);
        for (c, gp) in cpu.iter().zip(&gpu) {
            if let (Some(c), Some(gp)) = (c, gp) {
                let (a, b) = (c.prediction.radiance, gp.prediction.radiance);
                se += (a - b) * (a - b);
                ss += a * a;
                n += 1;
                if (a - b).abs() > 1e-2 * a.abs().max(1e-3) {
                    off += 1;
                }
            }
        }
        let rms = (se / ss).sqrt();
        eprintln!(
            "bandwidth pass, textured line-up: L̂ relative RMS {rms:.2e}, {off} of {n} pixels off \
             by > 1 %"
        );
        assert!(
            rms < 5e-3 && (off as f64) < 0.01 * n as f64,
            "rms {rms}, {off} of {n}"
        );

        // The adaptive pass against render_adaptive on the same buffer.
        let buffer = BandwidthBuffer::build(&g, &shading, &env_bw, BufferOptions::default())
            .expect("buffer");
        let cpu = render_adaptive(&g, &shading, &buffer, Lighting::Direct, 11).expect("cpu");
        let scene_gpu = AdaptiveScene::from_context(&gpu_ctx, &shading, Some(&scene))
            .expect("the adaptive pass takes textured materials");
        let mut pass = AdaptivePass::new(&gpu_ctx).expect("compile");
        let out = pass
            .render(&gpu_ctx, &scene_gpu, &g, &buffer, None, 11)
            .expect("gpu");
        let (rms, over1) = difference(&g, &cpu.image, &out.frame.image, None);
        eprintln!(
            "adaptive pass, textured line-up {w} × {h}: relative RMS {rms:.2e}, {:.2} % of \
             surface pixels off by > 1 % of the peak",
            100.0 * over1
        );
        assert!(rms < 5e-3 && over1 < 0.01, "rms {rms}, {over1}");
        for (m, name) in [(0, "gold"), (1, "glTF"), (3, "floor")] {
            let (rms, _) = difference(&g, &cpu.image, &out.frame.image, Some(m));
            eprintln!("  {name}: relative RMS {rms:.2e}");
            assert!(rms < 1e-2, "{name}: rms {rms}");
        }
    });
}
