// The view-dependent part of the walkthrough frame over a G-buffer (000 §4,
// Eq. 4.4): the twin of `lustre_shade::frame::shade_gbuffer_view_dependent`, i.e. of
// `frame::view_dependent` per G-buffer pixel, in f32. Per pixel: the material record
// (GpuBsdf) → the model's sample/eval; n points (the Fibonacci lattice, CK's SplitMix64 points,
// or frame f's R2-rotated lattice) pushed through the warp; f − kd/π on the reflection side;
// Dirac-only materials summed over their branches (≤ 2 lookups); each sample read from the
// mirror buffer of an in-plane reflector triangle, the see-through buffer of a transmissive
// probe object, the probe of the object (else probe::choose_probe's, two room probes blended by
// depth where their boxes overlap; through its bounding planes) or
// the environment's pyramid. `samples_main` runs one thread per G-buffer pixel over samples
// [first, end) of each: llvmpipe (lavapipe) ends an invocation's loops silently once they have
// run 65,535 iterations together, and 16 G-buffer pixels × 256 samples did (frame_shade.rs
// `SAMPLES_PER_DISPATCH`); each dispatch adds its share of the mean into `partial`. `main`
// then runs one thread per output pixel: it box-averages its k×k G-buffer pixels and adds the
// light-mapped image; progressive frames accumulate per G-buffer pixel in `accum`.

struct Params {
    origin: vec4<f32>,
    forward: vec4<f32>,
    right: vec4<f32>,
    up: vec4<f32>,
    // x: tan(fov_y / 2), y: aspect of the G-buffer (W / H).
    cam: vec4<f32>,
    // G-buffer width, height, k, samples n.
    sizes: vec4<u32>,
    // method (0 regular, 1 CK, 2 progressive), progressive frame f, probes, light-map page width.
    method: vec4<u32>,
    // seed (low, high word), environment cube (NONE: none), light-map page height.
    seed: vec4<u32>,
    // (columns, rows, 1: only the pixels of covered tiles have a view-dependent part (the rest:
    // the light-mapped image alone; a see-through layer's tiles, mirror::ScreenTiles), 0).
    tiles: vec4<u32>,
    // x: 1 when see-through buffers are not read (a see-through layer's own shading,
    // frame::shade_see_through_layer, or a mirror layer's), 0 otherwise; y: 1 when mirror
    // buffers are not read (a mirror layer's own shading, frame::shade_mirror_layer).
    flags: vec4<u32>,
    // samples_main's share: samples first..end of each pixel's n (x, y), 0, 0.
    chunk: vec4<u32>,
    // The first vec4 of each part of the arena (at_tris … at_tex_info).
    parts: array<vec4<u32>, 5>,
};

@group(0) @binding(0) var<uniform> u: Params;
@group(0) @binding(1) var prim_tex: texture_2d<u32>;
@group(0) @binding(2) var bary_tex: texture_2d<f32>;
// Everything the pass reads besides the G-buffer, the light-mapped image and the tile mask, in
// one buffer (frame_shade.rs `FrameShadeScene`, parts at `u.parts`): WebGPU allows as few as 8
// storage buffers per shader stage. Read as vec4<f32> (`arena`) and, for the parts that hold
// integers, as vec4<u32> (`arena_u`, the same buffer).
@group(0) @binding(3) var<storage, read> arena: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> arena_u: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> lightmapped: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> accum: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out_px: array<vec4<f32>>;
// (glossy hits, lookups), summed per workgroup first.
@group(0) @binding(8) var<storage, read_write> counts: array<atomic<u32>, 2>;
// Per SCREEN_TILE² tile of the output (row-major): 1 where covered (read when u.tiles.z = 1).
@group(0) @binding(9) var<storage, read> tile_mask: array<u32>;
// Per G-buffer pixel: the view-dependent radiance summed over the dispatches so far.
@group(0) @binding(10) var<storage, read_write> partial: array<vec4<f32>>;

