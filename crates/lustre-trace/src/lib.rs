//! lustre-trace: ray tracing on the CPU, the path-traced reference and light-map baking.
//!
//! - [`accel`]: ray casting (obvhs CWBVH, watertight triangles).
//! - [`path_tracer`]: the path tracer (BSDF sampling, next-event estimation of the environment and
//!   emitters, MIS).
//! - [`reference`](mod@reference): path-traced reference images of a scene, resumable.
//! - [`bake`]: light maps of irradiance (000 §4.3), tiled, resumable, shardable, denoised; the
//!   light-mapped G-buffer and rendering.
//! - [`baked`]: a scene's light maps and environment pyramid, baked or read back.
//! - [`setup`]: the automatic real-time set-up (mirrors, object probes, room probes).
//! - [`sampling`]: the shading frame and the MIS weight shared with lustre-shade's kernels.
//! - [`image`], [`metrics`]: float images, RMS / PSNR / CIE Lab ΔE, false-colour differences.

pub mod accel;
pub mod bake;
pub mod baked;
pub mod error;
pub mod image;
pub mod metrics;
pub mod path_tracer;
pub mod reference;
pub mod sampling;
pub mod setup;

pub use error::{Result, TraceError};
