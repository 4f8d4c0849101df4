//! Probes captured and filtered on the GPU, and the mirror and see-through passes on the GPU,
//! against their CPU twins (the same shading, pyramid and box MIP on the read-back G-buffers,
//! ≥ 90 dB) and against the CPU ray casting of `lustre_shade::probe` / `lustre_shade::mirror`
//! (raster vs ray-cast edges may differ), on the built-in room and the Modern Hall (light maps
//! baked small and fast). Fails (does not skip) without an adapter.

mod common;
use common::{ctx, quick_bake, Baked};
use glam::DVec3;
use lustre_brdf::rgb::Rgb;
use lustre_env::{CubeMap, CubePyramid, MipFilter};
use lustre_gpu::{
    face_camera, mesh_triangles, DrawOptions, GpuContext, GpuProbeCapture, GpuPyramidBuilder,
    GpuTimer, GpuViewPass, LightmapFrameScene, PYRAMID_USAGE,
};
use lustre_scene::Scene;
use lustre_shade::mirror::{box_levels, render_mirror, render_see_through, ViewBuffer};
use lustre_shade::probe::{capture_cube, probe_placement, LitScene, ProbeOptions};
use lustre_trace::bake::diffuse_path_scene;
use lustre_trace::bake::gbuffer::{shade_gbuffer, VisibilityBuffer, SKY};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::image::Image;
use lustre_trace::metrics::psnr;
use lustre_trace::path_tracer::{PathCamera, PathOptions, PathScene, PathTracer};
use lustre_trace::reference::path_camera;

fn room() -> Baked {
    quick_bake(lustre_scene::builtin::room().expect("built-in room"), 4.0)
}

fn hall() -> Baked {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/modern_hall.toml");
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    quick_bake(scene, 4.0)
}

fn mesh_named(scene: &Scene, name: &str) -> usize {
    scene
        .meshes
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| panic!("no mesh {name}"))
}

/// Runs `f` with the CPU's lit scene of `b` and its path scene.
fn with_lit<R>(b: &Baked, f: impl FnOnce(&LitScene, &PathScene) -> R) -> R {
    let (ps, bases, _) = diffuse_path_scene(&b.scene).expect("path scene");
    let lm = Lightmapped::new(&b.scene, &b.atlas, &b.pages, &ps.geometry, bases).expect("lit");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(&b.scene, &ps, &pt, &lm).expect("lit scene");
    f(&lit, &ps)
}

/// The six faces stacked vertically as one image.
fn cube_image(c: &CubeMap) -> Image {
    let data = c.faces.iter().flat_map(|f| f.iter().copied()).collect();
    Image::from_data(c.size, 6 * c.size, data).expect("image")
}

fn rgb_image(w: usize, h: usize, px: &[Rgb]) -> Image {
    Image::from_data(w, h, px.iter().map(|p| p.0.map(|v| v as f32)).collect()).expect("image")
}

/// The exposure mapping the mean of `img` to ½ (so that display clamping hides little).
fn exposure(img: &Image) -> f64 {
    0.5 / img.mean().max(1e-6)
}

/// Fraction of texels whose largest channel differs by more than 1 % of the image mean.
fn differing(a: &Image, b: &Image) -> f64 {
    let tol = 0.01 * b.mean();
    let n = a
        .data
        .iter()
        .zip(&b.data)
        .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() as f64 > tol))
        .count();
    n as f64 / a.data.len() as f64
}

const FACE: usize = 48;
const K: u32 = 2;

