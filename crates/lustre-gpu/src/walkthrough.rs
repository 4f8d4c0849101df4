//! The walkthrough frame on the GPU (000 §4, Fig. 4.1): the passes of this crate in
//! the order a frame needs them, every intermediate staying on the GPU.
//!
//! When the scene loads ([`GpuWalkthrough::new`]): every probe object's cube map captured from
//! the light-mapped scene with the object left out and filtered into its Gaussian 6×6 pyramid
//! ([`GpuProbeCapture`]; bounding planes on the CPU), or the environment's pyramid uploaded for
//! scenes without probes. Per camera: the mirror buffer of every planar reflector and the
//! see-through buffer of every transmissive probe object ([`GpuViewPass`], 000 §4.5), the k×k
//! supersampled raster G-buffer ([`GBufferPass`]) and the light-mapped diffuse shading
//! ([`LightmapShadePass`], 000 Eq. 4.1); per frame, the view-dependent pass ([`FrameShadePass`]:
//! regular, CK or progressive sampling through each material's warp).
//!
//! [`GpuFrameSession`] keeps the targets and the per-camera buffers between displayed frames:
//! at a still camera a progressive refinement adds one QMC frame per step (000 §4.4.2) and a regular or CK frame is not re-rendered; motion resets. [`GpuWalkthrough::render`]
//! is one fresh session stepped through its frames.
//!
//! The CPU frame ([`lustre_shade::frame::render_frame`]) is the same frame from ray casts; each
//! pass's CPU twin reads the GPU's intermediates ([`GpuFrame`], [`SessionIntermediates`]) for
//! the parity tests.

use crate::context::GpuContext;
use crate::error::{invalid, Result};
use crate::material::pack_material;
use crate::passes::frame_shade::{FrameShadePass, FrameShadeScene, FrameShadeTarget};
use crate::passes::gbuffer::{GBufferPass, GBufferTarget};
use crate::passes::lightmap_shade::{LightmapFrameScene, LightmapShadePass, ShadeTarget};
use crate::passes::probe_capture::{GpuProbe, GpuProbeCapture};
use crate::passes::pyramid::GpuPyramid;
use crate::passes::view::GpuViewPass;
use crate::timer::GpuTimer;
use crate::view_buffer::GpuViewBuffer;
use lustre_env::pyramid::CubePyramid;
use lustre_shade::frame::{view_meshes, walkthrough_request, FrameStats, FrameTables};
use lustre_shade::mirror::{mirror_camera, Reflector, ScreenTiles};
use lustre_shade::probe::{LitScene, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::image::Image;
use lustre_trace::path_tracer::PathCamera;

/// The compiled passes of a walkthrough, kept when the scene is uploaded again (a viewer's
/// material edit): compiling them is most of a walkthrough's set-up on a software adapter.
#[derive(Debug)]
pub struct WalkthroughPasses {
    gbuffer: GBufferPass,
    lightmap: LightmapShadePass,
    views: GpuViewPass,
    shade: FrameShadePass,
    capture: GpuProbeCapture,
}

impl WalkthroughPasses {
    /// Compiles every pass of the walkthrough frame, the view-dependent pass with every
    /// material kind (what a material editor needs).
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Self::with_kinds(ctx, crate::material::kinds::all_sampled())
    }

    /// Compiles every pass of the walkthrough frame, the view-dependent pass with the material
    /// kinds of `scene` only ([`FrameShadePass::for_kinds`]): what a renderer that does not
    /// change materials compiles. A material the GPU cannot pack adds nothing here; the
    /// walkthrough refuses it by name.
    pub fn for_scene(ctx: &GpuContext, scene: &lustre_scene::Scene) -> Result<Self> {
        let kinds = scene
            .materials
            .iter()
            .filter_map(|m| pack_material(m, &mut vec![]).ok())
            .filter(|b| b.kind != crate::material::KIND_NONE)
            .fold(0, |mask, b| {
                mask | crate::material::kinds::sampled_kinds(b.kind)
            });
        Self::with_kinds(ctx, kinds)
    }

    fn with_kinds(ctx: &GpuContext, kinds: u32) -> Result<Self> {
        Ok(WalkthroughPasses {
            gbuffer: GBufferPass::new(ctx)?,
            lightmap: LightmapShadePass::new(ctx)?,
            views: GpuViewPass::new(ctx)?,
            shade: FrameShadePass::for_kinds(ctx, kinds)?,
            capture: GpuProbeCapture::new(ctx)?,
        })
    }
}

