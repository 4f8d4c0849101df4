//! The GPU passes as nodes. Each `passes/<name>/` holds one pass's Rust (its pipelines, bind
//! groups and dispatches) beside its own WGSL (bindings and entry points; the binding-free
//! modules it composes are [`crate::wgsl`]'s and [`crate::material`]'s), and declares a
//! [`Node`]: its shaders and the [`Resource`]s it reads and writes. The chains lustre runs —
//! [`WALKTHROUGH`] (`crate::walkthrough`), [`ADAPTIVE`] and [`SPHERE`] — list the nodes in the
//! order they run; a unit test checks that every input is external or written by an earlier node.
//! Every pass has a CPU twin, named in its module's header, and a parity test.
//!
//! | pass | reads | writes |
//! |---|---|---|
//! | [`gbuffer`] | scene, camera | G-buffer |
//! | [`lightmap_shade`] | G-buffer, scene, light maps, environment | light-mapped image |
//! | [`pyramid`] | a cube's base level | its MIP pyramid |
//! | [`probe_capture`] | scene, light maps, environment | probe pyramids (through the three above) |
//! | [`view`] | scene, light maps, environment, camera | mirror and see-through view buffers |
//! | [`frame_shade`] | G-buffer, light-mapped image, materials, probe and environment pyramids, view buffers | the frame |
//! | [`bandwidth`] | shading points, materials, environment, area lights | bandwidth and variance sums |
//! | [`adaptive`] | bandwidth levels, shading points, materials, environment, area lights | the adaptive frame |
//! | [`sphere`] | sphere scene, environment pyramid | the sphere pass's image |

pub mod adaptive;
pub mod bandwidth;
pub mod frame_shade;
pub mod gbuffer;
pub mod lightmap_shade;
pub mod probe_capture;
pub mod pyramid;
pub mod sphere;
pub mod view;

/// What a pass reads or writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Resource {
    /// The scene's triangles, per-triangle records and textures (external).
    Scene,
    /// The camera (external).
    Camera,
    /// The baked light-map pages (external).
    LightMaps,
    /// The environment: its equirect map or filtered cube pyramid (external).
    Environment,
    /// The scene's emitters as textured area lights (external).
    AreaLights,
    /// The materials as [`crate::material::GpuBsdf`] records and measured tables (external).
    Materials,
    /// A cube map's base level (external to the pyramid pass; written by a probe capture).
    CubeBase,
    /// Triangle id, barycentrics, depth and shading normal per pixel.
    GBuffer,
    /// The adaptive method's shading points: per pixel the surface, its normal, material and
    /// screen-space rates, ray-cast on the CPU (`lustre_adaptive::gbuffer`) (external).
    ShadingPoints,
    /// Emission plus light-mapped diffuse light per pixel.
    LightmappedImage,
    /// A cube map's filtered MIP pyramid.
    Pyramid,
    /// Every probe's filtered pyramid.
    ProbePyramids,
    /// The mirror and see-through view buffers with their MIP levels.
    ViewBuffers,
    /// The walkthrough frame (and its progressive accumulation).
    Frame,
    /// Per pixel the one-bounce bandwidth and variance sums (004 §IV.4.1).
    Bandwidth,
    /// The adaptive method's frame.
    AdaptiveFrame,
    /// The sphere pass's scene: spheres, planes and lobes ([`crate::PackedScene`]) (external).
    SphereScene,
    /// The sphere pass's image.
    SphereImage,
}

impl Resource {
    /// Whether lustre's CPU side provides it (no pass writes it).
    pub fn external(self) -> bool {
        matches!(
            self,
            Resource::Scene
                | Resource::Camera
                | Resource::LightMaps
                | Resource::Environment
                | Resource::AreaLights
                | Resource::Materials
                | Resource::CubeBase
                | Resource::ShadingPoints
                | Resource::SphereScene
        )
    }
}

/// A pass: its name, its own WGSL files (name, source) and what it reads and writes.
#[derive(Debug)]
pub struct Node {
    /// The pass's folder under `passes/`.
    pub name: &'static str,
    /// Its own WGSL: bindings and entry points (none for a pass that only chains others).
    pub shaders: &'static [(&'static str, &'static str)],
    /// What it reads.
    pub inputs: &'static [Resource],
    /// What it writes.
    pub outputs: &'static [Resource],
}

/// The walkthrough frame (`crate::walkthrough`): probes and view buffers once per scene or
/// camera, then the G-buffer, the light-mapped image and the view-dependent part per frame.
pub const WALKTHROUGH: [&Node; 5] = [
    &probe_capture::NODE,
    &view::NODE,
    &gbuffer::NODE,
    &lightmap_shade::NODE,
    &frame_shade::NODE,
];

/// 004's adaptive shading of a G-buffer: the bandwidth pass, then the hierarchical shading.
pub const ADAPTIVE: [&Node; 2] = [&bandwidth::NODE, &adaptive::NODE];

/// The sphere pass (`lustre demo`): an environment pyramid, then the spheres.
pub const SPHERE: [&Node; 2] = [&pyramid::NODE, &sphere::NODE];

/// Every pass.
pub const ALL: [&Node; 9] = [
    &gbuffer::NODE,
    &lightmap_shade::NODE,
    &pyramid::NODE,
    &probe_capture::NODE,
    &view::NODE,
    &frame_shade::NODE,
    &bandwidth::NODE,
    &adaptive::NODE,
    &sphere::NODE,
];

#[cfg(test)]
mod tests {
    use super::*;

    /// In every chain each input is external or written by an earlier node, and every node
    /// writes something.
    #[test]
    fn every_input_is_external_or_written_before() {
        for chain in [&WALKTHROUGH[..], &ADAPTIVE[..], &SPHERE[..]] {
            let mut written: Vec<Resource> = Vec::new();
            for n in chain {
                for r in n.inputs {
                    assert!(
                        r.external() || written.contains(r),
                        "{}: {r:?} is read before any pass writes it",
                        n.name
                    );
                }
                assert!(!n.outputs.is_empty(), "{} writes nothing", n.name);
                assert!(n.outputs.iter().all(|r| !r.external()), "{}", n.name);
                written.extend(n.outputs);
            }
        }
        for (i, a) in ALL.iter().enumerate() {
            assert!(ALL[i + 1..].iter().all(|b| b.name != a.name), "{}", a.name);
        }
    }

    /// Each pass's shaders live in its folder: `<name>.wgsl` or named after it.
    #[test]
    fn every_pass_declares_its_own_wgsl() {
        for n in ALL {
            for (file, source) in n.shaders {
                assert!(file.ends_with(".wgsl"), "{}: {file}", n.name);
                assert!(!source.is_empty(), "{}: {file}", n.name);
                // A pass's own WGSL carries its bindings or entry points.
                assert!(
                    source.contains("@compute")
                        || source.contains("@vertex")
                        || source.contains("@group"),
                    "{}: {file} is a module, not a pass",
                    n.name
                );
            }
        }
    }
}
