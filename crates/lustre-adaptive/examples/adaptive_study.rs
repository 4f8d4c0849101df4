//! 004 Fig. IV.15–IV.17 on the CPU: adaptive shading against brute-force importance sampling at
//! equal PSNR, the predicted against the measured per-pixel variance, and the effect of n_b.
//!
//! `cargo run --release -p lustre-adaptive --example adaptive_study -- [--size N]
//! [--reference N] [--map FILE] [--scene sphere|lineup|FILE] [--materials a,b,…] [--out DIR] [--aa]
//! [--rates 2,1] [--n-b 16,8] [--speed-only [--preconvolved] [--coverage]] [--repeat N]`
//! (`--aa`: only Fig. IV.14's anti-aliasing costs, at 1, 4 and 16 sub-pixels per pixel)
//!
//! `--scene FILE` studies a scene file from its first camera, lit by its environment (`--map`
//! is for the built-in scenes) and its planar emitters as area lights
//! (`lustre_adaptive::light::scene_lights`).
//!
//! Prints Markdown tables; with `--out`, writes each case's images (reference, brute force and
//! adaptive at equal PSNR, the level and N_p maps). `--rates` sets the sampling rates of the
//! constant-N_p rows (samples per cycle of b_p; 2 and 1 by default), `--n-b` the incident
//! directions of the bandwidth pass (`buffer::DEFAULT_N_B` by default; 004 uses 16; every row
//! is repeated for each);
//! `--speed-only` prints only the constant-N_p rows, without the sample rules, pre-convolved
//! shading and Fig. IV.16–IV.17; `--preconvolved` adds pre-convolved constant-N_p rows at
//! every rate to them, `--coverage` rows with N_p by the level's coverage
//! (`SampleRule::Coverage`) beside every constant-N_p row. Each adaptive row gives its speed-up
//! (brute force's time at its PSNR over its time) and, beside it, brute force's samples at its
//! PSNR over its samples, which does not move between runs. `--repeat N` times every row of
//! Fig. IV.15 (brute force and adaptive) as the least of N runs, which steadies the speed-ups on
//! a shared machine. With pre-convolved rows, each case first says where their lookups read the
//! pyramid (the BRDF's largest bandwidth, the level, the share of pixels at level 0).

use lustre_adaptive::buffer::{
    level_map, BandwidthBuffer, BrdfWeights, BufferOptions, SampleRule, NO_LEVEL,
};
use lustre_adaptive::compare::{samples_at_psnr, time_at_psnr, Measured};
use lustre_adaptive::gbuffer::GBuffer;
use lustre_adaptive::hierarchy::{box_downsample, render_adaptive, render_brute};
use lustre_adaptive::light::scene_lights;
use lustre_adaptive::shading::{Lighting, ShadingContext, ShadingOptions};
use lustre_freq::pixel::EnvironmentBandwidth;
use lustre_trace::baked::read_environment;
use lustre_trace::image::Image;
use lustre_trace::metrics::{psnr, rms};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};
use std::path::PathBuf;
use std::time::Instant;

struct Args {
    size: usize,
    reference: usize,
    map: PathBuf,
    scene: String,
    materials: Vec<String>,
    out: Option<PathBuf>,
    aa: bool,
    /// Rates of the constant-N_p rows (direct lighting); 1 and 2 by default.
    rates: Vec<f64>,
    /// Only Fig. IV.15's constant-N_p rows, without Fig. IV.16–IV.17.
    speed_only: bool,
    /// The n_b of Fig. IV.15's rows (`buffer::DEFAULT_N_B` by default), each with every row.
    n_bs: Vec<usize>,
    /// Where the bandwidth pass reads ρ (`--weights tabulated,evaluated`; the default's only).
    weights: Vec<BrdfWeights>,
    /// With `--speed-only`, also the pre-convolved constant-N_p rows at every rate.
    preconvolved: bool,
    /// Also rows with N_p by the level's coverage (`SampleRule::Coverage`) beside every
    /// constant-N_p row.
    coverage: bool,
    /// Times of Fig. IV.15's rows: the least of this many runs (brute force and adaptive alike).
    repeat: usize,
}

