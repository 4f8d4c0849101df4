//! The viewer's adaptive method: 004 chapter IV's adaptive shading of measured materials (the
//! same pipeline as `lustre render --method adaptive`: lustre-gpu's bandwidth and adaptive
//! passes where the GPU takes the scene's materials, else `lustre-adaptive` on the CPU) in the
//! render thread, and its buffer views (004 Fig. IV.13, IV.22).
//!
//! Per frame: the G-buffer from the render thread's path tracer (k×k per pixel with the
//! G-buffer supersampling, box-filtered after shading), the bandwidth buffer (n_b = 8
//! directions per pixel against the environment's bandwidth), and the hierarchical shading.
//! The shading context (the materials' sampling and bandwidth tables) is built once per scene:
//! the render thread builds it on the first adaptive frame and again after a material edit. The
//! environment and the scene's planar emitters (as area lights, `lustre_adaptive::light::
//! scene_lights`) light everything, without visibility, as in 004: a scene with neither is
//! refused with a message.
//!
//! The buffer views colour b_p, ℓ + 1, N_p and the level each pixel was shaded at on the log
//! heat map of the CLI's `frame_{bandwidth,level,samples,shaded}.png` (`lustre_plot::heat::
//! heat_rgb`: inferno over the octaves between the 1st and the 99.9th percentile of the positive
//! values, zero black). In the shaded-pixel view the
//! up-sampled surface pixels are grey (the CLI's map leaves them black like the background).

use crate::render::ViewRequest;
use crate::AdaptiveDevice;
use lustre_adaptive::buffer::{level_map, BandwidthBuffer, BufferOptions, SampleRule};
use lustre_adaptive::gbuffer::{GBuffer, GPixel};
use lustre_adaptive::hierarchy::{box_downsample, render_adaptive};
use lustre_adaptive::light::{check_lit, scene_lights};
use lustre_adaptive::shading::{Lighting, ShadingContext, ShadingOptions};
use lustre_freq::pixel::EnvironmentBandwidth;
use lustre_gpu::passes::adaptive::{AdaptivePass, AdaptiveScene};
use lustre_gpu::passes::bandwidth::{BandwidthPass, BandwidthScene};
use lustre_gpu::GpuContext;
use lustre_plot::heat::heat_rgb;
use lustre_scene::Scene;
use lustre_shade::request::{FrameRequest, Method, MAX_ADAPTIVE_SAMPLES};
use lustre_trace::image::Image;
use lustre_trace::path_tracer::{PathCamera, PathScene, PathTracer};
use std::time::Instant;

/// Incident directions per pixel of the bandwidth buffer (the CLI's default; 004: 16).
pub const N_B: usize = lustre_adaptive::buffer::DEFAULT_N_B;
/// The largest N_p of a pixel (the CLI's).
pub const MAX_SAMPLES: usize = MAX_ADAPTIVE_SAMPLES as usize;
/// The colour of up-sampled surface pixels in the shaded-pixel view.
pub const UPSAMPLED_GREY: [u8; 3] = [110, 110, 110];

/// What the adaptive method shows in the 3D view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BufferView {
    /// The shaded image.
    #[default]
    Image,
    /// The bandwidth buffer b_p (cycles per pixel).
    Bandwidth,
    /// The level ℓ_p each pixel must be shaded at (shown as ℓ + 1).
    Level,
    /// N_p, the samples of each shaded pixel.
    Samples,
    /// The level each pixel was shaded at (ℓ + 1); up-sampled pixels grey.
    Shaded,
}

impl BufferView {
    /// Every view, in the panel's order.
    pub const ALL: [BufferView; 5] = [
        BufferView::Image,
        BufferView::Bandwidth,
        BufferView::Level,
        BufferView::Samples,
        BufferView::Shaded,
    ];

    /// Its name in scripts and screenshot JSON.
    pub fn name(self) -> &'static str {
        match self {
            BufferView::Image => "image",
            BufferView::Bandwidth => "bandwidth",
            BufferView::Level => "level",
            BufferView::Samples => "samples",
            BufferView::Shaded => "shaded",
        }
    }

    /// The view named `name` (see [`BufferView::name`]).
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|v| v.name() == name)
    }

    /// Its label in the panel.
    pub fn label(self) -> &'static str {
        match self {
            BufferView::Image => "shaded image",
            BufferView::Bandwidth => "bandwidth b_p",
            BufferView::Level => "level ℓ + 1",
            BufferView::Samples => "samples N_p",
            BufferView::Shaded => "shaded pixels (level; grey: up-sampled)",
        }
    }
}

