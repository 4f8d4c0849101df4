//! Input scripts for unattended runs (`lustre view --script FILE`): one command per line, run
//! in order through the same actions the keyboard, the mouse and the panels use. `#` starts a
//! comment.
//!
//! ```text
//! wait 3                 # 3 rendered frames
//! walk forward 0.5       # hold W for 0.5 s (forward | back | left | right | up | down)
//! look 40 -10            # a mouse motion of (40, −10) pixels
//! camera default         # a scene camera (bookmark)
//! select 160 120         # click the 3D view at pixel (160, 120) of the rendered frame
//! select gold-paint      # or select the first object with that material
//! set alpha 0.2          # a parameter of the selected object's material
//! material kurt-demo     # swap it for a material specification
//! method progressive     # regular | ck | progressive | reference | adaptive (an
//!                        #   adaptive-only scene refuses the first three, by name)
//! samples 8              # the global sample budget (adaptive: the mean N_p)
//! buffer level           # what the adaptive method shows: image | bandwidth | level | samples
//!                        #   | shaded (the pixels shaded, by level; up-sampled ones grey)
//! rate 1                 # the adaptive method's samples per cycle of b_p: 1 | 2
//! sample-rule relative   # its N_p rule: constant | coverage | relative | relative-mse | absolute
//! budget 3               # the selected object's own (budget global: back to the global one)
//! exposure 1.5
//! setup on               # draw the real-time set-up over the frame (setup off: hide it)
//! fit data:measured/merl/…binary sgd   # fit a measured file (sgd | kurt | beckmann | ggx)
//! record start           # record the camera path …
//! record stop walk.json  # … and write it (lustre render --path walk.json)
//! screenshot shot.png    # the window (and shot.json: camera, settings, edits, the view's rect)
//! save-material m.json
//! save-scene s.toml
//! quit
//! ```
//!
//! Every command that changes what is rendered is followed by a wait for the frame that shows
//! it, so a `screenshot` captures the result of the commands before it.

use crate::adaptive::{parse_rule, BufferView};
use crate::Method;
use lustre_adaptive::buffer::SampleRule;

/// Which way `walk` moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// W.
    Forward,
    /// S.
    Back,
    /// A.
    Left,
    /// D.
    Right,
    /// E.
    Up,
    /// Q.
    Down,
}

/// One command.
#[derive(Clone, Debug, PartialEq)]
pub enum Command {
    /// Wait for this many rendered frames.
    Wait(u32),
    /// Hold a movement key for this many seconds.
    Walk(Direction, f64),
    /// A mouse motion, pixels.
    Look(f64, f64),
    /// Jump to a named scene camera.
    Camera(String),
    /// Click the 3D view at a pixel of the rendered frame.
    Select(f64, f64),
    /// Select the first object whose material has this name.
    SelectMaterial(String),
    /// Set a parameter of the selected material.
    Set(String, String),
    /// Swap the selected material for a specification.
    Material(String),
    /// The glossy integration.
    Method(Method),
    /// Glossy samples per pixel (the adaptive method's mean N_p).
    Samples(u32),
    /// What the adaptive method shows.
    Buffer(BufferView),
    /// The adaptive method's samples per cycle of b_p (1 or 2).
    Rate(u8),
    /// The adaptive method's N_p rule.
    SampleRule(SampleRule),
    /// The selected object's own sample budget (`None`: the global one).
    Budget(Option<u32>),
    /// Display exposure.
    Exposure(f64),
    /// Draw the real-time set-up (probe boxes, reflectors) over the frame, or not.
    ShowSetup(bool),
    /// Fit a measured file with a model, apply it to the selected material.
    Fit(String, String),
    /// Start recording the camera path.
    RecordStart,
    /// Stop recording and write the path to a file.
    RecordStop(String),
    /// Save a screenshot of the window.
    Screenshot(String),
    /// Save the selected material as a material JSON.
    SaveMaterial(String),
    /// Save the scene file with the edits.
    SaveScene(String),
    /// Close the window.
    Quit,
}

