//! `lustre render`: a walkthrough frame of a light-mapped scene (000 §4): light maps for the
//! diffuse light, a probe per probe object for the glossy light, regular sampling through every
//! material's warp. On the GPU (`lustre_gpu::GpuFrameSession`, progressive refinement stepped
//! one still frame at a time) when it can, else the CPU frame (`lustre_shade::frame`); it writes
//! PNG and EXR, a CSV of the time per stage, and, against a `lustre reference` image, PSNR / ΔE /
//! relative RMS and a false-colour difference.

use anyhow::{bail, Context};
use clap::builder::TypedValueParser;
use indicatif::{ProgressBar, ProgressStyle};
use lustre_env::pyramid::CubePyramid;
use lustre_gpu::{
    GpuContext, GpuFrameSession, GpuFrameTimes, GpuWalkthrough, LightmapFrameScene,
    WalkthroughPasses,
};
use lustre_scene::camera_path_file::CameraPathFile;
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::material_edit::{parse_assignment, set_named};
use lustre_scene::Environment;
use lustre_scene::Scene;
use lustre_shade::frame::{render_frame, FrameLight, FrameStats};
use lustre_shade::probe::{capture_probes, has_probes, LitScene, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{base_albedo, BaseAlbedo};
use lustre_trace::baked::{environment_pyramid, read_environment, BakedScene};
use lustre_trace::image::Image;
use lustre_trace::path_tracer::PathCamera;
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::film_camera;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `--method`'s parser: the names of [`Method`], each with its description in the help.
pub fn method_parser() -> impl TypedValueParser<Value = Method> {
    clap::builder::PossibleValuesParser::new(
        Method::ALL
            .into_iter()
            .filter(|m| *m != Method::Reference)
            .map(|m| clap::builder::PossibleValue::new(m.name()).help(m.description())),
    )
    .try_map(|s| Method::parse(&s))
}

/// How `--method adaptive` sets each pixel's sample count.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleRuleArg {
    /// --samples at every shaded pixel (spatial adaptivity only; the fastest at equal PSNR in
    /// our measurements).
    Constant,
    /// --samples at pixels shaded at level 0 and ⅔ · 2^k times as many at level k: a pixel
    /// shaded at a coarse level covers 4^k pixels through the up-sampling, and its noise with
    /// them.
    Coverage,
    /// 004's Eq. IV.9 bound relative to the pixel's squared radiance, N_p ∝ S / L̂².
    Relative,
    /// N_p ∝ √S / L̂ (the allocation minimizing the summed squared relative error).
    RelativeMse,
    /// 004's Eq. IV.9 bound as is, N_p ∝ S.
    Absolute,
}

/// Where the frame is rendered.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Device {
    /// The GPU when an adapter is found and every pass can run there, else the CPU (said so);
    /// `--method adaptive | brute` keeps the CPU on a software adapter (lavapipe), slower there.
    Auto,
    /// The GPU (lustre-gpu); an error without an adapter or for a material it cannot shade.
    Gpu,
    /// The CPU (lustre-shade's ray-cast twin of the same frame).
    Cpu,
}

