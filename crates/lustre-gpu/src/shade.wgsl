// The regular-sampling kernel of lustre-shade (kernel::shade_regular with Weighting::Pdf002) and
// the scene ray casting of lustre_shade::scene, in f32. One invocation shades one pixel.
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
    // The pattern's half vectors: samples[sample_start .. sample_start + sample_count].
    sample_start: u32,
    sample_count: u32,
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

// ShadingFrame::new(n, t_hint): Gram–Schmidt, t = normalize(t_hint − (t_hint·n) n), b = n × t.
fn frame_t(n: vec3<f32>, t_hint: vec3<f32>) -> vec3<f32> {
    let t = t_hint - dot(t_hint, n) * n;
    let l = length(t);
    if (l < 1e-6) {
        // A hint along n: any perpendicular tangent.
        var other = vec3<f32>(1.0, 0.0, 0.0);
        if (abs(n.x) > 0.9) {
            other = vec3<f32>(0.0, 0.0, 1.0);
        }
        return normalize(other - dot(other, n) * n);
    }
    return t / l;
}

// Primary ray of pixel (x, y) in a W×H image (contract): px = (2(x+0.5)/W − 1)·a·W/H;
// py = (1 − 2(y+0.5)/H)·a; dir = normalize(fwd + px·right + py·up').
fn primary_dir(x: u32, y: u32) -> vec3<f32> {
    let w = f32(globals.dims.x);
    let h = f32(globals.dims.y);
    let a = globals.params.x;
    let px = (2.0 * (f32(x) + 0.5) / w - 1.0) * a * globals.params.y;
    let py = (1.0 - 2.0 * (f32(y) + 0.5) / h) * a;
    return normalize(globals.fwd.xyz + px * globals.right.xyz + py * globals.up.xyz);
}

const T_MIN: f32 = 1e-4;

// Ray–sphere: |o + s d − c|² = r², nearest s > T_MIN. The tangent follows the sphere's axis:
// t = normalize(axis × n), falling back to x̂ × n, then ẑ, where the cross product vanishes.
fn hit_sphere(o: vec3<f32>, d: vec3<f32>, s: Sphere, best: f32) -> Hit {
    let oc = o - s.center;
    let bb = dot(oc, d);
    let cc = dot(oc, oc) - s.radius * s.radius;
    let disc = bb * bb - cc;
    if (disc < 0.0) {
        return no_hit();
    }
    let sq = sqrt(disc);
    var dist = -bb - sq;
    if (dist <= T_MIN) {
        dist = -bb + sq;
    }
    if (dist <= T_MIN || dist >= best) {
        return no_hit();
    }
    let p = o + dist * d;
    let n = normalize(p - s.center);
    var c = cross(s.axis, n);
    if (length(c) < 1e-6) {
        c = cross(vec3<f32>(1.0, 0.0, 0.0), n);
        if (length(c) < 1e-6) {
            c = vec3<f32>(0.0, 0.0, 1.0);
        }
    }
    let t = frame_t(n, normalize(c));
    return Hit(true, dist, p, t, cross(n, t), n, s.material);
}

// Ray–square: (o + s d − point)·normal = 0, |local x|, |local y| ≤ half_size.
fn hit_plane(o: vec3<f32>, d: vec3<f32>, q: Plane, best: f32) -> Hit {
    let n = normalize(q.normal);
    let denom = dot(d, n);
    if (abs(denom) < 1e-12) {
        return no_hit();
    }
    let dist = dot(q.point - o, n) / denom;
    if (dist <= T_MIN || dist >= best) {
        return no_hit();
    }
    let p = o + dist * d;
    let t = frame_t(n, q.tangent);
    let b = cross(n, t);
    let r = p - q.point;
    if (abs(dot(r, t)) > q.half_size || abs(dot(r, b)) > q.half_size) {
        return no_hit();
    }
    return Hit(true, dist, p, t, b, n, q.material);
}