/// Every sample rule, in the panel's order.
pub const SAMPLE_RULES: [SampleRule; 5] = [
    SampleRule::Constant,
    SampleRule::Coverage,
    SampleRule::Relative,
    SampleRule::RelativeMse,
    SampleRule::Absolute,
];

/// A sample rule's name (as `lustre render --sample-rule`).
pub fn rule_name(rule: SampleRule) -> &'static str {
    match rule {
        SampleRule::Constant => "constant",
        SampleRule::Coverage => "coverage",
        SampleRule::Relative => "relative",
        SampleRule::RelativeMse => "relative-mse",
        SampleRule::Absolute => "absolute",
    }
}

/// The sample rule named `name` (see [`rule_name`]).
pub fn parse_rule(name: &str) -> Option<SampleRule> {
    SAMPLE_RULES.into_iter().find(|r| rule_name(*r) == name)
}

/// The adaptive method's settings (its mean N_p is the frame's sample count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AdaptiveOptions {
    /// Image samples per cycle of b_p: 2 (Nyquist's rate) or 1 (Eq. IV.11 as printed).
    pub rate: u8,
    /// How N_p is set per pixel.
    pub rule: SampleRule,
}

impl Default for AdaptiveOptions {
    /// The CLI's defaults: rate 2, a constant N_p.
    fn default() -> Self {
        Self {
            rate: 2,
            rule: SampleRule::Constant,
        }
    }
}

/// One adaptive frame's buffers (at the G-buffer's resolution, row-major) and counts.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveMaps {
    /// G-buffer width (the frame's × k).
    pub width: usize,
    /// G-buffer height.
    pub height: usize,
    /// b_p, cycles per pixel (0 on the background).
    pub bandwidth: Vec<f64>,
    /// ℓ_p + 1 (0 on the background).
    pub level: Vec<f64>,
    /// N_p at the shaded pixels (0 elsewhere).
    pub samples: Vec<f64>,
    /// The level each pixel was shaded at, + 1 (0: up-sampled or background).
    pub shaded: Vec<f64>,
    /// Whether a surface is seen at each pixel.
    pub surface: Vec<bool>,
    /// Surface pixels.
    pub surface_pixels: usize,
    /// Pixels shaded.
    pub shaded_pixels: usize,
    /// Pixels up-sampled.
    pub upsampled_pixels: usize,
    /// Shading samples in all.
    pub samples_total: u64,
    /// The G-buffer pass, ms.
    pub gbuffer_ms: f64,
    /// The bandwidth pass (predictions, levels, sample counts, pyramids), ms.
    pub bandwidth_ms: f64,
    /// The hierarchical shading (and the k×k box filter), ms.
    pub shading_ms: f64,
    /// Building the shading context (material tables, environment bandwidth) for this scene,
    /// ms: paid by the scene's first adaptive frame only.
    pub tables_ms: f64,
    /// Whether the bandwidth pass and the shading ran on the GPU.
    pub on_gpu: (bool, bool),
    /// Why a pass ran on the CPU although a GPU was offered (a material it does not take).
    pub why_cpu: Option<String>,
}

impl AdaptiveMaps {
    /// The shaded pixels' share of the surface pixels.
    pub fn shaded_share(&self) -> f64 {
        self.shaded_pixels as f64 / self.surface_pixels.max(1) as f64
    }

