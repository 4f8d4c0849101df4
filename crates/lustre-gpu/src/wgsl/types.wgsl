// module types: the constants and the material records every pass shares.
// CPU twins: lustre_gpu::packed::{GpuMaterial, GpuLobe} (the byte layouts, checked by
// shade.rs's record_layouts_match_wgsl) packed from lustre_brdf::models::kurt::{Kurt, KurtLobe}
// and a lustre_shade::integrator::MaterialPlan. No bindings, no entry points.
//
// Conventions (contracts.md): shading frame (t, b, n) with b = n × t; local = (w·t, w·b, w·n);
// `wi` to the light, `wo` to the viewer.

const PI: f32 = 3.14159265358979323846;

struct Material {
    kd: vec3<f32>,
    // Index of the first lobe in `lobes`: reflection lobes first, then transmission lobes.
    lobe_start: u32,
    reflection: u32,
    transmission: u32,
    // The suns split off the environment: suns[sun_start .. sun_start + sun_count].
    sun_start: u32,
    sun_count: u32,
}

// A sun split off the environment (lustre_env::Sun): a directional light of irradiance E.
struct Sun {
    direction: vec3<f32>,
    spread: f32,
    irradiance: vec3<f32>,
    pad1: f32,
}

struct Lobe {
    ks: vec3<f32>,
    mx: f32,
    my: f32,
    r0: f32,
    alpha: f32,
    // The pattern's threshold ξ0 and its PDF constant (002 Eq. 18).
    xi0: f32,
    pdf_constant: f32,
    // The pattern's half vectors: samples[sample_start .. sample_start + sample_count]; for the
    // row lattices (schemes 1, 2) sample_count is the budget and nothing is stored.
    sample_start: u32,
    sample_count: u32,
    // 0: stored pattern with Pdf002 weights; 1: the row lattice; 2: the row lattice with
    // several taps in its long cells (packed::LOBE_SCHEME_*).
    scheme: u32,
}
