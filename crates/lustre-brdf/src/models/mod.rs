//! Analytic BSDF models, one per file.

pub mod abc;
pub mod ashikhmin_shirley;
pub mod blinn_phong;
pub mod conductor;
pub mod conductor_presets;
pub mod cook_torrance;
pub mod dielectric;
mod glossy_diffuse;
pub mod kurt;
pub mod lafortune;
pub mod lambert;
pub mod oren_nayar;
pub mod pbr_metallic_roughness;
pub mod phong;
pub mod plastic;
pub mod rough_conductor;
pub mod rough_dielectric;
pub mod rough_plastic;
pub mod sheen;
pub mod thin_dielectric;
pub mod two_sided;
pub mod ward;
pub mod ward_duer;
pub mod ward_gmd;