/// Captures the probe of `mesh` on the GPU and checks it against the twin (≥ 90 dB at every
/// level) and the ray-cast CPU capture (reported; asserted loosely, raster vs ray edges).
fn check_probe(
    ctx: &GpuContext,
    cap: &GpuProbeCapture,
    b: &Baked,
    up: &LightmapFrameScene,
    mesh: usize,
    label: &str,
) {
    with_lit(b, |lit, ps| {
        let opts = ProbeOptions {
            face_size: FACE,
            supersample: K,
            plane_rays: 32,
        };
        let probe = cap.capture_probe(ctx, up, lit, mesh, &opts).unwrap();
        let (_, centre) = probe_placement(lit, mesh).unwrap();
        assert_eq!(probe.centre, centre);
        assert!(!probe.planes.is_empty(), "{label}: no bounding planes");
        let host = probe.read_back(ctx).unwrap();
        assert_eq!((host.mesh, host.centre), (Some(mesh as u32), centre));
        assert_eq!(host.planes, probe.planes);
        let gpu = host.pyramid;
        // The twin: the same G-buffer faces shaded on the CPU, the CPU pyramid.
        let skip = mesh_triangles(&b.scene, mesh).unwrap();
        let faces: Vec<Vec<[f32; 3]>> = (0..6)
            .map(|f| {
                let gb = cap
                    .face_gbuffer(ctx, up, centre, Some(skip.clone()), f, FACE, K)
                    .unwrap();
                assert!(
                    gb.prim.iter().all(|&p| p == SKY || !skip.contains(&p)),
                    "{label}: the probe's own triangles were drawn"
                );
                let img = shade_gbuffer(
                    lit.lit,
                    &ps.geometry,
                    ps.environment.as_ref(),
                    &face_camera(centre, f),
                    &gb,
                    K,
                )
                .unwrap();
                img.data
            })
            .collect();
        let twin_cube = CubeMap::new(FACE, faces.try_into().unwrap()).unwrap();
        let twin = CubePyramid::build(twin_cube.clone(), MipFilter::Gauss6).unwrap();
        assert_eq!(gpu.levels.len(), twin.levels.len());
        let e = exposure(&cube_image(&twin_cube));
        let mut worst = f64::INFINITY;
        for (l, (g, c)) in gpu.levels.iter().zip(&twin.levels).enumerate() {
            let db = psnr(&cube_image(g), &cube_image(c), e).unwrap();
            worst = worst.min(db);
            assert!(db >= 90.0, "{label}: level {l} twin parity {db} dB");
        }
        // The CPU ray-cast capture of the same probe.
        let ray = capture_cube(lit, centre, Some(mesh as u32), &opts).unwrap();
        let (gi, ri) = (cube_image(&gpu.levels[0]), cube_image(&ray));
        let db = psnr(&gi, &ri, e).unwrap();
        let diff = differing(&gi, &ri);
        eprintln!(
            "{label} probe ({}, {FACE}² faces, {K}×{K}): twin parity ≥ {worst:.1} dB over {} levels; vs CPU ray-cast capture {db:.1} dB, {:.2} % of texels differ by > 1 % of the mean",
            probe.name,
            gpu.levels.len(),
            100.0 * diff
        );
        assert!(
            db >= 30.0 && diff < 0.05,
            "{label}: ray-cast agreement {db} dB, {diff}"
        );
    });
}

#[test]
fn gpu_probes_match_their_twin_and_the_ray_cast_capture() {
    let ctx = ctx();
    let cap = GpuProbeCapture::new(&ctx).unwrap();
    let b = room();
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let probes: Vec<usize> = (0..b.scene.meshes.len())
        .filter(|&m| b.scene.meshes[m].hints.probe)
        .collect();
    assert_eq!(probes.len(), 3);
    for m in probes {
        check_probe(&ctx, &cap, &b, &up, m, "built-in room");
    }
    let h = hall();
    let up = LightmapFrameScene::upload(&ctx, &h.scene, &h.atlas, &h.pages).unwrap();
    let m = mesh_named(&h.scene, "Mesh014");
    check_probe(&ctx, &cap, &h, &up, m, "Modern Hall");
}

