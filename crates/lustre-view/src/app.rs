//! The window: winit events, the egui panels, the 3D view drawn from the render thread's
//! latest frame, input scripts, screenshots, and the surface's life (resize, outdated or lost
//! surfaces reconfigured, a lost device ends the run cleanly).

use crate::adaptive::{rule_name, AdaptiveSettings, BufferView, SAMPLE_RULES};
use crate::camera::{FlyCamera, Movement};
use crate::fit::{FitDone, FitJob, PLOT_THETA_I};
use crate::plot::polar_points;
use crate::render::{self, FrameReply, FrameSettings, Reply, Request, SceneInfo, SceneSource};
use crate::script::{self, Command, Direction};
use crate::{ViewArgs, ViewMethod};
use anyhow::{anyhow, bail, Context};
use lustre_scene::camera_path_file::CameraPathFile;
use lustre_scene::material_edit::{self, Field, FieldValue};
use lustre_scene::{CameraPath, Keyframe, Material, MaterialKind};
use lustre_trace::path::PathCamera;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// Radians of turn per pixel of mouse drag.
const LOOK_RADIANS_PER_PIXEL: f64 = 0.004;
/// Width of the view panel, points.
const LEFT_PANEL: f32 = 210.0;
/// Width of the material panel, points.
const RIGHT_PANEL: f32 = 280.0;
/// Frames kept in the frame-time graph.
const HISTORY: usize = 120;

/// `WxH` in pixels.
fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| anyhow!("--size {s:?}: expected WxH"))?;
    let (w, h): (u32, u32) = (
        w.trim().parse().context("--size width")?,
        h.trim().parse().context("--size height")?,
    );
    if !(64..=8192).contains(&w) || !(64..=8192).contains(&h) {
        bail!("--size {w}x{h}: each side must be 64 … 8192");
    }
    Ok((w, h))
}

/// Runs the viewer (see the crate docs).
pub fn run(args: &ViewArgs) -> anyhow::Result<()> {
    let size = parse_size(&args.size)?;
    if !(0.1..=1.0).contains(&args.scale) {
        bail!("--scale {}: must be 0.1 … 1", args.scale);
    }
    if !(1..=256).contains(&args.samples) {
        bail!("--samples {}: must be 1 … 256", args.samples);
    }
    if !(1..=4).contains(&args.supersampling) {
        bail!("--supersampling {}: must be 1 … 4", args.supersampling);
    }
    lustre_shade::probe::ProbeOptions {
        face_size: args.probe_size,
        ..Default::default()
    }
    .validate()
    .map_err(|e| anyhow!("--probe-size: {e}"))?;
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!("--timeout {}: must be positive", args.timeout);
    }
    let commands = match &args.script {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .with_context(|| format!("reading the script {}", p.display()))?;
            script::parse(&text).map_err(|e| anyhow!("{}: {e}", p.display()))?
        }
        None => vec![],
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let source = scene_source(args)?;
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!("no window system ({e}); run under X11 (or xvfb-run for a virtual display)")
    })?;
    let (req_tx, req_rx) = channel();
    let (rep_tx, rep_rx) = channel();
    let src = source.clone();
    let probe_size = args.probe_size;
    let adaptive_device = args.adaptive_device;
    let render_thread = std::thread::Builder::new()
        .name("lustre-view render".into())
        .spawn(move || render::run(src, probe_size, adaptive_device, req_rx, rep_tx))
        .context("starting the render thread")?;
    let mut app = App::new(args.clone(), size, source, commands, req_tx, rep_rx);
    let looped = event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop: {e}"));
    // An orderly end: the window's GPU objects first, then the render thread's (it ends at
    // its next request; one busy baking or rendering is given a while, then left to the exit).
    app.gfx = None;
    let _ = app.to_render.send(Request::Quit);
    let t = Instant::now();
    while !render_thread.is_finished() && t.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(20));
    }
    if render_thread.is_finished() {
        let _ = render_thread.join();
    }
    looped?;
    app.outcome.unwrap_or(Ok(())).map_err(|e| anyhow!(e))
}

/// What `args` open: a scene file, `--material`'s preview, `--lineup`, or the built-in room.
/// The in-memory scenes are made here, so that a bad specification or map fails before the
/// window opens.
fn scene_source(args: &ViewArgs) -> anyhow::Result<SceneSource> {
    use lustre_scene::builtin::{lineup, preview, LINEUP_FLOOR, LINEUP_PAINTS};
    let unbaked = args.material.is_some() || args.lineup;
    if let (Some(env), false) = (&args.env, unbaked) {
        bail!(
            "--env {}: applies to --material and --lineup (a scene file, and the built-in room, \
             have their own environment)",
            env.display()
        );
    }
    let environment = args
        .env
        .as_deref()
        .map(|p| {
            lustre_trace::baked::read_environment(p)
                .with_context(|| format!("--env {}", p.display()))
        })
        .transpose()?;
    Ok(match (&args.scene, &args.material) {
        (Some(p), _) => {
            if !p.is_file() {
                bail!("{}: no such scene file", p.display());
            }
            SceneSource::File(p.clone())
        }
        (None, Some(spec)) => SceneSource::Unbaked(Box::new(
            preview(spec, environment).with_context(|| format!("--material {spec}"))?,
        )),
        (None, None) if args.lineup => SceneSource::Unbaked(Box::new(
            lineup(LINEUP_PAINTS, LINEUP_FLOOR, environment).context("--lineup")?,
        )),
        (None, None) => SceneSource::BuiltinRoom(args.bake_dir.clone()),
    })
}

/// The window's GPU objects.
struct Gfx {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    renderer: egui_wgpu::Renderer,
    state: egui_winit::State,
    lost: Arc<AtomicBool>,
    present_modes: Vec<wgpu::PresentMode>,
}

/// What a script command waits for before the next one runs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Wait {
    /// Window frames.
    Frames(u32),
    /// The frame of the current camera and settings, every edit answered.
    Settle,
    /// The screenshot asked for has been written.
    Screenshot,
}

/// The material editor's state for the selected material.
struct Draft {
    material: usize,
    fields: Vec<Field>,
    spec: String,
}

/// A recording of the camera path.
struct Recording {
    started: Instant,
    keyframes: Vec<Keyframe>,
    file: String,
}

/// A message in the window.
struct Note {
    text: String,
    error: bool,
}

struct App {
    args: ViewArgs,
    size: (u32, u32),
    source: SceneSource,
    ctx: egui::Context,
    gfx: Option<Gfx>,
    to_render: Sender<Request>,
    from_render: Receiver<Reply>,
    outcome: Option<Result<(), String>>,
    started: Instant,
    last_tick: Instant,
    status: String,
    info: Option<SceneInfo>,
    fatal: Option<String>,
    camera: Option<FlyCamera>,
    speed: f64,
    settings: FrameSettings,
    scale: f64,
    exposure: f64,
    vsync: bool,
    view_size: (usize, usize),
    view_rect_px: [f32; 4],
    sent: Option<(PathCamera, (usize, usize), FrameSettings)>,
    /// The last request the render thread could not render.
    failed: Option<(PathCamera, (usize, usize), FrameSettings)>,
    frame: Option<FrameReply>,
    /// What the adaptive method shows, and the heat map's range when a buffer is shown.
    buffer_view: BufferView,
    heat_range: Option<(f64, f64)>,
    texture: Option<egui::TextureHandle>,
    frames_received: u32,
    frames_shown: u32,
    frame_times: VecDeque<(f64, lustre_gpu::GpuFrameTimes)>,
    ui_times: VecDeque<f64>,
    last_frame_at: Option<Instant>,
    selected: Option<usize>,
    draft: Option<Draft>,
    pending_edits: u32,
    pending_pick: bool,
    edits: Vec<(String, String, String)>,
    notes: Vec<Note>,
    catalog: Vec<String>,
    catalog_filter: String,
    fit: Option<FitJob>,
    fit_input: String,
    fit_model: String,
    fit_done: Option<FitDone>,
    fit_pressed: Option<Instant>,
    fit_applied: Option<String>,
    fit_to_screen: Option<f64>,
    save_material_path: String,
    save_scene_path: String,
    recording: Option<Recording>,
    record_name: String,
    script: VecDeque<Command>,
    unattended: bool,
    wait: Option<Wait>,
    screenshot: Option<PathBuf>,
    screenshots: u32,
    quit_after_screenshot: bool,
}

