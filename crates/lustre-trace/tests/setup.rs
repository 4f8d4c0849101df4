//! The automatic real-time set-up (`lustre_trace::setup`) on scenes without hints: the sunroom
//! (scenes/sunroom, a room lit by a sky through two windows), the Modern Hall from its own
//! Mitsuba XML, the Cornell box, an open scene, and thousands of small glossy objects.

use glam::{DMat4, DVec3};
use lustre_scene::{mesh, ObjectHints, Scene};
use lustre_trace::path_tracer::{PathOptions, PathTracer};
use lustre_trace::reference::path_scene;
use lustre_trace::setup::{apply, auto_setup, clear_hints, Setup, SetupOptions};
use std::path::Path;

fn setup_of(scene: &Scene) -> Setup {
    let (ps, _) = path_scene(scene).expect("path scene");
    let tracer = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
    auto_setup(scene, &tracer, &SetupOptions::default())
}

fn sunroom() -> Scene {
    Scene::load(Path::new("../../scenes/sunroom/scene.xml")).expect("the sunroom")
}

fn hints<'s>(s: &'s Setup, name: &str) -> Option<&'s ObjectHints> {
    s.objects.iter().find(|(n, _)| n == name).map(|(_, h)| h)
}

#[test]
fn sunroom_gets_mirrors_probes_and_a_room_box_inside_its_walls() {
    let scene = sunroom();
    let s = setup_of(&scene);
    eprintln!("{}", s.report);
    // Its pane is a thin sheet (thindielectric): no slab.
    assert!(s.report.slabs.is_empty(), "{}", s.report);
    for name in ["Floor", "Mirror", "Picture"] {
        assert!(
            hints(&s, name).is_some_and(|h| h.planar_reflector),
            "{name}: {:?}",
            s.objects
        );
    }
    for name in ["GoldSphere", "Table"] {
        assert!(
            hints(&s, name).is_some_and(|h| h.probe && !h.planar_reflector),
            "{name}: {:?}",
            s.objects
        );
    }
    // The pane: a probe (its see-through pass) and a mirror pass (its reflections).
    assert!(
        hints(&s, "WindowPane").is_some_and(|h| h.probe && h.planar_reflector),
        "{:?}",
        s.objects
    );
    assert_eq!(s.report.see_through, 1, "the pane");
    // Diffuse walls get nothing.
    assert!(hints(&s, "WestWall").is_none());
    // Room probes: inside the room, their boxes the room's walls (within a cell), covering
    // the free space.
    assert!(!s.probes.is_empty() && s.probes.len() <= 8);
    assert!(s.report.covered >= 0.9, "{}", s.report);
    let (lo, hi) = (DVec3::new(-3.0, 0.0, -2.5), DVec3::new(3.0, 3.0, 2.5));
    let cell = 6.0 / 24.0;
    for p in &s.probes {
        p.validate().expect("a valid probe");
        let c = DVec3::from_array(p.centre);
        assert!(c.cmpgt(lo).all() && c.cmplt(hi).all(), "{p:?}");
        let (bl, bh) = p.parallax_box().expect("a box");
        for k in 0..3 {
            assert!(bl[k] >= lo[k] - cell && bh[k] <= hi[k] + cell, "{p:?}");
        }
    }
    // The first probe's box is the room: it spans most of each side.
    let (bl, bh) = s.probes[0].parallax_box().expect("a box");
    for k in 0..3 {
        assert!(
            bh[k] - bl[k] >= 0.8 * (hi[k] - lo[k]),
            "axis {k}: {:?}",
            s.probes[0]
        );
    }
    assert!(s
        .report
        .to_string()
        .starts_with("real-time set-up: 4 mirror"));
}