// The parts of the arena (their first vec4; frame_shade.rs `Part`), in this order:
// - tris: 7 vec4 per triangle (frame_shade.rs `FrameShadeScene::new`);
// - bsdfs: the material records (GpuBsdf), 9 vec4 each (`load_bsdf`);
// - tables: the materials' tables (f32, 4 a vec4; `bsdf_table`);
// - cube_texels: every level of every cube, RGBA f32, face-major, row-major;
// - cube_levels (u32): per cube level (first texel, face size, first ring entry, 0);
// - cubes: per cube (centre xyz, first level bits), (level count, first plane, plane count, a
//   room probe) as bits;
// - planes: per bounding plane (point xyz, 0), (normal xyz, 0), relative to the cube's centre;
// - ring (u32, read as i32): per cube level, per face, the 4(n + 1) texels one texel beyond
//   the edges: up to three global texel indices and their count;
// - view_radiance, view_geometry: the view buffers' levels;
// - views: per view buffer, 8 vec4: camera origin, forward, right, up (w: tan(fov_y / 2) in
//   origin.w); (width, height, levels, first radiance texel) bits; (first geometry vec4, has
//   front, slab thickness, relative index); front point; front normal;
// - params: per material, 5 vec4 (`pack_material_params`): the textured parameters (rgb, three
//   scalars) and the normal map, read where the record is flagged;
// - tangents: per triangle of a normal-mapped material (its record's r6.w): the corners'
//   tangents (xyz, w: the bitangent's sign, 0: derive T from ∂p/∂u) and (∂p/∂v, 0);
// - albedo_tris, mats, texels, tex_info (u32): the light-map pass's records
//   (lightmap_shade.rs `shading_records`), read for the diffuse albedo kd at each pixel
//   (`Lightmapped::albedo`): 8 vec4 per triangle, 4 per material (material_albedo.wgsl), the
//   textures (texture_sample.wgsl; the material parameters' too).
fn at_tris() -> u32 { return u.parts[0].x; }
fn at_bsdfs() -> u32 { return u.parts[0].y; }
fn at_tables() -> u32 { return u.parts[0].z; }
fn at_cube_texels() -> u32 { return u.parts[0].w; }
fn at_cube_levels() -> u32 { return u.parts[1].x; }
fn at_cubes() -> u32 { return u.parts[1].y; }
fn at_planes() -> u32 { return u.parts[1].z; }
fn at_ring() -> u32 { return u.parts[1].w; }
fn at_view_radiance() -> u32 { return u.parts[2].x; }
fn at_view_geometry() -> u32 { return u.parts[2].y; }
fn at_views() -> u32 { return u.parts[2].z; }
fn at_params() -> u32 { return u.parts[2].w; }
fn at_tangents() -> u32 { return u.parts[3].x; }
fn at_albedo_tris() -> u32 { return u.parts[3].y; }
fn at_mats() -> u32 { return u.parts[3].z; }
fn at_texels() -> u32 { return u.parts[3].w; }
fn at_tex_info() -> u32 { return u.parts[4].x; }

// Material record `m` (GpuBsdf: kind, flags, two pads, 8 vec4).
fn load_bsdf(m: u32) -> GpuBsdf {
    let o = at_bsdfs() + 9u * m;
    let h = arena_u[o];
    var b: GpuBsdf;
    b.kind = h.x;
    b.flags = h.y;
    b.pad0 = h.z;
    b.pad1 = h.w;
    for (var i = 0u; i < 8u; i++) {
        b.p[i] = arena[o + 1u + i];
    }
    return b;
}

// texture_sample.wgsl's texels and per-texture records.
fn texture_texel(i: u32) -> vec4<f32> {
    return arena[at_texels() + i];
}

fn texture_info(t: u32) -> vec4<u32> {
    return arena_u[at_tex_info() + t];
}

// material_albedo.wgsl's material rows.
fn material_row(i: u32) -> vec4<f32> {
    return arena[at_mats() + i];
}
var<workgroup> wg_counts: array<atomic<u32>, 2>;

// lustre_shade::mirror::SCREEN_TILE.
const SCREEN_TILE: u32 = 8u;

const SKY: u32 = 0xffffffffu;
const NONE: u32 = 0xffffffffu;
const TRI_STRIDE: u32 = 7u;
const NO_PAGE: u32 = 0xffffffffu;
const METHOD_REGULAR: u32 = 0u;
const METHOD_CK: u32 = 1u;
const METHOD_PROGRESSIVE: u32 = 2u;
const BIG: f32 = 3.4e38;

// The rough plastic's transmittance tables (rough_plastic.wgsl's hook).
fn bsdf_table(i: u32) -> f32 {
    return arena[at_tables() + i / 4u][i % 4u];
}

fn finite3(c: vec3<f32>) -> bool {
    return all(abs(c) <= vec3<f32>(BIG));
}

// ---- cube maps (module cube_storage): its texels, levels and rings are this pass's.

fn cube_texel(i: u32) -> vec3<f32> {
    return arena[at_cube_texels() + i].xyz;
}

fn cube_ring(i: u32) -> vec4<i32> {
    return bitcast<vec4<i32>>(arena_u[at_ring() + i]);
}

fn cube_level(i: u32) -> vec4<u32> {
    return arena_u[at_cube_levels() + i];
}

// CubePyramid::sample on cube `cube` of the pass.
fn cube_sample(cube: u32, d: vec3<f32>, lod_in: f32) -> vec3<f32> {
    let first = bitcast<u32>(arena[at_cubes() + 2u * cube].w);
    let count = bitcast<u32>(arena[at_cubes() + 2u * cube + 1u].x);
    return cube_trilinear(first, count, d, lod_in);
}

// integrator::corrected_direction over the cube's planes (planes.wgsl).
fn cube_direction(cube: u32, rel: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let info = arena[at_cubes() + 2u * cube + 1u];
    let first = bitcast<u32>(info.y);
    let count = bitcast<u32>(info.z);
    if (count == 0u) {
        return wi;
    }
    var best = -1.0;
    for (var k = 0u; k < count; k++) {
        let pl = BoundingPlane(arena[at_planes() + 2u * (first + k)].xyz, arena[at_planes() + 2u * (first + k) + 1u].xyz);
        best = nearer_plane(best, pl, rel, wi);
    }
    return corrected_lookup(best, rel, wi);
}

