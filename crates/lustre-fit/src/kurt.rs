//! Kurt et al. hierarchical fitting (000 §3.4.1).