#[test]
fn hand_written_hints_win_and_count_against_the_budget() {
    let mut scene = sunroom();
    let mut hand = 0;
    for m in scene.meshes.iter_mut() {
        if m.name == "Floor" {
            m.hints.diffuse_only = true;
            hand += 1;
        }
        if m.name == "Picture" {
            m.hints.planar_reflector = true;
            hand += 1;
        }
    }
    assert_eq!(hand, 2);
    scene.probes.push(lustre_scene::ProbeSite {
        name: "mine".into(),
        centre: [0.0, 1.5, 0.0],
        box_min: None,
        box_max: None,
    });
    let s = setup_of(&scene);
    assert!(hints(&s, "Floor").is_none() && hints(&s, "Picture").is_none());
    assert!(hints(&s, "Mirror").is_some_and(|h| h.planar_reflector));
    assert_eq!(s.report.hand_written, 2);
    assert!(s.probes.is_empty() && s.report.hand_probes);
    let mut applied = scene.clone();
    apply(&mut applied, &s);
    let floor = applied
        .meshes
        .iter()
        .find(|m| m.name == "Floor")
        .expect("floor");
    assert!(floor.hints.diffuse_only && !floor.hints.planar_reflector);
    assert_eq!(applied.probes.len(), 1, "the hand-written probe stays");
    // A budget of one mirror: the hand-written picture takes it.
    {
        let (ps, _) = path_scene(&scene).expect("path scene");
        let tracer = PathTracer::new(&ps, PathOptions::default()).expect("tracer");
        let one = SetupOptions {
            max_mirrors: 1,
            ..SetupOptions::default()
        };
        let s = auto_setup(&scene, &tracer, &one);
        assert!(s.report.mirrors.is_empty(), "{}", s.report);
        assert!(s.report.left_out.iter().any(|n| n == "Mirror"));
    }
    // clear_hints forgets them all.
    clear_hints(&mut scene);
    assert!(scene
        .meshes
        .iter()
        .all(|m| m.hints == ObjectHints::default()));
    assert!(scene.probes.is_empty());
}

#[test]
fn thousands_of_small_glossy_objects_stay_within_the_budget() {
    let mut scene = sunroom();
    let gold = scene.material_index("Gold").expect("gold");
    for i in 0..2000 {
        let mut c = mesh::cube(&format!("bead{i}"), gold);
        let (x, z) = ((i % 50) as f64 * 0.1 - 2.5, (i / 50) as f64 * 0.1 - 2.0);
        c.transform(
            &(DMat4::from_translation(DVec3::new(x, 0.02, z))
                * DMat4::from_scale(DVec3::splat(0.01))),
        );
        scene.meshes.push(c);
    }
    let s = setup_of(&scene);
    eprintln!("{}", s.report);
    let probes = s.objects.iter().filter(|(_, h)| h.probe).count();
    assert_eq!(probes, SetupOptions::default().max_object_probes);
    // The pane, the sphere, the table and the beads compete for the budget.
    assert_eq!(s.report.left_out.len(), 2003 - probes);
    let line = s.report.to_string();
    assert!(line.contains("left out") && line.contains("more"), "{line}");
}

#[test]
fn hall_from_its_xml_gets_its_floor_mirror_and_glass_probe_and_mirror() {
    let scene = Scene::load(Path::new(
        "../../../shared/data/scenes/modern_hall/mitsuba/scene.xml",
    ))
    .expect("the Hall");
    let s = setup_of(&scene);
    eprintln!("{}", s.report);
    let material = |name: &str| {
        let m = scene.meshes.iter().find(|m| m.name == name).expect("mesh");
        scene.materials[m.material].name.clone()
    };
    // The tiled floor is the Hall's large near-mirror; the glass balustrade gets a probe (and
    // a see-through pass) and a mirror pass for the face of its long slab toward the camera.
    assert!(s.report.mirrors.iter().any(|n| material(n) == "FloorTiles"));
    assert!(s.report.mirrors.iter().any(|n| material(n) == "Glass"));
    assert!(s
        .report
        .object_probes
        .iter()
        .any(|n| material(n) == "Glass"));
    assert!(
        !s.probes.is_empty() && s.report.covered >= 0.5,
        "{}",
        s.report
    );
    // The balustrade's panes are solid glass 3.1–3.7 cm thick: a slab with its thickness (the
    // nearest opposite face of its row of panes, 3.5 cm), for the refraction offset.
    let glass = scene
        .meshes
        .iter()
        .find(|m| scene.materials[m.material].name == "Glass")
        .expect("glass");
    let t = hints(&s, &glass.name)
        .and_then(|h| h.thickness)
        .expect("a thickness");
    assert!((0.030..=0.038).contains(&t), "{t}");
    assert_eq!(s.report.slabs, vec![(glass.name.clone(), t)]);
    assert!(
        s.report.to_string().contains("1 glass slab(s)"),
        "{}",
        s.report
    );
    // Applied, the thickness joins the probe hint.
    let mut applied = scene.clone();
    apply(&mut applied, &s);
    let h = applied
        .meshes
        .iter()
        .find(|m| m.name == glass.name)
        .expect("glass")
        .hints;
    assert!(h.probe && h.thickness == Some(t), "{h:?}");
}