// Whether `rel` (relative to cube `cube`'s centre) lies outside one of its bounding planes
// (probe::outside_plane: by more than 10⁻³ of the plane's distance).
// probe::plane_depth: the least signed distance of `rel` to cube `cube`'s bounding planes.
fn cube_depth(cube: u32, rel: vec3<f32>) -> f32 {
    let info = arena[at_cubes() + 2u * cube + 1u];
    let first = bitcast<u32>(info.y);
    let count = bitcast<u32>(info.z);
    var d = BIG;
    for (var k = 0u; k < count; k++) {
        let point = arena[at_planes() + 2u * (first + k)].xyz;
        let normal = arena[at_planes() + 2u * (first + k) + 1u].xyz;
        d = min(d, dot(rel - point, normal));
    }
    return d;
}

fn cube_outside(cube: u32, rel: vec3<f32>) -> bool {
    let info = arena[at_cubes() + 2u * cube + 1u];
    let first = bitcast<u32>(info.y);
    let count = bitcast<u32>(info.z);
    for (var k = 0u; k < count; k++) {
        let point = arena[at_planes() + 2u * (first + k)].xyz;
        let normal = arena[at_planes() + 2u * (first + k) + 1u].xyz;
        if (dot(rel - point, normal) < -1e-3 * length(point)) {
            return true;
        }
    }
    return false;
}

// mip::ck_level_at: ½ log2(Ωs/Ωp(ω)) + 1, clamped.
fn ck_level_at(pdf: f32, total: f32, face: f32, dir: vec3<f32>) -> f32 {
    let top = log2(max(face, 1.0));
    if (!(pdf > 0.0)) {
        return top;
    }
    let l = 0.5 * log2((1.0 / (total * pdf)) / texel_solid_angle_at(dir, face)) + 1.0;
    if (l != l) {
        return 0.0;
    }
    return clamp(l, 0.0, top);
}

// ---- view buffers (lustre_shade::mirror::ViewBuffer).

struct View {
    origin: vec3<f32>,
    forward: vec3<f32>,
    right: vec3<f32>,
    up: vec3<f32>,
    tan_half: f32,
    w: u32,
    h: u32,
    levels: u32,
    radiance: u32,
    geometry: u32,
    has_front: bool,
    front_normal: vec3<f32>,
    // a see-through buffer's slab: thickness (0: a thin sheet) and relative index
    slab: vec2<f32>,
}

fn load_view(v: u32) -> View {
    let b = 8u * v;
    let s = arena[at_views() + b + 4u];
    let g = arena[at_views() + b + 5u];
    return View(arena[at_views() + b].xyz, arena[at_views() + b + 1u].xyz, arena[at_views() + b + 2u].xyz, arena[at_views() + b + 3u].xyz,
                arena[at_views() + b].w, bitcast<u32>(s.x), bitcast<u32>(s.y), bitcast<u32>(s.z),
                bitcast<u32>(s.w), bitcast<u32>(g.x), bitcast<u32>(g.y) == 1u,
                arena[at_views() + b + 7u].xyz, g.zw);
}

// mirror::project_dir: image position of direction v (z = 0: none).
fn project_dir(view: View, v: vec3<f32>) -> vec3<f32> {
    let z = dot(v, view.forward);
    if (!(z > 1e-12)) {
        return vec3<f32>(0.0);
    }
    let a = view.tan_half;
    let wf = f32(view.w);
    let hf = f32(view.h);
    let px = dot(v, view.right) / z;
    let py = dot(v, view.up) / z;
    let x = (px / (a * wf / hf) + 1.0) * 0.5 * wf;
    let y = (1.0 - py / a) * 0.5 * hf;
    if (!(abs(x) <= BIG && abs(y) <= BIG)) {
        return vec3<f32>(0.0);
    }
    return vec3<f32>(x, y, 1.0);
}

fn project(view: View, p: vec3<f32>) -> vec3<f32> {
    return project_dir(view, p - view.origin);
}

// mirror::ray_plane: (point, 1) where p + s d (s > 0) meets the plane (q, n), else w = 0.
fn ray_plane(p: vec3<f32>, d: vec3<f32>, q: vec3<f32>, n: vec3<f32>) -> vec4<f32> {
    let denom = dot(d, n);
    if (!(abs(denom) >= 1e-12)) {
        return vec4<f32>(0.0);
    }
    let s = dot(q - p, n) / denom;
    if (!(s > 0.0 && s <= BIG)) {
        return vec4<f32>(0.0);
    }
    return vec4<f32>(p + d * s, 1.0);
}

// ViewBuffer::texel_at: the texel index at (x, y), NONE outside.
fn texel_at(view: View, xy: vec3<f32>) -> u32 {
    if (!(xy.z > 0.0 && xy.x >= 0.0 && xy.y >= 0.0 && xy.x < f32(view.w) && xy.y < f32(view.h))) {
        return NONE;
    }
    return u32(xy.y) * view.w + u32(xy.x);
}

struct Located {
    // (x, y, 1 found / 0 none)
    xy: vec3<f32>,
    // the tangent plane's point (w = 1) or at infinity (w = 0)
    q: vec4<f32>,
    n: vec3<f32>,
}

// One tangent-plane step of ViewBuffer::locate from texel t.
fn locate_step(view: View, t: u32, p: vec3<f32>, wi: vec3<f32>) -> Located {
    let g = arena[at_view_geometry() + view.geometry + 2u * t];
    let n = arena[at_view_geometry() + view.geometry + 2u * t + 1u].xyz;
    if (g.w > 0.5) {
        let hit = ray_plane(p, wi, g.xyz, n);
        if (hit.w > 0.0) {
            return Located(project(view, hit.xyz), vec4<f32>(hit.xyz, 1.0), n);
        }
    }
    return Located(project_dir(view, wi), vec4<f32>(0.0), vec3<f32>(0.0));
}

