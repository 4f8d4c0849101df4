//! One frame request: what every renderer takes — the CPU walkthrough ([`crate::frame`]), the
//! GPU walkthrough (`lustre_gpu::walkthrough`), the adaptive method (lustre-adaptive, its GPU
//! passes), the command line and the viewer — validated once ([`FrameRequest::validate`]) with
//! one set of limits, and the one [`Method`] enum they share.

use crate::{Result, ShadeError};

/// How a frame's glossy part is integrated.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Regular samples through the material's warp, MIP-filtered (000 §4.4.3, 002).
    Regular,
    /// Colbert–Křivánek: random samples, MIP-filtered.
    Ck,
    /// Progressive refinement: [`FrameRequest::frames`] rotated regular sets, averaged.
    Progressive,
    /// 004 ch. IV: measured materials shaded adaptively by frequency analysis (bandwidth
    /// buffer, hierarchical shading; [`FrameRequest::samples`] the mean N_p), the
    /// environment's and the scene's planar emitters' light without visibility.
    Adaptive,
    /// The brute force adaptive shading is compared with: [`FrameRequest::samples`]
    /// importance samples at every pixel, the same light and estimator.
    Brute,
    /// The converged path-traced reference, filling in one sample per pixel per pass (the
    /// viewer).
    Reference,
}

impl Method {
    /// Every method, in the order of its names.
    pub const ALL: [Method; 6] = [
        Method::Regular,
        Method::Ck,
        Method::Progressive,
        Method::Adaptive,
        Method::Brute,
        Method::Reference,
    ];

    /// Its name on the command line, in scripts and in the viewer's panel.
    pub fn name(self) -> &'static str {
        match self {
            Method::Regular => "regular",
            Method::Ck => "ck",
            Method::Progressive => "progressive",
            Method::Adaptive => "adaptive",
            Method::Brute => "brute",
            Method::Reference => "reference",
        }
    }

    /// One line on what it does (the command line's help).
    pub fn description(self) -> &'static str {
        match self {
            Method::Regular => "Regular samples through the material's warp, MIP-filtered",
            Method::Ck => "Colbert–Křivánek: random samples, MIP-filtered",
            Method::Progressive => {
                "Progressive refinement: --frames rotated regular sets, averaged"
            }
            Method::Adaptive => {
                "004 ch. IV: measured materials shaded adaptively by frequency analysis \
                 (bandwidth buffer, hierarchical shading, --samples the mean N_p), the \
                 environment's and the scene's planar emitters' light without visibility, on \
                 the CPU or the GPU"
            }
            Method::Brute => {
                "The brute force adaptive shading is compared with: --samples importance \
                 samples at every pixel, the same light and estimator, on the CPU"
            }
            Method::Reference => "The path-traced reference, one sample per pixel per pass",
        }
    }

    /// The method named `name`. Errors: an unknown name (the known ones listed).
    pub fn parse(name: &str) -> Result<Method> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                let known: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
                ShadeError::Parameter(format!(
                    "unknown method {name:?} (use {})",
                    known.join(", ")
                ))
            })
    }

    /// Whether it is one of the walkthrough's methods (regular, CK, progressive): light maps,
    /// probes and view buffers, the glossy part regularly sampled.
    pub fn walkthrough(self) -> bool {
        matches!(self, Method::Regular | Method::Ck | Method::Progressive)
    }

    /// Whether it is 004's adaptive method or the brute force it is compared with.
    pub fn adaptive(self) -> bool {
        matches!(self, Method::Adaptive | Method::Brute)
    }

    /// The most samples per pixel it takes: [`MAX_WALKTHROUGH_SAMPLES`] per pixel and lobe for
    /// the walkthrough's methods, [`MAX_ADAPTIVE_SAMPLES`] (the mean N_p) for the adaptive
    /// ones, [`MAX_REFERENCE_SAMPLES`] passes for the reference.
    pub fn max_samples(self) -> u32 {
        if self.walkthrough() {
            MAX_WALKTHROUGH_SAMPLES
        } else if self.adaptive() {
            MAX_ADAPTIVE_SAMPLES
        } else {
            MAX_REFERENCE_SAMPLES
        }
    }
}

/// Largest glossy sample count per pixel and lobe of the walkthrough's methods.
pub const MAX_WALKTHROUGH_SAMPLES: u32 = 256;
/// Largest mean sample count N_p of the adaptive methods.
pub const MAX_ADAPTIVE_SAMPLES: u32 = 1024;
/// Largest sample count per pixel of the reference.
pub const MAX_REFERENCE_SAMPLES: u32 = 1 << 20;
/// Largest k of a k×k supersampled G-buffer (the GPU walkthrough, the adaptive methods).
pub const MAX_SUPERSAMPLING: u32 = 4;
/// Most progressive frames.
pub const MAX_FRAMES: u32 = 4096;
/// Most camera rays per pixel (the CPU walkthrough's jittered rays; the GPU takes the k×k
/// nearest, k ≤ [`MAX_SUPERSAMPLING`]).
pub const MAX_RAYS: u32 = 1024;

