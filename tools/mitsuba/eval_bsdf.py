"""Evaluates the BSDF of a Mitsuba 3 XML file that lustre exported, with Mitsuba itself.

    python3 eval_bsdf.py FILE.xml < pairs.json

stdin: a JSON list of [wi, wo] pairs (unit vectors in the local frame, z up; wi towards the
light, wo towards the viewer, as lustre's Bsdf::eval). stdout: a JSON list of RGB values f(wi, wo),
without the cosine Mitsuba's eval includes. Uses the scalar_rgb variant.
"""
import json
import re
import sys

import mitsuba as mi

mi.set_variant("scalar_rgb")
path = sys.argv[1]
text = open(path, encoding="utf-8").read()
m = re.search(r"<bsdf\b.*?</bsdf>", text, re.S)
if m is None:
    sys.exit(f"{path}: no <bsdf> element")
bsdf_xml = m.group(0).replace("<bsdf ", '<bsdf version="3.0.0" ', 1)
# A measured BSDF names its file relative to the XML.
mi.file_resolver().prepend(str(mi.filesystem.path(path).parent_path()))
bsdf = mi.load_string(bsdf_xml)
ctx = mi.BSDFContext()
out = []
for wi, wo in json.load(sys.stdin):
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wo)  # Mitsuba's wi points to the viewer
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    value = bsdf.eval(ctx, si, mi.Vector3f(*wi))
    cos = wi[2]
    out.append([float(value[c]) / cos if cos > 0 else 0.0 for c in range(3)])
json.dump(out, sys.stdout)
