//! Cube maps on the GPU: every level of a pyramid in one cube texture (faces as they are, Vulkan
//! order +X, −X, +Y, −Y, +Z, −Z; texel (i, j) of a face at `data[j*N + i]`, row j = t).

use crate::context::GpuContext;
use crate::error::{invalid, Result};

/// One level of a cube map as the CPU stores it (lustre-env `CubeMap`): face size and six faces
/// of `size²` linear RGB texels each.
#[derive(Clone, Copy, Debug)]
pub struct CubeLevelRef<'a> {
    /// Face size N of this level.
    pub size: usize,
    /// The six faces in Vulkan order.
    pub faces: [&'a [[f32; 3]]; 6],
}

/// A cube texture with all the mip levels it was given, and its cube view.
#[derive(Debug)]
pub struct GpuCube {
    /// The texture (6 array layers).
    pub texture: wgpu::Texture,
    /// A `Cube` view over all levels.
    pub view: wgpu::TextureView,
    /// Face size of level 0.
    pub size: usize,
    /// Number of mip levels.
    pub levels: usize,
}

/// Texel format of the environment textures: Rgba32Float where the adapter can filter it,
/// Rgba16Float otherwise.
pub fn env_format(ctx: &GpuContext) -> wgpu::TextureFormat {
    if ctx.float32_filterable {
        wgpu::TextureFormat::Rgba32Float
    } else {
        wgpu::TextureFormat::Rgba16Float
    }
}

impl GpuCube {
    /// Uploads `levels` (level l must have face size max(1, N >> l)); `label` names the map in
    /// errors.
    pub fn upload(ctx: &GpuContext, label: &str, levels: &[CubeLevelRef<'_>]) -> Result<Self> {
        let Some(first) = levels.first() else {
            return Err(invalid(label, "the cube map has no levels"));
        };
        let size = first.size;
        let max_dim = ctx.device.limits().max_texture_dimension_2d as usize;
        if size == 0 || size > max_dim {
            return Err(invalid(
                label,
                format!("face size {size} is outside 1..={max_dim}"),
            ));
        }
        let full_chain = usize::BITS as usize - size.leading_zeros() as usize;
        if levels.len() > full_chain {
            return Err(invalid(
                label,
                format!(
                    "{} levels for face size {size} (at most {full_chain})",
                    levels.len()
                ),
            ));
        }
        for (l, level) in levels.iter().enumerate() {
            let want = (size >> l).max(1);
            if level.size != want {
                return Err(invalid(
                    label,
                    format!("level {l} has face size {}, expected {want}", level.size),
                ));
            }
            for (f, face) in level.faces.iter().enumerate() {
                if face.len() != want * want {
                    return Err(invalid(
                        label,
                        format!(
                            "level {l} face {f} has {} texels, expected {}",
                            face.len(),
                            want * want
                        ),
                    ));
                }
            }
        }
        let format = env_format(ctx);
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: size as u32,
                height: size as u32,
                depth_or_array_layers: 6,
            },
            mip_level_count: levels.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        for (l, level) in levels.iter().enumerate() {
            let n = level.size;
            let bytes = texel_bytes(format, level.faces.iter().flat_map(|f| f.iter()));
            let texel_size = bytes.len() / (6 * n * n);
            ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: l as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                &bytes,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some((n * texel_size) as u32),
                    rows_per_image: Some(n as u32),
                },
                wgpu::Extent3d {
                    width: n as u32,
                    height: n as u32,
                    depth_or_array_layers: 6,
                },
            );
        }
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some(label),
            dimension: Some(wgpu::TextureViewDimension::Cube),
            ..Default::default()
        });
        Ok(GpuCube {
            texture,
            view,
            size,
            levels: levels.len(),
        })
    }
}

/// RGB texels as RGBA bytes of `format` (alpha 1).
fn texel_bytes<'a>(
    format: wgpu::TextureFormat,
    texels: impl Iterator<Item = &'a [f32; 3]>,
) -> Vec<u8> {
    match format {
        wgpu::TextureFormat::Rgba32Float => texels
            .flat_map(|t| [t[0], t[1], t[2], 1.0])
            .flat_map(f32::to_le_bytes)
            .collect(),
        _ => texels
            .flat_map(|t| [t[0], t[1], t[2], 1.0])
            .flat_map(|v| half::f16::from_f32(v).to_le_bytes())
            .collect(),
    }
}

/// The trilinear, clamp-to-edge sampler of every environment lookup (seamless across cube faces
/// on Vulkan).
pub fn linear_sampler(ctx: &GpuContext) -> wgpu::Sampler {
    ctx.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("lustre-gpu trilinear"),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        address_mode_w: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        lod_min_clamp: 0.0,
        lod_max_clamp: 32.0,
        compare: None,
        anisotropy_clamp: 1,
        border_color: None,
    })
}
