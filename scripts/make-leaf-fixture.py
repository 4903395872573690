#!/usr/bin/env python3
"""Writes crates/shadowlab/assets/masked/leaf.gltf and leaf.png: an alpha-masked leaf quad
over a ground plane, for shadowlab's tests of alpha-masked casters and orthographic cameras.

The quad (y = 1, x and z in [-1, 1]) has alphaMode MASK with alphaCutoff 0.5 and a 64x64
texture whose alpha is 255 inside a leaf outline and 0 elsewhere, so its four corners are
cut out. A directional KHR_lights_punctual light shines down at a slant; camera 0 is a
perspective camera, camera 1 an orthographic one. Standard library only; the output is the
same on every run. The tests keep `leaf_alpha` below in step with their own copy."""

import base64
import json
import math
import os
import struct
import zlib

SIDE = 64


def leaf_alpha(u, v):
    """1 inside the leaf (a lens along u), 0 outside: the texel centre (u, v) decides."""
    if not 0.05 < u < 0.95:
        return 0
    half = 0.38 * math.sin(math.pi * (u - 0.05) / 0.9)
    return 1 if abs(v - 0.5) < half else 0


def png(width, height, rgba_rows):
    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + bytes(row) for row in rgba_rows)
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9))
            + chunk(b"IEND", b""))


def basis_matrix(eye, forward):
    """A column-major node matrix at `eye` whose -Z is `forward` and +Y is as up as can be."""
    f = normalize(forward)
    z = [-c for c in f]
    up = [0.0, 1.0, 0.0] if abs(f[1]) < 0.99 else [0.0, 0.0, -1.0]
    x = normalize(cross(up, z))
    y = cross(z, x)
    return x + [0.0] + y + [0.0] + z + [0.0] + list(eye) + [1.0]


def normalize(a):
    n = math.sqrt(sum(c * c for c in a))
    return [c / n for c in a]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def main():
    out = os.path.join(os.path.dirname(__file__), "..", "crates", "shadowlab", "assets", "masked")
    rows = []
    for j in range(SIDE):
        row = []
        for i in range(SIDE):
            a = leaf_alpha((i + 0.5) / SIDE, (j + 0.5) / SIDE)
            row += [40, 140, 50, 255 * a]
        rows.append(row)
    with open(os.path.join(out, "leaf.png"), "wb") as f:
        f.write(png(SIDE, SIDE, rows))

    g = 3.0
    positions = [
        (-g, 0, -g), (-g, 0, g), (g, 0, g), (g, 0, -g),    # ground
        (-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1),    # leaf quad
    ]
    uvs = [(0, 0), (0, 1), (1, 1), (1, 0)]                 # u along x, v along z
    indices = [0, 1, 2, 0, 2, 3]
    pos_bytes = b"".join(struct.pack("<3f", *p) for p in positions)
    uv_bytes = b"".join(struct.pack("<2f", *t) for t in uvs)
    idx_bytes = b"".join(struct.pack("<H", i) for i in indices)
    blob = pos_bytes + uv_bytes + idx_bytes
    views = [
        {"buffer": 0, "byteOffset": 0, "byteLength": 48},
        {"buffer": 0, "byteOffset": 48, "byteLength": 48},
        {"buffer": 0, "byteOffset": 96, "byteLength": 32},
        {"buffer": 0, "byteOffset": 128, "byteLength": 12},
    ]
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [-g, 0, -g], "max": [g, 0, g]},
        {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3",
         "min": [-1, 1, -1], "max": [1, 1, 1]},
        {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
    ]
    light_dir = normalize([0.3, -1.0, 0.2])
    doc = {
        "asset": {"version": "2.0", "generator": "shadowlab scripts/make-leaf-fixture.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional"}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
        "nodes": [
            {"mesh": 0, "name": "ground"},
            {"mesh": 1, "name": "leaf"},
            {"extensions": {"KHR_lights_punctual": {"light": 0}},
             "matrix": basis_matrix([0, 5, 0], light_dir)},
            {"camera": 0, "matrix": basis_matrix([0.5, 4.0, 4.0], [-0.5, -4.0, -4.0])},
            {"camera": 1, "matrix": basis_matrix([0.5, 5.0, 3.0], [-0.5, -5.0, -3.0])},
        ],
        "cameras": [
            {"type": "perspective",
             "perspective": {"yfov": 0.7, "aspectRatio": 1.3333, "znear": 0.1, "zfar": 30}},
            {"type": "orthographic",
             "orthographic": {"xmag": 3.2, "ymag": 2.4, "znear": 0.1, "zfar": 30}},
        ],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 3, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 1, "TEXCOORD_0": 2}, "indices": 3,
                             "material": 1}]},
        ],
        "materials": [
            {"name": "ground", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.65, 1]}},
            {"name": "leaf", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": [{"uri": "leaf.png"}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64,"
                            + base64.b64encode(blob).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    with open(os.path.join(out, "leaf.gltf"), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
