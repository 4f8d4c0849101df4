//! The published one-lobe Lafortune fits of Ngan et al. 2005 ("Experimental Analysis of BRDF
//! Models") for the MERL materials: `fits/merl_lafortune_fits_ngan2005.csv`, columns
//! `index, name, kd_r, kd_g, kd_b, ks_r, ks_g, ks_b, Cxy, Cz, n`.
//!
//! # How the published values are evaluated
//!
//! Every row's C vector has unit length (2Cxy² + Cz² = 1 to the printed digits; Cxy ≈ −0.577,
//! Cz ≈ 0.577 for most), ks ~ 0.1 and n reaches 16600. Lafortune's raw form ks·(C·(u∘v))^n is
//! then at most ks·0.577^n ≈ 0: the values are meant for a normalized lobe. We evaluate
//!
//! f = kd/π + ks · (n + 2)/(2π) · max(0, (Cxy(ux vx + uy vy) + Cz uz vz) / max(|Cxy|, |Cz|))^n,
//!
//! ([`crate::models::lafortune::LobeNorm::Peak`]). Evidence: the pbrt plugin `MerlLafortune.cpp`
//! by Joo-Haeng Lee (2007, "based on 'Exp. Anal. of BRDF Models' by A. Ngan et al (2005)") and
//! its port to the GIRL renderer (Sung-Soo Kim, ETRI 2008), both in public repositories (the same
//! table as this CSV is `RealtimeRender/Libs/include/lafortune1.h` in ca1773130n/Gorilla), keep in
//! `#if 0` blocks the raw per-channel pbrt lobe coefficients (xy, z, e) derived for three
//! materials. They equal C·(ks_c (n+2)/(2π))^(1/n)/|Cxy| to 4 significant digits:
//! gold-metallic-paint (xy_r = −1.00881: ks_r = 0.475, n = 12.8, Cxy = −0.596), gold-paint
//! (−0.958097: 0.209, 14.3, −0.595) and gold-metallic-paint3 (−1.00316: 0.233, 27.4, −0.583;
//! labelled "gold-metallic-paint2" in the source, but those are gold-metallic-paint3's values),
//! in all three channels, with the diffuse term kd/π (pbrt's Lafortune adds R/π). That is the
//! formula above with the divisor |Cxy|; we divide by max(|Cxy|, |Cz|), the maximum of the
//! bilinear form, which is |Cxy| for every row whose ks is non-zero (only `sugar`, ks = 0, has
//! Cz > |Cxy|). We could not read Ngan et al.'s own fitting code, so this convention is inferred
//! from that implementation, not quoted from the paper. The tests check it against Bagher's SGD
//! fits of the same materials: the ratio of green directional albedos (θo = 0.05 and 0.7 rad, 86
//! materials in both tables) has median 0.84 and all 172 pairs lie within a factor 3, while the raw
//! reading gives a median lobe albedo of 10⁻⁶·ks.
//!
//! Two rows, `red-specular-plastic` and `violet-acrylic`, have Cxy = +0.577: evaluated as published
//! their sharp lobe sits in the retro-reflection direction, not the mirror direction (probably a
//! sign lost in the published table). They are loaded as published.

use crate::error::{Error, Result};
use crate::fits::{fit_table_api, FitTable};
use crate::models::lafortune::{Lafortune, LafortuneLobe};
use crate::rgb::Rgb;

/// The file's name (in the shared data folder under `fits/`, and embedded).
pub const LAFORTUNE_FITS_FILE: &str = "merl_lafortune_fits_ngan2005.csv";

/// The table of Lafortune fits.
#[derive(Clone, Debug)]
pub struct LafortuneFits {
    table: FitTable,
}

/// The raw published parameters of one material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NganLafortuneParams {
    /// Diffuse albedo.
    pub kd: Rgb,
    /// Lobe weight.
    pub ks: Rgb,
    /// Cx = Cy.
    pub cxy: f64,
    /// Cz.
    pub cz: f64,
    /// Exponent.
    pub n: f64,
}

