//! The sampled kinds' sample / eval / pdf run on a list of cases on the GPU (`harness.wgsl`
//! beside this file, composed with the generated dispatch [`super::kinds::BSDF`]): the twins the
//! parity tests hold against lustre-brdf.

use super::kinds::BSDF;
use super::GpuBsdf;
use crate::bindings::{buffer_entry, compute_pipeline, map_read, storage_buffer, storage_entry};
use crate::context::GpuContext;
use crate::error::{invalid, push_scope, Result};
use crate::wgsl;
use std::sync::OnceLock;

/// The WGSL source of the harness.
pub fn harness_wgsl() -> String {
    wgsl::compose(&[&BSDF], include_str!("harness.wgsl"))
}

/// One case of [`evaluate_models`]: record `record` at ωo, evaluated at ωi and sampled at u.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelCase {
    /// Index into the records.
    pub record: u32,
    /// ωo (local frame).
    pub wo: [f32; 3],
    /// ωi (local frame) of eval and pdf.
    pub wi: [f32; 3],
    /// The sample's (u1, u2).
    pub u: [f32; 2],
}

/// What [`evaluate_models`] returns per case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelResult {
    /// f(ωi, ωo).
    pub eval: [f32; 3],
    /// pdf(ωi, ωo).
    pub pdf: f32,
    /// The sampled direction.
    pub sample_wi: [f32; 3],
    /// Its pdf (0: no sample, the CPU's `None`).
    pub sample_pdf: f32,
    /// Its value.
    pub sample_value: [f32; 3],
    /// Whether it came from a Dirac lobe.
    pub delta: bool,
}

/// Runs the generated `bsdf_sample` / `bsdf_eval` / `bsdf_pdf` of `records` (with their `tables`) on `cases` on
/// the GPU: the twins the parity tests hold against lustre-brdf.
pub fn evaluate_models(
    ctx: &GpuContext,
    records: &[GpuBsdf],
    tables: &[f32],
    cases: &[ModelCase],
) -> Result<Vec<ModelResult>> {
    static SRC: OnceLock<String> = OnceLock::new();
    let src = SRC.get_or_init(harness_wgsl);
    if let Some(c) = cases.iter().find(|c| c.record as usize >= records.len()) {
        return Err(invalid(
            "model case",
            format!("record {} of {}", c.record, records.len()),
        ));
    }
    let (pipeline, layout) = compute_pipeline(
        ctx,
        "harness.wgsl",
        "compiling harness.wgsl",
        src,
        &[
            storage_entry(0, true),
            storage_entry(1, true),
            storage_entry(2, true),
            storage_entry(3, false),
        ],
    )?;
    let input: Vec<[f32; 4]> = cases
        .iter()
        .flat_map(|c| {
            [
                [c.wo[0], c.wo[1], c.wo[2], f32::from_bits(c.record)],
                [c.wi[0], c.wi[1], c.wi[2], 0.0],
                [c.u[0], c.u[1], 0.0, 0.0],
            ]
        })
        .collect();
    let scope = push_scope(ctx);
    let out_bytes = (input.len().max(1) * 16) as u64;
    let results = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("model results"),
        size: out_bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("model results readback"),
        size: out_bytes,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let (r, t, c) = (
        storage_buffer(ctx, "model records", records),
        storage_buffer(ctx, "model tables", tables),
        storage_buffer(ctx, "model cases", &input),
    );
    let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("harness.wgsl"),
        layout: &layout,
        entries: &[
            buffer_entry(0, &r),
            buffer_entry(1, &t),
            buffer_entry(2, &c),
            buffer_entry(3, &results),
        ],
    });
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("model cases"),
        });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("model cases"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((cases.len() as u32).div_ceil(64).max(1), 1, 1);
    }
    enc.copy_buffer_to_buffer(&results, 0, &staging, 0, out_bytes);
    ctx.queue.submit([enc.finish()]);
    let bytes = map_read(ctx, &staging, "model cases", scope)?;
    let v: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    Ok(cases
        .iter()
        .enumerate()
        .map(|(i, _)| {
            let (a, b, c) = (v[3 * i], v[3 * i + 1], v[3 * i + 2]);
            ModelResult {
                eval: [a[0], a[1], a[2]],
                pdf: a[3],
                sample_wi: [b[0], b[1], b[2]],
                sample_pdf: b[3],
                sample_value: [c[0], c[1], c[2]],
                delta: c[3] > 0.5,
            }
        })
        .collect())
}
