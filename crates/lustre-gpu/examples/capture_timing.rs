//! Times the GPU probe capture, the GPU pyramid build and the GPU mirror / see-through passes
//! with [`GpuTimer`] (GPU timestamps where the adapter has `TIMESTAMP_QUERY`, and wall time
//! until the queue is idle), next to the CPU versions from the same run:
//! - Gauss 6×6 pyramid build from a base already on the GPU, 256², 512², 1024² faces (002
//!   Table 1: 5.97 ms for 1024² on a Quadro 6000), against `CubePyramid::build`;
//! - probe capture per probe object of the built-in room and the Modern Hall
//!   (`scenes/modern_hall.toml`), 128² faces, 2×2 samples per texel (the CPU's defaults),
//!   capture + filter, against `capture_cube` + `CubePyramid::build` (the bounding planes, on
//!   the CPU for both, are not timed);
//! - mirror pass (the floor) and see-through pass (the room's frosted glass) at 1680×1050
//!   against `render_mirror` / `render_see_through`.
//!
//! GPU figures are the median of `--repeat` runs after one warm-up; CPU figures one run. The
//! light maps come from a quick bake (1 path per texel, 4 texels/m): the timings do not depend
//! on their quality.
//!
//! `cargo run --release -p lustre-gpu --example capture_timing -- [--repeat N] [--no-cpu]`

use glam::DVec3;
use lustre_env::{CubeMap, CubePyramid, MipFilter};
use lustre_gpu::{
    mesh_triangles, GpuContext, GpuProbeCapture, GpuPyramidBuilder, GpuTimer, GpuViewPass,
    LightmapFrameScene, Timing, PYRAMID_USAGE,
};
use lustre_scene::lightmap::{build_atlas, AtlasOptions, LightmapAtlas};
use lustre_scene::Scene;
use lustre_shade::mirror::{render_mirror, render_see_through};
use lustre_shade::probe::{capture_cube, probe_placement, LitScene, ProbeOptions};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{assemble, bake_tiles, diffuse_path_scene, BakeOptions, Denoiser};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::path_camera;
use std::error::Error;
use std::time::Instant;
use wgpu::util::DeviceExt;

type Res<T> = std::result::Result<T, Box<dyn Error>>;

struct Baked {
    scene: Scene,
    atlas: LightmapAtlas,
    pages: Vec<Vec<[f32; 3]>>,
}

fn bake(mut scene: Scene) -> Res<Baked> {
    let (atlas, _) = build_atlas(
        &mut scene,
        &AtlasOptions {
            texels_per_metre: 4.0,
            ..AtlasOptions::default()
        },
    )?;
    let opts = BakeOptions {
        spp: 1,
        bounces: 2,
        seed: 5,
        denoiser: Denoiser::None,
        ..BakeOptions::default()
    };
    let dir = tempfile::tempdir()?;
    bake_tiles(&scene, &atlas, &opts, dir.path(), None, &|_, _| {})?;
    let pages = assemble(&scene, &atlas, &opts, dir.path())?.pages;
    Ok(Baked {
        scene,
        atlas,
        pages,
    })
}

