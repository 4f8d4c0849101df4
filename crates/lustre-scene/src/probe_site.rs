//! Room-scale reflection probes (000 §4.4 placed in the free space rather than at an object):
//! a capture point and, optionally, the box its parallax is corrected against (the room's
//! walls, as Godot's ReflectionProbe box projection and Bevy's parallax-corrected light probes
//! model them). A scene file lists them as `[[probe]]` sections; `lustre bake` writes the ones
//! its automatic set-up places, and a hand-written list replaces them.

use serde::{Deserialize, Serialize};

/// The most room probes a scene may list.
pub const MAX_PROBE_SITES: usize = 64;

/// A room probe: where it is captured, and the axis-aligned box (world space) its lookups are
/// corrected against. Without a box the renderer measures one by ray casting from the centre.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProbeSite {
    /// Unique name.
    pub name: String,
    /// The capture point (world space).
    pub centre: [f64; 3],
    /// The parallax box's low corner (with `box_max`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub box_min: Option<[f64; 3]>,
    /// The parallax box's high corner (with `box_min`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub box_max: Option<[f64; 3]>,
}

impl ProbeSite {
    /// The parallax box (low, high corners), when both corners are given.
    pub fn parallax_box(&self) -> Option<([f64; 3], [f64; 3])> {
        self.box_min.zip(self.box_max)
    }

    /// Whether world point `p` lies in the parallax box (every point when there is none).
    pub fn contains(&self, p: [f64; 3]) -> bool {
        self.parallax_box()
            .is_none_or(|(lo, hi)| (0..3).all(|i| lo[i] <= p[i] && p[i] <= hi[i]))
    }

    /// Checks the values; the error names the probe and the field: an empty name, a
    /// non-finite coordinate, one box corner without the other, an empty box, or a centre
    /// outside its box.
    pub fn validate(&self) -> Result<(), String> {
        let name = &self.name;
        if name.trim().is_empty() {
            return Err("probe name is empty".into());
        }
        let finite = |field: &str, v: &[f64; 3]| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(format!("probe {name:?}: {field} {v:?} is not finite"))
            }
        };
        finite("centre", &self.centre)?;
        match (self.box_min, self.box_max) {
            (None, None) => Ok(()),
            (Some(lo), Some(hi)) => {
                finite("box_min", &lo)?;
                finite("box_max", &hi)?;
                if (0..3).any(|i| lo[i] >= hi[i]) {
                    return Err(format!(
                        "probe {name:?}: the box {lo:?} … {hi:?} is empty (box_min must lie below box_max on every axis)"
                    ));
                }
                if !self.contains(self.centre) {
                    return Err(format!(
                        "probe {name:?}: the centre {:?} lies outside its box {lo:?} … {hi:?}",
                        self.centre
                    ));
                }
                Ok(())
            }
            _ => Err(format!(
                "probe {name:?}: box_min and box_max go together (one is missing)"
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn site(lo: Option<[f64; 3]>, hi: Option<[f64; 3]>) -> ProbeSite {
        ProbeSite {
            name: "room".into(),
            centre: [0.0, 1.0, 0.0],
            box_min: lo,
            box_max: hi,
        }
    }

    #[test]
    fn validate_names_each_problem() {
        assert!(site(None, None).validate().is_ok());
        assert!(site(Some([-1.0; 3]), Some([1.0, 2.0, 1.0]))
            .validate()
            .is_ok());
        let e = site(Some([-1.0; 3]), None).validate().unwrap_err();
        assert!(e.contains("go together"), "{e}");
        let e = site(Some([-1.0; 3]), Some([1.0, -1.0, 1.0]))
            .validate()
            .unwrap_err();
        assert!(e.contains("empty"), "{e}");
        let e = site(Some([-1.0; 3]), Some([1.0, 0.5, 1.0]))
            .validate()
            .unwrap_err();
        assert!(e.contains("outside its box"), "{e}");
        let mut s = site(None, None);
        s.centre[1] = f64::NAN;
        assert!(s.validate().unwrap_err().contains("not finite"));
        s.name = " ".into();
        assert!(s.validate().unwrap_err().contains("empty"));
    }

    #[test]
    fn contains_is_the_closed_box() {
        let s = site(Some([-1.0; 3]), Some([1.0, 2.0, 1.0]));
        assert!(s.contains([1.0, 2.0, -1.0]));
        assert!(!s.contains([1.0001, 0.0, 0.0]));
        assert!(site(None, None).contains([1e9, 0.0, 0.0]));
    }
}
