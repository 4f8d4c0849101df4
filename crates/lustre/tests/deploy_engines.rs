//! The `deploy/` templates run on the engines they are written for, and their merged results
//! equal one machine's unsharded run:
//!
//! - **SLURM**: a one-node cluster (`deploy/slurm/test-cluster.sh`: munged, slurmctld, slurmd on
//!   localhost) runs `bake-array.sh` on the Cornell box and the Modern Hall (3 shards each) and
//!   `fit-array.sh` on four MERL tables (2 shards); one Hall task is cancelled while it bakes and
//!   resubmitted alone, and resumes from its tiles; a request no node can satisfy is refused
//!   before anything is submitted.
//! - **OpenJD**: `openjd check` and `openjd run` (every shard task, then the merge) of both
//!   templates.
//! - **Kubernetes**: the manifests validated against the Kubernetes API schema
//!   (`kubernetes-validate`, pinned in `.ci/run`), and every index of each Indexed Job run as its
//!   pod would run it (`JOB_COMPLETION_INDEX`), then the merge Job's command.
//!
//! CI installs the engines (`.ci/run`); without them these tests fail and name what to install.

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn lustre_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_lustre"))
}

/// `PATH` with the lustre under test first (the templates call `lustre`).
fn path_with_lustre() -> std::ffi::OsString {
    let dir = lustre_bin().parent().expect("bin dir").to_path_buf();
    let mut paths = vec![dir];
    paths.extend(std::env::split_paths(
        &std::env::var_os("PATH").unwrap_or_default(),
    ));
    std::env::join_paths(paths).expect("PATH")
}

fn text(o: &Output) -> String {
    format!(
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn run_ok(c: &mut Command) -> String {
    let o = c
        .output()
        .unwrap_or_else(|e| panic!("{c:?} did not start: {e}"));
    assert!(o.status.success(), "{c:?} failed:\n{}", text(&o));
    text(&o)
}

fn shared() -> PathBuf {
    lustre_brdf::shared_data_dir()
}

fn cornell() -> PathBuf {
    shared().join("scenes/cornell_box/cornell_box.obj")
}

fn hall() -> PathBuf {
    shared().join("scenes/modern_hall/mitsuba/scene.xml")
}

/// Small bakes: the Cornell box (in millimetres) at 0.1 texels per unit has 108 tiles of 16²;
/// the Hall at 4 texels per metre 187.
const CORNELL_BAKE: [&str; 8] = [
    "--spp",
    "16",
    "--bounces",
    "2",
    "--texels-per-metre",
    "0.1",
    "--tile",
    "16",
];
const HALL_BAKE: [&str; 8] = [
    "--spp",
    "64",
    "--bounces",
    "2",
    "--texels-per-metre",
    "4",
    "--tile",
    "16",
];

/// One machine's unsharded bake of `scene` into `out`.
fn bake_whole(scene: &Path, out: &Path, opts: &[&str]) {
    run_ok(
        Command::new(lustre_bin())
            .arg("bake")
            .arg(scene)
            .arg("--out")
            .arg(out)
            .args(opts),
    );
}

/// The light-map pages and glTF of a bake folder, by name.
fn bake_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    for e in std::fs::read_dir(dir).expect("bake folder").flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if (name.starts_with("lightmap_") && name.ends_with(".exr")) || name == "lightmap.glb" {
            files.insert(name, std::fs::read(e.path()).expect("read"));
        }
    }
    assert!(
        files.contains_key("lightmap_000.exr") && files.contains_key("lightmap.glb"),
        "{}: no pages: {:?}",
        dir.display(),
        files.keys()
    );
    files
}

fn assert_same_bake(sharded: &Path, whole: &Path) {
    let (a, b) = (bake_files(sharded), bake_files(whole));
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{} vs {}",
        sharded.display(),
        whole.display()
    );
    for (name, bytes) in &a {
        assert!(
            *bytes == b[name],
            "{name} of {} differs from the unsharded bake",
            sharded.display()
        );
    }
}

