//! 004 Fig. IV.15 on the GPU and the CPU side by side: adaptive shading against brute-force
//! importance sampling at equal PSNR, each device against its own brute-force curve, from one
//! run. The GPU runs the bandwidth pass and the hierarchical shading (lustre-gpu's
//! `bandwidth_pass` and `adaptive_pass`); the CPU their twins in lustre-adaptive. Both start
//! from the same G-buffer and tables; the levels and the variance target are assembled on the
//! CPU in both.
//!
//! `cargo run --release -p lustre-gpu --example adaptive_study_gpu -- [--size N]
//! [--reference N] [--map FILE] [--scene sphere|lineup] [--materials a,b,…]`
//!
//! The reference is the CPU's brute force with --reference samples per pixel in two
//! independent halves. Prints Markdown tables.

use lustre_adaptive::buffer::{BandwidthBuffer, BufferOptions, SampleRule};
use lustre_adaptive::compare::{time_at_psnr, Measured};
use lustre_adaptive::gbuffer::GBuffer;
use lustre_adaptive::hierarchy::{render_adaptive, render_brute};
use lustre_adaptive::shading::{Lighting, ShadingContext, ShadingOptions};
use lustre_gpu::passes::adaptive::{AdaptivePass, AdaptiveScene};
use lustre_gpu::passes::bandwidth::{BandwidthPass, BandwidthScene};
use lustre_gpu::GpuContext;
use lustre_trace::baked::read_environment;
use lustre_trace::image::Image;
use lustre_trace::metrics::{psnr, rms};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{film_camera, path_scene};
use std::path::PathBuf;
use std::time::Instant;

struct Args {
    size: usize,
    reference: usize,
    map: PathBuf,
    scene: String,
    materials: Vec<String>,
}

