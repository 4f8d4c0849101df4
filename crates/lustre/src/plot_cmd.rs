//! `lustre plot`: lobe plots in the plane of incidence and transfer-probability arrays
//! (000 Fig. 2.6, 3.11, 3.12; 004 Fig. V.11) for materials named by catalog specs, and with
//! `--pattern` the regular half-vector sample patterns of one lobe (002 Fig. 4–5, 000 Fig. 4.17).

use anyhow::{bail, Context, Result};
use lustre_brdf::{catalog, Bsdf};
use lustre_plot::{ArrayColor, ArrayOptions, Channels, PolarOptions, Quantity};
use lustre_shade::pattern::{self, PatternKind, Spacing};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

/// The material plotted when no SPEC is given.
pub const DEFAULT_SPEC: &str = "kurt-demo";

/// Which figures to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PlotKind {
    /// Lobes in the plane of incidence, one panel per θi.
    Polar,
    /// Transfer-probability disc arrays (rows θi, columns φi).
    Array,
    /// Both.
    All,
}

/// The radial quantity of the polar plots.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PlotQuantity {
    /// p = f·|cos θo|, the transfer probability.
    Transfer,
    /// f, the BSDF value in 1/sr.
    Bsdf,
}

/// Which regular sample pattern `--pattern` draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PlotPattern {
    /// 002 §5 concentric circles: one panel per spacing (s1, s2), each with the circle count
    /// closest to `--budget` (or `--circles`), plus the overall choice for the budget.
    Concentric,
    /// 000 §4.4.3: centre + ring, or the linear pattern for strong anisotropy.
    Thesis,
    /// 000 §4.5.3: centre + `--rings` rings.
    MultiRing,
    /// All of the above.
    All,
}

/// Arguments of `lustre plot`.
#[derive(Debug, clap::Args)]
pub struct PlotArgs {
    /// Material specs (catalog names, model specs or measured files); several are overlaid in
    /// the polar plot and get one array each. Default: the built-in demo material.
    #[arg(value_name = "SPEC")]
    pub specs: Vec<String>,
    /// A second material to compare with (e.g. a fit against its measurement): overlaid in the
    /// polar plot, drawn side by side on a shared scale in the arrays.
    #[arg(long, value_name = "SPEC")]
    pub compare: Option<String>,
    /// Which figures to draw.
    #[arg(long, value_enum, default_value_t = PlotKind::All)]
    pub kind: PlotKind,
    /// Incidence angles θi (degrees) of the polar panels, at most 16.
    #[arg(
        long = "theta-i",
        value_delimiter = ',',
        default_value = "10,30,50,70",
        allow_hyphen_values = true
    )]
    pub theta_i: Vec<f64>,
    /// Azimuth φi (degrees) of the plane of incidence of the polar plots.
    #[arg(long = "phi-i", default_value_t = 0.0, allow_hyphen_values = true)]
    pub phi_i: f64,
    /// Apply the cube root to the polar lobes (the arrays always use it, as Fig. 2.6 does).
    #[arg(long)]
    pub cube_root: bool,
    /// Radial quantity of the polar plots.
    #[arg(long, value_enum, default_value_t = PlotQuantity::Transfer)]
    pub quantity: PlotQuantity,
    /// Polar plots: one curve per RGB channel instead of luminance.
    #[arg(long)]
    pub rgb: bool,
    /// Arrays: colour-map the luminance instead of showing RGB.
    #[arg(long)]
    pub colormap: bool,
    /// Array rows θi (degrees).
    #[arg(
        long = "array-theta",
        value_delimiter = ',',
        default_value = "0,5,20,35,50,65"
    )]
    pub array_theta: Vec<f64>,
    /// Array columns φi (degrees).
    #[arg(
        long = "array-phi",
        value_delimiter = ',',
        default_value = "0,15,30,45,60,75,90",
        allow_hyphen_values = true
    )]
    pub array_phi: Vec<f64>,
    /// Array disc diameter in pixels.
    #[arg(long, default_value_t = 96)]
    pub disc_px: u32,
    /// Output folder (created if missing).
    #[arg(long, default_value = "lustre-plots")]
    pub out: PathBuf,
    /// Draw a regular half-vector sample pattern of one lobe instead of material plots.
    #[arg(long, value_enum)]
    pub pattern: Option<PlotPattern>,
    /// Pattern lobe roughness along the tangent (1e-6 to 10).
    #[arg(long, default_value_t = 0.2)]
    pub mx: f64,
    /// Pattern lobe roughness along the bitangent (1e-6 to 10).
    #[arg(long, default_value_t = 0.075)]
    pub my: f64,
    /// Pattern sample budget (at most 4096, as `lustre render --samples`).
    #[arg(long, default_value_t = 17,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(0..=4096))]
    pub budget: usize,
    /// Pattern threshold ξ0 of 002 §5 (the concentric patterns).
    #[arg(long, default_value_t = 0.1)]
    pub xi0: f64,
    /// Concentric patterns: this many circles nc (1 to 64) instead of the largest count within
    /// the budget.
    #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=64))]
    pub circles: Option<usize>,
    /// Multi-ring pattern: the number of rings, 1 to 64 (the budget less the centre is spread
    /// over them).
    #[arg(long, default_value_t = 3,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=64))]
    pub rings: usize,
    /// Refuse MERL tables with unmeasured (negative) bins instead of masking them.
    #[arg(long)]
    pub strict: bool,
}