/// Arguments of `lustre render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// A scene: a scene.toml with baked light maps (what `lustre bake --out DIR` writes), or
    /// any scene lustre reads (.xml, .gltf, .glb, .obj, a .toml without light maps), baked into
    /// OUT/bake on first use (16 texels per unit within 2²⁰ texels: the few largest meshes, such
    /// as a ground plane, coarser first, else fewer for all; 64 paths per texel, 32 bounces,
    /// full transport, the automatic real-time set-up) and reused
    /// while the scene is unchanged. Without one, the
    /// built-in room (baked into OUT/bake the same way).
    pub scene: Option<PathBuf>,
    /// Ignore the scene's real-time hints (probes, mirrors, room probes) and decide them
    /// automatically, as `lustre bake` does for a scene without hints.
    #[arg(long)]
    pub auto_setup: bool,
    /// Render this material (any material specification, `lustre list`) on a sphere under the
    /// environment instead of a scene: the material preview.
    #[arg(long, conflicts_with = "scene")]
    pub material: Option<String>,
    /// An equirect `.hdr` / `.exr` environment for the preview or the built-in room (the
    /// built-in sky by default).
    #[arg(long, conflicts_with = "scene")]
    pub env: Option<PathBuf>,
    /// Set a material parameter first, MATERIAL.PARAMETER=VALUE (repeatable): the parameters
    /// `lustre view`'s material editor shows, e.g. `floor.alpha=0.1`, `floor.diffuse=0.3,0.2,0.1`,
    /// `gold-paint.spec=sgd:gold-metallic-paint`.
    #[arg(long = "set", value_name = "MATERIAL.PARAMETER=VALUE")]
    pub set: Vec<String>,
    /// Camera name (the scene's first camera by default).
    #[arg(long, conflicts_with = "path")]
    pub camera: Option<String>,
    /// Render the frames of this camera path (frame_0000.png …), at --fps.
    #[arg(long, conflicts_with = "compare_reference")]
    pub path: Option<String>,
    /// Frames per second along --path.
    #[arg(long, default_value_t = 24.0)]
    pub fps: f64,
    /// Glossy samples per pixel (per camera ray), 1–256; with --method adaptive | brute the
    /// mean N_p, 1–1024.
    #[arg(long, default_value_t = 16)]
    pub samples: u32,
    /// Integration of the glossy part.
    #[arg(long, default_value = "regular", value_parser = method_parser())]
    pub method: Method,
    /// Still frames accumulated by --method progressive.
    #[arg(long, default_value_t = 64)]
    pub frames: u32,
    /// Where to render: the GPU when it can, else the CPU (auto), or one of them.
    #[arg(long, value_enum, default_value_t = Device::Auto)]
    pub device: Device,
    /// Render each frame this many times and report the median, minimum and maximum frame time
    /// (timing runs: `scripts/frame_tables.py`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub repeat: u32,
    /// Film size WxH (the scene's film by default).
    #[arg(long)]
    pub size: Option<String>,
    /// Camera rays per pixel (anti-aliasing).
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
    /// Probe cube face size in texels.
    #[arg(long, default_value_t = 128)]
    pub probe_size: usize,
    /// Run even when the job's memory or disk estimate exceeds what the machine has.
    #[arg(long)]
    pub force: bool,
    /// Exposure of the PNG (and of the comparison's display values): finite and > 0.
    #[arg(long, default_value_t = 1.0, value_parser = parse_exposure)]
    pub exposure: f64,
    /// Seed of the camera jitter and of the random method.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// A `lustre reference` EXR of the same camera and size to compare with.
    #[arg(long)]
    pub compare_reference: Option<PathBuf>,
    /// `--method adaptive`: how N_p is set per pixel (its mean is --samples).
    #[arg(long, value_enum, default_value_t = SampleRuleArg::Constant)]
    pub sample_rule: SampleRuleArg,
    /// `--method adaptive`: read the environment pre-convolved at the BRDF's bandwidth
    /// (004 §IV.3.5) instead of at full resolution.
    #[arg(long)]
    pub preconvolved: bool,
    /// `--method adaptive`: image samples per cycle of the predicted bandwidth (2: Nyquist's
    /// rate; 1: 004's Eq. IV.11 as printed, fewer pixels shaded).
    #[arg(long, default_value_t = 2.0)]
    pub rate: f64,
    /// `--method adaptive | brute`: a textured area light (an `.hdr` / `.exr` image, 004
    /// §IV.5.3) as a square facing down above the scene, half as wide as the scene, as high
    /// above it as it is wide; shaded without visibility, besides the scene's own emitters.
    #[arg(long)]
    pub area_light: Option<PathBuf>,
    /// Radiance scale of --area-light.
    #[arg(long, default_value_t = 1.0)]
    pub area_light_radiance: f64,
    /// `--method adaptive`: incident directions per pixel of the bandwidth buffer (004: 16; 8
    /// shades fewer pixels at the same PSNR, `lustre_adaptive::buffer::DEFAULT_N_B`).
    #[arg(long, default_value_t = lustre_adaptive::buffer::DEFAULT_N_B as u32,
          value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub n_b: u32,
    /// Output folder (frame.exr, frame.png, times.csv; diff.png with --compare-reference;
    /// bandwidth.png, level.png, samples.png and shaded.png with --method adaptive).
    #[arg(long)]
    pub out: PathBuf,
}

/// A scene with its light-map atlas and baked pages.
pub(crate) type Baked = (Scene, LightmapAtlas, Vec<Vec<[f32; 3]>>);

/// A scene file with baked light maps: the scene, its atlas and its pages.
fn load_baked(path: &Path) -> anyhow::Result<Baked> {
    let b = BakedScene::load(path)?;
    for w in &b.warnings {
        eprintln!("warning: {w}");
    }
    Ok((b.scene, b.atlas, b.pages))
}

