//! The WGSL modules every pass imports and the composer that joins them to a pass's source.
//!
//! A module is a piece of WGSL without bindings or entry points (`wgsl/*.wgsl`): the Kurt lobe,
//! the MIP levels, the row lattice, the regular-sampling weights, the bounding planes, the QMC
//! points. Each names its CPU twin in its header. WGSL has no imports, so a pass is the plain
//! concatenation [`compose`] builds: the modules it asks for and, transitively, theirs, each
//! once and after everything it depends on, then the pass's own source (its bindings, its entry
//! point, what only it needs). Functions that read the environment take the cube texture and
//! its sampler as parameters, so one function serves every pass whatever its bindings.

/// One WGSL module: a name (unique), its source and the modules it uses.
#[derive(Debug)]
pub struct Module {
    /// The module's name, `wgsl/<name>.wgsl`.
    pub name: &'static str,
    /// The WGSL source: constants, structs and functions only.
    pub source: &'static str,
    /// The modules whose declarations the source uses.
    pub deps: &'static [&'static Module],
}

/// `PI`, the `Material` and `Lobe` records (`packed::GpuMaterial`, `packed::GpuLobe`).
pub const TYPES: Module = Module {
    name: "types",
    source: include_str!("wgsl/types.wgsl"),
    deps: &[],
};

/// Reflection about a half vector, the tangent-plane mirror, local → world.
pub const FRAME: Module = Module {
    name: "frame",
    source: include_str!("wgsl/frame.wgsl"),
    deps: &[],
};

/// The Kurt lobe: Schlick, Beckmann D, the lobe's value (002 Eq. 2–5).
pub const LOBE: Module = Module {
    name: "lobe",
    source: include_str!("wgsl/lobe.wgsl"),
    deps: &[&TYPES],
};

/// Per-sample MIP levels: lobe area, 002 Eq. 16, texel solid angle, footprint level.
pub const MIP: Module = Module {
    name: "mip",
    source: include_str!("wgsl/mip.wgsl"),
    deps: &[&TYPES, &FRAME],
};

/// The row lattice: Gaussian quantile, rows, row lengths.
pub const PATTERN: Module = Module {
    name: "pattern",
    source: include_str!("wgsl/pattern.wgsl"),
    deps: &[],
};

/// Regular in-lobe sampling and its weighting: stored-pattern samples, the (tap) row lattice.
pub const REGULAR: Module = Module {
    name: "regular",
    source: include_str!("wgsl/regular.wgsl"),
    deps: &[&TYPES, &FRAME, &LOBE, &MIP, &PATTERN],
};

/// Bounding-plane (parallax) correction of cube-map lookups (000 §4.4.1).
pub const PLANES: Module = Module {
    name: "planes",
    source: include_str!("wgsl/planes.wgsl"),
    deps: &[],
};

/// Sobol' (0,2) points, SplitMix64 pixel seeds and rotations (000 §4.4.2).
pub const QMC: Module = Module {
    name: "qmc",
    source: include_str!("wgsl/qmc.wgsl"),
    deps: &[],
};

/// Anisotropic GGX and Beckmann: D, Smith G1, visible-normal density and sampling, and the
/// rough-conductor lobe's value, pdf and sampling warp (unit Fresnel).
pub const MICROFACET: Module = Module {
    name: "microfacet",
    source: include_str!("wgsl/microfacet.wgsl"),
    deps: &[&TYPES, &FRAME, &PATTERN],
};

/// Regular sampling through the rough conductor's warp: the Fibonacci lattice, footprint
/// levels (`lustre_shade::warp::shade_regular_warp`).
pub const WARP: Module = Module {
    name: "warp",
    source: include_str!("wgsl/warp.wgsl"),
    deps: &[&TYPES, &FRAME, &MIP, &MICROFACET],
};

/// The record every BSDF model's sampling returns (`BsdfSample`).
pub const BSDF_SAMPLE: Module = Module {
    name: "bsdf_sample",
    source: include_str!("wgsl/bsdf_sample.wgsl"),
    deps: &[],
};

/// Dielectric and conductor Fresnel, refraction, `split_uniform`, the cosine lobe.
pub const FRESNEL: Module = Module {
    name: "fresnel",
    source: include_str!("wgsl/fresnel.wgsl"),
    deps: &[&TYPES],
};

