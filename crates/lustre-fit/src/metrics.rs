//! Error metrics and albedos.