/// Checks a GPU view buffer against its twin (shading, box MIP, geometry from the read-back
/// G-buffer; ≥ 90 dB at every level, positions within 10⁻⁵ of the scene's diagonal) and
/// returns its agreement with the CPU ray-cast buffer.
fn check_view(
    gpu: &ViewBuffer,
    gb: &VisibilityBuffer,
    lit: &LitScene,
    ps: &PathScene,
    cpu: &ViewBuffer,
    label: &str,
) -> ViewAgreement {
    let (w, h) = (gpu.width, gpu.height);
    let cam: &PathCamera = &gpu.camera;
    // Twin radiance and its levels.
    let img = shade_gbuffer(lit.lit, &ps.geometry, ps.environment.as_ref(), cam, gb, 1).unwrap();
    let level0: Vec<Rgb> = img.data.iter().map(|p| Rgb(p.map(f64::from))).collect();
    let twin = box_levels(w, h, level0);
    assert_eq!(twin.len(), gpu.levels.len(), "{label}");
    let e = exposure(&img);
    for (l, (t, g)) in twin.iter().zip(&gpu.levels).enumerate() {
        assert_eq!((t.0, t.1), (g.0, g.1), "{label}: level {l} size");
        let db = psnr(&rgb_image(g.0, g.1, &g.2), &rgb_image(t.0, t.1, &t.2), e).unwrap();
        assert!(db >= 90.0, "{label}: level {l} twin parity {db} dB");
    }
    // Twin geometry: corners interpolated with the read-back barycentrics (f64).
    let g = &ps.geometry;
    let (lo, hi) = g
        .positions
        .iter()
        .flatten()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), p| {
            (a.min(*p), b.max(*p))
        });
    let diag = (hi - lo).length();
    for (i, t) in gpu.texels.iter().enumerate() {
        match gb.prim[i] {
            SKY => assert!(t.position.is_none() && t.normal == DVec3::ZERO, "{label}"),
            p => {
                let tri = &g.positions[p as usize];
                let [b1, b2] = gb.bary[i].map(f64::from);
                let x = tri[0] * (1.0 - b1 - b2) + tri[1] * b1 + tri[2] * b2;
                let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
                let q = t
                    .position
                    .unwrap_or_else(|| panic!("{label}: texel {i} lost its hit"));
                assert!(
                    (q - x).length() <= 1e-5 * diag,
                    "{label}: position {q} vs {x}"
                );
                assert!(
                    (t.normal - n).length() <= 1e-4,
                    "{label}: normal {} vs {n}",
                    t.normal
                );
            }
        }
    }
    // Against the CPU ray-cast buffer.
    let hits = gpu
        .texels
        .iter()
        .zip(&cpu.texels)
        .filter(|(a, b)| a.position.is_some() == b.position.is_some())
        .count() as f64
        / (w * h) as f64;
    let pos = gpu
        .texels
        .iter()
        .zip(&cpu.texels)
        .filter(|(a, b)| match (a.position, b.position) {
            (Some(p), Some(q)) => (p - q).length() <= 1e-3 * diag,
            (None, None) => true,
            _ => false,
        })
        .count() as f64
        / (w * h) as f64;
    let c0 = rgb_image(w, h, &cpu.levels[0].2);
    let g0 = rgb_image(w, h, &gpu.levels[0].2);
    let db = psnr(&g0, &c0, e).unwrap();
    // The same over the texels whose positions agree (the others set equal).
    let mut masked = g0.clone();
    for (i, (a, b)) in gpu.texels.iter().zip(&cpu.texels).enumerate() {
        let same = match (a.position, b.position) {
            (Some(p), Some(q)) => (p - q).length() <= 1e-3 * diag,
            (None, None) => true,
            _ => false,
        };
        if !same {
            masked.data[i] = c0.data[i];
        }
    }
    let db_agreeing = psnr(&masked, &c0, e).unwrap();
    ViewAgreement {
        db,
        db_agreeing,
        hits,
        positions: pos,
    }
}

/// A GPU view buffer against the CPU ray-cast one.
struct ViewAgreement {
    /// PSNR of the level-0 radiance.
    db: f64,
    /// The same over the texels whose positions agree.
    db_agreeing: f64,
    /// Fraction of texels whose hit flags agree.
    hits: f64,
    /// Fraction whose positions agree (within 10⁻³ of the scene's diagonal, or both none).
    positions: f64,
}

impl std::fmt::Display for ViewAgreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "vs CPU ray cast {:.1} dB ({:.1} dB over texels whose positions agree), hit flags agree on {:.2} %, positions on {:.2} %",
            self.db,
            self.db_agreeing,
            100.0 * self.hits,
            100.0 * self.positions
        )
    }
}

