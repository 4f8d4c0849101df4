//! Side tables of the measured BRDFs the GPU evaluates and samples (`measured.wgsl`, read
//! through a pass's `bsdf_table`): a MERL table's stored values, a neural BRDF's weights, an RGL
//! tensor's tables, an ALTA table's samples per search node, and the tabulated CDFs of
//! [`lustre_brdf::tabulated::TabulatedSampler`].

use crate::bindings::{compute_pipeline, storage_entry};
use crate::context::GpuContext;
use crate::error::{invalid, Result};
use crate::material::analytic::pack_analytic;
use crate::material::fitted::pack_fit;
use crate::material::kinds::{record_sampling, ANALYTIC, BSDF, TEXTURED};
use crate::material::{
    pack_material, pack_material_params, GpuBsdf, FLAG_TEXTURED, FLAG_TWO_SIDED, KIND_OREN_NAYAR,
    MATERIAL_PARAMS,
};
use crate::passes::gbuffer::{pack_textures, PackedTextures};
use crate::wgsl::{compose, Module, Source, BSDF_SAMPLE, FRESNEL, TEXTURE_SAMPLE, TYPES};
use lustre_brdf::measured::alta::{
    alta_grid_cells, AltaTable, AltaUnit, ALTA_CELL, ALTA_COS_FLOOR, ALTA_HALF_EXTENT, ALTA_SPLIT,
};
use lustre_brdf::measured::merl::{MerlTable, BINS, RES_PHI_D, RES_THETA_D, RES_THETA_H};
use lustre_brdf::measured::nbrdf::Nbrdf;
use lustre_brdf::measured::rgl::RglBsdf;
use lustre_brdf::measured::rgl_warp::Marginal2D;
use lustre_brdf::tabulated::TabulatedSampler;
use lustre_brdf::Bsdf;
use lustre_scene::{Material, MaterialKind, Scene};

/// The materials of a pass that evaluates any BRDF it takes through its `material_eval`: the
/// measured BRDFs' words (read through `bsdf_table`) and the records of bsdf.wgsl and
/// analytic.wgsl ([`EVAL_RECORD`], `base` indexing them, evaluated by `record_eval`): the fitted models
/// (`material::fitted::pack_fit`), the scene's materials (`material::pack_material`, textured ones
/// with their [`pack_material_params`] rows and textures) and every reflection model a scene
/// material's spec resolves to (`material::analytic::pack_analytic`).
#[derive(Default)]
pub struct PackedBrdfs {
    /// The measured BRDFs' words, and the analytic models' side tables.
    pub table: Vec<f32>,
    /// The records of bsdf.wgsl and analytic.wgsl.
    pub fitted: Vec<GpuBsdf>,
    /// Per record of `fitted`: its textured parameters ([`pack_material_params`]), read where
    /// the record is flagged [`FLAG_TEXTURED`] (zeros otherwise).
    pub params: Vec<[[f32; 4]; MATERIAL_PARAMS]>,
    /// The scene's textures those rows read, in slot order.
    pub slots: Vec<usize>,
}

/// `material_eval`'s source of a material (its `kind` word in the adaptive and bandwidth
/// passes): a neural BRDF.
pub const EVAL_NBRDF: u32 = 0;
/// A MERL table.
pub const EVAL_MERL: u32 = 1;
/// A record of [`crate::material`] (a fitted or an analytic model, a scene material).
pub const EVAL_RECORD: u32 = 2;
/// An RGL tensor.
pub const EVAL_RGL: u32 = 3;
/// An ALTA goniometric table.
pub const EVAL_ALTA: u32 = 4;

/// Measured BRDFs: MERL tables (trilinear, missing bins left out) and tabulated-CDF importance
/// sampling (004 §IV.4.3), read from the pass's `bsdf_table`; the [`EVAL_NBRDF`] … constants
/// generated after `measured.wgsl`'s text.
pub const MEASURED: Module = Module {
    name: "measured",
    source: Source::Generated(measured_source),
    deps: &[&TYPES, &FRESNEL],
};

