// module measured: measured BRDFs on the GPU (004 §IV.4.3): MERL tables evaluated from the half/difference
// angles (lustre_brdf::measured::merl), neural BRDFs (lustre_brdf::measured::nbrdf), RGL
// tensors (lustre_brdf::measured::rgl, their Marginal2D tables: measured::pack_rgl), ALTA
// goniometric tables (lustre_brdf::measured::alta: measured::pack_alta), and
// importance sampling by numerical inversion of
// tabulated CDFs (lustre_brdf::tabulated). Both read the pass's side table through
// `bsdf_table(i)`: the words of measured::pack_merl (3 × 90·90·180 stored values, channel-major,
// a missing bin as −1), measured::pack_nbrdf (the network's 675 weights) and measured::pack_tabulated (per view bin, the cumulative cell weights
// over their total, then each cell's weight over the total, so that a cell's density does not
// come from the difference of two f32 sums).
// Requires (the pass defines): fn bsdf_table(i: u32) -> f32.

const MERL_RES_TH: u32 = 90u;
const MERL_RES_TD: u32 = 90u;
const MERL_RES_PD: u32 = 180u;
const MERL_BINS: u32 = 1458000u;
const MERL_SCALE: vec3<f32> = vec3<f32>(1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0);

// merl::merl_angles: (θh, θd, φd folded into [0, π), 1), or w = 0 when either direction is at or
// below the surface or they are opposite. θ from atan2 (acos loses the small angles in f32).
fn merl_angles(wi: vec3<f32>, wo: vec3<f32>) -> vec4<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec4<f32>(0.0);
    }
    let s = wi + wo;
    let l2 = dot(s, s);
    if (!(l2 > 1e-24)) {
        return vec4<f32>(0.0);
    }
    let h = s / sqrt(l2);
    let theta_h = atan2(length(h.xy), h.z);
    let phi_h = atan2(h.y, h.x);
    // frame::to_half_diff: wi turned by −φh about z, then by −θh about y.
    let cz = cos(phi_h);
    let sz = sin(phi_h);
    let a = vec3<f32>(cz * wi.x + sz * wi.y, -sz * wi.x + cz * wi.y, wi.z);
    let cy = cos(theta_h);
    let sy = sin(theta_h);
    let d = vec3<f32>(cy * a.x - sy * a.z, a.y, sy * a.x + cy * a.z);
    let theta_d = atan2(length(d.xy), d.z);
    var phi_d = atan2(d.y, d.x);
    // merl::fold_phi_d.
    phi_d = phi_d - PI * floor(phi_d / PI);
    if (phi_d >= PI) {
        phi_d = 0.0;
    }
    return vec4<f32>(theta_h, theta_d, phi_d, 1.0);
}

// merl::clamped_axis: the two nodes around index coordinate x and the second's weight
// (x, y: indices as f32; z: weight).
fn merl_clamped_axis(x: f32, n: u32) -> vec3<f32> {
    if (!(x > 0.0)) {
        return vec3<f32>(0.0);
    }
    let last = f32(n - 1u);
    if (x >= last) {
        return vec3<f32>(last, last, 0.0);
    }
    let i0 = floor(x);
    return vec3<f32>(i0, i0 + 1.0, x - i0);
}

