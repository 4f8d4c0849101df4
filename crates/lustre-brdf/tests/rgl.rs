//! RGL tensor `.bsdf` files: the reader on the five real measurements and on broken inputs, and
//! the measured BSDF (Mitsuba 3 `measured` port) through the validation battery.

use lustre_brdf::frame::{reflect, spherical};
use lustre_brdf::measured::rgl::{
    phi2u, theta2u, u2phi, u2theta, RglBsdf, RglTensorFile, TensorDtype,
};
use lustre_brdf::numeric::{gamma_q, GaussRule, SphereQuadrature};
use lustre_brdf::sampling::{uniform_sphere, SplitMix64};
use lustre_brdf::validate::{
    albedo_quadrature, chi2_test, pdf_integral, sample_success_fraction, test_directions,
};
use lustre_brdf::{Bsdf, DVec3, Error};
use proptest::prelude::*;
use std::f64::consts::PI;
use std::path::PathBuf;
use std::sync::OnceLock;

const FILES: [&str; 5] = [
    "cc_ibiza_sunset_rgb",
    "cg_sunflower_rgb",
    "colodur_napoli_4f_rgb",
    "paper_white_rgb",
    "vch_golden_yellow_rgb",
];

fn path(name: &str) -> PathBuf {
    lustre_brdf::shared_data_dir()
        .join("measured/rgl")
        .join(format!("{name}.bsdf"))
}

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(path(name)).expect("shared RGL data present")
}

/// All five materials, loaded once per test binary.
fn all() -> &'static [(String, RglBsdf)] {
    static CELL: OnceLock<Vec<(String, RglBsdf)>> = OnceLock::new();
    CELL.get_or_init(|| {
        FILES
            .iter()
            .map(|n| {
                (
                    n.to_string(),
                    RglBsdf::read(path(n)).expect("real file loads"),
                )
            })
            .collect()
    })
}

fn material(name: &str) -> &'static RglBsdf {
    &all()
        .iter()
        .find(|(n, _)| n == name)
        .expect("known material")
        .1
}

#[test]
fn real_files_parse_with_expected_fields() {
    let names = [
        "version",
        "description",
        "phi_i",
        "theta_i",
        "sigma",
        "ndf",
        "vndf",
        "luminance",
        "rgb",
        "jacobian",
        "valid",
    ];
    for name in FILES {
        let t = RglTensorFile::read(path(name)).expect("parses");
        assert_eq!(t.version(), (1, 0));
        let got: Vec<&str> = t.fields().iter().map(|f| f.name.as_str()).collect();
        assert_eq!(got, names, "{name}");
        let n = if name == "cg_sunflower_rgb" { 64 } else { 32 };
        let shape = |f: &str| t.field(f).expect("present").shape.clone();
        let dtype = |f: &str| t.field(f).expect("present").dtype;
        assert_eq!(shape("version"), [2]);
        assert_eq!(dtype("version"), TensorDtype::UInt32);
        assert_eq!(t.field("version").expect("present").to_f64(), [1.0, 0.0]);
        assert_eq!(shape("phi_i"), [1]);
        assert_eq!(shape("theta_i"), [8]);
        assert_eq!(shape("sigma"), [2, 128]);
        assert_eq!(shape("ndf"), [2, 128]);
        assert_eq!(shape("vndf"), [1, 8, 128, 128]);
        assert_eq!(shape("luminance"), [1, 8, n, n]);
        assert_eq!(shape("rgb"), [1, 8, 3, n, n]);
        assert_eq!(shape("jacobian"), [1]);
        assert_eq!(shape("valid"), [n * n]);
        for f in [
            "theta_i",
            "phi_i",
            "sigma",
            "ndf",
            "vndf",
            "luminance",
            "rgb",
        ] {
            assert_eq!(dtype(f), TensorDtype::Float32, "{name} {f}");
        }
        assert_eq!(dtype("description"), TensorDtype::UInt8);
        let b = material(name);
        assert!(
            b.is_isotropic() && b.jacobian() && b.reduction() == 1,
            "{name}"
        );
        assert!(!b.flags().anisotropic && !b.flags().reciprocal && !b.flags().transmission);
        let th = b.theta_i();
        assert!(th[0] == 0.0 && (th[7] - PI / 2.0).abs() < 1e-6, "{th:?}");
        eprintln!("{name}: \"{}\"", b.description());
    }
    assert_eq!(
        material("paper_white_rgb").description(),
        "White A4 paper (160 gsm)"
    );
}

