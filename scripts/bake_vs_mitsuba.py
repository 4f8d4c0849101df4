#!/usr/bin/env python3
"""`lustre bake` and Mitsuba 3 tracing the same number of paths.

Bakes the Modern Hall (the Mitsuba XML) with `lustre bake` at the density, spp and bounces
asked for; then the same number of paths through the diffuse scene from the scene camera (a
16:9 film at `--camera-spp`, max depth = bounces + 1: the camera segment, then the bake's
path), traced by `lustre reference --diffuse` and by Mitsuba 3 (each variant asked for), one
after the other in this process. Mitsuba's scene is the XML with every BSDF made diffuse as the
bake makes it (rough plastics become Lambertian with their diffuse reflectance, texture kept;
conductors and the dielectric black) and a box pixel filter; the two image means check that
both traced the same light transport. (Mitsuba's `irradiancemeter` would start paths on the
surfaces as the bake does, but it cannot be attached to the XML's multi-object OBJ shapes.)

Times: lustre bake's trace wall clock (its own timer) and the CPU time of its tracing, measured
as the CPU of the bake process minus the CPU of an identical second run that resumes every tile
(the same unwrap, set-up and assembly, no tracing); `lustre reference`: its render timer and
the CPU of the process (scene loading included); Mitsuba: the render's wall clock and CPU time
(`llvm_ad_rgb`'s kernel compilation done by a warm-up render outside). A bake sample also pays
for its validity test (4 probe rays per sample point and a visibility ray to the texel's
reference sample), which camera paths do not do.

Usage (from the repository root, after `cargo build --release -p lustre`):
  python3 scripts/bake_vs_mitsuba.py --density 8 --spp 64 --bounces 4 \
      --variants scalar_rgb,llvm_ad_rgb --out /tmp/bake_vs_mitsuba
"""

import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import time
import xml.etree.ElementTree as ET

import numpy as np

from hall_vs_mitsuba import HALL, reference_cmd


def children_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_lustre(args):
    out = os.path.join(args.out, "lustre")
    shutil.rmtree(out, ignore_errors=True)
    cmd = [
        args.lustre,
        "bake",
        f"{HALL}/mitsuba/scene.xml",
        "--out",
        out,
        "--spp",
        str(args.spp),
        "--bounces",
        str(args.bounces),
        "--texels-per-metre",
        str(args.density),
    ]
    c0, t0 = children_cpu(), time.time()
    first = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    wall, c1 = time.time() - t0, children_cpu()
    second = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    c2 = children_cpu()
    m = re.search(r"(\d+) texels, (\d+) paths, (\d+) invalid samples.*trace ([\d.]+) s", first)
    assert m, first
    assert "(0 baked" in second, second
    report = json.load(open(os.path.join(out, "bake.json")))
    return dict(
        name="lustre bake",
        texels=int(m.group(1)),
        paths=int(m.group(2)),
        invalid=int(m.group(3)),
        wall=float(m.group(4)),
        process_wall=wall,
        cpu=(c1 - c0) - (c2 - c1),
        mean=sum(p["mean_irradiance"] * p["covered_texels"] for p in report["pages"])
        / sum(p["covered_texels"] for p in report["pages"]),
    )


def diffuse_xml(max_depth):
    """The Modern Hall XML with every BSDF made diffuse as the bake does and the path
    integrator at max_depth = `max_depth`."""
    tree = ET.parse(f"{HALL}/mitsuba/scene.xml")
    root = tree.getroot()
    for b in root.iter("bsdf"):
        t = b.get("type")
        if t in ("roughplastic", "plastic"):
            kids = [c for c in b if c.get("name") in ("diffuseReflectance", "diffuse_reflectance")]
            for c in list(b):
                b.remove(c)
            b.set("type", "diffuse")
            for c in kids:
                c.set("name", "reflectance")
                b.append(c)
        elif t in ("roughconductor", "conductor", "dielectric", "roughdielectric", "thindielectric"):
            for c in list(b):
                b.remove(c)
            b.set("type", "diffuse")
            ET.SubElement(b, "rgb", name="reflectance", value="0")
    for i in root.findall("integrator"):
        root.remove(i)
    integ = ET.SubElement(root, "integrator", type="path")
    ET.SubElement(integ, "integer", name="maxDepth", value=str(max_depth))
    return root


