//! The view-dependent part of the walkthrough frame on the GPU,
//! `frame_shade.wgsl`: a compute pass over the G-buffer the raster pass produced (read on the
//! GPU, no read-back between the passes) that adds, per G-buffer pixel, the material's rest
//! f − kd/π integrated against the pre-filtered incident light to the light-mapped image of
//! [`crate::LightmapShadePass`]. The CPU twin is
//! [`lustre_shade::frame::shade_gbuffer_view_dependent`] (per pixel
//! [`lustre_shade::frame::view_dependent`]).
//!
//! Materials are [`GpuBsdf`] records ([`crate::material`]: one module per kind, registered in
//! [`material::kinds::KINDS`]); the pass takes the sampled kinds and refuses the evaluated ones
//! (only the adaptive and bandwidth passes evaluate those). [`material::KIND_NONE`] marks no
//! view-dependent part (a light-mapped Lambertian). Per pixel the pass reads the diffuse albedo
//! kd as `Lightmapped::albedo` does (textures included) from the light-map pass's records
//! (`material_albedo.wgsl`); a material's textured parameters at uv0 from its
//! [`pack_material_params`] record, resolved into the model's by `textured_bsdf`
//! ([`material::FLAG_TEXTURED`]: diffuse and specular colours, roughness, the glTF base colour,
//! metallic, roughness and transmission); and tilts the shading frame by a normal map as the
//! CPU's `PathTracer::shading_point` does ([`material::FLAG_NORMAL_MAPPED`]; tangents from the
//! mesh or ∂p/∂u). Materials the pass cannot shade (fitted specs not on the GPU) are refused
//! with a named error, so the caller falls back to the CPU frame.
//!
//! Incident light: every probe's pyramid and the environment's are concatenated into one
//! storage buffer with an offset table and read trilinearly and seamlessly as
//! `CubePyramid::sample` reads them (the texels beyond a face edge from a table built by
//! `lustre_env::cube::fetch_sources`), through the probe's bounding planes; view buffers
//! ([`GpuViewBuffer`]) are read with `ViewBuffer::{locate, level, sample}`'s arithmetic.
//! Methods: regular (Fibonacci lattice), Colbert–Křivánek (per G-buffer pixel SplitMix64
//! points, seeded as the CPU twin) and progressive refinement (frame f's R2 rotation, averaged
//! on the GPU across calls in the target's accumulation buffer; frame 0 resets it).

use crate::bindings::{
    buffer_entry, buffer_init, compute_pipelines, read_buffer, read_buffer_later, storage_buffer,
    storage_entry, texture_entry, uniform_entry,
};
use crate::context::GpuContext;
use crate::cube_storage::ring_entries;
use crate::error::{invalid, push_scope, scope_result, wgpu_error, Result};
use crate::material::{
    self, pack_material, pack_material_params, GpuBsdf, FLAG_NORMAL_MAPPED, MATERIAL_PARAMS,
};
use crate::passes::gbuffer::{camera_uniform, GBufferTarget};
use crate::passes::lightmap_shade::{shading_records, ShadeTarget};
use crate::passes::probe_capture::GpuProbe;
use crate::passes::pyramid::GpuPyramid;
use crate::view_buffer::GpuViewBuffer;
use crate::wgsl;
use glam::DVec3;

use lustre_shade::frame::{
    layer_request, walkthrough_request, FrameBuffers, FrameLight, FrameStats, FrameTables,
};
use lustre_shade::integrator::BoundingPlane;
use lustre_shade::mirror::ScreenTiles;
use lustre_shade::probe::LitScene;
use lustre_shade::request::{FrameRequest, Method, MAX_WALKTHROUGH_SAMPLES};
use lustre_trace::image::Image;
use lustre_trace::path_tracer::PathCamera;
use std::sync::OnceLock;

/// Everything the pass reads besides the G-buffer: per-triangle records, materials with their
/// per-pixel parameter records ([`pack_material_params`]) and tangents, the cube maps, the view
/// buffers, and what the per-pixel diffuse albedo kd is read from (the light-map pass's
/// triangle and material records and textures, [`crate::passes::lightmap_shade`]).
///
/// All of it is one storage buffer, the arena, in [`PARTS`] parts (frame_shade.wgsl's `at_*`):
/// WebGPU guarantees only 8 storage buffers per shader stage (a browser's SwiftShader offers
/// 10), and the pass had 23.
#[derive(Debug)]
pub struct FrameShadeScene {
    arena: wgpu::Buffer,
    /// The first vec4 of each part, in frame_shade.wgsl's order.
    parts: [u32; PARTS],
    /// Per view buffer: its first texel in the arena.
    view_offsets: Vec<u32>,
    /// The end of the view buffers' radiance in the arena (vec4).
    view_end: u32,
    page: [u32; 2],
    probes: u32,
    environment: u32,
    /// The largest of the objects' own sample budgets (0: none has one).
    own_samples: u32,
    /// The scene's view-dependent materials, as packed.
    pub materials: Vec<GpuBsdf>,
}

/// The arena's parts: triangles, material records, material tables, cube texels, cube levels,
/// cubes, bounding planes, cube rings, view radiance, view geometry, view records, material
/// parameters, tangents, and the light-map pass's triangles, materials, texels and texture
/// records.
pub const PARTS: usize = 17;

