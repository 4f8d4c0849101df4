//! The scene, materials and sample patterns as flat GPU records (the layouts of `shade.wgsl`).

use bytemuck::{Pod, Zeroable};
use glam::DVec3;

/// The camera basis of the contract's primary rays, computed in f64: fwd = normalize(target −
/// eye), right = normalize(fwd × up), up' = right × fwd, a = tan(fov_y / 2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraBasis {
    /// Ray origin.
    pub eye: DVec3,
    /// Viewing direction.
    pub fwd: DVec3,
    /// Image x axis.
    pub right: DVec3,
    /// Image y axis (up').
    pub up: DVec3,
    /// tan(fov_y / 2).
    pub a: f64,
}

impl CameraBasis {
    /// The basis of a camera at `eye` looking at `target` with the hint `up` and vertical field
    /// of view `fov_y_deg` degrees.
    pub fn new(eye: DVec3, target: DVec3, up: DVec3, fov_y_deg: f64) -> Self {
        let fwd = (target - eye).normalize();
        let right = fwd.cross(up).normalize();
        let up = right.cross(fwd);
        CameraBasis {
            eye,
            fwd,
            right,
            up,
            a: (fov_y_deg.to_radians() / 2.0).tan(),
        }
    }

    /// True when every component is finite (a degenerate camera gives NaN).
    pub fn is_finite(&self) -> bool {
        self.eye.is_finite()
            && self.fwd.is_finite()
            && self.right.is_finite()
            && self.up.is_finite()
            && self.a.is_finite()
    }
}

/// A sphere (WGSL `Sphere`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSphere {
    /// Centre.
    pub center: [f32; 3],
    /// Radius.
    pub radius: f32,
    /// Tangent axis: t = normalize(axis × n).
    pub axis: [f32; 3],
    /// Index into the materials.
    pub material: u32,
}

/// A square (WGSL `Plane`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPlane {
    /// Centre of the square.
    pub point: [f32; 3],
    /// Half the side length.
    pub half_size: f32,
    /// Normal.
    pub normal: [f32; 3],
    /// Index into the materials.
    pub material: u32,
    /// Tangent hint (orthogonalized against the normal).
    pub tangent: [f32; 3],
    /// Padding.
    pub pad: u32,
}

/// A Kurt material (WGSL `Material`): kd and the range of its lobes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuKurtMaterial {
    /// Diffuse coefficient.
    pub kd: [f32; 3],
    /// First lobe (reflection lobes, then transmission lobes).
    pub lobe_start: u32,
    /// Number of reflection lobes.
    pub reflection: u32,
    /// Number of transmission lobes.
    pub transmission: u32,
    /// First sun in the sun array (`integrator::MaterialPlan::suns`).
    pub sun_start: u32,
    /// Number of suns.
    pub sun_count: u32,
}

/// A sun split off the environment (WGSL `Sun`; `lustre_env::Sun`), shaded exactly.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSun {
    /// Unit direction towards the sun, world space.
    pub direction: [f32; 3],
    /// Energy-weighted RMS angle of its texels around `direction`, radians (the lobes are
    /// widened by it, `integrator::sun_widened`).
    pub spread: f32,
    /// ∫ (excess radiance) dω per channel.
    pub irradiance: [f32; 3],
    /// Padding.
    pub pad1: f32,
}

/// One Kurt lobe with its regular pattern (WGSL `Lobe`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLobe {
    /// ks (kt for transmission).
    pub ks: [f32; 3],
    /// Roughness along the tangent.
    pub mx: f32,
    /// Roughness along the bitangent.
    pub my: f32,
    /// Schlick r0.
    pub r0: f32,
    /// Shadowing exponent α.
    pub alpha: f32,
    /// The pattern's threshold ξ0.
    pub xi0: f32,
    /// The pattern's PDF constant (002 Eq. 18).
    pub pdf_constant: f32,
    /// First half vector in the sample array.
    pub sample_start: u32,
    /// Number of half vectors; for [`LOBE_SCHEME_LATTICE`] and [`LOBE_SCHEME_TAP_LATTICE`] the
    /// budget (no stored vectors).
    pub sample_count: u32,
    /// [`LOBE_SCHEME_PATTERN`] (002's stored pattern, Pdf002 weights),
    /// [`LOBE_SCHEME_LATTICE`] (ours, the per-pixel row lattice) or
    /// [`LOBE_SCHEME_TAP_LATTICE`] (the lattice with several taps in its long cells).
    pub scheme: u32,
}

/// `GpuLobe::scheme` of a stored pattern (`integrator::plan_regular`, Pdf002 weights).
pub const LOBE_SCHEME_PATTERN: u32 = 0;
/// `GpuLobe::scheme` of ours, the per-pixel row lattice (`integrator::plan_lattice`).
pub const LOBE_SCHEME_LATTICE: u32 = 1;
/// `GpuLobe::scheme` of the row lattice with anisotropic footprints
/// (`integrator::plan_tap_lattice`; up to `pattern::LATTICE_MAX_TAPS` taps per cell).
pub const LOBE_SCHEME_TAP_LATTICE: u32 = 2;

/// The most lookups a stored pattern or row lattice may plan for one lobe on the GPU pass:
/// llvmpipe (lavapipe) ends all loops of a shader invocation once they have run 65,535
/// iterations together, silently. Measured on `tests/parity.rs`'s scene (two lobes a
/// material): patterns of 4,096 and row lattices of 1,024 still at 138–141 dB against the CPU.
pub const MAX_LOBE_LOOKUPS: u32 = 1024;

/// The largest budget of a tap lattice on the GPU pass: its cell search
/// (`regular.wgsl` `lattice_cells`, as `integrator::lattice_cells`) is quadratic in the budget;
/// on `tests/parity.rs`'s scene 160 came out at 141 dB against the CPU, 256 at 75 dB and 1,024
/// at 18 dB (llvmpipe's loop limit, as [`MAX_LOBE_LOOKUPS`]).
pub const MAX_TAP_LATTICE_BUDGET: u32 = 64;

/// Everything `shade.wgsl` reads besides the environment, ready to upload.
#[derive(Clone, Debug, PartialEq)]
pub struct PackedScene {
    /// The camera.
    pub camera: CameraBasis,
    /// Spheres.
    pub spheres: Vec<GpuSphere>,
    /// Squares.
    pub planes: Vec<GpuPlane>,
    /// Materials.
    pub materials: Vec<GpuKurtMaterial>,
    /// Lobes of all materials.
    pub lobes: Vec<GpuLobe>,
    /// Half vectors of all patterns (xyz, w = 0), in the lobe's local frame.
    pub samples: Vec<[f32; 4]>,
    /// Suns of all materials.
    pub suns: Vec<GpuSun>,
}

/// f64 vector → f32 array.
pub(crate) fn f3(v: DVec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}