#[test]
fn eval_and_pdf_finite_and_non_negative() {
    for (name, b) in all() {
        let mut rng = SplitMix64::new(11);
        for k in 0..3000 {
            let mut a = uniform_sphere(rng.next_f64(), rng.next_f64());
            let mut o = uniform_sphere(rng.next_f64(), rng.next_f64());
            // Every third pair grazing, and some exactly at or below the horizon.
            if k % 3 == 0 {
                a.z = 10f64.powf(-1.0 - 8.0 * rng.next_f64());
                o.z = o.z.abs() * 1e-3;
            }
            if k % 50 == 0 {
                a.z = 0.0;
            }
            let (a, o) = (a.normalize(), o.normalize());
            let f = b.eval(a, o);
            let p = b.pdf(a, o);
            assert!(
                f.is_finite() && f.min_component() >= 0.0,
                "{name}: f({a}, {o}) = {f:?}"
            );
            assert!(p.is_finite() && p >= 0.0, "{name}: pdf({a}, {o}) = {p}");
            if a.z <= 0.0 || o.z <= 0.0 {
                assert_eq!(p, 0.0);
                assert_eq!(f.max_component(), 0.0);
            }
            if let Some(s) = b.sample(o, rng.next_f64(), rng.next_f64()) {
                assert!(s.wi.z > 0.0 && (s.wi.length() - 1.0).abs() < 1e-9);
                assert!(s.value.is_finite() && s.pdf.is_finite() && s.pdf > 0.0);
            }
        }
    }
}

/// ∫ D(h) cos θh dωh over the hemisphere (with θ = u² π/2, panels on the table's nodes).
fn ndf_projected_integral(b: &RglBsdf) -> f64 {
    let rule = GaussRule::new(4);
    let grid = b.ndf_grid();
    let n = grid.theta.len() - 1;
    rule.integrate(-PI, PI, 4, |phi| {
        rule.integrate(0.0, 1.0, n, |u| {
            let t = u2theta(u);
            b.ndf(t, phi) * t.cos() * t.sin() * PI * u
        })
    })
}

/// σ(ω) = ∫ D(h) max(0, ω·h) dωh by quadrature over the hemisphere of h.
fn projected_area(b: &RglBsdf, theta: f64) -> f64 {
    let rule = GaussRule::new(4);
    let w = spherical(theta, 0.0);
    let n = b.ndf_grid().theta.len() - 1;
    rule.integrate(-PI, PI, 64, |phi| {
        rule.integrate(0.0, 1.0, n, |u| {
            let t = u2theta(u);
            b.ndf(t, phi) * w.dot(spherical(t, phi)).max(0.0) * t.sin() * PI * u
        })
    })
}

#[test]
fn ndf_is_normalized_and_sigma_is_its_projected_area() {
    for (name, b) in all() {
        let norm = ndf_projected_integral(b);
        let grid = b.ndf_grid();
        assert_eq!(grid.values.len(), grid.theta.len() * grid.phi.len());
        assert!(grid.values.iter().all(|v| v.is_finite() && *v >= 0.0));
        let mut line = format!("{name}: ∫D cos = {norm:.5}, D(0) = {:.4}", b.ndf(0.0, 0.0));
        // The bilinear interpolant of every file's table gives 1.008 ± 0.001: the files were
        // normalized on a slightly different discretization (σ(0) = 1 in the tables likewise).
        assert!((norm - 1.0).abs() < 0.015, "{line}");
        for &t in &[0.0, 0.5, 1.0, 1.3, 1.5] {
            let direct = projected_area(b, t);
            let table = b.sigma(t, 0.0);
            line += &format!("; σ({t}) table {table:.4} vs ∫ {direct:.4}");
            assert!((direct - table).abs() < 0.02 * table.max(0.1), "{line}");
        }
        eprintln!("{line}");
    }
}