#[test]
fn gpu_mirror_and_see_through_buffers_match_their_twin_and_ray_casting() {
    let ctx = ctx();
    let pass = GpuViewPass::new(&ctx).unwrap();
    let (w, h) = (168, 105);
    let b = room();
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let cam = path_camera(&b.scene, None, w as u32, h as u32).unwrap();
    let floor = (0..b.scene.meshes.len())
        .find(|&m| b.scene.meshes[m].hints.planar_reflector)
        .unwrap();
    let glass = mesh_named(&b.scene, "frosted-glass");
    with_lit(&b, |lit, ps| {
        let (refl, r) = pass
            .render_mirror(&ctx, &up, lit, floor, &cam, w, h)
            .unwrap();
        let gpu = r.view.read_back(&ctx).unwrap();
        let gb = r.gbuffer.read_back(&ctx).unwrap();
        let cpu = render_mirror(lit, floor, &cam, w, h).unwrap();
        assert_eq!(refl, cpu.reflector);
        assert_eq!(gpu.camera, cpu.view.camera);
        assert_eq!(gpu.front, cpu.view.front);
        let a = check_view(&gpu, &gb, lit, ps, &cpu.view, "room mirror");
        eprintln!("built-in room floor mirror {w}×{h}: twin ≥ 90 dB at every level; {a}");
        assert!(
            a.hits >= 0.995 && a.positions >= 0.99 && a.db >= 60.0,
            "room mirror: {a}"
        );
        let r = pass
            .render_see_through(&ctx, &up, lit, glass, &cam, w, h)
            .unwrap();
        let gpu = r.view.read_back(&ctx).unwrap();
        let gb = r.gbuffer.read_back(&ctx).unwrap();
        assert!(gb
            .prim
            .iter()
            .all(|&p| p == SKY || !mesh_triangles(&b.scene, glass).unwrap().contains(&p)));
        let cpu = render_see_through(lit, glass, &cam, w, h).unwrap();
        assert!(gpu.front.is_none() && gpu.mesh == glass as u32);
        let a = check_view(&gpu, &gb, lit, ps, &cpu, "room see-through");
        eprintln!("built-in room see-through (frosted glass) {w}×{h}: twin ≥ 90 dB; {a}");
        assert!(
            a.hits >= 0.995 && a.positions >= 0.99 && a.db >= 40.0,
            "room see-through: {a}"
        );
    });
    let a = floor_mirror(&ctx, &pass, &hall(), "Mesh011", (w, h), "hall mirror");
    eprintln!("Modern Hall floor (Mesh011) mirror {w}×{h}: twin ≥ 90 dB at every level; {a}");
    // Raster vs ray casting: surfaces seen edge-on at the mirrored eye's height rasterise as a
    // one-texel line the rays miss.
    assert!(
        a.hits >= 0.99 && a.positions >= 0.99 && a.db >= 25.0 && a.db_agreeing >= 40.0,
        "hall mirror: {a}"
    );
}

