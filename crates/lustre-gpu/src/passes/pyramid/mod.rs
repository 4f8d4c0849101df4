//! Cube-map MIP pyramids built on the GPU (probes are filtered where they are
//! captured): `pyramid.wgsl`, one compute dispatch per level, the GPU twin of
//! [`lustre_env::CubePyramid::build`] (002 §3, Table 1: Box 2×2, Gauss 4×4 and 6×6, each tap
//! weighted by its exact texel solid angle, seamless across faces and corners).
//!
//! The levels stay in storage buffers (RGBA f32, face-major, row-major), built in one command
//! buffer; [`GpuPyramid::read_back`] brings them to the host as a `CubePyramid`. The texels a
//! tap beyond a face edge reads come from [`lustre_env::cube::fetch_sources`], uploaded per
//! level as a table, so the CPU and the GPU read the same texels by construction.

use crate::bindings::{buffer_entry, buffer_init, compute_pipeline, storage_entry, uniform_entry};
use crate::context::GpuContext;
use crate::error::{invalid, push_scope, scope_result, wgpu_error, Result};
use lustre_env::cube::{fetch_sources, solid_angle_table};
use lustre_env::{CubeMap, CubePyramid, MipFilter};

/// The WGSL source of the down-sampling step.
pub const PYRAMID_WGSL: &str = include_str!("pyramid.wgsl");

/// Texels of the ring kept outside each face edge (the widest kernel's margin, Gauss 6×6).
const MARGIN: i64 = 2;

/// The usage of every level buffer of a [`GpuPyramid`]: read and written by the shaders,
/// copied out for readback.
pub const PYRAMID_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

/// The compiled down-sampling pass.
#[derive(Debug)]
pub struct GpuPyramidBuilder {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
}

/// A pyramid on the GPU: one storage buffer per level (level 0 is the uploaded base).
#[derive(Debug)]
pub struct GpuPyramid {
    /// Face size of each level, finest first.
    pub sizes: Vec<usize>,
    /// The level buffers (6·size² RGBA f32 texels each).
    pub levels: Vec<wgpu::Buffer>,
    /// The filter.
    pub filter: MipFilter,
}

/// The ring table of a parent of face size `n`: for each face, each tap position within
/// [`MARGIN`] outside the face in the order `pyramid.wgsl`'s `ring_index` expects, the global
/// indices of the texels [`fetch_sources`] names and their count.
fn ring_table(n: usize) -> Vec<[i32; 4]> {
    let nn = n as i64;
    let e = nn + 2 * MARGIN;
    let mut positions = Vec::new();
    for j in -MARGIN..0 {
        for i in -MARGIN..nn + MARGIN {
            positions.push((i, j));
        }
    }
    for j in nn..nn + MARGIN {
        for i in -MARGIN..nn + MARGIN {
            positions.push((i, j));
        }
    }
    for j in 0..nn {
        for i in -MARGIN..0 {
            positions.push((i, j));
        }
    }
    for j in 0..nn {
        for i in nn..nn + MARGIN {
            positions.push((i, j));
        }
    }
    debug_assert_eq!(positions.len() as i64, 2 * MARGIN * e + 2 * nn * MARGIN);
    let mut out = Vec::with_capacity(6 * positions.len());
    for face in 0..6 {
        for &(i, j) in &positions {
            // Taps further out than the face size (tiny faces) read as `fetch` clamps them.
            let (ci, cj) = (i.clamp(-nn, 2 * nn - 1), j.clamp(-nn, 2 * nn - 1));
            let (src, count) = fetch_sources(n, face, ci, cj);
            let idx = src.map(|(f, a, b)| ((f * n + b) * n + a) as i32);
            out.push([idx[0], idx[1], idx[2], count as i32]);
        }
    }
    out
}

