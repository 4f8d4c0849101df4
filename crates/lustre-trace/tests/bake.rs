//! Light-map bake checks: a plane under a constant sky (E = πL), a closed diffuse
//! box (total irradiance against the geometric series, one bounce against the direct term by
//! quadrature), seams across charts, leaks under thin walls, resume and shards bit for bit.
//! Scenes are built by hand with hand-made light-map uvs and atlases.

use glam::{DVec3, Vec2, Vec3};
use lustre_brdf::rgb::Rgb;
use lustre_scene::lightmap::{AtlasSource, LightmapAtlas};
use lustre_scene::{Environment, Material, Mesh, Scene};
use lustre_trace::bake::trace::TexelRecord;
use lustre_trace::bake::{assemble, bake_texels, bake_tiles, Assembled, BakeOptions, Denoiser};
use std::f64::consts::PI;
use std::path::Path;

/// A quad p0, p0+eu, p0+eu+ev, p0+ev (front = eu × ev) mapped to the texel block
/// [bx, bx+nu] × [by, by+nv] of a W×H page.
#[allow(clippy::too_many_arguments)]
fn quad(
    name: &str,
    p0: DVec3,
    eu: DVec3,
    ev: DVec3,
    block: (u32, u32, u32, u32),
    page: (u32, u32),
    material: usize,
) -> Mesh {
    let f = |v: DVec3| v.as_vec3();
    let (bx, by, nu, nv) = block;
    let (w, h) = (page.0 as f32, page.1 as f32);
    let mut m = Mesh::new(
        name,
        vec![f(p0), f(p0 + eu), f(p0 + eu + ev), f(p0 + ev)],
        vec![[0, 1, 2], [0, 2, 3]],
        material,
    );
    let uv = |i: u32, j: u32| Vec2::new((bx + i * nu) as f32 / w, (by + j * nv) as f32 / h);
    m.uv1 = Some(vec![uv(0, 0), uv(1, 0), uv(1, 1), uv(0, 1)]);
    m
}

/// A closed box [lo, hi] with outward faces, without its bottom face unless `bottom` (it stands
/// on a floor); not light-mapped.
fn block(name: &str, lo: DVec3, hi: DVec3, bottom: bool) -> Mesh {
    let c = |x: usize, y: usize, z: usize| {
        Vec3::new(
            [lo.x, hi.x][x] as f32,
            [lo.y, hi.y][y] as f32,
            [lo.z, hi.z][z] as f32,
        )
    };
    let positions = vec![
        c(0, 0, 0),
        c(1, 0, 0),
        c(1, 1, 0),
        c(0, 1, 0),
        c(0, 0, 1),
        c(1, 0, 1),
        c(1, 1, 1),
        c(0, 1, 1),
    ];
    // Outward faces (counter-clockwise from outside): −z, +z, −x, +x, +y.
    let quads = [
        [0, 3, 2, 1],
        [4, 5, 6, 7],
        [0, 4, 7, 3],
        [1, 2, 6, 5],
        [3, 7, 6, 2],
    ];
    let under = [[0, 1, 5, 4]];
    let indices = quads
        .iter()
        .chain(under.iter().filter(|_| bottom))
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    Mesh::new(name, positions, indices, 0)
}

fn atlas(w: u32, h: u32, mesh_page: Vec<Option<u32>>, gutter: u32) -> LightmapAtlas {
    LightmapAtlas {
        width: w,
        height: h,
        pages: 1,
        mesh_page,
        gutter,
        texels_per_metre: 0.0,
        source: AtlasSource::Texcoord1,
    }
}

fn bake(scene: &Scene, atlas: &LightmapAtlas, opts: &BakeOptions, dir: &Path) -> Assembled {
    let r = bake_tiles(scene, atlas, opts, dir, None, &|_, _| {}).expect("bake");
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    assemble(scene, atlas, opts, dir).expect("assemble")
}

fn raw_opts(spp: u32, bounces: u32) -> BakeOptions {
    BakeOptions {
        spp,
        bounces,
        seed: 7,
        tile: 16,
        denoiser: Denoiser::None,
        transport: Default::default(),
    }
}

fn scene_with(meshes: Vec<Mesh>, materials: Vec<Material>, env: Option<Rgb>) -> Scene {
    let mut s = Scene::new("hand-made");
    s.materials = materials;
    s.meshes = meshes;
    s.environment = env.map(Environment::constant);
    s
}

