//! Published data compiled into the library (see `crates/lustre-brdf/data/README.md` for the
//! sources and licences): the SGD, ABC and Lafortune fit tables of the 100 MERL materials and
//! the MERL neural BRDFs. With them `sgd:NAME`, `abc:NAME`, `lafortune:NAME` and `nbrdf:NAME`
//! resolve in an installed binary, from any directory, without a data folder.

use std::path::Path;

/// The SGD fits (Bagher et al. 2012), `merl_sgd_fits_bagher2012.csv`.
pub const SGD_FITS: &[u8] = include_bytes!("../data/merl_sgd_fits_bagher2012.csv");
/// The ABC fits (Löw et al. 2012), `merl_abc_fits_low2012.csv`.
pub const ABC_FITS: &[u8] = include_bytes!("../data/merl_abc_fits_low2012.csv");
/// The one-lobe Lafortune fits (Ngan et al. 2005), `merl_lafortune_fits_ngan2005.csv`.
pub const LAFORTUNE_FITS: &[u8] = include_bytes!("../data/merl_lafortune_fits_ngan2005.csv");
/// The MERL neural BRDFs (Sztrajman et al. 2021), `merl_nbrdf.json`.
pub const MERL_NBRDF: &[u8] = include_bytes!("../data/merl_nbrdf.json");
/// The MIT licence of the neural BRDF weights.
pub const NBRDF_LICENSE: &str = include_str!("../data/Neural-BRDF_LICENSE.txt");

/// The name under which an embedded file appears in messages: `<embedded>/FILE`.
pub fn label(file: &str) -> std::path::PathBuf {
    Path::new("<embedded>").join(file)
}

/// The embedded MERL neural BRDF set.
pub fn merl_nbrdf() -> crate::Result<crate::measured::nbrdf::NbrdfSet> {
    crate::measured::nbrdf::NbrdfSet::parse(label("merl_nbrdf.json"), MERL_NBRDF)
}

/// Where the published data of `lustre list` comes from, in words.
pub fn sources() -> Vec<(&'static str, &'static str)> {
    vec![
        (
            "sgd:NAME, sgd-numeric:NAME",
            "Bagher, Soler & Holzschuch 2012 (jdupuy/dj_brdf, public domain)",
        ),
        (
            "abc:NAME",
            "Löw et al. 2012 (jdupuy/dj_brdf, public domain)",
        ),
        (
            "lafortune:NAME",
            "Ngan et al. 2005, published one-lobe fits (numbers)",
        ),
        (
            "nbrdf:NAME",
            "Sztrajman et al. 2021, asztr/Neural-BRDF weights (MIT licence)",
        ),
    ]
}
