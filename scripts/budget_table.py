#!/usr/bin/env python3
"""The relation of Mizuno-Okumoto-Takata-Joe's Table 1 on our meshes: covered pixels at
1920x1080, 1600x900, 1280x720 and 800x600 (conelod budget: orthographic, framed on the bounding
sphere, worst of the six axis directions by default) and the face budgets 1/10, 1, 10, 40, 50,
60 and 100 x pixels. Prints Markdown: our table, the pixel ratios next to the paper's, and the
paper's Table 1.

Our framing fits the bounding sphere to the shorter side of the screen (as MeshLab's "fit to
window"), so pixels scale with (shorter side)^2. The paper's pixel counts scale with the screen
area (its 4:3 row too): --area-framing sets the fill so that the sphere spans sqrt(W H 9/16)
pixels (the shorter side at 16:9), which reproduces that.

  scripts/budget_table.py [--build BUILD] [--view V] [--area-framing] [MESH.ply ...]
"""
import math
import argparse
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RESOLUTIONS = [(1920, 1080), (1600, 900), (1280, 720), (800, 600)]
FACTORS = [0.1, 1, 10, 40, 50, 60, 100]
FACTOR_NAMES = ["1/10", "1", "10", "40", "50", "60", "100"]
# Table 1 of the paper (the five-storey pagoda of Kairyuo-ji): faces at each factor.
PAPER = {
    (1920, 1080): [15604, 156072, 1560719, 6242877, 7803599, 6216389, 15607198],
    (1600, 900): [10939, 109441, 1094308, 4377238, 5471549, 6565857, 10943098],
    (1280, 720): [6798, 68004, 680037, 2720159, 3400199, 4080236, 6800398],
    (800, 600): [3659, 36616, 366169, 1464677, 1830849, 2197020, 3661697],
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="*", default=["stanford_bunny_bun_zipper.ply", "stanford_dragon_vrip_res2.ply"])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--meshes-dir", default=os.environ.get("CONELOD_TEST_MESHES",
                                                             os.path.join(ROOT, "..", "shared", "test_meshes")))
    ap.add_argument("--view", default="worst")
    ap.add_argument("--area-framing", action="store_true", help="model size proportional to sqrt(screen area)")
    a = ap.parse_args()
    cli = os.path.join(a.build, "conelod", "conelod")

    for name in a.meshes:
        mesh = name if os.path.exists(name) else os.path.join(a.meshes_dir, name)
        rows = []
        for w, h in RESOLUTIONS:
            fill = math.sqrt(w * h * 9.0 / 16.0) / min(w, h) if a.area_framing else 1.0
            p = subprocess.run([cli, "budget", mesh, "--width", str(w), "--height", str(h), "--view", a.view,
                                "--fill", "%.6f" % fill, "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            if p.returncode != 0:
                sys.exit(p.stderr.decode())
            rows.append(((w, h), json.loads(p.stdout)))
        faces = rows[0][1]["faces"]
        print("### %s (%d faces), view: %s, framing: %s\n" % (
            os.path.basename(mesh), faces, rows[0][1]["view"],
            "sphere spans sqrt(W H 9/16) pixels" if a.area_framing else "sphere spans the shorter side"))
        print("| resolution | covered pixels | " + " | ".join("%s x" % f for f in FACTOR_NAMES) + " |")
        print("|---|---:|" + "---:|" * len(FACTORS))
        for (w, h), r in rows:
            budgets = ["%d" % round(f * r["covered_pixels"]) for f in FACTORS]
            print("| %d x %d | %d | %s |" % (w, h, r["covered_pixels"], " | ".join(budgets)))
        print("\nPixels relative to 1920 x 1080:\n")
        print("| resolution | ours | screen area | (shorter side)^2 | paper (1x column) |")
        print("|---|---:|---:|---:|---:|")
        base = rows[0][1]["covered_pixels"]
        for (w, h), r in rows:
            print("| %d x %d | %.4f | %.4f | %.4f | %.4f |" % (
                w, h, r["covered_pixels"] / base, (w * h) / (1920 * 1080), (min(w, h) / 1080) ** 2,
                PAPER[(w, h)][1] / PAPER[(1920, 1080)][1]))
        print()
    print("### The paper's Table 1 (faces)\n")
    print("| resolution | " + " | ".join("%s x" % f for f in FACTOR_NAMES) + " |")
    print("|---|" + "---:|" * len(FACTORS))
    for (w, h) in RESOLUTIONS:
        print("| %d x %d | %s |" % (w, h, " | ".join("%d" % v for v in PAPER[(w, h)])))


if __name__ == "__main__":
    main()