#[test]
fn plane_under_constant_sky_gets_pi_l() {
    let l = Rgb([0.5, 1.0, 2.0]);
    let (w, h) = (16, 16);
    let floor = quad(
        "floor",
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -2.0),
        (2, 2, 12, 12),
        (w, h),
        0,
    );
    let scene = scene_with(
        vec![floor],
        vec![Material::diffuse("grey", Rgb::splat(0.5))],
        Some(l),
    );
    let at = atlas(w, h, vec![Some(0)], 2);
    let dir = tempfile::tempdir().unwrap();
    let a = bake(&scene, &at, &raw_opts(32, 3), dir.path());
    let covered: Vec<&TexelRecord> = a.texels[0].iter().filter(|t| t.covered()).collect();
    assert_eq!(
        covered.len(),
        144,
        "the quad covers its 12×12 block exactly"
    );
    for c in 0..3 {
        let want = PI * l[c];
        let mean = covered.iter().map(|t| f64::from(t.e[c])).sum::<f64>() / 144.0;
        eprintln!("channel {c}: mean E / πL = {:.5}", mean / want);
        assert!(
            (mean / want - 1.0).abs() < 0.01,
            "channel {c}: mean E {mean} vs πL = {want}"
        );
        for t in &covered {
            let se = f64::from(t.var[c]).sqrt();
            assert!(
                (f64::from(t.e[c]) - want).abs() < 5.0 * se && se < 0.2 * want,
                "texel E {} ± {se} vs {want}",
                t.e[c]
            );
        }
    }
    // The EXR holds the same values (half precision), dilated into the gutter.
    let img = image::open(&a.files[0]).unwrap().to_rgb32f();
    let centre = img.get_pixel(8, 8).0;
    assert!((f64::from(centre[1]) / PI - 1.0).abs() < 0.05, "{centre:?}");
    let gutter = img.get_pixel(1, 8).0;
    assert!(gutter[1] > 0.0, "gutter texel dilated: {gutter:?}");
    assert!(a.report.pages[0].noise_std_error > 0.0);
    // The same tiles assembled with the denoiser (it runs at assembly, outside the hash):
    // closer to πL, mean kept.
    let dn = BakeOptions {
        denoiser: Denoiser::ATrous(Default::default()),
        ..raw_opts(32, 3)
    };
    let d = assemble(&scene, &at, &dn, dir.path()).expect("assemble denoised");
    let err = |e: &[[f32; 3]]| {
        let (mut s2, mut s, mut n) = (0.0, 0.0, 0.0);
        for (k, t) in a.texels[0].iter().enumerate() {
            if t.covered() {
                let v = f64::from(e[k][1]) / (PI * l[1]);
                s2 += (v - 1.0).powi(2);
                s += v;
                n += 1.0;
            }
        }
        ((s2 / n).sqrt(), s / n)
    };
    let ((raw_rms, raw_mean), (dn_rms, dn_mean)) = (err(&a.pages[0]), err(&d.pages[0]));
    eprintln!("plane: relative RMS error raw {raw_rms:.4}, denoised {dn_rms:.4}");
    assert!(dn_rms < raw_rms / 2.0, "denoised {dn_rms} vs raw {raw_rms}");
    assert!(
        (dn_mean - raw_mean).abs() < 0.005,
        "mean {raw_mean} → {dn_mean}"
    );
}

