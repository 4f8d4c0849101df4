//! The persistent GPU frame (`GpuFrameSession`) on the built-in room: F still steps
//! of a progressive refinement give the image of one `GpuWalkthrough::render` with F frames; a
//! moved camera resets to a fresh first frame; a new size or supersampling reallocates and
//! renders that size; a still regular frame runs no pass and keeps its image; bad options are
//! refused without losing the frame. And the accumulation converges: after 1, 16 and 64 still
//! frames the PSNR against the CPU twin's converged integral of the same incident light
//! (`shade_gbuffer_view_dependent` with many progressive frames on the GPU's read-back
//! intermediates) rises. Fails without an adapter.

mod common;
use common::{ctx, frame_buffers, quick_bake};
use glam::DVec3;
use lustre_gpu::{
    GpuContext, GpuFrameSession, GpuWalkthrough, LightmapFrameScene, SessionIntermediates, StepWork,
};
use lustre_scene::Scene;
use lustre_shade::frame::{shade_gbuffer_view_dependent, FrameLight};
use lustre_shade::probe::{LitScene, Probe, ProbeOptions};
use lustre_shade::request::{FrameRequest, Method};
use lustre_trace::bake::render::Lightmapped;
use lustre_trace::bake::{base_albedo, BaseAlbedo};
use lustre_trace::image::Image;
use lustre_trace::metrics::psnr;
use lustre_trace::path_tracer::{PathCamera, PathOptions, PathTracer};
use lustre_trace::reference::{path_camera, path_scene};

const PROBES: ProbeOptions = ProbeOptions {
    face_size: 32,
    supersample: 1,
    plane_rays: 16,
};

/// Runs `f` on the built-in room (quick bake) with its GPU walkthrough.
fn with_room(f: impl FnOnce(&GpuContext, &Scene, &LitScene, &mut GpuWalkthrough)) {
    let ctx = ctx();
    let scene = lustre_scene::builtin::room().expect("room");
    let common::Baked {
        scene,
        atlas,
        pages,
    } = quick_bake(scene, 4.0);
    let (ps, _) = path_scene(&scene).expect("path scene");
    let bases: Vec<BaseAlbedo> = scene.materials.iter().map(base_albedo).collect();
    let lm = Lightmapped::new(&scene, &atlas, &pages, &ps.geometry, bases).expect("light maps");
    let pt = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    let lit = LitScene::new(&scene, &ps, &pt, &lm).expect("lit");
    let up = LightmapFrameScene::upload(&ctx, &scene, &atlas, &pages).expect("upload");
    let mut walk = GpuWalkthrough::new(&ctx, &lit, up, &PROBES, None).expect("walkthrough");
    f(&ctx, &scene, &lit, &mut walk);
}

fn options(method: (Method, u32), supersampling: u32) -> FrameRequest {
    FrameRequest {
        method: method.0,
        samples: 8,
        rays: supersampling * supersampling,
        frames: method.1,
        seed: 3,
    }
}

const fn progressive(frames: u32) -> (Method, u32) {
    (Method::Progressive, frames)
}

/// Bit-for-bit equality of two images.
fn same(a: &Image, b: &Image) -> bool {
    (a.width, a.height) == (b.width, b.height)
        && a.data
            .iter()
            .flatten()
            .zip(b.data.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits())
}

