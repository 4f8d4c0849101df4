//! Per-sample MIP levels.
