//! The CPU walkthrough frame: probes captured from the light-mapped scene with their
//! object left out, bounding planes that remove the parallax of a box room, regular sampling
//! through the material's warp against the converged integral of the same incident light, and
//! the diffuse-only frame equal to the light-mapped image.
//!
//! The scene is a 4 × 3 × 5 m box room with hand-made light maps (a smooth pattern per wall,
//! written straight into the page: no bake needed) around a rough metal sphere.

use glam::{DVec3, Vec2, Vec3};
use lustre_brdf::rgb::Rgb;
use lustre_brdf::sampling::SplitMix64;
use lustre_scene::lightmap::{AtlasSource, LightmapAtlas};
use lustre_scene::material::{MicrofacetType, TexturedRgb, TexturedScalar};
use lustre_scene::{Material, MaterialKind, Mesh, Scene};
use lustre_shade::frame::{render_frame, FrameLight};
use lustre_shade::integrator::corrected_direction;
use lustre_shade::probe::{capture_cube, capture_probe, LitScene, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method, MAX_WALKTHROUGH_SAMPLES};
use lustre_trace::bake::render::{render_lightmapped, Lightmapped};
use lustre_trace::bake::{base_albedo, BaseAlbedo};
use lustre_trace::path_tracer::{PathCamera, PathOptions, PathTracer};
use std::f64::consts::PI;

const PAGE: u32 = 64;
const ROOM: [f64; 3] = [4.0, 3.0, 5.0];
const CENTRE: [f64; 3] = [2.0, 1.2, 2.5];

/// The pattern of wall `k` at block coordinates (u, v) ∈ [0, 1]².
fn pattern(k: usize, u: f64, v: f64) -> [f32; 3] {
    let base = [
        [1.0, 0.3, 0.2],
        [0.2, 1.0, 0.3],
        [0.3, 0.2, 1.0],
        [1.0, 1.0, 0.3],
        [0.3, 1.0, 1.0],
        [1.0, 0.3, 1.0],
    ][k];
    let m = 1.0 + 0.6 * (2.0 * PI * 1.5 * u).sin() * (2.0 * PI * 1.5 * v).cos();
    base.map(|c| (c * m * 3.0) as f32)
}

/// The room (six inward quads, light-mapped, kd 0.8) and a sphere of radius 0.5 at `CENTRE` of
/// material `sphere`, marked as a probe object; with the pages.
fn room(sphere: MaterialKind) -> (Scene, LightmapAtlas, Vec<Vec<[f32; 3]>>) {
    let v = DVec3::new;
    let [x, y, z] = ROOM;
    let walls = [
        ("floor", v(0.0, 0.0, 0.0), v(0.0, 0.0, z), v(x, 0.0, 0.0)),
        ("ceiling", v(0.0, y, 0.0), v(x, 0.0, 0.0), v(0.0, 0.0, z)),
        ("x0", v(0.0, 0.0, 0.0), v(0.0, y, 0.0), v(0.0, 0.0, z)),
        ("x1", v(x, 0.0, 0.0), v(0.0, 0.0, z), v(0.0, y, 0.0)),
        ("z0", v(0.0, 0.0, 0.0), v(x, 0.0, 0.0), v(0.0, y, 0.0)),
        ("z1", v(0.0, 0.0, z), v(0.0, y, 0.0), v(x, 0.0, 0.0)),
    ];
    let mut page = vec![[0.0f32; 3]; (PAGE * PAGE) as usize];
    let mut meshes = vec![];
    let block = 18u32;
    for (k, (name, p0, eu, ev)) in walls.iter().enumerate() {
        let (bx, by) = (2 + 20 * (k as u32 % 3), 2 + 20 * (k as u32 / 3));
        let f = |p: DVec3| p.as_vec3();
        let mut m = Mesh::new(
            *name,
            vec![f(*p0), f(*p0 + *eu), f(*p0 + *eu + *ev), f(*p0 + *ev)],
            vec![[0, 1, 2], [0, 2, 3]],
            0,
        );
        let uv = |i: u32, j: u32| {
            Vec2::new(
                (bx + i * block) as f32 / PAGE as f32,
                (by + j * block) as f32 / PAGE as f32,
            )
        };
        m.uv1 = Some(vec![uv(0, 0), uv(1, 0), uv(1, 1), uv(0, 1)]);
        meshes.push(m);
        // The block's texels and a one-texel border (clamped coordinates).
        for ty in by - 1..by + block + 1 {
            for tx in bx - 1..bx + block + 1 {
                let u = ((f64::from(tx) + 0.5 - f64::from(bx)) / f64::from(block)).clamp(0.0, 1.0);
                let w = ((f64::from(ty) + 0.5 - f64::from(by)) / f64::from(block)).clamp(0.0, 1.0);
                page[(ty * PAGE + tx) as usize] = pattern(k, u, w);
            }
        }
    }
    let c = DVec3::from_array(CENTRE).as_vec3();
    let mut ball = Mesh::uv_sphere("ball", c, 0.5, 1);
    ball.hints.probe = true;
    meshes.push(ball);
    let mut scene = Scene::new("room");
    scene.environment = Some(lustre_scene::Environment::constant(Rgb::splat(1.0)));
    scene.materials = vec![
        Material::diffuse("wall", Rgb::splat(0.8)),
        Material::new("ball", sphere),
    ];
    scene.meshes = meshes;
    let mut mesh_page = vec![Some(0); 6];
    mesh_page.push(None);
    let atlas = LightmapAtlas {
        width: PAGE,
        height: PAGE,
        pages: 1,
        mesh_page,
        gutter: 1,
        texels_per_metre: 0.0,
        source: AtlasSource::Texcoord1,
    };
    (scene, atlas, vec![page])
}