impl App {
    fn new(
        args: ViewArgs,
        size: (u32, u32),
        source: SceneSource,
        commands: Vec<Command>,
        to_render: Sender<Request>,
        from_render: Receiver<Reply>,
    ) -> Self {
        let unattended = !commands.is_empty() || args.frames.is_some();
        App {
            settings: FrameSettings {
                method: ViewMethod::Regular,
                samples: args.samples,
                supersampling: args.supersampling,
                refine_frames: 64,
                seed: 1,
                generation: 0,
                adaptive: AdaptiveSettings::default(),
            },
            scale: args.scale,
            vsync: !args.no_vsync,
            args,
            size,
            source,
            ctx: egui::Context::default(),
            gfx: None,
            to_render,
            from_render,
            outcome: None,
            started: Instant::now(),
            last_tick: Instant::now(),
            status: "starting".into(),
            info: None,
            fatal: None,
            camera: None,
            speed: 1.0,
            exposure: 1.0,
            view_size: (0, 0),
            view_rect_px: [0.0; 4],
            sent: None,
            failed: None,
            frame: None,
            buffer_view: BufferView::Image,
            heat_range: None,
            texture: None,
            frames_received: 0,
            frames_shown: 0,
            frame_times: VecDeque::new(),
            ui_times: VecDeque::new(),
            last_frame_at: None,
            selected: None,
            draft: None,
            pending_edits: 0,
            pending_pick: false,
            edits: vec![],
            notes: vec![],
            catalog: lustre_brdf::catalog::list(),
            catalog_filter: String::new(),
            fit: None,
            fit_input: String::new(),
            fit_model: "sgd".into(),
            fit_done: None,
            fit_pressed: None,
            fit_applied: None,
            fit_to_screen: None,
            save_material_path: "material.json".into(),
            save_scene_path: "scene-edited.toml".into(),
            recording: None,
            record_name: "walk".into(),
            script: commands.into(),
            unattended,
            wait: None,
            screenshot: None,
            screenshots: 0,
            quit_after_screenshot: false,
        }
    }

