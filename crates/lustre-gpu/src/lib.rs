//! lustre-gpu: lustre's shading on the GPU through wgpu (WGSL), headless, every pass beside a CPU
//! twin it is tested against.
//!
//! - [`passes`]: one folder per pass, its Rust beside its WGSL, each declared as a node with
//!   what it reads and writes; [`walkthrough`] chains the walkthrough's.
//! - [`material`]: the material record every pass reads, one home per material kind
//!   (`<kind>.rs` + `<kind>.wgsl`) registered in [`material::kinds::KINDS`], and the measured
//!   BRDFs' tables ([`material::measured`]).
//! - [`wgsl`]: the binding-free WGSL modules and the one composer that joins them to a pass;
//!   each module's header states what the pass must define.
//! - [`bindings`](crate::bindings) (crate-private): buffers, bind-group entries, pipelines and read-back.
//!
//! The sphere pass ([`passes::sphere`], `sphere.wgsl`) mirrors
//! `lustre_shade::integrator::shade_regular` with `Weighting::Pdf002` (002 §4–7, the pseudo code
//! `EvaluateSpecularLobe`) and the scene ray casting of `lustre_shade::analytic_scene`, in f32; its lobe,
//! MIP-level, lattice and weighting functions are the modules of [`wgsl`], composed in front of
//! it by [`sphere_wgsl`]. The environment pyramid is one cube texture with all its mip levels,
//! faces in Vulkan order as lustre-env stores them, sampled trilinearly and seamlessly by the
//! hardware.
//!
//! Use: `GpuContext::new()?`, `GpuRenderer::new(&ctx)?`, then
//! `renderer.render(&scene, &plans, &env, w, h)?` (one `MaterialPlan` per scene material) gives
//! an `Image`. For repeated frames upload once ([`GpuScene::upload`], [`GpuEnvironment::new`],
//! [`RenderTarget::new`]), [`GpuRenderer::bind`] them and time [`GpuRenderer::draw`]
//! (dispatch + wait) apart from [`RenderTarget::read_back`].
//!
//! Probes and view buffers: [`GpuProbeCapture::capture_probe`]
//! renders a probe's cube with the raster G-buffer and light-map shading passes straight into a
//! [`GpuPyramid`]'s base level and filters it on the GPU; [`GpuViewPass::render_mirror`] and
//! [`GpuViewPass::render_see_through`] fill the mirror / see-through view buffers
//! ([`GpuViewBuffer`]); [`GpuTimer`] times GPU work (timestamps where available).
//!
//! Measured (lavapipe on the shared 2-core machine, load ≈ 12): parity with the CPU integrator
//! 122 dB PSNR (7 samples per lobe) and 129 dB (19) at 128×96; 1920×1080 frames of a screen
//! full of one-lobe specular pixels 3.9 s (n = 3), 6.0 s (n = 11), 9.7 s (n = 19); half
//! specular 4.2 s (n = 11); readback 29 ms; upload of a 256² pyramid 243 ms (`benches/frame.rs`).

mod bindings;
pub mod context;
pub mod contract;
pub mod cube;
pub mod cube_storage;
pub mod error;
pub mod material;
pub mod packed;
pub mod passes;
pub mod timer;
pub mod view_buffer;
pub mod walkthrough;
pub mod wgsl;

pub use bindings::record_texture_readback;
pub use context::GpuContext;
pub use cube::{CubeLevelRef, GpuCube};
pub use error::{GpuError, Result};
pub use material::GpuBsdf;
pub use packed::{
    CameraBasis, GpuKurtMaterial, GpuLobe, GpuPlane, GpuSphere, GpuSun, PackedScene,
    LOBE_SCHEME_LATTICE, LOBE_SCHEME_PATTERN, LOBE_SCHEME_TAP_LATTICE, MAX_LOBE_LOOKUPS,
    MAX_TAP_LATTICE_BUDGET,
};
pub use passes::frame_shade::{FrameShadePass, FrameShadeScene, FrameShadeTarget};
pub use passes::gbuffer::{gbuffer_wgsl, DrawOptions, GBufferPass, GBufferTarget, GpuGeometry};
pub use passes::lightmap_shade::{
    lightmap_shade_wgsl, GpuLightmapScene, LightmapFrameScene, LightmapRenderer, LightmapShadePass,
    ShadeTarget,
};
pub use passes::probe_capture::{face_camera, mesh_triangles, GpuProbe, GpuProbeCapture};
pub use passes::pyramid::{GpuPyramid, GpuPyramidBuilder, PYRAMID_USAGE, PYRAMID_WGSL};
pub use passes::sphere::{
    sphere_wgsl, GpuEnvironment, GpuRenderer, GpuScene, RenderTarget, SphereBindings,
    SPHERE_PASS_WGSL,
};
pub use passes::view::{GpuViewPass, ViewRender};
pub use timer::{GpuTimer, Timing};
pub use view_buffer::GpuViewBuffer;
pub use walkthrough::{
    GpuFrame, GpuFrameSession, GpuFrameTimes, GpuStep, GpuWalkthrough, SessionIntermediates,
    StepWork, WalkthroughPasses,
};
