//! The contract's entry points: lustre-shade's `AnalyticScene`, `MaterialPlan`s and `FilteredEnvironment` in,
//! an `Image` out.

use crate::context::GpuContext;
use crate::cube::CubeLevelRef;
use crate::error::{invalid, Result};
use crate::packed::{
    f3, CameraBasis, GpuKurtMaterial, GpuLobe, GpuPlane, GpuSphere, GpuSun, PackedScene,
    LOBE_SCHEME_LATTICE, LOBE_SCHEME_PATTERN, LOBE_SCHEME_TAP_LATTICE,
};
use crate::passes::sphere::{GpuEnvironment, GpuRenderer};
use lustre_brdf::models::kurt::KurtLobe;
use lustre_env::CubeMap;
use lustre_shade::analytic_scene::AnalyticScene;
use lustre_shade::integrator::{FilteredEnvironment, LobePlan, MaterialPlan};
use lustre_shade::pattern::PatternKind;
use lustre_trace::image::Image;

fn level_ref(map: &CubeMap) -> CubeLevelRef<'_> {
    CubeLevelRef {
        size: map.size,
        faces: std::array::from_fn(|k| map.faces[k].as_slice()),
    }
}

impl GpuEnvironment {
    /// Uploads the contract's environment: every pyramid level and the irradiance map.
    pub fn new(ctx: &GpuContext, env: &FilteredEnvironment<'_>) -> Result<Self> {
        let levels: Vec<CubeLevelRef> = env.pyramid.levels.iter().map(level_ref).collect();
        GpuEnvironment::from_levels(ctx, &levels, level_ref(env.irradiance))
    }
}

impl PackedScene {
    /// Packs a scene with one plan per material (`plans[i]` shades `scene.materials[i]`; the
    /// plan's own `kurt` supplies kd and the lobe parameters, as `shade_regular` uses it).
    pub fn new(scene: &AnalyticScene, plans: &[MaterialPlan]) -> Result<Self> {
        if plans.len() != scene.materials.len() {
            return Err(invalid(
                "material plans",
                format!(
                    "{} plans for {} materials",
                    plans.len(),
                    scene.materials.len()
                ),
            ));
        }
        let c = &scene.camera;
        let mut packed = PackedScene {
            camera: CameraBasis::new(c.eye, c.target, c.up, c.fov_y_deg),
            spheres: scene
                .spheres
                .iter()
                .map(|s| GpuSphere {
                    center: f3(s.center),
                    radius: s.radius as f32,
                    axis: f3(s.axis),
                    material: index(s.material),
                })
                .collect(),
            planes: scene
                .planes
                .iter()
                .map(|p| GpuPlane {
                    point: f3(p.point),
                    half_size: p.half_size as f32,
                    normal: f3(p.normal),
                    material: index(p.material),
                    tangent: f3(p.tangent),
                    pad: 0,
                })
                .collect(),
            materials: Vec::with_capacity(plans.len()),
            lobes: Vec::new(),
            samples: Vec::new(),
            suns: Vec::new(),
        };
        for (i, plan) in plans.iter().enumerate() {
            let k = &plan.kurt;
            packed.materials.push(GpuKurtMaterial {
                kd: [k.kd.0[0] as f32, k.kd.0[1] as f32, k.kd.0[2] as f32],
                lobe_start: packed.lobes.len() as u32,
                reflection: plan.reflection.len() as u32,
                transmission: plan.transmission.len() as u32,
                sun_start: packed.suns.len() as u32,
                sun_count: plan.suns.len() as u32,
            });
            packed.suns.extend(plan.suns.iter().map(|s| GpuSun {
                direction: f3(s.direction),
                spread: s.spread as f32,
                irradiance: s.irradiance.map(|v| v as f32),
                pad1: 0.0,
            }));
            for (what, lobes, lobe_plans) in [
                ("reflection", &k.reflection, &plan.reflection),
                ("transmission", &k.transmission, &plan.transmission),
            ] {
                if lobes.len() != lobe_plans.len() {
                    return Err(invalid(
                        format!("material plan {i}"),
                        format!(
                            "{} {what} lobes but {} {what} patterns",
                            lobes.len(),
                            lobe_plans.len()
                        ),
                    ));
                }
                for (lobe, lp) in lobes.iter().zip(lobe_plans) {
                    packed.push_lobe(lobe, lp);
                }
            }
        }
        Ok(packed)
    }

