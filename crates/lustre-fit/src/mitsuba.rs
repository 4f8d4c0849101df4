//! Mitsuba 3 BSDFs fitted to measured data, for export: `roughconductor` (GGX, the `none`
//! material, an RGB `specular_reflectance`) and `roughplastic` (GGX, an RGB
//! `diffuse_reflectance`, interior IOR 1.49, linear), each fitted by Ngan's L2; the better one
//! is exported.
//!
//! Both are linear in their colour ([`crate::linear`]): the rough conductor with the `none`
//! material (F = 1) is R·D G/(4 cos θi cos θo), the rough plastic (`nonlinear` off) is a
//! specular term independent of the diffuse reflectance plus ρ/(1 − F_dr) times a diffuse term.
//! α is searched on a geometric grid (25 values from 1e-3 to 1) and refined by golden section
//! in log α. The models are lustre's Mitsuba-compatible implementations, built through the
//! catalog from the same parameters the XML carries.

use crate::data::MeasuredData;
use crate::linear::{golden, Rows, Sums};
use crate::metrics::{evaluate_masked, ErrorReport};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::catalog::resolve;
use lustre_brdf::Result;

/// The smallest α searched.
pub const MIN_ALPHA: f64 = 1e-3;

/// The rough plastic's interior index of refraction (Mitsuba's default for polypropylene).
pub const PLASTIC_IOR: f64 = 1.49;

/// The Mitsuba 3 BSDFs the exporter fits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MitsubaBsdf {
    /// `roughconductor`, `distribution` ggx, `material` none.
    RoughConductor {
        /// `specular_reflectance` (RGB).
        specular: [f64; 3],
        /// `alpha`.
        alpha: f64,
    },
    /// `roughplastic`, `distribution` ggx, `int_ior` 1.49, `nonlinear` false.
    RoughPlastic {
        /// `diffuse_reflectance` (RGB).
        diffuse: [f64; 3],
        /// `alpha`.
        alpha: f64,
    },
}

impl MitsubaBsdf {
    /// The Mitsuba plugin name.
    pub fn plugin(&self) -> &'static str {
        match self {
            MitsubaBsdf::RoughConductor { .. } => "roughconductor",
            MitsubaBsdf::RoughPlastic { .. } => "roughplastic",
        }
    }

    /// lustre's catalog spec of the same BSDF (what `lustre info` and the fit evaluate).
    pub fn spec(&self) -> String {
        let rgb = |key: &str, c: &[f64; 3]| {
            format!("{key}_r={:e},{key}_g={:e},{key}_b={:e}", c[0], c[1], c[2])
        };
        match self {
            MitsubaBsdf::RoughConductor { specular, alpha } => format!(
                "roughconductor(material=none,distribution=ggx,alpha={alpha:e},{})",
                rgb("specular", specular)
            ),
            MitsubaBsdf::RoughPlastic { diffuse, alpha } => format!(
                "roughplastic(distribution=ggx,alpha={alpha:e},int_ior={PLASTIC_IOR},{})",
                rgb("diffuse", diffuse)
            ),
        }
    }

    /// The BSDF through lustre's catalog.
    pub fn bsdf(&self) -> Result<Box<dyn Bsdf>> {
        resolve(&self.spec())
    }

    fn with(&self, colour: [f64; 3], alpha: f64) -> MitsubaBsdf {
        match self {
            MitsubaBsdf::RoughConductor { .. } => MitsubaBsdf::RoughConductor {
                specular: colour,
                alpha,
            },
            MitsubaBsdf::RoughPlastic { .. } => MitsubaBsdf::RoughPlastic {
                diffuse: colour,
                alpha,
            },
        }
    }
}

/// A fitted Mitsuba BSDF with its errors against the data.
#[derive(Clone, Debug, PartialEq)]
pub struct MitsubaFit {
    /// The better of the two.
    pub bsdf: MitsubaBsdf,
    /// Its errors against the data.
    pub errors: ErrorReport,
    /// Both candidates with their Ngan L2 (mean of the channels), the chosen one first.
    pub candidates: Vec<(MitsubaBsdf, f64)>,
}