fn rough_metal(alpha: f64) -> MaterialKind {
    MaterialKind::RoughConductor {
        eta: Rgb([0.2, 0.4, 1.2]),
        k: Rgb([3.9, 2.4, 1.8]),
        specular: TexturedRgb::constant(Rgb::ONE),
        alpha_u: TexturedScalar::constant(alpha),
        alpha_v: TexturedScalar::constant(alpha),
        distribution: MicrofacetType::Ggx,
    }
}

/// Runs `f` with the lit scene of `scene`.
fn with_lit<R>(
    scene: &Scene,
    atlas: &LightmapAtlas,
    pages: &[Vec<[f32; 3]>],
    f: impl FnOnce(&LitScene) -> R,
) -> R {
    let (ps, _) = lustre_trace::reference::path_scene(scene).unwrap();
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = Lightmapped::new(scene, atlas, pages, &ps.geometry, bases).unwrap();
    let pt = PathTracer::new(&ps, PathOptions::default()).unwrap();
    let lit = LitScene::new(scene, &ps, &pt, &lm).unwrap();
    f(&lit)
}

fn probe_opts() -> ProbeOptions {
    ProbeOptions {
        face_size: 64,
        supersample: 2,
        plane_rays: 64,
    }
}

#[test]
fn bounding_planes_find_the_walls_and_remove_the_parallax() {
    let (scene, atlas, pages) = room(rough_metal(0.2));
    with_lit(&scene, &atlas, &pages, |lit| {
        let probe = capture_probe(lit, 6, &probe_opts()).unwrap();
        let c = DVec3::from_array(CENTRE);
        assert!(probe.centre.distance(c) < 1e-5, "{}", probe.centre);
        // One plane per wall, at the wall's distance from the centre.
        assert_eq!(probe.planes.len(), 6, "{:?}", probe.planes);
        for p in &probe.planes {
            let axis = -p.normal;
            let want = if axis.x > 0.5 {
                ROOM[0] - c.x
            } else if axis.x < -0.5 {
                c.x
            } else if axis.y > 0.5 {
                ROOM[1] - c.y
            } else if axis.y < -0.5 {
                c.y
            } else if axis.z > 0.5 {
                ROOM[2] - c.z
            } else {
                c.z
            };
            let got = p.point.dot(axis);
            assert!((got / want - 1.0).abs() < 0.01, "{axis}: {got} vs {want}");
        }
        // From points on the sphere, the probe read through the planes sees what a ray from the
        // point sees; read along the ray itself it does not.
        let mut rng = SplitMix64::new(11);
        let (mut e_fix, mut e_raw, mut norm) = (0.0, 0.0, 0.0);
        for _ in 0..400 {
            let n = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
            let p = c + n * 0.5;
            let mut d = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
            if d.dot(n) < 0.0 {
                d = -d;
            }
            let truth = lit.radiance(p, d, Some(6));
            let fix = Rgb(probe
                .pyramid
                .sample(corrected_direction(&probe.planes, p - c, d), 0.0));
            let raw = Rgb(probe.pyramid.sample(d, 0.0));
            for ch in 0..3 {
                e_fix += (fix.0[ch] - truth.0[ch]).powi(2);
                e_raw += (raw.0[ch] - truth.0[ch]).powi(2);
                norm += truth.0[ch].powi(2);
            }
        }
        let (fix, raw) = ((e_fix / norm).sqrt(), (e_raw / norm).sqrt());
        eprintln!("probe lookup rel. RMS: through the planes {fix:.4}, along the ray {raw:.4}");
        // Measured 0.072 at 64² (0.060 at 128², 0.040 at 256²: the cube's resolution).
        assert!(fix < 0.09, "corrected lookups off by {fix}");
        assert!(fix < 0.25 * raw, "{fix} vs {raw}");
    });
}

