//! The path-traced reference of a [`lustre_scene::Scene`]: the adapter from the scene model to
//! the path tracer's [`PathScene`], and the resumable job behind `lustre reference`.
//!
//! Files of a job writing `OUT.exr`: `OUT.exr` (the mean, RGB float), `OUT.even.exr` and
//! `OUT.odd.exr` (the two independent halves), `OUT.json` (sample count, settings, the noise
//! estimate, timings) and `OUT.png` (a preview with exposure). All are written atomically after
//! every pass (the halves committed through the JSON, [`commit_halves`], so that a kill at any
//! point resumes consistently); `resume` reads the halves and the JSON back and continues with the next sample
//! index, so a resumed render equals an uninterrupted one (up to the f32 rounding of the halves).

use crate::image::Image;
use crate::path_tracer::{
    Accumulator, EnvLight, Geometry, PathCamera, PathOptions, PathScene, PathTracer, Surface,
};
use crate::{Result, TraceError};
use glam::{DMat3, DVec3, Vec2};
use lustre_brdf::bsdf::Bsdf;
use lustre_brdf::models::lambert::Lambert;
use lustre_brdf::rgb::Rgb;
use lustre_scene::{Camera, EnvironmentSource, Material, Scene, Texture};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A scene material as a [`Surface`]: textures evaluated at the hit by
/// [`Material::bsdf_at`], alpha masks by [`Material::alpha_at`] (opaque at opacity ≥ ½: a
/// stochastic Mitsuba `mask` is thresholded), two-sidedness from the material.
struct SceneSurface<'s> {
    material: &'s Material,
    textures: &'s [Texture],
}

impl Surface for SceneSurface<'_> {
    fn with_bsdf(&self, uv: [f64; 2], f: &mut dyn FnMut(&dyn Bsdf)) {
        let uv = [Vec2::new(uv[0] as f32, uv[1] as f32); 2];
        if self
            .material
            .with_bsdf_at(self.textures, &uv, &mut *f)
            .is_err()
        {
            // `path_scene` checked every material at uv = 0; a texel that still fails (it
            // cannot for clamped textures) renders black rather than aborting a long render.
            f(&Lambert { kd: Rgb::ZERO });
        }
    }
    fn masked(&self) -> bool {
        self.material.alpha_mask.is_some()
    }
    fn opaque(&self, uv: [f64; 2]) -> bool {
        let uv = [Vec2::new(uv[0] as f32, uv[1] as f32); 2];
        self.material.alpha_at(self.textures, &uv) >= 0.5
    }
    fn two_sided(&self) -> bool {
        self.material.two_sided
    }
    fn normal_mapped(&self) -> bool {
        self.material.normal_map.is_some()
    }
    fn normal_map(&self, uv: [f64; 2]) -> Option<DVec3> {
        let uv = [Vec2::new(uv[0] as f32, uv[1] as f32); 2];
        self.material.normal_map_at(self.textures, &uv)
    }
    fn bsdf_textures(&self) -> Vec<&Texture> {
        let m = self.material;
        let mask = m.alpha_mask.and_then(|a| a.opacity.texture);
        let mut out: Vec<usize> = m
            .texture_refs()
            .into_iter()
            .filter(|r| Some(*r) != mask && Some(*r) != m.emission_texture)
            .map(|r| r.texture)
            .filter(|&k| k < self.textures.len())
            .collect();
        out.sort_unstable();
        out.dedup();
        out.into_iter().map(|k| &self.textures[k]).collect()
    }
    fn emission_textured(&self) -> bool {
        self.material.emission_texture.is_some()
    }
    fn emission_factor(&self, uv: [f64; 2]) -> Rgb {
        let uv = [Vec2::new(uv[0] as f32, uv[1] as f32); 2];
        self.material.emission_at(self.textures, &uv)
    }
}

/// A material the BSDF library cannot build (reported as a warning, rendered grey).
#[derive(Debug)]
struct Fallback(Lambert);