fn measured_source() -> String {
    let mut s = include_str!("measured.wgsl").to_string();
    s += "\n// material_eval's sources (lustre_gpu::material::measured::EVAL_*).\n";
    for (name, code) in [
        ("EVAL_NBRDF", EVAL_NBRDF),
        ("EVAL_MERL", EVAL_MERL),
        ("EVAL_RECORD", EVAL_RECORD),
        ("EVAL_RGL", EVAL_RGL),
        ("EVAL_ALTA", EVAL_ALTA),
    ] {
        s += &format!("const {name}: u32 = {code}u;\n");
    }
    s
}

impl PackedBrdfs {
    /// Appends `b`, the BSDF of the scene material `material` of `scene` when known; returns
    /// (kind, first word or record, MERL node offset). Without the scene only measured BRDFs
    /// and fitted models are taken (an analytic model's parameters may be textured: only the
    /// scene material says). A textured material's parameters are read per pixel at the
    /// G-buffer's uv (`material_prepare`); a normal map needs nothing here: the G-buffer's
    /// shading frame is already tilted by it (`PathTracer::shading_point`). Errors (naming the
    /// model, and the material and its spec when known): a model without a GPU twin
    /// ([`EVALUATED`] lists those with one).
    pub fn push(
        &mut self,
        b: &dyn Bsdf,
        material: Option<(&Scene, &Material)>,
    ) -> Result<(u32, u32, f32)> {
        if let Some(brdf) = MeasuredBrdf::of(b) {
            return Ok(brdf.pack(&mut self.table));
        }
        let fit = pack_fit(b);
        let mut params = [[0.0f32; 4]; MATERIAL_PARAMS];
        let record = match (fit, material) {
            (Ok((kind, p)), _) => GpuBsdf {
                kind,
                flags: 0,
                pad0: 0,
                pad1: 0,
                p,
            },
            (Err(e), None) => {
                return Err(invalid(
                    b.name(),
                    format!(
                        "{e}; without the scene's materials the GPU takes measured and fitted \
                         models only"
                    ),
                ))
            }
            (Err(_), Some((scene, m))) => {
                let name = format!("material {:?}", m.name);
                if let MaterialKind::Spec(s) = &m.kind {
                    pack_analytic(b, &mut self.table)
                        .map_err(|e| invalid(name, format!("spec {:?}: {e}", s.spec)))?
                } else if let MaterialKind::Dielectric { .. } = &m.kind {
                    // Smooth glass as the CPU shades it (the walkthrough's frame takes it as a
                    // thin sheet instead: `pack_material`).
                    pack_analytic(b, &mut self.table).map_err(|e| invalid(name, e.to_string()))?
                } else {
                    let mut rec = pack_material(m, &mut self.table)?;
                    if rec.flags & FLAG_TEXTURED != 0 {
                        params = pack_material_params(scene, m, &mut self.slots)?;
                    }
                    // Two-sided as the CPU wraps it (`TwoSided`): reflection-only models.
                    if b.flags().transmission {
                        rec.flags &= !FLAG_TWO_SIDED;
                    }
                    rec
                }
            }
        };
        self.fitted.push(record);
        self.params.push(params);
        Ok((EVAL_RECORD, (self.fitted.len() - 1) as u32, 0.0))
    }

    /// The records' parameter rows, one zero row when there is none (a binding may not be
    /// empty).
    pub fn params_or_zero(&self) -> Vec<[f32; 4]> {
        let mut rows: Vec<[f32; 4]> = self.params.iter().flatten().copied().collect();
        if rows.is_empty() {
            rows.push([0.0; 4]);
        }
        rows
    }

    /// The texels of the textures the parameter rows read ([`crate::passes::gbuffer`]'s
    /// `pack_textures`; one dummy texel when none), and per texture (first texel, width,
    /// height, 0). Errors: more texels than a binding of `limit` bytes holds.
    pub(crate) fn textures(&self, scene: Option<&Scene>, limit: usize) -> Result<PackedTextures> {
        match scene {
            Some(scene) => pack_textures(scene, &self.slots, limit),
            None => Ok((vec![[0.0; 4]], vec![[0; 4]])),
        }
    }

    /// The table's words, one zero word when there is none (a binding may not be empty: a
    /// scene of analytic models alone may need no table).
    pub fn table_or_zero(&self) -> Vec<f32> {
        if self.table.is_empty() {
            vec![0.0]
        } else {
            self.table.clone()
        }
    }

