#!/usr/bin/env python3
"""Feature-preserving simplification (conelod feature-simplify) against MeshLab's built-in
"Simplification: Quadric Edge Collapse Decimation" at the same face count.

For each mesh: our simplifier runs to PERCENT % of the faces; MeshLab's QEM (its default
parameters, through meshlabserver) runs to the face count we reached; MeshLab's "Hausdorff
Distance" measures both ways (output -> input and input -> output: max, mean, RMS as % of the
input's bounding-box diagonal); `conelod feature-edges --reference` counts the output's feature
edges lying on the input's feature lines. Prints a Markdown table.

  scripts/compare_feature.py [--build BUILD] [--meshes DIR] [--percent P] [--angle DEG]
                             [--meshlabserver PATH] [--keep DIR] [--pure] [MESH.ply ...]
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from mlx_filters import builtin_qem, hausdorff as hausdorff_filter, script  # noqa: E402


def run(cmd, **kw):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)
    if p.returncode != 0:
        sys.exit("failed (%d): %s\n%s%s" % (p.returncode, " ".join(cmd), p.stdout.decode(errors="replace")[-3000:],
                                           p.stderr.decode(errors="replace")[-3000:]))
    return p.stdout.decode(errors="replace")


def meshlab(server, inputs, script_text, tmp, output=None):
    script = os.path.join(tmp, "script.mlx")
    with open(script, "w") as f:
        f.write(script_text)
    log = os.path.join(tmp, "meshlab.log")
    if os.path.exists(log):
        os.remove(log)
    cmd = ["xvfb-run", "-a", server, "-l", log, "-i"] + inputs + ["-s", script]
    if output:
        cmd += ["-o", output]
    run(cmd, cwd=tmp)
    return open(log, errors="replace").read()


def hausdorff(server, original, simplified, samples, tmp):
    """{'out_in': (max, mean, rms), 'in_out': (...)} in absolute units (last occurrence of each)."""
    text = script(hausdorff_filter(1, 0, samples, sample_edges=False),
                  hausdorff_filter(0, 1, samples, sample_edges=False))
    log = meshlab(server, [original, simplified], text, tmp)
    blocks = re.findall(r"Sampled \d+ pts \(rng: \d+\) on (\S+) searched closest on (\S+)\s*\n\s*min : ([0-9.eE+-]+)\s+"
                        r"max ([0-9.eE+-]+)\s+mean : ([0-9.eE+-]+)\s+RMS : ([0-9.eE+-]+)", log)
    result = {}
    orig = os.path.basename(original)
    for sampled, _target, _mn, mx, mean, rms in blocks:
        key = "in_out" if os.path.basename(sampled) == orig else "out_in"
        result[key] = (float(mx), float(mean), float(rms))
    assert "in_out" in result and "out_in" in result, log[-2000:]
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="*", default=["fandisk.ply", "mech_holes_shark.ply"])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--meshes-dir", default=os.environ.get("CONELOD_TEST_MESHES",
                                                             os.path.join(ROOT, "..", "shared", "test_meshes")))
    ap.add_argument("--percent", type=float, default=10.0)
    ap.add_argument("--angle", type=float, default=135.0)
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--meshlabserver", default=shutil.which("meshlabserver") or "/usr/bin/meshlabserver")
    ap.add_argument("--keep", help="keep the simplified meshes in this folder")
    ap.add_argument("--pure", action="store_true", help="also run the paper's pure curvature order (--no-grow)")
    a = ap.parse_args()
    # meshlabserver runs in a scratch folder: every path it is given must be absolute.
    if os.path.sep in a.meshlabserver:
        a.meshlabserver = os.path.abspath(a.meshlabserver)
    cli = os.path.join(a.build, "conelod", "conelod")
    tmp = tempfile.mkdtemp(prefix="conelod_cmp_")
    keep = os.path.abspath(a.keep) if a.keep else tmp
    os.makedirs(keep, exist_ok=True)

    rows = []
    for name in a.meshes:
        mesh = os.path.abspath(name if os.path.exists(name) else os.path.join(a.meshes_dir, name))
        stem = os.path.splitext(os.path.basename(mesh))[0]
        info = json.loads(run([cli, "info", mesh, "--json"]))
        variants = [("ours", [])] + ([("ours, paper order", ["--no-grow"])] if a.pure else [])
        target = None
        for label, extra in variants:
            out = os.path.join(keep, "%s_%s.ply" % (stem, "ours" if not extra else "ours_pure"))
            r = json.loads(run([cli, "feature-simplify", mesh, "--target-percent", str(a.percent), "--angle",
                                str(a.angle), "-o", out, "--json"] + extra))
            target = target or r["faces_out"]
            rows.append((stem, label, out, r["faces_out"], r["seconds"], r["diagonal"]))
        qem = os.path.join(keep, "%s_qem.ply" % stem)
        t0 = time.time()
        log = meshlab(a.meshlabserver, [mesh], script(builtin_qem(target)), tmp, qem)
        qem_wall = time.time() - t0
        faces = int(re.findall(r"saved as .* \((\d+) vn (\d+) fn\)", log)[-1][1])
        rows.append((stem, "MeshLab QEM", qem, faces, None, rows[-1][5]))
        rows[-1] = rows[-1] + (qem_wall,)
        del info

    print("| mesh | method | faces | seconds | out→in max / mean / RMS (% diag) | in→out max / mean / RMS (% diag) "
          "| output feature edges on input lines | input line length covered |")
    print("|---|---|---:|---:|---|---|---|---:|")
    for row in rows:
        stem, label, out, faces, seconds, diag = row[:6]
        mesh = os.path.join(a.meshes_dir, stem + ".ply") if not os.path.exists(stem) else stem
        h = hausdorff(a.meshlabserver, mesh, out, a.samples, tmp)
        fe = json.loads(run([cli, "feature-edges", out, "--reference", mesh, "--angle", str(a.angle),
                             "--no-extend", "--json"]))
        pct = lambda v: 100.0 * v / diag
        sec = "%.3f" % seconds if seconds is not None else "%.2f (wall, incl. meshlabserver start)" % row[6]
        print("| %s | %s | %d | %s | %.3f / %.4f / %.4f | %.3f / %.4f / %.4f | %d of %d | %.1f %% |" % (
            stem, label, faces, sec, pct(h["out_in"][0]), pct(h["out_in"][1]), pct(h["out_in"][2]),
            pct(h["in_out"][0]), pct(h["in_out"][1]), pct(h["in_out"][2]),
            fe["line_edges_on_reference_lines"], fe["line_edges"], 100.0 * fe["reference_line_length_covered"]))
    if not a.keep:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