/// Runs `lustre plot`: resolves the specs, draws the requested figures into `--out` and prints
/// the path of every file written.
pub fn run(args: &PlotArgs) -> Result<()> {
    if let Some(choice) = args.pattern {
        return run_pattern(args, choice);
    }
    let specs: Vec<String> = if args.specs.is_empty() {
        vec![DEFAULT_SPEC.to_string()]
    } else {
        args.specs.clone()
    };
    let materials: Vec<(String, Box<dyn Bsdf>)> = specs
        .iter()
        .map(|s| Ok((s.clone(), resolve(s, args.strict)?)))
        .collect::<Result<_>>()?;
    let compare = args
        .compare
        .as_deref()
        .map(|s| Ok::<_, anyhow::Error>((s.to_string(), resolve(s, args.strict)?)))
        .transpose()?;
    let mut written = Vec::new();
    let result = draw(args, &materials, compare.as_ref(), &mut written);
    if result.is_err() {
        // No half-finished set of figures: remove what this run wrote before the failure (the
        // folder goes too when this run made it: `crate::output::in_folder`).
        for p in &written {
            let _ = std::fs::remove_file(p);
        }
        return result;
    }
    for p in &written {
        println!("{}", p.display());
    }
    Ok(())
}

/// Draws the figures of `run` into `args.out`, pushing every file written onto `written`.
fn draw(
    args: &PlotArgs,
    materials: &[(String, Box<dyn Bsdf>)],
    compare: Option<&(String, Box<dyn Bsdf>)>,
    written: &mut Vec<PathBuf>,
) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create the output folder {}", args.out.display()))?;
    if !lustre_plot::font::font_available() {
        eprintln!(
            "note: no system font found (set {} to a .ttf file); the PNG files carry no text, the SVG files do",
            lustre_plot::font::FONT_ENV
        );
    }
    let mut names = UniqueNames::default();

    if matches!(args.kind, PlotKind::Polar | PlotKind::All) {
        let mut all: Vec<(&dyn Bsdf, &str)> = materials
            .iter()
            .map(|(s, b)| (b.as_ref(), s.as_str()))
            .collect();
        if let Some((s, b)) = compare {
            all.push((b.as_ref(), s.as_str()));
        }
        let opts = PolarOptions {
            quantity: match args.quantity {
                PlotQuantity::Transfer => Quantity::TransferProbability,
                PlotQuantity::Bsdf => Quantity::Bsdf,
            },
            cube_root: args.cube_root,
            channels: if args.rgb {
                Channels::Rgb
            } else {
                Channels::Luminance
            },
            phi_i_deg: args.phi_i,
            ..PolarOptions::default()
        };
        let stem = all
            .iter()
            .map(|(_, s)| slug(s))
            .collect::<Vec<_>>()
            .join("-vs-");
        let base = args.out.join(names.claim(&format!("polar-{stem}")));
        let files = lustre_plot::polar_plot(&all, &args.theta_i, &opts, &base)
            .with_context(|| format!("drawing the polar plot into {}", args.out.display()))?;
        written.extend(files.paths().into_iter().map(Path::to_path_buf));
    }

    if matches!(args.kind, PlotKind::Array | PlotKind::All) {
        let opts = ArrayOptions {
            thetas_deg: args.array_theta.clone(),
            phis_deg: args.array_phi.clone(),
            disc_px: args.disc_px,
            color: if args.colormap {
                ArrayColor::Colormap
            } else {
                ArrayColor::Rgb
            },
            ..ArrayOptions::default()
        };
        for (spec, bsdf) in materials {
            let files = match compare {
                Some((cspec, cbsdf)) => {
                    let base = args.out.join(names.claim(&format!(
                        "array-{}-vs-{}",
                        slug(spec),
                        slug(cspec)
                    )));
                    lustre_plot::transfer_array_compare(
                        (bsdf.as_ref(), spec),
                        (cbsdf.as_ref(), cspec),
                        &opts,
                        &base,
                    )
                }
                None => {
                    let base = args.out.join(names.claim(&format!("array-{}", slug(spec))));
                    lustre_plot::transfer_array(bsdf.as_ref(), spec, &opts, &base)
                }
            }
            .with_context(|| {
                format!(
                    "drawing the transfer array of '{spec}' into {}",
                    args.out.display()
                )
            })?;
            written.extend(files.paths().into_iter().map(Path::to_path_buf));
        }
    }
    Ok(())
}