/// The compiled passes and the scene's GPU data, probes included.
#[derive(Debug)]
pub struct GpuWalkthrough {
    scene: LightmapFrameScene,
    gbuffer: GBufferPass,
    lightmap: LightmapShadePass,
    views: GpuViewPass,
    shade: FrameShadePass,
    /// The probes captured when the scene loaded, in mesh order.
    pub probes: Vec<GpuProbe>,
    /// The environment's pyramid, for scenes without probes.
    pub environment: Option<GpuPyramid>,
    /// Capture time of each probe (name, ms; GPU timestamps where the adapter has them).
    pub capture_ms: Vec<(String, f64)>,
    /// True when times are the GPU's own timestamps (else the wall clock until it finished).
    pub timestamps: bool,
    /// The probe capture pass, kept for captures on request.
    capture: GpuProbeCapture,
    /// Counts captures on request: a session's per-camera inputs hold copies of the probes
    /// and are rebuilt when it changed.
    probe_generation: u64,
}

/// Time of each stage of one frame (or of one [`GpuFrameSession::step`]: 0 for a pass it did
/// not run), ms: GPU timestamps where the adapter has them, else the wall time until the GPU
/// had finished.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuFrameTimes {
    /// Mirror and see-through buffers (their mirror and see-through layers included).
    pub views_ms: f64,
    /// Of `views_ms`: the mirror and see-through layers' view-dependent shading and MIP
    /// rebuild.
    pub layers_ms: f64,
    /// The raster G-buffer.
    pub gbuffer_ms: f64,
    /// Light-mapped diffuse shading.
    pub lightmap_ms: f64,
    /// The view-dependent pass (in a [`GpuFrame`] all frames of a progressive refinement, in a
    /// [`GpuStep`] the frame of that call).
    pub shade_ms: f64,
    /// True when the times are the GPU's own timestamps.
    pub timestamps: bool,
}

impl GpuFrameTimes {
    /// The whole frame on the GPU.
    pub fn total_ms(&self) -> f64 {
        self.views_ms + self.gbuffer_ms + self.lightmap_ms + self.shade_ms
    }
}

/// A rendered frame and the intermediates its CPU twins read.
#[derive(Debug)]
pub struct GpuFrame {
    /// The w×h frame.
    pub image: Image,
    /// Counts of the view-dependent pass (of its last frame, for progressive refinement).
    pub stats: FrameStats,
    /// Stage times.
    pub times: GpuFrameTimes,
    /// The (k·w)×(k·h) G-buffer.
    pub gbuffer: GBufferTarget,
    /// The w×h light-mapped shading of it.
    pub lightmapped: ShadeTarget,
    /// The mirror buffers (with their reflectors), then the see-through buffers (their
    /// layers shaded).
    pub views: Vec<GpuViewBuffer>,
    /// The w×h G-buffer of each see-through buffer (its layer's input).
    pub see_through_gbuffers: Vec<GBufferTarget>,
    /// The w×h G-buffer of each mirror buffer (its layer's input, seen from the mirrored
    /// camera).
    pub mirror_gbuffers: Vec<GBufferTarget>,
    /// The reflector of each mirror buffer.
    pub reflectors: Vec<Reflector>,
    /// The per-mesh tables the view-dependent pass read.
    pub tables: FrameTables,
}