fn args() -> anyhow::Result<Args> {
    let data = lustre_env::shared_data_dir();
    let mut a = Args {
        size: 256,
        reference: 2048,
        map: data.join("envmaps/royal_esplanade_1k.hdr"),
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
        out: None,
        aa: false,
        rates: vec![2.0, 1.0],
        speed_only: false,
        n_bs: vec![lustre_adaptive::buffer::DEFAULT_N_B],
        weights: vec![BufferOptions::default().weights],
        preconvolved: false,
        coverage: false,
        repeat: 1,
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
            "--out" => a.out = Some(v()?.into()),
            "--aa" => a.aa = true,
            "--rates" => {
                a.rates = v()?
                    .split(',')
                    .map(|r| r.trim().parse::<f64>())
                    .collect::<Result<_, _>>()?
            }
            "--speed-only" => a.speed_only = true,
            "--preconvolved" => a.preconvolved = true,
            "--coverage" => a.coverage = true,
            "--repeat" => a.repeat = v()?.parse::<usize>()?.max(1),
            "--n-b" => {
                a.n_bs = v()?
                    .split(',')
                    .map(|r| r.trim().parse::<usize>())
                    .collect::<Result<_, _>>()?
            }
            "--weights" => {
                a.weights = v()?
                    .split(',')
                    .map(|w| match w.trim() {
                        "tabulated" => Ok(BrdfWeights::Tabulated),
                        "evaluated" => Ok(BrdfWeights::Evaluated),
                        other => Err(anyhow::anyhow!(
                            "--weights: {other:?} (tabulated or evaluated)"
                        )),
                    })
                    .collect::<anyhow::Result<_>>()?
            }
            other => anyhow::bail!("unknown argument {other}"),
        }
    }
    Ok(a)
}

fn main() -> anyhow::Result<()> {
    let a = args()?;
    let env = read_environment(&a.map)?.0;
    println!(
        "# Adaptive shading vs brute force (CPU, {} threads)\n\n- map {}, {}² pixels{}\n",
        rayon::current_num_threads(),
        a.map.display(),
        a.size,
        if a.aa {
            String::new()
        } else {
            format!(", reference {} samples per pixel (two halves)", a.reference)
        }
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
        file => {
            let path = PathBuf::from(file);
            if !path.is_file() {
                anyhow::bail!("--scene {file}: neither sphere, lineup nor a scene file");
            }
            let name = path
                .file_stem()
                .map_or_else(|| file.to_string(), |s| s.to_string_lossy().into_owned());
            vec![(name, lustre_scene::Scene::load(&path)?)]
        }
    };
    for (name, scene) in &cases {
        if a.aa {
            aa_study(&a, name, scene)?;
        } else {
            study(&a, name, scene)?;
        }
    }
    Ok(())
}