/// The inside of the unit box [0, 1]³ at texel size 0.1: six faces, the ceiling in four pieces
/// around a 0.2 × 0.2 emitter at its centre (facing down). Every face maps to a texel-aligned
/// block of a 64×64 page, 2-texel gutters. Albedo `rho` everywhere (the emitter too).
fn cornell_like(rho: f64, le: f64) -> (Scene, LightmapAtlas, Vec<(usize, f64)>) {
    let page = (64, 64);
    let t = 0.1;
    let mut meshes = vec![];
    let mut areas = vec![]; // (mesh, texel area)
    let mut cursor = (2u32, 2u32, 0u32); // x, y, row height
    let mut place = |nu: u32, nv: u32| {
        if cursor.0 + nu + 2 > page.0 {
            cursor = (2, cursor.1 + cursor.2 + 2, 0);
        }
        let b = (cursor.0, cursor.1, nu, nv);
        cursor.0 += nu + 2;
        cursor.2 = cursor.2.max(nv);
        b
    };
    let v = DVec3::new;
    let faces: Vec<(&str, DVec3, DVec3, DVec3)> = vec![
        (
            "floor",
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(1.0, 0.0, 0.0),
        ),
        ("back", v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)),
        (
            "front",
            v(0.0, 0.0, 1.0),
            v(0.0, 1.0, 0.0),
            v(1.0, 0.0, 0.0),
        ),
        ("left", v(0.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0)),
        (
            "right",
            v(1.0, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
            v(0.0, 1.0, 0.0),
        ),
        (
            "ceil-a",
            v(0.0, 1.0, 0.0),
            v(0.4, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
        ),
        (
            "ceil-b",
            v(0.6, 1.0, 0.0),
            v(0.4, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
        ),
        (
            "ceil-c",
            v(0.4, 1.0, 0.0),
            v(0.2, 0.0, 0.0),
            v(0.0, 0.0, 0.4),
        ),
        (
            "ceil-d",
            v(0.4, 1.0, 0.6),
            v(0.2, 0.0, 0.0),
            v(0.0, 0.0, 0.4),
        ),
        (
            "emitter",
            v(0.4, 1.0, 0.4),
            v(0.2, 0.0, 0.0),
            v(0.0, 0.0, 0.2),
        ),
    ];
    for (name, p0, eu, ev) in faces {
        let (nu, nv) = (
            (eu.length() / t).round() as u32,
            (ev.length() / t).round() as u32,
        );
        let mut m = quad(name, p0, eu, ev, place(nu, nv), page, 0);
        if name == "emitter" {
            m.emission = Some(Rgb::splat(le));
        }
        areas.push((meshes.len(), t * t));
        meshes.push(m);
    }
    let n = meshes.len();
    let scene = scene_with(
        meshes,
        vec![Material::diffuse("walls", Rgb::splat(rho))],
        None,
    );
    (scene, atlas(page.0, page.1, vec![Some(0); n], 2), areas)
}

/// Σ E·area over covered texels and its standard error.
fn total(a: &Assembled, texel_area: f64) -> (f64, f64) {
    let mut s = 0.0;
    let mut v = 0.0;
    for t in a.texels[0].iter().filter(|t| t.covered()) {
        s += f64::from(t.e[0]) * texel_area;
        v += f64::from(t.var[0]) * texel_area * texel_area;
    }
    (s, v.sqrt())
}

#[test]
fn closed_box_total_irradiance_is_the_geometric_series() {
    let (rho, le) = (0.5, 10.0);
    let (scene, at, areas) = cornell_like(rho, le);
    let texel_area = areas[0].1;
    let phi = le * PI * 0.2 * 0.2; // a one-sided Lambertian emitter's power
    let dir = tempfile::tempdir().unwrap();
    for bounces in [1u32, 12] {
        let sub = dir.path().join(format!("b{bounces}"));
        let a = bake(&scene, &at, &raw_opts(32, bounces), &sub);
        let covered = a.texels[0].iter().filter(|t| t.covered()).count();
        assert_eq!(
            covered, 600,
            "5 faces of 100 texels, ceiling 96 + emitter 4"
        );
        // Every photon lands on the closed box's surface; each landing reflects ρ of it.
        let want = phi * (1.0 - rho.powi(bounces as i32)) / (1.0 - rho);
        let (got, se) = total(&a, texel_area);
        eprintln!("bounces {bounces}: ∫E dA = {got:.5} ± {se:.5}, series {want:.5}");
        assert!(
            se / want < 0.01,
            "standard error {se} too large for the test"
        );
        assert!(
            (got - want).abs() < 4.0 * se + 0.002 * want,
            "bounces {bounces}: ∫E dA = {got} ± {se}, geometric series {want}"
        );
    }
}

/// Direct irradiance at `p` (normal `n`) from the emitter square [0.4, 0.6]² at y = 1 facing
/// down, by the midpoint rule on a k×k grid (the form factor integrand).
fn direct(p: DVec3, n: DVec3, le: f64, k: usize) -> f64 {
    let mut s = 0.0;
    let da = (0.2 / k as f64).powi(2);
    for i in 0..k {
        for j in 0..k {
            let q = DVec3::new(
                0.4 + 0.2 * (i as f64 + 0.5) / k as f64,
                1.0,
                0.4 + 0.2 * (j as f64 + 0.5) / k as f64,
            );
            let d = q - p;
            let r2 = d.length_squared();
            let w = d / r2.sqrt();
            let (c, cl) = (w.dot(n), w.y);
            if c > 0.0 && cl > 0.0 {
                s += le * c * cl / r2 * da;
            }
        }
    }
    s
}

#[test]
fn one_bounce_matches_the_direct_term() {
    let (rho, le) = (0.5, 10.0);
    let (scene, at, _) = cornell_like(rho, le);
    let dir = tempfile::tempdir().unwrap();
    let a = bake(&scene, &at, &raw_opts(64, 1), dir.path());
    // The floor is the first mesh: block (2, 2, 10, 10), u along +z, v along +x.
    let mut sum_err = 0.0;
    let mut sum_want = 0.0;
    let mut worst_z: f64 = 0.0;
    for ty in 0..10 {
        for tx in 0..10 {
            let t = &a.texels[0][((2 + ty) * 64 + 2 + tx) as usize];
            // The texel's mean over its footprint (4×4 points).
            let mut want = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    let p = DVec3::new(
                        0.1 * (ty as f64 + (b as f64 + 0.5) / 4.0),
                        0.0,
                        0.1 * (tx as f64 + (a as f64 + 0.5) / 4.0),
                    );
                    want += direct(p, DVec3::Y, le, 24) / 16.0;
                }
            }
            let got = f64::from(t.e[0]);
            let se = f64::from(t.var[0]).sqrt();
            worst_z = worst_z.max((got - want).abs() / se.max(1e-9));
            sum_err += got - want;
            sum_want += want;
        }
    }
    eprintln!(
        "direct term: floor mean off by {:.3} %, worst texel {worst_z:.2} σ",
        100.0 * sum_err / sum_want
    );
    assert!(
        (sum_err / sum_want).abs() < 0.01,
        "floor mean off by {:.3} %",
        100.0 * sum_err / sum_want
    );
    assert!(
        worst_z < 5.0,
        "a floor texel {worst_z:.1} standard errors off"
    );
}

/// A floor of 4 m × 4 m (32×32 texels of 0.125 m, one chart) with a sealed room on it: walls
/// 4 cm thick (thinner than a texel) from |x|, |z| = 0.95 to 0.99 and a roof, and a solid step
/// outside, under a constant sky. The inside gets no light at all.
fn sealed_room() -> (Scene, LightmapAtlas) {
    let (w, h) = (36, 36);
    let floor = quad(
        "floor",
        DVec3::new(-2.0, 0.0, -2.0),
        DVec3::new(0.0, 0.0, 4.0),
        DVec3::new(4.0, 0.0, 0.0),
        (2, 2, 32, 32),
        (w, h),
        0,
    );
    let v = DVec3::new;
    let (a, b, top) = (0.95, 0.99, 1.0);
    let walls = vec![
        block("wall-x-", v(-b, 0.0, -b), v(-a, top, b), false),
        block("wall-x+", v(a, 0.0, -b), v(b, top, b), false),
        block("wall-z-", v(-b, 0.0, -b), v(b, top, -a), false),
        block("wall-z+", v(-b, 0.0, a), v(b, top, b), false),
        block("roof", v(-b, top, -b), v(b, top + 0.04, b), true),
        // A solid step outside, off the texel grid.
        block("step", v(1.31, 0.0, -0.43), v(1.57, 0.5, 0.29), false),
    ];
    let mut meshes = vec![floor];
    meshes.extend(walls);
    let scene = scene_with(
        meshes,
        vec![Material::diffuse("grey", Rgb::splat(0.5))],
        Some(Rgb::splat(1.0)),
    );
    let mut mesh_page = vec![None; 7];
    mesh_page[0] = Some(0);
    (scene, atlas(w, h, mesh_page, 2))
}