/// The XML file: a comment (`note`, e.g. the source and the fit's error), then
/// `<scene version="3.0.0">` with one BSDF of id `id` and its `properties` (lines).
fn scene_xml(id: &str, plugin: &str, properties: &[String], note: &str) -> String {
    // A comment may not hold "--".
    let note = note.replace("--", "- -");
    let body: String = properties
        .iter()
        .map(|p| format!("        {p}\n"))
        .collect();
    format!(
        "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<!-- {note} -->\n<scene version=\"3.0.0\">\n    \
         <bsdf type=\"{plugin}\" id=\"{}\">\n{body}    </bsdf>\n</scene>\n",
        attr(id)
    )
}

impl MitsubaBsdf {
    /// A Mitsuba 3 scene file holding this BSDF with id `id` (which a Mitsuba scene can
    /// `<include>`, or copy and `<ref>`), `note` in a comment. Values in their shortest
    /// round-trip form: the file holds exactly the fitted values.
    pub fn xml(&self, id: &str, note: &str) -> String {
        let rgb = |name: &str, c: &[f64; 3]| {
            format!(
                "<rgb name=\"{name}\" value=\"{}, {}, {}\"/>",
                c[0], c[1], c[2]
            )
        };
        let ggx = "<string name=\"distribution\" value=\"ggx\"/>".to_string();
        let alpha = |a: f64| format!("<float name=\"alpha\" value=\"{a}\"/>");
        let properties = match self {
            MitsubaBsdf::RoughConductor { specular, alpha: a } => vec![
                ggx,
                alpha(*a),
                "<string name=\"material\" value=\"none\"/>".into(),
                rgb("specular_reflectance", specular),
            ],
            MitsubaBsdf::RoughPlastic { diffuse, alpha: a } => vec![
                ggx,
                alpha(*a),
                format!("<float name=\"int_ior\" value=\"{PLASTIC_IOR}\"/>"),
                "<boolean name=\"nonlinear\" value=\"false\"/>".into(),
                rgb("diffuse_reflectance", diffuse),
            ],
        };
        scene_xml(id, self.plugin(), &properties, note)
    }
}

/// A Mitsuba 3 scene file holding the `measured` BSDF of the RGL file `filename` (relative to
/// the XML) with id `id`.
pub fn measured_xml(id: &str, filename: &str, note: &str) -> String {
    scene_xml(
        id,
        "measured",
        &[format!(
            "<string name=\"filename\" value=\"{}\"/>",
            attr(filename)
        )],
        note,
    )
}

