//! The binding-free WGSL modules of `lustre_gpu::wgsl`: each validates with naga composed with
//! its dependencies alone and declares no binding or entry point; the functions new on the GPU
//! (bounding planes, QMC points and seeds, GGX/Beckmann microfacet evaluation, densities and
//! sampling warps, regular sampling through the rough conductor's warp on a real pyramid) run
//! in a small test shader and are compared with their CPU twins in
//! lustre-shade and lustre-brdf. The sphere-pass modules (lobe, mip, pattern, regular) are
//! checked end to end by `tests/parity.rs`. GPU tests fail (never skip) without an adapter.

use glam::DVec3;
use lustre_brdf::sampling::{uniform_sphere, SplitMix64};
use lustre_gpu::wgsl::{self, compose};
use lustre_gpu::GpuEnvironment;
use lustre_shade::integrator::{corrected_direction, pixel_seed, sobol02, BoundingPlane};

mod common;
use common::ctx;
use common::shader::{angle, f32_round, run_shader, validate};

#[test]
fn every_module_validates_alone_and_has_no_bindings() {
    for m in wgsl::ALL {
        // The functions a module reads the pass's buffers through (its header's `Requires`
        // lines, transitively) are stubbed here with zero values.
        let alone = compose(&[m], "");
        let mut pass = String::new();
        for line in alone.lines() {
            if let Some(sig) = line.strip_prefix("// Requires (the pass defines): ") {
                let sig = sig.trim_end_matches('.');
                let ret = sig.rsplit("-> ").next().unwrap_or("f32");
                let stub = format!("{sig} {{\n    return {ret}();\n}}\n");
                if !pass.contains(&stub) {
                    pass.push_str(&stub);
                }
            }
        }
        let src = compose(&[m], &pass);
        let module = validate(&src);
        assert!(module.entry_points.is_empty(), "{}: entry point", m.name);
        assert!(
            module.global_variables.is_empty(),
            "{}: module-scope variables (bindings)",
            m.name
        );
        for word in [
            "@group",
            "@binding",
            "@compute",
            "@vertex",
            "@fragment",
            "var<",
        ] {
            assert!(!m.text().contains(word), "{} contains {word}", m.name);
        }
        // Every name the module declares is declared once in the composition.
        assert_eq!(
            src.matches(&format!("module {}.wgsl\n", m.name)).count(),
            1,
            "{}",
            m.name
        );
    }
}

/// Most planes per case in the plane test.
const MAX_PLANES: usize = 6;
/// Words per plane-test case: position, direction, plane count, planes (point, normal).
const PLANE_CASE: usize = 7 + 6 * MAX_PLANES;

/// A seeded plane-test case: a point inside a box (axis-aligned, or turned about a random axis),
/// or a few random planes around the origin (which the ray may miss), and a direction.
fn plane_case(g: &mut SplitMix64, k: usize) -> (DVec3, DVec3, Vec<BoundingPlane>) {
    let mut r = |lo: f64, hi: f64| lo + (hi - lo) * g.next_f64();
    let dir = uniform_sphere(r(0.0, 1.0), r(0.0, 1.0));
    let mut planes = Vec::new();
    let pos;
    if k % 3 < 2 {
        // A box with half-extents in [1, 3] around a centre near the projection centre; the
        // point lies inside it.
        let ext = DVec3::new(r(1.0, 3.0), r(1.0, 3.0), r(1.0, 3.0));
        let c = DVec3::new(r(-0.5, 0.5), r(-0.5, 0.5), r(-0.5, 0.5));
        let turn = if k % 3 == 1 {
            glam::DQuat::from_axis_angle(
                uniform_sphere(r(0.0, 1.0), r(0.0, 1.0)),
                r(0.0, std::f64::consts::PI),
            )
        } else {
            glam::DQuat::IDENTITY
        };
        for axis in 0..3 {
            for sign in [-1.0, 1.0] {
                let mut n = DVec3::ZERO;
                n[axis] = sign;
                let normal = turn * n;
                planes.push((c + normal * ext[axis], -normal));
            }
        }
        pos = c + turn
            * DVec3::new(
                r(-0.9, 0.9) * ext.x,
                r(-0.9, 0.9) * ext.y,
                r(-0.9, 0.9) * ext.z,
            );
    } else {
        let n = 2 + (k / 3) % (MAX_PLANES - 1);
        for _ in 0..n {
            let p = DVec3::new(r(-3.0, 3.0), r(-3.0, 3.0), r(-3.0, 3.0));
            let normal = uniform_sphere(r(0.0, 1.0), r(0.0, 1.0));
            planes.push((p, normal));
        }
        pos = DVec3::new(r(-1.0, 1.0), r(-1.0, 1.0), r(-1.0, 1.0));
    }
    let planes = planes
        .into_iter()
        .map(|(p, n)| BoundingPlane {
            point: f32_round(p),
            normal: f32_round(n),
        })
        .collect();
    (f32_round(pos), f32_round(dir), planes)
}