fn args() -> anyhow::Result<Args> {
    let mut a = Args {
        size: 128,
        reference: 2048,
        map: lustre_env::shared_data_dir().join("envmaps/royal_esplanade_1k.hdr"),
        scene: "sphere".into(),
        materials: [
            "gold-paint",
            "red-metallic-paint",
            "color-changing-paint3",
            "blue-rubber",
            "white-marble",
        ]
        .map(|m| format!("nbrdf:{m}"))
        .to_vec(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let mut v = || {
            it.next()
                .ok_or_else(|| anyhow::anyhow!("{k} needs a value"))
        };
        match k.as_str() {
            "--size" => a.size = v()?.parse()?,
            "--reference" => a.reference = v()?.parse()?,
            "--map" => a.map = v()?.into(),
            "--scene" => a.scene = v()?,
            "--materials" => a.materials = v()?.split(',').map(str::to_string).collect(),
            other => anyhow::bail!("unknown argument {other}"),
        }
    }
    Ok(a)
}

fn main() -> anyhow::Result<()> {
    let a = args()?;
    let env = read_environment(&a.map)?.0;
    let gpu = GpuContext::new()?;
    println!(
        "# Adaptive shading vs brute force, GPU and CPU side by side\n\n- GPU: {}\n- CPU: {} threads\n- map {}, {}² pixels, reference {} samples per pixel (CPU, two halves)\n",
        gpu.describe(),
        rayon::current_num_threads(),
        a.map.display(),
        a.size,
        a.reference
    );
    let cases: Vec<(String, lustre_scene::Scene)> = match a.scene.as_str() {
        "sphere" => a
            .materials
            .iter()
            .map(|m| {
                Ok((
                    m.clone(),
                    lustre_scene::builtin::preview(m, Some(env.clone()))?,
                ))
            })
            .collect::<anyhow::Result<_>>()?,
        "lineup" => {
            let m = |k: usize| a.materials.get(k).map_or("nbrdf:gold-paint", |s| s);
            vec![(
                "line-up".into(),
                lustre_scene::builtin::lineup([m(2), m(1), m(0)], m(4), Some(env.clone()))?,
            )]
        }
        other => anyhow::bail!("unknown scene {other} (sphere, lineup)"),
    };
    for (name, scene) in &cases {
        study(&a, &gpu, name, scene)?;
    }
    Ok(())
}

/// One device's brute-force curve and adaptive runs.
struct Runs {
    brute: Vec<Measured>,
    adaptive: Vec<(Measured, f64)>,
}

fn study(
    a: &Args,
    gpu: &GpuContext,
    name: &str,
    scene: &lustre_scene::Scene,
) -> anyhow::Result<()> {
    let (ps, _) = path_scene(scene)?;
    let tracer = PathTracer::new(&ps, PathOptions::default())?;
    let cam = film_camera(&scene.cameras[0], a.size as u32, a.size as u32)?;
    let g = GBuffer::render(&tracer, &ps, &cam, a.size, a.size)?;
    let ctx = ShadingContext::new(
        &ps,
        ShadingOptions {
            pyramid_face: 0,
            ..Default::default()
        },
        &|_, _| {},
    )?;
    let env_bw = ctx.environment_bandwidth()?;
    let half = (a.reference / 2).max(1);
    let (r1, _) = render_brute(&g, &ctx, half, 1_000_001)?;
    let (r2, _) = render_brute(&g, &ctx, half, 2_000_002)?;
    let reference = r1.average(&r2)?;
    let exposure = 0.5 / reference.mean().max(1e-9);
    let ref_psnr = psnr(&r1, &r2, exposure)? + 20.0 * 2f64.log10();
    let bw_scene = BandwidthScene::from_context(gpu, &ctx, &env_bw, Some(scene))?;
    let mut bw_pass = BandwidthPass::new(gpu)?;
    let shade_scene = AdaptiveScene::from_context(gpu, &ctx, Some(scene))?;
    let mut pass = AdaptivePass::new(gpu)?;
    // Warm-ups: llvmpipe compiles a shader at its first dispatch.
    pass.render_brute(gpu, &shade_scene, &g, 1, 1)?;
    bw_pass.predict(gpu, &bw_scene, &g, &ctx, 16)?;

    let score = |img: &Image| psnr(&reference, img, exposure);
    let mut cpu = Runs {
        brute: vec![],
        adaptive: vec![],
    };
    let mut on_gpu = Runs {
        brute: vec![],
        adaptive: vec![],
    };
    for n in [1usize, 2, 4, 8, 16, 32, 64, 128, 256, 512] {
        let t = Instant::now();
        let (img, st) = render_brute(&g, &ctx, n, 7)?;
        let time_s = t.elapsed().as_secs_f64();
        cpu.brute.push(Measured {
            label: format!("brute {n}"),
            time_s,
            psnr: score(&img)?,
            samples: st.samples,
            shaded: st.shaded,
        });
        let t = Instant::now();
        let out = pass.render_brute(gpu, &shade_scene, &g, n, 7)?;
        let time_s = t.elapsed().as_secs_f64();
        on_gpu.brute.push(Measured {
            label: format!("brute {n}"),
            time_s,
            psnr: score(&out.frame.image)?,
            samples: out.frame.stats.samples,
            shaded: out.frame.stats.shaded,
        });
    }
    for rate in [2.0, 1.0] {
        for mean_samples in [16.0, 64.0, 256.0] {
            let options = BufferOptions {
                mean_samples,
                scale: SampleRule::Constant,
                rate,
                ..Default::default()
            };
            let label = format!("adaptive rate {rate}, N_p {mean_samples}");
            let t = Instant::now();
            let buffer = BandwidthBuffer::build(&g, &ctx, &env_bw, options)?;
            let t_bw = t.elapsed().as_secs_f64();
            let f = render_adaptive(&g, &ctx, &buffer, Lighting::Direct, 7)?;
            let time_s = t.elapsed().as_secs_f64();
            cpu.adaptive.push((
                Measured {
                    label: label.clone(),
                    time_s,
                    psnr: score(&f.image)?,
                    samples: f.stats.samples,
                    shaded: f.stats.shaded,
                },
                t_bw,
            ));
            let t = Instant::now();
            let (estimates, _) = bw_pass.predict(gpu, &bw_scene, &g, &ctx, 16)?;
            let buffer = BandwidthBuffer::assemble(&g, &estimates, options)?;
            let t_bw = t.elapsed().as_secs_f64();
            let out = pass.render(gpu, &shade_scene, &g, &buffer, None, 7)?;
            let time_s = t.elapsed().as_secs_f64();
            on_gpu.adaptive.push((
                Measured {
                    label,
                    time_s,
                    psnr: score(&out.frame.image)?,
                    samples: out.frame.stats.samples,
                    shaded: out.frame.stats.shaded,
                },
                t_bw,
            ));
        }
    }
    let cpu_gpu_rms = {
        let (a_cpu, _) = render_brute(&g, &ctx, 64, 9)?;
        let a_gpu = pass.render_brute(gpu, &shade_scene, &g, 64, 9)?;
        rms(&a_cpu, &a_gpu.frame.image)? / reference.mean().max(1e-9)
    };
    println!(
        "## {name}\n\n- {} surface pixels; reference PSNR against the truth ≈ {ref_psnr:.1} dB; brute force 64 spp, GPU vs CPU from the same seed: RMS {cpu_gpu_rms:.1e} of the mean\n",
        g.surface_pixels()
    );
    println!("| device | renderer | time (s) | bandwidth pass, buffer (s) | PSNR (dB) | samples | shaded pixels | brute force at equal PSNR (s) | speed-up |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (device, runs) in [("CPU", &cpu), ("GPU", &on_gpu)] {
        for m in &runs.brute {
            println!(
                "| {device} | {} | {:.4} | – | {:.2} | {} | {} | | |",
                m.label, m.time_s, m.psnr, m.samples, m.shaded
            );
        }
        for (m, t_bw) in &runs.adaptive {
            let equal = time_at_psnr(&runs.brute, m.psnr);
            println!(
                "| {device} | {} | {:.4} | {:.4} | {:.2} | {} | {} | {} | {} |",
                m.label,
                m.time_s,
                t_bw,
                m.psnr,
                m.samples,
                m.shaded,
                equal.map_or("–".into(), |e| format!("{e:.4}")),
                equal.map_or("–".into(), |e| format!("{:.1}×", e / m.time_s)),
            );
        }
    }
    println!();
    Ok(())
}
