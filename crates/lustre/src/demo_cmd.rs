//! `lustre demo`: renders the built-in scene (procedural sky, three Kurt spheres — anisotropic
//! metal, frosted glass, plastic — on a glossy floor) with regular sampling, writes a PNG and
//! prints its PSNR against a Monte-Carlo reference.

use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use lustre_env::{CubeMap, MipFilter};
use lustre_shade::harness::{self, EnvSetup};
use lustre_shade::integrator::{self, Weighting};
use lustre_shade::pattern::ConcentricOptions;
use lustre_shade::render;
use lustre_trace::metrics;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `lustre demo`.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {
    /// Output PNG.
    #[arg(long, default_value = "lustre-demo.png")]
    pub out: PathBuf,
    /// Image size as WIDTHxHEIGHT.
    #[arg(long, default_value = "480x270")]
    pub size: String,
    /// Regular samples per lobe (1–1024).
    #[arg(long, default_value_t = 16)]
    pub samples: usize,
    /// Reference samples per pixel (for the printed PSNR; at most 2²⁰).
    #[arg(long, default_value_t = 512)]
    pub reference_spp: usize,
    /// Exposure of the PNG and of the PSNR: finite and > 0.
    #[arg(long, default_value_t = 1.0, value_parser = crate::render_cmd::parse_exposure)]
    pub exposure: f64,
    /// Render on the CPU (lustre-shade) instead of the GPU (lustre-gpu; without an adapter the
    /// demo falls back to the CPU).
    #[arg(long)]
    pub cpu: bool,
    /// Run even when the job's memory or disk estimate exceeds what the machine has.
    #[arg(long)]
    pub force: bool,
}

/// Parses `WxH` (both > 0).
pub fn parse_size(s: &str) -> anyhow::Result<(usize, usize)> {
    let parse = |v: &str| v.trim().parse::<usize>().ok().filter(|&n| n > 0);
    match s.split_once(['x', 'X']) {
        Some((w, h)) => match (parse(w), parse(h)) {
            (Some(w), Some(h)) => Ok((w, h)),
            _ => bail!("--size {s:?}: width and height must be positive integers, e.g. 640x360"),
        },
        None => bail!("--size {s:?}: expected WIDTHxHEIGHT, e.g. 640x360"),
    }
}

fn bar(label: &str, len: usize) -> ProgressBar {
    let b = ProgressBar::new(len as u64);
    b.set_style(
        ProgressStyle::with_template("{msg:12} [{bar:30}] {pos}/{len} rows, {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    b.set_message(label.to_string());
    b
}

/// Runs `lustre demo`.
pub fn run(args: &DemoArgs) -> anyhow::Result<()> {
    let png = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        bail!(
            "--out {}: the demo writes a PNG image; give a file name ending in .png",
            args.out.display()
        );
    }
    let (w, h) = parse_size(&args.size)?;
    crate::render_cmd::check_side(
        u32::try_from(w).unwrap_or(u32::MAX),
        u32::try_from(h).unwrap_or(u32::MAX),
    )?;
    if args.samples == 0 || args.reference_spp == 0 {
        bail!("--samples and --reference-spp must be > 0");
    }
    if args.reference_spp > 1 << 20 {
        bail!(
            "--reference-spp {}: at most {}",
            args.reference_spp,
            1 << 20
        );
    }
    let most = lustre_gpu::MAX_LOBE_LOOKUPS as usize;
    if args.samples > most {
        bail!(
            "--samples {}: at most {most} a lobe (the GPU pass's limit; the CPU keeps it too, \
             so both render the same image)",
            args.samples
        );
    }
    let pixels = (w as u64).saturating_mul(h as u64);
    let need = lustre_brdf::budget::Budget::new(format!("lustre demo at {w}×{h}"), "lower --size")
        .memory(
            "GPU device",
            u64::from(!args.cpu),
            crate::budget::DEMO_GPU_DEVICE,
        )
        .memory(
            "images",
            pixels,
            if args.cpu {
                crate::budget::DEMO_PIXEL_CPU
            } else {
                crate::budget::DEMO_PIXEL_GPU
            },
        )
        .disk(&args.out, "PNG", pixels, 3);
    crate::budget::check(&need, args.force)?;
    let gpu = if args.cpu {
        None
    } else {
        match lustre_gpu::GpuContext::new()
            .and_then(|ctx| Ok((lustre_gpu::GpuRenderer::new(&ctx)?, ctx)))
        {
            Ok(g) => Some(g),
            Err(e) => {
                eprintln!("note: {e}; rendering on the CPU");
                None
            }
        }
    };
    let t0 = Instant::now();
    let base = CubeMap::from_fn(128, harness::procedural_sky)?;
    let env_setup = EnvSetup::new(base, MipFilter::Gauss6, 16)?;
    let env = env_setup.environment();
    let scene = harness::demo_scene()?;
    scene.validate()?;
    let plans = scene
        .materials
        .iter()
        .map(|m| {
            // The concentric pattern with its rings reaching θmax: measured better than the
            // printed radii (`lustre compare`, lustre-shade examples/regular_study.rs).
            integrator::plan_regular_with(
                m,
                args.samples,
                0.2,
                ConcentricOptions { reach: Some(1.0) },
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let t_env = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    let img = if let Some((renderer, _)) = &gpu {
        renderer.render(&scene, &plans, &env, w, h)?
    } else {
        let pb = bar("regular", h);
        let img = render::render_with_progress(
            &scene,
            w,
            h,
            |hit| {
                integrator::shade_regular(
                    &hit.frame,
                    hit.wo,
                    &plans[hit.material],
                    &env,
                    Weighting::Pdf002,
                )
            },
            harness::background(&env),
            &|r| pb.set_position(r as u64),
        );
        pb.finish_and_clear();
        img
    };
    let t_regular = t1.elapsed().as_secs_f64();

    let pb = bar("reference", h);
    let t2 = Instant::now();
    let reference = harness::render_reference(&scene, &env, w, h, args.reference_spp, 1, &|r| {
        pb.set_position(r as u64)
    });
    let t_reference = t2.elapsed().as_secs_f64();
    pb.finish_and_clear();

    img.write_png(&args.out, args.exposure)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let psnr = metrics::psnr(&img, &reference, args.exposure)?;
    let rms = metrics::rms(&img, &reference)?;
    match &gpu {
        Some((_, ctx)) => println!("renderer: GPU (lustre-gpu, {})", ctx.describe()),
        None => println!(
            "renderer: CPU (lustre-shade, {} threads)",
            rayon::current_num_threads()
        ),
    }
    println!(
        "scene: 3 spheres (anisotropic metal, frosted glass, plastic) on a glossy floor, {w}×{h}, regular sampling ({} samples per lobe, 002 weighting)",
        args.samples
    );
    println!(
        "time: environment {t_env:.2} s, regular render {t_regular:.2} s, reference ({} spp) {t_reference:.2} s",
        args.reference_spp
    );
    println!(
        "PSNR against the reference: {psnr:.2} dB (RMS {rms:.5}; the reference's own noise included)"
    );
    println!("wrote {}", args.out.display());
    Ok(())
}
