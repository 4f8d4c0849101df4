#!/usr/bin/env python3
"""The walkthrough frame's speed in the shape of 000 Tables 4.1 and 4.2 ("What to
show"): frames per second at 1680x1050 of the built-in room's benchmark views, the screen full of
and about half full of view-dependent pixels, on a curved probe object (cameras `curved-full`,
`curved-half`: Table 4.1, the cube-map approach) and on the planar reflector (`planar-full`,
`planar-half`: Table 4.2, the mirror buffer), for n = 3, 5, ..., 19 glossy samples per pixel.

Each cell is `lustre render --camera VIEW --samples n --repeat R`: the median frame time of R
renders of the same still frame, the mirror and see-through passes included (times.csv). The
share of view-dependent pixels is measured (the glossy camera hits the renderer reports), not
assumed. The built-in room's light maps are baked once into OUT/work/bake and reused.

Usage (from the repository root, after `cargo build --release -p lustre`):
  python3 scripts/frame_tables.py --out /tmp/frame_tables [--size 1680x1050] [--repeat 3] \
      [--spp 1] [-- EXTRA lustre render ARGUMENTS]
"""

import argparse
import csv
import os
import re
import shutil
import subprocess
import sys

LUSTRE = os.path.join(os.path.dirname(__file__), "..", "target", "release", "lustre")
VIEWS = [("Table 4.1, curved (probe)", "curved"), ("Table 4.2, planar (mirror)", "planar")]


def render(args, view, n, extra):
    work = os.path.join(args.out, "work")
    cmd = [LUSTRE, "render", "--camera", view, "--samples", str(n), "--size", args.size,
           "--spp", str(args.spp), "--repeat", str(args.repeat), "--out", work] + extra
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{p.stderr}")
    with open(os.path.join(work, "times.csv")) as f:
        stages = {r["stage"]: float(r["seconds"]) for r in csv.DictReader(f)}
    frame_s = stages["frame"] + stages.get("frame: mirror and see-through passes", 0.0)
    hits = re.search(r"(\d+)×(\d+), (\d+) camera rays/pixel, .*: (\d+) glossy hits", p.stdout)
    if not hits:
        sys.exit(f"no glossy-hit count in the output of {' '.join(cmd)}:\n{p.stdout}")
    w, h, spp, glossy = map(int, hits.groups())
    device = "GPU" if "rendered on the GPU" in p.stderr + p.stdout else "CPU"
    keep = os.path.join(args.out, f"{view}-{n}")
    os.makedirs(keep, exist_ok=True)
    for name in ("frame.png", "times.csv"):
        shutil.copy(os.path.join(work, name), keep)
    return frame_s, glossy / (w * h * spp), device


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--size", default="1680x1050")
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--samples", default="3,5,7,9,11,13,15,17,19")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    samples = list(map(int, args.samples.split(",")))
    lines = [f"# 000 Tables 4.1 / 4.2 on this machine: {args.size}, {args.spp} camera ray(s) "
             f"per pixel, median of {args.repeat} frames; extra arguments: {' '.join(extra) or '-'}",
             ""]
    for title, kind in VIEWS:
        cells = {}
        for cover in ("full", "half"):
            for n in samples:
                cells[(cover, n)] = render(args, f"{kind}-{cover}", n, extra)
                s, share, device = cells[(cover, n)]
                print(f"{kind}-{cover} n={n}: {s * 1e3:.1f} ms ({1 / s:.2f} fps), "
                      f"{share * 100:.1f} % view-dependent, {device}", flush=True)
        lines.append(f"## {title}")
        lines.append("")
        lines.append("| screen | view-dependent pixels | " +
                     " | ".join(f"{n} samples" for n in samples) + " |")
        lines.append("|---|---:|" + "---:|" * len(samples))
        for cover in ("full", "half"):
            share = sum(cells[(cover, n)][1] for n in samples) / len(samples)
            device = cells[(cover, samples[0])][2]
            lines.append(f"| {cover} ({device}) | {share * 100:.1f} % | " + " | ".join(
                f"{1 / cells[(cover, n)][0]:.2f} fps ({cells[(cover, n)][0] * 1e3:.0f} ms)"
                for n in samples) + " |")
        lines.append("")
    text = "\n".join(lines)
    with open(os.path.join(args.out, "tables.md"), "w") as f:
        f.write(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