#[test]
fn no_light_leaks_under_thin_walls() {
    let (scene, at) = sealed_room();
    let opts = BakeOptions {
        spp: 32,
        bounces: 2,
        seed: 3,
        tile: 16,
        denoiser: Denoiser::ATrous(Default::default()),
        transport: Default::default(),
    };
    let dir = tempfile::tempdir().unwrap();
    let a = bake(&scene, &at, &opts, dir.path());
    let mut inside = 0;
    let mut outside_lit = 0;
    for ty in 0..32u32 {
        for tx in 0..32u32 {
            let i = ((2 + ty) * 36 + 2 + tx) as usize;
            // Texel (tx, ty) covers z ∈ −2 + 0.125·[tx, tx+1], x ∈ −2 + 0.125·[ty, ty+1].
            let (z, x) = (
                -2.0 + 0.125 * (tx as f64 + 0.5),
                -2.0 + 0.125 * (ty as f64 + 0.5),
            );
            let rec = &a.texels[0][i];
            let e = a.pages[0][i];
            // Nothing is brighter than the sky allows: radiance ≤ 1 everywhere, so E ≤ π.
            assert!(
                f64::from(rec.e[1]) <= PI * (1.0 + 1e-6) + 5.0 * f64::from(rec.var[1]).sqrt(),
                "texel at x {x}, z {z}: E {} > π",
                rec.e[1]
            );
            if x.abs() < 0.95 && z.abs() < 0.95 {
                inside += 1;
                // Raw: exactly dark. Final: the denoiser's edge-stopping weight of a lit
                // neighbour is exp(−ΔE/ε), vanishingly small but not always zero.
                assert!(
                    rec.e == [0.0; 3] && e.iter().all(|&c| c < 1e-6),
                    "texel centred inside the sealed room at x {x}, z {z} is lit (raw {:?}, final {e:?}; {} valid samples)",
                    rec.e,
                    rec.valid
                );
            } else if x.abs() > 1.7 || z.abs() > 1.2 {
                outside_lit += usize::from(e[1] > 1.0);
            }
        }
    }
    assert_eq!(inside, 16 * 16);
    assert!(outside_lit > 400, "outside texels lit: {outside_lit}");
}

/// A UV sphere (radius 1, 32 segments × 16 rings) cut into two charts along the meridians
/// φ = 0 and φ = π, each a 16×16 texel block (one texel per segment and ring), above a floor
/// under a constant sky. The lighting is symmetric about the vertical axis, so irradiance is
/// the same on both sides of a meridian seam.
fn split_sphere() -> (Scene, LightmapAtlas) {
    let (w, h) = (40, 20);
    let (nseg, nring) = (32u32, 16u32);
    let mut positions = vec![];
    let mut uv1 = vec![];
    let mut normals = vec![];
    let mut indices = vec![];
    for half in 0..2u32 {
        let bx = 2 + half * 20;
        let base = positions.len() as u32;
        for j in 0..=nring {
            for i in 0..=nseg / 2 {
                let phi = PI * f64::from(half * nseg / 2 + i) / f64::from(nseg / 2);
                let theta = PI * f64::from(j) / f64::from(nring);
                let n = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                );
                positions.push(n.as_vec3());
                normals.push(n.as_vec3());
                uv1.push(Vec2::new(
                    (bx + i) as f32 / w as f32,
                    (2 + j) as f32 / h as f32,
                ));
            }
        }
        let row = nseg / 2 + 1;
        for j in 0..nring {
            for i in 0..nseg / 2 {
                let (a, b) = (base + j * row + i, base + j * row + i + 1);
                let (c, d) = (a + row, b + row);
                indices.push([a, c, d]);
                indices.push([a, d, b]);
            }
        }
    }
    let mut sphere = Mesh::new("sphere", positions, indices, 0);
    sphere.uv1 = Some(uv1);
    sphere.normals = Some(normals);
    let floor = block(
        "floor",
        DVec3::new(-4.0, -1.3, -4.0),
        DVec3::new(4.0, -1.2, 4.0),
        false,
    );
    let scene = scene_with(
        vec![sphere, floor],
        vec![Material::diffuse("grey", Rgb::splat(0.6))],
        Some(Rgb::splat(1.0)),
    );
    (scene, atlas(w, h, vec![Some(0), None], 2))
}

#[test]
fn seams_between_charts_agree_within_the_noise() {
    let (scene, at) = split_sphere();
    let dir = tempfile::tempdir().unwrap();
    let a = bake(&scene, &at, &raw_opts(64, 2), dir.path());
    let t = |x: u32, y: u32| a.texels[0][(y * 40 + x) as usize];
    // z-scores of texel pairs: the two seams (φ = π: A's last column and B's first; φ = 0:
    // A's first and B's last) and, as a control, two adjacent columns inside chart A.
    let z = |p: TexelRecord, q: TexelRecord| {
        (f64::from(p.e[1]) - f64::from(q.e[1])) / f64::from(p.var[1] + q.var[1]).sqrt()
    };
    let (mut seam, mut control) = (vec![], vec![]);
    for j in 1..15 {
        let y = 2 + j;
        assert!(t(17, y).covered() && t(22, y).covered());
        seam.push(z(t(17, y), t(22, y)));
        seam.push(z(t(2, y), t(37, y)));
        control.push(z(t(9, y), t(10, y)));
    }
    let rms = |v: &[f64]| (v.iter().map(|z| z * z).sum::<f64>() / v.len() as f64).sqrt();
    let (rs, rc) = (rms(&seam), rms(&control));
    eprintln!("seam RMS z {rs:.2}, control (inside a chart) {rc:.2}");
    assert!(
        rs < 1.6,
        "seam differences: RMS z = {rs:.2} (control {rc:.2})"
    );
    assert!(seam.iter().all(|z| z.abs() < 4.5), "{seam:?}");
    // Two charts are never mixed: the uncovered column between them stays apart.
    assert!(!t(19, 8).covered() && !t(20, 8).covered());
}

