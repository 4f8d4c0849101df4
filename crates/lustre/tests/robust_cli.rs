//! The command line on day one: unmeasured MERL bins, `lustre score`, the built-in
//! published data from any directory, batch folders that keep every fit, and the rough edges.

mod common;

use common::{fails, lustre, ok};
use std::path::{Path, PathBuf};

/// A MERL table of a published SGD fit at the bins' lower edges with a block of bins marked
/// unmeasured (negative), written by `lustre merl synth --from`.
fn holey_table(dir: &Path) -> PathBuf {
    let path = dir.join("nickel.binary");
    let t = ok(lustre()
        .args(["merl", "synth", "--from", "sgd:nickel", "-o"])
        .arg(&path));
    assert!(t.contains("lower-edge"), "{t}");
    let mut b = std::fs::read(&path).expect("table");
    // θh index 85..90 of every channel: the grazing half-vectors MERL often lacks.
    let per = 90 * 180;
    for c in 0..3 {
        for n in (c * 90 * per + 85 * per)..(c * 90 * per + 90 * per) {
            b[12 + 8 * n..20 + 8 * n].copy_from_slice(&(-1.0f64).to_le_bytes());
        }
    }
    std::fs::write(&path, &b).expect("write");
    path
}

#[test]
fn unmeasured_bins_are_masked_everywhere_and_strict_refuses_them() {
    let dir = tempfile::tempdir().expect("dir");
    let table = holey_table(dir.path());
    let t = ok(lustre().args(["merl", "info"]).arg(&table));
    assert!(
        t.contains("unmeasured (negative) values: 243000 (81000 of"),
        "{t}"
    );
    let t = ok(lustre().arg("info").arg(&table));
    assert!(t.contains("masked"), "{t}");
    for args in [
        vec!["merl", "info", "--strict"],
        vec!["info", "--strict"],
        vec!["plot", "--strict", "--kind", "polar", "--out"],
    ] {
        let mut c = lustre();
        c.args(&args);
        if args[0] == "plot" {
            c.arg(dir.path().join("plots"));
        }
        let t = fails(c.arg(&table));
        assert!(
            t.contains("243000 negative values") && t.contains("--strict") && !t.contains("::"),
            "{args:?}: {t}"
        );
    }
    ok(lustre()
        .args(["plot", "--kind", "polar", "--out"])
        .arg(dir.path().join("plots"))
        .arg(&table));
    let out = dir.path().join("fits");
    let t = ok(lustre()
        .args(["fit", "--model", "ggx", "--out"])
        .arg(&out)
        .arg(&table));
    assert!(t.contains("masked"), "{t}");
    let t = ok(lustre()
        .arg("score")
        .arg(out.join("nickel.json"))
        .arg(&table));
    assert!(
        t.contains("243000 unmeasured values") && t.contains("Ngan L2"),
        "{t}"
    );
    fails(
        lustre()
            .args(["fit", "--strict", "--model", "ggx", "--force", "--out"])
            .arg(&out)
            .arg(&table),
    );
    // An all-zero table is no measurement.
    let zero = dir.path().join("zero.binary");
    let mut b = vec![0u8; 12 + 3 * 90 * 90 * 180 * 8];
    b[0] = 90;
    b[4] = 90;
    b[8] = 180;
    std::fs::write(&zero, &b).expect("write");
    let t = fails(lustre().args(["merl", "info"]).arg(&zero));
    assert!(
        t.contains("zero.binary") && t.contains("every measured value is zero"),
        "{t}"
    );
}

#[test]
fn score_lists_errors_and_albedos_without_fitting() {
    let t = ok(lustre().args(["score", "sgd:nickel", "nbrdf:nickel"]));
    for needle in [
        "Ngan L2",
        "L1 of Eq. 3.7",
        "albedo at θo = 0, data",
        "max albedo",
    ] {
        assert!(t.contains(needle), "{t}");
    }
    let t = fails(lustre().args(["score", "sgd:nope", "nbrdf:nickel"]));
    assert!(t.contains("nope"), "{t}");
}

