//! Float RGB images.
