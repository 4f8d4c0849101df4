//! Parameter names, default search ranges, fixed values and user ranges.
//!
//! Names (lobes numbered from 1): `kd` (all channels), `kd_r`, `kd_g`, `kd_b`; per reflection
//! lobe i: `ks{i}` (all channels), `ks{i}_r`, `ks{i}_g`, `ks{i}_b`, `mx{i}`, `my{i}`, `r0{i}`,
//! `alpha{i}`; per transmission lobe j: `kt{j}`, `kt{j}_r`, `kt{j}_g`, `kt{j}_b`, `mxt{j}`,
//! `myt{j}`, `r0t{j}`, `alphat{j}`. A whole-colour name (`ks1`) applies to the three channels;
//! a channel name (`ks1_g`) then overrides its channel.
//!
//! For isotropic data (the BSDF's flags say so) my is tied to mx (an isotropic lobe) unless
//! `my{i}` (`myt{j}`) is fixed or given a range; for anisotropic data both are free.
//!
//! Default ranges: ks, kt ∈ [0, 1]; mx, my ∈ [0.001, 1] searched on a logarithmic scale;
//! r0, α ∈ [0, 1]. kd is never searched: it comes from the histogram (000 §3.4.1) and is
//! clamped to its range when one is given; the polish refines it within that range.

use super::KurtOptions;
use crate::{FitError, Result};
use lustre_brdf::models::kurt::{MAX_ROUGHNESS, MIN_ROUGHNESS};

/// Default roughness search range.
const DEFAULT_M: (f64, f64) = (1e-3, 1.0);

/// One scalar parameter: fixed, or free within `[lo, hi]` (in its own units, not log).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Param {
    /// Held at this value.
    Fixed(f64),
    /// Searched within [lo, hi]; `log` when searched on a logarithmic scale.
    Free { lo: f64, hi: f64, log: bool },
}

impl Param {
    /// Maps a value to the search coordinate (ln for log parameters).
    pub fn to_coord(self, v: f64) -> f64 {
        match self {
            Param::Free { log: true, .. } => v.ln(),
            _ => v,
        }
    }

    /// Maps a search coordinate back to a value.
    pub fn value_at(self, x: f64) -> f64 {
        match self {
            Param::Free { log: true, .. } => x.exp(),
            _ => x,
        }
    }

    /// The range in search coordinates, or `None` when fixed.
    pub fn coord_range(self) -> Option<(f64, f64)> {
        match self {
            Param::Fixed(_) => None,
            Param::Free { lo, hi, log } => Some(if log { (lo.ln(), hi.ln()) } else { (lo, hi) }),
        }
    }
}

/// The parameters of one lobe: ks per channel, then mx, my, r0, α.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LobeSpace {
    /// ks (kt) per channel.
    pub ks: [Param; 3],
    /// mx, my, r0, α.
    pub shape: [Param; 4],
    /// my is tied to mx (isotropic data, no `my{i}`/`myt{j}` given).
    pub tie_my: bool,
}

/// The whole parameter space of a fit.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Space {
    /// kd per channel: `Fixed` or a clamp range for the histogram estimate.
    pub kd: [Param; 3],
    /// Reflection lobes.
    pub refl: Vec<LobeSpace>,
    /// Transmission lobes.
    pub trans: Vec<LobeSpace>,
}

/// Valid domain of a parameter kind.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Weight,
    Roughness,
    Unit,
}

impl Kind {
    fn domain(self) -> (f64, f64) {
        match self {
            Kind::Weight => (0.0, f64::INFINITY),
            Kind::Roughness => (MIN_ROUGHNESS, MAX_ROUGHNESS),
            Kind::Unit => (0.0, 1.0),
        }
    }
}

const SHAPE_NAMES: [&str; 4] = ["mx", "my", "r0", "alpha"];
const CHANNELS: [&str; 3] = ["r", "g", "b"];

/// Where a name points.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    /// kd; `None` = all channels.
    Kd(Option<usize>),
    /// Lobe weight of (transmission?, lobe index); `None` = all channels.
    Ks(bool, usize, Option<usize>),
    /// Shape parameter k of (transmission?, lobe index).
    Shape(bool, usize, usize),
}

impl Slot {
    fn kind(self) -> Kind {
        match self {
            Slot::Kd(_) | Slot::Ks(..) => Kind::Weight,
            Slot::Shape(_, _, k) if k < 2 => Kind::Roughness,
            Slot::Shape(..) => Kind::Unit,
        }
    }

    /// Whole-colour names are applied before channel names.
    fn is_group(self) -> bool {
        matches!(self, Slot::Kd(None) | Slot::Ks(_, _, None))
    }
}

/// All names with their slots, in documentation order.
fn slots(opts: &KurtOptions) -> Vec<(String, Slot)> {
    let mut v = vec![("kd".to_string(), Slot::Kd(None))];
    for (c, ch) in CHANNELS.iter().enumerate() {
        v.push((format!("kd_{ch}"), Slot::Kd(Some(c))));
    }
    for (trans, n, w, suffix) in [
        (false, opts.lobes, "ks", ""),
        (true, opts.transmission_lobes, "kt", "t"),
    ] {
        for i in 0..n {
            let k = i + 1;
            v.push((format!("{w}{k}"), Slot::Ks(trans, i, None)));
            for (c, ch) in CHANNELS.iter().enumerate() {
                v.push((format!("{w}{k}_{ch}"), Slot::Ks(trans, i, Some(c))));
            }
            for (s, name) in SHAPE_NAMES.iter().enumerate() {
                v.push((format!("{name}{suffix}{k}"), Slot::Shape(trans, i, s)));
            }
        }
    }
    v
}