#[test]
fn scenes_without_glossy_surfaces_or_walls_get_no_room_probes() {
    // The Cornell box: every material diffuse.
    let cornell = Scene::load(Path::new(
        "../../../shared/data/scenes/cornell_box/cornell_box.obj",
    ))
    .expect("cornell");
    let s = setup_of(&cornell);
    assert!(s.objects.is_empty() && s.probes.is_empty(), "{}", s.report);
    // A gold sphere under the sky with nothing around it: an object probe, no room.
    let mut open = sunroom();
    open.meshes.retain(|m| m.name == "GoldSphere");
    let s = setup_of(&open);
    assert!(hints(&s, "GoldSphere").is_some_and(|h| h.probe));
    assert!(
        s.probes.is_empty() && s.report.free_cells == 0,
        "{}",
        s.report
    );
}

#[test]
fn a_room_on_a_vast_site_gets_a_probe_at_its_camera() {
    // The sunroom on a 2 km ground plane: the free-space cells (1/24 of the scene's longest
    // side, 83 m) are far larger than the room, none is free, and before the floor read the
    // bare sky through the walls. Now a probe stands at the camera with the room's box.
    let mut site = sunroom();
    let plaster = site.material_index("Plaster").expect("plaster");
    let mut ground = mesh::rectangle("Ground", plaster);
    // Mitsuba's rectangle spans [-1, 1]² in z = 0: turned to face up, 1 km half-width, just
    // below the floor.
    ground.transform(
        &(DMat4::from_translation(DVec3::new(0.0, -0.05, 0.0))
            * DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2)
            * DMat4::from_scale(DVec3::splat(1000.0))),
    );
    site.meshes.push(ground);
    let s = setup_of(&site);
    eprintln!("{}", s.report);
    assert_eq!(s.report.free_cells, 0, "{}", s.report);
    assert!(s.report.at_cameras, "{}", s.report);
    assert_eq!(s.probes.len(), 1, "{}", s.report);
    let camera = site.cameras[0].position;
    let p = &s.probes[0];
    assert!(DVec3::from(p.centre).distance(camera) < 1e-3, "{p:?}");
    // The box is the room's: floor to ceiling (y 0 to 3), inside the walls (x ±3, z ±2.5).
    let (lo, hi) = p.parallax_box().expect("a box");
    for (k, (a, b)) in [(-3.0, 3.0), (0.0, 3.0), (-2.5, 2.5)]
        .into_iter()
        .enumerate()
    {
        assert!(lo[k] > a - 0.3 && hi[k] < b + 0.3, "axis {k}: {p:?}");
        assert!(hi[k] - lo[k] > 0.5 * (b - a), "axis {k}: {p:?}");
    }
    assert!(
        s.report.to_string().contains("at the cameras"),
        "{}",
        s.report
    );
    // The floor, the mirror, the picture and the pane keep their mirror passes (planes
    // measured against the room, not the site).
    assert_eq!(s.report.mirrors.len(), 4, "{}", s.report);
}
