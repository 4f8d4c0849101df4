//! `wgsl/measured.wgsl` against its CPU twins: a MERL table (synthesized from the gold-paint
//! neural BRDF of 004's scenes, with bins marked missing) evaluated by `merl_eval` vs
//! `MerlTable::eval`, the neural BRDFs of 004's five materials (`nbrdf_eval` vs `Nbrdf::eval`),
//! the RGL tensors and ALTA goniometric tables of ../shared/data (`rgl_eval`, `alta_eval`),
//! and tabulated-CDF importance sampling (`tabulated_sample`,
//! `tabulated_pdf`) vs `TabulatedSampler`. GPU tests fail (never skip) without an adapter.

use glam::DVec3;
use lustre_brdf::measured::alta::{AltaTable, AltaUnit};
use lustre_brdf::measured::merl::{MerlTable, NegativeValues, BINS, HEADER_BYTES};
use lustre_brdf::measured::nbrdf::{synthesize_merl, NbrdfSet};
use lustre_brdf::measured::rgl::RglBsdf;
use lustre_brdf::models::ward::Ward;
use lustre_brdf::sampling::SplitMix64;
use lustre_brdf::tabulated::{TabulatedOptions, TabulatedSampler};
use lustre_brdf::{Bsdf, Rgb};
use lustre_gpu::material::measured::{pack_alta, pack_merl, pack_nbrdf, pack_rgl, pack_tabulated};
use lustre_gpu::wgsl::{Module, Source};
use lustre_gpu::GpuContext;

mod common;
use common::ctx;
use common::shader::{pairs, run_shader, upper};

/// The side table of the test shader: the first words of its `input`.
const TABLE: Module = Module {
    name: "test_table",
    source: Source::File("fn bsdf_table(i: u32) -> f32 {\n    return bitcast<f32>(input[i]);\n}\n"),
    deps: &[],
};

/// gold-paint's MERL table with every 997th stored value marked missing (−1 in the file).
fn gold_paint_with_holes() -> MerlTable {
    let table = synthesize_merl(&set().material("gold-paint").expect("gold-paint"), |_| {});
    let mut bytes = table.to_bytes();
    for n in (0..3 * BINS).step_by(997) {
        let at = HEADER_BYTES + 8 * n;
        bytes[at..at + 8].copy_from_slice(&(-1.0f64).to_le_bytes());
    }
    let t = MerlTable::parse_with("<gold-paint with holes>", &bytes, NegativeValues::Missing)
        .expect("table");
    assert!(t.missing_count() > 4000);
    t
}