/// The environment of `--env`, its sanitizing warning (non-finite or negative texels) printed.
pub fn env_arg(args: &RenderArgs) -> anyhow::Result<Option<Environment>> {
    if let Some(p) = &args.env {
        crate::budget::map(p, "--env", args.force)?;
    }
    Ok(
        match args.env.as_deref().map(read_environment).transpose()? {
            Some((env, warning)) => {
                if let Some(w) = warning {
                    eprintln!("warning: {w}");
                }
                Some(env)
            }
            None => None,
        },
    )
}

/// The longest image side `lustre render` and `lustre demo` draw, on the GPU (its texture
/// limit) and on the CPU alike, so that both devices accept the same frames.
pub const MAX_SIDE: u32 = 16384;

/// Refuses a frame side above [`MAX_SIDE`].
pub fn check_side(w: u32, h: u32) -> anyhow::Result<()> {
    if w > MAX_SIDE || h > MAX_SIDE {
        anyhow::bail!(
            "--size {w}x{h}: each side must be at most {MAX_SIDE} (the GPU's texture limit; the \
             CPU keeps it too)"
        );
    }
    Ok(())
}

/// A scene file with light maps as it is; any other scene baked into `out/bake` first (reused
/// while the scene and the bake's options are unchanged: a fingerprint in
/// `out/bake/source.txt`).
fn load_or_bake(path: &Path, render: &RenderArgs, k: u32) -> anyhow::Result<Baked> {
    let (out, force) = (&render.out, render.force);
    let scene = Scene::load(path).with_context(|| format!("loading {}", path.display()))?;
    if scene.lightmap.is_some() {
        return load_baked(path);
    }
    let dir = out.join("bake");
    let density = first_use_density(&scene);
    let args = crate::bake_cmd::BakeArgs {
        scene: path.to_path_buf(),
        out: dir.clone(),
        spp: 64,
        bounces: 32,
        texels_per_metre: Some(density),
        max_texels: FIRST_USE_TEXELS,
        seed: 0,
        tile: 64,
        no_denoise: false,
        transport: crate::bake_cmd::TransportArg::Full,
        shard: crate::shard::ShardArgs::default(),
        setup: crate::bake_cmd::SetupArg::Auto,
        merge: false,
        plan: false,
        force,
    };
    let key = fingerprint(path, &scene, &format!("{:?}", args.options()));
    let stamp = dir.join("source.txt");
    let toml = dir.join(crate::bake_cmd::SCENE_FILE);
    if toml.is_file() && std::fs::read_to_string(&stamp).is_ok_and(|k| k == key) {
        eprintln!(
            "light maps: reusing {} (the scene is unchanged)",
            dir.display()
        );
        return load_baked(&toml);
    }
    // A frame the machine cannot hold is refused before the bake; the full check (all frames
    // of a path, the baked pages) follows it.
    if !force {
        let size = frame_size(render, &scene)?;
        crate::budget::refuse(&frame_budget(render, &scene, 0, 1, size, k))?;
    }
    // Tiles of another scene or other options must not be resumed.
    let tiles = dir.join("tiles");
    if tiles.exists() && !std::fs::read_to_string(&stamp).is_ok_and(|k| k == key) {
        std::fs::remove_dir_all(&tiles)
            .with_context(|| format!("removing the stale tiles in {}", tiles.display()))?;
    }
    eprintln!(
        "{} has no light maps: baking them into {} ({density} texels per scene unit, 64 paths per texel, 32 bounces, full transport; reused on the next run)",
        path.display(),
        dir.display()
    );
    std::fs::create_dir_all(&dir).with_context(|| format!("creating {}", dir.display()))?;
    // The stamp first: a bake stopped half-way resumes its tiles on the next run.
    lustre_scene::scene_file::write_atomic(&stamp, key.as_bytes())?;
    std::fs::remove_file(&toml).or_else(|e| match e.kind() {
        std::io::ErrorKind::NotFound => Ok(()),
        _ => Err(e),
    })?;
    let written = crate::bake_cmd::bake(&args)?
        .with_context(|| format!("baking {} wrote no scene file", path.display()))?;
    load_baked(&written)
}

/// Texels per scene unit of a first-use bake: 16 (6 cm texels in a scene in metres), fewer where
/// the scene's surface would need more than 2²⁰ texels at 16 even with its few largest meshes
/// coarser (a scene in centimetres), halved until it fits (`fit_densities`; the bake caps the
/// largest meshes within the same budget).
fn first_use_density(scene: &Scene) -> f32 {
    crate::bake_cmd::fit_densities(scene, 16.0, FIRST_USE_TEXELS).density
}

