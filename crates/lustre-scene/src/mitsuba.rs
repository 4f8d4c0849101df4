//! Mitsuba scene XML, versions 0.5 and 3.x: the subset that B. Bitterli's interiors use.
//!
//! - **Shapes**: `obj` (all objects of the file merged into one mesh; `faceNormals` drops the
//!   normals, `flipTexCoords` (default on) is the OBJ v flip, `flipNormals` reverses the
//!   winding), `rectangle`, `disk` (a fan of [`crate::mesh::DISK_SEGMENTS`] triangles), `cube`,
//!   `sphere` (`center`, `radius`; tessellated, see [`crate::mesh::sphere`]), each with `toWorld`.
//! - **BSDFs**: `diffuse`, `plastic`, `roughplastic`, `conductor`, `roughconductor` (named metal
//!   presets from `lustre_brdf`), `dielectric`, `roughdielectric`, `thindielectric`,
//!   `twosided`, `mask`; `bumpmap`/`normalmap` are read through with a warning (the bump is
//!   ignored). Named IORs (`bk7`, `air`, `water`, …) as Mitsuba's table.
//! - **Textures**: `bitmap` (sRGB-decoded unless `raw`/`gamma = 1`).
//! - **Emitters**: `area` (on a shape), `envmap` (`filename`, `scale`, `toWorld`; converted to
//!   lustre's equirect convention, see [`crate::environment`]), `constant`.
//! - **Sensor**: `perspective` (`fov`, `fovAxis`, `toWorld`; `thinlens` read as a pinhole with
//!   a warning), the film's `width`/`height`.
//! - `<default name value>` and `$name` substitution; properties in either spelling (`intIOR` and
//!   `int_ior` are the same property).
//!
//! An unknown plugin or element is an error naming it and its line; a property that is read but
//! not used is a named warning (film and sampler settings of no meaning here pass silently).

use crate::camera::{Camera, FovAxis};
use crate::environment::{Environment, EnvironmentSource};
use crate::error::{read_referenced, Result, SceneError};
use crate::material::{
    AlphaMask, Material, MaterialKind, MicrofacetType, TexturedRgb, TexturedScalar,
};
use crate::mesh::{self, Mesh};
use crate::texture::{srgb_to_linear, ColorSpace};
use crate::{obj, Film, Scene};
use glam::{DMat3, DMat4, DVec3};
use lustre_brdf::Rgb;
use roxmltree::{Document, Node};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Mitsuba's default exterior IOR (air).
const AIR: f64 = 1.000277;

/// Properties that have no meaning for lustre and pass without a warning.
const SILENT: &[&str] = &[
    "filter_type",
    "wrap_mode",
    "banner",
    "high_quality_edges",
    "file_format",
    "pixel_format",
    "component_format",
    "sample_count",
    "max_depth",
    "rr_depth",
    "near_clip",
    "far_clip",
    "shutter_open",
    "shutter_close",
    "sampling_weight",
    "strict_normals",
    "sample_visible",
    "cache",
    "max_anisotropy",
];

/// Mitsuba 0.5's camelCase to 3.x's snake_case: `intIOR` → `int_ior`, `toWorld` → `to_world`.
pub fn normalize_name(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    let mut prev_lower = false;
    for c in name.chars() {
        if c.is_ascii_uppercase() && prev_lower {
            out.push('_');
        }
        prev_lower = c.is_ascii_lowercase() || c.is_ascii_digit();
        out.push(c.to_ascii_lowercase());
    }
    out
}

const PROPERTY_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "srgb",
    "spectrum",
    "color",
    "point",
    "vector",
    "transform",
    "blackbody",
];
const PLUGIN_TAGS: &[&str] = &[
    "bsdf",
    "texture",
    "emitter",
    "film",
    "sampler",
    "rfilter",
    "shape",
    "medium",
    "phase",
    "integrator",
    "sensor",
];

/// One plugin element with its properties, nested plugins and references.
struct Plugin<'a, 'i> {
    tag: String,
    ty: String,
    line: u32,
    props: Vec<(String, Node<'a, 'i>)>,
    children: Vec<Node<'a, 'i>>,
    refs: Vec<Node<'a, 'i>>,
    used: HashSet<String>,
}

struct Reader<'a, 'i> {
    path: &'a Path,
    base: PathBuf,
    doc: &'a Document<'i>,
    defaults: HashMap<String, String>,
    scene: Scene,
    bsdfs: HashMap<String, usize>,
    textures: HashMap<String, Node<'a, 'i>>,
    anonymous: Vec<usize>,
}