#[test]
fn a_probe_leaves_its_own_object_out() {
    let (mut scene, atlas, pages) = room(rough_metal(0.2));
    scene.meshes[6].emission = Some(Rgb([100.0, 0.0, 0.0]));
    with_lit(&scene, &atlas, &pages, |lit| {
        let c = DVec3::from_array(CENTRE);
        let max_red = |cube: &lustre_env::cube::CubeMap| {
            cube.faces
                .iter()
                .flatten()
                .map(|t| t[0])
                .fold(0.0f32, f32::max)
        };
        let without = capture_cube(lit, c, Some(6), &probe_opts()).unwrap();
        assert!(max_red(&without) < 5.0, "{}", max_red(&without));
        // From inside the sphere the (one-sided) emitter faces away, so look from outside.
        let with = capture_cube(lit, c + DVec3::new(1.2, 0.0, 0.0), None, &probe_opts()).unwrap();
        assert!(max_red(&with) > 50.0, "{}", max_red(&with));
    });
}

#[test]
fn a_probe_inside_a_solid_is_refused() {
    let (mut scene, atlas, pages) = room(rough_metal(0.2));
    // A closed pillar (outward faces) around the sphere.
    let (lo, hi) = (Vec3::new(1.0, 0.0, 1.5), Vec3::new(3.0, 2.5, 3.5));
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
    ];
    let idx = quads
        .iter()
        .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    scene
        .meshes
        .push(Mesh::new("pillar", (0..8).map(c).collect(), idx, 0));
    let mut atlas = atlas;
    atlas.mesh_page.push(None);
    with_lit(&scene, &atlas, &pages, |lit| {
        let err = capture_probe(lit, 6, &probe_opts())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("inside a solid") && err.contains("ball"),
            "{err}"
        );
        assert!(capture_probe(lit, 99, &probe_opts()).is_err());
        let bad = ProbeOptions {
            face_size: 0,
            ..probe_opts()
        };
        assert!(capture_probe(lit, 6, &bad).is_err());
    });
    // A `probe_centre` hint outside the pillar places the probe there (the planes found from
    // it); one inside the pillar is refused.
    for (centre, inside) in [([2.0, 2.6, 0.8], false), ([2.0, 1.0, 2.0], true)] {
        let mut scene = scene.clone();
        scene.meshes[6].hints.probe_centre = Some(centre);
        with_lit(&scene, &atlas, &pages, |lit| {
            match capture_probe(lit, 6, &probe_opts()) {
                Ok(probe) => {
                    assert!(!inside, "{centre:?}");
                    assert_eq!(probe.centre, DVec3::from_array(centre));
                    assert_eq!(probe.planes.len(), 6, "{:?}", probe.planes);
                }
                Err(e) => assert!(inside && e.to_string().contains("inside a solid"), "{e}"),
            }
        });
    }
}

fn camera() -> PathCamera {
    PathCamera::look_at(
        DVec3::new(2.0, 1.5, 0.4),
        DVec3::from_array(CENTRE),
        DVec3::Y,
        30.0,
    )
    .unwrap()
}

/// A frame of `lit` with `probes` at `cam`, w×h, one camera ray per pixel.
fn frame(
    lit: &LitScene,
    probes: &[lustre_shade::probe::Probe],
    cam: &PathCamera,
    (w, h): (usize, usize),
    method: (Method, u32),
    n: usize,
) -> (lustre_trace::image::Image, lustre_shade::frame::FrameStats) {
    let light = FrameLight {
        probes,
        environment: None,
    };
    let opts = FrameRequest {
        method: method.0,
        samples: n as u32,
        rays: 1,
        frames: method.1,
        seed: 3,
    };
    render_frame(lit, &light, cam, w, h, &opts).unwrap()
}

