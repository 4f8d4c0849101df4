// module bsdf_sample: the record every BSDF model's `<model>_sample` returns. CPU twin:
// lustre_brdf::bsdf::BsdfSample (fields wi, pdf, value; delta = is_delta()). pdf = 0 stands for
// the CPU's None (a failed sample); for a Dirac lobe pdf is the discrete probability of the
// branch and value = weight·pdf/|cos θi| (BsdfSample::delta).

struct BsdfSample {
    wi: vec3<f32>,
    pdf: f32,
    value: vec3<f32>,
    delta: u32,
}

// The CPU's None.
fn no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0u);
}

// BsdfSample::delta: a Dirac sample picked with probability `prob` of throughput `weight`;
// none for a direction in the surface plane or a probability outside (0, 1].
fn delta_sample(wi: vec3<f32>, weight: vec3<f32>, prob: f32) -> BsdfSample {
    let c = abs(wi.z);
    if (!(c > 0.0 && prob > 0.0 && prob <= 1.0)) {
        return no_sample();
    }
    return BsdfSample(wi, prob, weight * (prob / c), 1u);
}
