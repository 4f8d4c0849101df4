//! The walkthrough frame on the GPU (issue 11; 000 §4, Fig. 4.1): the passes of this crate in
//! the order a frame needs them, every intermediate staying on the GPU.
//!
//! When the scene loads ([`GpuWalkthrough::new`]): every probe object's cube map captured from
//! the light-mapped scene with the object left out and filtered into its Gaussian 6×6 pyramid
//! ([`GpuProbeCapture`]; bounding planes on the CPU), or the environment's pyramid uploaded for
//! scenes without probes. Per frame ([`GpuWalkthrough::render`]): the mirror buffer of every
//! planar reflector and the see-through buffer of every transmissive probe object
//! ([`GpuViewPass`], 000 §4.5), the k×k supersampled raster G-buffer ([`GBufferPass`]), the
//! light-mapped diffuse shading ([`LightmapShadePass`], 000 Eq. 4.1) and the view-dependent pass
//! ([`FrameShadePass`]: regular, CK or progressive sampling through each material's warp).
//!
//! The CPU frame ([`lustre_shade::frame::render_frame`]) is the same frame from ray casts; each
//! pass's CPU twin reads the GPU's intermediates ([`GpuFrame`] keeps them) for the parity tests.

use crate::context::GpuContext;
use crate::error::{invalid, Result};
use crate::frame_shade::{
    pack_material, FrameShadeOptions, FrameShadePass, FrameShadeScene, FrameShadeTarget,
};
use crate::gbuffer::{GBufferPass, GBufferTarget};
use crate::lightmap_shade::{LightmapFrameScene, LightmapShadePass, ShadeTarget};
use crate::probe_capture::{GpuProbe, GpuProbeCapture};
use crate::pyramid::GpuPyramid;
use crate::timer::GpuTimer;
use crate::view_buffer::GpuViewBuffer;
use crate::view_pass::GpuViewPass;
use lustre_env::pyramid::CubePyramid;
use lustre_shade::frame::{view_meshes, FrameMethod, FrameStats, FrameTables};
use lustre_shade::image::Image;
use lustre_shade::mirror::Reflector;
use lustre_shade::path::PathCamera;
use lustre_shade::probe::{LitScene, ProbeOptions};

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
}

/// Time of each stage of one frame, ms: GPU timestamps where the adapter has them, else the
/// wall time until the GPU had finished.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuFrameTimes {
    /// Mirror and see-through buffers.
    pub views_ms: f64,
    /// The raster G-buffer.
    pub gbuffer_ms: f64,
    /// Light-mapped diffuse shading.
    pub lightmap_ms: f64,
    /// The view-dependent pass (all frames of a progressive refinement).
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
    /// The mirror buffers (with their reflectors), then the see-through buffers.
    pub views: Vec<GpuViewBuffer>,
    /// The reflector of each mirror buffer.
    pub reflectors: Vec<Reflector>,
    /// The per-mesh tables the view-dependent pass read.
    pub tables: FrameTables,
}