/// Escapes text for an XML attribute value.
fn attr(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn sums(rows: &Rows, kind: &MitsubaBsdf, alpha: f64) -> Result<Sums> {
    let black = kind.with([0.0; 3], alpha).bsdf()?;
    let white = kind.with([1.0; 3], alpha).bsdf()?;
    Ok(rows.sums(black.as_ref(), white.as_ref()))
}

/// Fits one kind: its colour and α.
fn fit_kind(rows: &Rows, kind: MitsubaBsdf) -> Result<(MitsubaBsdf, f64)> {
    let steps = 24;
    let lo = MIN_ALPHA.ln();
    let step = -lo / steps as f64;
    let objective =
        |la: f64| -> Result<f64> { Ok(sums(rows, &kind, la.exp())?.solve(&rows.amax).1) };
    let (mut best_la, mut best) = (0.0, f64::INFINITY);
    for k in 0..=steps {
        let la = lo + step * k as f64;
        let e = objective(la)?;
        if e < best {
            (best_la, best) = (la, e);
        }
    }
    let (la, e) = golden(
        (best_la - step).max(lo),
        (best_la + step).min(0.0),
        objective,
    )?;
    if e < best {
        (best_la, best) = (la, e);
    }
    let alpha = best_la.exp();
    let (colour, _) = sums(rows, &kind, alpha)?.solve(&rows.amax);
    Ok((kind.with(colour, alpha), best))
}

/// Fits `roughconductor` and `roughplastic` to `data` and keeps the better (module notes).
pub fn fit_mitsuba(data: &MeasuredData) -> Result<MitsubaFit> {
    let rows = Rows::new(data);
    let conductor = fit_kind(
        &rows,
        MitsubaBsdf::RoughConductor {
            specular: [1.0; 3],
            alpha: 0.1,
        },
    )?;
    let plastic = fit_kind(
        &rows,
        MitsubaBsdf::RoughPlastic {
            diffuse: [0.5; 3],
            alpha: 0.1,
        },
    )?;
    let mut candidates = vec![conductor, plastic];
    candidates.sort_by(|a, b| a.1.total_cmp(&b.1));
    let bsdf = candidates[0].0;
    let errors = evaluate_masked(
        data.bsdf.as_ref(),
        bsdf.bsdf()?.as_ref(),
        data.transmission,
        data.coverage.as_ref(),
    );
    Ok(MitsubaFit {
        bsdf,
        errors,
        candidates,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both models are linear in their colour, as the fit assumes.
    #[test]
    fn both_models_are_linear_in_their_colour() {
        let wi = glam::DVec3::new(0.3, 0.1, 0.8).normalize();
        let wo = glam::DVec3::new(-0.2, 0.4, 0.7).normalize();
        for kind in [
            MitsubaBsdf::RoughConductor {
                specular: [0.0; 3],
                alpha: 0.2,
            },
            MitsubaBsdf::RoughPlastic {
                diffuse: [0.0; 3],
                alpha: 0.3,
            },
        ] {
            let c = [0.2, 0.55, 0.9];
            let f0 = kind.with([0.0; 3], 0.2).bsdf().expect("model").eval(wi, wo);
            let f1 = kind.with([1.0; 3], 0.2).bsdf().expect("model").eval(wi, wo);
            let f = kind.with(c, 0.2).bsdf().expect("model").eval(wi, wo);
            for (k, ck) in c.iter().enumerate() {
                let lin = ck * (f1.0[k] - f0.0[k]) + f0.0[k];
                assert!(
                    (lin - f.0[k]).abs() <= 1e-12 * f.0[k].abs().max(1.0),
                    "{kind:?}"
                );
            }
        }
    }

    /// Data made by either model is fitted back by that model.
    #[test]
    fn recovers_each_model_and_chooses_it() {
        for truth in [
            MitsubaBsdf::RoughConductor {
                specular: [0.9, 0.6, 0.3],
                alpha: 0.15,
            },
            MitsubaBsdf::RoughPlastic {
                diffuse: [0.1, 0.5, 0.7],
                alpha: 0.25,
            },
        ] {
            let fit = fit_mitsuba(&MeasuredData::from_bsdf(
                "truth",
                truth.bsdf().expect("model"),
            ))
            .expect("fit");
            assert_eq!(fit.bsdf.plugin(), truth.plugin(), "{fit:?}");
            assert!(fit.errors.ngan_mean() < 2e-3, "{fit:?}");
            let (got, want) = (fit.bsdf, truth);
            match (got, want) {
                (
                    MitsubaBsdf::RoughConductor {
                        specular: a,
                        alpha: x,
                    },
                    MitsubaBsdf::RoughConductor {
                        specular: b,
                        alpha: y,
                    },
                )
                | (
                    MitsubaBsdf::RoughPlastic {
                        diffuse: a,
                        alpha: x,
                    },
                    MitsubaBsdf::RoughPlastic {
                        diffuse: b,
                        alpha: y,
                    },
                ) => {
                    assert!((x - y).abs() < 0.01 * y, "{got:?}");
                    for k in 0..3 {
                        assert!((a[k] - b[k]).abs() < 0.01, "{got:?}");
                    }
                }
                _ => unreachable!(),
            }
        }
    }

    #[test]
    fn the_xml_names_every_property_and_escapes_text() {
        let x = MitsubaBsdf::RoughPlastic {
            diffuse: [0.1, 0.2, 0.3],
            alpha: 0.25,
        }
        .xml("a\"b", "from x -- y");
        assert!(
            x.contains("<bsdf type=\"roughplastic\" id=\"a&quot;b\">"),
            "{x}"
        );
        assert!(x.contains("<rgb name=\"diffuse_reflectance\" value=\"0.1, 0.2, 0.3\"/>"));
        assert!(x.contains("<float name=\"int_ior\" value=\"1.49\"/>"));
        assert!(x.contains("<!-- from x - - y -->"), "{x}");
        let m = measured_xml("p", "paper & co.bsdf", "n");
        assert!(
            m.contains("<string name=\"filename\" value=\"paper &amp; co.bsdf\"/>"),
            "{m}"
        );
    }
}