// MerlTable::lookup_trilinear on the table at word `base`: trilinear between the nodes at
// `offset` (0: the lower edge, ½: the centre) in index space, θ ends clamped, φd periodic; a
// missing (negative) corner is left out and the present weights renormalized; 0 without any.
fn merl_lookup(base: u32, theta_h: f32, theta_d: f32, phi_d: f32, offset: f32) -> vec3<f32> {
    var uh = 0.0;
    if (theta_h > 0.0) {
        uh = sqrt(theta_h / (0.5 * PI)) * f32(MERL_RES_TH);
    }
    let h = merl_clamped_axis(uh - offset, MERL_RES_TH);
    let d = merl_clamped_axis(theta_d / (0.5 * PI) * f32(MERL_RES_TD) - offset, MERL_RES_TD);
    let p = phi_d - PI * floor(phi_d / PI);
    let x = p / PI * f32(MERL_RES_PD) - offset;
    var p0 = 0u;
    var tp = 0.0;
    if (abs(x) <= 3.4e38) {
        let f = floor(x);
        tp = clamp(x - f, 0.0, 1.0);
        let n = i32(MERL_RES_PD);
        p0 = u32(((i32(f) % n) + n) % n);
    }
    let p1 = (p0 + 1u) % MERL_RES_PD;
    var sum = vec3<f32>(0.0);
    var wsum = vec3<f32>(0.0);
    for (var c = 0u; c < 8u; c++) {
        var i = u32(h.x);
        var wi = 1.0 - h.z;
        if ((c & 4u) != 0u) {
            i = u32(h.y);
            wi = h.z;
        }
        var j = u32(d.x);
        var wj = 1.0 - d.z;
        if ((c & 2u) != 0u) {
            j = u32(d.y);
            wj = d.z;
        }
        var k = p0;
        var wk = 1.0 - tp;
        if ((c & 1u) != 0u) {
            k = p1;
            wk = tp;
        }
        let w = wi * wj * wk;
        let off = k + MERL_RES_PD * (j + MERL_RES_TD * i);
        for (var ch = 0u; ch < 3u; ch++) {
            let v = bsdf_table(base + ch * MERL_BINS + off);
            if (v >= 0.0) {
                sum[ch] += w * v;
                wsum[ch] += w;
            }
        }
    }
    var out = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch++) {
        if (wsum[ch] > 0.0) {
            out[ch] = sum[ch] / wsum[ch] * MERL_SCALE[ch];
        }
    }
    return out;
}

// MerlTable::eval (trilinear): f(wi, wo) in 1/sr, 0 unless both lie above the surface.
fn merl_eval(base: u32, offset: f32, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let a = merl_angles(wi, wo);
    if (a.w == 0.0) {
        return vec3<f32>(0.0);
    }
    return merl_lookup(base, a.x, a.y, a.z, offset);
}

// nbrdf::Nbrdf's hidden width.
const NBRDF_HIDDEN: u32 = 21u;

// Nbrdf::eval: the 6-21-21-3 network (ReLU, ReLU, e^z − 1 clamped at 0) on
// (sin θh, 0, cos θh, sin θd cos φd, sin θd sin φd, cos θd) at the pair's MERL angles, with the
// weights at word `base` (measured::pack_nbrdf: w1, b1, w2, b2, w3, b3); 0 unless both lie
// above the surface.
fn nbrdf_eval(base: u32, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    let a = merl_angles(wi, wo);
    if (a.w == 0.0) {
        return vec3<f32>(0.0);
    }
    let x = array<f32, 6>(sin(a.x), 0.0, cos(a.x), sin(a.y) * cos(a.z), sin(a.y) * sin(a.z),
                          cos(a.y));
    let b1 = base + 6u * NBRDF_HIDDEN;
    let w2 = b1 + NBRDF_HIDDEN;
    let b2 = w2 + NBRDF_HIDDEN * NBRDF_HIDDEN;
    let w3 = b2 + NBRDF_HIDDEN;
    let b3 = w3 + 3u * NBRDF_HIDDEN;
    var h1: array<f32, 21>;
    for (var j = 0u; j < NBRDF_HIDDEN; j++) {
        var s = bsdf_table(b1 + j);
        for (var i = 0u; i < 6u; i++) {
            s += x[i] * bsdf_table(base + i * NBRDF_HIDDEN + j);
        }
        h1[j] = max(s, 0.0);
    }
    var h2: array<f32, 21>;
    for (var j = 0u; j < NBRDF_HIDDEN; j++) {
        var s = bsdf_table(b2 + j);
        for (var i = 0u; i < NBRDF_HIDDEN; i++) {
            s += h1[i] * bsdf_table(w2 + i * NBRDF_HIDDEN + j);
        }
        h2[j] = max(s, 0.0);
    }
    var out = vec3<f32>(0.0);
    for (var c = 0u; c < 3u; c++) {
        var z = bsdf_table(b3 + c);
        for (var i = 0u; i < NBRDF_HIDDEN; i++) {
            z += h2[i] * bsdf_table(w3 + i * 3u + c);
        }
        out[c] = max(exp(min(z, 80.0)) - 1.0, 0.0);
    }
    return out;
}

