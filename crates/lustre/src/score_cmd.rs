//! `lustre score SPEC DATA`: the error metrics and albedos of any material (a published fit, a
//! material JSON, a model with parameters) against any measured input, without fitting.

use anyhow::Context;
use lustre_brdf::catalog;
use lustre_fit::{data, metrics};

/// Arguments of `lustre score`.
#[derive(Debug, clap::Args)]
pub struct ScoreArgs {
    /// The material to score (see `lustre list`), e.g. `sgd:nickel` or `out/nickel.json`.
    #[arg(value_name = "SPEC")]
    pub spec: String,
    /// The measured input it is scored against (as `lustre fit` takes it), e.g. `nbrdf:nickel`
    /// or a MERL `.binary`.
    #[arg(value_name = "DATA")]
    pub input: String,
    /// Refuse MERL tables with unmeasured (negative) bins instead of masking them.
    #[arg(long)]
    pub strict: bool,
}

/// Runs `lustre score`.
pub fn run(args: &ScoreArgs) -> anyhow::Result<()> {
    let model = catalog::resolve_with(
        &args.spec,
        &catalog::ResolveOptions {
            strict: args.strict,
        },
    )
    .with_context(|| format!("cannot resolve {:?}", args.spec))?;
    let d = data::load_with(
        &args.input,
        &data::LoadOptions {
            strict: args.strict,
        },
    )
    .with_context(|| format!("cannot load {:?}", args.input))?;
    let r = metrics::evaluate_masked(
        d.bsdf.as_ref(),
        model.as_ref(),
        d.transmission,
        d.coverage.as_ref(),
    );
    let amax_model = metrics::max_albedo(model.as_ref(), d.transmission);
    let amax_data = metrics::max_albedo(d.bsdf.as_ref(), d.transmission);
    let rgb = |v: [f64; 3]| format!("{:.4e} / {:.4e} / {:.4e}", v[0], v[1], v[2]);
    let mean = |v: [f64; 3]| v.iter().sum::<f64>() / 3.0;
    println!("{} against {}", model.name(), d.source);
    if !d.mask_note().is_empty() {
        println!("  {}", d.mask_note());
    }
    println!(
        "  Ngan L2 (004 §V.5.3):      {:.4e}  (r/g/b {})",
        mean(r.ngan_l2),
        rgb(r.ngan_l2)
    );
    println!(
        "  L1 of Eq. 3.7 (000):       {:.4e}  (r/g/b {})",
        mean(r.l1),
        rgb(r.l1)
    );
    println!("  albedo at θo = 0, data:    {}", rgb(r.albedo_data));
    println!("  albedo at θo = 0, model:   {}", rgb(r.albedo_model));
    println!("  max albedo θo ≤ 80°, data: {}", rgb(amax_data));
    println!("  max albedo θo ≤ 80°, model: {}", rgb(amax_model));
    Ok(())
}
