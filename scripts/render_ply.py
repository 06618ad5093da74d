#!/usr/bin/env python3
"""Renders a triangle mesh PLY to a PNG, headless, with nothing but the Python standard library:
an orthographic z-buffer with flat shading (a head light), per-face colours when the PLY has them,
and optionally the triangle edges. Made for the pictures in docs/ (cluster colourings, coarse
meshes); meshlabserver has no snapshot filter.

  render_ply.py IN.ply OUT.png [--size 480] [--azimuth 0] [--elevation 0] [--edges] [--supersample 2]

The view looks along -Z of the model rotated by azimuth (about Y) then elevation (about X), in
degrees; the model is framed to fill the image.
"""
import argparse
import math
import os
import struct
import sys
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from meshdata import read_ply_elements  # noqa: E402


def read_ply(path):
    """The mesh's vertex positions, its faces as triangles (polygons fanned) and, when every face
    has one, each triangle's colour (else None)."""
    verts, faces, colors = [], [], []
    for name, records in read_ply_elements(path):
        if name == "vertex":
            verts = [(r["x"], r["y"], r["z"]) for r in records]
        elif name == "face":
            for rec in records:
                idx = rec.get("vertex_indices", rec.get("vertex_index"))
                for k in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[k], idx[k + 1]))
                    if "red" in rec:
                        colors.append((rec["red"], rec["green"], rec["blue"]))
    return verts, faces, colors if len(colors) == len(faces) else None


def write_png(path, width, height, rgb):
    raw = b"".join(b"\x00" + bytes(rgb[y * width * 3:(y + 1) * width * 3]) for y in range(height))

    def chunk(kind, data):
        c = struct.pack(">I", len(data)) + kind + data
        return c + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--size", type=int, default=480)
    ap.add_argument("--azimuth", type=float, default=0)
    ap.add_argument("--elevation", type=float, default=0)
    ap.add_argument("--edges", action="store_true", help="darken the triangle edges")
    ap.add_argument("--supersample", type=int, default=2)
    a = ap.parse_args()

    verts, faces, colors = read_ply(a.input)
    az, el = math.radians(a.azimuth), math.radians(a.elevation)
    ca, sa, ce, se = math.cos(az), math.sin(az), math.cos(el), math.sin(el)

    def view(p):  # rotate about Y by azimuth, then about X by elevation
        x, y, z = p
        x, z = ca * x + sa * z, -sa * x + ca * z
        y, z = ce * y - se * z, se * y + ce * z
        return x, y, z
    used = set(i for f in faces for i in f)
    pv = [view(p) for p in verts]
    xs = [pv[i][0] for i in used]
    ys = [pv[i][1] for i in used]
    cx, cy = (min(xs) + max(xs)) / 2, (min(ys) + max(ys)) / 2
    extent = max(max(xs) - min(xs), max(ys) - min(ys)) * 1.04
    S = a.size * a.supersample
    scale = S / extent
    sp = [((x - cx) * scale + S / 2, S / 2 - (y - cy) * scale, z) for x, y, z in pv]

    zbuf = [-1e300] * (S * S)
    img = [255] * (S * S * 3)
    for fi, (i0, i1, i2) in enumerate(faces):
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = sp[i0], sp[i1], sp[i2]
        # Normal in view space (y down on screen, so flip it back).
        p0, p1, p2 = pv[i0], pv[i1], pv[i2]
        ux, uy, uz = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
        vx, vy, vz = p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        ln = math.sqrt(nx * nx + ny * ny + nz * nz)
        shade = 0.25 + 0.75 * (abs(nz) / ln if ln > 0 else 0.0)
        if nz < 0:
            shade *= 0.6  # back faces darker
        base = colors[fi] if colors else (200, 200, 200)
        col = tuple(min(255, int(c * shade)) for c in base)
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if area == 0:
            continue
        minx, maxx = max(0, int(min(x0, x1, x2))), min(S - 1, int(max(x0, x1, x2)) + 1)
        miny, maxy = max(0, int(min(y0, y1, y2))), min(S - 1, int(max(y0, y1, y2)) + 1)
        edge_w = 1.2 * a.supersample  # pixels
        for py in range(miny, maxy + 1):
            fy = py + 0.5
            for px in range(minx, maxx + 1):
                fx = px + 0.5
                w0 = ((x1 - fx) * (y2 - fy) - (x2 - fx) * (y1 - fy)) / area
                w1 = ((x2 - fx) * (y0 - fy) - (x0 - fx) * (y2 - fy)) / area
                w2 = 1 - w0 - w1
                if w0 < 0 or w1 < 0 or w2 < 0:
                    continue
                z = w0 * z0 + w1 * z1 + w2 * z2
                k = py * S + px
                if z <= zbuf[k]:
                    continue
                zbuf[k] = z
                c = col
                if a.edges:
                    # Distance to the nearest edge in pixels: barycentric / gradient length.
                    d = min(w0 * abs(area) / math.hypot(x2 - x1, y2 - y1),
                            w1 * abs(area) / math.hypot(x0 - x2, y0 - y2),
                            w2 * abs(area) / math.hypot(x1 - x0, y1 - y0))
                    if d < edge_w:
                        c = (int(c[0] * 0.35), int(c[1] * 0.35), int(c[2] * 0.35))
                img[3 * k:3 * k + 3] = c
    n = a.supersample
    W = a.size
    out = [0] * (W * W * 3)
    for y in range(W):
        for x in range(W):
            for ch in range(3):
                s = 0
                for dy in range(n):
                    row = (y * n + dy) * S
                    for dx in range(n):
                        s += img[3 * (row + x * n + dx) + ch]
                out[3 * (y * W + x) + ch] = s // (n * n)
    write_png(a.output, W, W, out)


if __name__ == "__main__":
    main()
