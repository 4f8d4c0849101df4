// The sphere pass: the scene ray casting of lustre_shade::analytic_scene and the regular-sampling integrator
// of lustre-shade (integrator::shade_regular with Weighting::Pdf002 for stored patterns, and ours,
// the per-pixel row lattice of integrator::plan_lattice), in f32. One invocation shades one pixel.
// The lobe, MIP-level, lattice and weighting functions come from the modules in wgsl/ (composed
// in front of this file by shade.rs); this file holds the scene, the bindings and the entry point.
//
// Conventions (contracts.md): world +y up; shading frame (t, b, n) with b = n × t; local =
// (w·t, w·b, w·n); `wi` to the light, `wo` to the viewer; cube maps in Vulkan face order, sampled
// seamlessly and trilinearly by textureSampleLevel (the GPU side of CubePyramid::sample).

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
@group(0) @binding(10) var<storage, read> suns: array<Sun>;

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

// ---------------------------------------------------------------- integrator (integrator.rs) --------

// integrator::regular_lobe with Weighting::Pdf002: one lobe by the 002 pseudo code
// (EvaluateSpecularLobe), in the frame facing the viewer, over the lobe's stored half vectors
// (regular.wgsl's pattern_sample per sample; skipped samples still count in n).
fn shade_lobe(lobe: Lobe, transmission: bool, wo_l: vec3<f32>,
              t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let count = lobe.sample_count;
    if (count == 0u) {
        return vec3<f32>(0.0);
    }
    // 002 Eq. 14–15: A = π u v.
    let area = lobe_area(lobe.mx, lobe.my, lobe.xi0, wo_l);
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < count; i++) {
        let h = samples[lobe.sample_start + i].xyz;
        sum += pattern_sample(lobe, transmission, wo_l, h, area, count, t, b, n, pyramid,
                              linear_sampler, globals.params.w, globals.params.z);
    }
    return lobe.ks * sum / f32(count);
}

// integrator::shade_regular_with (Pdf002, no bounding planes): the frame faces the viewer (flipped to
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
            c += lattice_lobe(lobe, k >= m.reflection, wo_l, t, b, n, 1u, pyramid, linear_sampler,
                              globals.params.w, globals.params.z);
        } else if (lobe.scheme == 2u) {
            c += lattice_lobe(lobe, k >= m.reflection, wo_l, t, b, n, LATTICE_MAX_TAPS, pyramid,
                              linear_sampler, globals.params.w, globals.params.z);
        } else {
            c += shade_lobe(lobe, k >= m.reflection, wo_l, t, b, n);
        }
    }
    // integrator::shade_suns: the suns of a lattice + sun plan, exactly, after the lobes.
    for (var s = 0u; s < m.sun_count; s++) {
        let sun = suns[m.sun_start + s];
        let sun_l = vec3<f32>(dot(sun.direction, t), dot(sun.direction, b), dot(sun.direction, n));
        for (var k = 0u; k < m.reflection + m.transmission; k++) {
            c += sun_lobe(lobes[m.lobe_start + k], k >= m.reflection, wo_l, sun_l, sun.irradiance,
                           sun.spread);
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
