//! The bandwidth pass of 004 §IV.4.1 on the GPU (`bandwidth_pass.wgsl`): per G-buffer pixel,
//! the one-bounce bandwidth and variance sums from n_b directions under a distant environment,
//! and from n_b points of each textured area light (§IV.5.3). Its CPU twin is
//! `lustre_adaptive::buffer::predict_pixels` (built on `lustre_freq::pixel::predict`); the
//! levels and sample counts are assembled from its output on the CPU
//! (`BandwidthBuffer::assemble`), the pyramids on the GPU (`adaptive_pass`). Materials are
//! measured BRDFs evaluated directly (neural BRDFs, 004's scenes; MERL tables; RGL tensors),
//! fitted models (SGD, Cook–Torrance, Kurt) and, given the scene's materials, lustre's analytic
//! reflection models (`analytic`; [`crate::material::measured::EVALUATED`]).

use crate::bindings::{buffer_entry, buffer_init, map_read, storage_entry, uniform_entry};
use crate::context::GpuContext;
use crate::error::{invalid, push_scope, Result};
use crate::material::measured::{
    Evaluates, MaterialPipelines, MeasuredBrdf, PackedBrdfs, EVALUATED,
};
use crate::passes::adaptive::pack_lights;
use crate::passes::gbuffer::PackedTextures;
use crate::timer::{GpuTimer, Timing};
use crate::wgsl::{AREA_LIGHT, ENV_LIGHT, FREQUENCY, TYPES};
use glam::DVec3;
use lustre_adaptive::buffer::PixelEstimate;
use lustre_adaptive::gbuffer::{GBuffer, GPixel};
use lustre_adaptive::shading::ShadingContext;
use lustre_env::EquirectMap;
use lustre_freq::brdf::{BrdfBandwidth, BrdfBandwidthOptions};
use lustre_freq::pixel::{EnvironmentBandwidth, PixelPrediction};
use lustre_freq::transport::Bandwidth;
use lustre_scene::Scene;

/// The pass's own WGSL (its bindings and entry point).
pub const BANDWIDTH_PASS_WGSL: &str = include_str!("bandwidth.wgsl");

/// One pixel for the pass: the shading frame and the direction to the eye in the map's frame,
/// the depth (distance to the eye), the curvature and the material; `None` for the background.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandwidthPixel {
    /// Position (the map's frame, as the lights are uploaded).
    pub position: DVec3,
    /// Tangent, bitangent, normal.
    pub frame: (DVec3, DVec3, DVec3),
    /// Unit direction to the eye.
    pub wo: DVec3,
    /// Distance to the eye.
    pub depth: f64,
    /// Curvature (1/m).
    pub curvature: f64,
    /// The spatial bandwidth of the material's textures (cycles per metre; 0 untextured).
    pub texture: f64,
    /// Index into the pass's materials.
    pub material: u32,
    /// Texture coordinates (a textured material's parameters are read there).
    pub uv: [f64; 2],
}

/// `Prediction` of the pass (read back).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuPrediction {
    /// (ν_s, ν_a) at the eye (Eq. IV.6).
    pub bandwidth: [f32; 2],
    /// Σ (ν_a^i + ν_ρa^i) χ_i² (Eq. IV.9).
    pub variance: f32,
    /// Σ 2 ν_ρa^i χ_i² (Eq. IV.10).
    pub variance_preconvolved: f32,
    /// π / n_b Σ χ_i.
    pub radiance: f32,
    /// The BRDF's largest bandwidth over the directions and the mirror direction.
    pub brdf_max: f32,
    /// Σ λ_i.
    pub weight: f32,
    _pad: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    pixels: u32,
    n_b: u32,
    env_width: u32,
    env_height: u32,
    incident: u32,
    out: u32,
    lights: u32,
    first: u32,
}

/// The most paths (environment directions and area-light points) one thread takes per
/// dispatch: a pixel's n_b (1 + lights) paths are taken over several dispatches, their sums
/// carried between them. Lavapipe ends every loop of a shader invocation once they have run
/// 65,535 iterations in all (llvmpipe's `LP_MAX_TGSI_LOOP_ITERATIONS`): in one dispatch, n_b =
/// 1024 lost paths there.
pub const DIRECTIONS_PER_DISPATCH: u32 = 128;