#[test]
fn the_session_accumulates_still_frames_and_resets_on_change() {
    with_room(|ctx, scene, lit, walk| {
        let walk = &*walk;
        let (w, h) = (48usize, 32usize);
        let camera = path_camera(scene, None, w as u32, h as u32).expect("camera");
        let render = |camera: &PathCamera, size, opts: FrameRequest| {
            walk.render(ctx, lit, camera, size, &opts)
                .expect("GPU frame")
                .image
        };
        let mut s = GpuFrameSession::new();
        assert!(s.image(ctx).is_err(), "no frame before the first step");
        assert!(s.intermediates().is_none());

        // Four still steps of a progressive refinement: one frame each, the view buffers,
        // G-buffer and light-map shading rendered by the first only.
        let prog4 = options(progressive(4), 1);
        let mut first = None;
        for i in 0..4u32 {
            let step = s
                .step(ctx, walk, lit, &camera, (w, h), &prog4)
                .expect("step");
            let t = step.times;
            assert_eq!(step.frames, i + 1);
            assert!(t.shade_ms > 0.0, "{t:?}");
            assert_eq!((step.stats.mirrors, step.stats.see_throughs), (1, 1));
            assert!(step.stats.glossy_hits > 0);
            if i == 0 {
                assert_eq!(step.work, StepWork::Allocated);
                assert!(t.views_ms > 0.0 && t.gbuffer_ms > 0.0 && t.lightmap_ms > 0.0);
                first = Some(s.image(ctx).expect("frame 1"));
            } else {
                assert_eq!(step.work, StepWork::Accumulated);
                assert_eq!((t.views_ms, t.gbuffer_ms, t.lightmap_ms), (0.0, 0.0, 0.0));
                assert_eq!(step.stats.mirror_seconds, 0.0);
            }
        }
        let still = s.image(ctx).expect("image");
        let once = render(&camera, (w, h), prog4);
        let db = psnr(&still, &once, 1.0).expect("psnr");
        let first = first.expect("frame 1");
        println!(
            "4 still steps vs one render of 4 progressive frames: bit for bit {}, {db:.1} dB; \
             against the first frame alone {:.1} dB",
            same(&still, &once),
            psnr(&still, &first, 1.0).expect("psnr")
        );
        assert!(same(&still, &once), "{db:.1} dB");
        assert!(!same(&still, &first), "frames 2–4 changed the image");

        // At its frame count the refinement holds: no pass, the same image.
        let step = s
            .step(ctx, walk, lit, &camera, (w, h), &prog4)
            .expect("step");
        assert_eq!((step.work, step.frames), (StepWork::Unchanged, 4));
        assert_eq!(step.times.total_ms(), 0.0);
        assert!(same(&s.image(ctx).expect("image"), &still));
        // A larger frame count continues; a smaller one than the image holds starts over.
        let step = s
            .step(ctx, walk, lit, &camera, (w, h), &options(progressive(6), 1))
            .expect("step");
        assert_eq!((step.work, step.frames), (StepWork::Accumulated, 5));
        let step = s
            .step(ctx, walk, lit, &camera, (w, h), &prog4)
            .expect("step");
        assert_eq!((step.work, step.frames), (StepWork::Reshaded, 1));
        assert_eq!(step.times.views_ms + step.times.gbuffer_ms, 0.0);
        assert!(same(&s.image(ctx).expect("image"), &first));

        // Bad options are refused by name and leave the frame as it was.
        let err = s
            .step(ctx, walk, lit, &camera, (w, h), &options(progressive(0), 1))
            .expect_err("0 frames")
            .to_string();
        assert!(err.contains("0 frames"), "{err}");
        let bad = FrameRequest {
            samples: 0,
            ..prog4
        };
        let err = s
            .step(ctx, walk, lit, &camera, (w, h), &bad)
            .expect_err("0 samples")
            .to_string();
        assert!(err.contains("samples"), "{err}");
        assert!(s
            .step(ctx, walk, lit, &camera, (0, h), &prog4)
            .expect_err("empty")
            .to_string()
            .contains("empty"));
        assert_eq!(s.frames(), 1);
        assert!(same(&s.image(ctx).expect("image"), &first));

        // A moved camera: the accumulation restarts at frame 0 of the new view.
        for _ in 0..3 {
            s.step(ctx, walk, lit, &camera, (w, h), &prog4)
                .expect("step");
        }
        let moved = PathCamera {
            origin: camera.origin + DVec3::new(0.05, 0.02, 0.0),
            ..camera
        };
        let step = s
            .step(ctx, walk, lit, &moved, (w, h), &prog4)
            .expect("step");
        assert_eq!((step.work, step.frames), (StepWork::Moved, 1));
        assert!(step.times.views_ms > 0.0 && step.times.gbuffer_ms > 0.0);
        let reset = s.image(ctx).expect("image");
        let fresh = render(&moved, (w, h), options(progressive(1), 1));
        let moved4 = render(&moved, (w, h), prog4);
        let (vs_old, vs_more) = (
            psnr(&reset, &still, 1.0).expect("psnr"),
            psnr(&reset, &moved4, 1.0).expect("psnr"),
        );
        println!(
            "moved camera: bit for bit a fresh 1-frame render {}; against the old camera's 4 \
             frames {vs_old:.1} dB, against 4 frames of the new camera {vs_more:.1} dB",
            same(&reset, &fresh)
        );
        assert!(same(&reset, &fresh));
        assert!(
            vs_old < 60.0 && vs_more < 90.0,
            "{vs_old:.1} / {vs_more:.1} dB"
        );
        // Camera equality is exact: the smallest change of one field resets.
        let nudged = PathCamera {
            tan_half_fov_y: f64::from_bits(moved.tan_half_fov_y.to_bits() + 1),
            ..moved
        };
        let step = s
            .step(ctx, walk, lit, &nudged, (w, h), &prog4)
            .expect("step");
        assert_eq!((step.work, step.frames), (StepWork::Moved, 1));

        // A new size, then a new supersampling: the targets reallocated, that frame rendered.
        let small = (40usize, 24usize);
        for k in [1, 2] {
            let opts = options(progressive(1), k);
            let step = s.step(ctx, walk, lit, &moved, small, &opts).expect("step");
            assert_eq!((step.work, step.frames), (StepWork::Allocated, 1));
            let img = s.image(ctx).expect("image");
            assert_eq!((img.width, img.height), small);
            assert!(same(&img, &render(&moved, small, opts)), "k = {k}");
            let gb = s.intermediates().expect("intermediates").gbuffer;
            assert_eq!((gb.width, gb.height), (40 * k, 24 * k));
        }

        // Regular sampling at the still camera: the view-dependent pass alone, once; then
        // nothing runs and the image stays.
        let regular = options((Method::Regular, 1), 2);
        let step = s
            .step(ctx, walk, lit, &moved, small, &regular)
            .expect("step");
        assert_eq!((step.work, step.frames), (StepWork::Reshaded, 1));
        let img = s.image(ctx).expect("image");
        assert!(same(&img, &render(&moved, small, regular)));
        for _ in 0..2 {
            let step = s
                .step(ctx, walk, lit, &moved, small, &regular)
                .expect("step");
            assert_eq!((step.work, step.frames), (StepWork::Unchanged, 1));
            assert_eq!(step.times.total_ms(), 0.0);
            assert!(step.stats.glossy_hits > 0, "the image's counts are kept");
            assert!(same(&s.image(ctx).expect("image"), &img));
        }
        // Other samples, CK, another seed: shaded again over the same G-buffer.
        for opts in [
            FrameRequest {
                samples: 5,
                ..regular
            },
            options((Method::Ck, 1), 2),
            FrameRequest {
                seed: 4,
                ..options((Method::Ck, 1), 2)
            },
        ] {
            let step = s.step(ctx, walk, lit, &moved, small, &opts).expect("step");
            assert_eq!(step.work, StepWork::Reshaded, "{opts:?}");
            assert!(same(
                &s.image(ctx).expect("image"),
                &render(&moved, small, opts)
            ));
        }
        // A reset keeps the targets and re-renders every pass.
        s.reset();
        assert_eq!(s.frames(), 0);
        assert!(s.image(ctx).is_err());
        let step = s
            .step(ctx, walk, lit, &moved, small, &regular)
            .expect("step");
        assert_eq!(step.work, StepWork::Moved);
        assert!(same(&s.image(ctx).expect("image"), &img));
    });
}

