//! lustre-shade: integration of incident light over BSDF lobes on the CPU.
//!
//! - [`pattern`]: regular sample patterns (002 §5, 000 §4.4.3, §4.5.3).
//! - [`mip`]: per-sample MIP levels (002 Eq. 14–16, 000 Eq. 4.14–4.17, Colbert-Křivánek).
//! - [`image`], [`metrics`]: float images, RMS / PSNR / CIE Lab ΔE, false-colour differences.
//! - [`kernel`]: per-pixel shading kernels: reference, progressive QMC, regular, Colbert-Křivánek.
//! - [`scene`], [`render`], [`harness`]: evaluation scenes, image rendering, the comparisons.
//! - [`truth`]: the exact environment integral over every texel (the truth harness).
//! - [`accel`], [`path`]: ray casting (BVH, watertight triangles) and the path-traced reference.
//! - [`bake`]: light maps of irradiance (000 §4.3), tiled, resumable, shardable, denoised.

pub mod accel;
pub mod bake;
pub mod baked;
pub mod error;
pub mod frame;
pub mod harness;
pub mod image;
pub mod kernel;
pub mod metrics;
pub mod mip;
pub mod mirror;
pub mod path;
pub mod pattern;
pub mod probe;
pub mod reference;
pub mod render;
pub mod request;
pub mod scene;
pub mod truth;
pub mod warp;

pub use error::{Result, ShadeError};
