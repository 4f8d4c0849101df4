//! Textured parameters at a pixel. `textured_params.wgsl` ([`PARAMS`]): the clamps and weights
//! each textured kind's `<kind>_textured` applies (lustre-scene's `unit` and `clamp_alpha`, the
//! coating grid's constants); `textured.wgsl`: the normal-map functions, composed with the
//! generated dispatch `textured_bsdf` into [`super::kinds::TEXTURED`].

use crate::wgsl::{Module, Source};

/// `textured_params.wgsl`: `textured_unit`, `textured_unit3`, `textured_alpha`,
/// `textured_coat_weight`, `COATING_ALPHAS`, `COATING_ALPHA_MIN`, `TEXTURED_PBR_ALPHA_MIN`.
pub const PARAMS: Module = Module {
    name: "textured_params",
    source: Source::File(include_str!("textured_params.wgsl")),
    deps: &[],
};
