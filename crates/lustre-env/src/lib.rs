//! lustre-env: environment maps (Radiance .hdr, OpenEXR), equirectangular and cube maps, cube MIP
//! pyramids with the filters of 002 §3, and procedural test maps.
//!
//! Conventions (see the workspace contracts): world +y up; equirect maps 2:1 with row 0 at the
//! top; cube maps in Vulkan/wgpu face order and orientation (+X, −X, +Y, −Y, +Z, −Z), so a GPU
//! can upload the faces as they are and sample them with `textureSampleLevel`.

pub mod cube;
pub mod equirect;
pub mod error;
pub mod io;
pub mod irradiance;
pub mod pyramid;
pub mod sampling;
pub mod spot;
pub mod sun;

pub use cube::CubeMap;
pub use equirect::EquirectMap;
pub use error::{EnvError, Result};
pub use io::{map_size, parse_exr, parse_hdr, read_map, shared_data_dir, LoadedMap};
pub use irradiance::irradiance_map;
pub use pyramid::{CubePyramid, MipFilter};
pub use sampling::{Distribution1D, EnvSample, EnvSampler};
pub use spot::{spot_map, SpotMapParams};
pub use sun::{split_suns, Sun, SunFill, SunOptions, SunSplit};
