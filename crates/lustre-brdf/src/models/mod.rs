//! Analytic BSDF models, one per file.

pub mod abc;
pub mod ashikhmin_shirley;
pub mod blinn_phong;
pub mod cook_torrance;
pub mod kurt;
pub mod lafortune;
pub mod lambert;
pub mod oren_nayar;
pub mod phong;
pub mod ward;
pub mod ward_duer;
pub mod ward_gmd;
