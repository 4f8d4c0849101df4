//! Images and metrics against hand-computed values.

use lustre_trace::image::{display_value, srgb_eotf, srgb_oetf, Image};
use lustre_trace::metrics::{delta_e, false_colour, psnr, ramp, rms, srgb_to_lab};

fn uniform(w: usize, h: usize, v: [f32; 3]) -> Image {
    Image::from_data(w, h, vec![v; w * h]).unwrap()
}

#[test]
fn image_basics_and_errors() {
    let mut img = Image::new(3, 2).unwrap();
    img.set(2, 1, [1.0, 2.0, 3.0]);
    assert_eq!(img.get(2, 1), [1.0, 2.0, 3.0]);
    assert_eq!(img.data[5], [1.0, 2.0, 3.0]);
    assert!(Image::new(0, 2).is_err());
    assert!(Image::from_data(2, 2, vec![[0.0; 3]; 3]).is_err());
}

#[test]
fn srgb_encoding_by_hand() {
    // 0.5 linear → 1.055 · 0.5^(1/2.4) − 0.055 = 0.735357 → 187.52 → 188.
    assert!((srgb_oetf(0.5) - 0.735_357).abs() < 1e-6);
    assert!((srgb_eotf(srgb_oetf(0.3)) - 0.3).abs() < 1e-12);
    let img = Image::from_data(2, 1, vec![[0.5, 0.0, 2.0], [0.25, f32::NAN, -1.0]]).unwrap();
    // Exposure 1: [188, 0, 255]; 0.25 → 0.537099 → 137; NaN and negative → 0.
    assert_eq!(img.to_srgb8(1.0), vec![188, 0, 255, 137, 0, 0]);
    // Exposure 2 doubles before the clamp: 0.25 → 0.5 → 188.
    assert_eq!(img.to_srgb8(2.0)[3], 188);
    assert_eq!(display_value(0.0031308, 1.0), 12.92 * 0.0031308);
}

#[test]
fn png_and_exr_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mut img = Image::new(4, 3).unwrap();
    for y in 0..3 {
        for x in 0..4 {
            img.set(x, y, [x as f32 * 0.3, y as f32 * 0.7, 1.5e3]);
        }
    }
    let png = dir.path().join("a.png");
    img.write_png(&png, 1.0).unwrap();
    let back = image::open(&png).unwrap().to_rgb8();
    assert_eq!(back.dimensions(), (4, 3));
    assert_eq!(back.into_raw(), img.to_srgb8(1.0));
    let exr = dir.path().join("a.exr");
    img.write_exr(&exr).unwrap();
    let back = image::open(&exr).unwrap().to_rgb32f();
    assert_eq!(back.dimensions(), (4, 3));
    let want: Vec<f32> = img.data.iter().flatten().copied().collect();
    assert_eq!(back.into_raw(), want);
    // Only the two files: no temporary files left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    // A missing directory is an error naming the path, not a panic.
    let bad = dir.path().join("missing").join("b.png");
    let err = img.write_png(&bad, 1.0).unwrap_err().to_string();
    assert!(err.contains("missing"), "{err}");
}

#[test]
fn rms_by_hand() {
    let a = uniform(5, 4, [0.2, 0.5, 1.0]);
    let b = uniform(5, 4, [0.3, 0.6, 1.1]);
    assert!((rms(&a, &b).unwrap() - 0.1).abs() < 1e-6);
    // One channel of one of two pixels off by 1: √(1/6).
    let c = Image::from_data(2, 1, vec![[0.0; 3], [0.0; 3]]).unwrap();
    let d = Image::from_data(2, 1, vec![[0.0; 3], [0.0, 1.0, 0.0]]).unwrap();
    assert!((rms(&c, &d).unwrap() - (1.0f64 / 6.0).sqrt()).abs() < 1e-12);
    assert_eq!(rms(&a, &a).unwrap(), 0.0);
    assert!(rms(&a, &uniform(4, 5, [0.0; 3])).is_err());
}

#[test]
fn psnr_by_hand() {
    let a = uniform(3, 3, [0.2, 0.4, 0.8]);
    assert_eq!(psnr(&a, &a, 1.0).unwrap(), f64::INFINITY);
    // Display difference 0.1 on every channel: MSE 0.01 → 20 dB.
    let lin = srgb_eotf(0.1) as f32;
    let black = uniform(3, 3, [0.0; 3]);
    let dim = uniform(3, 3, [lin; 3]);
    assert!((psnr(&black, &dim, 1.0).unwrap() - 20.0).abs() < 1e-4);
    // Values above 1 clamp: 2 vs 5 look the same.
    assert_eq!(
        psnr(&uniform(1, 1, [2.0; 3]), &uniform(1, 1, [5.0; 3]), 1.0).unwrap(),
        f64::INFINITY
    );
}

#[test]
fn delta_e_by_hand() {
    let white = uniform(2, 2, [1.0; 3]);
    let black = uniform(2, 2, [0.0; 3]);
    assert!((delta_e(&white, &black, 1.0).unwrap() - 100.0).abs() < 1e-3);
    assert_eq!(delta_e(&white, &white, 1.0).unwrap(), 0.0);
    // Published Lab (D65) of sRGB red: (53.24, 80.09, 67.20).
    let lab = srgb_to_lab([1.0, 0.0, 0.0]);
    for (got, want) in lab.iter().zip([53.2408, 80.0925, 67.2032]) {
        assert!((got - want).abs() < 0.01, "{lab:?}");
    }
    // White Lab is (100, 0, 0).
    let w = srgb_to_lab([1.0; 3]);
    assert!((w[0] - 100.0).abs() < 1e-4 && w[1].abs() < 1e-3 && w[2].abs() < 1e-3);
    // Mean over pixels: one of two pixels white vs black → 50.
    let a = Image::from_data(2, 1, vec![[1.0; 3], [0.0; 3]]).unwrap();
    let b = Image::from_data(2, 1, vec![[0.0; 3], [0.0; 3]]).unwrap();
    assert!((delta_e(&a, &b, 1.0).unwrap() - 50.0).abs() < 1e-3);
}

#[test]
fn false_colour_ramp() {
    assert_eq!(ramp(0.0), [0.0, 0.0, 1.0]);
    assert_eq!(ramp(0.5), [0.0, 1.0, 0.0]);
    assert_eq!(ramp(1.0), [1.0, 0.0, 0.0]);
    assert_eq!(ramp(7.0), [1.0, 0.0, 0.0]);
    assert_eq!(ramp(0.125), [0.0, 0.5, 1.0]);
    // |ΔY| = 0.5 (grey 0.5 vs 0) with max 1 → green; PNG shows pure green.
    let a = uniform(2, 2, [0.5; 3]);
    let b = uniform(2, 2, [0.0; 3]);
    let f = false_colour(&a, &b, 1.0).unwrap();
    assert_eq!(f.to_srgb8(1.0)[..3], [0, 255, 0]);
    // Identical → blue; above max → red.
    assert_eq!(
        false_colour(&a, &a, 1.0).unwrap().to_srgb8(1.0)[..3],
        [0, 0, 255]
    );
    assert_eq!(
        false_colour(&a, &b, 0.1).unwrap().to_srgb8(1.0)[..3],
        [255, 0, 0]
    );
    assert!(false_colour(&a, &b, 0.0).is_err());
}