/// The installed binary needs no build tree: run from an empty folder without LUSTRE_DATA, the
/// published fits and networks are built in, and larger data asks for LUSTRE_DATA or --data.
#[test]
fn works_from_any_directory() {
    let dir = tempfile::tempdir().expect("dir");
    let run = || {
        let mut c = lustre();
        c.current_dir(dir.path()).env_remove("LUSTRE_DATA");
        c
    };
    ok(run().args(["info", "sgd:nickel"]));
    ok(run().args(["info", "lafortune:nickel"]));
    ok(run().args(["info", "abc:nickel"]));
    ok(run().args(["info", "nbrdf:nickel"]));
    let t = ok(run().args(["merl", "list"]));
    assert!(t.contains("100 materials in the built-in set"), "{t}");
    let t = ok(run().arg("list"));
    assert!(
        t.contains("the 100 MERL materials") && t.contains("yellow-plastic"),
        "{t}"
    );
    assert!(
        t.contains("MIT licence") && t.contains("LUSTRE_DATA"),
        "{t}"
    );
    // Every MERL name stands on its own (the longest once ran into their neighbours).
    let words: std::collections::HashSet<&str> = t.split_whitespace().collect();
    for name in lustre_brdf::fits::sgd::list_materials().expect("names") {
        assert!(
            words.contains(name.as_str()),
            "{name} not listed on its own"
        );
    }
    let t = fails(run().args(["info", "data:measured/rgl/paper_white_rgb.bsdf"]));
    assert!(t.contains("LUSTRE_DATA") && t.contains("--data"), "{t}");
    let shared = lustre_brdf::shared_data_dir();
    ok(run()
        .arg("--data")
        .arg(&shared)
        .args(["info", "data:measured/rgl/paper_white_rgb.bsdf"]));
    // No build-tree path is compiled into the binary.
    let bin = std::fs::read(env!("CARGO_BIN_EXE_lustre")).expect("binary");
    assert!(
        !bin.windows(11).any(|w| w == b"shared/data"),
        "the binary holds a shared/data path"
    );
}

#[test]
fn rough_edges() {
    let dir = tempfile::tempdir().expect("dir");
    // Negative numbers after an option.
    ok(lustre()
        .args(["plot", "--kind", "polar", "--phi-i", "-30", "--out"])
        .arg(dir.path().join("neg")));
    // The demo writes PNG only, and says so before rendering.
    let jpg = dir.path().join("x.jpg");
    let t = fails(lustre().args(["demo", "--out"]).arg(&jpg));
    assert!(t.contains(".png") && !jpg.exists(), "{t}");
    // A plot that fails leaves no files behind.
    let p = dir.path().join("bad");
    fails(
        lustre()
            .args(["plot", "--array-theta", "95", "--out"])
            .arg(&p),
    );
    let left: Vec<_> = std::fs::read_dir(&p).map_or(Vec::new(), |d| d.flatten().collect());
    assert!(left.is_empty(), "{left:?}");
    assert!(!p.exists(), "a failed plot left its (empty) folder");
    // An OS error once, and no stack trace for a user's error even with RUST_BACKTRACE=1.
    let t = fails(
        lustre()
            .env("RUST_BACKTRACE", "1")
            .args(["info", "/nonexistent/file.binary"]),
    );
    assert_eq!(t.matches("No such file").count(), 1, "{t}");
    assert!(
        !t.contains("stack backtrace") && t.starts_with("error: "),
        "{t}"
    );
    // Kurt with no lobe is refused.
    let t = fails(
        lustre()
            .args(["fit", "--model", "kurt", "--lobes", "0", "--out"])
            .arg(dir.path())
            .arg("nbrdf:nickel"),
    );
    assert!(t.contains("--lobes 0"), "{t}");
}

