//! A scene as a Mitsuba 3 scene folder that Mitsuba renders as it is (`lustre export scene SCENE
//! --to mitsuba --out DIR`): `DIR/scene.xml`, the meshes in `DIR/meshes/` and the textures and
//! environment map in `DIR/textures/`.
//!
//! - **Meshes**: one Wavefront OBJ per scene mesh, in world space (`v`, `vn` where the mesh has
//!   normals, `vt` = (u, 1 − v) where it has UVs, as Mitsuba's and lustre's OBJ readers flip v
//!   back), a `<shape type="obj">` each (`face_normals` where the mesh has no normals), with an
//!   `area` emitter where the mesh emits.
//! - **Materials**: lustre's kinds are Mitsuba's plugins (the reader's names and parameters), so
//!   `diffuse`, `plastic`, `roughplastic`, `conductor`, `roughconductor`, `dielectric`,
//!   `roughdielectric` and `thindielectric` are written as they are, inside `twosided` and
//!   `mask` where the material says; glTF metallic-roughness as `principled`; a lustre
//!   specification (a fit, a measured file) as what the caller fits to it.
//! - **Textures**: an image file the scene read (JPEG, PNG) with a unit factor is copied as it
//!   is; any other (a factor times a texture, one channel of a texture, a float image) is written
//!   as a linear RGB EXR (`raw`) holding the parameter's values, since Mitsuba 3 multiplies no
//!   texture by a constant.
//! - **Environment**: an equirect map as `envmap` (the file copied, or written as EXR; lustre's
//!   equirect convention turned into Mitsuba's by the transform, as the reader turns it back);
//!   the built-in sky as a 1024×512 EXR map; a constant as `constant`.
//! - **Cameras**: one `perspective` sensor per camera (`lookat`, `fov`, `fov_axis`), the first
//!   the one `mi.render` uses; `hdrfilm` at the scene's film size with a box filter (lustre's),
//!   an `independent` sampler and the `path` integrator, their settings as `<default>`s
//!   (`spp`, `max_depth`, `resx`, `resy`) that `mitsuba -D` overrides.

use crate::camera::{Camera, FovAxis};
use crate::environment::{Environment, EnvironmentSource};
use crate::error::{Result, SceneError};
use crate::material::{Material, MaterialKind, TextureRef, TexturedRgb, TexturedScalar};
use crate::scene_file::write_atomic;
use crate::texture::ColorSpace;
use crate::Scene;
use glam::{DMat3, DVec3};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

/// What [`write_mitsuba_scene`] wrote.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MitsubaExport {
    /// Shapes (one OBJ file each).
    pub meshes: usize,
    /// Triangles.
    pub triangles: usize,
    /// BSDFs.
    pub materials: usize,
    /// Texture files (the environment map included).
    pub textures: usize,
    /// Area emitters.
    pub emitters: usize,
    /// Sensors.
    pub cameras: usize,
    /// Bytes of every file written.
    pub bytes: usize,
    /// What Mitsuba's plugins cannot say exactly, per material.
    pub approximations: Vec<String>,
}

/// A lustre material specification's BSDF for Mitsuba, from the caller (a fit): `(the <bsdf>
/// element with the given id, what it approximates)`; `None` when it has none.
pub type SpecBsdf<'a> = dyn Fn(&Material, &str, &Path) -> Option<(String, String)> + 'a;

/// Render settings written as the XML's `<default>`s.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MitsubaSettings {
    /// Samples per pixel.
    pub spp: u32,
    /// The path integrator's `max_depth` (lustre reference's `--max-depth`).
    pub max_depth: u32,
}

/// `s` escaped for an XML attribute value.
fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
        .replace('\'', "&apos;")
}

/// Three numbers as Mitsuba's `value="a, b, c"` (shortest round-trip decimals).
fn triple(v: [f64; 3]) -> String {
    format!("{}, {}, {}", v[0], v[1], v[2])
}

/// A name as a file name: letters, digits, `-`, `_`, `.` kept, the rest `_`.
fn file_name(s: &str) -> String {
    let f: String = s
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "-_.".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    f.chars().take(64).collect()
}

/// A texture file to write or copy; its contents keyed so that a texture shared by materials is
/// written once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum TexKey {
    /// The file as it is.
    Copy(usize),
    /// Factor × texture (RGB), the factor's bits.
    Scaled(usize, [u64; 3]),
    /// Factor × one channel, as grey RGB.
    Channel(usize, u8, u64),
}

struct Writer<'a> {
    scene: &'a Scene,
    dir: &'a Path,
    files: HashMap<TexKey, String>,
    out: MitsubaExport,
}

