//! Light-map baking: per-texel irradiance from the path tracer (000 §4.3: the real-time
//! renderer shades diffuse light as Lo = kd·E/π, Eq. 4.1, from these maps).
//!
//! Stages, one file each:
//! - [`raster`]: which light-mapped triangles cover each texel of a page (conservatively, in uv1
//!   space), the chart of each texel, and the supersample points spread over a texel's footprint
//!   (stratified, seeded by a hash of (seed, page, x, y, sample)).
//! - [`trace`]: per sample point, a validity test (leak-proof origins) and one path of
//!   [`PathTracer::irradiance`](crate::path_tracer::PathTracer::irradiance); per texel the mean, the
//!   variance of the mean and the guides (position, normal, albedo).
//! - [`tile`]: deterministic tiles of [`BakeOptions::tile`]² texels, written atomically to
//!   `OUT/tiles/` with a header (format, scene/options hash, rectangle) and a CRC; a bake
//!   resumes from the tiles on disk and re-bakes (with a warning naming the file) a corrupt or
//!   mismatched one.
//! - [`fill`]: buried texels (every sample invalid) filled from valid neighbours of the same
//!   chart; charts dilated into their gutters.
//! - [`denoise`]: the edge-aware à-trous filter ([`Denoiser`]).
//! - [`output`]: half-float RGB EXR per page, the JSON report.
//!
//! **What is baked.** E is the irradiance on the front side (the shading normal's side) of the
//! surface, in the path tracer's units, with every bounce diffuse: each material scatters with
//! its *diffuse albedo* only ([`diffuse_albedo`]); its glossy and specular energy is dropped,
//! not redistributed (000 keeps the view-independent part of the light in the maps; the real-time
//! renderer adds the glossy part from its environment probes). Conductors and dielectrics are
//! therefore black occluders in the bake. Emitters and the environment light the scene as in
//! `lustre reference`.
//!
//! **Leaks.** A sample point is *invalid* when it lies inside or under other geometry: when at
//! least [`PROBE_BACKFACE_LIMIT`] of [`PROBES`] probe rays from it hit the back of a one-sided
//! surface, or when the segment from the texel's reference sample (the valid one nearest the
//! texel centre) to it is blocked (a wall thinner than the texel between them). Invalid samples
//! do not count; a texel without a valid sample is *buried* and filled. Ray origins are offset
//! along the geometric normal (the path tracer's rule). A sample that falls beyond its
//! triangle's edge in the atlas is snapped onto the edge and, as one within
//! [`raster::EDGE_INSET`] of an edge, moved that far (in texels) inside: on or within a hair of
//! the edge, where a wall meets a ceiling made of another mesh, its rays would start on the
//! other surface's plane and pass out through the seam (a two-sided material has no back faces
//! to reveal it).
//!
//! **Sharding.** [`bake_tiles`] bakes the tiles whose index k (pages in order, tiles row-major
//! within a page) satisfies k mod N = K for `shard = Some((K, N))`, all tiles for `None`;
//! [`assemble`] reads every tile and writes the pages, so N shards baked anywhere and merged
//! equal an unsharded bake bit for bit.

pub mod denoise;
pub mod fill;
pub mod gbuffer;
pub mod output;
pub mod raster;
pub mod render;
pub mod tile;
pub mod trace;

pub use denoise::{ATrousOptions, Denoiser};
pub use output::{assemble, Assembled, BakeReport, PageReport};
pub use tile::{bake_texels, bake_tiles, check_shard_tiles, TilesReport};

use crate::path_tracer::{PathScene, Surface};
use crate::{Result, TraceError};
use glam::{DVec3, Vec2};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::models::plastic::{CoatedBase, Plastic};
use lustre_brdf::models::rough_plastic::{RoughPlastic, RoughPlasticCoating};
use lustre_brdf::rgb::Rgb;
use lustre_scene::lightmap::LightmapAtlas;
use lustre_scene::{Material, MaterialKind, Scene, Texture};

/// Largest page side a bake accepts (the GPU texture limit the renderer relies on).
pub const MAX_PAGE_SIZE: u32 = 8192;
/// Probe rays per sample point for the validity test.
pub const PROBES: u32 = 4;
/// A sample is invalid when at least this many probes hit a back face.
pub const PROBE_BACKFACE_LIMIT: u32 = 2;

/// Settings of a bake.
#[derive(Clone, Debug, PartialEq)]
pub struct BakeOptions {
    /// Sample points (one path each) per texel, ≥ 1.
    pub spp: u32,
    /// Diffuse bounces: 1 = direct light only, B = paths of up to B reflections after the
    /// texel (the path tracer's `max_depth` = B + 1). ≥ 1.
    pub bounces: u32,
    /// Seed of every texel's sample stream.
    pub seed: u64,
    /// Tile side in texels, ≥ 1.
    pub tile: u32,
    /// The denoiser run by [`assemble`].
    pub denoiser: Denoiser,
    /// Which light transport the irradiance includes.
    pub transport: Transport,
}