/// Reusing a folder with other options never overwrites silently; the summary covers every
/// material JSON in it; the counts add up.
#[test]
fn batch_folders_keep_every_fit() {
    let dir = tempfile::tempdir().expect("dir");
    let out = dir.path().join("o");
    let t = ok(lustre()
        .args(["fit", "--model", "ggx", "--out"])
        .arg(&out)
        .arg("nbrdf:nickel"));
    assert!(t.contains("1 inputs: 1 fitted, 0 resumed, 0 failed"), "{t}");
    let t = fails(
        lustre()
            .args(["fit", "--model", "beckmann", "--out"])
            .arg(&out)
            .arg("nbrdf:nickel"),
    );
    assert!(t.contains("--force") && t.contains("--suffix"), "{t}");
    let t = fails(
        lustre()
            .args([
                "fit", "--model", "beckmann", "--suffix", "beckmann", "--out",
            ])
            .arg(&out)
            .args(["nbrdf:nickel", "nbrdf:no-such-material"]),
    );
    assert!(
        t.contains("2 inputs: 1 fitted, 0 resumed, 1 failed")
            && t.contains("also lists 1 earlier fits"),
        "{t}"
    );
    let summary = std::fs::read_to_string(out.join("summary.csv")).expect("summary");
    let names: Vec<&str> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap_or(""))
        .collect();
    assert_eq!(
        names,
        ["nickel-beckmann", "no-such-material-beckmann", "nickel"]
    );
}

/// Inputs that used to be accepted silently (or wrongly) and their messages: each is
/// refused, names the problem in plain words, and leaves nothing behind.
#[test]
fn silent_acceptances_are_refused_in_plain_words() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    // An exposure of 0 or NaN gave a black PNG with exit 0.
    for e in ["0", "NaN", "-1", "inf"] {
        let out = d.join(format!("exposure-{e}"));
        let t = fails(
            lustre()
                .args(["render", "--material", "sgd:nickel", "--device", "cpu"])
                .args(["--size", "8x8", "--exposure", e, "--out"])
                .arg(&out),
        );
        assert!(
            t.contains("--exposure") && t.contains("finite number > 0"),
            "{t}"
        );
        assert!(!out.exists(), "{e}: {} written", out.display());
    }
    let t = fails(
        lustre()
            .args(["demo", "--exposure", "0", "--out"])
            .arg(d.join("d.png")),
    );
    assert!(t.contains("finite number > 0"), "{t}");
    // A suffix with a folder separator dropped the input's name (a/b wrote b.json).
    let t = fails(
        lustre()
            .args(["fit", "--model", "sgd", "--suffix", "a/b", "--out"])
            .arg(d.join("fits"))
            .arg("nbrdf:nickel"),
    );
    assert!(t.contains("part of a file name"), "{t}");
    // Count options have upper bounds.
    let t = fails(
        lustre()
            .args(["fit", "--model", "kurt", "--lobes", "1000", "--out"])
            .arg(d.join("fits"))
            .arg("nbrdf:nickel"),
    );
    assert!(t.contains("at most 8"), "{t}");
    let t = fails(
        lustre()
            .args([
                "plot",
                "--pattern",
                "multi-ring",
                "--rings",
                "1000000",
                "--out",
            ])
            .arg(d.join("plot")),
    );
    assert!(t.contains("1000000") && t.contains("1..=64"), "{t}");
    // A file with no usable geometry is an error, not an empty scene.
    std::fs::write(d.join("text.obj"), "hello world\n").expect("write");
    std::fs::write(d.join("two.obj"), "v 0 0 0\nv 1 0 0\nf 1 2\n").expect("write");
    for f in ["text.obj", "two.obj"] {
        let t = fails(lustre().args(["scene", "info"]).arg(d.join(f)));
        assert!(t.contains(f) && t.contains("no geometry"), "{t}");
    }
    // Non-finite and negative texels of a map: reported the same way by every command.
    let mut img = image::Rgb32FImage::from_pixel(8, 4, image::Rgb([0.5, 0.5, 0.5]));
    img.put_pixel(1, 1, image::Rgb([f32::NAN, 0.5, 0.5]));
    img.put_pixel(2, 2, image::Rgb([-1.0, 0.5, 0.5]));
    let map = d.join("bad.exr");
    image::DynamicImage::ImageRgb32F(img)
        .save(&map)
        .expect("exr");
    let note = "1 non-finite and 1 negative texels were set to 0";
    let t = ok(lustre()
        .args(["bandwidth", "--map"])
        .arg(&map)
        .arg("--out")
        .arg(d.join("bw.png")));
    assert!(t.contains(&format!("bad.exr: {note}")), "{t}");
    let t = ok(lustre()
        .args([
            "render",
            "--material",
            "sgd:nickel",
            "--device",
            "cpu",
            "--size",
            "8x8",
        ])
        .arg("--env")
        .arg(&map)
        .arg("--out")
        .arg(d.join("env-frame")));
    assert!(t.contains(&format!("bad.exr: {note}")), "{t}");
    // A reference of another size: refused before rendering, no frame left behind.
    let out = d.join("cmp");
    let t = fails(
        lustre()
            .args([
                "render",
                "--material",
                "sgd:nickel",
                "--device",
                "cpu",
                "--size",
                "8x8",
            ])
            .arg("--compare-reference")
            .arg(&map)
            .arg("--out")
            .arg(&out),
    );
    assert!(t.contains("the reference is 8×4, the frame 8×8"), "{t}");
    assert!(
        !out.join("frame.exr").exists() && !out.join("frame.png").exists(),
        "a refused comparison left a frame"
    );
    // Model errors name the spec's own parameters, and numbers print in plain form.
    let t = fails(lustre().args(["info", "ward(kd=0.2, ks=0.1, ax=0)"]));
    assert!(t.contains("ax = 0") && !t.contains("alpha"), "{t}");
    let t = fails(lustre().args(["info", "lambert(kd=1e300)"]));
    assert!(
        t.contains("kd.r = 1e300: must lie in [0, 1e6]") && !t.contains("00000000"),
        "{t}"
    );
    // `--camera` on a scene without cameras: `auto` (what the record says) is the framing view.
    let cornell = lustre_brdf::shared_data_dir().join("scenes/cornell_box/cornell_box.obj");
    let t = fails(
        lustre()
            .arg("reference")
            .arg(&cornell)
            .args(["--camera", "nosuch", "--size", "8x8", "--spp", "2", "--out"])
            .arg(d.join("r.exr")),
    );
    assert!(
        t.contains("the scene has no camera") && !t.contains("(cameras: )"),
        "{t}"
    );
    let out = d.join("auto.exr");
    ok(lustre()
        .arg("reference")
        .arg(&cornell)
        .args(["--camera", "auto", "--size", "8x8", "--spp", "2", "--out"])
        .arg(&out));
    let record = std::fs::read_to_string(out.with_extension("json")).expect("record");
    assert!(record.contains("\"camera\": \"auto\""), "{record}");
}

