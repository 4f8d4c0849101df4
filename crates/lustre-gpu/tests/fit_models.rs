//! The fitted models on the GPU (`wgsl/{sgd, cook_torrance, kurt}.wgsl`, packed by
//! `lustre_gpu::material::fitted`) against their CPU twins on real fits: the published SGD fits of
//! the shared data, the SGD fits `lustre fit` wrote into docs/results/fits-004, Beckmann and GGX
//! fits of a MERL material made here with `lustre_fit::ct::fit`, and the Kurt catalog models
//! (anisotropic `kurt-demo`, transmissive `kurt-glass`). Per model: eval, pdf and sample over a
//! grid of ωo (θo to 85°, every φo quadrant, and below the surface for the two-sided Kurt) and
//! u points; and the regular-warp estimate of the directional albedo against a constant
//! environment vs `lustre_shade::warp::integrate_warp`. GPU tests fail (never skip) without an
//! adapter.

use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::fits::sgd::SgdFits;
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::{uniform_sphere, SplitMix64};
use lustre_gpu::material::fitted::{fit_kd, pack_fit};
use lustre_gpu::material::kurt::KURT_MAX_LOBES;
use lustre_gpu::material::{cook_torrance, kurt, sgd, RecordParams, KIND_SGD};
use lustre_gpu::wgsl;
use lustre_shade::warp::{fibonacci_point, integrate_warp};
use std::collections::BTreeMap;
use std::f64::consts::PI;

mod common;
use common::ctx;
use common::shader::{angle, f32_round, run_shader};

/// A material under test: its group (the model reported), name and BSDF.
struct Case {
    model: &'static str,
    name: String,
    bsdf: Box<dyn Bsdf>,
}

/// Published SGD fits of the shared data tested on the GPU: per-channel distributions,
/// tiny α (brass, alumina-oxide), huge c (black-obsidian), θ0 not tied to (λ, c, k)
/// (chrome-steel), p > 1 (teflon), the built-in scene's gold-metallic-paint.
const PUBLISHED: [&str; 8] = [
    "gold-metallic-paint",
    "alum-bronze",
    "brass",
    "alumina-oxide",
    "black-obsidian",
    "chrome-steel",
    "teflon",
    "pvc",
];

fn published_table() -> SgdFits {
    let path = lustre_brdf::shared_data_dir().join("fits/merl_sgd_fits_bagher2012.csv");
    SgdFits::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The materials under test, built once (the Beckmann and GGX fits take a moment).
fn cases() -> &'static [Case] {
    static CASES: std::sync::OnceLock<Vec<Case>> = std::sync::OnceLock::new();
    CASES.get_or_init(build_cases)
}

fn build_cases() -> Vec<Case> {
    let mut out = Vec::new();
    let table = published_table();
    for m in PUBLISHED {
        out.push(Case {
            model: "sgd (published)",
            name: format!("sgd:{m}"),
            bsdf: Box::new(
                table
                    .cook_torrance(m)
                    .unwrap_or_else(|e| panic!("{m}: {e}")),
            ),
        });
    }
    // `lustre fit` SGD fits kept in the repository.
    let docs = concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/results/fits-004");
    for m in ["gold-metallic-paint", "nickel", "white-paint"] {
        let path = std::path::Path::new(docs).join(format!("{m}.json"));
        out.push(Case {
            model: "sgd (lustre fit)",
            name: path.display().to_string(),
            bsdf: lustre_brdf::catalog::resolve(&path.to_string_lossy())
                .unwrap_or_else(|e| panic!("{}: {e}", path.display())),
        });
    }
    // Beckmann and GGX fits of a MERL material (the neural representation of the shared data)
    // as `lustre fit` makes them (two-slice fit, no refinement, for speed).
    let data =
        lustre_fit::data::load("nbrdf:gold-metallic-paint").unwrap_or_else(|e| panic!("{e}"));
    let opts = lustre_fit::ct::CtOptions {
        refine: false,
        ..Default::default()
    };
    for (model, d) in [
        ("beckmann", lustre_fit::ct::CtDistribution::Beckmann),
        ("ggx", lustre_fit::ct::CtDistribution::Ggx),
    ] {
        let fit =
            lustre_fit::ct::fit(data.bsdf.as_ref(), d, &opts).unwrap_or_else(|e| panic!("{e}"));
        out.push(Case {
            model,
            name: format!("{model} fit of nbrdf:gold-metallic-paint"),
            bsdf: Box::new(fit.to_bsdf(model).unwrap_or_else(|e| panic!("{e}"))),
        });
    }
    for spec in ["kurt-demo", "kurt-glass", "kurt-plastic"] {
        out.push(Case {
            model: "kurt",
            name: spec.into(),
            bsdf: lustre_brdf::catalog::resolve(spec).unwrap_or_else(|e| panic!("{e}")),
        });
    }
    out
}