/// The light transport a bake's irradiance E includes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Transport {
    /// Paths through the diffuse scene ([`diffuse_path_scene`]: every material replaced by its
    /// diffuse albedo): the image kd·E/π converges to `lustre reference --diffuse`.
    #[default]
    Diffuse,
    /// Paths through the scene's own materials: E also carries light that glossy and specular
    /// surfaces (a glossy floor, glass) reflect onto the light-mapped ones, as a walkthrough
    /// renderer that adds only the last, view-dependent bounce needs.
    Full,
}

impl Default for BakeOptions {
    fn default() -> Self {
        BakeOptions {
            spp: 256,
            bounces: 4,
            seed: 0,
            tile: 64,
            denoiser: Denoiser::ATrous(ATrousOptions::default()),
            transport: Transport::Diffuse,
        }
    }
}

impl BakeOptions {
    /// Checks the settings; errors name the absurd one.
    pub fn validate(&self) -> Result<()> {
        if self.spp == 0 || self.spp > 1 << 20 {
            return Err(TraceError::Parameter(format!(
                "--spp {} must be between 1 and {}",
                self.spp,
                1 << 20
            )));
        }
        if self.bounces == 0 || self.bounces > 64 {
            return Err(TraceError::Parameter(format!(
                "--bounces {} must be between 1 and 64",
                self.bounces
            )));
        }
        if self.tile == 0 || self.tile > MAX_PAGE_SIZE {
            return Err(TraceError::Parameter(format!(
                "tile side {} must be between 1 and {MAX_PAGE_SIZE}",
                self.tile
            )));
        }
        if let Denoiser::ATrous(a) = &self.denoiser {
            a.validate()?;
        }
        Ok(())
    }
}

/// What [`diffuse_albedo`] needs of a material beyond its parameters, computed once per
/// material by [`base_albedo`]: a catalog specification's albedo and a plastic's coating.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BaseAlbedo {
    /// A catalog specification's hemispherical albedo at normal incidence (zero for the other
    /// kinds): fitted models have no separate diffuse term at this interface, so their glossy
    /// energy is counted as diffuse there — the one exception to "glossy energy dropped".
    pub spec: Rgb,
    /// A (rough) plastic's base seen through its coating ([`CoatedBase`]); uncoated otherwise.
    pub coat: CoatedBase,
}

impl Default for BaseAlbedo {
    fn default() -> Self {
        BaseAlbedo {
            spec: Rgb::ZERO,
            coat: CoatedBase::UNCOATED,
        }
    }
}

/// The [`BaseAlbedo`] of `m`: a catalog specification's albedo at normal incidence (1024
/// stratified samples); a plastic's coated base (a rough one's at its roughness factor, a
/// textured roughness's mean not known here; uncoated where the coating is invalid).
pub fn base_albedo(m: &Material) -> BaseAlbedo {
    let mut out = BaseAlbedo::default();
    match &m.kind {
        MaterialKind::Spec(r) => {
            out.spec = r.bsdf.albedo(DVec3::Z, 1024).map(|v| {
                if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            });
        }
        MaterialKind::Plastic {
            int_ior,
            ext_ior,
            nonlinear,
            ..
        } => {
            if let Ok(p) = Plastic::new(Rgb::ZERO, Rgb::ZERO, *int_ior, *ext_ior, *nonlinear) {
                out.coat = p.coated_base();
            }
        }
        MaterialKind::RoughPlastic {
            alpha,
            distribution,
            int_ior,
            ext_ior,
            nonlinear,
            ..
        } => {
            let a = RoughPlasticCoating::clamp(alpha.factor);
            if let Ok(p) = RoughPlastic::new(
                *distribution,
                a,
                Rgb::ZERO,
                Rgb::ZERO,
                *int_ior,
                *ext_ior,
                *nonlinear,
            ) {
                out.coat = p.coated_base();
            }
        }
        _ => {}
    }
    out
}