#[test]
fn albedo_at_normal_incidence() {
    let q = SphereQuadrature::default();
    for (name, b) in all() {
        let quad = albedo_quadrature(b, DVec3::Z, &q);
        let mc = b.albedo(DVec3::Z, 20_000);
        eprintln!(
            "{name}: albedo(normal) quadrature [{:.4}, {:.4}, {:.4}], sampled [{:.4}, {:.4}, {:.4}]",
            quad[0], quad[1], quad[2], mc[0], mc[1], mc[2]
        );
        for c in 0..3 {
            assert!(quad[c] > 0.0 && quad[c] <= 1.0, "{name}: {quad:?}");
            assert!(
                (mc[c] - quad[c]).abs() < 0.02 * quad[c] + 3e-3,
                "{name}: {mc:?} vs {quad:?}"
            );
        }
    }
    let paper = albedo_quadrature(material("paper_white_rgb"), DVec3::Z, &q);
    assert!(paper.iter().all(|&a| (0.6..=1.0).contains(&a)), "{paper:?}");
    let yellow = albedo_quadrature(material("vch_golden_yellow_rgb"), DVec3::Z, &q);
    assert!(
        yellow[2] < 0.2 * yellow[0] && yellow[1] < yellow[0],
        "{yellow:?}"
    );
}

#[test]
fn pdf_integrates_to_sample_success_fraction() {
    let q = SphereQuadrature::default();
    let dirs = test_directions();
    for (name, b) in all() {
        for &wo in &[dirs[0], dirs[2], dirs[4]] {
            let int = pdf_integral(b, wo, &q);
            let frac = sample_success_fraction(b, wo, 50_000, 5);
            assert!(
                (int - frac).abs() < 4e-3,
                "{name} θo={:.2}: ∫pdf {int} vs {frac}",
                wo.z.acos()
            );
            assert!(int <= 1.0 + 1e-3);
        }
    }
}

/// Mitsuba's chi-square test as the battery runs it, on a (cos θ, φ) grid of wi, for all five
/// files at every test direction. Sunflower's lobe (D(0) = 600) and the grazing lobes of the vinyl
/// films defeated the battery's former fixed cell quadrature (cell sums of ∫pdf 1.011 and 1.081
/// against 0.999 and 0.991 for sunflower at θo = 1.30 and 1.52); its adaptive cubature matches
/// the lobe-centred ∫pdf to 1e-4 (measured p-values for sunflower 0.07 to 0.80).
#[test]
fn chi2_battery() {
    let dirs = test_directions();
    let n = FILES.len() * dirs.len();
    for (name, b) in all() {
        for (k, &wo) in dirs.iter().enumerate() {
            let r = chi2_test(b, wo, 10, 40_000, 17 + k as u64);
            eprintln!(
                "{name} θo={:.2}: p = {:.3}, ∫pdf {:.4}, fraction {:.4}",
                wo.z.acos(),
                r.p_value,
                r.pdf_integral,
                r.sample_fraction
            );
            assert!(r.passed(0.01, n), "{name} θo={:.2}: {r:?}", wo.z.acos());
        }
    }
}

