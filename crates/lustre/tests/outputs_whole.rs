//! Outputs whole or absent on a full disk, and the messages of the remaining bounds.
//!
//! A full disk is the file-size limit (`ulimit -f`, with SIGXFSZ ignored, so that a write past
//! it fails with EFBIG as on a full file system): every command must fail with the file it
//! was writing named, leave no temporary or half-written file, and remove the folder it made
//! when nothing reusable is in it.

mod common;

use common::{fails, lustre, ok, text};
use std::path::{Path, PathBuf};
use std::process::Command;

fn cornell() -> PathBuf {
    lustre_brdf::shared_data_dir().join("scenes/cornell_box/cornell_box.obj")
}

/// `lustre ARGS` with writes limited to `kib` KiB a file (0: no file can grow at all).
fn on_full_disk(kib: u32, args: &[&str]) -> Command {
    let mut c = Command::new("bash");
    c.env("RUST_BACKTRACE", "0")
        .arg("-c")
        .arg(format!("trap '' XFSZ; ulimit -f {kib}; exec \"$@\""))
        .arg("bash")
        .arg(env!("CARGO_BIN_EXE_lustre"))
        .args(args);
    c
}

/// Every file under `dir`, relative paths.
fn files(dir: &Path) -> Vec<String> {
    let mut out = vec![];
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap_or(&p);
                out.push(rel.display().to_string());
            }
        }
    }
    out.sort();
    out
}

/// A write failure: the file named, EFBIG's words, no hidden temporary file named.
fn assert_disk_full(t: &str, file: &str) {
    assert!(t.contains(file), "{t}");
    assert!(t.contains("File too large"), "{t}");
    assert!(!t.contains(".tmp") && !t.contains(".lustre-plot-"), "{t}");
}

#[test]
fn a_full_disk_leaves_whole_files_or_none() {
    // Not `.tmp…`: the messages must not name a hidden temporary file.
    let dir = tempfile::Builder::new()
        .prefix("full-disk-")
        .tempdir()
        .expect("dir");
    let d = dir.path();
    let at = |name: &str| d.join(name).display().to_string();

    // reference: its first checkpoint half fails; no `.next` file, no image.
    let reference = d.join("ref");
    std::fs::create_dir_all(&reference).expect("mkdir");
    let exr = reference.join("r.exr").display().to_string();
    let t = fails(&mut on_full_disk(
        64,
        &[
            "reference",
            "--size",
            "128x128",
            "--spp",
            "2",
            "--out",
            &exr,
        ],
    ));
    assert_disk_full(&t, "r.even.next.exr");
    assert_eq!(files(&reference), Vec::<String>::new());

    // render: the frame fails; the folder it made is gone.
    let render = at("render");
    let t = fails(&mut on_full_disk(
        16,
        &[
            "render",
            "--material",
            "sgd:nickel",
            "--device",
            "cpu",
            "--size",
            "96x96",
            "--samples",
            "2",
            "--out",
            &render,
        ],
    ));
    assert_disk_full(&t, "frame.exr");
    assert!(!Path::new(&render).exists(), "{t}");

    // fit, compare, plot (both kinds): nothing written, no folder left.
    let fit = at("fit");
    let t = fails(&mut on_full_disk(
        0,
        &["fit", "sgd:nickel", "--model", "ggx", "--out", &fit],
    ));
    assert_disk_full(&t, "summary.csv");
    assert!(!Path::new(&fit).exists(), "{t}");
    let compare = at("compare");
    let t = fails(&mut on_full_disk(
        0,
        &[
            "compare",
            "--size",
            "32",
            "--face-size",
            "16",
            "--out",
            &compare,
        ],
    ));
    assert_disk_full(&t, ".png");
    assert!(!Path::new(&compare).exists(), "{t}");
    for args in [vec!["plot", "sgd:nickel"], vec!["plot", "--pattern", "all"]] {
        let plots = at("plots");
        let mut all = args.clone();
        all.extend(["--out", &plots]);
        let t = fails(&mut on_full_disk(4, &all));
        assert_disk_full(&t, ".png");
        assert!(!Path::new(&plots).exists(), "{t}");
    }

    // Single files: merl synth, bandwidth, demo.
    let binary = at("x.binary");
    let t = fails(&mut on_full_disk(
        0,
        &["merl", "synth", "--from", "sgd:nickel", "-o", &binary],
    ));
    assert_disk_full(&t, "x.binary");
    let png = at("b.png");
    let t = fails(&mut on_full_disk(
        0,
        &["bandwidth", "--material", "sgd:nickel", "--out", &png],
    ));
    assert_disk_full(&t, "b.png");
    let demo = at("demo.png");
    let t = fails(&mut on_full_disk(
        0,
        &["demo", "--cpu", "--size", "64x64", "--out", &demo],
    ));
    assert_disk_full(&t, "demo.png");
    let left: Vec<String> = files(d)
        .into_iter()
        .filter(|f| !f.starts_with("ref"))
        .collect();
    assert_eq!(left, Vec::<String>::new());

    // bake: the first tile fails; what is left (the atlas, the lock) is whole and resumes.
    let bake = d.join("bake");
    let scene = cornell();
    let scene = scene.to_str().expect("utf-8 path");
    let bake_args = [
        "bake",
        scene,
        "--spp",
        "1",
        "--bounces",
        "1",
        "--texels-per-metre",
        "0.25",
        "--no-denoise",
        "--out",
    ];
    let mut args = bake_args.to_vec();
    let out = bake.display().to_string();
    args.push(&out);
    let t = fails(&mut on_full_disk(16, &args));
    assert_disk_full(&t, "page0_tile00000.bin");
    assert_eq!(files(&bake), ["lightmap.glb", "tiles/all.lock"], "{t}");
    let t = ok(lustre().args(&args));
    assert!(t.contains("wrote"), "{t}");
    assert!(bake.join("scene.toml").is_file());
}

