//! Building blocks the passes share: initialised buffers, bind-group-layout and bind-group
//! entries, compiled single-bind-group compute pipelines, and read-back ([`map_read`], [`read_buffer`],
//! [`record_texture_readback`]).

use crate::context::GpuContext;
use crate::error::{push_scope, scope_result, wgpu_error, Result, Scope};
use wgpu::util::DeviceExt;

/// A buffer holding `contents`, for `usage`.
pub(crate) fn buffer_init(
    ctx: &GpuContext,
    label: &str,
    contents: &[u8],
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    ctx.device
        .create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
}

/// A storage buffer of `data`, one zero element when it is empty (bindings are never empty).
pub(crate) fn storage_buffer<T: bytemuck::Pod + bytemuck::Zeroable>(
    ctx: &GpuContext,
    label: &str,
    data: &[T],
) -> wgpu::Buffer {
    let zero = [T::zeroed()];
    let data = if data.is_empty() { &zero[..] } else { data };
    buffer_init(
        ctx,
        label,
        bytemuck::cast_slice(data),
        wgpu::BufferUsages::STORAGE,
    )
}

/// The whole of buffer `b` at `binding` of a bind group.
pub(crate) fn buffer_entry(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry {
        binding,
        resource: b.as_entire_binding(),
    }
}

/// A sampled texture of `view_dimension` at `binding`, visible to compute.
pub(crate) fn texture_entry(
    binding: u32,
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension,
            multisampled: false,
        },
        count: None,
    }
}

/// A uniform buffer at `binding`, visible to compute.
pub(crate) fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A storage buffer at `binding`, visible to compute.
pub(crate) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// Compiles the WGSL `source` (entry point `main`, one bind group laid out as `entries`);
/// `label` names the shader in wgpu's messages and `stage` in ours.
pub(crate) fn compute_pipeline(
    ctx: &GpuContext,
    label: &'static str,
    stage: &'static str,
    source: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> Result<(wgpu::ComputePipeline, wgpu::BindGroupLayout)> {
    let ([pipeline], layout) = compute_pipelines(ctx, label, stage, source, entries, ["main"])?;
    Ok((pipeline, layout))
}

/// [`compute_pipeline`] for several entry points of one module sharing one bind-group layout,
/// in the order of `entry_points`.
pub(crate) fn compute_pipelines<const N: usize>(
    ctx: &GpuContext,
    label: &'static str,
    stage: &'static str,
    source: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
    entry_points: [&str; N],
) -> Result<([wgpu::ComputePipeline; N], wgpu::BindGroupLayout)> {
    let scope = push_scope(ctx);
    let module = ctx
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
    let layout = ctx
        .device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries,
        });
    let pipeline_layout = ctx
        .device
        .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
    let pipelines = entry_points.map(|entry| {
        ctx.device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
    });
    scope_result(scope, stage)?;
    Ok((pipelines, layout))
}

/// The bytes of the whole of `buffer` (COPY_SRC): copied into a staging buffer and mapped
/// ([`map_read`]), `label` naming the staging buffer, the copy and the stage in errors.
pub(crate) fn read_buffer(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    label: &'static str,
) -> Result<Vec<u8>> {
    let scope = push_scope(ctx);
    let staging = staged_copy(ctx, buffer, label);
    map_read(ctx, &staging, label, scope)
}

/// A MAP_READ staging buffer holding a copy of the whole of `buffer` (the copy submitted).
fn staged_copy(ctx: &GpuContext, buffer: &wgpu::Buffer, label: &'static str) -> wgpu::Buffer {
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: buffer.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
    ctx.queue.submit([enc.finish()]);
    staging
}

/// Maps `buffer` (MAP_READ, its copy already submitted), waits, checks `scope` and returns
/// its bytes.
pub(crate) fn map_read(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    stage: &'static str,
    scope: Scope,
) -> Result<Vec<u8>> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        // The receiver lives until the poll below has returned.
        let _ = tx.send(r);
    });
    ctx.wait()?;
    scope_result(scope, stage)?;
    rx.recv()
        .map_err(|e| wgpu_error(stage, e))?
        .map_err(|e| wgpu_error(stage, e))?;
    let out = slice
        .get_mapped_range()
        .map_err(|e| wgpu_error(stage, e))?
        .to_vec();
    buffer.unmap();
    Ok(out)
}

/// Records on `enc` the copy of level 0 of `texture`, `w`×`h` texels of `bpp` bytes, into a new
/// MAP_READ buffer labelled `label` whose rows are padded to
/// [`wgpu::COPY_BYTES_PER_ROW_ALIGNMENT`]: returns the buffer and its row length in bytes.
pub fn record_texture_readback(
    device: &wgpu::Device,
    enc: &mut wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    (w, h): (u32, u32),
    bpp: u32,
    label: &str,
) -> (wgpu::Buffer, u32) {
    let row = w * bpp;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: u64::from(padded) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    enc.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    (buffer, padded)
}

/// The bytes of the whole of `buffer` (COPY_SRC) without blocking: the copy into a staging
/// buffer is recorded and submitted now, its mapping requested, and the future completes when
/// the mapping has. In a browser the page's event loop completes the mapping; natively the
/// device is polled first, so the future is ready when first polled.
pub(crate) fn read_buffer_later(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    label: &'static str,
) -> Result<impl std::future::Future<Output = Result<Vec<u8>>> + 'static> {
    let staging = staged_copy(ctx, buffer, label);
    let mapped = Mapping::default();
    let done = mapped.clone();
    staging
        .slice(..)
        .map_async(wgpu::MapMode::Read, move |r| done.finish(r));
    ctx.wait()?;
    Ok(async move {
        mapped.await.map_err(|e| wgpu_error(label, e))?;
        let out = staging
            .slice(..)
            .get_mapped_range()
            .map_err(|e| wgpu_error(label, e))?
            .to_vec();
        staging.unmap();
        Ok(out)
    })
}

/// A mapping's outcome once known, and the task waiting for it.
#[derive(Debug, Default)]
struct MappingState {
    done: Option<std::result::Result<(), wgpu::BufferAsyncError>>,
    waker: Option<std::task::Waker>,
}

/// A buffer mapping in flight, as a future: `map_async`'s callback calls [`Mapping::finish`].
#[derive(Clone, Debug, Default)]
struct Mapping(std::sync::Arc<std::sync::Mutex<MappingState>>);

impl Mapping {
    fn finish(&self, r: std::result::Result<(), wgpu::BufferAsyncError>) {
        let waker = match self.0.lock() {
            Ok(mut s) => {
                s.done = Some(r);
                s.waker.take()
            }
            Err(_) => None,
        };
        if let Some(w) = waker {
            w.wake();
        }
    }
}

impl std::future::Future for Mapping {
    type Output = std::result::Result<(), String>;

    fn poll(
        self: std::pin::Pin<&mut Self>,
        cx: &mut std::task::Context<'_>,
    ) -> std::task::Poll<Self::Output> {
        let Ok(mut s) = self.0.lock() else {
            return std::task::Poll::Ready(Err("the mapping's state was poisoned".into()));
        };
        match s.done.take() {
            Some(r) => std::task::Poll::Ready(r.map_err(|e| e.to_string())),
            None => {
                s.waker = Some(cx.waker().clone());
                std::task::Poll::Pending
            }
        }
    }
}