/// Regular sampling and CK at 8 and 19 samples against progressive refinement (256 frames of
/// 16 samples, the converged integral of the same incident light): regular wins at both counts
/// and reaches 38 dB at 19 (PSNR of display values with the truth's peak at white).
fn regular_beats_ck(label: &str, run: impl Fn((Method, u32), usize) -> lustre_trace::image::Image) {
    let truth = run((Method::Progressive, 256), 16);
    let peak = truth.data.iter().flatten().fold(0.0f32, |a, &b| a.max(b));
    let exposure = 1.0 / f64::from(peak);
    for n in [8, 19] {
        let p_reg =
            lustre_trace::metrics::psnr(&run((Method::Regular, 1), n), &truth, exposure).unwrap();
        let p_ck = lustre_trace::metrics::psnr(&run((Method::Ck, 1), n), &truth, exposure).unwrap();
        eprintln!("{label}, n {n}: regular {p_reg:.1} dB, CK {p_ck:.1} dB");
        assert!(p_reg > p_ck, "{label} n {n}: {p_reg} vs {p_ck}");
        if n == 19 {
            assert!(p_reg >= 38.0, "{label}: {p_reg} dB");
        }
    }
}

#[test]
fn regular_sampling_approaches_the_converged_probe_integral_and_beats_ck() {
    for alpha in [0.1, 0.3] {
        let (scene, atlas, pages) = room(rough_metal(alpha));
        with_lit(&scene, &atlas, &pages, |lit| {
            let probe = capture_probe(lit, 6, &probe_opts()).unwrap();
            let probes = [probe];
            regular_beats_ck(&format!("probe, alpha {alpha}"), |method, n| {
                frame(lit, &probes, &camera(), (40, 40), method, n).0
            });
        });
    }
}

#[test]
fn a_diffuse_frame_is_the_light_mapped_image() {
    let (mut scene, atlas, pages) = room(rough_metal(0.2));
    scene.materials[1] = Material::diffuse("ball", Rgb::splat(0.5));
    with_lit(&scene, &atlas, &pages, |lit| {
        let cam = camera();
        let opts = FrameRequest {
            method: Method::Regular,
            samples: 8,
            rays: 2,
            frames: 1,
            seed: 5,
        };
        let light = FrameLight {
            probes: &[],
            environment: None,
        };
        let (img, stats) = render_frame(lit, &light, &cam, 24, 16, &opts).unwrap();
        assert_eq!(stats.lookups, 0);
        let lm = render_lightmapped(&scene, &atlas, &pages, &cam, 24, 16, 2, 5).unwrap();
        assert_eq!(img.data, lm.data);
        // Bad sample counts are refused.
        for samples in [0, MAX_WALKTHROUGH_SAMPLES + 1] {
            let bad = FrameRequest { samples, ..opts };
            assert!(render_frame(lit, &light, &cam, 24, 16, &bad).is_err());
        }
        let bad = FrameRequest {
            method: Method::Progressive,
            frames: 0,
            ..opts
        };
        assert!(render_frame(lit, &light, &cam, 24, 16, &bad).is_err());
    });
}

fn glossy_floor(alpha: f64) -> MaterialKind {
    MaterialKind::RoughPlastic {
        diffuse: TexturedRgb::constant(Rgb::splat(0.3)),
        specular: Rgb::ONE,
        alpha: TexturedScalar::constant(alpha),
        distribution: MicrofacetType::Ggx,
        int_ior: 1.5,
        ext_ior: 1.0,
        nonlinear: false,
    }
}

/// The room with its floor a glossy planar reflector (material 2).
fn room_with_mirror_floor(alpha: f64) -> (Scene, LightmapAtlas, Vec<Vec<[f32; 3]>>) {
    let (mut scene, atlas, pages) = room(rough_metal(0.2));
    scene
        .materials
        .push(Material::new("floor", glossy_floor(alpha)));
    scene.meshes[0].material = 2;
    scene.meshes[0].hints.planar_reflector = true;
    (scene, atlas, pages)
}

