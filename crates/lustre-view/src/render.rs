//! The viewer's render thread: it loads the scene (baking the built-in room's light maps on
//! first use), opens its own headless GPU device and steps a [`GpuFrameSession`] of the
//! walkthrough renderer (`lustre render`'s frame) for the camera the window asks for, sending
//! every new image back. The window thread never waits for it: requests and replies are
//! channel messages, frame requests coalesce (only the newest is rendered), and a still camera
//! keeps refining (progressive refinement, or the CPU path-traced reference filling in). The
//! adaptive method ([`crate::adaptive`]) renders each new view once on the CPU, its shading
//! context built on the scene's first adaptive frame.
//!
//! A scene the walkthrough cannot show — without baked light maps (the material preview and
//! the line-up of `--material` / `--lineup`, an unbaked scene file), or with a material the
//! GPU walkthrough does not take (measured BRDFs: neural, MERL, RGL) — opens *adaptive-only*:
//! the adaptive method and the CPU reference render it, and a frame asked of a walkthrough
//! method (regular, CK, progressive) fails with [`SceneInfo::no_walkthrough`], the reason.
//!
//! Material edits (`lustre_scene::material_edit::set`) are checked against the GPU's models
//! first (adaptive-only: not, the walkthrough does not show them); a refused edit is answered
//! with its error and the scene keeps running with the old material. An accepted one rebuilds
//! the scene: the path scene and the adaptive method's tables (on its next frame), and with the
//! walkthrough the light-mapped scene, the GPU upload and the probes. The mode is chosen when
//! the scene opens: an edit does not make an adaptive-only scene a walkthrough one.

use crate::adaptive::{AdaptiveMaps, AdaptiveOptions, AdaptiveRenderer};
use crate::{AdaptiveDevice, Method};
use lustre_gpu::material::pack_material;
use lustre_gpu::{
    GpuContext, GpuFrameSession, GpuFrameTimes, GpuWalkthrough, LightmapFrameScene, StepWork,
    WalkthroughPasses,
};
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::material_edit;
use lustre_scene::mesh::MAX_OBJECT_SAMPLES;
use lustre_scene::{Camera, Material, MaterialKind, Scene};
use lustre_shade::frame::FrameStats;
use lustre_shade::probe::{LitScene, ProbeOptions};
use lustre_shade::request::FrameRequest;
use lustre_trace::bake::base_albedo;
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::baked::{environment_pyramid, BakedScene};
use lustre_trace::image::Image;
use lustre_trace::path_tracer::{Accumulator, PathCamera, PathOptions, PathScene, PathTracer};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender, TryRecvError};
use std::time::Instant;

/// What to show.
#[derive(Clone, Debug, PartialEq)]
pub enum SceneSource {
    /// A scene file, with baked light maps for the walkthrough methods (adaptive-only without).
    File(PathBuf),
    /// The built-in room, its light maps baked into (and reused from) this folder.
    BuiltinRoom(PathBuf),
    /// A scene made in memory without light maps (`lustre_scene::builtin::preview` of
    /// `--material`, the line-up of `--lineup`): adaptive-only.
    Unbaked(Box<Scene>),
}

/// How a frame is rendered: the frame request (validated once, by
/// [`FrameRequest::validate`], where a method renders it) and what only the viewer tracks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewRequest {
    /// Method, glossy samples per G-buffer pixel (the adaptive method: the mean N_p), camera
    /// rays k² of a k×k G-buffer, the frames a still camera accumulates (progressive
    /// refinement; the reference: the samples per pixel it stops at) and the seed of the CK
    /// points, the reference's paths and the adaptive method's point sets.
    pub frame: FrameRequest,
    /// The adaptive method's rate and sample rule.
    pub adaptive: AdaptiveOptions,
    /// The window's count of accepted material edits, echoed in the reply: a frame asked
    /// for after an edit is told apart from the one before it.
    pub generation: u64,
}

