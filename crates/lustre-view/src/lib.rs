//! `lustre view`: the interactive walkthrough and material editor (000's walkthrough
//! application). A winit window with egui panels over the walkthrough renderer of
//! `lustre render` (lustre-gpu's [`lustre_gpu::GpuFrameSession`]), which runs in its own
//! thread ([`render`]) so that the window never waits for a frame, a material rebuild or a fit.
//!
//! - Walking: WASD / arrows (Q / E down and up), drag the view to look, the wheel sets the
//!   speed, shift runs; the scene's cameras as bookmarks; a camera path recorded to a
//!   `lustre-camera-path` JSON that `lustre render --path FILE.json` replays.
//! - Overlays: frames per second, a frame-time graph with the GPU's per-pass times, the sample
//!   budget, the method (regular, Colbert–Křivánek, progressive refinement while still, a CPU
//!   path-traced reference filling in, or 004 ch. IV's adaptive shading on the CPU), exposure.
//! - The adaptive method ([`adaptive`], `lustre render --method adaptive` in the render
//!   thread): each new view rendered from a bandwidth buffer and shaded hierarchically, with
//!   controls for the mean N_p, the rate (1 or 2) and the sample rule, a line with the shaded
//!   share, the samples and the bandwidth pass's and the shading's times, and the buffer views
//!   of 004 Fig. IV.13 / IV.22 (the shaded image, b_p, ℓ, N_p, the shaded pixels by level) as
//!   the CLI's heat maps. It lights by the scene's environment and its planar emitters (as
//!   area lights): a scene with neither is refused with a message.
//! - Measured materials (`--material SPEC`: `lustre_scene::builtin::preview` of a neural, MERL
//!   or RGL BRDF or any material specification, under `--env MAP` or the built-in sky;
//!   `--lineup`: 004 Fig. IV.13's three measured paints on white marble), and any scene without
//!   light maps or with a material the GPU walkthrough does not take, open *adaptive-only*: the
//!   window starts in the adaptive method and says why; the walkthrough methods (regular, CK,
//!   progressive) are refused with that reason; the reference and material edits work.
//! - Material editor: click an object to select it; its material's parameters as controls
//!   ([`lustre_scene::material_edit`]); swap it for any material specification (a catalog
//!   entry, a fitted material JSON, a measured file); **Fit** a measured file in a background
//!   thread and apply the result; the polar lobe plot of measurement and fit; save the material
//!   JSON and the scene file.
//! - The real-time set-up ([`setup_overlay`]): "show set-up" draws the room probes' parallax
//!   boxes (cyan), the object probes (yellow) and the planar reflectors (magenta) over the frame.
//! - Unattended runs: `--script FILE` ([`script`]), `--frames N --screenshot FILE`.

pub mod adaptive;
pub mod app;
pub mod camera;
pub mod fit;
pub mod plot;
pub mod render;
pub mod script;
pub mod setup_overlay;

use std::path::PathBuf;

/// How the glossy part is integrated in the view: the method every renderer shares.
pub use lustre_shade::request::Method;

/// Where the adaptive method's passes run (`--adaptive-device`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum AdaptiveDevice {
    /// The GPU where it takes the scene's materials and is not a software rasterizer.
    #[default]
    Auto,
    /// The GPU where it takes the scene's materials, a software rasterizer included.
    Gpu,
    /// The CPU.
    Cpu,
}

/// Arguments of `lustre view`.
#[derive(clap::Args, Debug, Clone)]
pub struct ViewArgs {
    /// A scene with baked light maps (the scene.toml `lustre bake --out DIR` writes); the
    /// built-in room when absent (its light maps baked once into --bake-dir). A scene without
    /// light maps, or with a material the GPU walkthrough does not take (measured BRDFs), opens
    /// adaptive-only.
    pub scene: Option<PathBuf>,
    /// Instead of a scene: the material preview of this specification (a sphere under --env,
    /// or the built-in sky; `lustre render --method adaptive --material`'s scene), e.g.
    /// `nbrdf:gold-paint`, a MERL `.binary`, an RGL `.bsdf`. Adaptive-only (no light maps).
    #[arg(long, conflicts_with = "scene")]
    pub material: Option<String>,
    /// Instead of a scene: 004 Fig. IV.13's line-up, three measured paints on white marble
    /// under --env or the built-in sky (`lustre render --method adaptive`'s default scene).
    /// Adaptive-only.
    #[arg(long, conflicts_with_all = ["scene", "material"])]
    pub lineup: bool,
    /// The environment map (.hdr / .exr) of --material or --lineup.
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Where the built-in room's light maps are baked and reused.
    #[arg(long, default_value = "lustre-view/bake")]
    pub bake_dir: PathBuf,
    /// Where fits, screenshots, camera paths and saved files go (relative names in the panels
    /// and scripts are taken from here).
    #[arg(long, default_value = "lustre-view")]
    pub out: PathBuf,
    /// Window size WxH in pixels.
    #[arg(long, default_value = "1280x800")]
    pub size: String,
    /// The 3D view's resolution as a fraction of its size on screen (0.1–1).
    #[arg(long, default_value_t = 0.5)]
    pub scale: f64,
    /// Glossy samples per pixel (the adaptive method: the mean N_p).
    #[arg(long, default_value_t = 8)]
    pub samples: u32,
    /// k: a k×k supersampled G-buffer per pixel (anti-aliasing).
    #[arg(long, default_value_t = 1)]
    pub supersampling: u32,
    /// Probe cube face size in texels (as `lustre render --probe-size`).
    #[arg(long, default_value_t = 128)]
    pub probe_size: usize,
    /// Where the adaptive method's bandwidth pass and shading run: auto (the GPU where it takes
    /// the scene's materials, unless the adapter is a software rasterizer such as lavapipe,
    /// slower there than the CPU), gpu or cpu.
    #[arg(long, value_enum, default_value_t = AdaptiveDevice::Auto)]
    pub adaptive_device: AdaptiveDevice,
    /// Present without waiting for the display's refresh.
    #[arg(long)]
    pub no_vsync: bool,
    /// Run this input script (see `lustre_view::script`), then stay open (or `quit`).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Close after this many rendered frames (after the script, if any).
    #[arg(long)]
    pub frames: Option<u32>,
    /// With --frames: save a screenshot of the window here before closing.
    #[arg(long, requires = "frames")]
    pub screenshot: Option<PathBuf>,
    /// Unattended runs (--script, --frames) fail after this many seconds (at most a week).
    #[arg(long, default_value_t = 900.0)]
    pub timeout: f64,
}

/// Runs `lustre view`. Errors: bad arguments or script, no window, no GPU adapter, a device
/// lost, or an unattended run that failed or timed out.
pub fn run(args: &ViewArgs) -> anyhow::Result<()> {
    app::run(args)
}