#[test]
fn mirror_lookups_see_what_rays_from_the_floor_see() {
    use lustre_shade::mirror::{render_mirror, ReflectorPlane};
    let (scene, atlas, pages) = room_with_mirror_floor(0.1);
    with_lit(&scene, &atlas, &pages, |lit| {
        let cam = camera();
        let (w, h) = (160, 120);
        let m = render_mirror(lit, 0, &cam, w, h).unwrap();
        assert!((m.plane.normal - DVec3::Y).length() < 1e-9, "{:?}", m.plane);
        assert!(m.reflector.in_plane.iter().all(|&k| k));
        // Floor points seen by the camera, sample directions within 15° of the mirror
        // direction: the buffer read at the located position against a ray from the point.
        let mut rng = SplitMix64::new(5);
        let (mut err, mut norm, mut n, mut left) = (0.0, 0.0, 0, 0);
        while n < 300 {
            let (x, y) = (rng.next_f64() * w as f64, rng.next_f64() * h as f64);
            let d = cam.direction(x, y, w, h);
            let Some(hit) = lit.tracer.intersect(cam.origin, d) else {
                continue;
            };
            if lit.mesh_of[hit.prim] != 0 {
                continue;
            }
            let p = cam.origin + d * hit.t;
            let r = d - 2.0 * d.dot(DVec3::Y) * DVec3::Y;
            let jitter = lustre_brdf::sampling::uniform_sphere(rng.next_f64(), rng.next_f64());
            let wi = (r + jitter * 0.25).normalize();
            if wi.y <= 0.05 {
                continue;
            }
            let Some(((lx, ly), _)) = m.view.locate(p, wi) else {
                left += 1;
                continue;
            };
            let got = m.view.sample(lx, ly, 0.0);
            let truth = lit.radiance(p, wi, Some(0));
            for c in 0..3 {
                err += (got.0[c] - truth.0[c]).powi(2);
                norm += truth.0[c].powi(2);
            }
            n += 1;
        }
        let rel = (err / norm).sqrt();
        eprintln!("mirror lookups: rel. RMS {rel:.4} over {n} samples, {left} left the buffer");
        assert!(rel < 0.03, "{rel}");
        // A sphere is no plane.
        let err = ReflectorPlane::of_mesh(lit, 6, camera().origin)
            .unwrap_err()
            .to_string();
        assert!(err.contains("not planar") && err.contains("ball"), "{err}");
    });
}

#[test]
fn a_glossy_mirror_floor_converges_and_regular_beats_ck() {
    for alpha in [0.05, 0.2] {
        let (scene, atlas, pages) = room_with_mirror_floor(alpha);
        with_lit(&scene, &atlas, &pages, |lit| {
            let probe = capture_probe(lit, 6, &probe_opts()).unwrap();
            let probes = [probe];
            let cam = PathCamera::look_at(
                DVec3::new(2.0, 1.6, 0.3),
                DVec3::new(2.0, 0.4, 3.5),
                DVec3::Y,
                50.0,
            )
            .unwrap();
            let (_, stats) = frame(lit, &probes, &cam, (8, 6), (Method::Regular, 1), 4);
            assert_eq!(stats.mirrors, 1);
            regular_beats_ck(&format!("mirror floor, alpha {alpha}"), |method, n| {
                frame(lit, &probes, &cam, (48, 36), method, n).0
            });
        });
    }
}

/// The room with a glass pane (smooth dielectric, reflection tinted black so only the
/// transmission remains) at z = 3.5 in front of the far wall, a probe object; or without it.
fn room_with_pane(with_pane: bool) -> (Scene, LightmapAtlas, Vec<Vec<[f32; 3]>>) {
    let (mut scene, mut atlas, pages) = room(rough_metal(0.2));
    // A glowing post close behind the pane: a probe at the pane's centre would see it from
    // another angle (parallax no plane corrects); the see-through buffer sees it as the camera.
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let mut post = Mesh::new(
        "post",
        vec![
            v(2.4, 1.8, 3.7),
            v(2.8, 1.8, 3.7),
            v(2.8, 2.6, 3.7),
            v(2.4, 2.6, 3.7),
        ],
        vec![[0, 2, 1], [0, 3, 2]],
        0,
    );
    post.emission = Some(Rgb::splat(5.0));
    scene.meshes.push(post);
    atlas.mesh_page.push(None);
    if with_pane {
        push_pane(&mut scene, &mut atlas, [1.8, 1.4, 3.4, 3.0], 3.5);
    }
    (scene, atlas, pages)
}

/// Appends a glass pane (smooth dielectric, reflection tinted black, material 2), a probe
/// object, over [x0, x1] × [y0, y1] at depth z.
fn push_pane(scene: &mut Scene, atlas: &mut LightmapAtlas, [x0, y0, x1, y1]: [f32; 4], z: f32) {
    scene.materials.push(Material::new(
        "glass",
        MaterialKind::Dielectric {
            int_ior: 1.5,
            ext_ior: 1.0,
            specular_reflectance: Rgb::ZERO,
            specular_transmittance: Rgb::ONE,
        },
    ));
    let v = |x: f32, y: f32| Vec3::new(x, y, z);
    let mut pane = Mesh::new(
        "pane",
        vec![v(x0, y0), v(x1, y0), v(x1, y1), v(x0, y1)],
        vec![[0, 2, 1], [0, 3, 2]],
        2,
    );
    pane.hints.probe = true;
    scene.meshes.push(pane);
    atlas.mesh_page.push(None);
}