impl Surface for Fallback {
    fn with_bsdf(&self, _uv: [f64; 2], f: &mut dyn FnMut(&dyn Bsdf)) {
        f(&self.0)
    }
    fn two_sided(&self) -> bool {
        true
    }
}

/// Width of the equirect map a rotated or analytic environment is resampled to.
pub const ENV_WIDTH: usize = 2048;

/// The path tracer's view of `scene`: world triangles with normals, tangents, uv0 and emission,
/// one [`Surface`] per material (textures, alpha masks, normal maps and emission textures
/// through [`Material`]) and the environment as an importance-sampled [`EnvLight`]. Returns
/// warnings for what is approximated (materials the BSDF library cannot build yet are rendered
/// as two-sided grey Lambert 0.5, named).
pub fn path_scene(scene: &Scene) -> Result<(PathScene<'_>, Vec<String>)> {
    let mut warnings = vec![];
    let mut g = Geometry::default();
    let any_normals = scene.meshes.iter().any(|m| m.normals.is_some());
    let any_uvs = scene.meshes.iter().any(|m| m.uv0.is_some());
    let any_emission = scene.meshes.iter().any(|m| m.emission.is_some());
    let any_tangents = scene.meshes.iter().any(|m| m.tangents.is_some());
    let d = |v: glam::Vec3| DVec3::new(v.x as f64, v.y as f64, v.z as f64);
    for m in &scene.meshes {
        for t in &m.indices {
            let corner = |k: usize| t[k] as usize;
            let p = [0, 1, 2].map(|k| d(m.positions[corner(k)]));
            g.positions.push(p);
            if any_normals {
                let n = match &m.normals {
                    Some(n) => [0, 1, 2].map(|k| d(n[corner(k)])),
                    None => [(p[1] - p[0]).cross(p[2] - p[0]); 3],
                };
                g.normals.push(n);
            }
            if any_uvs {
                let uv = match &m.uv0 {
                    Some(uv) => [0, 1, 2].map(|k| {
                        let v = uv[corner(k)];
                        [v.x as f64, v.y as f64]
                    }),
                    None => [[0.0; 2]; 3],
                };
                g.uvs.push(uv);
            }
            if any_tangents {
                let t = match &m.tangents {
                    Some(t) => [0, 1, 2].map(|k| {
                        let v = t[corner(k)];
                        [v.x as f64, v.y as f64, v.z as f64, v.w as f64]
                    }),
                    None => [[0.0; 4]; 3],
                };
                g.tangents.push(t);
            }
            if any_emission {
                g.emission.push(m.emission.unwrap_or(Rgb::ZERO));
            }
            g.material.push(m.material as u32);
        }
    }
    let mut materials: Vec<Box<dyn Surface + '_>> = vec![];
    for mat in &scene.materials {
        match mat.check(&scene.textures) {
            Ok(()) => materials.push(Box::new(SceneSurface {
                material: mat,
                textures: &scene.textures,
            })),
            Err(e) => {
                warnings.push(format!(
                    "material {:?} renders as grey Lambert 0.5: {e}",
                    mat.name
                ));
                materials.push(Box::new(Fallback(Lambert {
                    kd: Rgb::splat(0.5),
                })));
            }
        }
    }
    let environment = match &scene.environment {
        None => None,
        Some(env) => {
            let width = match env.source {
                EnvironmentSource::Constant(_) => 8,
                _ => ENV_WIDTH,
            };
            let map = env.to_world_equirect(width);
            if map.data.iter().all(|p| p.iter().all(|&c| c == 0.0)) {
                warnings.push("environment is black: ignored".into());
                None
            } else {
                Some(EnvLight::new(map, DMat3::IDENTITY, 1.0)?)
            }
        }
    };
    Ok((
        PathScene {
            geometry: g,
            materials,
            environment,
        },
        warnings,
    ))
}

