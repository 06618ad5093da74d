#!/usr/bin/env python3
"""Renders a triangle PLY with its per-face colours (e.g. ConeLOD's group colours) to a PNG:
orthographic view, flat Lambert shading, z-buffer, optional wireframe. Python 3 standard library
only (no numpy), for the pictures in docs/.

  render_ply.py IN.ply OUT.png [--size 480] [--yaw 0] [--pitch 0] [--wire] [--title TEXT]
"""
import argparse
import math
import struct
import sys
import zlib

SIZES = {"char": "b", "uchar": "B", "int8": "b", "uint8": "B", "short": "h", "ushort": "H", "int": "i",
         "int32": "i", "uint": "I", "uint32": "I", "float": "f", "float32": "f", "double": "d", "float64": "d"}


def read_ply(path):
    """Vertices [(x,y,z)], faces [[i,j,k]], face colours [(r,g,b)] or None."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            header.append(line)
            if line == "end_header":
                break
        body = f.read()
    fmt = [l.split()[1] for l in header if l.startswith("format")][0]
    elements, cur = [], None
    for l in header:
        w = l.split()
        if w and w[0] == "element":
            cur = {"name": w[1], "count": int(w[2]), "props": []}
            elements.append(cur)
        elif w and w[0] == "property":
            cur["props"].append(w[1:])
    verts, faces, colours = [], [], []
    if fmt == "ascii":
        tok = body.decode().split()
        pos = 0

        def take():
            nonlocal pos
            pos += 1
            return tok[pos - 1]
        readers = None
    else:
        assert fmt == "binary_little_endian", fmt
        pos = 0
    for el in elements:
        for _ in range(el["count"]):
            rec = {}
            for p in el["props"]:
                if p[0] == "list":
                    if fmt == "ascii":
                        n = int(take())
                        rec[p[-1]] = [int(take()) for _ in range(n)]
                    else:
                        cs = struct.calcsize("<" + SIZES[p[1]])
                        n = struct.unpack_from("<" + SIZES[p[1]], body, pos)[0]
                        pos += cs
                        rec[p[-1]] = list(struct.unpack_from("<%d%s" % (n, SIZES[p[2]]), body, pos))
                        pos += n * struct.calcsize("<" + SIZES[p[2]])
                else:
                    if fmt == "ascii":
                        rec[p[-1]] = float(take())
                    else:
                        s = "<" + SIZES[p[0]]
                        rec[p[-1]] = struct.unpack_from(s, body, pos)[0]
                        pos += struct.calcsize(s)
            if el["name"] == "vertex":
                verts.append((rec["x"], rec["y"], rec["z"]))
            elif el["name"] == "face":
                idx = rec.get("vertex_indices", rec.get("vertex_index"))
                for k in range(1, len(idx) - 1):
                    faces.append([idx[0], idx[k], idx[k + 1]])
                    if "red" in rec:
                        colours.append((rec["red"], rec["green"], rec["blue"]))
    return verts, faces, (colours if len(colours) == len(faces) else None)


def write_png(path, width, height, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def render(verts, faces, colours, size, yaw, pitch, wire):
    cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    used = sorted({i for f in faces for i in f})
    view = {}
    for i in used:
        x, y, z = verts[i]
        x, z = cy * x + sy * z, -sy * x + cy * z
        y, z = cp * y - sp * z, sp * y + cp * z
        view[i] = (x, y, z)
    xs = [p[0] for p in view.values()]
    ys = [p[1] for p in view.values()]
    scale = 0.92 * size / max(max(xs) - min(xs), max(ys) - min(ys))
    ox, oy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    scr = {i: (size / 2 + (p[0] - ox) * scale, size / 2 - (p[1] - oy) * scale, p[2]) for i, p in view.items()}
    img = [[255] * (3 * size) for _ in range(size)]
    depth = [[-1e30] * size for _ in range(size)]
    light = (0.3, 0.4, 0.866)
    for fi, (a, b, c) in enumerate(faces):
        pa, pb, pc = view[a], view[b], view[c]
        ux, uy, uz = pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]
        vx, vy, vz = pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        nl = math.sqrt(nx * nx + ny * ny + nz * nz) or 1.0
        shade = 0.35 + 0.65 * abs((nx * light[0] + ny * light[1] + nz * light[2]) / nl)
        col = colours[fi] if colours else (200, 200, 200)
        rgb = [min(255, int(ch * shade)) for ch in col]
        (x0, y0, z0), (x1, y1, z1), (x2, y2, z2) = scr[a], scr[b], scr[c]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if area == 0:
            continue
        minx, maxx = max(0, int(min(x0, x1, x2))), min(size - 1, int(max(x0, x1, x2)) + 1)
        miny, maxy = max(0, int(min(y0, y1, y2))), min(size - 1, int(max(y0, y1, y2)) + 1)
        edge = 1.2 / max(abs(area), 1e-9) ** 0.5 if wire else -1
        for py in range(miny, maxy + 1):
            fy = py + 0.5
            row, drow = img[py], depth[py]
            for px in range(minx, maxx + 1):
                fx = px + 0.5
                w0 = ((x1 - fx) * (y2 - fy) - (x2 - fx) * (y1 - fy)) / area
                w1 = ((x2 - fx) * (y0 - fy) - (x0 - fx) * (y2 - fy)) / area
                w2 = 1 - w0 - w1
                if w0 < 0 or w1 < 0 or w2 < 0:
                    continue
                z = w0 * z0 + w1 * z1 + w2 * z2
                if z <= drow[px]:
                    continue
                drow[px] = z
                k = 3 * px
                if wire and min(w0, w1, w2) < edge * 0.5:
                    row[k:k + 3] = [int(ch * 0.45) for ch in rgb]
                else:
                    row[k:k + 3] = rgb
    return img


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("ply")
    ap.add_argument("png")
    ap.add_argument("--size", type=int, default=480)
    ap.add_argument("--yaw", type=float, default=0.0, help="rotation about the vertical axis, degrees")
    ap.add_argument("--pitch", type=float, default=0.0, help="rotation about the horizontal axis, degrees")
    ap.add_argument("--wire", action="store_true", help="darken triangle edges")
    a = ap.parse_args()
    verts, faces, colours = read_ply(a.ply)
    if not faces:
        sys.exit("%s has no faces" % a.ply)
    img = render(verts, faces, colours, a.size, math.radians(a.yaw), math.radians(a.pitch), a.wire)
    write_png(a.png, a.size, a.size, img)


if __name__ == "__main__":
    main()
