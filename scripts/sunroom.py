#!/usr/bin/env python3
"""Writes scenes/sunroom/scene.xml: a 6 × 3 × 5 m room lit only by a sky through two windows
(one glazed with a thin glass pane, one open), with a glossy wooden floor, a silver mirror, a
gold sphere, a glossy picture and a glossy table block. A test interior for the automatic
real-time set-up: nothing in it carries a real-time hint.

    python3 scripts/sunroom.py [OUT.xml] [--site]

--site puts the room on a 2 km ground plane (scenes/sunroom/site.xml): an interior on a vast
site, whose free-space cells (1/24 of the scene's longest side) are far larger than the room.
"""
import sys

X0, X1, Y0, Y1, Z0, Z1 = -3.0, 3.0, 0.0, 3.0, -2.5, 2.5
ENV = "../../../shared/data/envmaps/venice_sunset_1k.hdr"


def rect(name, centre, u, v, bsdf, flip=False):
    """A rectangle spanning centre ± u ± v (Mitsuba's [-1,1]² in z=0 mapped by a matrix)."""
    n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    ln = sum(c * c for c in n) ** 0.5
    n = tuple(c / ln for c in n)
    if flip:
        n = tuple(-c for c in n)
        u = tuple(-c for c in u)
    m = [u[0], v[0], n[0], centre[0],
         u[1], v[1], n[1], centre[1],
         u[2], v[2], n[2], centre[2],
         0, 0, 0, 1]
    vals = " ".join(f"{x:g}" for x in m)
    return (f'  <shape type="rectangle" id="{name}">\n'
            f'    <transform name="to_world"><matrix value="{vals}"/></transform>\n'
            f'    <ref id="{bsdf}"/>\n  </shape>\n')


def box(name, lo, hi, bsdf):
    c = [(a + b) / 2 for a, b in zip(lo, hi)]
    s = [(b - a) / 2 for a, b in zip(lo, hi)]
    return (f'  <shape type="cube" id="{name}">\n'
            f'    <transform name="to_world"><scale x="{s[0]:g}" y="{s[1]:g}" z="{s[2]:g}"/>'
            f'<translate x="{c[0]:g}" y="{c[1]:g}" z="{c[2]:g}"/></transform>\n'
            f'    <ref id="{bsdf}"/>\n  </shape>\n')


def wall_with_hole(prefix, axis_pos, hole, bsdf, facing):
    """A wall on plane z = axis_pos (facing ±z) or x = axis_pos, as 4 rectangles around `hole`
    = (a0, a1, y0, y1) in the wall's horizontal coordinate a and height y."""
    a0, a1, y0, y1 = hole
    out = []
    if facing in ("+z", "-z"):
        lo, hi = X0, X1
    else:
        lo, hi = Z0, Z1
    parts = [
        (lo, a0, Y0, Y1), (a1, hi, Y0, Y1),  # left, right of the hole
        (a0, a1, Y0, y0), (a0, a1, y1, Y1),  # below, above
    ]
    for i, (p0, p1, q0, q1) in enumerate(parts):
        ca, cy = (p0 + p1) / 2, (q0 + q1) / 2
        ha, hy = (p1 - p0) / 2, (q1 - q0) / 2
        if facing == "+z":
            out.append(rect(f"{prefix}{i}", (ca, cy, axis_pos), (ha, 0, 0), (0, hy, 0), bsdf))
        elif facing == "-x":
            out.append(rect(f"{prefix}{i}", (axis_pos, cy, ca), (0, 0, ha), (0, hy, 0), bsdf))
    return "".join(out)