/// The arena being laid out: host data written at its offset, GPU buffers copied there.
#[derive(Default)]
struct Arena<'a> {
    /// Bytes so far (a multiple of 16).
    len: u64,
    parts: Vec<u32>,
    host: Vec<(u64, Vec<u8>)>,
    gpu: Vec<(u64, &'a wgpu::Buffer)>,
}

impl<'a> Arena<'a> {
    /// Starts the next part with `data` (host data, padded to whole vec4).
    fn host<T: bytemuck::Pod>(&mut self, data: &[T]) {
        self.parts.push((self.len / 16) as u32);
        let bytes: Vec<u8> = bytemuck::cast_slice(data).to_vec();
        let n = bytes.len() as u64;
        self.host.push((self.len, bytes));
        self.len += n.div_ceil(16) * 16;
    }

    /// Starts the next part with GPU buffers `bufs` one after the other (each a whole number of
    /// vec4); returns each one's first vec4 in the arena.
    fn gpu(&mut self, bufs: &[&'a wgpu::Buffer]) -> Vec<u32> {
        self.parts.push((self.len / 16) as u32);
        bufs.iter()
            .map(|b| {
                let at = (self.len / 16) as u32;
                self.gpu.push((self.len, b));
                self.len += b.size().div_ceil(16) * 16;
                at
            })
            .collect()
    }

    /// The buffer: host parts written, GPU parts copied (submitted). Errors: beyond the
    /// device's largest storage buffer binding (named with both sizes).
    fn build(self, ctx: &GpuContext) -> Result<(wgpu::Buffer, Vec<u32>)> {
        let limits = ctx.device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let size = self.len.max(16);
        if size > limit {
            return Err(invalid(
                "scene",
                format!(
                    "the view-dependent pass's data (geometry, materials, textures, probes and                      view buffers) take {}, more than this GPU's largest storage buffer binding                      ({}, max_storage_buffer_binding_size)",
                    lustre_brdf::budget::bytes(size),
                    lustre_brdf::budget::bytes(limit)
                ),
            ));
        }
        let arena = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame arena"),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        for (at, bytes) in &self.host {
            // write_buffer needs a multiple of 4 bytes: every part is.
            ctx.queue.write_buffer(&arena, *at, bytes);
        }
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame arena"),
            });
        for (at, b) in &self.gpu {
            enc.copy_buffer_to_buffer(b, 0, &arena, *at, b.size());
        }
        ctx.queue.submit([enc.finish()]);
        Ok((arena, self.parts))
    }
}

const NONE: u32 = u32::MAX;

