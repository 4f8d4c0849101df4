//! `lustre render`: a walkthrough frame of a light-mapped scene (000 §4): light maps for the
//! diffuse light, a probe per probe object for the glossy light, regular sampling through every
//! material's warp. This is the CPU frame (`lustre_shade::frame`); it writes PNG and EXR, a CSV
//! of the time per stage, and, against a `lustre reference` image, PSNR / ΔE / relative RMS and a
//! false-colour difference.

use anyhow::{bail, Context};
use indicatif::{ProgressBar, ProgressStyle};
use lustre_brdf::rgb::Rgb;
use lustre_env::cube::CubeMap;
use lustre_env::pyramid::{CubePyramid, MipFilter};
use lustre_shade::bake::render::{read_pages, Lightmapped};
use lustre_shade::bake::spec_albedo;
use lustre_shade::frame::{render_frame, FrameLight, FrameMethod, FrameOptions};
use lustre_shade::image::Image;
use lustre_shade::path::{PathOptions, PathTracer};
use lustre_shade::probe::{capture_probe, LitScene, ProbeOptions};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// How the glossy part is integrated.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Regular samples through the material's warp, MIP-filtered.
    Regular,
    /// Colbert–Křivánek: random samples, MIP-filtered.
    Ck,
    /// Progressive refinement: --frames rotated regular sets, averaged.
    Progressive,
}

/// Arguments of `lustre render`.
#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// A scene with baked light maps: the scene.toml `lustre bake --out DIR` writes.
    pub scene: PathBuf,
    /// Camera name (the scene's first camera by default).
    #[arg(long)]
    pub camera: Option<String>,
    /// Glossy samples per pixel (per camera ray), 1–256.
    #[arg(long, default_value_t = 16)]
    pub samples: usize,
    /// Integration of the glossy part.
    #[arg(long, value_enum, default_value_t = Method::Regular)]
    pub method: Method,
    /// Still frames accumulated by --method progressive.
    #[arg(long, default_value_t = 64)]
    pub frames: u32,
    /// Film size WxH (the scene's film by default).
    #[arg(long)]
    pub size: Option<String>,
    /// Camera rays per pixel (anti-aliasing).
    #[arg(long, default_value_t = 4)]
    pub spp: u32,
    /// Probe cube face size in texels.
    #[arg(long, default_value_t = 128)]
    pub probe_size: usize,
    /// Exposure of the PNG (and of the comparison's display values).
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f64,
    /// Seed of the camera jitter and of the random method.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// A `lustre reference` EXR of the same camera and size to compare with.
    #[arg(long)]
    pub compare_reference: Option<PathBuf>,
    /// Output folder (frame.exr, frame.png, times.csv; diff.png with --compare-reference).
    #[arg(long)]
    pub out: PathBuf,
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

