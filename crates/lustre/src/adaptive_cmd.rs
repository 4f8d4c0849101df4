//! `lustre render --method adaptive | brute`: 004 chapter IV (`lustre-adaptive` on the CPU,
//! `lustre-gpu`'s bandwidth and adaptive passes on the GPU). Measured (or any) materials shaded
//! directly under the environment and the scene's planar emitters (as area lights,
//! `lustre_adaptive::light::scene_lights`), without visibility: the adaptive method renders a
//! bandwidth buffer and shades hierarchically; brute force shades every pixel with --samples samples.
//! The G-buffer, the material tables and the buffer's levels and variance target are the
//! CPU's; the passes run on the GPU with --device gpu, or with auto where the GPU takes the
//! scene (measured materials, fitted models, the scene's reflection materials, textured and
//! normal-mapped ones too, and the analytic reflection models of a spec:
//! `lustre_gpu::material::measured::EVALUATED`; area lights) and the adapter
//! is not a software rasterizer. Without a scene or --material, 004 Fig. IV.13's line-up (three
//! spheres of measured paints on white marble).

use crate::render_cmd::{compare, path_cameras, Device, RenderArgs, SampleRuleArg};
use anyhow::{bail, Context};
use glam::DVec3;
use indicatif::{ProgressBar, ProgressStyle};
use lustre_adaptive::buffer::{level_map, BandwidthBuffer, BufferOptions, SampleRule};
use lustre_adaptive::gbuffer::GBuffer;
use lustre_adaptive::hierarchy::{box_downsample, render_adaptive, render_brute};
use lustre_adaptive::light::{check_lit, scene_lights, AreaLight};
use lustre_adaptive::shading::{Lighting, ShadingContext, ShadingOptions};
use lustre_brdf::rgb::Rgb;
use lustre_freq::pixel::EnvironmentBandwidth;
use lustre_gpu::passes::adaptive::{AdaptivePass, AdaptiveScene};
use lustre_gpu::passes::bandwidth::{BandwidthPass, BandwidthScene};
use lustre_gpu::GpuContext;
use lustre_scene::builtin::{LINEUP_FLOOR, LINEUP_PAINTS};
use lustre_scene::material_edit::{parse_assignment, set_named};
use lustre_scene::Scene;
use lustre_shade::request::{FrameRequest, Method, MAX_ADAPTIVE_SAMPLES};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};
use std::fmt::Write as _;
use std::time::Instant;