/// Median of the GPU times (else of the wall times) of `repeat` runs after one warm-up, as
/// "gpu ms / wall ms".
fn time(
    ctx: &GpuContext,
    timer: &mut GpuTimer,
    repeat: usize,
    mut f: impl FnMut() -> Res<()>,
) -> Res<String> {
    f()?;
    let mut runs: Vec<Timing> = Vec::with_capacity(repeat);
    for _ in 0..repeat {
        timer.start(ctx)?;
        f()?;
        runs.push(timer.stop(ctx)?);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let wall = median(runs.iter().map(|t| t.wall_ms).collect());
    let gpu: Option<Vec<f64>> = runs.iter().map(|t| t.gpu_ms).collect();
    Ok(match gpu {
        Some(g) => format!("{:.1} ms GPU / {wall:.1} ms wall", median(g)),
        None => format!("— / {wall:.1} ms wall"),
    })
}

fn cpu_ms(f: impl FnOnce() -> Res<()>) -> Res<String> {
    let t = Instant::now();
    f()?;
    Ok(format!("{:.0} ms", t.elapsed().as_secs_f64() * 1e3))
}

fn main() -> Res<()> {
    let mut repeat = 5usize;
    let mut cpu = true;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--repeat" => {
                repeat = args
                    .next()
                    .ok_or("--repeat needs a number")?
                    .parse::<usize>()?
                    .max(1)
            }
            "--no-cpu" => cpu = false,
            _ => return Err(format!("unknown argument {a:?}").into()),
        }
    }
    let ctx = GpuContext::new()?;
    let mut timer = GpuTimer::new(&ctx);
    println!(
        "adapter: {}; GPU timestamps (TIMESTAMP_QUERY): {}; RAYON_NUM_THREADS: {}",
        ctx.describe(),
        if timer.has_timestamps() {
            "yes"
        } else {
            "no (wall time with device polling only)"
        },
        std::env::var("RAYON_NUM_THREADS").unwrap_or_else(|_| "unset (all cores)".into())
    );

    println!(
        "\n| Gauss 6×6 pyramid, base face | GPU (from a GPU base) | CPU `CubePyramid::build` |"
    );
    println!("|---:|---:|---:|");
    let builder = GpuPyramidBuilder::new(&ctx)?;
    let sun = DVec3::new(0.3, 0.8, -0.5).normalize();
    for n in [256usize, 512, 1024] {
        let base = CubeMap::from_fn(n, |d| {
            let d = d.normalize();
            let s = if d.dot(sun) > 0.9995 { 5000.0 } else { 0.0 };
            [0.3 + s, 0.5 + s, 0.9 * (0.5 + 0.5 * d.y) + s]
        })?;
        let texels: Vec<[f32; 4]> = base
            .faces
            .iter()
            .flat_map(|f| f.iter().map(|v| [v[0], v[1], v[2], 1.0]))
            .collect();
        let mut level0 = Vec::new();
        for _ in 0..=repeat {
            level0.push(
                ctx.device
                    .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("timing base"),
                        contents: bytemuck::cast_slice(&texels),
                        usage: PYRAMID_USAGE,
                    }),
            );
        }
        let gpu = time(&ctx, &mut timer, repeat, || {
            let b = level0.pop().ok_or("out of bases")?;
            builder.build_from_buffer(&ctx, b, n, MipFilter::Gauss6)?;
            Ok(())
        })?;
        let c = if cpu {
            cpu_ms(|| {
                CubePyramid::build(base.clone(), MipFilter::Gauss6)?;
                Ok(())
            })?
        } else {
            "—".into()
        };
        println!("| {n}² | {gpu} | {c} |");
    }

    let cap = GpuProbeCapture::new(&ctx)?;
    let pass = GpuViewPass::new(&ctx)?;
    let opts = ProbeOptions::default();
    let hall_path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/modern_hall.toml");
    let scenes = [
        ("built-in room", bake(lustre_scene::builtin::room()?)?),
        ("Modern Hall", bake(Scene::load(&hall_path)?)?),
    ];
    println!(
        "\n| probe capture ({}² faces, {}×{} per texel, Gauss 6×6) | GPU capture + filter | CPU ray cast + filter |",
        opts.face_size, opts.supersample, opts.supersample
    );
    println!("|---|---:|---:|");
    let mut view_rows = Vec::new();
    for (label, b) in &scenes {
        let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages)?;
        let (ps, bases, _) = diffuse_path_scene(&b.scene)?;
        let lm = Lightmapped::new(&b.scene, &b.atlas, &b.pages, &ps.geometry, bases)?;
        let pt = PathTracer::new(&ps, PathOptions::default())?;
        let lit = LitScene::new(&b.scene, &ps, &pt, &lm)?;
        for m in 0..b.scene.meshes.len() {
            if !b.scene.meshes[m].hints.probe {
                continue;
            }
            let (name, centre) = probe_placement(&lit, m)?;
            let skip = mesh_triangles(&b.scene, m)?;
            let gpu = time(&ctx, &mut timer, repeat, || {
                cap.capture(
                    &ctx,
                    &up,
                    centre,
                    Some(skip.clone()),
                    opts.face_size,
                    opts.supersample,
                    MipFilter::Gauss6,
                )?;
                Ok(())
            })?;
            let c = if cpu {
                cpu_ms(|| {
                    let cube = capture_cube(&lit, centre, Some(m as u32), &opts)?;
                    CubePyramid::build(cube, MipFilter::Gauss6)?;
                    Ok(())
                })?
            } else {
                "—".into()
            };
            println!(
                "| {label}: {name} ({} triangles) | {gpu} | {c} |",
                b.scene.meshes[m].indices.len()
            );
        }
        let (w, h) = (1680usize, 1050usize);
        let cam = path_camera(&b.scene, None, w as u32, h as u32)?;
        if let Some(floor) =
            (0..b.scene.meshes.len()).find(|&m| b.scene.meshes[m].hints.planar_reflector)
        {
            let gpu = time(&ctx, &mut timer, repeat, || {
                pass.render_mirror(&ctx, &up, &lit, floor, &cam, w, h)?;
                Ok(())
            })?;
            let c = if cpu {
                cpu_ms(|| {
                    render_mirror(&lit, floor, &cam, w, h)?;
                    Ok(())
                })?
            } else {
                "—".into()
            };
            view_rows.push(format!(
                "| {label}: mirror of {} | {gpu} | {c} |",
                b.scene.meshes[floor].name
            ));
        }
        if let Some(glass) = b
            .scene
            .meshes
            .iter()
            .position(|m| m.name == "frosted-glass")
        {
            let gpu = time(&ctx, &mut timer, repeat, || {
                pass.render_see_through(&ctx, &up, &lit, glass, &cam, w, h)?;
                Ok(())
            })?;
            let c = if cpu {
                cpu_ms(|| {
                    render_see_through(&lit, glass, &cam, w, h)?;
                    Ok(())
                })?
            } else {
                "—".into()
            };
            view_rows.push(format!(
                "| {label}: see-through frosted-glass | {gpu} | {c} |"
            ));
        }
    }
    println!("\n| view buffer 1680×1050 (with its MIP levels) | GPU | CPU ray cast |");
    println!("|---|---:|---:|");
    for r in view_rows {
        println!("{r}");
    }
    Ok(())
}
