//! Kurt fits with 1, 2 and 3 lobes of the five RGL files and the two goniometric tables, in the
//! manner of 000 Tables 3.1–3.3, plus measured-vs-model plots in the style of Fig. 3.11–3.12.
//!
//! ```text
//! cargo run --release -p lustre-fit --example kurt_tables -- --out DIR [--lobes 1,2,3] [--no-plots] [--only NAME]
//! ```
//!
//! Writes `DIR/kurt_tables.md` (parameters, L1 error of Eq. 3.7 on the fit's direction set and
//! from `metrics`, Ngan's L2, albedo at normal incidence of data and model, fit time, status) and, per material, a transfer-probability
//! array of the data next to the 2-lobe model (Fig. 3.11) and polar plots of the data with the
//! 1- and 2-lobe models in the planes φi = 0° and 90° (Fig. 3.12, cube root).

use lustre_brdf::{catalog, shared_data_dir, Bsdf, DVec3};
use lustre_fit::kurt::{fit, KurtFit, KurtOptions};
use lustre_fit::metrics;
use lustre_plot::{ArrayOptions, PolarOptions};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

struct Args {
    out: PathBuf,
    lobes: Vec<usize>,
    plots: bool,
    only: Option<String>,
}

fn parse_args() -> Result<Args, String> {
    let mut out = None;
    let mut lobes = vec![1, 2, 3];
    let mut plots = true;
    let mut only = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => out = it.next().map(PathBuf::from),
            "--lobes" => {
                let v = it.next().ok_or("--lobes needs a list such as 1,2,3")?;
                lobes = v
                    .split(',')
                    .map(|s| s.trim().parse::<usize>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("--lobes {v}: {e}"))?;
            }
            "--no-plots" => plots = false,
            "--only" => only = it.next(),
            other => return Err(format!("unknown argument {other}")),
        }
    }
    let out =
        out.ok_or("usage: kurt_tables --out DIR [--lobes 1,2,3] [--no-plots] [--only NAME]")?;
    Ok(Args {
        out,
        lobes,
        plots,
        only,
    })
}

/// The inputs: (short name, catalog specification).
fn inputs() -> Vec<(String, String)> {
    let d = shared_data_dir().join("measured");
    let mut v: Vec<(String, String)> = [
        "cc_ibiza_sunset_rgb",
        "cg_sunflower_rgb",
        "colodur_napoli_4f_rgb",
        "paper_white_rgb",
        "vch_golden_yellow_rgb",
    ]
    .iter()
    .map(|n| {
        let p = d.join("rgl").join(format!("{n}.bsdf"));
        (n.to_string(), p.display().to_string())
    })
    .collect();
    let g = d.join("goniometric");
    v.push((
        "retro-3M-jaune".into(),
        g.join("retro-3M-jaune.dat").display().to_string(),
    ));
    v.push((
        "retro-gray-tape".into(),
        format!("{}#inv-sr-cos", g.join("retro-gray-tape.dat").display()),
    ));
    v
}

fn rgb(v: [f64; 3]) -> String {
    format!("{:.3}, {:.3}, {:.3}", v[0], v[1], v[2])
}

fn mean(v: [f64; 3]) -> f64 {
    (v[0] + v[1] + v[2]) / 3.0
}

/// One table row per fit.
struct Row {
    name: String,
    lobes: usize,
    fit: KurtFit,
    l1: [f64; 3],
    ngan: [f64; 3],
    albedo_data: [f64; 3],
    albedo_model: [f64; 3],
    seconds: f64,
}

fn row_markdown(r: &Row) -> String {
    let m = &r.fit.model;
    let lobes: Vec<String> = m
        .reflection
        .iter()
        .enumerate()
        .map(|(i, l)| {
            format!(
                "{}: ks ({}) mx {:.4} my {:.4} r0 {:.3} α {:.2}",
                i + 1,
                rgb(l.ks.0),
                l.mx,
                l.my,
                l.r0,
                l.alpha
            )
        })
        .collect();
    format!(
        "| {} | {} | {} | {} | {:.4e} | {:.4e} ({}) | {:.4} | {:.3} | {:.3} | {:.1} | {} | {:?} |\n",
        r.name,
        r.lobes,
        rgb(m.kd.0),
        lobes.join("<br>"),
        r.fit.objective,
        mean(r.l1),
        r.l1.iter()
            .map(|v| format!("{v:.2e}"))
            .collect::<Vec<_>>()
            .join(", "),
        mean(r.ngan),
        mean(r.albedo_data),
        mean(r.albedo_model),
        r.seconds,
        r.fit.evaluations,
        r.fit.status
    )
}

