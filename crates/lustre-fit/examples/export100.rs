//! What an export loses, on the 100 MERL materials (their neural BRDFs, `nbrdf:NAME`, as the
//! data): Ngan's L2 of the glTF metallic-roughness fit (`lustre export material --to gltf`)
//! without and with the layers it chose (`KHR_materials_specular` S, `_clearcoat` C, `_sheen`
//! Sh), of
//! the Mitsuba 3 fit (`--to mitsuba`: rough conductor or rough plastic, the better), of lustre's
//! own GGX Cook–Torrance fit and of the published SGD fit (`sgd:NAME`), one row per material,
//! then the medians.
//!
//! `cargo run --release -p lustre-fit --example export100 -- [--out FILE.md] [--limit N]`

use lustre_brdf::catalog::resolve;
use lustre_fit::ct::{fit_masked, CtDistribution, CtOptions};
use lustre_fit::data::load;
use lustre_fit::metrics::{max_albedo, ngan_l2};
use std::fmt::Write;
use std::time::Instant;

fn mean(r: &[f64; 3]) -> f64 {
    r.iter().sum::<f64>() / 3.0
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let opt = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let limit: usize = opt("--limit").map_or(Ok(100), |v| v.parse())?;
    let names = lustre_brdf::fits::sgd::list_materials()?;
    let t0 = Instant::now();
    let mut table = String::from(
        "| material | glTF (m, r) | glTF core | glTF layers | glTF + layers | Mitsuba (plugin) | Mitsuba | lustre GGX | published SGD |\n\
         |---|---|---:|---|---:|---|---:|---:|---:|\n",
    );
    let (mut g, mut m, mut c, mut s, mut gc) = (vec![], vec![], vec![], vec![], vec![]);
    let mut with_layers = std::collections::BTreeMap::new();
    let mut plugins = std::collections::BTreeMap::new();
    for name in names.iter().take(limit) {
        let data = load(&format!("nbrdf:{name}"))?;
        let amax = max_albedo(data.bsdf.as_ref(), false);
        let gltf = lustre_fit::gltf::fit_gltf(&data)?;
        let mits = lustre_fit::mitsuba::fit_mitsuba(&data)?;
        let ggx = fit_masked(
            data.bsdf.as_ref(),
            CtDistribution::Ggx,
            &CtOptions::default(),
            None,
        )?
        .to_bsdf(name)?;
        let ggx = mean(&ngan_l2(data.bsdf.as_ref(), &ggx, &amax));
        let sgd = mean(&ngan_l2(
            data.bsdf.as_ref(),
            resolve(&format!("sgd:{name}"))?.as_ref(),
            &amax,
        ));
        let (ge, me) = (gltf.errors.ngan_mean(), mits.errors.ngan_mean());
        *plugins.entry(mits.bsdf.plugin()).or_insert(0) += 1;
        let l = &gltf.layers;
        let mut used = vec![];
        if l.has_specular() {
            used.push("S");
        }
        if l.has_clearcoat() {
            used.push("C");
        }
        if l.has_sheen() {
            used.push("Sh");
        }
        for u in &used {
            *with_layers.entry(*u).or_insert(0) += 1;
        }
        let used = if used.is_empty() {
            "—".to_string()
        } else {
            used.join("+")
        };
        writeln!(
            table,
            "| {name} | {:.2}, {:.3} | {:.4} | {used} | {ge:.4} | {} | {me:.4} | {ggx:.4} | {sgd:.4} |",
            gltf.metallic,
            gltf.roughness,
            gltf.core_ngan_l2,
            mits.bsdf.plugin()
        )?;
        eprintln!(
            "{name}: glTF {:.4} → {ge:.4} ({used}), Mitsuba {me:.4}, GGX {ggx:.4}, SGD {sgd:.4}",
            gltf.core_ngan_l2
        );
        gc.push(gltf.core_ngan_l2);
        g.push(ge);
        m.push(me);
        c.push(ggx);
        s.push(sgd);
    }
    let n = g.len();
    let ratio = |a: &[f64], b: &[f64]| median(a.iter().zip(b).map(|(x, y)| x / y).collect());
    writeln!(
        table,
        "\n{n} materials in {:.0} s. Medians of Ngan's L2: glTF core {:.4}, glTF + layers {:.4}, \
         Mitsuba {:.4}, lustre GGX {:.4}, published SGD {:.4}; median ratio to lustre's GGX fit: \
         glTF core {:.2}, glTF + layers {:.2}, Mitsuba {:.2}. Layers chosen: {with_layers:?}. \
         Mitsuba plugins chosen: {plugins:?}.",
        t0.elapsed().as_secs_f64(),
        median(gc.clone()),
        median(g.clone()),
        median(m.clone()),
        median(c.clone()),
        median(s.clone()),
        ratio(&gc, &c),
        ratio(&g, &c),
        ratio(&m, &c),
    )?;
    match opt("--out") {
        Some(p) => std::fs::write(&p, &table)?,
        None => print!("{table}"),
    }
    Ok(())
}