#[test]
fn planes_match_corrected_direction() {
    let ctx = ctx();
    let cases = 600;
    let mut g = SplitMix64::new(0x9a11_ab1e);
    let data: Vec<_> = (0..cases).map(|k| plane_case(&mut g, k)).collect();
    let mut input = Vec::with_capacity(cases * PLANE_CASE);
    for (pos, dir, planes) in &data {
        let mut w = |v: f64| input.push((v as f32).to_bits());
        for v in [*pos, *dir] {
            w(v.x);
            w(v.y);
            w(v.z);
        }
        input.push(planes.len() as u32);
        for k in 0..MAX_PLANES {
            let (p, n) = planes
                .get(k)
                .map_or((DVec3::ZERO, DVec3::Z), |q| (q.point, q.normal));
            for v in [p.x, p.y, p.z, n.x, n.y, n.z] {
                input.push((v as f32).to_bits());
            }
        }
    }
    let body = format!(
        "let base = i * {PLANE_CASE}u;\n\
         var f: array<f32, {PLANE_CASE}>;\n\
         for (var k = 0u; k < {PLANE_CASE}u; k++) {{ f[k] = bitcast<f32>(input[base + k]); }}\n\
         let p = vec3<f32>(f[0], f[1], f[2]);\n\
         let w = vec3<f32>(f[3], f[4], f[5]);\n\
         let count = input[base + 6u];\n\
         var s = -1.0;\n\
         var first = BoundingPlane(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0));\n\
         for (var k = 0u; k < count; k++) {{\n\
             let o = 7u + 6u * k;\n\
             let q = BoundingPlane(vec3<f32>(f[o], f[o + 1u], f[o + 2u]),\n\
                                   vec3<f32>(f[o + 3u], f[o + 4u], f[o + 5u]));\n\
             if (k == 0u) {{ first = q; }}\n\
             s = nearer_plane(s, q, p, w);\n\
         }}\n\
         let all = corrected_lookup(s, p, w);\n\
         let one = plane_corrected_direction(first, p, w);\n\
         let out = array<f32, 6>(all.x, all.y, all.z, one.x, one.y, one.z);\n\
         for (var k = 0u; k < 6u; k++) {{ output[i * 6u + k] = bitcast<u32>(out[k]); }}"
    );
    let out = run_shader(
        &ctx,
        &[&wgsl::PLANES],
        &body,
        &input,
        cases * 6,
        cases as u32,
        None,
    );
    let read = |k: usize| {
        DVec3::new(
            f64::from(f32::from_bits(out[k])),
            f64::from(f32::from_bits(out[k + 1])),
            f64::from(f32::from_bits(out[k + 2])),
        )
    };
    let (mut worst_all, mut worst_one, mut corrected) = (0.0f64, 0.0f64, 0usize);
    for (k, (pos, dir, planes)) in data.iter().enumerate() {
        let cpu_all = corrected_direction(planes, *pos, *dir);
        let cpu_one = planes[0].corrected_direction(*pos, *dir);
        let (gpu_all, gpu_one) = (read(6 * k), read(6 * k + 3));
        if angle(cpu_all, *dir) > 1e-3 {
            corrected += 1;
        }
        let (ea, eo) = (angle(cpu_all, gpu_all), angle(cpu_one, gpu_one));
        assert!(
            ea < 1e-5 && eo < 1e-5,
            "case {k}: pos {pos}, dir {dir}: CPU {cpu_all} / {cpu_one}, GPU {gpu_all} / {gpu_one}"
        );
        worst_all = worst_all.max(ea);
        worst_one = worst_one.max(eo);
    }
    println!(
        "planes: {cases} cases ({corrected} corrected by more than 1 mrad), max angular error \
         {worst_all:.2e} rad (nearest of several planes), {worst_one:.2e} rad (one plane) on {}",
        ctx.describe()
    );
    // The cases exercise the correction, not only misses.
    assert!(corrected > cases / 2, "{corrected} of {cases} corrected");
}