fn study(a: &Args, name: &str, scene: &lustre_scene::Scene) -> anyhow::Result<()> {
    let (ps, _) = path_scene(scene)?;
    let tracer = PathTracer::new(&ps, PathOptions::default())?;
    let cam = path_camera(scene, None, a.size as u32, a.size as u32)?;
    let t = Instant::now();
    let g = GBuffer::render(&tracer, &ps, &cam, a.size, a.size)?;
    let t_g = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut ctx = ShadingContext::new(&ps, ShadingOptions::default(), &|_, _| {})?;
    // The scene's planar emitters light it besides its environment (none on the built-ins).
    ctx.lights = scene_lights(&ps)?;
    ctx.check_lit()?;
    let t_tables = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let env_bw = ctx.environment_bandwidth()?;
    let t_env = t.elapsed().as_secs_f64();
    // The reference: two independent halves, their mean; its noise is half their RMS difference.
    let half = (a.reference / 2).max(1);
    let (r1, _) = render_brute(&g, &ctx, half, 1_000_001)?;
    let (r2, _) = render_brute(&g, &ctx, half, 2_000_002)?;
    let reference = r1.average(&r2)?;
    let exposure = 0.5 / reference.mean().max(1e-9);
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir)?;
        reference.write_png(&dir.join(format!("{}_reference.png", slug(name))), exposure)?;
    }
    let ref_noise = rms(&r1, &r2)? / 2.0;
    let ref_psnr = psnr(&r1, &r2, exposure)? + 20.0 * 2f64.log10();
    println!(
        "## {name}\n\n- G-buffer {:.3} s, material tables {:.2} s, environment bandwidth {:.3} s (each once per scene)\n- {} surface pixels; reference noise RMS {:.2e} (PSNR of the reference against the truth ≈ {:.1} dB)\n",
        t_g,
        t_tables,
        t_env,
        g.surface_pixels(),
        ref_noise,
        ref_psnr
    );
    let mut brute = vec![];
    for n in [1usize, 2, 4, 8, 16, 32, 64, 128, 256, 512] {
        // The least of `--repeat` wall times (the render is deterministic).
        let mut time_s = f64::INFINITY;
        let mut out = None;
        for _ in 0..a.repeat {
            let t = Instant::now();
            out = Some(render_brute(&g, &ctx, n, 7)?);
            time_s = time_s.min(t.elapsed().as_secs_f64());
        }
        let (img, st) = out.ok_or_else(|| anyhow::anyhow!("--repeat 0"))?;
        let p = psnr(&reference, &img, exposure)?;
        brute.push((
            img,
            Measured {
                label: format!("brute {n}"),
                time_s,
                psnr: p,
                samples: st.samples,
                shaded: st.shaded,
            },
        ));
    }
    if a.preconvolved || !a.speed_only {
        preconvolved_levels(&g, &ctx, &env_bw)?;
    }
    println!("| renderer | time (s) | bandwidth pass (s) | PSNR (dB) | samples | shaded pixels | brute-force time at equal PSNR (s) | speed-up | brute-force samples at equal PSNR ÷ samples |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    let curve: Vec<Measured> = brute.iter().map(|(_, m)| m.clone()).collect();
    for m in &curve {
        println!(
            "| {} | {:.3} | – | {:.2} | {} | {} | | | |",
            m.label, m.time_s, m.psnr, m.samples, m.shaded
        );
    }
    let mut rows = vec![];
    if !a.speed_only {
        rows.push((Lighting::Direct, SampleRule::Absolute, 2.0));
    }
    let mut rules = vec![SampleRule::Constant];
    if a.coverage {
        rules.push(SampleRule::Coverage);
    }
    let mut lightings = vec![Lighting::Direct];
    if a.speed_only && a.preconvolved {
        lightings.push(Lighting::Preconvolved);
    }
    for &l in &lightings {
        for &rule in &rules {
            rows.extend(a.rates.iter().map(|&r| (l, rule, r)));
        }
    }
    if !a.speed_only {
        rows.extend([
            (Lighting::Direct, SampleRule::Relative, 2.0),
            (Lighting::Direct, SampleRule::RelativeMse, 2.0),
            (Lighting::Preconvolved, SampleRule::Relative, 2.0),
            (Lighting::Preconvolved, SampleRule::Constant, 2.0),
            (Lighting::Preconvolved, SampleRule::Constant, 1.0),
        ]);
    }
    let rows: Vec<(Lighting, SampleRule, f64, usize, BrdfWeights)> = a
        .weights
        .iter()
        .flat_map(|&w| a.n_bs.iter().map(move |&n_b| (n_b, w)))
        .flat_map(|(n_b, w)| rows.iter().map(move |&(l, s, r)| (l, s, r, n_b, w)))
        .collect();
    for (lighting, scale, rate, n_b, weights) in rows {
        let means: &[f64] = if matches!(scale, SampleRule::Constant | SampleRule::Coverage) {
            &[1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0, 128.0, 256.0]
        } else {
            &[1.0, 2.0, 4.0, 8.0, 16.0, 32.0, 64.0]
        };
        for &mean_samples in means {
            // The least of `--repeat` wall times, for the pass and for the whole frame.
            let (mut t_bw, mut time_s) = (f64::INFINITY, f64::INFINITY);
            let mut out = None;
            for _ in 0..a.repeat {
                let t = Instant::now();
                let buffer = BandwidthBuffer::build(
                    &g,
                    &ctx,
                    &env_bw,
                    BufferOptions {
                        n_b,
                        mean_samples,
                        lighting,
                        scale,
                        rate,
                        weights,
                        ..Default::default()
                    },
                )?;
                t_bw = t_bw.min(t.elapsed().as_secs_f64());
                let f = render_adaptive(&g, &ctx, &buffer, lighting, 7)?;
                time_s = time_s.min(t.elapsed().as_secs_f64());
                out = Some((buffer, f));
            }
            let (buffer, f) = out.ok_or_else(|| anyhow::anyhow!("--repeat 0"))?;
            let p = psnr(&reference, &f.image, exposure)?;
            let equal = time_at_psnr(&curve, p);
            let equal_samples = samples_at_psnr(&curve, p);
            let pictured = mean_samples == 32.0
                && rate == 2.0
                && lighting == Lighting::Direct
                && matches!(scale, SampleRule::Constant | SampleRule::Absolute);
            if let (Some(dir), true) = (&a.out, pictured) {
                let tag = format!(
                    "{}_{}_{:?}_{}",
                    slug(name),
                    if lighting == Lighting::Preconvolved {
                        "pre"
                    } else {
                        "direct"
                    },
                    scale,
                    mean_samples
                );
                std::fs::create_dir_all(dir)?;
                f.image
                    .write_png(&dir.join(format!("{tag}.png")), exposure)?;
                let maps = [
                    ("shaded", level_map(&f.shaded_level)),
                    ("level", level_map(&buffer.level)),
                    ("samples", f.samples.iter().map(|v| f64::from(*v)).collect()),
                ];
                for (what, values) in maps {
                    let path = dir.join(format!("{tag}_{what}.png"));
                    lustre_plot::heat::heat_map(&values, g.width, g.height, &path)?;
                }
                eprintln!(
                    "{tag}: per level (shaded, up-sampled) {:?}",
                    f.stats.per_level
                );
            }
            println!(
                "| adaptive{}{}{} mean {} | {:.3} | {:.3} | {:.2} | {} | {} | {} | {} | {} |",
                if lighting == Lighting::Preconvolved {
                    " pre-convolved"
                } else {
                    ""
                },
                match scale {
                    SampleRule::Absolute => " (004's absolute V)",
                    SampleRule::Constant => " (constant N_p)",
                    SampleRule::Coverage => " (N_p by coverage)",
                    SampleRule::Relative => "",
                    SampleRule::RelativeMse => " (N_p ∝ σ)",
                },
                if rate == 1.0 {
                    ", Eq. IV.11 as printed (1 sample per cycle)".to_string()
                } else if rate == 2.0 {
                    String::new()
                } else {
                    format!(", rate {rate}")
                } + &if n_b == lustre_adaptive::buffer::DEFAULT_N_B {
                    String::new()
                } else {
                    format!(", n_b {n_b}")
                } + if weights == BufferOptions::default().weights {
                    ""
                } else {
                    ", ρ evaluated"
                },
                mean_samples,
                time_s,
                t_bw,
                p,
                f.stats.samples,
                f.stats.shaded,
                equal.map_or("–".into(), |e| format!("{e:.3}")),
                equal.map_or("–".into(), |e| format!("{:.1}×", e / time_s)),
                equal_samples.map_or("–".into(), |e| format!(
                    "{:.1}×",
                    e / f.stats.samples.max(1) as f64
                )),
            );
        }
    }
    println!();
    if !a.speed_only {
        validation(&g, &ctx, &env_bw, &reference)?;
        n_b_study(&g, &ctx, &env_bw, &reference, exposure)?;
    }
    Ok(())
}

