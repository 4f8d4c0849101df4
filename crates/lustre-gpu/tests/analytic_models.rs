//! lustre's analytic models on the GPU (`wgsl/analytic.wgsl`'s `record_eval`, packed by
//! `lustre_gpu::material::analytic::pack_analytic` from what `lustre_brdf::catalog::resolve` returns)
//! against their CPU twins' `Bsdf::eval`: every reflection model of the catalog, several
//! parameter sets each (isotropic and anisotropic, rough and near-specular, the published
//! `lafortune:` and `abc:` fits, `twosided:` seen from below), on random pairs and pairs near
//! the mirror direction; and the specs the GPU still refuses, named. The end-to-end check (a
//! `ward(…)` sphere through the adaptive pass) is in `tests/adaptive_pass.rs`. GPU tests fail
//! (never skip) without an adapter.

use glam::DVec3;
use lustre_brdf::catalog::resolve;
use lustre_brdf::microfacet::fresnel::Fresnel;
use lustre_brdf::microfacet::ndf::Ndf;
use lustre_brdf::microfacet::smith::SgdG1Approx;
use lustre_brdf::models::cook_torrance::{CookTorrance, CtChannel, G1Model};
use lustre_brdf::sampling::SplitMix64;
use lustre_brdf::Bsdf;
use lustre_gpu::material::analytic::pack_analytic;
use lustre_gpu::wgsl::{Module, Source};

mod common;
use common::ctx;
use common::shader::{f32_round, run_shader};

/// The side table of the test shader: the first words of its `input`.
const TABLE: Module = Module {
    name: "test_table",
    source: Source::File("fn bsdf_table(i: u32) -> f32 {\n    return bitcast<f32>(input[i]);\n}\n"),
    deps: &[],
};

/// (spec, largest relative RMS, largest worst-pair error). The bounds are f32 level, except for
/// the near-specular lobes that raise a cosine close to 1 to a power n (Phong, Blinn–Phong,
/// Lafortune, Ashikhmin–Shirley): one rounding of the cosine in f32 (≈ 6e-8 of it) becomes
/// n·6e-8 of the value, so their bounds grow with n (stated per case).
const CASES: [(&str, f64, f64); 35] = [
    ("lambert(kd_r=0.8, kd_g=0.5, kd_b=0.2)", 1e-7, 1e-6),
    (
        "oren-nayar(kd_r=0.8, kd_g=0.5, kd_b=0.2, sigma=0.3)",
        1e-7,
        1e-6,
    ),
    ("oren-nayar(kd=0.6, sigma=1.2)", 1e-7, 1e-6),
    ("phong(kd=0.2, ks=0.5, n=10)", 1e-6, 1e-5),
    // n = 1000: n·6e-8 ≈ 6e-5 per rounding of V·R.
    ("phong(kd=0.02, ks=0.9, n=1000)", 1e-4, 5e-4),
    ("blinn-phong(kd=0.3, ks=0.2, n=20)", 2e-6, 1e-5),
    // n = 2000: ≈ 1.2e-4 per rounding of h·n.
    ("blinn-phong(kd=0.02, ks=0.5, n=2000)", 2e-4, 1e-3),
    ("ward(kd=0.2, ks=0.2, ax=0.3)", 1e-6, 1e-5),
    ("ward(kd=0.1, ks=0.5, ax=0.05, ay=0.3)", 1e-6, 1e-5),
    ("ward(kd=0.02, ks=0.8, ax=0.01)", 1e-6, 1e-5),
    ("ward-duer(kd=0.2, ks=0.3, ax=0.2, ay=0.1)", 1e-6, 1e-5),
    ("ward-duer(kd=0.1, ks=0.5, ax=0.03)", 1e-6, 1e-5),
    ("ward-gmd(kd=0.2, ks=0.3, ax=0.1, ay=0.4)", 1e-6, 1e-5),
    ("ward-gmd(kd=0.05, ks=0.9, ax=0.02)", 1e-6, 1e-5),
    (
        "lafortune(kd=0.2, ks=1, cx=-1, cy=-1, cz=1, n=20)",
        2e-6,
        2e-5,
    ),
    // An anisotropic lobe off the mirror direction, and a retro-reflective one.
    (
        "lafortune(kd=0.1, ks=2, cx=-0.9, cy=-0.5, cz=0.95, n=50)",
        2e-6,
        2e-5,
    ),
    (
        "lafortune(kd=0.3, ks=0.5, cx=0.8, cy=0.8, cz=0.9, n=5)",
        1e-6,
        1e-5,
    ),
    // Published peak-normalized fits (Ngan et al. 2005); nickel's exponent is in the thousands.
    ("lafortune:nickel", 5e-5, 3e-4),
    ("lafortune:blue-metallic-paint", 2e-6, 2e-5),
    ("ashikhmin-shirley(rd=0.3, rs=0.2, nu=100)", 5e-6, 5e-5),
    // nv = 1000, nu = 5000: the exponent of h·n.
    (
        "ashikhmin-shirley(rd=0.2, rs=0.1, nu=10, nv=1000)",
        2e-5,
        5e-4,
    ),
    ("ashikhmin-shirley(rd=0.05, rs=0.9, nu=5000)", 2e-4, 2e-3),
    ("abc(kd=0.1, a=100, b=1000, c=1, ior=1.5)", 1e-6, 1e-5),
    ("abc(kd=0.05, a=5000, b=100000, c=0.5, ior=2.2)", 1e-6, 1e-5),
    ("abc:nickel", 1e-6, 1e-5),
    ("exponential(rho_d=0.1, rho_s=0.5, alpha=0.1)", 1e-6, 1e-5),
    // The SGD with its numeric Smith G1 (kind 27; the fitted layout takes Eq. V.3 only).
    ("sgd(alpha=0.1, p=0.5)", 1e-6, 1e-5),
    ("sgd-numeric:nickel", 1e-6, 1e-5),
    (
        "exponential(rho_d=0.02, rho_s=0.8, alpha=0.02, f0=0.04)",
        1e-6,
        1e-5,
    ),
    (
        "exponential(rho_d=0.3, rho_s=0.3, alpha=0.6, f0=0.5, f1=0.2)",
        1e-6,
        1e-5,
    ),
    ("twosided:ward(kd=0.1, ks=0.5, ax=0.05, ay=0.3)", 1e-6, 1e-5),
    (
        "twosided:ashikhmin-shirley(rd=0.3, rs=0.2, nu=100)",
        5e-6,
        5e-5,
    ),
    // Models bsdf.wgsl already has, now from a spec.
    (
        "roughconductor(material=Au, alpha_u=0.05, alpha_v=0.3, distribution=ggx)",
        1e-6,
        1e-5,
    ),
    (
        "roughplastic(diffuse=0.5, alpha=0.2, distribution=ggx)",
        1e-6,
        1e-5,
    ),
    ("pbr(base_color=0.9, metallic=1, roughness=0.3)", 1e-6, 1e-5),
];