/// Parses a script; errors name the line and what is wrong with it.
pub fn parse(text: &str) -> Result<Vec<Command>, String> {
    let mut out = vec![];
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let n = i + 1;
        let (word, rest) = match line.split_once(char::is_whitespace) {
            Some((w, r)) => (w, r.trim()),
            None => (line, ""),
        };
        let err = |why: &str| format!("line {n}: {line:?}: {why}");
        let num = |s: &str| -> Result<f64, String> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(&format!("{s:?} is not a finite number")))
        };
        let args: Vec<&str> = rest.split_whitespace().collect();
        let need = |k: usize| -> Result<(), String> {
            if args.len() == k {
                Ok(())
            } else {
                Err(err(&format!("takes {k} argument(s)")))
            }
        };
        let text_arg = || -> Result<String, String> {
            if rest.is_empty() {
                Err(err("takes an argument"))
            } else {
                Ok(rest.to_string())
            }
        };
        let cmd = match word {
            "wait" => {
                need(1)?;
                let k = args[0]
                    .parse::<u32>()
                    .ok()
                    .filter(|k| *k <= 100_000)
                    .ok_or_else(|| err("frames must be 0 … 100000"))?;
                Command::Wait(k)
            }
            "walk" => {
                need(2)?;
                let d = match args[0] {
                    "forward" => Direction::Forward,
                    "back" => Direction::Back,
                    "left" => Direction::Left,
                    "right" => Direction::Right,
                    "up" => Direction::Up,
                    "down" => Direction::Down,
                    _ => return Err(err("direction: forward | back | left | right | up | down")),
                };
                let s = num(args[1])?;
                if !(0.0..=600.0).contains(&s) {
                    return Err(err("seconds must be 0 … 600"));
                }
                Command::Walk(d, s)
            }
            "look" => {
                need(2)?;
                Command::Look(num(args[0])?, num(args[1])?)
            }
            "camera" => Command::Camera(text_arg()?),
            "select" if args.len() == 1 && args[0].parse::<f64>().is_err() => {
                Command::SelectMaterial(args[0].to_string())
            }
            "select" => {
                need(2)?;
                Command::Select(num(args[0])?, num(args[1])?)
            }
            "set" => {
                let (f, v) = rest
                    .split_once(char::is_whitespace)
                    .ok_or_else(|| err("set PARAMETER VALUE"))?;
                Command::Set(f.to_string(), v.trim().to_string())
            }
            "material" => Command::Material(text_arg()?),
            "method" => {
                need(1)?;
                Command::Method(match args[0] {
                    "regular" => Method::Regular,
                    "ck" => Method::Ck,
                    "progressive" => Method::Progressive,
                    "reference" => Method::Reference,
                    "adaptive" => Method::Adaptive,
                    _ => {
                        return Err(err(
                            "method: regular | ck | progressive | reference | adaptive",
                        ))
                    }
                })
            }
            "buffer" => {
                need(1)?;
                Command::Buffer(
                    BufferView::parse(args[0]).ok_or_else(|| {
                        err("buffer: image | bandwidth | level | samples | shaded")
                    })?,
                )
            }
            "rate" => {
                need(1)?;
                match args[0] {
                    "1" => Command::Rate(1),
                    "2" => Command::Rate(2),
                    _ => return Err(err("rate: 1 | 2 (image samples per cycle of b_p)")),
                }
            }
            "sample-rule" => {
                need(1)?;
                Command::SampleRule(parse_rule(args[0]).ok_or_else(|| {
                    err("sample-rule: constant | coverage | relative | relative-mse | absolute")
                })?)
            }
            "samples" => {
                need(1)?;
                let k = args[0]
                    .parse::<u32>()
                    .ok()
                    .filter(|k| (1..=256).contains(k))
                    .ok_or_else(|| err("samples must be 1 … 256"))?;
                Command::Samples(k)
            }
            "budget" => {
                need(1)?;
                if args[0] == "global" {
                    Command::Budget(None)
                } else {
                    let k = args[0]
                        .parse::<u32>()
                        .ok()
                        .filter(|k| (1..=256).contains(k))
                        .ok_or_else(|| err("budget: 1 … 256 or global"))?;
                    Command::Budget(Some(k))
                }
            }
            "exposure" => {
                need(1)?;
                let e = num(args[0])?;
                if e <= 0.0 {
                    return Err(err("exposure must be positive"));
                }
                Command::Exposure(e)
            }
            "setup" => match args.as_slice() {
                ["on"] => Command::ShowSetup(true),
                ["off"] => Command::ShowSetup(false),
                _ => return Err(err("setup on | off")),
            },
            "fit" => {
                let (file, model) = match args.as_slice() {
                    [f] => (f.to_string(), "sgd".to_string()),
                    [f, m] if ["sgd", "kurt", "beckmann", "ggx"].contains(m) => {
                        (f.to_string(), m.to_string())
                    }
                    _ => return Err(err("fit FILE [sgd | kurt | beckmann | ggx]")),
                };
                Command::Fit(file, model)
            }
            "record" => match args.as_slice() {
                ["start"] => Command::RecordStart,
                ["stop", f] => Command::RecordStop(f.to_string()),
                _ => return Err(err("record start | record stop FILE")),
            },
            "screenshot" => Command::Screenshot(text_arg()?),
            "save-material" => Command::SaveMaterial(text_arg()?),
            "save-scene" => Command::SaveScene(text_arg()?),
            "quit" => {
                need(0)?;
                Command::Quit
            }
            _ => return Err(err("unknown command")),
        };
        out.push(cmd);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_command() {
        let s = "wait 2\nwalk forward 0.5 # go\nlook 10 -5\ncamera default\nselect 1 2\n\
                 set alpha 0.2\nmaterial kurt(kd=0.1, ks=0.5, mx=0.1, my=0.1, r0=0.9)\n\
                 method ck\nsamples 8\nbudget 3\nexposure 1.5\nfit a.binary kurt\nrecord start\n\
                 record stop w.json\nscreenshot s.png\nsave-material m.json\nsave-scene s.toml\n\
                 \n# only a comment\nquit\nselect gold-paint\n";
        let c = parse(s).unwrap();
        assert_eq!(c.len(), 19);
        assert_eq!(c[18], Command::SelectMaterial("gold-paint".into()));
        assert_eq!(c[1], Command::Walk(Direction::Forward, 0.5));
        assert_eq!(c[5], Command::Set("alpha".into(), "0.2".into()));
        assert_eq!(
            c[6],
            Command::Material("kurt(kd=0.1, ks=0.5, mx=0.1, my=0.1, r0=0.9)".into())
        );
        assert_eq!(c[9], Command::Budget(Some(3)));
        assert_eq!(c[11], Command::Fit("a.binary".into(), "kurt".into()));
        assert_eq!(c[17], Command::Quit);
        assert_eq!(
            parse("setup on\nsetup off").unwrap(),
            vec![Command::ShowSetup(true), Command::ShowSetup(false)]
        );
    }

    #[test]
    fn parses_the_adaptive_commands() {
        let s = "method adaptive
buffer image
buffer bandwidth
buffer level # ℓ + 1
                 buffer samples
buffer shaded
rate 1
rate 2
sample-rule constant
sample-rule coverage
                 sample-rule relative
sample-rule relative-mse
sample-rule absolute
";
        let c = parse(s).unwrap();
        assert_eq!(
            c,
            vec![
                Command::Method(Method::Adaptive),
                Command::Buffer(BufferView::Image),
                Command::Buffer(BufferView::Bandwidth),
                Command::Buffer(BufferView::Level),
                Command::Buffer(BufferView::Samples),
                Command::Buffer(BufferView::Shaded),
                Command::Rate(1),
                Command::Rate(2),
                Command::SampleRule(SampleRule::Constant),
                Command::SampleRule(SampleRule::Coverage),
                Command::SampleRule(SampleRule::Relative),
                Command::SampleRule(SampleRule::RelativeMse),
                Command::SampleRule(SampleRule::Absolute),
            ]
        );
        for (s, says) in [
            ("method adaptiv", "| adaptive"),
            ("buffer", "1 argument"),
            (
                "buffer mask",
                "image | bandwidth | level | samples | shaded",
            ),
            ("buffer level samples", "1 argument"),
            ("\n\nrate 3", "line 3"),
            ("rate 1.5", "rate: 1 | 2"),
            ("rate", "1 argument"),
            ("sample-rule uniform", "constant | coverage | relative"),
            ("sample-rule", "1 argument"),
        ] {
            let e = parse(s).unwrap_err();
            assert!(e.contains(says), "{s:?}: {e}");
        }
    }

    #[test]
    fn bad_lines_are_named() {
        for (s, says) in [
            ("wait x", "line 1"),
            ("\nwalk sideways 1", "line 2"),
            ("look 1", "2 argument"),
            ("select 3", "2 argument"),
            ("samples 0", "1 … 256"),
            ("exposure -1", "positive"),
            ("budget 0", "global"),
            ("look NaN 1", "finite"),
            ("fly 1", "unknown command"),
            ("record stop", "record start"),
            ("set alpha", "PARAMETER VALUE"),
        ] {
            let e = parse(s).unwrap_err();
            assert!(e.contains(says), "{s:?}: {e}");
        }
    }

    #[test]
    fn more_bad_lines_are_named() {
        for (s, says) in [
            ("wait 100001", "0 … 100000"),
            ("wait -1", "0 … 100000"),
            ("walk forward", "2 argument"),
            ("walk up 601", "0 … 600"),
            ("walk down -0.5", "0 … 600"),
            ("camera", "takes an argument"),
            ("material", "takes an argument"),
            ("screenshot", "takes an argument"),
            ("save-material", "takes an argument"),
            ("save-scene", "takes an argument"),
            ("method", "1 argument"),
            ("samples 257", "1 … 256"),
            ("samples 8.5", "1 … 256"),
            ("budget 257", "global"),
            ("exposure 0", "positive"),
            ("exposure", "1 argument"),
            ("setup", "setup on | off"),
            ("setup maybe", "setup on | off"),
            ("fit", "fit FILE"),
            ("fit a.binary phong", "sgd | kurt | beckmann | ggx"),
            ("fit a b c", "fit FILE"),
            ("record", "record start"),
            ("record start now", "record start"),
            ("quit now", "0 argument"),
            ("\n# a comment\n\nfly", "line 4: \"fly\": unknown command"),
        ] {
            let e = parse(s).unwrap_err();
            assert!(e.contains(says), "{s:?}: {e}");
        }
    }

    #[test]
    fn defaults_edge_values_and_comments() {
        let s = "fit data:merl/gold.binary\nbudget global\nwait 0\nwalk back 0\n\
                 select 3.5 -2\nset base.alpha  0.3 0.4\n  # an indented comment\n\n\
                 look 0 0 # a trailing one\n";
        assert_eq!(
            parse(s).unwrap(),
            vec![
                Command::Fit("data:merl/gold.binary".into(), "sgd".into()),
                Command::Budget(None),
                Command::Wait(0),
                Command::Walk(Direction::Back, 0.0),
                Command::Select(3.5, -2.0),
                Command::Set("base.alpha".into(), "0.3 0.4".into()),
                Command::Look(0.0, 0.0),
            ]
        );
        assert_eq!(parse("# nothing\n\n").unwrap(), vec![]);
    }
}