/// The texel budget of a first-use bake: 2²⁰.
const FIRST_USE_TEXELS: u64 = 1 << 20;

/// A fingerprint of `scene` as loaded from `path` and of the bake's `options`: the file's
/// canonical path and modification time, every mesh (name, vertices, triangles, material,
/// hints), the materials, the room probes and the environment's description.
fn fingerprint(path: &Path, scene: &Scene, options: &str) -> String {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    std::fs::canonicalize(path)
        .unwrap_or_else(|_| path.to_path_buf())
        .hash(&mut h);
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .ok()
        .hash(&mut h);
    for m in &scene.meshes {
        m.name.hash(&mut h);
        for p in &m.positions {
            p.to_array().map(f32::to_bits).hash(&mut h);
        }
        m.indices.hash(&mut h);
        m.material.hash(&mut h);
        format!("{:?}{:?}", m.hints, m.emission).hash(&mut h);
    }
    format!("{:?}", scene.materials).hash(&mut h);
    format!("{:?}", scene.probes).hash(&mut h);
    scene
        .environment
        .as_ref()
        .map(|e| {
            let source = match &e.source {
                lustre_scene::EnvironmentSource::Map { path, .. } => format!("map {path:?}"),
                other => format!("{other:?}"),
            };
            format!("{source} {:?} {}", e.to_local, e.intensity)
        })
        .hash(&mut h);
    options.hash(&mut h);
    format!("lustre-bake-cache-1 {:016x}\n", h.finish())
}

/// The built-in room with its light maps, baked into `out/bake` (tiles reused on the next run).
pub(crate) fn builtin(out: &Path, environment: Option<Environment>) -> anyhow::Result<Baked> {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template(
            "baking the built-in room: [{bar:30}] {pos}/{len} tiles, {elapsed}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let b = BakedScene::builtin_room(&out.join("bake"), environment, &|k, n| {
        bar.set_length(n as u64);
        bar.set_position(k as u64);
    })
    .context("baking the built-in room")?;
    bar.finish_and_clear();
    Ok((b.scene, b.atlas, b.pages))
}

/// The material preview: a sphere of `spec` under `environment`, no light maps.
fn preview(spec: &str, environment: Option<Environment>) -> anyhow::Result<Baked> {
    let b = BakedScene::preview(spec, environment).with_context(|| format!("--material {spec}"))?;
    Ok((b.scene, b.atlas, b.pages))
}

/// Wall time per stage.
struct Stages {
    times: Vec<(String, f64)>,
    t: Instant,
}

impl Stages {
    /// Ends the current stage as `name` and starts the next.
    fn lap(&mut self, name: impl Into<String>) {
        self.times
            .push((name.into(), self.t.elapsed().as_secs_f64()));
        self.t = Instant::now();
    }
}

/// The frame request of `args` (--method, --samples, --spp, --frames, --seed), validated once
/// for every method.
pub fn request(args: &RenderArgs) -> anyhow::Result<FrameRequest> {
    let req = FrameRequest {
        method: args.method,
        samples: args.samples,
        rays: args.spp,
        frames: args.frames,
        seed: args.seed,
    };
    req.validate().map_err(|e| {
        anyhow::anyhow!(
            "--method {} --samples {} --spp {} --frames {}: {e}",
            req.method.name(),
            req.samples,
            req.rays,
            req.frames
        )
    })?;
    Ok(req)
}

/// The memory and disk of `frames` frames of `w`×`h` (k×k G-buffer samples a pixel on the
/// GPU) of `scene` with `page_texels` light-map texels.
fn frame_budget(
    args: &RenderArgs,
    scene: &Scene,
    page_texels: u64,
    frames: u64,
    (w, h): (u32, u32),
    k: u32,
) -> lustre_brdf::budget::Budget {
    let pixels = u64::from(w) * u64::from(h);
    let probes_n =
        (scene.probes.len() + scene.meshes.iter().filter(|m| m.hints.probe).count()) as u64;
    let face = args.probe_size as u64;
    let k = u64::from(k);
    let mut need = crate::budget::scene(
        lustre_brdf::budget::Budget::new(
            format!("lustre render at {w}×{h}"),
            "lower --size (or --probe-size)",
        ),
        scene,
    )
    .memory("light-map pages", page_texels, 12)
    // Each probe: six faces of colour and distance with their MIP pyramid (4/3), 16 B a texel.
    .memory("probes", probes_n * 6 * face * face * 4 / 3, 16)
    .memory("frame buffers", pixels, crate::budget::RENDER_PIXEL);
    if args.device != Device::Cpu {
        need = need
            .memory("GPU device", 1, crate::budget::GPU_DEVICE)
            .memory("G-buffer", pixels * k * k, crate::budget::GBUFFER_SAMPLE);
    }
    need.disk(
        &args.out,
        "frames",
        pixels * frames,
        crate::budget::RENDER_PIXEL_DISK,
    )
}

