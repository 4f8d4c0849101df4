// module mixture: component selection and the diffuse component of the fitted models' mixtures,
// the 32 floats of their records.
// CPU twins: lustre_brdf::bsdf::{select_component, sample_diffuse_mixture} and
// lustre_brdf::sampling::{cosine_hemisphere, cosine_hemisphere_pdf}. Selection: component i
// with probability wᵢ/Σw, the uniform number rescaled to (u Σw − Σ_{j<i} wⱼ)/wᵢ and reused by
// the component's warp (pbrt-v4's trick); cosine sampling r = √u1, φ = 2πu2, z = √(1 − u1).

// The largest f32 below 1 (the CPU clamps to 1 − f64::EPSILON).
const MIX_ONE_MINUS_EPSILON: f32 = 0.99999994;

// The component picked and the rescaled uniform number; index = the count when no weight is
// positive (the CPU's None).
struct MixSelected {
    index: u32,
    u: f32,
}

// select_component over w[0 .. n] (n ≤ 8).
fn mix_select(w_in: array<f32, 8>, n: u32, u: f32) -> MixSelected {
    var w = w_in;
    var total = 0.0;
    for (var i = 0u; i < n; i++) {
        total += w[i];
    }
    if (!(total > 0.0)) {
        return MixSelected(n, 0.0);
    }
    let goal = u * total;
    var acc = 0.0;
    var last = n;
    for (var i = 0u; i < n; i++) {
        let wi = w[i];
        if (!(wi > 0.0)) {
            continue;
        }
        last = i;
        if (goal < acc + wi || i == n - 1u) {
            return MixSelected(i, clamp((goal - acc) / wi, 0.0, MIX_ONE_MINUS_EPSILON));
        }
        acc += wi;
    }
    // Rounding left the goal past the last positive weight.
    return MixSelected(last, MIX_ONE_MINUS_EPSILON);
}

// sampling::cosine_hemisphere: density cos θ / π.
fn mix_cosine_hemisphere(u1: f32, u2: f32) -> vec3<f32> {
    let r = sqrt(u1);
    let phi = 2.0 * PI * u2;
    return vec3<f32>(r * cos(phi), r * sin(phi), sqrt(max(1.0 - u1, 0.0)));
}

// ln(1 − u) for u in [0, 1): below 0.1 its series −Σ uᵏ/k to k = 9 (relative error < 1e-10;
// the f32 log near 1 has an absolute, not a relative, error), else log(1 − u).
fn mix_ln_one_minus(u: f32) -> f32 {
    if (u < 0.1) {
        return -u * (1.0 + u * (1.0 / 2.0 + u * (1.0 / 3.0 + u * (1.0 / 4.0 + u * (1.0 / 5.0
            + u * (1.0 / 6.0 + u * (1.0 / 7.0 + u * (1.0 / 8.0 + u / 9.0))))))));
    }
    return log(1.0 - u);
}

// Rgb::luminance (Rec. 709 weights).
fn mix_luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// The 32 floats of a fitted model's record, float k at [k].
fn mix_floats(p: array<vec4<f32>, 8>) -> array<f32, 32> {
    var f: array<f32, 32>;
    for (var i = 0u; i < 8u; i++) {
        for (var j = 0u; j < 4u; j++) {
            f[4u * i + j] = p[i][j];
        }
    }
    return f;
}

// A failed sample (the CPU's None).
fn mix_no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0u);
}

// Whether every component is finite (neither NaN nor ±∞).
fn mix_finite3(v: vec3<f32>) -> bool {
    return all(abs(v) <= vec3<f32>(0x1.fffffep+127f));
}
