//! The WGSL scene models of the view-dependent pass (`src/wgsl/{rough_conductor, rough_plastic,
//! rough_dielectric, conductor, thin_dielectric, pbr_metallic_roughness, lambert, plastic, dielectric}.wgsl`, dispatched by `bsdf.wgsl`) against
//! their lustre-brdf twins: eval, pdf and sample over a grid of ωo, ωi and u, in f32 against
//! f64. Fails (does not skip) without an adapter.

use glam::DVec3;
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::microfacet::distribution::{MicrofacetDistribution, MicrofacetType};
use lustre_brdf::models::conductor::{ComplexIor, Conductor};
use lustre_brdf::models::dielectric::Dielectric;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::models::pbr_metallic_roughness::{PbrLayers, PbrMetallicRoughness};
use lustre_brdf::models::plastic::Plastic;
use lustre_brdf::models::rough_conductor::RoughConductor;
use lustre_brdf::models::rough_dielectric::RoughDielectric;
use lustre_brdf::models::rough_plastic::RoughPlastic;
use lustre_brdf::models::thin_dielectric::ThinDielectric;
use lustre_brdf::rgb::Rgb;
use lustre_gpu::material::harness::{evaluate_models, ModelCase};
use lustre_gpu::material::{
    pack_conductor, pack_dielectric, pack_lambert, pack_pbr_metallic_roughness, pack_plastic,
    pack_rough_conductor, pack_rough_dielectric, pack_rough_plastic, pack_thin_dielectric,
    rough_plastic_table, GpuBsdf, FLAG_DELTA_ONLY, FLAG_DIFFUSE_ONLY, KIND_CONDUCTOR,
    KIND_DIELECTRIC, KIND_LAMBERT, KIND_PBR_METALLIC_ROUGHNESS, KIND_PLASTIC, KIND_ROUGH_CONDUCTOR,
    KIND_ROUGH_DIELECTRIC, KIND_ROUGH_PLASTIC, KIND_THIN_DIELECTRIC,
};
use lustre_gpu::GpuContext;

fn record(kind: u32, flags: u32, p: [[f32; 4]; 8]) -> GpuBsdf {
    GpuBsdf {
        kind,
        flags,
        pad0: 0,
        pad1: 0,
        p,
    }
}

fn dir(theta: f64, phi: f64) -> DVec3 {
    DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    )
}

/// Directions on both hemispheres (θ from near-normal to grazing-ish).
fn directions() -> Vec<DVec3> {
    let mut out = vec![];
    for &t in &[0.05, 0.4, 0.8, 1.2, 1.45] {
        for k in 0..5 {
            let d = dir(t, 0.3 + 1.3 * f64::from(k));
            out.push(d);
            out.push(DVec3::new(d.x, d.y, -d.z));
        }
    }
    out
}

/// Points in [0, 1)² on the 2⁻²⁴ grid (as the pass draws them).
fn points() -> Vec<(f64, f64)> {
    let g = |x: f64| (x * 16_777_216.0).floor() / 16_777_216.0;
    (0..24)
        .map(|i| {
            let (u, v) = lustre_shade::warp::fibonacci_point(i, 24);
            (g(u), g(v))
        })
        .collect()
}

fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}

