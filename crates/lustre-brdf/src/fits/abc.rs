//! The published ABC fits of the 100 MERL materials (Löw et al. 2012, as distributed in
//! jdupuy/dj_brdf's `dj_brdf.h`, public domain): `fits/merl_abc_fits_low2012.csv` with columns
//! `name, kD_r, kD_g, kD_b, A_r, A_g, A_b, B, C, ior`, loaded by material name into
//! [`crate::models::abc::Abc`], which evaluates them exactly as dj_brdf's `abc::eval` does.

use crate::error::{Error, Result};
use crate::fits::{fit_table_api, FitTable};
use crate::models::abc::Abc;
use crate::rgb::Rgb;

/// The file's name (in the shared data folder under `fits/`, and embedded).
pub const ABC_FITS_FILE: &str = "merl_abc_fits_low2012.csv";

/// The table of ABC fits.
#[derive(Clone, Debug)]
pub struct AbcFits {
    table: FitTable,
}

fit_table_api!(AbcFits, ABC_FITS_FILE, crate::embedded::ABC_FITS);

impl AbcFits {
    /// The fitted ABC BRDF of `material`; [`Error::NotFound`] for an unknown name, a format
    /// error naming the file and the material for an invalid parameter.
    pub fn material(&self, material: &str) -> Result<Abc> {
        let t = &self.table;
        let kd = Rgb(t.rgb(material, "kD")?);
        let a = Rgb(t.rgb(material, "A")?);
        let b = t.value(material, "B")?;
        let c = t.value(material, "C")?;
        let ior = t.value(material, "ior")?;
        Abc::new(kd, a, b, c, ior)
            .map(|m| m.with_label(material))
            .map_err(|e| Error::format(&t.path, format!("{material}: {e}")))
    }
}

/// The ABC fit of MERL material `name`, from the embedded table.
pub fn load(name: &str) -> Result<Abc> {
    AbcFits::load_default()?.material(name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const HEADER: &str = "name,kD_r,kD_g,kD_b,A_r,A_g,A_b,B,C,ior\n";

    #[test]
    fn parses_and_rejects() {
        let good = format!("{HEADER}x,0.1,0.1,0.1,5,5,5,100,1.2,1.5\n");
        let f = AbcFits::parse(Path::new("<mem>"), good.as_bytes()).expect("valid");
        assert_eq!(f.names(), vec!["x"]);
        assert!(matches!(f.material("y"), Err(Error::NotFound(_))));
        for bad in [
            format!("{HEADER}x,0.1,0.1,0.1,5,5,5,100,1.2,0.9\n"),
            format!("{HEADER}x,0.1,0.1,0.1,-5,5,5,100,1.2,1.5\n"),
            format!("{HEADER}x,0.1,0.1,0.1,5,5,5,NaN,1.2,1.5\n"),
            format!("{HEADER}x,0.1,0.1,0.1,5,5,5,100,1.2\n"),
            "name,kD_r\nx,0.1\n".to_string(),
            String::new(),
        ] {
            let e = AbcFits::parse(Path::new("<mem>"), bad.as_bytes()).expect_err(&bad);
            assert!(e.to_string().contains("<mem>"), "{e}");
        }
    }
}