impl FrameShadeScene {
    /// Uploads the CPU frame's incident light (`light`'s probes, else its environment) and
    /// view buffers (`buffers`) and builds the per-triangle records of `lit`.
    pub fn upload(
        ctx: &GpuContext,
        lit: &LitScene,
        light: &FrameLight,
        buffers: &FrameBuffers,
    ) -> Result<Self> {
        let probes = light
            .probes
            .iter()
            .map(|p| {
                Ok(GpuProbe {
                    name: p.name.clone(),
                    mesh: p.mesh,
                    pyramid: GpuPyramid::upload(ctx, &p.pyramid)?,
                    centre: p.centre,
                    planes: p.planes.clone(),
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let environment = match (light.probes.is_empty(), light.environment) {
            (true, Some(e)) => Some(GpuPyramid::upload(ctx, e)?),
            _ => None,
        };
        let views = buffers
            .mirrors
            .iter()
            .map(|m| &m.view)
            .chain(&buffers.see_throughs)
            .map(|v| GpuViewBuffer::upload(ctx, v))
            .collect::<Result<Vec<_>>>()?;
        Self::new(
            ctx,
            lit,
            &buffers.tables(),
            &probes,
            environment.as_ref(),
            &views,
        )
    }

    /// The pass's inputs from GPU-resident probes (one per `lit` probe object, in the order of
    /// `links.probe_of_mesh`), the environment's pyramid (read when there is no probe) and
    /// view buffers (`links`' mirrors then see-throughs, in order). Errors: a material the
    /// pass cannot shade ([`pack_material`]), too many probes or views.
    pub fn new(
        ctx: &GpuContext,
        lit: &LitScene,
        links: &FrameTables,
        probes: &[GpuProbe],
        environment: Option<&GpuPyramid>,
        views: &[GpuViewBuffer],
    ) -> Result<Self> {
        let scene = lit.scene;
        let g = &lit.path_scene.geometry;
        if views.len() != links.mirrors() + links.see_throughs {
            return Err(invalid(
                "view buffers",
                format!(
                    "{} given, the frame has {} mirrors and {} see-through buffers",
                    views.len(),
                    links.mirrors(),
                    links.see_throughs
                ),
            ));
        }
        // Materials, packed only where a triangle of a shaded mesh uses them.
        let mut used = vec![false; scene.materials.len()];
        for (prim, &m) in lit.mesh_of.iter().enumerate() {
            if !scene.meshes[m as usize].hints.diffuse_only {
                if let Some(u) = used.get_mut(g.material[prim] as usize) {
                    *u = true;
                }
            }
        }
        let mut tables = vec![];
        let mut materials = vec![GpuBsdf::zeroed_record(); scene.materials.len()];
        let mut params = vec![[0.0f32; 4]; MATERIAL_PARAMS * scene.materials.len().max(1)];
        let mut slots = vec![];
        for (k, m) in scene.materials.iter().enumerate() {
            if used[k] {
                materials[k] = pack_material(m, &mut tables)?;
                params[MATERIAL_PARAMS * k..MATERIAL_PARAMS * (k + 1)]
                    .copy_from_slice(&pack_material_params(scene, m, &mut slots)?);
            }
        }
        let atlas = lit.lit.atlas();
        // Per triangle: 7 vec4 (frame_shade.wgsl `shade_point`); per triangle of a
        // normal-mapped material, 4 vec4 in `tangents`.
        let bits = |u: u32| f32::from_bits(u);
        let v4 = |v: DVec3, w: f32| [v.x as f32, v.y as f32, v.z as f32, w];
        let mut tris: Vec<[f32; 4]> = Vec::with_capacity(g.positions.len() * 7);
        let mut own_samples = 0;
        let mut tangents: Vec<[f32; 4]> = vec![];
        for (prim, t) in g.positions.iter().enumerate() {
            let mesh = lit.mesh_of[prim] as usize;
            let k = g.material[prim];
            let material = if scene.meshes[mesh].hints.diffuse_only {
                NONE
            } else {
                k
            };
            let normals = g.normals.get(prim);
            let nz = [DVec3::ZERO; 3];
            let n = normals.unwrap_or(&nz);
            let (dpdu, dpdv) = g.surface_derivatives(prim);
            // A normal-mapped material's tangent block (`mapped_normal`'s inputs): the corners'
            // tangents (xyz, w: the bitangent's sign; w = 0: derive T from ∂p/∂u), ∂p/∂v.
            let mapped = material != NONE
                && materials
                    .get(k as usize)
                    .is_some_and(|b| b.flags & FLAG_NORMAL_MAPPED != 0);
            let tangent_block = if mapped {
                let at = u32::try_from(tangents.len()).unwrap_or(NONE);
                let tc = g.tangents.get(prim).copied().unwrap_or([[0.0; 4]; 3]);
                let sign = if tc[0][3] != 0.0 {
                    tc[0][3].signum()
                } else {
                    0.0
                };
                for c in tc {
                    tangents.push([c[0] as f32, c[1] as f32, c[2] as f32, sign as f32]);
                }
                tangents.push(v4(dpdv, 0.0));
                at
            } else {
                NONE
            };
            let probe = links.probe_of_mesh[mesh].map_or(NONE, |i| i as u32);
            let mirror = links.mirror_at(mesh, prim).map_or(NONE, |i| i as u32);
            let see =
                links.see_through_of_mesh[mesh].map_or(NONE, |i| (links.mirrors() + i) as u32);
            // The object's own sample budget (0: the frame's).
            let samples = scene.meshes[mesh]
                .hints
                .samples
                .map_or(0, |s| s.clamp(1, MAX_WALKTHROUGH_SAMPLES));
            own_samples = own_samples.max(samples);
            tris.extend([
                v4(t[0], bits(material)),
                v4(t[1], bits(samples)),
                v4(t[2], bits(u32::from(normals.is_some()))),
                v4(n[0], bits(probe)),
                v4(n[1], bits(mirror)),
                v4(n[2], bits(see)),
                v4(dpdu, bits(tangent_block)),
            ]);
        }
        // Cube maps: the probes, then the environment when there is no probe.
        // (pyramid, centre, planes, a room probe).
        let mut pyramids: Vec<(&GpuPyramid, DVec3, &[BoundingPlane], bool)> = probes
            .iter()
            .map(|p| (&p.pyramid, p.centre, &p.planes[..], p.mesh.is_none()))
            .collect();
        let env_index = match environment {
            Some(e) if probes.is_empty() => {
                pyramids.push((e, DVec3::ZERO, &[], false));
                0
            }
            _ => NONE,
        };
        let level_buffers: Vec<&wgpu::Buffer> = pyramids
            .iter()
            .flat_map(|(p, ..)| p.levels.iter())
            .collect();
        // Each level's first texel, relative to the cube texels' part.
        let offsets = relative_offsets(&level_buffers);
        let mut cube_levels: Vec<[u32; 4]> = vec![];
        let mut cubes: Vec<[f32; 4]> = vec![];
        let mut planes: Vec<[f32; 4]> = vec![];
        let mut ring = vec![];
        for (p, centre, pl, room) in &pyramids {
            let first = cube_levels.len() as u32;
            for &n in &p.sizes {
                let texel = offsets[cube_levels.len()];
                cube_levels.push([texel, n as u32, ring.len() as u32, 0]);
                ring_entries(n, texel, &mut ring);
            }
            cubes.push(v4(*centre, bits(first)));
            cubes.push([
                bits(p.sizes.len() as u32),
                bits((planes.len() / 2) as u32),
                bits(pl.len() as u32),
                bits(u32::from(*room)),
            ]);
            for b in *pl {
                planes.push(v4(b.point, 0.0));
                planes.push(v4(b.normal, 0.0));
            }
        }
        // View buffers: each one's radiance and geometry relative to their parts.
        let radiance: Vec<&wgpu::Buffer> = views.iter().map(|v| &v.radiance).collect();
        let geometry: Vec<&wgpu::Buffer> = views.iter().map(|v| &v.geometry).collect();
        let (r_off, g_off) = (relative_offsets(&radiance), relative_offsets(&geometry));
        let mut view_records: Vec<[f32; 4]> = vec![];
        for (i, v) in views.iter().enumerate() {
            let c = &v.camera;
            let front = v.front;
            // A see-through buffer's slab (thickness, relative index; 0: a thin sheet).
            let (thickness, eta) = if i >= links.mirrors() {
                lustre_shade::frame::slab_of(scene, v.mesh as usize).unwrap_or((0.0, 1.0))
            } else {
                (0.0, 1.0)
            };
            view_records.extend([
                v4(c.origin, c.tan_half_fov_y as f32),
                v4(c.forward, 0.0),
                v4(c.right, 0.0),
                v4(c.up, 0.0),
                [
                    bits(v.width as u32),
                    bits(v.height as u32),
                    bits(v.level_sizes.len() as u32),
                    bits(r_off[i]),
                ],
                [
                    bits(g_off[i]),
                    bits(u32::from(front.is_some())),
                    thickness as f32,
                    eta as f32,
                ],
                v4(front.map_or(DVec3::ZERO, |f| f.point), 0.0),
                v4(front.map_or(DVec3::ZERO, |f| f.normal), 0.0),
            ]);
        }
        // The arena, in frame_shade.wgsl's order.
        let mut arena = Arena::default();
        arena.host(&tris);
        arena.host(&materials);
        arena.host(&tables);
        arena.gpu(&level_buffers);
        arena.host(&cube_levels);
        arena.host(&cubes);
        arena.host(&planes);
        arena.host(&ring);
        let radiance_at = arena.gpu(&radiance);
        let view_end = (arena.len / 16) as u32;
        arena.gpu(&geometry);
        arena.host(&view_records);
        arena.host(&params);
        arena.host(&tangents);
        // kd per pixel (`Lightmapped::albedo`): the light-map pass's records, their textures
        // after the parameters', within what the rest of the arena leaves.
        let limits = ctx.device.limits();
        let limit = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let left = usize::try_from(limit.saturating_sub(arena.len)).unwrap_or(usize::MAX);
        let albedo = shading_records(scene, lit.lit, g, lit.lit.bases(), slots, left)?;
        arena.host(&albedo.tris);
        arena.host(&albedo.mats);
        arena.host(&albedo.texels);
        arena.host(&albedo.info);
        let (arena, parts) = arena.build(ctx)?;
        let parts: [u32; PARTS] = parts.try_into().map_err(|p: Vec<u32>| {
            invalid(
                "frame arena",
                format!("{} parts, the pass reads {PARTS}", p.len()),
            )
        })?;
        Ok(FrameShadeScene {
            arena,
            parts,
            view_offsets: radiance_at,
            view_end,
            page: [atlas.width, atlas.height],
            probes: probes.len() as u32,
            environment: env_index,
            own_samples,
            materials,
        })
    }
}

/// Each buffer's first vec4 when `bufs` are laid one after the other.
fn relative_offsets(bufs: &[&wgpu::Buffer]) -> Vec<u32> {
    let mut at = 0;
    bufs.iter()
        .map(|b| {
            let o = (at / 16) as u32;
            at += b.size().div_ceil(16) * 16;
            o
        })
        .collect()
}

impl FrameShadeScene {
    /// The sampled material kinds its records need (bit mask, `material::kinds::sampled_kinds`).
    pub fn kinds(&self) -> u32 {
        self.materials
            .iter()
            .filter(|b| b.kind != material::KIND_NONE)
            .fold(0, |m, b| m | material::kinds::sampled_kinds(b.kind))
    }

    /// Copies view buffer `index`'s radiance (every level) into the pass's concatenation,
    /// after `view` was shaded again (a see-through layer). Submitted, not waited for.
    /// Errors: no such view, a buffer of another size.
    pub fn refresh_view(&self, ctx: &GpuContext, index: usize, view: &GpuViewBuffer) -> Result<()> {
        let at = self.view_offsets.get(index).copied().ok_or_else(|| {
            invalid(
                "view buffer",
                format!("no view {index} among {}", self.view_offsets.len()),
            )
        })?;
        let start = u64::from(at) * 16;
        let end = u64::from(
            self.view_offsets
                .get(index + 1)
                .copied()
                .unwrap_or(self.view_end),
        ) * 16;
        if view.radiance.size() != end - start {
            return Err(invalid(
                "view buffer",
                format!(
                    "view {index} holds {} bytes, the frame's copy {}",
                    view.radiance.size(),
                    end - start
                ),
            ));
        }
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("view refresh"),
            });
        enc.copy_buffer_to_buffer(&view.radiance, 0, &self.arena, start, end - start);
        ctx.queue.submit([enc.finish()]);
        Ok(())
    }
}

/// The WGSL source of the pass: the modules it imports, then `frame_shade.wgsl`.
pub fn frame_shade_wgsl() -> &'static str {
    static SRC: OnceLock<String> = OnceLock::new();
    SRC.get_or_init(|| {
        wgsl::compose(
            &[
                &material::BSDF,
                &wgsl::MIP,
                &wgsl::PLANES,
                &wgsl::QMC,
                &wgsl::WARP,
                &material::TEXTURED,
                &wgsl::CUBE_STORAGE,
                &wgsl::MATERIAL_ALBEDO,
            ],
            include_str!("frame_shade.wgsl"),
        )
    })
}

/// The output of the pass: the frame (light-mapped + view-dependent), the progressive
/// accumulation and the view-dependent sums of a frame's sample dispatches (per G-buffer pixel)
/// and the counts.
#[derive(Debug)]
pub struct FrameShadeTarget {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    out: wgpu::Buffer,
    accum: wgpu::Buffer,
    partial: wgpu::Buffer,
    counts: wgpu::Buffer,
}

impl FrameShadeTarget {
    /// An output of `w`×`h` pixels of a G-buffer supersampled k×k. Errors: a zero size, a
    /// buffer beyond the device's limit.
    pub fn new(ctx: &GpuContext, w: u32, h: u32, k: u32) -> Result<Self> {
        let bytes = u64::from(w) * u64::from(h) * 16;
        let accum = bytes * u64::from(k) * u64::from(k);
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        if w == 0 || h == 0 || k == 0 {
            return Err(invalid(
                "image size",
                format!("{w}×{h} at {k}×{k} samples is empty"),
            ));
        }
        if accum > limit {
            return Err(invalid(
                "image size",
                format!(
                    "{w}×{h} at {k}×{k} samples a pixel needs a storage buffer of {}, more than \
                     this GPU's {}: render a smaller image or fewer camera rays a pixel",
                    lustre_brdf::budget::bytes(accum),
                    lustre_brdf::budget::bytes(limit)
                ),
            ));
        }
        let buffer = |label: &str, size: u64| {
            ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        Ok(FrameShadeTarget {
            width: w,
            height: h,
            out: buffer("frame output", bytes),
            accum: buffer("frame accumulation", accum),
            partial: buffer("frame sample sums", accum),
            counts: buffer("frame counts", 8),
        })
    }

    /// Copies the frame to the host.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<Image> {
        let bytes = read_buffer(ctx, &self.out, "frame readback")?;
        let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
        Image::from_data(
            self.width as usize,
            self.height as usize,
            px.iter().map(|p| [p[0], p[1], p[2]]).collect(),
        )
        .map_err(|e| wgpu_error("frame readback", e))
    }

