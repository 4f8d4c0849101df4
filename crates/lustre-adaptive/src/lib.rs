//! Adaptive shading by frequency analysis (004 chapter IV): acquired BRDFs shaded directly,
//! on any geometry, under a distant environment, by predicting per pixel how fast the image
//! varies and how noisy the shading integral is, then shading only the pixels and the samples
//! that need it.
//!
//! The pipeline of Fig. IV.11, on the CPU:
//! - [`gbuffer`]: the geometry pass (position, shading frame, depth, material, texture
//!   coordinates) and the screen-space curvature estimated from it.
//! - [`buffer`]: the bandwidth buffer (§IV.4.1): per pixel the pyramid level at which it must
//!   be shaded (Eq. IV.6, IV.7, IV.11) and the variance bound that sets its sample count
//!   (Eq. IV.9, or IV.10 for pre-convolved shading), with the min-filtered level and
//!   max-filtered variance pyramids.
//! - [`shading`]: the shading integral (§IV.4.3): BRDF importance sampling by inversion of
//!   tabulated CDFs, the environment read at level 0 or, pre-convolved (§IV.3.5), at the level
//!   of the BRDF's bandwidth. No visibility, as in 004.
//! - [`compare`]: the time to reach a PSNR, for equal-quality comparisons (Fig. IV.15).
//! - [`light`]: textured quad emitters (§IV.5.3) and their bandwidth.
//! - [`hierarchy`]: coarse-to-fine shading interleaved with bilateral up-sampling (§IV.4.2,
//!   Fig. IV.12), and the brute-force renderer it is compared with.

pub mod buffer;
pub mod compare;
pub mod gbuffer;
pub mod hierarchy;
pub mod light;
pub mod shading;

/// What can go wrong in adaptive shading.
#[derive(Debug, thiserror::Error)]
pub enum AdaptiveError {
    /// An absurd parameter (zero size, zero samples, a non-finite target).
    #[error("{0}")]
    Parameter(String),
    /// From the scene, the path tracer's geometry or the images.
    #[error(transparent)]
    Trace(#[from] lustre_trace::TraceError),
    /// From the frequency analysis.
    #[error(transparent)]
    Freq(#[from] lustre_freq::FreqError),
    /// From a BRDF's tables.
    #[error(transparent)]
    Brdf(#[from] lustre_brdf::Error),
    /// From the environment's pyramid.
    #[error(transparent)]
    Env(#[from] lustre_env::EnvError),
}

/// The result type of lustre-adaptive.
pub type Result<T> = std::result::Result<T, AdaptiveError>;
