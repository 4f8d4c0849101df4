//! Writing binary glTF (GLB) files: buffer views and accessors, and the container
//! (glTF 2.0 §4.4: a 12-byte header, a JSON chunk padded with spaces and a BIN chunk padded
//! with zeros, each to 4 bytes).

use crate::error::{Result, SceneError};
use serde_json::{json, Value};
use std::path::Path;

/// `bufferView.target` of vertex attributes.
pub const ARRAY_BUFFER: u32 = 34962;
/// `bufferView.target` of indices.
pub const ELEMENT_ARRAY_BUFFER: u32 = 34963;
/// `componentType` f32.
pub const FLOAT: u32 = 5126;
/// `componentType` u32.
pub const UNSIGNED_INT: u32 = 5125;

/// Buffer views and accessors under construction.
#[derive(Default)]
pub struct Builder {
    /// The binary chunk.
    pub bin: Vec<u8>,
    /// `bufferViews`.
    pub views: Vec<Value>,
    /// `accessors`.
    pub accessors: Vec<Value>,
}

impl Builder {
    /// Appends `data` (f32 or u32 words) as a view and an accessor; returns the accessor index.
    pub fn push(
        &mut self,
        words: &[[u8; 4]],
        count: usize,
        kind: &str,
        component: u32,
        target: Option<u32>,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let offset = self.bin.len();
        for w in words {
            self.bin.extend_from_slice(w);
        }
        let mut view = json!({
            "buffer": 0,
            "byteOffset": offset,
            "byteLength": words.len() * 4,
        });
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.views.push(view);
        let mut acc = json!({
            "bufferView": self.views.len() - 1,
            "componentType": component,
            "count": count,
            "type": kind,
        });
        if let Some((lo, hi)) = bounds {
            acc["min"] = json!(lo);
            acc["max"] = json!(hi);
        }
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    /// Appends f32 vectors as a vertex-attribute accessor of `kind` (`VEC3`…), with min/max when
    /// `bounds`.
    pub fn floats<const N: usize>(&mut self, data: &[[f32; N]], kind: &str, bounds: bool) -> usize {
        self.floats_to(data, kind, bounds, Some(ARRAY_BUFFER))
    }

    /// Appends mesh `m`'s own vertex attributes (POSITION with its bounds; NORMAL, TANGENT and
    /// TEXCOORD_0 where it has them): the primitive's `attributes` so far.
    pub fn mesh_attributes(&mut self, m: &crate::Mesh) -> serde_json::Map<String, Value> {
        let mut a = serde_json::Map::new();
        let pos: Vec<[f32; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
        a.insert("POSITION".into(), json!(self.floats(&pos, "VEC3", true)));
        if let Some(n) = &m.normals {
            let n: Vec<[f32; 3]> = n.iter().map(|v| v.to_array()).collect();
            a.insert("NORMAL".into(), json!(self.floats(&n, "VEC3", false)));
        }
        if let Some(t) = &m.tangents {
            let t: Vec<[f32; 4]> = t.iter().map(|v| v.to_array()).collect();
            a.insert("TANGENT".into(), json!(self.floats(&t, "VEC4", false)));
        }
        if let Some(u) = &m.uv0 {
            let u: Vec<[f32; 2]> = u.iter().map(|v| v.to_array()).collect();
            a.insert("TEXCOORD_0".into(), json!(self.floats(&u, "VEC2", false)));
        }
        a
    }

    /// Appends f32 vectors as an animation sampler's accessor (its view has no `target`).
    pub fn animation_floats<const N: usize>(
        &mut self,
        data: &[[f32; N]],
        kind: &str,
        bounds: bool,
    ) -> usize {
        self.floats_to(data, kind, bounds, None)
    }

    fn floats_to<const N: usize>(
        &mut self,
        data: &[[f32; N]],
        kind: &str,
        bounds: bool,
        target: Option<u32>,
    ) -> usize {
        let words: Vec<[u8; 4]> = data.iter().flatten().map(|f| f.to_le_bytes()).collect();
        let b = bounds.then(|| {
            let mut lo = vec![f32::INFINITY; N];
            let mut hi = vec![f32::NEG_INFINITY; N];
            for v in data {
                for k in 0..N {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            (lo, hi)
        });
        self.push(&words, data.len(), kind, FLOAT, target, b)
    }
}

/// The GLB file of the glTF JSON `doc` and the binary chunk `bin` (`buffers` is set from
/// `bin`); `path` names the file in errors (a file over 4 GB).
pub fn glb_bytes(path: &Path, doc: &Value, bin: Vec<u8>) -> Result<Vec<u8>> {
    let fmt = |p: String| SceneError::format(path, p);
    let mut doc = doc.clone();
    if !bin.is_empty() {
        doc["buffers"] = json!([{ "byteLength": bin.len() }]);
    }
    let mut json_bytes = serde_json::to_vec(&doc).map_err(|e| fmt(format!("JSON: {e}")))?;
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    let mut bin = bin;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json_bytes.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = u32::try_from(total).map_err(|_| fmt(format!("{total} bytes exceed a GLB")))?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(json_bytes.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json_bytes);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    Ok(out)
}

impl Builder {
    /// Appends triangle indices as a u32 accessor; returns the accessor index.
    pub fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let words: Vec<[u8; 4]> = tris.iter().flatten().map(|i| i.to_le_bytes()).collect();
        let n = words.len();
        self.push(
            &words,
            n,
            "SCALAR",
            UNSIGNED_INT,
            Some(ELEMENT_ARRAY_BUFFER),
            None,
        )
    }
}