/// `n` pairs (ωi, ωo) in the local frame: a third anywhere above the surface, a third within a
/// few degrees of the mirror direction (the peak), a third of those two kinds mirrored below
/// the surface (ωo under it: zero for a one-sided model, the upper side's value for a
/// two-sided one). Rounded to f32 (the GPU's input), so the CPU evaluates the same pairs.
fn pairs(g: &mut SplitMix64, n: usize) -> Vec<(DVec3, DVec3)> {
    let flip = |w: DVec3| DVec3::new(w.x, w.y, -w.z);
    common::shader::pairs(g, n)
        .into_iter()
        .enumerate()
        .map(|(k, (wi, wo))| {
            let (wi, wo) = if k % 3 == 2 {
                (flip(wi), flip(wo))
            } else {
                (wi, wo)
            };
            (f32_round(wi), f32_round(wo))
        })
        .collect()
}

/// Relative error per channel of the GPU's values against the CPU's, over the value's scale
/// (the larger of the two and 1e-3 of the case's peak): (RMS, worst, the worst pair's index).
fn relative_error(cpu: &[[f64; 3]], gpu: &[[f32; 3]]) -> (f64, f64, usize) {
    let peak = cpu.iter().flatten().fold(0.0f64, |m, &v| m.max(v));
    let (mut worst, mut at, mut sq) = (0.0f64, 0, 0.0);
    for (k, (c, g)) in cpu.iter().zip(gpu).enumerate() {
        for ch in 0..3 {
            let gv = f64::from(g[ch]);
            let e = (gv - c[ch]).abs() / c[ch].abs().max(gv.abs()).max(1e-3 * peak);
            sq += e * e;
            if e > worst {
                (worst, at) = (e, k);
            }
        }
    }
    ((sq / (3 * cpu.len()) as f64).sqrt(), worst, at)
}