// ViewBuffer::locate: the two tangent-plane steps; xy.z = 0 when the sample leaves the buffer.
fn locate(view: View, p: vec3<f32>, wi: vec3<f32>) -> Located {
    let fail = Located(vec3<f32>(0.0), vec4<f32>(0.0), vec3<f32>(0.0));
    if (view.has_front && dot(wi, view.front_normal) <= 0.0) {
        return fail;
    }
    let first = texel_at(view, project(view, p));
    if (first == NONE) {
        return fail;
    }
    let a = locate_step(view, first, p, wi);
    let second = texel_at(view, a.xy);
    if (second == NONE) {
        return fail;
    }
    let b = locate_step(view, second, p, wi);
    if (texel_at(view, b.xy) == NONE) {
        return fail;
    }
    return b;
}

// glam's DVec3::any_orthonormal_pair (Frisvad / Duff et al.).
fn orthonormal_pair(v: vec3<f32>) -> array<vec3<f32>, 2> {
    let sgn = select(-1.0, 1.0, v.z >= 0.0);
    let a = -1.0 / (sgn + v.z);
    let b = v.x * v.y * a;
    return array<vec3<f32>, 2>(vec3<f32>(1.0 + sgn * v.x * v.x * a, sgn * b, -sgn * v.x),
                               vec3<f32>(b, sgn + v.y * v.y * a, -v.y));
}

// ViewBuffer::level: ½ log2 of the footprint's area in texels + bias, clamped.
fn view_level(view: View, p: vec3<f32>, wi: vec3<f32>, found: Located, omega: f32,
              bias: f32) -> f32 {
    let tb = orthonormal_pair(wi);
    let e = sqrt(max(omega, 0.0));
    let wu = wi + tb[0] * e;
    let wv = wi + tb[1] * e;
    var c: vec3<f32>;
    var cu: vec3<f32>;
    var cv: vec3<f32>;
    if (found.q.w > 0.0) {
        c = project(view, found.q.xyz);
        let hu = ray_plane(p, wu, found.q.xyz, found.n);
        let hv = ray_plane(p, wv, found.q.xyz, found.n);
        cu = select(vec3<f32>(0.0), project(view, hu.xyz), hu.w > 0.0);
        cv = select(vec3<f32>(0.0), project(view, hv.xyz), hv.w > 0.0);
    } else {
        c = project_dir(view, wi);
        cu = project_dir(view, wu);
        cv = project_dir(view, wv);
    }
    let top = f32(view.levels - 1u);
    if (c.z == 0.0 || cu.z == 0.0 || cv.z == 0.0) {
        return top;
    }
    let area = abs((cu.x - c.x) * (cv.y - c.y) - (cu.y - c.y) * (cv.x - c.x));
    if (!(area > 0.0 && area <= BIG)) {
        return 0.0;
    }
    return clamp(0.5 * log2(area) + bias, 0.0, top);
}

// ViewBuffer::bilinear on one level.
fn view_bilinear(view: View, level: u32, x: f32, y: f32) -> vec3<f32> {
    var off = view.radiance;
    var lw = view.w;
    var lh = view.h;
    for (var l = 0u; l < level; l++) {
        off += lw * lh;
        lw = (lw + 1u) / 2u;
        lh = (lh + 1u) / 2u;
    }
    let s = f32(1u << level);
    let fx = clamp(x / s - 0.5, 0.0, f32(lw - 1u));
    let fy = clamp(y / s - 0.5, 0.0, f32(lh - 1u));
    let x0 = u32(floor(fx));
    let y0 = u32(floor(fy));
    let x1 = min(x0 + 1u, lw - 1u);
    let y1 = min(y0 + 1u, lh - 1u);
    let tx = fx - f32(x0);
    let ty = fy - f32(y0);
    let a = arena[at_view_radiance() + off + y0 * lw + x0].xyz;
    let b = arena[at_view_radiance() + off + y0 * lw + x1].xyz;
    let c = arena[at_view_radiance() + off + y1 * lw + x0].xyz;
    let e = arena[at_view_radiance() + off + y1 * lw + x1].xyz;
    return (a * (1.0 - tx) + b * tx) * (1.0 - ty) + (c * (1.0 - tx) + e * tx) * ty;
}

// ViewBuffer::sample: trilinear.
fn view_sample(view: View, x: f32, y: f32, lod_in: f32) -> vec3<f32> {
    let top = f32(view.levels - 1u);
    var lod = 0.0;
    if (lod_in == lod_in) {
        lod = clamp(lod_in, 0.0, top);
    }
    let l0f = floor(lod);
    let f = lod - l0f;
    let l0 = u32(l0f);
    let a = view_bilinear(view, l0, x, y);
    if (f == 0.0) {
        return a;
    }
    return a * (1.0 - f) + view_bilinear(view, min(l0 + 1u, view.levels - 1u), x, y) * f;
}

// ---- one shading point.

struct Point {
    p: vec3<f32>,
    n: vec3<f32>,
    wo: vec3<f32>,
    mirror: u32,
    see_through: u32,
    // the cube read (NONE: no probe and no environment) and p relative to its centre
    cube: u32,
    rel: vec3<f32>,
    // the second room probe blended in (NONE: none), p relative to it, and its weight
    cube2: u32,
    rel2: vec3<f32>,
    w2: f32,
}

