//! Neural BRDFs (Sztrajman et al. 2021, "Neural BRDF Representation and Importance Sampling";
//! weights from asztr/Neural-BRDF) in the `nbrdf-mlp-v1` JSON format, and the synthesis of full
//! MERL tables from them.
//!
//! # File format
//! A JSON object with `format` = `"nbrdf-mlp-v1"`, descriptive strings `network`, `input`,
//! `output` (and optionally `dataset`, `source`), and `materials`: name → `{w1, b1, w2, b2, w3,
//! b3}` with shapes 6×21, 21, 21×21, 21, 21×3, 3, where `w_k[i][j]` maps input i to output j.
//!
//! # Network (as the file's `network` and `input` strings state)
//! x = (hx, hy, hz, dx, dy, dz) with the half vector at φh = 0, h = (sin θh, 0, cos θh), and the
//! Rusinkiewicz difference vector d = (sin θd cos φd, sin θd sin φd, cos θd);
//! a1 = relu(x·w1 + b1), a2 = relu(a1·w2 + b2), f = max(exp(a2·w3 + b3) − 1, 0).
//! The output is the RGB f_r in 1/sr, MERL channel scales already applied.
//!
//! Evaluation is in f64 with fixed-size arrays on the stack (no allocation): the weights are
//! f32-trained, but f64 makes the synthesized table and any independent re-evaluation agree to
//! rounding (~1e-15), which the round-trip tests rely on; cost is ~630 multiply-adds and 3
//! `exp` per evaluation. To keep every output finite, weights are validated finite with
//! |w| ≤ 1e6 (so no sum can overflow) and the last pre-activation is capped at 700 before `exp`.

use crate::bsdf::{cosine_pdf, cosine_sample, Bsdf, BsdfFlags, BsdfSample, LobeFlags};
use crate::error::{Error, Result};
use crate::measured::merl::{bin_node_with, fill_bins, merl_angles, BinConvention, MerlTable};
use crate::rgb::Rgb;
use glam::DVec3;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The format string this reader accepts.
pub const FORMAT: &str = "nbrdf-mlp-v1";
/// Hidden layer width.
pub const HIDDEN: usize = 21;
/// Largest accepted weight magnitude.
pub const MAX_WEIGHT: f64 = 1e6;

/// One material's 6-21-21-3 MLP.
#[derive(Clone, Debug)]
pub struct Nbrdf {
    name: String,
    w1: [[f64; HIDDEN]; 6],
    b1: [f64; HIDDEN],
    w2: [[f64; HIDDEN]; HIDDEN],
    b2: [f64; HIDDEN],
    w3: [[f64; 3]; HIDDEN],
    b3: [f64; 3],
}

/// All materials of one `nbrdf-mlp-v1` file, by name (sorted).
#[derive(Clone, Debug)]
pub struct NbrdfSet {
    path: PathBuf,
    dataset: String,
    network: String,
    input: String,
    materials: BTreeMap<String, Nbrdf>,
}

/// Reads a `rows × N` matrix (or, with `rows == 0`, a vector of N) from `v`, checking shape,
/// numbers and magnitudes; `what` names the material and key in messages.
fn matrix<const N: usize>(
    v: Option<&Value>,
    rows: usize,
    what: &str,
) -> std::result::Result<Vec<[f64; N]>, String> {
    let v = v.ok_or_else(|| format!("{what} is missing"))?;
    let row = |r: &Value, label: &str| -> std::result::Result<[f64; N], String> {
        let a = r
            .as_array()
            .ok_or_else(|| format!("{label} is not an array"))?;
        if a.len() != N {
            return Err(format!("{label} has {} entries, expected {N}", a.len()));
        }
        let mut out = [0.0; N];
        for (j, (o, x)) in out.iter_mut().zip(a).enumerate() {
            let x = x
                .as_f64()
                .ok_or_else(|| format!("{label}[{j}] is not a number"))?;
            if !x.is_finite() || x.abs() > MAX_WEIGHT {
                return Err(format!(
                    "{label}[{j}] = {x:e} is not finite or exceeds {MAX_WEIGHT:e} in magnitude"
                ));
            }
            *o = x;
        }
        Ok(out)
    };
    if rows == 0 {
        return Ok(vec![row(v, what)?]);
    }
    let a = v
        .as_array()
        .ok_or_else(|| format!("{what} is not an array"))?;
    if a.len() != rows {
        return Err(format!(
            "{what} has {} rows, expected {rows} (shape {rows}x{N})",
            a.len()
        ));
    }
    a.iter()
        .enumerate()
        .map(|(i, r)| row(r, &format!("{what}[{i}]")))
        .collect()
}

