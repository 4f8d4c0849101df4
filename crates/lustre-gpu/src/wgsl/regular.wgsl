// module regular: regular in-lobe sampling of one Kurt lobe and its weighting, per pixel.
// CPU twins: lustre_shade::integrator::{regular_lobe (Weighting::Pdf002), lattice_lobe,
// lattice_axes, lattice_taps, lattice_cells, LatticeGeometry, shade_suns}. Equations: ωi = 2(ωo·h)h − ωo
// (000 Eq. 4.8), mirrored through the tangent plane for transmission (000 Eq. 3.5); stored
// patterns: p_o = p_h / (4 h·ωi) with the pattern's PDF constant (002 Eq. 17–18), estimate
// ks/n Σ L(ωi) f cos θi / p_o (002 Eq. 9), level 002 Eq. 16; row lattice: weight
// μ F cos θi / (G cos θh) per cell of mass μ, level from its solid angle μ/p(ωi); suns split off
// the map (integrator::shade_suns): ks f(ωs, ωo) cos θs E per lobe.
//
// The pyramid is a parameter (`env`, `env_sampler`; `face` = N, `max_lod` = levels − 1), so the
// module holds no binding; stored patterns live in the pass's buffers, which loops over them
// and calls `pattern_sample` per half vector.

// One half vector h of a stored pattern of `count` (integrator::regular_lobe with Pdf002), in the
// frame (t, b, n) facing the viewer, ωo = wo_l local: L(ωi) f cos θi / p_o with unit ks, or 0
// for a sample with ωo·h ≤ 0 or ωi below the horizon (it still counts in n). `area` is
// lobe_area(mx, my, ξ0, ωo) (002 Eq. 14–15).
fn pattern_sample(lobe: Lobe, transmission: bool, wo_l: vec3<f32>, h: vec3<f32>, area: f32,
                  count: u32, t: vec3<f32>, b: vec3<f32>, n: vec3<f32>,
                  env: texture_cube<f32>, env_sampler: sampler, face: f32,
                  max_lod: f32) -> vec3<f32> {
    let ho = dot(wo_l, h); // ωo·h = ωi·h
    if (!(ho > 0.0)) {
        return vec3<f32>(0.0);
    }
    let r = reflect_about(wo_l, h); // 000 Eq. 4.8
    let cos_i = r.z;
    if (!(cos_i > 0.0)) {
        return vec3<f32>(0.0);
    }
    var wi_l = r;
    if (transmission) {
        wi_l = mirror_z(r); // 000 Eq. 3.5: the thin BTDF's direction
    }
    let wi = to_world(wi_l, t, b, n);
    // 002 Eq. 16 (the sampler clamps the level to the pyramid as CubePyramid::sample does).
    let level = min(regular_level(area, count, wi, ho, face), max_lod);
    let li = textureSampleLevel(env, env_sampler, wi, level).rgb;
    // 002 Eq. 2 with unit ks (ks is applied once at the end).
    let g = lobe_eval(lobe, transmission, r, wo_l);
    // 002 Eq. 17–18: p_o = p_h / (4 h·ωi).
    let pdf = lobe.pdf_constant / (4.0 * ho);
    if (pdf > 0.0) {
        return li * (g * cos_i / pdf); // 002 Eq. 9, inner sum
    }
    return vec3<f32>(0.0);
}

// pattern::LATTICE_MAX_TAPS: the most taps one cell of the tap lattice (scheme 2) takes.
const LATTICE_MAX_TAPS: u32 = 3u;

// integrator::LatticeGeometry::slope: x e1 + y e2 with e2 = e1 turned by 90°.
fn lattice_slope(e1: vec2<f32>, x: f32, y: f32) -> vec2<f32> {
    return vec2<f32>(x * e1.x - y * e1.y, x * e1.y + y * e1.x);
}

// integrator::LatticeGeometry::stretch: |∂ωi/∂s| along the slope-space unit vector e at h = n/|n|.
fn lattice_stretch(mx: f32, my: f32, wo_l: vec3<f32>, h: vec3<f32>, len: f32,
                   e: vec2<f32>) -> f32 {
    let dn = vec3<f32>(mx * e.x, my * e.y, 0.0);
    let dh = (dn - h * dot(h, dn)) / len;
    return length(2.0 * (dot(wo_l, dh) * h + dot(wo_l, h) * dh));
}

// integrator::lattice_taps: the taps of cell i of m in row j of rows (x: the count, 0 for a cell
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

// integrator::lattice_cells: with one tap per cell, budget cells; otherwise the largest cell count
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

// The unnormalized major eigenvector of [[a, b], [b, c]] with half = (a − c)/2 and
// root = √(half² + b²): (half + root, b) when half ≥ 0, else (b, root − half).
fn major_axis(half: f32, root: f32, b: f32) -> vec2<f32> {
    if (half >= 0.0) {
        return vec2<f32>(half + root, b);
    }
    return vec2<f32>(b, root - half);
}

// integrator::lattice_lobe: ours, the row lattice of `budget` lookups: equal-mass cells of the
// slope-space Gaussian, rows along the minor axis of the lobe's image in ωi
// (integrator::lattice_axes), each cell read once (max_taps = 1) or, for the tap lattice, by up to
// max_taps taps at its sub-quantiles along its long axis, each at the level of its solid angle
// μ/p(ωi); weight μ F cos θi / (G cos θh).
fn lattice_lobe(lobe: Lobe, transmission: bool, wo_l: vec3<f32>,
                t: vec3<f32>, b: vec3<f32>, n: vec3<f32>, max_taps_in: u32,
                env: texture_cube<f32>, env_sampler: sampler, face: f32,
                max_lod: f32) -> vec3<f32> {
    let budget = lobe.sample_count;
    if (budget == 0u) {
        return vec3<f32>(0.0);
    }
    let mx = lobe.mx;
    let my = lobe.my;
    // integrator::lattice_axes: JᵀJ of s ↦ ωi at s = 0 and its major eigenvector.
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
                    wi_l = mirror_z(r);
                }
                let wi = to_world(wi_l, t, b, n);
                let cell = mass * 4.0 * PI * mx * my * ho * h.z * h.z * h.z * exp(dot(s, s));
                let level = min(footprint_level(cell, wi, face), max_lod);
                let li = textureSampleLevel(env, env_sampler, wi, level).rgb;
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

// integrator::shade_suns for one lobe and one sun: ks f(ωs, ωo) cos θs E, the sun at `sun_l` in the
// frame facing the viewer, the lobe widened by the sun's spread (integrator::sun_widened:
// m'² = m² + spread²/4). A reflection lobe takes a sun above the surface, a transmission lobe
// one below, evaluated on the pair mirrored through the tangent plane (000 Eq. 3.5).
fn sun_lobe(lobe_in: Lobe, transmission: bool, wo_l: vec3<f32>, sun_l: vec3<f32>,
            irradiance: vec3<f32>, spread: f32) -> vec3<f32> {
    var lobe = lobe_in;
    let w = spread * spread * 0.25;
    lobe.mx = sqrt(lobe.mx * lobe.mx + w);
    lobe.my = sqrt(lobe.my * lobe.my + w);
    var wi = sun_l;
    if (transmission) {
        wi = mirror_z(sun_l);
    }
    if (!(wi.z > 0.0)) {
        return vec3<f32>(0.0);
    }
    return lobe.ks * irradiance * (lobe_eval(lobe, transmission, wi, wo_l) * wi.z);
}
