//! Measured inputs as fitting data.