/// The environment and the materials, uploaded once.
pub struct BandwidthScene {
    environment: wgpu::Buffer,
    env_size: (u32, u32),
    materials: wgpu::Buffer,
    table: wgpu::Buffer,
    brdf_bandwidth: wgpu::Buffer,
    fitted: wgpu::Buffer,
    /// The records' textured parameters and the textures they read.
    params: wgpu::Buffer,
    texels: wgpu::Buffer,
    tex_info: wgpu::Buffer,
    evaluates: Evaluates,
    lights: wgpu::Buffer,
    light_texels: wgpu::Buffer,
    light_count: u32,
    material_count: u32,
    grid: (u32, u32),
}

/// The compiled pass.
pub struct BandwidthPass {
    pipelines: MaterialPipelines,
    timer: GpuTimer,
}

impl BandwidthScene {
    /// Uploads `map` with its per-texel bandwidth (`lustre_freq::environment::angular_bandwidth`)
    /// and each material's measured BRDF and bandwidth table (every table on the same grids);
    /// no area light.
    pub fn new(
        ctx: &GpuContext,
        map: &EquirectMap,
        map_bandwidth: &[f64],
        materials: &[(MeasuredBrdf, &BrdfBandwidth)],
    ) -> Result<Self> {
        let mut packed = Packed::default();
        for (k, (brdf, b)) in materials.iter().enumerate() {
            let record = brdf.pack(&mut packed.brdfs.table);
            packed.push(k, record, b)?;
        }
        // No area light (one unread record), no texture (one unread texel).
        (packed.lights, packed.light_texels) = pack_lights(&[], glam::DMat3::IDENTITY);
        packed.textures = packed.brdfs.textures(None, 0)?;
        Self::upload(ctx, map, 1.0, map_bandwidth, packed)
    }

    /// The environment, materials and area lights of an adaptive-shading context: every
    /// material must be one the GPU evaluates ([`crate::material::measured::EVALUATED`]; the error names
    /// the first that is not).
    /// `scene`: as [`crate::passes::adaptive::AdaptiveScene::from_context`]'s.
    pub fn from_context(
        ctx: &GpuContext,
        shading: &ShadingContext,
        env: &EnvironmentBandwidth,
        scene: Option<&Scene>,
    ) -> Result<Self> {
        let mut packed = Packed::default();
        for (k, m) in shading.scene.materials.iter().enumerate() {
            let tables = &shading.materials[k];
            let mut brdf = None;
            let scene_material = scene.and_then(|sc| sc.materials.get(k).map(|m| (sc, m)));
            m.with_bsdf([0.5, 0.5], &mut |b| {
                brdf = Some(packed.brdfs.push(b, scene_material))
            });
            let brdf = brdf
                .unwrap_or_else(|| Err(invalid(&tables.name, "no BSDF")))
                .map_err(|e| {
                    invalid(
                        "bandwidth pass",
                        format!(
                            "material {k} ({}): {e}; the GPU bandwidth pass evaluates {EVALUATED} \
                             only",
                            tables.name
                        ),
                    )
                })?;
            packed.push(k, brdf, &tables.bandwidth)?;
        }
        // The lights in the map's frame, as the pixels.
        (packed.lights, packed.light_texels) =
            pack_lights(&shading.lights, shading.env.to_world().transpose());
        packed.light_count = shading.lights.len() as u32;
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        packed.textures = packed.brdfs.textures(scene, limit)?;
        Self::upload(ctx, &env.map, env.scale, &env.bandwidth, packed)
    }