/// Fig. IV.14 (right): the cost of k × k anti-aliasing, brute force (every sub-pixel shaded)
/// against adaptive shading of the supersampled G-buffer (sub-pixels shaded only where the
/// bandwidth asks), both with 32 samples per shaded sub-pixel, and the exponent of time against
/// sub-pixels per pixel.
fn aa_study(a: &Args, name: &str, scene: &lustre_scene::Scene) -> anyhow::Result<()> {
    let (ps, _) = path_scene(scene)?;
    let tracer = PathTracer::new(&ps, PathOptions::default())?;
    let mut ctx = ShadingContext::new(&ps, ShadingOptions::default(), &|_, _| {})?;
    // The scene's planar emitters light it besides its environment (none on the built-ins).
    ctx.lights = scene_lights(&ps)?;
    ctx.check_lit()?;
    let env_bw = ctx.environment_bandwidth()?;
    println!(
        "## {name}: anti-aliasing, {}² pixels, 32 samples per shaded sub-pixel\n",
        a.size
    );
    println!("| sub-pixels | brute force (s) | adaptive (s) | of which bandwidth pass (s) | sub-pixels shaded, adaptive | speed-up |");
    println!("|---:|---:|---:|---:|---:|---:|");
    let mut rows = vec![];
    for k in [1usize, 2, 4] {
        let (w, h) = (a.size * k, a.size * k);
        let cam = path_camera(scene, None, w as u32, h as u32)?;
        let g = GBuffer::render(&tracer, &ps, &cam, w, h)?;
        let t = Instant::now();
        let (img, _) = render_brute(&g, &ctx, 32, 7)?;
        let _ = box_downsample(&img, k)?;
        let t_brute = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let buffer = BandwidthBuffer::build(
            &g,
            &ctx,
            &env_bw,
            BufferOptions {
                mean_samples: 32.0,
                scale: SampleRule::Constant,
                ..Default::default()
            },
        )?;
        let t_bw = t.elapsed().as_secs_f64();
        let f = render_adaptive(&g, &ctx, &buffer, Lighting::Direct, 7)?;
        let _ = box_downsample(&f.image, k)?;
        let t_ad = t.elapsed().as_secs_f64();
        println!(
            "| {} | {t_brute:.3} | {t_ad:.3} | {t_bw:.3} | {} of {} | {:.1}× |",
            k * k,
            f.stats.shaded,
            g.surface_pixels(),
            t_brute / t_ad
        );
        rows.push((t_brute, t_ad));
    }
    // From 1 to 16 sub-pixels per pixel.
    let exponent = |a: f64, b: f64| (b / a).ln() / 16f64.ln();
    println!(
        "\nTime ∝ (sub-pixels)^e from 1 to 16: brute force e = {:.2}, adaptive e = {:.2}.\n",
        exponent(rows[0].0, rows[2].0),
        exponent(rows[0].1, rows[2].1)
    );
    Ok(())
}