    /// A path in the output folder (absolute paths kept).
    fn out_path(&self, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            self.args.out.join(p)
        }
    }

    fn note(&mut self, text: impl Into<String>, error: bool) {
        let text = text.into();
        if self.unattended {
            let t = self.started.elapsed().as_secs_f64();
            if error {
                eprintln!("lustre view: [{t:.1} s] {text}");
            } else {
                println!("[{t:.1} s] {text}");
            }
        }
        self.notes.push(Note { text, error });
        if self.notes.len() > 8 {
            self.notes.remove(0);
        }
    }

    fn finish(&mut self, event_loop: &ActiveEventLoop, outcome: Result<(), String>) {
        if self.outcome.is_none() {
            self.outcome = Some(outcome);
        }
        event_loop.exit();
    }

    /// Creates the window, its surface and egui's renderer.
    fn create_gfx(&mut self, event_loop: &ActiveEventLoop) -> Result<Gfx, String> {
        let attrs = Window::default_attributes()
            .with_title("lustre view")
            .with_inner_size(PhysicalSize::new(self.size.0, self.size.1));
        let window = Arc::new(
            event_loop
                .create_window(attrs)
                .map_err(|e| format!("no window: {e}"))?,
        );
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
                Box::new(event_loop.owned_display_handle()),
            ));
        let surface = instance.create_surface(window.clone()).map_err(|e| {
            format!(
                "no GPU adapter can draw to this window (no surface: {e}); install a Vulkan \
                     driver (mesa-vulkan-drivers gives lavapipe)"
            )
        })?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: Some(&surface),
            apply_limit_buckets: false,
        }))
        .map_err(|e| format!("no GPU adapter can draw to this window ({e}); install a Vulkan driver (mesa-vulkan-drivers gives lavapipe)"))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lustre-view window"),
            required_features: wgpu::Features::empty(),
            required_limits: wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits()),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| format!("the window's GPU device ({}): {e}", adapter.get_info().name))?;
        let caps = surface.get_capabilities(&adapter);
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| !f.is_srgb())
            .or_else(|| caps.formats.first().copied())
            .ok_or_else(|| "the window's surface offers no format".to_string())?;
        let inner = window.inner_size();
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format,
            color_space: wgpu::SurfaceColorSpace::Auto,
            width: inner.width.max(1),
            height: inner.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats: vec![],
        };
        let lost = Arc::new(AtomicBool::new(false));
        let flag = lost.clone();
        device.set_device_lost_callback(move |_, _| flag.store(true, Ordering::SeqCst));
        let renderer = egui_wgpu::Renderer::new(
            &device,
            format,
            egui_wgpu::RendererOptions {
                // The 3D view's pixels are shown as they are (no dither noise).
                dithering: false,
                ..Default::default()
            },
        );
        let state = egui_winit::State::new(
            self.ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(device.limits().max_texture_dimension_2d as usize),
        );
        let mut gfx = Gfx {
            window,
            surface,
            device,
            queue,
            config,
            renderer,
            state,
            lost,
            present_modes: caps.present_modes.clone(),
        };
        configure(&mut gfx, self.vsync);
        Ok(gfx)
    }

    /// Takes the render thread's replies.
    fn poll_replies(&mut self) {
        while let Ok(r) = self.from_render.try_recv() {
            match r {
                Reply::Status(s) => {
                    if s.starts_with("render error") || s.starts_with("warning") {
                        self.note(s.clone(), s.starts_with("render error"));
                    } else if self.unattended && !s.contains(" tile ") {
                        println!("[{:.1} s] {s}", self.started.elapsed().as_secs_f64());
                    }
                    self.status = s;
                }
                Reply::Ready(info) => {
                    let aspect = f64::from(info.film.0) / f64::from(info.film.1).max(1.0);
                    self.camera = Some(FlyCamera::from_camera(&info.start, aspect));
                    self.speed = (info.extent / 10.0).max(0.05);
                    self.status = format!("{} on {}", info.name, info.adapter);
                    let text = self.status.clone();
                    self.note(format!("ready: {text}"), false);
                    if let Some(why) = &info.no_walkthrough {
                        // Adaptive-only: the window starts in the adaptive method.
                        self.settings.method = ViewMethod::Adaptive;
                        self.note(format!("adaptive method only: {why}"), false);
                    }
                    self.info = Some(*info);
                }
                Reply::Frame(f) => {
                    self.frames_received += 1;
                    let now = Instant::now();
                    if let Some(t) = self.last_frame_at.replace(now) {
                        self.frame_times
                            .push_back(((now - t).as_secs_f64() * 1e3, f.times));
                        if self.frame_times.len() > HISTORY {
                            self.frame_times.pop_front();
                        }
                    }
                    if let (Some(pressed), Some(_)) = (self.fit_pressed, self.fit_applied.take()) {
                        let s = pressed.elapsed().as_secs_f64();
                        self.fit_to_screen = Some(s);
                        self.fit_pressed = None;
                        self.note(
                            format!("fit on screen {s:.2} s after Fit was pressed"),
                            false,
                        );
                    }
                    self.failed = None;
                    // A frame ends the adaptive method's table building and any render error.
                    let passing = ["adaptive shading", "render error"];
                    if passing.iter().any(|p| self.status.starts_with(p)) {
                        if let Some(info) = &self.info {
                            self.status = format!("{} on {}", info.name, info.adapter);
                        }
                    }
                    self.frame = Some(*f);
                    self.upload_frame();
                }
                Reply::FrameFailed {
                    camera,
                    size,
                    settings,
                    error,
                } => {
                    // Said in the view (the frame before it would not be what was asked for)
                    // and in the notes; a script goes on with its next command.
                    self.failed = Some((camera, size, settings));
                    self.frame = None;
                    let text = format!("render error: {error}");
                    // Once, not at every camera move (a scene the method cannot light).
                    if self.notes.last().is_none_or(|n| n.text != text) {
                        self.note(text.clone(), true);
                    }
                    self.status = text;
                }
                Reply::Picked(mesh) => {
                    self.pending_pick = false;
                    self.select(mesh);
                }
                Reply::MaterialSet {
                    material,
                    edit,
                    result,
                    seconds,
                } => {
                    self.pending_edits = self.pending_edits.saturating_sub(1);
                    if let Some(info) = &self.info {
                        self.status = format!("{} on {}", info.name, info.adapter);
                    }
                    match result {
                        Ok(m) => {
                            let name = m.name.clone();
                            if let Some((field, value)) = edit.split_once('=') {
                                self.edits.push((
                                    name.clone(),
                                    field.to_string(),
                                    value.to_string(),
                                ));
                                if field == "spec" && self.fit_pressed.is_some() {
                                    self.fit_applied = Some(value.to_string());
                                }
                            }
                            if let Some(info) = &mut self.info {
                                if let Some(slot) = info.materials.get_mut(material) {
                                    *slot = *m;
                                }
                            }
                            self.note(format!("{name}: {edit} (rebuilt in {seconds:.2} s)"), false);
                            // The rebuilt scene renders nothing until asked: ask again, and
                            // wait for that frame (not the one before the edit).
                            self.settings.generation += 1;
                            self.refresh_draft();
                        }
                        Err(e) => {
                            self.fit_pressed = None;
                            self.note(format!("{edit}: {e}"), true);
                            self.refresh_draft();
                        }
                    }
                }
                Reply::Fatal(e) => {
                    self.status = "stopped".into();
                    self.note(e.clone(), true);
                    self.fatal = Some(e);
                }
            }
        }
    }

    /// The frame as the egui texture, at the current exposure (or the adaptive method's buffer
    /// view as a heat map).
    fn upload_frame(&mut self) {
        let Some(f) = &self.frame else { return };
        let buffer = f
            .adaptive
            .as_ref()
            .and_then(|a| Some((a.width, a.height, a.rgb(self.buffer_view)?)));
        self.heat_range = buffer.as_ref().map(|b| b.2 .1);
        let img = match buffer {
            Some((w, h, (rgb, _))) => egui::ColorImage::from_rgb([w, h], &rgb),
            None => egui::ColorImage::from_rgb(
                [f.image.width, f.image.height],
                &f.image.to_srgb8(self.exposure),
            ),
        };
        let opts = if self.scale >= 1.0 {
            egui::TextureOptions::NEAREST
        } else {
            egui::TextureOptions::LINEAR
        };
        match &mut self.texture {
            Some(t) => t.set(img, opts),
            None => self.texture = Some(self.ctx.load_texture("view", img, opts)),
        }
    }

    fn select(&mut self, mesh: Option<usize>) {
        self.selected = mesh;
        self.refresh_draft();
        if let (Some(m), Some(info)) = (mesh, &self.info) {
            if let Some((name, mat)) = info.meshes.get(m) {
                let mname = info.materials.get(*mat).map_or("?", |x| x.name.as_str());
                let text = format!("selected {name:?} (material {mname:?})");
                self.note(text, false);
            }
        }
    }

    fn selected_material(&self) -> Option<usize> {
        let info = self.info.as_ref()?;
        info.meshes.get(self.selected?).map(|m| m.1)
    }

    fn refresh_draft(&mut self) {
        self.draft = self.selected_material().and_then(|m| {
            let mat = self.info.as_ref()?.materials.get(m)?;
            let spec = match &mat.kind {
                MaterialKind::Spec(s) => s.spec.clone(),
                _ => String::new(),
            };
            Some(Draft {
                material: m,
                fields: material_edit::fields(mat),
                spec,
            })
        });
    }

    /// Asks the render thread to set a parameter of the selected material.
    fn set_material(&mut self, field: &str, value: &str) {
        let Some(material) = self.selected_material() else {
            self.note("select an object first (click it)", true);
            return;
        };
        self.pending_edits += 1;
        let _ = self.to_render.send(Request::SetMaterial {
            material,
            field: field.to_string(),
            value: value.to_string(),
        });
    }

    /// Switches to method `m`, unless it is a walkthrough method and the scene is adaptive-only
    /// (said, and the method kept).
    fn choose_method(&mut self, m: ViewMethod) {
        match self.walkthrough_refusal(m) {
            Some(why) => {
                let text = format!("{} method refused: {why}", m.name());
                self.note(text.clone(), true);
                self.status = text;
            }
            None => self.settings.method = m,
        }
    }

    /// Why method `m` cannot show the scene: a walkthrough method on an adaptive-only scene.
    fn walkthrough_refusal(&self, m: ViewMethod) -> Option<String> {
        let why = self.info.as_ref()?.no_walkthrough.as_ref()?;
        m.walkthrough().then(|| why.clone())
    }

    /// Gives mesh `mesh` its own sample budget (`None`: the global one).
    fn set_object_samples(&mut self, mesh: usize, samples: Option<u32>) {
        if let Some(slot) = self
            .info
            .as_mut()
            .and_then(|i| i.object_samples.get_mut(mesh))
        {
            *slot = samples;
        }
        self.pending_edits += 1;
        let _ = self
            .to_render
            .send(Request::SetObjectSamples { mesh, samples });
    }

    fn pick(&mut self, pixel: (f64, f64)) {
        let Some((camera, size, _)) = self.sent else {
            return;
        };
        self.pending_pick = true;
        let _ = self.to_render.send(Request::Pick {
            camera,
            size,
            pixel,
        });
    }

    fn start_fit(&mut self, input: &str, model: &str) {
        if self.selected_material().is_none() {
            self.note("select the object to fit a material for first", true);
            return;
        }
        self.fit_pressed = Some(Instant::now());
        self.fit_to_screen = None;
        self.fit = Some(FitJob::start(input, model, &self.args.out.join("fits")));
    }

    fn poll_fit(&mut self) {
        let Some(job) = &mut self.fit else { return };
        let Some(r) = job.poll() else { return };
        let (input, model) = (job.input.clone(), job.model.clone());
        self.fit = None;
        match r {
            Ok(done) => {
                let json = done.json.display().to_string();
                self.note(
                    format!(
                        "fitted {input} ({model}) in {:.2} s: Ngan L2 ({:.4}, {:.4}, {:.4}) → {json}",
                        done.seconds, done.ngan_l2[0], done.ngan_l2[1], done.ngan_l2[2]
                    ),
                    false,
                );
                self.fit_done = Some(done);
                self.set_material("spec", &json);
            }
            Err(e) => {
                self.fit_pressed = None;
                self.note(format!("fit of {input} failed: {e}"), true);
            }
        }
    }

    fn set_camera_named(&mut self, name: &str) -> bool {
        let Some(info) = &self.info else { return false };
        let Some(c) = info.cameras.iter().find(|c| c.name == name) else {
            return false;
        };
        let (w, h) = self.view_size;
        let aspect = if h > 0 {
            w as f64 / h as f64
        } else {
            16.0 / 9.0
        };
        self.camera = Some(FlyCamera::from_camera(c, aspect));
        true
    }

    /// Sends a frame request when the camera, size or settings changed.
    fn request_frame(&mut self) {
        let Some(cam) = self.camera else { return };
        let (w, h) = self.view_size;
        if w == 0 || h == 0 || self.fatal.is_some() {
            return;
        }
        let Some(pc) = cam.path_camera(w as u32, h as u32) else {
            return;
        };
        let key = (pc, (w, h), self.settings);
        if self.sent != Some(key) {
            self.sent = Some(key);
            let _ = self.to_render.send(Request::Frame {
                camera: pc,
                size: (w, h),
                settings: self.settings,
            });
        }
        if let Some(r) = &mut self.recording {
            let t = r.started.elapsed().as_secs_f64();
            let c = cam.to_camera(&self.record_name);
            let moved = r
                .keyframes
                .last()
                .is_none_or(|k| k.camera.position != c.position || k.camera.forward != c.forward);
            if moved && r.keyframes.last().is_none_or(|k| t > k.time) {
                r.keyframes.push(Keyframe { time: t, camera: c });
            }
        }
    }

    /// True when the frame on screen is the one of the current request and every edit and
    /// pick has been answered.
    fn settled(&self) -> bool {
        let shown = self
            .frame
            .as_ref()
            .map(|f| (f.camera, (f.image.width, f.image.height), f.settings));
        self.pending_edits == 0
            && !self.pending_pick
            && self.fit.is_none()
            && self.sent.is_some()
            && (shown == self.sent || self.failed == self.sent)
    }

    /// Runs script commands until one has to wait.
    fn step_script(&mut self) {
        if self.info.is_none() || self.camera.is_none() {
            return;
        }
        loop {
            match self.wait {
                Some(Wait::Frames(n)) if n > 0 => {
                    self.wait = Some(Wait::Frames(n - 1));
                    return;
                }
                Some(Wait::Settle) if !self.settled() => return,
                Some(Wait::Screenshot) if self.screenshot.is_some() => return,
                _ => self.wait = None,
            }
            if self.script.front() == Some(&Command::Quit) {
                return;
            }
            let Some(cmd) = self.script.pop_front() else {
                return;
            };
            self.exec(cmd);
            if self.wait.is_some() {
                return;
            }
        }
    }

    fn exec(&mut self, cmd: Command) {
        let settle = Some(Wait::Settle);
        match cmd {
            Command::Wait(n) => self.wait = Some(Wait::Frames(n)),
            Command::Walk(d, secs) => {
                let m = match d {
                    Direction::Forward => Movement {
                        forward: 1.0,
                        ..Default::default()
                    },
                    Direction::Back => Movement {
                        forward: -1.0,
                        ..Default::default()
                    },
                    Direction::Right => Movement {
                        right: 1.0,
                        ..Default::default()
                    },
                    Direction::Left => Movement {
                        right: -1.0,
                        ..Default::default()
                    },
                    Direction::Up => Movement {
                        up: 1.0,
                        ..Default::default()
                    },
                    Direction::Down => Movement {
                        up: -1.0,
                        ..Default::default()
                    },
                };
                let speed = self.speed;
                if let Some(c) = &mut self.camera {
                    c.walk(m, speed, secs);
                }
                self.wait = settle;
            }
            Command::Look(dx, dy) => {
                if let Some(c) = &mut self.camera {
                    c.look(dx, dy, LOOK_RADIANS_PER_PIXEL);
                }
                self.wait = settle;
            }
            Command::Camera(name) => {
                if !self.set_camera_named(&name) {
                    self.note(format!("script: no camera named {name:?}"), true);
                }
                self.wait = settle;
            }
            Command::Select(x, y) => {
                self.pick((x, y));
                self.wait = settle;
            }
            Command::SelectMaterial(name) => {
                let mesh = self.info.as_ref().and_then(|i| {
                    i.meshes
                        .iter()
                        .position(|(_, m)| i.materials.get(*m).is_some_and(|x| x.name == name))
                });
                match mesh {
                    Some(m) => self.select(Some(m)),
                    None => self.note(format!("script: no object with material {name:?}"), true),
                }
            }
            Command::Set(field, value) => {
                self.set_material(&field, &value);
                self.wait = settle;
            }
            Command::Material(spec) => {
                self.set_material("spec", &spec);
                self.wait = settle;
            }
            Command::Method(m) => {
                self.choose_method(m);
                self.wait = settle;
            }
            Command::Samples(n) => {
                self.settings.samples = n;
                self.wait = settle;
            }
            Command::Buffer(v) => {
                self.buffer_view = v;
                self.upload_frame();
            }
            Command::Rate(r) => {
                self.settings.adaptive.rate = r;
                self.wait = settle;
            }
            Command::SampleRule(r) => {
                self.settings.adaptive.rule = r;
                self.wait = settle;
            }
            Command::Budget(n) => {
                match self.selected {
                    Some(mesh) => self.set_object_samples(mesh, n),
                    None => self.note("script: budget needs a selected object", true),
                }
                self.wait = settle;
            }
            Command::Exposure(e) => {
                self.exposure = e;
                self.upload_frame();
            }
            Command::Fit(file, model) => {
                self.start_fit(&file, &model);
                self.wait = settle;
            }
            Command::RecordStart => self.start_recording(),
            Command::RecordStop(file) => {
                self.record_name = Path::new(&file)
                    .file_stem()
                    .map_or("walk".into(), |s| s.to_string_lossy().into_owned());
                if let Some(r) = &mut self.recording {
                    r.file = file;
                }
                self.stop_recording();
            }
            Command::Screenshot(file) => {
                self.screenshot = Some(self.out_path(&file));
                self.wait = Some(Wait::Screenshot);
            }
            Command::SaveMaterial(file) => {
                self.save_material_path = file;
                self.save_material();
            }
            Command::SaveScene(file) => {
                self.save_scene_path = file;
                self.save_scene();
            }
            // Left at the front of the script for `check_end`.
            Command::Quit => {}
        }
    }

    /// Starts a recording at the current camera (its first keyframe, at 0 s).
    fn start_recording(&mut self) {
        let keyframes = self
            .camera
            .map(|c| Keyframe {
                time: 0.0,
                camera: c.to_camera(&self.record_name),
            })
            .into_iter()
            .collect();
        self.recording = Some(Recording {
            started: Instant::now(),
            keyframes,
            file: format!("{}.json", self.record_name),
        });
    }

    fn stop_recording(&mut self) {
        let Some(mut r) = self.recording.take() else {
            return;
        };
        // The camera where the recording stops is its last keyframe (a script's instant walk
        // ends between two frames).
        if let Some(c) = self.camera {
            let c = c.to_camera(&self.record_name);
            let t = r.started.elapsed().as_secs_f64();
            let moved = r
                .keyframes
                .last()
                .is_none_or(|k| k.camera.position != c.position || k.camera.forward != c.forward);
            if moved {
                let t = r.keyframes.last().map_or(t, |k| t.max(k.time + 1e-3));
                r.keyframes.push(Keyframe { time: t, camera: c });
            }
        }
        let path = CameraPath {
            name: self.record_name.clone(),
            keyframes: r.keyframes,
            looped: false,
        };
        let file = self.out_path(&r.file);
        match CameraPathFile::write(&file, &path) {
            Ok(()) => self.note(
                format!(
                    "camera path of {} keyframes, {:.1} s → {} (lustre render --path {})",
                    path.keyframes.len(),
                    path.duration(),
                    file.display(),
                    file.display()
                ),
                false,
            ),
            Err(e) => self.note(e.to_string(), true),
        }
    }

    fn save_material(&mut self) {
        let file = self.out_path(&self.save_material_path);
        let Some(m) = self
            .selected_material()
            .and_then(|m| self.info.as_ref()?.materials.get(m).cloned())
        else {
            self.note("select an object first", true);
            return;
        };
        let r = match &m.kind {
            // An unedited material JSON is copied with its fit record.
            MaterialKind::Spec(s)
                if s.edits.is_empty() && s.spec.to_ascii_lowercase().ends_with(".json") =>
            {
                lustre_brdf::material::read(Path::new(&s.spec))
                    .and_then(|f| lustre_brdf::material::write(&file, &f))
                    .map_err(|e| e.to_string())
            }
            // Anything else fitted (a catalog fit, an edited model) is written from its
            // parameters; an edited model has no fit record.
            MaterialKind::Spec(s) => {
                lustre_brdf::material::MaterialModel::from_bsdf(s.bsdf.as_ref())
                    .and_then(|model| {
                        lustre_brdf::material::MaterialFile::new(m.name.clone(), model, None)
                    })
                    .and_then(|f| lustre_brdf::material::write(&file, &f))
                    .map_err(|e| format!("{:?} ({}): {e}; save the scene to keep it", m.name, s.spec))
            }
            k => Err(format!(
                "{:?} is a {} material, not a fitted model: its parameters are saved with the scene",
                m.name,
                k.name()
            )),
        };
        match r {
            Ok(()) => self.note(format!("material {:?} → {}", m.name, file.display()), false),
            Err(e) => self.note(e, true),
        }
    }

    fn save_scene(&mut self) {
        let file = self.out_path(&self.save_scene_path);
        let r = match &self.source {
            SceneSource::BuiltinRoom(_) => Err(
                "the built-in room has no scene file: save the material JSON or the camera path; \
                 `lustre render --set MATERIAL.PARAMETER=VALUE` replays the edits"
                    .to_string(),
            ),
            SceneSource::Unbaked(scene) => Err(format!(
                "{} has no scene file: save the material JSON or the camera path; `lustre render \
                 --method adaptive --set MATERIAL.PARAMETER=VALUE` replays the edits",
                scene.source.display()
            )),
            SceneSource::File(src) => {
                let current = self.info.as_ref().map_or(&[][..], |i| &i.materials[..]);
                edited_scene_file(src, &self.edits, current).and_then(|f| {
                    lustre_scene::scene_file::write(&file, &f).map_err(|e| e.to_string())
                })
            }
        };
        match r {
            Ok(()) => self.note(format!("scene → {}", file.display()), false),
            Err(e) => self.note(e, true),
        }
    }

    /// The panels and the 3D view.
    fn ui(&mut self, ui: &mut egui::Ui, dt: f64) {
        egui::Panel::top("top").show(ui, |ui| {
            ui.horizontal(|ui| {
                ui.strong("lustre view");
                ui.label(&self.status);
                if let Some(f) = &self.fatal {
                    ui.colored_label(egui::Color32::RED, f);
                }
            });
        });
        // Panels of a fixed width (long lines wrap), the rest is the 3D view.
        egui::Panel::left("view")
            .resizable(false)
            .exact_size(LEFT_PANEL)
            .show(ui, |ui| {
                egui::ScrollArea::vertical()
                    .auto_shrink([false; 2])
                    .show(ui, |ui| self.view_panel(ui));
            });
        egui::Panel::right("material")
            .resizable(false)
            .exact_size(RIGHT_PANEL)
            .show(ui, |ui| {
                egui::ScrollArea::vertical()
                    .auto_shrink([false; 2])
                    .show(ui, |ui| self.material_panel(ui));
            });
        egui::CentralPanel::default().show(ui, |ui| self.central(ui, dt));
    }

    fn view_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("View");
        let ui_fps = if self.ui_times.is_empty() {
            0.0
        } else {
            1e3 * self.ui_times.len() as f64 / self.ui_times.iter().sum::<f64>().max(1e-9)
        };
        let view_fps = if self.frame_times.is_empty() {
            0.0
        } else {
            1e3 * self.frame_times.len() as f64
                / self.frame_times.iter().map(|f| f.0).sum::<f64>().max(1e-9)
        };
        ui.label(format!(
            "window {ui_fps:.1} fps · 3D {view_fps:.2} frames/s"
        ));
        if let Some(a) = self.frame.as_ref().and_then(|f| f.adaptive.as_deref()) {
            // The adaptive method's line: what it shaded and what it cost.
            ui.label(format!(
                "adaptive: {:.1} % of {} surface px shaded · {} samples ({:.2}/px) · bandwidth pass {:.0} ms · shading {:.0} ms · G-buffer {:.0} ms",
                100.0 * a.shaded_share(),
                a.surface_pixels,
                a.samples_total,
                a.samples_total as f64 / a.surface_pixels.max(1) as f64,
                a.bandwidth_ms,
                a.shading_ms,
                a.gbuffer_ms,
            ));
            let place = |gpu: bool| if gpu { "GPU" } else { "CPU" };
            ui.small(format!(
                "bandwidth pass on the {}, shading on the {} · material tables {:.2} s (once per scene and material edit)",
                place(a.on_gpu.0),
                place(a.on_gpu.1),
                a.tables_ms * 1e-3
            ));
            if let Some(why) = &a.why_cpu {
                ui.small(format!("CPU because: {why}"));
            }
        }
        if let Some(f) = &self.frame {
            let t = &f.times;
            ui.label(format!(
                "{}×{} · {} · {} frame(s) · step {:.1} ms",
                f.image.width,
                f.image.height,
                f.settings.method.name(),
                f.frames,
                f.wall_ms
            ));
            if f.work.is_some() {
                let clock = if t.timestamps { "GPU" } else { "wall" };
                ui.label(format!(
                    "passes ({clock} ms): views {:.1} (layers {:.1}) · G-buffer {:.1} · light map {:.1} · glossy {:.1}",
                    t.views_ms, t.layers_ms, t.gbuffer_ms, t.lightmap_ms, t.shade_ms
                ));
                let hits = f.stats.glossy_hits.max(1);
                ui.label(format!(
                    "budget {} lookups/pixel · made {:.2} per glossy hit",
                    f.settings.samples,
                    f.stats.lookups as f64 / hits as f64
                ));
            }
        }
        frame_graph(ui, &self.frame_times);
        ui.separator();
        ui.label("Method");
        for m in [
            ViewMethod::Regular,
            ViewMethod::Ck,
            ViewMethod::Progressive,
            ViewMethod::Reference,
            ViewMethod::Adaptive,
        ] {
            let text = match m {
                ViewMethod::Regular => "regular sampling",
                ViewMethod::Ck => "Colbert–Křivánek",
                ViewMethod::Progressive => "progressive when still",
                ViewMethod::Reference => "path-traced reference (CPU)",
                ViewMethod::Adaptive => "adaptive shading (004 ch. IV)",
            };
            let refused = self.walkthrough_refusal(m);
            let radio = egui::RadioButton::new(self.settings.method == m, text);
            let clicked = match refused {
                Some(why) => ui.add_enabled(false, radio).on_disabled_hover_text(why),
                None => ui.add(radio),
            }
            .clicked();
            if clicked {
                self.choose_method(m);
            }
        }
        if self.settings.method == ViewMethod::Adaptive {
            self.adaptive_panel(ui);
        } else {
            ui.add(egui::Slider::new(&mut self.settings.samples, 1..=64).text("samples (global)"));
        }
        ui.add(egui::Slider::new(&mut self.settings.supersampling, 1..=4).text("k×k G-buffer"));
        ui.add(
            egui::Slider::new(&mut self.settings.refine_frames, 1..=1024)
                .logarithmic(true)
                .text("refine to"),
        );
        ui.add(egui::Slider::new(&mut self.scale, 0.1..=1.0).text("resolution"));
        if ui
            .add(
                egui::Slider::new(&mut self.exposure, 0.05..=20.0)
                    .logarithmic(true)
                    .text("exposure"),
            )
            .changed()
        {
            self.upload_frame();
        }
        if ui.checkbox(&mut self.vsync, "vsync").changed() {
            if let Some(g) = &mut self.gfx {
                configure(g, self.vsync);
            }
        }
        ui.separator();
        ui.label("Walk: WASD / arrows, Q/E down/up, drag to look, wheel: speed, shift: run");
        ui.add(
            egui::Slider::new(&mut self.speed, 0.01..=100.0)
                .logarithmic(true)
                .text("speed (units/s)"),
        );
        let names: Vec<String> = self
            .info
            .as_ref()
            .map(|i| i.cameras.iter().map(|c| c.name.clone()).collect())
            .unwrap_or_default();
        if !names.is_empty() {
            ui.label("Cameras");
            ui.horizontal_wrapped(|ui| {
                for n in names {
                    if ui.button(&n).clicked() {
                        self.set_camera_named(&n);
                    }
                }
            });
        }
        ui.horizontal(|ui| {
            ui.label("path");
            ui.add(egui::TextEdit::singleline(&mut self.record_name).desired_width(120.0));
        });
        if self.recording.is_some() {
            if ui.button("⏹ stop recording").clicked() {
                if let Some(r) = &mut self.recording {
                    r.file = format!("{}.json", self.record_name);
                }
                self.stop_recording();
            }
        } else if ui.button("⏺ record camera path").clicked() {
            self.start_recording();
        }
        if ui.button("screenshot (F12)").clicked() {
            self.screenshots += 1;
            self.screenshot =
                Some(self.out_path(&format!("screenshot-{:03}.png", self.screenshots)));
        }
    }

    /// The adaptive method's controls: mean N_p, rate, sample rule, the buffer shown.
    fn adaptive_panel(&mut self, ui: &mut egui::Ui) {
        ui.add(
            egui::Slider::new(&mut self.settings.samples, 1..=256)
                .logarithmic(true)
                .text("mean N_p"),
        );
        let a = &mut self.settings.adaptive;
        ui.horizontal(|ui| {
            ui.label("rate");
            ui.radio_value(&mut a.rate, 2, "2")
                .on_hover_text("image samples per cycle of b_p: Nyquist's rate");
            ui.radio_value(&mut a.rate, 1, "1")
                .on_hover_text("Eq. IV.11 as printed: fewer pixels shaded");
        });
        egui::ComboBox::from_label("N_p rule")
            .selected_text(rule_name(a.rule))
            .show_ui(ui, |ui| {
                for r in SAMPLE_RULES {
                    ui.selectable_value(&mut a.rule, r, rule_name(r));
                }
            });
        ui.label("show");
        let before = self.buffer_view;
        for v in BufferView::ALL {
            ui.radio_value(&mut self.buffer_view, v, v.label());
        }
        if self.buffer_view != before {
            self.upload_frame();
        }
        if let Some((lo, hi)) = self.heat_range {
            ui.small(format!(
                "log heat map {lo:.3} … {hi:.3} (1st–99.9th percentile; black: 0)"
            ));
        }
    }

    fn material_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Material");
        let Some(info) = &self.info else {
            ui.label("loading…");
            return;
        };
        let sel = self.selected.and_then(|m| info.meshes.get(m).cloned());
        let Some((mesh_name, _)) = sel else {
            ui.label("click an object to select it");
            self.notes_ui(ui);
            return;
        };
        ui.label(format!("object {mesh_name:?}"));
        // The object's own sample budget (else the global one).
        let mesh = self.selected.unwrap_or(0);
        let own = info.object_samples.get(mesh).copied().flatten();
        let mut on = own.is_some();
        let mut n = own.unwrap_or(self.settings.samples);
        let mut budget = None;
        let c = ui.checkbox(&mut on, "its own sample budget");
        let r = ui.add_enabled(on, egui::Slider::new(&mut n, 1..=64));
        if c.changed() || r.drag_stopped() || (r.changed() && !r.dragged()) {
            budget = Some(on.then_some(n));
        }
        let mut commits: Vec<(String, String)> = vec![];
        if let Some(d) = &mut self.draft {
            let mat = &info.materials[d.material];
            ui.label(format!("material {:?} ({})", mat.name, mat.kind.name()));
            // Grouped names (`model.reflection[0].mx`) get a group line and their last part
            // as the label, so that rows stay within the panel.
            let mut group = String::new();
            for f in &mut d.fields {
                let g = f.name.rsplit_once('.').map_or("", |(g, _)| g).to_string();
                if g != group && !g.is_empty() && g != "spec" {
                    ui.small(&g);
                }
                group = g;
                if let Some(v) = field_ui(ui, f) {
                    commits.push((f.name.clone(), v));
                }
            }
            ui.separator();
            ui.label("swap for a specification (catalog, material JSON, measured file)");
            ui.add(egui::TextEdit::singleline(&mut d.spec).desired_width(f32::INFINITY));
            ui.horizontal(|ui| {
                ui.label("catalog");
                ui.add(egui::TextEdit::singleline(&mut self.catalog_filter).desired_width(120.0));
            });
            let filter = self.catalog_filter.to_ascii_lowercase();
            egui::ComboBox::from_id_salt("catalog")
                .selected_text("pick…")
                .show_ui(ui, |ui| {
                    for name in self
                        .catalog
                        .iter()
                        .filter(|n| n.to_ascii_lowercase().contains(&filter))
                        .take(200)
                    {
                        if ui.selectable_label(false, name).clicked() {
                            d.spec = name.clone();
                        }
                    }
                });
            if ui.button("apply").clicked() && !d.spec.trim().is_empty() {
                commits.push(("spec".into(), d.spec.trim().to_string()));
            }
        }
        for (f, v) in commits {
            self.set_material(&f, &v);
        }
        if let Some(samples) = budget {
            self.set_object_samples(mesh, samples);
        }
        ui.separator();
        ui.label("Fit a measured file (MERL .binary, RGL .bsdf, nbrdf:NAME, data:…)");
        ui.add(egui::TextEdit::singleline(&mut self.fit_input).desired_width(f32::INFINITY));
        ui.horizontal(|ui| {
            for m in ["sgd", "kurt", "beckmann", "ggx"] {
                ui.radio_value(&mut self.fit_model, m.to_string(), m);
            }
        });
        if let Some(job) = &self.fit {
            ui.add(egui::ProgressBar::new(0.0).animate(true).text(format!(
                "{} · {:.1} s",
                job.stage,
                job.started.elapsed().as_secs_f64()
            )));
        } else if ui.button("Fit").clicked() && !self.fit_input.trim().is_empty() {
            let (i, m) = (self.fit_input.trim().to_string(), self.fit_model.clone());
            self.start_fit(&i, &m);
        }
        if let Some(s) = self.fit_to_screen {
            ui.label(format!("last fit on screen {s:.2} s after pressing Fit"));
        }
        if let Some(done) = &self.fit_done {
            lobe_plot(ui, done);
        }
        ui.separator();
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_material_path).desired_width(120.0));
            if ui.button("save material JSON").clicked() {
                self.save_material();
            }
        });
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_scene_path).desired_width(120.0));
            if ui.button("save scene").clicked() {
                self.save_scene();
            }
        });
        self.notes_ui(ui);
    }

    fn notes_ui(&self, ui: &mut egui::Ui) {
        ui.separator();
        for n in self.notes.iter().rev() {
            if n.error {
                ui.colored_label(egui::Color32::from_rgb(255, 110, 110), &n.text);
            } else {
                ui.label(&n.text);
            }
        }
    }

    fn central(&mut self, ui: &mut egui::Ui, dt: f64) {
        let ppp = ui.ctx().pixels_per_point();
        let avail = ui.available_size();
        let (rect, resp) = ui.allocate_exact_size(avail, egui::Sense::click_and_drag());
        let w = ((f64::from(avail.x * ppp)) * self.scale).floor().max(16.0) as usize;
        let h = ((f64::from(avail.y * ppp)) * self.scale).floor().max(16.0) as usize;
        self.view_size = (w, h);
        // The image on whole pixels from the panel's corner.
        let min_px = (rect.min.to_vec2() * ppp).round();
        let min = egui::pos2(min_px.x / ppp, min_px.y / ppp);
        if let (Some(t), Some(f)) = (&self.texture, &self.frame) {
            let size_px =
                egui::vec2(f.image.width as f32, f.image.height as f32) / self.scale as f32;
            let r = egui::Rect::from_min_size(min, size_px / ppp);
            ui.painter().with_clip_rect(rect).image(
                t.id(),
                r,
                egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                egui::Color32::WHITE,
            );
            self.view_rect_px = [min_px.x, min_px.y, size_px.x, size_px.y];
        } else {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                &self.status,
                egui::FontId::proportional(16.0),
                egui::Color32::GRAY,
            );
        }
        if resp.clicked() {
            if let Some(p) = resp.interact_pointer_pos() {
                let px = (p - min) * ppp * self.scale as f32;
                self.pick((f64::from(px.x), f64::from(px.y)));
            }
        }
        if resp.dragged() {
            let d = resp.drag_delta() * ppp;
            if let Some(c) = &mut self.camera {
                c.look(f64::from(d.x), f64::from(d.y), LOOK_RADIANS_PER_PIXEL);
            }
        }
        let ctx = ui.ctx().clone();
        if resp.hovered() {
            let scroll = ctx.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.speed =
                    (self.speed * 1.2f64.powf(f64::from(scroll) / 50.0)).clamp(0.01, 100.0);
            }
        }
        if !ctx.egui_wants_keyboard_input() {
            let (m, run, shot) = ctx.input(|i| {
                let k = |a: egui::Key, b: egui::Key| {
                    if i.key_down(a) || i.key_down(b) {
                        1.0
                    } else {
                        0.0
                    }
                };
                (
                    Movement {
                        forward: k(egui::Key::W, egui::Key::ArrowUp)
                            - k(egui::Key::S, egui::Key::ArrowDown),
                        right: k(egui::Key::D, egui::Key::ArrowRight)
                            - k(egui::Key::A, egui::Key::ArrowLeft),
                        up: k(egui::Key::E, egui::Key::E) - k(egui::Key::Q, egui::Key::Q),
                    },
                    i.modifiers.shift,
                    i.key_pressed(egui::Key::F12),
                )
            });
            let speed = self.speed * if run { 4.0 } else { 1.0 };
            if let Some(c) = &mut self.camera {
                c.walk(m, speed, dt.min(0.25));
            }
            if shot {
                self.screenshots += 1;
                self.screenshot =
                    Some(self.out_path(&format!("screenshot-{:03}.png", self.screenshots)));
            }
        }
    }

    /// Draws one window frame; `false` when the run must end.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        self.poll_replies();
        self.poll_fit();
        let now = Instant::now();
        let dt = (now - self.last_tick).as_secs_f64();
        self.last_tick = now;
        self.ui_times.push_back(dt * 1e3);
        if self.ui_times.len() > HISTORY {
            self.ui_times.pop_front();
        }
        let Some(mut gfx) = self.gfx.take() else {
            return;
        };
        if gfx.lost.load(Ordering::SeqCst) {
            self.finish(event_loop, Err("the window's GPU device was lost".into()));
            return;
        }
        let raw = gfx.state.take_egui_input(&gfx.window);
        let ctx = self.ctx.clone();
        let out = ctx.run_ui(raw, |ui| self.ui(ui, dt));
        gfx.state
            .handle_platform_output(&gfx.window, out.platform_output);
        let jobs = ctx.tessellate(out.shapes, out.pixels_per_point);
        let shot = if self.settled() || !self.unattended {
            self.screenshot.take()
        } else {
            None
        };
        let r = paint(
            &mut gfx,
            &jobs,
            out.textures_delta,
            out.pixels_per_point,
            shot.is_some(),
        );
        self.gfx = Some(gfx);
        match r {
            Ok(Some(pixels)) => {
                if let Some(path) = shot {
                    self.write_screenshot(&path, pixels);
                }
            }
            Ok(None) => {
                if let Some(path) = shot {
                    // Not drawn this time (surface outdated): try again next frame.
                    self.screenshot = Some(path);
                }
            }
            Err(e) => {
                self.finish(event_loop, Err(e));
                return;
            }
        }
        if self.frame.is_some() {
            self.frames_shown += 1;
        }
        self.request_frame();
        self.step_script();
        self.check_end(event_loop);
    }

    /// Ends unattended runs: a fatal error, the script's quit, --frames reached, the timeout.
    fn check_end(&mut self, event_loop: &ActiveEventLoop) {
        if !self.unattended {
            return;
        }
        if let Some(e) = &self.fatal {
            let e = e.clone();
            self.finish(event_loop, Err(e));
            return;
        }
        if self.started.elapsed() > Duration::from_secs_f64(self.args.timeout) {
            let msg = format!(
                "timed out after {:.0} s ({} command(s) left, status: {})",
                self.args.timeout,
                self.script.len(),
                self.status
            );
            self.finish(event_loop, Err(msg));
            return;
        }
        if self.screenshot.is_some() || self.wait.is_some() {
            return;
        }
        if self.script.front() == Some(&Command::Quit) {
            self.finish(event_loop, Ok(()));
            return;
        }
        if !self.script.is_empty() {
            return;
        }
        if let Some(n) = self.args.frames {
            if self.frames_shown >= n && self.settled() {
                if let (Some(p), false) = (&self.args.screenshot, self.quit_after_screenshot) {
                    self.screenshot = Some(p.clone());
                    self.quit_after_screenshot = true;
                    return;
                }
                self.finish(event_loop, Ok(()));
            }
        }
    }

    /// Writes the window's pixels as PNG and, beside it, what the 3D view shows (JSON) and its
    /// camera as a camera path file.
    fn write_screenshot(&mut self, path: &Path, (w, h, rgba): (u32, u32, Vec<u8>)) {
        let r = (|| -> anyhow::Result<()> {
            if let Some(d) = path.parent() {
                std::fs::create_dir_all(d)?;
            }
            let img = image::RgbaImage::from_raw(w, h, rgba)
                .ok_or_else(|| anyhow!("screenshot buffer of the wrong size"))?;
            let mut png = std::io::Cursor::new(vec![]);
            image::DynamicImage::ImageRgba8(img).write_to(&mut png, image::ImageFormat::Png)?;
            lustre_brdf::error::write_atomic(path, png.get_ref())?;
            let cam_file = path.with_extension("camera.json");
            if let Some(c) = self.camera {
                CameraPathFile::write(
                    &cam_file,
                    &CameraPath {
                        name: "screenshot".into(),
                        keyframes: vec![Keyframe {
                            time: 0.0,
                            camera: c.to_camera("screenshot"),
                        }],
                        looped: false,
                    },
                )?;
            }
            let set: Vec<String> = self
                .edits
                .iter()
                .map(|(m, f, v)| format!("{m}.{f}={v}"))
                .collect();
            let f = self.frame.as_ref();
            let selected = self.selected.and_then(|m| {
                let info = self.info.as_ref()?;
                let (name, mat) = info.meshes.get(m)?;
                Some(serde_json::json!({
                    "mesh": name,
                    "material": info.materials.get(*mat).map(|x| x.name.clone()),
                }))
            });
            let side = serde_json::json!({
                "window": [w, h],
                "view": {
                    "rect": self.view_rect_px,
                    "size": f.map(|f| [f.image.width, f.image.height]),
                    "scale": self.scale,
                },
                "camera": cam_file.file_name().map(|n| n.to_string_lossy().into_owned()),
                "method": self.settings.method.name(),
                "adaptive": (self.settings.method == ViewMethod::Adaptive).then(|| {
                    let a = f.and_then(|f| f.adaptive.as_deref());
                    serde_json::json!({
                        "buffer": self.buffer_view.name(),
                        "rate": self.settings.adaptive.rate,
                        "sample_rule": rule_name(self.settings.adaptive.rule),
                        "heat_range": self.heat_range.map(|(lo, hi)| [lo, hi]),
                        "surface_pixels": a.map(|a| a.surface_pixels),
                        "shaded_pixels": a.map(|a| a.shaded_pixels),
                        "upsampled_pixels": a.map(|a| a.upsampled_pixels),
                        "samples": a.map(|a| a.samples_total),
                        "gbuffer_ms": a.map(|a| a.gbuffer_ms),
                        "bandwidth_ms": a.map(|a| a.bandwidth_ms),
                        "shading_ms": a.map(|a| a.shading_ms),
                        "tables_ms": a.map(|a| a.tables_ms),
                        "bandwidth_on_gpu": a.map(|a| a.on_gpu.0),
                        "shading_on_gpu": a.map(|a| a.on_gpu.1),
                        "why_cpu": a.and_then(|a| a.why_cpu.clone()),
                    })
                }),
                "samples": self.settings.samples,
                "supersampling": self.settings.supersampling,
                "exposure": self.exposure,
                "frames": f.map(|f| f.frames),
                "set": set,
                "object_samples": self.info.as_ref().map(|i| {
                    i.meshes
                        .iter()
                        .zip(&i.object_samples)
                        .filter_map(|((name, _), n)| n.map(|n| (name.clone(), n)))
                        .collect::<std::collections::BTreeMap<String, u32>>()
                }),
                "selected": selected,
                "scene": self.info.as_ref().map(|i| i.name.clone()),
                "adapter": self.info.as_ref().map(|i| i.adapter.clone()),
                "step_ms": f.map(|f| f.wall_ms),
                "pass_ms": f.map(|f| serde_json::json!({
                    "views": f.times.views_ms, "layers": f.times.layers_ms,
                    "gbuffer": f.times.gbuffer_ms, "lightmap": f.times.lightmap_ms,
                    "shade": f.times.shade_ms, "gpu_timestamps": f.times.timestamps,
                })),
                "window_frame_ms": self.ui_times.back(),
                "fit_to_screen_s": self.fit_to_screen,
            });
            lustre_brdf::error::write_atomic(
                &path.with_extension("json"),
                serde_json::to_string_pretty(&side)?.as_bytes(),
            )?;
            Ok(())
        })();
        match r {
            Ok(()) => self.note(format!("screenshot → {}", path.display()), false),
            Err(e) => self.note(format!("screenshot {}: {e:#}", path.display()), true),
        }
    }
}