#[test]
fn a_glass_pane_transmits_what_lies_behind_it() {
    let cam = PathCamera::look_at(
        DVec3::new(2.6, 2.2, 0.5),
        DVec3::new(2.6, 2.2, 3.5),
        DVec3::Y,
        20.0,
    )
    .unwrap();
    let (w, h) = (32, 32);
    // The pane's probe, captured once and read by both frames: the post (no light map) takes
    // its diffuse light from the nearest probe, seen directly or through the pane's layer.
    let (scene, atlas, pages) = room_with_pane(true);
    let probes = [with_lit(&scene, &atlas, &pages, |lit| {
        capture_probe(lit, 8, &probe_opts()).unwrap()
    })];
    let render = |with_pane: bool| {
        let (scene, atlas, pages) = room_with_pane(with_pane);
        with_lit(&scene, &atlas, &pages, |lit| {
            let light = FrameLight {
                probes: &probes,
                environment: None,
            };
            let opts = FrameRequest {
                method: Method::Regular,
                samples: 8,
                rays: 1,
                frames: 1,
                seed: 1,
            };
            render_frame(lit, &light, &cam, w, h, &opts).unwrap()
        })
    };
    let (with, stats) = render(true);
    assert_eq!(stats.see_throughs, 1);
    let (without, _) = render(false);
    // At the centre the view is normal to the pane: a thin sheet transmits 1 − R' with
    // R' = 2R/(1 + R), R = ((1.5 − 1)/(1.5 + 1))² (both interfaces, all internal bounces).
    let r = (0.5f64 / 2.5).powi(2);
    let t = 1.0 - 2.0 * r / (1.0 + r);
    let centre = (h / 2) * w + w / 2;
    for c in 0..3 {
        let ratio = f64::from(with.data[centre][c]) / f64::from(without.data[centre][c]);
        assert!((ratio - t).abs() < 0.005, "channel {c}: {ratio} vs {t}");
    }
    // Every pane pixel is the wall behind it, dimmed by the sheet (no reflection: tint 0).
    // Inside the post and the wall, away from the post's edges (where the buffer's texels
    // blend what a jittered ray sees sharply), every pixel is what lies behind, dimmed.
    let (mut good, mut total, mut post) = (0, 0, 0);
    for y in 2..h - 2 {
        for x in 2..w - 2 {
            let b = without.data[y * w + x][1];
            let on_post = |q: f32| q > 4.0;
            let edge = (0..25).any(|k| {
                let q = without.data[(y + k / 5 - 2) * w + x + k % 5 - 2][1];
                on_post(q) != on_post(b)
            });
            if edge {
                continue;
            }
            let ratio = f64::from(with.data[y * w + x][1]) / f64::from(b);
            total += 1;
            good += usize::from((ratio - t).abs() < 0.03);
            post += usize::from(b > 4.0 && (ratio - t).abs() < 0.03);
        }
    }
    eprintln!("{good} of {total} pixels off the post's edges within 0.03 of T = {t:.4}, {post} on the post");
    assert!(post > 20, "the post behind the pane: {post} pixels");
    assert!(good as f64 >= 0.97 * total as f64, "{good} of {total}");
}

#[test]
fn a_thick_slab_displaces_what_shows_through_it() {
    // The pane seen at 28° from the normal: hinted a 15 cm slab, the post behind it appears
    // displaced by the refraction offset (frame::slab_offset), as a ray through the slab sees
    // it: the post's image moves by the projection of −δ; unhinted, it stays.
    let cam = PathCamera::look_at(
        DVec3::new(1.0, 2.2, 0.5),
        DVec3::new(2.6, 2.2, 3.5),
        DVec3::Y,
        20.0,
    )
    .unwrap();
    let (w, h) = (96, 96);
    let (scene, atlas, pages) = room_with_pane(true);
    let pane = scene.meshes.len() - 1;
    let probes = [with_lit(&scene, &atlas, &pages, |lit| {
        capture_probe(lit, pane, &probe_opts()).unwrap()
    })];
    let thickness = 0.15;
    // The brightness-weighted column of the post (radiance > 4) in the frame.
    let post_column = |t: Option<f64>| {
        let (mut scene, atlas, pages) = room_with_pane(true);
        scene.meshes[pane].hints.thickness = t;
        let (img, _) = with_lit(&scene, &atlas, &pages, |lit| {
            frame(lit, &probes, &cam, (w, h), (Method::Regular, 1), 8)
        });
        let (mut sx, mut sw) = (0.0, 0.0);
        for (i, p) in img.data.iter().enumerate() {
            let v = f64::from(p[1]);
            if v > 4.0 {
                sx += (i % w) as f64 * v;
                sw += v;
            }
        }
        assert!(sw > 0.0, "the post is seen");
        sx / sw
    };
    let thin = post_column(None);
    let thick = post_column(Some(thickness));
    // Predicted: the post's centre P shows where the camera sees P − δ, δ the offset along the
    // ray towards P (the offset is nearly constant over the post).
    let project = |q: DVec3| {
        let v = q - cam.origin;
        let px = v.dot(cam.right) / v.dot(cam.forward);
        (px / (cam.tan_half_fov_y * w as f64 / h as f64) + 1.0) * 0.5 * w as f64
    };
    let centre = DVec3::new(2.6, 2.2, 3.7);
    let wi = (centre - cam.origin).normalize();
    let delta = lustre_shade::frame::slab_offset(thickness, 1.5, DVec3::Z, wi);
    let expect = project(centre - delta) - project(centre);
    let got = thick - thin;
    eprintln!("post column: thin {thin:.2}, 15 cm slab {thick:.2}: shift {got:.2} px, predicted {expect:.2} px (δ = {delta})");
    assert!(expect.abs() > 1.5, "a visible offset: {expect}");
    assert!(
        (got - expect).abs() < 0.25 * expect.abs(),
        "{got} vs {expect}"
    );
}

