//! Reader edge cases: synthetic .hdr/.exr files, truncation, wrong magic, bad shapes,
//! non-finite and negative texels, and random corruption (never a panic).

use lustre_env::{parse_exr, parse_hdr, read_map, shared_data_dir, EnvError};
use proptest::prelude::*;
use std::io::Cursor;
use std::path::Path;

/// A flat (non-RLE) Radiance file of w×h pixels, all (r, g, b, e).
fn hdr_bytes(w: usize, h: usize, rgbe: [u8; 4]) -> Vec<u8> {
    let mut b = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
    for _ in 0..w * h {
        b.extend_from_slice(&rgbe);
    }
    b
}

/// An OpenEXR file (f32 RGB, default compression) with pixel values from `f`.
fn exr_bytes(w: usize, h: usize, f: impl Fn(usize, usize) -> (f32, f32, f32) + Sync) -> Vec<u8> {
    use exr::prelude::*;
    let img = Image::from_channels(
        (w, h),
        SpecificChannels::rgb(|p: Vec2<usize>| f(p.x(), p.y())),
    );
    let mut buf = Cursor::new(Vec::new());
    img.write().to_buffered(&mut buf).unwrap();
    buf.into_inner()
}

fn problem(e: EnvError) -> String {
    match e {
        EnvError::Format { problem, .. } => problem,
        other => panic!("expected a Format error, got {other}"),
    }
}

#[test]
fn synthetic_hdr_decodes_to_the_expected_value() {
    let p = Path::new("mem.hdr");
    // RGBE (128, 64, 32, 129): mantissa/256 · 2^(129−128) = (1, ½, ¼).
    let m = parse_hdr(p, &hdr_bytes(8, 4, [128, 64, 32, 129])).unwrap();
    assert_eq!(
        (m.map.width, m.map.height, m.nonfinite, m.negative),
        (8, 4, 0, 0)
    );
    for v in &m.map.data {
        assert!(
            (v[0] - 1.0).abs() < 1e-6 && (v[1] - 0.5).abs() < 1e-6 && (v[2] - 0.25).abs() < 1e-6,
            "{v:?}"
        );
    }
}

#[test]
fn hdr_shape_and_truncation_errors() {
    let p = Path::new("mem.hdr");
    let e = problem(parse_hdr(p, &hdr_bytes(4, 3, [1, 1, 1, 128])).unwrap_err());
    assert!(e.contains("2 × height"), "{e}");
    assert!(parse_hdr(p, &hdr_bytes(0, 0, [1, 1, 1, 128])).is_err());
    // A 2×1 or 4×2 image is no environment map.
    for (w, h) in [(2, 1), (4, 2)] {
        let e = problem(parse_hdr(p, &hdr_bytes(w, h, [128, 64, 32, 129])).unwrap_err());
        assert!(e.contains("too small") && e.contains("8×4"), "{e}");
    }
    let mut t = hdr_bytes(8, 4, [1, 1, 1, 128]);
    t.truncate(t.len() - 20);
    let e = parse_hdr(p, &t).unwrap_err().to_string();
    assert!(e.contains("mem.hdr"), "{e}");
    let e = problem(parse_hdr(p, b"").unwrap_err());
    assert!(e.contains("empty"), "{e}");
    let e = problem(parse_hdr(p, b"P6 not hdr").unwrap_err());
    assert!(e.contains("magic"), "{e}");
    // A real file cut in half.
    let real = std::fs::read(shared_data_dir().join("envmaps/spot1Lux.hdr")).unwrap();
    assert!(parse_hdr(p, &real[..real.len() / 2]).is_err());
    assert!(parse_hdr(p, &real[..40]).is_err());
}

