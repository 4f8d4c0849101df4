//! Adaptive shading on the GPU (004 §IV.4): the bandwidth buffer's pyramids
//! (`adaptive_pyramid.wgsl`) and hierarchical shading with bilateral up-sampling, one dispatch
//! per level from the coarsest down (`adaptive_pass.wgsl`). CPU twins:
//! `lustre_adaptive::buffer::BandwidthBuffer::assemble`'s pyramids and
//! `lustre_adaptive::hierarchy::{render_adaptive, render_brute}` with
//! `ShadingContext::shade` (the same points, seeds and estimator, in f32).
//!
//! What stays on the CPU: the G-buffer (ray traced), the levels ℓ_p and the variance target V
//! (`BandwidthBuffer::assemble`, whose bisection on V needs every pixel's sum), then the
//! upload of ℓ_p and of each pixel's quota 4π² S_p / V. Materials are measured BRDFs the GPU
//! evaluates directly (neural BRDFs, MERL tables, RGL tensors), fitted models (SGD,
//! Cook–Torrance, Kurt: `material::fitted`) or, given the scene, its reflection materials and
//! lustre's analytic reflection models (`analytic`; [`crate::material::measured::EVALUATED`]), each
//! sampled by its tabulated CDFs (built at uv (½, ½), as the CPU's). A textured material's
//! parameters are read at the pixel's uv (`material_prepare`; the G-buffer's uv rides in the
//! surfel's n.w and wo.w), a normal map is in the G-buffer's shading frame. The lighting is
//! the environment at full resolution (`Lighting::Direct`) or its pyramid at each pixel's BRDF
//! bandwidth (`Lighting::Preconvolved`, `cube_storage`), plus area lights.

use crate::bindings::{
    buffer_entry, buffer_init, compute_pipeline, map_read, storage_entry, uniform_entry,
};
use crate::context::GpuContext;
use crate::cube_storage::{pack_pyramid, PackedPyramid};
use crate::error::{invalid, push_scope, Result};
use crate::material::kinds::sampled_kinds;
use crate::material::measured::{
    pack_tabulated, Evaluates, GpuTabulatedDims, MaterialPipelines, PackedBrdfs, EVALUATED,
    EVAL_RECORD,
};
use crate::timer::{GpuTimer, Timing};
use crate::wgsl::{AREA_LIGHT, CUBE_STORAGE, ENV_LIGHT, QMC, TYPES};
use bytemuck::Zeroable;
use glam::{DMat3, DVec3};
use lustre_adaptive::buffer::{BandwidthBuffer, NO_LEVEL};
use lustre_adaptive::gbuffer::{GBuffer, GPixel};
use lustre_adaptive::hierarchy::{AdaptiveFrame, HierarchyStats, NOT_SHADED};
use lustre_adaptive::light::AreaLight;
use lustre_adaptive::shading::ShadingContext;
use lustre_env::{Distribution1D, EnvSampler};
use lustre_scene::Scene;
use lustre_trace::image::Image;
use std::f64::consts::PI;

/// The shading pass's own WGSL (its bindings and entry point).
pub const ADAPTIVE_PASS_WGSL: &str = include_str!("adaptive.wgsl");
/// The pyramid pass's WGSL.
pub const ADAPTIVE_PYRAMID_WGSL: &str = include_str!("adaptive_pyramid.wgsl");

/// The area lights for `area_light.wgsl`, their geometry turned by `to_frame` (the identity for
/// world space): five vec4 per light (`AreaLight`), and every light's texels (RGB, and in w the
/// spatial bandwidth at the texel's centre, cycles per metre). Neither is empty: without lights
/// one unread record and texel stand in (a binding may not be empty).
pub fn pack_lights(lights: &[AreaLight], to_frame: DMat3) -> (Vec<[f32; 4]>, Vec<[f32; 4]>) {
    let mut records = vec![];
    let mut texels: Vec<[f32; 4]> = vec![];
    let v = |d: DVec3, w: f32| {
        let d = to_frame * d;
        [d.x as f32, d.y as f32, d.z as f32, w]
    };
    for l in lights {
        let (tw, th, tex) = l.texture();
        let r = l.radiance.0;
        records.extend([
            v(l.corner, tw as f32),
            v(l.edge_u, th as f32),
            v(l.edge_v, texels.len() as f32),
            [r[0] as f32, r[1] as f32, r[2] as f32, l.area() as f32],
            v(l.normal(), 0.0),
        ]);
        for (k, t) in tex.iter().enumerate() {
            let (x, y) = ((k % tw) as f64 + 0.5, (k / tw) as f64 + 0.5);
            let nu = l.bandwidth_at(x / tw as f64, y / th as f64);
            texels.push([t[0], t[1], t[2], nu as f32]);
        }
    }
    if records.is_empty() {
        records.extend([[0.0; 4]; 5]);
    }
    if texels.is_empty() {
        texels.push([0.0; 4]);
    }
    (records, texels)
}