impl Nbrdf {
    /// Builds a network from one material's JSON object; the error text names the problem.
    fn from_json(name: &str, m: &Value) -> std::result::Result<Self, String> {
        if !m.is_object() {
            return Err(format!("material '{name}' is not an object"));
        }
        let what = |k: &str| format!("material '{name}': {k}");
        let mut net = Nbrdf {
            name: name.to_string(),
            w1: [[0.0; HIDDEN]; 6],
            b1: [0.0; HIDDEN],
            w2: [[0.0; HIDDEN]; HIDDEN],
            b2: [0.0; HIDDEN],
            w3: [[0.0; 3]; HIDDEN],
            b3: [0.0; 3],
        };
        net.w1
            .copy_from_slice(&matrix::<HIDDEN>(m.get("w1"), 6, &what("w1"))?);
        net.b1 = matrix::<HIDDEN>(m.get("b1"), 0, &what("b1"))?[0];
        net.w2
            .copy_from_slice(&matrix::<HIDDEN>(m.get("w2"), HIDDEN, &what("w2"))?);
        net.b2 = matrix::<HIDDEN>(m.get("b2"), 0, &what("b2"))?[0];
        net.w3
            .copy_from_slice(&matrix::<3>(m.get("w3"), HIDDEN, &what("w3"))?);
        net.b3 = matrix::<3>(m.get("b3"), 0, &what("b3"))?[0];
        Ok(net)
    }

    /// The material name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The network's parameters in one flat list: w1 (6 rows of HIDDEN), b1, w2 (HIDDEN rows
    /// of HIDDEN), b2, w3 (HIDDEN rows of 3), b3 — the layout the GPU reads
    /// (`lustre_gpu::material::measured::pack_nbrdf`).
    pub fn parameters(&self) -> Vec<f64> {
        let mut out =
            Vec::with_capacity(6 * HIDDEN + HIDDEN + HIDDEN * HIDDEN + HIDDEN + 3 * HIDDEN + 3);
        self.w1.iter().for_each(|r| out.extend_from_slice(r));
        out.extend_from_slice(&self.b1);
        self.w2.iter().for_each(|r| out.extend_from_slice(r));
        out.extend_from_slice(&self.b2);
        self.w3.iter().for_each(|r| out.extend_from_slice(r));
        out.extend_from_slice(&self.b3);
        out
    }

    /// The network input (hx, hy, hz, dx, dy, dz) for half/difference angles, with φh = 0.
    #[inline]
    pub fn input(theta_h: f64, theta_d: f64, phi_d: f64) -> [f64; 6] {
        let (sh, ch) = theta_h.sin_cos();
        let (sd, cd) = theta_d.sin_cos();
        let (sp, cp) = phi_d.sin_cos();
        [sh, 0.0, ch, sd * cp, sd * sp, cd]
    }

