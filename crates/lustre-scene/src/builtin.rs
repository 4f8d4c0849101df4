//! The built-in scene (no files needed): a 6 × 3 × 8 m room with a window in the far wall open
//! to the built-in sky, a ceiling light panel, a glossy dark-wood floor (the planar reflector),
//! and on pedestals three probe objects — a sphere of a fitted measured material (the SGD fit of
//! MERL's gold metallic paint), a brushed-aluminium sphere (anisotropic) and a frosted-glass
//! sphere (transmissive). What `lustre render` shows with no scene given.

use crate::camera::{Camera, CameraPath, FovAxis, Keyframe};
use crate::environment::{Environment, EnvironmentSource, Sky};
use crate::material::{
    Material, MaterialKind, MicrofacetType, ResolvedSpec, TexturedRgb, TexturedScalar,
};
use crate::mesh::Mesh;
use crate::{Film, Result, Scene, SceneError};
use glam::{DMat3, DVec3, Vec2, Vec3};
use lustre_brdf::rgb::Rgb;

/// Room width (x), height (y) and depth (z), metres.
pub const ROOM: [f32; 3] = [6.0, 3.0, 8.0];

/// The fitted measured material of the first sphere.
pub const FITTED_SPEC: &str = "sgd:gold-metallic-paint";

/// 004 Fig. IV.13's three measured paints, left to right, for [`lineup`] (what `lustre render
/// --method adaptive` and `lustre view --lineup` show by default).
pub const LINEUP_PAINTS: [&str; 3] = [
    "nbrdf:color-changing-paint3",
    "nbrdf:red-metallic-paint",
    "nbrdf:gold-paint",
];

/// The floor under [`LINEUP_PAINTS`] in 004 Fig. IV.13: white marble.
pub const LINEUP_FLOOR: &str = "nbrdf:white-marble";

/// A quad p0, p0+eu, p0+eu+ev, p0+ev facing eu × ev.
fn quad(name: &str, p0: Vec3, eu: Vec3, ev: Vec3, material: usize) -> Mesh {
    let n = eu.cross(ev).normalize();
    let mut m = Mesh::new(
        name,
        vec![p0, p0 + eu, p0 + eu + ev, p0 + ev],
        vec![[0, 1, 2], [0, 2, 3]],
        material,
    );
    m.normals = Some(vec![n; 4]);
    m.uv0 = Some(vec![
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ]);
    m
}

/// A closed axis-aligned box [lo, hi] with outward faces.
fn block(name: &str, lo: Vec3, hi: Vec3, material: usize) -> Mesh {
    let c = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    // Per face: the four corners counter-clockwise seen from outside, and the normal.
    let faces: [([usize; 4], Vec3); 6] = [
        ([0, 2, 3, 1], Vec3::NEG_Z),
        ([4, 5, 7, 6], Vec3::Z),
        ([0, 4, 6, 2], Vec3::NEG_X),
        ([1, 3, 7, 5], Vec3::X),
        ([0, 1, 5, 4], Vec3::NEG_Y),
        ([2, 6, 7, 3], Vec3::Y),
    ];
    let mut positions = vec![];
    let mut normals = vec![];
    let mut indices = vec![];
    for (q, n) in faces {
        let b = positions.len() as u32;
        positions.extend(q.iter().map(|&i| c(i)));
        normals.extend([n; 4]);
        indices.push([b, b + 1, b + 2]);
        indices.push([b, b + 2, b + 3]);
    }
    let mut m = Mesh::new(name, positions, indices, material);
    m.normals = Some(normals);
    m
}

