//! `lustre view` end to end in a real window under Xvfb, rendered on lavapipe: the
//! built-in room opened, an input script replayed (walk, look, record the walk, click an object
//! to select it, change its material's roughness, a refused material swap, select the fitted
//! gold sphere by material, change its SGD fit's α and ρd, save it as material JSON, then the
//! adaptive method of 004 ch. IV and its shaded-pixel and bandwidth views), screenshots taken.
//! The 3D view in the last screenshot matches `lustre render` of the same camera and material
//! edits within [`PSNR_MIN`]; the panels are drawn; the edit changed the floor; the recorded
//! walk is a camera path file `lustre render --path` reads; the adaptive view is lit, and its
//! shaded-pixel view shows as many shaded and up-sampled pixels as the frame counted. Bad input
//! and a missing adapter or display end with a clear message and a non-zero exit, never a hang;
//! the adaptive method on a scene without an environment is refused with a message, and the
//! run goes on.
//!
//!
//! Measured materials, which the GPU walkthrough does not take, open adaptive-only (004 ch. IV):
//! `--material nbrdf:gold-paint`, `--lineup` (004 Fig. IV.13) and an unbaked scene file of a
//! measured material start in the adaptive method, their views match `lustre render --method
//! adaptive` of the same camera, the buffer views work, a walkthrough method is refused by
//! name, and a material swap applies to the adaptive method.
//!
//! `xvfb-run` must be installed (CI installs `xvfb xauth`): without it this test fails.

use lustre_scene::camera_path_file::CameraPathFile;
use lustre_trace::image::Image;
use std::path::Path;
use std::process::{Command, Output};

/// The 3D view in the window against `lustre render` of the same camera, 8-bit sRGB PSNR.
const PSNR_MIN: f64 = 40.0;

/// The adaptive method's 3D view against `lustre render --method adaptive` of the same camera,
/// seed and mean N_p, 8-bit sRGB PSNR.
const ADAPTIVE_PSNR_MIN: f64 = 40.0;

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

/// `lustre view ARGS` in a virtual X display.
fn view_in_xvfb(dir: &Path, args: &[&str]) -> Output {
    Command::new("xvfb-run")
        .current_dir(dir)
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_lustre"))
        .arg("view")
        .args(args)
        .output()
        .unwrap_or_else(|e| {
            panic!("xvfb-run could not be started ({e}): apt-get install xvfb xauth")
        })
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn read_json(p: &Path) -> serde_json::Value {
    let t = std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&t).unwrap()
}

/// The RGB bytes of `img` inside the rectangle (x, y, w, h).
fn crop(img: &image::RgbaImage, (x, y, w, h): (u32, u32, u32, u32)) -> Vec<u8> {
    let mut out = Vec::with_capacity((3 * w * h) as usize);
    for j in y..y + h {
        for i in x..x + w {
            out.extend_from_slice(&img.get_pixel(i, j).0[..3]);
        }
    }
    out
}

/// PSNR of two 8-bit buffers, dB.
fn psnr8(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    let mse = a
        .iter()
        .zip(b)
        .map(|(&x, &y)| (f64::from(x) - f64::from(y)).powi(2))
        .sum::<f64>()
        / a.len() as f64;
    10.0 * (255.0f64.powi(2) / mse.max(1e-12)).log10()
}

