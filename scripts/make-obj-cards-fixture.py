#!/usr/bin/env python3
"""Writes the OBJ cut-out fixtures into crates/shadowlab/assets/masked/: cards.obj with
cards.mtl, its Z-up twin cards-zup.obj, its glTF twin cards.gltf, and leaf-mask.png.

Two cards over a floor, both cut out by the leaf of leaf.png (written by
make-leaf-fixture.py):
- `leaf_d`: an upright card whose `map_d` is leaf-mask.png, a grey image (no alpha
  channel) whose grey level is leaf.png's alpha; its `map_Kd` is leaf.png, which `map_d`
  takes precedence over.
- `leaf_kd`: a tilted card with only `map_Kd leaf.png`, cut out by that image's alpha;
  its texture coordinates run to 2, so the leaf repeats 2 x 2 across it.

cards-zup.obj holds the same file written Z-up: each point (x, y, z) as (x, -z, y), which
`--up z` turns back to (x, y, z) exactly. cards.gltf holds the same triangles, in the same
order, as glTF MASK materials (alphaCutoff 0.5, REPEAT sampling) on leaf.png, the texture
coordinates' v turned to count from the image's top row (1 - v). None has a camera or a
light: each is framed and lit automatically, the same way. Standard library only; the
output is the same on every run."""

import base64
import json
import os
import struct
import zlib

SIDE = 64
HERE = os.path.dirname(__file__)
OUT = os.path.join(HERE, "..", "crates", "shadowlab", "assets", "masked")


def leaf_alpha(u, v):
    """make-leaf-fixture.py's leaf: 1 inside, 0 outside, at the texel centre (u, v)."""
    import math

    if not 0.05 < u < 0.95:
        return 0
    half = 0.38 * math.sin(math.pi * (u - 0.05) / 0.9)
    return 1 if abs(v - 0.5) < half else 0


def grey_png(width, height, rows):
    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes(row) for row in rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))


# (material, points, texture coordinates as OBJ writes them: v from the image's bottom)
FLOOR = ("floor", [(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)], None)
CARD_D = ("leaf_d", [(-2, 0.25, -0.5), (-0.25, 0.25, -0.5), (-0.25, 2, -0.5), (-2, 2, -0.5)],
          [(0, 0), (1, 0), (1, 1), (0, 1)])
CARD_KD = ("leaf_kd", [(0.25, 0.5, -1), (2.25, 0.5, -1), (2.25, 1.5, 1), (0.25, 1.5, 1)],
           [(0, 0), (2, 0), (2, 2), (0, 2)])
PARTS = [FLOOR, CARD_D, CARD_KD]


def num(x):
    return repr(float(x)).rstrip("0").rstrip(".") if x != 0 else "0"


def write_obj(name, turn):
    lines = ["# shadowlab test fixture (scripts/make-obj-cards-fixture.py)", "mtllib cards.mtl"]
    v = vt = 0
    for mat, points, uvs in PARTS:
        lines.append(f"o {mat}")
        for p in points:
            lines.append("v " + " ".join(num(c) for c in turn(p)))
        if uvs:
            for t in uvs:
                lines.append("vt " + " ".join(num(c) for c in t))
        lines.append(f"usemtl {mat}")
        if uvs:
            lines.append("f " + " ".join(f"{v + i + 1}/{vt + i + 1}" for i in range(4)))
            vt += 4
        else:
            lines.append("f " + " ".join(str(v + i + 1) for i in range(4)))
        v += 4
    with open(os.path.join(OUT, name), "w") as f:
        f.write("\n".join(lines) + "\n")


def write_mtl():
    text = """# shadowlab test fixture (scripts/make-obj-cards-fixture.py)
newmtl floor
Kd 0.75 0.75 0.72

newmtl leaf_d
Kd 0.2 0.55 0.2
map_Kd leaf.png
map_d leaf-mask.png

newmtl leaf_kd
Kd 0.2 0.55 0.2
map_Kd leaf.png
"""
    with open(os.path.join(OUT, "cards.mtl"), "w") as f:
        f.write(text)


def write_gltf():
    blob = b""
    views, accessors, primitives = [], [], []

    def add(data, target, count, kind, ctype, extra=None):
        nonlocal blob
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                      "target": target})
        accessors.append(dict({"bufferView": len(views) - 1, "componentType": ctype,
                               "count": count, "type": kind}, **(extra or {})))
        blob += data
        return len(accessors) - 1

    for m, (mat, points, uvs) in enumerate(PARTS):
        pos = add(b"".join(struct.pack("<3f", *p) for p in points), 34962, 4, "VEC3", 5126, {
            "min": [min(p[i] for p in points) for i in range(3)],
            "max": [max(p[i] for p in points) for i in range(3)]})
        attributes = {"POSITION": pos}
        if uvs:
            gl = [(u, 1 - v) for u, v in uvs]
            attributes["TEXCOORD_0"] = add(b"".join(struct.pack("<2f", *t) for t in gl),
                                           34962, 4, "VEC2", 5126)
        idx = add(struct.pack("<6H", 0, 1, 2, 0, 2, 3), 34963, 6, "SCALAR", 5123)
        primitives.append({"attributes": attributes, "indices": idx, "material": m})
    leaf = {"baseColorTexture": {"index": 0}, "metallicFactor": 0}
    doc = {
        "asset": {"version": "2.0", "generator": "shadowlab make-obj-cards-fixture.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": primitives}],
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.75, 0.75, 0.72, 1]}},
            {"name": "leaf_d", "alphaMode": "MASK", "pbrMetallicRoughness": leaf},
            {"name": "leaf_kd", "alphaMode": "MASK", "pbrMetallicRoughness": leaf},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "images": [{"uri": "leaf.png"}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    with open(os.path.join(OUT, "cards.gltf"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def main():
    rows = [[255 * leaf_alpha((i + 0.5) / SIDE, (j + 0.5) / SIDE) for i in range(SIDE)]
            for j in range(SIDE)]
    with open(os.path.join(OUT, "leaf-mask.png"), "wb") as f:
        f.write(grey_png(SIDE, SIDE, rows))
    write_mtl()
    write_obj("cards.obj", lambda p: p)
    write_obj("cards-zup.obj", lambda p: (p[0], -p[2], p[1]))
    write_gltf()


if __name__ == "__main__":
    main()