    /// The buffer `view` as 8-bit RGB (`width · height` pixels) and the heat map's value range
    /// (`None` for [`BufferView::Image`], which is the frame's image).
    pub fn rgb(&self, view: BufferView) -> Option<(Vec<u8>, (f64, f64))> {
        let values = match view {
            BufferView::Image => return None,
            BufferView::Bandwidth => &self.bandwidth,
            BufferView::Level => &self.level,
            BufferView::Samples => &self.samples,
            BufferView::Shaded => &self.shaded,
        };
        let (mut rgb, scale) = heat_rgb(values);
        let scale = (scale.low, scale.high);
        if view == BufferView::Shaded {
            for (k, v) in values.iter().enumerate() {
                if *v == 0.0 && self.surface.get(k) == Some(&true) {
                    rgb[3 * k..3 * k + 3].copy_from_slice(&UPSAMPLED_GREY);
                }
            }
        }
        Some((rgb, scale))
    }
}

/// The adaptive renderer of one scene: its shading context and environment bandwidth.
pub struct AdaptiveRenderer<'a, 's> {
    ctx: ShadingContext<'a, 's>,
    env: EnvironmentBandwidth<'a>,
    tables_ms: f64,
    gpu: GpuPasses,
}

/// lustre-gpu's twins of the bandwidth pass and of the hierarchical shading, where the GPU
/// takes the scene's materials (`lustre_gpu::material::measured::EVALUATED`); `why_cpu` says why not.
#[derive(Default)]
struct GpuPasses {
    bandwidth: Option<(BandwidthScene, BandwidthPass)>,
    shading: Option<(AdaptiveScene, AdaptivePass)>,
    why_cpu: Option<String>,
}

impl GpuPasses {
    /// Both passes on the CPU, for `why`.
    fn cpu(why: String) -> Self {
        Self {
            why_cpu: Some(why),
            ..Self::default()
        }
    }

    fn new(
        gpu: &GpuContext,
        ctx: &ShadingContext,
        env: &EnvironmentBandwidth,
        scene: Option<&Scene>,
    ) -> Self {
        let mut why = vec![];
        let bandwidth = BandwidthScene::from_context(gpu, ctx, env, scene)
            .and_then(|s| Ok((s, BandwidthPass::new(gpu)?)))
            .map_err(|e| why.push(format!("bandwidth pass: {e}")))
            .ok();
        let shading = AdaptiveScene::from_context(gpu, ctx, scene)
            .and_then(|s| Ok((s, AdaptivePass::new(gpu)?)))
            .map_err(|e| why.push(format!("shading: {e}")))
            .ok();
        Self {
            bandwidth,
            shading,
            why_cpu: (!why.is_empty()).then(|| why.join("; ")),
        }
    }
}

impl<'a, 's> AdaptiveRenderer<'a, 's> {
    /// Builds the shading context of `scene` (`progress(k, n)` after each material's tables).
    /// Errors: a scene that nothing lights (no environment, no planar emitter), an emitter
    /// that is not planar, a material whose tables cannot be built.
    ///
    /// With `gpu` (the context and the scene, whose materials are the path scene's in its order), the
    /// bandwidth pass and the shading run there when it takes the scene's materials (each pass
    /// on its own; the maps say where each ran and why not the GPU) and `device` allows it
    /// ([`AdaptiveDevice::Auto`] keeps a software rasterizer off).
    pub fn new(
        scene: &'a PathScene<'s>,
        progress: &dyn Fn(usize, usize),
        gpu: Option<(&GpuContext, &Scene)>,
        device: AdaptiveDevice,
    ) -> anyhow::Result<Self> {
        let t = Instant::now();
        // The scene's planar emitters light it besides its environment (004 §IV.5.3).
        let lights = scene_lights(scene)
            .map_err(|e| anyhow::anyhow!("adaptive shading's area lights: {e}"))?;
        check_lit(scene, &lights).map_err(|e| anyhow::anyhow!("{e}: choose another method"))?;
        let options = ShadingOptions {
            // Direct lighting (the CLI's default) reads the map itself: no pyramid.
            pyramid_face: 0,
            ..ShadingOptions::default()
        };
        let mut ctx = ShadingContext::new(scene, options, progress)
            .map_err(|e| anyhow::anyhow!("adaptive shading's material tables: {e}"))?;
        ctx.lights = lights;
        let env = ctx
            .environment_bandwidth()
            .map_err(|e| anyhow::anyhow!("the environment's bandwidth: {e}"))?;
        let gpu = match (gpu, device) {
            (None, _) => GpuPasses::default(),
            (Some(_), AdaptiveDevice::Cpu) => GpuPasses::cpu("--adaptive-device cpu".into()),
            (Some((g, _)), AdaptiveDevice::Auto) if g.is_software() => GpuPasses::cpu(format!(
                "the adapter {} is a software rasterizer, slower than the CPU path \
                 (--adaptive-device gpu runs the passes on it)",
                g.describe()
            )),
            (Some((g, scene)), _) => GpuPasses::new(g, &ctx, &env, Some(scene)),
        };
        Ok(Self {
            ctx,
            env,
            tables_ms: t.elapsed().as_secs_f64() * 1e3,
            gpu,
        })
    }