/// A plot panel of a pattern.
fn panel(title: String, p: &pattern::Pattern) -> lustre_plot::PatternPanel {
    lustre_plot::PatternPanel {
        title: format!("{title}: {} samples", p.h.len()),
        h: p.h.clone(),
        mx: p.mx,
        my: p.my,
        xi0: p.xi0,
    }
}

/// The panels of a concentric-pattern plot: s1 and s2 with `--circles` circles, or each with the
/// largest circle count within the budget followed by the overall pick for the budget.
fn concentric_panels(args: &PlotArgs) -> Result<Vec<lustre_plot::PatternPanel>> {
    let (mx, my, xi0) = (args.mx, args.my, args.xi0);
    let mut panels = Vec::new();
    for (spacing, name) in [(Spacing::S1, "s1"), (Spacing::S2, "s2")] {
        let p = match args.circles {
            Some(nc) => pattern::concentric(mx, my, nc, spacing, xi0)?,
            None => pattern::concentric_for_budget_with(mx, my, args.budget, xi0, spacing)?,
        };
        let nc = match p.kind {
            PatternKind::Concentric { circles, .. } => circles,
            _ => 0,
        };
        panels.push(panel(format!("{name}, nc = {nc}"), &p));
    }
    if args.circles.is_none() {
        let p = pattern::concentric_for_budget(mx, my, args.budget, xi0)?;
        panels.push(panel(format!("largest within budget {}", args.budget), &p));
    }
    Ok(panels)
}

/// `lustre plot --pattern`: draws the chosen patterns for the lobe (`--mx`, `--my`) into `--out`.
fn run_pattern(args: &PlotArgs, choice: PlotPattern) -> Result<()> {
    let (mx, my) = (args.mx, args.my);
    if args.budget == 0 {
        bail!("--budget must be at least 1");
    }
    for (name, m) in [("--mx", mx), ("--my", my)] {
        lustre_brdf::error::check_range(name, m, pattern::MIN_ROUGHNESS, pattern::MAX_ROUGHNESS)?;
    }
    if !(args.xi0 > 0.0 && args.xi0 < 1.0) {
        bail!(
            "--xi0 {}: must lie in (0, 1)",
            lustre_brdf::error::plain_number(args.xi0)
        );
    }
    let mut panels = Vec::new();
    if matches!(choice, PlotPattern::Concentric | PlotPattern::All) {
        panels.extend(concentric_panels(args).context("--pattern concentric")?);
    }
    if matches!(choice, PlotPattern::Thesis | PlotPattern::All) {
        let p = pattern::thesis(mx, my, args.budget).context("--pattern thesis")?;
        let name = match p.kind {
            PatternKind::ThesisLinear => "thesis, linear",
            _ => "thesis, ring",
        };
        panels.push(panel(name.into(), &p));
    }
    if matches!(choice, PlotPattern::MultiRing | PlotPattern::All) {
        let per_ring = (args.budget.saturating_sub(1) / args.rings.max(1)).max(1);
        let p =
            pattern::multi_ring(mx, my, args.rings, per_ring).context("--pattern multi-ring")?;
        panels.push(panel(
            format!("multi-ring, {} × {per_ring}", args.rings),
            &p,
        ));
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create the output folder {}", args.out.display()))?;
    let opts = lustre_plot::PatternOptions {
        title: format!(
            "Half-vector patterns: mx = {mx}, my = {my}, ξ0 = {}, budget {}",
            args.xi0, args.budget
        ),
        ..lustre_plot::PatternOptions::default()
    };
    let stem = format!(
        "pattern-{}-mx{mx}-my{my}-n{}",
        format!("{choice:?}").to_lowercase(),
        args.budget
    );
    let files = lustre_plot::pattern_plot(&panels, &opts, &args.out.join(slug(&stem)))
        .with_context(|| format!("drawing the pattern plot into {}", args.out.display()))?;
    for p in files.paths() {
        println!("{}", p.display());
    }
    Ok(())
}

/// Resolves a spec; the catalog's error names the spec and what a spec may be (`lustre list`
/// lists every name).
fn resolve(spec: &str, strict: bool) -> Result<Box<dyn Bsdf>> {
    if spec.trim().is_empty() {
        bail!("empty material spec");
    }
    catalog::resolve_with(spec, &catalog::ResolveOptions { strict })
        .with_context(|| format!("cannot resolve material spec '{spec}' (lustre list names all)"))
}

/// A file-name-safe short form of a spec: the last path component, other characters as '-'.
fn slug(spec: &str) -> String {
    let last = spec
        .rsplit(['/', '\\'])
        .find(|s| !s.is_empty())
        .unwrap_or(spec);
    let s: String = last
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '-'
            }
        })
        .take(48)
        .collect();
    let s = s.trim_matches(|c| c == '-' || c == '.').to_string();
    if s.is_empty() {
        "material".into()
    } else {
        s
    }
}