/// `n` (at most 8) MERL tables synthesized from the built-in neural BRDFs into `dir/merl`, in
/// the order a shell's glob lists them.
fn merl_tables(dir: &Path, n: usize) -> Vec<PathBuf> {
    let merl = dir.join("merl");
    std::fs::create_dir_all(&merl).expect("merl dir");
    [
        "alum-bronze",
        "beige-fabric",
        "blue-fabric",
        "gold-paint",
        "nickel",
        "red-plastic",
        "silver-paint",
        "white-marble",
    ][..n]
        .iter()
        .map(|m| {
            let p = merl.join(format!("{m}.binary"));
            run_ok(
                Command::new(lustre_bin())
                    .args(["merl", "synth", "--material", m, "-o"])
                    .arg(&p),
            );
            p
        })
        .collect()
}

fn fit_whole(out: &Path, inputs: &[PathBuf]) {
    run_ok(
        Command::new(lustre_bin())
            .args(["fit", "--model", "sgd", "--jobs", "1", "--out"])
            .arg(out)
            .args(inputs),
    );
}

/// The fits (JSON) and `summary.csv` of a fit folder with the wall times zeroed (the only field
/// two runs of one batch differ in).
fn fit_files(dir: &Path) -> BTreeMap<String, String> {
    let mut files = BTreeMap::new();
    for e in std::fs::read_dir(dir).expect("fit folder").flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let body = if name.ends_with(".json") {
            let mut v: Value =
                serde_json::from_slice(&std::fs::read(e.path()).expect("read")).expect("json");
            v["fit"]["time_s"] = 0.into();
            v.to_string()
        } else if name == "summary.csv" {
            let s = std::fs::read_to_string(e.path()).expect("csv");
            let mut lines = s.lines();
            let head = lines.next().expect("header");
            let t = head
                .split(',')
                .position(|c| c == "time_s")
                .expect("time_s column");
            let rows: Vec<String> = lines
                .map(|l| {
                    let mut c: Vec<&str> = l.splitn(t + 2, ',').collect();
                    c[t] = "0";
                    c.join(",")
                })
                .collect();
            format!("{head}\n{}", rows.join("\n"))
        } else {
            continue;
        };
        files.insert(name, body);
    }
    assert!(
        files.contains_key("summary.csv") && files.len() > 1,
        "{}: {:?}",
        dir.display(),
        files.keys()
    );
    files
}

// ---------------------------------------------------------------------------------------------
// SLURM

/// A one-node SLURM cluster, stopped when dropped.
struct Cluster {
    dir: tempfile::TempDir,
    conf: PathBuf,
}

impl Cluster {
    fn start() -> Cluster {
        for tool in ["sbatch", "squeue", "scancel"] {
            assert!(
                Command::new(tool).arg("--version").output().is_ok(),
                "{tool} not found: install SLURM and munge (apt-get install slurm-wlm munge), as \
                 .ci/run does"
            );
        }
        let dir = tempfile::tempdir().expect("cluster dir");
        let out = run_ok(
            Command::new("bash")
                .arg(repo().join("deploy/slurm/test-cluster.sh"))
                .arg("start")
                .arg(dir.path()),
        );
        let conf = out
            .lines()
            .find_map(|l| l.strip_prefix("export SLURM_CONF="))
            .unwrap_or_else(|| panic!("no SLURM_CONF in {out}"))
            .trim()
            .into();
        Cluster { dir, conf }
    }

