#!/usr/bin/env python3
"""Picture of docs/feature_simplify.md: where the bunny is cut when it is simplified in two parts
(conelod feature-simplify, the default --faces-per-part 32768), on the input and on the output.
Faces of one part blue, of the other green, faces spanning the two (the seam) red. The cut is
recomputed here as in the core (CutIntoParts: the median of the used vertices across the longest
side of their box, ties by index), for two parts only.

  scripts/make_parts_picture.py IN.ply OUT.ply PICTURE.png   (OUT: conelod feature-simplify IN --target-percent 10)

Renders with tools/render_mesh (CONELOD_BUILD_DIR, default build/).
"""
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from meshdata import read_ply_elements  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RENDER = os.path.join(os.environ.get("CONELOD_BUILD_DIR", os.path.join(ROOT, "build")), "tools", "render_mesh")


def read_ply(path):
    """The mesh's vertex positions and its faces as triangles (polygons fanned)."""
    verts, faces = [], []
    for name, records in read_ply_elements(path):
        if name == "vertex":
            verts = [(r["x"], r["y"], r["z"]) for r in records]
        elif name == "face":
            for rec in records:
                idx = rec.get("vertex_indices", rec.get("vertex_index"))
                faces.extend((idx[0], idx[k], idx[k + 1]) for k in range(1, len(idx) - 1))
    return verts, faces


def write_coloured(path, verts, faces, colours):
    with open(path, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %d\nproperty list uchar int vertex_indices\nproperty uchar red\nproperty uchar green\n"
                "property uchar blue\nend_header\n" % (len(verts), len(faces)))
        for v in verts:
            f.write("%g %g %g\n" % tuple(v))
        for t, c in zip(faces, colours):
            f.write("3 %d %d %d %d %d %d\n" % (tuple(t) + tuple(c)))


def main():
    src, out, picture = sys.argv[1:4]
    verts, faces = read_ply(src)[:2]
    used = sorted({v for t in faces for v in t})
    lo = [min(verts[v][k] for v in used) for k in range(3)]
    hi = [max(verts[v][k] for v in used) for k in range(3)]
    axis = max(range(3), key=lambda k: hi[k] - lo[k])
    order = sorted(used, key=lambda v: (verts[v][axis], v))
    cut = (verts[order[len(order) // 2]][axis], order[len(order) // 2])  # first vertex of the upper half
    side = lambda p, i: (p[axis], i) >= cut  # noqa: E731
    palette = {(False, False, False): (110, 150, 230), (True, True, True): (120, 200, 120)}
    tmp = tempfile.mkdtemp()
    panels = []
    for name, path in (("input", src), ("output", out)):
        vs, fs = read_ply(path)[:2]
        # Output vertices are input vertices (they never move): their side is found by position.
        index = {tuple(verts[v]): v for v in used}
        cols = []
        for t in fs:
            key = tuple(side(vs[v], index.get(tuple(vs[v]), 0)) for v in t)
            cols.append(palette.get(key, (230, 60, 60)))
        ply = os.path.join(tmp, name + ".ply")
        write_coloured(ply, vs, fs, cols)
        png = os.path.join(tmp, name + ".png")
        subprocess.check_call([RENDER, ply, png, "--size", "600", "600", "--azimuth", "20", "--elevation", "10",
                               "--colors", "--no-features"] + (["--wire"] if name == "output" else []),
                              stdout=subprocess.DEVNULL)
        subprocess.check_call(["convert", png, "-font", "DejaVu-Sans", "-gravity", "North", "-pointsize", "16", "-annotate", "+0+4",
                               "%s (%d faces)" % (name, len(fs)), png])
        panels.append(png)
    subprocess.check_call(["convert"] + panels + ["+append", picture])


if __name__ == "__main__":
    main()
