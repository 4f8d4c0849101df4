//! Microfacet building blocks: normal distributions (P22 form, and the anisotropic GGX/Beckmann with
//! visible-normal sampling), Smith shadowing, Fresnel terms.

pub mod distribution;
pub mod fresnel;
pub mod ndf;
pub mod smith;
