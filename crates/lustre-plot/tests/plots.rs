//! Plot tests over small test BSDFs: files are valid PNG/SVG and written atomically, the sampled
//! curves have the right geometry, the arrays peak where the lobe does, bad paths are errors.

use lustre_brdf::frame::{deg, spherical};
use lustre_brdf::{Bsdf, BsdfFlags, BsdfSample, DVec3, Rgb};
use lustre_plot::*;
use std::f64::consts::PI;
use std::path::Path;

/// Lambert with albedo `rho`.
#[derive(Debug)]
struct Lambert(Rgb);

/// Lambert plus a normalized Phong lobe around the mirror direction, and optionally a Phong
/// transmission lobe around −ωi (a thin translucent sheet).
#[derive(Debug)]
struct Lobe {
    kd: Rgb,
    ks: Rgb,
    n: f64,
    kt: Rgb,
}

fn phong(n: f64, c: f64) -> f64 {
    (n + 2.0) / (2.0 * PI) * c.max(0.0).powf(n)
}

macro_rules! no_sampling {
    () => {
        fn sample(&self, _wo: DVec3, _u1: f64, _u2: f64) -> Option<BsdfSample> {
            None
        }
        fn pdf(&self, _wi: DVec3, _wo: DVec3) -> f64 {
            0.0
        }
    };
}

impl Bsdf for Lambert {
    fn name(&self) -> String {
        "lambert".into()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z > 0.0 && wo.z > 0.0 {
            self.0 / PI
        } else {
            Rgb::ZERO
        }
    }
    no_sampling!();
    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            reciprocal: true,
            energy_conserving: true,
            ..Default::default()
        }
    }
}

impl Bsdf for Lobe {
    fn name(&self) -> String {
        "lobe".into()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        if wi.z <= 0.0 {
            return Rgb::ZERO;
        }
        if wo.z > 0.0 {
            let r = DVec3::new(-wi.x, -wi.y, wi.z);
            self.kd / PI + self.ks * phong(self.n, r.dot(wo))
        } else {
            self.kt * phong(self.n, (-wi).dot(wo))
        }
    }
    no_sampling!();
    fn flags(&self) -> BsdfFlags {
        BsdfFlags {
            transmission: self.kt.max_component() > 0.0,
            ..Default::default()
        }
    }
}

fn glossy() -> Lobe {
    Lobe {
        kd: Rgb::new(0.25, 0.18, 0.1),
        ks: Rgb::new(0.5, 0.5, 0.55),
        n: 60.0,
        kt: Rgb::ZERO,
    }
}

fn translucent() -> Lobe {
    Lobe {
        kd: Rgb::splat(0.2),
        ks: Rgb::splat(0.3),
        n: 40.0,
        kt: Rgb::new(0.3, 0.35, 0.2),
    }
}

fn assert_png(path: &Path, min_w: u32, min_h: u32) {
    let bytes = std::fs::read(path).expect("png written");
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{}", path.display());
    assert_eq!(&bytes[12..16], b"IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert!(w >= min_w && h >= min_h, "{w}x{h}");
    assert!(
        bytes.len() > 2000,
        "suspiciously small png: {} bytes",
        bytes.len()
    );
}

fn assert_svg(path: &Path) {
    let s = std::fs::read_to_string(path).expect("svg written");
    assert!(
        s.starts_with("<svg") || s.starts_with("<?xml"),
        "{}",
        &s[..40.min(s.len())]
    );
    assert!(s.trim_end().ends_with("</svg>"));
    assert!(s.contains("θi = 30°"), "panel titles are in the svg");
}

fn no_temp_files(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().to_string();
        assert!(
            !name.starts_with(".lustre-plot-"),
            "temporary file left behind: {name}"
        );
    }
}

