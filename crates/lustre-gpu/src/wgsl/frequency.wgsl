// module frequency: frequency analysis on the GPU (004 §IV.3): the one-bounce bandwidth of a
// distant light (Fig. IV.9, Eq. IV.4–IV.5; lustre_freq::transport::one_bounce with d = 0 and
// ν_s = 0) and of a light at a distance (an area light), the n_b cosine-weighted directions (lustre_freq::pixel::incident_direction), the
// cells of a BRDF bandwidth table (lustre_freq::brdf::BrdfBandwidth::at).

// Direction k of n (lustre_freq::pixel::incident_direction): the centred Hammersley point,
// warped to the cosine-weighted hemisphere (Malley).
fn freq_cosine_direction(k: u32, n: u32) -> vec3<f32> {
    let u1 = (f32(k) + 0.5) / f32(n);
    let u2 = f32(reverseBits(k)) * (1.0 / 4294967296.0) + 0.5 / f32(n);
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
}

// ν^i at the eye for a distant light of angular bandwidth nu_l: P_x C_−c S B_{t,ρ} C_c P_i,
// then T_d' (the incident projection scales ν_s = 0, so it drops out). Returns (ν_s, ν_a).
fn freq_one_bounce_distant(nu_l: f32, cos_x: f32, curvature: f32, texture: f32, rho: f32,
                           d_eye: f32) -> vec2<f32> {
    let c = abs(curvature);
    let angular = min(nu_l, rho);
    let spatial = (c * nu_l + texture + c * angular) / cos_x;
    return vec2<f32>(spatial, abs(d_eye) * spatial + angular);
}

// Eq. IV.5 for a light at distance d of bandwidth nu = (ν_s, ν_a) (lustre_freq::transport::
// one_bounce): T_d' P_x C_−c S B_{t,ρ} C_c P_i T_d ν, each operator |M| ν. Returns (ν_s, ν_a).
fn freq_one_bounce(nu: vec2<f32>, d: f32, cos_i: f32, cos_x: f32, curvature: f32,
                   texture: f32, rho: f32, d_eye: f32) -> vec2<f32> {
    let c = abs(curvature);
    var v = vec2<f32>(nu.x, abs(d) * nu.x + nu.y);
    v = vec2<f32>(cos_i * v.x, v.y);
    v = vec2<f32>(v.x + c * v.y, v.y);
    v = vec2<f32>(v.x + texture, min(v.y, rho));
    v = vec2<f32>(v.x + c * v.y, v.y);
    v = vec2<f32>(v.x / cos_x, v.y);
    return vec2<f32>(v.x, abs(d_eye) * v.x + v.y);
}

// (θ row, φ column) of direction w on an n × n hemisphere grid.
fn freq_cell(w: vec3<f32>, n: u32) -> vec2<u32> {
    let theta = acos(clamp(w.z, 0.0, 1.0));
    var phi = atan2(w.y, w.x);
    if (phi < 0.0) {
        phi += 2.0 * PI;
    }
    let t = min(u32(theta / (0.5 * PI) * f32(n)), n - 1u);
    let p = min(u32(phi / (2.0 * PI) * f32(n)), n - 1u);
    return vec2<u32>(t, p);
}

// The index of BrdfBandwidth::at(wi, wo) in a table of `incident`² × `out`² cells.
fn freq_brdf_index(wi: vec3<f32>, wo: vec3<f32>, incident: u32, out: u32) -> u32 {
    let i = freq_cell(wi, incident);
    let o = freq_cell(wo, out);
    return (i.x * incident + i.y) * out * out + o.x * out + o.y;
}