/// A probe captured again on request (`GpuWalkthrough::recapture_probe`) is read from the
/// session's next step: with the same options the same probe and image, bit for bit; with
/// smaller faces another image; a mesh without a probe is refused by name.
#[test]
fn a_probe_captured_again_is_read_from_the_next_step() {
    with_room(|ctx, scene, lit, walk| {
        let (w, h) = (40usize, 24usize);
        let camera = path_camera(scene, None, w as u32, h as u32).expect("camera");
        let regular = options((Method::Regular, 1), 1);
        let mut s = GpuFrameSession::new();
        s.step(ctx, walk, lit, &camera, (w, h), &regular)
            .expect("step");
        let before = s.image(ctx).expect("image");
        let mesh = walk.probes[0].mesh.expect("an object probe") as usize;
        let ms = walk
            .recapture_probe(ctx, lit, mesh, &PROBES)
            .expect("captured again");
        assert!(ms > 0.0, "{ms}");
        let step = s
            .step(ctx, walk, lit, &camera, (w, h), &regular)
            .expect("step");
        assert_eq!(step.work, StepWork::Moved);
        assert!(same(&s.image(ctx).expect("image"), &before));
        let small = ProbeOptions {
            face_size: 16,
            ..PROBES
        };
        walk.recapture_probe(ctx, lit, mesh, &small)
            .expect("captured again");
        let probe = walk.probes[0].read_back(ctx).expect("probe read-back");
        assert_eq!(probe.pyramid.base_size(), 16);
        let step = s
            .step(ctx, walk, lit, &camera, (w, h), &regular)
            .expect("step");
        assert_eq!(step.work, StepWork::Moved);
        let after = s.image(ctx).expect("image");
        let db = psnr(&after, &before, 1.0).expect("psnr");
        println!("probe captured again at 16² faces instead of 32²: {db:.1} dB from before");
        assert!(db < 90.0, "{db:.1} dB: the new probe is not read");
        // The next step at the still camera runs nothing.
        let step = s
            .step(ctx, walk, lit, &camera, (w, h), &regular)
            .expect("step");
        assert_eq!(step.work, StepWork::Unchanged);
        let plain = (0..scene.meshes.len())
            .find(|m| !walk.probes.iter().any(|p| p.mesh == Some(*m as u32)))
            .expect("a mesh without a probe");
        let err = walk
            .recapture_probe(ctx, lit, plain, &PROBES)
            .expect_err("no probe")
            .to_string();
        assert!(
            err.contains("no probe") && err.contains(&scene.meshes[plain].name),
            "{err}"
        );
    });
}

