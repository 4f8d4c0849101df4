//! Building blocks the passes share: initialised buffers, bind-group-layout entries and a
//! compiled single-bind-group compute pipeline.

use crate::context::GpuContext;
use crate::error::{scope_result, Result};
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
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
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
