// Hierarchical shading (004 §IV.4.2, Fig. IV.11 c–d, Fig. IV.12) of one level of the
// bandwidth buffer's pyramid: each pixel of level k's grid that no coarser grid holds is
// up-sampled from its four parents (depth Gaussian × anisotropic screen-space Gaussian ×
// bilinear weights) when the min-filtered level allows it, else shaded with the N_p of its
// block's max-filtered variance. CPU twin: lustre_adaptive::hierarchy::render_adaptive, its
// shading lustre_adaptive::shading::ShadingContext::shade (direct or pre-convolved): tabulated-CDF
// BRDF samples and environment samples combined by the balance heuristic, plus area lights.
// Materials: measured BRDFs evaluated directly (measured_eval: kinds 0, 1 and 3) or records
// (kind 2, `base` indexing `fitted`; textured ones read at the pixel's uv by material_prepare);
// records of transmissive or Dirac models (no tabulated CDFs: tab_base NO_TABLE) sampled by
// material_sample. A pixel's samples are shaded SAMPLES_PER_DISPATCH per dispatch (phase 1
// repeated, each adding its share), within lavapipe's 65,535 loop iterations per invocation.
// Imports: types, measured, qmc, env_light, cube_storage, area_light, bsdf_sample, and with
// records bsdf (or analytic) and textured.