/// Words of a material record in the kernels' input: kind, 32 floats.
const MAT_WORDS: usize = 33;

fn material_words(cases: &[Case]) -> Vec<u32> {
    let mut input = Vec::new();
    for c in cases {
        let (kind, p): (u32, RecordParams) =
            pack_fit(c.bsdf.as_ref()).unwrap_or_else(|e| panic!("{}: {e}", c.name));
        input.push(kind);
        input.extend(p.iter().flatten().map(|v| v.to_bits()));
    }
    input
}

/// WGSL reading material `mi` into `kind` and `p`, and a dispatch on the kind running `then`
/// with `EVAL`, `PDF`, `SAMPLE` replaced by the model's functions applied to `m`.
fn dispatch(then: &str) -> String {
    let mut s = format!(
        "let mb = mi * {MAT_WORDS}u;\n\
         let kind = input[mb];\n\
         var p: array<vec4<f32>, 8>;\n\
         for (var k = 0u; k < 8u; k++) {{\n\
             p[k] = vec4<f32>(bitcast<f32>(input[mb + 1u + 4u * k]), \
                              bitcast<f32>(input[mb + 2u + 4u * k]), \
                              bitcast<f32>(input[mb + 3u + 4u * k]), \
                              bitcast<f32>(input[mb + 4u + 4u * k]));\n\
         }}\n",
    );
    for (cond, model) in [
        ("kind == 16u", "sgd"),
        ("kind == 17u || kind == 18u", "cook_torrance"),
        ("kind == 19u", "kurt"),
    ] {
        let body = then
            .replace("EVAL", &format!("{model}_eval"))
            .replace("PDF", &format!("{model}_pdf"))
            .replace("SAMPLE", &format!("{model}_sample"));
        s.push_str(&format!(
            "if ({cond}) {{\n let m = {model}_unpack(p);\n{body}\n}}\n"
        ));
    }
    s
}

/// Words per parity query: material, ωo, ωi, u; words out: f(ωi, ωo), pdf, sampled ωi, pdf,
/// value.
const Q_IN: usize = 9;
const Q_OUT: usize = 11;

/// ωo of the grid: θo = 0°, 10°, …, 80°, 85° at φo = 0.3 + k π/2 (k = 0..3); for models
/// with transmission also the same below the surface.
fn wo_grid(below: bool) -> Vec<DVec3> {
    let mut v = Vec::new();
    let thetas: Vec<f64> = (0..9).map(|k| 10.0 * k as f64).chain([85.0]).collect();
    for &t in &thetas {
        for k in 0..4 {
            let (t, ph) = (t.to_radians(), 0.3 + k as f64 * PI / 2.0);
            let w = DVec3::new(t.sin() * ph.cos(), t.sin() * ph.sin(), t.cos());
            v.push(f32_round(w));
            if below {
                v.push(f32_round(DVec3::new(w.x, w.y, -w.z)));
            }
        }
    }
    v
}

/// Per-model figures of the parity test.
#[derive(Default)]
struct Figures {
    queries: usize,
    eval: f64,
    pdf: f64,
    sampled: usize,
    agree: usize,
    flips: usize,
    sample_pdf: f64,
    sample_value: f64,
}

