//! Resolves a material specification (a model with parameters, a published fit by name, a
//! measured file or an NBRDF material) to a [`crate::Bsdf`].
