#!/usr/bin/env python3
"""Writes crate.glb: hprt's own glTF 2.0 sample (CC0, made by this script, deterministic).

A checkerboard-textured crate standing on a plain stepped plinth, turned by a node hierarchy:
root "sample" (translation), child "plinth" (a box), child "crate" (rotated 30 degrees about +Y,
scaled, lifted onto the plinth). The crate's base colour is a 64 x 64 sRGB PNG embedded in the
binary chunk; the plinth has a base colour factor only. Run: python3 make_sample_glb.py
"""
import json
import math
import struct
import zlib
from pathlib import Path


def png(width, height, rows):
    """An 8-bit RGB PNG from rows of bytes."""
    raw = b"".join(b"\0" + bytes(row) for row in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def checkerboard(size=64, cells=8):
    a, b = (214, 112, 48), (236, 226, 200)  # sRGB: orange and cream
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            row.extend(a if ((x * cells // size) + (y * cells // size)) % 2 == 0 else b)
        rows.append(row)
    return png(size, size, rows)


def box(lo, hi):
    """24 vertices (4 per face, own normals and uvs), 12 triangles, outward normals."""
    positions, normals, uvs, indices = [], [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = sign
            u_axis, v_axis = [(1, 2), (2, 0), (0, 1)][axis]
            base = len(positions)
            for (du, dv) in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0.0, 0.0, 0.0]
                p[axis] = hi[axis] if sign > 0 else lo[axis]
                p[u_axis] = hi[u_axis] if du else lo[u_axis]
                p[v_axis] = hi[v_axis] if dv else lo[v_axis]
                positions.append(p)
                normals.append(n)
                uvs.append([float(du), 1.0 - dv])
            # Counter-clockwise seen from outside: flip for the negative faces.
            quad = [0, 1, 2, 0, 2, 3] if sign > 0 else [0, 2, 1, 0, 3, 2]
            indices.extend(base + q for q in quad)
    return positions, normals, uvs, indices


class Builder:
    def __init__(self):
        self.bin = bytearray()
        self.views, self.accessors = [], []

    def view(self, data, target=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if target:
            view["target"] = target
        self.bin.extend(data)
        self.views.append(view)
        return len(self.views) - 1

    def floats(self, rows, kind):
        data = b"".join(struct.pack("<%df" % len(r), *r) for r in rows)
        accessor = {"bufferView": self.view(data, 34962), "componentType": 5126,
                    "count": len(rows), "type": kind}
        if kind == "VEC3":
            accessor["min"] = [min(r[i] for r in rows) for i in range(3)]
            accessor["max"] = [max(r[i] for r in rows) for i in range(3)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def indices(self, values):
        data = struct.pack("<%dH" % len(values), *values)
        self.accessors.append({"bufferView": self.view(data, 34963), "componentType": 5123,
                               "count": len(values), "type": "SCALAR"})
        return len(self.accessors) - 1

    def mesh(self, name, lo, hi, material):
        p, n, t, i = box(lo, hi)
        return {"name": name, "primitives": [{
            "attributes": {"POSITION": self.floats(p, "VEC3"), "NORMAL": self.floats(n, "VEC3"),
                           "TEXCOORD_0": self.floats(t, "VEC2")},
            "indices": self.indices(i), "material": material}]}


def main():
    b = Builder()
    meshes = [
        b.mesh("plinth", [-0.8, 0.0, -0.8], [0.8, 0.3, 0.8], 0),
        b.mesh("crate", [-0.5, 0.0, -0.5], [0.5, 1.0, 0.5], 1),
    ]
    image_view = b.view(checkerboard())
    half = math.radians(30.0) / 2
    document = {
        "asset": {"version": "2.0", "generator": "hprt scenes/models/make_sample_glb.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [
            {"name": "sample", "children": [1, 2], "translation": [0.0, 0.0, 0.0]},
            {"name": "plinth", "mesh": 0},
            {"name": "crate", "mesh": 1, "translation": [0.0, 0.3, 0.0],
             "rotation": [0.0, math.sin(half), 0.0, math.cos(half)], "scale": [0.9, 0.9, 0.9]},
        ],
        "meshes": meshes,
        "materials": [
            {"name": "stone", "pbrMetallicRoughness": {
                "baseColorFactor": [0.55, 0.55, 0.58, 1.0], "metallicFactor": 0.0}},
            {"name": "checker", "pbrMetallicRoughness": {
                "baseColorTexture": {"index": 0}, "metallicFactor": 0.0}},
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"magFilter": 9728, "minFilter": 9728}],
        "images": [{"bufferView": image_view, "mimeType": "image/png"}],
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": len(b.bin)}],
    }
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary = bytes(b.bin) + b"\0" * (-len(b.bin) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    out = (b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(text)) + b"JSON" + text
           + struct.pack("<I", len(binary)) + b"BIN\0" + binary)
    Path(__file__).with_name("crate.glb").write_bytes(out)


if __name__ == "__main__":
    main()