/// Runs the adaptive or brute-force renderer.
pub fn run(args: &RenderArgs, req: &FrameRequest) -> anyhow::Result<()> {
    let adaptive = req.method == Method::Adaptive;
    let k = req.supersampling() as usize;
    let mut times: Vec<(String, f64)> = vec![];
    let mut t = Instant::now();
    let environment = crate::render_cmd::env_arg(args)?;
    let mut scene = match (&args.scene, &args.material) {
        (Some(path), _) => {
            if environment.is_some() {
                bail!("--env applies to --material and the built-in line-up, not to a scene file");
            }
            Scene::load(path)?
        }
        (None, Some(spec)) => lustre_scene::builtin::preview(spec, environment)
            .with_context(|| format!("--material {spec}"))?,
        (None, None) => lustre_scene::builtin::lineup(LINEUP_PAINTS, LINEUP_FLOOR, environment)?,
    };
    for a in &args.set {
        let (material, field, value) =
            parse_assignment(a).map_err(|e| anyhow::anyhow!("--set {e}"))?;
        set_named(&mut scene.materials, &material, &field, &value)
            .with_context(|| format!("--set {a}"))?;
    }
    let extra_light = match &args.area_light {
        Some(path) => {
            crate::budget::map(path, "--area-light", args.force)?;
            Some(area_light(&scene, path, args.area_light_radiance)?)
        }
        None => None,
    };
    let (w, h) = match args.size.as_deref() {
        Some(s) => crate::reference_cmd::parse_size(s)?,
        None => (scene.film.width, scene.film.height),
    };
    crate::render_cmd::check_side(w, h)?;
    crate::render_cmd::check_reference(args, w, h)?;
    let (gw, gh) = (w as usize * k, h as usize * k);
    let cameras = match &args.path {
        None => vec![(
            "frame".to_string(),
            path_camera(&scene, args.camera.as_deref(), gw as u32, gh as u32)?,
        )],
        Some(p) => path_cameras(&scene, p, args.fps, gw as u32, gh as u32)?,
    };
    let need = crate::budget::scene(
        lustre_brdf::budget::Budget::new(
            format!(
                "lustre render --method {} at {w}×{h}, {k}×{k} samples a pixel",
                format!("{:?}", req.method).to_lowercase()
            ),
            "lower --size or --spp",
        ),
        &scene,
    )
    .memory(
        "G-buffer and shading buffers",
        gw as u64 * gh as u64,
        crate::budget::ADAPTIVE_SAMPLE,
    )
    .disk(
        &args.out,
        "frames",
        u64::from(w) * u64::from(h) * cameras.len() as u64,
        crate::budget::RENDER_PIXEL_DISK,
    );
    crate::budget::check(&need, args.force)?;
    let (ps, warnings) = path_scene(&scene)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    // The scene's own planar emitters are area lights (004 §IV.5.3), with --area-light's.
    let mut lights =
        scene_lights(&ps).with_context(|| format!("{}: its emitters", scene.source.display()))?;
    lights.extend(extra_light);
    check_lit(&ps, &lights).with_context(|| scene.source.display().to_string())?;
    let tracer = PathTracer::new(&ps, PathOptions::default())?;
    lap(&mut times, "load, BVH", &mut t);
    let bar = ProgressBar::new(ps.materials.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("material tables [{bar:30}] {pos}/{len}, {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let lighting = if args.preconvolved {
        Lighting::Preconvolved
    } else {
        Lighting::Direct
    };
    let shading = ShadingOptions {
        pyramid_face: if lighting == Lighting::Preconvolved {
            ShadingOptions::default().pyramid_face
        } else {
            0
        },
        ..Default::default()
    };
    let mut ctx = ShadingContext::new(&ps, shading, &|i, _| bar.set_position(i as u64))?;
    bar.finish_and_clear();
    ctx.lights = lights;
    lap(
        &mut times,
        "material tables (sampling CDFs, bandwidth)",
        &mut t,
    );
    let env_bw = ctx.environment_bandwidth()?;
    lap(&mut times, "environment bandwidth", &mut t);
    // The passes run on the GPU where they can (--device auto) or must (--device gpu).
    let mut gpu = match args.device {
        Device::Cpu => None,
        device => gpu_passes(&ctx, &env_bw, adaptive, device == Device::Gpu, &scene)?,
    };
    if let Some(g) = &gpu {
        let place = |on: bool| if on { "GPU" } else { "CPU" };
        eprintln!(
            "{}shading on the {} ({})",
            if adaptive {
                format!("bandwidth pass on the {}, ", place(g.bandwidth.is_some()))
            } else {
                String::new()
            },
            place(g.shading.is_some()),
            g.ctx.describe()
        );
        lap(&mut times, "GPU: adapter, upload", &mut t);
    }

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let rule = match args.sample_rule {
        SampleRuleArg::Constant => SampleRule::Constant,
        SampleRuleArg::Coverage => SampleRule::Coverage,
        SampleRuleArg::Relative => SampleRule::Relative,
        SampleRuleArg::RelativeMse => SampleRule::RelativeMse,
        SampleRuleArg::Absolute => SampleRule::Absolute,
    };
    let mut summary = String::new();
    for (stem, camera) in &cameras {
        let g = GBuffer::render(&tracer, &ps, camera, gw, gh)?;
        lap(&mut times, &format!("{stem}: G-buffer"), &mut t);
        let surface = g.surface_pixels();
        let full = if adaptive {
            let options = BufferOptions {
                n_b: args.n_b as usize,
                mean_samples: f64::from(req.samples),
                max_samples: MAX_ADAPTIVE_SAMPLES as usize,
                lighting,
                scale: rule,
                rate: args.rate,
                ..Default::default()
            };
            let buffer = match gpu
                .as_mut()
                .and_then(|p| Some((&p.ctx, p.bandwidth.as_mut()?)))
            {
                Some((gctx, (scene, pass))) => {
                    let (estimates, timing) = pass.predict(gctx, scene, &g, &ctx, args.n_b)?;
                    if let Some(ms) = timing.gpu_ms {
                        times.push((
                            format!("{stem}: bandwidth pass (GPU timestamps)"),
                            ms * 1e-3,
                        ));
                    }
                    let b = BandwidthBuffer::assemble(&g, &estimates, options)?;
                    lap(
                        &mut times,
                        &format!("{stem}: bandwidth buffer (GPU pass, read-back, assembly)"),
                        &mut t,
                    );
                    b
                }
                None => {
                    let b = BandwidthBuffer::build(&g, &ctx, &env_bw, options)?;
                    lap(
                        &mut times,
                        &format!("{stem}: bandwidth buffer (CPU)"),
                        &mut t,
                    );
                    b
                }
            };
            let f = match gpu
                .as_mut()
                .and_then(|p| Some((&p.ctx, p.shading.as_mut()?)))
            {
                Some((gctx, (scene, pass))) => {
                    let lod_for = |nu: f64| ctx.preconvolved_lod(nu);
                    let lod = (lighting == Lighting::Preconvolved)
                        .then_some(&lod_for as &dyn Fn(f64) -> Option<f64>);
                    let out = pass.render(gctx, scene, &g, &buffer, lod, args.seed)?;
                    if let Some(ms) = out.timing.gpu_ms {
                        times.push((
                            format!("{stem}: pyramids, hierarchical shading (GPU timestamps)"),
                            ms * 1e-3,
                        ));
                    }
                    lap(
                        &mut times,
                        &format!("{stem}: hierarchical shading (GPU, upload, read-back)"),
                        &mut t,
                    );
                    out.frame
                }
                None => {
                    let f = render_adaptive(&g, &ctx, &buffer, lighting, args.seed)?;
                    lap(&mut times, &format!("{stem}: hierarchical shading"), &mut t);
                    f
                }
            };
            write_maps(args, stem, &g, &buffer, &f.shaded_level, &f.samples)?;
            writeln!(
                summary,
                "{stem}: {gw}×{gh} G-buffer, {surface} surface pixels: {} shaded ({:.1} %), {} up-sampled, {} samples ({:.2} per surface pixel)",
                f.stats.shaded,
                100.0 * f.stats.shaded as f64 / surface.max(1) as f64,
                f.stats.upsampled,
                f.stats.samples,
                f.stats.samples as f64 / surface.max(1) as f64
            )?;
            f.image
        } else {
            let (img, shaded, samples) = match gpu
                .as_mut()
                .and_then(|p| Some((&p.ctx, p.shading.as_mut()?)))
            {
                Some((gctx, (scene, pass))) => {
                    let out =
                        pass.render_brute(gctx, scene, &g, req.samples as usize, args.seed)?;
                    if let Some(ms) = out.timing.gpu_ms {
                        times.push((
                            format!("{stem}: brute-force shading (GPU timestamps)"),
                            ms * 1e-3,
                        ));
                    }
                    lap(
                        &mut times,
                        &format!("{stem}: brute-force shading (GPU, upload, read-back)"),
                        &mut t,
                    );
                    let st = out.frame.stats;
                    (out.frame.image, st.shaded, st.samples)
                }
                None => {
                    let (img, st) = render_brute(&g, &ctx, req.samples as usize, args.seed)?;
                    lap(&mut times, &format!("{stem}: brute-force shading"), &mut t);
                    (img, st.shaded, st.samples)
                }
            };
            writeln!(
                summary,
                "{stem}: {gw}×{gh} G-buffer, {shaded} surface pixels shaded with {} samples each ({samples} samples)",
                args.samples
            )?;
            img
        };
        let img = box_downsample(&full, k)?;
        img.write_exr(&args.out.join(format!("{stem}.exr")))?;
        img.write_png(&args.out.join(format!("{stem}.png")), args.exposure)?;
        if cameras.len() == 1 {
            compare(args, &img)?;
        }
    }
    let mut csv = String::from("stage,seconds\n");
    for (name, s) in &times {
        writeln!(csv, "{},{s:.6}", name.replace(',', ";"))?;
    }
    lustre_brdf::error::write_atomic(&args.out.join("times.csv"), csv.as_bytes())?;
    print!("{summary}");
    for (name, s) in &times {
        println!("  {name}: {:.3} s", s);
    }
    Ok(())
}

/// `--area-light`: the image at `path` as a square light facing down above the scene's bounds,
/// half as wide as the scene (at least 0.5 m), as high above its top as it is wide.
fn area_light(scene: &Scene, path: &std::path::Path, radiance: f64) -> anyhow::Result<AreaLight> {
    let loaded =
        lustre_env::read_map(path).with_context(|| format!("--area-light {}", path.display()))?;
    if let Some(w) = loaded.sanitized_warning(path) {
        eprintln!("warning: {w}");
    }
    let (lo, hi) = scene
        .bounds()
        .ok_or_else(|| anyhow::anyhow!("--area-light: the scene has no geometry to light"))?;
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let size = (0.5 * (hi.x - lo.x).max(hi.z - lo.z)).max(0.5);
    let centre = DVec3::new(0.5 * (lo.x + hi.x), hi.y + size, 0.5 * (lo.z + hi.z));
    let map = loaded.map;
    AreaLight::new(
        centre - DVec3::new(0.5 * size, 0.0, 0.5 * size),
        DVec3::new(size, 0.0, 0.0),
        DVec3::new(0.0, 0.0, size),
        Rgb::splat(radiance),
        Some((map.width, map.height, map.data)),
    )
    .with_context(|| format!("--area-light {}", path.display()))
}

/// Ends the stage `name` (its time since `t`) and starts the next.
fn lap(times: &mut Vec<(String, f64)>, name: &str, t: &mut Instant) {
    times.push((name.to_string(), t.elapsed().as_secs_f64()));
    *t = Instant::now();
}

/// The GPU's passes with the scene uploaded: the bandwidth pass (adaptive only) and the
/// shading. A pass the GPU cannot run (no adapter, a material or light it does not take) is an
/// error when `required`, else said and left to the CPU.
struct GpuPasses {
    ctx: GpuContext,
    bandwidth: Option<(BandwidthScene, BandwidthPass)>,
    shading: Option<(AdaptiveScene, AdaptivePass)>,
}

fn gpu_passes(
    ctx: &ShadingContext,
    env: &EnvironmentBandwidth,
    adaptive: bool,
    required: bool,
    scene: &lustre_scene::Scene,
) -> anyhow::Result<Option<GpuPasses>> {
    let fallback = |what: &str, e: anyhow::Error| -> anyhow::Result<()> {
        if required {
            Err(e.context(format!("--device gpu: {what}")))
        } else {
            eprintln!("{what} on the CPU: {e:#}");
            Ok(())
        }
    };
    let gctx = match GpuContext::new() {
        Ok(c) => c,
        Err(e) => {
            fallback("the whole frame", e.into())?;
            return Ok(None);
        }
    };
    // A software adapter (lavapipe) runs these passes on the same cores as the CPU path, at a
    // third of its samples per second (BENCHMARKS.md, "Adaptive shading on the GPU"): auto
    // keeps the CPU; --device gpu still runs them there.
    if !required && gctx.is_software() {
        eprintln!(
            "the whole frame on the CPU: the adapter {} is a software rasterizer, slower than \
             the CPU path (--device gpu runs the passes on it anyway)",
            gctx.describe()
        );
        return Ok(None);
    }
    let bandwidth = if adaptive {
        match BandwidthScene::from_context(&gctx, ctx, env, Some(scene))
            .and_then(|s| Ok((s, BandwidthPass::new(&gctx)?)))
        {
            Ok(b) => Some(b),
            Err(e) => {
                fallback("the bandwidth pass", e.into())?;
                None
            }
        }
    } else {
        None
    };
    let shading = match AdaptiveScene::from_context(&gctx, ctx, Some(scene))
        .and_then(|s| Ok((s, AdaptivePass::new(&gctx)?)))
    {
        Ok(p) => Some(p),
        Err(e) => {
            fallback("shading", e.into())?;
            None
        }
    };
    Ok(Some(GpuPasses {
        ctx: gctx,
        bandwidth,
        shading,
    }))
}

/// The bandwidth buffer's maps (004 Fig. IV.13, IV.22): b_p, the level ℓ_p, N_p at the shaded
/// pixels, and the level each pixel was shaded at (black: up-sampled or background).
fn write_maps(
    args: &RenderArgs,
    stem: &str,
    g: &GBuffer,
    buffer: &BandwidthBuffer,
    shaded: &[u8],
    samples: &[u32],
) -> anyhow::Result<()> {
    let (w, h) = (g.width, g.height);
    let maps: [(&str, Vec<f64>); 4] = [
        ("bandwidth", buffer.bandwidth.clone()),
        ("level", level_map(&buffer.level)),
        ("samples", samples.iter().map(|n| f64::from(*n)).collect()),
        ("shaded", level_map(shaded)),
    ];
    for (name, values) in maps {
        let path = args.out.join(format!("{stem}_{name}.png"));
        lustre_plot::heat::heat_map(&values, w, h, &path)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}
