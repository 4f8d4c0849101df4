//! Every input bounded and every output whole: the budget check refuses jobs larger
//! than the machine (with both numbers and the option to change) before anything is written,
//! `--force` runs them anyway, special files are refused before they are opened, and a
//! resumable job refuses the checkpoint of another scene.

mod common;

use common::{fails, lustre, ok};
use std::path::{Path, PathBuf};
use std::process::Command;

fn cornell() -> PathBuf {
    lustre_brdf::shared_data_dir().join("scenes/cornell_box/cornell_box.obj")
}

/// A budget refusal: the job, its estimate, what the machine has, the option and --force.
fn assert_refused(t: &str, job: &str, option: &str) {
    assert!(t.contains(job), "{t}");
    assert!(t.contains("needs about"), "{t}");
    assert!(
        t.contains("of memory are available") || t.contains("of disk are free"),
        "{t}"
    );
    assert!(
        t.contains(option) && t.contains("or pass --force to run it anyway"),
        "{t}"
    );
}

#[test]
fn jobs_larger_than_the_machine_are_refused_before_they_start() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    // Jobs that used to abort ("memory allocation of N bytes failed", exit 134).
    // Frame sides are bounded on both devices (the GPU's texture limit).
    let png = d.join("demo.png");
    let t = fails(
        lustre()
            .args(["demo", "--cpu", "--size", "100000x100000", "--out"])
            .arg(&png),
    );
    assert!(t.contains("each side must be at most 16384"), "{t}");
    let out = d.join("render");
    let t = fails(
        lustre()
            .args(["render", "--material", "sgd:nickel", "--device", "cpu"])
            .args(["--size", "100000x100000", "--out"])
            .arg(&out),
    );
    assert!(t.contains("each side must be at most 16384"), "{t}");
    // Within the sides, the memory decides (a 4 GB machine, then an 8 GB one, here).
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "4G")
            .args(["demo", "--cpu", "--size", "16000x9000", "--out"])
            .arg(&png),
    );
    assert_refused(&t, "lustre demo at 16000×9000", "lower --size");
    assert!(
        t.contains("needs about 5.4 GB of memory (images 5.4 GB)"),
        "{t}"
    );
    assert!(!png.exists());
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "8G")
            .args(["render", "--material", "sgd:nickel", "--device", "cpu"])
            .args(["--size", "16384x16384", "--out"])
            .arg(&out),
    );
    assert_refused(&t, "lustre render at 16384×16384", "lower --size");
    assert!(!out.exists(), "no output folder for a refused job");

    let out = d.join("compare");
    let t = fails(
        lustre()
            .args(["compare", "--size", "100000", "--face-size", "16"])
            .args(["--reference-spp", "0", "--out"])
            .arg(&out),
    );
    assert_refused(
        &t,
        "lustre compare at 100000×100000",
        "lower --size or --face-size",
    );
    assert!(!out.exists());
    let t = fails(lustre().args(["compare", "--size", "0", "--out"]).arg(&out));
    assert!(t.contains("--size must be > 0"), "{t}");

    // The runaways: a 20000² reference (it used to grow past 6.9 GB) on a machine of
    // 4 GB, and a bake of 14 GB of tiles on a disk with 1 GB free.
    let exr = d.join("r.exr");
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "4G")
            .args(["reference", "--size", "20000x20000", "--spp", "1", "--out"])
            .arg(&exr),
    );
    assert_refused(&t, "lustre reference at 20000×20000", "lower --size");
    assert!(t.contains("4.0 GB of memory are available"), "{t}");
    assert!(!exr.exists() && !d.join("r.json").exists());

    let bake = d.join("bake");
    let t = fails(
        lustre()
            .env("LUSTRE_DISK_LIMIT", "1G")
            .arg("bake")
            .arg(cornell())
            .args(["--texels-per-metre", "10", "--tile", "512", "--out"])
            .arg(&bake),
    );
    assert_refused(&t, "lustre bake of", "lower --texels-per-metre or --tile");
    assert!(t.contains("1.0 GB of disk are free at"), "{t}");
    assert!(!bake.exists(), "a refused bake leaves no folder");
    // --plan prints the same estimate, writing nothing.
    let t = ok(lustre()
        .arg("bake")
        .arg(cornell())
        .args([
            "--texels-per-metre",
            "10",
            "--tile",
            "512",
            "--plan",
            "--out",
        ])
        .arg(&bake));
    assert!(
        t.contains("budget: about") && t.contains("of disk (tile files"),
        "{t}"
    );
    assert!(!bake.exists());

    // Counts have upper bounds.
    let t = fails(
        lustre()
            .args(["fit", "--model", "ggx", "--jobs", "100000", "--out"])
            .arg(d.join("fit"))
            .arg("nbrdf:nickel"),
    );
    assert!(t.contains("expected a whole number from 1 to 256"), "{t}");
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "10M")
            .args(["fit", "--model", "ggx", "--out"])
            .arg(d.join("fit"))
            .arg("nbrdf:nickel"),
    );
    assert_refused(&t, "lustre fit of 1 input(s), 1 at once", "lower --jobs");
    let t = fails(
        lustre()
            .env("LUSTRE_MEMORY_LIMIT", "lots")
            .args(["demo", "--out"])
            .arg(d.join("x.png")),
    );
    assert!(
        t.contains("LUSTRE_MEMORY_LIMIT=\"lots\": expected a byte count"),
        "{t}"
    );
}