#[test]
fn fitted_models_match_their_cpu_twins() {
    let ctx = ctx();
    let cases = cases();
    let mut input = material_words(cases);
    let header = input.len();
    let mut queries: Vec<(usize, DVec3, DVec3, f64, f64)> = Vec::new();
    let mut g = SplitMix64::new(0x0f17_5eed);
    let n_u = 24;
    for (mi, c) in cases.iter().enumerate() {
        let below = c.bsdf.flags().transmission;
        for wo in wo_grid(below) {
            for k in 0..n_u {
                // Fibonacci points and random ones, in f32.
                let (u1, u2) = if k < n_u / 2 {
                    fibonacci_point(k, n_u / 2)
                } else {
                    (g.next_f64(), g.next_f64())
                };
                let (u1, u2) = (f64::from(u1 as f32), f64::from(u2 as f32));
                let (u1, u2) = (u1.min(0.999_999), u2.min(0.999_999));
                // ωi: the CPU's sample where there is one (in the lobe), else a sphere point.
                let wi = match c.bsdf.sample(wo, u1, u2) {
                    Some(s) if k % 3 != 2 => s.wi,
                    _ => uniform_sphere(g.next_f64(), g.next_f64()),
                };
                queries.push((mi, wo, f32_round(wi), u1, u2));
            }
        }
    }
    for &(mi, wo, wi, u1, u2) in &queries {
        input.push(mi as u32);
        for v in [wo.x, wo.y, wo.z, wi.x, wi.y, wi.z, u1, u2] {
            input.push((v as f32).to_bits());
        }
    }
    let n = queries.len();
    let body = format!(
        "let b = {header}u + i * {Q_IN}u;\n\
         let mi = input[b];\n\
         var f: array<f32, {Q_IN}>;\n\
         for (var k = 1u; k < {Q_IN}u; k++) {{ f[k] = bitcast<f32>(input[b + k]); }}\n\
         let wo = vec3<f32>(f[1], f[2], f[3]);\n\
         let wi = vec3<f32>(f[4], f[5], f[6]);\n\
         let u = vec2<f32>(f[7], f[8]);\n\
         var out: array<f32, {Q_OUT}>;\n\
         {}\n\
         for (var k = 0u; k < {Q_OUT}u; k++) {{ output[i * {Q_OUT}u + k] = bitcast<u32>(out[k]); }}",
        dispatch(
            "let e = EVAL(m, wi, wo);\n\
             let s = SAMPLE(m, wo, u);\n\
             out = array<f32, 11>(e.x, e.y, e.z, PDF(m, wi, wo), s.wi.x, s.wi.y, s.wi.z, \
             s.pdf, s.value.x, s.value.y, s.value.z);"
        )
    );
    let start = std::time::Instant::now();
    let out = run_shader(
        &ctx,
        &[&sgd::MODULE, &cook_torrance::MODULE, &kurt::MODULE],
        &body,
        &input,
        n * Q_OUT,
        n as u32,
        None,
    );
    let gpu_time = start.elapsed();
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-3);
    let mut figs: BTreeMap<&str, Figures> = BTreeMap::new();
    let mut worst: BTreeMap<&str, (f64, String)> = BTreeMap::new();
    for (q, &(mi, wo, wi, u1, u2)) in queries.iter().enumerate() {
        let c = &cases[mi];
        let o: Vec<f64> = out[Q_OUT * q..Q_OUT * (q + 1)]
            .iter()
            .map(|&w| f64::from(f32::from_bits(w)))
            .collect();
        let fig = figs.entry(c.model).or_default();
        fig.queries += 1;
        let what = || format!("{}: ωo {wo} ωi {wi} u ({u1}, {u2})", c.name);
        let f = c.bsdf.eval(wi, wo);
        for ch in 0..3 {
            let e = rel(o[ch], f[ch]);
            if e > fig.eval {
                fig.eval = e;
                worst.insert(
                    c.model,
                    (e, format!("eval {} vs CPU {}: {}", o[ch], f[ch], what())),
                );
            }
        }
        fig.pdf = fig.pdf.max(rel(o[3], c.bsdf.pdf(wi, wo)));
        let gpu_ok = o[7] > 0.0;
        match c.bsdf.sample(wo, u1, u2) {
            Some(s) if gpu_ok => {
                fig.sampled += 1;
                let gwi = DVec3::new(o[4], o[5], o[6]);
                if angle(s.wi, gwi) < 1e-4 {
                    fig.agree += 1;
                    fig.sample_pdf = fig.sample_pdf.max(rel(o[7], s.pdf));
                    for ch in 0..3 {
                        fig.sample_value = fig.sample_value.max(rel(o[8 + ch], s.value[ch]));
                    }
                } else {
                    fig.flips += 1;
                }
            }
            None if !gpu_ok => {}
            _ => {
                fig.sampled += 1;
                fig.flips += 1;
            }
        }
    }
    println!(
        "fitted models on {}: {n} queries, {} materials, GPU {:.2} s",
        ctx.describe(),
        cases.len(),
        gpu_time.as_secs_f64()
    );
    println!("model | queries | max rel eval | max rel pdf | samples | wi agree (1e-4 rad) | flips | max rel sample pdf | max rel sample value");
    for (model, f) in &figs {
        println!(
            "{model} | {} | {:.1e} | {:.1e} | {} | {:.4} | {} | {:.1e} | {:.1e}",
            f.queries,
            f.eval,
            f.pdf,
            f.sampled,
            f.agree as f64 / f.sampled.max(1) as f64,
            f.flips,
            f.sample_pdf,
            f.sample_value
        );
        if let Some((_, w)) = worst.get(model) {
            println!("  worst eval: {w}");
        }
    }
    for (model, f) in &figs {
        assert!(f.eval < 1e-3, "{model}: eval {:.2e}", f.eval);
        assert!(f.pdf < 1e-3, "{model}: pdf {:.2e}", f.pdf);
        assert!(
            f.sample_pdf < 1e-3 && f.sample_value < 1e-3,
            "{model}: samples"
        );
        assert!(
            f.agree as f64 >= 0.99 * f.sampled as f64 && f.sampled > f.queries / 2,
            "{model}: {} of {} samples agree",
            f.agree,
            f.sampled
        );
    }
}

