//! `lustre bake` end to end on a tiny scene (an OBJ floor and block under a constant sky):
//! files written, the updated scene file loads, a second run resumes every tile, and a scene
//! without light is a clear error; the same bake in shards (`--shard`, a job array's index) and
//! merged gives the same files byte for byte.

use std::process::Command;

fn lustre() -> Command {
    Command::new(env!("CARGO_BIN_EXE_lustre"))
}

const OBJ: &str = "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n\
v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 1 -0.5\nv -0.5 1 -0.5\n\
v -0.5 0 0.5\nv 0.5 0 0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n\
f 1 3 2\nf 1 4 3\n\
f 5 8 7\nf 5 7 6\nf 9 10 11\nf 9 11 12\nf 5 9 12\nf 5 12 8\nf 6 7 11\nf 6 11 10\nf 8 12 11\nf 8 11 7\n";

/// Writes the floor-and-block OBJ and a scene file lighting it with a constant sky into `dir`;
/// returns the scene file.
fn write_scene(dir: &std::path::Path) -> std::path::PathBuf {
    std::fs::write(dir.join("floor.obj"), OBJ).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"floor.obj\"\n[environment]\nconstant = [1.0, 1.0, 1.0]\n",
    )
    .unwrap();
    scene
}

/// `lustre bake SCENE --out OUT` at the tests' small settings (4 spp, 2 bounces, 8 texels/m).
fn bake_cmd(scene: &std::path::Path, out: &std::path::Path) -> Command {
    let mut c = lustre();
    c.arg("bake").arg(scene).arg("--out").arg(out).args([
        "--spp",
        "4",
        "--bounces",
        "2",
        "--texels-per-metre",
        "8",
    ]);
    c
}

#[test]
fn bake_writes_pages_and_a_scene_file_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let out = dir.path().join("out");
    let o = bake_cmd(&scene, &out).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("baked") && stdout.contains("noise"),
        "{stdout}"
    );
    for f in [
        "lightmap_000.exr",
        "lightmap.glb",
        "scene.toml",
        "bake.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let exr = std::fs::read(out.join("lightmap_000.exr")).unwrap();
    let info = lustre()
        .args(["scene", "info"])
        .arg(out.join("scene.toml"))
        .output()
        .unwrap();
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    let o = bake_cmd(&scene, &out).output().unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    assert!(stdout.contains("0 baked"), "{stdout}");
    assert_eq!(std::fs::read(out.join("lightmap_000.exr")).unwrap(), exr);
    // A relative input with `..`: the written scene file names it by its canonical path.
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    let o = lustre()
        .current_dir(&sub)
        .args(["bake", "../scene.toml", "--out", "../rel", "--spp", "1"])
        .args(["--bounces", "1", "--texels-per-metre", "4"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = std::fs::read_to_string(dir.path().join("rel/scene.toml")).unwrap();
    let floor = std::fs::canonicalize(dir.path().join("floor.obj")).unwrap();
    assert!(
        written.contains(&*floor.to_string_lossy()) && !written.contains(".."),
        "{written}"
    );
    // Without the environment: no light at all.
    std::fs::write(
        &scene,
        "schema = \"lustre-scene\"\nversion = 1\n[[geometry]]\nfile = \"floor.obj\"\n",
    )
    .unwrap();
    let o = bake_cmd(&scene, &dir.path().join("dark")).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("no emitter"),
        "{stderr}"
    );
}

#[test]
fn sharded_bake_merges_to_the_unsharded_pages() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path());
    let bake = |out: &std::path::Path, extra: &[&str], envs: &[(&str, &str)]| {
        let mut c = bake_cmd(&scene, out);
        c.args(["--tile", "8"]).args(extra);
        for (k, v) in envs {
            c.env(k, v);
        }
        let o = c.output().unwrap();
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        (o.status.success(), text)
    };
    let whole = dir.path().join("whole");
    let (ok, t) = bake(&whole, &[], &[]);
    assert!(ok, "{t}");
    let shared = dir.path().join("shared");
    let (ok, t) = bake(&shared, &["--shard", "0/3"], &[]);
    assert!(
        ok && t.contains("shard 0/3 done") && t.contains("--merge"),
        "{t}"
    );
    assert!(!shared.join("lightmap_000.exr").exists());
    // Merging before every shard ran names a tile not baked yet.
    let (ok, t) = bake(&shared, &["--merge"], &[]);
    assert!(!ok && t.contains("not baked yet"), "{t}");
    let (ok, t) = bake(
        &shared,
        &["--shard-count", "3"],
        &[("JOB_COMPLETION_INDEX", "1")],
    );
    assert!(ok, "{t}");
    let (ok, t) = bake(
        &shared,
        &["--shard-count", "3"],
        &[("SLURM_ARRAY_TASK_ID", "3"), ("SLURM_ARRAY_TASK_MIN", "1")],
    );
    assert!(ok, "{t}");
    let (ok, t) = bake(&shared, &["--merge"], &[]);
    assert!(ok, "{t}");
    for f in ["lightmap_000.exr", "lightmap.glb"] {
        assert_eq!(
            std::fs::read(shared.join(f)).unwrap(),
            std::fs::read(whole.join(f)).unwrap(),
            "{f} differs"
        );
    }
    let tiles = std::fs::read_dir(whole.join("tiles"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "bin"))
        })
        .count();
    assert!(tiles >= 3, "{tiles} tiles: too few to shard");

    // --plan: the tile count (the most shards), writing nothing; too many shards refused.
    let planned = dir.path().join("planned");
    let (ok, t) = bake(&planned, &["--plan", "--shard", "0/3"], &[]);
    assert!(
        ok && t.contains(&format!(
            "in {tiles} tiles of 8² texels: at most {tiles} shards"
        )),
        "{t}"
    );
    let too_many = format!("0/{}", tiles + 1);
    let (ok, t) = bake(&planned, &["--plan", "--shard", &too_many], &[]);
    assert!(!ok && t.contains("shards for"), "{t}");
    assert!(!planned.exists(), "--plan wrote {}", planned.display());

    // Refusals that leave the merged folder as it is.
    let page = shared.join("lightmap_000.exr");
    let modified = || std::fs::metadata(&page).and_then(|m| m.modified()).unwrap();
    let (page_bytes, page_time) = (std::fs::read(&page).unwrap(), modified());
    // More shards than tiles.
    let many = format!("0/{}", tiles + 1);
    let (ok, t) = bake(&shared, &["--shard", &many], &[]);
    assert!(
        !ok && t.contains(&format!("{} shards for {tiles} tiles", tiles + 1)),
        "{t}"
    );
    // The same shard run twice at once (a resubmitted task while the first still runs), and a
    // merge while a shard runs: the test holds shard 1/3's lock as a running bake would.
    let held =
        lustre_brdf::error::lock_output(&shared.join("tiles/shard-1-of-3.lock"), "shard 1/3")
            .unwrap();
    let (ok, t) = bake(&shared, &["--shard", "1/3"], &[]);
    assert!(
        !ok && t.contains("shard 1/3 is being written by another process"),
        "{t}"
    );
    let (ok, t) = bake(&shared, &["--merge"], &[]);
    assert!(!ok && t.contains("still baking"), "{t}");
    drop(held);
    // A merge with a tile missing (a shard not finished).
    let tile0 = std::fs::read_dir(shared.join("tiles"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "bin"))
        .unwrap();
    std::fs::remove_file(&tile0).unwrap();
    let (ok, t) = bake(&shared, &["--merge"], &[]);
    assert!(!ok && t.contains("not baked yet"), "{t}");
    assert_eq!(std::fs::read(&page).unwrap(), page_bytes);
    assert_eq!(modified(), page_time, "a refused run rewrote the page");
}