// frame::slab_offset: the refraction offset of a slab of thickness t and relative index eta.
fn slab_offset(t: f32, eta: f32, n: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let c = abs(dot(wi, n));
    let perp = wi - dot(wi, n) * n;
    let s2 = dot(perp, perp) / (eta * eta);
    if (!(c > 1e-6 && eta > 0.0 && s2 < 1.0)) {
        return vec3<f32>(0.0);
    }
    return perp * (t * (1.0 / (eta * sqrt(1.0 - s2)) - 1.0 / c));
}

// A view buffer's filtered radiance for a sample (w = 0: not answered). pdf < 0: Dirac. A
// see-through buffer of a slab is read from the point its refraction offset moves p to.
fn read_view(v: u32, pt: Point, wi: vec3<f32>, pdf: f32, total: f32, ck: bool) -> vec4<f32> {
    let view = load_view(v);
    var o = pt.p;
    if (view.slab.x > 0.0) {
        o += slab_offset(view.slab.x, view.slab.y, pt.n, wi);
    }
    let loc = locate(view, o, wi);
    if (loc.xy.z == 0.0) {
        return vec4<f32>(0.0);
    }
    var lod = 0.0;
    if (pdf >= 0.0) {
        let bias = select(FOOTPRINT_LEVEL_BIAS, 1.0, ck);
        lod = view_level(view, o, wi, loc, 1.0 / (total * pdf), bias);
    }
    return vec4<f32>(view_sample(view, loc.xy.x, loc.xy.y, lod), 1.0);
}

// frame::view_dependent's fetch. Each view and cube read has one call site (in a loop): a
// compiler that inlines every call (SwiftShader, a browser's software WebGPU) compiled the
// pass's sampling loop for minutes with one site per source.
fn fetch(pt: Point, wi: vec3<f32>, pdf: f32, total: f32, ck: bool) -> vec3<f32> {
    // The mirror buffer, then the see-through buffer (wi leaving through the other side): the
    // first that holds the point.
    for (var k = 0u; k < 2u; k++) {
        var v = pt.mirror;
        if (k == 1u) {
            v = NONE;
            if (pt.see_through != NONE && dot(wi, pt.n) * dot(pt.wo, pt.n) < 0.0) {
                v = pt.see_through;
            }
        }
        if (v != NONE) {
            let c = read_view(v, pt, wi, pdf, total, ck);
            if (c.w > 0.0) {
                return c.xyz;
            }
        }
    }
    // The probe, or two blended by depth.
    var c = vec3<f32>(0.0);
    for (var j = 0u; j < 2u; j++) {
        let cube = select(pt.cube, pt.cube2, j == 1u);
        if (cube == NONE) {
            break;
        }
        let r = read_cube(cube, select(pt.rel, pt.rel2, j == 1u), wi, pdf, total, ck);
        if (j == 0u) {
            c = r;
        } else {
            c = c * (1.0 - pt.w2) + r * pt.w2;
        }
    }
    return c;
}

// One cube's filtered radiance along wi (rel: the point relative to its centre).
fn read_cube(cube: u32, rel: vec3<f32>, wi: vec3<f32>, pdf: f32, total: f32, ck: bool) -> vec3<f32> {
    let face = f32(arena_u[at_cube_levels() + bitcast<u32>(arena[at_cubes() + 2u * cube].w)].y);
    var lod = 0.0;
    if (pdf >= 0.0) {
        if (ck) {
            lod = ck_level_at(pdf, total, face, wi);
        } else {
            lod = footprint_level(1.0 / (total * pdf), wi, face);
        }
    }
    return cube_sample(cube, cube_direction(cube, rel, wi), lod);
}

// SplitMix64 draw → top 24 bits (frame::ck_point).
fn ck_draw(state: ptr<function, vec2<u32>>) -> f32 {
    return f32(splitmix64_next(state).y >> 8u) * (1.0 / 16777216.0);
}

// frame::r2_bits.
fn r2_bits(f: u32) -> vec2<u32> {
    return vec2<u32>((f * 12664746u) & 0xffffffu, (f * 9560334u) & 0xffffffu);
}

