//! Plots of BSDF lobes (in progress).