#[test]
fn resume_and_shards_are_bit_identical_and_bad_tiles_are_rebaked() {
    let (scene, at) = sealed_room();
    let opts = BakeOptions {
        spp: 8,
        bounces: 2,
        seed: 11,
        tile: 8,
        denoiser: Denoiser::ATrous(Default::default()),
        transport: Default::default(),
    };
    let dir = tempfile::tempdir().unwrap();
    let whole = dir.path().join("whole");
    let a = bake(&scene, &at, &opts, &whole);
    let exr = std::fs::read(&a.files[0]).unwrap();
    // Interrupted: some tiles missing, one corrupt, one truncated, one of another bake.
    let tiles = whole.join("tiles");
    // The tile files (the folder also holds the bake's lock file, all.lock).
    let mut names: Vec<_> = std::fs::read_dir(&tiles)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "bin"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 25, "36×36 texels in 8×8 tiles");
    assert!(tiles.join("all.lock").is_file());
    std::fs::remove_file(&names[3]).unwrap();
    std::fs::remove_file(&names[12]).unwrap();
    let mut bytes = std::fs::read(&names[6]).unwrap();
    bytes[100] ^= 0x20;
    std::fs::write(&names[6], &bytes).unwrap();
    let bytes = std::fs::read(&names[7]).unwrap();
    std::fs::write(&names[7], &bytes[..bytes.len() / 2]).unwrap();
    let other = BakeOptions {
        seed: 12,
        ..opts.clone()
    };
    let odir = dir.path().join("other");
    bake_tiles(&scene, &at, &other, &odir, Some((8, 25)), &|_, _| {}).unwrap();
    std::fs::copy(
        odir.join("tiles").join(names[8].file_name().unwrap()),
        &names[8],
    )
    .unwrap();
    // Assembling now fails and names a missing tile.
    let err = assemble(&scene, &at, &opts, &whole)
        .unwrap_err()
        .to_string();
    assert!(err.contains("page0_tile0000"), "{err}");
    let r = bake_tiles(&scene, &at, &opts, &whole, None, &|_, _| {}).unwrap();
    assert_eq!((r.baked, r.reused), (5, 20));
    // One warning for the three tiles, each named with its reason.
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    assert!(r.warnings[0].starts_with("3 tile(s)"), "{:?}", r.warnings);
    for (k, why) in [(6, "checksum"), (7, "truncated"), (8, "hash")] {
        let name = names[k].file_name().unwrap().to_string_lossy().to_string();
        assert!(
            r.warnings
                .iter()
                .any(|w| w.contains(&name) && w.contains(why)),
            "{name}: {:?}",
            r.warnings
        );
    }
    let b = assemble(&scene, &at, &opts, &whole).unwrap();
    assert_eq!(
        std::fs::read(&b.files[0]).unwrap(),
        exr,
        "resumed EXR differs"
    );
    assert_eq!(a.report.pages, b.report.pages);
    assert_eq!(a.pages, b.pages);
    // Three shards baked separately, then merged.
    let sharded = dir.path().join("sharded");
    for k in 0..3 {
        bake_tiles(&scene, &at, &opts, &sharded, Some((k, 3)), &|_, _| {}).unwrap();
    }
    let c = assemble(&scene, &at, &opts, &sharded).unwrap();
    assert_eq!(
        std::fs::read(&c.files[0]).unwrap(),
        exr,
        "merged shards differ"
    );
    assert!(bake_tiles(&scene, &at, &opts, &sharded, Some((3, 3)), &|_, _| {}).is_err());
}

#[test]
fn bad_input_is_a_clear_error() {
    let (mut scene, at) = sealed_room();
    scene.environment = None;
    let dir = tempfile::tempdir().unwrap();
    let err = bake_tiles(&scene, &at, &raw_opts(4, 1), dir.path(), None, &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("no emitter"), "{err}");
    let (scene, mut at) = sealed_room();
    at.width = 9000;
    let err = bake_tiles(&scene, &at, &raw_opts(4, 1), dir.path(), None, &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("8192"), "{err}");
    let (scene, at) = sealed_room();
    for bad in [raw_opts(0, 1), raw_opts(4, 0)] {
        assert!(bake_tiles(&scene, &at, &bad, dir.path(), None, &|_, _| {}).is_err());
    }
    let mut short = at.clone();
    short.mesh_page.pop();
    assert!(bake_tiles(
        &scene,
        &short,
        &raw_opts(4, 1),
        dir.path(),
        None,
        &|_, _| {}
    )
    .is_err());
}

