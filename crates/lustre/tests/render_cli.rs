//! `lustre render` end to end on a tiny baked scene (an OBJ floor and a gold block under a
//! constant sky, the block a probe object): the frame files, the stage times, each method, the
//! reference comparison, and clear errors for a scene without light maps, bad sample counts and
//! a reference of another size.

use lustre_trace::image::Image;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

const MTL: &str = "newmtl grey\nKd 0.6 0.6 0.6\nnewmtl metal\nKd 0.5 0.5 0.5\n";

const OBJ: &str = "mtllib floor.mtl\nusemtl grey\no floor\n\
v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\nf 1 4 3\n\
o block\nusemtl metal\n\
v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 1 -0.5\nv -0.5 1 -0.5\n\
v -0.5 0 0.5\nv 0.5 0 0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n\
f 5 8 7\nf 5 7 6\nf 9 10 11\nf 9 11 12\nf 5 9 12\nf 5 12 8\nf 6 7 11\nf 6 11 10\nf 8 12 11\nf 8 11 7\n";

/// The scene file: the OBJ under a constant sky, the block made of rough gold, and `extra`.
fn write_scene(dir: &Path, extra: &str) -> PathBuf {
    std::fs::write(dir.join("floor.obj"), OBJ).unwrap();
    std::fs::write(dir.join("floor.mtl"), MTL).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        format!(
            "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"floor.obj\"\n\
             [environment]\nconstant = [1.0, 1.0, 1.0]\n\
             [materials]\nmetal = \"roughconductor(material=Au, alpha=0.2)\"\n{extra}"
        ),
    )
    .unwrap();
    scene
}