#[test]
fn polar_plot_writes_png_and_svg_atomically() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (glossy(), Lambert(Rgb::splat(0.5)));
    let bsdfs: [(&dyn Bsdf, &str); 2] = [(&a, "glossy model"), (&b, "lambert")];
    let opts = PolarOptions {
        cube_root: true,
        samples: 360,
        panel_px: 300,
        ..Default::default()
    };
    let files = polar_plot(
        &bsdfs,
        &[10.0, 30.0, 50.0, 70.0],
        &opts,
        &dir.path().join("lobes"),
    )
    .unwrap();
    assert_eq!(files.png, dir.path().join("lobes.png"));
    assert_png(&files.png, 600, 400);
    assert_svg(files.svg.as_deref().unwrap());
    assert_eq!(files.paths().len(), 2);
    // Overwriting an existing plot works and still leaves no temporary files.
    let opts = PolarOptions {
        channels: Channels::Rgb,
        ..opts
    };
    polar_plot(&bsdfs, &[30.0], &opts, &dir.path().join("lobes")).unwrap();
    assert_png(&files.png, 300, 200);
    no_temp_files(dir.path());
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn lambert_lobe_is_a_circle_of_diameter_rho_over_pi() {
    // f·cos θo = ρ/π·cos ψ: in polar coordinates (r, ψ) that is the circle through the origin with
    // its centre on the normal at height ρ/(2π).
    let rho = 0.6;
    let l = Lambert(Rgb::splat(rho));
    for theta in [0.0, 30.0, 75.0] {
        for phi in [0.0, 40.0] {
            let opts = PolarOptions {
                phi_i_deg: phi,
                samples: 720,
                ..Default::default()
            };
            let c = polar_curve(&l, theta, &opts);
            assert_eq!(c.samples.len(), 721);
            let (cy, r0) = (rho / (2.0 * PI), rho / (2.0 * PI));
            let mut worst: f64 = 0.0;
            for s in c.samples.iter().filter(|s| s.angle_deg.abs() <= 90.0) {
                let (x, y) = s.point(s.channel(Channels::Luminance, 0));
                worst = worst.max(((x * x + (y - cy) * (y - cy)).sqrt() - r0).abs());
            }
            assert!(
                worst < 1e-12,
                "θi {theta}: distance from the circle {worst:e}"
            );
            assert!((c.max(Channels::Luminance) - rho / PI).abs() < 1e-12);
            assert!(!c.transmits());
            // The light direction sits at ψ = −θi.
            assert!((c.wi - spherical(deg(theta), deg(phi))).length() < 1e-12);
        }
    }
    // With Quantity::Bsdf the curve is the constant ρ/π: a half circle around the origin.
    let opts = PolarOptions {
        quantity: Quantity::Bsdf,
        ..Default::default()
    };
    let c = polar_curve(&l, 20.0, &opts);
    for s in c.samples.iter().filter(|s| s.angle_deg.abs() < 90.0) {
        assert!((s.value[1] - rho / PI).abs() < 1e-12);
    }
}

#[test]
fn polar_lobe_peaks_at_the_mirror_angle_and_shows_transmission() {
    let g = glossy();
    let c = polar_curve(&g, 35.0, &PolarOptions::default());
    let peak = c
        .samples
        .iter()
        .max_by(|a, b| a.value.luminance().total_cmp(&b.value.luminance()))
        .unwrap();
    // f·cos θo peaks slightly before the mirror angle (the cosine pulls it toward the normal).
    assert!(
        peak.angle_deg > 30.0 && peak.angle_deg <= 35.0,
        "peak at {}",
        peak.angle_deg
    );
    let t = translucent();
    let c = polar_curve(&t, 35.0, &PolarOptions::default());
    assert!(c.transmits());
    let below = c.samples.iter().filter(|s| s.wo.z < 0.0);
    let peak = below
        .max_by(|a, b| a.value.luminance().total_cmp(&b.value.luminance()))
        .unwrap();
    // Straight-through transmission (−ωi) is at ψ = 180° − 35° = 145°, on the mirror side.
    assert!(
        (peak.angle_deg - 145.0).abs() <= 5.0,
        "transmission peak at {}",
        peak.angle_deg
    );
    let dir = tempfile::tempdir().unwrap();
    let bsdfs: [(&dyn Bsdf, &str); 1] = [(&t, "translucent")];
    let files = polar_plot(
        &bsdfs,
        &[0.0, 45.0],
        &PolarOptions::default(),
        &dir.path().join("t"),
    )
    .unwrap();
    assert_png(&files.png, 600, 300);
}

#[test]
fn disc_mapping_round_trips_and_puts_the_light_on_top() {
    let size = 64;
    for phi in [0.0, 15.0, 90.0, 200.0] {
        for (x, y) in [(10, 40), (32, 5), (50, 30), (31, 31)] {
            for h in [Hemisphere::Reflection, Hemisphere::Transmission] {
                let w = disc_direction(size, x, y, h, phi).expect("inside the disc");
                assert_eq!(h == Hemisphere::Transmission, w.z < 0.0);
                assert_eq!(direction_pixel(w, size, phi), (x, y), "φi {phi}");
            }
        }
        // The light's own azimuth maps straight up from the centre.
        let (x, y) = direction_pixel(spherical(deg(45.0), deg(phi)), size, phi);
        assert!((x as i32 - 32).abs() <= 1 && y < 20, "({x}, {y})");
    }
    assert!(disc_direction(size, 0, 0, Hemisphere::Reflection, 0.0).is_none());
}