/// The scene file `src` with the edits: `spec` swaps as material overrides (dropping earlier
/// parameter edits of that material), the rest as `[material_params]`; paths made absolute.
/// Where a fitted model's distribution, α or p was edited, all three are written with their
/// values in `current` (the materials as edited), so that the file rebuilds the same
/// distribution whatever the order of the edits.
fn edited_scene_file(
    src: &Path,
    edits: &[(String, String, String)],
    current: &[Material],
) -> Result<lustre_scene::scene_file::SceneFile, String> {
    let text = std::fs::read_to_string(src).map_err(|e| format!("{}: {e}", src.display()))?;
    let base = src.parent().unwrap_or(Path::new("."));
    let mut f = lustre_scene::scene_file::parse(src, &text)
        .map_err(|e| e.to_string())?
        .with_absolute_paths(base);
    for (m, field, value) in edits {
        if field == "spec" {
            f.materials.insert(m.clone(), value.clone());
            let prefix = format!("{m}.");
            f.material_params.retain(|k, _| !k.starts_with(&prefix));
        } else {
            f.material_params
                .insert(format!("{m}.{field}"), value.clone());
        }
    }
    const SHAPE: [&str; 3] = ["model.distribution", "model.alpha", "model.p"];
    for m in current {
        let prefix = format!("{}.", m.name);
        let reshaped = SHAPE
            .iter()
            .any(|k| f.material_params.contains_key(&format!("{prefix}{k}")));
        if reshaped {
            for k in SHAPE {
                f.material_params.remove(&format!("{prefix}{k}"));
            }
            for field in material_edit::fields(m) {
                if SHAPE.contains(&field.name.as_str()) {
                    f.material_params
                        .insert(format!("{prefix}{}", field.name), field.value.to_text());
                }
            }
        }
    }
    Ok(f)
}