#[test]
fn exr_sanitizes_nonfinite_and_negative_texels() {
    let bytes = exr_bytes(8, 4, |x, y| match (x, y) {
        (0, 0) => (f32::NAN, 1.0, 1.0),
        (1, 0) => (1.0, f32::INFINITY, 1.0),
        (2, 0) => (1.0, 1.0, -3.0),
        (3, 1) => (f32::NEG_INFINITY, -1.0, 2.0),
        _ => (0.5, 0.25, 2.0),
    });
    let m = parse_exr(Path::new("mem.exr"), &bytes).unwrap();
    assert_eq!((m.nonfinite, m.negative), (3, 2));
    assert_eq!(m.map.data[0], [0.0, 1.0, 1.0]);
    assert_eq!(m.map.data[1], [1.0, 0.0, 1.0]);
    assert_eq!(m.map.data[2], [1.0, 1.0, 0.0]);
    assert_eq!(m.map.data[8 + 3], [0.0, 0.0, 2.0]);
    assert_eq!(m.map.data[5], [0.5, 0.25, 2.0]);
}

#[test]
fn exr_shape_and_truncation_errors() {
    let p = Path::new("mem.exr");
    let e = problem(parse_exr(p, &exr_bytes(6, 4, |_, _| (1.0, 1.0, 1.0))).unwrap_err());
    assert!(e.contains("2 × height"), "{e}");
    let good = exr_bytes(8, 4, |_, _| (1.0, 1.0, 1.0));
    assert!(parse_exr(p, &good).is_ok());
    for cut in [4, 20, good.len() / 2, good.len() - 3] {
        assert!(parse_exr(p, &good[..cut]).is_err(), "cut at {cut}");
    }
    let real = std::fs::read(shared_data_dir().join("envmaps/studio_night.exr")).unwrap();
    let e = parse_exr(p, &real[..real.len() / 2])
        .unwrap_err()
        .to_string();
    assert!(e.contains("mem.exr"), "{e}");
    let e = problem(parse_exr(p, b"#?RADIANCE").unwrap_err());
    assert!(e.contains("magic"), "{e}");
}

#[test]
fn read_map_dispatches_on_magic_and_reports_files() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("looks_like.exr");
    std::fs::write(&a, hdr_bytes(8, 4, [128, 128, 128, 128])).unwrap();
    assert_eq!(read_map(&a).unwrap().map.width, 8);
    let b = dir.path().join("looks_like.hdr");
    std::fs::write(&b, exr_bytes(8, 4, |_, _| (1.0, 2.0, 3.0))).unwrap();
    assert_eq!(read_map(&b).unwrap().map.data[0], [1.0, 2.0, 3.0]);
    let c = dir.path().join("junk.hdr");
    std::fs::write(&c, b"hello").unwrap();
    let e = read_map(&c).unwrap_err().to_string();
    assert!(e.contains("junk.hdr") && e.contains("magic"), "{e}");
    let d = dir.path().join("empty.exr");
    std::fs::write(&d, b"").unwrap();
    assert!(read_map(&d).unwrap_err().to_string().contains("empty"));
    let e = read_map(&dir.path().join("missing.hdr")).unwrap_err();
    assert!(matches!(e, EnvError::Io { .. }), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Random byte flips and truncations of valid files: an error or a map, never a panic.
    #[test]
    fn corrupted_files_never_panic(flips in proptest::collection::vec((0usize..4096, any::<u8>()), 1..8), cut in 0usize..4096, exr in any::<bool>()) {
        let mut b = if exr {
            exr_bytes(16, 8, |x, y| (x as f32, y as f32, 1.0))
        } else {
            hdr_bytes(16, 8, [200, 100, 50, 130])
        };
        for (i, v) in flips {
            let n = b.len();
            b[i % n] = v;
        }
        b.truncate(cut.max(1).min(b.len()));
        let p = Path::new("fuzz");
        if let Ok(m) = if exr { parse_exr(p, &b) } else { parse_hdr(p, &b) } {
            prop_assert_eq!(m.map.width, 2 * m.map.height);
            prop_assert!(m.map.data.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
        }
    }
}
