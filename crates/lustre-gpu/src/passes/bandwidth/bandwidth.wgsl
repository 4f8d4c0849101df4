// The bandwidth pass (004 §IV.4.1, Fig. IV.11 b): per G-buffer pixel, the prediction of
// lustre_freq::pixel::predict from n_b directions under a distant environment, and the BRDF's
// largest bandwidth over them and the mirror direction (lustre_adaptive::buffer::predict_pixels).
// Area lights add their paths (buffer::light_paths, merge). Materials are measured BRDFs
// (measured.wgsl's measured_eval: neural BRDFs, MERL tables, RGL tensors) and
// fitted models (bsdf.wgsl's records). Imports: types, measured, frequency, env_light,
// area_light, and bsdf with fitted models.

struct Params {
    pixels: u32,
    n_b: u32,
    env_width: u32,
    env_height: u32,
    incident: u32,
    out: u32,
    lights: u32,
    // The first direction (or area-light point) of this dispatch's share: a pixel's
    // n_b (1 + lights) paths are taken DIRECTIONS_PER_DISPATCH a dispatch, the sums carried
    // in `partials` between them (bandwidth_pass::DIRECTIONS_PER_DISPATCH).
    first: u32,
}

// The sums of a pixel between dispatches: (Σλ, Σλν (2), Σχ), (the variance sums (2), the
// BRDF's largest bandwidth, the lights' Σ contribution), (their Σ contribution · ν (2), their
// paths, 0).
struct Partial {
    a: vec4<f32>,
    b: vec4<f32>,
    c: vec4<f32>,
}

// bandwidth_pass::DIRECTIONS_PER_DISPATCH.
const DIRECTIONS_PER_DISPATCH: u32 = 128u;

// A surface pixel in the map's frame: t, b, n, wo (xyz), depth in t.w, curvature in b.w, the
// material in n.w (bitcast u32), 1 in wo.w for a surface (0: background); its position (xyz)
// and its textures' spatial bandwidth (cycles per metre) in p.w; its texture coordinates in
// uv.xy.
struct Surfel {
    t: vec4<f32>,
    b: vec4<f32>,
    n: vec4<f32>,
    wo: vec4<f32>,
    p: vec4<f32>,
    uv: vec4<f32>,
}