/// The GPU mirror buffer of mesh `floor` of `b` from its first camera at w×h, held to its twin
/// at every level ([`check_view`]) and against the CPU's ray-cast mirror.
fn floor_mirror(
    ctx: &GpuContext,
    pass: &GpuViewPass,
    b: &Baked,
    floor: &str,
    (w, h): (usize, usize),
    label: &str,
) -> ViewAgreement {
    let up = LightmapFrameScene::upload(ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let cam = path_camera(&b.scene, None, w as u32, h as u32).unwrap();
    let floor = mesh_named(&b.scene, floor);
    with_lit(b, |lit, ps| {
        let (_, r) = pass
            .render_mirror(ctx, &up, lit, floor, &cam, w, h)
            .unwrap();
        let gpu = r.view.read_back(ctx).unwrap();
        let gb = r.gbuffer.read_back(ctx).unwrap();
        let cpu = render_mirror(lit, floor, &cam, w, h).unwrap();
        check_view(&gpu, &gb, lit, ps, &cpu.view, label)
    })
}

/// The sunroom on its 2 km ground plane (scenes/sunroom/site.xml): the floor's mirror buffer on
/// the GPU keeps the bottom of the walls. Surfaces count as in the clip plane within 10⁻⁴ of the
/// reflector's diagonal, not of the scene's (28 cm here, which clipped the walls' bottom out of
/// the mirror and let it show the sunlit ground through them).
#[test]
fn gpu_mirror_of_a_room_on_a_vast_site_keeps_its_walls() {
    let ctx = ctx();
    let pass = GpuViewPass::new(&ctx).unwrap();
    let (w, h) = (96, 72);
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sunroom/site.xml");
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    // The ground coarse in the light maps (16 texels), the room at 4 per metre.
    let ground = mesh_named(&scene, "Ground");
    scene.meshes[ground].hints.lightmap_texels_per_metre = Some(0.002);
    let b = quick_bake(scene, 4.0);
    let a = floor_mirror(&ctx, &pass, &b, "Floor", (w, h), "site mirror");
    eprintln!("sunroom on its site, floor mirror {w}×{h}: twin ≥ 90 dB at every level; {a}");
    assert!(
        a.hits >= 0.995 && a.positions >= 0.99 && a.db >= 40.0,
        "site mirror: {a}"
    );
}

/// The clip plane removes exactly what lies between the eye and the plane: a camera above the
/// floor clipping at a plane through the room's middle height sees nothing below it except
/// along rays that leave the plane.
#[test]
fn clip_plane_discards_between_eye_and_plane_and_bad_input_errs() {
    let ctx = ctx();
    let pass = GpuViewPass::new(&ctx).unwrap();
    let b = room();
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let cam = PathCamera::look_at(
        DVec3::new(3.0, 2.5, 7.0),
        DVec3::new(3.0, 0.0, 2.0),
        DVec3::Y,
        60.0,
    )
    .unwrap();
    let y0 = 1.5;
    let opts = DrawOptions {
        skip: None,
        plane: Some((DVec3::new(0.0, y0, 0.0), DVec3::Y)),
        plane_tolerance: None,
        through_glass: false,
    };
    let r = pass
        .render_view(&ctx, &up, &cam, 64, 48, &opts, 0, None)
        .unwrap();
    let v = r.view.read_back(&ctx).unwrap();
    let mut seen = 0;
    for t in &v.texels {
        if let Some(p) = t.position {
            // The eye is at y = 2.5 > y0: nothing between y0 and 2.5 survives.
            assert!(
                !(p.y > y0 + 1e-4 && p.y < 2.5 - 1e-4),
                "{p} was not clipped"
            );
            seen += 1;
        }
    }
    assert!(
        seen > 64 * 48 / 2,
        "the view below the plane is mostly empty: {seen}"
    );
    // Bad input.
    let ok_lit = |f: &dyn Fn(&LitScene)| with_lit(&b, |lit, _| f(lit));
    ok_lit(&|lit| {
        let cap = GpuProbeCapture::new(&ctx).unwrap();
        let bad = ProbeOptions {
            face_size: 0,
            ..ProbeOptions::default()
        };
        let e = cap.capture_probe(&ctx, &up, lit, 5, &bad).unwrap_err();
        assert!(e.to_string().contains("face size"), "{e}");
        let e = cap
            .capture_probe(&ctx, &up, lit, 999, &ProbeOptions::default())
            .unwrap_err();
        assert!(e.to_string().contains("999"), "{e}");
        // A sphere is not a planar reflector.
        let sphere = mesh_named(&b.scene, "gold-paint");
        let e = pass
            .render_mirror(&ctx, &up, lit, sphere, &cam, 8, 8)
            .unwrap_err();
        assert!(e.to_string().contains("not planar"), "{e}");
        let e = pass
            .render_see_through(&ctx, &up, lit, 999, &cam, 8, 8)
            .unwrap_err();
        assert!(e.to_string().contains("999"), "{e}");
    });
    // A base buffer of the wrong size for the pyramid.
    let builder = GpuPyramidBuilder::new(&ctx).unwrap();
    let small = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: 6 * 4 * 4 * 16,
        usage: PYRAMID_USAGE,
        mapped_at_creation: false,
    });
    let e = builder
        .build_from_buffer(&ctx, small, 8, MipFilter::Gauss6)
        .unwrap_err();
    assert!(e.to_string().contains("cube pyramid"), "{e}");
    let e = pass
        .render_view(&ctx, &up, &cam, 0, 8, &DrawOptions::default(), 0, None)
        .unwrap_err();
    assert!(e.to_string().contains("view buffer size"), "{e}");
    let degenerate = DrawOptions {
        skip: None,
        plane: Some((DVec3::ZERO, DVec3::ZERO)),
        plane_tolerance: None,
        through_glass: false,
    };
    let e = pass
        .render_view(&ctx, &up, &cam, 8, 8, &degenerate, 0, None)
        .unwrap_err();
    assert!(e.to_string().contains("clip plane"), "{e}");
}

/// The timer measures a real interval: GPU time within wall time, both positive; a stop
/// without a start errs.
#[test]
fn gpu_timer_measures_work() {
    let ctx = ctx();
    let pass = GpuViewPass::new(&ctx).unwrap();
    let b = room();
    let up = LightmapFrameScene::upload(&ctx, &b.scene, &b.atlas, &b.pages).unwrap();
    let cam = path_camera(&b.scene, None, 320, 200).unwrap();
    let mut timer = GpuTimer::new(&ctx);
    assert!(timer.stop(&ctx).is_err());
    timer.start(&ctx).unwrap();
    pass.render_view(&ctx, &up, &cam, 320, 200, &DrawOptions::default(), 0, None)
        .unwrap();
    let t = timer.stop(&ctx).unwrap();
    eprintln!(
        "{}: timestamps {}; view pass 320×200: {t:?}",
        ctx.describe(),
        timer.has_timestamps()
    );
    assert!(t.wall_ms > 0.0);
    if let Some(g) = t.gpu_ms {
        assert!(g > 0.0 && g <= t.wall_ms * 1.01, "{g} vs {}", t.wall_ms);
    }
}