/// The room with a glass pane (reflection tinted black) between the camera and the ball, a
/// probe object; or without it. Mesh 7 is the pane.
fn room_with_pane_before_ball(with_pane: bool) -> (Scene, LightmapAtlas, Vec<Vec<[f32; 3]>>) {
    let (mut scene, mut atlas, pages) = room(rough_metal(0.2));
    if with_pane {
        push_pane(&mut scene, &mut atlas, [1.8, 1.0, 2.2, 1.4], 1.0);
    }
    (scene, atlas, pages)
}

/// What shows through glass keeps its view-dependent part (the see-through layer): the rough
/// metal ball (no diffuse part, so nothing without its glossy integral) seen through a pane is
/// the ball seen directly, dimmed by the sheet's transmittance T, reading the same probe.
/// Before the layer the ball behind the pane came out black.
#[test]
fn a_glossy_object_behind_glass_keeps_its_reflections() {
    use lustre_shade::mirror::{ScreenTiles, SCREEN_TILE, SCREEN_TILE_MARGIN};
    let cam = PathCamera::look_at(
        DVec3::new(2.0, 1.2, 0.1),
        DVec3::from_array(CENTRE),
        DVec3::Y,
        50.0,
    )
    .unwrap();
    let (w, h) = (48, 48);
    // The ball's probe, captured once (with the pane in the room) and read by both frames.
    let (scene, atlas, pages) = room_with_pane_before_ball(true);
    let probe = with_lit(&scene, &atlas, &pages, |lit| {
        // The pane's tiles: those of its pixels, widened by the margin; no other.
        // (At 192² the pane spans about half the view.)
        let (w, h) = (192, 192);
        let tiles = ScreenTiles::of_mesh(lit, 7, &cam, w, h);
        let margin = w.max(h) as f64 * SCREEN_TILE_MARGIN;
        let pane_px: Vec<[f64; 2]> = lit.scene.meshes[7]
            .positions
            .iter()
            .map(|p| {
                // The pixel of the vertex, found by the camera's own rays (a fine scan).
                let d = (p.as_dvec3() - cam.origin).normalize();
                let (mut best, mut at) = (f64::INFINITY, [0.0, 0.0]);
                for j in 0..=4 * h {
                    for i in 0..=4 * w {
                        let (x, y) = (i as f64 / 4.0, j as f64 / 4.0);
                        let e = (cam.direction(x, y, w, h) - d).length();
                        if e < best {
                            (best, at) = (e, [x, y]);
                        }
                    }
                }
                at
            })
            .collect();
        let lo = [0, 1].map(|k| pane_px.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min));
        let hi = [0, 1].map(|k| {
            pane_px
                .iter()
                .map(|p| p[k])
                .fold(f64::NEG_INFINITY, f64::max)
        });
        let (mut inside, mut covered_far) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                let dist = (lo[0] - cx).max(cx - hi[0]).max(lo[1] - cy).max(cy - hi[1]);
                if dist <= 0.0 {
                    // Every pixel of the (axis-aligned) pane is in a covered tile.
                    assert!(tiles.covers(x, y), "pane pixel ({x}, {y}) not covered");
                    inside += 1;
                }
                // No tile reaches beyond the margin plus a tile's diagonal.
                if dist > margin + SCREEN_TILE as f64 * 1.5 && tiles.covers(x, y) {
                    covered_far += 1;
                }
            }
        }
        assert!(inside > 100, "{inside} pane pixels");
        if covered_far > 0 {
            for r in 0..tiles.rows {
                let row: String = (0..tiles.cols)
                    .map(|c| {
                        if tiles.covered[r * tiles.cols + c] {
                            '#'
                        } else {
                            '.'
                        }
                    })
                    .collect();
                eprintln!("{row}");
            }
            eprintln!("pane pixels {lo:?} .. {hi:?}, margin {margin}");
        }
        assert_eq!(covered_far, 0);
        let share =
            tiles.covered.iter().filter(|&&c| c).count() as f64 / tiles.covered.len() as f64;
        eprintln!(
            "pane tiles: {:.1} % of the 192² view's, {inside} pane pixels",
            share * 100.0
        );
        assert!(share < 0.6, "{share}");
        // A camera facing away: every tile.
        let back =
            PathCamera::look_at(cam.origin, cam.origin - cam.forward, DVec3::Y, 50.0).unwrap();
        assert_eq!(
            ScreenTiles::of_mesh(lit, 7, &back, w, h),
            ScreenTiles::all(w, h)
        );
        capture_probe(lit, 6, &probe_opts()).unwrap()
    });
    let probes = [probe];
    let render = |with_pane: bool| {
        let (scene, atlas, pages) = room_with_pane_before_ball(with_pane);
        with_lit(&scene, &atlas, &pages, |lit| {
            frame(lit, &probes, &cam, (w, h), (Method::Regular, 1), 8)
        })
    };
    let ((with, stats), (without, _)) = (render(true), render(false));
    assert_eq!(stats.see_throughs, 1);
    let r = (0.5f64 / 2.5).powi(2);
    let t = 1.0 - 2.0 * r / (1.0 + r);
    // Ball pixels away from its silhouette (the jittered rays and the buffer's texel centres
    // see the same smooth reflection).
    let on_ball = |x: usize, y: usize| {
        let d = cam.direction(x as f64 + 0.5, y as f64 + 0.5, w, h);
        let to = DVec3::from_array(CENTRE) - cam.origin;
        (to - d * to.dot(d)).length() < 0.35
    };
    let (mut sum, mut good, mut total) = (0.0, 0, 0);
    for y in 0..h {
        for x in 0..w {
            if !on_ball(x, y) {
                continue;
            }
            let a: f64 = (0..3).map(|c| f64::from(with.data[y * w + x][c])).sum();
            let b: f64 = (0..3).map(|c| f64::from(without.data[y * w + x][c])).sum();
            assert!(b > 0.05, "the ball seen directly is lit: {b}");
            let ratio = a / b;
            sum += ratio;
            total += 1;
            good += usize::from((ratio - t).abs() < 0.05);
        }
    }
    let mean = sum / total as f64;
    eprintln!(
        "ball behind glass: mean ratio {mean:.4} (T = {t:.4}), {good} of {total} within 0.05"
    );
    assert!(total > 150, "{total} ball pixels");
    assert!((mean - t).abs() < 0.02, "mean ratio {mean} vs T {t}");
    assert!(good as f64 >= 0.9 * total as f64, "{good} of {total}");
}