fn slug(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

fn plots(
    out: &Path,
    name: &str,
    data: &dyn Bsdf,
    fits: &[(usize, &KurtFit)],
) -> Result<Vec<PathBuf>, String> {
    let mut written = Vec::new();
    let labels: Vec<String> = fits.iter().map(|(n, _)| format!("{n} lobe(s)")).collect();
    if let Some(&(n, f)) = fits.iter().find(|(n, _)| *n == 2).or(fits.first()) {
        let base = out.join(format!("array-{}-{}lobes", slug(name), n));
        let files = lustre_plot::transfer_array_compare(
            (data, "measured"),
            (&f.model, &format!("Kurt, {n} lobe(s)")),
            &ArrayOptions {
                title: Some(format!("{name}: measured vs Kurt {n} lobe(s)")),
                ..ArrayOptions::default()
            },
            &base,
        )
        .map_err(|e| e.to_string())?;
        written.extend(files.paths().into_iter().map(Path::to_path_buf));
    }
    let mut all: Vec<(&dyn Bsdf, &str)> = vec![(data, "measured")];
    for ((_, f), l) in fits.iter().zip(&labels) {
        all.push((&f.model, l.as_str()));
    }
    for phi in [0.0, 90.0] {
        let base = out.join(format!("polar-{}-phi{}", slug(name), phi as i32));
        let files = lustre_plot::polar_plot(
            &all,
            &[0.0, 20.0, 65.0],
            &PolarOptions {
                cube_root: true,
                phi_i_deg: phi,
                title: Some(format!("{name}: φi = {phi}°, cube root of p")),
                ..PolarOptions::default()
            },
            &base,
        )
        .map_err(|e| e.to_string())?;
        written.extend(files.paths().into_iter().map(Path::to_path_buf));
    }
    Ok(written)
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let mut md = String::from(
        "# Kurt fits of the measured materials (000 Tables 3.1–3.3 style)\n\n\
         Hierarchical brute force (grid 5, 6 levels) + Levenberg-Marquardt polish, \
         `lustre_fit::kurt::fit`. L1 fit = Eq. 3.7 on the fit's own direction set (its objective, \
         mean of RGB); L1 metrics and Ngan L2 = `lustre_fit::metrics::evaluate` (Eq. 3.7 on a 5° \
         grid; Ngan's normalized L2), mean (R, G, B). Albedo = directional albedo at normal \
         incidence (Eq. 2.6), mean of RGB. Time = wall-clock seconds of the fit alone. \
         Evaluations = lobe evaluations over the direction set.\n\n\
         | material | lobes | kd (RGB) | lobes: ks (RGB), mx, my, r0, α | L1 fit | L1 metrics mean (R, G, B) | Ngan L2 | albedo data | albedo model | time (s) | evaluations | status |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut written = Vec::new();
    for (name, spec) in inputs() {
        if args
            .only
            .as_ref()
            .is_some_and(|o| !name.contains(o.as_str()))
        {
            continue;
        }
        let data = catalog::resolve(&spec).map_err(|e| format!("{spec}: {e}"))?;
        let amax = metrics::max_albedo(data.as_ref(), false);
        let albedo_data = metrics::albedo(data.as_ref(), DVec3::Z, false);
        let mut fits: Vec<(usize, KurtFit)> = Vec::new();
        for &lobes in &args.lobes {
            let opts = KurtOptions {
                lobes,
                ..KurtOptions::default()
            };
            let t = Instant::now();
            let f = fit(data.as_ref(), false, &opts).map_err(|e| format!("{name}: {e}"))?;
            let seconds = t.elapsed().as_secs_f64();
            let row = Row {
                name: name.clone(),
                lobes,
                albedo_data,
                albedo_model: metrics::albedo(&f.model, DVec3::Z, false),
                l1: metrics::l1_error(data.as_ref(), &f.model, false),
                ngan: metrics::ngan_l2(data.as_ref(), &f.model, &amax),
                seconds,
                fit: f,
            };
            let line = row_markdown(&row);
            eprint!("{line}");
            md.push_str(&line);
            fits.push((lobes, row.fit));
        }
        if args.plots {
            let two: Vec<(usize, &KurtFit)> = fits
                .iter()
                .filter(|(n, _)| *n <= 2)
                .map(|(n, f)| (*n, f))
                .collect();
            written.extend(plots(&args.out, &name, data.as_ref(), &two)?);
        }
    }
    let path = args.out.join("kurt_tables.md");
    let tmp = args.out.join(".kurt_tables.md.tmp");
    std::fs::write(&tmp, &md).map_err(|e| format!("{}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, &path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut list = String::new();
    for p in written.iter().chain(std::iter::once(&path)) {
        let _ = writeln!(list, "{}", p.display());
    }
    print!("{list}");
    Ok(())
}