// The layout of a tabulated sampler (measured::GpuTabulatedDims): view elevation bins, view
// azimuth bins (0: an isotropic BRDF's tables, one per elevation, φ folded onto [0, π]; else
// unfolded over [0, 2π)), θi cells, φ cells per table; ε.
struct TabulatedDims {
    view_bins: u32,
    azimuth_bins: u32,
    theta_bins: u32,
    phi_cells: u32,
    defensive: f32,
}

// The width of a φ cell (radians).
fn tabulated_dphi(dims: TabulatedDims) -> f32 {
    if (dims.azimuth_bins == 0u) {
        return PI / f32(dims.phi_cells);
    }
    return 2.0 * PI / f32(dims.phi_cells);
}

// tabulated::theta_cos_range: (cos θa, cos θb) of θ cell i of n.
fn tabulated_cos_range(i: u32, n: u32) -> vec2<f32> {
    let a = f32(i) / f32(n) * 0.5 * PI;
    var cb = 0.0;
    if (i + 1u < n) {
        cb = cos(f32(i + 1u) / f32(n) * 0.5 * PI);
    }
    return vec2<f32>(cos(a), cb);
}

// TabulatedSampler::tables: the first words of the two tables serving wo and the first's
// weight (the second's is 1 − w0): θo's nearest bin and, when anisotropic, the two azimuth bins
// around φo, weighted linearly; an isotropic BRDF's one table twice, w0 = 1. wo.z > 0.
struct TabulatedView {
    t0: u32,
    t1: u32,
    w0: f32,
}

fn tabulated_view(base: u32, dims: TabulatedDims, wo: vec3<f32>) -> TabulatedView {
    let theta_o = atan2(length(wo.xy), wo.z);
    let k = min(u32(theta_o / (0.5 * PI) * f32(dims.view_bins)), dims.view_bins - 1u);
    let size = 2u * dims.theta_bins * dims.phi_cells + 1u;
    if (dims.azimuth_bins == 0u) {
        let t = base + k * size;
        return TabulatedView(t, t, 1.0);
    }
    let az = dims.azimuth_bins;
    var phi_o = atan2(wo.y, wo.x);
    if (phi_o < 0.0) {
        phi_o += 2.0 * PI;
    }
    let x = phi_o / (2.0 * PI) * f32(az) - 0.5;
    let lo = floor(x);
    let w = clamp(x - lo, 0.0, 1.0);
    let a0 = u32((i32(lo) + i32(az)) % i32(az));
    let a1 = (a0 + 1u) % az;
    return TabulatedView(base + (k * az + a0) * size, base + (k * az + a1) * size, 1.0 - w);
}

// The density of table t (first word) at wi: ε cos θi / π + (1 − ε) w_c / (W · Ω_c) (the
// table holds w_c / W; Ω_c doubled when folded), cos θi / π for a black table.
fn tabulated_table_pdf(t: u32, dims: TabulatedDims, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    let cells = dims.theta_bins * dims.phi_cells;
    let total = bsdf_table(t + cells);
    let cosine = wi.z / PI;
    if (!(total > 0.0)) {
        return cosine;
    }
    var phi = atan2(wi.y, wi.x) - atan2(wo.y, wo.x);
    if (phi < 0.0) {
        phi += 2.0 * PI;
    }
    var fold = 1.0;
    if (dims.azimuth_bins == 0u) {
        fold = 2.0;
        if (phi > PI) {
            phi = 2.0 * PI - phi;
        }
    }
    let dphi = tabulated_dphi(dims);
    let theta = atan2(length(wi.xy), wi.z);
    let i = min(u32(theta / (0.5 * PI) * f32(dims.theta_bins)), dims.theta_bins - 1u);
    let j = min(u32(phi / dphi), dims.phi_cells - 1u);
    let c = i * dims.phi_cells + j;
    let w = bsdf_table(t + cells + 1u + c);
    let cr = tabulated_cos_range(i, dims.theta_bins);
    let omega = fold * (cr.x - cr.y) * dphi;
    let eps = dims.defensive;
    return eps * cosine + (1.0 - eps) * w / omega;
}