fn set() -> NbrdfSet {
    NbrdfSet::read(lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json"))
        .expect("merl_nbrdf.json")
}

/// The pairs as kernel input after `input`'s first `q` words: wi, wo (6 f32 each).
fn push_pairs(input: &mut Vec<u32>, pairs: &[(DVec3, DVec3)]) {
    for &(wi, wo) in pairs {
        push_dir(input, wi);
        push_dir(input, wo);
    }
}

/// Relative error per channel of the GPU's RGB values (`out`, 3 words each) against the CPU's,
/// over the value's scale (the larger of the two and 1e-3 of the sample's peak): RMS and worst.
fn relative_error(cpu: &[[f64; 3]], out: &[u32]) -> (f64, f64) {
    let peak = cpu.iter().flatten().fold(0.0f64, |m, &v| m.max(v));
    let mut worst = 0.0f64;
    let mut sq = 0.0;
    for (k, c) in cpu.iter().enumerate() {
        for ch in 0..3 {
            let gv = f64::from(f32::from_bits(out[3 * k + ch]));
            let e = (gv - c[ch]).abs() / c[ch].abs().max(gv.abs()).max(1e-3 * peak);
            sq += e * e;
            worst = worst.max(e);
        }
    }
    ((sq / (3 * cpu.len()) as f64).sqrt(), worst)
}

/// The kernel body that evaluates `call` (a WGSL expression of `wi`, `wo`) on the pairs at
/// word `q` and writes its RGB.
fn eval_body(q: usize, call: &str) -> String {
    format!(
        "let b = {q}u + i * 6u;\n\
         let wi = vec3<f32>(bitcast<f32>(input[b]), bitcast<f32>(input[b + 1u]), bitcast<f32>(input[b + 2u]));\n\
         let wo = vec3<f32>(bitcast<f32>(input[b + 3u]), bitcast<f32>(input[b + 4u]), bitcast<f32>(input[b + 5u]));\n\
         let f = {call};\n\
         for (var c = 0u; c < 3u; c++) {{ output[i * 3u + c] = bitcast<u32>(f[c]); }}"
    )
}

#[test]
fn nbrdf_eval_matches_the_cpu_on_the_five_materials_of_004() {
    let ctx = ctx();
    let set = set();
    let mut g = SplitMix64::new(5);
    let n = 4096;
    let pairs = pairs(&mut g, n);
    for name in [
        "gold-paint",
        "red-metallic-paint",
        "color-changing-paint3",
        "blue-rubber",
        "white-marble",
    ] {
        let net = set.material(name).expect("material");
        let mut input = words(&pack_nbrdf(&net));
        let q = input.len();
        push_pairs(&mut input, &pairs);
        let out = run_shader(
            &ctx,
            &[&TABLE, &lustre_gpu::material::measured::MEASURED],
            &eval_body(q, "nbrdf_eval(0u, wi, wo)"),
            &input,
            3 * n,
            n as u32,
            None,
        );
        let cpu: Vec<[f64; 3]> = pairs.iter().map(|&(wi, wo)| net.eval(wi, wo).0).collect();
        let (rms, worst) = relative_error(&cpu, &out);
        eprintln!("nbrdf_eval vs Nbrdf::eval, {name}, {n} pairs: relative error RMS {rms:.2e}, worst {worst:.2e}");
        assert!(
            rms < 1e-4 && worst < 5e-3,
            "{name}: rms {rms:e}, worst {worst:e}"
        );
    }
}

fn words(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn push_dir(input: &mut Vec<u32>, w: DVec3) {
    input.extend([w.x as f32, w.y as f32, w.z as f32].map(f32::to_bits));
}

#[test]
fn merl_eval_and_tabulated_sampling_match_the_cpu() {
    let ctx = ctx();
    let table = gold_paint_with_holes();
    let packed = pack_merl(&table);
    let mut g = SplitMix64::new(11);
    let n = 8192;
    let pairs = pairs(&mut g, n);
    let mut input = words(&packed);
    let q = input.len();
    push_pairs(&mut input, &pairs);
    let call = format!(
        "merl_eval(0u, {:?}, wi, wo)",
        table.convention().offset() as f32
    );
    let out = run_shader(
        &ctx,
        &[&TABLE, &lustre_gpu::material::measured::MEASURED],
        &eval_body(q, &call),
        &input,
        3 * n,
        n as u32,
        None,
    );
    let cpu: Vec<[f64; 3]> = pairs.iter().map(|&(wi, wo)| table.eval(wi, wo).0).collect();
    let (rms, worst) = relative_error(&cpu, &out);
    eprintln!(
        "merl_eval vs MerlTable::eval on {n} pairs (half near the mirror direction, {} missing values): relative error RMS {rms:.2e}, worst {worst:.2e}; {}",
        table.missing_count(),
        ctx.describe()
    );
    assert!(rms < 1e-4 && worst < 5e-3, "rms {rms:e}, worst {worst:e}");

    // Tabulated sampling of the same table, and of an anisotropic model (tables per view
    // azimuth, unfolded).
    let sampler = TabulatedSampler::new(&table, TabulatedOptions::default()).expect("tabulate");
    tabulated_parity(&ctx, &sampler, "gold-paint (MERL)", &mut g, n);
    let ward = Ward::new(Rgb::splat(0.05), Rgb::splat(0.6), 0.3, 0.06).expect("ward");
    let sampler = TabulatedSampler::new(&ward, TabulatedOptions::default()).expect("tabulate");
    assert!(sampler.is_anisotropic());
    tabulated_parity(&ctx, &sampler, "anisotropic Ward 0.3 / 0.06", &mut g, n);
}

/// `tabulated_sample` / `tabulated_pdf` against `sampler` on `n` random draws.
fn tabulated_parity(
    ctx: &GpuContext,
    sampler: &TabulatedSampler,
    name: &str,
    g: &mut SplitMix64,
    n: usize,
) {
    let (tab, dims) = pack_tabulated(sampler);
    let mut input = words(&tab);
    let q = input.len();
    let cases: Vec<(DVec3, f64, f64, DVec3)> = (0..n)
        .map(|_| (upper(g), g.next_f64(), g.next_f64(), upper(g)))
        .collect();
    for &(wo, u1, u2, wi) in &cases {
        push_dir(&mut input, wo);
        input.extend([u1 as f32, u2 as f32].map(f32::to_bits));
        push_dir(&mut input, wi);
    }
    let body = format!(
        "let b = {q}u + i * 8u;\n\
         let dims = TabulatedDims({}u, {}u, {}u, {}u, {:?});\n\
         let wo = vec3<f32>(bitcast<f32>(input[b]), bitcast<f32>(input[b + 1u]), bitcast<f32>(input[b + 2u]));\n\
         let u = vec2<f32>(bitcast<f32>(input[b + 3u]), bitcast<f32>(input[b + 4u]));\n\
         let wi = vec3<f32>(bitcast<f32>(input[b + 5u]), bitcast<f32>(input[b + 6u]), bitcast<f32>(input[b + 7u]));\n\
         let s = tabulated_sample(0u, dims, wo, u.x, u.y);\n\
         let ps = tabulated_pdf(0u, dims, s.xyz, wo);\n\
         let pw = tabulated_pdf(0u, dims, wi, wo);\n\
         let o = array<f32, 6>(s.x, s.y, s.z, s.w, ps, pw);\n\
         for (var c = 0u; c < 6u; c++) {{ output[i * 6u + c] = bitcast<u32>(o[c]); }}",
        dims.view_bins, dims.azimuth_bins, dims.theta_bins, dims.phi_cells, dims.defensive
    );
    let out = run_shader(
        ctx,
        &[&TABLE, &lustre_gpu::material::measured::MEASURED],
        &body,
        &input,
        6 * n,
        n as u32,
        None,
    );
    let f = |w: u32| f64::from(f32::from_bits(w));
    let (mut apart, mut worst_dir, mut worst_pdf, mut off_pdf) = (0, 0.0f64, 0.0f64, 0);
    let (mut edge, mut off_pw, mut worst_pw) = (0, 0, 0.0f64);
    for (k, &(wo, u1, u2, wi)) in cases.iter().enumerate() {
        let o = &out[6 * k..6 * k + 6];
        // The CPU draws from the same f32-rounded numbers the GPU got.
        let (u1, u2) = (f64::from(u1 as f32), f64::from(u2 as f32));
        let wo32 = DVec3::new(
            f64::from(wo.x as f32),
            f64::from(wo.y as f32),
            f64::from(wo.z as f32),
        );
        let cpu = sampler.sample(wo32, u1, u2).expect("wo above the surface");
        assert!(f(o[3]) > 0.0, "case {k}: no sample");
        let gpu = DVec3::new(f(o[0]), f(o[1]), f(o[2]));
        let angle = gpu.normalize().dot(cpu).clamp(-1.0, 1.0).acos();
        if angle > 1e-2 {
            // A target on a cell boundary falls on the other side in f32.
            apart += 1;
            continue;
        }
        worst_dir = worst_dir.max(angle);
        // The density drawn with the sample against the CPU's at its own sample.
        let p = sampler.pdf(cpu, wo32);
        let e = (f(o[3]) - p).abs() / p;
        worst_pdf = worst_pdf.max(e);
        if e > 1e-2 {
            off_pdf += 1;
        }
        // Looked up again from the f32 direction, a draw at a cell's edge may fall into the
        // neighbour (why `tabulated_sample` returns the drawn cell's density).
        if (f(o[4]) - p).abs() > 1e-2 * p {
            edge += 1;
        }
        let pw = sampler.pdf(wi, wo32);
        if pw > 0.0 {
            let e = (f(o[5]) - pw).abs() / pw;
            worst_pw = worst_pw.max(e);
            if e > 1e-2 {
                off_pw += 1;
            }
        }
    }
    eprintln!(
        "{name}: tabulated_sample / tabulated_pdf vs TabulatedSampler on {n} draws: {apart} in \
         another cell, direction within {worst_dir:.2e} rad, the density drawn with the sample \
         within {worst_pdf:.2e} (relative; {off_pdf} off by > 1 %; looked up again from the f32 \
         direction: {edge} off by > 1 %), the density of a random direction: {off_pw} off by > 1 %, worst {worst_pw:.2e}"
    );
    assert!(
        apart * 200 < n,
        "{name}: {apart} of {n} draws in another cell"
    );
    assert!(worst_dir < 2e-3, "{name}: direction {worst_dir:e} rad");
    // A view ωo within f32 rounding of a view bin's edge reads the neighbour's table, and a
    // random direction near a cell's edge the neighbour's density: at most 1 in 1000.
    assert!(
        off_pdf * 1000 <= n,
        "{name}: {off_pdf} of {n} samples' densities off by > 1 % (worst {worst_pdf:e})"
    );
    assert!(
        off_pw * 1000 <= n,
        "{name}: {off_pw} of {n} random directions off by > 1 % (worst {worst_pw:e})"
    );
}

#[test]
fn rgl_eval_matches_the_cpu_on_the_shared_rgl_measurements() {
    // The five RGL tensors of ../shared/data (all isotropic, with the Jacobian flag):
    // `rgl_eval` against RglBsdf::eval, in f32 against f64. The chain (the VNDF warp inverted
    // through f32 CDFs, then the RGB table read at the warped point) loses more than a direct
    // lookup: RMS 0.9–1.9e-3, the worst of 4096 pairs 1–4.5 %.
    let ctx = ctx();
    let mut g = SplitMix64::new(17);
    let n = 4096;
    let pairs = pairs(&mut g, n);
    let dir = lustre_brdf::shared_data_dir().join("measured/rgl");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("measured/rgl")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "bsdf"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 5, "{files:?}");
    for path in files {
        let rgl = RglBsdf::read(&path).expect("RGL file");
        let mut input = words(&pack_rgl(&rgl));
        let q = input.len();
        push_pairs(&mut input, &pairs);
        let out = run_shader(
            &ctx,
            &[&TABLE, &lustre_gpu::material::measured::MEASURED],
            &eval_body(q, "rgl_eval(0u, wi, wo)"),
            &input,
            3 * n,
            n as u32,
            None,
        );
        let cpu: Vec<[f64; 3]> = pairs.iter().map(|&(wi, wo)| rgl.eval(wi, wo).0).collect();
        let (rms, worst) = relative_error(&cpu, &out);
        eprintln!(
            "rgl_eval vs RglBsdf::eval, {} (isotropic {}, reduction {}, Jacobian {}), {n} pairs: relative error RMS {rms:.2e}, worst {worst:.2e}",
            path.file_name().map(|f| f.to_string_lossy()).unwrap_or_default(),
            rgl.is_isotropic(),
            rgl.reduction(),
            rgl.jacobian()
        );
        assert!(
            rms < 4e-3 && worst < 0.1,
            "{path:?}: rms {rms:e}, worst {worst:e}"
        );
    }
}

#[test]
fn alta_eval_matches_the_cpu_on_the_shared_goniometric_measurements() {
    // The two CEA retro-reflection tables (cosine-weighted values; the gray tape's file names no
    // unit, so the test gives it, as `#inv-sr-cos` does): `alta_eval` against AltaTable::eval in
    // f32 against f64, on random pairs, pairs near the mirror direction and pairs near the
    // retro-reflection direction (ωi ≈ ωo), where the tables are densest.
    let ctx = ctx();
    let mut g = SplitMix64::new(23);
    let n = 6144;
    let mut pairs = pairs(&mut g, 2 * n / 3);
    while pairs.len() < n {
        let wo = upper(&mut g);
        let jitter = DVec3::new(g.next_f64() - 0.5, g.next_f64() - 0.5, g.next_f64() - 0.5);
        let wi = (wo + jitter * 0.08 * g.next_f64()).normalize();
        pairs.push((DVec3::new(wi.x, wi.y, wi.z.abs().max(1e-3)).normalize(), wo));
    }
    let dir = lustre_brdf::shared_data_dir().join("measured/goniometric");
    for (file, unit) in [
        (
            "retro-gray-tape.dat",
            Some(AltaUnit::InvSteradianCosineFactor),
        ),
        ("retro-3M-jaune.dat", None),
    ] {
        let alta = AltaTable::read(&dir.join(file), unit).expect("ALTA file");
        let packed = pack_alta(&alta);
        let mut input = words(&packed);
        let q = input.len();
        push_pairs(&mut input, &pairs);
        let out = run_shader(
            &ctx,
            &[&TABLE, &lustre_gpu::material::measured::MEASURED],
            &eval_body(q, "alta_eval(0u, wi, wo)"),
            &input,
            3 * n,
            n as u32,
            None,
        );
        let cpu: Vec<[f64; 3]> = pairs.iter().map(|&(wi, wo)| alta.eval(wi, wo).0).collect();
        let (rms, worst) = relative_error(&cpu, &out);
        let lit = cpu.iter().filter(|c| c[0] > 0.0).count();
        eprintln!(
            "alta_eval vs AltaTable::eval, {file} ({} rows, {} slices, {} words), {n} pairs ({lit} non-zero): relative error RMS {rms:.2e}, worst {worst:.2e}",
            alta.len(),
            alta.theta_l_slices().len(),
            packed.len()
        );
        assert!(lit > n / 2, "{file}: {lit} non-zero values of {n}");
        assert!(
            rms < 2e-4 && worst < 1e-2,
            "{file}: rms {rms:e}, worst {worst:e}"
        );
    }
}
