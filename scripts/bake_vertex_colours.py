#!/usr/bin/env python3
"""Bakes a textured mesh's texture into per-vertex colour (python3 standard library only): each
vertex takes the texture's colour at its texture coordinates (bilinear), and the vertices at one
position take the mean of theirs, so that the result has no colour seam. Writes a binary PLY with
x y z and uchar red green blue per vertex and the faces as they are.

  bake_vertex_colours.py IN.ply TEXTURE.ppm OUT.ply [--comment TEXT]...

The vertices at one position become one (the texture's seams are no seams of the colour).

IN.ply: per-vertex texture_u/texture_v (as scripts/gltf_to_ply.py writes); TEXTURE.ppm: binary
P6, 8 bit (`convert texture.jpg texture.ppm`).
"""
import argparse
import math
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from meshdata import read_ply_elements  # noqa: E402


def read_ppm(path):
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:
        while data[pos:pos + 1].isspace():
            pos += 1
        start = pos
        while not data[pos:pos + 1].isspace():
            pos += 1
        fields.append(data[start:pos])
    if fields[0] != b"P6" or int(fields[3]) != 255:
        sys.exit("%s: not an 8-bit binary PPM" % path)
    return int(fields[1]), int(fields[2]), data[pos + 1:]


def sample(image, u, v):
    w, h, rgb = image
    x = (u - math.floor(u)) * w - 0.5
    y = (1 - (v - math.floor(v))) * h - 0.5
    x0, y0 = math.floor(x), math.floor(y)
    fx, fy = x - x0, y - y0
    c = [0.0, 0.0, 0.0]
    for dy in (0, 1):
        for dx in (0, 1):
            xi, yi = (x0 + dx) % w, (y0 + dy) % h
            wgt = (fx if dx else 1 - fx) * (fy if dy else 1 - fy)
            at = 3 * (yi * w + xi)
            for k in range(3):
                c[k] += wgt * rgb[at + k]
    return c


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("texture")
    ap.add_argument("out")
    ap.add_argument("--comment", action="append", default=[])
    a = ap.parse_args()
    image = read_ppm(a.texture)
    verts, faces = [], []
    for name, records in read_ply_elements(a.mesh):
        if name == "vertex":
            verts = records
        elif name == "face":
            faces = [r["vertex_indices"] for r in records]
    total = {}
    for v in verts:
        key = (v["x"], v["y"], v["z"])
        c = sample(image, v["texture_u"], v["texture_v"])
        s = total.setdefault(key, [0.0, 0.0, 0.0, 0])
        for k in range(3):
            s[k] += c[k]
        s[3] += 1
    # One vertex per position (numbered by first use): what a scanner's coloured mesh has.
    index, order = {}, []
    for v in verts:
        key = (v["x"], v["y"], v["z"])
        if key not in index:
            index[key] = len(order)
            order.append(key)
    header = ["ply", "format binary_little_endian 1.0"] + ["comment %s" % c for c in a.comment]
    header += ["element vertex %d" % len(order)] + ["property float %s" % p for p in "xyz"]
    header += ["property uchar red", "property uchar green", "property uchar blue"]
    header += ["element face %d" % len(faces), "property list uchar int vertex_indices", "end_header"]
    with open(a.out, "wb") as f:
        f.write(("\n".join(header) + "\n").encode())
        for key in order:
            s = total[key]
            rgb = [min(255, max(0, round(s[k] / s[3]))) for k in range(3)]
            f.write(struct.pack("<3f3B", key[0], key[1], key[2], *rgb))
        for t in faces:
            f.write(struct.pack("<B3i", 3, *[index[(verts[i]["x"], verts[i]["y"], verts[i]["z"])] for i in t]))


if __name__ == "__main__":
    main()