/// The built-in scene. Errors only if the built-in fitted material cannot be resolved.
pub fn room() -> Result<Scene> {
    let [w, h, d] = ROOM;
    let v = Vec3::new;
    let diffuse = |name: &str, c: [f64; 3]| Material::diffuse(name, Rgb(c));
    let materials = vec![
        diffuse("wall", [0.78, 0.76, 0.72]),
        diffuse("ceiling", [0.85, 0.85, 0.85]),
        Material::new(
            "floor",
            MaterialKind::RoughPlastic {
                diffuse: TexturedRgb::constant(Rgb([0.22, 0.14, 0.09])),
                specular: Rgb::ONE,
                alpha: TexturedScalar::constant(0.04),
                distribution: MicrofacetType::Ggx,
                int_ior: 1.5,
                ext_ior: 1.0,
                nonlinear: false,
            },
        ),
        diffuse("pedestal", [0.55, 0.56, 0.6]),
        diffuse("lamp", [0.8, 0.8, 0.8]),
        Material::new(
            "gold-paint",
            MaterialKind::Spec(ResolvedSpec::resolve("gold-paint", FITTED_SPEC)?),
        ),
        Material::new(
            "brushed-aluminium",
            MaterialKind::RoughConductor {
                eta: Rgb([1.66, 0.88, 0.52]),
                k: Rgb([9.22, 6.27, 4.84]),
                specular: TexturedRgb::constant(Rgb::ONE),
                alpha_u: TexturedScalar::constant(0.3),
                alpha_v: TexturedScalar::constant(0.04),
                distribution: MicrofacetType::Ggx,
            },
        ),
        Material::new(
            "frosted-glass",
            MaterialKind::RoughDielectric {
                int_ior: 1.5,
                ext_ior: 1.0,
                alpha: TexturedScalar::constant(0.2),
                distribution: MicrofacetType::Ggx,
                specular_reflectance: Rgb::ONE,
                specular_transmittance: Rgb::ONE,
            },
        ),
    ];
    let (wall, ceiling, floor, pedestal, lamp) = (0, 1, 2, 3, 4);
    let mut meshes = vec![
        quad(
            "floor",
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, d),
            v(w, 0.0, 0.0),
            floor,
        ),
        quad(
            "ceiling",
            v(0.0, h, 0.0),
            v(w, 0.0, 0.0),
            v(0.0, 0.0, d),
            ceiling,
        ),
        quad(
            "wall-left",
            v(0.0, 0.0, 0.0),
            v(0.0, h, 0.0),
            v(0.0, 0.0, d),
            wall,
        ),
        quad(
            "wall-right",
            v(w, 0.0, 0.0),
            v(0.0, 0.0, d),
            v(0.0, h, 0.0),
            wall,
        ),
        quad(
            "wall-back",
            v(0.0, 0.0, 0.0),
            v(w, 0.0, 0.0),
            v(0.0, h, 0.0),
            wall,
        ),
    ];
    // The far wall (z = d, facing −z) around a window x ∈ [1.5, 4.5], y ∈ [0.8, 2.5].
    let (x0, x1, y0, y1) = (1.5, 4.5, 0.8, 2.5);
    for (name, lo, hi) in [
        ("wall-window-left", v(0.0, 0.0, d), v(x0, h, d)),
        ("wall-window-right", v(x1, 0.0, d), v(w, h, d)),
        ("wall-window-below", v(x0, 0.0, d), v(x1, y0, d)),
        ("wall-window-above", v(x0, y1, d), v(x1, h, d)),
    ] {
        meshes.push(quad(
            name,
            lo,
            v(0.0, hi.y - lo.y, 0.0),
            v(hi.x - lo.x, 0.0, 0.0),
            wall,
        ));
    }
    // The window's reveal (the wall's thickness, 0.2 m), facing into the opening.
    let t = 0.2;
    meshes.push(quad(
        "reveal-bottom",
        v(x0, y0, d),
        v(0.0, 0.0, t),
        v(x1 - x0, 0.0, 0.0),
        wall,
    ));
    meshes.push(quad(
        "reveal-top",
        v(x0, y1, d),
        v(x1 - x0, 0.0, 0.0),
        v(0.0, 0.0, t),
        wall,
    ));
    meshes.push(quad(
        "reveal-left",
        v(x0, y0, d),
        v(0.0, y1 - y0, 0.0),
        v(0.0, 0.0, t),
        wall,
    ));
    meshes.push(quad(
        "reveal-right",
        v(x1, y0, d),
        v(0.0, 0.0, t),
        v(0.0, y1 - y0, 0.0),
        wall,
    ));
    let mut panel = quad(
        "lamp",
        v(2.4, h - 0.01, 3.0),
        v(1.2, 0.0, 0.0),
        v(0.0, 0.0, 1.2),
        lamp,
    );
    panel.emission = Some(Rgb([9.0, 8.5, 7.5]));
    meshes.push(panel);
    // Pedestals and spheres.
    let r = 0.38;
    for (k, (x, z, name, m)) in [
        (1.6, 4.6, "gold-paint", 5),
        (3.0, 5.4, "brushed-aluminium", 6),
        (4.4, 4.6, "frosted-glass", 7),
    ]
    .into_iter()
    .enumerate()
    {
        meshes.push(block(
            &format!("pedestal-{k}"),
            v(x - 0.3, 0.0, z - 0.3),
            v(x + 0.3, 0.6, z + 0.3),
            pedestal,
        ));
        let mut s = Mesh::uv_sphere(name, v(x, 0.6 + r, z), r, m);
        s.hints.probe = true;
        meshes.push(s);
    }
    meshes[0].hints.planar_reflector = true;
    let mut scene = Scene::new("built-in room");
    scene.materials = materials;
    scene.meshes = meshes;
    scene.environment = Some(Environment {
        source: EnvironmentSource::Sky(Sky {
            zenith: [1.0, 1.7, 3.4],
            horizon: [3.6, 3.8, 4.0],
            ground: [0.9, 0.85, 0.75],
        }),
        to_local: DMat3::IDENTITY,
        intensity: 1.0,
    });
    let look = |name: &str, eye: [f64; 3], target: [f64; 3], fov: f64| {
        Camera::look_at(
            name,
            DVec3::from(eye),
            DVec3::from(target),
            DVec3::Y,
            fov,
            FovAxis::X,
        )
        .ok_or_else(|| SceneError::Format {
            path: "built-in room".into(),
            problem: format!("the camera {name:?} is degenerate"),
        })
    };
    let camera = look("default", [3.0, 1.55, 0.9], [3.0, 0.85, 5.6], 62.0)?;
    let close = look("close", [2.2, 1.2, 2.9], [3.0, 0.9, 5.0], 55.0)?;
    // The views of 000 Tables 4.1 and 4.2 (`scripts/frame_tables.py`): the screen full of and
    // about half full of view-dependent pixels, on a curved probe object (the brushed-aluminium
    // sphere, centre (3, 0.98, 5.4), radius 0.38) and on the planar reflector (the floor).
    let sphere = [3.0, 0.6 + f64::from(r), 5.4];
    let benchmark = [
        look("curved-full", [3.0, sphere[1], 4.92], sphere, 62.0)?,
        look("curved-half", [3.0, sphere[1], 4.25], sphere, 62.0)?,
        look("planar-full", [3.0, 1.6, 1.0], [3.0, 0.0, 2.4], 62.0)?,
        look("planar-half", [3.0, 1.0, 0.3], [3.0, 0.62, 4.0], 62.0)?,
    ];
    scene.camera_paths = vec![CameraPath {
        name: "walk".into(),
        keyframes: vec![
            Keyframe {
                time: 0.0,
                camera: camera.clone(),
            },
            Keyframe {
                time: 2.0,
                camera: close.clone(),
            },
        ],
        looped: false,
    }];
    scene.cameras = [camera, close].into_iter().chain(benchmark).collect();
    scene.film = Film {
        width: 960,
        height: 540,
    };
    Ok(scene)
}