// TabulatedSampler::sample: (wi, its density), or w = 0 when wo lies at or below the horizon.
// The drawn table's density is the drawn cell's, not looked up again from wi: in f32 a draw at
// a cell's edge may round into its neighbour, whose weight can be far smaller.
fn tabulated_sample(base: u32, dims: TabulatedDims, wo: vec3<f32>, u1: f32,
                    u2_in: f32) -> vec4<f32> {
    if (!(wo.z > 0.0)) {
        return vec4<f32>(0.0);
    }
    let view = tabulated_view(base, dims, wo);
    // The table by u2 (rescaled), with the probabilities of the weights; u2 then only places
    // the point inside its cell's φ range (unfolded tables).
    var t = view.t0;
    var other = view.t1;
    var w_t = view.w0;
    var u2 = u2_in / view.w0;
    if (!(u2_in < view.w0 || view.w0 >= 1.0)) {
        t = view.t1;
        other = view.t0;
        w_t = 1.0 - view.w0;
        u2 = (u2_in - view.w0) / w_t;
    }
    u2 = clamp(u2, 0.0, 0.99999994);
    let cells = dims.theta_bins * dims.phi_cells;
    let total = bsdf_table(t + cells);
    let eps = dims.defensive;
    var wi = vec3<f32>(0.0);
    var p_t = 0.0;
    if (u1 < eps || !(total > 0.0)) {
        var u = u1;
        if (total > 0.0) {
            u = u1 / eps;
        }
        wi = cosine_hemisphere(min(u, 0.99999994), u2);
        p_t = tabulated_table_pdf(t, dims, wi, wo);
    } else {
        let goal = (u1 - eps) / (1.0 - eps);
        // The first cell whose cumulative weight exceeds the goal.
        var lo = 0u;
        var hi = cells;
        while (lo < hi) {
            let mid = (lo + hi) / 2u;
            if (bsdf_table(t + mid + 1u) <= goal) {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        let c = min(lo, cells - 1u);
        let a = bsdf_table(t + c);
        let b = bsdf_table(t + c + 1u);
        var r = 0.5;
        if (b > a) {
            r = clamp((goal - a) / (b - a), 0.0, 0.99999994);
        }
        let i = c / dims.phi_cells;
        let j = c % dims.phi_cells;
        let cr = tabulated_cos_range(i, dims.theta_bins);
        let cos_i = cr.x + (cr.y - cr.x) * r;
        var sign = 1.0;
        var v = u2;
        var fold = 1.0;
        if (dims.azimuth_bins == 0u) {
            // Folded: either side of the view's plane.
            fold = 2.0;
            v = 2.0 * u2;
            if (u2 >= 0.5) {
                sign = -1.0;
                v = 2.0 * u2 - 1.0;
            }
        }
        let dphi = tabulated_dphi(dims);
        let phi = sign * (f32(j) + v) * dphi + atan2(wo.y, wo.x);
        let sin_i = sqrt(max(1.0 - cos_i * cos_i, 0.0));
        wi = vec3<f32>(sin_i * cos(phi), sin_i * sin(phi), cos_i);
        p_t = eps * cos_i / PI + (1.0 - eps) * bsdf_table(t + cells + 1u + c)
            / (fold * (cr.x - cr.y) * dphi);
    }
    var pdf = w_t * p_t;
    if (w_t < 1.0) {
        pdf += (1.0 - w_t) * tabulated_table_pdf(other, dims, wi, wo);
    }
    return vec4<f32>(wi, pdf);
}

// TabulatedSampler::pdf: the weighted sum of the serving tables' densities.
fn tabulated_pdf(base: u32, dims: TabulatedDims, wi: vec3<f32>, wo: vec3<f32>) -> f32 {
    if (!(wo.z > 0.0 && wi.z > 0.0)) {
        return 0.0;
    }
    let view = tabulated_view(base, dims, wo);
    var pdf = view.w0 * tabulated_table_pdf(view.t0, dims, wi, wo);
    if (view.w0 < 1.0) {
        pdf += (1.0 - view.w0) * tabulated_table_pdf(view.t1, dims, wi, wo);
    }
    return pdf;
}

// The measured BRDF of a material record (lustre-gpu's measured::MeasuredBrdf::pack): EVAL_NBRDF
// a neural BRDF, EVAL_MERL a MERL table read at node offset `offset`, EVAL_RGL an RGL tensor,
// EVAL_ALTA an ALTA table;
// f(wi, wo) in 1/sr.
fn measured_eval(kind: u32, base: u32, offset: f32, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (kind == EVAL_MERL) {
        return merl_eval(base, offset, wi, wo);
    }
    if (kind == EVAL_RGL) {
        return rgl_eval(base, wi, wo);
    }
    if (kind == EVAL_ALTA) {
        return alta_eval(base, wi, wo);
    }
    return nbrdf_eval(base, wi, wo);
}

// An ALTA table (lustre_brdf::measured::alta::AltaTable; measured::pack_alta's words at `base`:
// slice count, cosine-weighted flag, grid cells per axis, cell size, half extent, cos θv floor,
// two pads, then per slice (θl, its nodes' and candidates' first words from `base`, a pad), then
// each slice's nodes (first, count; count −1: split into 4 × 4 children from `first`) and its
// candidates (x, y, value)). Isotropic, reflection only: θl = θ(wi), (x, y) = θv (cos Δφ,
// sin Δφ) with θv = θ(wo) and Δφ = φo − φi.
const ALTA_NEIGHBOURS: u32 = 6u;
// lustre_brdf::measured::alta::ALTA_MAX_DEPTH: a cell is split at most 3 times.
const ALTA_MAX_DEPTH: u32 = 3u;

// θ of a direction by atan2 (acos loses the small angles in f32).
fn alta_theta(w: vec3<f32>) -> f32 {
    return atan2(length(w.xy), w.z);
}

// Slice s's value at (x, y): Shepard's inverse-distance weighting (power 2) of its
// ALTA_NEIGHBOURS nearest samples, which are among the candidates of the leaf holding (x, y)
// (AltaCandidates::leaf), kept sorted as the CPU's ring search keeps them (a sample enters after
// those at the same distance; an exact hit returns its value).
fn alta_slice_value(base: u32, s: u32, x: f32, y: f32) -> f32 {
    let n = u32(bsdf_table(base + 2u));
    let cell = bsdf_table(base + 3u);
    let half = bsdf_table(base + 4u);
    let h = base + 8u + 4u * s;
    let nodes = base + u32(bsdf_table(h + 1u));
    let pts = base + u32(bsdf_table(h + 2u));
    let last = i32(n) - 1;
    let cx = u32(clamp(i32(floor((x + half) / cell)), 0, last));
    let cy = u32(clamp(i32(floor((y + half) / cell)), 0, last));
    var node = cy * n + cx;
    var x0 = -half + f32(cx) * cell;
    var y0 = -half + f32(cy) * cell;
    var size = cell;
    var first = bsdf_table(nodes + 2u * node);
    var count = bsdf_table(nodes + 2u * node + 1u);
    for (var depth = 0u; depth < ALTA_MAX_DEPTH && count < 0.0; depth++) {
        size *= 0.25;
        let sx = u32(clamp(i32(floor((x - x0) / size)), 0, 3));
        let sy = u32(clamp(i32(floor((y - y0) / size)), 0, 3));
        x0 += f32(sx) * size;
        y0 += f32(sy) * size;
        node = u32(first) + 4u * sy + sx;
        first = bsdf_table(nodes + 2u * node);
        count = bsdf_table(nodes + 2u * node + 1u);
    }
    if (count < 0.0) {
        return 0.0;
    }
    let start = u32(first);
    let end = start + u32(count);
    var d = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    var v = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    var kept = 0u;
    for (var i = start; i < end; i++) {
        let p = pts + 3u * i;
        let dx = bsdf_table(p) - x;
        let dy = bsdf_table(p + 1u) - y;
        let d2 = dx * dx + dy * dy;
        if (kept == ALTA_NEIGHBOURS && d2 >= d[ALTA_NEIGHBOURS - 1u]) {
            continue;
        }
        var j = min(kept, ALTA_NEIGHBOURS - 1u);
        loop {
            if (j == 0u || d[j - 1u] <= d2) {
                break;
            }
            d[j] = d[j - 1u];
            v[j] = v[j - 1u];
            j -= 1u;
        }
        d[j] = d2;
        v[j] = bsdf_table(p + 2u);
        kept = min(kept + 1u, ALTA_NEIGHBOURS);
    }
    if (kept == 0u) {
        return 0.0;
    }
    if (d[0] < 1e-24) {
        return v[0];
    }
    var num = 0.0;
    var den = 0.0;
    for (var k = 0u; k < kept; k++) {
        num += v[k] / d[k];
        den += 1.0 / d[k];
    }
    return num / den;
}

// AltaTable::brdf: the value linear in θl between the slices around it (clamped to the first
// and last), divided by max(cos θv, the floor) for cosine-weighted data; zero below the surface.
fn alta_eval(base: u32, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let tl = alta_theta(wi);
    let tv = alta_theta(wo);
    let dphi = atan2(wo.y, wo.x) - atan2(wi.y, wi.x);
    let x = tv * cos(dphi);
    let y = tv * sin(dphi);
    let count = u32(bsdf_table(base));
    // k: the slices with θ ≤ θl.
    var k = 0u;
    loop {
        if (k == count || bsdf_table(base + 8u + 4u * k) > tl) {
            break;
        }
        k += 1u;
    }
    var lo = 0u;
    var t = 0.0;
    if (k == count) {
        lo = count - 1u;
    } else if (k > 0u) {
        lo = k - 1u;
        let a = bsdf_table(base + 8u + 4u * lo);
        t = (tl - a) / (bsdf_table(base + 8u + 4u * k) - a);
    }
    let hi = select(lo, lo + 1u, t > 0.0);
    // One call site for both slices (llvmpipe inlines each).
    var value = 0.0;
    for (var s = lo; s <= hi; s++) {
        let w = select(1.0 - t, t, s > lo);
        value += w * alta_slice_value(base, s, x, y);
    }
    if (bsdf_table(base + 1u) != 0.0) {
        value /= max(wo.z, bsdf_table(base + 5u));
    }
    return vec3<f32>(value);
}

// An RGL table (lustre_brdf::measured::rgl_warp::Marginal2D, measured::pack_rgl's block at word
// b): resolution, conditioning parameters (node counts, slice strides, first words of their
// nodes), and the first words of the values and of the marginal and conditional CDFs.
struct M2d {
    w: u32,
    h: u32,
    np: u32,
    normalized: bool,
    size: vec3<u32>,
    stride: vec3<u32>,
    nodes: vec3<u32>,
    data: u32,
    marg: u32,
    cond: u32,
}

fn m2d_word(i: u32) -> u32 {
    return u32(bsdf_table(i));
}

fn m2d_load(b: u32) -> M2d {
    var m: M2d;
    m.w = m2d_word(b);
    m.h = m2d_word(b + 1u);
    m.np = m2d_word(b + 2u);
    m.normalized = m2d_word(b + 3u) != 0u;
    for (var k = 0u; k < 3u; k++) {
        m.size[k] = m2d_word(b + 4u + k);
        m.stride[k] = m2d_word(b + 8u + k);
        m.nodes[k] = b + m2d_word(b + 12u + k);
    }
    m.data = b + m2d_word(b + 16u);
    m.marg = b + m2d_word(b + 17u);
    m.cond = b + m2d_word(b + 18u);
    return m;
}

// Marginal2D::corners: the up to 8 slices a parameter vector blends, with their weights.
struct M2dCorners {
    n: u32,
    slice: array<u32, 8>,
    weight: array<f32, 8>,
}

fn m2d_corners(m: M2d, param: vec3<f32>) -> M2dCorners {
    var c: M2dCorners;
    c.n = 1u;
    c.weight[0] = 1.0;
    for (var k = 0u; k < m.np; k++) {
        let n = m.size[k];
        if (n == 1u) {
            continue;
        }
        let x = param[k];
        // find_interval: the last i in [0, n − 2] with nodes[i] < x.
        var lo = 0u;
        var hi = n;
        while (lo < hi) {
            let mid = (lo + hi) / 2u;
            if (bsdf_table(m.nodes[k] + mid) < x) {
                lo = mid + 1u;
            } else {
                hi = mid;
            }
        }
        let i = min(max(lo, 1u) - 1u, n - 2u);
        let p0 = bsdf_table(m.nodes[k] + i);
        let p1 = bsdf_table(m.nodes[k] + i + 1u);
        var t = (x - p0) / (p1 - p0);
        if (!(t > 0.0)) {
            t = 0.0;
        }
        t = min(t, 1.0);
        let cn = c.n;
        for (var j = 0u; j < cn; j++) {
            let s = c.slice[j];
            let wg = c.weight[j];
            c.slice[j] = s + m.stride[k] * i;
            c.weight[j] = wg * (1.0 - t);
            c.slice[cn + j] = s + m.stride[k] * (i + 1u);
            c.weight[cn + j] = wg * t;
        }
        c.n = 2u * cn;
    }
    return c;
}

// Marginal2D::lookup: entry idx of the table at word `table` (per_slice entries a slice),
// blended over the corners.
fn m2d_lookup(table: u32, per_slice: u32, corners: M2dCorners, idx: u32) -> f32 {
    var c = corners;
    var v = 0.0;
    for (var j = 0u; j < c.n; j++) {
        if (c.weight[j] != 0.0) {
            v += c.weight[j] * bsdf_table(table + c.slice[j] * per_slice + idx);
        }
    }
    return v;
}

// Marginal2D::locate: (ix, iy) as f32 in xy, (fx, fy) in zw.
fn m2d_locate(m: M2d, pos: vec2<f32>) -> vec4<f32> {
    let sx = clamp(pos.x, 0.0, 1.0) * f32(m.w - 1u);
    let sy = clamp(pos.y, 0.0, 1.0) * f32(m.h - 1u);
    let ix = min(u32(max(sx, 0.0)), m.w - 2u);
    let iy = min(u32(max(sy, 0.0)), m.h - 2u);
    return vec4<f32>(f32(ix), f32(iy), sx - f32(ix), sy - f32(iy));
}

// Marginal2D::patch: the corner values (v00, v10, v01, v11) of patch (ix, iy).
fn m2d_patch(m: M2d, c: M2dCorners, ix: u32, iy: u32) -> vec4<f32> {
    let n = m.w * m.h;
    let o = iy * m.w + ix;
    return vec4<f32>(m2d_lookup(m.data, n, c, o), m2d_lookup(m.data, n, c, o + 1u),
                     m2d_lookup(m.data, n, c, o + m.w), m2d_lookup(m.data, n, c, o + m.w + 1u));
}

// Marginal2D::eval: the bilinear interpolant at pos.
fn m2d_eval(m: M2d, pos: vec2<f32>, param: vec3<f32>) -> f32 {
    let c = m2d_corners(m, param);
    let l = m2d_locate(m, pos);
    let v = m2d_patch(m, c, u32(l.x), u32(l.y));
    return mix(mix(v.x, v.y, l.z), mix(v.z, v.w, l.z), l.w);
}

// Marginal2D::invert: the uniform variates of pos (xy) and the density there (z).
fn m2d_invert(m: M2d, pos: vec2<f32>, param: vec3<f32>) -> vec3<f32> {
    let n_cond = m.h * (m.w - 1u);
    let n_marg = m.h - 1u;
    let c = m2d_corners(m, param);
    let l = m2d_locate(m, pos);
    let ix = u32(l.x);
    let iy = u32(l.y);
    let v = m2d_patch(m, c, ix, iy);
    let c0 = mix(v.x, v.z, l.w);
    let c1 = mix(v.y, v.w, l.w);
    let pdf = mix(c0, c1, l.z);
    // invert_segment: t · lerp(v0, v1, t / 2) · width.
    var sx = l.z * mix(c0, c1, 0.5 * l.z) / f32(m.w - 1u);
    let off = iy * (m.w - 1u);
    if (ix > 0u) {
        let v0 = m2d_lookup(m.cond, n_cond, c, off + ix - 1u);
        let v1 = m2d_lookup(m.cond, n_cond, c, off + (m.w - 1u) + ix - 1u);
        sx += mix(v0, v1, l.w);
    }
    let r0 = m2d_lookup(m.cond, n_cond, c, off + (m.w - 1u) - 1u);
    let r1 = m2d_lookup(m.cond, n_cond, c, off + 2u * (m.w - 1u) - 1u);
    let row_total = mix(r0, r1, l.w);
    if (row_total > 0.0) {
        sx = sx / row_total;
    } else {
        sx = 0.0;
    }
    var sy = l.w * mix(r0, r1, 0.5 * l.w) / f32(m.h - 1u);
    if (iy > 0u) {
        sy += m2d_lookup(m.marg, n_marg, c, iy - 1u);
    }
    if (!m.normalized) {
        let total = m2d_lookup(m.marg, n_marg, c, n_marg - 1u);
        if (total > 0.0) {
            sy = sy / total;
        } else {
            sy = 0.0;
        }
    }
    return vec3<f32>(clamp(sx, 0.0, 1.0), clamp(sy, 0.0, 1.0), pdf);
}

// rgl::elevation: θ of a unit vector, accurate near the pole.
fn rgl_elevation(d: vec3<f32>) -> f32 {
    let dist = sqrt(d.x * d.x + d.y * d.y + (d.z - 1.0) * (d.z - 1.0));
    return 2.0 * asin(clamp(0.5 * dist, -1.0, 1.0));
}

fn rgl_theta2u(theta: f32) -> f32 {
    return sqrt(max(theta * (2.0 / PI), 0.0));
}

fn rgl_phi2u(phi: f32) -> f32 {
    return (phi + PI) * (0.5 / PI);
}

// rgl::mulsign_neg: a when b's sign bit is set, else −a.
fn rgl_mulsign_neg(a: f32, b: f32) -> f32 {
    if ((bitcast<u32>(b) >> 31u) != 0u) {
        return a;
    }
    return -a;
}

// RglBsdf::eval: f(wi, wo) in 1/sr from measured::pack_rgl's record at word `base` (Mitsuba's
// `Measured`: the pair folded by the file's symmetry, the VNDF warp inverted at the half vector,
// the RGB table read there, times D / 4σ with the Jacobian flag); 0 unless both lie above.
fn rgl_eval(base: u32, wi: vec3<f32>, wo: vec3<f32>) -> vec3<f32> {
    if (!(wi.z > 0.0 && wo.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    let isotropic = m2d_word(base) != 0u;
    let jacobian = m2d_word(base + 1u) != 0u;
    let reduction = m2d_word(base + 2u);
    var sx = -1.0;
    var sy = -1.0;
    if (reduction >= 2u) {
        sy = wo.y;
        sx = sy;
        if (reduction == 4u) {
            sx = wo.x;
        }
    }
    let v = vec3<f32>(rgl_mulsign_neg(wo.x, sx), rgl_mulsign_neg(wo.y, sy), wo.z);
    let l = vec3<f32>(rgl_mulsign_neg(wi.x, sx), rgl_mulsign_neg(wi.y, sy), wi.z);
    let s = v + l;
    let len = length(s);
    if (!(len > 0.0 && len < 3.0e38)) {
        return vec3<f32>(0.0);
    }
    let m = s / len;
    let theta_i = rgl_elevation(v);
    let phi_i = atan2(v.y, v.x);
    let u_wi = vec2<f32>(rgl_theta2u(theta_i), rgl_phi2u(phi_i));
    var phi_m = atan2(m.y, m.x);
    if (isotropic) {
        phi_m -= phi_i;
    }
    let uy = rgl_phi2u(phi_m);
    let u_m = vec2<f32>(rgl_theta2u(rgl_elevation(m)), uy - floor(uy));
    let vndf = m2d_load(base + m2d_word(base + 6u));
    let sample = m2d_invert(vndf, u_m, vec3<f32>(phi_i, theta_i, 0.0)).xy;
    let rgb = m2d_load(base + m2d_word(base + 8u));
    var spec = vec3<f32>(0.0);
    for (var ch = 0u; ch < 3u; ch++) {
        spec[ch] = max(m2d_eval(rgb, sample, vec3<f32>(phi_i, theta_i, f32(ch))), 0.0);
    }
    if (jacobian) {
        let sigma = m2d_eval(m2d_load(base + m2d_word(base + 5u)), u_wi, vec3<f32>(0.0));
        if (!(sigma > 0.0)) {
            return vec3<f32>(0.0);
        }
        spec *= m2d_eval(m2d_load(base + m2d_word(base + 4u)), u_m, vec3<f32>(0.0))
            / (4.0 * sigma);
    }
    let f = spec / wi.z;
    if (!(all(abs(f) < vec3<f32>(3.0e38)))) {
        return vec3<f32>(0.0);
    }
    return f;
}
