//! Light-mapped diffuse shading (000 §4.3, Eq. 4.1: Lo = kd·E/π) of a scene with every material
//! made diffuse, against the path-traced reference of the same diffuse scene at the scene's
//! camera: PSNR and relative RMS as functions of the bake's spp and texel
//! density, and the bake's time per stage (unwrap, trace, fill, denoise, write).
//!
//! ```sh
//! cargo run --release -p lustre-trace --example bake_study -- --out DIR \
//!     [--scene FILE] [--size 160x90] [--ref-spp 4096] [--densities 4,8,16] [--spp 16,64,256] \
//!     [--bounces 4] [--lm-spp 16]
//! ```
//!
//! The reference (`lustre reference --diffuse`'s job: `render_reference` with `diffuse`, max
//! depth = bounces + 1, so that it converges to exactly what the bake estimates) is written to
//! `DIR/reference.exr` and resumed when it is there; each bake's tiles go to `DIR/d{D}-s{S}/`
//! and are reused on a rerun (the bake resumes), so an interrupted study continues. Results:
//! `DIR/bake_study.md` (and the PNGs beside it).
//!
//! Errors against the reference: PSNR of the display values (sRGB, exposure 1, clamped, peak
//! 1); relative RMS of the linear values; the same with the reference's own noise removed,
//! √max(0, RMS² − noise²) / mean, where noise is the RMS noise of the reference's mean
//! estimated from its two independent halves.

use lustre_scene::lightmap::{build_atlas, AtlasOptions};
use lustre_scene::Scene;
use lustre_trace::bake::render::render_lightmapped;
use lustre_trace::bake::{assemble, bake_tiles, ATrousOptions, BakeOptions, Denoiser};
use lustre_trace::image::Image;
use lustre_trace::metrics::{psnr, rms};
use lustre_trace::reference::{path_camera, render_reference, ReferenceOptions};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

struct Args {
    scene: PathBuf,
    out: PathBuf,
    size: (u32, u32),
    ref_spp: u32,
    densities: Vec<f32>,
    spps: Vec<u32>,
    bounces: u32,
    lm_spp: u32,
}

fn list<T: std::str::FromStr>(s: &str, what: &str) -> Vec<T> {
    s.split(',')
        .map(|v| {
            v.trim()
                .parse()
                .unwrap_or_else(|_| panic!("{what}: cannot read {v:?}"))
        })
        .collect()
}

fn args() -> Args {
    let mut a = Args {
        scene: lustre_env::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml"),
        out: PathBuf::new(),
        size: (160, 90),
        ref_spp: 4096,
        densities: vec![4.0, 8.0, 16.0],
        spps: vec![16, 64, 256],
        bounces: 4,
        lm_spp: 16,
    };
    let mut it = std::env::args().skip(1);
    while let Some(k) = it.next() {
        let v = it.next().unwrap_or_else(|| panic!("{k} needs a value"));
        match k.as_str() {
            "--scene" => a.scene = v.into(),
            "--out" => a.out = v.into(),
            "--size" => {
                let s: Vec<u32> = v
                    .split('x')
                    .map(|c| c.parse().expect("--size WxH"))
                    .collect();
                assert_eq!(s.len(), 2, "--size WxH");
                a.size = (s[0], s[1]);
            }
            "--ref-spp" => a.ref_spp = v.parse().expect("--ref-spp N"),
            "--densities" => a.densities = list(&v, "--densities"),
            "--spp" => a.spps = list(&v, "--spp"),
            "--bounces" => a.bounces = v.parse().expect("--bounces N"),
            "--lm-spp" => a.lm_spp = v.parse().expect("--lm-spp N"),
            _ => panic!("unknown option {k}"),
        }
    }
    assert!(!a.out.as_os_str().is_empty(), "--out DIR is required");
    a
}

/// CPU seconds (user + system, all threads) of this process so far, from /proc/self/stat.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(vec![], |(_, r)| r.split_whitespace().collect());
    // Fields after the command: state is index 0, utime index 11, stime index 12 (clock ticks).
    let tick = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(11) + tick(12)) / 100.0
}

/// (PSNR dB, rel. RMS, rel. RMS without the reference's noise, mean ratio) of `img`.
fn errors(img: &Image, reference: &Image, noise: f64) -> (f64, f64, f64, f64) {
    let m = reference.mean();
    let r = rms(img, reference).expect("same size");
    (
        psnr(img, reference, 1.0).expect("same size"),
        r / m,
        (r * r - noise * noise).max(0.0).sqrt() / m,
        img.mean() / m,
    )
}

