#!/usr/bin/env python3
"""lustre's path tracer and Mitsuba 3 side by side on the Modern Hall.

Renders the Mitsuba XML with `lustre reference` and with Mitsuba 3 (each variant asked for) at
the same resolution, samples per pixel and maximum depth, one after the other in this process,
and prints one Markdown table: render time, own noise, time to equal noise, and the errors
against TungstenRender.exr box-filtered to the film size (raw and after a Gaussian blur that
removes Monte-Carlo noise).

Noise is measured the same way for every renderer: two independent half-sample images (lustre:
its even/odd halves; Mitsuba: two renders of spp/2 with different seeds), whose mean is the
image; noise RMS = RMS(a - b) / 2, relative to the image mean. Times: the render's wall clock
(lustre: its own render timer; Mitsuba: the two `mi.render` calls) and the CPU time of all
threads (lustre: the whole process, scene loading included; Mitsuba: the two renders, with
`llvm_ad_rgb`'s kernel compilation done by a warm-up render outside). CPU time is what a shared
machine measures least badly. With variance ∝ 1/spp, the CPU time to reach lustre's noise is
cpu · (noise / noise_lustre)².

Mitsuba reads the XML after dropping the film properties it no longer knows (fileFormat, banner,
high_quality_edges); `nonlinear` is kept (Mitsuba 3's roughplastic supports it: dropping it makes
the image 14 % too bright). `--mitsuba-filter box` replaces the XML's tent pixel filter by a box
(lustre's filter); `xml` keeps the tent.

Usage (from the repository root, after `cargo build --release -p lustre`):
  python3 scripts/hall_vs_mitsuba.py --size 256 --spp 128 --variants scalar_rgb,llvm_ad_rgb \
      --out /tmp/hall
"""

import argparse
import json
import os
import re
import resource
import subprocess
import time

import numpy as np

HALL = "../shared/data/scenes/modern_hall"


def load_exr(path):
    import mitsuba as mi

    bmp = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False)
    return np.array(bmp, dtype=np.float64)


def blur(a, sigma):
    r = int(3 * sigma)
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    a = np.pad(a, ((r, r), (r, r), (0, 0)), "edge")
    a = np.apply_along_axis(lambda v: np.convolve(v, k, "valid"), 0, a)
    return np.apply_along_axis(lambda v: np.convolve(v, k, "valid"), 1, a)


def errors(img, ref):
    mean_ratio = img.mean() / ref.mean()
    rel_rms = np.sqrt(((img - ref) ** 2).mean()) / ref.mean()
    mse = ((np.clip(img, 0, 1) - np.clip(ref, 0, 1)) ** 2).mean()
    return mean_ratio, rel_rms, 10 * np.log10(1 / mse)


def reference_cmd(lustre, out, size, spp, max_depth, extra=()):
    """The `lustre reference` command of the Hall's XML writing `out`, after removing the files
    of an earlier job there (so that it starts afresh instead of resuming)."""
    for ext in ("json", "even.exr", "odd.exr"):
        p = out[: -len("exr")] + ext
        if os.path.exists(p):
            os.remove(p)
    return [
        lustre,
        "reference",
        f"{HALL}/mitsuba/scene.xml",
        *extra,
        "--size",
        size,
        "--spp",
        str(spp),
        "--max-depth",
        str(max_depth),
        "--out",
        out,
    ]


def run_lustre(args, n):
    out = os.path.join(args.out, f"lustre_{n}_{args.spp}.exr")
    cmd = reference_cmd(args.lustre, out, f"{n}x{n}", args.spp, args.max_depth)
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.time() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime + r1.ru_stime) - (r0.ru_utime + r0.ru_stime)
    state = json.load(open(out[: -len("exr")] + "json"))
    a = load_exr(out[: -len("exr")] + "even.exr")
    b = load_exr(out[: -len("exr")] + "odd.exr")
    return dict(name="lustre", time=state["seconds"], cpu=cpu, a=a, b=b, img=load_exr(out))