/// The names `fixed` and `ranges` accept for these options (see the module documentation).
pub fn parameter_names(opts: &KurtOptions) -> Vec<String> {
    slots(opts).into_iter().map(|(n, _)| n).collect()
}

/// Default space: everything free in its default range.
fn default_space(opts: &KurtOptions) -> Space {
    let w = Param::Free {
        lo: 0.0,
        hi: 1.0,
        log: false,
    };
    let m = Param::Free {
        lo: DEFAULT_M.0,
        hi: DEFAULT_M.1,
        log: true,
    };
    let lobe = LobeSpace {
        ks: [w; 3],
        shape: [m, m, w, w],
        tie_my: false,
    };
    let kd = Param::Free {
        lo: 0.0,
        hi: f64::INFINITY,
        log: false,
    };
    Space {
        kd: [kd; 3],
        refl: vec![lobe; opts.lobes],
        trans: vec![lobe; opts.transmission_lobes],
    }
}

/// Sets the slot's parameter(s) to `p`.
fn assign(space: &mut Space, slot: Slot, p: Param) {
    let chans = |c: Option<usize>| c.map_or(0..3, |c| c..c + 1);
    match slot {
        Slot::Kd(c) => chans(c).for_each(|c| space.kd[c] = p),
        Slot::Ks(t, i, c) => {
            let l = if t {
                &mut space.trans[i]
            } else {
                &mut space.refl[i]
            };
            chans(c).for_each(|c| l.ks[c] = p);
        }
        Slot::Shape(t, i, k) => {
            let l = if t {
                &mut space.trans[i]
            } else {
                &mut space.refl[i]
            };
            l.shape[k] = p;
        }
    }
}

/// Validates the options and builds the parameter space.
pub(crate) fn build_space(
    opts: &KurtOptions,
    transmission: bool,
    isotropic: bool,
) -> Result<Space> {
    if opts.grid < 2 {
        return Err(FitError::Option(format!(
            "grid = {}: the brute-force search needs at least 2 values per parameter",
            opts.grid
        )));
    }
    if opts.grid > 64 {
        return Err(FitError::Option(format!(
            "grid = {}: at most 64 values per parameter",
            opts.grid
        )));
    }
    if opts.levels == 0 {
        return Err(FitError::Option(
            "levels = 0: the search needs at least one level".into(),
        ));
    }
    if opts.transmission_lobes > 0 && !transmission {
        return Err(FitError::Option(format!(
            "{} transmission lobe(s) requested but the data is fitted without transmission",
            opts.transmission_lobes
        )));
    }
    let all = slots(opts);
    let lookup = |name: &str| -> Result<Slot> {
        all.iter()
            .find(|(n, _)| n == name)
            .map(|(_, s)| *s)
            .ok_or_else(|| {
                FitError::Option(format!(
                    "unknown parameter '{name}' (known for {} reflection and {} transmission lobe(s): {})",
                    opts.lobes,
                    opts.transmission_lobes,
                    parameter_names(opts).join(", ")
                ))
            })
    };
    let mut seen: Vec<&str> = Vec::new();
    let mut entries: Vec<(Slot, Param)> = Vec::new();
    for (name, v) in &opts.fixed {
        let slot = lookup(name)?;
        let (lo, hi) = slot.kind().domain();
        if !v.is_finite() || *v < lo || *v > hi {
            return Err(FitError::Option(format!(
                "fixed {name} = {v} lies outside its valid range [{lo}, {hi}]"
            )));
        }
        if seen.contains(&name.as_str()) {
            return Err(FitError::Option(format!("parameter '{name}' given twice")));
        }
        seen.push(name);
        entries.push((slot, Param::Fixed(*v)));
    }
    for (name, a, b) in &opts.ranges {
        let slot = lookup(name)?;
        let (lo, hi) = slot.kind().domain();
        if !a.is_finite() || !b.is_finite() {
            return Err(FitError::Option(format!(
                "range of {name} [{a}, {b}] is not finite"
            )));
        }
        if a >= b {
            return Err(FitError::Option(format!(
                "range of {name} [{a}, {b}] is empty or inverted (lower must be below upper; fix the parameter to hold it at one value)"
            )));
        }
        if *a < lo || *b > hi {
            return Err(FitError::Option(format!(
                "range of {name} [{a}, {b}] leaves its valid range [{lo}, {hi}]"
            )));
        }
        if seen.contains(&name.as_str()) {
            return Err(FitError::Option(format!(
                "parameter '{name}' given twice (fixed and/or ranged)"
            )));
        }
        seen.push(name);
        let log = matches!(slot, Slot::Shape(_, _, k) if k < 2);
        entries.push((
            slot,
            Param::Free {
                lo: *a,
                hi: *b,
                log,
            },
        ));
    }
    let mut space = default_space(opts);
    // Isotropic data: my follows mx unless my is given.
    for (trans, lobes) in [(false, &mut space.refl), (true, &mut space.trans)] {
        for (i, l) in lobes.iter_mut().enumerate() {
            l.tie_my = isotropic && !entries.iter().any(|(s, _)| *s == Slot::Shape(trans, i, 1));
        }
    }
    // Whole-colour names first, so that channel names override them.
    entries.sort_by_key(|(s, _)| !s.is_group());
    for (slot, p) in entries {
        assign(&mut space, slot, p);
    }
    Ok(space)
}