/// One frame to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRequest {
    /// How the glossy part is integrated.
    pub method: Method,
    /// Glossy samples per pixel (per camera ray; the adaptive methods: the mean N_p).
    pub samples: u32,
    /// Camera rays per pixel: jittered on the CPU walkthrough; a k×k supersampled G-buffer
    /// elsewhere, k = [`FrameRequest::supersampling`].
    pub rays: u32,
    /// Progressive frames accumulated (read by the progressive method only).
    pub frames: u32,
    /// Seed of the camera jitter and the random methods.
    pub seed: u64,
}

impl Default for FrameRequest {
    /// 16 regular samples per pixel, one camera ray, one frame, seed 1.
    fn default() -> Self {
        FrameRequest {
            method: Method::Regular,
            samples: 16,
            rays: 1,
            frames: 1,
            seed: 1,
        }
    }
}

impl FrameRequest {
    /// Errors (naming the value and its range): samples outside 1..=[`Method::max_samples`],
    /// no camera rays, progressive frames outside 1..=[`MAX_FRAMES`], and for the adaptive methods camera
    /// rays that are not k² with k in 1..=[`MAX_SUPERSAMPLING`].
    pub fn validate(&self) -> Result<()> {
        let max = self.method.max_samples();
        if !(1..=max).contains(&self.samples) {
            let mean = if self.method.adaptive() {
                " (the mean N_p)"
            } else {
                ""
            };
            return Err(ShadeError::Parameter(format!(
                "{} glossy samples per pixel{mean} is outside 1..={max} for the {} method",
                self.samples,
                self.method.name()
            )));
        }
        if self.rays == 0 || self.rays > MAX_RAYS {
            return Err(ShadeError::Parameter(format!(
                "{} camera rays per pixel is outside 1..={MAX_RAYS}",
                self.rays
            )));
        }
        if self.method == Method::Progressive && !(1..=MAX_FRAMES).contains(&self.frames) {
            return Err(ShadeError::Parameter(format!(
                "a progressive refinement of {} frames is outside 1..={MAX_FRAMES}",
                self.frames
            )));
        }
        if self.method.adaptive() {
            let k = self.supersampling();
            if k * k != self.rays || k > MAX_SUPERSAMPLING {
                return Err(ShadeError::Parameter(format!(
                    "{} camera rays per pixel: the {} method takes k×k with k in \
                     1..={MAX_SUPERSAMPLING} (1, 4, 9 or 16)",
                    self.rays,
                    self.method.name()
                )));
            }
        }
        Ok(())
    }

    /// k of the k×k supersampled G-buffer nearest to [`FrameRequest::rays`] (at least 1).
    pub fn supersampling(&self) -> u32 {
        (f64::from(self.rays).sqrt().round() as u32).max(1)
    }

    /// The frames the walkthrough's point sets average: [`FrameRequest::frames`] for the
    /// progressive method, 1 otherwise.
    pub fn accumulated_frames(&self) -> u32 {
        if self.method == Method::Progressive {
            self.frames
        } else {
            1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_ones_are_named() {
        for m in Method::ALL {
            assert_eq!(Method::parse(m.name()).ok(), Some(m));
        }
        let e = Method::parse("fast").unwrap_err().to_string();
        assert!(e.contains("\"fast\"") && e.contains("regular, ck"), "{e}");
    }

    #[test]
    fn one_set_of_limits() {
        let ok = FrameRequest::default();
        assert!(ok.validate().is_ok());
        let walk = FrameRequest {
            samples: MAX_WALKTHROUGH_SAMPLES + 1,
            ..ok
        };
        assert!(walk.validate().unwrap_err().to_string().contains("1..=256"));
        let adaptive = FrameRequest {
            method: Method::Adaptive,
            ..walk
        };
        assert!(adaptive.validate().is_ok());
        let over = FrameRequest {
            samples: MAX_ADAPTIVE_SAMPLES + 1,
            ..adaptive
        };
        assert!(over
            .validate()
            .unwrap_err()
            .to_string()
            .contains("1..=1024"));
        for (rays, fine) in [(1, true), (4, true), (16, true), (2, false), (25, false)] {
            let r = FrameRequest { rays, ..adaptive };
            assert_eq!(r.validate().is_ok(), fine, "{rays}");
        }
        // The walkthrough takes any ray count; k is the nearest square root.
        let two = FrameRequest { rays: 2, ..ok };
        assert!(two.validate().is_ok());
        assert_eq!(two.supersampling(), 1);
        assert_eq!(FrameRequest { rays: 9, ..ok }.supersampling(), 3);
        for bad in [
            FrameRequest { samples: 0, ..ok },
            FrameRequest { rays: 0, ..ok },
            FrameRequest {
                method: Method::Progressive,
                frames: 0,
                ..ok
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
        let p = FrameRequest {
            method: Method::Progressive,
            frames: 8,
            ..ok
        };
        assert_eq!((p.accumulated_frames(), ok.accumulated_frames()), (8, 1));
    }
}
