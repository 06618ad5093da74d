#!/usr/bin/env python3
"""Accuracy of .clod cuts per budget (issue 29; scripts/lod_cracks.py is its sibling for cracks).
For each mesh: `conelod lod build` with the defaults (its seconds and bytes), then for each budget
(% of the input's faces) a cut of the file from a far eye by the error in model units (`conelod lod
extract --priority error --no-cull --budget N`), and at the cut's face count the same input simplified
statically by `conelod simplify --groups cone:auto` and by MeshLab's Quadric Edge Collapse
Decimation (asked again until it lands on the count, scripts/compare_qem.py), and Nexus's cut
(`nxsedit FILE.nxs -t T -p cut.ply`) when NXSBUILD and NXSEDIT name its tools. nxsedit's -t bounds
the faces of the cut and of the coarser nodes it replaced together, so its cut holds about half of T:
T is searched (bisection) for the largest Nexus cut of at most the cut's faces, and our file is cut
again to Nexus's count, so that "cut ÷ Nexus" compares the two at equal faces. Errors as
scripts/compare_qem.py measures them: MeshLab's Hausdorff Distance both ways against the input
(samples on vertices, edges and faces), the larger RMS of the two directions, % of the diagonal.

  scripts/lod_fidelity.py MESH.ply... [--budgets 2,5,10,25] [--samples N] [--out DIR]
                          [--build-args '...']

Needs a build (CONELOD_BUILD_DIR, default build/) with conelod and the private meshlabserver
(target private_meshlab); xvfb-run. Prints a markdown table per mesh (also OUT/summary.md) and
writes OUT/results.tsv; the meshes and logs stay in OUT/work/.
"""
import argparse
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from compare_qem import CaseError, Comparison, fmt, last_line, ply_face_count, run  # noqa: E402
from meshdata import read_ply_elements  # noqa: E402

COLUMNS = ["mesh", "faces_in", "budget_pct", "budget", "cut_faces", "fill_pct", "static_faces", "meshlab_faces",
           "nexus_faces", "cut_rms", "static_rms", "meshlab_rms", "nexus_rms", "cut_vs_static", "cut_vs_meshlab",
           "cut_vs_nexus", "build_s", "file_bytes", "nexus_t", "cut_at_nexus_faces", "cut_at_nexus_rms", "error"]


