// module lambert: kind 7, a Lambertian reflector (flag DIFFUSE_ONLY: a pixel the light map
// covers, kd ≠ 0, has no view-dependent part; one it does not cover is integrated like any
// other material, as the CPU frame does). CPU twin: lustre_brdf::models::lambert::Lambert::
// {eval, pdf, sample}: f = kd/π above the surface, cosine-weighted sampling.
// Parameters (pack_lambert): p0 = (kd rgb, 0).

struct Lambert {
    kd: vec3<f32>,
}

fn lambert_unpack(p: array<vec4<f32>, 8>) -> Lambert {
    return Lambert(p[0].xyz);
}

fn lambert_eval(m: Lambert, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (wi.z > 0.0 && wo.z > 0.0) {
        return m.kd / PI;
    }
    return vec3<f32>(0.0);
}

fn lambert_pdf(m: Lambert, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (wo.z > 0.0 && wi.z > 0.0) {
        return wi.z / PI;
    }
    return 0.0;
}

fn lambert_sample(m: Lambert, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    if (!(wo.z > 0.0)) {
        return no_sample();
    }
    let wi = cosine_hemisphere(u.x, u.y);
    if (!(wi.z > 0.0)) {
        return no_sample();
    }
    return BsdfSample(wi, lambert_pdf(m, wi, wo), lambert_eval(m, wi, wo), 0u);
}

// The record with its textured parameters at the pixel (FLAG_TEXTURED; textured.wgsl's
// `textured_bsdf` dispatches here): c = the clamped colour, s = the scalars as
// material::scene::pack_material_params lists them for this kind, unclamped.
fn lambert_textured(b_in: GpuBsdf, c: vec3<f32>, s: vec3<f32>) -> GpuBsdf {
    var b = b_in;
    b.p[0] = vec4<f32>(c, 0.0);
    return b;
}
