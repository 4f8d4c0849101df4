#!/usr/bin/env python3
"""The walkthrough frame's quality study ("What to show"): `lustre render` of a baked
scene per glossy sample count, regular sampling vs Colbert-Křivánek at equal samples, and
progressive refinement after 1, 16 and 256 still frames, judged two ways:

  (a) against the converged integral of the same incident light (probes, mirror and see-through
      buffers, light maps): `lustre render --method progressive` with many frames — the
      thesis's own measure (000 Fig. 4.39-4.42);
  (b) against a `lustre reference` image of the same camera and size (the full path-traced
      frame), when one is given.

Every render uses the same camera rays (same seed and camera rays per pixel), so (a) isolates
the glossy integration. Each row's time is the frame stage of `times.csv` (`--device cpu` by
default, this machine).

Usage (from the repository root, after `cargo build --release -p lustre`):
  python3 scripts/frame_study.py BAKED/scene.toml --size 160x90 --spp 16 \
      --reference REF.exr --out /tmp/frame_study
"""

import argparse
import csv
import os
import re
import subprocess
import sys

LUSTRE = os.path.join(os.path.dirname(__file__), "..", "target", "release", "lustre")


def render(args, out, extra):
    cmd = [LUSTRE, "render", args.scene, "--size", args.size, "--spp", str(args.spp),
           "--seed", "1", "--device", args.device, "--out", out] + extra
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    with open(os.path.join(out, "times.csv")) as f:
        frame_s = sum(float(r["seconds"]) for r in csv.DictReader(f)
                      if r["stage"] in ("frame", "frame: mirror and see-through passes"))
    m = re.search(r"PSNR (\S+) dB, mean ΔE (\S+), relative RMS (\S+) %", p.stdout)
    lookups = re.search(r"(\S+) lookups per glossy hit", p.stdout)
    return (m.groups() if m else None), frame_s, (lookups.group(1) if lookups else "?")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--size", default="160x90")
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--samples", default="3,5,8,12,16,19")
    ap.add_argument("--truth-frames", type=int, default=64)
    ap.add_argument("--reference")
    ap.add_argument("--device", default="cpu", choices=["cpu", "gpu", "auto"],
                    help="lustre render --device (the CPU frame by default)")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    truth_dir = os.path.join(args.out, "truth")
    _, t_truth, _ = render(args, truth_dir, ["--method", "progressive", "--samples", "16",
                                             "--frames", str(args.truth_frames)])
    truth = os.path.join(truth_dir, "frame.exr")
    rows = []
    runs = [(m, n, []) for n in map(int, args.samples.split(",")) for m in ("regular", "ck")]
    runs += [("progressive", 16, ["--frames", str(f)]) for f in (1, 16, 256)]
    for method, n, extra in runs:
        label = method if not extra else f"{method} {extra[1]} frames"
        d = os.path.join(args.out, f"{method}-{n}" + (f"-{extra[1]}" if extra else ""))
        base = ["--method", method, "--samples", str(n)] + extra
        a, secs, lookups = render(args, d, base + ["--compare-reference", truth])
        b = None
        if args.reference:
            b, _, _ = render(args, d + "-ref", base + ["--compare-reference", args.reference])
        rows.append((label, n, lookups, a, b, secs))
        print(label, n, a, b, f"{secs:.2f} s", flush=True)
    lines = [
        f"# Frame study: {args.scene}, {args.size}, {args.spp} camera rays/pixel",
        "",
        f"(a) against progressive refinement with {args.truth_frames} frames of 16 samples "
        f"({t_truth:.1f} s); (b) against {args.reference or '(none)'}. PSNR of display values "
        "(exposure 1), mean CIE76 ΔE, relative RMS of linear values.",
        "",
        "| method | samples | lookups/hit | (a) PSNR | (a) ΔE | (a) rel RMS | (b) PSNR | (b) ΔE | (b) rel RMS | frame s |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for label, n, lookups, a, b, secs in rows:
        a = a or ("-", "-", "-")
        b = b or ("-", "-", "-")
        lines.append(f"| {label} | {n} | {lookups} | {a[0]} dB | {a[1]} | {a[2]} % | {b[0]} dB "
                     f"| {b[1]} | {b[2]} % | {secs:.2f} |")
    with open(os.path.join(args.out, "frame_study.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