def far_eye(mesh):
    """An eye 100 diagonals in front of the box (+Z): far, so that no group is nearer than another."""
    pos = [(v["x"], v["y"], v["z"]) for v in dict(read_ply_elements(mesh))["vertex"]]
    lo = [min(p[k] for p in pos) for k in range(3)]
    hi = [max(p[k] for p in pos) for k in range(3)]
    diag = sum((h - l) ** 2 for h, l in zip(hi, lo)) ** 0.5
    return "%.9g,%.9g,%.9g" % ((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2 + 100 * diag)


def json_of(cmd, what):
    rc, out, err, _, wall = run(cmd)
    if rc != 0:
        raise CaseError("%s failed (%d): %s" % (what, rc, last_line(err or out)))
    try:
        return json.loads(out), wall
    except ValueError:
        raise CaseError("%s printed no JSON: %s" % (what, last_line(out)))


class Fidelity:
    def __init__(self, a, tools):
        self.a = a
        self.tools = tools
        self.cmp = Comparison(a, tools)  # MeshLab's QEM to an exact count and the Hausdorff runs
        self.cmp.base_cpu = 0.0
        self.nexus = (os.environ.get("NXSBUILD"), os.environ.get("NXSEDIT"))
        self.rows = []

    def mesh(self, mesh):
        a, conelod = self.a, self.tools["conelod"]
        name = os.path.splitext(os.path.basename(mesh))[0]
        work = os.path.join(a.out, "work", name)
        os.makedirs(work, exist_ok=True)
        faces_in = ply_face_count(mesh)
        clod = os.path.join(work, name + ".clod")
        built, _ = json_of([conelod, "lod", "build", mesh, "-o", clod, "--json"] + a.build_args, "conelod lod build")
        eye = far_eye(mesh)
        nxs = None
        if all(self.nexus):
            nxs = os.path.join(work, name + ".nxs")
            rc, out, err, _, _ = run([self.nexus[0], mesh, "-o", nxs])
            if rc != 0 or not os.path.exists(nxs):
                print("  nxsbuild failed (%d): %s" % (rc, last_line(err or out)), flush=True)
                nxs = None
        rows = []
        for b in a.budgets:
            budget = max(1, int(round(b / 100.0 * faces_in)))
            row = {c: "" for c in COLUMNS}
            row.update(mesh=name, faces_in=faces_in, budget_pct=b, budget=budget, build_s=built["seconds"],
                       file_bytes=built["file_bytes"])
            try:
                self.case(mesh, work, clod, eye, budget, nxs, row)
            except CaseError as e:
                row["error"] = str(e)
            rows.append(row)
            print("  %s" % self.text(row), flush=True)
        self.rows += rows
        return name, faces_in, built, rows

    def case(self, mesh, work, clod, eye, budget, nxs, row):
        conelod = self.tools["conelod"]
        tag = "%d" % budget
        cut = os.path.join(work, "cut_%s.ply" % tag)
        j, _ = json_of([conelod, "lod", "extract", clod, "--eye", eye, "--budget", str(budget), "--priority", "error",
                        "--no-cull", "--json", "-o", cut], "conelod lod extract")
        n = int(j["faces"])
        row.update(cut_faces=n, fill_pct=100.0 * n / budget)
        static = os.path.join(work, "static_%s.ply" % tag)
        j, _ = json_of([conelod, "simplify", mesh, "--groups", "cone:auto", "--target-faces", str(n), "--json", "-o",
                        static], "conelod simplify")
        row["static_faces"] = int(j["faces_out"])
        peer = self.cmp.peer_meshlab(mesh, work, n)
        row["meshlab_faces"] = peer["faces"]
        results = [("cut", cut), ("static", static), ("meshlab", peer["path"])]
        if nxs:
            found = self.nexus_cut(nxs, work, tag, n)
            if isinstance(found, str):
                row["error"] = found
            else:
                t, faces, path = found
                row.update(nexus_t=t, nexus_faces=faces)
                results.append(("nexus", path))
                at = cut
                if faces != n:  # our file cut again to Nexus's count
                    at = os.path.join(work, "cut_at_nexus_%s.ply" % tag)
                    j, _ = json_of([conelod, "lod", "extract", clod, "--eye", eye, "--budget", str(faces), "--priority",
                                    "error", "--no-cull", "--json", "-o", at], "conelod lod extract")
                    row["cut_at_nexus_faces"] = int(j["faces"])
                    results.append(("cut_at_nexus", at))
                else:
                    row["cut_at_nexus_faces"] = n
        # Each result in a run of its own: MeshLab's Hausdorff can abort on one of them (a vcglib
        # grid assertion on the bunny's MeshLab QEM result at 6,893 faces), and a peer's abort
        # must not lose the others' figures.
        for key, path in results:
            try:
                row[key + "_rms"] = self.cmp.measure(mesh, work, "measure_%s_%s" % (key, tag), [path])[0][0]
            except CaseError as e:
                if key == "cut":
                    raise
                note = "%s not measured: %s" % (key, e)
                row["error"] = note if not row["error"] else row["error"] + "; " + note
        if row["nexus_faces"] != "" and row["cut_at_nexus_rms"] == "" and row["cut_at_nexus_faces"] == n:
            row["cut_at_nexus_rms"] = row["cut_rms"]
        for key in ("static", "meshlab"):
            if row[key + "_rms"] != "" and row[key + "_rms"] > 0:
                row["cut_vs_" + key] = row["cut_rms"] / row[key + "_rms"]
        if row["nexus_rms"] != "" and row["nexus_rms"] > 0 and row["cut_at_nexus_rms"] != "":
            row["cut_vs_nexus"] = row["cut_at_nexus_rms"] / row["nexus_rms"]

    def nexus_cut(self, nxs, work, tag, n):
        """The largest cut nxsedit gives of at most n faces: (its -t, faces, path), or a message."""
        cache = {}

        def faces_at(t):
            if t not in cache:
                path = os.path.join(work, "nexus_%s_t%d.ply" % (tag, t))
                rc, out, err, _, _ = run([self.nexus[1], nxs, "-t", str(t), "-p", path])
                if rc != 0 or not os.path.exists(path):
                    raise CaseError("nxsedit failed (%d): %s" % (rc, last_line(err or out)))
                cache[t] = (ply_face_count(path), path)
            return cache[t][0]

        try:
            lo, hi = 1, 8 * n  # faces_at(lo) <= n; the cut grows with -t
            if faces_at(hi) <= n:
                lo = hi
            while hi - lo > max(1, n // 2000):
                mid = (lo + hi) // 2
                if faces_at(mid) <= n:
                    lo = mid
                else:
                    hi = mid
            faces = faces_at(lo)
        except CaseError as e:
            return str(e)
        if faces == 0:
            return "Nexus has no cut of at most %d faces (its coarsest nodes hold more)" % n
        for t, (_, path) in cache.items():
            if t != lo:
                os.remove(path)
        return lo, faces, cache[lo][1]

    @staticmethod
    def text(r):
        if r["cut_rms"] == "":
            return "%s %g%%: FAILED: %s" % (r["mesh"], r["budget_pct"], r["error"])
        return "%s %g%%: budget %d, cut %s faces (%.1f %%), RMS cut %s / static %s / MeshLab %s%s%s" % (
            r["mesh"], r["budget_pct"], r["budget"], r["cut_faces"], r["fill_pct"], fmt(r["cut_rms"]),
            fmt(r["static_rms"]), fmt(r["meshlab_rms"]),
            "" if r["nexus_rms"] == "" else " / Nexus %s at %s faces (our cut there %s)" % (
                fmt(r["nexus_rms"]), r["nexus_faces"], fmt(r["cut_at_nexus_rms"])),
            "" if not r["error"] else "; " + r["error"])


def table(name, faces_in, built, rows, nexus):
    out = ["### %s (%s faces): build %.2f s, %s bytes" % (name, "{:,}".format(faces_in), built["seconds"],
                                                           "{:,}".format(built["file_bytes"])), "",
           "| budget | cut faces (fill) | RMS: cut | static (cone:auto) | MeshLab QEM |%s cut ÷ static | "
           "cut ÷ MeshLab |%s" % (" Nexus cut (faces) | our cut at Nexus's faces |" if nexus else "",
                                  " cut ÷ Nexus, equal faces |" if nexus else ""),
           "|---|---|---|---|---|---|---|" + ("---|---|---|" if nexus else "")]
    for r in rows:
        if r["cut_rms"] == "":
            out.append("| %g %% | failed: %s |" % (r["budget_pct"], r["error"]))
            continue
        cells = ["%g %% (%s)" % (r["budget_pct"], "{:,}".format(r["budget"])),
                 "%s (%.1f %%)" % ("{:,}".format(r["cut_faces"]), r["fill_pct"]), fmt(r["cut_rms"]),
                 fmt(r["static_rms"]), fmt(r["meshlab_rms"])]
        if nexus:
            if r["nexus_faces"] == "":
                cells += ["— (%s)" % r["error"], "—"]
            else:
                cells += ["%s (%s)" % (fmt(r["nexus_rms"]), "{:,}".format(r["nexus_faces"])),
                          "%s (%s)" % (fmt(r["cut_at_nexus_rms"]), "{:,}".format(r["cut_at_nexus_faces"]))]
        cells += [fmt(r["cut_vs_static"], 2), fmt(r["cut_vs_meshlab"], 2)]
        if nexus:
            cells.append(fmt(r["cut_vs_nexus"], 2))
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+", metavar="MESH")
    ap.add_argument("--budgets", default="2,5,10,25", help="budgets, %% of the input's faces [2,5,10,25]")
    ap.add_argument("--samples", type=int, default=500000, help="Hausdorff samples per direction [500000]")
    ap.add_argument("--out", default="lod_fidelity", help="output folder [lod_fidelity]")
    ap.add_argument("--build-args", default="", help="extra options for conelod lod build")
    a = ap.parse_args()
    try:
        a.budgets = [float(b) for b in a.budgets.split(",") if b.strip()]
    except ValueError:
        sys.exit("--budgets: comma-separated percentages, e.g. 2,5,10,25")
    if not a.budgets or not all(0 < b <= 100 for b in a.budgets):
        sys.exit("--budgets: percentages in (0, 100]")
    if a.samples < 1000:
        sys.exit("--samples: at least 1000")
    for m in a.meshes:
        if not os.path.isfile(m):
            sys.exit("no mesh file %s" % m)
    a.build_args = a.build_args.split()
    build = os.environ.get("CONELOD_BUILD_DIR") or os.path.join(HERE, "..", "build")
    tools = {"conelod": os.path.join(build, "conelod", "conelod"),
             "server": os.path.join(build, "meshlab", "bin", "meshlabserver")}
    for t in tools.values():
        if not os.path.exists(t):
            sys.exit("missing %s: build the project first (cmake --build %s --target conelod private_meshlab)" %
                     (t, build))
    a.out = os.path.abspath(a.out)
    os.makedirs(os.path.join(a.out, "work"), exist_ok=True)
    f = Fidelity(a, tools)
    nexus = all(f.nexus)
    md = []
    for mesh in a.meshes:
        print("== %s" % mesh, flush=True)
        try:
            name, faces_in, built, rows = f.mesh(os.path.abspath(mesh))
        except CaseError as e:
            print("  FAILED: %s" % e, flush=True)
            continue
        md.append(table(name, faces_in, built, rows, nexus))
        print(md[-1], flush=True)
    with open(os.path.join(a.out, "summary.md"), "w") as out:
        out.write("\n".join(md))
    with open(os.path.join(a.out, "results.tsv"), "w") as out:
        out.write("\t".join(COLUMNS) + "\n")
        for r in f.rows:
            out.write("\t".join(str(r[c]) for c in COLUMNS) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