/// `EnvDims` of `env_light.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuEnvDims {
    /// Map width in texels.
    pub width: u32,
    /// Map height in texels.
    pub height: u32,
    /// First word of the rows' distribution.
    pub rows: u32,
    /// First word of row 0's texel distribution.
    pub cols: u32,
}

/// The words of an environment sampler for `env_light.wgsl` (`env_table`) and their layout:
/// the rows' distribution, each row's distribution over its texels, the rows' solid angles. A
/// distribution of n cells is its n + 1 cumulative values, then its n probabilities (from the
/// f64 weights, so that a texel's density does not come from the difference of two f32 sums).
pub fn pack_sampler(sampler: &EnvSampler) -> (Vec<f32>, GpuEnvDims) {
    let (w, h) = (sampler.width(), sampler.height());
    let mut out = Vec::with_capacity(2 * h + 1 + h * (2 * w + 1) + h);
    let push = |out: &mut Vec<f32>, d: &Distribution1D| {
        out.extend(d.cdf().iter().map(|&c| c as f32));
        out.extend((0..d.len()).map(|k| d.probability(k) as f32));
    };
    push(&mut out, sampler.rows());
    let cols = out.len() as u32;
    for j in 0..h {
        push(&mut out, sampler.row(j));
    }
    out.extend((0..h).map(|j| sampler.row_solid_angle(j) as f32));
    let dims = GpuEnvDims {
        width: w as u32,
        height: h as u32,
        rows: 0,
        cols,
    };
    (out, dims)
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    level: u32,
    top: u32,
    seed: [u32; 2],
    lights: u32,
    max_samples: u32,
    constant: u32,
    pyramid_levels: u32,
    phase: u32,
    first: u32,
    env: GpuEnvDims,
    to_map: [[f32; 4]; 3],
    right: [f32; 4],
    up: [f32; 4],
    env_lit: u32,
    _pad: [u32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PyramidParams {
    width: u32,
    height: u32,
    level: u32,
    _pad: u32,
}

/// The most samples (and area-light points) one thread takes per dispatch: a pixel with more is
/// shaded over several dispatches, each adding its share (the same sum). Lavapipe ends every
/// loop of a shader invocation once they have run 65,535 iterations in all (llvmpipe's
/// `LP_MAX_TGSI_LOOP_ITERATIONS`), and a neural BRDF's evaluation and the samplers' searches
/// take ≈ 190 of them a sample: unchunked, a pixel's samples past the ≈ 350th were dropped
/// there.
pub const SAMPLES_PER_DISPATCH: u32 = 128;

/// `tab_base` of a material sampled by its record's own `bsdf_sample` (`NO_TABLE` in
/// adaptive_pass.wgsl).
const NO_TABLE: u32 = u32::MAX;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuMaterialSlot {
    kind: u32,
    base: u32,
    offset: u32,
    tab_base: u32,
    dims: GpuTabulatedDims,
}

/// The environment, the materials and the area lights of an adaptive-shading context,
/// uploaded once.
pub struct AdaptiveScene {
    env_texels: wgpu::Buffer,
    env_words: wgpu::Buffer,
    env: GpuEnvDims,
    to_world: DMat3,
    materials: wgpu::Buffer,
    table: wgpu::Buffer,
    lights: wgpu::Buffer,
    light_texels: wgpu::Buffer,
    fitted: wgpu::Buffer,
    /// The records' textured parameters and the textures they read.
    params: wgpu::Buffer,
    texels: wgpu::Buffer,
    tex_info: wgpu::Buffer,
    evaluates: Evaluates,
    /// The record kinds (bit mask, `measured::sampled_kinds`) of the materials sampled by their
    /// record's own model (no tabulated CDFs): the pass's variant compiles their sampling only.
    samples_records: u32,
    cube_texels: wgpu::Buffer,
    cube_levels: wgpu::Buffer,
    cube_rings: wgpu::Buffer,
    pyramid_levels: u32,
    light_count: u32,
    material_count: u32,
    /// Whether the environment lights the scene (`ShadingContext::lit_by_environment`): else
    /// a pixel takes no BRDF or environment sample, as on the CPU.
    env_lit: bool,
}

impl AdaptiveScene {
    /// Uploads `shading`'s environment (its texels times its scale, and its sampler), every
    /// material's BRDF with its tabulated CDFs (a transmissive or Dirac model, which has none,
    /// is sampled by its record's own `bsdf_sample`), and the area lights. Errors, naming the
    /// material, on one the GPU does not evaluate ([`EVALUATED`]; `PackedBrdfs::push` says
    /// why).
    ///
    /// `scene`, whose materials are the path scene's in its order, lets the GPU shade the
    /// scene's materials (textured ones read at each pixel's uv, normal-mapped ones in the
    /// G-buffer's tilted frame) and every analytic model of a spec too (`None`: measured and
    /// fitted models only).
    pub fn from_context(
        ctx: &GpuContext,
        shading: &ShadingContext,
        scene: Option<&Scene>,
    ) -> Result<Self> {
        let mut brdfs = PackedBrdfs::default();
        let mut materials = vec![];
        for (k, m) in shading.scene.materials.iter().enumerate() {
            let tables = &shading.materials[k];
            let mut packed = None;
            let scene_material = scene.and_then(|sc| sc.materials.get(k).map(|m| (sc, m)));
            m.with_bsdf([0.5, 0.5], &mut |b| {
                packed = Some(brdfs.push(b, scene_material))
            });
            let (kind, base, offset) = packed
                .unwrap_or_else(|| Err(invalid(&tables.name, "no BSDF")))
                .map_err(|e| {
                    invalid(
                        "adaptive pass",
                        format!(
                            "material {k} ({}): {e}; the GPU shades {EVALUATED} only",
                            tables.name
                        ),
                    )
                })?;
            // A transmissive or Dirac model has no tabulated CDFs (`shading::tables`): the
            // pass samples its record by the model's own `bsdf_sample`.
            let (tab_base, dims) = match &tables.sampler {
                Some(sampler) => {
                    let (words, dims) = pack_tabulated(sampler);
                    let tab_base = brdfs.table.len() as u32;
                    brdfs.table.extend(words);
                    (tab_base, dims)
                }
                None if kind == EVAL_RECORD => (NO_TABLE, GpuTabulatedDims::zeroed()),
                None => {
                    return Err(invalid(
                        "adaptive pass",
                        format!(
                            "material {k} ({}) has neither tabulated CDFs nor a record to \
                             sample",
                            tables.name
                        ),
                    ))
                }
            };
            materials.push(GpuMaterialSlot {
                kind,
                base,
                offset: offset.to_bits(),
                tab_base,
                dims,
            });
        }
        if materials.is_empty() {
            return Err(invalid("adaptive pass", "a scene without materials"));
        }
        if brdfs.table.len() > u32::MAX as usize {
            return Err(invalid(
                "adaptive pass",
                format!("{} words of BRDF tables", brdfs.table.len()),
            ));
        }
        // Every material's BRDF and sampling tables share one binding (an anisotropic BRDF's
        // tabulated CDFs, per view azimuth, take 16.8 MB with the default options).
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        if 4 * brdfs.table.len() > limit {
            let sizes: Vec<String> = shading
                .materials
                .iter()
                .enumerate()
                .map(|(k, t)| {
                    let words = t.sampler.as_ref().map_or(0, |s| {
                        s.table_count() * (2 * s.options().theta_bins * s.phi_cells() + 1)
                    });
                    format!(
                        "material {k} ({}): {:.1} MB",
                        t.name,
                        4.0 * words as f64 / 1e6
                    )
                })
                .collect();
            return Err(invalid(
                "adaptive pass",
                format!(
                    "the BRDF tables take {:.1} MB, beyond this GPU's {:.1} MB per binding \
                     (sampling tables: {})",
                    4.0 * brdfs.table.len() as f64 / 1e6,
                    limit as f64 / 1e6,
                    sizes.join(", ")
                ),
            ));
        }
        let (texture_texels, tex_info) = brdfs.textures(scene, limit)?;
        let env = &*shading.env;
        let scale = env.scale() as f32;
        let texels: Vec<[f32; 4]> = env
            .map()
            .data
            .iter()
            .map(|p| [p[0] * scale, p[1] * scale, p[2] * scale, 0.0])
            .collect();
        let (env_words, env_dims) = pack_sampler(env.sampler());
        let (lights, light_texels) = pack_lights(&shading.lights, DMat3::IDENTITY);
        // The pre-convolved pyramid when the context built one (one unread texel else).
        let pyramid = shading.pyramid.as_ref().map(pack_pyramid);
        let pyramid_levels = pyramid.as_ref().map_or(0, |p| p.levels.len() as u32);
        let pyramid = pyramid.unwrap_or(PackedPyramid {
            texels: vec![[0.0; 4]],
            levels: vec![[0; 4]],
            ring: vec![[0; 4]],
        });
        let storage = wgpu::BufferUsages::STORAGE;
        let init = |label, bytes: &[u8]| buffer_init(ctx, label, bytes, storage);
        Ok(Self {
            cube_texels: init(
                "adaptive pyramid texels",
                bytemuck::cast_slice(&pyramid.texels),
            ),
            cube_levels: init(
                "adaptive pyramid levels",
                bytemuck::cast_slice(&pyramid.levels),
            ),
            cube_rings: init(
                "adaptive pyramid rings",
                bytemuck::cast_slice(&pyramid.ring),
            ),
            pyramid_levels,
            env_texels: init("adaptive env texels", bytemuck::cast_slice(&texels)),
            env_words: init("adaptive env sampler", bytemuck::cast_slice(&env_words)),
            env: env_dims,
            to_world: env.to_world(),
            materials: init("adaptive materials", bytemuck::cast_slice(&materials)),
            table: init(
                "adaptive BRDF tables",
                bytemuck::cast_slice(&brdfs.table_or_zero()),
            ),
            lights: init("adaptive lights", bytemuck::cast_slice(&lights)),
            light_texels: init("adaptive light texels", bytemuck::cast_slice(&light_texels)),
            fitted: init(
                "adaptive fitted models",
                bytemuck::cast_slice(&brdfs.fitted_or_zero()),
            ),
            params: init(
                "adaptive material parameters",
                bytemuck::cast_slice(&brdfs.params_or_zero()),
            ),
            texels: init("adaptive textures", bytemuck::cast_slice(&texture_texels)),
            tex_info: init("adaptive texture sizes", bytemuck::cast_slice(&tex_info)),
            evaluates: brdfs.evaluates(),
            samples_records: materials
                .iter()
                .filter(|m| m.tab_base == NO_TABLE)
                .filter_map(|m| brdfs.fitted.get(m.base as usize))
                .fold(0, |mask, b| mask | sampled_kinds(b.kind)),
            light_count: shading.lights.len() as u32,
            env_lit: shading.lit_by_environment(),
            material_count: materials.len() as u32,
        })
    }
}

/// The compiled passes.
pub struct AdaptivePass {
    shade: MaterialPipelines,
    pyramid: wgpu::ComputePipeline,
    pyramid_layout: wgpu::BindGroupLayout,
    timer: GpuTimer,
}

/// What one GPU frame did and took.
#[derive(Clone, Debug)]
pub struct GpuAdaptiveFrame {
    /// The frame, as `render_adaptive` returns it.
    pub frame: AdaptiveFrame,
    /// The passes' time (uploads of the G-buffer and the buffer, the pyramids, every level's
    /// dispatch; not the read-back).
    pub timing: Timing,
}

impl AdaptivePass {
    /// Compiles both passes.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let mut entries = vec![uniform_entry(0)];
        entries.extend((1..=9).map(|b| storage_entry(b, true)));
        entries.extend([
            storage_entry(10, false),
            storage_entry(11, false),
            storage_entry(12, true),
            storage_entry(13, true),
            storage_entry(14, true),
            storage_entry(15, true),
            storage_entry(16, false),
            storage_entry(17, false),
        ]);
        let shade = MaterialPipelines::new(
            ctx,
            "adaptive pass",
            &[&TYPES, &QMC, &ENV_LIGHT, &CUBE_STORAGE, &AREA_LIGHT],
            ADAPTIVE_PASS_WGSL,
            (12, 18),
            entries,
        )?;
        let (pyramid, pyramid_layout) = compute_pipeline(
            ctx,
            "adaptive pyramid",
            "adaptive pyramid",
            ADAPTIVE_PYRAMID_WGSL,
            &[
                uniform_entry(0),
                storage_entry(1, false),
                storage_entry(2, false),
            ],
        )?;
        Ok(Self {
            shade,
            pyramid,
            pyramid_layout,
            timer: GpuTimer::new(ctx),
        })
    }

    /// The GPU twin of `render_adaptive(g, shading, buffer, lighting, seed)`: the pyramids of
    /// `buffer`'s levels and quotas, then every level's shading and up-sampling. `lod` is
    /// `None` for `Lighting::Direct`; for `Lighting::Preconvolved`, where a BRDF bandwidth
    /// reads (`ShadingContext::preconvolved_lod`: a pyramid level, or `None` for the map itself),
    /// asked at each pixel's largest (`buffer.brdf_max`); it errors when the scene was uploaded
    /// without a pyramid.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        scene: &AdaptiveScene,
        g: &GBuffer,
        buffer: &BandwidthBuffer,
        lod: Option<&dyn Fn(f64) -> Option<f64>>,
        seed: u64,
    ) -> Result<GpuAdaptiveFrame> {
        if lod.is_some() && scene.pyramid_levels == 0 {
            return Err(invalid(
                "adaptive pass",
                "pre-convolved shading of a scene uploaded without its pyramid (build the \
                 shading context with a pyramid face)",
            ));
        }
        if g.width != buffer.width || g.height != buffer.height {
            return Err(invalid(
                "adaptive pass",
                format!(
                    "G-buffer of {} × {} with a bandwidth buffer of {} × {}",
                    g.width, g.height, buffer.width, buffer.height
                ),
            ));
        }
        let quota: Vec<f32> = buffer
            .variance
            .iter()
            .map(|v| (4.0 * PI * PI * v / buffer.target) as f32)
            .collect();
        let level: Vec<u32> = buffer.level.iter().map(|&l| u32::from(l)).collect();
        // Per level: N_p when the rule sets it without the variance (0: from the quotas).
        let constant = (0..buffer.levels)
            .map(|k| {
                buffer
                    .constant
                    .map_or(0, |_| buffer.samples(k, 0, 0) as u32)
            })
            .collect();
        // −1: the map itself.
        let lods = match lod {
            Some(f) => (buffer.brdf_max.iter())
                .map(|&nu| f(nu).map_or(-1.0, |l| l as f32))
                .collect(),
            None => vec![-1.0; g.pixels.len()],
        };
        self.run(
            ctx,
            scene,
            g,
            Levels {
                count: buffer.levels,
                level,
                quota,
                constant,
                max_samples: buffer.max_samples as u32,
                lods,
            },
            seed,
        )
    }

    /// The GPU twin of `render_brute(g, shading, n, seed)`: one level, every surface pixel
    /// shaded with `n` samples.
    pub fn render_brute(
        &mut self,
        ctx: &GpuContext,
        scene: &AdaptiveScene,
        g: &GBuffer,
        n: usize,
        seed: u64,
    ) -> Result<GpuAdaptiveFrame> {
        if n == 0 || n > u32::MAX as usize {
            return Err(invalid(
                "adaptive pass",
                format!("brute-force shading with {n} samples per pixel"),
            ));
        }
        let pixels = g.width * g.height;
        self.run(
            ctx,
            scene,
            g,
            Levels {
                count: 1,
                level: vec![0; pixels],
                quota: vec![0.0; pixels],
                constant: vec![n as u32],
                max_samples: n as u32,
                lods: vec![-1.0; pixels],
            },
            seed,
        )
    }

    fn run(
        &mut self,
        ctx: &GpuContext,
        scene: &AdaptiveScene,
        g: &GBuffer,
        levels: Levels,
        seed: u64,
    ) -> Result<GpuAdaptiveFrame> {
        let (w, h) = (g.width, g.height);
        if w == 0 || h == 0 || levels.count == 0 || levels.count > 16 {
            return Err(invalid(
                "adaptive pass",
                format!("a {w} × {h} frame with {} levels", levels.count),
            ));
        }
        let mut surfels: Vec<[f32; 4]> = Vec::with_capacity(w * h * 5);
        for (p, &lod) in g.pixels.iter().zip(&levels.lods) {
            match p {
                GPixel::Surface(s) => {
                    if s.material >= scene.material_count as usize {
                        return Err(invalid(
                            "adaptive pass",
                            format!(
                                "material {} of {} uploaded",
                                s.material, scene.material_count
                            ),
                        ));
                    }
                    let v = |d: DVec3, w: f32| [d.x as f32, d.y as f32, d.z as f32, w];
                    surfels.push(v(s.position, s.depth as f32));
                    surfels.push(v(s.frame.t, f32::from_bits(s.material as u32)));
                    surfels.push(v(s.frame.b, lod));
                    // The texture coordinates in n.w and wo.w (material_prepare).
                    surfels.push(v(s.frame.n, s.uv[0] as f32));
                    surfels.push(v(s.wo, s.uv[1] as f32));
                }
                GPixel::Background(_) => {
                    surfels.push([0.0; 4]);
                    surfels.push([0.0, 0.0, 0.0, f32::from_bits(u32::MAX)]);
                    surfels.extend([[0.0; 4]; 3]);
                }
            }
        }
        // Level 0 of the pyramids, then room for the coarser levels.
        let sizes: Vec<usize> = (0..levels.count)
            .map(|k| w.div_ceil(1 << k) * h.div_ceil(1 << k))
            .collect();
        let total: usize = sizes.iter().sum();
        // The largest N_p `samples_at` can give from the quotas (the max-filtered pyramid holds
        // level 0's maxima).
        let max_samples = levels.max_samples.max(1);
        let most_samples = levels
            .quota
            .iter()
            .filter(|q| **q > 0.0)
            .map(|q| q.min(max_samples as f32).ceil() as u32)
            .fold(1, u32::max)
            .min(max_samples);
        let mut min_level = levels.level;
        min_level.resize(total, u32::from(NO_LEVEL));
        let mut quota = levels.quota;
        quota.resize(total, 0.0);
        let m = self.to_map(scene);
        let cam = &g.camera;
        let v4 = |d: DVec3| [d.x as f32, d.y as f32, d.z as f32, 0.0];
        let base = Params {
            width: w as u32,
            height: h as u32,
            level: 0,
            top: (levels.count - 1) as u32,
            seed: [seed as u32, (seed >> 32) as u32],
            lights: scene.light_count,
            max_samples: levels.max_samples.max(1),
            constant: 0,
            pyramid_levels: scene.pyramid_levels,
            phase: 0,
            first: 0,
            env: scene.env,
            to_map: m,
            right: v4(cam.right),
            up: v4(cam.up),
            env_lit: u32::from(scene.env_lit),
            _pad: [0; 3],
        };

        self.timer.start(ctx)?;
        let scope = push_scope(ctx);
        let storage = wgpu::BufferUsages::STORAGE;
        let surfel_buf = buffer_init(
            ctx,
            "adaptive surfels",
            bytemuck::cast_slice(&surfels),
            storage,
        );
        let level_buf = buffer_init(
            ctx,
            "adaptive min level",
            bytemuck::cast_slice(&min_level),
            storage,
        );
        let quota_buf = buffer_init(
            ctx,
            "adaptive max quota",
            bytemuck::cast_slice(&quota),
            storage,
        );
        let values = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("adaptive values"),
            size: (w * h * 16) as u64,
            usage: storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let shaded = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("adaptive shaded"),
            size: (w * h * 8) as u64,
            usage: storage | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("adaptive pass"),
            });
        // Zeros: no value yet (w = 0), nothing shaded.
        enc.clear_buffer(&values, 0, None);
        enc.clear_buffer(&shaded, 0, None);
        let pyramid_groups: Vec<(wgpu::BindGroup, (u32, u32))> = (1..levels.count)
            .map(|k| {
                let p = PyramidParams {
                    width: w as u32,
                    height: h as u32,
                    level: k as u32,
                    _pad: 0,
                };
                let ub = buffer_init(
                    ctx,
                    "adaptive pyramid params",
                    bytemuck::bytes_of(&p),
                    wgpu::BufferUsages::UNIFORM,
                );
                let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("adaptive pyramid"),
                    layout: &self.pyramid_layout,
                    entries: &[
                        buffer_entry(0, &ub),
                        buffer_entry(1, &level_buf),
                        buffer_entry(2, &quota_buf),
                    ],
                });
                let size = (w.div_ceil(1 << k) as u32, h.div_ceil(1 << k) as u32);
                (group, size)
            })
            .collect();
        let (shade_pipeline, shade_layout) =
            self.shade
                .get(ctx, scene.evaluates, scene.samples_records)?;
        let queue = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("adaptive queue"),
            size: (w * h * 4) as u64,
            usage: storage,
            mapped_at_creation: false,
        });
        let counts = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("adaptive queue counts"),
            size: 4 * 16,
            usage: storage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        enc.clear_buffer(&counts, 0, None);
        // Per level, coarsest first: its classification, then its shading in dispatches of
        // at most SAMPLES_PER_DISPATCH samples (and area-light points) per pixel, each a 1-D
        // dispatch over the level's grid points.
        let dispatches = |k: usize| {
            let n = if levels.constant[k] > 0 {
                levels.constant[k]
            } else {
                most_samples
            };
            let points = u64::from(n.max(1)) * (1 + u64::from(scene.light_count));
            points.div_ceil(u64::from(SAMPLES_PER_DISPATCH)) as u32
        };
        let shade_groups: Vec<(wgpu::BindGroup, u32)> = (0..levels.count)
            .rev()
            .flat_map(|k| {
                std::iter::once((k, 0u32, 0u32))
                    .chain((0..dispatches(k)).map(move |c| (k, 1, c * SAMPLES_PER_DISPATCH)))
            })
            .map(|(k, phase, first)| {
                let p = Params {
                    level: k as u32,
                    phase,
                    first,
                    constant: levels.constant[k],
                    ..base
                };
                let ub = buffer_init(
                    ctx,
                    "adaptive params",
                    bytemuck::bytes_of(&p),
                    wgpu::BufferUsages::UNIFORM,
                );
                let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("adaptive pass"),
                    layout: shade_layout,
                    entries: &[
                        buffer_entry(0, &ub),
                        buffer_entry(1, &surfel_buf),
                        buffer_entry(2, &scene.env_texels),
                        buffer_entry(3, &scene.env_words),
                        buffer_entry(4, &scene.materials),
                        buffer_entry(5, &scene.table),
                        buffer_entry(6, &scene.lights),
                        buffer_entry(7, &scene.light_texels),
                        buffer_entry(8, &level_buf),
                        buffer_entry(9, &quota_buf),
                        buffer_entry(10, &values),
                        buffer_entry(11, &shaded),
                        buffer_entry(12, &scene.fitted),
                        buffer_entry(13, &scene.cube_texels),
                        buffer_entry(14, &scene.cube_levels),
                        buffer_entry(15, &scene.cube_rings),
                        buffer_entry(16, &queue),
                        buffer_entry(17, &counts),
                        buffer_entry(18, &scene.params),
                        buffer_entry(19, &scene.texels),
                        buffer_entry(20, &scene.tex_info),
                    ],
                });
                let points = (w.div_ceil(1 << k) * h.div_ceil(1 << k)) as u32;
                (group, points)
            })
            .collect();
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("adaptive pass"),
                timestamp_writes: None,
            });
            // Each dispatch reads what the one before it wrote (wgpu orders them).
            pass.set_pipeline(&self.pyramid);
            for (group, (gw, gh)) in &pyramid_groups {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(gw.div_ceil(8), gh.div_ceil(8), 1);
            }
            pass.set_pipeline(shade_pipeline);
            for (group, points) in &shade_groups {
                pass.set_bind_group(0, group, &[]);
                let groups = points.div_ceil(64);
                pass.dispatch_workgroups(groups.min(65_535), groups.div_ceil(65_535), 1);
            }
        }
        ctx.queue.submit([enc.finish()]);
        let timing = self.timer.stop(ctx)?;
        let copy = |src: &wgpu::Buffer, label: &'static str| -> wgpu::Buffer {
            let size = src.size();
            let dst = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut enc = ctx
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
            enc.copy_buffer_to_buffer(src, 0, &dst, 0, size);
            ctx.queue.submit([enc.finish()]);
            dst
        };
        let values_dst = copy(&values, "adaptive values readback");
        let shaded_dst = copy(&shaded, "adaptive shaded readback");
        let value_bytes = map_read(ctx, &values_dst, "adaptive pass", scope)?;
        let scope = push_scope(ctx);
        let shaded_bytes = map_read(ctx, &shaded_dst, "adaptive pass", scope)?;
        let value_px = bytemuck::cast_slice::<u8, [f32; 4]>(&value_bytes);
        let shaded_px = bytemuck::cast_slice::<u8, [u32; 2]>(&shaded_bytes);
        let frame = assemble(g, value_px, shaded_px, levels.count)?;
        Ok(GpuAdaptiveFrame { frame, timing })
    }

    /// The rows of the rotation taking world directions to the map's (the columns of its
    /// to-world rotation).
    fn to_map(&self, scene: &AdaptiveScene) -> [[f32; 4]; 3] {
        let m = scene.to_world.transpose();
        let row = |r: DVec3| [r.x as f32, r.y as f32, r.z as f32, 0.0];
        [row(m.row(0)), row(m.row(1)), row(m.row(2))]
    }
}