    /// The network on a raw input vector: RGB f_r (1/sr), finite and ≥ 0.
    #[inline]
    pub fn forward(&self, x: &[f64; 6]) -> [f64; 3] {
        let mut a1 = self.b1;
        for (xi, w) in x.iter().zip(&self.w1) {
            for (a, wij) in a1.iter_mut().zip(w) {
                *a += xi * wij;
            }
        }
        let mut a2 = self.b2;
        for (&h, w) in a1.iter().zip(&self.w2) {
            let h = h.max(0.0);
            for (a, wij) in a2.iter_mut().zip(w) {
                *a += h * wij;
            }
        }
        let mut z = self.b3;
        for (&h, w) in a2.iter().zip(&self.w3) {
            let h = h.max(0.0);
            for (a, wij) in z.iter_mut().zip(w) {
                *a += h * wij;
            }
        }
        z.map(|v| (v.min(700.0).exp() - 1.0).max(0.0))
    }

    /// f_r (1/sr) at exactly the given half/difference angles (no folding of φd).
    #[inline]
    pub fn eval_angles(&self, theta_h: f64, theta_d: f64, phi_d: f64) -> Rgb {
        Rgb(self.forward(&Self::input(theta_h, theta_d, phi_d)))
    }
}

impl Bsdf for Nbrdf {
    fn name(&self) -> String {
        format!("NBRDF {}", self.name)
    }

    /// The network at the pair's Rusinkiewicz angles with φd folded into [0, π), which makes the
    /// evaluation exactly reciprocal; 0 unless both directions lie above the surface.
    fn eval(&self, wi: DVec3, wo: DVec3) -> Rgb {
        merl_angles(wi, wo).map_or(Rgb::ZERO, |hd| {
            self.eval_angles(hd.theta_h, hd.theta_d, hd.phi_d)
        })
    }

    /// Cosine-weighted hemisphere sampling; fails when `wo` is below the surface.
    fn sample(&self, wo: DVec3, u1: f64, u2: f64) -> Option<BsdfSample> {
        cosine_sample(self, wo, u1, u2, LobeFlags::GLOSSY)
    }

    fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        cosine_pdf(wi, wo)
    }

    /// Reciprocal (by the φd fold) and isotropic; a fitted network promises no energy bound.
    fn flags(&self) -> BsdfFlags {
        BsdfFlags::isotropic_reflection(true, false)
    }

    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
}