/// The sunroom (scenes/sunroom: no hints): `--setup auto` (the default) writes the floor, the
/// mirror and the picture as planar reflectors, probes for the pane, the sphere and the table,
/// and a room probe with its box, and says so in one line; `--setup manual` writes none of it;
/// `lustre scene setup --svg` prints the same choices and draws them.
#[test]
fn bake_writes_the_automatic_set_up_and_scene_setup_draws_it() {
    let dir = tempfile::tempdir().unwrap();
    let sunroom = std::path::Path::new("../../scenes/sunroom/scene.xml");
    let mut tomls = vec![];
    for setup in ["auto", "manual"] {
        let out = dir.path().join(setup);
        let o = lustre()
            .arg("bake")
            .arg(sunroom)
            .arg("--out")
            .arg(&out)
            .args(["--spp", "1", "--bounces", "1", "--texels-per-metre", "2"])
            .args(["--setup", setup])
            .output()
            .unwrap();
        let all = format!(
            "{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(o.status.success(), "{all}");
        assert_eq!(
            all.contains("real-time set-up: 4 mirror pass(es)"),
            setup == "auto",
            "{all}"
        );
        tomls.push(std::fs::read_to_string(out.join("scene.toml")).unwrap());
    }
    let auto = &tomls[0];
    for mirror in ["Floor", "Mirror", "Picture"] {
        assert!(
            auto.contains(&format!("[objects.{mirror}]\nplanar_reflector = true")),
            "{auto}"
        );
    }
    for probe in ["GoldSphere", "Table"] {
        assert!(
            auto.contains(&format!("[objects.{probe}]\nprobe = true")),
            "{auto}"
        );
    }
    // The pane: a mirror pass for its reflections, a probe for its see-through pass.
    let pane = auto
        .split("[objects.WindowPane]\n")
        .nth(1)
        .and_then(|rest| rest.split("\n[").next())
        .expect("the pane's hints");
    assert!(
        pane.contains("planar_reflector = true") && pane.contains("probe = true"),
        "{auto}"
    );
    assert!(
        auto.contains("[[probe]]\nname = \"room-1\"") && auto.contains("box_min"),
        "{auto}"
    );
    assert!(
        !tomls[1].contains("[objects.") && !tomls[1].contains("[[probe]]"),
        "{}",
        tomls[1]
    );
    // The baked file loads with its probes.
    let baked = lustre_scene::Scene::load(&dir.path().join("auto/scene.toml")).unwrap();
    assert!(!baked.probes.is_empty());
    // `lustre scene setup`: the same choices, and the top view.
    let base = dir.path().join("top");
    let o = lustre()
        .args(["scene", "setup"])
        .arg(sunroom)
        .arg("--top-view")
        .arg(&base)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && out.contains("Floor: planar reflector"),
        "{out}"
    );
    let drawing = std::fs::read_to_string(dir.path().join("top.svg")).unwrap();
    assert!(
        drawing.contains("<svg") && drawing.contains("room-1"),
        "{drawing}"
    );
    let png = image::open(dir.path().join("top.png")).unwrap().to_rgb8();
    // Cyan (the room box), magenta (the reflectors) and yellow (the probes) are drawn.
    let has = |f: &dyn Fn(&image::Rgb<u8>) -> bool| png.pixels().any(f);
    assert!(has(&|p| p[0] < 80 && p[1] > 140 && p[2] > 180));
    assert!(has(&|p| p[0] > 180 && p[1] < 100 && p[2] > 160));
    assert!(has(&|p| p[0] > 170 && p[1] > 130 && p[2] < 60));
}