// warp::integrate_warp over samples first..min(end, n) of n: (their share of the mean
// radiance, lookups).
fn integrate(b: GpuBsdf, kd: vec3<f32>, t: vec3<f32>, bt: vec3<f32>, pt: Point,
             wo_l: vec3<f32>, n: u32, seed: vec2<u32>, first: u32, end: u32) -> vec4<f32> {
    var sum = vec3<f32>(0.0);
    var lookups = 0u;
    // Dirac lobes only: the branches at both ends of the lobe choice, each once (iterations 0
    // and 1 of the loop below, in the first dispatch only). One loop samples and fetches for
    // both cases: one call site each (see fetch).
    let dirac = (b.flags & FLAG_DELTA_ONLY) != 0u && n >= 2u;
    if (dirac && first > 0u) {
        return vec4<f32>(0.0);
    }
    var seen = vec3<f32>(0.0);
    var have = false;
    // CK's points 0..first took 2·first SplitMix64 draws: the state steps over them at once.
    var state = add64(seed, mul64(vec2<u32>(2u * first, 0u), vec2<u32>(0x7F4A7C15u, 0x9E3779B9u)));
    let f = u.method.y;
    let ck = u.method.x == METHOD_CK && !dirac;
    var total = f32(n);
    var off = vec2<u32>(0u);
    if (u.method.x == METHOD_PROGRESSIVE && !dirac) {
        total = f32(n * (f + 1u));
        off = r2_bits(f);
    }
    var i = first;
    var stop = min(end, n);
    if (dirac) {
        i = 0u;
        stop = 2u;
    }
    for (; i < stop; i++) {
        var uv: vec2<f32>;
        if (dirac) {
            uv = vec2<f32>(select(1e-9, ONE_MINUS_EPS, i == 1u), 0.5);
        } else if (ck) {
            let a = ck_draw(&state);
            uv = vec2<f32>(a, ck_draw(&state));
        } else {
            uv = fibonacci_point(i, n);
            if (u.method.x == METHOD_PROGRESSIVE) {
                let v24 = u32(uv.y * 16777216.0);
                uv = vec2<f32>(fract(uv.x + f32(off.x) * (1.0 / 16777216.0)),
                               f32((v24 + off.y) & 0xffffffu) * (1.0 / 16777216.0));
            }
        }
        let s = bsdf_sample(b, wo_l, uv);
        var weight: vec3<f32>;
        var pdf = s.pdf;
        if (dirac) {
            if (s.pdf == 0.0 || !finite3(s.wi)) {
                continue;
            }
            let dd = s.wi - seen;
            if (have && dot(dd, dd) < 1e-18) {
                continue;
            }
            seen = s.wi;
            have = true;
            weight = s.value * abs(s.wi.z);
            pdf = -1.0;
        } else {
            if (!(s.pdf > 0.0) || !finite3(s.wi)) {
                continue;
            }
            if (s.delta == 1u) {
                weight = s.value * (abs(s.wi.z) / s.pdf);
            } else {
                var fv = s.value;
                if (s.wi.z * wo_l.z > 0.0) {
                    fv = s.value - kd * (1.0 / PI);
                }
                weight = fv * (abs(s.wi.z) / s.pdf);
            }
            if (!finite3(weight) || all(weight == vec3<f32>(0.0))) {
                continue;
            }
            if (s.delta == 1u) {
                pdf = -1.0;
            }
        }
        lookups += 1u;
        let wi = to_world(s.wi, t, bt, pt.n);
        sum += fetch(pt, wi, pdf, total, ck) * weight;
    }
    if (dirac) {
        return vec4<f32>(sum, f32(lookups));
    }
    return vec4<f32>(sum / f32(n), f32(lookups));
}