/// Milliseconds of a timed interval: the GPU's timestamps where present.
fn ms(t: crate::timer::Timing) -> f64 {
    t.gpu_ms.unwrap_or(t.wall_ms)
}

impl GpuWalkthrough {
    /// Uploads `scene` (geometry, light maps), compiles the passes and captures a probe for
    /// every mesh hinted `probe` (`probe_opts`: face size, supersampling, plane rays); without
    /// probes, `environment` (the environment's pyramid) lights the glossy surfaces.
    pub fn new(
        ctx: &GpuContext,
        lit: &LitScene,
        scene: LightmapFrameScene,
        probe_opts: &ProbeOptions,
        environment: Option<&CubePyramid>,
    ) -> Result<Self> {
        let passes = WalkthroughPasses::new(ctx)?;
        Self::with_passes(ctx, passes, lit, scene, probe_opts, environment)
    }

    /// [`GpuWalkthrough::new`] with passes compiled before (kept from
    /// [`GpuWalkthrough::into_passes`] of an earlier upload).
    pub fn with_passes(
        ctx: &GpuContext,
        passes: WalkthroughPasses,
        lit: &LitScene,
        scene: LightmapFrameScene,
        probe_opts: &ProbeOptions,
        environment: Option<&CubePyramid>,
    ) -> Result<Self> {
        // Every material a shaded mesh uses must have a GPU model: refuse the scene now (named)
        // rather than at its first frame.
        for (m, mesh) in lit.scene.meshes.iter().enumerate() {
            let material = lit.scene.materials.get(mesh.material);
            if let (false, Some(material)) = (mesh.hints.diffuse_only, material) {
                pack_material(material, &mut vec![]).map_err(|e| {
                    invalid(
                        format!("mesh {:?} (#{m})", mesh.name),
                        format!("material {:?}: {e}", material.name),
                    )
                })?;
            }
        }
        let WalkthroughPasses {
            gbuffer,
            lightmap,
            views,
            shade,
            capture,
        } = passes;
        let mut timer = GpuTimer::new(ctx);
        let mut probes = vec![];
        let mut capture_ms = vec![];
        for (m, mesh) in lit.scene.meshes.iter().enumerate() {
            if !mesh.hints.probe {
                continue;
            }
            timer.start(ctx)?;
            let probe = capture.capture_probe(ctx, &scene, lit, m, probe_opts)?;
            capture_ms.push((mesh.name.clone(), ms(timer.stop(ctx)?)));
            probes.push(probe);
        }
        for (i, site) in lit.scene.probes.iter().enumerate() {
            timer.start(ctx)?;
            let probe = capture.capture_room_probe(ctx, &scene, lit, i, probe_opts)?;
            capture_ms.push((site.name.clone(), ms(timer.stop(ctx)?)));
            probes.push(probe);
        }
        let environment = match (probes.is_empty(), environment) {
            (true, Some(e)) => Some(GpuPyramid::upload(ctx, e)?),
            _ => None,
        };
        Ok(GpuWalkthrough {
            scene,
            gbuffer,
            lightmap,
            views,
            shade,
            probes,
            environment,
            capture_ms,
            timestamps: timer.has_timestamps(),
            capture,
            probe_generation: 0,
        })
    }

    /// The compiled passes, for [`GpuWalkthrough::with_passes`] (the scene's data is dropped).
    pub fn into_passes(self) -> WalkthroughPasses {
        WalkthroughPasses {
            gbuffer: self.gbuffer,
            lightmap: self.lightmap,
            views: self.views,
            shade: self.shade,
            capture: self.capture,
        }
    }