#[test]
fn force_runs_a_job_over_the_budget_with_a_warning() {
    let dir = tempfile::tempdir().expect("dir");
    let png = dir.path().join("demo.png");
    let t = ok(lustre()
        .env("LUSTRE_MEMORY_LIMIT", "1M")
        .args(["demo", "--cpu", "--size", "32x18", "--samples", "4"])
        .args(["--reference-spp", "4", "--force", "--out"])
        .arg(&png));
    assert!(
        t.contains("1.0 MB of memory are available; running anyway (--force)"),
        "{t}"
    );
    assert!(png.is_file());
}

#[test]
fn special_files_are_refused_before_they_are_opened() {
    let dir = tempfile::tempdir().expect("dir");
    let fifo = dir.path().join("pipe.binary");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    // Each would block forever on the FIFO, or read /dev/zero until memory runs out.
    let t = fails(lustre().arg("info").arg(&fifo));
    assert!(
        t.contains("pipe.binary: a FIFO (named pipe), not a regular file"),
        "{t}"
    );
    let obj = dir.path().join("pipe.obj");
    let made = Command::new("mkfifo").arg(&obj).status().expect("mkfifo");
    assert!(made.success());
    let t = fails(lustre().args(["scene", "info"]).arg(&obj));
    assert!(t.contains("a FIFO (named pipe), not a regular file"), "{t}");
    let t = fails(
        lustre()
            .args(["render", "--material", "sgd:nickel", "--env", "/dev/zero"])
            .args(["--device", "cpu", "--out"])
            .arg(dir.path().join("r")),
    );
    assert!(
        t.contains("/dev/zero: a character device, not a regular file"),
        "{t}"
    );
    let t = fails(
        lustre()
            .args(["bandwidth", "--map"])
            .arg(dir.path())
            .args(["--out", "b.png"]),
    );
    assert!(t.contains("a folder, not a regular file"), "{t}");
}

/// A one-quad scene lit by a constant environment.
fn quad_scene(dir: &Path, grey: f64) -> PathBuf {
    std::fs::write(
        dir.join("quad.obj"),
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 3 2\nf 1 4 3\n",
    )
    .expect("obj");
    let scene = dir.join("quad.toml");
    std::fs::write(
        &scene,
        format!(
            "schema = \"lustre-scene\"\nversion = 1\n\n[[geometry]]\nfile = \"quad.obj\"\n\n\
             [environment]\nconstant = [{grey}, {grey}, {grey}]\n"
        ),
    )
    .expect("toml");
    scene
}

#[test]
fn a_reference_resumes_only_the_scene_that_made_it() {
    let dir = tempfile::tempdir().expect("dir");
    let scene = quad_scene(dir.path(), 0.5);
    let exr = dir.path().join("r.exr");
    let run = |spp: &str| {
        let mut c = lustre();
        c.arg("reference")
            .arg(&scene)
            .args(["--size", "8x8", "--spp", spp, "--out"])
            .arg(&exr);
        c
    };
    ok(&mut run("2"));
    let json = std::fs::read_to_string(dir.path().join("r.json")).expect("json");
    assert!(json.contains("\"scene_hash\": \""), "{json}");
    ok(run("4").arg("--resume"));
    // The same file, edited: another scene.
    quad_scene(dir.path(), 0.25);
    let t = fails(run("8").arg("--resume"));
    assert!(
        t.contains("differs (fingerprint") && t.contains("render it without --resume"),
        "{t}"
    );
    assert!(
        !t.contains("invalid parameter: resume: invalid parameter"),
        "{t}"
    );
    let json2 = std::fs::read_to_string(dir.path().join("r.json")).expect("json");
    assert!(
        json2.contains("\"spp\": 4"),
        "the checkpoint is untouched: {json2}"
    );

    // A pass whose second half cannot be written (here a folder stands in its way, as a full
    // disk would) leaves no half-written `.next` file and the checkpoint as it was.
    quad_scene(dir.path(), 0.5);
    let blocker = dir.path().join("r.odd.next.exr");
    std::fs::create_dir(&blocker).expect("blocker");
    let t = fails(&mut run("2"));
    assert!(t.contains("r.odd.next.exr"), "{t}");
    assert!(!dir.path().join("r.even.next.exr").exists(), "{t}");
    let json3 = std::fs::read_to_string(dir.path().join("r.json")).expect("json");
    assert_eq!(json3, json2);
    std::fs::remove_dir(&blocker).expect("unblock");
    let t = ok(run("8").arg("--resume"));
    assert!(t.contains("8 spp"), "{t}");
}

#[test]
fn a_plot_of_an_unknown_material_says_why_without_a_list_of_names() {
    let dir = tempfile::tempdir().expect("dir");
    let t = fails(
        lustre()
            .args(["plot", "nosuch-material", "--out"])
            .arg(dir.path().join("p")),
    );
    assert!(
        t.contains("unknown material \"nosuch-material\"") && !t.contains("built-in names"),
        "{t}"
    );
    assert!(!dir.path().join("p").exists());
}