/// Chi-square test in the coordinates the sampler works in (a second, finer view of the lobe than
/// the wi grid of `chi2_battery`): the half vector m of (wi, wo) as
/// u = (√(2θm/π), (φm − φo + π)/2π). Expected counts integrate pdf(wi)·|dωi/du| =
/// pdf·4(wo·m)·2π² u_x sin θm over each cell, which the adaptive parameterization keeps smooth
/// however narrow the lobe is in solid angle. Returns (p-value, ∫pdf, success fraction).
fn chi2_half_vector(
    b: &RglBsdf,
    wo: DVec3,
    res: usize,
    samples: usize,
    seed: u64,
) -> (f64, f64, f64) {
    let phi_o = wo.y.atan2(wo.x);
    let to_u = |wi: DVec3| -> Option<(f64, f64)> {
        let m = (wi + wo).try_normalize()?;
        let u = phi2u(m.y.atan2(m.x) - phi_o);
        Some((theta2u(m.z.clamp(-1.0, 1.0).acos()), u - u.floor()))
    };
    let mut hist = vec![0.0; res * res];
    let mut rng = SplitMix64::new(seed);
    let mut ok = 0usize;
    for _ in 0..samples {
        if let Some(s) = b.sample(wo, rng.next_f64(), rng.next_f64()) {
            let (ux, uy) = to_u(s.wi).expect("sampled wi is not opposite to wo");
            let i = ((ux * res as f64) as usize).min(res - 1);
            let j = ((uy * res as f64) as usize).min(res - 1);
            hist[j * res + i] += 1.0;
            ok += 1;
        }
    }
    let rule = GaussRule::new(5);
    let density = |ux: f64, uy: f64| {
        let (t, p) = (u2theta(ux), u2phi(uy) + phi_o);
        let m = spherical(t, p);
        let wi = reflect(wo, m);
        if wi.z <= 0.0 || wo.dot(m) <= 0.0 {
            return 0.0;
        }
        b.pdf(wi, wo) * 4.0 * wo.dot(m) * 2.0 * PI * PI * ux * t.sin()
    };
    let h = 1.0 / res as f64;
    let mut expected = vec![0.0; res * res];
    for j in 0..res {
        for i in 0..res {
            let (x0, y0) = (i as f64 * h, j as f64 * h);
            expected[j * res + i] = samples as f64
                * rule.integrate(y0, y0 + h, 4, |y| {
                    rule.integrate(x0, x0 + h, 4, |x| density(x, y))
                });
        }
    }
    let integral = expected.iter().sum::<f64>() / samples as f64;
    let mut order: Vec<usize> = (0..res * res).collect();
    order.sort_by(|&a, &c| expected[a].total_cmp(&expected[c]));
    let (mut pe, mut po, mut stat, mut dof) = (0.0, 0.0, 0.0, 0usize);
    for i in order {
        if expected[i] < 5.0 {
            pe += expected[i];
            po += hist[i];
            if pe >= 5.0 {
                stat += (po - pe) * (po - pe) / pe;
                dof += 1;
                pe = 0.0;
                po = 0.0;
            }
        } else {
            stat += (hist[i] - expected[i]).powi(2) / expected[i];
            dof += 1;
        }
    }
    if pe > 0.0 {
        stat += (po - pe) * (po - pe) / pe;
        dof += 1;
    }
    let p = gamma_q((dof.saturating_sub(1).max(1)) as f64 / 2.0, stat / 2.0);
    (p, integral, ok as f64 / samples as f64)
}

#[test]
fn chi2_half_vector_all_files_and_directions() {
    let dirs = test_directions();
    let n_tests = FILES.len() * dirs.len();
    let alpha = 1.0 - (1.0 - 0.01f64).powf(1.0 / n_tests as f64);
    for (name, b) in all() {
        for &wo in &dirs {
            let (p, int, frac) = chi2_half_vector(b, wo, 12, 40_000, 23);
            eprintln!(
                "{name} θo={:.2}: half-vector chi2 p = {p:.3}, ∫pdf {int:.4}, fraction {frac:.4}",
                wo.z.acos()
            );
            assert!(p > alpha, "{name} θo={:.2}: p = {p}", wo.z.acos());
            assert!((int - frac).abs() < 5e-3, "{name}: {int} vs {frac}");
        }
    }
}