/// Reads a Mitsuba scene from XML text; `path` names the file and its folder resolves relative
/// file names.
pub fn from_str(path: &Path, text: &str) -> Result<Scene> {
    let doc = Document::parse(text)
        .map_err(|e| SceneError::format(path, format!("not valid XML: {e}")))?;
    let root = doc.root_element();
    let mut r = Reader {
        path,
        base: path.parent().unwrap_or(Path::new("")).to_path_buf(),
        doc: &doc,
        defaults: HashMap::new(),
        scene: Scene::new(path),
        bsdfs: HashMap::new(),
        textures: HashMap::new(),
        anonymous: Vec::new(),
    };
    if root.tag_name().name() != "scene" {
        return Err(r.err(
            root,
            format!(
                "the root element is <{}>, expected <scene>",
                root.tag_name().name()
            ),
        ));
    }
    match root.attribute("version") {
        Some(v) if ["0.", "2.", "3."].iter().any(|p| v.starts_with(p)) => {}
        Some(v) => return Err(r.err(root, format!("scene version {v:?} is not 0.x, 2.x or 3.x"))),
        None => return Err(r.err(root, "the <scene> element has no version attribute")),
    }
    // Defaults first: they may be used before they appear.
    for c in root
        .children()
        .filter(|c| c.is_element() && c.has_tag_name("default"))
    {
        let name = r.raw_attr(c, "name")?;
        let value = r.raw_attr(c, "value")?;
        r.defaults
            .entry(name.to_string())
            .or_insert(value.to_string());
    }
    for c in root.children().filter(Node::is_element) {
        match c.tag_name().name() {
            "default" => {}
            "integrator" => {
                r.plugin(c)?;
            }
            "sensor" => r.sensor(c)?,
            "bsdf" => {
                let id = r.attr(c, "id")?;
                let m = r.bsdf(c, id.clone())?;
                let idx = r.add_material(m, id.is_none());
                if let Some(id) = id {
                    r.bsdfs.insert(id, idx);
                }
            }
            "texture" => {
                let id = r.attr(c, "id")?.ok_or_else(|| {
                    r.err(
                        c,
                        "a <texture> at the top level needs an id to be referenced",
                    )
                })?;
                r.textures.insert(id, c);
            }
            "shape" => r.shape(c)?,
            "emitter" => r.emitter(c)?,
            "medium" | "phase" => r.warn(
                c,
                "participating media are not supported: ignored".to_string(),
            ),
            "include" => return Err(r.err(c, "<include> is not supported")),
            other => return Err(r.err(c, format!("unknown element <{other}>"))),
        }
    }
    if r.scene.meshes.is_empty() {
        r.scene
            .warnings
            .push(format!("{}: the scene has no shapes", path.display()));
    }
    Ok(r.scene)
}

/// Reads a Mitsuba scene file.
pub fn read(path: &Path) -> Result<Scene> {
    let bytes = lustre_brdf::error::read_input(path).map_err(|e| SceneError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| SceneError::format(path, format!("not UTF-8 text: {e}")))?;
    from_str(path, text)
}

impl<'a, 'i> Reader<'a, 'i> {
    fn line(&self, n: Node) -> u32 {
        self.doc.text_pos_at(n.range().start).row
    }

    fn err(&self, n: Node, problem: impl Into<String>) -> SceneError {
        SceneError::format(
            self.path,
            format!("line {}: {}", self.line(n), problem.into()),
        )
    }

    fn warn(&mut self, n: Node, problem: String) {
        let line = self.line(n);
        self.scene
            .warnings
            .push(format!("{}: line {line}: {problem}", self.path.display()));
    }