/// Options of a GPU frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuFrameOptions {
    /// Glossy samples per G-buffer pixel.
    pub samples: u32,
    /// Regular, CK or progressive (its frame count accumulated in this call).
    pub method: FrameMethod,
    /// k: the G-buffer is (k·w)×(k·h), box-averaged into the frame (anti-aliasing).
    pub supersampling: u32,
    /// Seed of the CK points.
    pub seed: u64,
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
        let capture = GpuProbeCapture::new(ctx)?;
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
        let environment = match (probes.is_empty(), environment) {
            (true, Some(e)) => Some(GpuPyramid::upload(ctx, e)?),
            _ => None,
        };
        Ok(GpuWalkthrough {
            scene,
            gbuffer: GBufferPass::new(ctx)?,
            lightmap: LightmapShadePass::new(ctx)?,
            views: GpuViewPass::new(ctx)?,
            shade: FrameShadePass::new(ctx)?,
            probes,
            environment,
            capture_ms,
            timestamps: ctx
                .device
                .features()
                .contains(wgpu::Features::TIMESTAMP_QUERY),
        })
    }

    /// Renders a w×h frame of `lit` from `camera`. Errors: an empty image, a sample count
    /// outside 1..=`MAX_SAMPLES`, no supersampling, a material the GPU cannot shade (named).
    pub fn render(
        &self,
        ctx: &GpuContext,
        lit: &LitScene,
        camera: &PathCamera,
        (w, h): (usize, usize),
        opts: &GpuFrameOptions,
    ) -> Result<GpuFrame> {
        let k = opts.supersampling;
        if w == 0 || h == 0 || k == 0 {
            return Err(invalid(
                "frame",
                format!("a {w}×{h} frame with {k}×{k} supersampling is empty"),
            ));
        }
        let mut timer = GpuTimer::new(ctx);
        let mut times = GpuFrameTimes {
            timestamps: ctx
                .device
                .features()
                .contains(wgpu::Features::TIMESTAMP_QUERY),
            ..GpuFrameTimes::default()
        };
        // The mirror and see-through passes (000 §4.5.1), at the frame's resolution.
        timer.start(ctx)?;
        let (reflector_meshes, transmissive) = view_meshes(lit);
        let mut views = vec![];
        let mut reflectors = vec![];
        let mut in_plane = vec![];
        for &m in &reflector_meshes {
            let (reflector, render) =
                self.views
                    .render_mirror(ctx, &self.scene, lit, m, camera, w, h)?;
            in_plane.push((m, reflector.in_plane.clone()));
            reflectors.push(reflector);
            views.push(render.view);
        }
        for &m in &transmissive {
            let render = self
                .views
                .render_see_through(ctx, &self.scene, lit, m, camera, w, h)?;
            views.push(render.view);
        }
        times.views_ms = ms(timer.stop(ctx)?);
        let probe_meshes: Vec<u32> = self.probes.iter().map(|p| p.mesh).collect();
        let tables = FrameTables::new(lit, &probe_meshes, in_plane);
        let shade_scene = FrameShadeScene::new(
            ctx,
            lit,
            &tables,
            &self.probes,
            self.environment.as_ref(),
            &views,
        )?;
        // The G-buffer and its light-mapped shading.
        let (gw, gh) = (w as u32 * k, h as u32 * k);
        let gbuffer = GBufferTarget::new(ctx, gw, gh)?;
        timer.start(ctx)?;
        self.gbuffer
            .draw(ctx, &self.scene.geometry, camera, &gbuffer)?;
        times.gbuffer_ms = ms(timer.stop(ctx)?);
        let lightmapped = ShadeTarget::new(ctx, w as u32, h as u32)?;
        timer.start(ctx)?;
        self.lightmap
            .shade(ctx, &self.scene.shading, &gbuffer, camera, k, &lightmapped)?;
        times.lightmap_ms = ms(timer.stop(ctx)?);
        // The view-dependent pass; progressive refinement accumulates its frames in `out`.
        let out = FrameShadeTarget::new(ctx, w as u32, h as u32, k)?;
        let frames = match opts.method {
            FrameMethod::Progressive { frames } => frames,
            _ => 1,
        };
        timer.start(ctx)?;
        for frame in 0..frames {
            let shade_opts = FrameShadeOptions {
                samples: opts.samples,
                method: opts.method,
                frame,
                seed: opts.seed,
            };
            self.shade.shade(
                ctx,
                &shade_scene,
                &gbuffer,
                &lightmapped,
                camera,
                k,
                &shade_opts,
                &out,
            )?;
        }
        times.shade_ms = ms(timer.stop(ctx)?);
        let mut stats = out.stats(ctx)?;
        stats.mirrors = reflectors.len();
        stats.see_throughs = transmissive.len();
        stats.mirror_seconds = times.views_ms * 1e-3;
        Ok(GpuFrame {
            image: out.read_back(ctx)?,
            stats,
            times,
            gbuffer,
            lightmapped,
            views,
            reflectors,
            tables,
        })
    }
}