/// Words per integration query: material, ωo, budget; out: the estimate of the whole f and of
/// f − kd/π on the reflection side (rgb each).
const I_IN: usize = 5;
const I_OUT: usize = 6;

/// The regular-warp estimate of the directional albedo (constant unit environment):
/// (1/n) Σ f |cos θi| / p over n Fibonacci points through the model's warp, whole and minus the
/// light-mapped kd/π, in WGSL vs `integrate_warp`. PSNR (peak: the largest CPU value of the
/// model) ≥ 90 dB, or every estimate within 1e-5 relative.
#[test]
fn regular_warp_albedo_matches_integrate_warp() {
    let ctx = ctx();
    let cases = cases();
    let mut input = material_words(cases);
    let header = input.len();
    let mut queries = Vec::new();
    for (mi, c) in cases.iter().enumerate() {
        for wo in wo_grid(c.bsdf.flags().transmission) {
            for n in [8u32, 13, 19, 64] {
                queries.push((mi, wo, n));
            }
        }
    }
    for &(mi, wo, n) in &queries {
        input.push(mi as u32);
        input.extend([wo.x, wo.y, wo.z].map(|v| (v as f32).to_bits()));
        input.push(n);
    }
    let kds: Vec<Rgb> = cases
        .iter()
        .map(|c| fit_kd(c.bsdf.as_ref()).unwrap_or_else(|e| panic!("{}: {e}", c.name)))
        .collect();
    for kd in &kds {
        input.extend(kd.0.map(|v| (v as f32).to_bits()));
    }
    let kd_at = header + queries.len() * I_IN;
    let n = queries.len();
    let body = format!(
        "let b = {header}u + i * {I_IN}u;\n\
         let mi = input[b];\n\
         let wo = vec3<f32>(bitcast<f32>(input[b + 1u]), bitcast<f32>(input[b + 2u]), \
                            bitcast<f32>(input[b + 3u]));\n\
         let budget = input[b + 4u];\n\
         let kb = {kd_at}u + 3u * mi;\n\
         let kd = vec3<f32>(bitcast<f32>(input[kb]), bitcast<f32>(input[kb + 1u]), \
                            bitcast<f32>(input[kb + 2u]));\n\
         var whole = vec3<f32>(0.0);\n\
         var glossy = vec3<f32>(0.0);\n\
         {}\n\
         let out = array<f32, 6>(whole.x, whole.y, whole.z, glossy.x, glossy.y, glossy.z);\n\
         for (var k = 0u; k < 6u; k++) {{ output[i * 6u + k] = bitcast<u32>(out[k]); }}",
        dispatch(
            "for (var j = 0u; j < budget; j++) {\n\
                 let s = SAMPLE(m, wo, fibonacci_point(j, budget));\n\
                 if (!(s.pdf > 0.0)) { continue; }\n\
                 let c = abs(s.wi.z) / s.pdf;\n\
                 whole += s.value * c;\n\
                 var f = s.value;\n\
                 if (s.wi.z * wo.z > 0.0) { f -= kd / PI; }\n\
                 glossy += f * c;\n\
             }\n\
             whole /= f32(budget);\n\
             glossy /= f32(budget);"
        )
    );
    let out = run_shader(
        &ctx,
        &[
            &sgd::MODULE,
            &cook_torrance::MODULE,
            &kurt::MODULE,
            &wgsl::WARP,
        ],
        &body,
        &input,
        n * I_OUT,
        n as u32,
        None,
    );
    // Per model: squared error, count, peak, worst relative.
    let mut acc: BTreeMap<&str, (f64, usize, f64, f64)> = BTreeMap::new();
    for (q, &(mi, wo, budget)) in queries.iter().enumerate() {
        let c = &cases[mi];
        let b = budget as usize;
        let points = |i: usize| {
            let (u1, u2) = fibonacci_point(i, b);
            (f64::from(u1 as f32), f64::from(u2 as f32))
        };
        let light = |_: DVec3, _: Option<f64>| Rgb::ONE;
        let (whole, _) = integrate_warp(c.bsdf.as_ref(), Rgb::ZERO, |v| v, wo, b, points, light);
        let (glossy, _) = integrate_warp(c.bsdf.as_ref(), kds[mi], |v| v, wo, b, points, light);
        let a = acc.entry(c.model).or_insert((0.0, 0, 0.0, 0.0));
        for (k, cpu) in [whole, glossy].iter().enumerate() {
            for ch in 0..3 {
                let gpu = f64::from(f32::from_bits(out[I_OUT * q + 3 * k + ch]));
                a.0 += (gpu - cpu[ch]).powi(2);
                a.1 += 1;
                a.2 = f64::max(a.2, cpu[ch].abs());
                a.3 = f64::max(a.3, (gpu - cpu[ch]).abs() / cpu[ch].abs().max(1e-6));
            }
        }
    }
    println!(
        "regular-warp albedo on {}: {n} estimates (n = 8, 13, 19, 64)",
        ctx.describe()
    );
    println!("model | PSNR (dB) | worst relative");
    for (model, &(se, count, peak, worst)) in &acc {
        let psnr = 20.0 * (peak / (se / count as f64).sqrt()).log10();
        println!("{model} | {psnr:.1} | {worst:.1e}");
        assert!(
            psnr >= 90.0 || worst <= 1e-5,
            "{model}: PSNR {psnr:.1} dB, worst relative {worst:.1e}"
        );
    }
}

