//! Measured materials: MERL tables, neural BRDFs, RGL tensors and goniometric tables.

pub mod alta;
pub mod gonio;
pub mod merl;
pub mod nbrdf;
pub mod rgl;
pub mod rgl_warp;
