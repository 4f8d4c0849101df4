//! Evaluation scenes.
