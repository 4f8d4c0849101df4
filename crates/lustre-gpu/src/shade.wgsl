// The regular-sampling kernel of lustre-shade (kernel::shade_regular with Weighting::Pdf002 for
// stored patterns, and ours, the per-pixel row lattice of kernel::plan_lattice) and the scene ray
// casting of lustre_shade::scene, in f32. One invocation shades one pixel.
//
// Conventions (contracts.md): world +y up; shading frame (t, b, n) with b = n × t; local =
// (w·t, w·b, w·n); `wi` to the light, `wo` to the viewer; cube maps in Vulkan face order, sampled
// seamlessly and trilinearly by textureSampleLevel (the GPU side of CubePyramid::sample).

const PI: f32 = 3.14159265358979323846;

struct Globals {
    // Camera basis computed on the CPU in f64 (scene.rs): fwd = normalize(target − eye),
    // right = normalize(fwd × up), up' = right × fwd.
    eye: vec4<f32>,
    fwd: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // x = a = tan(fov_y / 2), y = W / H, z = levels − 1 (the largest lod), w = face size N.
    params: vec4<f32>,
    // x = W, y = H, z = number of spheres, w = number of planes.
    dims: vec4<u32>,
}

struct Sphere {
    center: vec3<f32>,
    radius: f32,
    axis: vec3<f32>,
    material: u32,
}

struct Plane {
    point: vec3<f32>,
    half_size: f32,
    normal: vec3<f32>,
    material: u32,
    tangent: vec3<f32>,
    pad: u32,
}