// lustre_brdf::frame::basis.
fn basis_tangent(n: vec3<f32>) -> vec3<f32> {
    let sgn = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    return vec3<f32>(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
}

// frame::view_dependent at G-buffer pixel (gx, gy) seen along d over this dispatch's samples
// (u.chunk): their share of the mean, before the finiteness check and the clamp to ≥ 0 of the
// whole (the progressive average is clamped, not its frames).
fn shade_point(prim: u32, bary: vec3<f32>, d: vec3<f32>, gx: u32, gy: u32) -> vec3<f32> {
    let base = prim * TRI_STRIDE;
    let r0 = arena[at_tris() + base];
    let r1 = arena[at_tris() + base + 1u];
    let r2 = arena[at_tris() + base + 2u];
    let r3 = arena[at_tris() + base + 3u];
    let r4 = arena[at_tris() + base + 4u];
    let r5 = arena[at_tris() + base + 5u];
    let material = bitcast<u32>(r0.w);
    if (material == NONE) {
        return vec3<f32>(0.0);
    }
    var b = load_bsdf(material);
    if (b.kind == KIND_NONE) {
        return vec3<f32>(0.0);
    }
    let p = r0.xyz * bary.x + r1.xyz * bary.y + r2.xyz * bary.z;
    // PathTracer::normals: the interpolated shading normal, else the face normal.
    let ng = normalize(cross(r1.xyz - r0.xyz, r2.xyz - r0.xyz));
    var ns = ng;
    let ni = r3.xyz * bary.x + r4.xyz * bary.y + r5.xyz * bary.z;
    if (bitcast<u32>(r2.w) == 1u) {
        let l = length(ni);
        if (l > 0.0 && l <= BIG) {
            ns = ni / l;
        }
    }
    // Lightmapped::albedo at the pixel: zero off the light map or on the back of a one-sided
    // material, else diffuse_albedo at (uv0, uv1 / page size).
    let ab = prim * 8u;
    let q3 = arena[at_albedo_tris() + ab + 3u];
    let q4 = arena[at_albedo_tris() + ab + 4u];
    let q5 = arena[at_albedo_tris() + ab + 5u];
    let uv0 = q3.xy * bary.x + q3.zw * bary.y + q4.xy * bary.z;
    let n_lm = arena[at_albedo_tris() + ab].xyz * bary.x + arena[at_albedo_tris() + ab + 1u].xyz * bary.y
        + arena[at_albedo_tris() + ab + 2u].xyz * bary.z;
    let front = dot(n_lm, -d) > 0.0;
    var kd = vec3<f32>(0.0);
    if (bitcast<u32>(arena[at_albedo_tris() + ab + 6u].w) != NO_PAGE
        && (front || arena[at_mats() + 4u * material + 1u].z > 0.5)) {
        let uv1 = (q4.zw * bary.x + q5.xy * bary.y + q5.zw * bary.z)
            / vec2<f32>(f32(u.method.w), f32(u.seed.w));
        kd = albedo(material, uv0, uv1);
    }
    // A Lambertian surface the light map covers has no view-dependent part left.
    if ((b.flags & FLAG_DIFFUSE_ONLY) != 0u && any(kd != vec3<f32>(0.0))) {
        return vec3<f32>(0.0);
    }
    // The textured parameters at uv0 (the CPU's view-dependent shading reads both uv sets at
    // uv0: Material::with_bsdf_at with [uv0; 2]).
    let q = 5u * material;
    if ((b.flags & FLAG_TEXTURED) != 0u) {
        let c = arena[at_params() + q];
        var rgb = c.xyz;
        let ct = bitcast<i32>(c.w);
        if (ct >= 0) {
            rgb = c.xyz * texture_sample(u32(ct), uv0).xyz;
        }
        let s = vec3<f32>(scalar_at(arena[at_params() + q + 1u], uv0, uv0), scalar_at(arena[at_params() + q + 2u], uv0, uv0),
                          scalar_at(arena[at_params() + q + 3u], uv0, uv0));
        b = textured_bsdf(b, rgb, s);
    }
    // ShadingFrame::new(ns, ∂p/∂u), or with the normal map (PathTracer::shading_point): the
    // mapped normal, its tangent from the mesh's tangents, else ∂p/∂u with glTF's handedness.
    let r6 = arena[at_tris() + base + 6u];
    let dpdu = r6.xyz;
    var n = ns;
    var t_hint = dpdu;
    if ((b.flags & FLAG_NORMAL_MAPPED) != 0u) {
        let nm = arena[at_params() + q + 4u];
        let n_ts = tangent_space_normal(texture_sample(bitcast<u32>(nm.y), uv0), nm.x);
        let tb = bitcast<u32>(r6.w);
        let t0 = arena[at_tangents() + tb];
        var tg = dpdu;
        var hand = 1.0;
        if (t0.w != 0.0) {
            tg = t0.xyz * bary.x + arena[at_tangents() + tb + 1u].xyz * bary.y + arena[at_tangents() + tb + 2u].xyz * bary.z;
            hand = t0.w;
        } else if (dot(cross(ns, dpdu), arena[at_tangents() + tb + 3u].xyz) > 0.0) {
            hand = -1.0;
        }
        let m = mapped_normal(ns, tg, hand, n_ts);
        n = m[0];
        t_hint = m[1];
    }
    let tp = t_hint - n * dot(n, t_hint);
    var t: vec3<f32>;
    if (length(tp) > 1e-9 * length(t_hint)) {
        t = normalize(tp);
    } else {
        t = basis_tangent(n);
    }
    var bt = cross(n, t);
    let wo = -d;
    if ((b.flags & FLAG_TWO_SIDED) != 0u && dot(wo, n) < 0.0) {
        n = -n;
        bt = -bt;
    }
    let wo_l = vec3<f32>(dot(wo, t), dot(wo, bt), dot(wo, n));
    // The incident light: the object's probe, else the room probes whose planes enclose the
    // point (the two deepest blended by depth), else an object probe whose planes do, else any;
    // the nearest of the first group that has one (probe::choose_probe); else the environment.
    var cube = bitcast<u32>(r3.w);
    var cube2 = NONE;
    var w2 = 0.0;
    if (cube == NONE) {
        var best = BIG;
        var best_rank = 3u;
        // The two room boxes holding p deepest: depth, squared distance, index.
        var r0 = vec3<f32>(-1.0, 0.0, 0.0);
        var r1 = vec3<f32>(-1.0, 0.0, 0.0);
        var i0 = NONE;
        var i1 = NONE;
        for (var c = 0u; c < u.method.z; c++) {
            let dc = arena[at_cubes() + 2u * c].xyz - p;
            let d2 = dot(dc, dc);
            var rank = 2u;
            if (!cube_outside(c, -dc)) {
                rank = select(1u, 0u, bitcast<u32>(arena[at_cubes() + 2u * c + 1u].w) != 0u);
            }
            if (rank < best_rank || (rank == best_rank && d2 < best)) {
                best = d2;
                best_rank = rank;
                cube = c;
            }
            if (rank == 0u) {
                let depth = max(cube_depth(c, -dc), 0.0);
                if (i0 == NONE || depth > r0.x || (depth == r0.x && d2 < r0.y)) {
                    r1 = r0;
                    i1 = i0;
                    r0 = vec3<f32>(depth, d2, 0.0);
                    i0 = c;
                } else if (i1 == NONE || depth > r1.x || (depth == r1.x && d2 < r1.y)) {
                    r1 = vec3<f32>(depth, d2, 0.0);
                    i1 = c;
                }
            }
        }
        if (i0 != NONE) {
            cube = i0;
            if (i1 != NONE && r0.x + r1.x > 0.0) {
                cube2 = i1;
                w2 = r1.x / (r0.x + r1.x);
            }
        }
    }
    if (cube == NONE) {
        cube = u.seed.z;
    }
    var rel = vec3<f32>(0.0);
    if (cube != NONE && cube < u.method.z) {
        rel = p - arena[at_cubes() + 2u * cube].xyz;
    }
    var rel2 = vec3<f32>(0.0);
    if (cube2 != NONE) {
        rel2 = p - arena[at_cubes() + 2u * cube2].xyz;
    }
    let see_through = select(bitcast<u32>(r5.w), NONE, u.flags.x != 0u);
    let mirror = select(bitcast<u32>(r4.w), NONE, u.flags.y != 0u);
    let pt = Point(p, n, wo, mirror, see_through, cube, rel, cube2, rel2, w2);
    if (pt.cube == NONE && pt.mirror == NONE && pt.see_through == NONE) {
        return vec3<f32>(0.0);
    }
    let seed = pixel_seed(gx, gy, u.seed.xy);
    // The object's own sample budget (r1.w, 0: the frame's; frame::object_samples).
    let own = bitcast<u32>(r1.w);
    let r = integrate(b, kd, t, bt, pt, wo_l, select(u.sizes.w, own, own > 0u), seed,
                      u.chunk.x, u.chunk.y);
    if (u.chunk.x == 0u) {
        atomicAdd(&wg_counts[0], 1u);
    }
    atomicAdd(&wg_counts[1], u32(r.w));
    return r.xyz;
}

// Whether output pixel (x, y) has a view-dependent part (every pixel unless u.tiles.z = 1).
fn covered(x: u32, y: u32) -> bool {
    if (u.tiles.z == 0u) {
        return true;
    }
    let c = x / SCREEN_TILE;
    let r = y / SCREEN_TILE;
    return c < u.tiles.x && r < u.tiles.y && tile_mask[r * u.tiles.x + c] != 0u;
}

// G-buffer pixel (gx, gy): this dispatch's samples, added to `partial`.
fn shade_samples(gx: u32, gy: u32) {
    let k = u.sizes.z;
    if (!covered(gx / k, gy / k)) {
        return;
    }
    let gi = gy * u.sizes.x + gx;
    var c = vec3<f32>(0.0);
    let prim = textureLoad(prim_tex, vec2<i32>(i32(gx), i32(gy)), 0).x;
    if (prim != SKY) {
        // PathCamera::direction(gx + ½, gy + ½, gw, gh).
        let a = u.cam.x;
        let px = (2.0 * (f32(gx) + 0.5) / f32(u.sizes.x) - 1.0) * a * u.cam.y;
        let py = (1.0 - 2.0 * (f32(gy) + 0.5) / f32(u.sizes.y)) * a;
        let d = normalize(u.forward.xyz + px * u.right.xyz + py * u.up.xyz);
        let bd = textureLoad(bary_tex, vec2<i32>(i32(gx), i32(gy)), 0);
        c = shade_point(prim, vec3<f32>(1.0 - bd.x - bd.y, bd.x, bd.y), d, gx, gy);
    }
    if (u.chunk.x == 0u) {
        partial[gi] = vec4<f32>(c, 1.0);
    } else {
        partial[gi] = vec4<f32>(partial[gi].xyz + c, 1.0);
    }
}

// Output pixel (x, y): its k×k G-buffer pixels' view-dependent radiance (`partial`, summed
// by every dispatch of samples_main) and its light-mapped shading.
fn shade_pixel(x: u32, y: u32, w: u32, k: u32) {
    let i = y * w + x;
    if (!covered(x, y)) {
        out_px[i] = vec4<f32>(lightmapped[i].xyz, 1.0);
        return;
    }
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < k; j++) {
        for (var s = 0u; s < k; s++) {
            let gx = x * k + s;
            let gy = y * k + j;
            let gi = gy * u.sizes.x + gx;
            let prim = textureLoad(prim_tex, vec2<i32>(i32(gx), i32(gy)), 0).x;
            if (prim == SKY) {
                if (u.method.x == METHOD_PROGRESSIVE) {
                    accum[gi] = vec4<f32>(0.0);
                }
                continue;
            }
            var c = partial[gi].xyz;
            if (!finite3(c)) {
                c = vec3<f32>(0.0);
            }
            if (u.method.x == METHOD_PROGRESSIVE) {
                // Frame f joins the running mean of frames 0..f of this G-buffer pixel.
                let f = f32(u.method.y);
                if (u.method.y > 0u) {
                    c = (accum[gi].xyz * f + c) / (f + 1.0);
                }
                accum[gi] = vec4<f32>(c, 1.0);
            }
            sum += max(c, vec3<f32>(0.0));
        }
    }
    out_px[i] = vec4<f32>(lightmapped[i].xyz + sum / f32(k * k), 1.0);
}

// One thread per G-buffer pixel: samples u.chunk.x..u.chunk.y of its view-dependent part.
@compute @workgroup_size(8, 8, 1)
fn samples_main(@builtin(global_invocation_id) gid: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    if (gid.x < u.sizes.x && gid.y < u.sizes.y) {
        shade_samples(gid.x, gid.y);
    }
    workgroupBarrier();
    if (li == 0u) {
        atomicAdd(&counts[0], atomicLoad(&wg_counts[0]));
        atomicAdd(&counts[1], atomicLoad(&wg_counts[1]));
    }
}

// One thread per output pixel, after every samples_main dispatch.
@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = u.sizes.z;
    let w = u.sizes.x / k;
    let h = u.sizes.y / k;
    if (gid.x < w && gid.y < h) {
        shade_pixel(gid.x, gid.y, w, k);
    }
}
