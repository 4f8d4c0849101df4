//! Microfacet building blocks: normal distributions (P22 form), Smith shadowing, Fresnel terms.

pub mod fresnel;
pub mod ndf;
pub mod smith;
