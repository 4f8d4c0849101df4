//! Fits SGD, Beckmann and GGX Cook-Torrance to the 100 MERL materials of the NBRDF set (and, with
//! `--rgl`, to the five RGL measurements), compares the SGD fit with the published one (004 Fig.
//! V.12), counts unphysical fits, and with `--kurt LIST` fits Kurt with 1–3 lobes to the listed
//! MERL materials and the RGL files; all errors by `metrics`.
//!
//! `cargo run --release -p lustre-fit --example merl100 -- [--out FILE.md] [--only A,B,...]
//! [--limit N] [--rgl] [--kurt A,B,...|all|none] [--kurt-lobes 3]`
//!
//! A fit is counted unphysical when a channel has ρd < 0 or ρs < 0, F0 outside [0, 1] or F1
//! outside [F0 − 1, F0] (so that Eq. V.5 leaves [0, 1]), or a directional albedo (θo = 0°, 10°,
//! …, 80°) above 1.001 where the data's stays ≤ 1, or below 0.

use lustre_brdf::material::MaterialModel;
use lustre_brdf::Bsdf;
use lustre_fit::ct::{fit, CtDistribution, CtFit, CtOptions};
use lustre_fit::kurt::{self, KurtOptions};
use lustre_fit::metrics::{albedo, max_albedo, ngan_l2, Metric, MetricJudge};
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
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

/// The smallest and largest directional albedo per channel over θo = 0°, 10°, …, 80°.
fn albedo_range(b: &dyn Bsdf) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for k in 0..9 {
        let a = albedo(
            b,
            lustre_brdf::frame::spherical((10.0 * k as f64).to_radians(), 0.0),
            false,
        );
        for c in 0..3 {
            lo[c] = lo[c].min(a[c]);
            hi[c] = hi[c].max(a[c]);
        }
    }
    (lo, hi)
}

/// Why a model is unphysical (empty: physical). `data_max`: the data's maximum albedo.
fn unphysical(model: &dyn Bsdf, params: Option<&CtFit>, data_max: &[f64; 3]) -> Vec<String> {
    let mut why = Vec::new();
    if let Some(f) = params {
        for (c, ch) in f.channels.iter().enumerate() {
            if ch.rho_d < 0.0 || ch.rho_s < 0.0 {
                why.push(format!("ch{c}: rho < 0"));
            }
            if !(0.0..=1.0).contains(&ch.f0) || ch.f1 > ch.f0 + 1e-12 || ch.f1 < ch.f0 - 1.0 - 1e-12
            {
                why.push(format!("ch{c}: F0 {:.3}, F1 {:.3}", ch.f0, ch.f1));
            }
        }
    }
    let (lo, hi) = albedo_range(model);
    for c in 0..3 {
        if lo[c] < 0.0 {
            why.push(format!("ch{c}: albedo {:.3} < 0", lo[c]));
        }
        if hi[c] > 1.001 && data_max[c] <= 1.0 {
            why.push(format!("ch{c}: albedo {:.3} > 1", hi[c]));
        }
    }
    why
}

struct CtResult {
    e: [f64; 3],
    wall: f64,
    cpu: f64,
    why: Vec<String>,
    status: String,
    notes: usize,
}

fn ct_one(
    d: &dyn Bsdf,
    dist: CtDistribution,
    amax: &[f64; 3],
) -> Result<CtResult, Box<dyn std::error::Error>> {
    let (t0, c0) = (Instant::now(), cpu_seconds());
    let f = fit(d, dist, &CtOptions::default())?;
    let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
    let b = f.to_bsdf(dist.as_str())?;
    Ok(CtResult {
        e: ngan_l2(d, &b, amax),
        wall,
        cpu,
        why: unphysical(&b, Some(&f), amax),
        status: format!("{:?}", f.status),
        notes: f.notes.len(),
    })
}

/// The 1-, 5- and 15-minute load averages (/proc/loadavg), or "?".
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "?".into())
}

fn stats(v: &[f64]) -> (f64, f64) {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    (
        v.get(v.len() / 2).copied().unwrap_or(0.0),
        v.last().copied().unwrap_or(0.0),
    )
}

/// One Kurt fit of a material with k lobes.
struct KurtRow {
    /// Ngan L2 (mean of channels) of this fit.
    ngan: f64,
    /// Eq. 3.7 objective.
    obj: f64,
    wall: f64,
    cpu: f64,
    converged: bool,
    /// The polish stopped at its iteration limit.
    limit: bool,
    /// The alternation of lobes did not settle.
    unsettled: bool,
    /// The search's result was kept (every polish was worse on Ngan's L2).
    kept_search: bool,
    unphysical: bool,
}

