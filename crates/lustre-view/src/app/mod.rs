//! The window of `lustre view` and everything it does, one module per concern; this module
//! holds the application's state (`App`) and its plain helpers (paths in the output folder,
//! the messages shown in the window, ending the run).
//!
//! - `launch`: the arguments checked, the scene source made, the render thread and the event
//!   loop started and ended in order ([`run`]).
//! - `window`: the window's GPU objects, the winit events and one window frame.
//! - `paint`: egui drawn into the surface, and the screenshot read back from the GPU.
//! - `frames`: the link to the render thread: frame requests, replies, the frame as texture.
//! - `edit`: the actions the panels and the script share (selection, material parameters,
//!   method, per-object sample budgets, scene cameras).
//! - `panels`: the egui layout, the view panel and the 3D view's input; `material_panel`:
//!   the material editor.
//! - `script`: the input script run command by command, and the end of unattended runs.
//! - `recording`: the camera path recorded while walking.
//! - `save`: the material JSON, the edited scene file and screenshots written.
//! - `jobs`: the background fit jobs.

mod edit;
mod frames;
mod jobs;
mod launch;
mod material_panel;
mod paint;
mod panels;
mod recording;
mod save;
mod script;
mod window;

pub use launch::run;

use crate::adaptive::{AdaptiveOptions, BufferView};
use crate::camera::FlyCamera;
use crate::fit::{FitDone, FitJob};
use crate::render::{FrameReply, Reply, Request, SceneInfo, SceneSource, ViewRequest};
use crate::script::Command;
use crate::ViewArgs;
use edit::Draft;
use launch::initial_request;
use lustre_trace::path_tracer::PathCamera;
use recording::Recording;
use script::Wait;
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, Sender};
use std::time::Instant;
use window::Gfx;
use winit::event_loop::ActiveEventLoop;

/// Radians of turn per pixel of mouse drag.
const LOOK_RADIANS_PER_PIXEL: f64 = 0.004;
/// Frames kept in the frame-time graph.
const HISTORY: usize = 120;

/// A message in the window.
struct Note {
    text: String,
    error: bool,
}

/// The viewer's state: the window, the link to the render thread, the view, the editor, the
/// fit, the recording and the script.
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
    settings: ViewRequest,
    scale: f64,
    exposure: f64,
    vsync: bool,
    /// Draw the real-time set-up (probe boxes, reflectors) over the frame.
    show_setup: bool,
    view_size: (usize, usize),
    view_rect_px: [f32; 4],
    sent: Option<(PathCamera, (usize, usize), ViewRequest)>,
    /// The last request the render thread could not render.
    failed: Option<(PathCamera, (usize, usize), ViewRequest)>,
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
            settings: ViewRequest {
                frame: initial_request(&args),
                generation: 0,
                adaptive: AdaptiveOptions::default(),
            },
            scale: args.scale,
            vsync: !args.no_vsync,
            show_setup: false,
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
}