/// The frame size: `--size`, else the scene's film.
fn frame_size(args: &RenderArgs, scene: &Scene) -> anyhow::Result<(u32, u32)> {
    let (w, h) = match args.size.as_deref() {
        Some(s) => crate::reference_cmd::parse_size(s)?,
        None => (scene.film.width, scene.film.height),
    };
    check_side(w, h)?;
    Ok((w, h))
}

/// Runs `lustre render`: load (or bake), check the budget, capture, render, write (a failed run
/// leaves no empty folder: `crate::output::in_folder`).
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let mut st = Stages {
        times: vec![],
        t: Instant::now(),
    };
    let req = request(args)?;
    if req.method.adaptive() {
        return crate::adaptive_cmd::run(args, &req);
    }
    let probe_opts = ProbeOptions {
        face_size: args.probe_size,
        ..ProbeOptions::default()
    };
    probe_opts.validate()?;
    let environment = env_arg(args)?;
    let (mut scene, atlas, pages) = match (&args.scene, &args.material) {
        (Some(path), _) => load_or_bake(path, args, req.supersampling())?,
        (None, Some(spec)) => preview(spec, environment)?,
        (None, None) => builtin(&args.out, environment)?,
    };
    for a in &args.set {
        let (material, field, value) =
            parse_assignment(a).map_err(|e| anyhow::anyhow!("--set {e}"))?;
        set_named(&mut scene.materials, &material, &field, &value)
            .with_context(|| format!("--set {a}"))?;
    }
    if args.auto_setup {
        lustre_trace::setup::clear_hints(&mut scene);
        let setup = crate::bake_cmd::decide_setup(&scene)?;
        lustre_trace::setup::apply(&mut scene, &setup);
    }
    let name = match (&args.scene, &args.material) {
        (Some(p), _) => p.display().to_string(),
        (None, Some(spec)) => format!("the preview of {spec}"),
        (None, None) => "the built-in room".to_string(),
    };
    let (w, h) = frame_size(args, &scene)?;
    check_reference(args, w, h)?;
    let cameras = match &args.path {
        None => vec![(
            "frame".to_string(),
            lustre_trace::reference::path_camera(&scene, args.camera.as_deref(), w, h)?,
        )],
        Some(p) => path_cameras(&scene, p, args.fps, w, h)?,
    };
    let page_texels: u64 = pages.iter().map(|p| p.len() as u64).sum();
    let need = frame_budget(
        args,
        &scene,
        page_texels,
        cameras.len() as u64,
        (w, h),
        req.supersampling(),
    );
    crate::budget::check(&need, args.force)?;
    st.lap("load, light maps");
    let (ps, warnings) = lustre_trace::reference::path_scene(&scene)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = Lightmapped::new(&scene, &atlas, &pages, &ps.geometry, bases)
        .with_context(|| format!("{name}: light maps"))?;
    let pt = PathTracer::new(&ps, PathOptions::default())?;
    let lit = LitScene::new(&scene, &ps, &pt, &lm)?;
    st.lap("BVH");

    let has_probes = has_probes(&scene);
    let env_pyramid = match (has_probes, &ps.environment) {
        (false, Some(env)) => {
            if args.material.is_none() {
                eprintln!("no probe objects: glossy surfaces reflect the environment only");
            }
            let p = environment_pyramid(env, args.probe_size)?;
            st.lap("environment pyramid");
            Some(p)
        }
        (false, None) => {
            eprintln!("no probe objects and no environment: diffuse (light-mapped) shading only");
            None
        }
        _ => None,
    };
    let gpu = match args.device {
        Device::Cpu => None,
        device => match gpu_renderer(
            &scene,
            &atlas,
            &pages,
            &lit,
            &probe_opts,
            env_pyramid.as_ref(),
        ) {
            Ok(r) => Some(r),
            Err(e) if device == Device::Auto => {
                eprintln!("GPU: {e:#}; rendering on the CPU");
                None
            }
            Err(e) => return Err(e),
        },
    };
    let mut probes = vec![];
    if let Some((_, walk)) = &gpu {
        for (name, ms) in &walk.capture_ms {
            eprintln!("probe {name:?} captured on the GPU in {ms:.1} ms");
            st.times.push((format!("probe {name}"), ms * 1e-3));
        }
        st.t = Instant::now();
    } else {
        probes = capture_probes(&lit, &probe_opts, &mut |probe, secs| {
            eprintln!(
                "probe {:?} at ({:.2}, {:.2}, {:.2}): {} bounding planes, {}² faces",
                probe.name,
                probe.centre.x,
                probe.centre.y,
                probe.centre.z,
                probe.planes.len(),
                args.probe_size
            );
            st.times.push((format!("probe {}", probe.name), secs));
        })
        .context("capturing the probes")?;
        st.t = Instant::now();
    }
    let light = FrameLight {
        probes: &probes,
        environment: env_pyramid.as_ref(),
    };
    // The GPU's anti-aliasing: a k×k supersampled G-buffer, k² nearest to the camera rays asked.
    let k = req.supersampling();
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let bar = ProgressBar::new(cameras.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames, {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    match &gpu {
        Some(_) => bar.set_message(format!("{w}×{h}, {k}×{k} G-buffer samples/pixel, GPU")),
        None => bar.set_message(format!("{w}×{h}, {} camera rays/pixel", args.spp)),
    }
    let mut session = GpuFrameSession::new();
    let progressive_frames = req.accumulated_frames();
    for (stem, camera) in &cameras {
        // Each repetition: (frame without its passes, mirror and see-through passes), seconds,
        // and for the GPU the time of each of its passes, and of its first and still frames.
        let mut runs = vec![];
        let mut rendered = None;
        let mut gpu_times = vec![];
        let (mut first_frames, mut still_frames) = (vec![], vec![]);
        for _ in 0..args.repeat {
            let t = Instant::now();
            let (img, stats) = match &gpu {
                Some((ctx, walk)) => {
                    // Every camera and repetition starts afresh (as on the CPU); progressive
                    // refinement then steps the session --frames times at the still camera,
                    // one QMC frame accumulated per step.
                    session.reset();
                    let size = (w as usize, h as usize);
                    let passes =
                        |t: &GpuFrameTimes| (t.gbuffer_ms + t.lightmap_ms + t.shade_ms) * 1e-3;
                    let mut step = session.step(ctx, walk, &lit, camera, size, &req)?;
                    first_frames.push(passes(&step.times));
                    let mut times = step.times;
                    for _ in 1..progressive_frames {
                        step = session.step(ctx, walk, &lit, camera, size, &req)?;
                        still_frames.push(passes(&step.times));
                        times.shade_ms += step.times.shade_ms;
                    }
                    runs.push((passes(&times), times.views_ms * 1e-3));
                    gpu_times.push(times);
                    let mut stats = step.stats;
                    stats.mirror_seconds = times.views_ms * 1e-3;
                    (session.image(ctx)?, stats)
                }
                None => {
                    let (img, stats) =
                        render_frame(&lit, &light, camera, w as usize, h as usize, &req)?;
                    let s = t.elapsed().as_secs_f64();
                    runs.push(((s - stats.mirror_seconds).max(0.0), stats.mirror_seconds));
                    (img, stats)
                }
            };
            rendered = Some((img, stats));
        }
        let Some((img, stats)) = rendered else {
            bail!("--repeat 0 renders nothing");
        };
        bar.inc(1);
        st.t = Instant::now();
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            (v[v.len() / 2], v[0], v[v.len() - 1])
        };
        if stats.mirrors + stats.see_throughs > 0 {
            // The mirror and see-through passes run inside the frame; report them apart.
            let (m, _, _) = median(&mut runs.iter().map(|r| r.1).collect());
            st.times
                .push((format!("{stem}: mirror and see-through passes"), m));
        }
        let (m, lo, hi) = median(&mut runs.iter().map(|r| r.0).collect());
        st.times.push((stem.clone(), m));
        if args.repeat > 1 {
            st.times
                .push((format!("{stem}: min of {}", args.repeat), lo));
            st.times
                .push((format!("{stem}: max of {}", args.repeat), hi));
        }
        // Progressive refinement: the frame above holds all --frames frames; on the GPU also
        // its first frame and the median still (accumulating) frame, the view buffers apart.
        let frames = req.frames;
        let progress = match req.method {
            Method::Progressive if gpu.is_some() => {
                let (first, _, _) = median(&mut first_frames);
                st.times.push((format!("{stem}: first frame"), first));
                let mut line = format!(
                    "progressive refinement on the GPU: {frames} frame(s) in {:.1} ms, the first \
                     {:.1} ms",
                    m * 1e3,
                    first * 1e3
                );
                if !still_frames.is_empty() {
                    let (still, _, _) = median(&mut still_frames);
                    st.times.push((format!("{stem}: still frame"), still));
                    write!(
                        line,
                        ", a still frame {:.1} ms (median of {})",
                        still * 1e3,
                        still_frames.len()
                    )?;
                }
                Some(line)
            }
            Method::Progressive => Some(format!(
                "progressive refinement on the CPU: {frames} frame(s) in one pass over the \
                 pixels, {:.1} ms",
                m * 1e3
            )),
            _ => None,
        };
        type Stage = fn(&GpuFrameTimes) -> f64;
        let stages: [(&str, Stage); 4] = [
            (
                "mirror and see-through layers (in the mirror and see-through passes)",
                |t| t.layers_ms,
            ),
            ("G-buffer", |t| t.gbuffer_ms),
            ("light-map shading", |t| t.lightmap_ms),
            ("view-dependent pass", |t| t.shade_ms),
        ];
        if !gpu_times.is_empty() {
            for (name, f) in stages {
                let (m, _, _) = median(&mut gpu_times.iter().map(f).collect());
                st.times.push((format!("{stem}: GPU {name}"), m * 1e-3));
            }
        }
        img.write_exr(&args.out.join(format!("{stem}.exr")))?;
        img.write_png_dithered(
            &args.out.join(format!("{stem}.png")),
            args.exposure,
            args.seed,
        )?;
        if cameras.len() == 1 {
            bar.finish_and_clear();
            report(args, &img, &stats, (w, h), gpu.is_some().then_some(k))?;
            if let Some(line) = &progress {
                println!("{line}");
            }
        }
        st.lap(format!("{stem}: write"));
    }
    bar.finish_and_clear();
    match &gpu {
        Some((ctx, walk)) => {
            let clock = if walk.timestamps {
                "GPU timestamps"
            } else {
                "wall clock until the GPU finished"
            };
            eprintln!(
                "rendered on the GPU ({}; pass times: {clock})",
                ctx.describe()
            );
        }
        None => {
            eprintln!("rendered on the CPU (lustre_shade::frame, the GPU frame's ray-cast twin)")
        }
    }
    let mut csv = String::from("stage,seconds\n");
    for (name, s) in &st.times {
        writeln!(csv, "{},{s:.4}", name.replace(',', " "))?;
    }
    writeln!(csv, "total,{:.4}", t0.elapsed().as_secs_f64())?;
    lustre_brdf::error::write_atomic(&args.out.join("times.csv"), csv.as_bytes())?;
    println!(
        "wrote {} ({} frame(s) as EXR and PNG, times.csv)",
        args.out.display(),
        cameras.len()
    );
    Ok(())
}