/// A message to the render thread.
#[derive(Clone, Debug)]
pub enum Request {
    /// Render (or keep refining) this view; newer requests replace older ones.
    Frame {
        /// The camera.
        camera: PathCamera,
        /// Frame size in pixels.
        size: (usize, usize),
        /// How.
        settings: ViewRequest,
    },
    /// Which mesh pixel (x, y) of a `size` frame from `camera` shows.
    Pick {
        /// The camera.
        camera: PathCamera,
        /// Frame size in pixels.
        size: (usize, usize),
        /// Pixel (x right, y down), centre at +0.5.
        pixel: (f64, f64),
    },
    /// Set parameter `field` of material `material` to `value` (material_edit::set).
    SetMaterial {
        /// Material index.
        material: usize,
        /// Parameter name.
        field: String,
        /// Its value as text.
        value: String,
    },
    /// Give mesh `mesh` its own glossy sample budget (`None`: the frame's).
    SetObjectSamples {
        /// Mesh index.
        mesh: usize,
        /// Samples per pixel, 1–256.
        samples: Option<u32>,
    },
    /// Stop.
    Quit,
}

/// What the scene holds, for the window.
#[derive(Clone, Debug)]
pub struct SceneInfo {
    /// Its name for the title.
    pub name: String,
    /// Materials.
    pub materials: Vec<Material>,
    /// Mesh names and their material index.
    pub meshes: Vec<(String, usize)>,
    /// Each mesh's own sample budget.
    pub object_samples: Vec<Option<u32>>,
    /// Named cameras.
    pub cameras: Vec<Camera>,
    /// The scene's film size.
    pub film: (u32, u32),
    /// The camera to start from: the scene's first (or the automatic one for scenes without).
    pub start: Camera,
    /// The adapter the frames are rendered on.
    pub adapter: String,
    /// Scene extent (diagonal of the bounds), for the walking speed.
    pub extent: f64,
    /// Why the walkthrough methods (regular, CK, progressive) cannot show the scene (no light
    /// maps, a material the GPU walkthrough does not take); `None` when they can.
    pub no_walkthrough: Option<String>,
    /// The real-time set-up's probes and reflectors.
    pub setup: crate::setup_overlay::SetupOverlay,
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct FrameReply {
    /// The linear image.
    pub image: Image,
    /// The camera it was rendered from.
    pub camera: PathCamera,
    /// Settings it was rendered with.
    pub settings: ViewRequest,
    /// GPU pass times of the step that made it (zero for the reference and adaptive methods).
    pub times: GpuFrameTimes,
    /// Frames (progressive) or samples per pixel (reference) the image holds (adaptive: 1).
    pub frames: u32,
    /// What the step ran.
    pub work: Option<StepWork>,
    /// Counts of the view-dependent pass.
    pub stats: FrameStats,
    /// Wall time of the step and read-back, ms.
    pub wall_ms: f64,
    /// The adaptive method's buffers, counts and times.
    pub adaptive: Option<Box<AdaptiveMaps>>,
}

/// A message from the render thread.
#[derive(Debug)]
pub enum Reply {
    /// What the thread is doing (loading, baking n of m tiles, …).
    Status(String),
    /// The scene is ready.
    Ready(Box<SceneInfo>),
    /// A new image.
    Frame(Box<FrameReply>),
    /// The frame asked for cannot be rendered (bad settings, a failed pass, a scene the
    /// method cannot light); nothing more is rendered until the window asks again.
    FrameFailed {
        /// The request's camera.
        camera: PathCamera,
        /// Its size.
        size: (usize, usize),
        /// Its settings.
        settings: ViewRequest,
        /// Why.
        error: String,
    },
    /// The answer to a pick: the mesh index, if any.
    Picked(Option<usize>),
    /// The answer to a material edit: the material as it is now, or why it was refused (the
    /// scene keeps the old one), and the time until the new material was ready to render.
    MaterialSet {
        /// Material index.
        material: usize,
        /// The edit's `field=value`.
        edit: String,
        /// The material after the edit, or the error.
        result: Result<Box<Material>, String>,
        /// Seconds from the request to the rebuilt scene.
        seconds: f64,
    },
    /// The thread cannot go on (no adapter, an unreadable scene); the message says why.
    Fatal(String),
}

/// Why [`serve`] returned.
enum Exit {
    Quit,
    Edit(Edit),
}

/// A change of the scene that needs it built again.
#[derive(Clone, Debug)]
enum Edit {
    /// material_edit::set of a material: the edit and the material it gave (checked once).
    Material {
        material: usize,
        field: String,
        value: String,
        edited: Box<Material>,
        asked: Instant,
    },
    /// An object's own sample budget.
    ObjectSamples {
        mesh: usize,
        samples: Option<u32>,
        asked: Instant,
    },
}

/// Runs the render thread until [`Request::Quit`] or the window's end of the channel closes;
/// probes are captured at `probe_size`² texels per face, and the adaptive method's passes run
/// where `adaptive_device` says.
pub fn run(
    source: SceneSource,
    probe_size: usize,
    adaptive_device: AdaptiveDevice,
    rx: Receiver<Request>,
    tx: Sender<Reply>,
) {
    if let Err(e) = run_inner(source, probe_size, adaptive_device, &rx, &tx) {
        let _ = tx.send(Reply::Fatal(format!("{e:#}")));
    }
}

fn run_inner(
    source: SceneSource,
    probe_size: usize,
    adaptive_device: AdaptiveDevice,
    rx: &Receiver<Request>,
    tx: &Sender<Reply>,
) -> anyhow::Result<()> {
    let probe_opts = ProbeOptions {
        face_size: probe_size,
        ..ProbeOptions::default()
    };
    probe_opts.validate()?;
    let (name, baked) = match source {
        SceneSource::File(p) => {
            let _ = tx.send(Reply::Status(format!("loading {}", p.display())));
            (p.display().to_string(), load_file(&p)?)
        }
        SceneSource::Unbaked(scene) => {
            let name = scene.source.display().to_string();
            let why = format!(
                "{name} has no light maps (the walkthrough methods need them) — use the \
                 adaptive method"
            );
            (name, (*scene, Err(why)))
        }
        SceneSource::BuiltinRoom(dir) => {
            let _ = tx.send(Reply::Status(format!(
                "baking the built-in room's light maps into {} (reused next time)",
                dir.display()
            )));
            let report = |k: usize, n: usize| {
                let _ = tx.send(Reply::Status(format!(
                    "baking the built-in room's light maps: tile {k} of {n}"
                )));
            };
            let b = BakedScene::builtin_room(&dir, None, &report)?;
            (
                "the built-in room".to_string(),
                (b.scene, Ok((b.atlas, b.pages))),
            )
        }
    };
    let (mut scene, lightmaps) = baked;
    // The light maps, or why the walkthrough cannot show the scene (a material first: baking
    // would not help there).
    let walkthrough = match scene.materials.iter().find_map(gpu_refusal) {
        Some(why) => Err(why),
        None => lightmaps,
    };
    let _ = tx.send(Reply::Status("opening the GPU".into()));
    let ctx = GpuContext::new().map_err(|e| anyhow::anyhow!("no GPU adapter: {e}"))?;
    let mut first = true;
    let mut passes: Option<WalkthroughPasses> = None;
    let mut edit: Option<Edit> = None;
    loop {
        let mut answer = None;
        match edit.take() {
            Some(Edit::Material {
                material,
                field,
                value,
                edited,
                asked,
            }) => {
                answer = Some((material, format!("{field}={value}"), asked));
                if let Some(mat) = scene.materials.get_mut(material) {
                    // Made and checked by `serve` (an SGD shape edit refits its G1 once).
                    *mat = *edited;
                }
            }
            Some(Edit::ObjectSamples {
                mesh,
                samples,
                asked,
            }) => {
                if let Some(m) = scene.meshes.get_mut(mesh) {
                    m.hints.samples = samples;
                    let what = samples.map_or("the frame's".to_string(), |n| n.to_string());
                    answer = Some((
                        m.material,
                        format!("samples of {:?}: {what}", m.name),
                        asked,
                    ));
                }
            }
            None => {}
        }
        let _ = tx.send(Reply::Status(match (first, walkthrough.is_ok()) {
            (true, true) => "preparing the scene for the GPU (upload, probes)".into(),
            (true, false) => "preparing the scene (BVH)".into(),
            (false, true) => "applying the material (light-mapped scene, upload, probes)".into(),
            (false, false) => {
                "applying the material (BVH; adaptive tables on its next frame)".into()
            }
        }));
        let (ps, warnings) = lustre_trace::reference::path_scene(&scene)?;
        if first {
            for w in warnings {
                let _ = tx.send(Reply::Status(format!("warning: {w}")));
            }
        }
        let pt = PathTracer::new(&ps, PathOptions::default())?;
        // The walkthrough's parts, each with what the next needs, or why there is none.
        let lm = match &walkthrough {
            Ok((atlas, pages)) => {
                let bases = scene.materials.iter().map(base_albedo).collect();
                let lm = Lightmapped::new(&scene, atlas, pages, &ps.geometry, bases)?;
                Ok((lm, atlas, pages))
            }
            Err(why) => Err(why.as_str()),
        };
        let lit = match &lm {
            Ok((lm, atlas, pages)) => Ok((LitScene::new(&scene, &ps, &pt, lm)?, *atlas, *pages)),
            Err(why) => Err(*why),
        };
        let walk = match &lit {
            Ok((lit, atlas, pages)) => {
                let has_probes = lustre_shade::probe::has_probes(&scene);
                let env = match (&ps.environment, has_probes) {
                    (Some(e), false) => Some(environment_pyramid(e, probe_size)?),
                    _ => None,
                };
                let uploaded = LightmapFrameScene::upload(&ctx, &scene, atlas, pages)?;
                // The passes are compiled once (a material edit only uploads the scene again).
                let compiled = match passes.take() {
                    Some(p) => p,
                    None => WalkthroughPasses::new(&ctx)?,
                };
                let walk = GpuWalkthrough::with_passes(
                    &ctx,
                    compiled,
                    lit,
                    uploaded,
                    &probe_opts,
                    env.as_ref(),
                )?;
                Ok((walk, lit))
            }
            Err(why) => Err(*why),
        };
        if first {
            let mut info = info(&scene, &name, &ctx);
            info.no_walkthrough = walkthrough.as_ref().err().cloned();
            let _ = tx.send(Reply::Ready(Box::new(info)));
            first = false;
        }
        if let Some((material, edit, asked)) = answer {
            let _ = tx.send(Reply::MaterialSet {
                material,
                edit,
                result: scene
                    .materials
                    .get(material)
                    .map(|m| Box::new(m.clone()))
                    .ok_or_else(|| "no such material".to_string()),
                seconds: asked.elapsed().as_secs_f64(),
            });
        }
        let view = walk.as_ref().map(|(w, l)| (w, *l)).map_err(|why| *why);
        let gpu = Gpu {
            ctx: &ctx,
            adaptive: adaptive_device,
        };
        let exit = serve(gpu, view, &scene, &ps, &pt, rx, tx)?;
        passes = walk.ok().map(|(w, _)| w.into_passes());
        match exit {
            Exit::Quit => return Ok(()),
            Exit::Edit(e) => edit = Some(e),
        }
    }
}

/// A scene's light-map atlas and its baked irradiance pages.
type Lightmaps = (LightmapAtlas, Vec<Vec<[f32; 3]>>);

/// The scene file at `path` with its light maps, or, for a scene file that was not baked, the
/// scene and why the walkthrough cannot show it.
fn load_file(path: &Path) -> anyhow::Result<(Scene, Result<Lightmaps, String>)> {
    match BakedScene::load(path) {
        Ok(b) => Ok((b.scene, Ok((b.atlas, b.pages)))),
        Err(baked) => match Scene::load(path) {
            Ok(scene) if scene.lightmap.is_none() => {
                let why = format!(
                    "{} has no light maps (the walkthrough methods need them: `lustre bake {} \
                     --out DIR`, then open DIR/scene.toml) — use the adaptive method",
                    path.display(),
                    path.display()
                );
                Ok((scene, Err(why)))
            }
            _ => Err(baked.into()),
        },
    }
}

/// Why the GPU walkthrough cannot shade material `m` (a measured BRDF, a model without a GPU
/// layout), or `None`.
fn gpu_refusal(m: &Material) -> Option<String> {
    let e = pack_material(m, &mut vec![]).err()?;
    let what = match &m.kind {
        MaterialKind::Spec(s) => s.spec.clone(),
        k => k.name().to_string(),
    };
    Some(format!(
        "material {:?} ({what}): not on the GPU walkthrough in this build — use the adaptive \
         method ({e})",
        m.name
    ))
}

/// The window's view of the scene.
fn info(scene: &Scene, name: &str, ctx: &GpuContext) -> SceneInfo {
    let extent = scene
        .bounds()
        .map_or(1.0, |(lo, hi)| f64::from((hi - lo).length()).max(1e-3));
    SceneInfo {
        name: name.to_string(),
        materials: scene.materials.clone(),
        meshes: scene
            .meshes
            .iter()
            .map(|m| (m.name.clone(), m.material))
            .collect(),
        object_samples: scene.meshes.iter().map(|m| m.hints.samples).collect(),
        cameras: scene.cameras.clone(),
        film: (scene.film.width, scene.film.height),
        start: start_camera(scene),
        adapter: ctx.describe(),
        extent,
        no_walkthrough: None,
        setup: crate::setup_overlay::SetupOverlay::of(scene),
    }
}

/// The scene's first camera, or the automatic one `lustre render` uses for scenes without.
fn start_camera(scene: &Scene) -> Camera {
    if let Some(c) = scene.cameras.first() {
        return c.clone();
    }
    let (w, h) = (scene.film.width.max(1), scene.film.height.max(1));
    match lustre_trace::reference::path_camera(scene, None, w, h) {
        Ok(p) => Camera {
            name: "automatic".into(),
            position: p.origin,
            forward: p.forward,
            up: p.up,
            fov_deg: 2.0 * p.tan_half_fov_y.atan().to_degrees(),
            fov_axis: lustre_scene::FovAxis::Y,
            aspect: None,
        },
        Err(_) => Camera {
            name: "automatic".into(),
            position: glam::DVec3::new(0.0, 1.0, 3.0),
            forward: glam::DVec3::NEG_Z,
            up: glam::DVec3::Y,
            fov_deg: 50.0,
            fov_axis: lustre_scene::FovAxis::Y,
            aspect: None,
        },
    }
}

/// The reference's running accumulation.
struct Reference {
    camera: PathCamera,
    size: (usize, usize),
    acc: Accumulator,
}

/// The render thread's device, and where the adaptive method's passes may run.
#[derive(Clone, Copy)]
struct Gpu<'a> {
    ctx: &'a GpuContext,
    adaptive: AdaptiveDevice,
}