/// The path camera of the scene's camera `name` (the first one when `None`) for a W×H film. A
/// scene without cameras (an OBJ) gets an automatic one when no name is asked: 40° vertical
/// field of view, looking along +z at the centre of the bounds from far enough back to see
/// them (the Cornell box convention).
pub fn path_camera(
    scene: &Scene,
    name: Option<&str>,
    width: u32,
    height: u32,
) -> Result<PathCamera> {
    let aspect = f64::from(width) / f64::from(height);
    // `auto` names the framing camera a scene without cameras gets (what a run's record says).
    let name = name.filter(|n| !(scene.cameras.is_empty() && *n == "auto"));
    if name.is_none() && scene.cameras.is_empty() {
        let (lo, hi) = scene.bounds().ok_or_else(|| {
            TraceError::Parameter(format!("{}: the scene is empty", scene.source.display()))
        })?;
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        let c = 0.5 * (lo + hi);
        let r = 0.5 * (hi - lo).length();
        let fov: f64 = 40.0;
        let dist = r
            / (fov.to_radians() * 0.5)
                .tan()
                .min(aspect * (fov.to_radians() * 0.5).tan());
        return PathCamera::look_at(c - DVec3::Z * dist.max(1e-6), c, DVec3::Y, fov);
    }
    let cam = scene.camera(name).ok_or_else(|| {
        TraceError::Parameter(match name {
            Some(n) if scene.cameras.is_empty() => format!(
                "{}: no camera named {n:?}: the scene has no camera (leave out the camera, or \
                 give `auto`, for a view framing the whole scene)",
                scene.source.display()
            ),
            Some(n) => format!(
                "{}: no camera named {n:?} (cameras: {})",
                scene.source.display(),
                scene
                    .cameras
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            None => format!("{}: the scene has no camera", scene.source.display()),
        })
    })?;
    film_camera(cam, width, height)
}

/// The path camera of scene camera `cam` on a W×H film (its field of view along its axis).
pub fn film_camera(cam: &Camera, width: u32, height: u32) -> Result<PathCamera> {
    let aspect = f64::from(width) / f64::from(height);
    let fov_y = cam.fov_y_deg(aspect);
    PathCamera::look_at(cam.position, cam.position + cam.forward, cam.up, fov_y)
}

/// Settings of a reference job.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceOptions {
    /// Camera name (the scene's first when `None`).
    pub camera: Option<String>,
    /// Samples per pixel in total.
    pub spp: u32,
    /// Longest path (segments).
    pub max_depth: u32,
    /// Film size; the scene's when `None`.
    pub size: Option<(u32, u32)>,
    /// Continue from the files of a previous run.
    pub resume: bool,
    /// The output `.exr`.
    pub out: PathBuf,
    /// Exposure of the PNG preview.
    pub exposure: f64,
    /// Seed of every pixel's sample stream.
    pub seed: u64,
    /// Render the bake's diffuse scene ([`crate::bake::diffuse_path_scene`]: every material
    /// replaced by its diffuse albedo), the image light-mapped shading converges to.
    pub diffuse: bool,
}

/// What a job wrote into `OUT.json` (and resumes from).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceState {
    /// The scene file.
    pub scene: String,
    /// Camera name.
    pub camera: String,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel accumulated.
    pub spp: u32,
    /// Longest path (segments).
    pub max_depth: u32,
    /// Seed.
    pub seed: u64,
    /// The diffuse scene ([`ReferenceOptions::diffuse`]).
    #[serde(default)]
    pub diffuse: bool,
    /// Estimated RMS noise of the mean (linear, all channels): RMS(even − odd)/2; `null` in
    /// the JSON when undefined (e.g. a black image's relative noise), read back as NaN.
    #[serde(with = "nan_as_null")]
    pub noise_rms: f64,
    /// `noise_rms` / mean pixel value (`null` when undefined).
    #[serde(with = "nan_as_null")]
    pub noise_relative: f64,
    /// Mean pixel value (all channels; `null` when undefined).
    #[serde(with = "nan_as_null")]
    pub mean: f64,
    /// Seconds of rendering, summed over runs.
    pub seconds: f64,
    /// The halves of this `spp` are in `OUT.even.next.exr` / `OUT.odd.next.exr`, not yet moved
    /// to `OUT.even.exr` / `OUT.odd.exr` (see [`commit_halves`]).
    #[serde(default)]
    pub pending: bool,
    /// Fingerprint of what the image depends on ([`scene_hash`]), hex: a resume of another scene,
    /// or of the same file edited, is refused.
    #[serde(default)]
    pub scene_hash: String,
}