/// The diffuse (view-independent) albedo of a material at texture coordinates `uv` (uv0, uv1),
/// the reflectance each bounce of a bake uses and the light-mapped shading's kd: `diffuse` →
/// its reflectance; (rough) plastic → its base seen through the coating
/// ([`CoatedBase::kd`]: ρ' T̄² / η², about half of ρ at η = 1.5 — what a light map can hold of
/// the base lobe; the rest of that lobe is view-dependent); glTF metallic-roughness → base
/// colour × (1 − metallic), 0 where the transmission weight is ≥ ½ (rendered as glass);
/// conductors and dielectrics → 0; a catalog specification → `base.spec` (see [`BaseAlbedo`]).
pub fn diffuse_albedo(m: &Material, textures: &[Texture], uv: &[Vec2; 2], base: BaseAlbedo) -> Rgb {
    let clamp = |c: Rgb| {
        c.map(|v| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        })
    };
    match &m.kind {
        MaterialKind::Diffuse { reflectance } => clamp(reflectance.at(textures, uv)),
        MaterialKind::Plastic { diffuse, .. } | MaterialKind::RoughPlastic { diffuse, .. } => {
            base.coat.kd(clamp(diffuse.at(textures, uv)))
        }
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            transmission,
            ..
        } => {
            if transmission.at(textures, uv) >= 0.5 {
                Rgb::ZERO
            } else {
                let k = 1.0 - metallic.at(textures, uv).clamp(0.0, 1.0);
                clamp(base_color.at(textures, uv)) * k
            }
        }
        MaterialKind::Conductor { .. }
        | MaterialKind::RoughConductor { .. }
        | MaterialKind::Dielectric { .. }
        | MaterialKind::RoughDielectric { .. }
        | MaterialKind::ThinDielectric { .. } => Rgb::ZERO,
        MaterialKind::Spec(_) => base.spec,
    }
}

/// A scene material as the bake sees it: a Lambertian of its [`diffuse_albedo`], with the
/// material's alpha mask, two-sidedness, normal map and emission texture.
struct DiffuseSurface<'s> {
    material: &'s Material,
    textures: &'s [Texture],
    base: BaseAlbedo,
}

fn uv2(uv: [f64; 2]) -> [Vec2; 2] {
    [Vec2::new(uv[0] as f32, uv[1] as f32); 2]
}

impl Surface for DiffuseSurface<'_> {
    fn with_bsdf(&self, uv: [f64; 2], f: &mut dyn FnMut(&dyn Bsdf)) {
        let kd = diffuse_albedo(self.material, self.textures, &uv2(uv), self.base);
        f(&Lambert { kd })
    }
    fn masked(&self) -> bool {
        self.material.alpha_mask.is_some()
    }
    fn opaque(&self, uv: [f64; 2]) -> bool {
        self.material.alpha_at(self.textures, &uv2(uv)) >= 0.5
    }
    fn two_sided(&self) -> bool {
        self.material.two_sided
    }
    fn normal_mapped(&self) -> bool {
        self.material.normal_map.is_some()
    }
    fn normal_map(&self, uv: [f64; 2]) -> Option<DVec3> {
        self.material.normal_map_at(self.textures, &uv2(uv))
    }
    fn emission_textured(&self) -> bool {
        self.material.emission_texture.is_some()
    }
    fn emission_factor(&self, uv: [f64; 2]) -> Rgb {
        self.material.emission_at(self.textures, &uv2(uv))
    }
}

/// The bake's view of `scene`: the path tracer's geometry and environment
/// ([`crate::reference::path_scene`]) with every material replaced by its diffuse part, and
/// what each material's diffuse albedo needs ([`base_albedo`], per material). Errors: a scene with neither an
/// emitter nor a non-black environment (it would bake black).
pub fn diffuse_path_scene(scene: &Scene) -> Result<(PathScene<'_>, Vec<BaseAlbedo>, Vec<String>)> {
    let (mut ps, warnings) = crate::reference::path_scene(scene)?;
    let emitters = ps
        .geometry
        .emission
        .iter()
        .any(|e| e.is_finite() && e.max_component() > 0.0);
    if !emitters && ps.environment.is_none() {
        return Err(TraceError::Parameter(format!(
            "{}: the scene has no emitter and no (non-black) environment: the light maps would be black",
            scene.source.display()
        )));
    }
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    ps.materials = scene
        .materials
        .iter()
        .zip(&bases)
        .map(|(m, &b)| {
            Box::new(DiffuseSurface {
                material: m,
                textures: &scene.textures,
                base: b,
            }) as Box<dyn Surface + '_>
        })
        .collect();
    Ok((ps, bases, warnings))
}