#[test]
fn transfer_disc_peaks_at_the_mirror_pixel() {
    let g = Lobe {
        kd: Rgb::ZERO,
        ks: Rgb::ONE,
        n: 200.0,
        kt: Rgb::ZERO,
    };
    for (theta, phi) in [(20.0, 0.0), (35.0, 45.0), (50.0, 90.0), (0.0, 30.0)] {
        let disc = transfer_disc(&g, theta, phi, Hemisphere::Reflection, 96, 1);
        let wi = spherical(deg(theta), deg(phi));
        let mirror = DVec3::new(-wi.x, -wi.y, wi.z);
        let (mx, my) = direction_pixel(mirror, 96, phi);
        let (px, py) = disc.argmax().unwrap();
        // p = f·cos θo moves the peak a fraction of a degree toward the centre: within 2 pixels.
        assert!(
            (px as i32 - mx as i32).abs() <= 2 && (py as i32 - my as i32).abs() <= 2,
            "θi {theta} φi {phi}: peak ({px}, {py}), mirror ({mx}, {my})"
        );
        // The mirror direction is below the centre (the light is on top).
        assert!(theta == 0.0 || my > 48);
        assert!(disc.get(0, 0).is_none() && disc.get(48, 48).is_some());
    }
    // A Lambertian disc is brightest at the centre: p = ρ/π·cos θo.
    let disc = transfer_disc(
        &Lambert(Rgb::splat(0.8)),
        30.0,
        0.0,
        Hemisphere::Reflection,
        64,
        2,
    );
    let c = disc.get(32, 32).unwrap()[0];
    assert!((c - 0.8 / PI).abs() < 0.01 * 0.8 / PI, "centre {c}");
}

#[test]
fn transfer_arrays_are_written_with_transmission_when_needed() {
    let dir = tempfile::tempdir().unwrap();
    let opts = ArrayOptions {
        disc_px: 40,
        supersample: 1,
        ..Default::default()
    };
    let (g, t) = (glossy(), translucent());
    assert!(!transmits(&g) && transmits(&t) && !transmits(&Lambert(Rgb::ONE)));
    let a = transfer_array(&g, "glossy", &opts, &dir.path().join("g")).unwrap();
    assert!(a.svg.is_none());
    assert_png(&a.png, 400, 300);
    let b = transfer_array(&t, "translucent", &opts, &dir.path().join("t")).unwrap();
    let cmp = transfer_array_compare(
        (&g, "glossy"),
        (&t, "translucent"),
        &opts,
        &dir.path().join("c"),
    )
    .unwrap();
    let dims = |p: &Path| {
        let b = std::fs::read(p).unwrap();
        (
            u32::from_be_bytes(b[16..20].try_into().unwrap()),
            u32::from_be_bytes(b[20..24].try_into().unwrap()),
        )
    };
    let (wa, ha) = dims(&a.png);
    let (wb, hb) = dims(&b.png);
    let (wc, hc) = dims(&cmp.png);
    assert!(
        hb > ha + 200,
        "the transmission array adds a row: {ha} vs {hb}"
    );
    assert_eq!(wa, wb);
    assert!(
        wc > wa + 200 && hc == hb,
        "comparison is side by side: {wc}x{hc}"
    );
    let opts = ArrayOptions {
        color: ArrayColor::Colormap,
        ..opts
    };
    assert_png(
        &transfer_array(&g, "glossy", &opts, &dir.path().join("m"))
            .unwrap()
            .png,
        400,
        300,
    );
    no_temp_files(dir.path());
}