/// Sets the present mode (vsync: FIFO; otherwise immediate or mailbox where offered) and
/// configures the surface.
fn configure(g: &mut Gfx, vsync: bool) {
    g.config.present_mode = if vsync {
        wgpu::PresentMode::Fifo
    } else {
        [wgpu::PresentMode::Immediate, wgpu::PresentMode::Mailbox]
            .into_iter()
            .find(|m| g.present_modes.contains(m))
            .unwrap_or(wgpu::PresentMode::Fifo)
    };
    g.surface.configure(&g.device, &g.config);
}

/// A parameter's control; returns the value to set when the user committed a change (a
/// slider let go, a box edited, a choice made).
fn field_ui(ui: &mut egui::Ui, f: &mut Field) -> Option<String> {
    let mut commit = false;
    let (lo, hi) = f.range;
    let bounded = hi - lo <= 1e6;
    let label = match f.name.rsplit_once('.') {
        Some((g, last)) if g != "spec" => last,
        _ => f.name.as_str(),
    };
    ui.horizontal_wrapped(|ui| {
        ui.label(label);
        match &mut f.value {
            FieldValue::Scalar(v) => {
                let r = if bounded {
                    ui.add(egui::Slider::new(v, lo..=hi).logarithmic(f.log))
                } else {
                    let speed = (v.abs() * 0.01).max(1e-3);
                    ui.add(egui::DragValue::new(v).speed(speed))
                };
                commit = r.drag_stopped() || (r.changed() && !r.dragged());
            }
            FieldValue::Rgb(c) => {
                // A step of 1% of the value (a fitted weight may be 1e-3 in a range of 10).
                let scale = c.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                let speed = ((hi - lo) * 0.002).min((scale * 0.01).max(1e-3)).max(1e-4);
                for x in c.iter_mut() {
                    let r = ui.add(
                        egui::DragValue::new(x)
                            .range(lo..=hi)
                            .speed(speed)
                            .max_decimals(4),
                    );
                    commit |= r.drag_stopped() || (r.changed() && !r.dragged());
                }
                let shown = |x: f64| (lustre_trace::image::display_value(x, 1.0) * 255.0) as u8;
                let (rect, _) =
                    ui.allocate_exact_size(egui::vec2(14.0, 14.0), egui::Sense::hover());
                ui.painter().rect_filled(
                    rect,
                    2.0,
                    egui::Color32::from_rgb(shown(c[0]), shown(c[1]), shown(c[2])),
                );
            }
            FieldValue::Choice(s) => {
                let before = s.clone();
                egui::ComboBox::from_id_salt(&f.name)
                    .selected_text(s.clone())
                    .show_ui(ui, |ui| {
                        for c in f.choices {
                            ui.selectable_value(s, c.to_string(), *c);
                        }
                    });
                commit = *s != before;
            }
            FieldValue::Flag(b) => commit = ui.checkbox(b, "").changed(),
            FieldValue::Text(t) => {
                ui.label(t.as_str());
            }
        }
        if f.textured {
            ui.label("× texture");
        }
    });
    if commit && !matches!(f.value, FieldValue::Text(_)) {
        Some(f.value.to_text())
    } else {
        None
    }
}