#[test]
fn qmc_matches_sobol02_and_pixel_seed() {
    let ctx = ctx();
    // Indices: the first 4096 (every 2^m-prefix up to m = 12) and some high ones.
    let mut idx: Vec<u32> = (0..4096).collect();
    idx.extend([
        u32::MAX,
        u32::MAX - 1,
        1 << 31,
        (1 << 31) - 1,
        0xdead_beef,
        123_456_789,
    ]);
    let mut g = SplitMix64::new(7);
    let cases: Vec<(u32, u32, u32, u64)> = idx
        .iter()
        .map(|&i| {
            let x = (g.next_u64() & 0xffff) as u32;
            let y = (g.next_u64() & 0xffff) as u32;
            (i, x, y, g.next_u64())
        })
        .collect();
    let mut input = Vec::new();
    for &(i, x, y, seed) in &cases {
        input.extend([i, x, y, seed as u32, (seed >> 32) as u32]);
    }
    let n = cases.len();
    let body = "let b = i * 5u;\n\
         let idx = input[b];\n\
         let seed = vec2<u32>(input[b + 3u], input[b + 4u]);\n\
         let bits = sobol02_bits(idx);\n\
         let p = sobol02(idx);\n\
         let ps = pixel_seed(input[b + 1u], input[b + 2u], seed);\n\
         let rot = qmc_rotation(ps);\n\
         let q = qmc_point(idx, rot);\n\
         let out = array<u32, 10>(bits.x, bits.y, bitcast<u32>(p.x), bitcast<u32>(p.y),\n\
             ps.x, ps.y, bitcast<u32>(rot.x), bitcast<u32>(rot.y),\n\
             bitcast<u32>(q.x), bitcast<u32>(q.y));\n\
         for (var k = 0u; k < 10u; k++) { output[i * 10u + k] = out[k]; }";
    let out = run_shader(&ctx, &[&wgsl::QMC], body, &input, n * 10, n as u32, None);
    let f = |w: u32| f64::from(f32::from_bits(w));
    // The CPU's value truncated to 24 bits, as the GPU keeps it.
    let top24 = |v: f64| (v * 16_777_216.0).floor() / 16_777_216.0;
    let mut worst_point = 0.0f64;
    for (k, &(i, x, y, seed)) in cases.iter().enumerate() {
        let o = &out[10 * k..10 * k + 10];
        let (sx, sy) = sobol02(i);
        assert_eq!(f64::from(o[0]) / 4_294_967_296.0, sx, "sobol x, i = {i}");
        assert_eq!(f64::from(o[1]) / 4_294_967_296.0, sy, "sobol y, i = {i}");
        assert_eq!(
            (f(o[2]), f(o[3])),
            (top24(sx), top24(sy)),
            "sobol f32, i = {i}"
        );
        let ps = pixel_seed(x as usize, y as usize, seed);
        assert_eq!(
            u64::from(o[4]) | u64::from(o[5]) << 32,
            ps,
            "pixel_seed({x}, {y}, {seed:#x})"
        );
        // Progressive::new(ps)'s rotation: two SplitMix64(ps) draws.
        let mut r = SplitMix64::new(ps);
        let (r1, r2) = (r.next_f64(), r.next_f64());
        assert_eq!(
            (f(o[6]), f(o[7])),
            (top24(r1), top24(r2)),
            "rotation of {ps:#x}"
        );
        // Progressive::add_samples' point: within the two truncations and one rounding.
        for (gpu, cpu) in [(f(o[8]), (sx + r1).fract()), (f(o[9]), (sy + r2).fract())] {
            let d = (gpu - cpu).abs();
            let e = d.min(1.0 - d);
            assert!(
                (0.0..1.0).contains(&gpu) && e < 4.0 / 16_777_216.0,
                "i = {i}: {gpu} vs {cpu}"
            );
            worst_point = worst_point.max(e);
        }
    }
    println!(
        "qmc: {n} indices, Sobol' bits, pixel seeds and rotations exact, points within \
         {worst_point:.2e} on {}",
        ctx.describe()
    );
}