#[test]
fn bad_outputs_and_requests_are_errors_not_panics() {
    let g = glossy();
    let bsdfs: [(&dyn Bsdf, &str); 1] = [(&g, "glossy")];
    let missing = Path::new("/nonexistent-lustre-folder/sub/plot");
    let e = polar_plot(&bsdfs, &[30.0], &PolarOptions::default(), missing).unwrap_err();
    assert!(matches!(e, PlotError::Io { .. }), "{e}");
    assert!(e.to_string().contains("nonexistent-lustre-folder"));
    let opts = ArrayOptions {
        disc_px: 20,
        thetas_deg: vec![10.0],
        phis_deg: vec![0.0],
        ..Default::default()
    };
    assert!(matches!(
        transfer_array(&g, "g", &opts, missing),
        Err(PlotError::Io { .. })
    ));
    // A path whose parent is a file.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("file"), b"x").unwrap();
    assert!(polar_plot(
        &bsdfs,
        &[30.0],
        &PolarOptions::default(),
        &dir.path().join("file/plot")
    )
    .is_err());
    // Invalid requests.
    let here = dir.path().join("p");
    let input = |r: Result<PlotFiles>| matches!(r, Err(PlotError::Input(_)));
    assert!(input(polar_plot(
        &[],
        &[30.0],
        &PolarOptions::default(),
        &here
    )));
    assert!(input(polar_plot(
        &bsdfs,
        &[],
        &PolarOptions::default(),
        &here
    )));
    assert!(input(polar_plot(
        &bsdfs,
        &[95.0],
        &PolarOptions::default(),
        &here
    )));
    assert!(input(polar_plot(
        &bsdfs,
        &[f64::NAN],
        &PolarOptions::default(),
        &here
    )));
    assert!(input(polar_plot(
        &bsdfs,
        &[30.0],
        &PolarOptions {
            panel_px: 0,
            ..Default::default()
        },
        &here
    )));
    assert!(input(transfer_array(
        &g,
        "g",
        &ArrayOptions {
            disc_px: 0,
            ..opts.clone()
        },
        &here
    )));
    assert!(input(transfer_array(
        &g,
        "g",
        &ArrayOptions {
            phis_deg: vec![],
            ..opts.clone()
        },
        &here
    )));
    assert!(input(transfer_array(
        &g,
        "g",
        &ArrayOptions {
            thetas_deg: vec![-1.0],
            ..opts
        },
        &here
    )));
    no_temp_files(dir.path());
}

/// A BSDF that returns NaN, infinities and negative values everywhere still plots (as zeros).
#[derive(Debug)]
struct Broken;

impl Bsdf for Broken {
    fn name(&self) -> String {
        "broken".into()
    }
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        Rgb::new(f64::NAN, f64::INFINITY, -(1.0 + wi.z.abs() + wo.z.abs()))
    }
    no_sampling!();
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::default()
    }
}

#[test]
fn non_finite_values_plot_as_zero() {
    let dir = tempfile::tempdir().unwrap();
    let bsdfs: [(&dyn Bsdf, &str); 1] = [(&Broken, "broken")];
    let c = polar_curve(&Broken, 30.0, &PolarOptions::default());
    assert!(c.samples.iter().all(|s| s.value == Rgb::ZERO));
    polar_plot(
        &bsdfs,
        &[30.0],
        &PolarOptions {
            cube_root: true,
            ..Default::default()
        },
        &dir.path().join("b"),
    )
    .unwrap();
    let opts = ArrayOptions {
        disc_px: 24,
        supersample: 1,
        ..Default::default()
    };
    transfer_array(&Broken, "broken", &opts, &dir.path().join("a")).unwrap();
}

#[test]
fn heat_colours_in_memory_are_the_png_heat_map() {
    // A ramp over six octaves with zeros, a constant map and an empty one: `heat_rgb` is pixel
    // for pixel the PNG `heat_map` writes (the viewer shows the former, the CLI writes the
    // latter).
    let (w, h) = (37, 11);
    let ramp: Vec<f64> = (0..w * h)
        .map(|k| {
            if k % 7 == 0 {
                0.0
            } else {
                (k as f64 / 60.0).exp2()
            }
        })
        .collect();
    let dir = tempfile::tempdir().expect("temp dir");
    for values in [ramp, vec![3.0; w * h], vec![0.0; w * h]] {
        let path = dir.path().join("heat.png");
        let scale = heat_map(&values, w, h, &path).expect("heat map");
        let png = image::open(&path).expect("png").to_rgb8();
        let (rgb, range) = lustre_plot::heat::heat_rgb(&values);
        assert_eq!(range, scale);
        assert_eq!(&rgb, png.as_raw());
    }
    // Not finite or negative: black, not a panic.
    let (rgb, _) = lustre_plot::heat::heat_rgb(&[f64::NAN, -1.0, f64::INFINITY, 2.0]);
    assert_eq!(&rgb[..9], &[0; 9]);
    // A constant positive map (the adaptive renderer's sample counts under a constant N_p) is
    // one colour, bright enough to tell from the zeros beside it (it used to draw black).
    let (rgb, scale) = lustre_plot::heat::heat_rgb(&[16.0, 16.0, 0.0, 16.0]);
    assert_eq!((scale.low, scale.high), (16.0, 16.0));
    assert_eq!(&rgb[6..9], &[0, 0, 0]);
    assert_eq!(&rgb[0..3], &rgb[3..6]);
    assert_eq!(&rgb[0..3], &rgb[9..12]);
    let sum: u32 = rgb[0..3].iter().map(|&c| u32::from(c)).sum();
    assert!(sum > 150, "{:?}", &rgb[0..3]);
}