/// The frame-time graph: the time between 3D frames and the GPU's per-pass times, stacked.
fn frame_graph(ui: &mut egui::Ui, times: &VecDeque<(f64, lustre_gpu::GpuFrameTimes)>) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(220.0, 70.0), egui::Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, egui::Color32::from_gray(24));
    let max = times.iter().map(|t| t.0).fold(1.0, f64::max);
    let n = HISTORY as f32;
    let y = |ms: f64| rect.bottom() - (ms / max) as f32 * rect.height();
    let colours = [
        egui::Color32::from_rgb(90, 160, 255),
        egui::Color32::from_rgb(120, 220, 120),
        egui::Color32::from_rgb(250, 200, 80),
        egui::Color32::from_rgb(240, 110, 90),
    ];
    for (i, (wall, t)) in times.iter().enumerate() {
        let x = rect.left() + (i as f32 + 0.5) * rect.width() / n;
        let mut acc = 0.0;
        for (k, ms) in [t.views_ms, t.gbuffer_ms, t.lightmap_ms, t.shade_ms]
            .into_iter()
            .enumerate()
        {
            p.line_segment(
                [egui::pos2(x, y(acc)), egui::pos2(x, y(acc + ms))],
                egui::Stroke::new(rect.width() / n, colours[k]),
            );
            acc += ms;
        }
        p.circle_filled(egui::pos2(x, y(*wall)), 1.2, egui::Color32::WHITE);
    }
    p.text(
        rect.left_top() + egui::vec2(3.0, 2.0),
        egui::Align2::LEFT_TOP,
        format!("{max:.0} ms · views, G-buffer, light map, glossy; • frame"),
        egui::FontId::proportional(10.0),
        egui::Color32::LIGHT_GRAY,
    );
}