/// Words per microfacet case: kind, αu, αv, ωo, ωi, u1, u2.
const MF_CASE: usize = 11;
/// Words out per microfacet case: D(h), G1(ωo, h), eval, pdf, sampled normal (3), sampled
/// ωi (3) and its pdf.
const MF_OUT: usize = 11;

#[test]
fn microfacet_matches_the_cpu_distributions() {
    use lustre_brdf::bsdf::Bsdf;
    use lustre_brdf::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
    use lustre_brdf::models::conductor::ComplexIor;
    use lustre_brdf::models::rough_conductor::RoughConductor;
    use lustre_brdf::rgb::Rgb;
    let ctx = ctx();
    let mut g = SplitMix64::new(0x00f1_ce75);
    let mut cases = Vec::new();
    for k in 0..800 {
        let kind = if k % 2 == 0 {
            MicrofacetType::Ggx
        } else {
            MicrofacetType::Beckmann
        };
        // A quarter of the cases isotropic, the rest anisotropic.
        let au = [0.05, 0.1, 0.2, 0.3, 0.5][(k / 2) % 5];
        let av = if k % 8 < 2 {
            au
        } else {
            [0.075, 0.15, 0.4][(k / 2) % 3]
        };
        // ωo with θo up to 80°, ωi from the sampler of a nearby configuration.
        let th = 80f64.to_radians() * g.next_f64();
        let ph = 2.0 * std::f64::consts::PI * g.next_f64();
        let wo = f32_round(DVec3::new(
            th.sin() * ph.cos(),
            th.sin() * ph.sin(),
            th.cos(),
        ));
        let wi = f32_round(uniform_sphere(0.5 * g.next_f64(), g.next_f64()));
        let (u1, u2) = (
            f64::from(g.next_f64() as f32),
            f64::from(g.next_f64() as f32),
        );
        cases.push((kind, au, av, wo, wi, u1.min(0.999_999), u2.min(0.999_999)));
    }
    let mut input = Vec::with_capacity(cases.len() * MF_CASE);
    for &(kind, au, av, wo, wi, u1, u2) in &cases {
        input.push(match kind {
            MicrofacetType::Beckmann => 0,
            MicrofacetType::Ggx => 1,
        });
        for v in [au, av, wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, u1, u2] {
            input.push((v as f32).to_bits());
        }
    }
    let n = cases.len();
    let body = format!(
        "let b = i * {MF_CASE}u;\n\
         var f: array<f32, {MF_CASE}>;\n\
         for (var k = 1u; k < {MF_CASE}u; k++) {{ f[k] = bitcast<f32>(input[b + k]); }}\n\
         let mf = Microfacet(f[1], f[2], input[b]);\n\
         let wo = vec3<f32>(f[3], f[4], f[5]);\n\
         let wi = vec3<f32>(f[6], f[7], f[8]);\n\
         let u1 = f[9];\n\
         let u2 = f[10];\n\
         let h = normalize(wi + wo);\n\
         let m = microfacet_sample_visible(mf, wo, u1, u2);\n\
         let s = microfacet_sample(mf, wo, u1, u2);\n\
         let out = array<f32, {MF_OUT}>(microfacet_d(mf, h), microfacet_g1(mf, wo, h),\n\
             microfacet_eval(mf, wi, wo), microfacet_pdf(mf, wi, wo), m.x, m.y, m.z,\n\
             s.x, s.y, s.z, s.w);\n\
         for (var k = 0u; k < {MF_OUT}u; k++) {{ output[i * {MF_OUT}u + k] = bitcast<u32>(out[k]); }}"
    );
    let out = run_shader(
        &ctx,
        &[&wgsl::MICROFACET],
        &body,
        &input,
        n * MF_OUT,
        n as u32,
        None,
    );
    let f = |w: u32| f64::from(f32::from_bits(w));
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-3);
    let (mut e_d, mut e_g, mut e_f, mut e_p, mut e_m, mut e_wi, mut e_sp) =
        (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut sampled = 0;
    for (k, &(kind, au, av, wo, wi, u1, u2)) in cases.iter().enumerate() {
        let o: Vec<f64> = out[MF_OUT * k..MF_OUT * (k + 1)]
            .iter()
            .map(|&w| f(w))
            .collect();
        let dist = MicrofacetDistribution::new(kind, au, av).unwrap_or_else(|e| panic!("{e}"));
        let rc = RoughConductor::new(
            dist,
            ComplexIor::preset("none").unwrap_or_else(|e| panic!("{e}")),
            Rgb::ONE,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let h = (wi + wo).normalize();
        let what = format!("case {k}: {kind:?} αu {au} αv {av} ωo {wo} ωi {wi} u ({u1}, {u2})");
        e_d = e_d.max(rel(o[0], dist.d(h)));
        e_g = e_g.max(rel(o[1], dist.g1(wo, h)));
        e_f = e_f.max(rel(o[2], rc.eval(wi, wo)[0]));
        e_p = e_p.max(rel(o[3], rc.pdf(wi, wo)));
        match dist.sample_visible(wo, u1, u2) {
            Some(m) => {
                let a = angle(m, DVec3::new(o[4], o[5], o[6]));
                assert!(a < 1e-3, "{what}: normal {m} vs GPU {:?}", &o[4..7]);
                e_m = e_m.max(a);
            }
            None => assert_eq!(o[6], 0.0, "{what}: GPU sampled a normal, CPU none"),
        }
        match rc.sample(wo, u1, u2) {
            Some(s) => {
                sampled += 1;
                let gwi = DVec3::new(o[7], o[8], o[9]);
                e_wi = e_wi.max(angle(s.wi, gwi));
                // The density at the GPU's own direction, so that direction and density
                // errors are told apart.
                e_sp = e_sp.max(rel(o[10], rc.pdf(f32_round(gwi).normalize(), wo)));
            }
            None => assert!(
                o[10] == 0.0 || o[9] < 1e-3,
                "{what}: GPU sampled {:?}, CPU none",
                &o[7..11]
            ),
        }
    }
    println!(
        "microfacet: {n} cases ({sampled} sampled on the CPU), max relative error D {e_d:.1e}, \
         G1 {e_g:.1e}, f {e_f:.1e}, pdf {e_p:.1e}, sampled pdf {e_sp:.1e}; max angle visible \
         normal {e_m:.1e} rad, ωi {e_wi:.1e} rad on {}",
        ctx.describe()
    );
    assert!(
        e_d < 2e-5 && e_g < 2e-5 && e_f < 2e-5 && e_p < 2e-5,
        "values {e_d} {e_g} {e_f} {e_p}"
    );
    assert!(e_sp < 1e-4, "sampled pdf {e_sp}");
    assert!(e_m < 1e-4 && e_wi < 1e-4, "directions {e_m} {e_wi}");
    assert!(sampled > n / 2, "{sampled} of {n} sampled");
}

/// Words per warp case: kind, αu, αv, budget, ωo (local), t, b, n.
const WARP_CASE: usize = 16;

/// `warp.wgsl`'s regular sampling through the rough conductor's warp against
/// `lustre_shade::warp::shade_regular_warp` on a real map's Gaussian pyramid: 240 seeded
/// configurations, GGX and Beckmann, isotropic and anisotropic, 8, 13 and 19 samples. PSNR
/// (peak = the brightest CPU value) ≥ 45 dB on any adapter, ≥ 90 dB on a CPU adapter with f32
/// filtering, as the sphere pass's parity.
#[test]
fn regular_warp_matches_shade_regular_warp() {
    use lustre_brdf::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
    use lustre_brdf::models::conductor::ComplexIor;
    use lustre_brdf::models::rough_conductor::RoughConductor;
    use lustre_brdf::rgb::Rgb;
    use lustre_env::{irradiance_map, read_map, shared_data_dir, CubeMap, CubePyramid, MipFilter};
    use lustre_shade::integrator::FilteredEnvironment;
    use lustre_shade::truth::configurations;
    use lustre_shade::warp::shade_regular_warp;
    let ctx = ctx();
    let path = shared_data_dir().join("envmaps/royal_esplanade_1k.hdr");
    let map = read_map(&path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .map;
    let base = CubeMap::from_equirect(&map, 64).unwrap_or_else(|e| panic!("{e}"));
    let pyramid = CubePyramid::build(base, MipFilter::Gauss6).unwrap_or_else(|e| panic!("{e}"));
    let irradiance = irradiance_map(&pyramid, 4).unwrap_or_else(|e| panic!("{e}"));
    let env = FilteredEnvironment {
        pyramid: &pyramid,
        irradiance: &irradiance,
    };
    let gpu_env = GpuEnvironment::new(&ctx, &env).unwrap_or_else(|e| panic!("{e}"));
    let configs = configurations(240, 85.0, 29);
    let none = ComplexIor::preset("none").unwrap_or_else(|e| panic!("{e}"));
    let mut input = Vec::new();
    let mut cpu = Vec::new();
    for (k, c) in configs.iter().enumerate() {
        let kind = [MicrofacetType::Ggx, MicrofacetType::Beckmann][k % 2];
        let (au, av) = [(0.1, 0.1), (0.3, 0.3), (0.2, 0.075)][(k / 2) % 3];
        let budget = [8u32, 13, 19][(k / 6) % 3];
        let dist = MicrofacetDistribution::new(kind, au, av).unwrap_or_else(|e| panic!("{e}"));
        let rc = RoughConductor::new(dist, none, Rgb::ONE).unwrap_or_else(|e| panic!("{e}"));
        cpu.push(shade_regular_warp(&c.frame, c.wo, &rc, &env, None, budget as usize).0);
        input.push(u32::from(kind == MicrofacetType::Ggx));
        input.extend([(au as f32).to_bits(), (av as f32).to_bits(), budget]);
        let wo_l = c.frame.to_local(c.wo);
        for v in [wo_l, c.frame.t, c.frame.b, c.frame.n] {
            input.extend([v.x, v.y, v.z].map(|x| (x as f32).to_bits()));
        }
    }
    let n = configs.len();
    let body = format!(
        "let b = i * {WARP_CASE}u;\n\
         var f: array<f32, {WARP_CASE}>;\n\
         for (var k = 0u; k < {WARP_CASE}u; k++) {{ f[k] = bitcast<f32>(input[b + k]); }}\n\
         let mf = Microfacet(f[1], f[2], input[b]);\n\
         let c = regular_warp_microfacet(mf, vec3<f32>(f[4], f[5], f[6]),\n\
             vec3<f32>(f[7], f[8], f[9]), vec3<f32>(f[10], f[11], f[12]),\n\
             vec3<f32>(f[13], f[14], f[15]), input[b + 3u], env_pyramid, env_sampler,\n\
             {face:.1}, {max_lod:.1});\n\
         for (var k = 0u; k < 3u; k++) {{ output[i * 3u + k] = bitcast<u32>(c[k]); }}",
        face = pyramid.base_size() as f64,
        max_lod = (pyramid.levels.len() - 1) as f64,
    );
    let out = run_shader(
        &ctx,
        &[&wgsl::WARP],
        &body,
        &input,
        n * 3,
        n as u32,
        Some(&gpu_env),
    );
    let (mut se, mut peak, mut worst) = (0.0f64, 0.0f64, 0.0f64);
    for (k, c) in cpu.iter().enumerate() {
        for ch in 0..3 {
            let g = f64::from(f32::from_bits(out[3 * k + ch]));
            se += (g - c[ch]).powi(2);
            peak = peak.max(c[ch]);
            worst = worst.max((g - c[ch]).abs() / c[ch].abs().max(1e-3));
        }
    }
    let psnr = 20.0 * (peak / (se / (3 * n) as f64).sqrt()).log10();
    println!(
        "regular warp: {n} configurations, PSNR {psnr:.2} dB, worst relative {worst:.1e} on {}",
        ctx.describe()
    );
    assert!(psnr >= 45.0, "PSNR {psnr:.2} dB < 45 dB");
    if ctx.info.device_type == wgpu::DeviceType::Cpu && ctx.float32_filterable {
        assert!(psnr >= 90.0, "PSNR {psnr:.2} dB < 90 dB on a CPU adapter");
    }
}