#[test]
fn viewer_replays_a_script_and_its_view_matches_lustre_render() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let script = dir.path().join("walk.txt");
    std::fs::write(
        &script,
        "# walk in, look about, record a short walk\n\
         walk forward 0.6\n\
         look 30 25\n\
         record start\n\
         walk right 0.2\n\
         record stop walk.json\n\
         select 150 380\n\
         screenshot before.png\n\
         set alpha 0.25\n\
         material ward(kd=0.2, ks=0.1, ax=0.1, ay=0.1)\n\
         screenshot mid.png\n\
         select gold-paint\n\
         set model.alpha 0.3,0.3,0.3\n\
         set model.rho_d 0.4,0.05,0.05\n\
         save-material gold.json\n\
         screenshot shot.png\n\
         method adaptive\n\
         screenshot adaptive.png\n\
         buffer shaded\n\
         screenshot mask.png\n\
         buffer bandwidth\n\
         screenshot bandwidth.png\n\
         quit\n",
    )
    .unwrap();
    let o = view_in_xvfb(
        dir.path(),
        &[
            "--size",
            "900x500",
            "--scale",
            "1",
            "--samples",
            "8",
            "--probe-size",
            "32",
            "--out",
            "out",
            "--bake-dir",
            "bake",
            "--script",
            "walk.txt",
            "--timeout",
            "900",
        ],
    );
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    // The refused swap (no GPU model for Ward) is said; the scene kept running.
    assert!(
        all.contains("ward(") && all.contains("not on the GPU"),
        "{all}"
    );
    assert_eq!(
        read_json(&out.join("mid.json"))["selected"]["material"],
        "floor"
    );
    let side = read_json(&out.join("shot.json"));
    assert_eq!(side["selected"]["material"], "gold-paint", "{side}");
    let edits = [
        "floor.alpha=0.25",
        "gold-paint.model.alpha=0.3,0.3,0.3",
        "gold-paint.model.rho_d=0.4,0.05,0.05",
    ];
    assert_eq!(side["set"], serde_json::json!(edits), "{side}");
    // The edited fit (sgd:gold-metallic-paint with α = 0.3: a normalized SGD, its Eq. V.3
    // shadowing refitted) saved as a material JSON.
    let gold = lustre_brdf::material::read(&out.join("gold.json")).unwrap();
    assert_eq!(gold.model.kind(), "sgd");
    match &gold.model {
        lustre_brdf::material::MaterialModel::CookTorrance { channels, .. } => {
            assert!(channels.iter().all(|c| c.alpha == 0.3 && c.g1.is_some()));
            assert_eq!(channels.map(|c| c.rho_d), [0.4, 0.05, 0.05]);
        }
        m => panic!("{m:?}"),
    }
    assert_eq!(side["method"], "regular");
    let rect: Vec<f64> = side["view"]["rect"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let size: Vec<u64> = side["view"]["size"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    let (x, y, w, h) = (
        rect[0].round() as u32,
        rect[1].round() as u32,
        size[0] as u32,
        size[1] as u32,
    );
    assert_eq!((rect[2].round() as u32, rect[3].round() as u32), (w, h));
    let shot = image::open(out.join("shot.png")).unwrap().to_rgba8();
    assert_eq!(shot.dimensions(), (900, 500));
    let before = image::open(out.join("before.png")).unwrap().to_rgba8();
    let mid = image::open(out.join("mid.png")).unwrap().to_rgba8();

    // `lustre render` of the same camera (the screenshot's camera path file) and edit, into
    // the folder whose bake/ the viewer made.
    let o = lustre()
        .current_dir(dir.path())
        .args(["render", "--out", ".", "--spp", "1", "--samples", "8"])
        .args(["--probe-size", "32", "--device", "gpu"])
        .args(["--size", &format!("{w}x{h}")])
        .args(["--path", "out/shot.camera.json"])
        .args(edits.iter().flat_map(|e| ["--set", e]))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let frame = Image::read_exr(&dir.path().join("frame_0000.exr")).unwrap();
    assert_eq!((frame.width, frame.height), (w as usize, h as usize));
    let rendered = frame.to_srgb8(side["exposure"].as_f64().unwrap());
    let shown = crop(&shot, (x, y, w, h));
    let psnr = psnr8(&shown, &rendered);
    println!("viewer 3D view vs lustre render, {w}×{h}: {psnr:.2} dB");
    assert!(psnr >= PSNR_MIN, "viewer vs lustre render: {psnr:.2} dB");
    // Each edit changed the picture: a rougher floor (softer reflections), then a rougher
    // gold sphere.
    let was = crop(&before, (x, y, w, h));
    let floor = crop(&mid, (x, y, w, h));
    for (what, a, b) in [
        ("floor.alpha=0.25", &was, &floor),
        (
            "gold-paint.model.{alpha=0.3, rho_d=0.4,0.05,0.05}",
            &floor,
            &shown,
        ),
    ] {
        let d = psnr8(a, b);
        // Pixels with a channel off by more than 8 levels (the gold sphere is at the view's
        // edge).
        let changed = a
            .chunks(3)
            .zip(b.chunks(3))
            .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 8))
            .count();
        println!("before vs after {what}: {d:.2} dB, {changed} pixels changed");
        assert!(
            changed > 1000,
            "{what} left the view unchanged ({d:.2} dB, {changed} pixels)"
        );
    }
    // The panels are drawn: text (light on the dark theme) left and right of the view.
    for (x0, x1) in [(0, x.saturating_sub(4)), ((x + w + 4).min(900), 900)] {
        let mut lit = 0;
        for j in 40..480 {
            for i in x0..x1 {
                let p = shot.get_pixel(i, j).0;
                if u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]) > 450 {
                    lit += 1;
                }
            }
        }
        assert!(lit > 300, "panel x {x0}..{x1}: {lit} light pixels");
    }
    // The recorded walk: a camera path file (lustre render --path reads it, as above).
    let walk = CameraPathFile::read(&out.join("walk.json")).unwrap();
    // From where `record start` was to where `walk right` ended.
    let (first, last) = (
        &walk.keyframes[0],
        &walk.keyframes[walk.keyframes.len() - 1],
    );
    assert!(
        walk.keyframes.len() >= 2 && last.time > first.time,
        "{walk:?}"
    );
    let moved = (last.camera.position - first.camera.position).length();
    assert!(moved > 0.05, "{moved} {walk:?}");

    // The adaptive method (004 ch. IV on the CPU) from the same camera: a lit image, its counts
    // and times in the screenshot's JSON.
    let side = read_json(&out.join("adaptive.json"));
    assert_eq!(side["method"], "adaptive", "{side}");
    let a = &side["adaptive"];
    assert_eq!(a["buffer"], "image", "{a}");
    assert_eq!(a["rate"], 2, "{a}");
    let count = |k: &str| a[k].as_u64().unwrap_or_else(|| panic!("{k}: {a}"));
    let (surface, shaded, upsampled) = (
        count("surface_pixels"),
        count("shaded_pixels"),
        count("upsampled_pixels"),
    );
    assert_eq!(shaded + upsampled, surface, "{a}");
    assert!(shaded * 100 > surface && upsampled * 100 > surface, "{a}");
    // The constant rule: the mean N_p (--samples 8) at every shaded pixel.
    assert_eq!(count("samples"), 8 * shaded, "{a}");
    for k in ["bandwidth_ms", "shading_ms"] {
        assert!(a[k].as_f64().is_some_and(|ms| ms > 0.0), "{k}: {a}");
    }
    println!(
        "adaptive frame {w}×{h}: {shaded} of {surface} surface pixels shaded, G-buffer {} ms, \
         bandwidth pass {} ms, shading {} ms (material tables {} ms)",
        a["gbuffer_ms"], a["bandwidth_ms"], a["shading_ms"], a["tables_ms"]
    );
    let lit_view = crop(
        &image::open(out.join("adaptive.png")).unwrap().to_rgba8(),
        (x, y, w, h),
    );
    let lit = lit_view
        .chunks(3)
        .filter(|p| p.iter().any(|c| *c > 40))
        .count();
    assert!(
        lit * 2 > (w * h) as usize,
        "adaptive view: {lit} of {} pixels lit",
        w * h
    );
    assert!(
        psnr8(&lit_view, &shown) < 30.0,
        "the adaptive view is the regular one"
    );
    // The shaded-pixel view: up-sampled surface pixels grey, shaded ones coloured by level (a
    // heat map, never pure black), the background black; as many of each as the frame counted.
    assert_eq!(
        read_json(&out.join("mask.json"))["adaptive"]["buffer"],
        "shaded"
    );
    let mask = crop(
        &image::open(out.join("mask.png")).unwrap().to_rgba8(),
        (x, y, w, h),
    );
    let grey = mask.chunks(3).filter(|p| *p == [110, 110, 110]).count() as u64;
    let coloured = mask
        .chunks(3)
        .filter(|p| *p != [110, 110, 110] && *p != [0, 0, 0])
        .count() as u64;
    println!("shaded-pixel view: {grey} grey (up-sampled), {coloured} coloured (shaded)");
    for (what, seen, counted) in [
        ("up-sampled", grey, upsampled),
        ("shaded", coloured, shaded),
    ] {
        assert!(
            seen.abs_diff(counted) * 100 <= surface,
            "{what}: {seen} pixels in the view, {counted} in the frame"
        );
    }
    // The bandwidth view: a heat map over a positive range of b_p.
    let range = &read_json(&out.join("bandwidth.json"))["adaptive"]["heat_range"];
    let (lo, hi) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
    assert!(lo > 0.0 && hi > lo, "b_p heat map range {range}");
}