/// The GPU renderer of a light-mapped scene: an adapter, the scene uploaded, the passes
/// compiled and the probes captured. Errors: no adapter, a scene the GPU cannot hold.
fn gpu_renderer(
    scene: &Scene,
    atlas: &LightmapAtlas,
    pages: &[Vec<[f32; 3]>],
    lit: &LitScene,
    probe_opts: &ProbeOptions,
    environment: Option<&CubePyramid>,
) -> anyhow::Result<(GpuContext, GpuWalkthrough)> {
    let ctx = GpuContext::new().context("no GPU adapter")?;
    let uploaded = LightmapFrameScene::upload(&ctx, scene, atlas, pages)
        .context("uploading the scene to the GPU")?;
    // The view-dependent pass compiles the scene's material kinds only.
    let passes = WalkthroughPasses::for_scene(&ctx, scene).context("compiling the GPU passes")?;
    let walk = GpuWalkthrough::with_passes(&ctx, passes, lit, uploaded, probe_opts, environment)
        .context("preparing the scene for the GPU (its materials, then its probes)")?;
    Ok((ctx, walk))
}

/// Prints a single frame's counts and, with --compare-reference, its comparison.
fn report(
    args: &RenderArgs,
    img: &Image,
    stats: &FrameStats,
    (w, h): (u32, u32),
    supersampling: Option<u32>,
) -> anyhow::Result<()> {
    // The GPU's camera rays are its k×k G-buffer samples per pixel.
    let rays = supersampling.map_or(args.spp, |k| k * k);
    if stats.mirrors + stats.see_throughs > 0 {
        eprintln!(
            "{} mirror and {} see-through buffer(s) of {w}×{h} in {:.3} s",
            stats.mirrors, stats.see_throughs, stats.mirror_seconds
        );
    }
    let glossy_rays = stats.glossy_hits.max(1);
    println!(
        "{w}×{h}, {rays} camera rays/pixel, {:?} with {} samples: {} glossy hits, {:.2} lookups per glossy hit",
        args.method,
        args.samples,
        stats.glossy_hits,
        stats.lookups as f64 / glossy_rays as f64
    );
    compare(args, img)
}