    /// `map`'s texels times `scale` with their bandwidth, and the packed materials and lights.
    fn upload(
        ctx: &GpuContext,
        map: &EquirectMap,
        scale: f64,
        map_bandwidth: &[f64],
        packed: Packed,
    ) -> Result<Self> {
        if map_bandwidth.len() != map.width * map.height {
            return Err(invalid(
                "map bandwidth",
                format!(
                    "{} values for a {} × {} map",
                    map_bandwidth.len(),
                    map.width,
                    map.height
                ),
            ));
        }
        let Some(grid) = packed.grid else {
            return Err(invalid(
                "materials",
                "the bandwidth pass needs one material",
            ));
        };
        let texels: Vec<[f32; 4]> = map
            .data
            .iter()
            .zip(map_bandwidth)
            .map(|(p, &b)| {
                let k = scale as f32;
                [p[0] * k, p[1] * k, p[2] * k, b as f32]
            })
            .collect();
        let storage = wgpu::BufferUsages::STORAGE;
        Ok(Self {
            environment: buffer_init(ctx, "bandwidth env", bytemuck::cast_slice(&texels), storage),
            env_size: (map.width as u32, map.height as u32),
            materials: buffer_init(
                ctx,
                "bandwidth materials",
                bytemuck::cast_slice(&packed.ids),
                storage,
            ),
            table: buffer_init(
                ctx,
                "bandwidth BRDFs",
                bytemuck::cast_slice(&packed.brdfs.table_or_zero()),
                storage,
            ),
            fitted: buffer_init(
                ctx,
                "bandwidth fitted models",
                bytemuck::cast_slice(&packed.brdfs.fitted_or_zero()),
                storage,
            ),
            brdf_bandwidth: buffer_init(
                ctx,
                "brdf bandwidth",
                bytemuck::cast_slice(&packed.bandwidth),
                storage,
            ),
            params: buffer_init(
                ctx,
                "bandwidth material parameters",
                bytemuck::cast_slice(&packed.brdfs.params_or_zero()),
                storage,
            ),
            texels: buffer_init(
                ctx,
                "bandwidth textures",
                bytemuck::cast_slice(&packed.textures.0),
                storage,
            ),
            tex_info: buffer_init(
                ctx,
                "bandwidth texture sizes",
                bytemuck::cast_slice(&packed.textures.1),
                storage,
            ),
            evaluates: packed.brdfs.evaluates(),
            light_count: packed.light_count,
            lights: buffer_init(
                ctx,
                "bandwidth lights",
                bytemuck::cast_slice(&packed.lights),
                storage,
            ),
            light_texels: buffer_init(
                ctx,
                "bandwidth light texels",
                bytemuck::cast_slice(&packed.light_texels),
                storage,
            ),
            material_count: packed.ids.len() as u32,
            grid: (grid.incident as u32, grid.out as u32),
        })
    }
}

/// The materials' and the lights' words on their way to the GPU.
#[derive(Default)]
struct Packed {
    ids: Vec<[u32; 4]>,
    brdfs: PackedBrdfs,
    bandwidth: Vec<f32>,
    grid: Option<BrdfBandwidthOptions>,
    /// `adaptive_pass::pack_lights`'s records and texels.
    lights: Vec<[f32; 4]>,
    light_texels: Vec<[f32; 4]>,
    light_count: u32,
    /// The textures the records' parameters read (`PackedBrdfs::textures`).
    textures: PackedTextures,
}

impl Packed {
    /// Appends material `k` (its BRDF's record, already packed); errors when its bandwidth
    /// table's grids differ from the first's.
    fn push(&mut self, k: usize, brdf: (u32, u32, f32), b: &BrdfBandwidth) -> Result<()> {
        let grid = *self.grid.get_or_insert(b.options);
        if b.options != grid {
            return Err(invalid(
                "BRDF bandwidth",
                format!(
                    "material {k}: its table's grids {:?} differ from the first material's {grid:?}",
                    b.options
                ),
            ));
        }
        let (kind, base, offset) = brdf;
        self.ids
            .push([kind, base, self.bandwidth.len() as u32, offset.to_bits()]);
        self.bandwidth.extend(b.data.iter().map(|&v| v as f32));
        Ok(())
    }
}

impl BandwidthPass {
    /// The pass's pixels of `g`: its surface pixels turned into the map's frame, with their
    /// textures' bandwidth ([`ShadingContext::texture_bandwidth`]); `None` for the background.
    pub fn pixels(g: &GBuffer, shading: &ShadingContext) -> Vec<Option<BandwidthPixel>> {
        let to_local = shading.env.to_world().transpose();
        g.pixels
            .iter()
            .map(|p| match p {
                GPixel::Surface(s) => Some(BandwidthPixel {
                    position: to_local * s.position,
                    frame: (
                        to_local * s.frame.t,
                        to_local * s.frame.b,
                        to_local * s.frame.n,
                    ),
                    wo: to_local * s.wo,
                    depth: s.depth,
                    curvature: s.curvature,
                    texture: shading.texture_bandwidth(s),
                    material: s.material as u32,
                    uv: s.uv,
                }),
                GPixel::Background(_) => None,
            })
            .collect()
    }