#[test]
fn viewer_refuses_bad_input_and_missing_devices_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("bad.txt"), "walk forward 1\nfly 3\n").unwrap();
    for (args, says) in [
        (vec!["--script", "bad.txt"], "line 2"),
        (vec!["--script", "missing.txt"], "missing.txt"),
        (vec!["nope.toml"], "no such scene file"),
        (vec!["--scale", "2"], "--scale"),
        (vec!["--size", "10x10"], "--size"),
        (vec!["--samples", "0"], "--samples"),
        (vec!["--probe-size", "0"], "--probe-size"),
        (
            vec!["--env", "sky.hdr"],
            "--env sky.hdr: applies to --material and --lineup",
        ),
        (vec!["--lineup", "--env", "missing.hdr"], "missing.hdr"),
        (
            vec!["--material", "nbrdf:no-such-paint"],
            "--material nbrdf:no-such-paint",
        ),
        (
            vec!["--material", "nbrdf:gold-paint", "--lineup"],
            "--lineup",
        ),
    ] {
        let o = lustre()
            .current_dir(d)
            .arg("view")
            .args(&args)
            .output()
            .unwrap();
        let all = text(&o);
        assert!(!o.status.success() && all.contains(says), "{args:?}: {all}");
    }
    // The adaptive method on a scene without an environment (a floor and a block under a
    // rectangle light, baked at tiny settings): the light is an area light of the adaptive
    // method (`scene_lights`), which renders, and the regular method renders after it. (A
    // scene that nothing lights is refused by name: lustre-view's unit test.)
    std::fs::write(
        d.join("floor.obj"),
        "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nv -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 1 -0.5\n\
         v -0.5 1 -0.5\nf 1 3 2\nf 1 4 3\nf 5 8 7\nf 5 7 6\n",
    )
    .unwrap();
    std::fs::write(
        d.join("dark.toml"),
        "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"floor.obj\"\n\
         [[emitter]]\nshape = \"rectangle\"\nradiance = [5.0, 5.0, 5.0]\n\
         transform = [0.5, 0, 0, 0,  0, 0, -0.5, 3,  0, 0.5, 0, 0,  0, 0, 0, 1]\n",
    )
    .unwrap();
    let o = lustre()
        .current_dir(d)
        .args([
            "bake",
            "dark.toml",
            "--out",
            "dark",
            "--spp",
            "4",
            "--bounces",
            "2",
        ])
        .args(["--texels-per-metre", "8"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    std::fs::write(
        d.join("dark.txt"),
        "method adaptive\nscreenshot a.png\nmethod regular\nscreenshot r.png\nquit\n",
    )
    .unwrap();
    let o = view_in_xvfb(
        d,
        &[
            "dark/scene.toml",
            "--size",
            "640x400",
            "--script",
            "dark.txt",
            "--timeout",
            "300",
        ],
    );
    let all = text(&o);
    assert!(
        o.status.success() && !all.contains("adaptive method:") && !all.contains("panicked"),
        "{all}"
    );
    let adaptive = read_json(&d.join("lustre-view/a.json"));
    assert!(adaptive["step_ms"].as_f64().is_some(), "{adaptive}");
    let regular = read_json(&d.join("lustre-view/r.json"));
    assert!(regular["step_ms"].as_f64().is_some(), "{regular}");
    // No display: a message, not a panic or a hang.
    let o = lustre()
        .current_dir(d)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .args(["view", "--frames", "1"])
        .output()
        .unwrap();
    let all = text(&o);
    assert!(
        !o.status.success() && all.contains("no window system") && !all.contains("panicked"),
        "{all}"
    );
    // No adapter (a Vulkan loader pointed at no driver): a message and a non-zero exit.
    let o = Command::new("xvfb-run")
        .current_dir(d)
        .env("WGPU_BACKEND", "vulkan")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .args(["-a", env!("CARGO_BIN_EXE_lustre"), "view", "--frames", "1"])
        .args(["--timeout", "120"])
        .output()
        .expect("xvfb-run (apt-get install xvfb xauth)");
    let all = text(&o);
    assert!(
        !o.status.success() && all.contains("no GPU adapter") && !all.contains("panicked"),
        "{all}"
    );
}

/// The 3D view of screenshot `stem` (its PNG and JSON in `out`; shown at --scale 1): the rectangle (x, y, w, h) in
/// the window, its RGB bytes, and the JSON.
fn view_of(out: &Path, stem: &str) -> ((u32, u32, u32, u32), Vec<u8>, serde_json::Value) {
    let side = read_json(&out.join(format!("{stem}.json")));
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("{stem}: {side}"));
    let rect = (
        num(&side["view"]["rect"][0]).round() as u32,
        num(&side["view"]["rect"][1]).round() as u32,
        num(&side["view"]["size"][0]) as u32,
        num(&side["view"]["size"][1]) as u32,
    );
    // Shown pixel for pixel (--scale 1).
    let shown = (
        num(&side["view"]["rect"][2]).round() as u32,
        num(&side["view"]["rect"][3]).round() as u32,
    );
    assert_eq!(shown, (rect.2, rect.3), "{stem}: {side}");
    let png = image::open(out.join(format!("{stem}.png")))
        .unwrap_or_else(|e| panic!("{stem}.png: {e}"))
        .to_rgba8();
    (rect, crop(&png, rect), side)
}