    /// Captures the probe of mesh `mesh` again, on request (probes are captured when
    /// the scene loads and on request, not every frame): after its surroundings changed (light
    /// maps, materials) or with other `probe_opts`. A [`GpuFrameSession`] reads the new probe
    /// from its next step on (re-rendering its per-camera inputs, as after a camera move).
    /// Returns the capture time, ms. Errors: `mesh` has no probe (named), or the capture's.
    pub fn recapture_probe(
        &mut self,
        ctx: &GpuContext,
        lit: &LitScene,
        mesh: usize,
        probe_opts: &ProbeOptions,
    ) -> Result<f64> {
        let i = self
            .probes
            .iter()
            .position(|p| p.mesh == Some(mesh as u32))
            .ok_or_else(|| {
                let name = lit.scene.meshes.get(mesh).map_or("", |m| m.name.as_str());
                invalid(
                    format!("mesh {name:?} (#{mesh})"),
                    "has no probe to capture again (hint it `probe = true`)",
                )
            })?;
        let mut timer = GpuTimer::new(ctx);
        timer.start(ctx)?;
        let probe = self
            .capture
            .capture_probe(ctx, &self.scene, lit, mesh, probe_opts)?;
        let t = ms(timer.stop(ctx)?);
        self.probes[i] = probe;
        self.capture_ms[i].1 = t;
        self.probe_generation += 1;
        Ok(t)
    }

    /// Renders a w×h frame of `lit` from `camera`: a fresh [`GpuFrameSession`] stepped once,
    /// or [`FrameRequest::frames`] times for the progressive method (still frames
    /// accumulated), its image read back with its intermediates. Errors: an empty image, a
    /// request `walkthrough_request` refuses, a material the GPU cannot shade (named).
    pub fn render(
        &self,
        ctx: &GpuContext,
        lit: &LitScene,
        camera: &PathCamera,
        size: (usize, usize),
        req: &FrameRequest,
    ) -> Result<GpuFrame> {
        let mut session = GpuFrameSession::new();
        // The first step validates the request (0 frames included).
        let mut step = session.step(ctx, self, lit, camera, size, req)?;
        let mut times = step.times;
        for _ in 1..req.accumulated_frames() {
            step = session.step(ctx, self, lit, camera, size, req)?;
            times.shade_ms += step.times.shade_ms;
        }
        let mut stats = step.stats;
        stats.mirror_seconds = times.views_ms * 1e-3;
        session.into_frame(ctx, stats, times)
    }
}

/// What one [`GpuFrameSession::step`] ran.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StepWork {
    /// The targets were allocated (the first step, or a new size or supersampling) and every
    /// pass ran.
    Allocated,
    /// The camera moved (or [`GpuFrameSession::reset`] was called, or a probe was captured
    /// again): the view buffers, the
    /// G-buffer, the light-map shading and frame 0 of the view-dependent pass re-rendered into
    /// the kept targets.
    Moved,
    /// Samples, method or seed changed at a still camera: frame 0 of the view-dependent pass
    /// alone, over the kept G-buffer and view buffers.
    Reshaded,
    /// The next progressive frame, accumulated (the view-dependent pass alone).
    Accumulated,
    /// Nothing changed and nothing is left to add (a still regular or CK frame, or a progressive
    /// refinement that holds its `frames`): no pass ran, the image is the previous one.
    Unchanged,
}

/// The record of one [`GpuFrameSession::step`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuStep {
    /// What ran.
    pub work: StepWork,
    /// Frames the image now holds: 1 for regular and CK, the progressive frames accumulated
    /// since the last reset (the last one shaded is frame `frames − 1`).
    pub frames: u32,
    /// Counts of the view-dependent pass's latest run (the image's last frame), the mirror and
    /// see-through buffers the image reads, and the time of this call's view passes (0 when
    /// they did not run).
    pub stats: FrameStats,
    /// Times of the passes this call ran (0 for those it did not).
    pub times: GpuFrameTimes,
}

/// The read-only intermediates of a session's current frame (what the CPU twins read).
#[derive(Clone, Copy, Debug)]
pub struct SessionIntermediates<'a> {
    /// The (k·w)×(k·h) G-buffer.
    pub gbuffer: &'a GBufferTarget,
    /// The mirror buffers, then the see-through buffers.
    pub views: &'a [GpuViewBuffer],
    /// The reflector of each mirror buffer.
    pub reflectors: &'a [Reflector],
    /// The per-mesh tables the view-dependent pass reads.
    pub tables: &'a FrameTables,
}