impl GpuPyramidBuilder {
    /// Compiles `pyramid.wgsl`.
    pub fn new(ctx: &GpuContext) -> Result<Self> {
        let (pipeline, layout) = compute_pipeline(
            ctx,
            "pyramid.wgsl",
            "compiling pyramid.wgsl",
            PYRAMID_WGSL,
            &[
                uniform_entry(0),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, true),
                storage_entry(4, true),
                storage_entry(5, false),
            ],
        )?;
        Ok(GpuPyramidBuilder { pipeline, layout })
    }

    /// Uploads `base` and builds every level down to 1×1 with `filter` in one submission
    /// (returns once the GPU has finished). Errors: a face larger than the device's storage
    /// buffers allow, wgpu validation.
    pub fn build(&self, ctx: &GpuContext, base: &CubeMap, filter: MipFilter) -> Result<GpuPyramid> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        let bytes = 6 * base.size * base.size * 16;
        if bytes > limit {
            return Err(invalid(
                "cube pyramid",
                format!(
                    "a {0}² base needs {bytes} bytes per storage buffer; the device allows {limit}",
                    base.size
                ),
            ));
        }
        let texels: Vec<[f32; 4]> = base
            .faces
            .iter()
            .flat_map(|f| f.iter().map(|v| [v[0], v[1], v[2], 1.0]))
            .collect();
        let level0 = buffer_init(
            ctx,
            "pyramid level 0",
            bytemuck::cast_slice(&texels),
            PYRAMID_USAGE,
        );
        self.build_from_buffer(ctx, level0, base.size, filter)
    }

    /// Builds every level down to 1×1 with `filter` above a base level already on the GPU:
    /// `level0` holds 6·size² RGBA f32 texels, face-major then row-major (as
    /// [`GpuPyramid::levels`]; usage [`PYRAMID_USAGE`]), e.g. a probe captured by
    /// [`crate::passes::probe_capture::GpuProbeCapture`]. One submission, no host round trip; returns
    /// once the GPU has finished. Errors: a size of 0 or beyond the device's storage buffers,
    /// a buffer of the wrong size, wgpu validation.
    pub fn build_from_buffer(
        &self,
        ctx: &GpuContext,
        level0: wgpu::Buffer,
        size: usize,
        filter: MipFilter,
    ) -> Result<GpuPyramid> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        let bytes = 6 * size * size * 16;
        if size == 0 || bytes > limit || level0.size() != bytes as u64 {
            return Err(invalid(
                "cube pyramid",
                format!(
                    "a {size}² base needs {bytes} bytes (the buffer has {}, the device allows {limit} per storage buffer)",
                    level0.size()
                ),
            ));
        }
        let scope = push_scope(ctx);
        let usage = PYRAMID_USAGE;
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            buffer_init(ctx, label, contents, usage)
        };
        let mut levels = vec![level0];
        let mut sizes = vec![size];
        let (kernel, first) = filter.kernel();
        let weights: Vec<f32> = kernel.iter().map(|&w| w as f32).collect();
        let weights = init(
            "pyramid kernel",
            bytemuck::cast_slice(&weights),
            wgpu::BufferUsages::STORAGE,
        );
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pyramid build"),
            });
        while let Some(&n) = sizes.last() {
            if n == 1 {
                break;
            }
            let m = (n / 2).max(1);
            let params: [u32; 4] = [n as u32, m as u32, kernel.len() as u32, first as i32 as u32];
            let params = init(
                "pyramid params",
                bytemuck::cast_slice(&params),
                wgpu::BufferUsages::UNIFORM,
            );
            let omega: Vec<f32> = solid_angle_table(n).iter().map(|&w| w as f32).collect();
            let omega = init(
                "pyramid solid angles",
                bytemuck::cast_slice(&omega),
                wgpu::BufferUsages::STORAGE,
            );
            let ring = init(
                "pyramid ring",
                bytemuck::cast_slice(&ring_table(n)),
                wgpu::BufferUsages::STORAGE,
            );
            let child = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("pyramid level"),
                size: (6 * m * m * 16) as u64,
                usage,
                mapped_at_creation: false,
            });
            let Some(parent) = levels.last() else {
                break;
            };
            let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("pyramid.wgsl"),
                layout: &self.layout,
                entries: &[
                    buffer_entry(0, &params),
                    buffer_entry(1, parent),
                    buffer_entry(2, &omega),
                    buffer_entry(3, &ring),
                    buffer_entry(4, &weights),
                    buffer_entry(5, &child),
                ],
            });
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("pyramid level"),
                    timestamp_writes: None,
                });
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &group, &[]);
                let groups = (m as u32).div_ceil(8);
                pass.dispatch_workgroups(groups, groups, 6);
            }
            levels.push(child);
            sizes.push(m);
        }
        ctx.queue.submit([enc.finish()]);
        ctx.wait()?;
        scope_result(scope, "building the cube pyramid")?;
        Ok(GpuPyramid {
            sizes,
            levels,
            filter,
        })
    }
}