#[test]
fn light_mapped_shading_matches_the_path_traced_diffuse_scene() {
    use lustre_trace::bake::diffuse_path_scene;
    use lustre_trace::bake::render::render_lightmapped;
    use lustre_trace::path_tracer::{Accumulator, PathCamera, PathOptions, PathTracer};
    let (rho, le) = (0.5, 10.0);
    let (scene, at, _) = cornell_like(rho, le);
    let bounces = 4;
    let opts = BakeOptions {
        denoiser: Denoiser::ATrous(Default::default()),
        ..raw_opts(64, bounces)
    };
    let dir = tempfile::tempdir().unwrap();
    let a = bake(&scene, &at, &opts, dir.path());
    let cam = PathCamera::look_at(
        DVec3::new(0.5, 0.5, 0.98),
        DVec3::new(0.5, 0.45, 0.0),
        DVec3::Y,
        60.0,
    )
    .unwrap();
    let (w, h) = (32, 32);
    let lm = render_lightmapped(&scene, &at, &a.pages, &cam, w, h, 16, 1).unwrap();
    // The reference: the path tracer on the same diffuse scene, one segment more than the bake
    // (camera → surface, then the bake's paths).
    let (ps, _, _) = diffuse_path_scene(&scene).unwrap();
    let pt = PathTracer::new(
        &ps,
        PathOptions {
            max_depth: bounces + 1,
            ..PathOptions::default()
        },
    )
    .unwrap();
    let mut acc = Accumulator::new(w, h).unwrap();
    pt.render(&cam, &mut acc, 256, 1, &|_, _| {});
    let reference = acc.image();
    let noise = acc.noise_rms().unwrap();
    let mean = |img: &lustre_trace::image::Image| {
        img.data.iter().map(|p| f64::from(p[1])).sum::<f64>() / img.data.len() as f64
    };
    let (m_lm, m_ref) = (mean(&lm), mean(&reference));
    let psnr = lustre_trace::metrics::psnr(&lm, &reference, 1.0).unwrap();
    eprintln!(
        "light-mapped mean {m_lm:.5} vs path traced {m_ref:.5} (noise RMS per pixel {noise:.4}), PSNR {psnr:.1} dB"
    );
    assert!((m_lm / m_ref - 1.0).abs() < 0.02, "{m_lm} vs {m_ref}");
}

/// Texels with valid and invalid samples (at the foot of walls and steps, where light leaks):
/// a baked mean must not be brighter than the irradiance anywhere near the texel: the largest
/// dense estimate (256 paths of `PathTracer::irradiance`) at the centroid of the texel's valid
/// samples and at 8 points around it at `radius` in its tangent plane (the texel's own
/// footprint, which may straddle the foot of a wall), beyond a 25 % margin and 5 standard
/// errors. The standard errors come from the dense estimate's per-path spread (for the baked
/// mean: spread / √valid), not from the baked texel's own variance, which a leak inflates.
/// Light from beyond the footprint (the other side of a wall thicker than it, the space under
/// a step) fails. `records` are (index, record) pairs. Returns the largest ratio baked / bound
/// (≤ 1 passes).
fn check_partial_texels(
    scene: &Scene,
    records: &[(usize, TexelRecord)],
    bounces: u32,
    radius: f64,
) -> f64 {
    use lustre_brdf::sampling::SplitMix64;
    use lustre_trace::bake::diffuse_path_scene;
    use lustre_trace::path_tracer::{PathOptions, PathTracer};
    let (ps, _, _) = diffuse_path_scene(scene).unwrap();
    let pt = PathTracer::new(
        &ps,
        PathOptions {
            max_depth: bounces + 1,
            ..PathOptions::default()
        },
    )
    .unwrap();
    let m = 256.0;
    let mut worst: f64 = 0.0;
    for &(k, rec) in records {
        let c = DVec3::from(rec.position.map(f64::from));
        let n = DVec3::from(rec.normal.map(f64::from));
        let t = n.any_orthonormal_vector();
        let b = n.cross(t);
        let mut rng = SplitMix64::new(k as u64);
        // (mean, per-path spread) at the centroid and around it.
        let (mean, spread) = (0..9)
            .map(|j| {
                let phi = f64::from(j) * PI / 4.0;
                let p = if j == 8 {
                    c
                } else {
                    c + (t * phi.cos() + b * phi.sin()) * radius
                };
                let (mut s, mut s2) = (0.0, 0.0);
                for _ in 0..256 {
                    let e = pt.irradiance(p, n, n, &mut rng)[1];
                    s += e;
                    s2 += e * e;
                }
                let mean = s / m;
                (mean, (s2 / m - mean * mean).max(0.0).sqrt())
            })
            .fold((0.0f64, 0.0f64), |a, b| if b.0 > a.0 { b } else { a });
        let got = f64::from(rec.e[1]);
        let se = spread * (1.0 / m.sqrt() + 1.0 / f64::from(rec.valid.max(1)).sqrt());
        let bound = 1.25 * mean + 5.0 * se;
        assert!(
            got <= bound,
            "texel {k} at {c}: baked E {got} ({} valid samples) > {bound}, from the brightest dense estimate {mean} (per-path spread {spread}) within {radius} of its valid samples: light leaks in",
            rec.valid
        );
        if bound > 0.0 {
            worst = worst.max(got / bound);
        }
    }
    worst
}

/// The covered texels of `a` with both valid and invalid samples, at most `limit`, as
/// ((page, x, y), index) pairs.
fn partial_texels(a: &Assembled, width: u32, limit: usize) -> Vec<((u32, u32, u32), usize)> {
    let spp = a.report.spp;
    let mut out = Vec::new();
    for (page, texels) in a.texels.iter().enumerate() {
        for (i, rec) in texels.iter().enumerate() {
            if rec.covered() && rec.valid > 0 && rec.valid < spp && out.len() < limit {
                let (x, y) = (i as u32 % width, i as u32 / width);
                out.push(((page as u32, x, y), out.len()));
            }
        }
    }
    out
}

