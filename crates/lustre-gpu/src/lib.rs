//! lustre-gpu: the regular-sampling kernel of lustre-shade in WGSL through wgpu, headless.
//!
//! `shade.wgsl` mirrors `lustre_shade::kernel::shade_regular` with `Weighting::Pdf002` (002 §4–7,
//! the pseudo code `EvaluateSpecularLobe`) and the scene ray casting of `lustre_shade::scene`, in
//! f32. The environment pyramid is one cube texture with all its mip levels, faces in Vulkan
//! order as lustre-env stores them, sampled trilinearly and seamlessly by the hardware.

pub mod context;
pub mod contract;
pub mod cube;
pub mod error;
pub mod packed;
pub mod shade;

pub use context::GpuContext;
pub use cube::{CubeLevelRef, GpuCube};
pub use error::{GpuError, Result};
pub use packed::{CameraBasis, GpuLobe, GpuMaterial, GpuPlane, GpuSphere, PackedScene};
pub use shade::{Frame, GpuEnvironment, GpuRenderer, GpuScene, RenderTarget, SHADE_WGSL};