impl GpuPyramid {
    /// Uploads a pyramid built on the CPU (a captured probe, the environment), level by level
    /// in the layout [`GpuPyramidBuilder::build`] writes. Errors: a level beyond the device's
    /// storage buffers.
    pub fn upload(ctx: &GpuContext, pyramid: &CubePyramid) -> Result<Self> {
        let limit = ctx.device.limits().max_storage_buffer_binding_size as usize;
        let mut levels = Vec::with_capacity(pyramid.levels.len());
        for level in &pyramid.levels {
            let bytes = 6 * level.size * level.size * 16;
            if bytes > limit {
                return Err(invalid(
                    "cube pyramid",
                    format!(
                        "a {0}² level needs {bytes} bytes; the device allows {limit}",
                        level.size
                    ),
                ));
            }
            let texels: Vec<[f32; 4]> = level
                .faces
                .iter()
                .flat_map(|f| f.iter().map(|v| [v[0], v[1], v[2], 1.0]))
                .collect();
            levels.push(buffer_init(
                ctx,
                "pyramid level",
                bytemuck::cast_slice(&texels),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            ));
        }
        Ok(GpuPyramid {
            sizes: pyramid.levels.iter().map(|l| l.size).collect(),
            levels,
            filter: pyramid.filter,
        })
    }

    /// Copies every level to the host.
    pub fn read_back(&self, ctx: &GpuContext) -> Result<CubePyramid> {
        let scope = push_scope(ctx);
        let mut enc = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("pyramid readback"),
            });
        let staging: Vec<wgpu::Buffer> = self
            .levels
            .iter()
            .map(|b| {
                let s = ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("pyramid readback"),
                    size: b.size(),
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                enc.copy_buffer_to_buffer(b, 0, &s, 0, b.size());
                s
            })
            .collect();
        ctx.queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        for (k, s) in staging.iter().enumerate() {
            let tx = tx.clone();
            s.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                // The receiver lives until the poll below has returned.
                let _ = tx.send((k, r));
            });
        }
        drop(tx);
        ctx.wait()?;
        scope_result(scope, "pyramid readback")?;
        for (_, r) in rx.iter() {
            r.map_err(|e| wgpu_error("pyramid readback", e))?;
        }
        let mut levels = Vec::with_capacity(staging.len());
        for (s, &n) in staging.iter().zip(&self.sizes) {
            let faces = {
                let view = s
                    .slice(..)
                    .get_mapped_range()
                    .map_err(|e| wgpu_error("pyramid readback", e))?;
                let texels: &[[f32; 4]] = bytemuck::cast_slice(&view);
                std::array::from_fn(|f| {
                    texels[f * n * n..(f + 1) * n * n]
                        .iter()
                        .map(|t| [t[0], t[1], t[2]])
                        .collect()
                })
            };
            s.unmap();
            levels
                .push(CubeMap::new(n, faces).map_err(|e| invalid("cube pyramid", e.to_string()))?);
        }
        Ok(CubePyramid {
            levels,
            filter: self.filter,
        })
    }
}

/// This pass as a node of [`crate::passes`].
pub const NODE: crate::passes::Node = crate::passes::Node {
    name: "pyramid",
    shaders: &[("pyramid.wgsl", PYRAMID_WGSL)],
    inputs: &[crate::passes::Resource::CubeBase],
    outputs: &[crate::passes::Resource::Pyramid],
};