/// Mean of 8-bit values.
fn mean8(p: &[u8]) -> f64 {
    p.iter().map(|&c| f64::from(c)).sum::<f64>() / p.len().max(1) as f64
}

/// Checks the adaptive view of screenshot `stem` in `dir/out` against `lustre render --method
/// adaptive SCENE_ARGS` from its camera (seed 1, the view's size, 8 samples, no supersampling,
/// as the viewer): a lit view, the CLI's image finite, PSNR ≥ [`ADAPTIVE_PSNR_MIN`] and the
/// mean 8-bit level within 2 %. Returns the view's mean level and its pixels.
fn check_adaptive_view(dir: &Path, out: &str, stem: &str, scene_args: &[&str]) -> (f64, Vec<u8>) {
    let ((_, _, w, h), shown, side) = view_of(&dir.join(out), stem);
    assert_eq!(side["method"], "adaptive", "{side}");
    let a = &side["adaptive"];
    let count = |k: &str| a[k].as_u64().unwrap_or_else(|| panic!("{k}: {a}"));
    let (surface, shaded, upsampled) = (
        count("surface_pixels"),
        count("shaded_pixels"),
        count("upsampled_pixels"),
    );
    assert!(surface > 0 && shaded + upsampled == surface, "{a}");
    println!(
        "{stem}: adaptive frame {w}×{h} in the viewer: {shaded} of {surface} surface pixels \
         shaded; G-buffer {:.0} ms, bandwidth pass {:.0} ms (GPU: {}), shading {:.0} ms (GPU: \
         {}); the step {:.0} ms; material tables {:.0} ms (the scene's first adaptive frame)",
        a["gbuffer_ms"].as_f64().unwrap_or(f64::NAN),
        a["bandwidth_ms"].as_f64().unwrap_or(f64::NAN),
        a["bandwidth_on_gpu"],
        a["shading_ms"].as_f64().unwrap_or(f64::NAN),
        a["shading_on_gpu"],
        side["step_ms"].as_f64().unwrap_or(f64::NAN),
        a["tables_ms"].as_f64().unwrap_or(f64::NAN),
    );
    let o = lustre()
        .current_dir(dir)
        .args([
            "render", "--method", "adaptive", "--out", "cli", "--spp", "1",
        ])
        .args([
            "--samples",
            "8",
            "--seed",
            "1",
            "--size",
            &format!("{w}x{h}"),
        ])
        .args(["--path", &format!("{out}/{stem}.camera.json")])
        .args(scene_args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let frame = Image::read_exr(&dir.join("cli/frame_0000.exr")).unwrap();
    assert_eq!((frame.width, frame.height), (w as usize, h as usize));
    assert!(frame.data.iter().flatten().all(|c| c.is_finite()));
    let rendered = frame.to_srgb8(side["exposure"].as_f64().unwrap());
    let psnr = psnr8(&shown, &rendered);
    let (m_view, m_cli) = (mean8(&shown), mean8(&rendered));
    println!(
        "{stem}: viewer vs lustre render --method adaptive {scene_args:?}: {psnr:.2} dB, mean \
         8-bit level {m_view:.2} vs {m_cli:.2}"
    );
    assert!(
        psnr >= ADAPTIVE_PSNR_MIN,
        "{stem}: viewer vs lustre render: {psnr:.2} dB"
    );
    assert!(
        (m_view - m_cli).abs() <= 0.02 * m_cli,
        "{stem}: mean level {m_view:.2} in the viewer, {m_cli:.2} from lustre render"
    );
    (m_view, shown)
}

#[test]
fn viewer_opens_a_measured_material_adaptive_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("gold.txt"),
        "screenshot gold.png\n\
         buffer shaded\n\
         screenshot mask.png\n\
         buffer bandwidth\n\
         screenshot bandwidth.png\n\
         buffer image\n\
         method regular\n\
         screenshot refused.png\n\
         select nbrdf:gold-paint\n\
         material lambert(kd=0.5)\n\
         screenshot swapped.png\n\
         quit\n",
    )
    .unwrap();
    let o = view_in_xvfb(
        d,
        &[
            "--material",
            "nbrdf:gold-paint",
            "--size",
            "640x360",
            "--scale",
            "1",
            "--samples",
            "8",
            "--adaptive-device",
            "gpu",
            "--script",
            "gold.txt",
            "--timeout",
            "600",
        ],
    );
    let all = text(&o);
    assert!(o.status.success() && !all.contains("panicked"), "{all}");
    // Adaptive-only from the start, said with the material; the regular method refused by
    // name, and the view stays in the adaptive method.
    let why = "material \"nbrdf:gold-paint\" (nbrdf:gold-paint): not on the GPU walkthrough \
               in this build — use the adaptive method";
    assert!(
        all.contains(&format!("adaptive method only: {why}")),
        "{all}"
    );
    assert!(
        all.contains(&format!("regular method refused: {why}")),
        "{all}"
    );
    let out = d.join("lustre-view");
    assert_eq!(read_json(&out.join("refused.json"))["method"], "adaptive");

    // The gold sphere under the built-in sky, as `lustre render --method adaptive` shows it;
    // its mean level measured at 640×360, --scale 1 (a 134×319 view): 86.5.
    let (level, gold) = check_adaptive_view(
        d,
        "lustre-view",
        "gold",
        &["--material", "nbrdf:gold-paint"],
    );
    assert!(
        (80.0..=93.0).contains(&level),
        "mean 8-bit level {level:.2} of the gold sphere's view"
    );
    // --adaptive-device gpu: both passes ran on the GPU (lavapipe in CI), and the view above
    // matched the CLI's frame, which `--device auto` renders on the CPU on a software adapter.
    let (_, _, side) = view_of(&out, "gold");
    let a = &side["adaptive"];
    assert!(
        a["bandwidth_on_gpu"] == true && a["shading_on_gpu"] == true,
        "{a}"
    );

    // The shaded-pixel view: as many grey (up-sampled) and coloured (shaded) pixels as the
    // frame counted; the bandwidth view over a positive range of b_p.
    let (_, mask, side) = view_of(&out, "mask");
    let a = &side["adaptive"];
    assert_eq!(a["buffer"], "shaded", "{a}");
    let grey = mask.chunks(3).filter(|p| *p == [110, 110, 110]).count() as u64;
    let coloured = mask
        .chunks(3)
        .filter(|p| *p != [110, 110, 110] && *p != [0, 0, 0])
        .count() as u64;
    let surface = a["surface_pixels"].as_u64().unwrap();
    for (what, seen, counted) in [
        ("up-sampled", grey, &a["upsampled_pixels"]),
        ("shaded", coloured, &a["shaded_pixels"]),
    ] {
        let counted = counted.as_u64().unwrap();
        assert!(
            counted > 0 && seen.abs_diff(counted) * 100 <= surface,
            "{what}: {seen} pixels in the view, {counted} in the frame"
        );
    }
    let range = &read_json(&out.join("bandwidth.json"))["adaptive"]["heat_range"];
    let (lo, hi) = (range[0].as_f64().unwrap(), range[1].as_f64().unwrap());
    assert!(lo > 0.0 && hi > lo, "b_p heat map range {range}");

    // The swap applies to the adaptive method: a grey Lambert sphere in place of the gold.
    let (_, swapped, side) = view_of(&out, "swapped");
    assert_eq!(side["method"], "adaptive", "{side}");
    assert_eq!(
        side["set"],
        serde_json::json!(["nbrdf:gold-paint.spec=lambert(kd=0.5)"]),
        "{side}"
    );
    let changed = gold
        .chunks(3)
        .zip(swapped.chunks(3))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    assert!(changed > 2000, "the swap changed {changed} pixels");
}

