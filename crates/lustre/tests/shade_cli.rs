//! End-to-end runs of `lustre demo` and `lustre compare` at tiny sizes, and their input errors;
//! output into a closed pipe.

use std::process::Command;

/// A map of the shared data's `envmaps/`.
macro_rules! envmap {
    ($name:literal) => {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../../shared/data/envmaps/",
            $name
        )
    };
}

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

fn run_ok(cmd: &mut Command) -> String {
    let out = cmd.output().expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn run_err(cmd: &mut Command) -> String {
    let out = cmd.output().expect("runs");
    assert!(!out.status.success(), "unexpected success");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn demo_at_a_tiny_size_writes_a_png_and_prints_psnr() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("demo.png");
    let stdout = run_ok(
        lustre()
            .args(["demo", "--cpu", "--size", "48x27", "--samples", "4"])
            .args(["--reference-spp", "16", "--out"])
            .arg(&png),
    );
    assert!(stdout.contains("renderer: CPU"), "{stdout}");
    let psnr: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("PSNR against the reference: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|v| v.parse().ok())
        .expect("a PSNR line");
    assert!(psnr.is_finite() && psnr > 5.0, "{psnr}");
    let bytes = std::fs::read(&png).expect("png written");
    assert!(bytes.starts_with(b"\x89PNG"));
}

#[test]
fn compare_with_a_tiny_configuration_writes_the_table() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("cmp");
    let stdout = run_ok(
        lustre()
            .args(["compare", "--experiment", "002", "--size", "8"])
            .args(["--reference-spp", "4", "--face-size", "16", "--out"])
            .arg(&out),
    );
    assert!(stdout.contains("| iso-0.15 | 270 | CK |"), "{stdout}");
    let md = std::fs::read_to_string(out.join("compare.md")).expect("compare.md");
    assert!(md.contains("## Experiment 002") && !md.contains("## Experiment 000"));
    assert!(
        md.contains("| aniso-0.2-0.075 | 17 | regular (Pdf002) |"),
        "{md}"
    );
    assert!(
        md.contains("| aniso-0.2-0.075 | 17 | lattice (ours) |"),
        "{md}"
    );
    assert!(
        md.contains("| aniso-0.2-0.075 | 17 | lattice + sun (ours) |")
            && md.contains("suns split off"),
        "{md}"
    );
    assert!(md.contains("lookups mean / max"), "{md}");
    // The exact reference, with the MIS one beside it.
    assert!(md.contains("| iso-0.1 | 0 | reference (exact) |"), "{md}");
    assert!(md.contains("| iso-0.1 | 4 | reference (MIS) |"), "{md}");
    assert!(out.join("002_iso-0.1_reference.png").is_file());
    assert!(out.join("002_iso-0.1_reference-mis.png").is_file());
    // The MIS reference alone.
    let out2 = dir.path().join("cmp-mis");
    let stdout = run_ok(
        lustre()
            .args(["compare", "--experiment", "002", "--size", "8"])
            .args(["--reference", "mis", "--reference-spp", "4"])
            .args(["--face-size", "16", "--out"])
            .arg(&out2),
    );
    assert!(
        stdout.contains("| iso-0.1 | 4 | reference (MIS) |"),
        "{stdout}"
    );
    assert!(!stdout.contains("reference (exact)"), "{stdout}");
}

#[test]
fn bad_inputs_are_clear_errors() {
    let dir = tempfile::tempdir().expect("temp dir");
    let e = run_err(
        lustre()
            .args(["demo", "--size", "0x5", "--out"])
            .arg(dir.path().join("a.png")),
    );
    assert!(e.contains("--size"), "{e}");
    let e = run_err(
        lustre()
            .args(["demo", "--size", "big", "--out"])
            .arg(dir.path().join("a.png")),
    );
    assert!(e.contains("WIDTHxHEIGHT"), "{e}");
    let e = run_err(
        lustre()
            .args(["demo", "--cpu", "--samples", "1025", "--out"])
            .arg(dir.path().join("a.png")),
    );
    assert!(e.contains("--samples 1025") && e.contains("1024"), "{e}");
    let e = run_err(
        lustre()
            .args(["compare", "--experiment", "123", "--out"])
            .arg(dir.path()),
    );
    assert!(e.contains("123"), "{e}");
    let e = run_err(
        lustre()
            .args(["compare", "--reference", "guess", "--out"])
            .arg(dir.path()),
    );
    assert!(e.contains("guess"), "{e}");
    let missing = dir.path().join("no-such-map.hdr");
    let e = run_err(
        lustre()
            .args(["compare", "--face-size", "8", "--map"])
            .arg(&missing)
            .arg("--out")
            .arg(dir.path()),
    );
    assert!(e.contains("no-such-map.hdr"), "{e}");
}

#[test]
fn output_into_a_closed_pipe_ends_quietly() {
    // `lustre scene info … | head` when head has already gone: the first write fails.
    let scene = lustre_brdf::shared_data_dir().join("scenes/cornell_box/cornell_box.obj");
    let mut child = lustre()
        .args(["scene", "info"])
        .arg(&scene)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs");
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("waits");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "{err}"
    );
}

