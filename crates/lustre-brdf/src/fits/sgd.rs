//! The SGD authors' published fits of the 100 MERL materials (Bagher, Soler, Holzschuch; table
//! `fits/merl_sgd_fits_bagher2012.csv`, see the data README), loaded as [`CookTorrance`] models:
//! per channel an SGD NDF with the table's kap, the Eq. V.3 shadowing approximation with the
//! table's (λ, c, k, θ0) and the generalized Schlick Fresnel of Eq. V.5 (004 §V.3–V.4).
//!
//! The table's kap equals 1/(αΓ(1−p, α)) to its six printed digits for every channel except
//! chrome (r and b differ by a factor 2.7–3.3), so [`SgdFits::cook_torrance`] uses the table's
//! kap (the published model as evaluated) and [`SgdFits::cook_torrance_normalized`] recomputes
//! it.

use super::FitTable;
use crate::error::Result;
use crate::microfacet::fresnel::Fresnel;
use crate::microfacet::ndf::Ndf;
use crate::microfacet::smith::SgdG1Approx;
use crate::models::cook_torrance::{CookTorrance, CtChannel, G1Model};
use std::path::Path;

/// The table's file name (in the shared data folder under `fits/`, and embedded).
pub const SGD_FITS_FILE: &str = "merl_sgd_fits_bagher2012.csv";

/// The published parameters of one channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SgdChannelParams {
    /// ρd.
    pub rho_d: f64,
    /// ρs.
    pub rho_s: f64,
    /// SGD α.
    pub alpha: f64,
    /// SGD p.
    pub p: f64,
    /// Eq. V.5 F0.
    pub f0: f64,
    /// Eq. V.5 F1.
    pub f1: f64,
    /// The stored normalization kap.
    pub kap: f64,
    /// Eq. V.3 λ.
    pub lambda: f64,
    /// Eq. V.3 c.
    pub c: f64,
    /// Eq. V.3 k.
    pub k: f64,
    /// Eq. V.3 θ0.
    pub theta0: f64,
    /// The fit error reported by the authors.
    pub error: f64,
}

/// The published SGD fit table.
#[derive(Clone, Debug)]
pub struct SgdFits {
    table: FitTable,
}

impl SgdFits {
    /// The table compiled into the library ([`crate::embedded`]).
    pub fn load_default() -> Result<Self> {
        Self::parse(
            &crate::embedded::label(SGD_FITS_FILE),
            crate::embedded::SGD_FITS,
        )
    }

    /// Reads a table from `path`.
    pub fn read(path: &Path) -> Result<Self> {
        Ok(SgdFits {
            table: FitTable::read(path, "name")?,
        })
    }

    /// Parses a table from memory (`path` is only used in messages).
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Self> {
        Ok(SgdFits {
            table: FitTable::parse(path, bytes, "name")?,
        })
    }

    /// Material names in file order.
    pub fn list_materials(&self) -> Vec<String> {
        self.table.names().into_iter().map(str::to_string).collect()
    }

    /// The published parameters of `material`, per channel (r, g, b); `Error::NotFound` for an
    /// unknown name, `Error::Format` for a missing or non-numeric column.
    pub fn params(&self, material: &str) -> Result<[SgdChannelParams; 3]> {
        let t = &self.table;
        let col = |p: &str| t.rgb(material, p);
        let (rd, rs, a, p, f0, f1) = (
            col("rhoD")?,
            col("rhoS")?,
            col("alpha")?,
            col("p")?,
            col("f0")?,
            col("f1")?,
        );
        let (kap, lam, c, k, t0, e) = (
            col("kap")?,
            col("lambda")?,
            col("c")?,
            col("k")?,
            col("theta0")?,
            col("error")?,
        );
        Ok(std::array::from_fn(|i| SgdChannelParams {
            rho_d: rd[i],
            rho_s: rs[i],
            alpha: a[i],
            p: p[i],
            f0: f0[i],
            f1: f1[i],
            kap: kap[i],
            lambda: lam[i],
            c: c[i],
            k: k[i],
            theta0: t0[i],
            error: e[i],
        }))
    }

    /// The published model of `material` with the table's kap (see the module notes).
    pub fn cook_torrance(&self, material: &str) -> Result<CookTorrance> {
        self.build(material, false)
    }

    /// The same with kap recomputed as 1/(αΓ(1−p, α)) (D normalized).
    pub fn cook_torrance_normalized(&self, material: &str) -> Result<CookTorrance> {
        self.build(material, true)
    }

    fn build(&self, material: &str, normalized: bool) -> Result<CookTorrance> {
        let ps = self.params(material)?;
        let ch = |q: &SgdChannelParams| -> Result<CtChannel> {
            let ndf = if normalized {
                Ndf::sgd(q.alpha, q.p)?
            } else {
                Ndf::sgd_with_kap(q.alpha, q.p, q.kap)?
            };
            Ok(CtChannel::new(
                q.rho_d,
                q.rho_s,
                ndf,
                G1Model::SgdApprox(SgdG1Approx::new(q.lambda, q.c, q.k, q.theta0)?),
                Fresnel::generalized_schlick(q.f0, q.f1)?,
            ))
        };
        let name = format!("sgd-published:{material}");
        CookTorrance::new(name, [ch(&ps[0])?, ch(&ps[1])?, ch(&ps[2])?])
    }
}

/// Names of the 100 materials in the embedded table.
pub fn list_materials() -> Result<Vec<String>> {
    Ok(SgdFits::load_default()?.list_materials())
}

/// The published SGD model of `material` from the embedded table.
pub fn load(material: &str) -> Result<CookTorrance> {
    SgdFits::load_default()?.cook_torrance(material)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Error;

    #[test]
    fn lists_and_rejects() {
        let f = SgdFits::load_default().unwrap();
        let names = f.list_materials();
        assert_eq!(names.len(), 100);
        assert!(names.iter().any(|n| n == "gold-paint"));
        match f.cook_torrance("no-such-material") {
            Err(Error::NotFound(m)) => assert!(m.contains("no-such-material"), "{m}"),
            other => panic!("{other:?}"),
        }
        let bad = b"name,other_name,rhoD_r\nx,x,abc\n";
        let t = SgdFits::parse(Path::new("<mem>"), bad).unwrap();
        assert!(matches!(t.cook_torrance("x"), Err(Error::Format { .. })));
        assert!(SgdFits::parse(Path::new("<mem>"), b"").is_err());
    }

    #[test]
    fn every_material_loads() {
        let f = SgdFits::load_default().unwrap();
        for n in f.list_materials() {
            f.cook_torrance(&n).unwrap_or_else(|e| panic!("{n}: {e}"));
            f.cook_torrance_normalized(&n)
                .unwrap_or_else(|e| panic!("{n}: {e}"));
        }
    }
}
