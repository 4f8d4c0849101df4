//! Rendering evaluation scenes.