#[test]
fn bandwidth_maps_of_an_environment_and_a_material() {
    let dir = tempfile::tempdir().expect("temp dir");
    let map = envmap!("quarry_01_1k.hdr");
    let png = dir.path().join("quarry.png");
    let stdout = run_ok(
        lustre()
            .args(["bandwidth", "--map", map, "--out"])
            .arg(&png),
    );
    assert!(
        stdout.contains("1024×512") && stdout.contains("cycles per radian"),
        "{stdout}"
    );
    let img = image::open(&png).expect("png").to_rgb8();
    assert_eq!(img.dimensions(), (1024, 512));
    // The heat map is not flat: the sun's region is brighter than the median pixel.
    let lum = |p: &image::Rgb<u8>| p.0.iter().map(|&c| c as u32).sum::<u32>();
    let max = img.pixels().map(lum).max().expect("pixels");
    assert!(max > 400, "{max}");
    let table = dir.path().join("gold.png");
    let stdout = run_ok(
        lustre()
            .args(["bandwidth", "--material", "nbrdf:gold-paint", "--out"])
            .arg(&table),
    );
    assert!(stdout.contains("256×256"), "{stdout}");
    assert_eq!(
        image::open(&table).expect("png").to_rgb8().dimensions(),
        (256, 256)
    );
    // Bad input: nothing to map, both, a missing map, an unknown material.
    let e = run_err(lustre().args(["bandwidth", "--out"]).arg(&png));
    assert!(e.contains("--map FILE or --material SPEC"), "{e}");
    let e = run_err(
        lustre()
            .args([
                "bandwidth",
                "--map",
                map,
                "--material",
                "nbrdf:gold-paint",
                "--out",
            ])
            .arg(&png),
    );
    assert!(e.contains("cannot be used with"), "{e}");
    let e = run_err(
        lustre()
            .args(["bandwidth", "--map", "/no/such/map.hdr", "--out"])
            .arg(&png),
    );
    assert!(e.contains("/no/such/map.hdr"), "{e}");
    let e = run_err(
        lustre()
            .args(["bandwidth", "--material", "nbrdf:unobtainium", "--out"])
            .arg(&png),
    );
    assert!(e.contains("unobtainium"), "{e}");
}