    /// A command that talks to this cluster, with the lustre under test on its path.
    fn cmd(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf)
            .env("PATH", path_with_lustre());
        c
    }

    /// Runs a submission script; returns the job ids it printed (array, merge).
    fn submit(&self, script: &str, args: &[&std::ffi::OsStr], env: &[(&str, &str)]) -> Vec<String> {
        let mut c = self.cmd("bash");
        c.arg(repo().join("deploy/slurm").join(script)).args(args);
        for (k, v) in env {
            c.env(k, v);
        }
        let out = run_ok(&mut c);
        let ids: Vec<String> = out
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && l.chars().all(|c| c.is_ascii_digit()))
            .map(String::from)
            .collect();
        assert_eq!(ids.len(), 2, "{script}: expected two job ids:\n{out}");
        ids
    }

    /// The states of a job's tasks (`squeue -t all`: finished jobs stay listed for MinJobAge).
    fn states(&self, job: &str) -> Vec<String> {
        let o = self
            .cmd("squeue")
            .args(["-h", "-t", "all", "-o", "%T", "-j", job])
            .output()
            .expect("squeue");
        String::from_utf8_lossy(&o.stdout)
            .split_whitespace()
            .map(String::from)
            .collect()
    }

    /// Waits until every task of `job` has ended; returns their states.
    fn wait(&self, job: &str, limit: Duration) -> Vec<String> {
        let t0 = Instant::now();
        loop {
            let s = self.states(job);
            let ended = |s: &String| {
                matches!(
                    s.as_str(),
                    "COMPLETED"
                        | "FAILED"
                        | "CANCELLED"
                        | "TIMEOUT"
                        | "OUT_OF_MEMORY"
                        | "NODE_FAIL"
                )
            };
            if !s.is_empty() && s.iter().all(ended) {
                return s;
            }
            assert!(
                t0.elapsed() < limit,
                "job {job} still {s:?} after {limit:?}; queue:\n{}\nlogs in {}",
                text(
                    &self
                        .cmd("squeue")
                        .args(["-t", "all", "-o", "%i %T %r"])
                        .output()
                        .expect("squeue")
                ),
                self.dir.path().display()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    fn wait_completed(&self, job: &str, logs: &Path) {
        let s = self.wait(job, Duration::from_secs(240));
        assert!(
            s.iter().all(|s| s == "COMPLETED"),
            "job {job}: {s:?}; logs:\n{}",
            slurm_logs(logs)
        );
    }

    fn queue_len(&self) -> usize {
        let o = self
            .cmd("squeue")
            .args(["-h", "-t", "all", "-o", "%i"])
            .output()
            .expect("squeue");
        String::from_utf8_lossy(&o.stdout).lines().count()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new("bash")
            .arg(repo().join("deploy/slurm/test-cluster.sh"))
            .arg("stop")
            .arg(self.dir.path())
            .output();
    }
}

/// Every `slurm-*.log` in `dir`, for failure messages.
fn slurm_logs(dir: &Path) -> String {
    let mut s = String::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.starts_with("slurm-") {
            s += &format!(
                "== {name}\n{}\n",
                std::fs::read_to_string(e.path()).unwrap_or_default()
            );
        }
    }
    s
}

/// Whether `dir/tiles` holds a tile of shard `k` of `n` (tile index mod n = k).
fn as_os(args: &[std::ffi::OsString]) -> Vec<&std::ffi::OsStr> {
    args.iter().map(|a| a.as_os_str()).collect()
}

fn has_tile_of_shard(dir: &Path, k: u32, n: u32) -> bool {
    std::fs::read_dir(dir.join("tiles"))
        .into_iter()
        .flatten()
        .flatten()
        .any(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            name.strip_suffix(".bin")
                .and_then(|s| s.rsplit_once("_tile"))
                .and_then(|(_, i)| i.parse::<u32>().ok())
                .is_some_and(|i| i % n == k)
        })
}

/// `tiles: T (B baked, R resumed)` of a bake log.
fn tiles_line(log: &str) -> (usize, usize) {
    let line = log
        .lines()
        .find(|l| l.starts_with("tiles: "))
        .unwrap_or_else(|| panic!("no tiles line in:\n{log}"));
    let inner = &line[line.find('(').expect("(") + 1..line.find(')').expect(")")];
    let nums: Vec<usize> = inner
        .split(", ")
        .map(|p| p.split(' ').next().expect("n").parse().expect("number"))
        .collect();
    (nums[0], nums[1])
}

