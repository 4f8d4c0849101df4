//! Taking lustre's results to other tools: [`material`] writes a fitted material as a glTF 2.0
//! file (a sample sphere carrying it); [`scene`] a baked scene as one binary glTF with its light
//! maps, and [`exact`] the lustre data a glTF cannot carry, in its `extras`, so that lustre reads
//! the file back unchanged; [`mitsuba`] a scene as a Mitsuba 3 scene folder. (A material's
//! Mitsuba 3 BSDF is written beside its fit: `lustre_fit::mitsuba`.)

pub mod exact;
pub mod material;
pub mod mitsuba;
pub mod scene;
