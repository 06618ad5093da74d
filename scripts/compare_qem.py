#!/usr/bin/env python3
"""Compares ConeLOD's group-preserving quadric edge collapse with MeshLab's built-in
"Simplification: Quadric Edge Collapse Decimation", through meshlabserver, on the same grouped
input, at the same targets. Python 3 standard library only (no numpy). Run it through
scripts/compare_qem.sh, which finds the build.

For each mesh: `conelod group --level L` writes the grouped input (per-face quality = normal-cone
group of level L). For each target and each method (built-in QEM; ours with conditions 1 and 2;
ours with locked group boundaries):
  - a timing run: meshlabserver loads the grouped input, runs the one simplification filter, saves;
    its CPU time minus that of the same run without the filter is the filter's time;
  - a measuring run on the input and the result: Cone LOD: Group Integrity, then MeshLab's
    Hausdorff Distance both ways (max, mean, RMS as % of the bounding-box diagonal).
Writes OUT/<mesh>.md (a Markdown table), OUT/<mesh>.tsv, OUT/<mesh>.png (RMS error against the
face count, gnuplot) and OUT/summary.md.
"""
import argparse
import os
import re
import resource
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mlx_filters import builtin_qem, hausdorff as hausdorff_filter, script as script_text  # noqa: E402

METHODS = [
    ("builtin", "MeshLab QEM (built-in)"),
    ("ours", "ours, conditions 1+2"),
    ("ours_locked", "ours, locked boundaries"),
]


def script(path, filters):
    with open(path, "w") as f:
        f.write(script_text(*filters))


def our_filter(source_dir, target, locked):
    """Our filter with the shipped defaults (scripts/mlx), the target and the lock set."""
    root = ET.parse(os.path.join(source_dir, "scripts", "mlx", "group_preserving_quadric_edge_collapse.mlx")).getroot()
    values = {"TargetFaceNum": str(target), "TargetPerc": "0", "GroupSource": "0",
              "LockGroupBoundaries": "true" if locked else "false"}
    for flt in root:
        for p in flt:
            if p.get("name") in values:
                p.set("value", values[p.get("name")])
    return "".join(" " + ET.tostring(flt, encoding="unicode").strip() + "\n" for flt in root)


def integrity_filter(source_dir):
    root = ET.parse(os.path.join(source_dir, "scripts", "mlx", "group_integrity.mlx")).getroot()
    return "".join(" " + ET.tostring(flt, encoding="unicode").strip() + "\n" for flt in root)


