#!/usr/bin/env python3
"""Colour error of the MeshLab filter Cone LOD: Group-Preserving Quadric Edge Collapse on a mesh
with per-vertex colour (issue 26), at AttributeWeight 0 and 1, and optionally of another build's
filter (e.g. one that keeps survivors' colours). Python 3 standard library; needs the build's
private meshlabserver (BUILD/meshlab/bin/meshlabserver, under xvfb-run) and tools/attribute_error.

  compare_filter_attributes.py --build BUILD --mesh MESH.ply [--reference BUILD2] [--ratios 0.1,0.02]
                               [--samples N] [--out DIR]

Each run: the filter at its shipped defaults (scripts/mlx of the source tree next to this script;
BUILD2's own source tree's scripts/mlx for --reference, found as BUILD2/..) with TargetPerc = R,
output saved with vertex colour; measured by tools/attribute_error (RMS of the RGB difference,
0-255, between samples of the original surface and the colour at their closest point on the
result; RMS distance in % of the diagonal). Prints a Markdown table.
"""
import argparse
import json
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from compare_attributes import faces_of  # noqa: E402


def run_filter(a, build, mlxdir, ratio, weight, tag):
    root = ET.parse(os.path.join(mlxdir, "group_preserving_quadric_edge_collapse.mlx")).getroot()
    for flt in root:
        for p in flt:
            if p.get("name") == "TargetPerc":
                p.set("value", str(ratio))
            if p.get("name") == "AttributeWeight" and weight is not None:
                p.set("value", str(weight))
    mlx = os.path.join(a.out, tag + ".mlx")
    with open(mlx, "w") as f:
        f.write("<!DOCTYPE FilterScript>\n<FilterScript>\n%s</FilterScript>\n" %
                "".join(ET.tostring(flt, encoding="unicode") for flt in root))
    out = os.path.join(a.out, tag + ".ply")
    server = os.path.join(build, "meshlab", "bin", "meshlabserver")
    p = subprocess.run(["xvfb-run", "-a", server, "-l", os.path.join(a.out, "meshlab.log"), "-i", a.mesh, "-s", mlx,
                        "-o", out, "-m", "vc"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=a.out)
    if p.returncode != 0:
        sys.exit("meshlabserver failed (%d): %s" % (p.returncode, p.stdout.decode(errors="replace")[-2000:]))
    m = json.loads(subprocess.run([os.path.join(a.build, "tools", "attribute_error"), a.mesh, out, "--samples",
                                   str(a.samples)], check=True, stdout=subprocess.PIPE).stdout)
    return faces_of(out), m


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", required=True)
    ap.add_argument("--mesh", required=True)
    ap.add_argument("--reference")
    ap.add_argument("--ratios", default="0.1,0.02")
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--out", default="filter_attributes_out")
    a = ap.parse_args()
    a.out = os.path.abspath(a.out)
    a.mesh = os.path.abspath(a.mesh)
    a.build = os.path.abspath(a.build)
    a.reference = os.path.abspath(a.reference) if a.reference else None
    os.makedirs(a.out, exist_ok=True)
    print("| target | filter | faces | colour RMS (0-255) | distance RMS (% diag) |")
    print("|---|---|---:|---:|---:|")
    for ratio in [float(r) for r in a.ratios.split(",")]:
        runs = []
        if a.reference:
            runs.append(("reference build", a.reference, os.path.join(a.reference, "..", "scripts", "mlx"), None))
        runs += [("AttributeWeight %d" % w, a.build, os.path.join(ROOT, "scripts", "mlx"), w) for w in (0, 1)]
        for name, build, mlxdir, weight in runs:
            faces, m = run_filter(a, build, mlxdir, ratio, weight, "r%g_%s" % (ratio, name.replace(" ", "_")))
            print("| %g %% | %s | %d | %.2f | %.4f |" % (100 * ratio, name, faces, m["colour_rms"], m["distance_rms_pct"]))


if __name__ == "__main__":
    main()
