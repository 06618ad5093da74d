#!/usr/bin/env python3
"""Crack edges of .clod cuts per budget (the LOD crack table of README.md and docs/lod_viewer.md):
for each mesh, `conelod lod build` with the defaults, then `conelod lod extract` from an eye 2
diagonals in front of the box (+Z), or --eye X,Y,Z, at each budget; the input and every cut welded
by identical position (so that a seam the file repeats, as the dragon's, is no border), edges used
by one face that the welded input does not have counted (cracks, T-junctions), and edges used by
3+ faces that the welded input does not have (overlaps). The input's border edges are taken at its
positions rounded on the file's grid (`conelod lod info --json`), as the file stores them.

  scripts/lod_cracks.py CONELOD MESH.ply... [--budgets 5,20,50,80,100] [--eye X,Y,Z] [--no-cull] [--tmp DIR]
"""
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "integration"))
from cases import on_grid, read_ply  # noqa: E402


def edges(ply):
    pos, count = ply["positions"], {}
    for f in ply["faces"]:
        if len({pos[v] for v in f}) < 3:
            continue  # two corners rounded onto one grid point: no area, neither a crack nor an overlap
        for i in range(3):
            a, b = pos[f[i]], pos[f[(i + 1) % 3]]
            key = (a, b) if a < b else (b, a)
            count[key] = count.get(key, 0) + 1
    return count


def main(argv):
    budgets, cull, tmp, eye, args = [5, 20, 50, 80, 100], [], None, None, []
    i = 1
    while i < len(argv):
        if argv[i] == "--budgets":
            budgets = [int(b) for b in argv[i + 1].split(",")]
            i += 1
        elif argv[i] == "--eye":
            eye = argv[i + 1]
            i += 1
        elif argv[i] == "--no-cull":
            cull = ["--no-cull"]
        elif argv[i] == "--tmp":
            tmp = argv[i + 1]
            i += 1
        else:
            args.append(argv[i])
        i += 1
    if len(args) < 2:
        print(__doc__)
        return 2
    conelod, meshes = args[0], args[1:]
    tmp = tmp or tempfile.mkdtemp(prefix="lod_cracks_")
    print("| mesh | faces | " + " | ".join("%d %%" % b for b in budgets) + " |")
    print("|---|---|" + "---|" * len(budgets))
    for mesh in meshes:
        src = read_ply(mesh)
        pos = src["positions"]
        lo = [min(p[k] for p in pos) for k in range(3)]
        hi = [max(p[k] for p in pos) for k in range(3)]
        diag = sum((h - l) ** 2 for h, l in zip(hi, lo)) ** 0.5
        at = eye or "%g,%g,%g" % ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2 + 2 * diag)
        clod = os.path.join(tmp, os.path.basename(mesh) + ".clod")
        subprocess.run([conelod, "lod", "build", mesh, "-o", clod], check=True, stdout=subprocess.DEVNULL)
        info = json.loads(subprocess.run([conelod, "lod", "info", clod, "--json"], check=True,
                                         stdout=subprocess.PIPE).stdout)
        inedges = edges(dict(src, positions=on_grid(pos, info)))
        inborder = {k for k, n in inedges.items() if n == 1}
        inover = {k for k, n in inedges.items() if n > 2}  # the dragon's slivers along its seams
        cells = []
        for b in budgets:
            out = os.path.join(tmp, "cut.ply")
            subprocess.run([conelod, "lod", "extract", clod, "--eye", at, "--budget", "%d%%" % b, "-o", out] + cull,
                           check=True, stdout=subprocess.DEVNULL)
            e = edges(read_ply(out))
            border = sum(1 for k, n in e.items() if n == 1 and k not in inborder)
            over = sum(1 for k, n in e.items() if n > 2 and k not in inover)
            cells.append("{:,}".format(border) + ("" if over == 0 else " (+%d over-used)" % over))
        print("| %s | %s | %s |" % (os.path.basename(mesh), "{:,}".format(len(src["faces"])), " | ".join(cells)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
