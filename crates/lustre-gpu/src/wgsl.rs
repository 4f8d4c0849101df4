//! The WGSL modules every pass imports and the composer that joins them to a pass's source.
//!
//! A module is a piece of WGSL without bindings or entry points (`wgsl/*.wgsl`): the Kurt lobe,
//! the MIP levels, the row lattice, the regular-sampling weights, the bounding planes, the QMC
//! points. Each names its CPU twin in its header. WGSL has no imports, so a pass is the plain
//! concatenation [`compose`] builds: the modules it asks for and, transitively, theirs, each
//! once and after everything it depends on, then the pass's own source (its bindings, its entry
//! point, what only it needs). Functions that read the environment take the cube texture and
//! its sampler as parameters, so one function serves every pass whatever its bindings.
//!
//! A module's contract is its header: the first comment block names the module, its CPU twin
//! and, on `// Requires (the pass defines): fn …` lines, each function the pass that composes it
//! must define (the buffers a binding-free module reads through: [`PASS_PROVIDED`]); a unit
//! test holds every module to it. Modules live beside the Rust that owns them: the shared ones
//! in `wgsl/`, each material kind's in `material/` (some generated from the kinds' registry,
//! [`Source::Generated`]), the measured BRDFs' beside `measured.rs`.

use crate::material;
use std::borrow::Cow;

/// One WGSL module: a name (unique), its source and the modules it uses.
#[derive(Debug)]
pub struct Module {
    /// The module's name: `<name>.wgsl` beside the Rust file that declares it.
    pub name: &'static str,
    /// The WGSL source: constants, structs and functions only.
    pub source: Source,
    /// The modules whose declarations the source uses.
    pub deps: &'static [&'static Module],
}

/// Where a module's text comes from.
#[derive(Debug)]
pub enum Source {
    /// A `.wgsl` file, included at compile time.
    File(&'static str),
    /// Generated from Rust tables (the material kinds' codes and dispatch,
    /// [`crate::material::kinds`]), so that the WGSL and the Rust cannot disagree.
    Generated(fn() -> String),
}

impl Module {
    /// The module's WGSL text.
    pub fn text(&self) -> Cow<'static, str> {
        match self.source {
            Source::File(s) => Cow::Borrowed(s),
            Source::Generated(f) => Cow::Owned(f()),
        }
    }
}

/// `PI`, the `Material` and `Lobe` records (`packed::GpuKurtMaterial`, `packed::GpuLobe`).
pub const TYPES: Module = Module {
    name: "types",
    source: Source::File(include_str!("wgsl/types.wgsl")),
    deps: &[],
};

/// Reflection about a half vector, the tangent-plane mirror, local → world.
pub const FRAME: Module = Module {
    name: "frame",
    source: Source::File(include_str!("wgsl/frame.wgsl")),
    deps: &[],
};

/// The Kurt lobe: Schlick, Beckmann D, the lobe's value (002 Eq. 2–5).
pub const LOBE: Module = Module {
    name: "lobe",
    source: Source::File(include_str!("wgsl/lobe.wgsl")),
    deps: &[&TYPES],
};

/// Per-sample MIP levels: lobe area, 002 Eq. 16, texel solid angle, footprint level.
pub const MIP: Module = Module {
    name: "mip",
    source: Source::File(include_str!("wgsl/mip.wgsl")),
    deps: &[&TYPES, &FRAME],
};

/// The row lattice: Gaussian quantile, rows, row lengths.
pub const PATTERN: Module = Module {
    name: "pattern",
    source: Source::File(include_str!("wgsl/pattern.wgsl")),
    deps: &[],
};

/// Regular in-lobe sampling and its weighting: stored-pattern samples, the (tap) row lattice.
pub const REGULAR: Module = Module {
    name: "regular",
    source: Source::File(include_str!("wgsl/regular.wgsl")),
    deps: &[&TYPES, &FRAME, &LOBE, &MIP, &PATTERN],
};

/// Bounding-plane (parallax) correction of cube-map lookups (000 §4.4.1).
pub const PLANES: Module = Module {
    name: "planes",
    source: Source::File(include_str!("wgsl/planes.wgsl")),
    deps: &[],
};