struct Material {
    kd: vec3<f32>,
    // Index of the first lobe in `lobes`: reflection lobes first, then transmission lobes.
    lobe_start: u32,
    reflection: u32,
    transmission: u32,
    pad0: u32,
    pad1: u32,
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

@group(0) @binding(0) var<uniform> globals: Globals;
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
@group(0) @binding(2) var<storage, read> planes: array<Plane>;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var<storage, read> lobes: array<Lobe>;
@group(0) @binding(5) var<storage, read> samples: array<vec4<f32>>;
@group(0) @binding(6) var pyramid: texture_cube<f32>;
@group(0) @binding(7) var irradiance: texture_cube<f32>;
@group(0) @binding(8) var linear_sampler: sampler;
@group(0) @binding(9) var target_image: texture_storage_2d<rgba32float, write>;

// ---------------------------------------------------------------- scene (scene.rs) ----------

struct Hit {
    found: bool,
    distance: f32,
    position: vec3<f32>,
    t: vec3<f32>,
    b: vec3<f32>,
    n: vec3<f32>,
    material: u32,
}

fn no_hit() -> Hit {
    return Hit(false, 0.0, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0u);
}

// Primary ray of pixel (x, y) in a W×H image (contract, Scene::primary): px = (2(x+½)/W − 1)·a·W/H;
// py = (1 − 2(y+½)/H)·a; dir = normalize(fwd + px·right + py·up').
fn primary_dir(x: u32, y: u32) -> vec3<f32> {
    let w = f32(globals.dims.x);
    let h = f32(globals.dims.y);
    let a = globals.params.x;
    let px = (2.0 * (f32(x) + 0.5) / w - 1.0) * a * globals.params.y;
    let py = (1.0 - 2.0 * (f32(y) + 0.5) / h) * a;
    return normalize(globals.fwd.xyz + px * globals.right.xyz + py * globals.up.xyz);
}

// scene::T_MIN: smallest accepted ray parameter.
const T_MIN: f32 = 1e-9;

// The tangent fallback of Sphere::frame_at and Plane::frame: where t is degenerate
// (|t| < 1e-6), t = x̂ × n, and where that is degenerate too, t = ẑ; then normalized.
fn tangent_or_fallback(t_in: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var t = t_in;
    if (length(t) < 1e-6) {
        t = cross(vec3<f32>(1.0, 0.0, 0.0), n);
        if (length(t) < 1e-6) {
            t = vec3<f32>(0.0, 0.0, 1.0);
        }
    }
    return normalize(t);
}

// Sphere::intersect: the nearest ray parameter > T_MIN of o + t·d (d unit). The discriminant is
// r² − |f − (f·d)d|² (f = o − c) and the roots the stable pair q = −f·d − sign(f·d)√disc, c/q.
// Returns −1 for a miss.
fn sphere_t(o: vec3<f32>, d: vec3<f32>, s: Sphere) -> f32 {
    let f = o - s.center;
    let b = dot(f, d);
    let perp = f - b * d;
    let r2 = s.radius * s.radius;
    let disc = r2 - dot(perp, perp);
    if (!(disc >= 0.0)) {
        return -1.0;
    }
    let c = dot(f, f) - r2;
    // Rust's signum: +1 for b = +0.
    let sgn = select(1.0, -1.0, b < 0.0);
    let q = -b - sgn * sqrt(disc);
    var t0 = 0.0;
    var t1 = 0.0;
    if (q != 0.0) {
        t0 = min(c / q, q);
        t1 = max(c / q, q);
    }
    if (t0 > T_MIN) {
        return t0;
    }
    if (t1 > T_MIN) {
        return t1;
    }
    return -1.0;
}

// Plane::frame: n = normal, t = the tangent made orthogonal to n (Gram–Schmidt), b = n × t.
fn plane_n(q: Plane) -> vec3<f32> {
    return normalize(q.normal);
}

fn plane_t(q: Plane) -> vec3<f32> {
    let n = plane_n(q);
    return tangent_or_fallback(q.tangent - n * dot(n, q.tangent), n);
}

// Plane::intersect: (o + t d − point)·n = 0 with t > T_MIN, inside the square
// |(p − point)·t| ≤ half_size, |(p − point)·b| ≤ half_size. Returns −1 for a miss.
fn plane_t_hit(o: vec3<f32>, d: vec3<f32>, q: Plane) -> f32 {
    let n = plane_n(q);
    let t_axis = plane_t(q);
    let b_axis = cross(n, t_axis);
    let denom = dot(d, n);
    if (!(abs(denom) > 1e-12)) {
        return -1.0;
    }
    let t = dot(q.point - o, n) / denom;
    if (!(t > T_MIN && t <= 3.4e38)) {
        return -1.0;
    }
    let r = o + t * d - q.point;
    if (abs(dot(r, t_axis)) <= q.half_size && abs(dot(r, b_axis)) <= q.half_size) {
        return t;
    }
    return -1.0;
}

// Scene::intersect: the nearest hit over all spheres, then all planes (a later surface wins only
// when strictly closer), with the frame flipped towards the viewer (n → −n, t kept, b = n × t).
fn intersect(o: vec3<f32>, d: vec3<f32>) -> Hit {
    var found = false;
    var best = 0.0;
    var t_axis = vec3<f32>(0.0);
    var n = vec3<f32>(0.0);
    var material = 0u;
    for (var i = 0u; i < globals.dims.z; i++) {
        let s = spheres[i];
        let t = sphere_t(o, d, s);
        if (t > 0.0 && (!found || t < best)) {
            found = true;
            best = t;
            // Sphere::frame_at: n = (p − c)/r, t = normalize(axis × n) with the fallbacks.
            n = normalize((o + t * d - s.center) / s.radius);
            t_axis = tangent_or_fallback(cross(s.axis, n), n);
            material = s.material;
        }
    }
    for (var i = 0u; i < globals.dims.w; i++) {
        let q = planes[i];
        let t = plane_t_hit(o, d, q);
        if (t > 0.0 && (!found || t < best)) {
            found = true;
            best = t;
            n = plane_n(q);
            t_axis = plane_t(q);
            material = q.material;
        }
    }
    if (!found) {
        return no_hit();
    }
    if (dot(n, -d) < 0.0) {
        n = -n;
    }
    return Hit(true, best, o + best * d, t_axis, cross(n, t_axis), n, material);
}

// ---------------------------------------------------------------- Kurt lobe (lustre-brdf) ---

// Schlick F(u) = r0 + (1 − r0)(1 − u)⁵ (000 Eq. 2.9, 002 Eq. 3).
fn schlick(r0: f32, u: f32) -> f32 {
    let m = clamp(1.0 - u, 0.0, 1.0);
    let m2 = m * m;
    return r0 + (1.0 - r0) * m2 * m2 * m;
}

// Beckmann D(h) = exp(−tan²θh (cos²φh/mx² + sin²φh/my²)) / (π mx my cos⁴θh) (002 Eq. 4–5).
fn beckmann_d(mx: f32, my: f32, h: vec3<f32>) -> f32 {
    if (h.z <= 0.0) {
        return 0.0;
    }
    let ax = h.x / (mx * h.z);
    let ay = h.y / (my * h.z);
    let e = -(ax * ax + ay * ay);
    // In logarithms as on the CPU: cos⁴θh and mx·my may under- or overflow in f32.
    return exp(e - log(PI) - log(mx) - log(my) - 4.0 * log(h.z));
}

// lobe_eval with unit ks: F D / (4 (ωo·h) ((ωi·n)(ωo·n))^α) (002 Eq. 2), 1 − F for a
// transmission lobe, in the reflection geometry (both directions above the surface).
fn lobe_eval(lobe: Lobe, transmission: bool, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return 0.0;
    }
    // lustre_brdf::frame::half_vector: none when |wi + wo|² ≤ 1e-24.
    let hs = wi + wo;
    let l2 = dot(hs, hs);
    if (!(l2 > 1e-24)) {
        return 0.0;
    }
    let h = hs / sqrt(l2);
    let u = dot(wo, h);
    if (!(u > 0.0)) {
        return 0.0;
    }
    var fresnel = schlick(lobe.r0, u);
    if (transmission) {
        fresnel = 1.0 - fresnel;
    }
    let d = beckmann_d(lobe.mx, lobe.my, h);
    var shadow = 1.0;
    if (lobe.alpha != 0.0) {
        shadow = pow(wi.z * wo.z, lobe.alpha);
    }
    return fresnel * d / (4.0 * u * shadow);
}

