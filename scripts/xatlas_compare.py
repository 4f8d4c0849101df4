#!/usr/bin/env python3
"""Unwraps the meshes that `unwrap_compare --dump DIR` wrote with xatlas (the Python bindings,
`pip install xatlas`), at the same texel density and gutter, and writes the result as OBJ files
with light-map UVs for `unwrap_compare --xatlas DIR`, which measures them with the same code as
lustre's own atlases (charts, utilisation, density, stretch, layout check at page resolution).

    python3 scripts/xatlas_compare.py DIR

For each DIR/NAME.obj it writes DIR/NAME.xatlas.obj: a header line
`# xatlas width W height H atlases A charts C time_s T padding P`, then per object `o NAME`,
`v` (positions, split at seams), `vt` (u, 1 - v: OBJ's v points up) and `f v/vt`.

xatlas `padding` adds that many texels around each chart; charts end up at least `padding`
texels apart. The gutter asked for is used as the padding; `unwrap_compare` measures the
distance actually achieved.
"""

import sys
import time
from pathlib import Path

import numpy as np
import xatlas


def read_obj(path):
    header = {}
    objects = []  # (name, positions, faces)
    pos, faces, name, base = [], [], None, 0
    all_pos = []
    with open(path) as f:
        for line in f:
            if line.startswith("# texels_per_metre"):
                t = line.split()
                header = {"density": float(t[2]), "gutter": int(t[4])}
            elif line.startswith("o "):
                if name is not None:
                    objects.append((name, np.array(pos, np.float32), np.array(faces, np.uint32)))
                    base += len(pos)
                name, pos, faces = line[2:].strip(), [], []
            elif line.startswith("v "):
                pos.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                faces.append([int(x) - 1 - base for x in line.split()[1:4]])
    if name is not None:
        objects.append((name, np.array(pos, np.float32), np.array(faces, np.uint32)))
    return header, objects


def main():
    folder = Path(sys.argv[1])
    for obj in sorted(folder.glob("*.obj")):
        if obj.name.endswith(".xatlas.obj"):
            continue
        header, objects = read_obj(obj)
        atlas = xatlas.Atlas()
        for _, p, f in objects:
            atlas.add_mesh(p, f)
        pack = xatlas.PackOptions()
        pack.texels_per_unit = header["density"]
        pack.padding = header["gutter"]
        pack.resolution = 0
        t0 = time.perf_counter()
        atlas.generate(pack_options=pack)
        dt = time.perf_counter() - t0
        out = obj.with_name(obj.stem + ".xatlas.obj")
        with open(out, "w") as f:
            f.write(
                f"# xatlas width {atlas.width} height {atlas.height} atlases {atlas.atlas_count} "
                f"charts {atlas.chart_count} time_s {dt:.4f} padding {pack.padding}\n"
            )
            vbase = 1
            for i, (name, p, _) in enumerate(objects):
                vmap, idx, uv = atlas.get_mesh(i)
                f.write(f"o {name}\n")
                for k in range(len(vmap)):
                    q = p[vmap[k]]
                    f.write(f"v {float(q[0])!r} {float(q[1])!r} {float(q[2])!r}\n")
                for k in range(len(vmap)):
                    f.write(f"vt {float(uv[k][0])!r} {1.0 - float(uv[k][1])!r}\n")
                for t in idx.reshape(-1, 3):
                    a, b, c = (int(x) + vbase for x in t)
                    f.write(f"f {a}/{a} {b}/{b} {c}/{c}\n")
                vbase += len(vmap)
        print(f"{obj.stem}: {atlas.width}x{atlas.height}, {atlas.chart_count} charts, {dt:.3f} s")


if __name__ == "__main__":
    main()
