//! Regular sample patterns.