/// f at a configuration chosen so that the warps land on table nodes, computed directly from
/// the raw tables (trapezoid CDF of one vndf row, linear rgb interpolation along one row).
#[test]
fn known_value_from_raw_tables() {
    for name in ["paper_white_rgb", "vch_golden_yellow_rgb"] {
        let t = RglTensorFile::read(path(name)).expect("parses");
        let b = material(name);
        let raw = |f: &str| t.field(f).expect("present").to_f64();
        let (theta_i, vndf, rgb, ndf, sigma) = (
            raw("theta_i"),
            raw("vndf"),
            raw("rgb"),
            raw("ndf"),
            raw("sigma"),
        );
        let n = t.field("rgb").expect("present").shape[4];
        let k = 2; // θi node
        let j = 40; // θm node of the 128-wide vndf/ndf grids
        let wo = spherical(theta_i[k], 0.0);
        // m at u = (j/127, 0): θm on node j, φm = φo − π.
        let m = spherical(u2theta(j as f64 / 127.0), -PI);
        let wi = reflect(wo, m);
        assert!(wi.z > 0.0);
        // vndf slice (φ node 0, θ node k), row 0: conditional CDF at node j.
        let row = &vndf[k * 128 * 128..k * 128 * 128 + 128];
        let cum = |x: usize| (0..x).map(|i| 0.5 * (row[i] + row[i + 1])).sum::<f64>();
        let sx = cum(j) / cum(127);
        // rgb slice (0, k, c), row 0, linear in x.
        let xs = sx * (n - 1) as f64;
        let (i0, fx) = (xs.floor() as usize, xs - xs.floor());
        let mut expect = [0.0; 3];
        let sig_x = theta2u(theta_i[k]) * 127.0;
        let (s0, sf) = (sig_x.floor() as usize, sig_x - sig_x.floor());
        let sig = sigma[s0] * (1.0 - sf) + sigma[s0 + 1] * sf;
        for (c, e) in expect.iter_mut().enumerate() {
            let base = (k * 3 + c) * n * n;
            let v = rgb[base + i0] * (1.0 - fx) + rgb[base + i0 + 1] * fx;
            *e = v.max(0.0) * ndf[j] / (4.0 * sig) / wi.z;
        }
        let f = b.eval(wi, wo);
        eprintln!("{name}: f = {f:?}, from the raw tables {expect:?}");
        for c in 0..3 {
            assert!(
                (f[c] - expect[c]).abs() < 1e-6 * expect[c].abs() + 1e-9,
                "{name} {c}: {f:?} vs {expect:?}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Bad input

/// A tensor file from (name, dtype code, shape, data) entries, data laid out after the header.
fn tensor_bytes(fields: &[(&str, u8, Vec<u64>, Vec<u8>)]) -> Vec<u8> {
    let header_len: usize = 18
        + fields
            .iter()
            .map(|(n, _, s, _)| 2 + n.len() + 2 + 1 + 8 + 8 * s.len())
            .sum::<usize>();
    let mut out = b"tensor_file\0".to_vec();
    out.extend([1u8, 0]);
    out.extend((fields.len() as u32).to_le_bytes());
    let mut offset = header_len as u64;
    for (name, dtype, shape, data) in fields {
        out.extend((name.len() as u16).to_le_bytes());
        out.extend(name.as_bytes());
        out.extend((shape.len() as u16).to_le_bytes());
        out.push(*dtype);
        out.extend(offset.to_le_bytes());
        for d in shape {
            out.extend(d.to_le_bytes());
        }
        offset += data.len() as u64;
    }
    for (_, _, _, data) in fields {
        out.extend(data);
    }
    out
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn format_error(r: Result<RglTensorFile, Error>) -> String {
    match r {
        Err(e @ Error::Format { .. }) => {
            let s = e.to_string();
            assert!(s.contains("bad.bsdf"), "error does not name the file: {s}");
            s
        }
        Err(e) => panic!("expected a format error, got {e}"),
        Ok(_) => panic!("expected an error"),
    }
}

#[test]
fn truncated_files_are_errors() {
    let b = bytes("paper_white_rgb");
    for len in [0, 5, 12, 13, 17, 18, 25, 100, 411, 412, 5000, b.len() - 1] {
        let e = format_error(RglTensorFile::parse("bad.bsdf", &b[..len]));
        assert!(
            e.contains("too short")
                || e.contains("truncated")
                || e.contains("beyond the end")
                || e.contains("fields but only"),
            "{len}: {e}"
        );
        assert!(RglBsdf::parse("bad.bsdf", &b[..len]).is_err());
    }
}

#[test]
fn header_corruptions_are_errors() {
    let b = bytes("paper_white_rgb");
    let mut m = b.clone();
    m[0] = b'T';
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &m)).contains("magic"));
    let mut m = b.clone();
    m[12] = 2;
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &m)).contains("version 2.0"));
    // First field ("version"): name length at 18, name at 20..27, rank 27, dtype 29, offset 30.
    let mut m = b.clone();
    m[30..38].copy_from_slice(&(b.len() as u64).to_le_bytes());
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &m)).contains("beyond the end"));
    let mut m = b.clone();
    m[30..38].copy_from_slice(&(u64::MAX - 3).to_le_bytes());
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &m)).contains("beyond the end"));
    let mut m = b.clone();
    m[29] = 12;
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &m)).contains("unknown dtype"));
    let mut m = b.clone();
    m[14..18].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &m)).contains("fields but only"));
}

