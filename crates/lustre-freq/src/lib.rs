//! Frequency analysis for adaptive shading (004 chapter IV): how fast the shading varies, so
//! that a renderer shades only the pixels and samples that need it.
//!
//! - [`wavelet`]: the local bandwidth of an image from a 2D Daubechies-4 pyramid (§IV.3.1,
//!   Fig. IV.4–IV.5).
//! - [`environment`]: the local angular bandwidth of a distant environment (§IV.3.1, Fig. IV.6).
//! - [`spatial`]: the spatial bandwidth of area lights (zero-padded) and textures (§IV.3.1,
//!   Fig. IV.7).
//! - [`brdf`]: a BRDF's angular bandwidth tabulated over incident directions (§IV.3.1,
//!   "Reflectance", Fig. IV.8).
//! - [`transport`]: the 2D bandwidth through one bounce (Fig. IV.9, Eq. IV.4–IV.5), the pixel's
//!   bandwidth and sampling rate (Eq. IV.6–IV.7) and the sample count from the variance bound
//!   (Eq. IV.9–IV.10).
//! - [`pixel`]: one pixel's prediction under a distant environment from n_b directions
//!   (§IV.3.6): its bandwidth and the sums of the variance bound.

pub mod brdf;
pub mod environment;
pub mod pixel;
pub mod spatial;
pub mod transport;
pub mod wavelet;

/// What can go wrong in a frequency analysis.
#[derive(Debug, thiserror::Error)]
pub enum FreqError {
    /// An absurd parameter or input (zero size, length mismatch, non-finite value).
    #[error("{0}")]
    Parameter(String),
}

/// The result type of lustre-freq.
pub type Result<T> = std::result::Result<T, FreqError>;