    /// [`FrameShadeTarget::read_back`] without blocking (a browser's page cannot wait for the
    /// GPU): the copy is recorded now, the future completes when the GPU has finished it.
    pub fn read_back_async(
        &self,
        ctx: &GpuContext,
    ) -> impl std::future::Future<Output = Result<Image>> + 'static {
        let pending = read_buffer_later(ctx, &self.out, "frame readback");
        let (w, h) = (self.width as usize, self.height as usize);
        async move {
            let bytes = pending?.await?;
            let px: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
            Image::from_data(w, h, px.iter().map(|p| [p[0], p[1], p[2]]).collect())
                .map_err(|e| wgpu_error("frame readback", e))
        }
    }

    /// The counts of the last call (one progressive frame): G-buffer pixels with a
    /// view-dependent part, lookups.
    pub fn stats(&self, ctx: &GpuContext) -> Result<FrameStats> {
        let bytes = read_buffer(ctx, &self.counts, "frame readback")?;
        let c: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(FrameStats {
            glossy_hits: u64::from(c[0]),
            lookups: u64::from(c[1]),
            ..FrameStats::default()
        })
    }
}

/// The light-mapped image a run adds to: the first w·h RGBA f32 texels of a buffer.
struct Lit<'a> {
    buffer: &'a wgpu::Buffer,
    width: u32,
    height: u32,
}