#[test]
fn absurd_shapes_are_errors() {
    // Dimensions whose product overflows, and a product that fits but exceeds the file.
    let huge = tensor_bytes(&[("x", 10, vec![1 << 40, 1 << 40], vec![0; 16])]);
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &huge)).contains("overflows"));
    let big = tensor_bytes(&[("x", 10, vec![1 << 20, 1 << 20], vec![0; 16])]);
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &big)).contains("beyond the end"));
    let ranky = {
        let mut v = tensor_bytes(&[("x", 10, vec![2], vec![0; 8])]);
        v[21..23].copy_from_slice(&u16::MAX.to_le_bytes()); // rank 65535, no room for the shape
        v
    };
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &ranky)).contains("truncated"));
    // Overlapping data and duplicate names.
    let dup = tensor_bytes(&[("a", 1, vec![4], vec![0; 4]), ("a", 1, vec![4], vec![0; 4])]);
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &dup)).contains("twice"));
    let two = tensor_bytes(&[("a", 1, vec![4], vec![0; 4]), ("b", 1, vec![8], vec![0; 4])]);
    let mut overlap = two.clone();
    // Point "b" (offset field at 18 + 22 + 2 + 1 + 2 + 1 = 46) at "a"'s data.
    let a_off = u64::from_le_bytes(two[24..32].try_into().expect("8 bytes"));
    overlap[46..54].copy_from_slice(&a_off.to_le_bytes());
    assert!(format_error(RglTensorFile::parse("bad.bsdf", &overlap)).contains("overlap"));
    // A well-formed small file parses, including half floats.
    let ok = tensor_bytes(&[
        ("h", 9, vec![2], vec![0x00, 0x3c, 0x00, 0xc0]),
        ("f", 10, vec![1], f32s(&[2.5])),
    ]);
    let t = RglTensorFile::parse("bad.bsdf", &ok).expect("valid");
    assert_eq!(t.field("h").expect("present").to_f64(), [1.0, -2.0]);
    assert_eq!(t.field("f").expect("present").to_f64(), [2.5]);
    assert!(RglBsdf::from_tensor(&t).is_err());
}

#[test]
fn bad_values_are_errors_naming_the_field() {
    let b = bytes("paper_white_rgb");
    let t = RglTensorFile::parse("bad.bsdf", &b).expect("valid");
    let at = |f: &str, i: usize| t.field(f).expect("present").offset as usize + 4 * i;
    for (field, value, what) in [
        ("vndf", f32::NAN, "NaN"),
        ("rgb", f32::INFINITY, "inf"),
        ("ndf", -1.0, "negative"),
        ("luminance", -0.5, "negative"),
        ("theta_i", f32::NEG_INFINITY, "inf"),
    ] {
        let mut m = b.clone();
        let o = at(field, 7);
        m[o..o + 4].copy_from_slice(&value.to_le_bytes());
        let e = format_error(RglTensorFile::parse("bad.bsdf", &m));
        assert!(
            e.contains(&format!("\"{field}\"")) && e.contains(what),
            "{e}"
        );
    }
    // Negative rgb values (out-of-gamut colours) are legal: the real files have them.
    let mut m = b.clone();
    let o = at("rgb", 3);
    m[o..o + 4].copy_from_slice(&(-0.01f32).to_le_bytes());
    assert!(RglBsdf::parse("bad.bsdf", &m).is_ok());
    // θi nodes out of order.
    let mut m = b.clone();
    let o = at("theta_i", 1);
    m[o..o + 4].copy_from_slice(&(-1.0f32).to_le_bytes());
    let e = RglBsdf::parse("bad.bsdf", &m)
        .expect_err("rejected")
        .to_string();
    assert!(e.contains("vndf") && e.contains("increasing"), "{e}");
}

