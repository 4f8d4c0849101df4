//! Fits SGD, Beckmann and GGX Cook-Torrance to the 100 MERL materials of the NBRDF set and
//! compares the SGD fit with the published one (004 Fig. V.12), all by `metrics::evaluate`.
//!
//! `cargo run --release -p lustre-fit --example merl100 -- [--out FILE.md] [--only A,B,...]
//! [--limit N]`

use lustre_fit::ct::{fit, CtOptions, Distribution};
use lustre_fit::metrics::{max_albedo, ngan_l2};
use std::time::Instant;

fn channels(r: &[f64; 3]) -> String {
    format!("{:.4e} / {:.4e} / {:.4e}", r[0], r[1], r[2])
}

fn mean(r: &[f64; 3]) -> f64 {
    r.iter().sum::<f64>() / 3.0
}

/// CPU seconds of this process (user + system, all threads) from /proc/self/stat; 0 where
/// unavailable. Wall time on a shared machine mostly measures the other users.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the parenthesized command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    // Clock ticks are 100 per second on Linux.
    (ticks(11) + ticks(12)) / 100.0
}

/// The Ngan errors (per channel) of one material's fits and the published fit.
struct Row {
    e_sgd: [f64; 3],
    e_pub: [f64; 3],
    e_beck: [f64; 3],
    e_ggx: [f64; 3],
    t_sgd: f64,
    c_sgd: f64,
    status: String,
}

fn one(
    data: &lustre_fit::data::MeasuredData,
    published: &lustre_brdf::fits::sgd::SgdFits,
    opts: &CtOptions,
) -> Result<Row, Box<dyn std::error::Error>> {
    let d = data.bsdf.as_ref();
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let sgd = fit(d, Distribution::Sgd, opts)?;
    let (t_sgd, c_sgd) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    let beck = fit(d, Distribution::Beckmann, opts)?;
    let ggx = fit(d, Distribution::Ggx, opts)?;
    let pubm = published.cook_torrance(&data.name)?;
    // The Ngan part of metrics::evaluate, with the data's maximum albedo computed once.
    let amax = max_albedo(d, false);
    Ok(Row {
        e_sgd: ngan_l2(d, &sgd.to_bsdf("sgd")?, &amax),
        e_pub: ngan_l2(d, &pubm, &amax),
        e_beck: ngan_l2(d, &beck.to_bsdf("beckmann")?, &amax),
        e_ggx: ngan_l2(d, &ggx.to_bsdf("ggx")?, &amax),
        t_sgd,
        c_sgd,
        status: format!("{:?}/{:?}/{:?}", sgd.status, beck.status, ggx.status),
    })
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut out: Option<String> = None;
    let mut only: Option<Vec<String>> = None;
    let mut limit = usize::MAX;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = Some(args.next().ok_or("--out needs a file")?),
            "--only" => {
                let v = args.next().ok_or("--only needs a list")?;
                only = Some(v.split(',').map(str::to_string).collect());
            }
            "--limit" => limit = args.next().ok_or("--limit needs a number")?.parse()?,
            other => return Err(format!("unknown argument {other:?}").into()),
        }
    }
    let file = lustre_brdf::shared_data_dir().join("nbrdf/merl_nbrdf.json");
    let inputs = lustre_fit::data::expand_inputs(&format!("nbrdf:{}#*", file.display()))?;
    let published = lustre_brdf::fits::sgd::SgdFits::load_default()?;
    let opts = CtOptions::default();
    let mut lines = vec![
        "| material | SGD ours | SGD published | Beckmann | GGX | SGD wall (s) | SGD CPU (s) | SGD ours r/g/b | SGD published r/g/b | Beckmann r/g/b | GGX r/g/b | status |".to_string(),
        "|---|---|---|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    let (mut n, mut better, mut beats_beckmann, mut failed) = (0usize, 0usize, 0usize, 0usize);
    let (mut times, mut cpu) = (Vec::new(), Vec::new());
    for input in inputs.iter() {
        let data = lustre_fit::data::load(input)?;
        if let Some(o) = &only {
            if !o.contains(&data.name) {
                continue;
            }
        }
        if n >= limit {
            break;
        }
        let r = match one(&data, &published, &opts) {
            Ok(r) => r,
            Err(e) => {
                let line = format!("| {} | error: {e} |", data.name);
                println!("{line}");
                lines.push(line);
                failed += 1;
                continue;
            }
        };
        let Row {
            e_sgd,
            e_pub,
            e_beck,
            e_ggx,
            t_sgd,
            c_sgd,
            status,
        } = r;
        n += 1;
        better += usize::from(mean(&e_sgd) <= mean(&e_pub));
        beats_beckmann += usize::from(mean(&e_sgd) < mean(&e_beck));
        times.push(t_sgd);
        cpu.push(c_sgd);
        let line = format!(
            "| {} | {:.4e} | {:.4e} | {:.4e} | {:.4e} | {:.3} | {:.2} | {} | {} | {} | {} | {} |",
            data.name,
            mean(&e_sgd),
            mean(&e_pub),
            mean(&e_beck),
            mean(&e_ggx),
            t_sgd,
            c_sgd,
            channels(&e_sgd),
            channels(&e_pub),
            channels(&e_beck),
            channels(&e_ggx),
            status,
        );
        println!("{line}");
        lines.push(line);
    }
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (
            v.get(v.len() / 2).copied().unwrap_or(0.0),
            v.last().copied().unwrap_or(0.0),
        )
    };
    let (median, worst) = stats(&mut times);
    let (median_cpu, worst_cpu) = stats(&mut cpu);
    let threads = rayon::current_num_threads();
    let summary = [
        String::new(),
        format!("- materials: {n} fitted, {failed} failed"),
        format!("- SGD ours ≤ published (Ngan L2, mean of channels): {better}/{n}"),
        format!("- SGD ours < Beckmann ours: {beats_beckmann}/{n}"),
        format!("- SGD fit wall time: median {median:.3} s, worst {worst:.3} s ({threads} rayon threads)"),
        format!("- SGD fit CPU time (all threads): median {median_cpu:.2} s, worst {worst_cpu:.2} s"),
    ];
    for s in &summary {
        println!("{s}");
    }
    lines.extend(summary);
    if let Some(path) = out {
        let text = format!(
            "# Cook-Torrance fits of the MERL NBRDF materials\n\nNgan L2 normalized by the data's \
             maximum albedo (004 §V.5.3), mean of the channels, then per channel.\n\n{}\n",
            lines.join("\n")
        );
        lustre_brdf::error::write_atomic(std::path::Path::new(&path), text.as_bytes())?;
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("merl100: {e}");
        std::process::exit(1);
    }
}