#[test]
fn a_render_refuses_a_frame_too_large_before_it_bakes() {
    let dir = tempfile::tempdir().expect("dir");
    let out = dir.path().join("r");
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "2G")
            .arg("render")
            .arg(cornell())
            .args(["--size", "8000x8000", "--out"])
            .arg(&out),
    );
    assert!(
        t.contains("lustre render at 8000×8000 needs about")
            && t.contains("but 2.0 GB of memory are available"),
        "{t}"
    );
    assert!(!t.contains("baking"), "{t}");
    assert!(!out.exists());
}

#[test]
fn a_bake_without_a_density_fits_a_scene_in_millimetres() {
    // The Cornell box is in millimetres: 32 texels per unit would need 17899×22960 texels
    // for its floor alone.
    let dir = tempfile::tempdir().expect("dir");
    let t = ok(lustre()
        .arg("bake")
        .arg(cornell())
        .arg("--plan")
        .arg("--out")
        .arg(dir.path().join("b")));
    assert!(t.contains("atlas: 2 texels per scene unit, not 32"), "{t}");
    assert!(t.contains("1 page(s) of 2246×3898"), "{t}");
}

#[test]
fn the_remaining_bounds_say_what_to_change_in_plain_numbers() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    let plots = d.join("p");
    let plot = |args: &[&str]| {
        let o = lustre()
            .arg("plot")
            .args(args)
            .arg("--out")
            .arg(&plots)
            .output()
            .expect("runs");
        assert!(!o.status.success());
        assert!(!plots.exists());
        text(&o)
    };
    let t = plot(&["--pattern", "all", "--mx", "1e308"]);
    assert!(t.contains("--mx = 1e308: must lie in [1e-6, 10]"), "{t}");
    let t = plot(&["--pattern", "all", "--xi0", "nan"]);
    assert!(t.contains("--xi0 NaN: must lie in (0, 1)"), "{t}");
    let t = plot(&["sgd:nickel", "--phi-i", "1e308"]);
    assert!(t.contains("φi = 1e308° must lie in [-360°, 360°]"), "{t}");
    let many = (1..=17)
        .map(|k| k.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let t = plot(&["sgd:nickel", "--theta-i", &many]);
    assert!(t.contains("at most 16 θi"), "{t}");

    // An output folder that does not exist is named, not the hidden temporary file.
    let t = fails(
        lustre()
            .args(["bandwidth", "--material", "sgd:nickel", "--out"])
            .arg(d.join("nodir/b.png")),
    );
    assert!(
        t.contains("nodir: no such folder (the output's folder must exist)"),
        "{t}"
    );
    assert!(!t.contains(".lustre-plot-"), "{t}");

    // A material path that is not a material file says what is wrong with it.
    let t = fails(lustre().args(["score", "sgd:nickel", "/dev/zero"]));
    assert!(
        t.contains("/dev/zero: a character device, not a regular file"),
        "{t}"
    );
    assert!(!t.contains("not a built-in"), "{t}");
    let txt = d.join("notes.txt");
    std::fs::write(&txt, "x").expect("write");
    let t = fails(lustre().arg("info").arg(&txt));
    assert!(t.contains("notes.txt: unknown extension"), "{t}");

    // The viewer's unattended timeout is bounded (a Duration of 1e300 s would not exist).
    let t = fails(lustre().args(["view", "--frames", "1", "--timeout", "1e300"]));
    assert!(
        t.contains("--timeout 1e300: must be positive and at most 604800 s"),
        "{t}"
    );
}

#[test]
fn an_environment_map_is_counted_from_its_header_before_it_is_decoded() {
    // A Radiance header declaring 65536×32768 texels (128 GB decoded) over 4 KB of data.
    let dir = tempfile::tempdir().expect("dir");
    let map = dir.path().join("huge.hdr");
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32768 +X 65536\n".to_vec();
    bytes.extend(std::iter::repeat_n([2u8, 2, 1, 0], 1024).flatten());
    std::fs::write(&map, bytes).expect("write");
    let budget = "reading the environment map";
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "8G")
            .args(["bandwidth", "--map"])
            .arg(&map)
            .args(["--out"])
            .arg(dir.path().join("b.png")),
    );
    assert!(
        t.contains(budget)
            && t.contains("(65536×32768) needs about 128 GB of memory")
            && t.contains("give --map a smaller map, or pass --force"),
        "{t}"
    );
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "8G")
            .args([
                "render",
                "--material",
                "sgd:nickel",
                "--device",
                "cpu",
                "--env",
            ])
            .arg(&map)
            .args(["--out"])
            .arg(dir.path().join("r")),
    );
    assert!(
        t.contains(budget) && t.contains("give --env a smaller map"),
        "{t}"
    );
    // Forced, the reader's own check refuses what the file cannot hold.
    let t = fails(
        lustre()
            .args(["bandwidth", "--force", "--map"])
            .arg(&map)
            .args(["--out"])
            .arg(dir.path().join("b.png")),
    );
    assert!(
        t.contains("truncated: 65536×32768 pixels cannot fit in"),
        "{t}"
    );
    assert!(!dir.path().join("r").exists() && !dir.path().join("b.png").exists());
}