/// The targets of one size and supersampling.
#[derive(Debug)]
struct Targets {
    size: (usize, usize),
    k: u32,
    gbuffer: GBufferTarget,
    lightmapped: ShadeTarget,
    out: FrameShadeTarget,
}

/// What was rendered for one camera: its view buffers and the view-dependent pass's inputs
/// built on them.
#[derive(Debug)]
struct CameraFrame {
    camera: PathCamera,
    /// The walkthrough's probe generation the inputs were built with.
    probes: u64,
    views: Vec<GpuViewBuffer>,
    reflectors: Vec<Reflector>,
    see_throughs: usize,
    /// The G-buffer of each see-through buffer (its layer's input).
    see_through_gbuffers: Vec<GBufferTarget>,
    /// The G-buffer of each mirror buffer (its layer's input).
    mirror_gbuffers: Vec<GBufferTarget>,
    tables: FrameTables,
    scene: FrameShadeScene,
}

/// What the image in the output target holds.
#[derive(Clone, Copy, Debug)]
struct Shaded {
    samples: u32,
    method: Method,
    seed: u64,
    frames: u32,
    stats: FrameStats,
}

/// A persistent GPU frame of one [`GpuWalkthrough`] (000 §4.4.2): the targets
/// for a size w×h and supersampling k (G-buffer, light-mapped image, the view-dependent pass's
/// output and progressive accumulation), the view buffers and the pass inputs built for the
/// current camera, and what the image holds (samples, method, seed, frames accumulated).
/// A walkthrough (or a viewer) calls [`GpuFrameSession::step`] once per displayed frame:
///
/// - size or k changed (or the first step): the targets are reallocated, every pass runs;
/// - the camera changed (or a probe was captured again,
///   [`GpuWalkthrough::recapture_probe`]): view buffers, G-buffer, light-map shading and
///   progressive frame 0 (the accumulation is reset) re-rendered into the kept targets;
/// - samples, method or seed changed: frame 0 of the view-dependent pass alone;
/// - nothing changed, progressive with fewer than `frames` accumulated: the next QMC frame
///   (frame f's R2 rotation, read at the level of the accumulated count) is averaged in, so a
///   still camera converges frame by frame to the integral of the same incident light;
/// - nothing changed otherwise (regular, CK, or `frames` reached): no pass runs.
///
/// `Progressive { frames }` is the number of frames to accumulate at a still camera; a step
/// with fewer `frames` than the image already holds resets it. Cameras are compared exactly:
/// every [`PathCamera`] field (origin, forward, right, up, tan ½fov) bit for bit, so any
/// change, however small, resets the accumulation, and a viewer keeps passing the same value
/// while the user is still. On a camera move the view buffers and the pass's scene inputs
/// ([`FrameShadeScene`], which concatenates the view buffers) are built anew; only size or k
/// reallocate the frame targets. The image stays on the GPU ([`GpuFrameSession::target`])
/// until [`GpuFrameSession::image`] reads it back. A session belongs to one walkthrough and
/// scene: pass the same ones to every step. After an error the next step re-renders
/// everything.
#[derive(Debug, Default)]
pub struct GpuFrameSession {
    targets: Option<Targets>,
    frame: Option<CameraFrame>,
    shaded: Option<Shaded>,
    /// Steps leave the view-dependent pass's counts on the GPU ([`GpuFrameSession::without_counts`]).
    skip_counts: bool,
}

/// Every field of a camera, bit for bit (origin, forward, right, up, tan ½fov).
fn camera_bits(c: &PathCamera) -> [u64; 13] {
    let v = [c.origin, c.forward, c.right, c.up];
    std::array::from_fn(|i| match v.get(i / 3) {
        Some(x) => x[i % 3].to_bits(),
        None => c.tan_half_fov_y.to_bits(),
    })
}