impl NbrdfSet {
    /// Reads an `nbrdf-mlp-v1` JSON file.
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = crate::error::read_file(path)?;
        Self::parse(path, &bytes)
    }

    /// Parses the bytes of an `nbrdf-mlp-v1` JSON file (`path` is used in messages); validates
    /// the format string and every material's shapes and values. Never panics.
    pub fn parse(path: impl AsRef<Path>, bytes: &[u8]) -> Result<Self> {
        let path = path.as_ref();
        let fail = |p: String| Error::format(path, p);
        let root: Value =
            serde_json::from_slice(bytes).map_err(|e| fail(format!("not valid JSON: {e}")))?;
        let text = |k: &str| root.get(k).and_then(Value::as_str).map(str::to_string);
        match text("format") {
            Some(f) if f == FORMAT => {}
            Some(f) => return Err(fail(format!("unknown format '{f}', expected '{FORMAT}'"))),
            None => return Err(fail(format!("no \"format\" string (expected '{FORMAT}')"))),
        }
        let network =
            text("network").ok_or_else(|| fail("no \"network\" description string".into()))?;
        let input = text("input").ok_or_else(|| fail("no \"input\" description string".into()))?;
        let mats = root
            .get("materials")
            .and_then(Value::as_object)
            .ok_or_else(|| fail("no \"materials\" object".into()))?;
        if mats.is_empty() {
            return Err(fail("\"materials\" is empty".into()));
        }
        let mut materials = BTreeMap::new();
        for (name, m) in mats {
            materials.insert(name.clone(), Nbrdf::from_json(name, m).map_err(fail)?);
        }
        Ok(NbrdfSet {
            path: path.to_path_buf(),
            dataset: text("dataset").unwrap_or_default(),
            network,
            input,
            materials,
        })
    }

    /// The material names, sorted.
    pub fn names(&self) -> Vec<&str> {
        self.materials.keys().map(String::as_str).collect()
    }

    /// Number of materials.
    pub fn len(&self) -> usize {
        self.materials.len()
    }

    /// Whether the set has no material (never true for a parsed file).
    pub fn is_empty(&self) -> bool {
        self.materials.is_empty()
    }

    /// The `dataset` string of the file (empty when absent).
    pub fn dataset(&self) -> &str {
        &self.dataset
    }

    /// The file's `network` description.
    pub fn network_description(&self) -> &str {
        &self.network
    }

    /// The file's `input` description.
    pub fn input_description(&self) -> &str {
        &self.input
    }

    /// One material's network (a copy), or `Error::NotFound` naming the file.
    pub fn material(&self, name: &str) -> Result<Nbrdf> {
        self.materials.get(name).cloned().ok_or_else(|| {
            Error::NotFound(format!(
                "{}: no material '{name}' ({} materials, e.g. {})",
                self.path.display(),
                self.materials.len(),
                self.names()
                    .iter()
                    .take(3)
                    .copied()
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
    }
}

/// A full 90×90×180 MERL table of `nbrdf`: the network at every bin's node in the crate's
/// convention (the lower edge, as the networks were trained; see [`crate::measured::merl`]),
/// stored value = f / channel scale, evaluated in parallel with rayon. `progress(n)` is called
/// with the number of bins just finished (they add up to [`crate::measured::merl::BINS`] =
/// 1,458,000), from worker threads.
pub fn synthesize_merl(nbrdf: &Nbrdf, progress: impl Fn(u64) + Sync) -> MerlTable {
    synthesize_merl_with(nbrdf, BinConvention::default(), progress)
}

/// [`synthesize_merl`] with the network evaluated at the nodes of `convention`; the table reads
/// its values back with the same convention.
pub fn synthesize_merl_with(
    nbrdf: &Nbrdf,
    convention: BinConvention,
    progress: impl Fn(u64) + Sync,
) -> MerlTable {
    let values = fill_bins(
        |i, j, k| {
            let c = bin_node_with(convention, i, j, k);
            nbrdf.eval_angles(c.theta_h, c.theta_d, c.phi_d)
        },
        progress,
    );
    MerlTable::from_valid_stored(nbrdf.name.clone(), values).with_convention(convention)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny(material: &str) -> String {
        let row = |n: usize, v: f64| format!("[{}]", vec![v.to_string(); n].join(","));
        let mat = |n: usize, m: usize, v: f64| format!("[{}]", vec![row(m, v); n].join(","));
        format!(
            r#"{{"format":"nbrdf-mlp-v1","network":"n","input":"i","output":"o","materials":{{"{material}":{{"w1":{},"b1":{},"w2":{},"b2":{},"w3":{},"b3":{}}}}}}}"#,
            mat(6, 21, 0.1),
            row(21, 0.0),
            mat(21, 21, 0.01),
            row(21, 0.0),
            mat(21, 3, 0.05),
            row(3, 0.5)
        )
    }

    #[test]
    fn parses_a_constant_network_and_computes_by_hand() {
        let set = NbrdfSet::parse("<t>", tiny("m").as_bytes()).expect("valid");
        assert_eq!(set.names(), vec!["m"]);
        let n = set.material("m").expect("present");
        // x = normal configuration: h = (0,0,1), d = (0,0,1): a1 = 0.2 each, a2 = 21·0.2·0.01,
        // z = 21·a2·0.05 + 0.5.
        let a2 = 21.0 * 0.2 * 0.01;
        let z: f64 = 21.0 * a2 * 0.05 + 0.5;
        let want = z.exp() - 1.0;
        let got = n.eval_angles(0.0, 0.0, 0.0);
        for c in 0..3 {
            assert!((got[c] - want).abs() < 1e-14 * want, "{got:?} vs {want}");
        }
        assert!(set.material("nope").is_err());
    }
}