#[test]
fn partially_buried_texels_are_not_brighter_than_their_valid_points() {
    let (scene, at) = sealed_room();
    let dir = tempfile::tempdir().unwrap();
    let a = bake(&scene, &at, &raw_opts(32, 2), dir.path());
    let records: Vec<(usize, TexelRecord)> = partial_texels(&a, at.width, 400)
        .into_iter()
        .map(|((p, x, y), k)| (k, a.texels[p as usize][(y * at.width + x) as usize]))
        .collect();
    // Texels of 4 m / 32 = 0.125 m; the walls are 0.04 m thick.
    let worst = check_partial_texels(&scene, &records, 2, 0.5 * 0.125);
    let checked = records.len();
    eprintln!("sealed room: {checked} partially buried texels, largest baked / bound {worst:.3}");
    assert!(checked > 70, "only {checked} partially buried texels");
    assert!(worst > 0.2, "no lit partially buried texel was checked");
}

#[test]
fn modern_hall_floor_under_walls_and_steps_does_not_leak() {
    use lustre_scene::lightmap::{build_atlas, AtlasOptions};
    let path = lustre_env::shared_data_dir().join("scenes/modern_hall/mitsuba/scene.xml");
    let mut scene = Scene::load(&path).expect("Modern Hall");
    let (at, report) = build_atlas(
        &mut scene,
        &AtlasOptions {
            texels_per_metre: 8.0,
            ..AtlasOptions::default()
        },
    )
    .expect("atlas");
    let opts = BakeOptions {
        spp: 8,
        bounces: 2,
        seed: 1,
        tile: 64,
        denoiser: Denoiser::ATrous(Default::default()),
        transport: Default::default(),
    };
    let dir = tempfile::tempdir().unwrap();
    let t0 = std::time::Instant::now();
    let a = bake(&scene, &at, &opts, dir.path());
    let p = &a.report.pages[0];
    eprintln!(
        "Modern Hall at 8 texels/m: {} charts, {}×{} × {} page(s), {} covered texels, {} buried (filled {}), bake {:.2} s",
        report.charts,
        at.width,
        at.height,
        at.pages,
        p.covered_texels,
        p.buried_filled + p.buried_unfilled,
        p.buried_filled,
        t0.elapsed().as_secs_f64()
    );
    // The texels to check, chosen without the bake's validity test: up-facing texels (floor,
    // steps) with a wall, step or other occluder within one texel (1/8 m) of their centre in
    // one of 8 horizontal directions, 1 cm above the surface; spread evenly over the atlas.
    // Baked again at 256 spp (the bake's own estimator and sample placement, little noise).
    let (ps, _, _) = lustre_trace::bake::diffuse_path_scene(&scene).unwrap();
    let pt = lustre_trace::path_tracer::PathTracer::new(&ps, Default::default()).unwrap();
    let foot: Vec<(u32, u32, u32)> = a.texels[0]
        .iter()
        .enumerate()
        .filter(|(_, r)| r.covered() && r.valid > 0 && r.normal[1] > 0.9)
        .filter(|(_, r)| {
            let o = DVec3::from(r.position.map(f64::from)) + DVec3::Y * 0.01;
            (0..8).any(|j| {
                let phi = f64::from(j) * PI / 4.0;
                pt.occluded(o, DVec3::new(phi.cos(), 0.0, phi.sin()), 0.125)
            })
        })
        .map(|(i, _)| (0, i as u32 % at.width, i as u32 / at.width))
        .collect();
    let stride = foot.len().div_ceil(300).max(1);
    let where_: Vec<(u32, u32, u32)> = foot.iter().copied().step_by(stride).collect();
    let dense = bake_texels(
        &scene,
        &at,
        &BakeOptions {
            spp: 256,
            ..opts.clone()
        },
        &where_,
    )
    .expect("re-bake");
    let partial = dense.iter().filter(|r| r.valid < 256).count();
    eprintln!(
        "Modern Hall: {} up-facing texels within 1/8 m of an occluder, {} checked, {partial} of them with invalid samples",
        foot.len(),
        where_.len()
    );
    assert!(
        partial > 30,
        "only {partial} texels at the foot of walls and steps have invalid samples"
    );
    let records: Vec<(usize, TexelRecord)> = dense
        .into_iter()
        .enumerate()
        .filter(|(_, r)| r.valid > 0)
        .collect();
    // Texels of 1/8 m.
    let worst = check_partial_texels(&scene, &records, 2, 0.5 / 8.0);
    let checked = records.len();
    eprintln!("Modern Hall: {checked} texels at the foot of walls and steps checked at 256 spp, largest baked / bound {worst:.3}");
    assert!(checked > 50, "only {checked} partially buried texels");
}

#[test]
fn single_texels_bake_to_the_tiles_records() {
    let (scene, at) = sealed_room();
    let dir = tempfile::tempdir().unwrap();
    let opts = raw_opts(8, 2);
    let a = bake(&scene, &at, &opts, dir.path());
    let some: Vec<(u32, u32, u32)> = (0..at.width * at.height)
        .step_by(37)
        .map(|i| (0, i % at.width, i / at.width))
        .collect();
    let recs = bake_texels(&scene, &at, &opts, &some).unwrap();
    for (&(_, x, y), r) in some.iter().zip(&recs) {
        assert_eq!(
            *r,
            a.texels[0][(y * at.width + x) as usize],
            "texel ({x}, {y})"
        );
    }
    assert!(bake_texels(&scene, &at, &opts, &[(0, at.width, 0)]).is_err());
    assert!(bake_texels(&scene, &at, &opts, &[(1, 0, 0)]).is_err());
}

