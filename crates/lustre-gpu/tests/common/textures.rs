//! Small synthetic textures and the textured materials' untextured twins, shared by the
//! tests of textured materials on the GPU (`textured`, `adaptive_textured`).

use lustre_brdf::models::pbr_metallic_roughness::PbrLayers;
use lustre_brdf::rgb::Rgb;
use lustre_scene::material::{MicrofacetType, TextureRef, TexturedRgb, TexturedScalar};
use lustre_scene::texture::{ColorSpace, Texture};
use lustre_scene::{Material, MaterialKind};
use std::f32::consts::TAU;

pub const SIDE: u32 = 16;

/// A SIDE² texture of `channels` channels, texel (x, y) from `f(u, v)` at its centre.
pub fn texture(name: &str, channels: u8, f: impl Fn(f32, f32) -> [f32; 4]) -> Texture {
    let mut data = vec![];
    for y in 0..SIDE {
        for x in 0..SIDE {
            let (u, v) = (
                (x as f32 + 0.5) / SIDE as f32,
                (y as f32 + 0.5) / SIDE as f32,
            );
            data.extend_from_slice(&f(u, v)[..usize::from(channels)]);
        }
    }
    Texture::new(name, SIDE, SIDE, channels, ColorSpace::Linear, data).expect("texture")
}

pub fn tref(texture: usize) -> Option<TextureRef> {
    Some(TextureRef { texture, uv_set: 0 })
}

pub fn scalar(texture: usize, channel: u8) -> TexturedScalar {
    TexturedScalar {
        factor: 1.0,
        texture: tref(texture),
        channel,
    }
}

/// The textures: 0 roughness (G), 1 base colour, 2 metallic-roughness (G, B), 3 normal map,
/// 4 wood colour, 5 transmission (R) and roughness (G).
pub fn textures() -> Vec<Texture> {
    let wave = |x: f32, k: f32| 0.5 + 0.5 * (TAU * k * x).sin();
    vec![
        texture("roughness", 3, |u, v| {
            [0.0, 0.03 + 0.45 * wave(u, 3.0) * wave(v, 2.0), 0.0, 1.0]
        }),
        texture("base colour", 3, |u, v| {
            [0.9 * wave(u, 2.0), 0.3 + 0.5 * wave(v, 3.0), 0.2, 1.0]
        }),
        texture("metallic-roughness", 3, |u, v| {
            [1.0, 0.15 + 0.6 * wave(v, 2.0), wave(u, 4.0), 1.0]
        }),
        texture("normal map", 3, |u, v| {
            let (x, y) = (0.5 * (TAU * 4.0 * u).sin(), 0.5 * (TAU * 3.0 * v).cos());
            let l = (x * x + y * y + 1.0).sqrt();
            [0.5 + 0.5 * x / l, 0.5 + 0.5 * y / l, 0.5 + 0.5 / l, 1.0]
        }),
        texture("wood", 3, |u, v| {
            let w = wave(u + 0.1 * v, 5.0);
            [0.15 + 0.3 * w, 0.1 + 0.15 * w, 0.05 + 0.06 * w, 1.0]
        }),
        texture("transmission", 3, |u, v| {
            let t = if (u * 4.0).fract() < 0.5 { 1.0 } else { 0.0 };
            [t, if v < 0.5 { 0.02 } else { 0.4 }, 0.0, 1.0]
        }),
    ]
}

/// `m` with every texture of its BSDF parameters replaced by the texture's mean (the factor
/// times the mean of the channel read) and without its normal map.
pub fn untextured(m: &Material, textures: &[Texture]) -> Material {
    let mean = |t: Option<TextureRef>| t.map_or([1.0; 4], |r| textures[r.texture].mean());
    let rgb = |c: &TexturedRgb| {
        let m = mean(c.texture);
        TexturedRgb::constant(Rgb::new(
            c.factor[0] * m[0],
            c.factor[1] * m[1],
            c.factor[2] * m[2],
        ))
    };
    let sc = |s: &TexturedScalar| {
        TexturedScalar::constant(s.factor * mean(s.texture)[usize::from(s.channel)])
    };
    let kind = match &m.kind {
        MaterialKind::RoughConductor {
            eta,
            k,
            specular,
            alpha_u,
            alpha_v,
            distribution,
        } => MaterialKind::RoughConductor {
            eta: *eta,
            k: *k,
            specular: rgb(specular),
            alpha_u: sc(alpha_u),
            alpha_v: sc(alpha_v),
            distribution: *distribution,
        },
        MaterialKind::RoughPlastic {
            diffuse,
            specular,
            alpha,
            distribution,
            int_ior,
            ext_ior,
            nonlinear,
        } => MaterialKind::RoughPlastic {
            diffuse: rgb(diffuse),
            specular: *specular,
            alpha: sc(alpha),
            distribution: *distribution,
            int_ior: *int_ior,
            ext_ior: *ext_ior,
            nonlinear: *nonlinear,
        },
        MaterialKind::PbrMetallicRoughness {
            base_color,
            metallic,
            roughness,
            transmission,
            ior,
            anisotropy,
            anisotropy_rotation,
            layers,
        } => MaterialKind::PbrMetallicRoughness {
            base_color: rgb(base_color),
            metallic: sc(metallic),
            roughness: sc(roughness),
            transmission: sc(transmission),
            ior: *ior,
            anisotropy: *anisotropy,
            anisotropy_rotation: *anisotropy_rotation,
            layers: *layers,
        },
        other => panic!("{} is not one of the textured materials", other.name()),
    };
    let mut out = Material::new(m.name.clone(), kind);
    out.two_sided = m.two_sided;
    out
}

/// A rough gold conductor (GGX) whose αu and αv are texture 0's G channel ([`textures`]).
pub fn textured_gold() -> MaterialKind {
    MaterialKind::RoughConductor {
        eta: Rgb::new(0.143, 0.374, 1.442),
        k: Rgb::new(3.983, 2.385, 1.603),
        specular: TexturedRgb::constant(Rgb::ONE),
        alpha_u: scalar(0, 1),
        alpha_v: scalar(0, 1),
        distribution: MicrofacetType::Ggx,
    }
}

/// A glTF metallic-roughness material with texture 1 as its base colour and texture 2's B and G
/// channels as its metallic and roughness ([`textures`]); opaque, anisotropic, with a tinted
/// specular, a clear coat and a sheen.
pub fn textured_gltf() -> MaterialKind {
    MaterialKind::PbrMetallicRoughness {
        base_color: TexturedRgb::texture(TextureRef {
            texture: 1,
            uv_set: 0,
        }),
        metallic: scalar(2, 2),
        roughness: scalar(2, 1),
        transmission: TexturedScalar::constant(0.0),
        ior: 1.5,
        // KHR_materials_anisotropy over a textured roughness: α_t from each texel's α.
        anisotropy: 0.6,
        anisotropy_rotation: 0.5,
        // KHR_materials_specular / _clearcoat / _sheen factors over the textured base.
        layers: PbrLayers {
            specular: 0.9,
            specular_color: Rgb::new(1.0, 0.9, 0.8),
            clearcoat: 0.5,
            clearcoat_roughness: 0.1,
            sheen_color: Rgb::new(0.3, 0.2, 0.1),
            sheen_roughness: 0.5,
        },
    }
}