// ---------------------------------------------------------------- MIP level (mip.rs) --------

fn reflect_about(w: vec3<f32>, h: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(w, h) * h - w;
}

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

// ---------------------------------------------------------------- row lattice (pattern.rs) --

// pattern::gauss_quantile: erfinv(2u − 1), Giles' single-precision polynomial.
fn gauss_quantile(u_in: f32) -> f32 {
    let x = clamp(2.0 * clamp(u_in, 1e-7, 1.0 - 1e-7) - 1.0, -1.0, 1.0);
    let w0 = -log((1.0 - x) * (1.0 + x));
    var p: f32;
    if (w0 < 5.0) {
        let w = w0 - 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        let w = sqrt(w0) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// pattern::lattice_rows: round(√(budget / ratio)) clamped to 1 ..= budget.
fn lattice_rows(budget: u32, ratio: f32) -> u32 {
    var r = ratio;
    if (!(r >= 1.0)) {
        r = 1.0;
    }
    let k = round(sqrt(f32(budget) / r));
    return u32(clamp(k, 1.0, f32(max(budget, 1u))));
}

// pattern::row_length: ⌊budget/rows⌋ plus one for the budget mod rows rows nearest the centre
// (order c, c−1, c+1, … ).
fn row_length(budget: u32, rows: u32, j: u32) -> u32 {
    let base = budget / rows;
    let extra = budget % rows;
    var rank: u32;
    if (rows % 2u == 1u) {
        let c = (rows - 1u) / 2u;
        if (j == c) {
            rank = 0u;
        } else if (j < c) {
            rank = 2u * (c - j) - 1u;
        } else {
            rank = 2u * (j - c);
        }
    } else {
        let c0 = rows / 2u - 1u;
        if (j <= c0) {
            rank = 2u * (c0 - j);
        } else {
            rank = 2u * (j - c0 - 1u) + 1u;
        }
    }
    return base + select(0u, 1u, rank < extra);
}

// ---------------------------------------------------------------- kernel (kernel.rs) --------

fn to_world(h: vec3<f32>, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return h.x * t + h.y * b + h.z * n;
}

// kernel::regular_lobe with Weighting::Pdf002: one lobe by the 002 pseudo code
// (EvaluateSpecularLobe), in the frame facing the viewer. Samples with ωo·h ≤ 0 or ωi below the
// horizon are skipped but still count in n. A transmission lobe takes its light from ωi mirrored
// through the tangent plane (000 Eq. 3.5) and is evaluated on the mirrored pair.
fn shade_lobe(lobe: Lobe, transmission: bool, wo_l: vec3<f32>,
              t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let count = lobe.sample_count;
    if (count == 0u) {
        return vec3<f32>(0.0);
    }
    let face = globals.params.w;
    // 002 Eq. 14–15: A = π u v.
    let area = lobe_area(lobe.mx, lobe.my, lobe.xi0, wo_l);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < count; i++) {
        let h = samples[lobe.sample_start + i].xyz;
        let ho = dot(wo_l, h); // ωo·h = ωi·h
        if (!(ho > 0.0)) {
            continue;
        }
        let r = reflect_about(wo_l, h); // 000 Eq. 4.8
        let cos_i = r.z;
        if (!(cos_i > 0.0)) {
            continue;
        }
        var wi_l = r;
        if (transmission) {
            wi_l = vec3<f32>(r.x, r.y, -r.z); // 000 Eq. 3.5: the thin BTDF's direction
        }
        let wi = to_world(wi_l, t, b, n);
        // 002 Eq. 16 (the sampler clamps the level to the pyramid as CubePyramid::sample does).
        let level = min(regular_level(area, count, wi, ho, face), globals.params.z);
        let li = textureSampleLevel(pyramid, linear_sampler, wi, level).rgb;
        // 002 Eq. 2 with unit ks (ks is applied once at the end).
        let g = lobe_eval(lobe, transmission, r, wo_l);
        // 002 Eq. 17–18: p_o = p_h / (4 h·ωi).
        let pdf = lobe.pdf_constant / (4.0 * ho);
        if (pdf > 0.0) {
            sum += li * (g * cos_i / pdf); // 002 Eq. 9, inner sum
        }
    }
    return lobe.ks * sum / f32(count);
}

// pattern::LATTICE_MAX_TAPS: the most taps one cell of the tap lattice (scheme 2) takes.
const LATTICE_MAX_TAPS: u32 = 3u;

// kernel::LatticeGeometry::slope: x e1 + y e2 with e2 = e1 turned by 90°.
fn lattice_slope(e1: vec2<f32>, x: f32, y: f32) -> vec2<f32> {
    return vec2<f32>(x * e1.x - y * e1.y, x * e1.y + y * e1.x);
}

// kernel::LatticeGeometry::stretch: |∂ωi/∂s| along the slope-space unit vector e at h = n/|n|.
fn lattice_stretch(mx: f32, my: f32, wo_l: vec3<f32>, h: vec3<f32>, len: f32,
                   e: vec2<f32>) -> f32 {
    let dn = vec3<f32>(mx * e.x, my * e.y, 0.0);
    let dh = (dn - h * dot(h, dn)) / len;
    return length(2.0 * (dot(wo_l, dh) * h + dot(wo_l, h) * dh));
}

// kernel::lattice_taps: the taps of cell i of m in row j of rows (x: the count, 0 for a cell
// whose centre lies below the horizon; y: 1 along e1, 0 along e2).
fn lattice_taps(mx: f32, my: f32, e1: vec2<f32>, wo_l: vec3<f32>,
                i: u32, m: u32, j: u32, rows: u32, max_taps: u32) -> vec2<u32> {
    let x = gauss_quantile((f32(i) + 0.5) / f32(m));
    let y = gauss_quantile((f32(j) + 0.5) / f32(rows));
    let s = lattice_slope(e1, x, y);
    let nv = vec3<f32>(mx * s.x, my * s.y, 1.0);
    let len = length(nv);
    let h = nv / len;
    let ho = dot(wo_l, h);
    if (!(ho > 0.0 && reflect_about(wo_l, h).z > 0.0)) {
        return vec2<u32>(0u, 1u);
    }
    let wx = lattice_stretch(mx, my, wo_l, h, len, e1) * exp(x * x) / f32(m);
    let wy = lattice_stretch(mx, my, wo_l, h, len, vec2<f32>(-e1.y, e1.x)) * exp(y * y)
        / f32(rows);
    let aspect = wx / wy;
    if (!(aspect > 0.0 && aspect <= 3.4e38)) {
        return vec2<u32>(1u, 1u);
    }
    var t = aspect;
    var along = 1u;
    if (aspect < 1.0) {
        t = 1.0 / aspect;
        along = 0u;
    }
    return vec2<u32>(u32(clamp(round(t), 1.0, f32(max(max_taps, 1u)))), along);
}

// kernel::lattice_cells: with one tap per cell, budget cells; otherwise the largest cell count
// whose taps fit the budget. x: cells, y: rows.
fn lattice_cells(mx: f32, my: f32, e1: vec2<f32>, wo_l: vec3<f32>,
                 budget: u32, ratio: f32, max_taps: u32) -> vec2<u32> {
    if (max_taps <= 1u) {
        return vec2<u32>(budget, lattice_rows(budget, ratio));
    }
    for (var cells = budget; cells >= 1u; cells--) {
        let rows = lattice_rows(cells, ratio);
        var total = 0u;
        for (var j = 0u; j < rows && total <= budget; j++) {
            let m = row_length(cells, rows, j);
            for (var i = 0u; i < m && total <= budget; i++) {
                total += lattice_taps(mx, my, e1, wo_l, i, m, j, rows, max_taps).x;
            }
        }
        if (total <= budget) {
            return vec2<u32>(cells, rows);
        }
    }
    return vec2<u32>(1u, 1u);
}

// kernel::lattice_lobe: ours, the row lattice of `budget` lookups: equal-mass cells of the
// slope-space Gaussian, rows along the minor axis of the lobe's image in ωi
// (kernel::lattice_axes), each cell read once (max_taps = 1) or, for the tap lattice, by up to
// max_taps taps at its sub-quantiles along its long axis, each at the level of its solid angle
// μ/p(ωi); weight μ F cos θi / (G cos θh).
fn lattice_lobe(lobe: Lobe, transmission: bool, wo_l: vec3<f32>,
                t: vec3<f32>, b: vec3<f32>, n: vec3<f32>, max_taps_in: u32) -> vec3<f32> {
    let budget = lobe.sample_count;
    if (budget == 0u) {
        return vec3<f32>(0.0);
    }
    let face = globals.params.w;
    let mx = lobe.mx;
    let my = lobe.my;
    // kernel::lattice_axes: JᵀJ of s ↦ ωi at s = 0 and its major eigenvector.
    let ja = 4.0 * mx * mx * (wo_l.x * wo_l.x + wo_l.z * wo_l.z);
    let jc = 4.0 * my * my * (wo_l.y * wo_l.y + wo_l.z * wo_l.z);
    let jb = 4.0 * mx * my * wo_l.x * wo_l.y;
    let half = 0.5 * (ja - jc);
    let root = sqrt(half * half + jb * jb);
    let l1 = 0.5 * (ja + jc) + root;
    let l2 = 0.5 * (ja + jc) - root;
    var ratio = sqrt(l1 / l2);
    if (!(abs(ratio) <= 3.4e38)) {
        ratio = 1.0;
    }
    let ev = major_axis(half, root, jb);
    let len = length(ev);
    var e1 = vec2<f32>(1.0, 0.0);
    if (len > 0.0 && len <= 3.4e38) {
        e1 = ev / len;
    }
    let max_taps = clamp(max_taps_in, 1u, budget);
    let lattice = lattice_cells(mx, my, e1, wo_l, budget, ratio, max_taps);
    let cells = lattice.x;
    let rows = lattice.y;
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < rows; j++) {
        let m = row_length(cells, rows, j);
        for (var i = 0u; i < m; i++) {
            var taps = vec2<u32>(1u, 1u);
            if (max_taps > 1u) {
                taps = lattice_taps(mx, my, e1, wo_l, i, m, j, rows, max_taps);
            }
            if (taps.x == 0u) {
                continue;
            }
            let mass = 1.0 / f32(rows * m * taps.x);
            for (var q = 0u; q < taps.x; q++) {
                let sub = (f32(q) + 0.5) / f32(taps.x);
                var ux = (f32(i) + 0.5) / f32(m);
                var uy = (f32(j) + 0.5) / f32(rows);
                if (taps.y == 1u) {
                    ux = (f32(i) + sub) / f32(m);
                } else {
                    uy = (f32(j) + sub) / f32(rows);
                }
                let s = lattice_slope(e1, gauss_quantile(ux), gauss_quantile(uy));
                let h = normalize(vec3<f32>(mx * s.x, my * s.y, 1.0));
                let ho = dot(wo_l, h);
                if (!(ho > 0.0)) {
                    continue;
                }
                let r = reflect_about(wo_l, h);
                let cos_i = r.z;
                if (!(cos_i > 0.0)) {
                    continue;
                }
                var wi_l = r;
                if (transmission) {
                    wi_l = vec3<f32>(r.x, r.y, -r.z);
                }
                let wi = to_world(wi_l, t, b, n);
                let cell = mass * 4.0 * PI * mx * my * ho * h.z * h.z * h.z * exp(dot(s, s));
                let level = min(footprint_level(cell, wi, face), globals.params.z);
                let li = textureSampleLevel(pyramid, linear_sampler, wi, level).rgb;
                var fresnel = schlick(lobe.r0, ho);
                if (transmission) {
                    fresnel = 1.0 - fresnel;
                }
                var shadow = 1.0;
                if (lobe.alpha != 0.0) {
                    shadow = pow(cos_i * wo_l.z, lobe.alpha);
                }
                sum += li * (mass * fresnel * cos_i / (shadow * h.z));
            }
        }
    }
    return lobe.ks * sum;
}

