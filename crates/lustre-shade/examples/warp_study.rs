//! Regular sampling through model warps (`lustre_shade::warp`) against the exact environment
//! integral, for the models `lustre fit` writes and the scenes' analytic materials.
//!
//! For each real map (equirect from ../shared/data/envmaps, resampled onto a cube of `--face`
//! texels, Gaussian 6×6 pyramid), each material (GGX and Beckmann Cook-Torrance at α 0.1 and
//! 0.3, anisotropic GGX and Beckmann rough conductors at α 0.2/0.075, a rough plastic, two SGD
//! fits) and each budget, `--configs` seeded shading configurations (`truth::configurations`,
//! θo uniform in [0°, 85°)) are shaded by `warp::shade_warp` with one point set and level rule
//! per method, all through the model's own `Bsdf::sample`, all with the same budget:
//!
//! - `regular`: ours, `shade_regular_warp` (Fibonacci lattice, footprint levels);
//! - `CK`: Colbert–Křivánek 2007, `shade_ck_warp` (Hammersley points, their level);
//! - `random/fp`: independent uniform points (seeded per configuration), footprint levels;
//! - `Hamm./fp`: Hammersley points, footprint levels;
//! - `Fib./CK`: Fibonacci points, the CK level;
//!
//! and compared with `truth::truth` over every level-0 texel. Reported: relative RMS % (RMS
//! error over RMS truth, all channels and configurations) per map × material × budget, and a
//! summary per material × budget pooled over the maps.
//!
//! Run: `cargo run --release -p lustre-shade --example warp_study -- [--face 64] [--configs 60]
//! [--budgets 8,13,19] [--maps a.hdr,b.exr] [--out FILE.md]`.

use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::catalog::resolve;
use lustre_brdf::rgb::Rgb;
use lustre_env::{irradiance_map, read_map, shared_data_dir, CubeMap, CubePyramid, MipFilter};
use lustre_shade::integrator::FilteredEnvironment;
use lustre_shade::truth::{configurations, supersampling_for, truth, Configuration};
use lustre_shade::warp::{shade_warp, LevelRule, PointSet};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

type Res<T> = Result<T, Box<dyn std::error::Error>>;

/// Name, catalog spec and the smallest slope width (for the truth's supersampling; for the SGD
/// fits a lower bound).
const MATERIALS: [(&str, &str, f64); 9] = [
    ("GGX α 0.1", "ggx(rho_d=0, rho_s=0.785398, alpha=0.1)", 0.1),
    ("GGX α 0.3", "ggx(rho_d=0, rho_s=0.785398, alpha=0.3)", 0.3),
    (
        "Beckmann α 0.1",
        "beckmann(rho_d=0, rho_s=0.785398, alpha=0.1)",
        0.1,
    ),
    (
        "Beckmann α 0.3",
        "beckmann(rho_d=0, rho_s=0.785398, alpha=0.3)",
        0.3,
    ),
    (
        "GGX 0.2/0.075",
        "roughconductor(material=none, alpha_u=0.2, alpha_v=0.075, distribution=ggx)",
        0.075,
    ),
    (
        "Beckmann 0.2/0.075",
        "roughconductor(material=none, alpha_u=0.2, alpha_v=0.075, distribution=beckmann)",
        0.075,
    ),
    (
        "rough plastic α 0.1",
        "roughplastic(alpha=0.1, diffuse=0.3)",
        0.1,
    ),
    ("SGD gold-metallic-paint", "sgd:gold-metallic-paint", 0.05),
    ("SGD nickel", "sgd:nickel", 0.05),
];

const METHODS: [&str; 5] = ["regular", "CK", "random/fp", "Hamm./fp", "Fib./CK"];
const NM: usize = METHODS.len();

fn method(k: usize, seed: u64) -> (PointSet, LevelRule) {
    match k {
        0 => (PointSet::Fibonacci, LevelRule::Footprint),
        1 => (PointSet::Hammersley, LevelRule::Ck),
        2 => (PointSet::Random(seed), LevelRule::Footprint),
        3 => (PointSet::Hammersley, LevelRule::Footprint),
        _ => (PointSet::Fibonacci, LevelRule::Ck),
    }
}

fn arg(args: &[String], name: &str, default: &str) -> String {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .cloned()
        .unwrap_or_else(|| default.to_string())
}

/// Σ error² and Σ truth² over channels.
#[derive(Clone, Copy, Default)]
struct Acc {
    err2: f64,
    truth2: f64,
}

impl Acc {
    fn add(&mut self, e: Rgb, t: Rgb) {
        for c in 0..3 {
            self.err2 += (e[c] - t[c]).powi(2);
            self.truth2 += t[c] * t[c];
        }
    }
    fn merge(&mut self, o: &Acc) {
        self.err2 += o.err2;
        self.truth2 += o.truth2;
    }
    fn rel(&self) -> f64 {
        (self.err2 / self.truth2).sqrt()
    }
}