/// Fig. IV.16: the predicted bound 4π² S_p (Eq. IV.9) against the variance of our estimator
/// measured over 32 seeds at 2 samples (×2: per sample), and the predicted b_p against the
/// local bandwidth of the reference image (the wavelet estimator of lustre-freq, cycles per
/// pixel).
fn validation(
    g: &GBuffer,
    ctx: &ShadingContext,
    env_bw: &EnvironmentBandwidth,
    reference: &Image,
) -> anyhow::Result<()> {
    let buffer = BandwidthBuffer::build(
        g,
        ctx,
        env_bw,
        BufferOptions {
            scale: SampleRule::Absolute,
            ..Default::default()
        },
    )?;
    let seeds = 32;
    let n = g.width * g.height;
    let (mut s1, mut s2) = (vec![0.0f64; n], vec![0.0f64; n]);
    for seed in 0..seeds {
        let (img, _) = render_brute(g, ctx, 2, 100 + seed)?;
        for (k, p) in img.data.iter().enumerate() {
            let l = lustre_brdf::rgb::Rgb([p[0].into(), p[1].into(), p[2].into()]).luminance();
            s1[k] += l;
            s2[k] += l * l;
        }
    }
    let lum: Vec<f64> = reference
        .data
        .iter()
        .map(|p| lustre_brdf::rgb::Rgb([p[0].into(), p[1].into(), p[2].into()]).luminance())
        .collect();
    let measured_bw = lustre_freq::wavelet::local_bandwidth(
        &lum,
        g.width,
        g.height,
        lustre_freq::wavelet::Edges::Reflect,
    )?;
    let (mut var_pairs, mut bw_pairs) = (vec![], vec![]);
    for k in 0..n {
        if buffer.level[k] == lustre_adaptive::buffer::NO_LEVEL {
            continue;
        }
        let m = s1[k] / seeds as f64;
        let v = 2.0 * (s2[k] / seeds as f64 - m * m).max(0.0) * seeds as f64 / (seeds - 1) as f64;
        let predicted = 4.0 * std::f64::consts::PI.powi(2) * buffer.variance[k];
        if v > 0.0 && predicted > 0.0 {
            var_pairs.push((predicted, v));
        }
        if buffer.bandwidth[k] > 0.0 && measured_bw[k] > 0.0 {
            bw_pairs.push((buffer.bandwidth[k], measured_bw[k]));
        }
    }
    let corr = |pairs: &[(f64, f64)]| -> f64 {
        let n = pairs.len() as f64;
        let (a, b): (Vec<f64>, Vec<f64>) = pairs.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
        let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
        let cov: f64 = a.iter().zip(&b).map(|(x, y)| (x - ma) * (y - mb)).sum();
        let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
        let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
        cov / (va * vb).sqrt()
    };
    let conservative = |pairs: &[(f64, f64)]| {
        100.0 * pairs.iter().filter(|(p, m)| p >= m).count() as f64 / pairs.len().max(1) as f64
    };
    let median_ratio = |pairs: &[(f64, f64)]| {
        let mut r: Vec<f64> = pairs.iter().map(|(p, m)| p / m).collect();
        r.sort_by(f64::total_cmp);
        r.get(r.len() / 2).copied().unwrap_or(f64::NAN)
    };
    println!(
        "Fig. IV.16 validation ({} / {} surface pixels with both values positive):
",
        var_pairs.len(),
        bw_pairs.len()
    );
    println!(
        "| quantity | correlation of logs | predicted ≥ measured | median predicted / measured |"
    );
    println!("|---|---:|---:|---:|");
    println!(
        "| variance: 4π² S_p (Eq. IV.9) vs our estimator's per-sample variance (32 seeds × 2 samples) | {:.3} | {:.1} % | {:.3e} |",
        corr(&var_pairs),
        conservative(&var_pairs),
        median_ratio(&var_pairs)
    );
    println!(
        "| image bandwidth: b_p (Eq. IV.7) vs the reference's local bandwidth (wavelets), cycles/pixel | {:.3} | {:.1} % | {:.3e} |\n",
        corr(&bw_pairs),
        conservative(&bw_pairs),
        median_ratio(&bw_pairs)
    );
    Ok(())
}

