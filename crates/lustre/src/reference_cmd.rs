//! `lustre reference`: the converged path-traced reference of a scene (lustre TOML, glTF, OBJ or
//! Mitsuba XML), resumable, with its own noise estimate.

use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use lustre_trace::reference::{render_reference, ReferenceOptions};
use std::path::PathBuf;

/// Arguments of `lustre reference`.
#[derive(clap::Args, Debug)]
pub struct ReferenceArgs {
    /// The scene: a lustre scene file (.toml), glTF (.gltf/.glb), OBJ or Mitsuba XML; the
    /// built-in room (the one `lustre render` shows without a scene) when absent.
    pub scene: Option<PathBuf>,
    /// Camera name (the scene's first camera by default).
    #[arg(long)]
    pub camera: Option<String>,
    /// Samples per pixel in total (with --resume: the total to reach).
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    /// Longest path in segments (Mitsuba's max_depth: 1 = emitters only, 2 = direct light).
    #[arg(long, default_value_t = 65)]
    pub max_depth: u32,
    /// Film size WxH (the scene's film by default).
    #[arg(long)]
    pub size: Option<String>,
    /// Continue from OUT.json / OUT.even.exr / OUT.odd.exr of an earlier run.
    #[arg(long)]
    pub resume: bool,
    /// Exposure of the PNG preview.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f64,
    /// Seed of the per-pixel sample streams.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Render the scene with every material made diffuse (the albedo `lustre bake` uses): the
    /// image that light-mapped shading (kd·E/π) converges to.
    #[arg(long)]
    pub diffuse: bool,
    /// Output OpenEXR file (OUT.png, OUT.json, OUT.even.exr, OUT.odd.exr are written beside it).
    #[arg(long)]
    pub out: PathBuf,
    /// Run even when the job's memory or disk estimate exceeds what the machine has.
    #[arg(long)]
    pub force: bool,
}

/// Parses `WxH`.
pub(crate) fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .with_context(|| format!("--size {s:?}: expected WxH, e.g. 1024x1024"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size {s:?}: bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size {s:?}: bad height"))?;
    if w == 0 || h == 0 {
        bail!("--size {s:?}: width and height must be > 0");
    }
    Ok((w, h))
}

/// Runs `lustre reference`.
pub fn run(args: &ReferenceArgs) -> anyhow::Result<()> {
    let size = args.size.as_deref().map(parse_size).transpose()?;
    match args.out.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("exr") => {}
        _ => bail!("--out {}: must be an .exr file", args.out.display()),
    }
    let (scene, name) = match &args.scene {
        Some(path) => (
            lustre_scene::Scene::load(path)
                .with_context(|| format!("loading {}", path.display()))?,
            path.display().to_string(),
        ),
        None => (
            lustre_scene::builtin::room().context("the built-in room")?,
            "the built-in room".to_string(),
        ),
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let (w, h) = size.unwrap_or((scene.film.width, scene.film.height));
    let pixels = u64::from(w) * u64::from(h);
    let need = crate::budget::scene(
        lustre_brdf::budget::Budget::new(format!("lustre reference at {w}×{h}"), "lower --size"),
        &scene,
    )
    .memory("image buffers", pixels, crate::budget::REFERENCE_PIXEL)
    .disk(
        &args.out,
        "EXR halves and images",
        pixels,
        crate::budget::REFERENCE_PIXEL_DISK,
    );
    crate::budget::check(&need, args.force)?;
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    eprintln!(
        "{}: {} triangles, {} emitting meshes, {} materials{}",
        name,
        scene.triangle_count(),
        scene.emitters().len(),
        scene.materials.len(),
        if scene.environment.is_some() {
            ", environment"
        } else {
            ""
        }
    );
    let opts = ReferenceOptions {
        camera: args.camera.clone(),
        spp: args.spp,
        max_depth: args.max_depth,
        size,
        resume: args.resume,
        out: args.out.clone(),
        exposure: args.exposure,
        seed: args.seed,
        diffuse: args.diffuse,
    };
    let bar = ProgressBar::new(args.spp as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} spp, {elapsed} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let (state, warnings) = render_reference(&scene, &opts, &|done, _total, t, n| {
        bar.set_position(done as u64);
        bar.set_message(format!("tile {t}/{n}"));
    })
    .with_context(|| format!("rendering {name}"))?;
    bar.finish_and_clear();
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    println!(
        "{}×{}, {} spp, max depth {}: mean {:.5}, noise RMS {:.5} ({:.2} % of the mean, from two independent halves), {:.1} s",
        state.width,
        state.height,
        state.spp,
        state.max_depth,
        state.mean,
        state.noise_rms,
        100.0 * state.noise_relative,
        state.seconds
    );
    println!(
        "wrote {} (+ .png, .json, .even.exr, .odd.exr)",
        args.out.display()
    );
    Ok(())
}