#[test]
fn full_transport_bakes_are_keyed_by_every_material_parameter() {
    use lustre_scene::material::{MaterialKind, MicrofacetType, TexturedRgb, TexturedScalar};
    use lustre_trace::bake::{bake_hash, Transport};
    let metal = |alpha: f64| {
        Material::new(
            "metal",
            MaterialKind::RoughConductor {
                eta: Rgb([0.2, 0.4, 1.2]),
                k: Rgb([3.9, 2.4, 1.8]),
                specular: TexturedRgb::constant(Rgb::ONE),
                alpha_u: TexturedScalar::constant(alpha),
                alpha_v: TexturedScalar::constant(alpha),
                distribution: MicrofacetType::Ggx,
            },
        )
    };
    let (w, h) = (16, 16);
    let floor = quad(
        "floor",
        DVec3::new(-1.0, 0.0, 1.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, -2.0),
        (2, 2, 12, 12),
        (w, h),
        0,
    );
    let at = atlas(w, h, vec![Some(0)], 2);
    let scene = |alpha| {
        scene_with(
            vec![floor.clone()],
            vec![metal(alpha)],
            Some(Rgb::splat(1.0)),
        )
    };
    let (a, b) = (scene(0.1), scene(0.3));
    for (transport, differ) in [(Transport::Diffuse, false), (Transport::Full, true)] {
        let opts = BakeOptions {
            transport,
            ..raw_opts(4, 2)
        };
        let changed = bake_hash(&a, &at, &opts) != bake_hash(&b, &at, &opts);
        assert_eq!(changed, differ, "{transport:?}");
    }
}

#[test]
fn a_room_of_separate_two_sided_faces_does_not_leak_at_its_seams() {
    // A 2 × 1 × 2 room of six separate rectangles meeting edge to edge, a two-sided material
    // (no back faces to tell inside from outside), a sky of radiance 1 outside and no light
    // inside: every texel should bake to exactly zero. Texel samples beyond a face's edge were
    // snapped onto it, where their rays started on the neighbouring face's plane and passed out
    // through the seam: 126 of the 2,520 texels were lit (2 bounces). Samples on or within
    // EDGE_INSET of an edge are now moved inside: with direct light none is lit; with a bounce,
    // 4 are (one escaped path each: a path vertex within a hair of a seam, whose next ray misses
    // the neighbouring face).
    let (w, h) = (66, 44);
    let v = DVec3::new;
    let faces = [
        (
            "floor",
            v(-1.0, 0.0, -1.0),
            v(0.0, 0.0, 2.0),
            v(2.0, 0.0, 0.0),
        ),
        (
            "ceiling",
            v(-1.0, 1.0, -1.0),
            v(2.0, 0.0, 0.0),
            v(0.0, 0.0, 2.0),
        ),
        (
            "wall-x-",
            v(-1.0, 0.0, -1.0),
            v(0.0, 1.0, 0.0),
            v(0.0, 0.0, 2.0),
        ),
        (
            "wall-x+",
            v(1.0, 0.0, -1.0),
            v(0.0, 0.0, 2.0),
            v(0.0, 1.0, 0.0),
        ),
        (
            "wall-z-",
            v(-1.0, 0.0, -1.0),
            v(2.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
        ),
        (
            "wall-z+",
            v(-1.0, 0.0, 1.0),
            v(0.0, 1.0, 0.0),
            v(2.0, 0.0, 0.0),
        ),
    ];
    // Blocks of 20 × 20 texels (10 cm texels on the 2 m sides), a 2-texel gutter.
    let meshes: Vec<Mesh> = faces
        .iter()
        .enumerate()
        .map(|(i, &(name, p0, eu, ev))| {
            let (bx, by) = (2 + 22 * (i as u32 % 3), 2 + 22 * (i as u32 / 3));
            quad(name, p0, eu, ev, (bx, by, 20, 20), (w, h), 0)
        })
        .collect();
    let mut plaster = Material::diffuse("plaster", Rgb::splat(0.7));
    plaster.two_sided = true;
    let scene = scene_with(meshes, vec![plaster], Some(Rgb::splat(1.0)));
    let at = atlas(w, h, (0..6).map(|_| Some(0)).collect(), 2);
    for bounces in [1, 2] {
        let dir = tempfile::tempdir().unwrap();
        let a = bake(&scene, &at, &raw_opts(16, bounces), dir.path());
        let lit: Vec<(usize, [f32; 3])> = a.texels[0]
            .iter()
            .enumerate()
            .filter(|(_, r)| r.covered() && r.e != [0.0; 3])
            .map(|(i, r)| (i, r.e))
            .collect();
        let covered = a.texels[0].iter().filter(|r| r.covered()).count();
        eprintln!(
            "{bounces} bounce(s): {} of {covered} covered texels lit",
            lit.len()
        );
        assert!(covered >= 6 * 400, "{covered}");
        let allowed = if bounces == 1 { 0 } else { covered / 200 };
        assert!(
            lit.len() <= allowed,
            "{bounces} bounce(s): {} lit texels (index, E): {:?}",
            lit.len(),
            &lit[..lit.len().min(8)]
        );
        let worst = lit.iter().map(|l| l.1[1]).fold(0.0f32, f32::max);
        assert!(
            worst < 0.25,
            "a texel lit by more than one escaped path: E {worst}"
        );
    }
}