def run_timed(cmd, cwd):
    """Runs cmd; returns (exit code, CPU seconds of it and its children, wall seconds)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    p = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=cwd)
    wall = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return p.returncode, cpu, wall


def meshlab(server, inputs, script_path, log, output=None, cwd=None):
    if os.path.exists(log):
        os.remove(log)
    cmd = ["xvfb-run", "-a", server, "-l", log, "-i"] + inputs + ["-s", script_path]
    if output:
        cmd += ["-o", output, "-m", "fq", "fc"]
    rc, cpu, wall = run_timed(cmd, cwd)
    text = open(log, errors="replace").read() if os.path.exists(log) else ""
    if rc != 0:
        sys.exit("meshlabserver failed (%d) on %s:\n%s" % (rc, script_path, text[-3000:]))
    return text, cpu, wall


def ply_face_count(path):
    with open(path, "rb") as f:
        for raw in f:
            line = raw.decode("ascii", "replace").strip()
            if line.startswith("element face"):
                return int(line.split()[2])
            if line == "end_header":
                break
    return 0


def last_number(log, key):
    vals = re.findall(re.escape(key) + r"\s+([0-9.eE+-]+)", log)
    return float(vals[-1]) if vals else float("nan")


def hausdorff(log):
    """The two Hausdorff results of the log, in script order: (max, mean, rms) in % of the diagonal."""
    out = []
    for m in re.finditer(r"Values w\.r\.t\. BBox Diag \(([0-9.eE+-]+)\)\s*\n\s*min : ([0-9.eE+-]+)\s+max ([0-9.eE+-]+)"
                         r"\s+mean : ([0-9.eE+-]+)\s+RMS : ([0-9.eE+-]+)", log):
        out.append(tuple(100 * float(m.group(i)) for i in (3, 4, 5)))
    # meshlabserver repeats the log after each filter: the last two are the two filters of this run.
    return out[-2:]


def fmt(x, digits=4):
    return "n/a" if x != x else ("%.*f" % (digits, x))


def compare(mesh, a, tools, out_dir):
    name = os.path.splitext(os.path.basename(mesh))[0]
    work = os.path.join(out_dir, "work_" + name)
    os.makedirs(work, exist_ok=True)
    print("== %s" % mesh, flush=True)

    import json
    if a.pca:
        # Grouped input: per-face quality = cluster of the recursive PCA partition cut at K.
        grouped = os.path.join(work, name + "_pca%d.ply" % a.pca)
        info = subprocess.run([tools["conelod"], "partition", mesh, "--clusters", str(a.pca), "-o", grouped, "--json"],
                              stdout=subprocess.PIPE, check=True)
        groups = json.loads(info.stdout)["clusters"]
        source = "%d PCA clusters" % groups
    else:
        # Grouped input: per-face quality = normal-cone group of level L (clamped to the levels built).
        info = subprocess.run([tools["conelod"], "group", mesh, "--json"], stdout=subprocess.PIPE, check=True)
        levels = json.loads(info.stdout)["levels"]
        level = min(a.level, len(levels))
        groups = levels[level - 1]["groups"]
        grouped = os.path.join(work, name + "_cone%d.ply" % level)
        subprocess.run([tools["conelod"], "group", mesh, "--level", str(level), "-o", grouped], check=True,
                       stdout=subprocess.DEVNULL)
        source = "%d normal-cone groups, level %d" % (groups, level)
    faces_in = ply_face_count(grouped)
    print("  %d faces, %s" % (faces_in, source), flush=True)

    noop = os.path.join(work, "noop.mlx")
    script(noop, [])
    log = os.path.join(work, "run.log")
    _, base_cpu, base_wall = meshlab(tools["server"], [grouped], noop, log, os.path.join(work, "noop.ply"), work)

    rows = []
    for ratio in a.targets:
        target = max(1, int(ratio * faces_in))
        todo = list(METHODS)
        while todo:
            method, label = todo.pop(0)
            if method == "builtin_same":
                label = "MeshLab QEM at our face count"
            tag = "%s_%g" % (method, ratio)
            simplified = os.path.join(work, tag + ".ply")
            run = os.path.join(work, tag + ".mlx")
            method_target = target
            if method == "builtin_same":  # ours stopped above the target: the built-in at our face count
                method_target = next(r["faces"] for r in rows if r["ratio"] == ratio and r["method"] == "ours")
            script(run, [builtin_qem(method_target) if method.startswith("builtin")
                         else our_filter(tools["source"], target, method == "ours_locked")])
            runlog, cpu, wall = meshlab(tools["server"], [grouped], run, log, simplified, work)
            filter_seconds = last_number(runlog, "seconds") if method.startswith("ours") else float("nan")
            measure = os.path.join(work, tag + "_measure.mlx")
            script(measure, [integrity_filter(tools["source"]),
                             hausdorff_filter(1, 0, a.samples, sample_edges=True),
                             hausdorff_filter(0, 1, a.samples, sample_edges=True)])
            mlog, _, _ = meshlab(tools["server"], [grouped, simplified], measure, log, None, work)
            h = hausdorff(mlog)
            if len(h) != 2:
                sys.exit("no Hausdorff figures in the log of %s:\n%s" % (measure, mlog[-2000:]))
            row = {
                "mesh": name, "method": method, "label": label, "ratio": ratio, "target": method_target,
                "faces": ply_face_count(simplified), "cpu": max(0.0, cpu - base_cpu), "wall": max(0.0, wall - base_wall),
                "filter_seconds": filter_seconds,
                "ab": h[0], "ba": h[1],
                "groups_before": last_number(mlog, "groups_before"), "groups_after": last_number(mlog, "groups_after"),
                "split": last_number(mlog, "groups_split"), "vanished": last_number(mlog, "groups_vanished"),
                "intact": last_number(mlog, "integrity_percent"),
            }
            rows.append(row)
            if method == "ours" and row["faces"] > 1.01 * target:
                todo.insert(0, ("builtin_same", ""))
            print("  %-24s target %7d: %7d faces, %6.2f s CPU, RMS %.4f%% / %.4f%%, %3.0f%% groups intact"
                  % (label, target, row["faces"], row["cpu"], h[0][2], h[1][2], row["intact"]), flush=True)
    write_outputs(name, mesh, source, faces_in, rows, out_dir, a)
    return rows


def write_outputs(name, mesh, source, faces_in, rows, out_dir, a):
    md = []
    md.append("### %s (%d faces; %s)\n" % (name, faces_in, source))
    md.append("| method | target | faces | CPU s | H max → | H mean → | H RMS → | H max ← | H mean ← | H RMS ← "
              "| groups after | split | vanished | intact |")
    md.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        md.append("| %s | %g%% (%d) | %d | %.2f | %s | %s | %s | %s | %s | %s | %d | %d | %d | %.1f%% |" % (
            r["label"], 100 * r["ratio"], r["target"], r["faces"], r["cpu"],
            fmt(r["ab"][0], 3), fmt(r["ab"][1]), fmt(r["ab"][2]), fmt(r["ba"][0], 3), fmt(r["ba"][1]), fmt(r["ba"][2]),
            r["groups_after"], r["split"], r["vanished"], r["intact"]))
    md.append("")
    md.append("H → : Hausdorff distance from the simplified mesh to the input, H ← : from the input to the simplified "
              "mesh (MeshLab's Hausdorff Distance, %d samples, vertices + edges + faces), in %% of the input's "
              "bounding-box diagonal. CPU s: the meshlabserver run's CPU time minus that of the same run without "
              "the filter." % a.samples)
    ratios = []
    for ratio in a.targets:
        by = {r["method"]: r for r in rows if r["ratio"] == ratio}
        if "builtin" in by and "ours" in by:
            rms = lambda r: max(r["ab"][2], r["ba"][2])
            ref = by.get("builtin_same", by["builtin"])
            ratios.append("target %g%%: ours %d faces, %.0f%% of groups intact (built-in: %d faces, %.0f%%); RMS "
                          "(larger of both ways) ours / built-in at %d faces = %.2f; locked boundaries: %d faces, "
                          "RMS / built-in at the target = %.2f; CPU ours / built-in = %.2f"
                          % (100 * ratio, by["ours"]["faces"], by["ours"]["intact"], by["builtin"]["faces"],
                             by["builtin"]["intact"], ref["faces"], rms(by["ours"]) / rms(ref),
                             by["ours_locked"]["faces"], rms(by["ours_locked"]) / rms(by["builtin"]),
                             by["ours"]["cpu"] / max(by["builtin"]["cpu"], 1e-9)))
    md.append("")
    md.extend("- " + r for r in ratios)
    md.append("")
    with open(os.path.join(out_dir, name + ".md"), "w") as f:
        f.write("\n".join(md) + "\n")
    tsv = os.path.join(out_dir, name + ".tsv")
    with open(tsv, "w") as f:
        f.write("# method\tratio\tfaces\trms_max_both_ways_pct\tcpu_s\tintact_pct\n")
        for method, _ in METHODS:  # the built-in's series includes its runs at our face counts
            series = (method, "builtin_same") if method == "builtin" else (method,)
            for r in sorted((r for r in rows if r["method"] in series), key=lambda r: r["faces"]):
                f.write("%s\t%g\t%d\t%.6f\t%.3f\t%.2f\n" % (method, r["ratio"], r["faces"],
                                                          max(r["ab"][2], r["ba"][2]), r["cpu"], r["intact"]))
            f.write("\n\n")
    png = os.path.join(out_dir, name + ".png")
    gp = """set terminal pngcairo size 720,450 font "DejaVu Sans,10"