impl Writer<'_> {
    fn write(&mut self, rel: &str, bytes: &[u8]) -> Result<()> {
        write_atomic(&self.dir.join(rel), bytes)?;
        self.out.bytes += bytes.len();
        Ok(())
    }

    /// An EXR of RGB texels in `textures/NAME.exr`; its relative path.
    fn exr(&mut self, name: &str, w: u32, h: u32, texels: Vec<f32>) -> Result<String> {
        let rel = format!("textures/{name}.exr");
        let path = self.dir.join(&rel);
        let img = image::Rgb32FImage::from_raw(w, h, texels)
            .ok_or_else(|| SceneError::format(&path, "texel count does not match the size"))?;
        let mut bytes = std::io::Cursor::new(Vec::new());
        img.write_to(&mut bytes, image::ImageFormat::OpenExr)
            .map_err(|e| SceneError::format(&path, format!("not encoded: {e}")))?;
        self.write(&rel, &bytes.into_inner())?;
        self.out.textures += 1;
        Ok(rel)
    }

    /// The file holding `key`'s texels (written once); its path relative to the folder and
    /// whether it holds linear values (`raw`).
    fn texture_file(&mut self, key: TexKey) -> Result<(String, bool)> {
        let (t, raw) = match key {
            TexKey::Copy(t) => (t, self.scene.textures[t].color_space == ColorSpace::Linear),
            TexKey::Scaled(t, _) | TexKey::Channel(t, _, _) => (t, true),
        };
        if let Some(f) = self.files.get(&key) {
            return Ok((f.clone(), raw));
        }
        let tex = &self.scene.textures[t];
        let stem = tex
            .source
            .file_stem()
            .map(|s| file_name(&s.to_string_lossy()))
            .unwrap_or_default();
        let n = self.files.len();
        let ch = usize::from(tex.channels);
        let colour = |texel: &[f32]| -> [f32; 3] {
            match ch {
                1 | 2 => [texel[0]; 3],
                _ => [texel[0], texel[1], texel[2]],
            }
        };
        let rel = match key {
            TexKey::Copy(_) => {
                let ext = tex
                    .source
                    .extension()
                    .map(|e| e.to_string_lossy().to_ascii_lowercase())
                    .unwrap_or_default();
                let rel = format!("textures/{n:03}_{stem}.{ext}");
                let bytes = std::fs::read(&tex.source)
                    .map_err(|e| SceneError::format(&tex.source, format!("not read: {e}")))?;
                self.write(&rel, &bytes)?;
                self.out.textures += 1;
                rel
            }
            TexKey::Scaled(_, bits) => {
                let f = bits.map(f64::from_bits);
                let data = tex
                    .data
                    .chunks(ch)
                    .flat_map(|texel| {
                        let c = colour(texel);
                        [0, 1, 2].map(|i| (f64::from(c[i]) * f[i]) as f32)
                    })
                    .collect();
                self.exr(&format!("{n:03}_{stem}"), tex.width, tex.height, data)?
            }
            TexKey::Channel(_, c, bits) => {
                let f = f64::from_bits(bits);
                let c = usize::from(c).min(ch - 1);
                let data = tex
                    .data
                    .chunks(ch)
                    .flat_map(|texel| [(f64::from(texel[c]) * f) as f32; 3])
                    .collect();
                self.exr(&format!("{n:03}_{stem}_ch{c}"), tex.width, tex.height, data)?
            }
        };
        self.files.insert(key, rel.clone());
        Ok((rel, raw))
    }

    fn bitmap(&mut self, name: &str, key: TexKey, uv: TextureRef, owner: &str) -> Result<String> {
        let (file, raw) = self.texture_file(key)?;
        if uv.uv_set != 0 {
            self.out.approximations.push(format!(
                "{owner}: {name} is textured through the second UV set; Mitsuba's OBJ meshes \
                 carry the first only"
            ));
        }
        Ok(format!(
            "<texture type=\"bitmap\" name=\"{name}\"><string name=\"filename\" value=\"{}\"/>\
             <boolean name=\"raw\" value=\"{raw}\"/></texture>",
            esc(&file)
        ))
    }

    fn rgb(&mut self, name: &str, v: &TexturedRgb, owner: &str) -> Result<String> {
        match v.texture {
            None => Ok(format!(
                "<rgb name=\"{name}\" value=\"{}\"/>",
                triple(v.factor.0)
            )),
            Some(t) => {
                let ext = self.scene.textures[t.texture]
                    .source
                    .extension()
                    .map(|e| e.to_string_lossy().to_ascii_lowercase());
                let file = matches!(ext.as_deref(), Some("jpg" | "jpeg" | "png"))
                    && self.scene.textures[t.texture].source.is_file();
                let key = if v.factor.0 == [1.0; 3] && file {
                    TexKey::Copy(t.texture)
                } else {
                    TexKey::Scaled(t.texture, v.factor.0.map(f64::to_bits))
                };
                self.bitmap(name, key, t, owner)
            }
        }
    }

    fn scalar(&mut self, name: &str, v: &TexturedScalar, owner: &str) -> Result<String> {
        match v.texture {
            None => Ok(format!("<float name=\"{name}\" value=\"{}\"/>", v.factor)),
            Some(t) => self.bitmap(
                name,
                TexKey::Channel(t.texture, v.channel, v.factor.to_bits()),
                t,
                owner,
            ),
        }
    }

    /// Mitsuba's roughplastic takes a constant α: a textured one as its mean over the texture.
    fn constant_alpha(&mut self, alpha: &TexturedScalar, owner: &str) -> String {
        let a = match alpha.texture {
            None => alpha.factor,
            Some(t) => {
                let tex = &self.scene.textures[t.texture];
                let ch = usize::from(tex.channels);
                let c = usize::from(alpha.channel).min(ch - 1);
                let n = (tex.data.len() / ch).max(1);
                let mean = tex.data.chunks(ch).map(|x| f64::from(x[c])).sum::<f64>() / n as f64;
                let a = alpha.factor * mean;
                self.out.approximations.push(format!(
                    "{owner}: roughplastic's alpha texture as its mean {a} (Mitsuba 3's \
                     roughplastic takes a constant alpha)"
                ));
                a
            }
        };
        format!("<float name=\"alpha\" value=\"{a}\"/>")
    }

    /// The `<bsdf>` of material `m` (id `id`).
    fn bsdf(&mut self, m: &Material, id: &str, spec: &SpecBsdf) -> Result<String> {
        let o = &m.name;
        let dist = |d: &crate::material::MicrofacetType| {
            format!("<string name=\"distribution\" value=\"{}\"/>", d.name())
        };
        let ior = |k: &str, v: f64| format!("<float name=\"{k}\" value=\"{v}\"/>");
        let col =
            |k: &str, v: lustre_brdf::Rgb| format!("<rgb name=\"{k}\" value=\"{}\"/>", triple(v.0));
        let transmissive = matches!(
            m.kind,
            MaterialKind::Dielectric { .. }
                | MaterialKind::RoughDielectric { .. }
                | MaterialKind::ThinDielectric { .. }
        );
        let body = match &m.kind {
            MaterialKind::Diffuse { reflectance } => format!(
                "<bsdf type=\"diffuse\">{}</bsdf>",
                self.rgb("reflectance", reflectance, o)?
            ),
            MaterialKind::Plastic { diffuse, specular, int_ior, ext_ior, nonlinear } => format!(
                "<bsdf type=\"plastic\">{}{}{}{}<boolean name=\"nonlinear\" value=\"{nonlinear}\"/></bsdf>",
                self.rgb("diffuse_reflectance", diffuse, o)?,
                col("specular_reflectance", *specular),
                ior("int_ior", *int_ior),
                ior("ext_ior", *ext_ior),
            ),
            MaterialKind::RoughPlastic { diffuse, specular, alpha, distribution, int_ior, ext_ior, nonlinear } => format!(
                "<bsdf type=\"roughplastic\">{}{}{}{}{}{}<boolean name=\"nonlinear\" value=\"{nonlinear}\"/></bsdf>",
                self.rgb("diffuse_reflectance", diffuse, o)?,
                col("specular_reflectance", *specular),
                self.constant_alpha(alpha, o),
                dist(distribution),
                ior("int_ior", *int_ior),
                ior("ext_ior", *ext_ior),
            ),
            MaterialKind::Conductor { eta, k, specular } => format!(
                "<bsdf type=\"conductor\">{}{}{}</bsdf>",
                col("eta", *eta),
                col("k", *k),
                self.rgb("specular_reflectance", specular, o)?
            ),
            MaterialKind::RoughConductor { eta, k, specular, alpha_u, alpha_v, distribution } => format!(
                "<bsdf type=\"roughconductor\">{}{}{}{}{}{}</bsdf>",
                col("eta", *eta),
                col("k", *k),
                self.rgb("specular_reflectance", specular, o)?,
                self.scalar("alpha_u", alpha_u, o)?,
                self.scalar("alpha_v", alpha_v, o)?,
                dist(distribution),
            ),
            MaterialKind::Dielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance }
            | MaterialKind::ThinDielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance } => format!(
                "<bsdf type=\"{}\">{}{}{}{}</bsdf>",
                m.kind.name(),
                ior("int_ior", *int_ior),
                ior("ext_ior", *ext_ior),
                col("specular_reflectance", *specular_reflectance),
                col("specular_transmittance", *specular_transmittance),
            ),
            MaterialKind::RoughDielectric { int_ior, ext_ior, alpha, distribution, specular_reflectance, specular_transmittance } => format!(
                "<bsdf type=\"roughdielectric\">{}{}{}{}{}{}</bsdf>",
                ior("int_ior", *int_ior),
                ior("ext_ior", *ext_ior),
                self.scalar("alpha", alpha, o)?,
                dist(distribution),
                col("specular_reflectance", *specular_reflectance),
                col("specular_transmittance", *specular_transmittance),
            ),
            MaterialKind::PbrMetallicRoughness { base_color, metallic, roughness, transmission, ior: eta, anisotropy, layers, .. } => {
                let mut note = String::from(
                    "glTF metallic-roughness as Mitsuba's principled (Disney's model: its own \
                     diffuse and Fresnel terms",
                );
                if *anisotropy > 0.0 {
                    note.push_str("; anisotropy as Disney's, its rotation dropped");
                }
                if layers.has_specular() {
                    note.push_str("; KHR_materials_specular dropped (F0 from the ior)");
                }
                let mut extra = String::new();
                if layers.has_clearcoat() {
                    note.push_str("; the clear coat as Disney's (gloss = 1 − roughness)");
                    extra += &format!(
                        "<float name=\"clearcoat\" value=\"{}\"/><float name=\"clearcoat_gloss\" value=\"{}\"/>",
                        layers.clearcoat,
                        1.0 - layers.clearcoat_roughness
                    );
                }
                if layers.has_sheen() {
                    note.push_str("; the sheen as Disney's (weight = its colour's largest channel, untinted)");
                    extra += &format!(
                        "<float name=\"sheen\" value=\"{}\"/>",
                        layers.sheen_color.max_component()
                    );
                }
                note.push(')');
                self.out.approximations.push(format!("{o} (pbr): {note}"));
                format!(
                    "<bsdf type=\"principled\">{}{}{}{}{}<float name=\"anisotropic\" value=\"{anisotropy}\"/>{extra}</bsdf>",
                    self.rgb("base_color", base_color, o)?,
                    self.scalar("metallic", metallic, o)?,
                    self.scalar("roughness", roughness, o)?,
                    self.scalar("spec_trans", transmission, o)?,
                    ior("eta", *eta),
                )
            }
            MaterialKind::Spec(s) => match spec(m, id, self.dir) {
                Some((xml, note)) => {
                    self.out.approximations.push(format!("{o} ({}): {note}", s.spec));
                    // The caller's element carries the id; wrappers below take it instead.
                    xml.replacen(&format!(" id=\"{}\"", esc(id)), "", 1)
                }
                None => {
                    return Err(SceneError::material(
                        o,
                        format!("{}: no Mitsuba BSDF for this specification", s.spec),
                    ))
                }
            },
        };
        let mut xml = body;
        if m.two_sided && !transmissive {
            xml = format!("<bsdf type=\"twosided\">{xml}</bsdf>");
        }
        if let Some(n) = &m.normal_map {
            let t = n.texture.texture;
            let key = if self.scene.textures[t].source.is_file() {
                TexKey::Copy(t)
            } else {
                TexKey::Scaled(t, [1f64.to_bits(); 3])
            };
            let tex = self.bitmap("normalmap", key, n.texture, o)?;
            self.out.approximations.push(format!(
                "{o}: normal map as Mitsuba's normalmap (its own tangent frame; scale {} dropped)",
                n.scale
            ));
            xml = format!("<bsdf type=\"normalmap\">{tex}{xml}</bsdf>");
        }
        if let Some(a) = &m.alpha_mask {
            if a.cutoff.is_some() {
                self.out.approximations.push(format!(
                    "{o}: glTF's alpha cut-off as Mitsuba's mask (stochastic: opacity as a \
                     probability)"
                ));
            }
            xml = format!(
                "<bsdf type=\"mask\">{}{xml}</bsdf>",
                self.scalar("opacity", &a.opacity, o)?
            );
        }
        // The outermost element takes the id.
        let at = xml.find('>').unwrap_or(0);
        let xml = format!("{} id=\"{}\"{}", &xml[..at], esc(id), &xml[at..]);
        self.out.materials += 1;
        Ok(xml)
    }

    /// The OBJ text of mesh `i`.
    fn obj(&self, i: usize) -> String {
        let m = &self.scene.meshes[i];
        let mut s = String::with_capacity(m.positions.len() * 80);
        let _ = writeln!(s, "# lustre export: mesh {:?}, world space", m.name);
        for p in &m.positions {
            let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
        }
        if let Some(n) = &m.normals {
            for n in n {
                let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
            }
        }
        if let Some(uv) = &m.uv0 {
            for t in uv {
                let _ = writeln!(s, "vt {} {}", t.x, 1.0 - t.y);
            }
        }
        let (n, t) = (m.normals.is_some(), m.uv0.is_some());
        for tri in &m.indices {
            s.push('f');
            for &v in tri {
                let v = v + 1;
                let _ = match (t, n) {
                    (true, true) => write!(s, " {v}/{v}/{v}"),
                    (true, false) => write!(s, " {v}/{v}"),
                    (false, true) => write!(s, " {v}//{v}"),
                    (false, false) => write!(s, " {v}"),
                };
            }
            s.push('\n');
        }
        s
    }

    /// The environment's `<emitter>`.
    fn environment(&mut self, e: &Environment) -> Result<String> {
        // lustre's to_local = R_y(π)·M⁻¹ for Mitsuba's to_world M (the reader's conversion).
        let to_world = |e: &Environment| -> String {
            let m = e.to_local.inverse() * DMat3::from_rotation_y(std::f64::consts::PI);
            let r = |i: usize| m.row(i);
            let (a, b, c) = (r(0), r(1), r(2));
            format!(
                "<transform name=\"to_world\"><matrix value=\"{} {} {} 0 {} {} {} 0 {} {} {} 0 0 0 0 1\"/></transform>",
                a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z
            )
        };
        let file = match &e.source {
            EnvironmentSource::Constant(c) => {
                return Ok(format!(
                    "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"{}\"/></emitter>",
                    triple((*c * e.intensity).0)
                ))
            }
            EnvironmentSource::Map { path, map } => {
                let ext = path
                    .extension()
                    .map(|x| x.to_string_lossy().to_ascii_lowercase());
                match ext.as_deref() {
                    Some(x @ ("hdr" | "exr")) if path.is_file() => {
                        let rel = format!("textures/environment.{x}");
                        let bytes = std::fs::read(path)
                            .map_err(|err| SceneError::format(path, format!("not read: {err}")))?;
                        self.write(&rel, &bytes)?;
                        self.out.textures += 1;
                        rel
                    }
                    _ => {
                        let data = map.data.iter().flatten().copied().collect();
                        self.exr("environment", map.width as u32, map.height as u32, data)?
                    }
                }
            }
            EnvironmentSource::Sky(sky) => {
                let (w, h) = (1024, 512);
                let data = (0..h)
                    .flat_map(|j| (0..w).map(move |i| (i, j)))
                    .flat_map(|(i, j)| {
                        let d = lustre_env::EquirectMap::pixel_dir(w, h, i, j);
                        sky.radiance(d).0.map(|x| x as f32)
                    })
                    .collect();
                self.exr("sky", w as u32, h as u32, data)?
            }
        };
        Ok(format!(
            "<emitter type=\"envmap\"><string name=\"filename\" value=\"{}\"/><float name=\"scale\" value=\"{}\"/>{}</emitter>",
            esc(&file),
            e.intensity,
            to_world(e)
        ))
    }
}

