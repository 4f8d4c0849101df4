//! MERL tables and neural BRDFs on the real data: synthesis → file → read round trip, bad-file
//! messages, an independent re-evaluation of the network from the JSON, and the BSDF battery.

use lustre_brdf::frame::{from_half_diff, spherical, HalfDiff};
use lustre_brdf::measured::merl::{
    bin_center, bin_node, merl_angles, table_from_fn, MerlTable, NegativeValues, BINS,
    CHANNEL_SCALE, FILE_BYTES, RES_PHI_D, RES_THETA_D, RES_THETA_H,
};
use lustre_brdf::measured::nbrdf::{synthesize_merl, Nbrdf, NbrdfSet};
use lustre_brdf::numeric::SphereQuadrature;
use lustre_brdf::{validate, Bsdf, Error, Rgb};
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;
use std::time::Instant;

const MATERIAL: &str = "gold-metallic-paint";

fn merl_json() -> PathBuf {
    lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json")
}

fn set() -> &'static NbrdfSet {
    static SET: OnceLock<NbrdfSet> = OnceLock::new();
    SET.get_or_init(|| NbrdfSet::read(merl_json()).expect("shared MERL nbrdf file loads"))
}

fn net() -> Nbrdf {
    set().material(MATERIAL).expect("material present")
}

/// The synthesized table of `MATERIAL`, shared by the tests of this binary.
fn synth() -> &'static MerlTable {
    static TABLE: OnceLock<MerlTable> = OnceLock::new();
    TABLE.get_or_init(|| {
        let done = AtomicU64::new(0);
        let t0 = Instant::now();
        let table = synthesize_merl(&net(), |n| {
            done.fetch_add(n, Ordering::Relaxed);
        });
        eprintln!(
            "synthesize_merl({MATERIAL}): {:.2} s",
            t0.elapsed().as_secs_f64()
        );
        assert_eq!(
            done.load(Ordering::Relaxed),
            BINS as u64,
            "progress adds up to the bin count"
        );
        table
    })
}

fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    // An absolute floor of 1e-15 /sr for values that the network clamps to (almost) zero.
    (a - b).abs() <= tol * a.abs().max(b.abs()) + 1e-15
}

fn format_problem(e: Error) -> String {
    match e {
        Error::Format { path, problem } => format!("{}: {problem}", path.display()),
        other => panic!("expected a format error, got {other}"),
    }
}

#[test]
fn round_trip_through_a_file_matches_the_network_at_every_bin_node() {
    let table = synth();
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("gold.binary");
    let t0 = Instant::now();
    table.write(&path).expect("write");
    assert_eq!(
        std::fs::metadata(&path).expect("written").len(),
        FILE_BYTES as u64
    );
    let back = MerlTable::read(&path).expect("read back");
    eprintln!("write + read: {:.2} s", t0.elapsed().as_secs_f64());
    assert_eq!(back.name(), "gold");
    assert_eq!(
        back.stored_values(),
        table.stored_values(),
        "f64 storage is exact"
    );
    assert_eq!(back.missing_count(), 0);

    let n = net();
    let t0 = Instant::now();
    let mut worst = 0.0f64;
    for i in 0..RES_THETA_H {
        for j in 0..RES_THETA_D {
            for k in 0..RES_PHI_D {
                // The value of a bin stands for its lower edge (the node): trilinear there is
                // the bin's value; nearest anywhere inside the bin (its centre) too.
                let c = bin_node(i, j, k);
                let m = bin_center(i, j, k);
                let near = back.lookup_nearest(m.theta_h, m.theta_d, m.phi_d);
                let tri = back.lookup_trilinear(c.theta_h, c.theta_d, c.phi_d);
                // The network itself on every 7th bin (it was already run on all by the synthesis).
                let want = if (i + j + k) % 7 == 0 {
                    n.eval_angles(c.theta_h, c.theta_d, c.phi_d)
                } else {
                    back.bin_value(i, j, k)
                };
                for ch in 0..3 {
                    assert!(
                        rel_close(near[ch], want[ch], 1e-12),
                        "nearest ({i},{j},{k}) {near:?} vs {want:?}"
                    );
                    let e = (tri[ch] - want[ch]).abs() / want[ch].abs().max(1e-300);
                    if want[ch] > 0.0 {
                        worst = worst.max(e);
                    }
                    // Rounding of the node's index coordinate leaves a weight of ~1e-14 on a
                    // neighbour (up to 10⁴ times larger near a peak).
                    assert!(
                        rel_close(tri[ch], want[ch], 1e-9),
                        "trilinear ({i},{j},{k}) {tri:?} vs {want:?}"
                    );
                }
            }
        }
    }
    eprintln!(
        "lookups at {} bin nodes: {:.2} s, worst trilinear relative error {worst:.2e}",
        BINS,
        t0.elapsed().as_secs_f64()
    );
}

