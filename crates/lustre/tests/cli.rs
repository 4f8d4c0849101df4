//! End-to-end runs of the `lustre` binary: the README's main job and clear errors.

use std::path::Path;
use std::process::Command;

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

fn is_png(p: &Path) -> bool {
    std::fs::read(p)
        .map(|b| b.starts_with(b"\x89PNG\r\n\x1a\n") && b.len() > 10_000)
        .unwrap_or(false)
}

#[test]
fn default_plot_writes_the_built_in_material() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = lustre()
        .args(["plot", "--out"])
        .arg(dir.path())
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "polar-kurt-demo.png",
        "polar-kurt-demo.svg",
        "array-kurt-demo.png",
    ] {
        assert!(dir.path().join(f).exists(), "{f} missing");
    }
    assert!(is_png(&dir.path().join("polar-kurt-demo.png")));
    assert!(is_png(&dir.path().join("array-kurt-demo.png")));
}

#[test]
fn comparison_of_a_fit_and_a_network() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = lustre()
        .args([
            "plot",
            "nbrdf:nickel",
            "--compare",
            "sgd:nickel",
            "--kind",
            "polar",
            "--out",
        ])
        .arg(dir.path())
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let written: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .flatten()
        .collect();
    assert!(written
        .iter()
        .any(|e| e.path().extension().is_some_and(|x| x == "png")));
}

#[test]
fn info_and_list() {
    let out = lustre()
        .args(["info", "kurt-glass"])
        .output()
        .expect("runs");
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(s.contains("transmission: true"), "{s}");
    let out = lustre().arg("list").output().expect("runs");
    let list = String::from_utf8_lossy(&out.stdout);
    assert!(
        list.contains("kurt-demo") && list.contains("roughconductor"),
        "{list}"
    );
    let out = lustre()
        .args(["info", "conductor(material=Au)"])
        .output()
        .expect("runs");
    assert!(out.status.success());
    let s = String::from_utf8_lossy(&out.stdout);
    assert!(
        s.contains("SPECULAR") && s.contains("has Dirac lobes"),
        "{s}"
    );
}

#[test]
fn bad_input_is_a_clear_error_not_a_panic() {
    for args in [
        vec!["info", "no-such-material"],
        vec!["info", "phong(kd=0.1, n=-4)"],
        vec!["info", "/nonexistent/file.binary"],
        vec!["merl", "info", "/nonexistent/file.binary"],
    ] {
        let out = lustre()
            .args(&args)
            .env("RUST_BACKTRACE", "0")
            .output()
            .expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} should fail");
        assert!(!err.contains("panicked"), "{args:?} panicked: {err}");
        assert!(err.contains("Error"), "{args:?}: {err}");
    }
    // A truncated MERL file names the file and the problem.
    let dir = tempfile::tempdir().expect("temp dir");
    let bad = dir.path().join("short.binary");
    std::fs::write(&bad, [90u8, 0, 0, 0, 90, 0, 0, 0, 180, 0, 0, 0, 1, 2, 3]).expect("write");
    let out = lustre()
        .args(["merl", "info"])
        .arg(&bad)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("short.binary"),
        "{err}"
    );
}

#[test]
fn scene_info_prints_counts_and_warnings() {
    let scene = lustre_brdf::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml");
    let out = lustre()
        .args(["scene", "info"])
        .arg(&scene)
        .output()
        .expect("runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("triangles 28815 (2432 degenerate dropped)"),
        "{text}"
    );
    assert!(text.contains("emitters 13"), "{text}");
    assert!(text.contains("warnings 2:"), "{text}");
    let out = lustre()
        .args(["scene", "info", "no/such.xml"])
        .output()
        .expect("runs");
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such.xml"));
}