fn sensor(c: &Camera) -> String {
    let axis = match c.fov_axis {
        FovAxis::X => "x",
        FovAxis::Y => "y",
        FovAxis::Diagonal => "diagonal",
        FovAxis::Smaller => "smaller",
        FovAxis::Larger => "larger",
    };
    let p = c.position;
    let t = p + c.forward;
    let id = format!(" id=\"{}\"", esc(&c.name));
    let v = |v: DVec3| format!("{}, {}, {}", v.x, v.y, v.z);
    format!(
        "  <sensor type=\"perspective\"{id}>\n    <string name=\"fov_axis\" value=\"{axis}\"/>\n    \
         <float name=\"fov\" value=\"{}\"/>\n    <transform name=\"to_world\"><lookat origin=\"{}\" \
         target=\"{}\" up=\"{}\"/></transform>\n    <sampler type=\"independent\"><integer \
         name=\"sample_count\" value=\"$spp\"/></sampler>\n    <film type=\"hdrfilm\"><integer \
         name=\"width\" value=\"$resx\"/><integer name=\"height\" value=\"$resy\"/><rfilter \
         type=\"box\"/></film>\n  </sensor>\n",
        c.fov_deg,
        v(p),
        v(t),
        v(c.up)
    )
}

/// Writes `scene` as a Mitsuba 3 scene folder `dir` (created; files in it replaced atomically,
/// `scene.xml` last). `spec` gives the BSDF of a lustre material specification.
pub fn write_mitsuba_scene(
    scene: &Scene,
    dir: &Path,
    settings: MitsubaSettings,
    spec: &SpecBsdf,
) -> Result<MitsubaExport> {
    for sub in ["meshes", "textures"] {
        std::fs::create_dir_all(dir.join(sub))
            .map_err(|e| SceneError::format(dir.join(sub), format!("not created: {e}")))?;
    }
    let mut w = Writer {
        scene,
        dir,
        files: HashMap::new(),
        out: MitsubaExport::default(),
    };
    let mut xml = String::new();
    let _ = writeln!(xml, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(
        xml,
        "<!-- written by lustre export from {} -->",
        esc(&scene.source.display().to_string()).replace("--", "- -")
    );
    let _ = writeln!(xml, "<scene version=\"3.0.0\">");
    let _ = writeln!(
        xml,
        "  <default name=\"spp\" value=\"{}\"/>\n  <default name=\"max_depth\" value=\"{}\"/>\n  \
         <default name=\"resx\" value=\"{}\"/>\n  <default name=\"resy\" value=\"{}\"/>",
        settings.spp, settings.max_depth, scene.film.width, scene.film.height
    );
    let _ = writeln!(
        xml,
        "  <integrator type=\"path\"><integer name=\"max_depth\" value=\"$max_depth\"/></integrator>"
    );
    for c in &scene.cameras {
        xml.push_str(&sensor(c));
    }
    w.out.cameras = scene.cameras.len();
    // Material ids: the names, made unique.
    let mut ids: Vec<String> = Vec::with_capacity(scene.materials.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let id = if ids.contains(&m.name) || m.name.is_empty() {
            format!("{}@{i}", m.name)
        } else {
            m.name.clone()
        };
        ids.push(id);
    }
    let used: std::collections::BTreeSet<usize> = scene.meshes.iter().map(|m| m.material).collect();
    for &i in &used {
        let b = w.bsdf(&scene.materials[i], &ids[i], spec)?;
        let _ = writeln!(xml, "  {b}");
    }
    let mut names: std::collections::HashSet<String> = std::collections::HashSet::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        let id = if names.contains(&m.name) || m.name.is_empty() {
            format!("{}@{i}", m.name)
        } else {
            m.name.clone()
        };
        names.insert(id.clone());
        let rel = format!("meshes/{i:03}_{}.obj", file_name(&m.name));
        let obj = w.obj(i);
        w.write(&rel, obj.as_bytes())?;
        let mut shape = format!(
            "  <shape type=\"obj\" id=\"{}\"><string name=\"filename\" value=\"{}\"/>",
            esc(&id),
            esc(&rel)
        );
        if m.normals.is_none() {
            shape.push_str("<boolean name=\"face_normals\" value=\"true\"/>");
        }
        let _ = write!(shape, "<ref id=\"{}\"/>", esc(&ids[m.material]));
        if let Some(e) = m.emission {
            let radiance = match scene.materials[m.material].emission_texture {
                Some(t) => w.bitmap(
                    "radiance",
                    TexKey::Scaled(t.texture, e.0.map(f64::to_bits)),
                    t,
                    &m.name,
                )?,
                None => format!("<rgb name=\"radiance\" value=\"{}\"/>", triple(e.0)),
            };
            let _ = write!(shape, "<emitter type=\"area\">{radiance}</emitter>");
            w.out.emitters += 1;
        }
        shape.push_str("</shape>\n");
        xml.push_str(&shape);
        w.out.meshes += 1;
        w.out.triangles += m.indices.len();
    }
    if let Some(e) = &scene.environment {
        let env = w.environment(e)?;
        let _ = writeln!(xml, "  {env}");
    }
    xml.push_str("</scene>\n");
    w.write("scene.xml", xml.as_bytes())?;
    Ok(w.out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::{AlphaMask, MicrofacetType, ResolvedSpec};
    use crate::texture::Texture;
    use crate::{Mesh, Vec2, Vec3};
    use lustre_brdf::Rgb;

    /// One mesh per material of every kind Mitsuba's plugins hold, textured and masked ones
    /// among them.
    fn scene() -> Scene {
        let mut s = Scene::new("test.toml");
        let texels: Vec<f32> = (0..4 * 4 * 3)
            .map(|i| 0.05 + (i % 7) as f32 * 0.1)
            .collect();
        s.textures
            .push(Texture::new("memory.png", 4, 4, 3, ColorSpace::Srgb, texels).expect("texture"));
        let tex = Some(TextureRef {
            texture: 0,
            uv_set: 0,
        });
        let k = |r: f64| Rgb([r, r * 0.8, r * 0.6]);
        let scaled = TexturedRgb {
            factor: k(0.5),
            texture: tex,
        };
        let alpha = TexturedScalar {
            factor: 0.4,
            texture: tex,
            channel: 1,
        };
        let c = TexturedScalar::constant;
        let kinds = vec![
            MaterialKind::Diffuse {
                reflectance: scaled,
            },
            MaterialKind::Plastic {
                diffuse: TexturedRgb::constant(k(0.4)),
                specular: k(1.0),
                int_ior: 1.49,
                ext_ior: 1.000277,
                nonlinear: true,
            },
            MaterialKind::RoughPlastic {
                diffuse: scaled,
                specular: k(0.9),
                alpha: c(0.3),
                distribution: MicrofacetType::Beckmann,
                int_ior: 1.5,
                ext_ior: 1.0,
                nonlinear: false,
            },
            MaterialKind::Conductor {
                eta: k(0.2),
                k: k(3.9),
                specular: TexturedRgb::constant(k(1.0)),
            },
            MaterialKind::RoughConductor {
                eta: k(0.2),
                k: k(3.9),
                specular: scaled,
                alpha_u: alpha,
                alpha_v: c(0.2),
                distribution: MicrofacetType::Ggx,
            },
            MaterialKind::Dielectric {
                int_ior: 1.5,
                ext_ior: 1.0,
                specular_reflectance: k(1.0),
                specular_transmittance: k(0.8),
            },
            MaterialKind::RoughDielectric {
                int_ior: 1.33,
                ext_ior: 1.0,
                alpha: c(0.1),
                distribution: MicrofacetType::Ggx,
                specular_reflectance: k(1.0),
                specular_transmittance: k(1.0),
            },
            MaterialKind::ThinDielectric {
                int_ior: 1.52,
                ext_ior: 1.0,
                specular_reflectance: k(0.9),
                specular_transmittance: k(0.7),
            },
        ];
        for (i, kind) in kinds.into_iter().enumerate() {
            let mut m = Material::new(format!("m{i}"), kind);
            m.two_sided = i % 2 == 0 && i < 5;
            if i == 2 {
                m.alpha_mask = Some(AlphaMask {
                    opacity: c(0.75),
                    cutoff: None,
                });
            }
            s.materials.push(m);
            let z = i as f32;
            s.meshes.push(Mesh {
                name: format!("mesh{i}"),
                positions: vec![
                    Vec3::new(0.0, 0.0, z),
                    Vec3::new(1.0, 0.0, z),
                    Vec3::new(0.0, 1.0, z),
                ],
                normals: (i != 3).then(|| vec![Vec3::Z; 3]),
                tangents: None,
                uv0: Some(vec![
                    Vec2::new(0.3, 0.6),
                    Vec2::new(0.9, 0.1),
                    Vec2::new(0.2, 0.2),
                ]),
                uv1: None,
                indices: vec![[0, 1, 2]],
                material: i,
                emission: (i == 1).then_some(Rgb([2.0, 3.0, 4.0])),
                hints: Default::default(),
            });
        }
        s.cameras.push(
            Camera::look_at(
                "main",
                DVec3::new(0.5, 0.5, 12.0),
                DVec3::new(0.5, 0.5, 0.0),
                DVec3::Y,
                45.0,
                FovAxis::Y,
            )
            .expect("camera"),
        );
        s.environment = Some(Environment::constant(Rgb([0.1, 0.2, 0.3])));
        s
    }

    fn temp_dir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!(
            "lustre-mitsuba-{tag}-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos())
        ));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    }

    fn no_spec(_: &Material, _: &str, _: &Path) -> Option<(String, String)> {
        None
    }

    #[test]
    fn every_kind_reads_back_and_evaluates_alike() {
        let s = scene();
        let dir = temp_dir("kinds");
        let settings = MitsubaSettings {
            spp: 64,
            max_depth: 8,
        };
        let out = write_mitsuba_scene(&s, &dir, settings, &no_spec).expect("written");
        assert_eq!(
            (out.meshes, out.materials, out.emitters, out.cameras),
            (8, 8, 1, 1)
        );
        // The scaled texture and the one-channel roughness are written once each.
        assert_eq!(out.textures, 2, "{out:?}");
        let back = Scene::load(&dir.join("scene.xml")).expect("lustre reads it back");
        assert_eq!(back.meshes.len(), 8);
        assert_eq!(back.cameras[0].name, "main");
        assert_eq!(back.film, s.film);
        assert_eq!(back.environment, s.environment);
        let pairs = [
            (DVec3::new(0.3, 0.1, 0.95), DVec3::new(-0.2, 0.4, 0.89)),
            (DVec3::new(0.0, 0.6, 0.8), DVec3::new(0.0, -0.6, 0.8)),
        ];
        for (a, b) in s.meshes.iter().zip(&back.meshes) {
            assert_eq!(a.name, b.name);
            assert_eq!(a.positions, b.positions);
            assert_eq!(a.emission, b.emission);
            let uv = a.uv0.as_ref().expect("uv")[0];
            let buv = b.uv0.as_ref().expect("uv")[0];
            assert!((uv - buv).length() < 1e-6, "{uv} {buv}");
            let (ma, mb) = (&s.materials[a.material], &back.materials[b.material]);
            assert_eq!(ma.kind.name(), mb.kind.name());
            assert_eq!(ma.two_sided, mb.two_sided, "{}", ma.name);
            assert_eq!(
                ma.alpha_mask.is_some(),
                mb.alpha_mask.is_some(),
                "{}",
                ma.name
            );
            let fa = ma.bsdf_at(&s.textures, &[uv, Vec2::ZERO]).expect("bsdf");
            let fb = mb
                .bsdf_at(&back.textures, &[buv, Vec2::ZERO])
                .expect("bsdf");
            for (wi, wo) in pairs {
                let (x, y) = (fa.eval(wi, wo), fb.eval(wi, wo));
                for c in 0..3 {
                    assert!(
                        (x.0[c] - y.0[c]).abs() <= 1e-5 * (1.0 + x.0[c].abs()),
                        "{}: {x:?} vs {y:?}",
                        ma.name
                    );
                }
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn what_mitsuba_cannot_hold_is_named() {
        let mut s = scene();
        s.materials[0].kind = MaterialKind::PbrMetallicRoughness {
            base_color: TexturedRgb::constant(Rgb([0.8, 0.5, 0.2])),
            metallic: TexturedScalar::constant(1.0),
            roughness: TexturedScalar::constant(0.3),
            transmission: TexturedScalar::constant(0.0),
            ior: 1.5,
            anisotropy: 0.5,
            anisotropy_rotation: 0.2,
            layers: Default::default(),
        };
        s.materials[1].kind =
            MaterialKind::Spec(ResolvedSpec::resolve("fit", "sgd:nickel").expect("spec"));
        s.materials[3].normal_map = Some(crate::material::NormalMap {
            texture: TextureRef {
                texture: 0,
                uv_set: 0,
            },
            scale: 1.0,
        });
        if let MaterialKind::RoughPlastic { alpha, .. } = &mut s.materials[2].kind {
            alpha.texture = Some(TextureRef {
                texture: 0,
                uv_set: 0,
            });
        }
        let dir = temp_dir("approx");
        let settings = MitsubaSettings {
            spp: 4,
            max_depth: 4,
        };
        // A specification without a Mitsuba BSDF is refused, naming the material.
        let e = write_mitsuba_scene(&s, &dir, settings, &no_spec).expect_err("no spec BSDF");
        assert!(e.to_string().contains("m1"), "{e}");
        let fitted = |_: &Material, id: &str, _: &Path| {
            Some((
                format!("<bsdf type=\"diffuse\" id=\"{id}\"><rgb name=\"reflectance\" value=\"0.5\"/></bsdf>"),
                "a test fit".to_string(),
            ))
        };
        let out = write_mitsuba_scene(&s, &dir, settings, &fitted).expect("written");
        let xml = std::fs::read_to_string(dir.join("scene.xml")).expect("xml");
        assert!(xml.contains("<bsdf type=\"twosided\" id=\"m0\"><bsdf type=\"principled\">"));
        assert!(xml.contains("<bsdf type=\"diffuse\" id=\"m1\">"), "{xml}");
        let notes = out.approximations.join("\n");
        assert!(notes.contains("m0 (pbr): glTF metallic-roughness as Mitsuba's principled"));
        assert!(notes.contains("anisotropy as Disney's"), "{notes}");
        assert!(notes.contains("m1 (sgd:nickel): a test fit"), "{notes}");
        assert!(
            notes.contains("m2: roughplastic's alpha texture as its mean"),
            "{notes}"
        );
        assert!(
            notes.contains("m3: normal map as Mitsuba's normalmap"),
            "{notes}"
        );
        assert!(
            xml.contains("<bsdf type=\"normalmap\" id=\"m3\"><texture"),
            "{xml}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }
}
