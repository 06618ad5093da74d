#!/usr/bin/env python3
"""The culling-cost experiment of Kamiya-Suzuki-Kawachi §5 (figures 4-6), reproduced with conelod.

For each weight setting (one of k_c, k_s, k_n varied, the others at their defaults) it builds the
normal-cone hierarchy and measures the cost of hierarchical back-face culling over N view
directions uniform on the sphere. Prints a Markdown table; with --plot writes a PNG (gnuplot).

  scripts/culling_experiment.py MESH [--views 1000] [--plot docs/img/culling_cost.png]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

DEFAULTS = {"cone": 1.0, "shape": 0.5, "size": 0.5}
VALUES = [0.0, 0.25, 0.5, 1.0, 2.0, 4.0]
THRESHOLDS = [2.5, 5, 10, 15, 20, 30, 45]


def conelod():
    here = os.path.dirname(os.path.abspath(__file__))
    built = os.path.join(here, "..", "build", "conelod", "conelod")
    return built if os.path.exists(built) else (shutil.which("conelod") or built)


def run(mesh, views, weights, extra=()):
    args = [conelod(), "cull-cost", mesh, "--views", str(views), "--json",
            "--cone-weight", str(weights["cone"]), "--shape-weight", str(weights["shape"]),
            "--size-weight", str(weights["size"])] + list(extra)
    return json.loads(subprocess.run(args, check=True, stdout=subprocess.PIPE).stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("--views", type=int, default=1000)
    ap.add_argument("--plot", help="write a PNG plot here")
    a = ap.parse_args()

    rows = []
    for varied in ["cone", "shape", "size"]:
        for v in VALUES:
            w = dict(DEFAULTS)
            w[varied] = v
            if sum(w.values()) == 0:
                continue
            r = run(a.mesh, a.views, w)
            rows.append((varied, v, w, r))
    persp = run(a.mesh, a.views, DEFAULTS, ["--camera-distance", "3"])
    sweep = [(t, run(a.mesh, a.views, DEFAULTS, ["--threshold", str(t)])) for t in THRESHOLDS]

    name = os.path.basename(a.mesh)
    print("Culling cost on %s (%d faces), %d orthographic views uniform on the sphere; cost = tests / faces "
          "(per-face back-face culling = 1)\n" % (name, rows[0][3]["faces"], a.views))
    print("| k_c | k_s | k_n | levels | groups L1 | groups top | two-state mean (min-max) | three-state mean (min-max) "
          "| culled at group level | ideal | culled / ideal |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")

    def line(w, r, note=""):
        print("| %g | %g | %g | %d | %d | %d | %.3f (%.3f-%.3f) | %.3f (%.3f-%.3f) | %.3f | %.3f | %.0f%% |%s" % (
            w["cone"], w["shape"], w["size"], r["levels"], r["level1_groups"], r["top_groups"],
            r["two_state_cost"], r["two_state_min"], r["two_state_max"],
            r["three_state_cost"], r["three_state_min"], r["three_state_max"],
            r["rejected_fraction"], r["ideal_fraction"], 100 * r["culled_of_ideal"], note))

    seen = set()
    for varied, v, w, r in rows:
        key = tuple(sorted(w.items()))
        if key in seen:
            continue
        seen.add(key)
        line(w, r)
    print("\nLevel-1 cone threshold (degrees, half-angle; default weights, growth 1.6 per level):\n")
    print("| threshold | levels | groups L1 | two-state | three-state | culled at group level | culled / ideal |")
    print("|---|---|---|---|---|---|---|")
    for t, r in sweep:
        print("| %g | %d | %d | %.3f | %.3f | %.3f | %.0f%% |" % (t, r["levels"], r["level1_groups"], r["two_state_cost"],
              r["three_state_cost"], r["rejected_fraction"], 100 * r["culled_of_ideal"]))
    print("\nPerspective eye at 3 bounding-sphere radii, default weights:\n")
    print("| two-state | three-state | culled at group level | ideal | culled / ideal |")
    print("|---|---|---|---|---|")
    print("| %.3f | %.3f | %.3f | %.3f | %.0f%% |" % (persp["two_state_cost"], persp["three_state_cost"],
                                                   persp["rejected_fraction"], persp["ideal_fraction"],
                                                   100 * persp["culled_of_ideal"]))

    if a.plot:
        tmp = tempfile.mkdtemp()
        for varied in ["cone", "shape", "size"]:
            with open(os.path.join(tmp, varied + ".dat"), "w") as f:
                for vv, v, w, r in rows:
                    if vv == varied:
                        f.write("%g %g %g %g\n" % (v, r["two_state_cost"], r["three_state_cost"],
                                                   1 - r["ideal_fraction"]))
        gp = """
set terminal pngcairo size 1600,420 font 'DejaVu Sans,10' noenhanced
set output '%s'
set multiplot layout 1,4 title "Culling cost on %s (%d views): tests / faces; per-face culling = 1"
set yrange [0:1.1]
set key bottom right
set grid
set ylabel 'cost'
""" % (a.plot, name, a.views)
        for varied, label in [("cone", "k_c (k_s=0.5, k_n=0.5)"), ("shape", "k_s (k_c=1, k_n=0.5)"),
                              ("size", "k_n (k_c=1, k_s=0.5)")]:
            d = os.path.join(tmp, varied + ".dat")
            gp += ("set xlabel '%s'\nplot '%s' u 1:2 w lp pt 7 lw 2 t 'two-state', '%s' u 1:3 w lp pt 5 lw 2 "
                   "t 'three-state', '%s' u 1:4 w l dt 2 lw 2 t 'faces to draw (ideal)', 1 w l lc rgb 'gray' "
                   "t 'per-face culling'\n") % (label, d, d, d)
        d = os.path.join(tmp, "threshold.dat")
        with open(d, "w") as f:
            for t, r in sweep:
                f.write("%g %g %g %g\n" % (t, r["two_state_cost"], r["three_state_cost"], 1 - r["ideal_fraction"]))
        gp += ("set xlabel 'level-1 cone threshold (deg)'\nplot '%s' u 1:2 w lp pt 7 lw 2 t 'two-state', '%s' u 1:3 "
               "w lp pt 5 lw 2 t 'three-state', '%s' u 1:4 w l dt 2 lw 2 t 'faces to draw (ideal)', 1 w l "
               "lc rgb 'gray' t 'per-face culling'\n") % (d, d, d)
        gp += "unset multiplot\n"
        subprocess.run(["gnuplot"], input=gp.encode(), check=True)
        shutil.rmtree(tmp)
        print("\nplot: %s" % a.plot, file=sys.stderr)


if __name__ == "__main__":
    main()
