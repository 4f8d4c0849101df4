//! Plots of BSDF lobes for lustre (and the top view of a scene's real-time set-up,
//! [`top_view`]): polar lobes in the plane of incidence (004 Fig. V.11,
//! 000 Fig. 3.12) and transfer-probability disc arrays (000 Fig. 2.6 and 3.11).
//!
//! Every function works on any [`lustre_brdf::Bsdf`] through `&dyn Bsdf`, so measured tables and
//! analytic models are plotted by the same code. The plotted quantity is the transfer
//! probability p(ωo|ωi) = f(ωi, ωo)·|cos θo| (000 §2.3) unless an option asks for f itself.
//! Files are written atomically (a temporary file in the target folder, then a rename). PNG text
//! needs a system font; see [`font`] for where it comes from.

pub mod array;
mod color;
mod draw;
pub mod font;
pub mod heat;
pub mod pattern;
pub mod polar;
pub mod top_view;

pub use array::{
    direction_pixel, disc_direction, transfer_array, transfer_array_compare, transfer_disc,
    transmits, ArrayColor, ArrayOptions, Disc, Hemisphere,
};
pub use heat::{heat_map, HeatScale};
pub use pattern::{pattern_plot, PatternOptions, PatternPanel};
pub use polar::{
    polar_curve, polar_plot, Channels, PolarCurve, PolarOptions, PolarSample, Quantity,
};
pub use top_view::{top_view, TopItem, TopKind};

use std::path::{Path, PathBuf};

/// Everything that can go wrong while plotting.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A file or folder could not be created, written or renamed.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The drawing backend failed (for example while encoding the PNG).
    #[error("{path}: drawing failed: {message}")]
    Draw {
        /// The file being drawn.
        path: PathBuf,
        /// The backend's message.
        message: String,
    },
    /// The request itself is invalid (no BSDF, an angle outside its range, a zero size).
    #[error("invalid plot request: {0}")]
    Input(String),
}

/// Result alias for this crate.
pub type Result<T> = std::result::Result<T, PlotError>;

/// The files one plot call wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PlotFiles {
    /// The PNG image.
    pub png: PathBuf,
    /// The SVG image, for the vector figures (polar lobes); `None` for raster arrays.
    pub svg: Option<PathBuf>,
}

impl PlotFiles {
    /// All written paths, PNG first.
    pub fn paths(&self) -> Vec<&Path> {
        std::iter::once(self.png.as_path())
            .chain(self.svg.as_deref())
            .collect()
    }
}

/// `base` with `.ext` appended (not replacing an existing extension, so `a/kurt-0.5` stays whole).
fn with_suffix(base: &Path, ext: &str) -> PathBuf {
    let mut s = base.as_os_str().to_os_string();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// The folder a file goes into (`.` for a bare name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Rejects a non-finite or out-of-range angle.
fn check_angle(name: &str, deg: f64, lo: f64, hi: f64) -> Result<()> {
    if deg.is_finite() && deg >= lo && deg <= hi {
        Ok(())
    } else {
        Err(PlotError::Input(format!(
            "{name} = {}° must lie in [{lo}°, {hi}°]",
            lustre_brdf::error::plain_number(deg)
        )))
    }
}

/// A finite, non-negative copy of a value (measured tables may hold noise below zero or NaN
/// holes; plots show those as zero).
fn clean(v: f64) -> f64 {
    if v.is_finite() && v > 0.0 {
        v
    } else {
        0.0
    }
}