/// `lustre fit --merge` reads every shard's fits before it writes: an empty (cut short) fit is
/// refused by name and nothing is copied.
#[test]
fn a_merge_refuses_a_damaged_shard_fit_and_copies_nothing() {
    let dir = tempfile::tempdir().expect("dir");
    let d = dir.path();
    let parts = [d.join("p0"), d.join("p1")];
    for (k, p) in parts.iter().enumerate() {
        ok(lustre()
            .args(["fit", "--model", "sgd", "--jobs", "1", "--shard"])
            .arg(format!("{k}/2"))
            .arg("--out")
            .arg(p)
            .args(["nbrdf:nickel", "nbrdf:gold-paint"]));
    }
    let damaged = parts[1].join("gold-paint.json");
    std::fs::write(&damaged, "").expect("truncate");
    let merged = d.join("merged");
    let t = fails(
        lustre()
            .args(["fit", "--merge", "--out"])
            .arg(&merged)
            .args(&parts),
    );
    assert!(
        t.contains("gold-paint.json") && t.contains("not a fit"),
        "{t}"
    );
    let copied: Vec<_> = std::fs::read_dir(&merged)
        .map_or(Vec::new(), |r| r.flatten().collect())
        .into_iter()
        .filter(|e| e.path().extension().is_some_and(|x| x == "json"))
        .collect();
    assert!(copied.is_empty(), "{copied:?}");
    assert!(!merged.join("summary.csv").exists());
}