// The unnormalized major eigenvector of [[a, b], [b, c]] with half = (a − c)/2 and
// root = √(half² + b²): (half + root, b) when half ≥ 0, else (b, root − half).
fn major_axis(half: f32, root: f32, b: f32) -> vec2<f32> {
    if (half >= 0.0) {
        return vec2<f32>(half + root, b);
    }
    return vec2<f32>(b, root - half);
}

// kernel::shade_regular_with (Pdf002, no bounding planes): the frame faces the viewer (flipped to
// (t, −b, −n) when ωo·n < 0); nothing when ωo lies in the tangent plane; diffuse = kd ·
// irradiance(n) (the map stores E/π) plus every reflection and transmission lobe.
fn shade(hit: Hit, wo: vec3<f32>) -> vec3<f32> {
    let m = materials[hit.material];
    var t = hit.t;
    var b = hit.b;
    var n = hit.n;
    if (dot(wo, n) < 0.0) {
        b = -b;
        n = -n;
    }
    let wo_l = vec3<f32>(dot(wo, t), dot(wo, b), dot(wo, n));
    if (!(wo_l.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    var c = m.kd * textureSampleLevel(irradiance, linear_sampler, n, 0.0).rgb;
    for (var k = 0u; k < m.reflection + m.transmission; k++) {
        let lobe = lobes[m.lobe_start + k];
        if (lobe.scheme == 1u) {
            c += lattice_lobe(lobe, k >= m.reflection, wo_l, t, b, n, 1u);
        } else if (lobe.scheme == 2u) {
            c += lattice_lobe(lobe, k >= m.reflection, wo_l, t, b, n, LATTICE_MAX_TAPS);
        } else {
            c += shade_lobe(lobe, k >= m.reflection, wo_l, t, b, n);
        }
    }
    return c;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= globals.dims.x || gid.y >= globals.dims.y) {
        return;
    }
    let o = globals.eye.xyz;
    let d = primary_dir(gid.x, gid.y);
    let hit = intersect(o, d);
    var c: vec3<f32>;
    if (hit.found) {
        c = shade(hit, -d);
    } else {
        // Background = level-0 lookup.
        c = textureSampleLevel(pyramid, linear_sampler, d, 0.0).rgb;
    }
    textureStore(target_image, vec2<i32>(gid.xy), vec4<f32>(c, 1.0));
}