impl GpuFrameSession {
    /// A session with nothing allocated; the first [`GpuFrameSession::step`] allocates.
    pub fn new() -> Self {
        Self::default()
    }

    /// A session whose steps never wait for the GPU: the view-dependent pass's counts (glossy
    /// hits, lookups) are not read back, and [`GpuStep::stats`] holds zeros for them. What a
    /// browser needs (it cannot wait inside a frame) and what a viewer that does not show the
    /// counts can take.
    pub fn without_counts() -> Self {
        GpuFrameSession {
            skip_counts: true,
            ..Self::default()
        }
    }

    /// Renders, refines or keeps the w×h frame of `lit` from `camera` (type docs) and returns
    /// what it did. Errors (the session is left as it was): an empty image, a request
    /// `walkthrough_request` refuses; and the passes' own errors (the next step then
    /// re-renders everything).
    pub fn step(
        &mut self,
        ctx: &GpuContext,
        walk: &GpuWalkthrough,
        lit: &LitScene,
        camera: &PathCamera,
        (w, h): (usize, usize),
        req: &FrameRequest,
    ) -> Result<GpuStep> {
        walkthrough_request(req).map_err(|e| invalid("frame request", e.to_string()))?;
        let k = req.supersampling();
        let (gw, gh) = match (u32::try_from(w), u32::try_from(h)) {
            (Ok(a), Ok(b)) if a > 0 && b > 0 && k > 0 => {
                match (a.checked_mul(k), b.checked_mul(k)) {
                    (Some(gw), Some(gh)) => (gw, gh),
                    _ => {
                        return Err(invalid(
                            "frame",
                            format!("a {w}×{h} frame at {k}×{k} supersampling is too large"),
                        ))
                    }
                }
            }
            _ => {
                return Err(invalid(
                    "frame",
                    format!("a {w}×{h} frame with {k}×{k} supersampling is empty"),
                ))
            }
        };
        let wanted = req.accumulated_frames();
        let mut timer = GpuTimer::new(ctx);
        let mut times = GpuFrameTimes {
            timestamps: walk.timestamps,
            ..GpuFrameTimes::default()
        };
        let mut work = StepWork::Unchanged;
        // The targets: kept unless the size or the supersampling changed.
        let targets = match &mut self.targets {
            Some(t) if t.size == (w, h) && t.k == k => t,
            slot => {
                // Free the old targets before allocating the new ones.
                *slot = None;
                self.frame = None;
                self.shaded = None;
                work = StepWork::Allocated;
                slot.insert(Targets {
                    size: (w, h),
                    k,
                    gbuffer: GBufferTarget::new(ctx, gw, gh)?,
                    lightmapped: ShadeTarget::new(ctx, gw / k, gh / k)?,
                    out: FrameShadeTarget::new(ctx, gw / k, gh / k, k)?,
                })
            }
        };
        // What the camera sees: kept while it is still.
        let frame = match &mut self.frame {
            Some(f)
                if camera_bits(&f.camera) == camera_bits(camera)
                    && f.probes == walk.probe_generation =>
            {
                f
            }
            slot => {
                *slot = None;
                self.shaded = None;
                if work == StepWork::Unchanged {
                    work = StepWork::Moved;
                }
                slot.insert(render_camera(
                    ctx, walk, lit, camera, targets, &mut timer, &mut times,
                )?)
            }
        };
        // The view-dependent pass: frame 0 after any change, the next frame of a still
        // progressive refinement, nothing otherwise.
        let same =
            |s: &Shaded| (s.samples, s.method, s.seed) == (req.samples, req.method, req.seed);
        let shaded = match self.shaded {
            Some(s) if same(&s) && s.frames == wanted => s,
            previous => {
                let f = match previous {
                    Some(s) if same(&s) && s.frames < wanted => s.frames,
                    _ => 0,
                };
                if work == StepWork::Unchanged {
                    work = if f == 0 {
                        StepWork::Reshaded
                    } else {
                        StepWork::Accumulated
                    };
                }
                // The accumulation is being rewritten: no image until the pass has finished.
                self.shaded = None;
                timer.start(ctx)?;
                walk.shade.shade(
                    ctx,
                    &frame.scene,
                    &targets.gbuffer,
                    &targets.lightmapped,
                    camera,
                    k,
                    (req, f),
                    &targets.out,
                )?;
                times.shade_ms = ms(timer.stop(ctx)?);
                let mut stats = if self.skip_counts {
                    FrameStats::default()
                } else {
                    targets.out.stats(ctx)?
                };
                stats.mirrors = frame.reflectors.len();
                stats.see_throughs = frame.see_throughs;
                Shaded {
                    samples: req.samples,
                    method: req.method,
                    seed: req.seed,
                    frames: f + 1,
                    stats,
                }
            }
        };
        self.shaded = Some(shaded);
        let mut stats = shaded.stats;
        stats.mirror_seconds = times.views_ms * 1e-3;
        Ok(GpuStep {
            work,
            frames: shaded.frames,
            stats,
            times,
        })
    }