#[test]
fn viewer_opens_the_line_up_and_an_unbaked_measured_scene_adaptive_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let env = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/envmaps/royal_esplanade_1k.hdr"
    );
    // 004 Fig. IV.13's line-up under the Royal Esplanade: the CK method refused by the first
    // paint's name.
    std::fs::write(
        d.join("lineup.txt"),
        "screenshot lineup.png\nmethod ck\nquit\n",
    )
    .unwrap();
    let o = view_in_xvfb(
        d,
        &[
            "--lineup",
            "--env",
            env,
            "--size",
            "640x360",
            "--scale",
            "1",
            "--out",
            "lineup",
            "--script",
            "lineup.txt",
            "--timeout",
            "600",
        ],
    );
    let all = text(&o);
    assert!(o.status.success() && !all.contains("panicked"), "{all}");
    assert!(
        all.contains(
            "ck method refused: material \"nbrdf:color-changing-paint3\" \
             (nbrdf:color-changing-paint3): not on the GPU walkthrough"
        ),
        "{all}"
    );
    check_adaptive_view(d, "lineup", "lineup", &["--env", env]);
    // --adaptive-device auto: the GPU passes, unless the adapter is a software rasterizer
    // (lavapipe), which is slower than the CPU path; the view says which and why.
    let (_, _, side) = view_of(&d.join("lineup"), "lineup");
    let a = &side["adaptive"];
    let software = side["adapter"].as_str().is_some_and(|s| s.contains("Cpu"));
    assert_eq!(a["bandwidth_on_gpu"], !software, "{side}");
    assert_eq!(a["shading_on_gpu"], !software, "{side}");
    if software {
        assert!(
            a["why_cpu"]
                .as_str()
                .is_some_and(|w| w.contains("software rasterizer")),
            "{a}"
        );
    }

    // A scene file of a measured material, not baked: a floor and a block of gold paint under
    // a constant sky.
    std::fs::write(
        d.join("floor.obj"),
        "mtllib floor.mtl\nusemtl grey\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\n\
         f 1 4 3\nusemtl metal\nv -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 1 -0.5\nv -0.5 1 -0.5\n\
         f 5 8 7\nf 5 7 6\n",
    )
    .unwrap();
    std::fs::write(
        d.join("floor.mtl"),
        "newmtl grey\nKd 0.6 0.6 0.6\nnewmtl metal\nKd 0.5 0.5 0.5\n",
    )
    .unwrap();
    std::fs::write(
        d.join("gold.toml"),
        "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"floor.obj\"\n\
         [environment]\nconstant = [1.0, 1.0, 1.0]\n\
         [materials]\nmetal = \"nbrdf:gold-paint\"\n",
    )
    .unwrap();
    std::fs::write(
        d.join("file.txt"),
        "screenshot file.png\nmethod progressive\nquit\n",
    )
    .unwrap();
    let o = view_in_xvfb(
        d,
        &[
            "gold.toml",
            "--size",
            "640x360",
            "--scale",
            "1",
            "--out",
            "file",
            "--script",
            "file.txt",
            "--timeout",
            "600",
        ],
    );
    let all = text(&o);
    assert!(o.status.success() && !all.contains("panicked"), "{all}");
    assert!(
        all.contains(
            "progressive method refused: material \"metal\" (nbrdf:gold-paint): not on the \
             GPU walkthrough"
        ),
        "{all}"
    );
    check_adaptive_view(d, "file", "file", &["gold.toml"]);
}