    /// Renders a `size` frame from `camera` with `settings`: a k×k G-buffer per pixel (k² camera
    /// rays, k in 1..=4), the mean N_p `samples` (1..=1024), its `adaptive` rate and rule and
    /// `seed`; the frame request is validated as the adaptive method's. Returns the frame's image
    /// (box-filtered to `size`) and the buffers.
    pub fn render(
        &mut self,
        gpu: Option<&GpuContext>,
        tracer: &PathTracer,
        camera: &PathCamera,
        size: (usize, usize),
        settings: &ViewRequest,
    ) -> anyhow::Result<(Image, AdaptiveMaps)> {
        let frame = FrameRequest {
            method: Method::Adaptive,
            ..settings.frame
        };
        frame.validate()?;
        let FrameRequest { samples, seed, .. } = frame;
        let settings = settings.adaptive;
        if !matches!(settings.rate, 1 | 2) {
            anyhow::bail!("rate {} must be 1 or 2", settings.rate);
        }
        let k = frame.supersampling() as usize;
        let (gw, gh) = (size.0 * k, size.1 * k);
        let mut t = Instant::now();
        let mut lap = || {
            let ms = t.elapsed().as_secs_f64() * 1e3;
            t = Instant::now();
            ms
        };
        let g = GBuffer::render(tracer, self.ctx.scene, camera, gw, gh)?;
        let gbuffer_ms = lap();
        let options = BufferOptions {
            n_b: N_B,
            mean_samples: f64::from(samples),
            max_samples: MAX_SAMPLES,
            lighting: Lighting::Direct,
            scale: settings.rule,
            rate: f64::from(settings.rate),
            ..Default::default()
        };
        let passes = &mut self.gpu;
        let buffer = match (gpu, passes.bandwidth.as_mut()) {
            (Some(gctx), Some((scene, pass))) => {
                let (estimates, _) = pass.predict(gctx, scene, &g, &self.ctx, N_B as u32)?;
                BandwidthBuffer::assemble(&g, &estimates, options)?
            }
            _ => BandwidthBuffer::build(&g, &self.ctx, &self.env, options)?,
        };
        let bandwidth_ms = lap();
        let f = match (gpu, passes.shading.as_mut()) {
            (Some(gctx), Some((scene, pass))) => {
                pass.render(gctx, scene, &g, &buffer, None, seed)?.frame
            }
            _ => render_adaptive(&g, &self.ctx, &buffer, Lighting::Direct, seed)?,
        };
        let on_gpu = (
            gpu.is_some() && passes.bandwidth.is_some(),
            gpu.is_some() && passes.shading.is_some(),
        );
        let image = box_downsample(&f.image, k)?;
        let shading_ms = lap();
        let maps = AdaptiveMaps {
            width: gw,
            height: gh,
            bandwidth: buffer.bandwidth.clone(),
            level: level_map(&buffer.level),
            samples: f.samples.iter().map(|n| f64::from(*n)).collect(),
            shaded: level_map(&f.shaded_level),
            surface: g
                .pixels
                .iter()
                .map(|p| matches!(p, GPixel::Surface(_)))
                .collect(),
            surface_pixels: g.surface_pixels(),
            shaded_pixels: f.stats.shaded,
            upsampled_pixels: f.stats.upsampled,
            samples_total: f.stats.samples,
            gbuffer_ms,
            bandwidth_ms,
            shading_ms,
            tables_ms: self.tables_ms,
            on_gpu,
            why_cpu: self.gpu.why_cpu.clone(),
        };
        Ok((image, maps))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lustre_trace::path_tracer::PathOptions;
    use lustre_trace::reference::{film_camera, path_scene};

    #[test]
    fn names_round_trip() {
        for v in BufferView::ALL {
            assert_eq!(BufferView::parse(v.name()), Some(v));
        }
        for r in SAMPLE_RULES {
            assert_eq!(parse_rule(rule_name(r)), Some(r));
        }
        assert_eq!(BufferView::parse("mask"), None);
        assert_eq!(parse_rule("uniform"), None);
    }

    #[test]
    fn a_scene_that_nothing_lights_is_refused_by_name() {
        let mut scene = lustre_scene::builtin::preview("lambert(kd=0.5)", None).unwrap();
        scene.environment = None;
        let (ps, _) = path_scene(&scene).unwrap();
        let e = match AdaptiveRenderer::new(&ps, &|_, _| {}, None, AdaptiveDevice::Auto) {
            Ok(_) => panic!("a scene without an environment or an emitter was accepted"),
            Err(e) => e.to_string(),
        };
        assert!(e.contains("nothing lights the scene"), "{e}");
    }

    #[test]
    fn a_small_frame_has_shaded_and_upsampled_pixels_and_its_views() {
        // The material preview (a glossy sphere under the built-in sky) at 48 × 32, 2 × 2
        // G-buffer: an image, every buffer view, shaded and up-sampled pixels.
        let scene = lustre_scene::builtin::preview(
            "ggx(rho_d=0.2, rho_s=0.6, alpha=0.15, f0=0.3, f1=0.1)",
            None,
        )
        .unwrap();
        let (ps, _) = path_scene(&scene).unwrap();
        let tracer = PathTracer::new(&ps, PathOptions::default()).unwrap();
        let mut r = AdaptiveRenderer::new(&ps, &|_, _| {}, None, AdaptiveDevice::Auto).unwrap();
        let cam = film_camera(&scene.cameras[0], 48, 32).unwrap();
        let settings = ViewRequest {
            frame: FrameRequest {
                method: Method::Adaptive,
                samples: 4,
                rays: 4,
                frames: 1,
                seed: 1,
            },
            generation: 0,
            adaptive: AdaptiveOptions::default(),
        };
        let (img, maps) = r.render(None, &tracer, &cam, (48, 32), &settings).unwrap();
        assert_eq!((img.width, img.height), (48, 32));
        assert_eq!((maps.width, maps.height), (96, 64));
        assert!(img.data.iter().all(|p| p.iter().all(|c| c.is_finite())));
        assert!(
            maps.shaded_pixels > 0 && maps.upsampled_pixels > 0,
            "{maps:?}"
        );
        assert_eq!(
            maps.shaded_pixels + maps.upsampled_pixels,
            maps.surface_pixels
        );
        // Constant rule: every shaded pixel has the mean N_p.
        assert_eq!(maps.samples_total, 4 * maps.shaded_pixels as u64);
        assert!(BufferView::Image.eq(&BufferView::default()));
        assert!(maps.rgb(BufferView::Image).is_none());
        for v in &BufferView::ALL[1..] {
            let (rgb, (lo, hi)) = maps.rgb(*v).unwrap();
            assert_eq!(rgb.len(), 3 * 96 * 64);
            assert!(lo > 0.0 && hi >= lo, "{v:?}: {lo} {hi}");
        }
        let (mask, _) = maps.rgb(BufferView::Shaded).unwrap();
        let grey = mask.chunks(3).filter(|p| *p == UPSAMPLED_GREY).count();
        assert_eq!(grey, maps.upsampled_pixels);
        // Bad settings are refused by name, not a panic.
        for (samples, supersampling, rate, says) in
            [(0, 1, 2, "N_p"), (4, 5, 2, "k×k"), (4, 1, 3, "rate")]
        {
            let s = ViewRequest {
                frame: FrameRequest {
                    samples,
                    rays: supersampling * supersampling,
                    ..settings.frame
                },
                adaptive: AdaptiveOptions {
                    rate,
                    ..settings.adaptive
                },
                ..settings
            };
            let e = r.render(None, &tracer, &cam, (48, 32), &s).unwrap_err();
            assert!(e.to_string().contains(says), "{e}");
        }
    }
}
