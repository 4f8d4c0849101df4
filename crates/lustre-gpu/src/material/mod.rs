//! The material record every shading pass reads ([`GpuBsdf`]: kind, flags, 32 floats) and one
//! home per material kind: `<kind>.rs` packs the lustre-brdf model into the record's floats,
//! `<kind>.wgsl` beside it evaluates, samples and (where textured) rewrites them — the twins of
//! the CPU's `Bsdf::{eval, pdf, sample}`. The kinds are registered once, in [`kinds::KINDS`]:
//! the WGSL constants and dispatch switches are generated from that table.
//!
//! - sampled kinds ([`kinds::Ops::Sampled`]): [`rough_conductor`], [`rough_plastic`],
//!   [`rough_dielectric`], [`conductor`], [`thin_dielectric`], [`pbr_metallic_roughness`],
//!   [`lambert`], [`plastic`], [`dielectric`], and the fitted models [`sgd`],
//!   [`cook_torrance`], [`kurt`] ([`fitted::pack_fit`] picks among them);
//! - evaluated kinds ([`kinds::Ops::Evaluated`]): the analytic models of [`analytic`];
//! - [`scene`]: a scene material as its record ([`scene::pack_material`]) and its per-pixel
//!   inputs ([`scene::pack_material_params`]); [`harness`]: the models run on a list of cases
//!   for the parity tests.

pub mod analytic;
pub mod conductor;
pub mod cook_torrance;
pub mod dielectric;
pub mod fitted;
pub mod harness;
pub mod kinds;
pub mod kurt;
pub mod lambert;
pub mod measured;
pub mod pbr_metallic_roughness;
pub mod plastic;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;
pub mod scene;
pub mod sgd;
pub mod textured;
pub mod thin_dielectric;

pub use conductor::pack_conductor;
pub use dielectric::pack_dielectric;
pub use kinds::*;
pub use lambert::pack_lambert;
pub use pbr_metallic_roughness::pack_pbr_metallic_roughness;
pub use plastic::pack_plastic;
pub use rough_conductor::pack_rough_conductor;
pub use rough_dielectric::pack_rough_dielectric;
pub use rough_plastic::{pack_rough_plastic, rough_plastic_table, ROUGH_PLASTIC_TABLE};
pub use scene::{pack_material, pack_material_params, MATERIAL_PARAMS};
pub use thin_dielectric::pack_thin_dielectric;

use crate::error::{invalid, Result};
use lustre_brdf::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use lustre_brdf::rgb::Rgb;

/// The 32 floats of a record, `p[i][j]` float 4i + j, in the kind's layout (its `.wgsl`
/// header).
pub type RecordParams = [[f32; 4]; 8];

/// [`GpuBsdf::flags`]: only diffuse lobes (no view-dependent part where kd ≠ 0).
pub const FLAG_DIFFUSE_ONLY: u32 = 4;
/// [`GpuBsdf::flags`]: only Dirac lobes (summed exactly over their branches).
pub const FLAG_DELTA_ONLY: u32 = 1;
/// [`GpuBsdf::flags`]: a two-sided material (the frame is turned towards the viewer).
pub const FLAG_TWO_SIDED: u32 = 2;
/// [`GpuBsdf::flags`]: a BSDF parameter is textured: the pass reads the material's parameters
/// at the pixel's uv0 from its [`pack_material_params`] record and rewrites the model's
/// (`textured_bsdf`, [`kinds::TEXTURED`]), as `Material::with_bsdf_at` builds the CPU model;
/// the record holds the clamped factors. The kinds with textured parameters ([`kinds::Ops::Sampled`] `{ textured: true }`; a glTF
/// record may turn into a rough or smooth dielectric per pixel: its transmission decides).
pub const FLAG_TEXTURED: u32 = 8;
/// [`GpuBsdf::flags`]: a normal-mapped material: the shading frame is tilted per pixel as the
/// CPU's `PathTracer::shading_point` tilts it (`textured.wgsl`'s `mapped_normal`).
pub const FLAG_NORMAL_MAPPED: u32 = 16;

/// One material of the view-dependent pass (144 bytes, `record.wgsl`'s `GpuBsdf`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuBsdf {
    /// The kind's code ([`kinds::KINDS`]).
    pub kind: u32,
    /// [`FLAG_DELTA_ONLY`] | [`FLAG_TWO_SIDED`] | [`FLAG_DIFFUSE_ONLY`] | [`FLAG_TEXTURED`] |
    /// [`FLAG_NORMAL_MAPPED`].
    pub flags: u32,
    /// Zero.
    pub pad0: u32,
    /// Zero.
    pub pad1: u32,
    /// The model's parameters, in its module's layout.
    pub p: [[f32; 4]; 8],
}

impl GpuBsdf {
    /// Kind 0 (no view-dependent part), no flags.
    pub fn zeroed_record() -> Self {
        bytemuck::Zeroable::zeroed()
    }
}

/// The parameters of a record, each checked finite (named in the error).
pub(crate) struct Params {
    pub(crate) p: [[f32; 4]; 8],
    model: &'static str,
}

impl Params {
    pub(crate) fn new(model: &'static str) -> Self {
        Params {
            p: [[0.0; 4]; 8],
            model,
        }
    }

    pub(crate) fn set(&mut self, row: usize, v: [f64; 4]) -> Result<()> {
        for (k, x) in v.iter().enumerate() {
            let y = *x as f32;
            if !y.is_finite() {
                return Err(invalid(
                    self.model,
                    format!("parameter p{row}[{k}] = {x} does not fit an f32"),
                ));
            }
            self.p[row][k] = y;
        }
        Ok(())
    }

    pub(crate) fn rgb(&mut self, row: usize, c: Rgb, w: f64) -> Result<()> {
        self.set(row, [c[0], c[1], c[2], w])
    }
}

pub(crate) fn distribution_code(d: &MicrofacetDistribution) -> f64 {
    match d.kind() {
        MicrofacetType::Beckmann => 0.0,
        MicrofacetType::Ggx => 1.0,
    }
}

/// [`FLAG_DIFFUSE_ONLY`] or [`FLAG_DELTA_ONLY`] as a model's lobes are.
pub(crate) fn lobe_flags(f: &lustre_brdf::bsdf::BsdfFlags) -> u32 {
    if f.diffuse_only() {
        FLAG_DIFFUSE_ONLY
    } else if f.delta_only() {
        FLAG_DELTA_ONLY
    } else {
        0
    }
}