/// Kurt fits with 1..=`max` lobes; per k the Ngan L2 (mean) of that fit, the reported one
/// (the best of 1..=k, as `lustre fit --model kurt --lobes k` reports), the times and status.
fn kurt_rows(
    name: &str,
    d: &dyn Bsdf,
    amax: &[f64; 3],
    max: usize,
) -> Result<(Vec<String>, Vec<KurtRow>), Box<dyn std::error::Error>> {
    let mut lines = Vec::new();
    let mut rows = Vec::new();
    let mut best = f64::INFINITY;
    // As `lustre fit --model kurt` (default `--metric ngan-l2`): Ngan's L2 picks the candidate.
    let judge = MetricJudge::new(Metric::NganL2, d, false, None);
    for k in 1..=max {
        let (t0, c0) = (Instant::now(), cpu_seconds());
        let f = kurt::fit_judged(
            d,
            false,
            &KurtOptions {
                lobes: k,
                ..KurtOptions::default()
            },
            None,
            Some(&judge),
        )?;
        let (t, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        let m = MaterialModel::from_kurt(&f.model).to_bsdf(name)?;
        let e = ngan_l2(d, m.as_ref(), amax);
        best = best.min(mean(&e));
        let why = unphysical(m.as_ref(), None, amax);
        lines.push(format!(
            "| {name} | {k} | {:.4e} | {best:.4e} | {:.4e} | {t:.2} | {cpu:.2} | {:?} | {} | {} |",
            mean(&e),
            f.objective,
            f.status,
            if why.is_empty() {
                "-".to_string()
            } else {
                why.join(", ")
            },
            f.note
        ));
        rows.push(KurtRow {
            ngan: mean(&e),
            obj: f.objective,
            wall: t,
            cpu,
            converged: f.status == lustre_fit::FitStatus::Converged,
            limit: f.kept.contains("iteration limit"),
            kept_search: f.kept.starts_with("the search"),
            unsettled: f.note.contains("did not settle"),
            unphysical: !why.is_empty(),
        });
    }
    Ok((lines, rows))
}

/// The summary lines of the Kurt fits (`per[input][k − 1]`).
fn kurt_summary(per: &[Vec<KurtRow>], max: usize) -> Vec<String> {
    let mut out = Vec::new();
    let n = per.len();
    for k in 1..=max {
        let rows: Vec<&KurtRow> = per.iter().filter_map(|r| r.get(k - 1)).collect();
        let (mw, ww) = stats(&rows.iter().map(|r| r.wall).collect::<Vec<_>>());
        let (mc, wc) = stats(&rows.iter().map(|r| r.cpu).collect::<Vec<_>>());
        let count = |f: &dyn Fn(&KurtRow) -> bool| rows.iter().filter(|r| f(r)).count();
        out.push(format!(
            "- Kurt {k} lobe(s), {} inputs: wall median {mw:.2} s, worst {ww:.2} s; CPU median {mc:.2} s, worst {wc:.2} s; status Converged {}, NotConverged {} (kept polish at its iteration limit {}, kept search result {}; alternation of lobes not settled {}); unphysical {}",
            rows.len(),
            count(&|r| r.converged),
            count(&|r| !r.converged),
            count(&|r| r.limit),
            count(&|r| r.kept_search),
            count(&|r| r.unsettled),
            count(&|r| r.unphysical),
        ));
        if k > 1 {
            let beats = |f: &dyn Fn(&KurtRow) -> f64| {
                per.iter()
                    .filter(|r| r.len() >= k && f(&r[k - 1]) < f(&r[0]))
                    .count()
            };
            out.push(format!(
                "- Kurt {k} lobes lower than 1 lobe: Ngan L2 on {}/{n}, Eq. 3.7 objective on {}/{n}",
                beats(&|r| r.ngan),
                beats(&|r| r.obj)
            ));
        }
    }
    out
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let mut out: Option<String> = None;
    let mut only: Option<Vec<String>> = None;
    let mut limit = usize::MAX;
    let mut rgl = false;
    let mut kurt_list: Vec<String> = Vec::new();
    let mut kurt_lobes = 3;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--out" => out = Some(args.next().ok_or("--out needs a file")?),
            "--only" => {
                let v = args.next().ok_or("--only needs a list")?;
                only = Some(v.split(',').map(str::to_string).collect());
            }
            "--limit" => limit = args.next().ok_or("--limit needs a number")?.parse()?,
            "--rgl" => rgl = true,
            "--kurt" => {
                let v = args.next().ok_or("--kurt needs a list")?;
                if v != "none" {
                    kurt_list = v.split(',').map(str::to_string).collect();
                }
            }
            "--kurt-lobes" => {
                kurt_lobes = args.next().ok_or("--kurt-lobes needs a number")?.parse()?
            }
            other => return Err(format!("unknown argument {other:?}").into()),
        }
    }
    let (run_start, load_start) = (Instant::now(), load_average());
    let mut inputs = lustre_fit::data::expand_inputs("nbrdf:*")?;
    if let Some(o) = &only {
        inputs.retain(|i| o.iter().any(|n| i == &format!("nbrdf:{n}")));
    }
    inputs.truncate(limit);
    let n_merl = inputs.len();
    let rgl_dir = lustre_brdf::shared_data_dir().join("measured/rgl");
    let rgl_files = [
        "cc_ibiza_sunset_rgb",
        "cg_sunflower_rgb",
        "colodur_napoli_4f_rgb",
        "paper_white_rgb",
        "vch_golden_yellow_rgb",
    ]
    .map(|n| rgl_dir.join(format!("{n}.bsdf")).display().to_string());
    if rgl {
        inputs.extend(rgl_files.iter().cloned());
    }
    let published = lustre_brdf::fits::sgd::SgdFits::load_default()?;
    let mut lines = vec![
        "| material | SGD ours | SGD published | Beckmann | GGX | SGD wall (s) | SGD CPU (s) | Beckmann / GGX CPU (s) | SGD ours r/g/b | SGD published r/g/b | status SGD/Beckmann/GGX | unphysical |".to_string(),
        "|---|---|---|---|---|---|---|---|---|---|---|---|".to_string(),
    ];
    let (mut n, mut better, mut beats_beckmann, mut failed) = (0usize, 0usize, 0usize, 0usize);
    let mut unphys = [0usize; 4];
    let mut capped = [0usize; 3];
    let mut n_pub = 0usize;
    let (mut wall, mut cpu, mut cpu_b, mut cpu_g) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut kurt_lines = Vec::new();
    let mut kurt_per: Vec<Vec<KurtRow>> = Vec::new();
    for input in &inputs {
        let data = lustre_fit::data::load(input)?;
        let d = data.bsdf.as_ref();
        let amax = max_albedo(d, false);
        let pubm = if input.starts_with("nbrdf:") {
            Some(published.cook_torrance(&data.name)?)
        } else {
            None
        };
        let res = (|| -> Result<_, Box<dyn std::error::Error>> {
            Ok((
                ct_one(d, CtDistribution::Sgd, &amax)?,
                ct_one(d, CtDistribution::Beckmann, &amax)?,
                ct_one(d, CtDistribution::Ggx, &amax)?,
            ))
        })();
        let (s, b, g) = match res {
            Ok(r) => r,
            Err(e) => {
                let line = format!("| {} | error: {e} |", data.name);
                println!("{line}");
                lines.push(line);
                failed += 1;
                continue;
            }
        };
        n += 1;
        let e_pub = pubm.as_ref().map(|p| ngan_l2(d, p, &amax));
        let pub_why = pubm
            .as_ref()
            .map(|p| unphysical(p, None, &amax))
            .unwrap_or_default();
        if let Some(ep) = &e_pub {
            n_pub += 1;
            better += usize::from(mean(&s.e) <= mean(ep));
            unphys[3] += usize::from(!pub_why.is_empty());
        }
        beats_beckmann += usize::from(mean(&s.e) < mean(&b.e));
        for (k, r) in [&s, &b, &g].iter().enumerate() {
            unphys[k] += usize::from(!r.why.is_empty());
            capped[k] += usize::from(r.notes > 0);
        }
        wall.push(s.wall);
        cpu.push(s.cpu);
        cpu_b.push(b.cpu);
        cpu_g.push(g.cpu);
        let why: Vec<String> = [("sgd", &s.why), ("beckmann", &b.why), ("ggx", &g.why)]
            .iter()
            .filter(|(_, w)| !w.is_empty())
            .map(|(m, w)| format!("{m}: {}", w.join(", ")))
            .collect();
        let line = format!(
            "| {} | {:.4e} | {} | {:.4e} | {:.4e} | {:.3} | {:.2} | {:.2} / {:.2} | {} | {} | {}/{}/{} | {} |",
            data.name,
            mean(&s.e),
            e_pub.map_or("-".into(), |e| format!("{:.4e}", mean(&e))),
            mean(&b.e),
            mean(&g.e),
            s.wall,
            s.cpu,
            b.cpu,
            g.cpu,
            channels(&s.e),
            e_pub.map_or("-".into(), |e| channels(&e)),
            s.status,
            b.status,
            g.status,
            if why.is_empty() { "-".into() } else { why.join("; ") }
        );
        println!("{line}");
        lines.push(line);
        let is_rgl = !input.starts_with("nbrdf:");
        let listed = kurt_list.iter().any(|k| k == &data.name || k == "all");
        if kurt_lobes > 0 && (is_rgl || listed) {
            let (kl, rows) = kurt_rows(&data.name, d, &amax, kurt_lobes)?;
            for l in &kl {
                println!("{l}");
            }
            kurt_lines.extend(kl);
            kurt_per.push(rows);
        }
    }
    let threads = rayon::current_num_threads();
    let (mw, ww) = stats(&wall);
    let (mc, wc) = stats(&cpu);
    let (mb, wb) = stats(&cpu_b);
    let (mg, wg) = stats(&cpu_g);
    let mut summary = vec![
        String::new(),
        format!(
            "- inputs: {n} fitted ({n_merl} MERL NBRDF materials{}), {failed} failed",
            if rgl { " + 5 RGL files" } else { "" }
        ),
        format!("- SGD ours ≤ published (Ngan L2, mean of channels): {better}/{n_pub} MERL materials"),
        format!("- SGD ours < Beckmann ours: {beats_beckmann}/{n}"),
        format!(
            "- unphysical fits (see the example's notes): SGD {}, Beckmann {}, GGX {} of {n}; published SGD {} of {n_pub}",
            unphys[0], unphys[1], unphys[2], unphys[3]
        ),
        format!(
            "- fits whose albedo was capped to stay ≤ 1 (step 5 of ct): SGD {}, Beckmann {}, GGX {}",
            capped[0], capped[1], capped[2]
        ),
        format!(
            "- whole run: {:.0} s wall; load average (1, 5, 15 min) at the start {load_start}, at the end {}",
            run_start.elapsed().as_secs_f64(),
            load_average()
        ),
        format!("- SGD fit wall time: median {mw:.3} s, worst {ww:.3} s ({threads} rayon threads)"),
        format!("- SGD fit CPU time (all threads): median {mc:.2} s, worst {wc:.2} s"),
        format!("- Beckmann CPU: median {mb:.2} s, worst {wb:.2} s; GGX CPU: median {mg:.2} s, worst {wg:.2} s"),
    ];
    if !kurt_lines.is_empty() {
        summary.extend(kurt_summary(&kurt_per, kurt_lobes));
        summary.push(String::new());
        summary.push("## Kurt, 1–3 lobes (the k-lobe fit judged by Ngan L2, and reported = best of 1..k on Ngan L2)".into());
        summary.push(String::new());
        summary.push("Each k-lobe fit keeps the best on Ngan's L2 of its candidates (the search's result, the Eq. 3.7 polish from it and, for k > 1, from the one-lobe fit, and the Ngan-L2 polish of the best of those), as `lustre fit --model kurt` does (`kurt::fit_judged`); the note lists them.".into());
        summary.push(String::new());
        summary.push("| material | lobes | Ngan L2 of this fit | reported (best of 1..k) | Eq. 3.7 objective | wall (s) | CPU (s) | status | unphysical | note |".into());
        summary.push("|---|---|---|---|---|---|---|---|---|---|".into());
        summary.extend(kurt_lines);
    }
    for s in &summary {
        println!("{s}");
    }
    lines.extend(summary);
    if let Some(path) = out {
        let text = format!(
            "# Cook-Torrance (and Kurt) fits of the MERL NBRDF materials and the RGL files\n\n\
             Generated by `cargo run --release -p lustre-fit --example merl100 -- --out {path} \
             --rgl --kurt ...`. Ngan L2 normalized by the data's maximum albedo (004 §V.5.3), \
             mean of the channels, then per channel. Fits are physical by construction (F in \
             [0, 1], albedo ≤ 1 where the data's is; see `lustre_fit::ct`).\n\n{}\n",
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
