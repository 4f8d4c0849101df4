//! Taking lustre's results to other tools: [`material`] writes a fitted material as a glTF 2.0
//! file (a sample sphere carrying it). (Mitsuba 3 BSDFs are written beside their fit:
//! `lustre_fit::mitsuba`.)

pub mod material;