    /// Forgets the current frame (the targets are kept): the next step re-renders every pass
    /// as after a camera move.
    pub fn reset(&mut self) {
        self.frame = None;
        self.shaded = None;
    }

    /// Frames the current image holds (0 before the first step and after a reset or an
    /// error).
    pub fn frames(&self) -> u32 {
        self.shaded.map_or(0, |s| s.frames)
    }

    /// The GPU output of the current frame (w×h pixels and the progressive accumulation),
    /// for display without a host round trip; `None` before the first step.
    pub fn target(&self) -> Option<&FrameShadeTarget> {
        self.targets.as_ref().map(|t| &t.out)
    }

    /// The current frame's intermediates; `None` when there is no frame.
    pub fn intermediates(&self) -> Option<SessionIntermediates<'_>> {
        match (&self.targets, &self.frame, &self.shaded) {
            (Some(t), Some(f), Some(_)) => Some(SessionIntermediates {
                gbuffer: &t.gbuffer,
                views: &f.views,
                reflectors: &f.reflectors,
                tables: &f.tables,
            }),
            _ => None,
        }
    }

    /// Reads the current frame back. Errors: no frame yet (or since a reset or an error).
    pub fn image(&self, ctx: &GpuContext) -> Result<Image> {
        match (&self.targets, &self.shaded) {
            (Some(t), Some(_)) => t.out.read_back(ctx),
            _ => Err(invalid("frame session", "no frame has been rendered")),
        }
    }

    /// The current frame with its intermediates, consuming the session.
    fn into_frame(
        self,
        ctx: &GpuContext,
        stats: FrameStats,
        times: GpuFrameTimes,
    ) -> Result<GpuFrame> {
        let image = self.image(ctx)?;
        match (self.targets, self.frame) {
            (Some(t), Some(f)) => Ok(GpuFrame {
                image,
                stats,
                times,
                gbuffer: t.gbuffer,
                lightmapped: t.lightmapped,
                views: f.views,
                see_through_gbuffers: f.see_through_gbuffers,
                mirror_gbuffers: f.mirror_gbuffers,
                reflectors: f.reflectors,
                tables: f.tables,
            }),
            _ => Err(invalid("frame session", "no frame has been rendered")),
        }
    }
}