    fn push_lobe(&mut self, lobe: &KurtLobe, plan: &LobePlan) {
        let p = &plan.pattern;
        let (scheme, count) = match p.kind {
            PatternKind::RowLattice { budget } => (LOBE_SCHEME_LATTICE, index(budget)),
            PatternKind::TapLattice { budget } => (LOBE_SCHEME_TAP_LATTICE, index(budget)),
            _ => (LOBE_SCHEME_PATTERN, p.h.len() as u32),
        };
        self.lobes.push(GpuLobe {
            ks: [
                lobe.ks.0[0] as f32,
                lobe.ks.0[1] as f32,
                lobe.ks.0[2] as f32,
            ],
            mx: lobe.mx as f32,
            my: lobe.my as f32,
            r0: lobe.r0 as f32,
            alpha: lobe.alpha as f32,
            xi0: p.xi0 as f32,
            pdf_constant: p.pdf_constant as f32,
            sample_start: self.samples.len() as u32,
            sample_count: count,
            scheme,
        });
        self.samples.extend(
            p.h.iter()
                .map(|h| [h.x as f32, h.y as f32, h.z as f32, 0.0]),
        );
    }
}

/// A material index as u32 (indices past u32::MAX become u32::MAX, which the range check of the
/// upload reports).
fn index(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

impl GpuRenderer {
    /// The contract's entry point: uploads `scene` (with `plans[i]` for material i) and `env`,
    /// renders `width`×`height` pixels and reads them back.
    pub fn render(
        &self,
        scene: &AnalyticScene,
        plans: &[MaterialPlan],
        env: &FilteredEnvironment<'_>,
        width: usize,
        height: usize,
    ) -> Result<Image> {
        let packed = PackedScene::new(scene, plans)?;
        let gpu_env = GpuEnvironment::new(self.context(), env)?;
        let data = self.render_packed(&packed, &gpu_env, width, height)?;
        Image::from_data(width, height, data).map_err(|e| invalid("image", e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use lustre_brdf::models::kurt::Kurt;
    use lustre_brdf::Rgb;
    use lustre_shade::analytic_scene::{LookAtCamera, Sphere};
    use lustre_shade::integrator::plan_regular;

    fn scene(materials: Vec<Kurt>) -> AnalyticScene {
        AnalyticScene {
            camera: LookAtCamera {
                eye: DVec3::new(0.0, 0.0, 4.0),
                target: DVec3::ZERO,
                up: DVec3::Y,
                fov_y_deg: 40.0,
            },
            spheres: vec![Sphere {
                center: DVec3::ZERO,
                radius: 1.0,
                material: 0,
                axis: DVec3::Y,
            }],
            planes: vec![],
            materials,
        }
    }

    fn material() -> Kurt {
        let lobe =
            KurtLobe::new(Rgb::splat(0.5), 0.1, 0.2, 0.3, 0.0).unwrap_or_else(|e| panic!("{e}"));
        Kurt::new(Rgb::splat(0.2), vec![lobe], vec![lobe]).unwrap_or_else(|e| panic!("{e}"))
    }

    /// Lobes and patterns are laid out material by material, reflection before transmission.
    #[test]
    fn packing_lays_out_lobes_and_patterns() {
        let m = material();
        let plan = plan_regular(&m, 9, 0.1).unwrap_or_else(|e| panic!("{e}"));
        let packed = PackedScene::new(&scene(vec![m.clone(), m]), &[plan.clone(), plan.clone()])
            .unwrap_or_else(|e| panic!("{e}"));
        let n = plan.reflection[0].pattern.h.len() as u32;
        assert_eq!(packed.lobes.len(), 4);
        assert_eq!(packed.samples.len(), 4 * n as usize);
        assert_eq!(packed.materials[1].lobe_start, 2);
        assert_eq!(
            (
                packed.materials[1].reflection,
                packed.materials[1].transmission
            ),
            (1, 1)
        );
        for (i, l) in packed.lobes.iter().enumerate() {
            assert_eq!((l.sample_start, l.sample_count), (i as u32 * n, n));
        }
        assert_eq!(packed.lobes[0].my, 0.2);
        let h = plan.reflection[0].pattern.h[1];
        assert_eq!(packed.samples[1], [h.x as f32, h.y as f32, h.z as f32, 0.0]);
    }

    /// A plan count or lobe count that does not match the scene is an error naming it.
    #[test]
    fn mismatched_plans_are_errors() {
        let m = material();
        let plan = plan_regular(&m, 9, 0.1).unwrap_or_else(|e| panic!("{e}"));
        let err = PackedScene::new(&scene(vec![m.clone()]), &[]).unwrap_err();
        assert!(err.to_string().contains("material plans"), "{err}");
        let mut short = plan.clone();
        short.transmission.clear();
        let err = PackedScene::new(&scene(vec![m]), &[short]).unwrap_err();
        assert!(err.to_string().contains("material plan 0"), "{err}");
        assert!(err.to_string().contains("transmission"), "{err}");
    }
}