/// Checks that `atlas` fits `scene` (one entry per mesh, pages in range, uv1 present and
/// finite on every light-mapped mesh, page size within [`MAX_PAGE_SIZE`]).
pub fn check_atlas(scene: &Scene, atlas: &LightmapAtlas) -> Result<()> {
    let src = scene.source.display();
    if atlas.width == 0 || atlas.height == 0 || atlas.pages == 0 {
        return Err(TraceError::Parameter(format!(
            "{src}: light-map atlas of {}×{} texels × {} pages is empty",
            atlas.width, atlas.height, atlas.pages
        )));
    }
    if atlas.width > MAX_PAGE_SIZE || atlas.height > MAX_PAGE_SIZE {
        return Err(TraceError::Parameter(format!(
            "{src}: light-map page {}×{} exceeds the GPU limit {MAX_PAGE_SIZE}² (lower the texel density)",
            atlas.width, atlas.height
        )));
    }
    if atlas.mesh_page.len() != scene.meshes.len() {
        return Err(TraceError::Parameter(format!(
            "{src}: light-map atlas lists {} meshes, the scene has {}",
            atlas.mesh_page.len(),
            scene.meshes.len()
        )));
    }
    for (m, page) in scene.meshes.iter().zip(&atlas.mesh_page) {
        let Some(page) = page else { continue };
        if *page >= atlas.pages {
            return Err(TraceError::Parameter(format!(
                "{src}: mesh {:?} is on light-map page {page} of {}",
                m.name, atlas.pages
            )));
        }
        match &m.uv1 {
            Some(uv) if uv.len() == m.positions.len() => {
                if let Some(k) = uv.iter().position(|v| !v.is_finite()) {
                    return Err(TraceError::Parameter(format!(
                        "{src}: mesh {:?}: light-map uv {k} is not finite",
                        m.name
                    )));
                }
            }
            _ => {
                return Err(TraceError::Parameter(format!(
                    "{src}: mesh {:?} has a light-map page but no light-map uvs (one per vertex)",
                    m.name
                )))
            }
        }
    }
    Ok(())
}

/// A 64-bit FNV-1a hash, the fingerprint of a scene and bake settings in tile headers.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fnv(pub u64);

impl Fnv {
    pub fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    pub fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub fn f32(&mut self, v: f32) {
        self.bytes(&v.to_bits().to_le_bytes());
    }
    pub fn f64(&mut self, v: f64) {
        self.bytes(&v.to_bits().to_le_bytes());
    }
}

/// The fingerprint of everything a tile's content depends on: the tile format, the atlas, the
/// geometry with its light-map uvs, normals, uv0, materials' baked albedo (constants and texture
/// sizes), emission, the environment (radiance in 4096 fixed directions) and the options that
/// change texel values (spp, bounces, seed, tile side; not the denoiser, which runs at assembly).
pub fn bake_hash(scene: &Scene, atlas: &LightmapAtlas, opts: &BakeOptions) -> u64 {
    let mut h = Fnv::new();
    h.bytes(tile::MAGIC);
    for v in [atlas.width, atlas.height, atlas.pages, atlas.gutter] {
        h.u64(u64::from(v));
    }
    for p in &atlas.mesh_page {
        h.u64(p.map_or(u64::MAX, u64::from));
    }
    for v in [
        u64::from(opts.spp),
        u64::from(opts.bounces),
        opts.seed,
        u64::from(opts.tile),
        opts.transport as u64,
    ] {
        h.u64(v);
    }
    for m in &scene.meshes {
        h.u64(m.positions.len() as u64);
        for p in &m.positions {
            for c in p.to_array() {
                h.f32(c);
            }
        }
        for t in &m.indices {
            for &i in t {
                h.u64(u64::from(i));
            }
        }
        for set in [&m.uv0, &m.uv1] {
            h.u64(set.as_ref().map_or(0, |v| v.len() as u64));
            for uv in set.iter().flatten() {
                for c in uv.to_array() {
                    h.f32(c);
                }
            }
        }
        for n in m.normals.iter().flatten() {
            for c in n.to_array() {
                h.f32(c);
            }
        }
        h.u64(m.material as u64);
        if let Some(e) = m.emission {
            for c in e.0 {
                h.f64(c);
            }
        }
    }
    for (m, s) in scene
        .materials
        .iter()
        .zip(scene.materials.iter().map(base_albedo))
    {
        h.bytes(m.name.as_bytes());
        h.bytes(m.kind.name().as_bytes());
        h.u64(u64::from(m.two_sided));
        let a = diffuse_albedo(m, &[], &[Vec2::ZERO; 2], s);
        for c in a.0 {
            h.f64(c);
        }
        for t in m.texture_refs() {
            h.u64(t.texture as u64);
            h.u64(u64::from(t.uv_set));
        }
        if opts.transport == Transport::Full {
            // Paths cross the materials themselves: every parameter counts.
            h.bytes(format!("{:?} {}", m.kind, m.two_sided).as_bytes());
        }
    }
    for t in &scene.textures {
        let m = t.mean();
        for c in m {
            h.f64(c);
        }
    }
    hash_environment(&mut h, scene);
    h.0
}

/// Adds the scene's environment (its radiance in 4096 fixed directions) to `h`.
pub(crate) fn hash_environment(h: &mut Fnv, scene: &Scene) {
    if let Some(env) = &scene.environment {
        let n = 4096;
        for k in 0..n {
            // Fibonacci sphere directions.
            let z = 1.0 - (2 * k + 1) as f64 / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = k as f64 * 2.399_963_229_728_653;
            let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
            for c in env.radiance(d).0 {
                h.f64(c);
            }
        }
    }
}
