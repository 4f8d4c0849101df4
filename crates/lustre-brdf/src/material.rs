//! The versioned material JSON (`lustre-material/1`) that the fitter writes and the renderer loads.