/// The per-camera passes of a frame into `targets`: the mirror and see-through buffers
/// (000 §4.5.1) at the frame's resolution, the view-dependent pass's inputs built on them, the
/// G-buffer and its light-mapped shading. Their times go to `times`.
fn render_camera(
    ctx: &GpuContext,
    walk: &GpuWalkthrough,
    lit: &LitScene,
    camera: &PathCamera,
    targets: &Targets,
    timer: &mut GpuTimer,
    times: &mut GpuFrameTimes,
) -> Result<CameraFrame> {
    let (w, h) = targets.size;
    timer.start(ctx)?;
    let (reflector_meshes, transmissive) = view_meshes(lit);
    let mut views = vec![];
    let mut reflectors = vec![];
    let mut in_plane = vec![];
    let mut mirror_gbuffers = vec![];
    for &m in &reflector_meshes {
        let (reflector, render) =
            walk.views
                .render_mirror(ctx, &walk.scene, lit, m, camera, w, h)?;
        in_plane.push((m, reflector.in_plane.clone()));
        reflectors.push(reflector);
        views.push(render.view);
        mirror_gbuffers.push(render.gbuffer);
    }
    let mut see_through_gbuffers = vec![];
    for &m in &transmissive {
        let render = walk
            .views
            .render_see_through(ctx, &walk.scene, lit, m, camera, w, h)?;
        views.push(render.view);
        see_through_gbuffers.push(render.gbuffer);
    }
    times.views_ms = ms(timer.stop(ctx)?);
    let probe_meshes: Vec<Option<u32>> = walk.probes.iter().map(|p| p.mesh).collect();
    let tables = FrameTables::new(lit, &probe_meshes, in_plane);
    let scene = FrameShadeScene::new(
        ctx,
        lit,
        &tables,
        &walk.probes,
        walk.environment.as_ref(),
        &views,
    )?;
    // The mirror layers (lustre_shade::frame::shade_mirror_layer): what each mirror buffer
    // shows gains its view-dependent part as the mirrored camera sees it, read from the probes;
    // then the see-through layers (lustre_shade::frame::shade_see_through_layer): what each
    // see-through buffer shows gains its view-dependent part, read from the mirror buffers and
    // probes. After each, the levels and the pass's copy are rebuilt.
    if !reflectors.is_empty() || !transmissive.is_empty() {
        timer.start(ctx)?;
        let (wu, hu) = (w as u32, h as u32);
        let out = FrameShadeTarget::new(ctx, wu, hu, 1)?;
        for (i, (gb, &m)) in mirror_gbuffers.iter().zip(&reflector_meshes).enumerate() {
            let cam = mirror_camera(camera, &reflectors[i].plane);
            let tiles = ScreenTiles::of_mesh(lit, m, camera, w, h);
            walk.shade
                .shade_mirror_layer(ctx, &scene, gb, &views[i], &cam, &tiles, &out)?;
            walk.views.build_levels(ctx, &views[i])?;
        }
        for (i, view) in views.iter().enumerate().take(reflectors.len()) {
            scene.refresh_view(ctx, i, view)?;
        }
        let first = reflectors.len();
        for (i, (&m, gb)) in transmissive.iter().zip(&see_through_gbuffers).enumerate() {
            let view = &views[first + i];
            let tiles = ScreenTiles::of_mesh(lit, m, camera, w, h);
            walk.shade
                .shade_see_through_layer(ctx, &scene, gb, view, camera, &tiles, &out)?;
            walk.views.build_levels(ctx, view)?;
        }
        for i in 0..transmissive.len() {
            scene.refresh_view(ctx, first + i, &views[first + i])?;
        }
        times.layers_ms = ms(timer.stop(ctx)?);
        times.views_ms += times.layers_ms;
    }
    timer.start(ctx)?;
    walk.gbuffer
        .draw(ctx, &walk.scene.geometry, camera, &targets.gbuffer)?;
    times.gbuffer_ms = ms(timer.stop(ctx)?);
    timer.start(ctx)?;
    walk.lightmap.shade(
        ctx,
        &walk.scene.shading,
        &targets.gbuffer,
        camera,
        targets.k,
        &targets.lightmapped,
    )?;
    times.lightmap_ms = ms(timer.stop(ctx)?);
    Ok(CameraFrame {
        camera: *camera,
        probes: walk.probe_generation,
        views,
        reflectors,
        see_throughs: transmissive.len(),
        see_through_gbuffers,
        mirror_gbuffers,
        tables,
        scene,
    })
}
