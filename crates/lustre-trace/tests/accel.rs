//! Ray casting: watertightness on shared edges and vertices, closest hit and any hit against a
//! brute-force f64 loop on the Cornell box (tobj), alpha rejection, bad input.

use glam::DVec3;
use lustre_brdf::sampling::{uniform_sphere, SplitMix64};
use lustre_trace::accel::Accel;

/// Triangles of the Cornell box OBJ from the shared data.
pub fn cornell() -> Vec<[DVec3; 3]> {
    let path = lustre_env::shared_data_dir().join("scenes/cornell_box/cornell_box.obj");
    let (models, _) = tobj::load_obj(
        &path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        },
    )
    .expect("cornell box");
    let mut tris = vec![];
    for m in models {
        let p = &m.mesh.positions;
        let v = |i: u32| {
            let i = i as usize * 3;
            DVec3::new(p[i] as f64, p[i + 1] as f64, p[i + 2] as f64)
        };
        for f in m.mesh.indices.chunks(3) {
            tris.push([v(f[0]), v(f[1]), v(f[2])]);
        }
    }
    tris
}

/// Independent f64 Möller–Trumbore: (t, triangle) of the closest hit with t > 1e-9.
fn brute(tris: &[[DVec3; 3]], o: DVec3, d: DVec3) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for (k, t) in tris.iter().enumerate() {
        let e1 = t[1] - t[0];
        let e2 = t[2] - t[0];
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = o - t[0];
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let tt = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && tt > 1e-9 && best.is_none_or(|(b, _)| tt < b) {
            best = Some((tt, k));
        }
    }
    best
}

#[test]
fn closest_and_any_hit_match_brute_force_on_the_cornell_box() {
    let tris = cornell();
    assert!(tris.len() >= 30, "{} triangles", tris.len());
    let accel = Accel::new(&tris).unwrap();
    let mut rng = SplitMix64::new(1);
    let (mut hits, mut n) = (0, 0);
    for _ in 0..20_000 {
        // Origins inside the box, random directions.
        let o = DVec3::new(
            20.0 + 510.0 * rng.next_f64(),
            20.0 + 510.0 * rng.next_f64(),
            20.0 + 510.0 * rng.next_f64(),
        );
        let d = uniform_sphere(rng.next_f64(), rng.next_f64());
        let a = accel.intersect(o, d, 0.0, f64::INFINITY, |_, _| true);
        let b = brute(&tris, o, d);
        n += 1;
        match (a, b) {
            (Some(h), Some((t, k))) => {
                hits += 1;
                assert!((h.t - t).abs() < 1e-3 * t.max(1.0), "t {} vs {t}", h.t);
                if h.prim != k {
                    // Two triangles at the same distance (a shared edge) are both right.
                    let t2 = brute(&tris[h.prim..=h.prim], o, d).map(|x| x.0);
                    assert!(
                        t2.is_some_and(|t2| (t2 - t).abs() < 1e-3),
                        "prim {} vs {k}",
                        h.prim
                    );
                }
                let s: f64 = h.bary.iter().sum();
                assert!((s - 1.0).abs() < 1e-5 && h.bary.iter().all(|&x| x >= -1e-6));
                let p = tris[h.prim][0] * h.bary[0]
                    + tris[h.prim][1] * h.bary[1]
                    + tris[h.prim][2] * h.bary[2];
                assert!(
                    (p - (o + d * h.t)).length() < 1e-2,
                    "{p} vs {}",
                    o + d * h.t
                );
                assert!(accel.occluded(o, d, 0.0, t * 1.01, |_, _| true));
                assert!(!accel.occluded(o, d, 0.0, t * 0.99, |_, _| true));
            }
            (None, None) => {
                assert!(!accel.occluded(o, d, 0.0, f64::INFINITY, |_, _| true));
            }
            (a, b) => panic!("bvh {a:?} vs brute {b:?} for {o} {d}"),
        }
    }
    // The box has an open front (z = 0 side): some rays escape.
    assert!(hits > n / 2 && hits < n, "{hits} of {n}");
}

#[test]
fn watertight_on_shared_edges_and_vertices() {
    // A 16×16 grid of unit squares (two triangles each) in z = 0; rays straight down through
    // every vertex and every edge midpoint of the grid, and along slanted directions.
    let n = 16;
    let mut tris = vec![];
    let p = |i: usize, j: usize| DVec3::new(i as f64 * 0.37, j as f64 * 0.37, 0.0);
    for i in 0..n {
        for j in 0..n {
            tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    let accel = Accel::new(&tris).unwrap();
    let mut misses = 0;
    let mut total = 0;
    for dir in [
        DVec3::new(0.0, 0.0, -1.0),
        DVec3::new(0.3, -0.2, -1.0),
        DVec3::new(-0.7, 0.5, -0.4),
    ] {
        for a in 1..2 * n {
            for b in 1..2 * n {
                let target = DVec3::new(a as f64 * 0.185, b as f64 * 0.185, 0.0);
                let o = target - dir * 3.0;
                total += 1;
                if accel
                    .intersect(o, dir, 0.0, f64::INFINITY, |_, _| true)
                    .is_none()
                {
                    misses += 1;
                }
            }
        }
    }
    assert_eq!(
        misses, 0,
        "{misses} of {total} rays leaked through the mesh"
    );
}

#[test]
fn accept_callback_skips_masked_triangles() {
    // Two parallel quads; rejecting the front one reveals the back one.
    let q = |z: f64| {
        [
            [
                DVec3::new(-1.0, -1.0, z),
                DVec3::new(1.0, -1.0, z),
                DVec3::new(1.0, 1.0, z),
            ],
            [
                DVec3::new(-1.0, -1.0, z),
                DVec3::new(1.0, 1.0, z),
                DVec3::new(-1.0, 1.0, z),
            ],
        ]
    };
    let mut tris = q(0.0).to_vec();
    tris.extend(q(-1.0));
    let accel = Accel::new(&tris).unwrap();
    let o = DVec3::new(0.2, 0.3, 5.0);
    let d = -DVec3::Z;
    let h = accel
        .intersect(o, d, 0.0, f64::INFINITY, |_, _| true)
        .unwrap();
    assert!(h.prim < 2 && (h.t - 5.0).abs() < 1e-5);
    let h = accel
        .intersect(o, d, 0.0, f64::INFINITY, |p, _| p >= 2)
        .unwrap();
    assert!(h.prim >= 2 && (h.t - 6.0).abs() < 1e-5);
    assert!(!accel.occluded(o, d, 0.0, 100.0, |_, _| false));
    assert!(accel.occluded(o, d, 0.0, 100.0, |p, _| p >= 2));
    assert!(!accel.occluded(o, d, 0.0, 5.5, |p, _| p >= 2));
}

#[test]
fn bad_input() {
    assert!(Accel::new(&[[DVec3::ZERO, DVec3::X, DVec3::splat(f64::NAN)]]).is_err());
    let empty = Accel::new(&[]).unwrap();
    assert!(empty
        .intersect(DVec3::ZERO, DVec3::X, 0.0, f64::INFINITY, |_, _| true)
        .is_none());
    let one = Accel::new(&[[DVec3::ZERO, DVec3::X, DVec3::Y]]).unwrap();
    // Zero / NaN directions miss instead of panicking.
    assert!(one
        .intersect(DVec3::Z, DVec3::ZERO, 0.0, f64::INFINITY, |_, _| true)
        .is_none());
    assert!(one
        .intersect(DVec3::Z, DVec3::NAN, 0.0, f64::INFINITY, |_, _| true)
        .is_none());
}
