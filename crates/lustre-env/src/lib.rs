//! lustre-env: environment maps (Radiance .hdr, OpenEXR), equirectangular and cube maps, cube MIP
//! pyramids with the filters of 002 §3, and procedural test maps.

pub mod error;

pub use error::{EnvError, Result};