#[test]
fn slurm_arrays_bake_and_fit_like_one_machine_and_a_cancelled_task_resumes() {
    let t0 = Instant::now();
    let cluster = Cluster::start();
    let work = tempfile::tempdir().expect("work dir");
    let w = work.path();
    let lustre = lustre_bin();
    let env = [("LUSTRE", lustre.to_str().expect("utf-8 path"))];

    // A request no node can satisfy (the old templates' hard-coded 8 CPUs on a 2-CPU node would
    // wait forever with reason PartitionConfig): refused with the reason, nothing submitted.
    let before = cluster.queue_len();
    let o = cluster
        .cmd("bash")
        .arg(repo().join("deploy/slurm/bake-array.sh"))
        .arg(cornell())
        .arg(w.join("never"))
        .arg("3")
        .env("LUSTRE_CPUS", "4096")
        .output()
        .expect("runs");
    assert!(
        !o.status.success()
            && text(&o).contains("no node can run a task with --cpus-per-task=4096")
            && text(&o).contains("nothing was submitted"),
        "{}",
        text(&o)
    );
    // Longer than the partition's limit (test-cluster.sh's `short`: 10 min), which sbatch
    // --test-only accepts and SLURM would leave pending forever.
    let o = cluster
        .cmd("bash")
        .arg(repo().join("deploy/slurm/fit-array.sh"))
        .arg(w.join("never"))
        .args(["sgd", "2", "a.binary", "b.binary"])
        .env("LUSTRE_PARTITION", "short")
        .env("LUSTRE_TIME", "1:00:00")
        .output()
        .expect("runs");
    assert!(
        !o.status.success()
            && text(&o).contains("LUSTRE_TIME=1:00:00 is longer than partition short allows"),
        "{}",
        text(&o)
    );
    // Shard lists and counts outside the array: refused as well.
    for (shards, tasks) in [("0", ""), ("3", "5"), ("x", "")] {
        let o = cluster
            .cmd("bash")
            .arg(repo().join("deploy/slurm/bake-array.sh"))
            .arg(cornell())
            .arg(w.join("never"))
            .arg(shards)
            .env("LUSTRE_TASKS", tasks)
            .output()
            .expect("runs");
        assert!(
            !o.status.success() && text(&o).to_lowercase().contains("shard"),
            "{shards} {tasks}: {}",
            text(&o)
        );
    }
    // More shards than tiles (the script runs `lustre bake --plan` first) or inputs.
    let o = cluster
        .cmd("bash")
        .arg(repo().join("deploy/slurm/bake-array.sh"))
        .arg(cornell())
        .arg(w.join("never"))
        .arg("500")
        .args(CORNELL_BAKE)
        .output()
        .expect("runs");
    assert!(
        !o.status.success()
            && text(&o).contains("500 shards for 108 tiles")
            && text(&o).contains("nothing was submitted"),
        "{}",
        text(&o)
    );
    let o = cluster
        .cmd("bash")
        .arg(repo().join("deploy/slurm/fit-array.sh"))
        .arg(w.join("never"))
        .args(["sgd", "3", "a.binary", "b.binary"])
        .output()
        .expect("runs");
    assert!(
        !o.status.success() && text(&o).contains("3 shards for 2 inputs"),
        "{}",
        text(&o)
    );
    assert!(
        !w.join("never").exists(),
        "a refused request wrote its folder"
    );
    assert_eq!(
        cluster.queue_len(),
        before,
        "a refused request submitted jobs"
    );

    // The Hall first, so that its shards 0 and 1 start at once on the two CPUs.
    let hall_scene = hall();
    let hall_args_for = |out: &Path| -> Vec<std::ffi::OsString> {
        [
            hall_scene.as_os_str(),
            out.as_os_str(),
            std::ffi::OsStr::new("3"),
        ]
        .into_iter()
        .chain(HALL_BAKE.iter().map(std::ffi::OsStr::new))
        .map(|a| a.to_os_string())
        .collect()
    };
    let mut hall_out = w.join("hall-0");
    let mut hall_args = hall_args_for(&hall_out);
    let mut hall_ids = cluster.submit("bake-array.sh", &as_os(&hall_args), &env);
    let cornell_out = w.join("cornell");
    let cornell_scene = cornell();
    let cornell_args: Vec<&std::ffi::OsStr> = [cornell_scene.as_os_str(), cornell_out.as_os_str()]
        .into_iter()
        .chain([std::ffi::OsStr::new("3")])
        .chain(CORNELL_BAKE.iter().map(std::ffi::OsStr::new))
        .collect();
    let cornell_ids = cluster.submit("bake-array.sh", &cornell_args, &env);
    let inputs = merl_tables(w, 4);
    let fit_out = w.join("fits");
    let mut fit_args: Vec<&std::ffi::OsStr> =
        vec![fit_out.as_os_str(), "sgd".as_ref(), "2".as_ref()];
    fit_args.extend(inputs.iter().map(|p| p.as_os_str()));
    let fit_ids = cluster.submit("fit-array.sh", &fit_args, &env);

    // Cancel the Hall's shard 1 once it has written a tile. On a loaded machine the shard can
    // finish its last tile before the cancel reaches it; then the experiment is repeated in a
    // fresh folder (at most three tries), with the same checks.
    let mut tries = 0;
    loop {
        tries += 1;
        let t_wait = Instant::now();
        while !has_tile_of_shard(&hall_out, 1, 3) {
            assert!(
                t_wait.elapsed() < Duration::from_secs(120),
                "shard 1 of the Hall wrote no tile in 120 s:\n{}",
                slurm_logs(&hall_out)
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        run_ok(cluster.cmd("scancel").arg(format!("{}_1", hall_ids[0])));
        let s = cluster.wait(&hall_ids[0], Duration::from_secs(240));
        if s.contains(&"CANCELLED".to_string()) {
            break;
        }
        assert!(
            tries < 3,
            "shard 1 of the Hall finished before its cancel in {tries} tries: {s:?}"
        );
        cluster.wait(&hall_ids[1], Duration::from_secs(240));
        hall_out = w.join(format!("hall-{tries}"));
        hall_args = hall_args_for(&hall_out);
        hall_ids = cluster.submit("bake-array.sh", &as_os(&hall_args), &env);
    }
    // The merge's dependency can no longer be met: SLURM cancels it (--kill-on-invalid-dep).
    let s = cluster.wait(&hall_ids[1], Duration::from_secs(60));
    assert_eq!(s, ["CANCELLED"], "the first merge job");
    assert!(
        !hall_out.join("lightmap_000.exr").exists(),
        "a merge ran without shard 1"
    );
    // Resubmit shard 1 alone: it resumes from its tiles, and the new merge assembles the bake.
    let again = cluster.submit(
        "bake-array.sh",
        &as_os(&hall_args),
        &[env[0], ("LUSTRE_TASKS", "1")],
    );
    cluster.wait_completed(&again[1], &hall_out);
    let log = std::fs::read_to_string(hall_out.join(format!("slurm-{}_1.log", again[0])))
        .expect("the resubmitted task's log");
    let (baked, resumed) = tiles_line(&log);
    assert!(
        baked > 0 && resumed > 0,
        "the resubmitted shard should resume part of its tiles: {baked} baked, {resumed} resumed\n{log}"
    );
    cluster.wait_completed(&cornell_ids[1], &cornell_out);
    cluster.wait_completed(&fit_ids[1], &fit_out);
    let slurm_s = t0.elapsed().as_secs_f64();

    // One machine, unsharded.
    let whole = w.join("whole");
    bake_whole(&hall(), &whole.join("hall"), &HALL_BAKE);
    bake_whole(&cornell(), &whole.join("cornell"), &CORNELL_BAKE);
    fit_whole(&whole.join("fits"), &inputs);
    assert_same_bake(&hall_out, &whole.join("hall"));
    assert_same_bake(&cornell_out, &whole.join("cornell"));
    assert_eq!(fit_files(&fit_out), fit_files(&whole.join("fits")));
    eprintln!(
        "SLURM: cluster up, 3 arrays and their merges (one task cancelled and resubmitted) in \
         {slurm_s:.1} s; with the unsharded runs {:.1} s; Hall shard 1 resumed {resumed} tiles \
         and baked {baked} (cancelled in try {tries})",
        t0.elapsed().as_secs_f64()
    );
}

// ---------------------------------------------------------------------------------------------
// OpenJD

fn openjd() -> Command {
    let mut c = Command::new("python3");
    c.args(["-m", "openjd"]).env("PATH", path_with_lustre());
    c
}

#[test]
fn openjd_templates_check_and_run_to_the_unsharded_result() {
    let probe = openjd().arg("--version").output();
    assert!(
        probe.as_ref().is_ok_and(|o| o.status.success()),
        "the OpenJD reference runner is missing: python3 -m pip install openjd-cli==0.8.0, as \
         .ci/run does"
    );
    for t in ["bake", "fit"] {
        let out = run_ok(
            openjd()
                .arg("check")
                .arg(repo().join(format!("deploy/openjd/{t}.yaml"))),
        );
        assert!(out.contains("passes validation checks"), "{out}");
    }
    let work = tempfile::tempdir().expect("work dir");
    let w = work.path();
    let lustre = lustre_bin();
    let param = |k: &str, v: &str| ["-p".to_string(), format!("{k}={v}")];
    let run_template = |t: &str, params: Vec<[String; 2]>| {
        let mut c = openjd();
        c.arg("run")
            .arg(repo().join(format!("deploy/openjd/{t}.yaml")))
            .args(["--step", "Merge", "--run-dependencies"])
            .args(params.iter().flatten());
        let out = run_ok(&mut c);
        assert!(out.contains("All actions completed successfully"), "{out}");
        out
    };
    let bake_out = w.join("bake");
    let out = run_template(
        "bake",
        vec![
            param("Lustre", lustre.to_str().expect("utf-8")),
            param("Scene", cornell().to_str().expect("utf-8")),
            param("Out", bake_out.to_str().expect("utf-8")),
            param("ShardCount", "3"),
            param("Cpus", "2"),
            param("Options", &CORNELL_BAKE.join(" ")),
        ],
    );
    for k in 0..3 {
        assert!(out.contains(&format!("shard {k}/3 done")), "{out}");
    }
    let inputs = merl_tables(w, 4);
    let fit_out = w.join("fits");
    let list: Vec<&str> = inputs.iter().map(|p| p.to_str().expect("utf-8")).collect();
    run_template(
        "fit",
        vec![
            param("Lustre", lustre.to_str().expect("utf-8")),
            param("Out", fit_out.to_str().expect("utf-8")),
            param("Model", "sgd"),
            param("ShardCount", "2"),
            param("Inputs", &list.join(" ")),
        ],
    );
    let whole = w.join("whole");
    bake_whole(&cornell(), &whole.join("bake"), &CORNELL_BAKE);
    fit_whole(&whole.join("fits"), &inputs);
    assert_same_bake(&bake_out, &whole.join("bake"));
    assert_eq!(fit_files(&fit_out), fit_files(&whole.join("fits")));
}

// ---------------------------------------------------------------------------------------------
// Kubernetes

/// A manifest as JSON (PyYAML, which kubernetes-validate brings).
fn manifest(name: &str) -> Value {
    let path = repo().join("deploy/kubernetes").join(name);
    let o = Command::new("python3")
        .args([
            "-c",
            "import json, sys, yaml; print(json.dumps(yaml.safe_load(open(sys.argv[1]))))",
        ])
        .arg(&path)
        .output()
        .expect("python3");
    assert!(o.status.success(), "{}: {}", path.display(), text(&o));
    serde_json::from_slice(&o.stdout).expect("json")
}

/// The container's command line of a Job manifest, with the shared volume's mount `/data`
/// moved to `data` and `--spp N` replaced by the small bake's options.
fn container_command(job: &Value, data: &Path) -> Vec<String> {
    let c = &job["spec"]["template"]["spec"]["containers"][0];
    let mut words: Vec<String> = c["command"]
        .as_array()
        .into_iter()
        .chain(c["args"].as_array())
        .flatten()
        .map(|v| v.as_str().expect("a string").to_string())
        .collect();
    let mount = c["volumeMounts"][0]["mountPath"].as_str().expect("mount");
    let to = data.to_str().expect("utf-8");
    for w in &mut words {
        *w = w.replace(&format!("{mount}/"), &format!("{to}/"));
    }
    if let Some(i) = words.iter().position(|w| w == "--spp") {
        words.splice(i..i + 2, HALL_BAKE.iter().map(|s| s.to_string()));
    }
    words
}

#[test]
fn kubernetes_manifests_validate_and_every_index_runs_to_the_unsharded_result() {
    let files = [
        "bake-indexed-job.yaml",
        "bake-merge-job.yaml",
        "fit-indexed-job.yaml",
        "fit-merge-job.yaml",
    ];
    for version in ["1.33.0", "1.37.0"] {
        let o = Command::new("python3")
            .args(["-m", "kubernetes_validate", "--strict", "-k", version])
            .args(
                files
                    .iter()
                    .map(|f| repo().join("deploy/kubernetes").join(f)),
            )
            .output();
        let o = o.unwrap_or_else(|e| {
            panic!(
                "kubernetes-validate did not start ({e}): python3 -m pip install \
                 kubernetes-validate==1.37.0, as .ci/run does"
            )
        });
        assert!(o.status.success(), "{}", text(&o));
        assert_eq!(
            text(&o).matches("passed").count(),
            files.len(),
            "{}",
            text(&o)
        );
    }
    // The shared volume: the Hall's files where the manifests expect them, MERL tables for the
    // fits.
    let work = tempfile::tempdir().expect("work dir");
    let data = work.path().join("data");
    let hall_dir = data.join("hall");
    std::fs::create_dir_all(&hall_dir).expect("hall dir");
    let src = hall().parent().expect("hall folder").to_path_buf();
    for e in std::fs::read_dir(&src).expect("hall files").flatten() {
        std::os::unix::fs::symlink(e.path(), hall_dir.join(e.file_name())).expect("symlink");
    }
    let inputs = merl_tables(&data, 8);
    for (shards, merge, out) in [
        ("bake-indexed-job.yaml", "bake-merge-job.yaml", "hall/bake"),
        ("fit-indexed-job.yaml", "fit-merge-job.yaml", "fits/sgd"),
    ] {
        let job = manifest(shards);
        assert_eq!(job["spec"]["completionMode"], "Indexed", "{shards}");
        let n = job["spec"]["completions"].as_u64().expect("completions");
        let cmd = container_command(&job, &data);
        assert!(
            cmd.join(" ").contains(&format!("--shard-count {n}")),
            "{shards}: --shard-count must equal completions ({n}): {cmd:?}"
        );
        for index in 0..n {
            let o = Command::new(&cmd[0])
                .args(&cmd[1..])
                .env("PATH", path_with_lustre())
                .env("JOB_COMPLETION_INDEX", index.to_string())
                .output()
                .expect("runs");
            assert!(o.status.success(), "{shards} index {index}: {}", text(&o));
        }
        let cmd = container_command(&manifest(merge), &data);
        let o = Command::new(&cmd[0])
            .args(&cmd[1..])
            .env("PATH", path_with_lustre())
            .output()
            .expect("runs");
        assert!(o.status.success(), "{merge}: {}", text(&o));
        let whole = work.path().join("whole").join(out);
        if shards.starts_with("bake") {
            bake_whole(&hall_dir.join("scene.xml"), &whole, &HALL_BAKE);
            assert_same_bake(&data.join(out), &whole);
        } else {
            fit_whole(&whole, &inputs);
            assert_eq!(fit_files(&data.join(out)), fit_files(&whole));
        }
    }
}
