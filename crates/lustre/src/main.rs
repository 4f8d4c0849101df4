//! The lustre command line.
fn main() {}
