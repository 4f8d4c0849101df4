// module mip: the MIP level of one lookup in a cube-map pyramid with faces N².
// CPU twins: lustre_shade::mip::{tan_between, lobe_area, regular_level, texel_solid_angle_at,
// footprint_level, MAX_TAN_ALPHA, FOOTPRINT_LEVEL_BIAS}. Equations: A = π u v with
// u = tan αU, v = tan αV (002 Eq. 14–15); level = log4(A N² / (4 n) · ‖ωi‖/‖ωi‖∞ / (ωi·h))
// (002 Eq. 16); Ωp(ω) = (2/N)² / d³, d = ‖ω‖/‖ω‖∞; footprint level = ½ log2(Ω / Ωp) + bias.
// Every level is clamped to [0, log2 N].

// mip::MAX_TAN_ALPHA: tan 89°, the cap of tan α for lobe edges at or beyond 90° from the centre.
const MAX_TAN_ALPHA: f32 = 57.28996163075942;

// mip::tan_between: tan of the angle between two unit vectors, capped at MAX_TAN_ALPHA.
fn tan_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    let alpha = acos(clamp(dot(a, b), -1.0, 1.0));
    let t = tan(alpha);
    if (alpha >= 0.5 * PI || !(abs(t) <= 3.4e38)) {
        return MAX_TAN_ALPHA;
    }
    return min(t, MAX_TAN_ALPHA);
}

// mip::lobe_area: 002 Eq. 14–15, A = π·u·v at unit distance. The extreme half vectors at the ξ0
// border, hU at θ = arctan(√(−ln ξ0) mx), φ = 0 and hV at θ = arctan(√(−ln ξ0) my), φ = 90°
// (002 Eq. 5, 11), reflect ωo into ωU and ωV; the lobe centre ωC reflects ωo about the normal.
// Eq. 14: αU = arccos(ωC·ωU), αV = arccos(ωC·ωV); Eq. 15: u = tan αU, v = tan αV.
fn lobe_area(mx: f32, my: f32, xi0: f32, wo: vec3<f32>) -> f32 {
    let k = sqrt(-log(xi0));
    let tu = atan(k * mx);
    let tv = atan(k * my);
    let hu = vec3<f32>(sin(tu), 0.0, cos(tu));
    let hv = vec3<f32>(0.0, sin(tv), cos(tv));
    let wc = reflect_about(wo, vec3<f32>(0.0, 0.0, 1.0));
    let u = tan_between(wc, reflect_about(wo, hu));
    let v = tan_between(wc, reflect_about(wo, hv));
    return PI * u * v;
}

// mip::regular_level: 002 Eq. 16, log4( A·N / (4 n) · ‖ωi‖/‖ωi‖∞ · 1/(ωi·h) ) with
// N = face_size², clamped to [0, log2(face_size)]; an invalid sample reads the top level.
fn regular_level(area: f32, n_samples: u32, wi: vec3<f32>, wi_dot_h: f32, face_size: f32) -> f32 {
    let top = log2(max(face_size, 1.0));
    let inf = max(abs(wi.x), max(abs(wi.y), abs(wi.z)));
    if (!(inf > 0.0 && wi_dot_h > 0.0 && n_samples > 0u)) {
        return top;
    }
    let n_texels = face_size * face_size;
    let d = length(wi) / inf;
    let pixels = area * n_texels / (4.0 * f32(n_samples)) * d / wi_dot_h;
    // log2(0) = −∞ clamps to 0 on the CPU; WGSL leaves log2(0) undefined, so it is spelled out.
    if (!(pixels > 0.0)) {
        return 0.0;
    }
    return clamp(log2(pixels) / 2.0, 0.0, top);
}

// mip::texel_solid_angle_at: (2/N)² / d³ with d = ‖ω‖/‖ω‖∞.
fn texel_solid_angle_at(dir: vec3<f32>, face_size: f32) -> f32 {
    let inf = max(abs(dir.x), max(abs(dir.y), abs(dir.z)));
    var d = 1.0;
    if (inf > 0.0) {
        d = length(dir) / inf;
    }
    return 4.0 / (face_size * face_size * d * d * d);
}

// mip::FOOTPRINT_LEVEL_BIAS.
const FOOTPRINT_LEVEL_BIAS: f32 = -0.5;

// mip::footprint_level: ½ log2(cell / Ωp(ωi)) + bias, clamped to [0, log2(face_size)].
fn footprint_level(cell: f32, wi: vec3<f32>, face_size: f32) -> f32 {
    let top = log2(max(face_size, 1.0));
    if (!(cell > 0.0)) {
        return top;
    }
    let l = 0.5 * log2(cell / texel_solid_angle_at(wi, face_size)) + FOOTPRINT_LEVEL_BIAS;
    return clamp(l, 0.0, top);
}
