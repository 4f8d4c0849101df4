//! View buffers on the GPU (000 §4.5): the mirror buffer of a planar reflector and the
//! see-through buffer of a transmissive probe object, in the layout the view-dependent pass
//! (`frame_shade.wgsl`) reads and the GPU mirror pass writes. The CPU twin is
//! [`lustre_shade::mirror::ViewBuffer`].
//!
//! Layout: `radiance` = every MIP level concatenated finest first, level l of
//! ⌈w/2^l⌉ × ⌈h/2^l⌉ texels row-major, each `vec4<f32>` (rgb, 1) (the CPU's 2×2 box rule);
//! `geometry` = level 0 only, two `vec4<f32>` per texel: (position.xyz, 1 if the texel hit a
//! surface else 0), (normal.xyz, 0).

use crate::bindings::buffer_init;
use crate::bindings::read_buffer;
use crate::context::GpuContext;
use crate::error::{invalid, wgpu_error, Result};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_shade::mirror::{MirrorTexel, ReflectorPlane, ViewBuffer};
use lustre_trace::path_tracer::PathCamera;

/// A view buffer on the GPU (module docs for the layout).
#[derive(Debug)]
pub struct GpuViewBuffer {
    /// Every radiance level, finest first, `vec4<f32>` (rgb, 1) per texel.
    pub radiance: wgpu::Buffer,
    /// Level 0's geometry, two `vec4<f32>` per texel.
    pub geometry: wgpu::Buffer,
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// (width, height) of each level, finest first.
    pub level_sizes: Vec<(usize, usize)>,
    /// The camera the buffer was rendered from.
    pub camera: PathCamera,
    /// The mesh left out.
    pub mesh: u32,
    /// A mirror buffer's reflector plane (samples below it are not answered).
    pub front: Option<ReflectorPlane>,
}

/// The level sizes of a w×h buffer: ⌈w/2^l⌉ × ⌈h/2^l⌉ down to 1×1.
pub fn level_sizes(w: usize, h: usize) -> Vec<(usize, usize)> {
    let mut out = vec![(w, h)];
    while let Some(&(lw, lh)) = out.last() {
        if lw <= 1 && lh <= 1 {
            break;
        }
        out.push((lw.div_ceil(2), lh.div_ceil(2)));
    }
    out
}

impl GpuViewBuffer {
    /// Uploads a CPU view buffer. Errors: mis-sized levels or texels, buffers beyond the
    /// device's storage limit.
    pub fn upload(ctx: &GpuContext, v: &ViewBuffer) -> Result<Self> {
        let sizes = level_sizes(v.width, v.height);
        let consistent = v.texels.len() == v.width * v.height
            && v.levels.len() == sizes.len()
            && v.levels
                .iter()
                .zip(&sizes)
                .all(|((w, h, d), &(sw, sh))| (*w, *h) == (sw, sh) && d.len() == w * h);
        if !consistent {
            return Err(invalid(
                "view buffer",
                format!(
                    "a {}×{} buffer with {} texels and {} levels does not follow the 2×2 MIP rule",
                    v.width,
                    v.height,
                    v.texels.len(),
                    v.levels.len()
                ),
            ));
        }
        let radiance: Vec<[f32; 4]> = v
            .levels
            .iter()
            .flat_map(|(_, _, d)| {
                d.iter()
                    .map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0])
            })
            .collect();
        let geometry: Vec<[f32; 4]> = v
            .texels
            .iter()
            .flat_map(|t| {
                let (p, hit) = t.position.map_or((DVec3::ZERO, 0.0), |p| (p, 1.0));
                [
                    [p.x as f32, p.y as f32, p.z as f32, hit],
                    [t.normal.x as f32, t.normal.y as f32, t.normal.z as f32, 0.0],
                ]
            })
            .collect();
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let bytes = (radiance.len().max(geometry.len()) * 16) as u64;
        if bytes > limit {
            return Err(invalid(
                "view buffer",
                format!("{bytes} bytes exceed the device's {limit}-byte storage buffers"),
            ));
        }
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        Ok(GpuViewBuffer {
            radiance: buffer_init(
                ctx,
                "view buffer radiance",
                bytemuck::cast_slice(&radiance),
                usage,
            ),
            geometry: buffer_init(
                ctx,
                "view buffer geometry",
                bytemuck::cast_slice(&geometry),
                usage,
            ),
            width: v.width,
            height: v.height,
            level_sizes: sizes,
            camera: v.camera,
            mesh: v.mesh,
            front: v.front,
        })
    }

    /// Copies the buffer back into a CPU view buffer (f32 values widened).
    pub fn read_back(&self, ctx: &GpuContext) -> Result<ViewBuffer> {
        let read = |b: &wgpu::Buffer| -> Result<Vec<[f32; 4]>> {
            let bytes = read_buffer(ctx, b, "view buffer readback")?;
            Ok(bytemuck::cast_slice(&bytes).to_vec())
        };
        let radiance = read(&self.radiance)?;
        let geometry = read(&self.geometry)?;
        let n = self.width * self.height;
        let total: usize = self.level_sizes.iter().map(|(w, h)| w * h).sum();
        if geometry.len() < 2 * n || radiance.len() < total {
            return Err(wgpu_error(
                "view buffer readback",
                format!(
                    "{} geometry and {} radiance texels for a {}×{} buffer",
                    geometry.len(),
                    radiance.len(),
                    self.width,
                    self.height
                ),
            ));
        }
        let rgb = |c: [f32; 4]| Rgb::new(c[0].into(), c[1].into(), c[2].into());
        let v3 = |c: [f32; 4]| DVec3::new(c[0].into(), c[1].into(), c[2].into());
        let texels = (0..n)
            .map(|i| {
                let (g, nn) = (geometry[2 * i], geometry[2 * i + 1]);
                MirrorTexel {
                    radiance: rgb(radiance[i]),
                    position: (g[3] > 0.5).then(|| v3(g)),
                    normal: v3(nn),
                }
            })
            .collect();
        let mut at = 0;
        let levels = self
            .level_sizes
            .iter()
            .map(|&(w, h)| {
                let l = (
                    w,
                    h,
                    radiance[at..at + w * h].iter().map(|&c| rgb(c)).collect(),
                );
                at += w * h;
                l
            })
            .collect();
        Ok(ViewBuffer {
            mesh: self.mesh,
            camera: self.camera,
            width: self.width,
            height: self.height,
            texels,
            levels,
            front: self.front,
        })
    }
}