#[test]
fn synthesized_values_are_the_network_divided_by_the_channel_scales() {
    let table = synth();
    let n = net();
    for &(i, j, k) in &[(0, 0, 0), (5, 40, 90), (89, 89, 179), (30, 10, 3)] {
        let c = bin_node(i, j, k);
        let f = n.eval_angles(c.theta_h, c.theta_d, c.phi_d);
        for ch in 0..3 {
            assert!(rel_close(
                table.stored(ch, i, j, k),
                f[ch] / CHANNEL_SCALE[ch],
                1e-15
            ));
        }
    }
    // Specular peak (θh ≈ 0) far above the grazing-θh floor for a metallic paint.
    assert!(table.bin_value(0, 10, 90)[0] > 10.0 * table.bin_value(80, 10, 90)[0]);
}

/// The network computed from the JSON with plain `Vec` loops, independently of the crate.
fn reference_network(material: &str, x: [f64; 6]) -> [f64; 3] {
    let text = std::fs::read_to_string(merl_json()).expect("read json");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let m = &v["materials"][material];
    let mat = |k: &str| -> Vec<Vec<f64>> {
        m[k].as_array()
            .expect("matrix")
            .iter()
            .map(|r| {
                r.as_array()
                    .expect("row")
                    .iter()
                    .map(|x| x.as_f64().expect("num"))
                    .collect()
            })
            .collect()
    };
    let vecf = |k: &str| -> Vec<f64> {
        m[k].as_array()
            .expect("vec")
            .iter()
            .map(|x| x.as_f64().expect("num"))
            .collect()
    };
    let layer = |inp: &[f64], w: &[Vec<f64>], b: &[f64]| -> Vec<f64> {
        (0..b.len())
            .map(|j| b[j] + (0..inp.len()).map(|i| inp[i] * w[i][j]).sum::<f64>())
            .collect()
    };
    let relu = |v: Vec<f64>| -> Vec<f64> {
        v.into_iter()
            .map(|x| if x > 0.0 { x } else { 0.0 })
            .collect()
    };
    let a1 = relu(layer(&x, &mat("w1"), &vecf("b1")));
    let a2 = relu(layer(&a1, &mat("w2"), &vecf("b2")));
    let z = layer(&a2, &mat("w3"), &vecf("b3"));
    [0, 1, 2].map(|c| f64::max(z[c].exp() - 1.0, 0.0))
}

