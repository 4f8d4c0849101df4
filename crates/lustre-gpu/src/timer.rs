//! Timing of GPU work: the GPU's own timestamps (wgpu `TIMESTAMP_QUERY`, requested by
//! [`GpuContext::new`] only where the adapter offers it) bracketing everything submitted between
//! [`GpuTimer::start`] and [`GpuTimer::stop`], and always the wall time from `start` until the
//! queue has drained (device polling). Without the feature only the wall time is reported. In a
//! browser (wasm32) nothing can wait for the GPU: no timestamps are read and the wall time is
//! that of recording and submitting.

use crate::context::GpuContext;
use crate::error::{push_scope, scope_result, wgpu_error, Result};
// std's Instant panics in a browser (wasm32): web-time's is std's natively, `performance.now()`
// there.
use web_time::Instant;

/// One measured interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timing {
    /// GPU time between the two timestamps, ms; `None` without `TIMESTAMP_QUERY`.
    pub gpu_ms: Option<f64>,
    /// Wall time from `start` until the GPU had finished, ms (includes the host's work of
    /// recording and submitting, and the wait).
    pub wall_ms: f64,
}

#[derive(Debug)]
struct Queries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

/// A reusable timer of one interval at a time.
#[derive(Debug)]
pub struct GpuTimer {
    queries: Option<Queries>,
    started: Option<Instant>,
}

impl GpuTimer {
    /// A timer on `ctx`: GPU timestamps where the device has `TIMESTAMP_QUERY`.
    pub fn new(ctx: &GpuContext) -> Self {
        // In a browser a timestamp read-back would have to wait for the page's event loop:
        // wall time only there.
        let queries = (!cfg!(target_arch = "wasm32")
            && ctx
                .device
                .features()
                .contains(wgpu::Features::TIMESTAMP_QUERY))
        .then(|| {
            let buffer = |label: &str, usage: wgpu::BufferUsages| {
                ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: 16,
                    usage,
                    mapped_at_creation: false,
                })
            };
            Queries {
                set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("gpu timer"),
                    ty: wgpu::QueryType::Timestamp,
                    count: 2,
                }),
                resolve: buffer(
                    "gpu timer resolve",
                    wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                ),
                readback: buffer(
                    "gpu timer readback",
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                ),
            }
        });
        GpuTimer {
            queries,
            started: None,
        }
    }

    /// Whether the timer reads GPU timestamps (else only wall time).
    pub fn has_timestamps(&self) -> bool {
        self.queries.is_some()
    }

    /// Waits for earlier work, then starts the interval (a timestamp submitted to the queue).
    pub fn start(&mut self, ctx: &GpuContext) -> Result<()> {
        ctx.wait()?;
        if let Some(q) = &self.queries {
            mark(ctx, &q.set, 0, None);
        }
        self.started = Some(Instant::now());
        Ok(())
    }

    /// Ends the interval (a timestamp after everything submitted since `start`), waits for the
    /// GPU and returns the times. Errors: not started, wgpu errors.
    pub fn stop(&mut self, ctx: &GpuContext) -> Result<Timing> {
        let t0 = self
            .started
            .take()
            .ok_or_else(|| wgpu_error("gpu timer", "stop without start"))?;
        let Some(q) = &self.queries else {
            ctx.wait()?;
            return Ok(Timing {
                gpu_ms: None,
                wall_ms: t0.elapsed().as_secs_f64() * 1e3,
            });
        };
        let scope = push_scope(ctx);
        mark(ctx, &q.set, 1, Some(q));
        let slice = q.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            // The receiver lives until the poll below has returned.
            let _ = tx.send(r);
        });
        ctx.wait()?;
        let wall_ms = t0.elapsed().as_secs_f64() * 1e3;
        scope_result(scope, "gpu timer")?;
        rx.recv()
            .map_err(|e| wgpu_error("gpu timer", e))?
            .map_err(|e| wgpu_error("gpu timer", e))?;
        let ticks: [u64; 2] = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| wgpu_error("gpu timer", e))?;
            let t: &[u64] = bytemuck::cast_slice(&view);
            [t[0], t[1]]
        };
        q.readback.unmap();
        let period = f64::from(ctx.queue.get_timestamp_period());
        Ok(Timing {
            gpu_ms: Some(ticks[1].saturating_sub(ticks[0]) as f64 * period * 1e-6),
            wall_ms,
        })
    }
}

/// Submits an empty compute pass writing timestamp `index` (at its start for 0, its end for 1);
/// with `resolve`, resolves both timestamps and copies them to the readback buffer.
fn mark(ctx: &GpuContext, set: &wgpu::QuerySet, index: u32, resolve: Option<&Queries>) {
    let mut enc = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("gpu timer"),
        });
    {
        let _pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gpu timer"),
            timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                query_set: set,
                beginning_of_pass_write_index: (index == 0).then_some(0),
                end_of_pass_write_index: (index == 1).then_some(1),
            }),
        });
    }
    if let Some(q) = resolve {
        enc.resolve_query_set(&q.set, 0..2, &q.resolve, 0);
        enc.copy_buffer_to_buffer(&q.resolve, 0, &q.readback, 0, 16);
    }
    ctx.queue.submit([enc.finish()]);
}