/// An object's own sample budget (`ObjectHints::samples`) replaces the frame's for its pixels:
/// the ball (mesh 6, the only glossy object) at 3 samples makes at most 3 lookups per glossy
/// hit while the frame asks 16, and the image equals the frame rendered at 3 throughout.
#[test]
fn an_objects_own_sample_budget_replaces_the_frames() {
    let (scene, atlas, pages) = room(rough_metal(0.2));
    let mut hinted = scene.clone();
    hinted.meshes[6].hints.samples = Some(3);
    let probe = with_lit(&scene, &atlas, &pages, |lit| {
        capture_probe(lit, 6, &probe_opts()).unwrap()
    });
    let probes = [probe];
    let at3 = with_lit(&scene, &atlas, &pages, |lit| {
        frame(lit, &probes, &camera(), (32, 32), (Method::Regular, 1), 3)
    });
    let (img, stats) = with_lit(&hinted, &atlas, &pages, |lit| {
        frame(lit, &probes, &camera(), (32, 32), (Method::Regular, 1), 16)
    });
    assert!(stats.glossy_hits > 50, "{stats:?}");
    assert!(stats.lookups <= 3 * stats.glossy_hits, "{stats:?}");
    assert_eq!(img.data, at3.0.data);
    assert_eq!(stats.lookups, at3.1.lookups);
}