/// A 64-bit fingerprint of everything a reference image depends on in `scene`: the geometry
/// (positions, indices, normals, uvs, materials, emission), every material's parameters, the
/// textures (size and mean), the environment (radiance in 4096 directions) and the cameras.
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut h = crate::bake::Fnv::new();
    for m in &scene.meshes {
        h.u64(m.positions.len() as u64);
        for p in &m.positions {
            p.to_array().into_iter().for_each(|c| h.f32(c));
        }
        for t in &m.indices {
            t.iter().for_each(|&i| h.u64(u64::from(i)));
        }
        for n in m.normals.iter().flatten() {
            n.to_array().into_iter().for_each(|c| h.f32(c));
        }
        for uv in m.uv0.iter().flatten() {
            uv.to_array().into_iter().for_each(|c| h.f32(c));
        }
        h.u64(m.material as u64);
        h.bytes(format!("{:?}", m.emission).as_bytes());
    }
    h.bytes(format!("{:?}", scene.materials).as_bytes());
    for t in &scene.textures {
        h.u64(u64::from(t.width) << 32 | u64::from(t.height));
        t.mean().into_iter().for_each(|c| h.f64(c));
    }
    h.bytes(format!("{:?}", scene.cameras).as_bytes());
    crate::bake::hash_environment(&mut h, scene);
    h.0
}

/// A number that JSON writes as `null` when it is not finite (serde_json's own choice) and that
/// reads `null` back as NaN, so that a checkpoint whose noise is undefined still resumes.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> std::result::Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
    }
}

/// Makes the halves just written to their `.next` files the job's state, so that a kill at any
/// point leaves a state `resume` reads consistently: the JSON (written atomically) is the commit
/// point. First the JSON with the new count and `pending`, then the renames, then the JSON
/// without `pending`. Before the first JSON write, `resume` drops the `.next` files and continues
/// from the previous count; after it, `resume` finishes the renames.
fn commit_halves(
    state: &mut ReferenceState,
    json_path: &Path,
    moves: [(&PathBuf, &PathBuf); 2],
) -> Result<()> {
    let write = |state: &ReferenceState| -> Result<()> {
        let json = serde_json::to_string_pretty(state)
            .map_err(|e| TraceError::Parameter(format!("state: {e}")))?;
        lustre_brdf::error::write_atomic(json_path, json.as_bytes())?;
        Ok(())
    };
    state.pending = true;
    if let Err(e) = write(state) {
        // The JSON still names the previous pass: the `.next` halves are not part of the job.
        state.pending = false;
        return Err(e);
    }
    for (next, fin) in moves {
        std::fs::rename(next, fin).map_err(|e| TraceError::Io {
            path: next.clone(),
            source: e,
        })?;
    }
    state.pending = false;
    write(state)
}

/// `OUT` with its extension replaced by `ext`.
fn sibling(out: &Path, ext: &str) -> PathBuf {
    out.with_extension(ext)
}

fn read_exr(path: &Path) -> Result<Image> {
    // One prefix: "invalid parameter: resume: cannot read …", not the parameter error twice.
    Image::read_exr(path).map_err(|e| match e {
        TraceError::Parameter(m) => TraceError::Parameter(format!("resume: {m}")),
        other => other,
    })
}