#[test]
fn adaptive_and_brute_force_renders_of_a_measured_paint_agree_and_bad_input_is_named() {
    // 004 ch. IV from the command line: gold-paint's neural BRDF under royal_esplanade_1k, a
    // brute-force frame with 128 samples per pixel on the CPU as the reference, an adaptive
    // frame with 16 per shaded pixel on the GPU (lavapipe in CI: its bandwidth pass and its
    // hierarchical shading) compared with it.
    let dir = tempfile::tempdir().expect("temp dir");
    let map = envmap!("royal_esplanade_1k.hdr");
    let base = [
        "render",
        "--material",
        "nbrdf:gold-paint",
        "--env",
        map,
        "--size",
        "64x48",
    ];
    let common = [&base[..], &["--spp", "1"]].concat();
    let brute = dir.path().join("brute");
    let stdout = run_ok(
        lustre()
            .args(&common)
            .args(["--method", "brute", "--samples", "128", "--device", "cpu"])
            .arg("--out")
            .arg(&brute),
    );
    assert!(stdout.contains("shaded with 128 samples each"), "{stdout}");
    let reference = brute.join("frame.exr");
    let adaptive = dir.path().join("adaptive");
    let stdout = run_ok(
        lustre()
            .args(&common)
            .args([
                "--method",
                "adaptive",
                "--samples",
                "16",
                "--exposure",
                "0.5",
                "--device",
                "gpu",
            ])
            .arg("--compare-reference")
            .arg(&reference)
            .arg("--out")
            .arg(&adaptive),
    );
    assert!(
        stdout.contains("up-sampled") && stdout.contains("hierarchical shading (GPU"),
        "{stdout}"
    );
    let psnr_of = |stdout: &str| -> f64 {
        stdout
            .split("PSNR ")
            .nth(1)
            .and_then(|s| s.split(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no PSNR in {stdout}"))
    };
    let psnr = psnr_of(&stdout);
    eprintln!("adaptive (16) vs brute force (128): {psnr:.2} dB");
    assert!(psnr > 30.0, "adaptive vs brute force: {psnr} dB");
    for f in [
        "frame.png",
        "frame.exr",
        "times.csv",
        "frame_bandwidth.png",
        "frame_level.png",
        "frame_samples.png",
        "frame_shaded.png",
    ] {
        assert!(adaptive.join(f).is_file(), "{f} missing");
    }
    // Bad input, by name: absurd counts, a sub-pixel count that is not a square, a sky or a
    // light that is not there, brute force on the GPU.
    let refused = |args: &[&str], named: &str| {
        let e = run_err(lustre().args(args).arg("--out").arg(&adaptive));
        assert!(e.contains(named), "{args:?}: {e}");
    };
    let with = |extra: &[&'static str]| [&common[..], extra].concat();
    refused(
        &with(&["--method", "adaptive", "--samples", "0"]),
        "--samples 0",
    );
    refused(
        &[&base[..], &["--method", "adaptive", "--spp", "2"]].concat(),
        "--spp 2",
    );
    refused(
        &[
            "render",
            "--method",
            "adaptive",
            "--env",
            "/no/such/sky.hdr",
        ],
        "/no/such/sky.hdr",
    );
    // Brute force on the GPU takes the CPU's points from the same seed: the frames agree to
    // f32 rounding.
    let brute_cpu = dir.path().join("brute16");
    let brute_gpu = dir.path().join("brute16-gpu");
    for (device, out) in [("cpu", &brute_cpu), ("gpu", &brute_gpu)] {
        let mut cmd = lustre();
        cmd.args(&common)
            .args(["--method", "brute", "--samples", "16", "--device", device])
            .arg("--out")
            .arg(out);
        if device == "gpu" {
            cmd.arg("--compare-reference")
                .arg(brute_cpu.join("frame.exr"));
        }
        let stdout = run_ok(&mut cmd);
        if device == "gpu" {
            assert!(stdout.contains("brute-force shading (GPU"), "{stdout}");
            let psnr = psnr_of(&stdout);
            eprintln!("brute force 16 spp, GPU vs CPU: {psnr:.2} dB");
            assert!(psnr > 60.0, "GPU vs CPU brute force: {psnr} dB");
        }
    }
    refused(
        &with(&["--method", "adaptive", "--area-light", "/no/such/light.exr"]),
        "--area-light /no/such/light.exr",
    );
    // A textured area light (a studio map as its emission) adds light: the frame, bandwidth
    // pass and shading on the GPU, is brighter.
    let lit = dir.path().join("lit");
    let light = envmap!("studio_sunrise.exr");
    run_ok(
        lustre()
            .args(&common)
            .args([
                "--method",
                "adaptive",
                "--samples",
                "16",
                "--area-light",
                light,
                "--device",
                "gpu",
            ])
            .args(["--area-light-radiance", "200", "--out"])
            .arg(&lit),
    );
    let mean = |p: &std::path::Path| {
        lustre_trace::image::Image::read_exr(&p.join("frame.exr"))
            .expect("frame")
            .mean()
    };
    eprintln!(
        "mean with the area light {:.4}, without {:.4}",
        mean(&lit),
        mean(&adaptive)
    );
    assert!(
        mean(&lit) > 1.2 * mean(&adaptive),
        "{} vs {}",
        mean(&lit),
        mean(&adaptive)
    );
}

#[test]
fn adaptive_shading_lights_a_scene_file_by_its_own_emitters() {
    // The Cornell box has no environment: its ceiling panel is the adaptive method's area
    // light, and the frame agrees with brute force's.
    let dir = tempfile::tempdir().expect("temp dir");
    let cornell = lustre_brdf::shared_data_dir().join("scenes/cornell_box/cornell_box.obj");
    let common = |method: &str, samples: &str, out: &std::path::Path| {
        let mut cmd = lustre();
        cmd.arg("render")
            .arg(&cornell)
            .args(["--method", method, "--samples", samples, "--size", "48x48"])
            .args(["--spp", "1", "--device", "cpu", "--out"])
            .arg(out);
        cmd
    };
    let brute = dir.path().join("brute");
    run_ok(&mut common("brute", "256", &brute));
    let adaptive = dir.path().join("adaptive");
    let stdout = run_ok(
        common("adaptive", "16", &adaptive)
            .arg("--compare-reference")
            .arg(brute.join("frame.exr")),
    );
    assert!(stdout.contains("up-sampled"), "{stdout}");
    let psnr: f64 = stdout
        .split("PSNR ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no PSNR in {stdout}"));
    eprintln!("Cornell box, adaptive (16) vs brute force (256): {psnr:.2} dB");
    assert!(psnr > 35.0, "{psnr} dB");
    // A scene that nothing lights (a floor, no environment, no emitter) is refused by name.
    let floor = dir.path().join("floor.obj");
    std::fs::write(
        &floor,
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 3 2\nf 1 4 3\n",
    )
    .expect("obj");
    let e = run_err(
        lustre()
            .arg("render")
            .arg(&floor)
            .args(["--method", "adaptive", "--size", "16x16", "--out"])
            .arg(dir.path().join("dark")),
    );
    assert!(e.contains("nothing lights the scene"), "{e}");
}
