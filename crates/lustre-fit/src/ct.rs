//! Two-slice Cook-Torrance fits (004 §V.4).