/// Samples per G-buffer pixel in one dispatch of the pass's sampling entry point. llvmpipe
/// (lavapipe) ends all loops of an invocation silently once they have run 65,535 iterations
/// together (`LP_MAX_TGSI_LOOP_ITERATIONS`); one output pixel of 4×4 G-buffer pixels at 256
/// samples each came out at 24.5 dB against the CPU twin, 64 samples at 129 dB. A frame's
/// sampling is dispatched ⌈n/64⌉ times, one thread per G-buffer pixel, each adding its share.
pub const SAMPLES_PER_DISPATCH: u32 = 64;

/// The compiled pass: the sampling entry point (per G-buffer pixel) and the resolve (per
/// output pixel).
#[derive(Debug)]
pub struct FrameShadePass {
    samples: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// The sampled material kinds compiled in (bit mask, `material::kinds::sampled_kinds`).
    kinds: u32,
}

impl FrameShadePass {
    /// Compiles `frame_shade.wgsl` with its modules, every sampled material kind.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        Self::for_kinds(ctx, material::kinds::all_sampled())
    }

    /// Compiles `frame_shade.wgsl` with the sampled material kinds in the bit mask `kinds` only
    /// ([`FrameShadeScene::kinds`] of the scenes it will shade; `material::kinds::
    /// restrict_kinds`): a scene with another kind is refused at [`FrameShadePass::shade`].
    pub fn for_kinds(ctx: &GpuContext, kinds: u32) -> Result<Self> {
        let src = material::kinds::restrict_kinds(frame_shade_wgsl(), kinds).ok_or_else(|| {
            invalid(
                "frame_shade.wgsl",
                "the material dispatch was not found to restrict",
            )
        })?;
        let mut entries = vec![
            uniform_entry(0),
            texture_entry(
                1,
                wgpu::TextureSampleType::Uint,
                wgpu::TextureViewDimension::D2,
            ),
            texture_entry(
                2,
                wgpu::TextureSampleType::Float { filterable: false },
                wgpu::TextureViewDimension::D2,
            ),
        ];
        // The arena twice (as vec4<f32> and vec4<u32>), the light-mapped image; accumulation,
        // output, counts; the tile mask; the sample sums.
        entries.extend((3..6).map(|b| storage_entry(b, true)));
        entries.extend((6..9).map(|b| storage_entry(b, false)));
        entries.push(storage_entry(9, true));
        entries.push(storage_entry(10, false));
        let ([samples, resolve], layout) = compute_pipelines(
            ctx,
            "frame_shade.wgsl",
            "compiling frame_shade.wgsl",
            &src,
            &entries,
            ["samples_main", "main"],
        )?;
        Ok(FrameShadePass {
            samples,
            resolve,
            layout,
            kinds,
        })
    }

    /// Shades the (k·w)×(k·h) `gbuffer` seen from `camera`: `lightmapped` (the w×h light-map
    /// shading of the same G-buffer) plus the view-dependent part of `req`, into `out`
    /// (submitted, not waited for); the progressive method shades frame `frame` and averages it
    /// into the target's accumulation (frame 0 resets it: a camera move). Errors: mismatched
    /// sizes, a request `lustre_shade::frame::walkthrough_request` refuses.
    #[allow(clippy::too_many_arguments)]
    pub fn shade(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        lightmapped: &ShadeTarget,
        camera: &PathCamera,
        k: u32,
        (req, frame): (&FrameRequest, u32),
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let lit = Lit {
            buffer: lightmapped.buffer(),
            width: lightmapped.width,
            height: lightmapped.height,
        };
        self.dispatch(
            ctx,
            scene,
            gbuffer,
            lit,
            camera,
            k,
            (req, frame),
            (None, true, true),
            out,
        )
    }

    /// The see-through layer of view buffer `view` (index `index` of `scene`'s views, a
    /// see-through buffer), as `lustre_shade::frame::shade_see_through_layer`: its light-mapped
    /// level 0 plus the view-dependent part of the pixels in the covered `tiles` of its
    /// w×h G-buffer `gbuffer` with `SEE_THROUGH_SAMPLES` regular samples, see-through buffers
    /// not read, written into `out` (w×h at k = 1) and copied over the view's level 0; the
    /// caller rebuilds its MIP levels ([`crate::GpuViewPass::build_levels`]) and the scene's
    /// copy ([`FrameShadeScene::refresh_view`]). Submitted, not waited for. Errors: sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn shade_see_through_layer(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        view: &GpuViewBuffer,
        camera: &PathCamera,
        tiles: &ScreenTiles,
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let layer = (Some(tiles), true, "see-through layer");
        self.shade_layer(ctx, scene, gbuffer, view, camera, layer, out)
    }

    /// The mirror layer of mirror buffer `view` (w×h), as
    /// `lustre_shade::frame::shade_mirror_layer`: its light-mapped level 0 plus the
    /// view-dependent part of the pixels in the covered `tiles` of its G-buffer `gbuffer` as the
    /// mirrored camera `camera` sees it, with `SEE_THROUGH_SAMPLES` regular samples, read from
    /// the probes only (no mirror or see-through buffer), written into `out` (w×h at k = 1) and
    /// copied over the view's level 0; the caller rebuilds its levels and the scene's copy.
    /// Submitted, not waited for. Errors: sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn shade_mirror_layer(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        view: &GpuViewBuffer,
        camera: &PathCamera,
        tiles: &ScreenTiles,
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let layer = (Some(tiles), false, "mirror layer");
        self.shade_layer(ctx, scene, gbuffer, view, camera, layer, out)
    }

    /// A view buffer's layer: (the tiles shaded, all when `None`; whether mirror buffers are
    /// read; its name), see-through buffers never read; `lustre_shade::frame::layer_request`.
    #[allow(clippy::too_many_arguments)]
    fn shade_layer(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        view: &GpuViewBuffer,
        camera: &PathCamera,
        (tiles, mirrors, what): (Option<&ScreenTiles>, bool, &str),
        out: &FrameShadeTarget,
    ) -> Result<()> {
        let (w, h) = (view.width as u32, view.height as u32);
        if (out.width, out.height) != (w, h) {
            return Err(invalid(
                what,
                format!(
                    "a {}×{} output for a {w}×{h} view buffer",
                    out.width, out.height
                ),
            ));
        }
        let lit = Lit {
            buffer: &view.radiance,
            width: w,
            height: h,
        };
        let req = layer_request();
        self.dispatch(
            ctx,
            scene,
            gbuffer,
            lit,
            camera,
            1,
            (&req, 0),
            (tiles, false, mirrors),
            out,
        )?;
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(what) });
        enc.copy_buffer_to_buffer(&out.out, 0, &view.radiance, 0, out.out.size());
        ctx.queue.submit([enc.finish()]);
        Ok(())
    }

    /// One run of the pass: the tiles shaded (all: `None`) and whether see-through buffers and
    /// mirror buffers are read.
    #[allow(clippy::too_many_arguments)]
    fn dispatch(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        gbuffer: &GBufferTarget,
        lightmapped: Lit,
        camera: &PathCamera,
        k: u32,
        (req, frame): (&FrameRequest, u32),
        (tiles, see_through, mirrors): (Option<&ScreenTiles>, bool, bool),
        out: &FrameShadeTarget,
    ) -> Result<()> {
        walkthrough_request(req).map_err(|e| invalid("frame request", e.to_string()))?;
        if scene.kinds() & !self.kinds != 0 {
            return Err(invalid(
                "frame shading",
                format!(
                    "the scene's materials need the kinds {:#x}, the pass was compiled for {:#x}",
                    scene.kinds(),
                    self.kinds
                ),
            ));
        }
        if k == 0
            || gbuffer.width != out.width * k
            || gbuffer.height != out.height * k
            || (lightmapped.width, lightmapped.height) != (out.width, out.height)
        {
            return Err(invalid(
                "supersampling",
                format!(
                    "a {}×{} G-buffer, a {}×{} light-mapped image and a {}×{} output do not \
                     agree at {k}×{k}",
                    gbuffer.width,
                    gbuffer.height,
                    lightmapped.width,
                    lightmapped.height,
                    out.width,
                    out.height
                ),
            ));
        }
        let scope = push_scope(ctx);
        let cam = camera_uniform(camera, gbuffer.width, gbuffer.height, 0.0);
        let mut u: Vec<[u32; 4]> = cam.iter().map(|v| v.map(f32::to_bits)).collect();
        let method = match req.method {
            Method::Ck => 1,
            Method::Progressive => 2,
            _ => 0,
        };
        u.push([gbuffer.width, gbuffer.height, k, req.samples]);
        u.push([method, frame, scene.probes, scene.page[0]]);
        u.push([
            req.seed as u32,
            (req.seed >> 32) as u32,
            scene.environment,
            scene.page[1],
        ]);
        let (mask, tile_u) = match tiles {
            Some(t) => {
                let (cols, rows) = (u32::try_from(t.cols), u32::try_from(t.rows));
                let (Ok(cols), Ok(rows)) = (cols, rows) else {
                    return Err(invalid("screen tiles", format!("{}×{}", t.cols, t.rows)));
                };
                let bits: Vec<u32> = t.covered.iter().map(|&c| u32::from(c)).collect();
                (
                    storage_buffer(ctx, "frame tile mask", &bits),
                    [cols, rows, 1, 0],
                )
            }
            None => (
                storage_buffer(ctx, "frame tile mask", &[0u32]),
                [0, 0, 0, 0],
            ),
        };
        u.push(tile_u);
        u.push([u32::from(!see_through), u32::from(!mirrors), 0, 0]);
        // The largest n of a pixel: the frame's, or an object's own budget.
        let n = req.samples.max(scene.own_samples);
        let chunks: Vec<u32> = (0..n).step_by(SAMPLES_PER_DISPATCH as usize).collect();
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let (prim, bary) = (view(&gbuffer.prim), view(&gbuffer.bary_depth));
        let binds: Vec<wgpu::BindGroup> = chunks
            .iter()
            .map(|&first| {
                let mut u = u.clone();
                u.push([first, first + SAMPLES_PER_DISPATCH, 0, 0]);
                u.extend(
                    scene
                        .parts
                        .chunks(4)
                        .map(|c| std::array::from_fn(|i| c.get(i).copied().unwrap_or(0))),
                );
                let uniform = buffer_init(
                    ctx,
                    "frame uniform",
                    bytemuck::cast_slice(&u),
                    wgpu::BufferUsages::UNIFORM,
                );
                self.bind_group(
                    ctx,
                    scene,
                    (&uniform, &mask),
                    (&prim, &bary),
                    &lightmapped,
                    out,
                )
            })
            .collect();
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("frame shading"),
            });
        enc.clear_buffer(&out.counts, 0, None);
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("frame shading"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.samples);
            for bind in &binds {
                pass.set_bind_group(0, bind, &[]);
                pass.dispatch_workgroups(gbuffer.width.div_ceil(8), gbuffer.height.div_ceil(8), 1);
            }
            pass.set_pipeline(&self.resolve);
            pass.dispatch_workgroups(out.width.div_ceil(8), out.height.div_ceil(8), 1);
        }
        ctx.queue.submit([enc.finish()]);
        scope_result(scope, "frame shading")
    }

    /// The bind group of one dispatch: its uniform block and the tile mask, the G-buffer's
    /// primitive and barycentric textures, the light-mapped image, the output.
    fn bind_group(
        &self,
        ctx: &GpuContext,
        scene: &FrameShadeScene,
        (uniform, mask): (&wgpu::Buffer, &wgpu::Buffer),
        (prim, bary): (&wgpu::TextureView, &wgpu::TextureView),
        lightmapped: &Lit,
        out: &FrameShadeTarget,
    ) -> wgpu::BindGroup {
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame_shade.wgsl"),
            layout: &self.layout,
            entries: &[
                buffer_entry(0, uniform),
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(prim),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(bary),
                },
                buffer_entry(3, &scene.arena),
                buffer_entry(4, &scene.arena),
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: lightmapped.buffer,
                        offset: 0,
                        size: wgpu::BufferSize::new(
                            u64::from(lightmapped.width) * u64::from(lightmapped.height) * 16,
                        ),
                    }),
                },
                buffer_entry(6, &out.accum),
                buffer_entry(7, &out.out),
                buffer_entry(8, &out.counts),
                buffer_entry(9, mask),
                buffer_entry(10, &out.partial),
            ],
        })
    }
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "frame_shade",
    shaders: &[("frame_shade.wgsl", include_str!("frame_shade.wgsl"))],
    inputs: &[
        crate::passes::Resource::GBuffer,
        crate::passes::Resource::LightmappedImage,
        crate::passes::Resource::Materials,
        crate::passes::Resource::ProbePyramids,
        crate::passes::Resource::Environment,
        crate::passes::Resource::ViewBuffers,
    ],
    outputs: &[crate::passes::Resource::Frame],
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::pack_thin_dielectric;
    use lustre_brdf::models::thin_dielectric::ThinDielectric;

    /// The pass and the model-evaluation shader parse and validate without an adapter; the
    /// uniform block and the material record have the sizes the Rust side writes.
    #[test]
    fn wgsl_parses_and_validates_with_naga() {
        let models = material::harness::harness_wgsl();
        for (src, types) in [
            (
                frame_shade_wgsl(),
                // 11 vec4 of camera and request, then the arena's part offsets, 4 a vec4.
                &[
                    ("Params", (11 + PARTS.div_ceil(4) as u32) * 16),
                    ("GpuBsdf", 144),
                ][..],
            ),
            (models.as_str(), &[("GpuBsdf", 144)][..]),
        ] {
            let m = crate::wgsl::validated(src);
            assert!(m.entry_points.iter().any(|p| p.name == "main"));
            if src == frame_shade_wgsl() {
                assert!(m.entry_points.iter().any(|p| p.name == "samples_main"));
            }
            for (name, bytes) in types {
                let size = m
                    .types
                    .iter()
                    .find(|(_, t)| t.name.as_deref() == Some(*name))
                    .map(|(_, t)| t.inner.size(m.to_ctx()))
                    .unwrap_or_else(|| panic!("no struct {name}"));
                assert_eq!(size, *bytes, "{name}");
            }
        }
        assert_eq!(std::mem::size_of::<GpuBsdf>(), 144);
        // Restricted to some kinds (or none), the pass still validates, and the dispatch keeps
        // exactly the kinds asked for.
        for kinds in [
            0,
            1 << material::KIND_ROUGH_PLASTIC,
            material::all_sampled(),
        ] {
            let src = material::restrict_kinds(frame_shade_wgsl(), kinds).expect("restricted");
            crate::wgsl::validated(&src);
            let calls = |p: &str| src.matches(&format!("return {p}_sample(")).count();
            assert_eq!(
                calls("rough_plastic"),
                usize::from(kinds != 0),
                "{kinds:#x}"
            );
            assert_eq!(
                calls("kurt"),
                usize::from(kinds == material::all_sampled()),
                "{kinds:#x}"
            );
        }
    }

    /// The WGSL's copies of the coating grid's and the screen tiles' constants are lustre-brdf's
    /// and lustre-shade's.
    #[test]
    fn coating_constants_match() {
        use lustre_brdf::models::rough_plastic::{COATING_ALPHAS, COATING_ALPHA_MIN};
        let src = frame_shade_wgsl();
        assert!(src.contains(&format!("const COATING_ALPHAS: u32 = {COATING_ALPHAS}u;")));
        assert_eq!(COATING_ALPHA_MIN, 1e-4);
        assert!(src.contains("const COATING_ALPHA_MIN: f32 = 1e-4;"));
        let tile = lustre_shade::mirror::SCREEN_TILE;
        assert!(src.contains(&format!("const SCREEN_TILE: u32 = {tile}u;")));
    }

    /// Every parameter must fit an f32: a named error otherwise.
    #[test]
    fn parameters_beyond_f32_are_named() {
        let t = ThinDielectric::new(1.5, 1.0).expect("thin");
        assert!(pack_thin_dielectric(&t).is_ok());
        let huge = ThinDielectric { eta: 1e300, ..t };
        let err = pack_thin_dielectric(&huge).unwrap_err().to_string();
        assert!(
            err.contains("thin dielectric") && err.contains("f32"),
            "{err}"
        );
    }
}