/// `upper_gamma_f32` (sgd.wgsl, from which the GPU derives the SGD's kap) against
/// `lustre_brdf::numeric::upper_gamma` over s = 1 − p for p in [−2, 3] and x = α in
/// [1e-5, 5], and against known values (mpmath 1.3 `gammainc`) near s = 0, where the CPU's
/// recurrence for s < 0 loses digits (8e-5 relative at s = −1e-6, x = 1.9).
#[test]
fn upper_gamma_matches_the_cpu() {
    let ctx = ctx();
    let mut pts = Vec::new();
    for i in 0..=100 {
        let s = -2.0 + 5.0 * i as f64 / 100.0;
        for j in 0..=24 {
            let x = 10f64.powf(-5.0 + 5.7 * j as f64 / 24.0);
            let want = lustre_brdf::numeric::upper_gamma(s, f64::from(x as f32));
            pts.push((s, f64::from(x as f32), want));
        }
    }
    let xs = [1e-4, 0.01, 0.3, 1.9, 2.1];
    let known: [(f64, [f64; 5]); 4] = [
        (
            -1e-6,
            [
                8.63326613185392,
                4.037939247218218,
                0.9056770124365329,
                0.05620432514226012,
                0.04261429785648886,
            ],
        ),
        (
            1e-6,
            [
                8.633183277554124,
                4.037919905889074,
                0.9056762909156173,
                0.0562044312068632,
                0.04261438516058839,
            ],
        ),
        (
            -1e-3,
            [
                8.674781471116349,
                4.047615790920751,
                0.9060376404880952,
                0.056151372668084044,
                0.04257071301166807,
            ],
        ),
        (
            1e-3,
            [
                8.591926573562384,
                4.028274425611248,
                0.9053161194756633,
                0.05625743729063019,
                0.04265801712916081,
            ],
        ),
    ];
    for (s, vals) in known {
        for (x, v) in xs.iter().zip(vals) {
            pts.push((s, *x, v));
        }
    }
    let input: Vec<u32> = pts
        .iter()
        .flat_map(|&(s, x, _)| [(s as f32).to_bits(), (x as f32).to_bits()])
        .collect();
    let n = pts.len();
    let body = "output[i] = bitcast<u32>(upper_gamma_f32(bitcast<f32>(input[2u * i]), \
                bitcast<f32>(input[2u * i + 1u])));";
    let out = run_shader(&ctx, &[&sgd::MODULE], body, &input, n, n as u32, None);
    let mut worst = (0.0f64, 0.0, 0.0);
    for (k, &(s, x, want)) in pts.iter().enumerate() {
        let gpu = f64::from(f32::from_bits(out[k]));
        let e = (gpu - want).abs() / want.abs();
        if e > worst.0 || e.is_nan() {
            worst = (e, s, x);
        }
    }
    println!(
        "upper_gamma_f32: {n} points, max relative error {:.2e} at s = {}, x = {} on {}",
        worst.0,
        worst.1,
        worst.2,
        ctx.describe()
    );
    assert!(worst.0 < 5e-5, "{worst:?}");
}