/// Answers requests over one built scene until a quit or an accepted material edit; `walk` is
/// the walkthrough renderer over the light-mapped scene, or why the scene has none
/// (adaptive-only: its methods' frames fail with that reason).
fn serve(
    gpu: Gpu,
    walk: Result<(&GpuWalkthrough, &LitScene), &str>,
    scene: &Scene,
    ps: &PathScene,
    pt: &PathTracer,
    rx: &Receiver<Request>,
    tx: &Sender<Reply>,
) -> anyhow::Result<Exit> {
    let ctx = gpu.ctx;
    // Mesh index of every triangle, in the path scene's order (as LitScene::mesh_of).
    let mesh_of: Vec<usize> = scene
        .meshes
        .iter()
        .enumerate()
        .flat_map(|(k, m)| std::iter::repeat_n(k, m.indices.len()))
        .collect();
    let mut session = GpuFrameSession::new();
    let mut wanted: Option<(PathCamera, (usize, usize), ViewRequest)> = None;
    // The request the last frame sent answered.
    let mut answered: Option<(PathCamera, (usize, usize), ViewRequest)> = None;
    let mut busy = false;
    let mut reference: Option<Reference> = None;
    // The adaptive method's shading context, built on this scene's first adaptive frame (or
    // why it cannot be), and the request its last frame answered.
    let mut adaptive: Option<Result<AdaptiveRenderer, String>> = None;
    let mut adaptive_done: Option<(PathCamera, (usize, usize), ViewRequest)> = None;
    loop {
        // Block while there is nothing to refine; otherwise take what has arrived.
        let mut requests = vec![];
        if busy {
            loop {
                match rx.try_recv() {
                    Ok(r) => requests.push(r),
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => return Ok(Exit::Quit),
                }
            }
        } else {
            match rx.recv() {
                Ok(r) => requests.push(r),
                Err(_) => return Ok(Exit::Quit),
            }
            while let Ok(r) = rx.try_recv() {
                requests.push(r);
            }
        }
        for r in requests {
            match r {
                Request::Quit => return Ok(Exit::Quit),
                Request::Frame {
                    camera,
                    size,
                    settings,
                } => {
                    wanted = Some((camera, size, settings));
                    busy = true;
                    // Every frame request is answered (the window asks again only for a
                    // change, e.g. back to the adaptive method after another).
                    adaptive_done = None;
                }
                Request::Pick {
                    camera,
                    size,
                    pixel,
                } => {
                    let d = camera.direction(pixel.0, pixel.1, size.0, size.1);
                    let mesh = pt
                        .intersect(camera.origin, d)
                        .and_then(|h| mesh_of.get(h.prim).copied());
                    let _ = tx.send(Reply::Picked(mesh));
                }
                Request::SetObjectSamples { mesh, samples } => {
                    let ok = mesh < scene.meshes.len()
                        && samples.is_none_or(|n| (1..=MAX_OBJECT_SAMPLES).contains(&n));
                    if ok {
                        return Ok(Exit::Edit(Edit::ObjectSamples {
                            mesh,
                            samples,
                            asked: Instant::now(),
                        }));
                    }
                    let _ = tx.send(Reply::Status(format!(
                        "render error: object #{mesh} samples {samples:?} (1..={MAX_OBJECT_SAMPLES})"
                    )));
                }
                Request::SetMaterial {
                    material,
                    field,
                    value,
                } => {
                    let asked = Instant::now();
                    let checked = scene
                        .materials
                        .get(material)
                        .ok_or_else(|| format!("no material #{material}"))
                        .and_then(|m| {
                            let mut trial = m.clone();
                            material_edit::set(&mut trial, &field, &value)
                                .map_err(|e| e.to_string())?;
                            if walk.is_ok() {
                                pack_material(&trial, &mut vec![])
                                    .map_err(|e| format!("{e} (the GPU keeps the old material)"))?;
                            }
                            Ok(trial)
                        });
                    match checked {
                        Ok(trial) => {
                            return Ok(Exit::Edit(Edit::Material {
                                material,
                                field,
                                value,
                                edited: Box::new(trial),
                                asked,
                            }))
                        }
                        Err(e) => {
                            let _ = tx.send(Reply::MaterialSet {
                                material,
                                edit: format!("{field}={value}"),
                                result: Err(e),
                                seconds: asked.elapsed().as_secs_f64(),
                            });
                        }
                    }
                }
            }
        }
        let Some((camera, size, settings)) = wanted else {
            busy = false;
            continue;
        };
        let t = Instant::now();
        if settings.frame.method == Method::Reference {
            let r = match reference.take() {
                Some(r) if r.camera == camera && r.size == size => r,
                _ => Reference {
                    camera,
                    size,
                    acc: Accumulator::new(size.0, size.1)?,
                },
            };
            let mut r = r;
            if r.acc.spp >= settings.frame.frames.max(1) {
                busy = false;
                reference = Some(r);
                continue;
            }
            pt.render(&camera, &mut r.acc, 1, settings.frame.seed, &|_, _| {});
            let _ = tx.send(Reply::Frame(Box::new(FrameReply {
                image: r.acc.image(),
                camera,
                settings,
                times: GpuFrameTimes::default(),
                frames: r.acc.spp,
                work: None,
                stats: FrameStats::default(),
                wall_ms: t.elapsed().as_secs_f64() * 1e3,
                adaptive: None,
            })));
            // The window now shows something else than the session's last frame: back to a GPU
            // method, an unchanged step is sent again.
            answered = None;
            reference = Some(r);
            continue;
        }
        if settings.frame.method == Method::Adaptive {
            let key = (camera, size, settings);
            busy = false;
            if adaptive_done == Some(key) {
                continue;
            }
            adaptive_done = Some(key);
            let renderer = adaptive.get_or_insert_with(|| {
                let progress = |k: usize, n: usize| {
                    let _ = tx.send(Reply::Status(format!(
                        "adaptive shading: material tables {k} of {n}"
                    )));
                };
                let passes = Some((ctx, &*scene));
                AdaptiveRenderer::new(ps, &progress, passes, gpu.adaptive)
                    .map_err(|e| format!("{e:#}"))
            });
            let rendered = renderer.as_mut().map_err(|e| e.clone()).and_then(|r| {
                r.render(Some(ctx), pt, &camera, size, &settings)
                    .map_err(|e| format!("{e:#}"))
            });
            let _ = tx.send(match rendered {
                Ok((image, maps)) => Reply::Frame(Box::new(FrameReply {
                    image,
                    camera,
                    settings,
                    times: GpuFrameTimes::default(),
                    frames: 1,
                    work: None,
                    stats: FrameStats::default(),
                    wall_ms: t.elapsed().as_secs_f64() * 1e3,
                    adaptive: Some(Box::new(maps)),
                })),
                Err(error) => Reply::FrameFailed {
                    camera,
                    size,
                    settings,
                    error: format!("adaptive method: {error}"),
                },
            });
            answered = None;
            continue;
        }
        let (walk, lit) = match walk {
            Ok(w) => w,
            Err(why) => {
                let _ = tx.send(Reply::FrameFailed {
                    camera,
                    size,
                    settings,
                    error: format!("the {} method: {why}", settings.frame.method.name()),
                });
                wanted = None;
                busy = false;
                continue;
            }
        };
        // The reference and adaptive methods returned above: a walkthrough method here.
        let opts = FrameRequest {
            frames: settings.frame.frames.max(1),
            ..settings.frame
        };
        let step = match session.step(ctx, walk, lit, &camera, size, &opts) {
            Ok(s) => s,
            Err(e) => {
                // Bad settings (or a failed pass): said, and nothing is asked again until the
                // window sends a new request.
                let _ = tx.send(Reply::FrameFailed {
                    camera,
                    size,
                    settings,
                    error: e.to_string(),
                });
                wanted = None;
                busy = false;
                continue;
            }
        };
        let key = (camera, size, settings);
        if step.work == StepWork::Unchanged {
            busy = false;
            // The frame is done, but a request that differs only in what the window tracks
            // (a new generation after a rebuild, queued behind a request made during it) is
            // answered with it, or the window would wait for it for ever.
            if answered == Some(key) {
                continue;
            }
        }
        answered = Some(key);
        let image = session.image(ctx)?;
        let _ = tx.send(Reply::Frame(Box::new(FrameReply {
            image,
            camera,
            settings,
            times: step.times,
            frames: step.frames,
            work: Some(step.work),
            stats: step.stats,
            wall_ms: t.elapsed().as_secs_f64() * 1e3,
            adaptive: None,
        })));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_materials_and_unbaked_files_are_refused_the_walkthrough_by_name() {
        let material = |spec| {
            let mut s = lustre_scene::builtin::preview(spec, None).unwrap();
            s.materials.remove(0)
        };
        let why = gpu_refusal(&material("nbrdf:gold-paint")).expect("a neural BRDF");
        assert!(
            why.starts_with(
                "material \"nbrdf:gold-paint\" (nbrdf:gold-paint): not on the GPU walkthrough"
            ),
            "{why}"
        );
        assert_eq!(gpu_refusal(&material("sgd:gold-metallic-paint")), None);

        // A scene file without light maps opens, saying how to bake it; a missing one does not.
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(
            d.join("floor.obj"),
            "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nf 1 3 2\n",
        )
        .unwrap();
        std::fs::write(
            d.join("floor.toml"),
            "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"floor.obj\"\n\
             [environment]\nconstant = [1.0, 1.0, 1.0]\n",
        )
        .unwrap();
        let (scene, lightmaps) = load_file(&d.join("floor.toml")).unwrap();
        assert_eq!(scene.meshes.len(), 1);
        let why = lightmaps.expect_err("no light maps");
        assert!(
            why.contains("floor.toml has no light maps") && why.contains("lustre bake"),
            "{why}"
        );
        let e = load_file(&d.join("nope.toml")).expect_err("a missing file");
        assert!(e.to_string().contains("nope.toml"), "{e}");
    }
}
