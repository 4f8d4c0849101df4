"""Renders a Mitsuba 3 scene file (one `lustre export scene --to mitsuba` wrote) with Mitsuba
itself, to compare with `lustre reference`.

    python3 render_scene.py SCENE.xml OUT.exr [--size WxH] [--spp N] [--variant V] [--seed S]

Writes OUT.exr (linear RGB float) and prints one JSON line: { file, variant, size, spp,
seconds }. --size and --spp set the scene's `resx`/`resy`/`spp` defaults.
"""
import argparse
import json
import time

import mitsuba as mi

ap = argparse.ArgumentParser()
ap.add_argument("scene")
ap.add_argument("out")
ap.add_argument("--size")
ap.add_argument("--spp", type=int)
ap.add_argument("--variant", default="scalar_rgb")
ap.add_argument("--seed", type=int, default=0)
a = ap.parse_args()
mi.set_variant(a.variant)
params = {}
if a.size:
    w, h = (int(x) for x in a.size.split("x"))
    params.update(resx=w, resy=h)
if a.spp:
    params["spp"] = a.spp
scene = mi.load_file(a.scene, **params)
t = time.time()
img = mi.render(scene, seed=a.seed)
seconds = time.time() - t
mi.Bitmap(img).write(a.out)
print(json.dumps({"file": a.out, "variant": a.variant, "size": a.size, "spp": a.spp,
                  "seconds": round(seconds, 2)}))