/// The viewer on the sunroom baked with the automatic set-up (room probe included, captured by
/// the viewer's walkthrough as by `lustre render`): `setup on` draws the room box (cyan), the
/// object probes (yellow) and the reflectors (magenta) over the frame; without it none of the
/// three colours is there.
#[test]
fn viewer_shows_the_automatic_set_up() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let sunroom = std::fs::canonicalize("../../scenes/sunroom/scene.xml").unwrap();
    let o = lustre()
        .current_dir(d)
        .arg("bake")
        .arg(&sunroom)
        .args(["--out", "sun", "--spp", "1", "--bounces", "1"])
        .args(["--texels-per-metre", "2"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    std::fs::write(
        d.join("setup.txt"),
        "screenshot plain.png\nsetup on\nscreenshot setup.png\nquit\n",
    )
    .unwrap();
    let o = view_in_xvfb(
        d,
        &[
            "sun/scene.toml",
            "--size",
            "640x400",
            "--probe-size",
            "16",
            "--script",
            "setup.txt",
            "--timeout",
            "300",
        ],
    );
    let all = text(&o);
    assert!(o.status.success() && !all.contains("panicked"), "{all}");
    let count = |file: &str, f: &dyn Fn(&image::Rgba<u8>) -> bool| {
        let img = image::open(d.join("lustre-view").join(file))
            .unwrap()
            .to_rgba8();
        img.pixels().filter(|p| f(p)).count()
    };
    let cyan = |p: &image::Rgba<u8>| p[0] < 40 && p[1] > 190 && p[2] > 230;
    let magenta = |p: &image::Rgba<u8>| p[0] > 230 && p[1] < 90 && p[2] > 200;
    let yellow = |p: &image::Rgba<u8>| p[0] > 230 && p[1] > 200 && p[2] < 40;
    for (name, f) in [
        ("cyan", &cyan as &dyn Fn(&image::Rgba<u8>) -> bool),
        ("magenta", &magenta),
        ("yellow", &yellow),
    ] {
        let (before, after) = (count("plain.png", f), count("setup.png", f));
        assert!(
            after > 50 && after > 10 * before,
            "{name}: {before} → {after}"
        );
    }
}