#[test]
fn network_matches_an_independent_evaluation_from_the_json() {
    for material in ["gold-metallic-paint", "white-diffuse-bball", "chrome"] {
        let n = set().material(material).expect("present");
        for &(th, td, pd) in &[
            (0.0, 0.0, 0.0),
            (0.01, 0.3, 1.0),
            (0.4, 1.2, 2.9),
            (1.5, 1.55, 0.2),
            (0.2, 0.7, 1.6),
        ] {
            let (sh, ch) = f64::sin_cos(th);
            let x = [
                sh,
                0.0,
                ch,
                f64::sin(td) * f64::cos(pd),
                f64::sin(td) * f64::sin(pd),
                f64::cos(td),
            ];
            let want = reference_network(material, x);
            let got = n.eval_angles(th, td, pd);
            for c in 0..3 {
                assert!(
                    rel_close(got[c], want[c], 1e-12),
                    "{material} ({th},{td},{pd}): {got:?} vs {want:?}"
                );
            }
            // Through the Bsdf interface (φd already in [0, π)) with wi, wo from the angles.
            let (wi, wo) = from_half_diff(&HalfDiff {
                theta_h: th,
                phi_h: 0.7,
                theta_d: td,
                phi_d: pd,
            });
            if wi.z > 1e-3 && wo.z > 1e-3 {
                let f = n.eval(wi, wo);
                for c in 0..3 {
                    assert!(
                        rel_close(f[c], want[c], 1e-6),
                        "{material} eval {f:?} vs {want:?}"
                    );
                }
            }
        }
    }
    // A white diffuse ball near normal incidence: Bagher's SGD fit of the same material has
    // rhoD/π ≈ (0.091, 0.076, 0.056) plus a broad lobe, so 0.05..0.4 /sr per channel.
    let w = set()
        .material("white-diffuse-bball")
        .expect("present")
        .eval(spherical(0.1, 0.0), spherical(0.2, 2.0));
    assert!(w.0.iter().all(|&v| (0.05..0.4).contains(&v)), "{w:?}");
}

#[test]
fn all_materials_load() {
    let s = set();
    assert_eq!(s.len(), 100);
    assert!(s.names().contains(&"alum-bronze") && s.names().contains(&"yellow-plastic"));
    for name in s.names() {
        let n = s.material(name).expect("listed");
        let f = n.eval_angles(0.3, 0.5, 1.0);
        assert!(
            f.0.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{name}: {f:?}"
        );
    }
    let rgl = NbrdfSet::read(lustre_brdf::shared_data_dir().join("nbrdf/rgl_isotropic_nbrdf.json"))
        .expect("rgl set");
    assert_eq!(rgl.len(), 49);
    let e = s.material("unobtainium").expect_err("absent");
    assert!(
        matches!(e, Error::NotFound(ref m) if m.contains("unobtainium") && m.contains("merl_nbrdf.json")),
        "{e}"
    );
}

#[test]
fn bad_nbrdf_files_name_file_material_and_problem() {
    let text = std::fs::read_to_string(merl_json()).expect("read");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let check = |v: &serde_json::Value, want: &[&str]| {
        let bytes = serde_json::to_vec(v).expect("serialize");
        let msg = format_problem(NbrdfSet::parse("bad.json", &bytes).expect_err("must fail"));
        assert!(msg.starts_with("bad.json: "), "{msg}");
        for w in want {
            assert!(msg.contains(w), "{msg} lacks {w}");
        }
    };
    let good = v.clone();
    v["format"] = "nbrdf-mlp-v2".into();
    check(&v, &["unknown format 'nbrdf-mlp-v2'"]);
    v = good.clone();
    v["materials"]["chrome"]["w2"]
        .as_array_mut()
        .expect("rows")
        .pop();
    check(&v, &["material 'chrome'", "w2 has 20 rows, expected 21"]);
    v = good.clone();
    v["materials"]["brass"]["w3"][4]
        .as_array_mut()
        .expect("row")
        .push(1.0.into());
    check(&v, &["material 'brass'", "w3[4] has 4 entries, expected 3"]);
    v = good.clone();
    v["materials"]["nickel"]["b1"][3] = "x".into();
    check(&v, &["material 'nickel'", "b1[3] is not a number"]);
    v = good.clone();
    v["materials"]["nickel"]["b3"][0] = 1e300.into();
    check(&v, &["material 'nickel'", "b3[0] = 1e300 is not finite"]);
    v = good.clone();
    v["materials"]["pvc"]
        .as_object_mut()
        .expect("obj")
        .remove("b2");
    check(&v, &["material 'pvc'", "b2 is missing"]);
    v = good;
    v.as_object_mut().expect("obj").remove("materials");
    check(&v, &["no \"materials\" object"]);
    let msg = format_problem(NbrdfSet::parse("t.json", b"{\"format\": ").expect_err("truncated"));
    assert!(msg.contains("not valid JSON"), "{msg}");
    let msg = format_problem(NbrdfSet::parse("t.json", &[0xff, 0x00, 0x13]).expect_err("garbage"));
    assert!(msg.contains("not valid JSON"), "{msg}");
}

