#!/usr/bin/env python3
"""Writes the committed seed corpus fuzz/seeds/<target>/ (small valid inputs per target).

Run from the repository root with the shared data beside it:
    python3 fuzz/make_seeds.py [../shared/data]
The seeds are derived from real files (a few rows of an ALTA table and of the published fit
table, one network of the MERL NBRDF set, a reduced RGL tensor file) or written by hand (a
Radiance HDR, a goniometric table, material JSON, the splice templates of the EXR and MERL
targets). Every seed parses as valid input of its target (checked by the seeds test in
crates/lustre-brdf/tests/fuzz_seeds.rs).
"""
import json, os, struct, sys

data = sys.argv[1] if len(sys.argv) > 1 else "../shared/data"
root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "seeds")


def put(target, name, content):
    d = os.path.join(root, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(content if isinstance(content, bytes) else content.encode())


# alta: the header and 40 rows of a real CEA table (the target supplies the unit).
lines = open(os.path.join(data, "measured/goniometric/retro-gray-tape.dat")).read().splitlines()
head = [l for l in lines if l.startswith("#")]
rows = [l for l in lines if l and not l.startswith("#")]
# (the real file has no PARAM_OUT line, which the target requires: the seed adds one)
put("alta", "gray-tape-inv-sr.dat", "\n".join(head + ["#PARAM_OUT INV_STERADIAN"] + rows[:20]) + "\n")

# fit_csv: the header and two rows of each published table.
for f in ["merl_sgd_fits_bagher2012.csv", "merl_abc_fits_low2012.csv", "merl_lafortune_fits_ngan2005.csv"]:
    l = open(os.path.join(data, "fits", f)).read().splitlines()
    put("fit_csv", f, "\n".join(l[:3]) + "\n")

# nbrdf: one real network in its own file.
full = json.load(open(os.path.join(data, "nbrdf/merl_nbrdf.json")))
one = {k: v for k, v in full.items() if k != "materials"}
one["materials"] = {"nickel": full["materials"]["nickel"]}
put("nbrdf", "nickel.json", json.dumps(one))

# hdr: an 8x4 flat RGBE map.
px = b"".join(struct.pack("4B", 128, 64 + i, 32, 129) for i in range(32))
put("hdr", "flat-8x4.hdr", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n" + px)

# exr: odd first byte = the target's built-in 8x4 ZIP file, spliced at offset 2*second byte.
put("exr", "template", b"\x01\x00")
put("exr", "template-channels", b"\x01\x08RGB")

# merl: odd first byte = a full-size table with the default header and this value repeated.
put("merl", "constant", b"\x01" + b"\x00" * 12 + struct.pack("<d", 1.0))
put("merl", "two-values", b"\x01" + b"\x00" * 12 + struct.pack("<dd", 0.5, 2.0))
put("merl", "unmeasured", b"\x01" + b"\x00" * 12 + struct.pack("<dd", -1.0, 2.0))

# gonio: a small isotropic table (2 x 1 x 4 x 4 grid).
g = ["#lustre-gonio 1", "#units brdf", "#angles degrees", "#name seed",
     "#theta_i 0 45", "#phi_i 0", "#theta_o 0 30 60 90", "#phi_o 0 90 180 270"]
for ti in [0, 45]:
    for to in [0, 30, 60, 90]:
        for po in [0, 90, 180, 270]:
            g.append(f"{ti} 0 {to} {po} {0.3 + 0.01 * to}")
put("gonio", "small.gonio", "\n".join(g) + "\n")

# material: a Kurt and a Cook-Torrance material file.
put("material", "kurt.json", json.dumps({
    "schema": "lustre-material", "version": 1, "name": "seed",
    "model": {"type": "kurt", "kd": [0.1, 0.2, 0.3],
              "reflection": [{"ks": [0.6, 0.4, 0.2], "mx": 0.1, "my": 0.1, "r0": 0.9, "alpha": 0.0}],
              "transmission": []}}, indent=1))

# rgl: a real RGL file reduced to 2 incident elevations and coarser grids (the structure
# checks of the reader hold: shapes agree across fields).
b = open(os.path.join(data, "measured/rgl/paper_white_rgb.bsdf"), "rb").read()
o = 14
n, = struct.unpack_from("<I", b, o); o += 4
fields = []
for _ in range(n):
    l, = struct.unpack_from("<H", b, o); o += 2
    name = b[o:o + l].decode(); o += l
    nd, = struct.unpack_from("<H", b, o); o += 2
    dt = b[o]; o += 1
    off, = struct.unpack_from("<Q", b, o); o += 8
    shape = list(struct.unpack_from("<%dQ" % nd, b, o)); o += 8 * nd
    size = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 8, 8: 8, 9: 2, 10: 4, 11: 8}[dt]
    cnt = 1
    for s in shape:
        cnt *= s
    fields.append([name, dt, shape, b[off:off + cnt * size], size])


def reshape_slice(raw, size, shape, keep):
    """keep: per axis, the list of indices to keep."""
    import itertools
    strides = [1] * len(shape)
    for i in range(len(shape) - 2, -1, -1):
        strides[i] = strides[i + 1] * shape[i + 1]
    out = bytearray()
    for idx in itertools.product(*keep):
        k = sum(i * s for i, s in zip(idx, strides))
        out += raw[k * size:(k + 1) * size]
    return bytes(out)


nt = 2  # incident elevations kept
for f in fields:
    name, dt, shape, raw, size = f
    if name == "theta_i":
        keep = [list(range(nt))]
    elif name in ("vndf",):
        keep = [range(shape[0]), range(nt), range(0, shape[2], 8), range(0, shape[3], 8)]
    elif name in ("luminance",):
        keep = [range(shape[0]), range(nt), range(0, shape[2], 4), range(0, shape[3], 4)]
    elif name == "rgb":
        keep = [range(shape[0]), range(nt), range(3), range(0, shape[3], 4), range(0, shape[4], 4)]
    elif name == "valid":
        side = int(round(shape[0] ** 0.5))
        keep2 = [(r * side + c) for r in range(0, side, 4) for c in range(0, side, 4)]
        f[3] = bytes(raw[k] for k in keep2)
        f[2] = [len(keep2)]
        continue
    else:
        continue
    f[3] = reshape_slice(raw, size, shape, [list(k) for k in keep])
    f[2] = [len(list(k)) for k in keep]

hdr = bytearray(b"tensor_file\0" + bytes([1, 0]) + struct.pack("<I", len(fields)))
hdr_len = len(hdr) + sum(2 + len(f[0]) + 2 + 1 + 8 + 8 * len(f[2]) for f in fields)
off = (hdr_len + 7) // 8 * 8
body = bytearray()
for name, dt, shape, raw, size in fields:
    hdr += struct.pack("<H", len(name)) + name.encode() + struct.pack("<HBQ", len(shape), dt, off + len(body))
    hdr += struct.pack("<%dQ" % len(shape), *shape)
    body += raw
    while len(body) % 8:
        body += b"\0"
put("rgl", "paper-white-reduced.bsdf", bytes(hdr) + b"\0" * (off - len(hdr)) + bytes(body))
print("seeds written to", root)