/// The polar lobe plot of the last fit: measurement (white) and fit (orange) at each θi.
fn lobe_plot(ui: &mut egui::Ui, done: &FitDone) {
    ui.label(format!(
        "lobes in the plane of incidence (cube-root radius), θi = {}°, {}°: measured white, fit orange",
        PLOT_THETA_I[0], PLOT_THETA_I[1]
    ));
    let (rect, _) = ui.allocate_exact_size(egui::vec2(280.0, 150.0), egui::Sense::hover());
    let p = ui.painter();
    p.rect_filled(rect, 2.0, egui::Color32::from_gray(20));
    let origin = egui::pos2(rect.center().x, rect.bottom() - 4.0);
    let radius = (rect.height() - 8.0).min(rect.width() / 2.0 - 4.0);
    p.circle_stroke(
        origin,
        radius,
        egui::Stroke::new(0.5, egui::Color32::from_gray(70)),
    );
    let max = done
        .measured
        .iter()
        .chain(&done.fitted)
        .flat_map(|s| s.values.iter().copied())
        .fold(1e-12, f64::max);
    let to_screen = |q: [f64; 2]| {
        egui::pos2(
            origin.x + q[0] as f32 * radius,
            origin.y - q[1] as f32 * radius,
        )
    };
    for (slices, colour) in [
        (&done.measured, egui::Color32::WHITE),
        (&done.fitted, egui::Color32::from_rgb(255, 150, 40)),
    ] {
        for s in slices {
            let pts: Vec<egui::Pos2> = polar_points(s, max).into_iter().map(to_screen).collect();
            p.add(egui::Shape::line(pts, egui::Stroke::new(1.2, colour)));
        }
    }
}