    /// The records, one zero record when there is none (a binding may not be empty).
    pub fn fitted_or_zero(&self) -> Vec<GpuBsdf> {
        if self.fitted.is_empty() {
            vec![bytemuck::Zeroable::zeroed()]
        } else {
            self.fitted.clone()
        }
    }
}

/// What the passes that take any material evaluate: neural BRDFs, MERL tables (a `.binary`
/// file), RGL tensors (a `.bsdf` file), ALTA goniometric tables (a `.dat` file), fitted models
/// (SGD, Cook–Torrance, Kurt) and, given the scene, its materials (textured ones read at each
/// pixel's uv, normal-mapped ones in the G-buffer's tilted frame) and every reflection model of
/// a spec (`lambert`, `oren-nayar`, `phong`, `blinn-phong`, `ward`, `ward-duer`, `ward-gmd`,
/// `lafortune` and the `lafortune:` fits, `ashikhmin-shirley`, `abc` and the `abc:` fits, every
/// Cook–Torrance (`exponential`, `sgd` and `sgd-numeric:` with the numeric Smith G1, mixed
/// distributions), the conductors, plastics, dielectrics and `pbr`, each also `twosided:`).
pub const EVALUATED: &str = "neural BRDFs (nbrdf:…), MERL tables (a .binary file), RGL tensors \
    (a .bsdf file), ALTA goniometric tables (a .dat file), fitted models (SGD, Cook–Torrance, \
    Kurt) and, given the scene, its reflection materials (textured and normal-mapped ones too) \
    and the analytic models of a spec (Lambert, Oren–Nayar, Phong, Blinn–Phong, Ward and its \
    variants, Lafortune, Ashikhmin–Shirley, ABC, any Cook–Torrance, conductors, plastics, \
    dielectrics, glTF metallic-roughness, two-sided or not)";