/// Fig. IV.17: n_b = 4 … 1024 at a constant N_p of 32.
fn n_b_study(
    g: &GBuffer,
    ctx: &ShadingContext,
    env_bw: &EnvironmentBandwidth,
    reference: &Image,
    exposure: f64,
) -> anyhow::Result<()> {
    println!("Fig. IV.17, n_b (constant N_p = 32):\n");
    println!("| n_b | bandwidth pass (s) | total (s) | shaded pixels | PSNR (dB) |");
    println!("|---:|---:|---:|---:|---:|");
    for n_b in [4, 8, 16, 64, 256, 1024] {
        let t = Instant::now();
        let buffer = BandwidthBuffer::build(
            g,
            ctx,
            env_bw,
            BufferOptions {
                n_b,
                mean_samples: 32.0,
                scale: SampleRule::Constant,
                ..Default::default()
            },
        )?;
        let t_bw = t.elapsed().as_secs_f64();
        let f = render_adaptive(g, ctx, &buffer, Lighting::Direct, 7)?;
        println!(
            "| {n_b} | {t_bw:.3} | {:.3} | {} | {:.2} |",
            t.elapsed().as_secs_f64(),
            f.stats.shaded,
            psnr(reference, &f.image, exposure)?
        );
    }
    println!();
    Ok(())
}

/// Where the pre-convolved lookups read the pyramid (`shading::preconvolved_level` of each
/// surface pixel's largest BRDF bandwidth ν): ν's and the level's median and 90th percentile,
/// and the share of pixels at level 0, where the map itself is read (nothing is pre-convolved).
fn preconvolved_levels(
    g: &GBuffer,
    ctx: &ShadingContext,
    env_bw: &EnvironmentBandwidth,
) -> anyhow::Result<()> {
    let buffer = BandwidthBuffer::build(g, ctx, env_bw, BufferOptions::default())?;
    let mut nu: Vec<f64> = buffer
        .level
        .iter()
        .zip(&buffer.brdf_max)
        .filter(|(l, _)| **l != NO_LEVEL)
        .map(|(_, &v)| v)
        .collect();
    if nu.is_empty() {
        return Ok(());
    }
    let mut level: Vec<f64> = nu.iter().map(|&v| ctx.level_for(v)).collect();
    nu.sort_by(f64::total_cmp);
    level.sort_by(f64::total_cmp);
    let q = |v: &[f64], p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    let at_zero = level.iter().filter(|&&l| l == 0.0).count() as f64 / level.len() as f64;
    println!(
        "- pre-convolved lookups: the BRDF's largest bandwidth ν median {:.1}, 90th percentile {:.1} cycles/rad (largest {:.1}); pyramid level median {:.2}, 90th percentile {:.2}; {:.1} % of the surface pixels are at level 0 (of {}² faces), where nothing is filtered and the map itself is read, as in direct shading\n",
        q(&nu, 0.5),
        q(&nu, 0.9),
        nu[nu.len() - 1],
        q(&level, 0.5),
        q(&level, 0.9),
        100.0 * at_zero,
        ctx.pyramid.as_ref().map_or(0, |p| p.base_size())
    );
    Ok(())
}

fn slug(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}