/// Draws egui into the surface (and, for a screenshot, into a texture read back as RGBA8).
/// `Ok(None)`: the surface was not ready (timeout, occluded, outdated: reconfigured).
#[allow(clippy::type_complexity)]
fn paint(
    g: &mut Gfx,
    jobs: &[egui::ClippedPrimitive],
    mut delta: egui::TexturesDelta,
    ppp: f32,
    capture: bool,
) -> Result<Option<(u32, u32, Vec<u8>)>, String> {
    // Textures are updated whether or not the surface draws this time; freed after painting.
    for (id, ds) in delta.set.drain() {
        for d in &ds {
            g.renderer.update_texture(&g.device, &g.queue, id, d);
        }
    }
    let free: Vec<egui::TextureId> = delta.free.drain().collect();
    let r = paint_surface(g, jobs, ppp, capture);
    for id in &free {
        g.renderer.free_texture(id);
    }
    r
}

/// [`paint`] once the textures are up to date.
fn paint_surface(
    g: &mut Gfx,
    jobs: &[egui::ClippedPrimitive],
    ppp: f32,
    capture: bool,
) -> Result<Option<(u32, u32, Vec<u8>)>, String> {
    let size = g.window.inner_size();
    if size.width == 0 || size.height == 0 {
        return Ok(None);
    }
    if (size.width, size.height) != (g.config.width, g.config.height) {
        g.config.width = size.width;
        g.config.height = size.height;
        g.surface.configure(&g.device, &g.config);
    }
    let frame = match g.surface.get_current_texture() {
        wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
        wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
            return Ok(None)
        }
        wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
            g.surface.configure(&g.device, &g.config);
            return Ok(None);
        }
        wgpu::CurrentSurfaceTexture::Validation => {
            return Err("the window's surface failed validation".into())
        }
    };
    let screen = egui_wgpu::ScreenDescriptor {
        size_in_pixels: [g.config.width, g.config.height],
        pixels_per_point: ppp,
    };
    let mut enc = g
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("egui"),
        });
    let extra = g
        .renderer
        .update_buffers(&g.device, &g.queue, &mut enc, jobs, &screen);
    let view = frame
        .texture
        .create_view(&wgpu::TextureViewDescriptor::default());
    let target = capture.then(|| {
        g.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("screenshot"),
            size: wgpu::Extent3d {
                width: g.config.width,
                height: g.config.height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: g.config.format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    });
    let target_view = target
        .as_ref()
        .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()));
    for v in std::iter::once(&view).chain(target_view.as_ref()) {
        let pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("egui"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let mut pass = pass.forget_lifetime();
        g.renderer.render(&mut pass, jobs, &screen);
    }
    let (w, h) = (g.config.width, g.config.height);
    let row = 4 * w;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let readback = target.as_ref().map(|t| {
        let buffer = g.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot readback"),
            size: u64::from(padded) * u64::from(h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: t,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(h),
                },
            },
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
        buffer
    });
    g.queue
        .submit(extra.into_iter().chain(std::iter::once(enc.finish())));
    g.queue.present(frame);
    let Some(buffer) = readback else {
        return Ok(Some((0, 0, vec![])));
    };
    let slice = buffer.slice(..);
    let (tx, rx) = channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    g.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("waiting for the screenshot: {e}"))?;
    rx.recv()
        .map_err(|e| e.to_string())?
        .map_err(|e| format!("mapping the screenshot: {e}"))?;
    let bgra = matches!(
        g.config.format,
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let data = slice.get_mapped_range().map_err(|e| e.to_string())?;
    let mut rgba = Vec::with_capacity((row * h) as usize);
    for y in 0..h as usize {
        let line = &data[y * padded as usize..y * padded as usize + row as usize];
        for px in line.chunks_exact(4) {
            if bgra {
                rgba.extend_from_slice(&[px[2], px[1], px[0], 255]);
            } else {
                rgba.extend_from_slice(&[px[0], px[1], px[2], 255]);
            }
        }
    }
    Ok(Some((w, h, rgba)))
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gfx.is_some() {
            return;
        }
        match self.create_gfx(event_loop) {
            Ok(g) => {
                g.window.request_redraw();
                self.gfx = Some(g);
            }
            Err(e) => self.finish(event_loop, Err(e)),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        if let Some(g) = &mut self.gfx {
            let _ = g.state.on_window_event(&g.window, &event);
        }
        match event {
            WindowEvent::CloseRequested => self.finish(event_loop, Ok(())),
            WindowEvent::Resized(s) => {
                if let Some(g) = &mut self.gfx {
                    if s.width > 0 && s.height > 0 {
                        g.config.width = s.width;
                        g.config.height = s.height;
                        g.surface.configure(&g.device, &g.config);
                    }
                }
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        if let Some(g) = &self.gfx {
            g.window.request_redraw();
        }
        // At most ~60 window frames a second: the render thread shares the CPU (lavapipe).
        event_loop.set_control_flow(ControlFlow::WaitUntil(
            Instant::now() + Duration::from_millis(16),
        ));
    }
}