/// With --compare-reference: reads the reference and checks that it is a W×H frame, before
/// anything is rendered or written (a bad reference leaves no frame behind).
pub(crate) fn check_reference(args: &RenderArgs, w: u32, h: u32) -> anyhow::Result<()> {
    if let Some(reference) = &args.compare_reference {
        let r = Image::read_exr(reference)
            .with_context(|| format!("--compare-reference {}", reference.display()))?;
        if (r.width, r.height) != (w as usize, h as usize) {
            bail!(
                "--compare-reference {}: the reference is {}×{}, the frame {w}×{h}; nothing \
                 was rendered",
                reference.display(),
                r.width,
                r.height
            );
        }
    }
    Ok(())
}

/// With --compare-reference: PSNR, ΔE and relative RMS against it, and diff.png.
pub(crate) fn compare(args: &RenderArgs, img: &Image) -> anyhow::Result<()> {
    if let Some(reference) = &args.compare_reference {
        let r = Image::read_exr(reference)?;
        if (r.width, r.height) != (img.width, img.height) {
            bail!(
                "{}: the reference is {}×{}, the frame {}×{}",
                reference.display(),
                r.width,
                r.height,
                img.width,
                img.height
            );
        }
        let psnr = lustre_trace::metrics::psnr(img, &r, args.exposure)?;
        let de = lustre_trace::metrics::delta_e(img, &r, args.exposure)?;
        let rel = lustre_trace::metrics::rms(img, &r)? / r.mean().max(1e-12);
        let diff = lustre_trace::metrics::false_colour(img, &r, 0.1 * r.mean().max(1e-6))?;
        diff.write_png(&args.out.join("diff.png"), 1.0)?;
        println!(
            "against {}: PSNR {psnr:.2} dB, mean ΔE {de:.2}, relative RMS {:.2} %, mean ratio {:.4}",
            reference.display(),
            100.0 * rel,
            img.mean() / r.mean().max(1e-12)
        );
    }
    Ok(())
}