// (ν_s, ν_a) at the eye, Σ(ν_a^i + ν_ρa^i)χ², Σ2ν_ρa^i χ², L̂, the BRDF's largest bandwidth,
// Σλ_i.
struct Prediction {
    bandwidth: vec2<f32>,
    variance: f32,
    variance_preconvolved: f32,
    radiance: f32,
    brdf_max: f32,
    weight: f32,
    _pad: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> surfels: array<Surfel>;
// Equirect texels: RGB, and the local bandwidth in w.
@group(0) @binding(2) var<storage, read> environment: array<vec4<f32>>;
// Per material: its kind (0 neural BRDF, 1 MERL table, 2 fitted model), the word where its BRDF
// starts in `table` (kind 2: its record in `fitted`), where its bandwidth table starts in
// `brdf_bandwidth`, and its MERL node offset (f32 bits).
@group(0) @binding(3) var<storage, read> materials: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> table: array<f32>;
@group(0) @binding(5) var<storage, read> brdf_bandwidth: array<f32>;
@group(0) @binding(6) var<storage, read_write> predictions: array<Prediction>;
// Binding 7, the records, bindings 10–12, their textured parameters and textures, and
// `material_prepare` / `material_eval` come with the pass's variant
// (measured::material_eval_source).
// The area lights, in the map's frame.
@group(0) @binding(8) var<storage, read> lights: array<AreaLight>;
// Per light texel: RGB and its spatial bandwidth (cycles per metre) in w.
@group(0) @binding(9) var<storage, read> light_texels: array<vec4<f32>>;
@group(0) @binding(13) var<storage, read_write> partials: array<Partial>;

fn bsdf_table(i: u32) -> f32 {
    return table[i];
}

fn env_texel(i: u32) -> vec3<f32> {
    return environment[i].xyz;
}

// The pass draws no directions from the map: its sampler is not uploaded.
fn env_table(i: u32) -> f32 {
    return 0.0;
}

fn env_radiance(d: vec3<f32>) -> vec3<f32> {
    return env_bilinear(EnvDims(params.env_width, params.env_height, 0u, 0u), d);
}

// EnvironmentBandwidth::bandwidth_at (nearest texel).
fn env_bandwidth(d: vec3<f32>) -> f32 {
    let uv = equirect_uv(d);
    let x = min(u32(max(uv.x, 0.0) * f32(params.env_width)), params.env_width - 1u);
    let y = min(u32(max(uv.y, 0.0) * f32(params.env_height)), params.env_height - 1u);
    return environment[y * params.env_width + x].w;
}

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= params.pixels) {
        return;
    }
    var out: Prediction;
    let s = surfels[i];
    let t = s.t.xyz;
    let b = s.b.xyz;
    let n = s.n.xyz;
    let wo = vec3<f32>(dot(s.wo.xyz, t), dot(s.wo.xyz, b), dot(s.wo.xyz, n));
    let depth = s.t.w;
    let curvature = s.b.w;
    let texture = s.p.w;
    let finite = abs(depth) < 3.0e38 && abs(curvature) < 3.0e38 && depth == depth
        && curvature == curvature && abs(texture) < 3.0e38 && texture == texture;
    if (s.wo.w == 0.0 || !(wo.z > 0.0 && finite && dot(n, n) > 0.5)) {
        if (params.first == 0u) {
            predictions[i] = out;
        }
        return;
    }
    let m = materials[bitcast<u32>(s.n.w)];
    material_prepare(m.x, m.y, s.uv.xy);
    let incident = params.incident;
    let cells = params.out;
    var weight_sum = 0.0;
    var nu = vec2<f32>(0.0);
    var chi_sum = 0.0;
    let mirror = vec3<f32>(-wo.x, -wo.y, wo.z);
    var brdf_max = brdf_bandwidth[m.z + freq_brdf_index(mirror, wo, incident, cells)];
    // One loop over the n_b environment directions, then n_b stratified points per area light
    // (buffer::light_paths), so that the material is evaluated at one call site.
    var light_nu = vec2<f32>(0.0);
    var light_sum = 0.0;
    var paths = 0u;
    let total = params.n_b * (1u + params.lights);
    if (params.first >= total) {
        return;
    }
    if (params.first > 0u) {
        let q = partials[i];
        weight_sum = q.a.x;
        nu = q.a.yz;
        chi_sum = q.a.w;
        out.variance = q.b.x;
        out.variance_preconvolved = q.b.y;
        brdf_max = q.b.z;
        light_sum = q.b.w;
        light_nu = q.c.xy;
        paths = u32(q.c.z);
    }
    let end = min(total, params.first + DIRECTIONS_PER_DISPATCH);
    for (var k = params.first; k < end; k++) {
        let from_env = k < params.n_b;
        var wi_l = vec3<f32>(0.0);
        // An area light's point: the light's radiance, its bandwidth there, the distance, the
        // cosine at the light and the solid-angle weight.
        var emitted = 0.0;
        var nu_s = 0.0;
        var dist = 0.0;
        var g = 0.0;
        if (from_env) {
            wi_l = freq_cosine_direction(k, params.n_b);
        } else {
            let light = lights[(k - params.n_b) / params.n_b];
            let j = (k - params.n_b) % params.n_b;
            let uv = vec2<f32>((f32(j) + 0.5) / f32(params.n_b),
                               fract(f32(reverseBits(j) >> 8u) * (1.0 / 16777216.0)
                                     + 0.5 / f32(params.n_b)));
            let dv = area_light_point(light, uv) - s.p.xyz;
            dist = length(dv);
            if (!(dist > 0.0 && dist < 3.0e38)) {
                continue;
            }
            let w = dv / dist;
            let cos_l = -dot(w, light.normal.xyz);
            wi_l = vec3<f32>(dot(w, t), dot(w, b), dot(w, n));
            if (cos_l <= 0.0 || wi_l.z <= 0.0) {
                continue;
            }
            g = cos_l * light.radiance.w / (dist * dist * f32(params.n_b));
            let texel = light_texels[area_light_texel(light, uv)];
            emitted = luminance(light.radiance.xyz * texel.xyz);
            nu_s = texel.w / max(cos_l, 1e-6);
        }
        let rho = luminance(material_eval(m.x, m.y, bitcast<f32>(m.w), wi_l, wo));
        let nu_brdf = brdf_bandwidth[m.z + freq_brdf_index(wi_l, wo, incident, cells)];
        brdf_max = max(brdf_max, nu_brdf);
        if (from_env) {
            let wi = t * wi_l.x + b * wi_l.y + n * wi_l.z;
            let nu_light = env_bandwidth(wi);
            let nu_i = freq_one_bounce_distant(nu_light, max(wo.z, 1e-6), curvature, texture,
                                               nu_brdf, depth);
            let chi = luminance(env_radiance(wi)) * rho;
            chi_sum += chi;
            let lambda = max(chi * wi_l.z, 0.0);
            weight_sum += lambda;
            nu += lambda * nu_i;
            out.variance += (nu_light + nu_brdf) * chi * chi;
            out.variance_preconvolved += 2.0 * nu_brdf * chi * chi;
        } else {
            // One path of buffer::light_paths: its share of L_p, its bandwidth at the eye
            // (Eq. IV.5 from the light's surface), its variance term on the environment's scale.
            let contribution = emitted * rho * wi_l.z * g;
            let path_nu = freq_one_bounce(vec2<f32>(nu_s, 0.0), dist, wi_l.z, max(wo.z, 1e-6),
                                          curvature, texture, nu_brdf, depth);
            light_nu += max(contribution, 0.0) * path_nu;
            light_sum += max(contribution, 0.0);
            let chi = contribution * f32(params.n_b) / PI;
            out.variance += (dist * nu_s + nu_brdf) * chi * chi;
            out.variance_preconvolved += 2.0 * nu_brdf * chi * chi;
            paths += 1u;
        }
    }
    if (end < total) {
        partials[i] = Partial(vec4<f32>(weight_sum, nu, chi_sum),
                              vec4<f32>(out.variance, out.variance_preconvolved, brdf_max,
                                        light_sum),
                              vec4<f32>(light_nu, f32(paths), 0.0));
        return;
    }
    var env_nu = vec2<f32>(0.0);
    if (weight_sum > 0.0) {
        env_nu = nu / weight_sum;
    }
    out.bandwidth = env_nu;
    out.radiance = PI * chi_sum / f32(params.n_b);
    out.weight = weight_sum;
    // buffer::merge: Eq. IV.6 over the environment's path (weighing its L̂) and the lights'.
    if (paths > 0u) {
        let env_weight = max(out.radiance, 0.0);
        let total_weight = env_weight + light_sum;
        out.bandwidth = vec2<f32>(0.0);
        if (total_weight > 0.0) {
            out.bandwidth = (env_weight * env_nu + light_nu) / total_weight;
        }
        out.radiance += light_sum;
        out.weight = out.radiance;
    }
    out.brdf_max = brdf_max;
    predictions[i] = out;
}
