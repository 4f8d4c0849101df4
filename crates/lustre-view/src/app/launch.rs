//! Starting and ending a run: the arguments checked, the scene source made (so that a bad
//! specification fails before the window opens), the render thread started, the event loop
//! run, and the window's and the render thread's GPU objects released in order.

use super::App;
use crate::render::{self, Request, SceneSource};
use crate::script;
use crate::{Method, ViewArgs};
use anyhow::{anyhow, bail, Context};
use lustre_shade::request::{FrameRequest, MAX_SUPERSAMPLING};
use std::sync::mpsc::channel;
use std::time::{Duration, Instant};
use winit::event_loop::EventLoop;

/// `WxH` in pixels.
fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| anyhow!("--size {s:?}: expected WxH"))?;
    let (w, h): (u32, u32) = (
        w.trim().parse().context("--size width")?,
        h.trim().parse().context("--size height")?,
    );
    if !(64..=8192).contains(&w) || !(64..=8192).contains(&h) {
        bail!("--size {w}x{h}: each side must be 64 … 8192");
    }
    Ok((w, h))
}

/// The longest `--timeout` of an unattended run: a week.
const MAX_TIMEOUT_S: f64 = 7.0 * 86400.0;

/// Runs the viewer (see the crate docs).
pub fn run(args: &ViewArgs) -> anyhow::Result<()> {
    let size = parse_size(&args.size)?;
    if !(0.1..=1.0).contains(&args.scale) {
        bail!("--scale {}: must be 0.1 … 1", args.scale);
    }
    if !(1..=MAX_SUPERSAMPLING).contains(&args.supersampling) {
        bail!(
            "--supersampling {}: must be 1 … {MAX_SUPERSAMPLING}",
            args.supersampling
        );
    }
    initial_request(args)
        .validate()
        .map_err(|e| anyhow!("--samples {}: {e}", args.samples))?;
    lustre_shade::probe::ProbeOptions {
        face_size: args.probe_size,
        ..Default::default()
    }
    .validate()
    .map_err(|e| anyhow!("--probe-size: {e}"))?;
    if !(args.timeout > 0.0 && args.timeout <= MAX_TIMEOUT_S) {
        bail!(
            "--timeout {}: must be positive and at most {MAX_TIMEOUT_S} s (a week)",
            lustre_brdf::error::plain_number(args.timeout)
        );
    }
    let commands = match &args.script {
        Some(p) => {
            let bytes = lustre_brdf::error::read_file(p).context("--script")?;
            let text = String::from_utf8(bytes)
                .map_err(|_| anyhow!("--script {}: not UTF-8 text", p.display()))?;
            script::parse(&text).map_err(|e| anyhow!("{}: {e}", p.display()))?
        }
        None => vec![],
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let source = scene_source(args)?;
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!("no window system ({e}); run under X11 (or xvfb-run for a virtual display)")
    })?;
    let (req_tx, req_rx) = channel();
    let (rep_tx, rep_rx) = channel();
    let src = source.clone();
    let probe_size = args.probe_size;
    let adaptive_device = args.adaptive_device;
    let render_thread = std::thread::Builder::new()
        .name("lustre-view render".into())
        .spawn(move || render::run(src, probe_size, adaptive_device, req_rx, rep_tx))
        .context("starting the render thread")?;
    let mut app = App::new(args.clone(), size, source, commands, req_tx, rep_rx);
    let looped = event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop: {e}"));
    // An orderly end: the window's GPU objects first, then the render thread's (it ends at
    // its next request; one busy baking or rendering is given a while, then left to the exit).
    app.gfx = None;
    let _ = app.to_render.send(Request::Quit);
    let t = Instant::now();
    while !render_thread.is_finished() && t.elapsed() < Duration::from_secs(20) {
        std::thread::sleep(Duration::from_millis(20));
    }
    if render_thread.is_finished() {
        let _ = render_thread.join();
    }
    looped?;
    app.outcome.unwrap_or(Ok(())).map_err(|e| anyhow!(e))
}

/// What `args` open: a scene file, `--material`'s preview, `--lineup`, or the built-in room.
/// The in-memory scenes are made here, so that a bad specification or map fails before the
/// window opens.
fn scene_source(args: &ViewArgs) -> anyhow::Result<SceneSource> {
    use lustre_scene::builtin::{lineup, preview, LINEUP_FLOOR, LINEUP_PAINTS};
    let unbaked = args.material.is_some() || args.lineup;
    if let (Some(env), false) = (&args.env, unbaked) {
        bail!(
            "--env {}: applies to --material and --lineup (a scene file, and the built-in room, \
             have their own environment)",
            env.display()
        );
    }
    let environment = args
        .env
        .as_deref()
        .map(|p| {
            let (env, warning) = lustre_trace::baked::read_environment(p)
                .with_context(|| format!("--env {}", p.display()))?;
            if let Some(w) = warning {
                eprintln!("warning: {w}");
            }
            anyhow::Ok(env)
        })
        .transpose()?;
    Ok(match (&args.scene, &args.material) {
        (Some(p), _) => {
            if !p.is_file() {
                bail!("{}: no such scene file", p.display());
            }
            SceneSource::File(p.clone())
        }
        (None, Some(spec)) => SceneSource::Unbaked(Box::new(
            preview(spec, environment).with_context(|| format!("--material {spec}"))?,
        )),
        (None, None) if args.lineup => SceneSource::Unbaked(Box::new(
            lineup(LINEUP_PAINTS, LINEUP_FLOOR, environment).context("--lineup")?,
        )),
        (None, None) => SceneSource::BuiltinRoom(args.bake_dir.clone()),
    })
}

/// The frame request the viewer starts with: the regular method, `--samples` glossy samples,
/// k² camera rays (k = `--supersampling`), 64 frames a still camera accumulates, seed 1.
pub(super) fn initial_request(args: &ViewArgs) -> FrameRequest {
    FrameRequest {
        method: Method::Regular,
        samples: args.samples,
        rays: args.supersampling * args.supersampling,
        frames: 64,
        seed: 1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_sizes_are_read_and_bad_ones_named() {
        assert_eq!(parse_size("1280x800").unwrap(), (1280, 800));
        assert_eq!(parse_size(" 64 X 8192 ").unwrap(), (64, 8192));
        for (s, says) in [
            ("1280", "expected WxH"),
            ("axb", "--size width"),
            ("640x", "--size height"),
            ("63x100", "64 … 8192"),
            ("100x8193", "64 … 8192"),
        ] {
            let e = format!("{:#}", parse_size(s).unwrap_err());
            assert!(e.contains(says), "{s:?}: {e}");
        }
    }
}