def run_mitsuba(args, n, variant):
    import mitsuba as mi

    mi.set_variant(variant)
    d = f"{HALL}/mitsuba/"
    x = open(d + "scene.xml").read()
    x = re.sub(r'\s*<(string|boolean) name="(fileFormat|banner|high_quality_edges)"[^>]*/>', "", x)
    x = x.replace('value="1280"', f'value="{n}"').replace('value="720"', f'value="{n}"')
    x = x.replace('name="maxDepth" value="65"', f'name="maxDepth" value="{args.max_depth}"')
    if args.mitsuba_filter == "box":
        x = x.replace('<rfilter name="rfilter" type="tent" />', '<rfilter type="box" />')
    mi.file_resolver().prepend(os.path.abspath(d))
    scene = mi.load_string(x)
    half = args.spp // 2
    if variant.startswith("llvm"):
        # Compile the kernels once outside the timed renders (Dr.Jit caches them).
        mi.render(scene, spp=half, seed=99)
    imgs, times = [], []
    c0 = time.process_time()
    for seed in (1, 2):
        t0 = time.time()
        img = np.array(mi.render(scene, spp=half, seed=seed), dtype=np.float64)
        times.append(time.time() - t0)
        imgs.append(img[..., :3])
    cpu = time.process_time() - c0
    a, b = imgs
    label = f"Mitsuba 3 {variant}" + (" (box filter)" if args.mitsuba_filter == "box" else " (XML's tent filter)")
    return dict(name=label, time=sum(times), cpu=cpu, a=a, b=b, img=0.5 * (a + b))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--spp", type=int, default=128)
    ap.add_argument("--max-depth", type=int, default=65)
    ap.add_argument("--variants", default="scalar_rgb")
    ap.add_argument("--mitsuba-filter", choices=["box", "xml"], default="box")
    ap.add_argument("--lustre", default="target/release/lustre")
    ap.add_argument("--blur", type=float, default=2.0)
    ap.add_argument("--out", required=True)
    ap.add_argument("--skip-lustre", action="store_true")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    n = args.size
    ref_full = load_exr(f"{HALL}/TungstenRender.exr")
    f = ref_full.shape[0] // n
    ref = ref_full.reshape(n, f, n, f, 3).mean(axis=(1, 3))
    print(f"load before: {os.getloadavg()}")
    runs = [] if args.skip_lustre else [run_lustre(args, n)]
    for v in filter(None, args.variants.split(",")):
        runs.append(run_mitsuba(args, n, v))
    print(f"load after: {os.getloadavg()}")
    base = runs[0]
    base_noise = np.sqrt(((base["a"] - base["b"]) ** 2).mean()) / 2 / base["img"].mean()
    print(
        f"\n{n}×{n}, {args.spp} spp, max depth {args.max_depth}; errors against TungstenRender.exr "
        f"box-filtered to {n}²; blur σ = {args.blur} px\n"
    )
    print(
        "| renderer | render wall (s) | CPU (s) | own noise (rel. RMS) | CPU to equal noise (s) | "
        "mean ratio | rel. RMS raw | rel. RMS blurred | own noise blurred | PSNR raw / blurred (dB) |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    rb = blur(ref, args.blur)
    for r in runs:
        img = r["img"]
        noise = np.sqrt(((r["a"] - r["b"]) ** 2).mean()) / 2 / img.mean()
        t_eq = r["cpu"] * (noise / base_noise) ** 2
        m0, e0, p0 = errors(img, ref)
        _, e1, p1 = errors(blur(img, args.blur), rb)
        nb = np.sqrt(((blur(r["a"], args.blur) - blur(r["b"], args.blur)) ** 2).mean()) / 2 / img.mean()
        print(
            f"| {r['name']} | {r['time']:.1f} | {r['cpu']:.1f} | {100 * noise:.2f} % | {t_eq:.1f} | {m0:.4f} | "
            f"{100 * e0:.2f} % | {100 * e1:.2f} % | {100 * nb:.2f} % | {p0:.2f} / {p1:.2f} |"
        )
        stem = os.path.join(args.out, re.sub(r"\W+", "_", r["name"]) + f"_{n}_{args.spp}")
        np.save(stem + ".npy", img)
        np.save(stem + "_halves.npy", np.stack([r["a"], r["b"]]))


if __name__ == "__main__":
    main()