/// A valid file of a constant table (stored value 1 everywhere).
fn constant_file() -> Vec<u8> {
    table_from_fn("c", |_, _, _| Rgb(CHANNEL_SCALE))
        .expect("finite")
        .to_bytes()
}

fn put_f64(bytes: &mut [u8], value_index: usize, v: f64) {
    let o = 12 + 8 * value_index;
    bytes[o..o + 8].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn bad_merl_files_give_clear_messages() {
    let good = constant_file();
    assert_eq!(good.len(), FILE_BYTES);
    let err = |b: &[u8]| format_problem(MerlTable::parse("x.binary", b).expect_err("must fail"));

    let m = err(&good[..FILE_BYTES - 1000]);
    assert!(m.starts_with("x.binary: truncated by 1000 bytes"), "{m}");
    let m = err(&good[..12]);
    assert!(
        m.contains(&format!("truncated by {} bytes", FILE_BYTES - 12)),
        "{m}"
    );
    let m = err(&good[..7]);
    assert!(
        m.contains("7 bytes, too short for the 12-byte MERL header"),
        "{m}"
    );
    let m = err(&[]);
    assert!(m.contains("0 bytes"), "{m}");
    let mut longer = good.clone();
    longer.extend_from_slice(&[0; 16]);
    let m = err(&longer);
    assert!(m.contains("16 trailing bytes"), "{m}");

    let mut dims = good.clone();
    dims[8..12].copy_from_slice(&360i32.to_le_bytes());
    let m = err(&dims);
    assert!(
        m.contains("wrong dims in header: (90, 90, 360), expected (90, 90, 180)"),
        "{m}"
    );
    dims[0..4].copy_from_slice(&(-5i32).to_le_bytes());
    assert!(err(&dims).contains("(-5, 90, 360)"));

    let mut nan = good.clone();
    put_f64(&mut nan, BINS + 181, f64::NAN);
    put_f64(&mut nan, 2 * BINS, f64::INFINITY);
    let m = err(&nan);
    assert!(
        m.contains("2 non-finite values") && m.contains("channel 1, bin (0, 1, 1)"),
        "{m}"
    );

    let mut neg = good.clone();
    for n in [5, 6, BINS + 5] {
        put_f64(&mut neg, n, -1.0);
    }
    // Strict reading refuses them, in words a user can act on (no Rust names).
    let m = format_problem(
        MerlTable::parse_with("x.binary", &neg, NegativeValues::Reject).expect_err("strict"),
    );
    assert!(
        m.contains("3 negative values") && m.contains("--strict") && !m.contains("::"),
        "{m}"
    );

    // By default the negatives become missing, evaluate as 0, and are reported.
    let t = MerlTable::parse("x.binary", &neg).expect("missing masked by default");
    assert_eq!(t.missing_count(), 3);
    assert!(t.is_missing(0, 0, 0, 5) && t.is_missing(0, 0, 0, 6) && t.is_missing(1, 0, 0, 5));
    assert!(!t.is_missing(2, 0, 0, 5) && !t.is_missing(0, 0, 0, 4));
    assert_eq!(
        t.missing_mask().map(|m| m.iter().filter(|x| **x).count()),
        Some(3)
    );
    let m5 = bin_center(0, 0, 5);
    let near = t.lookup_nearest(m5.theta_h, m5.theta_d, m5.phi_d);
    assert_eq!(near.0, [0.0, 0.0, CHANNEL_SCALE[2]]);
    // Trilinear between the nodes of bins 5 and 6 (both missing in red) and the rest (present):
    // renormalized over present corners it still returns the constant.
    let (c, c6) = (bin_node(0, 0, 5), bin_node(0, 0, 6));
    let tri = t.lookup_trilinear(c.theta_h, c.theta_d, 0.5 * (c.phi_d + c6.phi_d));
    assert_eq!(tri.0, [0.0, CHANNEL_SCALE[1], CHANNEL_SCALE[2]]);
    let tri = t.lookup_trilinear(
        0.6 * c.theta_h + 0.4 * bin_node(1, 0, 0).theta_h,
        0.01,
        c.phi_d,
    );
    for ch in 0..3 {
        assert!(rel_close(tri[ch], CHANNEL_SCALE[ch], 1e-14), "{tri:?}");
    }
    // Writing marks them negative again; reading back gives the same mask.
    let again =
        MerlTable::parse_with("y.binary", &t.to_bytes(), NegativeValues::Missing).expect("reads");
    assert_eq!(again.missing_mask(), t.missing_mask());

    // A missing file is an I/O error naming it.
    let e = MerlTable::read("/nonexistent/zz.binary").expect_err("absent");
    assert!(e.to_string().contains("/nonexistent/zz.binary"), "{e}");
}

#[test]
fn trilinear_is_continuous_across_the_phi_seam_and_reciprocal() {
    let t = synth();
    for &(th, td) in &[(0.05, 0.3), (0.6, 1.0), (1.2, 0.1)] {
        let a = t.lookup_trilinear(th, td, 1e-9);
        let b = t.lookup_trilinear(th, td, PI - 1e-9);
        let c = t.lookup_trilinear(th, td, -1e-9);
        for ch in 0..3 {
            assert!(
                rel_close(a[ch], b[ch], 1e-6) && rel_close(a[ch], c[ch], 1e-6),
                "{a:?} {b:?} {c:?}"
            );
        }
    }
    // Clamped θ ends: beyond the last node the value is the last bin's.
    let last = t.bin_value(RES_THETA_H - 1, 3, 7);
    let c = bin_node(RES_THETA_H - 1, 3, 7);
    let edge = t.lookup_trilinear(FRAC_PI_2, c.theta_d, c.phi_d);
    for ch in 0..3 {
        assert!(rel_close(edge[ch], last[ch], 1e-12), "{edge:?} vs {last:?}");
    }
    // Swapping wi and wo gives the same folded MERL angles.
    for &(a, b) in &[
        ((0.3, 0.2), (1.1, 2.8)),
        ((1.4, -2.0), (0.1, 0.5)),
        ((0.7, 1.0), (0.7, -1.0)),
    ] {
        let (wi, wo) = (spherical(a.0, a.1), spherical(b.0, b.1));
        let (x, y) = (
            merl_angles(wi, wo).expect("above"),
            merl_angles(wo, wi).expect("above"),
        );
        assert!((x.theta_h - y.theta_h).abs() < 1e-12 && (x.theta_d - y.theta_d).abs() < 1e-12);
        assert!(
            (x.phi_d - y.phi_d).abs() < 1e-9 && (0.0..PI).contains(&x.phi_d),
            "{x:?} {y:?}"
        );
    }
    assert!(merl_angles(spherical(0.3, 0.0), -spherical(0.3, 1.0)).is_none());
    assert!(validate::reciprocity_error(t, 2000, 3) < 1e-6);
    let near = t
        .clone()
        .with_interpolation(lustre_brdf::measured::merl::Interpolation::Nearest);
    assert!(validate::reciprocity_error(&near, 2000, 4) < 1e-6);
    assert!(validate::reciprocity_error(&net(), 2000, 5) < 1e-6);
}

#[test]
fn trilinear_table_approximates_the_network_between_bins() {
    // The table is a sampling of a smooth network: between centres it must stay close to it
    // for a diffuse-ish configuration range (away from the θh ≈ 0 peak).
    let t = synth();
    let n = net();
    let mut rng = lustre_brdf::sampling::SplitMix64::new(11);
    let mut errs = Vec::new();
    let mut worst = (0.0f64, [0.0; 3]);
    for _ in 0..2000 {
        let (th, td, pd) = (
            0.2 + 1.2 * rng.next_f64(),
            1.4 * rng.next_f64(),
            PI * rng.next_f64(),
        );
        let a = t.lookup_trilinear(th, td, pd);
        let b = n.eval_angles(th, td, pd);
        for c in 0..3 {
            let e = (a[c] - b[c]).abs() / b[c].max(1e-3);
            if e > worst.0 {
                worst = (e, [th, td, pd]);
            }
            errs.push(e);
        }
    }
    errs.sort_by(f64::total_cmp);
    let mean = errs.iter().sum::<f64>() / errs.len() as f64;
    let p99 = errs[errs.len() * 99 / 100];
    eprintln!("trilinear vs network off-centre: mean {mean:.2e}, p99 {p99:.2e}, worst {worst:?}");
    assert!(
        mean < 0.01 && p99 < 0.05 && worst.0 < 0.25,
        "{mean} {p99} {worst:?}"
    );
}

#[test]
fn bsdf_battery_for_table_and_network() {
    let t = synth();
    let n = net();
    let q = SphereQuadrature::default();
    let dirs = validate::test_directions();
    let bsdfs: [&dyn Bsdf; 2] = [t, &n];
    for b in bsdfs {
        assert!(b.flags().reciprocal && !b.flags().anisotropic && !b.flags().transmission);
        for (k, &wo) in dirs.iter().enumerate() {
            let integral = validate::pdf_integral(b, wo, &q);
            let frac = validate::sample_success_fraction(b, wo, 20_000, k as u64);
            assert!(
                (integral - frac).abs() < 1e-2,
                "{}: ∫pdf {integral} vs {frac}",
                b.name()
            );
            let r = validate::chi2_test(b, wo, 10, 20_000, 100 + k as u64);
            assert!(r.passed(0.01, dirs.len() * 2), "{}: {r:?}", b.name());
            // Measured gold paint: albedo below 1 at every tested angle.
            let a = validate::albedo_quadrature(b, wo, &q);
            assert!(
                a.iter().all(|&x| x > 0.0 && x < 1.0),
                "{}: albedo {a:?}",
                b.name()
            );
        }
        assert!(b.sample(-dirs[0], 0.3, 0.3).is_none() && b.pdf(dirs[0], -dirs[0]) == 0.0);
        assert_eq!(b.eval(dirs[0], -dirs[1]), Rgb::ZERO);
    }
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig {
        cases: 256,
        failure_persistence: None,
        ..proptest::prelude::ProptestConfig::default()
    })]
    #[test]
    fn finite_everywhere_including_grazing(
        ti in 0.0..FRAC_PI_2, pi in -PI..PI, to in 0.0..FRAC_PI_2, po in -PI..PI,
        th in -1.0..3.0f64, td in -1.0..3.0f64, pd in -7.0..7.0f64,
    ) {
        let (wi, wo) = (spherical(ti, pi), spherical(to, po));
        let n = net();
        let t = synth();
        for f in [n.eval(wi, wo), t.eval(wi, wo), t.lookup_nearest(th, td, pd), t.lookup_trilinear(th, td, pd),
                  n.eval_angles(th, td, pd)] {
            proptest::prop_assert!(f.0.iter().all(|v| v.is_finite() && *v >= 0.0), "{:?}", f);
        }
    }
}

#[test]
fn no_panics_on_odd_angles() {
    let t = synth();
    for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 1e300] {
        let _ = t.lookup_nearest(x, x, x);
        let _ = t.lookup_trilinear(x, 0.3, x);
        let _ = lustre_brdf::measured::merl::nearest_bin(x, x, x);
    }
}