    fn raw_attr(&self, n: Node<'a, 'i>, name: &str) -> Result<&'a str> {
        n.attribute(name).ok_or_else(|| {
            self.err(
                n,
                format!("<{}> has no {name} attribute", n.tag_name().name()),
            )
        })
    }

    /// An attribute with `$name` defaults substituted.
    fn attr(&self, n: Node, name: &str) -> Result<Option<String>> {
        let Some(v) = n.attribute(name) else {
            return Ok(None);
        };
        if !v.contains('$') {
            return Ok(Some(v.to_string()));
        }
        let mut out = String::new();
        let mut rest = v;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let tail = &rest[i + 1..];
            let end = tail
                .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .unwrap_or(tail.len());
            let var = &tail[..end];
            let value = self.defaults.get(var).ok_or_else(|| {
                self.err(
                    n,
                    format!("${var} has no value (no <default name=\"{var}\">)"),
                )
            })?;
            out.push_str(value);
            rest = &tail[end..];
        }
        out.push_str(rest);
        Ok(Some(out))
    }

    fn req_attr(&self, n: Node, name: &str) -> Result<String> {
        self.attr(n, name)?.ok_or_else(|| {
            self.err(
                n,
                format!("<{}> has no {name} attribute", n.tag_name().name()),
            )
        })
    }

    fn plugin(&self, n: Node<'a, 'i>) -> Result<Plugin<'a, 'i>> {
        let mut p = Plugin {
            tag: n.tag_name().name().to_string(),
            ty: self.attr(n, "type")?.unwrap_or_default(),
            line: self.line(n),
            props: Vec::new(),
            children: Vec::new(),
            refs: Vec::new(),
            used: HashSet::new(),
        };
        for c in n.children().filter(Node::is_element) {
            let tag = c.tag_name().name();
            let named_texture = tag == "texture" && c.attribute("name").is_some();
            if PROPERTY_TAGS.contains(&tag) || named_texture {
                let name = normalize_name(&self.req_attr(c, "name")?);
                if p.props.iter().any(|(k, _)| *k == name) {
                    return Err(self.err(c, format!("property {name:?} is given twice")));
                }
                p.props.push((name, c));
            } else if tag == "ref" {
                p.refs.push(c);
            } else if PLUGIN_TAGS.contains(&tag) {
                p.children.push(c);
            } else {
                return Err(self.err(c, format!("unknown element <{tag}> in <{}>", p.tag)));
            }
        }
        Ok(p)
    }

    /// Warns about properties of `p` that were never read.
    fn finish(&mut self, p: &Plugin) {
        for (name, node) in &p.props {
            if !p.used.contains(name) && !SILENT.contains(&name.as_str()) {
                let msg = format!("{} {:?}: property {name:?} ignored", p.tag, p.ty);
                self.warn(*node, msg);
            }
        }
    }

    fn numbers(&self, n: Node, text: &str) -> Result<Vec<f64>> {
        text.split(|c: char| c == ',' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| {
                let v: f64 = s
                    .parse()
                    .map_err(|_| self.err(n, format!("{s:?} is not a number")))?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(self.err(n, format!("{s:?} is not a finite number")))
                }
            })
            .collect()
    }

    fn float_node(&self, n: Node) -> Result<f64> {
        let v = self.req_attr(n, "value")?;
        match self.numbers(n, &v)?.as_slice() {
            [x] => Ok(*x),
            _ => Err(self.err(n, format!("{v:?} is not one number"))),
        }
    }

    fn get(&self, p: &mut Plugin<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
        let node = p.props.iter().find(|(k, _)| k == name).map(|(_, n)| *n)?;
        p.used.insert(name.to_string());
        Some(node)
    }

    fn float(&self, p: &mut Plugin<'a, 'i>, name: &str, default: f64) -> Result<f64> {
        match self.get(p, name) {
            None => Ok(default),
            Some(n) if matches!(n.tag_name().name(), "float" | "integer") => self.float_node(n),
            Some(n) => Err(self.err(n, format!("{name} must be a <float>"))),
        }
    }

    fn boolean(&self, p: &mut Plugin<'a, 'i>, name: &str, default: bool) -> Result<bool> {
        match self.get(p, name) {
            None => Ok(default),
            Some(n) => match self.req_attr(n, "value")?.to_ascii_lowercase().as_str() {
                "true" | "1" => Ok(true),
                "false" | "0" => Ok(false),
                v => Err(self.err(n, format!("{name} = {v:?} is not true or false"))),
            },
        }
    }

    fn string(&self, p: &mut Plugin<'a, 'i>, name: &str) -> Result<Option<String>> {
        match self.get(p, name) {
            None => Ok(None),
            Some(n) => self.req_attr(n, "value").map(Some),
        }
    }

    /// A colour property node (`rgb`, `srgb`, `spectrum`, `color`, `float`) as linear RGB.
    fn color_node(&mut self, n: Node) -> Result<Rgb> {
        let tag = n.tag_name().name();
        if tag == "spectrum" && n.attribute("filename").is_some() {
            return Err(self.err(n, "spectrum files are not supported"));
        }
        if tag == "blackbody" {
            return Err(self.err(n, "blackbody spectra are not supported"));
        }
        let v = self.req_attr(n, "value")?;
        let t = v.trim();
        if let Some(hex) = t.strip_prefix('#') {
            let bad = || self.err(n, format!("{v:?} is not a #rrggbb colour"));
            if hex.len() != 6 || !hex.is_ascii() {
                return Err(bad());
            }
            let ch = |i: usize| -> Result<f64> {
                u8::from_str_radix(&hex[i..i + 2], 16)
                    .map(|b| f64::from(srgb_to_linear(f32::from(b) / 255.0)))
                    .map_err(|_| bad())
            };
            return Ok(Rgb::new(ch(0)?, ch(2)?, ch(4)?));
        }
        let c = if tag == "spectrum" && t.contains(':') {
            let mut vals = Vec::new();
            for pair in t.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                let (_, val) = pair
                    .split_once(':')
                    .ok_or_else(|| self.err(n, format!("{pair:?} is not wavelength:value")))?;
                vals.extend(self.numbers(n, val)?);
            }
            if vals.is_empty() {
                return Err(self.err(n, "empty spectrum"));
            }
            let mean = vals.iter().sum::<f64>() / vals.len() as f64;
            self.warn(
                n,
                format!("sampled spectrum {v:?} reduced to its mean {mean}"),
            );
            Rgb::splat(mean)
        } else {
            match self.numbers(n, t)?.as_slice() {
                [g] => Rgb::splat(*g),
                [r, g, b] => Rgb::new(*r, *g, *b),
                _ => return Err(self.err(n, format!("{v:?} is not 1 or 3 numbers"))),
            }
        };
        Ok(if tag == "srgb" {
            c.map(|x| f64::from(srgb_to_linear(x as f32)))
        } else {
            c
        })
    }

    fn color(&mut self, p: &mut Plugin<'a, 'i>, name: &str, default: Rgb) -> Result<Rgb> {
        match self.get(p, name) {
            None => Ok(default),
            Some(n) if n.tag_name().name() == "texture" => {
                Err(self.err(n, format!("{name} cannot be a texture here")))
            }
            Some(n) => self.color_node(n),
        }
    }

    /// A texture-or-colour property. `ref` children with `name` count too.
    fn textured_rgb(
        &mut self,
        p: &mut Plugin<'a, 'i>,
        name: &str,
        default: Rgb,
    ) -> Result<TexturedRgb> {
        match self.texture_prop(p, name)? {
            Some(Ok(t)) => Ok(TexturedRgb::texture(t)),
            Some(Err(n)) => Ok(TexturedRgb::constant(self.color_node(n)?)),
            None => Ok(TexturedRgb::constant(default)),
        }
    }

    fn textured_scalar(
        &mut self,
        p: &mut Plugin<'a, 'i>,
        name: &str,
        default: f64,
    ) -> Result<TexturedScalar> {
        match self.texture_prop(p, name)? {
            Some(Ok(t)) => Ok(TexturedScalar {
                factor: 1.0,
                texture: Some(t),
                channel: 0,
            }),
            Some(Err(n)) if matches!(n.tag_name().name(), "float" | "integer") => {
                Ok(TexturedScalar::constant(self.float_node(n)?))
            }
            Some(Err(n)) => {
                let c = self.color_node(n)?;
                Ok(TexturedScalar::constant(c.mean()))
            }
            None => Ok(TexturedScalar::constant(default)),
        }
    }

    /// `Some(Ok(texture))` for a texture (inline or by reference), `Some(Err(node))` for a plain
    /// value node, `None` when absent.
    #[allow(clippy::type_complexity)]
    fn texture_prop(
        &mut self,
        p: &mut Plugin<'a, 'i>,
        name: &str,
    ) -> Result<Option<std::result::Result<crate::TextureRef, Node<'a, 'i>>>> {
        if let Some(n) = self.get(p, name) {
            if n.tag_name().name() == "texture" {
                return self.bitmap(n).map(|t| Some(Ok(t)));
            }
            return Ok(Some(Err(n)));
        }
        let mut found = None;
        for r in &p.refs {
            if self
                .attr(*r, "name")?
                .map(|s| normalize_name(&s))
                .as_deref()
                == Some(name)
            {
                found = Some(*r);
            }
        }
        let Some(r) = found else {
            return Ok(None);
        };
        p.refs.retain(|x| *x != r);
        let id = self.req_attr(r, "id")?;
        let tex = *self
            .textures
            .get(&id)
            .ok_or_else(|| self.err(r, format!("no texture with id {id:?}")))?;
        self.bitmap(tex).map(|t| Some(Ok(t)))
    }

    fn bitmap(&mut self, n: Node<'a, 'i>) -> Result<crate::TextureRef> {
        let mut p = self.plugin(n)?;
        if p.ty != "bitmap" {
            return Err(self.unknown(&p));
        }
        let file = self
            .string(&mut p, "filename")?
            .ok_or_else(|| self.err(n, "bitmap texture without a filename"))?;
        let raw = self.boolean(&mut p, "raw", false)?;
        let gamma = self.float(&mut p, "gamma", -1.0)?;
        for (key, default) in [
            ("uscale", 1.0),
            ("vscale", 1.0),
            ("uoffset", 0.0),
            ("voffset", 0.0),
        ] {
            let v = self.float(&mut p, key, default)?;
            if v != default {
                self.warn(
                    n,
                    format!("bitmap {key} = {v} ignored (UVs used as they are)"),
                );
            }
        }
        let cs = if raw || gamma == 1.0 {
            ColorSpace::Linear
        } else {
            ColorSpace::Srgb
        };
        let full = self.base.join(&file);
        let t = self.scene.texture(self.path, &full, cs)?;
        self.finish(&p);
        Ok(t)
    }

    fn unknown(&self, p: &Plugin) -> SceneError {
        SceneError::UnknownPlugin {
            path: self.path.to_path_buf(),
            line: p.line,
            kind: p.tag.clone(),
            name: p.ty.clone(),
        }
    }

    fn ior(&self, p: &mut Plugin<'a, 'i>, name: &str, default: f64) -> Result<f64> {
        let Some(n) = self.get(p, name) else {
            return Ok(default);
        };
        let v = if n.tag_name().name() == "string" {
            let s = self.req_attr(n, "value")?;
            lustre_brdf::models::dielectric::ior_preset(s.trim())
                .ok_or_else(|| self.err(n, format!("unknown IOR name {s:?}")))?
        } else {
            self.float_node(n)?
        };
        if !(v > 0.0 && v.is_finite()) {
            return Err(self.err(n, format!("{name} = {v} must be positive")));
        }
        Ok(v)
    }

    fn distribution(&mut self, p: &mut Plugin<'a, 'i>) -> Result<MicrofacetType> {
        let Some(n) = self.get(p, "distribution") else {
            return Ok(MicrofacetType::Beckmann);
        };
        let v = self.req_attr(n, "value")?;
        match v.to_ascii_lowercase().as_str() {
            "beckmann" => Ok(MicrofacetType::Beckmann),
            "ggx" => Ok(MicrofacetType::Ggx),
            "phong" | "as" => {
                self.warn(n, format!("distribution {v:?} read as beckmann"));
                Ok(MicrofacetType::Beckmann)
            }
            _ => Err(self.err(n, format!("unknown microfacet distribution {v:?}"))),
        }
    }

    /// Reads `alpha`, or `alpha_u`/`alpha_v`; returns (αu, αv).
    fn alphas(&mut self, p: &mut Plugin<'a, 'i>) -> Result<(TexturedScalar, TexturedScalar)> {
        let alpha = self.textured_scalar(p, "alpha", 0.1)?;
        let has_uv = p
            .props
            .iter()
            .any(|(k, _)| k == "alpha_u" || k == "alpha_v");
        if has_uv {
            let u = self.textured_scalar(p, "alpha_u", 0.1)?;
            let v = self.textured_scalar(p, "alpha_v", 0.1)?;
            return Ok((u, v));
        }
        Ok((alpha, alpha))
    }

    fn nested_bsdf(&mut self, p: &mut Plugin<'a, 'i>, name: Option<String>) -> Result<Material> {
        let line = p.line;
        let mut inner: Vec<Material> = Vec::new();
        for c in p.children.clone() {
            match c.tag_name().name() {
                "bsdf" => inner.push(self.bsdf(c, name.clone())?),
                "texture" => {} // a bumpmap's height texture
                other => return Err(self.err(c, format!("<{other}> inside a <bsdf>"))),
            }
        }
        for r in p.refs.clone() {
            if r.attribute("name").is_none() {
                let id = self.req_attr(r, "id")?;
                let idx = *self
                    .bsdfs
                    .get(&id)
                    .ok_or_else(|| self.err(r, format!("no bsdf with id {id:?}")))?;
                inner.push(self.scene.materials[idx].clone());
            }
        }
        let mut it = inner.into_iter();
        let first = it.next().ok_or_else(|| {
            SceneError::format(
                self.path,
                format!("line {line}: {} {:?} needs a nested bsdf", p.tag, p.ty),
            )
        })?;
        if it.next().is_some() {
            let msg = format!("{} {:?}: only the first nested bsdf is used", p.tag, p.ty);
            self.scene
                .warnings
                .push(format!("{}: line {line}: {msg}", self.path.display()));
        }
        Ok(first)
    }

    fn bsdf(&mut self, n: Node<'a, 'i>, name: Option<String>) -> Result<Material> {
        if n.ancestors().filter(|a| a.has_tag_name("bsdf")).count() > 16 {
            return Err(self.err(n, "bsdfs nested more than 16 deep"));
        }
        let mut p = self.plugin(n)?;
        let own = self.attr(n, "id")?;
        let name = name
            .or(own)
            .unwrap_or_else(|| format!("{}@{}", p.ty, p.line));
        let kind = match p.ty.as_str() {
            "twosided" => {
                let mut m = self.nested_bsdf(&mut p, Some(name))?;
                m.two_sided = true;
                self.finish(&p);
                return Ok(m);
            }
            "mask" => {
                let opacity = self.textured_scalar(&mut p, "opacity", 0.5)?;
                let mut m = self.nested_bsdf(&mut p, Some(name))?;
                m.alpha_mask = Some(AlphaMask {
                    opacity,
                    cutoff: None,
                });
                self.finish(&p);
                return Ok(m);
            }
            "bumpmap" | "normalmap" => {
                self.warn(
                    n,
                    format!("{} ignored: the nested bsdf is used without it", p.ty),
                );
                p.used.extend(p.props.iter().map(|(k, _)| k.clone()));
                let m = self.nested_bsdf(&mut p, Some(name))?;
                return Ok(m);
            }
            "diffuse" => MaterialKind::Diffuse {
                reflectance: self.textured_rgb(&mut p, "reflectance", Rgb::splat(0.5))?,
            },
            "plastic" | "roughplastic" => {
                let diffuse = self.textured_rgb(&mut p, "diffuse_reflectance", Rgb::splat(0.5))?;
                let specular = self.color(&mut p, "specular_reflectance", Rgb::ONE)?;
                let int_ior = self.ior(&mut p, "int_ior", 1.49)?;
                let ext_ior = self.ior(&mut p, "ext_ior", AIR)?;
                let nonlinear = self.boolean(&mut p, "nonlinear", false)?;
                if p.ty == "plastic" {
                    MaterialKind::Plastic {
                        diffuse,
                        specular,
                        int_ior,
                        ext_ior,
                        nonlinear,
                    }
                } else {
                    let distribution = self.distribution(&mut p)?;
                    let alpha = self.textured_scalar(&mut p, "alpha", 0.1)?;
                    MaterialKind::RoughPlastic {
                        diffuse,
                        specular,
                        alpha,
                        distribution,
                        int_ior,
                        ext_ior,
                        nonlinear,
                    }
                }
            }
            "conductor" | "roughconductor" => {
                let specular = self.textured_rgb(&mut p, "specular_reflectance", Rgb::ONE)?;
                let ext_eta = self.ior(&mut p, "ext_eta", AIR)?;
                let has_eta = p.props.iter().any(|(k, _)| k == "eta" || k == "k");
                let material = self.string(&mut p, "material")?;
                let (eta, k) = if has_eta {
                    if material.is_some() {
                        self.warn(n, "material preset ignored: eta and k are given".into());
                    }
                    (
                        self.color(&mut p, "eta", Rgb::splat(0.0))?,
                        self.color(&mut p, "k", Rgb::splat(1.0))?,
                    )
                } else {
                    let m = material.unwrap_or_else(|| "Cu".to_string());
                    lustre_brdf::models::conductor_presets::conductor_preset(&m).ok_or_else(
                        || {
                            SceneError::format(
                                self.path,
                                format!("line {}: unknown conductor material {m:?}", p.line),
                            )
                        },
                    )?
                };
                let (eta, k) = (eta / ext_eta, k / ext_eta);
                if p.ty == "conductor" {
                    MaterialKind::Conductor { eta, k, specular }
                } else {
                    let distribution = self.distribution(&mut p)?;
                    let (alpha_u, alpha_v) = self.alphas(&mut p)?;
                    MaterialKind::RoughConductor {
                        eta,
                        k,
                        specular,
                        alpha_u,
                        alpha_v,
                        distribution,
                    }
                }
            }
            "dielectric" | "roughdielectric" | "thindielectric" => {
                let int_ior = self.ior(&mut p, "int_ior", 1.5046)?;
                let ext_ior = self.ior(&mut p, "ext_ior", AIR)?;
                let specular_reflectance = self.color(&mut p, "specular_reflectance", Rgb::ONE)?;
                let specular_transmittance =
                    self.color(&mut p, "specular_transmittance", Rgb::ONE)?;
                match p.ty.as_str() {
                    "dielectric" => MaterialKind::Dielectric {
                        int_ior,
                        ext_ior,
                        specular_reflectance,
                        specular_transmittance,
                    },
                    "thindielectric" => MaterialKind::ThinDielectric {
                        int_ior,
                        ext_ior,
                        specular_reflectance,
                        specular_transmittance,
                    },
                    _ => {
                        let distribution = self.distribution(&mut p)?;
                        let (au, av) = self.alphas(&mut p)?;
                        let alpha = if au == av {
                            au
                        } else {
                            self.warn(n, "anisotropic roughdielectric read with alpha_u".into());
                            au
                        };
                        MaterialKind::RoughDielectric {
                            int_ior,
                            ext_ior,
                            alpha,
                            distribution,
                            specular_reflectance,
                            specular_transmittance,
                        }
                    }
                }
            }
            _ => return Err(self.unknown(&p)),
        };
        if let Some(c) = p.children.first() {
            return Err(self.err(
                *c,
                format!(
                    "unexpected <{}> inside a {} bsdf",
                    c.tag_name().name(),
                    p.ty
                ),
            ));
        }
        self.finish(&p);
        Ok(Material::new(name, kind))
    }

    /// Adds a material; anonymous ones equal to an earlier anonymous one are shared.
    fn add_material(&mut self, m: Material, anonymous: bool) -> usize {
        if anonymous {
            for &i in &self.anonymous {
                let mut other = self.scene.materials[i].clone();
                other.name = m.name.clone();
                if other == m {
                    return i;
                }
            }
        }
        self.scene.materials.push(m);
        let i = self.scene.materials.len() - 1;
        if anonymous {
            self.anonymous.push(i);
        }
        i
    }

    fn transform_node(&self, n: Node) -> Result<DMat4> {
        if n.tag_name().name() != "transform" {
            return Err(self.err(n, "expected a <transform>"));
        }
        let mut m = DMat4::IDENTITY;
        for c in n.children().filter(Node::is_element) {
            let vec_attrs = |default: f64| -> Result<DVec3> {
                if let Some(v) = self.attr(c, "value")? {
                    return match self.numbers(c, &v)?.as_slice() {
                        [s] => Ok(DVec3::splat(*s)),
                        [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
                        _ => Err(self.err(c, format!("{v:?} is not 1 or 3 numbers"))),
                    };
                }
                let get = |k: &str| -> Result<f64> {
                    match self.attr(c, k)? {
                        None => Ok(default),
                        Some(s) => match self.numbers(c, &s)?.as_slice() {
                            [x] => Ok(*x),
                            _ => Err(self.err(c, format!("{k} = {s:?} is not a number"))),
                        },
                    }
                };
                Ok(DVec3::new(get("x")?, get("y")?, get("z")?))
            };
            let point = |name: &str| -> Result<DVec3> {
                let s = self.req_attr(c, name)?;
                match self.numbers(c, &s)?.as_slice() {
                    [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
                    _ => Err(self.err(c, format!("{name} = {s:?} is not 3 numbers"))),
                }
            };
            let t = match c.tag_name().name() {
                "translate" => DMat4::from_translation(vec_attrs(0.0)?),
                "scale" => DMat4::from_scale(vec_attrs(1.0)?),
                "rotate" => {
                    let axis = vec_attrs(0.0)?;
                    let angle = match self.attr(c, "angle")? {
                        Some(a) => match self.numbers(c, &a)?.as_slice() {
                            [x] => *x,
                            _ => return Err(self.err(c, "angle is not a number")),
                        },
                        None => 0.0,
                    };
                    let axis = axis
                        .try_normalize()
                        .ok_or_else(|| self.err(c, "rotation axis is zero"))?;
                    DMat4::from_axis_angle(axis, angle.to_radians())
                }
                "matrix" => {
                    let v = self.req_attr(c, "value")?;
                    match self.numbers(c, &v)?.as_slice() {
                        a if a.len() == 16 => {
                            let mut arr = [0.0; 16];
                            arr.copy_from_slice(a);
                            DMat4::from_cols_array(&arr).transpose()
                        }
                        a if a.len() == 9 => {
                            let mut arr = [0.0; 9];
                            arr.copy_from_slice(a);
                            DMat4::from_mat3(DMat3::from_cols_array(&arr).transpose())
                        }
                        a => {
                            return Err(
                                self.err(c, format!("matrix has {} numbers (16 or 9)", a.len()))
                            )
                        }
                    }
                }
                "lookat" => {
                    let origin = point("origin")?;
                    let target = point("target")?;
                    let up = match self.attr(c, "up")? {
                        Some(_) => point("up")?,
                        None => DVec3::Y,
                    };
                    let dir = (target - origin)
                        .try_normalize()
                        .ok_or_else(|| self.err(c, "lookat origin equals target"))?;
                    let left = up.cross(dir).try_normalize().ok_or_else(|| {
                        self.err(c, "lookat up is parallel to the view direction")
                    })?;
                    let new_up = dir.cross(left);
                    DMat4::from_cols(
                        left.extend(0.0),
                        new_up.extend(0.0),
                        dir.extend(0.0),
                        origin.extend(1.0),
                    )
                }
                other => return Err(self.err(c, format!("unknown transform element <{other}>"))),
            };
            m = t * m;
        }
        if !m.is_finite() {
            return Err(self.err(n, "the transform is not finite"));
        }
        Ok(m)
    }

    fn transform(&self, p: &mut Plugin<'a, 'i>, name: &str) -> Result<Option<DMat4>> {
        match self.get(p, name) {
            None => Ok(None),
            Some(n) => self.transform_node(n).map(Some),
        }
    }

    fn shape(&mut self, n: Node<'a, 'i>) -> Result<()> {
        let mut p = self.plugin(n)?;
        let to_world = self
            .transform(&mut p, "to_world")?
            .unwrap_or(DMat4::IDENTITY);
        let flip_normals = self.boolean(&mut p, "flip_normals", false)?;
        let id = self.attr(n, "id")?;
        // Material: a nested bsdf or a reference; Mitsuba's default is diffuse 0.5.
        let mut material = None;
        let mut emission = None;
        for c in p.children.clone() {
            match c.tag_name().name() {
                "bsdf" => {
                    let cid = self.attr(c, "id")?;
                    let m = self.bsdf(c, cid.clone())?;
                    let idx = self.add_material(m, cid.is_none());
                    if let Some(cid) = cid {
                        self.bsdfs.insert(cid, idx);
                    }
                    material = Some(idx);
                }
                "emitter" => {
                    let mut e = self.plugin(c)?;
                    if e.ty != "area" {
                        return Err(self.unknown(&e));
                    }
                    let radiance = self.color(&mut e, "radiance", Rgb::ONE)?;
                    if !radiance.is_finite() || radiance.min_component() < 0.0 {
                        return Err(self.err(c, "area emitter radiance must be finite and ≥ 0"));
                    }
                    self.finish(&e);
                    emission = Some(radiance);
                }
                "medium" => self.warn(c, "participating media are not supported: ignored".into()),
                other => return Err(self.err(c, format!("<{other}> inside a <shape>"))),
            }
        }
        for r in p.refs.clone() {
            let id = self.req_attr(r, "id")?;
            match self.bsdfs.get(&id) {
                Some(&i) => material = Some(i),
                None => return Err(self.err(r, format!("no bsdf with id {id:?}"))),
            }
        }
        let material = match material {
            Some(m) => m,
            None => self.add_material(Material::diffuse("diffuse-default", Rgb::splat(0.5)), true),
        };
        let line = p.line;
        let default_name = move |ty: &str| format!("{ty}@{line}");
        let (mut mesh, mesh_path) = match p.ty.as_str() {
            "obj" => {
                let file = self
                    .string(&mut p, "filename")?
                    .ok_or_else(|| self.err(n, "obj shape without a filename"))?;
                let full = self.base.join(&file);
                let bytes = read_referenced(self.path, &full)?;
                let (models, _) = obj::parse(&full, &bytes, false)?;
                let name = id.clone().unwrap_or_else(|| {
                    Path::new(&file)
                        .file_stem()
                        .map_or_else(|| default_name("obj"), |s| s.to_string_lossy().into_owned())
                });
                let mut merged = Mesh::new(name.clone(), Vec::new(), Vec::new(), material);
                let mut normals = Some(Vec::new());
                let mut uvs = Some(Vec::new());
                for model in &models {
                    let m = obj::to_mesh(&full, model, material)?;
                    let off = merged.positions.len() as u32;
                    merged
                        .indices
                        .extend(m.indices.iter().map(|t| t.map(|i| i + off)));
                    let count = m.positions.len();
                    merged.positions.extend(m.positions);
                    match (&mut normals, m.normals) {
                        (Some(acc), Some(v)) => acc.extend(v),
                        _ => normals = None,
                    }
                    match (&mut uvs, m.uv0) {
                        (Some(acc), Some(v)) => acc.extend(v),
                        (Some(_), None) if count == 0 => {}
                        _ => uvs = None,
                    }
                }
                if self.boolean(&mut p, "face_normals", false)? {
                    normals = None;
                }
                if !self.boolean(&mut p, "flip_tex_coords", true)? {
                    if let Some(uv) = &mut uvs {
                        for t in uv.iter_mut() {
                            t.y = 1.0 - t.y;
                        }
                    }
                }
                merged.normals = normals.filter(|v| !v.is_empty());
                merged.uv0 = uvs.filter(|v| !v.is_empty());
                (merged, full)
            }
            "rectangle" => (
                mesh::rectangle(
                    &id.clone().unwrap_or_else(|| default_name("rectangle")),
                    material,
                ),
                self.path.to_path_buf(),
            ),
            "disk" => (
                mesh::disk(
                    &id.clone().unwrap_or_else(|| default_name("disk")),
                    material,
                ),
                self.path.to_path_buf(),
            ),
            "cube" => (
                mesh::cube(
                    &id.clone().unwrap_or_else(|| default_name("cube")),
                    material,
                ),
                self.path.to_path_buf(),
            ),
            "sphere" => {
                let center = match self.get(&mut p, "center") {
                    None => DVec3::ZERO,
                    Some(c) => self.vector_node(c)?,
                };
                let radius = self.float(&mut p, "radius", 1.0)?;
                if radius.is_nan() || radius <= 0.0 {
                    return Err(self.err(n, format!("sphere radius {radius} must be positive")));
                }
                let name = id.clone().unwrap_or_else(|| default_name("sphere"));
                (
                    mesh::sphere(&name, center.as_vec3(), radius as f32, material),
                    self.path.to_path_buf(),
                )
            }
            _ => return Err(self.unknown(&p)),
        };
        mesh.transform(&to_world);
        if flip_normals {
            for t in &mut mesh.indices {
                t.swap(1, 2);
            }
            if let Some(normals) = &mut mesh.normals {
                for v in normals.iter_mut() {
                    *v = -*v;
                }
            }
        }
        mesh.emission = emission;
        self.finish(&p);
        self.scene.push_mesh(&mesh_path, mesh)
    }

    fn vector_node(&self, n: Node) -> Result<DVec3> {
        if let Some(v) = self.attr(n, "value")? {
            return match self.numbers(n, &v)?.as_slice() {
                [x, y, z] => Ok(DVec3::new(*x, *y, *z)),
                _ => Err(self.err(n, format!("{v:?} is not 3 numbers"))),
            };
        }
        let get = |k: &str| -> Result<f64> {
            match self.attr(n, k)? {
                None => Ok(0.0),
                Some(s) => match self.numbers(n, &s)?.as_slice() {
                    [x] => Ok(*x),
                    _ => Err(self.err(n, format!("{k} = {s:?} is not a number"))),
                },
            }
        };
        Ok(DVec3::new(get("x")?, get("y")?, get("z")?))
    }

    fn emitter(&mut self, n: Node<'a, 'i>) -> Result<()> {
        let mut p = self.plugin(n)?;
        let env = match p.ty.as_str() {
            "envmap" => {
                let file = self
                    .string(&mut p, "filename")?
                    .ok_or_else(|| self.err(n, "envmap without a filename"))?;
                let full = self.base.join(&file);
                if !full.exists() {
                    return Err(SceneError::MissingFile {
                        path: self.path.to_path_buf(),
                        referenced: full,
                    });
                }
                let loaded = lustre_env::read_map(&full)?;
                self.scene.warnings.extend(loaded.sanitized_warning(&full));
                let scale = self.float(&mut p, "scale", 1.0)?;
                if scale.is_nan() || scale < 0.0 {
                    return Err(self.err(n, format!("envmap scale {scale} must be ≥ 0")));
                }
                let to_world = self
                    .transform(&mut p, "to_world")?
                    .unwrap_or(DMat4::IDENTITY);
                let m3 = DMat3::from_mat4(to_world);
                if m3.determinant().abs() < 1e-12 {
                    return Err(self.err(n, "envmap transform is singular"));
                }
                // Mitsuba reads u = atan2(v.x, −v.z)/2π; lustre half a turn further.
                let to_local = DMat3::from_rotation_y(std::f64::consts::PI) * m3.inverse();
                Environment {
                    source: EnvironmentSource::Map {
                        path: full,
                        map: Arc::new(loaded.map),
                    },
                    to_local,
                    intensity: scale,
                }
            }
            "constant" => {
                let radiance = self.color(&mut p, "radiance", Rgb::ONE)?;
                if !radiance.is_finite() || radiance.min_component() < 0.0 {
                    return Err(self.err(n, "constant emitter radiance must be finite and ≥ 0"));
                }
                Environment::constant(radiance)
            }
            "area" => return Err(self.err(n, "an area emitter must be inside a <shape>")),
            _ => return Err(self.unknown(&p)),
        };
        if self.scene.environment.is_some() {
            self.warn(n, "a second environment emitter replaces the first".into());
        }
        self.scene.environment = Some(env);
        self.finish(&p);
        Ok(())
    }

    fn sensor(&mut self, n: Node<'a, 'i>) -> Result<()> {
        let mut p = self.plugin(n)?;
        match p.ty.as_str() {
            "perspective" => {}
            "thinlens" => {
                self.warn(
                    n,
                    "thinlens sensor read as a pinhole (no depth of field)".into(),
                );
                for k in ["aperture_radius", "focus_distance"] {
                    p.used.insert(k.to_string());
                }
            }
            _ => return Err(self.unknown(&p)),
        }
        let fov = match self.get(&mut p, "fov") {
            Some(f) => self.float_node(f)?,
            None => {
                let focal = self
                    .string(&mut p, "focal_length")?
                    .unwrap_or_else(|| "50mm".into());
                let mm: f64 = focal
                    .trim()
                    .trim_end_matches("mm")
                    .parse()
                    .map_err(|_| self.err(n, format!("focal length {focal:?} is not NNmm")))?;
                2.0 * (18.0 / mm).atan().to_degrees()
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.err(n, format!("fov {fov} must lie in (0, 180) degrees")));
        }
        let fov_axis = match self.string(&mut p, "fov_axis")?.as_deref() {
            None | Some("x") => FovAxis::X,
            Some("y") => FovAxis::Y,
            Some("diagonal") => FovAxis::Diagonal,
            Some("smaller") => FovAxis::Smaller,
            Some("larger") => FovAxis::Larger,
            Some(other) => return Err(self.err(n, format!("unknown fovAxis {other:?}"))),
        };
        let m = self
            .transform(&mut p, "to_world")?
            .unwrap_or(DMat4::IDENTITY);
        let position = m.transform_point3(DVec3::ZERO);
        let forward = m.transform_vector3(DVec3::Z);
        let up = m.transform_vector3(DVec3::Y);
        let left = m.transform_vector3(DVec3::X);
        if left.dot(up.cross(forward)) < 0.0 {
            self.warn(
                n,
                "the camera transform mirrors the image; lustre renders it unmirrored".into(),
            );
        }
        let name = self.attr(n, "id")?.unwrap_or_else(|| {
            if self.scene.cameras.is_empty() {
                "default".into()
            } else {
                format!("sensor@{}", p.line)
            }
        });
        let camera = Camera::look_at(name, position, position + forward, up, fov, fov_axis)
            .ok_or_else(|| self.err(n, "the sensor transform is degenerate"))?;
        for c in p.children.clone() {
            match c.tag_name().name() {
                "film" => {
                    let mut f = self.plugin(c)?;
                    let w = self.float(&mut f, "width", 768.0)?;
                    let h = self.float(&mut f, "height", 576.0)?;
                    let ok = |v: f64| (1.0..=65536.0).contains(&v) && v.fract() == 0.0;
                    if !ok(w) || !ok(h) {
                        return Err(
                            self.err(c, format!("film size {w}×{h} is not 1..=65536 pixels"))
                        );
                    }
                    for k in [
                        "crop_offset_x",
                        "crop_offset_y",
                        "crop_width",
                        "crop_height",
                    ] {
                        if self.get(&mut f, k).is_some() {
                            self.warn(c, format!("film {k} ignored"));
                        }
                    }
                    self.scene.film = Film {
                        width: w as u32,
                        height: h as u32,
                    };
                    self.finish(&f);
                }
                "sampler" | "rfilter" => {}
                other => return Err(self.err(c, format!("<{other}> inside a <sensor>"))),
            }
        }
        self.scene.cameras.push(camera);
        self.finish(&p);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::normalize_name;

    #[test]
    fn spellings() {
        for (a, b) in [
            ("intIOR", "int_ior"),
            ("toWorld", "to_world"),
            ("alphaU", "alpha_u"),
            ("diffuseReflectance", "diffuse_reflectance"),
            ("fov_axis", "fov_axis"),
            ("flipTexCoords", "flip_tex_coords"),
            ("alpha", "alpha"),
        ] {
            assert_eq!(normalize_name(a), b);
        }
    }
}