/// Sobol' (0,2) points, SplitMix64 pixel seeds and rotations (000 §4.4.2).
pub const QMC: Module = Module {
    name: "qmc",
    source: Source::File(include_str!("wgsl/qmc.wgsl")),
    deps: &[],
};

/// Anisotropic GGX and Beckmann: D, Smith G1, visible-normal density and sampling, and the
/// rough-conductor lobe's value, pdf and sampling warp (unit Fresnel).
pub const MICROFACET: Module = Module {
    name: "microfacet",
    source: Source::File(include_str!("wgsl/microfacet.wgsl")),
    deps: &[&TYPES, &FRAME, &PATTERN],
};

/// Regular sampling through the rough conductor's warp: the Fibonacci lattice, footprint
/// levels (`lustre_shade::warp::shade_regular_warp`).
pub const WARP: Module = Module {
    name: "warp",
    source: Source::File(include_str!("wgsl/warp.wgsl")),
    deps: &[&TYPES, &FRAME, &MIP, &MICROFACET],
};

/// The record every BSDF model's sampling returns (`BsdfSample`).
pub const BSDF_SAMPLE: Module = Module {
    name: "bsdf_sample",
    source: Source::File(include_str!("wgsl/bsdf_sample.wgsl")),
    deps: &[],
};

/// Dielectric and conductor Fresnel, refraction, `split_uniform`, the cosine lobe.
pub const FRESNEL: Module = Module {
    name: "fresnel",
    source: Source::File(include_str!("wgsl/fresnel.wgsl")),
    deps: &[&TYPES],
};

/// A visible-normal microfacet lobe beside a cosine lobe: the density and sampled direction of
/// The `KHR_materials_sheen` lobe: Charlie D, Neubelt V, the albedo table
/// (`lustre_brdf::models::sheen`).
pub const SHEEN: Module = Module {
    name: "sheen",
    source: Source::Generated(sheen_source),
    deps: &[&TYPES],
};

/// `sheen.wgsl` with [`lustre_brdf::models::sheen::SHEEN_ALBEDO_FIT`] appended as a WGSL
/// constant (one `vec4` per power of x).
fn sheen_source() -> String {
    use lustre_brdf::models::sheen::SHEEN_ALBEDO_FIT;
    let rows: Vec<String> = SHEEN_ALBEDO_FIT
        .iter()
        .map(|r| format!("vec4<f32>({:?}, {:?}, {:?}, {:?})", r[0], r[1], r[2], r[3]))
        .collect();
    format!(
        "{}\nconst SHEEN_ALBEDO_FIT = array<vec4<f32>, {}>({});\n",
        include_str!("wgsl/sheen.wgsl"),
        rows.len(),
        rows.join(", ")
    )
}

/// the rough plastic and the glTF metallic-roughness model.
pub const GLOSSY_DIFFUSE: Module = Module {
    name: "glossy_diffuse",
    source: Source::File(include_str!("wgsl/glossy_diffuse.wgsl")),
    deps: &[&TYPES, &FRAME, &MICROFACET, &FRESNEL],
};

/// Component selection, cosine sampling and luminance of the fitted models' mixtures.
pub const MIXTURE: Module = Module {
    name: "mixture",
    source: Source::File(include_str!("wgsl/mixture.wgsl")),
    deps: &[&TYPES, &BSDF_SAMPLE],
};

/// The CPU's texture lookup (`texture_sample`, `scalar_at`) through the pass's `texture_texel`
/// and `texture_info`.
pub const TEXTURE_SAMPLE: Module = Module {
    name: "texture_sample",
    source: Source::File(include_str!("wgsl/texture_sample.wgsl")),
    deps: &[],
};

/// A material's diffuse albedo at a hit (`albedo`) through the pass's `material_row`.
pub const MATERIAL_ALBEDO: Module = Module {
    name: "material_albedo",
    source: Source::File(include_str!("wgsl/material_albedo.wgsl")),
    deps: &[&TEXTURE_SAMPLE],
};

/// Frequency analysis (004 §IV.3): one-bounce bandwidth of a distant light, the n_b
/// directions, BRDF bandwidth cells.
pub const FREQUENCY: Module = Module {
    name: "frequency",
    source: Source::File(include_str!("wgsl/frequency.wgsl")),
    deps: &[&TYPES],
};