#[test]
fn structural_problems_are_clear_errors() {
    let tiny = |extra: Vec<(&'static str, u8, Vec<u64>, Vec<u8>)>| {
        let mut v = vec![("description", 1, vec![1], b"x".to_vec())];
        v.extend(extra);
        tensor_bytes(&v)
    };
    let e = RglBsdf::parse("bad.bsdf", &tiny(vec![]))
        .expect_err("rejected")
        .to_string();
    assert!(
        e.contains("bad.bsdf") && e.contains("\"theta_i\" is missing"),
        "{e}"
    );
    let spectral = tiny(vec![
        ("spectra", 10, vec![1, 1, 2, 2, 2], f32s(&[1.0; 8])),
        ("wavelengths", 10, vec![2], f32s(&[400.0, 500.0])),
    ]);
    let e = RglBsdf::parse("bad.bsdf", &spectral)
        .expect_err("rejected")
        .to_string();
    assert!(e.contains("spectral") && e.contains("2 wavelengths"), "{e}");
    let wrong_type = tiny(vec![("theta_i", 11, vec![1], vec![0; 8])]);
    let e = RglBsdf::parse("bad.bsdf", &wrong_type)
        .expect_err("rejected")
        .to_string();
    assert!(e.contains("theta_i") && e.contains("f64"), "{e}");
    let e = RglBsdf::read("/nonexistent/bad.bsdf")
        .expect_err("no file")
        .to_string();
    assert!(e.contains("bad.bsdf"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, failure_persistence: None, ..ProptestConfig::default() })]

    /// Random byte mutations of a real file's header region never panic the reader.
    #[test]
    fn mutated_headers_never_panic(edits in prop::collection::vec((0usize..420, any::<u8>()), 1..8), cut in 0usize..2) {
        static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
        let b = BYTES.get_or_init(|| bytes("paper_white_rgb"));
        let mut m = b.clone();
        for (i, v) in edits {
            m[i] = v;
        }
        if cut == 1 {
            m.truncate(2000);
        }
        if let Ok(t) = RglTensorFile::parse("mutant.bsdf", &m) {
            if let Ok(bsdf) = RglBsdf::from_tensor(&t) {
                let f = bsdf.eval(spherical(0.3, 0.2), spherical(0.5, 2.0));
                prop_assert!(f.is_finite());
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Anisotropic layout (no real anisotropic file is available): paper_white's tables replicated
// over several φi nodes. The φ axis of the vndf/rgb tables then means absolute φm instead of
// φm − φi, so the material differs from the isotropic one except at φo = 0, where both agree.

fn synthetic_anisotropic(phi: &[f32]) -> Vec<u8> {
    let t = RglTensorFile::read(path("paper_white_rgb")).expect("parses");
    let f = |n: &str| t.field(n).expect("present");
    let rep = |n: &'static str| {
        let field = f(n);
        let mut shape: Vec<u64> = field.shape.iter().map(|&d| d as u64).collect();
        shape[0] = phi.len() as u64;
        let data = field.data.repeat(phi.len());
        (n, 10u8, shape, data)
    };
    let keep = |n: &'static str| {
        let field = f(n);
        let code = if field.dtype == TensorDtype::UInt8 {
            1
        } else {
            10
        };
        (
            n,
            code,
            field.shape.iter().map(|&d| d as u64).collect(),
            field.data.clone(),
        )
    };
    tensor_bytes(&[
        keep("description"),
        ("phi_i", 10, vec![phi.len() as u64], f32s(phi)),
        keep("theta_i"),
        keep("sigma"),
        keep("ndf"),
        rep("vndf"),
        rep("luminance"),
        rep("rgb"),
        keep("jacobian"),
    ])
}

#[test]
fn anisotropic_layout_and_symmetry_reductions() {
    use std::f32::consts::PI as P;
    let iso = material("paper_white_rgb");
    let aniso = RglBsdf::parse("aniso.bsdf", &synthetic_anisotropic(&[-P, 0.0, P])).expect("valid");
    assert!(!aniso.is_isotropic() && aniso.reduction() == 1 && aniso.flags().anisotropic);
    let mut rng = SplitMix64::new(3);
    for _ in 0..200 {
        let wo = spherical(1.4 * rng.next_f64(), 0.0);
        let mut wi = uniform_sphere(rng.next_f64(), rng.next_f64());
        wi.z = wi.z.abs();
        let (a, b) = (aniso.eval(wi, wo), iso.eval(wi, wo));
        for c in 0..3 {
            assert!(
                (a[c] - b[c]).abs() <= 1e-9 * b[c].max(1e-3),
                "{a:?} vs {b:?}"
            );
        }
        assert!((aniso.pdf(wi, wo) - iso.pdf(wi, wo)).abs() <= 1e-9 * iso.pdf(wi, wo).max(1e-3));
    }
    // Away from φo = 0 the two differ, and the anisotropic sampler still matches its pdf.
    let wo = spherical(0.7, 1.2);
    let wi = spherical(0.5, -2.0);
    assert!((aniso.eval(wi, wo)[0] - iso.eval(wi, wo)[0]).abs() > 1e-6);

    let half =
        RglBsdf::parse("r2.bsdf", &synthetic_anisotropic(&[-P, -P / 2.0, 0.0])).expect("valid");
    assert_eq!(half.reduction(), 2);
    let quarter = RglBsdf::parse(
        "r4.bsdf",
        &synthetic_anisotropic(&[-P, -0.75 * P, -P / 2.0]),
    )
    .expect("valid");
    assert_eq!(quarter.reduction(), 4);
    let e = RglBsdf::parse(
        "bad.bsdf",
        &synthetic_anisotropic(&[-P, -P + 1.0, -P + 2.0]),
    )
    .expect_err("reduction 3")
    .to_string();
    assert!(e.contains("bad.bsdf") && e.contains("reduction"), "{e}");
    // Symmetries the reductions impose (Mitsuba folds with sx = sy = sign(wo.y) for 2, i.e. a
    // half turn about the normal; with sx = sign(wo.x), sy = sign(wo.y) for 4, two mirrors).
    let my = |w: DVec3| DVec3::new(w.x, -w.y, w.z);
    let rot = |w: DVec3| DVec3::new(-w.x, -w.y, w.z);
    let mx = |w: DVec3| DVec3::new(-w.x, w.y, w.z);
    for _ in 0..200 {
        let mut wo = uniform_sphere(rng.next_f64(), rng.next_f64());
        let mut wi = uniform_sphere(rng.next_f64(), rng.next_f64());
        wo.z = wo.z.abs();
        wi.z = wi.z.abs();
        let close = |a: lustre_brdf::Rgb, b: lustre_brdf::Rgb| {
            (0..3).all(|c| (a[c] - b[c]).abs() <= 1e-9 * a[c].max(b[c]).max(1e-3))
        };
        assert!(close(half.eval(wi, wo), half.eval(rot(wi), rot(wo))));
        assert!(
            (half.pdf(wi, wo) - half.pdf(rot(wi), rot(wo))).abs()
                <= 1e-9 * half.pdf(wi, wo).max(1e-3)
        );
        assert!(close(quarter.eval(wi, wo), quarter.eval(mx(wi), mx(wo))));
        assert!(close(quarter.eval(wi, wo), quarter.eval(my(wi), my(wo))));
    }
    let q = SphereQuadrature::default();
    for (name, b) in [
        ("aniso", &aniso),
        ("reduction 2", &half),
        ("reduction 4", &quarter),
    ] {
        for wo in [spherical(0.6, 1.2), spherical(1.1, -2.5)] {
            let (p, int, frac) = chi2_half_vector(b, wo, 12, 40_000, 29);
            let pint = pdf_integral(b, wo, &q);
            eprintln!(
                "{name} θo={:.1}: p = {p:.3}, ∫pdf {int:.4} / {pint:.4}, fraction {frac:.4}",
                wo.z.acos()
            );
            assert!(
                p > 1e-3 && (pint - frac).abs() < 5e-3,
                "{name}: p = {p}, {pint} vs {frac}"
            );
        }
    }
}