/// The material preview: a sphere of radius 1 (tangents along its longitude, for anisotropic
/// materials) of material `spec` (any lustre material specification) under `environment`, or
/// the built-in sky when `None`, seen from 4.2 units away with a 30° vertical field of view. No
/// light maps: the whole material is integrated against the environment.
pub fn preview(spec: &str, environment: Option<Environment>) -> Result<Scene> {
    let mut scene = Scene::new(format!("preview of {spec}"));
    scene.materials = vec![Material::new(
        spec,
        MaterialKind::Spec(ResolvedSpec::resolve(spec, spec)?),
    )];
    scene.meshes = vec![Mesh::uv_sphere("preview", Vec3::ZERO, 1.0, 0)];
    scene.environment = Some(environment.unwrap_or_else(builtin_sky));
    let camera = default_camera(
        "material preview",
        DVec3::new(0.0, 1.2, 4.0),
        DVec3::ZERO,
        30.0,
    )?;
    scene.cameras = vec![camera];
    scene.film = Film {
        width: 512,
        height: 512,
    };
    Ok(scene)
}

/// The camera "default" of a built-in scene at `eye` looking at `target` (+y up, vertical
/// field of view `fov_y` degrees).
fn default_camera(scene: &str, eye: DVec3, target: DVec3, fov_y: f64) -> Result<Camera> {
    Camera::look_at("default", eye, target, DVec3::Y, fov_y, FovAxis::Y).ok_or_else(|| {
        SceneError::Format {
            path: scene.into(),
            problem: "the camera is degenerate".into(),
        }
    })
}

/// The built-in sky, unrotated, at intensity 1.
fn builtin_sky() -> Environment {
    Environment {
        source: EnvironmentSource::Sky(Sky::default()),
        to_local: DMat3::IDENTITY,
        intensity: 1.0,
    }
}

/// 004 Fig. IV.13's arrangement: three spheres of radius 1 side by side, of materials `spheres`
/// (left to right), on a 12 × 12 floor of material `floor`, under `environment` (the built-in
/// sky when `None`), seen from slightly above. No light maps: every surface is integrated
/// against the environment.
pub fn lineup(spheres: [&str; 3], floor: &str, environment: Option<Environment>) -> Result<Scene> {
    let mut scene = Scene::new(format!(
        "line-up of {}, {}, {} on {floor}",
        spheres[0], spheres[1], spheres[2]
    ));
    for spec in spheres.iter().chain([&floor]) {
        scene.materials.push(Material::new(
            *spec,
            MaterialKind::Spec(ResolvedSpec::resolve(spec, spec)?),
        ));
    }
    for (k, x) in [-2.3f32, 0.0, 2.3].into_iter().enumerate() {
        scene.meshes.push(Mesh::uv_sphere(
            &format!("sphere {k}"),
            Vec3::new(x, 1.0, 0.0),
            1.0,
            k,
        ));
    }
    let mut ground = crate::mesh::rectangle("floor", 3);
    // The square [−1, 1]² of z = 0 turned to face +y and scaled to 12 × 12.
    ground.transform(
        &(glam::DMat4::from_scale(DVec3::new(6.0, 1.0, 6.0))
            * glam::DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2)),
    );
    scene.meshes.push(ground);
    scene.environment = Some(environment.unwrap_or_else(builtin_sky));
    let camera = default_camera(
        "line-up",
        DVec3::new(0.0, 2.6, 7.5),
        DVec3::new(0.0, 0.8, 0.0),
        40.0,
    )?;
    scene.cameras = vec![camera];
    scene.film = Film {
        width: 768,
        height: 512,
    };
    Ok(scene)
}