def main():
    args = [a for a in sys.argv[1:] if a != "--site"]
    site = "--site" in sys.argv[1:]
    out = args[0] if args else "scenes/sunroom/scene.xml"
    x = ['<?xml version="1.0" encoding="utf-8"?>\n<!-- written by scripts/sunroom.py' + (' (site)' if site else '') + ' -->\n'
         '<scene version="3.0.0">\n']
    x.append('''  <bsdf type="twosided" id="Plaster"><bsdf type="diffuse"><rgb name="reflectance" value="0.72, 0.70, 0.66"/></bsdf></bsdf>
  <bsdf type="twosided" id="Oak"><bsdf type="roughplastic"><float name="alpha" value="0.06"/><string name="distribution" value="ggx"/><rgb name="diffuse_reflectance" value="0.42, 0.24, 0.11"/></bsdf></bsdf>
  <bsdf type="conductor" id="Silver"><string name="material" value="Ag"/></bsdf>
  <bsdf type="roughconductor" id="Gold"><string name="material" value="Au"/><float name="alpha" value="0.15"/></bsdf>
  <bsdf type="thindielectric" id="Pane"><float name="int_ior" value="1.5"/></bsdf>
  <bsdf type="twosided" id="Lacquer"><bsdf type="roughplastic"><float name="alpha" value="0.12"/><rgb name="diffuse_reflectance" value="0.10, 0.30, 0.45"/></bsdf></bsdf>
  <bsdf type="twosided" id="Walnut"><bsdf type="roughplastic"><float name="alpha" value="0.25"/><rgb name="diffuse_reflectance" value="0.20, 0.11, 0.06"/></bsdf></bsdf>
''')
    # Floor and ceiling.
    x.append(rect("Floor", (0, Y0, 0), (3, 0, 0), (0, 0, -2.5), "Oak"))
    x.append(rect("Ceiling", (0, Y1, 0), (3, 0, 0), (0, 0, 2.5), "Plaster"))
    # North wall (z = Z0, facing +z) with a glazed window; east wall (x = X1, facing -x) with an
    # open one; west and south walls whole.
    x.append(wall_with_hole("NorthWall", Z0, (-1.5, 1.5, 0.8, 2.4), "Plaster", "+z"))
    x.append(wall_with_hole("EastWall", X1, (-1.0, 1.0, 1.0, 2.2), "Plaster", "-x"))
    x.append(rect("WestWall", (X0, 1.5, 0), (0, 0, -2.5), (0, 1.5, 0), "Plaster"))
    x.append(rect("SouthWall", (0, 1.5, Z1), (-3, 0, 0), (0, 1.5, 0), "Plaster"))
    # The glass pane in the north window, 5 cm inside the opening.
    x.append(rect("WindowPane", (0, 1.6, Z0 + 0.05), (1.5, 0, 0), (0, 0.8, 0), "Pane"))
    # A mirror on the west wall, a glossy picture on the south wall.
    x.append(rect("Mirror", (X0 + 0.01, 1.4, 0.3), (0, 0, -0.6), (0, 0.8, 0), "Silver"))
    x.append(rect("Picture", (-0.8, 1.6, Z1 - 0.01), (-0.5, 0, 0), (0, 0.35, 0), "Lacquer"))
    # A gold sphere on the floor and a walnut block.
    x.append('''  <shape type="sphere" id="GoldSphere">
    <point name="center" x="1.1" y="0.4" z="0.4"/><float name="radius" value="0.4"/>
    <ref id="Gold"/>
  </shape>
''')
    x.append(box("Table", (-1.4, 0.0, -0.2), (-0.4, 0.7, 0.4), "Walnut"))
    if site:
        x.append('  <bsdf type="diffuse" id="Gravel"><rgb name="reflectance" value="0.30, 0.28, 0.25"/></bsdf>\n')
        x.append(rect("Ground", (0, Y0 - 0.05, 0), (1000, 0, 0), (0, 0, -1000), "Gravel"))
    x.append(f'''  <emitter type="envmap">
    <string name="filename" value="{ENV}"/>
    <float name="scale" value="1.0"/>
  </emitter>
  <sensor type="perspective">
    <float name="fov" value="70"/>
    <transform name="to_world"><lookat origin="2.4, 1.55, 2.2" target="-1.0, 0.9, -1.4" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="320"/><integer name="height" value="240"/></film>
  </sensor>
</scene>
''')
    with open(out, "w") as f:
        f.write("".join(x))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
