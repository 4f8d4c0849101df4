// module bsdf_sample: the result of a model's sampling warp, shared by every `<model>_sample`.
// CPU twin: lustre_brdf::bsdf::BsdfSample (fields wi, pdf, value and is_delta()). pdf = 0 is
// the CPU's `None` (a failed sample); for a Dirac lobe pdf is the probability of the lobe.

struct BsdfSample {
    wi: vec3<f32>,
    pdf: f32,
    value: vec3<f32>,
    delta: u32,
}