    /// The GPU twin of `lustre_adaptive::buffer::predict_pixels`: the pixels of `g` (turned into
    /// the map's frame) through [`BandwidthPass::run`].
    pub fn predict(
        &mut self,
        ctx: &GpuContext,
        scene: &BandwidthScene,
        g: &GBuffer,
        shading: &ShadingContext,
        n_b: u32,
    ) -> Result<(Vec<Option<PixelEstimate>>, Timing)> {
        let pixels = Self::pixels(g, shading);
        let (out, timing) = self.run(ctx, scene, &pixels, n_b)?;
        let estimates = pixels
            .iter()
            .zip(&out)
            .map(|(p, o)| {
                p.map(|_| PixelEstimate {
                    prediction: PixelPrediction {
                        bandwidth: Bandwidth::new(
                            f64::from(o.bandwidth[0]),
                            f64::from(o.bandwidth[1]),
                        ),
                        variance: f64::from(o.variance),
                        variance_preconvolved: f64::from(o.variance_preconvolved),
                        radiance: f64::from(o.radiance),
                        weight: f64::from(o.weight),
                    },
                    brdf_max: f64::from(o.brdf_max),
                })
            })
            .collect();
        Ok((estimates, timing))
    }

    /// Compiles the pass.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let entries = [
            uniform_entry(0),
            storage_entry(1, true),
            storage_entry(2, true),
            storage_entry(3, true),
            storage_entry(4, true),
            storage_entry(5, true),
            storage_entry(6, false),
            storage_entry(7, true),
            storage_entry(8, true),
            storage_entry(9, true),
            storage_entry(13, false),
        ];
        let pipelines = MaterialPipelines::new(
            ctx,
            "bandwidth pass",
            &[&TYPES, &FREQUENCY, &ENV_LIGHT, &AREA_LIGHT],
            BANDWIDTH_PASS_WGSL,
            (7, 10),
            entries.to_vec(),
        )?;
        Ok(Self {
            pipelines,
            timer: GpuTimer::new(ctx),
        })
    }

    /// Runs the pass over `pixels` (one per G-buffer pixel) with `n_b` directions; returns the
    /// predictions (zeros on the background) and the pass's time (upload of the pixels, the
    /// dispatch; not the read-back).
    pub fn run(
        &mut self,
        ctx: &GpuContext,
        scene: &BandwidthScene,
        pixels: &[Option<BandwidthPixel>],
        n_b: u32,
    ) -> Result<(Vec<GpuPrediction>, Timing)> {
        if pixels.is_empty() || n_b == 0 || n_b > 4096 {
            return Err(invalid(
                "bandwidth pass",
                format!("{} pixels with n_b = {n_b} (1..=4096)", pixels.len()),
            ));
        }
        let mut surfels = Vec::with_capacity(pixels.len() * 24);
        for p in pixels {
            match p {
                Some(p) => {
                    if p.material >= scene.material_count {
                        return Err(invalid(
                            "bandwidth pass",
                            format!(
                                "material {} of {} uploaded",
                                p.material, scene.material_count
                            ),
                        ));
                    }
                    let (t, b, n) = p.frame;
                    let v = |d: DVec3, w: f32| [d.x as f32, d.y as f32, d.z as f32, w];
                    surfels.extend(v(t, p.depth as f32));
                    surfels.extend(v(b, p.curvature as f32));
                    surfels.extend(v(n, f32::from_bits(p.material)));
                    surfels.extend(v(p.wo, 1.0));
                    surfels.extend(v(p.position, p.texture as f32));
                    surfels.extend([p.uv[0] as f32, p.uv[1] as f32, 0.0, 0.0]);
                }
                None => surfels.extend([0.0f32; 24]),
            }
        }
        let params = Params {
            pixels: pixels.len() as u32,
            n_b,
            env_width: scene.env_size.0,
            env_height: scene.env_size.1,
            incident: scene.grid.0,
            out: scene.grid.1,
            lights: scene.light_count,
            first: 0,
        };
        self.timer.start(ctx)?;
        let scope = push_scope(ctx);
        let surfel_buf = buffer_init(
            ctx,
            "bandwidth surfels",
            bytemuck::cast_slice(&surfels),
            wgpu::BufferUsages::STORAGE,
        );
        let size = (pixels.len() * std::mem::size_of::<GpuPrediction>()) as u64;
        let out = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bandwidth predictions"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bandwidth readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // Σλ, Σλν, … of each pixel between the dispatches (3 vec4s).
        let partials = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("bandwidth partial sums"),
            size: (pixels.len() * 48) as u64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        // The bandwidth pass samples no BRDF.
        let (pipeline, layout) = self.pipelines.get(ctx, scene.evaluates, 0)?;
        let paths = u64::from(n_b) * (1 + u64::from(scene.light_count));
        let dispatches = paths.div_ceil(u64::from(DIRECTIONS_PER_DISPATCH)) as u32;
        let groups: Vec<wgpu::BindGroup> = (0..dispatches)
            .map(|c| {
                let p = Params {
                    first: c * DIRECTIONS_PER_DISPATCH,
                    ..params
                };
                let params_buf = buffer_init(
                    ctx,
                    "bandwidth params",
                    bytemuck::bytes_of(&p),
                    wgpu::BufferUsages::UNIFORM,
                );
                bind_group(
                    ctx,
                    layout,
                    scene,
                    [&params_buf, &surfel_buf, &out, &partials],
                )
            })
            .collect();
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bandwidth pass"),
            });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("bandwidth pass"),
                timestamp_writes: None,
            });
            pass.set_pipeline(pipeline);
            // Each dispatch continues the sums the one before it left (wgpu orders them).
            for group in &groups {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups((pixels.len() as u32).div_ceil(64), 1, 1);
            }
        }
        ctx.queue.submit([enc.finish()]);
        let timing = self.timer.stop(ctx)?;
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("bandwidth readback"),
            });
        enc.copy_buffer_to_buffer(&out, 0, &readback, 0, size);
        ctx.queue.submit([enc.finish()]);
        let bytes = map_read(ctx, &readback, "bandwidth pass", scope)?;
        let predictions = bytemuck::cast_slice::<u8, GpuPrediction>(&bytes).to_vec();
        Ok((predictions, timing))
    }
}