/// Per budget and method, the accumulated errors of one map × material.
fn study(
    bsdf: &dyn Bsdf,
    roughness: f64,
    env: &FilteredEnvironment,
    configs: &[Configuration],
    budgets: &[usize],
) -> Vec<[Acc; NM]> {
    let base = &env.pyramid.levels[0];
    let face = base.size;
    let rows: Vec<Vec<[(Rgb, Rgb); NM]>> = configs
        .par_iter()
        .enumerate()
        .map(|(k, c)| {
            let s = supersampling_for(roughness, c.frame.to_local(c.wo), face);
            let t = truth(base, &c.frame, c.wo, bsdf, s);
            budgets
                .iter()
                .map(|&n| {
                    std::array::from_fn(|m| {
                        let (points, levels) = method(m, 0x5eed + k as u64);
                        let (e, _) = shade_warp(&c.frame, c.wo, bsdf, env, None, n, points, levels);
                        (e, t)
                    })
                })
                .collect()
        })
        .collect();
    let mut acc = vec![[Acc::default(); NM]; budgets.len()];
    for row in &rows {
        for (b, per) in row.iter().enumerate() {
            for (m, &(e, t)) in per.iter().enumerate() {
                acc[b][m].add(e, t);
            }
        }
    }
    acc
}

fn main() -> Res<()> {
    let args: Vec<String> = std::env::args().collect();
    let face: usize = arg(&args, "--face", "64").parse()?;
    let n_configs: usize = arg(&args, "--configs", "60").parse()?;
    let budgets: Vec<usize> = arg(&args, "--budgets", "8,13,19")
        .split(',')
        .map(str::parse)
        .collect::<Result<_, _>>()?;
    let maps = arg(
        &args,
        "--maps",
        "venice_sunset_1k.hdr,royal_esplanade_1k.hdr,quarry_01_1k.hdr,studio_interior.exr",
    );
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
        .cloned();
    let seed = 17;
    let configs = configurations(n_configs, 85.0, seed);
    let materials: Vec<(&str, Box<dyn Bsdf>, f64)> = MATERIALS
        .iter()
        .map(|&(name, spec, r)| Ok((name, resolve(spec)?, r)))
        .collect::<Res<_>>()?;
    let t_all = Instant::now();
    let mut md = format!(
        "- {n_configs} configurations per map (seed {seed}), θo uniform in [0°, 85°); cube faces \
         {face}², Gaussian 6×6 pyramid; truth = Σ over all {} level-0 texels of L · ∫texel f cos θi \
         dω (`truth::truth`, supersampled where the lobe is narrow)\n- every method: the same \
         budget of points through the model's own `Bsdf::sample`, weight f cos θi / p; fp = \
         footprint level of Ω = 1/(n p), CK = Colbert–Křivánek level\n- cells: relative RMS % \
         (RMS error / RMS truth over all configurations and channels)\n",
        6 * face * face
    );
    // Per material, budget, method: pooled over maps.
    let mut pooled = vec![vec![[Acc::default(); NM]; budgets.len()]; materials.len()];
    let (mut wins, mut cells) = (0usize, 0usize);
    for map in maps.split(',') {
        let path = shared_data_dir().join("envmaps").join(map);
        let t0 = Instant::now();
        let loaded = read_map(&path)?;
        let base = CubeMap::from_equirect(&loaded.map, face)?;
        let pyramid = CubePyramid::build(base, MipFilter::Gauss6)?;
        let irradiance = irradiance_map(&pyramid, 8)?;
        let env = FilteredEnvironment {
            pyramid: &pyramid,
            irradiance: &irradiance,
        };
        let _ = writeln!(
            md,
            "\n#### {map}\n\n| material | n | {} |\n|---|---:|{}",
            METHODS.join(" | "),
            "---:|".repeat(NM)
        );
        for (mi, (name, bsdf, r)) in materials.iter().enumerate() {
            let acc = study(&**bsdf, *r, &env, &configs, &budgets);
            for (b, per) in acc.iter().enumerate() {
                let rel: Vec<f64> = per.iter().map(Acc::rel).collect();
                cells += 1;
                if rel[0] < rel[1] && rel[0] < rel[2] {
                    wins += 1;
                }
                let row: Vec<String> = rel.iter().map(|x| format!("{:.2}", 100.0 * x)).collect();
                let _ = writeln!(md, "| {name} | {} | {} |", budgets[b], row.join(" | "));
                for m in 0..NM {
                    pooled[mi][b][m].merge(&per[m]);
                }
            }
        }
        eprintln!("{map}: {:.1} s", t0.elapsed().as_secs_f64());
    }
    let _ = writeln!(
        md,
        "\n#### All maps pooled\n\n| material | n | {} |\n|---|---:|{}",
        METHODS.join(" | "),
        "---:|".repeat(NM)
    );
    for (mi, (name, _, _)) in materials.iter().enumerate() {
        for (b, per) in pooled[mi].iter().enumerate() {
            let row: Vec<String> = per
                .iter()
                .map(|a| format!("{:.2}", 100.0 * a.rel()))
                .collect();
            let _ = writeln!(md, "| {name} | {} | {} |", budgets[b], row.join(" | "));
        }
    }
    let _ = writeln!(
        md,
        "\nregular below both CK and random/fp in {wins} of {cells} map × material × budget \
         cells; {:.0} s in all",
        t_all.elapsed().as_secs_f64()
    );
    println!("{md}");
    if let Some(path) = out {
        std::fs::write(&path, &md)?;
        eprintln!("wrote {path}");
    }
    Ok(())
}