fn bake(scene: &Path, out: &Path) {
    let o = lustre()
        .arg("bake")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--spp", "4", "--bounces", "2", "--texels-per-metre", "8"])
        .args(["--setup", "manual"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn render(scene: &Path, out: &Path, args: &[&str]) -> Output {
    lustre()
        .arg("render")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--size", "48x32", "--probe-size", "32"])
        .args(args)
        .output()
        .unwrap()
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// The PSNR `--compare-reference` printed.
fn psnr_of(output: &str) -> f64 {
    output
        .split("PSNR ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no PSNR in {output}"))
}

#[test]
fn render_writes_a_frame_times_and_a_comparison() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "[objects.block]\nprobe = true\n");
    let baked = dir.path().join("baked");
    bake(&scene, &baked);
    let frames = dir.path().join("frames");
    let o = render(&baked.join("scene.toml"), &frames, &["--samples", "8"]);
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    assert!(all.contains("probe \"block\""), "{all}");
    // At most the budget of 8 lookups per glossy hit (samples the warp rejects make none).
    let per_hit: f64 = all
        .split(" lookups per glossy hit")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{all}"));
    assert!(per_hit > 6.0 && per_hit <= 8.0, "{per_hit}");
    let png = Image::read_exr(&frames.join("frame.png")).unwrap();
    assert_eq!((png.width, png.height), (48, 32));
    let times = std::fs::read_to_string(frames.join("times.csv")).unwrap();
    for stage in ["stage,seconds", "probe block,", "frame,", "total,"] {
        assert!(times.contains(stage), "{stage} missing: {times}");
    }
    // The frame against itself, and against a different method.
    let reference = dir.path().join("self.exr");
    std::fs::copy(frames.join("frame.exr"), &reference).unwrap();
    let o = render(
        &baked.join("scene.toml"),
        &frames,
        &[
            "--samples",
            "8",
            "--compare-reference",
            reference.to_str().unwrap(),
        ],
    );
    let all = text(&o);
    assert!(o.status.success() && all.contains("PSNR inf dB"), "{all}");
    assert!(frames.join("diff.png").is_file());
    for method in ["ck", "progressive"] {
        let o = render(
            &baked.join("scene.toml"),
            &dir.path().join(method),
            &[
                "--samples",
                "4",
                "--method",
                method,
                "--frames",
                "4",
                "--compare-reference",
                reference.to_str().unwrap(),
            ],
        );
        let all = text(&o);
        assert!(o.status.success(), "{method}: {all}");
        let psnr = psnr_of(&all);
        assert!(psnr.is_finite() && psnr > 20.0, "{method}: {psnr} dB");
        if method == "progressive" {
            // On the GPU the session steps 4 still frames: the first frame's time and the
            // median of the 3 still frames; on the CPU the 4 frames in one pass.
            let times = std::fs::read_to_string(dir.path().join(method).join("times.csv")).unwrap();
            if all.contains("rendered on the GPU") {
                assert!(
                    all.contains("a still frame") && all.contains("(median of 3)"),
                    "{all}"
                );
                for stage in ["frame,", "frame: first frame,", "frame: still frame,"] {
                    assert!(times.contains(stage), "{stage} missing: {times}");
                }
            } else {
                assert!(
                    all.contains("progressive refinement on the CPU: 4 frame(s)"),
                    "{all}"
                );
            }
        }
    }
    // A reference of another size is refused, naming both sizes.
    let other = dir.path().join("other.exr");
    Image::from_data(40, 30, vec![[0.5; 3]; 1200])
        .unwrap()
        .write_exr(&other)
        .unwrap();
    let o = render(
        &baked.join("scene.toml"),
        &frames,
        &["--compare-reference", other.to_str().unwrap()],
    );
    let all = text(&o);
    assert!(
        !o.status.success() && all.contains("48×32") && all.contains("40×30"),
        "{all}"
    );
}

#[test]
fn render_refuses_bad_input_and_says_what_it_renders() {
    let dir = tempfile::tempdir().unwrap();
    // A scene without light maps is baked on first use (with the automatic set-up: the gold
    // block gets a probe, the open floor no room probe), reused while it is unchanged, and
    // baked again once it changes.
    let scene = write_scene(dir.path(), "");
    let x = dir.path().join("x");
    let o = render(&scene, &x, &[]);
    let all = text(&o);
    assert!(
        o.status.success()
            && all.contains("has no light maps: baking them")
            && all.contains("real-time set-up: 0 mirror pass(es), 1 object probe(s) (block)")
            && all.contains("0 room probe(s)"),
        "{all}"
    );
    let toml = std::fs::read_to_string(x.join("bake/scene.toml")).unwrap();
    assert!(toml.contains("[objects.block]\nprobe = true"), "{toml}");
    let o = render(&scene, &x, &[]);
    let all = text(&o);
    assert!(o.status.success() && all.contains("reusing"), "{all}");
    let scene = write_scene(dir.path(), "[objects.block]\ndiffuse_only = true\n");
    let o = render(&scene, &x, &[]);
    let all = text(&o);
    assert!(
        o.status.success() && all.contains("baking them") && !all.contains("reusing"),
        "{all}"
    );
    let toml = std::fs::read_to_string(x.join("bake/scene.toml")).unwrap();
    assert!(
        toml.contains("[objects.block]\ndiffuse_only = true"),
        "{toml}"
    );
    let scene = write_scene(dir.path(), "");
    // No probe objects (baked with --setup manual): the environment only, and it says so.
    let baked = dir.path().join("baked");
    bake(&scene, &baked);
    let o = render(
        &baked.join("scene.toml"),
        &dir.path().join("f"),
        &["--samples", "4"],
    );
    let all = text(&o);
    assert!(
        o.status.success()
            && all.contains("no probe objects: glossy surfaces reflect the environment only"),
        "{all}"
    );
    for samples in ["0", "257"] {
        let o = render(
            &baked.join("scene.toml"),
            &dir.path().join("f"),
            &["--samples", samples],
        );
        let all = text(&o);
        assert!(
            !o.status.success() && all.contains("glossy samples"),
            "{all}"
        );
    }
    let o = render(
        &baked.join("scene.toml"),
        &dir.path().join("f"),
        &["--method", "progressive", "--frames", "0"],
    );
    assert!(
        !o.status.success() && text(&o).contains("0 frames"),
        "{}",
        text(&o)
    );
    let o = render(
        &baked.join("scene.toml"),
        &dir.path().join("f"),
        &["--camera", "nope"],
    );
    assert!(
        !o.status.success() && text(&o).contains("no camera named"),
        "{}",
        text(&o)
    );
    // A light-map page of the wrong size.
    let page = baked.join("lightmap_000.exr");
    Image::from_data(3, 3, vec![[1.0; 3]; 9])
        .unwrap()
        .write_exr(&page)
        .unwrap();
    let o = render(&baked.join("scene.toml"), &dir.path().join("f"), &[]);
    let all = text(&o);
    assert!(
        !o.status.success() && all.contains("lightmap_000.exr") && all.contains("3×3"),
        "{all}"
    );
}

#[test]
fn render_without_a_scene_renders_the_built_in_room() {
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &str, extra: &[&str]| {
        lustre()
            .current_dir(dir.path())
            .args(["render", "--out", out, "--size", "64x36", "--spp", "1"])
            .args(["--probe-size", "32"])
            .args(extra)
            .output()
            .unwrap()
    };
    // The converged integral of the same incident light, then the regular frame against it.
    let o = run("truth", &["--method", "progressive", "--frames", "64"]);
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    for probe in ["gold-paint", "brushed-aluminium", "frosted-glass"] {
        assert!(
            all.contains(&format!("probe \"{probe}\"")),
            "{probe}: {all}"
        );
    }
    assert!(
        all.contains("1 mirror and 1 see-through buffer(s)"),
        "{all}"
    );
    assert!(dir.path().join("truth/bake").is_dir());
    let truth = dir.path().join("truth/frame.exr");
    let img = Image::read_exr(&truth).unwrap();
    assert_eq!((img.width, img.height), (64, 36));
    // The bake is reused from the first run's folder only; a new --out bakes again, so share it.
    std::fs::rename(dir.path().join("truth/bake"), dir.path().join("bake")).unwrap();
    let o = run(
        ".",
        &[
            "--samples",
            "19",
            "--compare-reference",
            truth.to_str().unwrap(),
        ],
    );
    let all = text(&o);
    assert!(o.status.success(), "{all}");
    let psnr = psnr_of(&all);
    assert!(psnr > 35.0, "regular (19 samples) vs converged: {psnr} dB");
    // The same frame on the CPU and on the GPU (lavapipe in CI): the GPU says so, times its
    // passes, and agrees with the CPU's ray-cast frame up to the sampling of the pixels (16
    // jittered camera rays against a 4×4 supersampled G-buffer).
    let frame = |device: &str, extra: &[&str]| {
        lustre()
            .current_dir(dir.path())
            .args(["render", "--out", ".", "--size", "64x36", "--spp", "16"])
            .args(["--probe-size", "32", "--samples", "8", "--device", device])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = frame("cpu", &[]);
    let all = text(&o);
    assert!(
        o.status.success() && all.contains("rendered on the CPU"),
        "{all}"
    );
    std::fs::rename(dir.path().join("frame.exr"), dir.path().join("cpu.exr")).unwrap();
    let cpu = dir.path().join("cpu.exr");
    let o = frame("gpu", &["--compare-reference", cpu.to_str().unwrap()]);
    let all = text(&o);
    assert!(
        o.status.success() && all.contains("rendered on the GPU"),
        "{all}"
    );
    assert!(all.contains("captured on the GPU"), "{all}");
    let psnr = psnr_of(&all);
    println!("GPU vs CPU frame, 64×36, 16 camera rays per pixel: {psnr:.2} dB");
    assert!(psnr > 28.0, "GPU vs CPU frame: {psnr} dB");
    let times = std::fs::read_to_string(dir.path().join("times.csv")).unwrap();
    for stage in [
        "GPU mirror and see-through layers",
        "GPU G-buffer",
        "GPU light-map shading",
        "GPU view-dependent pass",
    ] {
        assert!(times.contains(stage), "{stage} missing: {times}");
    }
    // The built-in camera path, 2 s at 1 frame per second: frames 0, 1 and 2.
    let o = run(".", &["--path", "walk", "--fps", "1", "--samples", "4"]);
    assert!(o.status.success(), "{}", text(&o));
    for k in 0..3 {
        assert!(
            dir.path().join(format!("frame_{k:04}.png")).is_file(),
            "frame {k}"
        );
    }
    assert!(!dir.path().join("frame_0003.png").exists());
    let o = run(".", &["--path", "nope"]);
    assert!(
        !o.status.success() && text(&o).contains("no camera path named \"nope\" (paths: walk)"),
        "{}",
        text(&o)
    );
}

#[test]
fn render_material_previews_any_material_and_names_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let env = "../../../shared/data/envmaps/royal_esplanade_1k.hdr";
    let run = |out: &str, extra: &[&str]| {
        lustre()
            .current_dir(dir.path())
            .args(["render", "--out", out, "--size", "48x48", "--spp", "1"])
            .args(["--material", "roughconductor(material=Au, alpha=0.15)"])
            .args(extra)
            .output()
            .unwrap()
    };
    let env = std::path::Path::new(env_dir()).join(env);
    let env = env.to_str().unwrap();
    let o = run(
        "truth",
        &["--env", env, "--method", "progressive", "--frames", "64"],
    );
    assert!(o.status.success(), "{}", text(&o));
    let truth = dir.path().join("truth/frame.exr");
    // Regular sampling against the converged preview, well above Colbert–Křivánek (measured
    // at 96×96: regular 33.4 dB, CK 22.2 dB).
    let judge = |method: &str| {
        let reference = truth.to_str().unwrap();
        let args = ["--env", env, "--samples", "16", "--method", method];
        let o = run(
            method,
            &[&args[..], &["--compare-reference", reference]].concat(),
        );
        let all = text(&o);
        assert!(o.status.success(), "{all}");
        psnr_of(&all)
    };
    let (regular, ck) = (judge("regular"), judge("ck"));
    assert!(
        regular > 30.0 && regular > ck + 5.0,
        "regular {regular} dB, CK {ck} dB"
    );
    // Bad input is named.
    let o = run("x", &["--env", "nope.hdr"]);
    assert!(
        !o.status.success() && text(&o).contains("nope.hdr"),
        "{}",
        text(&o)
    );
    let o = lustre()
        .current_dir(dir.path())
        .args(["render", "--out", "x", "--material", "no-such-material"])
        .output()
        .unwrap();
    assert!(
        !o.status.success() && text(&o).contains("no-such-material"),
        "{}",
        text(&o)
    );
}

/// The crate's folder (tests run with it as the working directory).
fn env_dir() -> &'static str {
    env!("CARGO_MANIFEST_DIR")
}