// Scene::intersect: the nearest hit over all spheres and planes.
fn intersect(o: vec3<f32>, d: vec3<f32>) -> Hit {
    var best = no_hit();
    var best_dist = 3.4e38;
    for (var i = 0u; i < globals.dims.z; i++) {
        let h = hit_sphere(o, d, spheres[i], best_dist);
        if (h.found) {
            best = h;
            best_dist = h.distance;
        }
    }
    for (var i = 0u; i < globals.dims.w; i++) {
        let h = hit_plane(o, d, planes[i], best_dist);
        if (h.found) {
            best = h;
            best_dist = h.distance;
        }
    }
    return best;
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

// lobe_eval: ks · F D / (4 (ωo·h) ((ωi·n)(ωo·n))^α) (002 Eq. 2); 1 − F for transmission.
fn lobe_eval(lobe: Lobe, transmission: bool, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let hs = wi + wo;
    let hl = length(hs);
    if (hl <= 0.0) {
        return vec3<f32>(0.0);
    }
    let h = hs / hl;
    let u = dot(wo, h);
    if (u <= 0.0) {
        return vec3<f32>(0.0);
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
    return lobe.ks * (fresnel * d / (4.0 * u * shadow));
}

// ---------------------------------------------------------------- MIP level (mip.rs) --------

fn reflect_about(w: vec3<f32>, h: vec3<f32>) -> vec3<f32> {
    return 2.0 * dot(w, h) * h - w;
}

// lobe_area: 002 Eq. 14–15, A = π·u·v at unit distance. The extreme half vectors at the ξ0
// border along x and y (θ = arctan(√(−ln ξ0)·m), 002 Eq. 11 per axis) reflect ωo into ωU and ωV;
// the lobe centre ωC is ωo mirrored about the normal.
fn lobe_area(mx: f32, my: f32, xi0: f32, wo: vec3<f32>) -> f32 {
    let s = sqrt(-log(xi0));
    let tx = atan(s * mx);
    let ty = atan(s * my);
    let hu = vec3<f32>(sin(tx), 0.0, cos(tx));
    let hv = vec3<f32>(0.0, sin(ty), cos(ty));
    let wc = vec3<f32>(-wo.x, -wo.y, wo.z);
    let wu = reflect_about(wo, hu);
    let wv = reflect_about(wo, hv);
    // Eq. 14: αU = arccos(ωC·ωU), αV = arccos(ωC·ωV); Eq. 15: u = tan αU, v = tan αV.
    let au = min(acos(clamp(dot(wc, wu), -1.0, 1.0)), 0.5 * PI - 1e-3);
    let av = min(acos(clamp(dot(wc, wv), -1.0, 1.0)), 0.5 * PI - 1e-3);
    return PI * tan(au) * tan(av);
}

// regular_level: 002 Eq. 16, pixels = A·N / (4 n) · ‖ωi‖/‖ωi‖∞ · 1/(ωi·h), N = face_size²;
// level = log4(pixels), at least 0.
fn regular_level(area: f32, n_samples: u32, wi: vec3<f32>, wi_dot_h: f32, face_size: f32) -> f32 {
    let inf_norm = max(abs(wi.x), max(abs(wi.y), abs(wi.z)));
    let pixels = area * face_size * face_size / (4.0 * f32(n_samples)) * (length(wi) / inf_norm)
        / max(wi_dot_h, 1e-6);
    return max(log2(max(pixels, 1e-30)) * 0.5, 0.0);
}

// ---------------------------------------------------------------- kernel (kernel.rs) --------

fn to_world(h: vec3<f32>, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return h.x * t + h.y * b + h.z * n;
}

// One lobe by the 002 pseudo code (EvaluateSpecularLobe) with the Pdf002 weighting.
// A transmission lobe is evaluated in the mirrored reflection geometry; its light arrives from
// the reflected direction mirrored through the surface plane.
fn shade_lobe(lobe: Lobe, transmission: bool, wo: vec3<f32>, wo_local: vec3<f32>,
              t: vec3<f32>, b: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let count = lobe.sample_count;
    if (count == 0u) {
        return vec3<f32>(0.0);
    }
    // Equation 14, 15 & area.
    let area = lobe_area(lobe.mx, lobe.my, lobe.xi0, wo_local);
    let lod_max = globals.params.z;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < count; i++) {
        let h_local = samples[lobe.sample_start + i].xyz;
        let h = to_world(h_local, t, b, n);
        // lightInVec = reflect(−lightOutVec, h).
        let wi = reflect_about(wo, h);
        let wi_dot_h = dot(wi, h);
        let wi_local = reflect_about(wo_local, h_local);
        var lookup = wi;
        if (transmission) {
            lookup = wi - 2.0 * dot(wi, n) * n;
        }
        // Equation 16.
        let level = clamp(regular_level(area, count, lookup, wi_dot_h, globals.params.w), 0.0, lod_max);
        // Environment map lookup.
        let l = textureSampleLevel(pyramid, linear_sampler, lookup, level).rgb;
        // Equation 2.
        let brdf = lobe_eval(lobe, transmission, wi_local, wo_local);
        // Equation 17 & 18.
        let pdf = lobe.pdf_constant / (4.0 * wi_dot_h);
        let cos_i = wi_local.z;
        // Equation 9 (inner sum).
        if (pdf > 0.0 && cos_i > 0.0) {
            sum += l * brdf / pdf * cos_i;
        }
    }
    return sum / f32(count);
}

// shade_regular: diffuse = kd · irradiance(n) (the map stores E/π) plus every lobe. The thin
// two-sided surface is shaded from the side of the viewer: n flips when ωo is below it.
fn shade(hit: Hit, wo: vec3<f32>) -> vec3<f32> {
    let m = materials[hit.material];
    var n = hit.n;
    let t = hit.t;
    let b = hit.b;
    var wo_local = vec3<f32>(dot(wo, t), dot(wo, b), dot(wo, n));
    if (wo_local.z < 0.0) {
        n = -n;
        wo_local.z = -wo_local.z;
    }
    var c = m.kd * textureSampleLevel(irradiance, linear_sampler, n, 0.0).rgb;
    for (var k = 0u; k < m.reflection + m.transmission; k++) {
        c += shade_lobe(lobes[m.lobe_start + k], k >= m.reflection, wo, wo_local, t, b, n);
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
