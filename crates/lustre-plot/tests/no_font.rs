//! Without a font (as on a machine with no system fonts) PNGs are still drawn, without text, and
//! SVGs keep their labels. Its own test binary, so the process-wide font state is not shared.

use lustre_brdf::{Bsdf, BsdfFlags, BsdfSample, DVec3, Rgb};
use lustre_plot::*;

#[derive(Debug)]
struct Grey;

impl Bsdf for Grey {
    fn name(&self) -> String {
        "grey".into()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z > 0.0 && wo.z > 0.0 {
            Rgb::splat(0.5 / std::f64::consts::PI)
        } else {
            Rgb::ZERO
        }
    }
    fn sample(&self, _wo: DVec3, _u1: f64, _u2: f64) -> Option<BsdfSample> {
        None
    }
    fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
        0.0
    }
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::default()
    }
}

#[test]
fn plots_without_a_font() {
    std::env::set_var(font::FONT_ENV, "none");
    assert!(!font::font_available() && font::font_source().is_none());
    let dir = tempfile::tempdir().unwrap();
    let bsdfs: [(&dyn Bsdf, &str); 1] = [(&Grey, "grey")];
    let files = polar_plot(
        &bsdfs,
        &[30.0],
        &PolarOptions::default(),
        &dir.path().join("p"),
    )
    .unwrap();
    let png = std::fs::read(&files.png).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(files.svg.unwrap()).unwrap();
    assert!(svg.contains("θi = 30°"), "SVG text needs no font file");
    let opts = ArrayOptions {
        disc_px: 24,
        supersample: 1,
        ..Default::default()
    };
    let a = transfer_array(&Grey, "grey", &opts, &dir.path().join("a")).unwrap();
    assert_eq!(&std::fs::read(a.png).unwrap()[..8], b"\x89PNG\r\n\x1a\n");
}