set output '{png}'
set termoption noenhanced
set title "{name}: RMS Hausdorff distance vs faces ({source})"
set xlabel "faces after simplification"
set ylabel "RMS distance, % of bbox diagonal (larger of both ways)"
set logscale xy
set grid
set key top right
plot '{tsv}' index 0 using 3:4 with linespoints lw 2 pt 7 title "MeshLab QEM (built-in)", \\
     '{tsv}' index 1 using 3:4 with linespoints lw 2 pt 5 title "ours, conditions 1+2", \\
     '{tsv}' index 2 using 3:4 with linespoints lw 2 pt 9 title "ours, locked group boundaries"
""".format(png=png, tsv=tsv, name=name, source=source)
    p = subprocess.run(["gnuplot"], input=gp.encode(), stderr=subprocess.PIPE)
    if p.returncode != 0:
        print("gnuplot failed: %s" % p.stderr.decode(), file=sys.stderr)
    print("  wrote %s, %s, %s" % (os.path.join(out_dir, name + ".md"), tsv, png), flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--build", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--out", default="qem_compare")
    ap.add_argument("--level", type=int, default=4, help="normal-cone hierarchy level of the groups [4]")
    ap.add_argument("--pca", type=int, default=0, help="use the K clusters of the PCA partition instead")
    ap.add_argument("--targets", default="0.5,0.1,0.01", help="target fractions of the input faces [0.5,0.1,0.01]")
    ap.add_argument("--samples", type=int, default=500000, help="Hausdorff samples [500000]")
    a = ap.parse_args()
    a.targets = [float(t) for t in a.targets.split(",")]
    tools = {"conelod": os.path.join(a.build, "conelod", "conelod"),
             "server": os.path.join(a.build, "meshlab", "bin", "meshlabserver"),
             "source": a.source}
    for t in ("conelod", "server"):
        if not os.path.exists(tools[t]):
            sys.exit("missing %s: build the project first (cmake --build %s)" % (tools[t], a.build))
    os.makedirs(a.out, exist_ok=True)
    a.out = os.path.abspath(a.out)
    summary = []
    for mesh in a.meshes:
        compare(os.path.abspath(mesh), a, tools, a.out)
        summary.append(open(os.path.join(a.out, os.path.splitext(os.path.basename(mesh))[0] + ".md")).read())
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write("\n".join(summary))
    print("summary: %s" % os.path.join(a.out, "summary.md"))


if __name__ == "__main__":
    main()