fit_table_api!(
    LafortuneFits,
    LAFORTUNE_FITS_FILE,
    crate::embedded::LAFORTUNE_FITS
);

impl LafortuneFits {
    /// The published parameters of `material`.
    pub fn params(&self, material: &str) -> Result<NganLafortuneParams> {
        let t = &self.table;
        Ok(NganLafortuneParams {
            kd: Rgb(t.rgb(material, "kd")?),
            ks: Rgb(t.rgb(material, "ks")?),
            cxy: t.value(material, "Cxy")?,
            cz: t.value(material, "Cz")?,
            n: t.value(material, "n")?,
        })
    }

    /// The fitted BRDF of `material`, evaluated as described in the module docs;
    /// [`Error::NotFound`] for an unknown name, a format error naming the file and the material
    /// for an invalid parameter.
    pub fn material(&self, material: &str) -> Result<Lafortune> {
        let p = self.params(material)?;
        let lobe = LafortuneLobe::ngan(p.cxy, p.cz, p.n, p.ks);
        Lafortune::new(p.kd, vec![lobe])
            .map(|m| m.with_label(material))
            .map_err(|e| Error::format(&self.table.path, format!("{material}: {e}")))
    }
}

/// The Ngan et al. 2005 Lafortune fit of material `name`, from the shared data folder.
pub fn load(name: &str) -> Result<Lafortune> {
    LafortuneFits::load_default()?.material(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Bsdf;
    use std::f64::consts::PI;
    use std::path::Path;

    const HEADER: &str = "index,name,kd_r,kd_g,kd_b,ks_r,ks_g,ks_b,Cxy,Cz,n\n";

    #[test]
    fn reproduces_the_pbrt_coefficients() {
        // gold-metallic-paint: the per-channel raw lobe (xy, z, e) hard-coded in MerlLafortune.cpp
        // must give the same BRDF as our normalized lobe.
        let row = format!("{HEADER}29,gold-metallic-paint,0.0601,0.0298,0.00487,0.475,0.27,0.0681,-0.596,0.537,12.8\n");
        let fits = LafortuneFits::parse(Path::new("<mem>"), row.as_bytes()).expect("valid");
        let m = fits.material("gold-metallic-paint").expect("valid");
        let xy = [-1.00881, -0.96526, -0.866779];
        let z = [0.908947, 0.869705, 0.780974];
        let wi = crate::frame::spherical(0.4, 0.3);
        let wo = crate::frame::spherical(0.6, 0.3 + PI - 0.2);
        let f = m.eval(wi, wo);
        let kd = [0.0601, 0.0298, 0.00487];
        for c in 0..3 {
            let d = xy[c] * (wi.x * wo.x + wi.y * wo.y) + z[c] * wi.z * wo.z;
            let pbrt = kd[c] / PI + d.powf(12.8);
            assert!(
                (f[c] - pbrt).abs() < 2e-3 * pbrt,
                "channel {c}: {} vs {pbrt}",
                f[c]
            );
        }
    }

    #[test]
    fn parses_and_rejects() {
        let good = format!("{HEADER}1,x,0.1,0.1,0.1,0.2,0.2,0.2,-0.577,0.577,100\n");
        let f = LafortuneFits::parse(Path::new("<mem>"), good.as_bytes()).expect("valid");
        assert!(matches!(f.material("nope"), Err(Error::NotFound(_))));
        for bad in [
            format!("{HEADER}1,x,0.1,0.1,0.1,0.2,0.2,0.2,-0.577,0.577,-3\n"),
            format!("{HEADER}1,x,0.1,0.1,0.1,0.2,0.2,0.2,0,0,3\n"),
            format!("{HEADER}1,x,0.1,0.1,0.1,0.2,0.2,inf,-0.577,0.577,3\n"),
            format!("{HEADER}1,x,0.1,0.1,0.1,0.2,0.2,abc,-0.577,0.577,3\n"),
        ] {
            let e = LafortuneFits::parse(Path::new("<mem>"), bad.as_bytes()).expect_err(&bad);
            assert!(e.to_string().contains("<mem>"), "{e}");
        }
    }
}