fn main() {
    let a = args();
    std::fs::create_dir_all(&a.out).expect("create --out");
    let threads = rayon::current_num_threads();
    let scene0 = Scene::load(&a.scene).unwrap_or_else(|e| panic!("{e}"));
    let (w, h) = a.size;
    let camera = path_camera(&scene0, None, w, h).expect("camera");

    // The reference of the diffuse scene (resumed when it is there).
    let ref_out = a.out.join("reference.exr");
    let t0 = Instant::now();
    let (state, _) = render_reference(
        &scene0,
        &ReferenceOptions {
            camera: None,
            spp: a.ref_spp,
            max_depth: a.bounces + 1,
            size: Some(a.size),
            resume: ref_out.with_extension("json").exists(),
            out: ref_out.clone(),
            exposure: 1.0,
            seed: 1,
            diffuse: true,
        },
        &|done, total, _, _| eprint!("\rreference {done}/{total} spp   "),
    )
    .expect("reference");
    eprintln!(
        "\rreference: {}×{}, {} spp, max depth {}, mean {:.5}, noise {:.3} % of the mean, {:.1} s rendering in all ({:.1} s now)",
        state.width,
        state.height,
        state.spp,
        state.max_depth,
        state.mean,
        100.0 * state.noise_relative,
        state.seconds,
        t0.elapsed().as_secs_f64()
    );
    let reference = Image::read_exr(&ref_out).unwrap_or_else(|e| panic!("{e}"));
    let noise = state.noise_rms;

    let mut md = String::new();
    writeln!(
        md,
        "# Light-mapped diffuse shading vs the path-traced diffuse scene\n\n\
         Scene `{}`, camera `{}`, {w}×{h}; reference: {} spp, max depth {} (bake bounces {} + the \
         camera segment), its own noise {:.3} % of the mean (RMS of the mean from two halves), \
         PSNR ceiling from that noise alone {:.1} dB (linear). Light-mapped images: {} jittered \
         camera rays per pixel (box filter, as the reference). {threads} threads.\n",
        a.scene.display(),
        state.camera,
        state.spp,
        state.max_depth,
        a.bounces,
        100.0 * state.noise_relative,
        -20.0 * (noise / 1.0).log10(),
        a.lm_spp
    )
    .unwrap();
    writeln!(
        md,
        "| texels/m | spp | charts | page(s) | covered texels | paths | unwrap s | trace s (CPU s) | fill s | denoise s | write s | texels/s | paths/s | paths/CPU-s | PSNR raw / denoised (dB) | rel. RMS raw / denoised | without ref. noise raw / denoised | mean ratio raw / denoised |\n\
         |---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|---|"
    )
    .unwrap();
    for &d in &a.densities {
        let mut scene = Scene::load(&a.scene).expect("scene");
        let (atlas, ar) = build_atlas(
            &mut scene,
            &AtlasOptions {
                texels_per_metre: d,
                ..AtlasOptions::default()
            },
        )
        .unwrap_or_else(|e| panic!("atlas at {d} texels/m: {e}"));
        for &spp in &a.spps {
            let dir = a.out.join(format!("d{d}-s{spp}"));
            let opts = BakeOptions {
                spp,
                bounces: a.bounces,
                seed: 0,
                tile: 64,
                denoiser: Denoiser::None,
                transport: Default::default(),
            };
            let c0 = cpu_seconds();
            let tr = bake_tiles(&scene, &atlas, &opts, &dir, None, &|k, n| {
                eprint!("\r{d} texels/m, {spp} spp: tile {k}/{n}   ")
            })
            .expect("bake");
            let trace_cpu = cpu_seconds() - c0;
            if tr.reused > 0 {
                eprintln!(
                    "\r{d} texels/m, {spp} spp: {} of {} tiles reused from an earlier run (trace time covers the rest)",
                    tr.reused, tr.tiles
                );
            }
            let raw = assemble(&scene, &atlas, &opts, &dir).expect("assemble raw");
            let den = assemble(
                &scene,
                &atlas,
                &BakeOptions {
                    denoiser: Denoiser::ATrous(ATrousOptions::default()),
                    ..opts.clone()
                },
                &dir,
            )
            .expect("assemble denoised");
            let img_raw = render_lightmapped(
                &scene, &atlas, &raw.pages, &camera, w as usize, h as usize, a.lm_spp, 1,
            )
            .expect("render");
            let img_den = render_lightmapped(
                &scene, &atlas, &den.pages, &camera, w as usize, h as usize, a.lm_spp, 1,
            )
            .expect("render");
            img_den
                .write_png(&a.out.join(format!("lm-d{d}-s{spp}.png")), 1.0)
                .expect("png");
            img_den
                .write_exr(&a.out.join(format!("lm-d{d}-s{spp}.exr")))
                .expect("exr");
            let (p_raw, r_raw, c_raw, ratio_raw) = errors(&img_raw, &reference, noise);
            let (p_den, r_den, c_den, ratio) = errors(&img_den, &reference, noise);
            let covered: u64 = den.report.pages.iter().map(|p| p.covered_texels).sum();
            let row = format!(
                "| {d} | {spp} | {} | {} × {}×{} | {covered} | {} | {:.2} | {:.2} ({:.2}) | {:.3} | {:.3} | {:.3} | {:.0} | {:.0} | {:.0} | {p_raw:.2} / {p_den:.2} | {:.2} % / {:.2} % | {:.2} % / {:.2} % | {ratio_raw:.4} / {ratio:.4} |",
                ar.charts,
                atlas.pages,
                atlas.width,
                atlas.height,
                tr.paths,
                ar.time_s,
                tr.trace_seconds,
                trace_cpu,
                den.report.fill_seconds,
                den.report.denoise_seconds,
                den.report.write_seconds,
                tr.texels as f64 / tr.trace_seconds,
                tr.paths as f64 / tr.trace_seconds,
                tr.paths as f64 / trace_cpu.max(1e-9),
                100.0 * r_raw,
                100.0 * r_den,
                100.0 * c_raw,
                100.0 * c_den,
            );
            eprintln!("\r{row}");
            writeln!(md, "{row}").unwrap();
            std::fs::write(a.out.join("bake_study.md"), &md).expect("write results");
        }
    }
    reference
        .write_png(&a.out.join("reference.png"), 1.0)
        .expect("png");
    println!("{md}");
}