/// A frame's level-0 levels and quotas, before the pyramids.
struct Levels {
    count: usize,
    level: Vec<u32>,
    quota: Vec<f32>,
    /// Per level, N_p when it does not come from the quotas (else 0).
    constant: Vec<u32>,
    max_samples: u32,
    /// Per pixel, the pre-convolved pyramid level (< 0: direct lighting).
    lods: Vec<f32>,
}

/// The frame from the read-back: surface pixels take the GPU's values, the background the
/// G-buffer's radiance.
fn assemble(
    g: &GBuffer,
    values: &[[f32; 4]],
    shaded: &[[u32; 2]],
    levels: usize,
) -> Result<AdaptiveFrame> {
    let mut stats = HierarchyStats {
        per_level: vec![(0, 0); levels],
        ..Default::default()
    };
    let n = g.pixels.len();
    let mut shaded_level = vec![NOT_SHADED; n];
    let mut samples = vec![0u32; n];
    let mut data = Vec::with_capacity(n);
    for (k, p) in g.pixels.iter().enumerate() {
        match p {
            GPixel::Background(l) => data.push(l.to_f32()),
            GPixel::Surface(_) => {
                let [r, gr, b, _] = values[k];
                data.push([r, gr, b]);
                let [lv, ns] = shaded[k];
                if lv < u32::from(NOT_SHADED) {
                    shaded_level[k] = lv as u8;
                    samples[k] = ns;
                    stats.shaded += 1;
                    stats.samples += u64::from(ns);
                    if let Some(e) = stats.per_level.get_mut(lv as usize) {
                        e.0 += 1;
                    }
                } else {
                    stats.upsampled += 1;
                    let x = k % g.width;
                    let y = k / g.width;
                    // The level of its grid: the largest 2^k dividing both coordinates.
                    let l = (x | y | (1 << (levels - 1))).trailing_zeros() as usize;
                    if let Some(e) = stats.per_level.get_mut(l.min(levels - 1)) {
                        e.1 += 1;
                    }
                }
            }
        }
    }
    Ok(AdaptiveFrame {
        image: Image::from_data(g.width, g.height, data)
            .map_err(|e| invalid("adaptive frame", e.to_string()))?,
        shaded_level,
        samples,
        stats,
    })
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "adaptive",
    shaders: &[
        ("adaptive.wgsl", ADAPTIVE_PASS_WGSL),
        ("adaptive_pyramid.wgsl", ADAPTIVE_PYRAMID_WGSL),
    ],
    inputs: &[
        crate::passes::Resource::Bandwidth,
        crate::passes::Resource::ShadingPoints,
        crate::passes::Resource::Materials,
        crate::passes::Resource::Environment,
        crate::passes::Resource::AreaLights,
    ],
    outputs: &[crate::passes::Resource::AdaptiveFrame],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shader_takes_the_same_share_per_dispatch_and_the_same_no_table_mark() {
        let share = format!("const SAMPLES_PER_DISPATCH: u32 = {SAMPLES_PER_DISPATCH}u;");
        assert!(ADAPTIVE_PASS_WGSL.contains(&share), "{share}");
        assert_eq!(NO_TABLE, 0xffff_ffff);
        assert!(ADAPTIVE_PASS_WGSL.contains("const NO_TABLE: u32 = 0xffffffffu;"));
    }
}