/// Hands out file stems, numbering repeats so no figure overwrites another of the same run.
#[derive(Default)]
struct UniqueNames(HashSet<String>);

impl UniqueNames {
    fn claim(&mut self, stem: &str) -> String {
        let mut name = stem.to_string();
        let mut k = 2;
        while !self.0.insert(name.clone()) {
            name = format!("{stem}-{k}");
            k += 1;
        }
        name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_are_file_name_safe() {
        assert_eq!(slug("kurt-demo"), "kurt-demo");
        assert_eq!(
            slug("/data/merl/gold-metallic-paint.binary"),
            "gold-metallic-paint.binary"
        );
        assert_eq!(slug("kurt(kd=0.1, ks=0.5)"), "kurt-kd-0.1--ks-0.5");
        assert_eq!(slug("../"), "material");
        let mut u = UniqueNames::default();
        assert_eq!(u.claim("a"), "a");
        assert_eq!(u.claim("a"), "a-2");
    }

    #[test]
    fn unknown_spec_and_unwritable_folder_are_errors() {
        let args = |specs: Vec<String>, out: PathBuf| PlotArgs {
            specs,
            compare: None,
            kind: PlotKind::Polar,
            theta_i: vec![30.0],
            phi_i: 0.0,
            cube_root: false,
            quantity: PlotQuantity::Transfer,
            rgb: false,
            colormap: false,
            array_theta: vec![0.0],
            array_phi: vec![0.0],
            disc_px: 32,
            out,
            pattern: None,
            mx: 0.2,
            my: 0.075,
            budget: 17,
            xi0: 0.1,
            circles: None,
            rings: 3,
            strict: false,
        };
        let dir = std::env::temp_dir().join(format!("lustre-plot-cmd-{}", std::process::id()));
        let e = run(&args(vec!["no-such-material-xyz".into()], dir.clone())).unwrap_err();
        assert!(format!("{e:#}").contains("no-such-material-xyz"), "{e:#}");
        let file =
            std::env::temp_dir().join(format!("lustre-plot-cmd-file-{}", std::process::id()));
        std::fs::write(&file, b"x").unwrap();
        let e = run(&args(vec![DEFAULT_SPEC.into()], file.join("sub"))).unwrap_err();
        assert!(format!("{e:#}").contains("output folder"), "{e:#}");
        std::fs::remove_file(&file).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn pattern_plots_are_written_and_bad_lobes_rejected() {
        let dir = std::env::temp_dir().join(format!("lustre-plot-pattern-{}", std::process::id()));
        let mut args = PlotArgs {
            specs: vec![],
            compare: None,
            kind: PlotKind::All,
            theta_i: vec![30.0],
            phi_i: 0.0,
            cube_root: false,
            quantity: PlotQuantity::Transfer,
            rgb: false,
            colormap: false,
            array_theta: vec![0.0],
            array_phi: vec![0.0],
            disc_px: 32,
            out: dir.clone(),
            pattern: Some(PlotPattern::All),
            mx: 0.2,
            my: 0.075,
            budget: 17,
            xi0: 0.1,
            circles: None,
            rings: 3,
            strict: false,
        };
        run(&args).unwrap();
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().any(|n| n.ends_with(".png")), "{names:?}");
        assert!(names.iter().any(|n| n.ends_with(".svg")), "{names:?}");
        // Fig. 4 panels with a fixed circle count.
        let panels = {
            args.circles = Some(3);
            args.mx = 0.2;
            args.my = 0.2;
            concentric_panels(&args).unwrap()
        };
        assert_eq!(panels[0].h.len(), 19);
        assert_eq!(panels[1].h.len(), 30);
        args.mx = -1.0;
        let e = run(&args).unwrap_err();
        assert!(format!("{e:#}").contains("mx"), "{e:#}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