/// Renders (or continues) the reference of `scene` with `opts`, writing the files after every
/// pass (passes double in size, from 2 up to 64 samples). `progress(spp_done, spp_total,
/// tiles_done, tiles)` reports. Returns the final state.
pub fn render_reference(
    scene: &Scene,
    opts: &ReferenceOptions,
    progress: &(dyn Fn(u32, u32, usize, usize) + Sync),
) -> Result<(ReferenceState, Vec<String>)> {
    let (w, h) = opts.size.unwrap_or((scene.film.width, scene.film.height));
    if w == 0 || h == 0 || w > 1 << 15 || h > 1 << 15 {
        return Err(TraceError::Parameter(format!(
            "image size {w}×{h} must be between 1 and 32768"
        )));
    }
    if opts.spp == 0 || opts.spp > 1 << 24 {
        return Err(TraceError::Parameter(format!(
            "--spp {} must be between 1 and {}",
            opts.spp,
            1 << 24
        )));
    }
    if opts.max_depth == 0 || opts.max_depth > 1024 {
        return Err(TraceError::Parameter(format!(
            "--max-depth {} must be between 1 and 1024",
            opts.max_depth
        )));
    }
    if !(opts.exposure.is_finite() && opts.exposure > 0.0) {
        return Err(TraceError::Parameter(format!(
            "exposure {} must be finite and > 0",
            opts.exposure
        )));
    }
    let camera = path_camera(scene, opts.camera.as_deref(), w, h)?;
    let cam_name = scene
        .camera(opts.camera.as_deref())
        .map_or_else(|| "auto".to_string(), |c| c.name.clone());
    let (ps, warnings) = if opts.diffuse {
        let (ps, _, warnings) = crate::bake::diffuse_path_scene(scene)?;
        (ps, warnings)
    } else {
        path_scene(scene)?
    };
    let pt = PathTracer::new(
        &ps,
        PathOptions {
            max_depth: opts.max_depth,
            ..PathOptions::default()
        },
    )?;
    let json_path = sibling(&opts.out, "json");
    let (even_path, odd_path) = (
        sibling(&opts.out, "even.exr"),
        sibling(&opts.out, "odd.exr"),
    );
    let mut state = ReferenceState {
        scene: scene.source.display().to_string(),
        camera: cam_name,
        width: w,
        height: h,
        spp: 0,
        max_depth: opts.max_depth,
        seed: opts.seed,
        diffuse: opts.diffuse,
        noise_rms: f64::NAN,
        noise_relative: f64::NAN,
        mean: f64::NAN,
        seconds: 0.0,
        pending: false,
        scene_hash: format!("{:016x}", scene_hash(scene)),
    };
    let (even_next, odd_next) = (
        sibling(&opts.out, "even.next.exr"),
        sibling(&opts.out, "odd.next.exr"),
    );
    let mut acc = Accumulator::new(w as usize, h as usize)?;
    if opts.resume {
        let text = std::fs::read_to_string(&json_path).map_err(|e| TraceError::Io {
            path: json_path.clone(),
            source: e,
        })?;
        let old: ReferenceState = serde_json::from_str(&text)
            .map_err(|e| TraceError::Parameter(format!("resume: {}: {e}", json_path.display())))?;
        if (
            old.width,
            old.height,
            old.max_depth,
            old.seed,
            &old.camera,
            old.diffuse,
        ) != (w, h, opts.max_depth, opts.seed, &state.camera, opts.diffuse)
        {
            return Err(TraceError::Parameter(format!(
                "resume: {} was rendered at {}×{}, max depth {}, seed {}, camera {:?}, diffuse {}; asked for {w}×{h}, {}, {}, {:?}, {}",
                json_path.display(),
                old.width,
                old.height,
                old.max_depth,
                old.seed,
                old.camera,
                old.diffuse,
                opts.max_depth,
                opts.seed,
                state.camera,
                opts.diffuse
            )));
        }
        if old.scene_hash != state.scene_hash {
            return Err(TraceError::Parameter(format!(
                "resume: {} was rendered from {} {}; this scene ({}) differs (fingerprint {}): \
                 render it without --resume, or into another --out",
                json_path.display(),
                if old.scene.is_empty() {
                    "a scene"
                } else {
                    &old.scene
                },
                if old.scene_hash.is_empty() {
                    "by an older lustre that recorded no fingerprint".to_string()
                } else {
                    format!("with fingerprint {}", old.scene_hash)
                },
                state.scene,
                state.scene_hash
            )));
        }
        // Finish a commit that was interrupted after its JSON, or drop the halves of a pass
        // whose JSON was never written.
        for (next, fin) in [(&even_next, &even_path), (&odd_next, &odd_path)] {
            if old.pending && next.exists() {
                std::fs::rename(next, fin).map_err(|e| TraceError::Io {
                    path: next.clone(),
                    source: e,
                })?;
            } else if !old.pending && next.exists() {
                std::fs::remove_file(next).map_err(|e| TraceError::Io {
                    path: next.clone(),
                    source: e,
                })?;
            }
        }
        let (a, b) = (read_exr(&even_path)?, read_exr(&odd_path)?);
        acc = Accumulator::from_halves(&a, &b, old.spp)?;
        state.seconds = old.seconds;
    }
    let total = opts.spp;
    while acc.spp < total {
        let pass = acc.spp.clamp(2, 64).min(total - acc.spp);
        let t0 = Instant::now();
        let done = acc.spp;
        pt.render(&camera, &mut acc, pass, opts.seed, &|t, n| {
            progress(done, total, t, n)
        });
        state.seconds += t0.elapsed().as_secs_f64();
        state.spp = acc.spp;
        let img = acc.image();
        state.mean = img.mean();
        state.noise_rms = acc.noise_rms().unwrap_or(f64::NAN);
        state.noise_relative = state.noise_rms / state.mean;
        let (a, b) = acc.halves();
        let committed = a
            .write_exr(&even_next)
            .and_then(|()| b.write_exr(&odd_next))
            .and_then(|()| {
                commit_halves(
                    &mut state,
                    &json_path,
                    [(&even_next, &even_path), (&odd_next, &odd_path)],
                )
            });
        if let Err(e) = committed {
            if !state.pending {
                // Uncommitted halves (a full disk, a failed write): leave none behind.
                for next in [&even_next, &odd_next] {
                    let _ = std::fs::remove_file(next);
                }
            }
            return Err(e);
        }
        img.write_exr(&opts.out)?;
        img.write_png(&sibling(&opts.out, "png"), opts.exposure)?;
    }
    let img = acc.image();
    state.spp = acc.spp;
    state.mean = img.mean();
    state.noise_rms = acc.noise_rms().unwrap_or(f64::NAN);
    state.noise_relative = state.noise_rms / state.mean;
    Ok((state, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkpoint of a black image (mean 0: the relative noise undefined) is written with
    /// `null` and reads back, so that it resumes.
    #[test]
    fn an_undefined_noise_round_trips_through_the_checkpoint() {
        let state = ReferenceState {
            scene: "s.toml".into(),
            camera: "auto".into(),
            width: 4,
            height: 4,
            spp: 2,
            max_depth: 3,
            seed: 1,
            diffuse: false,
            noise_rms: 0.0,
            noise_relative: f64::NAN,
            mean: 0.0,
            seconds: 0.5,
            pending: false,
            scene_hash: "0123456789abcdef".into(),
        };
        let json = serde_json::to_string(&state).expect("json");
        assert!(json.contains("\"noise_relative\":null"), "{json}");
        let back: ReferenceState = serde_json::from_str(&json).expect("reads back");
        assert!(back.noise_relative.is_nan());
        assert_eq!((back.noise_rms, back.mean, back.spp), (0.0, 0.0, 2));
    }
}
