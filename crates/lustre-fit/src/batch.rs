//! The batch runner behind `lustre fit`.