/// A distant environment light: bilinear equirect radiance, importance sampling by texels and
/// its density, read through the pass's `env_texel` and `env_table`.
pub const ENV_LIGHT: Module = Module {
    name: "env_light",
    source: Source::File(include_str!("wgsl/env_light.wgsl")),
    deps: &[&TYPES],
};

/// Cube-map pyramids in storage buffers: face coordinates, edge-crossing fetches, bilinear and
/// trilinear lookups, read through the pass's `cube_texel`, `cube_level` and `cube_ring`.
pub const CUBE_STORAGE: Module = Module {
    name: "cube_storage",
    source: Source::File(include_str!("wgsl/cube_storage.wgsl")),
    deps: &[],
};

/// Textured parallelogram emitters: the record, a point, the texel of a point.
pub const AREA_LIGHT: Module = Module {
    name: "area_light",
    source: Source::File(include_str!("wgsl/area_light.wgsl")),
    deps: &[],
};

/// The functions a binding-free module may ask its pass to define (its `Requires` lines).
pub const PASS_PROVIDED: [&str; 9] = [
    "bsdf_table",
    "texture_texel",
    "texture_info",
    "material_row",
    "env_texel",
    "env_table",
    "cube_texel",
    "cube_level",
    "cube_ring",
];

/// Every module, in an order [`compose`] would emit them.
pub const ALL: [&Module; 40] = [
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
    &GLOSSY_DIFFUSE,
    &SHEEN,
    &material::kinds::RECORD,
    &material::textured::PARAMS,
    &material::rough_conductor::MODULE,
    &material::rough_plastic::MODULE,
    &material::rough_dielectric::MODULE,
    &material::conductor::MODULE,
    &material::thin_dielectric::MODULE,
    &material::pbr_metallic_roughness::MODULE,
    &material::lambert::MODULE,
    &material::plastic::MODULE,
    &material::dielectric::MODULE,
    &MIXTURE,
    &material::cook_torrance::MODULE,
    &material::sgd::MODULE,
    &material::kurt::MODULE,
    &material::kinds::BSDF,
    &material::analytic::MODULE,
    &material::kinds::ANALYTIC,
    &material::kinds::TEXTURED,
    &crate::material::measured::MEASURED,
    &FREQUENCY,
    &ENV_LIGHT,
    &CUBE_STORAGE,
    &AREA_LIGHT,
    &TEXTURE_SAMPLE,
    &MATERIAL_ALBEDO,
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
        let text = m.text();
        out.push_str(&text);
        if !text.ends_with('\n') {
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

/// `src` parsed and validated by naga, or a panic showing naga's message on the source (the
/// unit tests' check of composed WGSL).
#[cfg(test)]
pub(crate) fn validated(src: &str) -> wgpu::naga::Module {
    use wgpu::naga;
    let m =
        naga::front::wgsl::parse_str(src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(src)));
    let mut v = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    );
    if let Err(e) = v.validate(&m) {
        panic!("{}", e.emit_to_string(src));
    }
    m
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

    /// Every module that calls a pass-provided function says so in its header, with the
    /// signature, and names nothing it does not call.
    #[test]
    fn module_contracts_are_written_in_their_headers() {
        for m in ALL {
            let text = m.text();
            let header: Vec<&str> = text.lines().take_while(|l| l.starts_with("//")).collect();
            for f in PASS_PROVIDED {
                let calls = text
                    .lines()
                    .filter(|l| !l.trim_start().starts_with("//"))
                    .any(|l| l.contains(&format!("{f}(")));
                let declared = header.iter().any(|l| {
                    l.starts_with("// Requires (the pass defines): ")
                        && l.contains(&format!("fn {f}("))
                });
                assert_eq!(calls, declared, "{}: {f}", m.name);
            }
        }
    }

    #[test]
    fn module_names_are_unique_and_match_their_files() {
        for (i, a) in ALL.iter().enumerate() {
            assert!(ALL[i + 1..].iter().all(|b| b.name != a.name), "{}", a.name);
            // The header names the module.
            let text = a.text();
            let first = text.lines().next().unwrap_or("");
            assert!(
                first.starts_with(&format!("// module {}:", a.name)),
                "{first}"
            );
        }
    }
}