/// A measured BRDF the GPU evaluates directly (`measured_eval` of `wgsl/measured.wgsl`).
#[derive(Clone, Copy, Debug)]
pub enum MeasuredBrdf<'a> {
    /// A neural BRDF ([`EVAL_NBRDF`]).
    Nbrdf(&'a Nbrdf),
    /// A MERL table ([`EVAL_MERL`]).
    Merl(&'a MerlTable),
    /// An RGL tensor ([`EVAL_RGL`]).
    Rgl(&'a RglBsdf),
    /// An ALTA goniometric table ([`EVAL_ALTA`]).
    Alta(&'a AltaTable),
}

impl<'a> MeasuredBrdf<'a> {
    /// The measured BRDF behind `b` (also inside a `TwoSided` wrapper: the passes' G-buffers
    /// turn a two-sided surface's frame towards the viewer, so ωo is above it), or `None` for
    /// any other model.
    pub fn of(b: &'a dyn Bsdf) -> Option<Self> {
        let any = b.as_any()?;
        if let Some(inner) = crate::material::analytic::two_sided_inner(any) {
            return Self::of(inner);
        }
        if let Some(n) = any.downcast_ref::<Nbrdf>() {
            return Some(Self::Nbrdf(n));
        }
        if let Some(m) = any.downcast_ref::<MerlTable>() {
            return Some(Self::Merl(m));
        }
        if let Some(a) = any.downcast_ref::<AltaTable>() {
            return Some(Self::Alta(a));
        }
        any.downcast_ref::<RglBsdf>().map(Self::Rgl)
    }

    /// Appends its words to `table`; returns `measured_eval`'s (kind, first word, node offset).
    pub fn pack(&self, table: &mut Vec<f32>) -> (u32, u32, f32) {
        let base = table.len() as u32;
        match self {
            Self::Nbrdf(n) => {
                table.extend(pack_nbrdf(n));
                (EVAL_NBRDF, base, 0.0)
            }
            Self::Merl(m) => {
                table.extend(pack_merl(m));
                (EVAL_MERL, base, m.convention().offset() as f32)
            }
            Self::Rgl(r) => {
                table.extend(pack_rgl(r));
                (EVAL_RGL, base, 0.0)
            }
            Self::Alta(a) => {
                table.extend(pack_alta(a));
                (EVAL_ALTA, base, 0.0)
            }
        }
    }
}

/// The words of an ALTA table for `alta_eval`: an 8-word header (slice count, 1 when the values
/// are cosine-weighted, the search grid's cells per axis, cell size, half extent, the cos θv
/// floor, two pads), per slice 4 words (θl, the first words of its nodes and of its candidates,
/// counted from the record's start, a pad), then per slice its nodes (first, count; a split
/// node's count −1 and first its first child) and its candidates (x, y, value)
/// (`AltaTable::candidates`: every sample that can be among the 6 nearest of a point in a leaf,
/// so the GPU searches one short list instead of the CPU's rings). Counts and offsets are f32
/// values (exact below 2²⁴).
pub fn pack_alta(t: &AltaTable) -> Vec<f32> {
    let slices = t.candidates();
    let mut out = vec![
        slices.len() as f32,
        f32::from(u8::from(t.unit() == AltaUnit::InvSteradianCosineFactor)),
        alta_grid_cells() as f32,
        ALTA_CELL as f32,
        ALTA_HALF_EXTENT as f32,
        ALTA_COS_FLOOR as f32,
        0.0,
        0.0,
    ];
    let heads = out.len();
    out.resize(heads + 4 * slices.len(), 0.0);
    for (k, s) in slices.iter().enumerate() {
        out[heads + 4 * k] = s.theta_l as f32;
        out[heads + 4 * k + 1] = out.len() as f32;
        out.extend(s.nodes.iter().flat_map(|&[first, count]| {
            let count = if count == ALTA_SPLIT {
                -1.0
            } else {
                count as f32
            };
            [first as f32, count]
        }));
        out[heads + 4 * k + 2] = out.len() as f32;
        out.extend(s.points.iter().flat_map(|p| p.map(|v| v as f32)));
    }
    out
}

/// The words of a MERL table for `merl_lookup`: its 3 × 90·90·180 stored values (unscaled,
/// channel-major, bin (i, j, k) at `k + 180·(j + 90·i)`), a missing bin as −1.
pub fn pack_merl(table: &MerlTable) -> Vec<f32> {
    let mut out = Vec::with_capacity(3 * BINS);
    for c in 0..3 {
        for i in 0..RES_THETA_H {
            for j in 0..RES_THETA_D {
                for k in 0..RES_PHI_D {
                    out.push(if table.is_missing(c, i, j, k) {
                        -1.0
                    } else {
                        table.stored(c, i, j, k) as f32
                    });
                }
            }
        }
    }
    out
}

/// The words of a neural BRDF for `nbrdf_eval`: its 6-21-21-3 network's parameters in
/// [`Nbrdf::parameters`]' order (w1, b1, w2, b2, w3, b3), 675 of them.
pub fn pack_nbrdf(net: &Nbrdf) -> Vec<f32> {
    net.parameters().iter().map(|&v| v as f32).collect()
}

/// The words of an RGL tensor for `rgl_eval`: a 16-word header (isotropic, the Jacobian flag,
/// the symmetry reduction, then at words 4–8 the offsets from the record's start of its five
/// tables: NDF, σ, VNDF, luminance, RGB), then each table as [`pack_marginal`] lays it out.
/// Counts and offsets are stored as f32 values (exact: a record is far below 2²⁴ words).
pub fn pack_rgl(r: &RglBsdf) -> Vec<f32> {
    let mut out = vec![0.0f32; 16];
    out[0] = f32::from(u8::from(r.is_isotropic()));
    out[1] = f32::from(u8::from(r.jacobian()));
    out[2] = r.reduction() as f32;
    for (k, m) in r.tables().iter().enumerate() {
        out[4 + k] = out.len() as f32;
        out.extend(pack_marginal(m));
    }
    out
}

/// The words of a [`Marginal2D`] for `m2d_load`: a 20-word header (w, h, parameter count,
/// normalized; node counts at 4–6, slice strides at 8–10, the offsets of each parameter's nodes
/// at 12–14, of the values, the marginal and the conditional CDFs at 16–18, all from the
/// block's start), then those arrays.
pub fn pack_marginal(m: &Marginal2D) -> Vec<f32> {
    let (w, h) = m.size();
    let mut out = vec![0.0f32; 20];
    out[0] = w as f32;
    out[1] = h as f32;
    out[2] = m.params().len() as f32;
    out[3] = f32::from(u8::from(m.is_normalized()));
    for (k, (nodes, stride)) in m.params().iter().zip(m.strides()).enumerate() {
        out[4 + k] = nodes.len() as f32;
        out[8 + k] = *stride as f32;
        out[12 + k] = out.len() as f32;
        out.extend(nodes.iter().map(|&v| v as f32));
    }
    for (slot, values) in [m.data(), m.marginal_cdf(), m.conditional_cdf()]
        .into_iter()
        .enumerate()
    {
        out[16 + slot] = out.len() as f32;
        out.extend(values.iter().map(|&v| v as f32));
    }
    out
}

/// `TabulatedDims` of `measured.wgsl`: the sampler's bins and defensive fraction.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTabulatedDims {
    /// View elevation bins.
    pub view_bins: u32,
    /// View azimuth bins per elevation of an anisotropic BRDF's tables (unfolded, φ over
    /// [0, 2π)); 0 for an isotropic BRDF's (one per elevation, φ folded onto [0, π]).
    pub azimuth_bins: u32,
    /// θi cells.
    pub theta_bins: u32,
    /// φ cells of a table.
    pub phi_cells: u32,
    /// The cosine-sampled fraction ε.
    pub defensive: f32,
}

/// The words of a tabulated sampler for `tabulated_sample` / `tabulated_pdf`, and its layout:
/// per table (view elevation, and azimuth when anisotropic, azimuth inner), the `cells + 1`
/// cumulative weights over the table's total (0 … 1; all 0 for a black table), then the
/// `cells` weights over the total (computed in f64, so a cell's density does not come from the
/// difference of two f32 sums).
pub fn pack_tabulated(sampler: &TabulatedSampler) -> (Vec<f32>, GpuTabulatedDims) {
    let o = sampler.options();
    let cells = o.theta_bins * sampler.phi_cells();
    let cdf = sampler.cumulative();
    let mut out = Vec::with_capacity(sampler.table_count() * (2 * cells + 1));
    for table in cdf.chunks_exact(cells + 1) {
        let total = table[cells];
        let norm = if total > 0.0 { 1.0 / total } else { 0.0 };
        out.extend(table.iter().map(|&v| (v * norm) as f32));
        out.extend(table.windows(2).map(|w| ((w[1] - w[0]) * norm) as f32));
    }
    let dims = GpuTabulatedDims {
        view_bins: o.view_bins as u32,
        azimuth_bins: if sampler.is_anisotropic() {
            o.azimuth_bins as u32
        } else {
            0
        },
        theta_bins: o.theta_bins as u32,
        phi_cells: sampler.phi_cells() as u32,
        defensive: o.defensive as f32,
    };
    (out, dims)
}

/// Which `material_eval` a pass compiles ([`MaterialPipelines`]' variants): the leanest that
/// evaluates every material of the scene (llvmpipe compiles every model a variant imports into
/// the pass).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Evaluates {
    /// Measured BRDFs only: the records are bound but unread.
    Measured = 0,
    /// bsdf.wgsl's records too (`bsdf_eval`): fitted models, the scene's materials and the
    /// specs of bsdf.wgsl's models. A two-sided record is evaluated as its model: the same
    /// wherever ωo lies above the surface, which is where these passes evaluate a two-sided
    /// material (the G-buffer turns its frame towards the viewer, `lustre_adaptive::gbuffer`).
    Records = 1,
    /// analytic.wgsl's records too (`record_eval`, which also mirrors a two-sided record seen
    /// from below, as `TwoSided::eval` does).
    Analytic = 2,
}

impl PackedBrdfs {
    /// The variant that evaluates these materials.
    pub(crate) fn evaluates(&self) -> Evaluates {
        if self.fitted.is_empty() {
            Evaluates::Measured
        } else if self.fitted.iter().any(|r| r.kind >= KIND_OREN_NAYAR) {
            Evaluates::Analytic
        } else {
            Evaluates::Records
        }
    }
}

/// `material_prepare(kind, base, uv)` and `material_eval(kind, base, offset, wi, wo)` for a
/// pass, with its `fitted` records at `binding` and, at `textures`, `textures + 1` and
/// `textures + 2`, the records' parameter rows ([`PackedBrdfs::params`]), the texels and the
/// per-texture offsets and sizes (`texture_sample.wgsl`). A pass calls `material_prepare` once
/// per pixel (its material, the G-buffer's uv): [`EVAL_RECORD`] copies record `base` into the pixel's
/// record, with its textured parameters at uv where it is flagged FLAG_TEXTURED
/// (`textured_bsdf`, as `frame_shade.wgsl` and the CPU's `Material::with_bsdf_at` with
/// [uv; 2]); `material_eval` then evaluates that record by bsdf.wgsl's `bsdf_eval`
/// ([`Evaluates::Records`]) or analytic.wgsl's `record_eval` ([`Evaluates::Analytic`]). With
/// [`Evaluates::Measured`] the records and textures are bound but unread and only measured
/// BRDFs are evaluated.
fn material_eval_source(binding: u32, textures: u32, evaluates: Evaluates, samples: u32) -> String {
    let record = match evaluates {
        Evaluates::Measured => {
            return format!(
                "// No fitted model among the materials: the records are bound but unread.\n\
                 @group(0) @binding({binding}) var<storage, read> fitted: array<vec4<f32>>;\n\n\
                 fn material_prepare(kind: u32, base: u32, uv: vec2<f32>) {{}}\n\n\
                 fn material_eval(kind: u32, base: u32, offset: f32, wi: vec3<f32>,\n                 \
                 wo: vec3<f32>) -> vec3<f32> {{\n    \
                 return measured_eval(kind, base, offset, wi, wo);\n}}\n\n\
                 {NO_SAMPLING}"
            )
        }
        Evaluates::Records => "bsdf_eval",
        Evaluates::Analytic => "record_eval",
    };
    let (params, texels, info) = (textures, textures + 1, textures + 2);
    format!(
        "@group(0) @binding({binding}) var<storage, read> fitted: array<GpuBsdf>;\n\
         @group(0) @binding({params}) var<storage, read> material_params: array<vec4<f32>>;\n\
         @group(0) @binding({texels}) var<storage, read> texels: array<vec4<f32>>;\n\
         @group(0) @binding({info}) var<storage, read> tex_info: array<vec4<u32>>;\n\n\
         fn texture_texel(i: u32) -> vec4<f32> {{\n    return texels[i];\n}}\n\n\
         fn texture_info(t: u32) -> vec4<u32> {{\n    return tex_info[t];\n}}\n\n\
         // The pixel's record (material_prepare).\n\
         var<private> prepared: GpuBsdf;\n\n\
         fn material_prepare(kind: u32, base: u32, uv: vec2<f32>) {{\n    \
         if (kind != EVAL_RECORD) {{\n        return;\n    }}\n    \
         var b = fitted[base];\n    \
         if ((b.flags & FLAG_TEXTURED) != 0u) {{\n        \
         let q = {MATERIAL_PARAMS}u * base;\n        \
         let c = material_params[q];\n        \
         var rgb = c.xyz;\n        \
         if (bitcast<i32>(c.w) >= 0) {{\n            \
         rgb = c.xyz * texture_sample(bitcast<u32>(c.w), uv).xyz;\n        }}\n        \
         let s = vec3<f32>(scalar_at(material_params[q + 1u], uv, uv),\n                          \
         scalar_at(material_params[q + 2u], uv, uv),\n                          \
         scalar_at(material_params[q + 3u], uv, uv));\n        \
         b = textured_bsdf(b, rgb, s);\n    }}\n    \
         prepared = b;\n}}\n\n\
         fn material_eval(kind: u32, base: u32, offset: f32, wi: vec3<f32>,\n                 \
         wo: vec3<f32>) -> vec3<f32> {{\n    \
         if (kind == EVAL_RECORD) {{\n        return {record}(prepared, wi, wo);\n    }}\n    \
         return measured_eval(kind, base, offset, wi, wo);\n}}\n\n\
         {}",
        if samples != 0 {
            material_sampling(samples)
        } else {
            NO_SAMPLING.to_string()
        }
    )
}

/// `material_sample` / `material_pdf` of a variant with materials that have no tabulated CDFs
/// (transmissive or Dirac), of the record kinds in the bit mask `kinds`: the prepared record's
/// own sampling and density, as bsdf.wgsl's `bsdf_sample` / `bsdf_pdf` but with only those
/// kinds' cases, so that llvmpipe compiles only their sampling (every model's took it ≈ 62 s
/// more).
fn material_sampling(kinds: u32) -> String {
    let (sample, pdf) = record_sampling(kinds);
    format!(
        "// The prepared record's own sampling and density (the generated dispatch's, for the record \
         kinds of this scene's\n\
         // materials without tabulated CDFs: transmissive or Dirac); a two-sided record seen \
         from below\n\
         // samples its model mirrored (TwoSided::sample, TwoSided::pdf).\n\
         const MATERIAL_SAMPLES: bool = true;\n\n\
         {sample}\n\
         {pdf}\n\
         fn material_sample(wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {{\n    \
         if ((prepared.flags & FLAG_TWO_SIDED) != 0u && wo.z < 0.0) {{\n        \
         var s = record_sample(prepared, vec3<f32>(wo.xy, -wo.z), u);\n        \
         s.wi.z = -s.wi.z;\n        \
         return s;\n    }}\n    \
         return record_sample(prepared, wo, u);\n}}\n\n\
         fn material_pdf(wi: vec3<f32>, wo: vec3<f32>) -> f32 {{\n    \
         if ((prepared.flags & FLAG_TWO_SIDED) != 0u && wo.z < 0.0) {{\n        \
         return record_pdf(prepared, vec3<f32>(wi.xy, -wi.z), vec3<f32>(wo.xy, -wo.z));\n    \
         }}\n    \
         return record_pdf(prepared, wi, wo);\n}}\n\n"
    )
}

/// `material_sample` / `material_pdf` of a variant whose materials all have tabulated CDFs:
/// never called (`MATERIAL_SAMPLES` false folds their branches away), so that no model's
/// sampling is compiled into the pass.
const NO_SAMPLING: &str = "// Every material is sampled by its tabulated CDFs, never by these.\n\
     const MATERIAL_SAMPLES: bool = false;\n\n\
     fn material_sample(wo: vec3<f32>, u: vec2<f32>) -> BsdfSample {\n    \
     return no_sample();\n}\n\n\
     fn material_pdf(wi: vec3<f32>, wo: vec3<f32>) -> f32 {\n    \
     return 0.0;\n}\n\n";

/// A pass that evaluates its materials through `material_eval`, compiled in variants
/// ([`Evaluates`]): for measured BRDFs only (at once), with bsdf.wgsl's records and with
/// analytic.wgsl's too (each on first need), the latter two without or with the records' own
/// sampling for the record kinds of the scene's materials without tabulated CDFs
/// (`material_sample`; every model's sampling took llvmpipe ≈ 40–50 s more to compile).
pub(crate) struct MaterialPipelines {
    label: &'static str,
    imports: Vec<&'static Module>,
    pass: &'static str,
    binding: u32,
    textures: u32,
    entries: Vec<wgpu::BindGroupLayoutEntry>,
    /// Per [`Evaluates`] and mask of the record kinds sampled by their own models, as compiled.
    compiled: Vec<(
        (Evaluates, u32),
        (wgpu::ComputePipeline, wgpu::BindGroupLayout),
    )>,
}

impl MaterialPipelines {
    /// Compiles the measured-only variant of `pass` (its `fitted` records at `binding`, the
    /// records' parameter rows and textures at `textures` … `textures + 2`, added to the
    /// pass's `entries`; the modules `imports` besides measured.wgsl).
    pub(crate) fn new(
        ctx: &GpuContext,
        label: &'static str,
        imports: &[&'static Module],
        pass: &'static str,
        (binding, textures): (u32, u32),
        mut entries: Vec<wgpu::BindGroupLayoutEntry>,
    ) -> Result<Self> {
        entries.extend((textures..textures + 3).map(|b| storage_entry(b, true)));
        let mut p = Self {
            label,
            imports: imports.to_vec(),
            pass,
            binding,
            textures,
            entries,
            compiled: Default::default(),
        };
        p.get(ctx, Evaluates::Measured, 0)?;
        Ok(p)
    }

    /// The variant that evaluates `evaluates`, with `material_sample` / `material_pdf` sampling
    /// the prepared record by its own model for the record kinds in the bit mask `samples`
    /// (materials without tabulated CDFs, [`sampled_kinds`]; 0: none; measured-only variants
    /// never sample records).
    pub(crate) fn get(
        &mut self,
        ctx: &GpuContext,
        evaluates: Evaluates,
        samples: u32,
    ) -> Result<&(wgpu::ComputePipeline, wgpu::BindGroupLayout)> {
        let samples = if evaluates == Evaluates::Measured {
            0
        } else {
            samples
        };
        let key = (evaluates, samples);
        let at = match self.compiled.iter().position(|(k, _)| *k == key) {
            Some(at) => at,
            None => {
                let mut imports = self.imports.clone();
                imports.push(&MEASURED);
                match evaluates {
                    Evaluates::Measured => imports.push(&BSDF_SAMPLE),
                    Evaluates::Records => imports.extend([&BSDF, &TEXTURED, &TEXTURE_SAMPLE]),
                    Evaluates::Analytic => imports.extend([&ANALYTIC, &TEXTURED, &TEXTURE_SAMPLE]),
                }
                let src = compose(
                    &imports,
                    &(material_eval_source(self.binding, self.textures, evaluates, samples)
                        + self.pass),
                );
                let compiled = compute_pipeline(ctx, self.label, self.label, &src, &self.entries)?;
                self.compiled.push((key, compiled));
                self.compiled.len() - 1
            }
        };
        Ok(&self.compiled[at].1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::kinds::{all_sampled, sampled_kinds, KINDS, KIND_PBR_METALLIC_ROUGHNESS};
    use crate::wgsl::compose;
    use lustre_brdf::measured::alta::{ALTA_MAX_DEPTH, NEIGHBOURS};
    use wgpu::naga;

    #[test]
    fn alta_eval_walks_as_deep_and_keeps_as_many_as_the_cpu() {
        for c in [
            format!("const ALTA_MAX_DEPTH: u32 = {ALTA_MAX_DEPTH}u;"),
            format!("const ALTA_NEIGHBOURS: u32 = {NEIGHBOURS}u;"),
        ] {
            assert!(MEASURED.text().contains(&c), "{c}");
        }
        assert!(MEASURED
            .text()
            .contains("var d = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);"));
    }

    /// Every sampling variant parses and validates: each record kind alone, a glTF record's
    /// three, all of them; and a glTF record's mask holds the dielectrics it may turn into.
    #[test]
    fn sampling_variants_validate() {
        let all = all_sampled();
        let masks = KINDS
            .iter()
            .filter(|k| all & (1 << k.code) != 0)
            .map(|k| 1 << k.code)
            .chain([sampled_kinds(KIND_PBR_METALLIC_ROUGHNESS), all, 0]);
        for mask in masks {
            for (evaluates, module) in [
                (Evaluates::Records, &BSDF),
                (Evaluates::Analytic, &ANALYTIC),
            ] {
                let pass = material_eval_source(0, 1, evaluates, mask)
                    + "@group(0) @binding(5) var<storage, read> table: array<f32>;\n\
                       fn bsdf_table(i: u32) -> f32 {\n    return table[i];\n}\n\
                       @compute @workgroup_size(1)\nfn main() {\n    \
                       material_prepare(2u, 0u, vec2<f32>(0.5));\n    \
                       let s = material_sample(vec3<f32>(0.0, 0.0, 1.0), vec2<f32>(0.5));\n    \
                       let p = material_pdf(s.wi, vec3<f32>(0.0, 0.0, 1.0));\n}\n";
                let src = compose(&[&MEASURED, module, &TEXTURED, &TEXTURE_SAMPLE], &pass);
                let m = naga::front::wgsl::parse_str(&src)
                    .unwrap_or_else(|e| panic!("mask {mask:#x}: {}", e.emit_to_string(&src)));
                let mut v = naga::valid::Validator::new(
                    naga::valid::ValidationFlags::all(),
                    naga::valid::Capabilities::empty(),
                );
                if let Err(e) = v.validate(&m) {
                    panic!("mask {mask:#x}: {}", e.emit_to_string(&src));
                }
                assert_eq!(
                    src.contains("const MATERIAL_SAMPLES: bool = true;"),
                    mask != 0
                );
            }
        }
    }
}