#[test]
fn gpu_models_match_lustre_brdf() {
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let ggx = |a, b| MicrofacetDistribution::new(MicrofacetType::Ggx, a, b).expect("ggx");
    let beck = |a, b| MicrofacetDistribution::new(MicrofacetType::Beckmann, a, b).expect("beck");
    let gold = ComplexIor::new(Rgb::new(0.143, 0.374, 1.442), Rgb::new(3.983, 2.385, 1.603))
        .expect("gold");
    let mut models: Vec<(&str, Box<dyn Bsdf>, GpuBsdf)> = vec![];
    let mut tables = vec![];
    for (name, d) in [
        ("rough conductor GGX aniso", ggx(0.3, 0.04)),
        ("rough conductor Beckmann", beck(0.2, 0.2)),
    ] {
        let m = RoughConductor::new(d, gold, Rgb::new(1.0, 0.9, 0.8)).expect("conductor");
        let r = record(
            KIND_ROUGH_CONDUCTOR,
            0,
            pack_rough_conductor(&m).expect("pack"),
        );
        models.push((name, Box::new(m), r));
    }
    for (name, kind, a, nonlinear) in [
        ("rough plastic GGX", MicrofacetType::Ggx, 0.1, false),
        (
            "rough plastic Beckmann nonlinear",
            MicrofacetType::Beckmann,
            0.3,
            true,
        ),
    ] {
        let m = RoughPlastic::new(
            kind,
            a,
            Rgb::new(0.22, 0.14, 0.09),
            Rgb::ONE,
            1.5,
            1.0,
            nonlinear,
        )
        .expect("plastic");
        let off = tables.len() as u32;
        tables.extend(rough_plastic_table(&m));
        let r = record(
            KIND_ROUGH_PLASTIC,
            0,
            pack_rough_plastic(&m, off).expect("pack"),
        );
        models.push((name, Box::new(m), r));
    }
    for (name, d) in [
        ("rough dielectric GGX", ggx(0.2, 0.2)),
        ("rough dielectric Beckmann aniso", beck(0.3, 0.1)),
    ] {
        let m = RoughDielectric::new(d, 1.5, 1.0)
            .and_then(|m| m.with_tints(Rgb::ONE, Rgb::new(0.9, 0.95, 1.0)))
            .expect("dielectric");
        let r = record(
            KIND_ROUGH_DIELECTRIC,
            0,
            pack_rough_dielectric(&m).expect("pack"),
        );
        models.push((name, Box::new(m), r));
    }
    for (name, metallic, roughness, anisotropy, rotation) in [
        ("glTF dielectric-ish", 0.3, 0.5, 0.0, 0.0),
        ("glTF metal", 1.0, 0.2, 0.0, 0.0),
        ("glTF brushed metal (anisotropy)", 1.0, 0.3, 0.8, 0.6),
        ("glTF anisotropic dielectric", 0.2, 0.5, 0.5, -1.2),
    ] {
        let m = PbrMetallicRoughness::new(Rgb::new(0.8, 0.5, 0.2), metallic, roughness)
            .and_then(|m| {
                if anisotropy > 0.0 {
                    m.with_anisotropy(anisotropy, rotation)
                } else {
                    Ok(m)
                }
            })
            .expect("pbr");
        let r = record(
            KIND_PBR_METALLIC_ROUGHNESS,
            0,
            pack_pbr_metallic_roughness(&m).expect("pack"),
        );
        models.push((name, Box::new(m), r));
    }
    // KHR_materials_ior / _specular / _clearcoat / _sheen layers.
    for (name, metallic, layers) in [
        (
            "glTF coated, sheened, tinted dielectric",
            0.0,
            PbrLayers {
                specular: 0.8,
                specular_color: Rgb::new(1.2, 1.0, 0.7),
                clearcoat: 0.8,
                clearcoat_roughness: 0.15,
                sheen_color: Rgb::new(0.6, 0.5, 0.9),
                sheen_roughness: 0.4,
            },
        ),
        (
            "glTF coated metal",
            1.0,
            PbrLayers {
                clearcoat: 1.0,
                clearcoat_roughness: 0.3,
                ..PbrLayers::default()
            },
        ),
        (
            "glTF sharp sheen",
            0.0,
            PbrLayers {
                sheen_color: Rgb::new(1.0, 0.8, 0.6),
                sheen_roughness: 0.05,
                ..PbrLayers::default()
            },
        ),
    ] {
        let m = PbrMetallicRoughness::new(Rgb::new(0.5, 0.2, 0.1), metallic, 0.6)
            .and_then(|m| m.with_layers(1.4, layers))
            .expect("pbr");
        let r = record(
            KIND_PBR_METALLIC_ROUGHNESS,
            0,
            pack_pbr_metallic_roughness(&m).expect("pack"),
        );
        models.push((name, Box::new(m), r));
    }
    for (name, nonlinear) in [("plastic", false), ("plastic nonlinear", true)] {
        let m =
            Plastic::new(Rgb::new(0.5, 0.3, 0.2), Rgb::ONE, 1.5, 1.0, nonlinear).expect("plastic");
        let r = record(KIND_PLASTIC, 0, pack_plastic(&m).expect("pack"));
        models.push((name, Box::new(m), r));
    }
    let l = Lambert::new(Rgb::new(0.7, 0.5, 0.3)).expect("lambert");
    let r = record(
        KIND_LAMBERT,
        FLAG_DIFFUSE_ONLY,
        pack_lambert(&l).expect("pack"),
    );
    models.push(("Lambert", Box::new(l), r));
    let g = Dielectric::new(1.5, 1.0)
        .and_then(|g| g.with_tints(Rgb::new(0.9, 1.0, 0.95), Rgb::new(0.8, 0.9, 1.0)))
        .expect("dielectric");
    let r = record(
        KIND_DIELECTRIC,
        FLAG_DELTA_ONLY,
        pack_dielectric(&g).expect("pack"),
    );
    models.push(("dielectric", Box::new(g), r));
    let c = Conductor::new(gold.eta, gold.k, Rgb::ONE).expect("conductor");
    let r = record(
        KIND_CONDUCTOR,
        FLAG_DELTA_ONLY,
        pack_conductor(&c).expect("pack"),
    );
    models.push(("conductor", Box::new(c), r));
    let t = ThinDielectric::new(1.5, 1.0)
        .and_then(|t| t.with_tints(Rgb::ONE, Rgb::new(0.8, 0.9, 1.0)))
        .expect("thin");
    let r = record(
        KIND_THIN_DIELECTRIC,
        FLAG_DELTA_ONLY,
        pack_thin_dielectric(&t).expect("pack"),
    );
    models.push(("thin dielectric", Box::new(t), r));

    let dirs = directions();
    let pts = points();
    let records: Vec<GpuBsdf> = models.iter().map(|m| m.2).collect();
    let f3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
    let mut cases = vec![];
    for k in 0..models.len() {
        for (i, wo) in dirs.iter().enumerate() {
            for (j, wi) in dirs.iter().enumerate() {
                let u = pts[(i * 7 + j) % pts.len()];
                cases.push(ModelCase {
                    record: k as u32,
                    wo: f3(*wo),
                    wi: f3(*wi),
                    u: [u.0 as f32, u.1 as f32],
                });
            }
        }
    }
    let out = evaluate_models(&ctx, &records, &tables, &cases).expect("gpu models");
    for (k, (name, bsdf, _)) in models.iter().enumerate() {
        let (mut e_eval, mut e_pdf, mut e_wi, mut e_spdf, mut e_val) =
            (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let (mut n_samples, mut n_mismatch) = (0, 0);
        for (c, g) in cases.iter().zip(&out).filter(|(c, _)| c.record == k as u32) {
            let v = |a: [f32; 3]| DVec3::new(a[0].into(), a[1].into(), a[2].into());
            let (wo, wi) = (v(c.wo), v(c.wi));
            let f = bsdf.eval(wi, wo);
            let scale = f.max_component().max(1e-3);
            for ch in 0..3 {
                e_eval = e_eval.max(rel(g.eval[ch].into(), f[ch], scale));
            }
            let p = bsdf.pdf(wi, wo);
            e_pdf = e_pdf.max(rel(g.pdf.into(), p, p.abs().max(1e-3)));
            let s = bsdf.sample(wo, c.u[0].into(), c.u[1].into());
            match (s, g.sample_pdf > 0.0) {
                (Some(s), true) => {
                    n_samples += 1;
                    e_wi = e_wi.max((v(g.sample_wi) - s.wi).length());
                    e_spdf = e_spdf.max(rel(g.sample_pdf.into(), s.pdf, 1e-3));
                    let scale = s.value.max_component().max(1e-3);
                    for ch in 0..3 {
                        e_val = e_val.max(rel(g.sample_value[ch].into(), s.value[ch], scale));
                    }
                    assert_eq!(g.delta, s.is_delta(), "{name}");
                }
                (None, false) => {}
                _ => n_mismatch += 1,
            }
        }
        eprintln!(
            "{name}: eval {e_eval:.1e}, pdf {e_pdf:.1e}; {n_samples} samples: ωi {e_wi:.1e}, \
             pdf {e_spdf:.1e}, value {e_val:.1e}; {n_mismatch} sampled on one side only"
        );
        assert!(
            e_eval < 1e-4 && e_pdf < 1e-4,
            "{name}: eval {e_eval} pdf {e_pdf}"
        );
        assert!(
            e_wi < 1e-4 && e_spdf < 1e-4 && e_val < 1e-4,
            "{name}: sample {e_wi} {e_spdf} {e_val}"
        );
        assert!(n_samples > 100, "{name}: {n_samples} samples");
        assert_eq!(n_mismatch, 0, "{name}");
    }
}