def run_reference(args, w, h, spp):
    """`lustre reference --diffuse` of the same camera paths Mitsuba traces."""
    out = os.path.join(args.out, "lustre_reference.exr")
    cmd = reference_cmd(args.lustre, out, f"{w}x{h}", spp, args.bounces + 1, ["--diffuse"])
    c0 = children_cpu()
    subprocess.run(cmd, check=True, capture_output=True)
    cpu = children_cpu() - c0
    state = json.load(open(out[: -len("exr")] + "json"))
    return dict(
        name="lustre reference --diffuse (camera paths)",
        paths=w * h * spp,
        wall=state["seconds"],
        cpu=cpu,
        mean=state["mean"],
    )


def run_mitsuba(args, variant, w, h, spp):
    import mitsuba as mi

    mi.set_variant(variant)
    mi.file_resolver().prepend(os.path.abspath(f"{HALL}/mitsuba/"))
    root = diffuse_xml(args.bounces + 1)
    x = ET.tostring(root, encoding="unicode")
    x = re.sub(r'\s*<(string|boolean) name="(fileFormat|banner|high_quality_edges)"[^>]*/>', "", x)
    x = x.replace('value="1280"', f'value="{w}"').replace('value="720"', f'value="{h}"')
    x = re.sub(r'<rfilter[^>]*type="tent"[^>]*/>', '<rfilter type="box" />', x)
    scene = mi.load_string(x)
    if variant.startswith("llvm"):
        mi.render(scene, spp=2, seed=99)
    c0, t0 = time.process_time(), time.time()
    img = np.array(mi.render(scene, spp=spp, seed=1), dtype=np.float64)[..., :3]
    wall, cpu = time.time() - t0, time.process_time() - c0
    return dict(
        name=f"Mitsuba 3 {variant} (camera paths)",
        paths=w * h * spp,
        wall=wall,
        cpu=cpu,
        mean=float(img.mean()),
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--density", type=float, default=8)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--bounces", type=int, default=4)
    ap.add_argument("--variants", default="scalar_rgb")
    ap.add_argument("--camera-spp", type=int, default=64)
    ap.add_argument("--lustre", default="target/release/lustre")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    print(f"load before: {os.getloadavg()}")
    runs = [run_lustre(args)]
    # The same number of paths from the scene camera: a 16:9 film at `--camera-spp` samples.
    n = runs[0]["paths"]
    h = max(1, round((n / args.camera_spp * 9 / 16) ** 0.5))
    w = max(1, round(h * 16 / 9))
    spp = max(1, round(n / (w * h)))
    runs.append(run_reference(args, w, h, spp))
    for v in filter(None, args.variants.split(",")):
        runs.append(run_mitsuba(args, v, w, h, spp))
    print(f"load after: {os.getloadavg()}")
    l = runs[0]
    print(
        f"\nModern Hall, {args.density} texels/m, {args.spp} spp, {args.bounces} bounces: lustre "
        f"{l['texels']} texels, {l['paths']} valid paths ({l['invalid']} invalid samples), "
        f"process wall {l['process_wall']:.1f} s, mean E (luminance, valid texels) {l['mean']:.4f}. "
        f"Camera paths: {w}×{h}, {spp} spp, max depth {args.bounces + 1}, box filter.\n"
    )
    print("| tracer | paths | trace wall (s) | trace CPU (s) | paths / CPU-s | image mean |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in runs:
        mean = "" if r is l else f"{r['mean']:.5f}"
        print(
            f"| {r['name']} | {r['paths']} | {r['wall']:.2f} | {r['cpu']:.2f} | "
            f"{r['paths'] / max(r['cpu'], 1e-9):.0f} | {mean} |"
        )


if __name__ == "__main__":
    main()