/// Kind 1: the rough conductor.
pub const ROUGH_CONDUCTOR: Module = Module {
    name: "rough_conductor",
    source: include_str!("wgsl/rough_conductor.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL, &FRAME, &MICROFACET],
};

/// Kind 2: the rough plastic (its transmittance table read through the pass's `bsdf_table`).
pub const ROUGH_PLASTIC: Module = Module {
    name: "rough_plastic",
    source: include_str!("wgsl/rough_plastic.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL, &FRAME, &MICROFACET],
};

/// Kind 3: the rough dielectric.
pub const ROUGH_DIELECTRIC: Module = Module {
    name: "rough_dielectric",
    source: include_str!("wgsl/rough_dielectric.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL, &FRAME, &MICROFACET],
};

/// Kind 4: the smooth conductor.
pub const CONDUCTOR: Module = Module {
    name: "conductor",
    source: include_str!("wgsl/conductor.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL],
};

/// Kind 5: the thin dielectric sheet.
pub const THIN_DIELECTRIC: Module = Module {
    name: "thin_dielectric",
    source: include_str!("wgsl/thin_dielectric.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL],
};

/// Kind 6: glTF 2.0 metallic-roughness.
pub const PBR_METALLIC_ROUGHNESS: Module = Module {
    name: "pbr_metallic_roughness",
    source: include_str!("wgsl/pbr_metallic_roughness.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL, &FRAME, &MICROFACET],
};

/// Kind 7: the Lambertian reflector.
pub const LAMBERT: Module = Module {
    name: "lambert",
    source: include_str!("wgsl/lambert.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL],
};

/// Kind 8: the smooth plastic.
pub const PLASTIC: Module = Module {
    name: "plastic",
    source: include_str!("wgsl/plastic.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL],
};

/// Kind 9: the smooth dielectric interface.
pub const DIELECTRIC: Module = Module {
    name: "dielectric",
    source: include_str!("wgsl/dielectric.wgsl"),
    deps: &[&BSDF_SAMPLE, &FRESNEL],
};

/// Component selection, cosine sampling and luminance of the fitted models' mixtures.
pub const MIXTURE: Module = Module {
    name: "mixture",
    source: include_str!("wgsl/mixture.wgsl"),
    deps: &[&TYPES, &BSDF_SAMPLE],
};

/// The Beckmann and GGX Cook-Torrance fits (kinds 17, 18): `cook_torrance_{unpack, eval, pdf,
/// sample}` (`fit_models::pack_cook_torrance`).
pub const COOK_TORRANCE: Module = Module {
    name: "cook_torrance",
    source: include_str!("wgsl/cook_torrance.wgsl"),
    deps: &[&TYPES, &FRAME, &MICROFACET, &MIXTURE, &BSDF_SAMPLE],
};

/// The SGD Cook-Torrance fits (kind 16): `sgd_{unpack, eval, pdf, sample}`, the f32 upper
/// incomplete gamma (`fit_models::pack_sgd`).
pub const SGD: Module = Module {
    name: "sgd",
    source: include_str!("wgsl/sgd.wgsl"),
    deps: &[&COOK_TORRANCE],
};

/// The Kurt model with reflection and transmission lobes as a whole BSDF (kind 19):
/// `kurt_{unpack, eval, pdf, sample}` (`fit_models::pack_kurt`).
pub const KURT: Module = Module {
    name: "kurt",
    source: include_str!("wgsl/kurt.wgsl"),
    deps: &[&TYPES, &FRAME, &LOBE, &MIXTURE, &BSDF_SAMPLE],
};

/// The `GpuBsdf` record and the dispatch by kind to the models' sample / eval / pdf.
pub const BSDF: Module = Module {
    name: "bsdf",
    source: include_str!("wgsl/bsdf.wgsl"),
    deps: &[
        &ROUGH_CONDUCTOR,
        &ROUGH_PLASTIC,
        &ROUGH_DIELECTRIC,
        &CONDUCTOR,
        &THIN_DIELECTRIC,
        &PBR_METALLIC_ROUGHNESS,
        &LAMBERT,
        &PLASTIC,
        &DIELECTRIC,
        &SGD,
        &COOK_TORRANCE,
        &KURT,
    ],
};

/// lustre's analytic models bsdf.wgsl does not have (Oren–Nayar, Phong, Blinn–Phong, the Ward
/// variants, Lafortune, Ashikhmin–Shirley, ABC, Cook–Torrance per channel), evaluation only, and
/// `record_eval`: a record of those passes that take any material (`analytic::pack_analytic`).
pub const ANALYTIC: Module = Module {
    name: "analytic",
    source: include_str!("wgsl/analytic.wgsl"),
    deps: &[&TYPES, &COOK_TORRANCE, &BSDF],
};

/// A material's textured parameters and normal map at a pixel: `textured_bsdf` (the record with
/// its parameters at the pixel), `tangent_space_normal`, `mapped_normal`.
pub const TEXTURED: Module = Module {
    name: "textured",
    source: include_str!("wgsl/textured.wgsl"),
    deps: &[&BSDF],
};

/// The CPU's texture lookup (`texture_sample`, `scalar_at`) over a shader's own `texels` and
/// `tex_info` bindings: prepended to the passes that read textures, not a binding-free module.
pub const TEXTURE_SAMPLE_WGSL: &str = include_str!("texture_sample.wgsl");

/// Measured BRDFs: MERL tables (trilinear, missing bins left out) and tabulated-CDF importance
/// sampling (004 §IV.4.3), read from the pass's `bsdf_table`.
pub const MEASURED: Module = Module {
    name: "measured",
    source: include_str!("wgsl/measured.wgsl"),
    deps: &[&TYPES, &FRESNEL],
};

/// Frequency analysis (004 §IV.3): one-bounce bandwidth of a distant light, the n_b
/// directions, BRDF bandwidth cells.
pub const FREQUENCY: Module = Module {
    name: "frequency",
    source: include_str!("wgsl/frequency.wgsl"),
    deps: &[&TYPES],
};

/// A distant environment light: bilinear equirect radiance, importance sampling by texels and
/// its density, read through the pass's `env_texel` and `env_table`.
pub const ENV_LIGHT: Module = Module {
    name: "env_light",
    source: include_str!("wgsl/env_light.wgsl"),
    deps: &[&TYPES],
};

/// Cube-map pyramids in storage buffers: face coordinates, edge-crossing fetches, bilinear and
/// trilinear lookups, read through the pass's `cube_texel`, `cube_level` and `cube_ring`.
pub const CUBE_STORAGE: Module = Module {
    name: "cube_storage",
    source: include_str!("wgsl/cube_storage.wgsl"),
    deps: &[],
};

/// Textured parallelogram emitters: the record, a point, the texel of a point.
pub const AREA_LIGHT: Module = Module {
    name: "area_light",
    source: include_str!("wgsl/area_light.wgsl"),
    deps: &[],
};

/// Every module, in an order [`compose`] would emit them.
pub const ALL: [&Module; 33] = [
    &TYPES,
    &FRAME,
    &LOBE,
    &MIP,
    &PATTERN,
    &REGULAR,
    &PLANES,
    &QMC,
    &MICROFACET,
    &WARP,
    &BSDF_SAMPLE,
    &FRESNEL,
    &ROUGH_CONDUCTOR,
    &ROUGH_PLASTIC,
    &ROUGH_DIELECTRIC,
    &CONDUCTOR,
    &THIN_DIELECTRIC,
    &PBR_METALLIC_ROUGHNESS,
    &LAMBERT,
    &PLASTIC,
    &DIELECTRIC,
    &MIXTURE,
    &COOK_TORRANCE,
    &SGD,
    &KURT,
    &BSDF,
    &ANALYTIC,
    &TEXTURED,
    &MEASURED,
    &FREQUENCY,
    &ENV_LIGHT,
    &CUBE_STORAGE,
    &AREA_LIGHT,
];

/// The source of a pass: every module in `imports` and, transitively, the modules they use,
/// each once and after its dependencies (depth-first, in the order listed), then `pass`. Each
/// module is preceded by a comment line naming it.
pub fn compose(imports: &[&Module], pass: &str) -> String {
    let mut order: Vec<&Module> = Vec::new();
    for m in imports {
        visit(m, &mut order);
    }
    let mut out = String::new();
    for m in &order {
        out.push_str("// ---------------------------------------------------------------- module ");
        out.push_str(m.name);
        out.push_str(".wgsl\n");
        out.push_str(m.source);
        if !m.source.ends_with('\n') {
            out.push('\n');
        }
        out.push('\n');
    }
    out.push_str("// ---------------------------------------------------------------- pass\n");
    out.push_str(pass);
    out
}

/// Post-order depth-first visit: `m`'s dependencies, then `m`, skipping modules already placed
/// (modules are `const`s, so identity is the name).
fn visit<'a>(m: &'a Module, order: &mut Vec<&'a Module>) {
    if order.iter().any(|o| o.name == m.name) {
        return;
    }
    for d in m.deps {
        visit(d, order);
    }
    order.push(m);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compose_emits_each_dependency_once_before_its_users() {
        let src = compose(&[&REGULAR, &LOBE, &QMC], "// the pass\n");
        let at = |name: &str| {
            let tag = format!("module {name}.wgsl\n");
            assert_eq!(src.matches(&tag).count(), 1, "{name} once");
            src.find(&tag).unwrap_or(usize::MAX)
        };
        for m in [&REGULAR, &QMC] {
            for d in m.deps {
                assert!(at(d.name) < at(m.name), "{} before {}", d.name, m.name);
            }
        }
        assert!(!src.contains("module planes.wgsl"));
        assert!(src.ends_with("// the pass\n"));
        assert!(at("qmc") < src.find("// the pass").unwrap_or(0));
    }

    #[test]
    fn module_names_are_unique_and_match_their_files() {
        for (i, a) in ALL.iter().enumerate() {
            assert!(ALL[i + 1..].iter().all(|b| b.name != a.name), "{}", a.name);
            // The header names the module.
            let first = a.source.lines().next().unwrap_or("");
            assert!(
                first.starts_with(&format!("// module {}:", a.name)),
                "{first}"
            );
        }
    }
}