fn words(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

#[test]
fn every_analytic_reflection_model_matches_its_cpu_twin() {
    let ctx = ctx();
    let mut g = SplitMix64::new(13);
    let n = 6144;
    let pairs = pairs(&mut g, n);
    let mut cases: Vec<(String, f64, f64)> = CASES
        .iter()
        .map(|&(spec, r, w)| (spec.to_string(), r, w))
        .collect();
    let mut models: Vec<Box<dyn Bsdf>> = CASES
        .iter()
        .map(|(spec, _, _)| resolve(spec).unwrap_or_else(|e| panic!("{spec}: {e}")))
        .collect();
    for (name, m) in constructed_cook_torrance() {
        // Eq. V.3 in f32: 1 + λ(1 − e^{c(θ−θ0)^k}) cancels near grazing (measured: RMS
        // 2.7e-6, worst 7.9e-5 at cos θ 0.002; the all-SGD kind 16 is held to 1e-3).
        let bounds = if name.contains("Eq. V.3") {
            (1e-5, 2e-4)
        } else {
            (1e-6, 1e-5)
        };
        cases.push((name, bounds.0, bounds.1));
        models.push(m);
    }
    // Input: the side table, the records (36 words each), the pairs (6 words each).
    let mut table = vec![];
    let records: Vec<_> = models
        .iter()
        .zip(&cases)
        .map(|(b, (spec, _, _))| {
            pack_analytic(b.as_ref(), &mut table).unwrap_or_else(|e| panic!("{spec}: {e}"))
        })
        .collect();
    let mut input = words(&table);
    let r0 = input.len();
    input.extend(bytemuck::cast_slice::<_, u32>(&records));
    let q = input.len();
    for &(wi, wo) in &pairs {
        input.extend([wi.x, wi.y, wi.z, wo.x, wo.y, wo.z].map(|v| (v as f32).to_bits()));
    }
    let body = format!(
        "let r = {r0}u + (i / {n}u) * 36u;\n\
         var rec: GpuBsdf;\n\
         rec.kind = input[r];\n\
         rec.flags = input[r + 1u];\n\
         for (var j = 0u; j < 8u; j++) {{\n\
             let w = r + 4u + 4u * j;\n\
             rec.p[j] = vec4<f32>(bitcast<f32>(input[w]), bitcast<f32>(input[w + 1u]),\n\
                                  bitcast<f32>(input[w + 2u]), bitcast<f32>(input[w + 3u]));\n\
         }}\n\
         let b = {q}u + (i % {n}u) * 6u;\n\
         let wi = vec3<f32>(bitcast<f32>(input[b]), bitcast<f32>(input[b + 1u]), bitcast<f32>(input[b + 2u]));\n\
         let wo = vec3<f32>(bitcast<f32>(input[b + 3u]), bitcast<f32>(input[b + 4u]), bitcast<f32>(input[b + 5u]));\n\
         let f = record_eval(rec, wi, wo);\n\
         for (var c = 0u; c < 3u; c++) {{ output[i * 3u + c] = bitcast<u32>(f[c]); }}"
    );
    let count = n * cases.len();
    let t = std::time::Instant::now();
    let out = run_shader(
        &ctx,
        &[&TABLE, &lustre_gpu::material::ANALYTIC],
        &body,
        &input,
        3 * count,
        count as u32,
        None,
    );
    eprintln!(
        "{count} evaluations (compile and run) in {:.1} s on {}",
        t.elapsed().as_secs_f64(),
        ctx.describe()
    );
    eprintln!("| spec | kind | rel. RMS | worst pair (ωi; ωo) |");
    eprintln!("|---|---|---|---|");
    let mut failures = vec![];
    for (k, (b, (spec, max_rms, max_worst))) in models.iter().zip(cases).enumerate() {
        let cpu: Vec<[f64; 3]> = pairs.iter().map(|&(wi, wo)| b.eval(wi, wo).0).collect();
        let gpu: Vec<[f32; 3]> = (0..n)
            .map(|p| {
                let o = 3 * (k * n + p);
                [0, 1, 2].map(|c| f32::from_bits(out[o + c]))
            })
            .collect();
        let (rms, worst, at) = relative_error(&cpu, &gpu);
        let (wi, wo) = pairs[at];
        eprintln!(
            "| `{spec}` | {} | {rms:.2e} | {worst:.2e} ({:.4}, {:.4}, {:.4}; {:.4}, {:.4}, {:.4}) |",
            records[k].kind, wi.x, wi.y, wi.z, wo.x, wo.y, wo.z
        );
        if !(rms < max_rms && worst < max_worst) {
            failures.push(format!(
                "{spec}: rms {rms:.2e} (bound {max_rms:e}), worst {worst:.2e} (bound {max_worst:e})"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Cook–Torrance models no spec writes, for kind 27: the numeric Smith G1 of Beckmann and GGX,
/// mixed distributions per channel (with the closed-form G1 and none), the Lazányi Fresnel.
fn constructed_cook_torrance() -> Vec<(String, Box<dyn Bsdf>)> {
    let ch = |rho_d: f64, rho_s: f64, ndf: Ndf, numeric: bool, fresnel: Fresnel| {
        let g1 = if numeric {
            G1Model::numeric(&ndf)
        } else {
            G1Model::Closed
        };
        CtChannel::new(rho_d, rho_s, ndf, g1, fresnel)
    };
    let ok = |r: lustre_brdf::Result<Ndf>| r.expect("ndf");
    let one = Fresnel::One;
    let gold = Fresnel::lazanyi(0.2, 3.4).expect("lazanyi");
    let beckmann = ch(0.1, 0.6, ok(Ndf::beckmann(0.15)), true, one);
    let ggx = ch(0.05, 0.8, ok(Ndf::ggx(0.08)), true, gold);
    let mut mixed = [
        ch(0.2, 0.5, ok(Ndf::beckmann(0.3)), false, gold),
        ch(
            0.1,
            0.7,
            ok(Ndf::ggx(0.05)),
            true,
            Fresnel::schlick(0.04).expect("f0"),
        ),
        ch(0.3, 0.4, ok(Ndf::sgd(0.2, 0.6)), true, one),
    ];
    mixed[2].g1 = G1Model::None;
    // 004's Eq. V.3 shadowing outside the all-SGD layout: a published SGD fit (its G1 by Eq.
    // V.3) with one channel turned Beckmann.
    let nickel = resolve("sgd:nickel").expect("sgd:nickel");
    let ct = nickel
        .as_any()
        .and_then(|a| a.downcast_ref::<CookTorrance>())
        .expect("sgd:nickel is a Cook-Torrance");
    let mut v3 = ct.channels().clone();
    assert!(v3.iter().all(|c| matches!(c.g1, G1Model::SgdApprox(_))));
    v3[1].ndf = ok(Ndf::beckmann(0.2));
    [
        (
            "beckmann, numeric G1",
            [beckmann.clone(), beckmann.clone(), beckmann],
        ),
        ("ggx, numeric G1, Lazányi", [ggx.clone(), ggx.clone(), ggx]),
        ("beckmann / ggx / sgd, Lazányi", mixed),
        ("sgd:nickel, channel 1 Beckmann (Eq. V.3 G1)", v3),
    ]
    .into_iter()
    .map(|(name, c)| {
        let m = CookTorrance::new(name, c).expect("cook-torrance");
        (name.to_string(), Box::new(m) as Box<dyn Bsdf>)
    })
    .collect()
}

#[test]
fn specs_without_a_gpu_twin_are_refused_by_name() {
    // A lustre goniometric table (the fuzz target's seed).
    let gonio = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fuzz/seeds/gonio/small.gonio"
    );
    let b = resolve(gonio).unwrap_or_else(|e| panic!("{gonio}: {e}"));
    match pack_analytic(b.as_ref(), &mut vec![]) {
        Ok(r) => panic!("{gonio}: packed as kind {}", r.kind),
        Err(e) => {
            let m = e.to_string();
            assert!(
                m.contains(&b.name()) && m.contains("no GPU evaluation"),
                "{gonio}: {m}"
            );
        }
    }
    // 004's Eq. V.3 with parameters beyond f32 (λ = 1e39): named.
    let nickel = resolve("sgd:nickel").expect("sgd:nickel");
    let any = nickel.as_any().expect("as_any");
    let ct = any.downcast_ref::<CookTorrance>().expect("a Cook-Torrance");
    let mut c = ct.channels().clone();
    c[0].g1 = G1Model::SgdApprox(SgdG1Approx::new(1e39, 1.0, 2.0, 1.0).expect("Eq. V.3"));
    c[1].ndf = Ndf::beckmann(0.2).expect("ndf");
    let huge = CookTorrance::new("nickel, λ 1e39", c).expect("model");
    let m = pack_analytic(&huge, &mut vec![]).expect_err("λ beyond f32");
    assert!(
        m.to_string().contains("Eq. V.3") && m.to_string().contains("f32"),
        "{m}"
    );
}