/// The CPU twin of the session's current frame after `frames` progressive frames, on its
/// read-back intermediates.
fn twin(
    ctx: &GpuContext,
    lit: &LitScene,
    probes: &[Probe],
    camera: &PathCamera,
    inter: SessionIntermediates,
    frames: u32,
) -> Image {
    let gb = inter.gbuffer.read_back(ctx).expect("G-buffer read-back");
    let buffers = frame_buffers(ctx, lit, inter.views, inter.reflectors, inter.tables);
    let light = FrameLight {
        probes,
        environment: None,
    };
    shade_gbuffer_view_dependent(
        lit,
        &light,
        &buffers,
        camera,
        &gb,
        1,
        &FrameRequest {
            method: Method::Progressive,
            samples: 8,
            rays: 1,
            frames,
            seed: 3,
        },
    )
    .expect("CPU twin")
    .0
}

/// Frames of the CPU twin's converged integral of the same incident light.
const CONVERGED: u32 = 256;

#[test]
fn still_frames_converge_to_the_integral_of_the_same_incident_light() {
    with_room(|ctx, scene, lit, walk| {
        let walk = &*walk;
        let (w, h) = (80usize, 48usize);
        let camera = path_camera(scene, None, w as u32, h as u32).expect("camera");
        let probes: Vec<_> = walk
            .probes
            .iter()
            .map(|p| p.read_back(ctx).expect("probe read-back"))
            .collect();
        let opts = options(progressive(64), 1);
        let mut s = GpuFrameSession::new();
        let mut images = vec![];
        let mut still_ms = vec![];
        for f in 1..=64u32 {
            let step = s
                .step(ctx, walk, lit, &camera, (w, h), &opts)
                .expect("step");
            assert_eq!(step.frames, f);
            if f > 1 {
                still_ms.push(step.times.total_ms());
            }
            if [1, 16, 64].contains(&f) {
                images.push((f, s.image(ctx).expect("image")));
            }
        }
        let inter = s.intermediates().expect("intermediates");
        let t0 = std::time::Instant::now();
        let truth = twin(ctx, lit, &probes, &camera, inter, CONVERGED);
        let twin_s = t0.elapsed().as_secs_f64();
        let same64 = twin(ctx, lit, &probes, &camera, inter, 64);
        let parity = psnr(&images[2].1, &same64, 1.0).expect("psnr");
        still_ms.sort_by(f64::total_cmp);
        println!(
            "GPU after 64 still frames vs its CPU twin of 64 frames: {parity:.1} dB; still frame \
             {:.1} ms (median of 63, 80×48, 8 samples); CPU twin of {CONVERGED} frames {twin_s:.1} s",
            still_ms[still_ms.len() / 2]
        );
        assert!(parity >= 90.0, "{parity:.1} dB");
        let dbs: Vec<f64> = images
            .iter()
            .map(|(f, img)| {
                let db = psnr(img, &truth, 1.0).expect("psnr");
                println!("after {f} still frame(s): {db:.2} dB against {CONVERGED} CPU frames");
                db
            })
            .collect();
        assert!(dbs[0] < dbs[1] && dbs[1] < dbs[2], "{dbs:?}");
    });
}