/// The bind group of one dispatch: its parameters, the pixels, the predictions and the partial
/// sums, with `scene`'s buffers.
fn bind_group(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    scene: &BandwidthScene,
    [params_buf, surfel_buf, out, partials]: [&wgpu::Buffer; 4],
) -> wgpu::BindGroup {
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("bandwidth pass"),
        layout,
        entries: &[
            buffer_entry(0, params_buf),
            buffer_entry(1, surfel_buf),
            buffer_entry(2, &scene.environment),
            buffer_entry(3, &scene.materials),
            buffer_entry(4, &scene.table),
            buffer_entry(5, &scene.brdf_bandwidth),
            buffer_entry(6, out),
            buffer_entry(7, &scene.fitted),
            buffer_entry(8, &scene.lights),
            buffer_entry(9, &scene.light_texels),
            buffer_entry(10, &scene.params),
            buffer_entry(11, &scene.texels),
            buffer_entry(12, &scene.tex_info),
            buffer_entry(13, partials),
        ],
    })
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "bandwidth",
    shaders: &[("bandwidth.wgsl", BANDWIDTH_PASS_WGSL)],
    inputs: &[
        crate::passes::Resource::ShadingPoints,
        crate::passes::Resource::Materials,
        crate::passes::Resource::Environment,
        crate::passes::Resource::AreaLights,
    ],
    outputs: &[crate::passes::Resource::Bandwidth],
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shader_takes_the_same_share_per_dispatch() {
        let share = format!("const DIRECTIONS_PER_DISPATCH: u32 = {DIRECTIONS_PER_DISPATCH}u;");
        assert!(BANDWIDTH_PASS_WGSL.contains(&share), "{share}");
    }
}