/// The cameras of path `name` at `fps` frames per second, named frame_0000 …: a camera path
/// file (`.json`, `lustre_scene::camera_path_file`, as `lustre view` records) or the name of
/// one of the scene's paths.
pub(crate) fn path_cameras(
    scene: &Scene,
    name: &str,
    fps: f64,
    w: u32,
    h: u32,
) -> anyhow::Result<Vec<(String, PathCamera)>> {
    if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
        bail!("--fps {fps}: must be in (0, 1000]");
    }
    let from_file;
    let path = if name.to_ascii_lowercase().ends_with(".json") {
        from_file = CameraPathFile::read(Path::new(name))?;
        &from_file
    } else {
        scene
            .camera_paths
            .iter()
            .find(|p| p.name == name)
            .with_context(|| {
                let names: Vec<&str> = scene.camera_paths.iter().map(|p| p.name.as_str()).collect();
                format!(
                    "no camera path named {name:?} (paths: {}); or give a camera path .json file",
                    names.join(", ")
                )
            })?
    };
    let n = (path.duration() * fps).floor() as usize + 1;
    if n > 100_000 {
        bail!("camera path {name:?} at {fps} fps is {n} frames: too many");
    }
    (0..n)
        .map(|k| {
            let c = path
                .at(k as f64 / fps)
                .with_context(|| format!("camera path {name:?} has no keyframes"))?;
            Ok((format!("frame_{k:04}"), film_camera(&c, w, h)?))
        })
        .collect()
}

/// Parses `--exposure`: a finite number > 0 (0 or NaN would write a black image).
pub fn parse_exposure(s: &str) -> std::result::Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?}: expected a finite number > 0, e.g. 1 or 4")),
    }
}
