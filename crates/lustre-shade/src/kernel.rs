//! Per-pixel shading kernels.