/// Runs `lustre render`.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let mut st = Stages {
        times: vec![],
        t: Instant::now(),
    };
    let method = match args.method {
        Method::Regular => FrameMethod::Regular,
        Method::Ck => FrameMethod::Ck,
        Method::Progressive => FrameMethod::Progressive {
            frames: args.frames,
        },
    };
    let opts = FrameOptions {
        samples: args.samples,
        method,
        spp: args.spp,
        seed: args.seed,
    };
    opts.validate()?;
    let probe_opts = ProbeOptions {
        face_size: args.probe_size,
        ..ProbeOptions::default()
    };
    probe_opts.validate()?;
    let scene = lustre_scene::Scene::load(&args.scene)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    let Some(lightmap) = &scene.lightmap else {
        bail!(
            "{}: no light maps; bake them first (`lustre bake {} --out DIR`) and render DIR/scene.toml",
            args.scene.display(),
            args.scene.display()
        );
    };
    let (w, h) = match args.size.as_deref() {
        Some(s) => crate::reference_cmd::parse_size(s)?,
        None => (scene.film.width, scene.film.height),
    };
    let camera = lustre_shade::reference::path_camera(&scene, args.camera.as_deref(), w, h)?;
    st.lap("load");
    let pages = read_pages(lightmap).with_context(|| format!("{}", args.scene.display()))?;
    let (ps, warnings) = lustre_shade::reference::path_scene(&scene)?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let spec: Vec<Rgb> = scene.materials.iter().map(spec_albedo).collect();
    let lm = Lightmapped::new(&scene, &lightmap.atlas, &pages, &ps.geometry, spec)
        .with_context(|| format!("{}: light maps", args.scene.display()))?;
    let pt = PathTracer::new(&ps, PathOptions::default())?;
    let lit = LitScene::new(&scene, &ps, &pt, &lm)?;
    st.lap("light maps and BVH");

    let mut probes = vec![];
    for (m, mesh) in scene.meshes.iter().enumerate() {
        if !mesh.hints.probe {
            continue;
        }
        let probe = capture_probe(&lit, m, &probe_opts)
            .with_context(|| format!("probe of {:?}", mesh.name))?;
        eprintln!(
            "probe {:?} at ({:.2}, {:.2}, {:.2}): {} bounding planes, {}² faces",
            probe.name,
            probe.centre.x,
            probe.centre.y,
            probe.centre.z,
            probe.planes.len(),
            args.probe_size
        );
        st.lap(format!("probe {}", probe.name));
        probes.push(probe);
    }
    let env_pyramid = match (&probes[..], &ps.environment) {
        ([], Some(env)) => {
            eprintln!("no probe objects: glossy surfaces reflect the environment only");
            let cube = CubeMap::from_fn(args.probe_size, |d| env.eval(d).0)?;
            let p = CubePyramid::build(cube, MipFilter::Gauss6)?;
            st.lap("environment pyramid");
            Some(p)
        }
        ([], None) => {
            eprintln!("no probe objects and no environment: diffuse (light-mapped) shading only");
            None
        }
        _ => None,
    };
    let light = FrameLight {
        probes: &probes,
        environment: env_pyramid.as_ref(),
    };
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.set_message(format!("frame {w}×{h}, {} spp", args.spp));
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let (img, stats) = render_frame(&lit, &light, &camera, w as usize, h as usize, &opts)?;
    bar.finish_and_clear();
    st.lap("frame");
    if stats.mirrors + stats.see_throughs > 0 {
        // The mirror and see-through passes run inside the frame; report them as a stage.
        let (_, frame_s) = st.times.pop().unwrap_or_default();
        st.times
            .push(("mirror and see-through passes".into(), stats.mirror_seconds));
        st.times
            .push(("frame".into(), (frame_s - stats.mirror_seconds).max(0.0)));
        eprintln!(
            "{} mirror and {} see-through buffer(s) of {w}×{h} in {:.3} s",
            stats.mirrors, stats.see_throughs, stats.mirror_seconds
        );
    }

    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    img.write_exr(&args.out.join("frame.exr"))?;
    img.write_png_dithered(&args.out.join("frame.png"), args.exposure, args.seed)?;
    let glossy_rays = stats.glossy_hits.max(1);
    println!(
        "{w}×{h}, {} camera rays/pixel, {:?} with {} samples: {} glossy hits, {:.2} lookups per glossy hit",
        args.spp,
        args.method,
        args.samples,
        stats.glossy_hits,
        stats.lookups as f64 / glossy_rays as f64
    );
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
        let psnr = lustre_shade::metrics::psnr(&img, &r, args.exposure)?;
        let de = lustre_shade::metrics::delta_e(&img, &r, args.exposure)?;
        let rel = lustre_shade::metrics::rms(&img, &r)? / r.mean().max(1e-12);
        let diff = lustre_shade::metrics::false_colour(&img, &r, 0.1 * r.mean().max(1e-6))?;
        diff.write_png(&args.out.join("diff.png"), 1.0)?;
        println!(
            "against {}: PSNR {psnr:.2} dB, mean ΔE {de:.2}, relative RMS {:.2} %, mean ratio {:.4}",
            reference.display(),
            100.0 * rel,
            img.mean() / r.mean().max(1e-12)
        );
    }
    st.lap("write");
    let mut csv = String::from("stage,seconds\n");
    for (name, s) in &st.times {
        writeln!(csv, "{},{s:.4}", name.replace(',', " "))?;
    }
    writeln!(csv, "total,{:.4}", t0.elapsed().as_secs_f64())?;
    lustre_brdf::error::write_atomic(&args.out.join("times.csv"), csv.as_bytes())?;
    println!(
        "wrote {} (frame.exr, frame.png, times.csv)",
        args.out.display()
    );
    Ok(())
}
