//! lustre-shade: integration of incident light over BSDF lobes on the CPU, the real-time
//! methods' CPU twins. Ray casting, the path tracer, the reference, baking, images and metrics are
//! in lustre-trace.
//!
//! - [`pattern`]: regular sample patterns (002 §5, 000 §4.4.3, §4.5.3).
//! - [`mip`]: per-sample MIP levels (002 Eq. 14–16, 000 Eq. 4.14–4.17, Colbert-Křivánek).
//! - [`integrator`]: per-pixel integrators: reference, progressive QMC, regular, Colbert-Křivánek.
//! - [`warp`]: regular sampling through any model's importance warp.
//! - [`analytic_scene`], [`render`], [`harness`]: evaluation scenes, image rendering, the comparisons.
//! - [`truth`]: the exact environment integral over every texel (the truth harness).
//! - [`frame`]: the walkthrough frame: light maps, probes ([`probe`]), mirror and see-through
//!   buffers ([`mirror`]).

pub mod analytic_scene;
pub mod error;
pub mod frame;
pub mod harness;
pub mod integrator;
pub mod mip;
pub mod mirror;
pub mod pattern;
pub mod probe;
pub mod render;
pub mod request;
pub mod truth;
pub mod warp;

pub use error::{Result, ShadeError};