struct Params {
    width: u32,
    height: u32,
    level: u32,
    top: u32,
    seed: vec2<u32>,
    lights: u32,
    max_samples: u32,
    // N_p at this level when > 0 (SampleRule::Constant, or Coverage's N_p for the level); else
    // from the variance quotas.
    constant: u32,
    // Levels of the pre-convolved pyramid (0: none uploaded).
    pyramid_levels: u32,
    // 0: classify level `level`'s new grid points (up-sample, or queue for shading); 1: shade
    // the queue.
    phase: u32,
    // Phase 1: the first sample (or area-light point) of this dispatch's share; each dispatch
    // takes at most SAMPLES_PER_DISPATCH of a pixel's (adaptive_pass::SAMPLES_PER_DISPATCH).
    first: u32,
    env: EnvDims,
    // Rows of the rotation taking world directions to the map's.
    to_map0: vec4<f32>,
    to_map1: vec4<f32>,
    to_map2: vec4<f32>,
    // The camera's right and up (world).
    right: vec4<f32>,
    up: vec4<f32>,
    // 1 where the environment lights the scene, 0 where it is black (no BRDF or environment
    // samples then, as on the CPU).
    env_lit: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// A pixel of the G-buffer: position (xyz) and depth; the shading frame t, b, n; the direction
// to the eye; the material index in t.w (bitcast u32; 0xffffffff: background); in b.w the
// pyramid level of pre-convolved shading (< 0: the map at full resolution); the texture
// coordinates in n.w and wo.w.
struct Surfel {
    p: vec4<f32>,
    t: vec4<f32>,
    b: vec4<f32>,
    n: vec4<f32>,
    wo: vec4<f32>,
}

// A material: its kind (0 neural BRDF, 1 MERL table, 2 fitted model), first word (kind 2: its
// record in `fitted`) and MERL offset (f32 bits), then the first word of its tabulated CDFs
// and their layout.
struct PassMaterial {
    kind: u32,
    base: u32,
    offset: u32,
    tab_base: u32,
    dims: TabulatedDims,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> surfels: array<Surfel>;
@group(0) @binding(2) var<storage, read> env_texels: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> env_words: array<f32>;
@group(0) @binding(4) var<storage, read> materials: array<PassMaterial>;
@group(0) @binding(5) var<storage, read> table: array<f32>;
@group(0) @binding(6) var<storage, read> lights: array<AreaLight>;
@group(0) @binding(7) var<storage, read> light_texels: array<vec4<f32>>;
// The pyramids (adaptive_pyramid.wgsl): per level k, row-major blocks of 2^k × 2^k pixels.
@group(0) @binding(8) var<storage, read> min_level: array<u32>;
@group(0) @binding(9) var<storage, read> max_quota: array<f32>;
// Per pixel: the value (rgb) and 1 in w once set.
@group(0) @binding(10) var<storage, read_write> values: array<vec4<f32>>;
// Per pixel: the level it was shaded at (255: not shaded) and its samples.
@group(0) @binding(11) var<storage, read_write> shaded: array<vec2<u32>>;
// Binding 12, the records, bindings 18–20, their textured parameters and textures, and
// `material_prepare` / `material_eval` come with the pass's variant
// (measured::material_eval_source).
// The pre-convolved pyramid (world directions; module cube_storage).
@group(0) @binding(13) var<storage, read> cube_texels: array<vec4<f32>>;
@group(0) @binding(14) var<storage, read> cube_levels: array<vec4<u32>>;
@group(0) @binding(15) var<storage, read> cube_rings: array<vec4<i32>>;

// The pixels a level shades (phase 0 appends, phase 1 reads) and, per level, how many.
@group(0) @binding(16) var<storage, read_write> queue: array<u32>;
@group(0) @binding(17) var<storage, read_write> counts: array<atomic<u32>>;

fn cube_texel(i: u32) -> vec3<f32> {
    return cube_texels[i].xyz;
}

fn cube_level(i: u32) -> vec4<u32> {
    return cube_levels[i];
}

fn cube_ring(i: u32) -> vec4<i32> {
    return cube_rings[i];
}

// The light arriving from world direction d (dm in the map's frame): the pyramid at `lod`
// (Lighting::Preconvolved), or the map itself.
fn incident(d: vec3<f32>, dm: vec3<f32>, lod: f32) -> vec3<f32> {
    if (lod >= 0.0 && params.pyramid_levels > 0u) {
        return cube_trilinear(0u, params.pyramid_levels, d, lod);
    }
    return env_bilinear(params.env, dm);
}

fn bsdf_table(i: u32) -> f32 {
    return table[i];
}

fn env_texel(i: u32) -> vec3<f32> {
    return env_texels[i].xyz;
}

fn env_table(i: u32) -> f32 {
    return env_words[i];
}

const BACKGROUND: u32 = 0xffffffffu;
const NOT_SHADED: u32 = 255u;
// adaptive_pass::SAMPLES_PER_DISPATCH.
const SAMPLES_PER_DISPATCH: u32 = 128u;
// PassMaterial::tab_base of a model sampled by its own `material_sample` (no tabulated CDFs).
const NO_TABLE: u32 = 0xffffffffu;
// hierarchy::MIN_WEIGHT and gbuffer::SAME_SURFACE.
const MIN_WEIGHT: f32 = 0.05;
const SAME_SURFACE: f32 = 0.05;

// The first entry of level k's blocks, and the width of its rows of blocks.
fn pyramid_row(k: u32) -> vec2<u32> {
    var offset = 0u;
    for (var m = 0u; m < k; m++) {
        let s = 1u << m;
        offset += ((params.width + s - 1u) / s) * ((params.height + s - 1u) / s);
    }
    let s = 1u << k;
    return vec2<u32>(offset, (params.width + s - 1u) / s);
}

fn block(k: u32, x: u32, y: u32) -> u32 {
    let r = pyramid_row(k);
    return r.x + (y >> k) * r.y + (x >> k);
}

// BandwidthBuffer::samples: N_p of the level-k block holding (x, y).
fn samples_at(k: u32, x: u32, y: u32) -> u32 {
    if (params.constant > 0u) {
        return params.constant;
    }
    let q = max_quota[block(k, x, y)];
    if (!(q > 0.0)) {
        return 1u;
    }
    return u32(clamp(ceil(min(q, f32(params.max_samples))), 1.0, f32(params.max_samples)));
}

fn to_map(d: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(params.to_map0.xyz, d), dot(params.to_map1.xyz, d),
                     dot(params.to_map2.xyz, d));
}

fn finite3(v: vec3<f32>) -> bool {
    return all(abs(v) < vec3<f32>(3.0e38)) && all(v == v);
}

// lustre_brdf::sampling::hammersley(k, n) as f32: ((k + ½) / n, the radical inverse's top 24
// bits).
fn hammersley(k: u32, n: u32) -> vec2<f32> {
    return vec2<f32>((f32(k) + 0.5) / f32(n),
                     f32(reverseBits(k) >> 8u) * (1.0 / 16777216.0));
}

// SplitMix64::next_f64's top 24 bits.
fn next_unit(state: ptr<function, vec2<u32>>) -> f32 {
    return f32(splitmix64_next(state).y >> 8u) * (1.0 / 16777216.0);
}

// shading::pixel_seed(seed, k): SplitMix64(seed ^ k · 0x9E3779B97F4A7C15).next_u64().
fn shading_seed(k: u32) -> vec2<u32> {
    var state = params.seed ^ mul64(vec2<u32>(k, 0u), vec2<u32>(0x7F4A7C15u, 0x9E3779B9u));
    return splitmix64_next(&state);
}

// Draw k of SplitMix64(seed) as next_unit returns it (the generator is a counter: state k + 1
// is seed + (k + 1) · γ).
fn draw_unit(seed: vec2<u32>, k: u32) -> f32 {
    var state = add64(seed, mul64(vec2<u32>(k, 0u), vec2<u32>(0x7F4A7C15u, 0x9E3779B9u)));
    return next_unit(&state);
}

// ShadingContext::shade at surfel s with n samples: ⌈n/2⌉ BRDF samples,
// ⌊n/2⌋ environment samples, then n points per area light, in the CPU's order, through one
// loop so that the material's evaluation is compiled once; this dispatch's share, the ones
// numbered first … first + SAMPLES_PER_DISPATCH − 1.
fn shade(s: Surfel, n_in: u32, seed: vec2<u32>, first: u32) -> vec3<f32> {
    let t = s.t.xyz;
    let b = s.b.xyz;
    let nn = s.n.xyz;
    let wo = vec3<f32>(dot(s.wo.xyz, t), dot(s.wo.xyz, b), dot(s.wo.xyz, nn));
    let m = materials[bitcast<u32>(s.t.w)];
    material_prepare(m.kind, m.base, vec2<f32>(s.n.w, s.wo.w));
    let n = max(n_in, 1u);
    let env_lit = params.env_lit != 0u;
    let n_f = select(0u, (n + 1u) / 2u, env_lit);
    let n_l = select(0u, n / 2u, env_lit);
    let rot = vec4<f32>(draw_unit(seed, 0u), draw_unit(seed, 1u), draw_unit(seed, 2u),
                        draw_unit(seed, 3u));
    let total = n_f + n_l + params.lights * n;
    // Transmissive and Dirac models have no tabulated CDFs: their BSDF samples are the
    // model's own (the CPU's `Bsdf::sample`), valued by the sample itself. (A variant whose
    // materials all have tabulated CDFs has none: MATERIAL_SAMPLES false folds these branches
    // away.)
    let own = MATERIAL_SAMPLES && m.tab_base == NO_TABLE;
    var sum = vec3<f32>(0.0);
    let end = min(total, first + SAMPLES_PER_DISPATCH);
    for (var k = first; k < end; k++) {
        var wi = vec3<f32>(0.0);
        // What multiplies f(wi, wo) (0: no contribution).
        var weight = vec3<f32>(0.0);
        // The sample's own value, used instead of f(wi, wo) when `valued`.
        var value = vec3<f32>(0.0);
        var valued = false;
        var dirac = false;
        if (k < n_f + n_l) {
            // The BRDF's samples by its tabulated CDFs, then the environment's.
            var d = vec3<f32>(0.0);
            var p_f = 0.0;
            if (k < n_f) {
                let u = fract(hammersley(k, n_f) + rot.xy);
                if (own) {
                    let smp = material_sample(wo, u);
                    if (smp.pdf == 0.0) {
                        continue;
                    }
                    wi = smp.wi;
                    d = t * wi.x + b * wi.y + nn * wi.z;
                    valued = true;
                    if (smp.delta != 0u) {
                        dirac = true;
                        // A Dirac lobe: its weight f |cos θi| / P, no MIS (env samples never
                        // reach it).
                        value = smp.value * (abs(wi.z) / smp.pdf);
                        weight = incident(d, to_map(d), s.b.w) / f32(n_f);
                    } else {
                        value = smp.value;
                        p_f = smp.pdf;
                    }
                } else {
                    let smp = tabulated_sample(m.tab_base, m.dims, wo, u.x, u.y);
                    if (smp.w == 0.0) {
                        continue;
                    }
                    wi = smp.xyz;
                    p_f = smp.w;
                    d = t * wi.x + b * wi.y + nn * wi.z;
                }
            } else {
                let u = fract(hammersley(k - n_f, n_l) + rot.zw);
                let e = env_sample(params.env, u.x, u.y);
                // The map's direction in world space, then in the shading frame.
                d = params.to_map0.xyz * e.x + params.to_map1.xyz * e.y
                    + params.to_map2.xyz * e.z;
                wi = vec3<f32>(dot(d, t), dot(d, b), dot(d, nn));
                if (own) {
                    p_f = material_pdf(wi, wo);
                } else {
                    p_f = tabulated_pdf(m.tab_base, m.dims, wi, wo);
                }
            }
            if (!dirac) {
                let dm = to_map(d);
                let den = f32(n_f) * p_f + f32(n_l) * env_pdf(params.env, dm);
                if (!(den > 0.0)) {
                    continue;
                }
                weight = incident(d, dm, s.b.w) * (abs(wi.z) / den);
            }
        } else {
            // Area light l's point j, stratified over its area; its rotation is the pair of
            // draws after the four above.
            let l = (k - n_f - n_l) / n;
            let j = (k - n_f - n_l) % n;
            let r = vec2<f32>(draw_unit(seed, 4u + 2u * l), draw_unit(seed, 5u + 2u * l));
            let light = lights[l];
            let uv = fract(hammersley(j, n) + r);
            let dv = area_light_point(light, uv) - s.p.xyz;
            let dist = length(dv);
            if (!(dist > 0.0 && dist < 3.0e38)) {
                continue;
            }
            let w = dv / dist;
            let cos_l = -dot(w, light.normal.xyz);
            if (cos_l <= 0.0) {
                continue;
            }
            wi = vec3<f32>(dot(w, t), dot(w, b), dot(w, nn));
            let g = cos_l * light.radiance.w / (dist * dist * f32(n));
            weight = light.radiance.xyz * light_texels[area_light_texel(light, uv)].xyz
                * (abs(wi.z) * g);
        }
        // Evaluated on every path (a Dirac direction evaluates to 0), the sample's own value
        // taken where it has one.
        let f = select(material_eval(m.kind, m.base, bitcast<f32>(m.offset), wi, wo), value,
                       valued);
        let v = f * weight;
        if (finite3(v)) {
            sum += v;
        }
    }
    return sum;
}

// hierarchy::upsample: the value of (x, y) at `level` from its parents, w = 1; w = 0 when it
// must be shaded.
fn upsample(s: Surfel, x: u32, y: u32, level: u32) -> vec4<f32> {
    let w = params.width;
    let p = 2u << level;
    let x0 = x / p * p;
    let y0 = y / p * p;
    let ax = f32(x - x0) / f32(p);
    let ay = f32(y - y0) / f32(p);
    let nn = s.n.xyz;
    let proj = vec2<f32>(dot(nn, params.right.xyz), -dot(nn, params.up.xyz));
    let len = length(proj);
    let cos_x = max(abs(dot(nn, s.wo.xyz)), 0.05);
    let mat = bitcast<u32>(s.t.w);
    var sum = vec3<f32>(0.0);
    var weight = 0.0;
    for (var c = 0u; c < 4u; c++) {
        let cx = x0 + p * (c & 1u);
        let cy = y0 + p * (c >> 1u);
        var alpha = 0.0;
        switch c {
            case 0u: { alpha = (1.0 - ax) * (1.0 - ay); }
            case 1u: { alpha = ax * (1.0 - ay); }
            case 2u: { alpha = (1.0 - ax) * ay; }
            default: { alpha = ax * ay; }
        }
        if (alpha == 0.0) {
            continue;
        }
        if (cx >= w || cy >= params.height) {
            return vec4<f32>(0.0);
        }
        if (min_level[block(level + 1u, cx, cy)] < level + 1u) {
            return vec4<f32>(0.0);
        }
        let qi = cy * w + cx;
        let q = surfels[qi];
        let value = values[qi];
        if (bitcast<u32>(q.t.w) != mat || value.w == 0.0) {
            continue;
        }
        let dz = (s.p.w - q.p.w) / (SAME_SURFACE * s.p.w);
        let v = vec2<f32>((f32(x) - f32(cx)) / f32(p), (f32(y) - f32(cy)) / f32(p));
        var quad = dot(v, v);
        // glam's try_normalize: a finite, non-zero length.
        if (len > 0.0 && len < 3.0e38) {
            let a = proj / len;
            let par = dot(v, a);
            let perp = v.x * a.y - v.y * a.x;
            quad = perp * perp + par * par / (cos_x * cos_x);
        }
        let wgt = exp(-dz * dz) * exp(-quad) * alpha;
        sum += value.xyz * wgt;
        weight += wgt;
    }
    if (weight >= MIN_WEIGHT) {
        return vec4<f32>(sum / weight, 1.0);
    }
    return vec4<f32>(0.0);
}

// Classification (phase 0), thread i: grid point i of the level (row-major over the ⌈W / 2^k⌉
// × ⌈H / 2^k⌉ points) is up-sampled now or appended to the queue; shading (phase 1), thread i:
// the i-th queued pixel. Queuing keeps the shading threads of a workgroup all busy (a level's
// shaded pixels are scattered) and the dispatches one-dimensional.
// Dispatches wider than the 65,535 workgroups of one dimension continue in y.
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid3: vec3<u32>,
        @builtin(num_workgroups) groups: vec3<u32>) {
    let i = gid3.y * groups.x * 64u + gid3.x;
    let level = params.level;
    if (params.phase == 1u) {
        if (i >= atomicLoad(&counts[level])) {
            return;
        }
        let k = queue[i];
        let x = k % params.width;
        let y = k / params.width;
        let n = samples_at(level, x, y);
        if (params.first > 0u && params.first >= n * (1u + params.lights)) {
            return;
        }
        // One call site, so that the shading is compiled once.
        let v = shade(surfels[k], n, shading_seed(k), params.first);
        if (params.first == 0u) {
            values[k] = vec4<f32>(v, 1.0);
            shaded[k] = vec2<u32>(level, n);
        } else {
            values[k] = vec4<f32>(values[k].xyz + v, 1.0);
        }
        return;
    }
    let nx = (params.width + (1u << level) - 1u) >> level;
    let x = (i % nx) << level;
    let y = (i / nx) << level;
    if (x >= params.width || y >= params.height) {
        return;
    }
    let parent = 2u << level;
    if (level < params.top && x % parent == 0u && y % parent == 0u) {
        return;
    }
    let k = y * params.width + x;
    let s = surfels[k];
    if (bitcast<u32>(s.t.w) == BACKGROUND) {
        return;
    }
    if (level < params.top) {
        let v = upsample(s, x, y, level);
        if (v.w > 0.0) {
            values[k] = v;
            shaded[k] = vec2<u32>(NOT_SHADED, 0u);
            return;
        }
    }
    queue[atomicAdd(&counts[level], 1u)] = k;
}
