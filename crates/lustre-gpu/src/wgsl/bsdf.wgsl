// module bsdf: the material record of the view-dependent pass and the dispatch to its models'
// sample / eval / pdf by kind. CPU twin: lustre_gpu::frame_shade::GpuBsdf and the lustre_brdf
// model each kind stands for. Kind codes: 0 none, 1 rough conductor, 2 rough plastic, 3 rough
// dielectric, 4 conductor, 5 thin dielectric, 6 glTF metallic-roughness, 7 Lambert, 8 plastic, 9 dielectric,
// 16 SGD, 17/18 Beckmann/GGX Cook-Torrance, 19 Kurt (lustre_gpu::fit_models; an unknown kind
// samples nothing and evaluates to 0).

struct GpuBsdf {
    kind: u32,
    flags: u32,
    pad0: u32,
    pad1: u32,
    p: array<vec4<f32>, 8>,
}

// Only Dirac lobes (summed exactly over their branches).
const FLAG_DELTA_ONLY: u32 = 1u;
// Two-sided: the shading frame is turned towards the viewer.
const FLAG_TWO_SIDED: u32 = 2u;
// Only diffuse lobes: no view-dependent part where the light map covers the pixel (kd ≠ 0).
const FLAG_DIFFUSE_ONLY: u32 = 4u;

fn bsdf_sample(b: GpuBsdf, wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {
    switch b.kind {
        case 1u: {
            return rough_conductor_sample(rough_conductor_unpack(b.p), wo, u);
        }
        case 2u: {
            return rough_plastic_sample(rough_plastic_unpack(b.p), wo, u);
        }
        case 3u: {
            return rough_dielectric_sample(rough_dielectric_unpack(b.p), wo, u);
        }
        case 4u: {
            return conductor_sample(conductor_unpack(b.p), wo, u);
        }
        case 5u: {
            return thin_dielectric_sample(thin_dielectric_unpack(b.p), wo, u);
        }
        case 6u: {
            return pbr_metallic_roughness_sample(pbr_metallic_roughness_unpack(b.p), wo, u);
        }
        case 7u: {
            return lambert_sample(lambert_unpack(b.p), wo, u);
        }
        case 8u: {
            return plastic_sample(plastic_unpack(b.p), wo, u);
        }
        case 9u: {
            return dielectric_sample(dielectric_unpack(b.p), wo, u);
        }
        case 16u: {
            return sgd_sample(sgd_unpack(b.p), wo, u);
        }
        case 17u, 18u: {
            return cook_torrance_sample(cook_torrance_unpack(b.p), wo, u);
        }
        case 19u: {
            return kurt_sample(kurt_unpack(b.p), wo, u);
        }
        default: {
            return no_sample();
        }
    }
}

fn bsdf_eval(b: GpuBsdf, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    switch b.kind {
        case 1u: {
            return rough_conductor_eval(rough_conductor_unpack(b.p), wi, wo);
        }
        case 2u: {
            return rough_plastic_eval(rough_plastic_unpack(b.p), wi, wo);
        }
        case 3u: {
            return rough_dielectric_eval(rough_dielectric_unpack(b.p), wi, wo);
        }
        case 4u: {
            return conductor_eval(conductor_unpack(b.p), wi, wo);
        }
        case 5u: {
            return thin_dielectric_eval(thin_dielectric_unpack(b.p), wi, wo);
        }
        case 6u: {
            return pbr_metallic_roughness_eval(pbr_metallic_roughness_unpack(b.p), wi, wo);
        }
        case 7u: {
            return lambert_eval(lambert_unpack(b.p), wi, wo);
        }
        case 8u: {
            return plastic_eval(plastic_unpack(b.p), wi, wo);
        }
        case 9u: {
            return dielectric_eval(dielectric_unpack(b.p), wi, wo);
        }
        case 16u: {
            return sgd_eval(sgd_unpack(b.p), wi, wo);
        }
        case 17u, 18u: {
            return cook_torrance_eval(cook_torrance_unpack(b.p), wi, wo);
        }
        case 19u: {
            return kurt_eval(kurt_unpack(b.p), wi, wo);
        }
        default: {
            return vec3<f32>(0.0);
        }
    }
}

fn bsdf_pdf(b: GpuBsdf, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    switch b.kind {
        case 1u: {
            return rough_conductor_pdf(rough_conductor_unpack(b.p), wi, wo);
        }
        case 2u: {
            return rough_plastic_pdf(rough_plastic_unpack(b.p), wi, wo);
        }
        case 3u: {
            return rough_dielectric_pdf(rough_dielectric_unpack(b.p), wi, wo);
        }
        case 4u: {
            return conductor_pdf(conductor_unpack(b.p), wi, wo);
        }
        case 5u: {
            return thin_dielectric_pdf(thin_dielectric_unpack(b.p), wi, wo);
        }
        case 6u: {
            return pbr_metallic_roughness_pdf(pbr_metallic_roughness_unpack(b.p), wi, wo);
        }
        case 7u: {
            return lambert_pdf(lambert_unpack(b.p), wi, wo);
        }
        case 8u: {
            return plastic_pdf(plastic_unpack(b.p), wi, wo);
        }
        case 9u: {
            return dielectric_pdf(dielectric_unpack(b.p), wi, wo);
        }
        case 16u: {
            return sgd_pdf(sgd_unpack(b.p), wi, wo);
        }
        case 17u, 18u: {
            return cook_torrance_pdf(cook_torrance_unpack(b.p), wi, wo);
        }
        case 19u: {
            return kurt_pdf(kurt_unpack(b.p), wi, wo);
        }
        default: {
            return 0.0;
        }
    }
}