/// What does not fit is a named error: too many Kurt lobes, a non-normalized SGD (the
/// published chrome), a numeric Smith G1, a model without a layout. Every published SGD fit
/// but chrome packs.
#[test]
fn packing_refuses_what_does_not_fit() {
    let table = published_table();
    let mut refused = Vec::new();
    for m in table.list_materials() {
        let ct = table
            .cook_torrance(&m)
            .unwrap_or_else(|e| panic!("{m}: {e}"));
        match pack_fit(&ct) {
            Ok((kind, _)) => assert_eq!(kind, KIND_SGD),
            Err(e) => refused.push((m, e.to_string())),
        }
    }
    println!("published SGD fits refused: {refused:?}");
    assert_eq!(refused.len(), 1, "{refused:?}");
    assert_eq!(refused[0].0, "chrome");
    assert!(refused[0].1.contains("kap"), "{}", refused[0].1);
    let five = lustre_brdf::catalog::resolve(
        "kurt(kd=0.1, ks=0.5, ks2=0.2, kt=0.3, mx=0.1, mx2=0.3, mxt=0.2)",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        pack_fit(five.as_ref()).is_ok(),
        "two reflection + one transmission lobes fit"
    );
    let k = lustre_brdf::models::kurt::Kurt::new(
        Rgb::splat(0.1),
        vec![
            lustre_brdf::models::kurt::KurtLobe::new(Rgb::splat(0.1), 0.1, 0.1, 0.5, 0.0)
                .unwrap_or_else(|e| panic!("{e}"));
            KURT_MAX_LOBES
        ],
        vec![
            lustre_brdf::models::kurt::KurtLobe::new(Rgb::splat(0.1), 0.2, 0.2, 0.5, 0.0)
                .unwrap_or_else(|e| panic!("{e}")),
        ],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let e = pack_fit(&k)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("holds 4 lobes"), "{e}");
    let numeric =
        lustre_brdf::catalog::resolve("sgd(alpha=0.05, p=0.5)").unwrap_or_else(|e| panic!("{e}"));
    let e = pack_fit(numeric.as_ref())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("numeric Smith G1"), "{e}");
    let lambert =
        lustre_brdf::catalog::resolve("lambert(kd=0.5)").unwrap_or_else(|e| panic!("{e}"));
    let e = pack_fit(lambert.as_ref())
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("not a fitted model"), "{e}");
    assert!(fit_kd(lambert.as_ref()).is_err());
    // What a scene's `MaterialKind::Spec` holds (the built-in room's fitted material).
    let spec = lustre_scene::ResolvedSpec::resolve("gold-paint", "sgd:gold-metallic-paint")
        .unwrap_or_else(|e| panic!("{e}"));
    let (kind, _) = pack_fit(spec.bsdf.as_ref()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(kind, KIND_SGD);
    let kd = fit_kd(spec.bsdf.as_ref()).unwrap_or_else(|e| panic!("{e}"));
    let want = table
        .params("gold-metallic-paint")
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(kd, Rgb::new(want[0].rho_d, want[1].rho_d, want[2].rho_d));
}
