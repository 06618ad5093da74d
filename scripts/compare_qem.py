#!/usr/bin/env python3
"""Compares ConeLOD's group-preserving quadric edge collapse (`conelod simplify`) with MeshLab's
"Simplification: Quadric Edge Collapse Decimation" and meshoptimizer's meshopt_simplify at equal
face counts. Python 3 standard library only. Run it through scripts/compare_qem.sh, which finds
the build.

For every mesh, every target (fraction of the input's faces) and every group source (each level of
the mesh's normal-cone hierarchy, plus `auto` when the CLI offers `--groups cone:auto`):
  1. ours: `conelod simplify MESH --groups cone:L --target-faces T --json -o ours.ply`; it reaches
     N faces (N may be above T when the groups leave no room);
  2. MeshLab's QEM (meshlabserver, its dialog's defaults) and meshopt_simplify (tools/
     meshopt_simplify), both on the same input to EXACTLY N faces: each is asked again with a
     corrected target until it lands on N (a peer that cannot is flagged in the table);
  3. the error of each result: MeshLab's Hausdorff Distance both ways between the input and the
     result (samples on vertices, edges and faces), the larger RMS of the two directions and the
     larger maximum, in % of the input's bounding-box diagonal;
  4. group integrity of ours (the CLI's own measure: groups neither split nor vanished) and, when
     the CLI reports them, the cones over their level's threshold.
A case that fails (a tool exits with an error, a log without figures) becomes a row with the
reason; the run goes on. Writes OUT/results.tsv (one row per case), OUT/summary.md (a table per
mesh and the overall figures), OUT/<mesh>.png (error against faces, one curve per tool) and keeps
the meshes and logs in OUT/work/.
"""
import argparse
import json
import math
import os
import re
import resource
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mlx_filters import builtin_qem, hausdorff as hausdorff_filter, script as script_text  # noqa: E402

TOOLS = ("ours", "meshlab", "meshopt")
TOOL_LABEL = {"ours": "ours", "meshlab": "MeshLab QEM", "meshopt": "meshopt_simplify"}
# results.tsv: one row per (mesh, target, level); these columns, always, in this order.
COLUMNS = ["mesh", "faces_in", "target_pct", "asked", "level", "group_level", "groups", "status",
           "ours_faces", "reached_pct", "target_reached", "ours_s", "ours_rms", "ours_max", "intact_pct",
           "cones_over_threshold", "mode",
           "meshlab_faces", "meshlab_exact", "meshlab_s", "meshlab_rms", "meshlab_max",
           "meshopt_faces", "meshopt_exact", "meshopt_s", "meshopt_rms", "meshopt_max",
           "rms_ratio_meshlab", "rms_ratio_meshopt", "meshopt_floor_faces", "meshopt_floor_nonmanifold_edges",
           "input_nonmanifold_edges", "error"]


class CaseError(Exception):
    """A step of one case failed: the case's row says why, the run goes on."""


def run(cmd, cwd=None, timeout=3600):
    """Runs cmd; returns (exit code, stdout, stderr, CPU seconds of it and its children, wall s)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=cwd, timeout=timeout)
        rc, out, err = p.returncode, p.stdout.decode(errors="replace"), p.stderr.decode(errors="replace")
    except subprocess.TimeoutExpired:
        rc, out, err = 124, "", "timed out after %d s" % timeout
    except OSError as e:
        rc, out, err = 127, "", str(e)
    wall = time.time() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return rc, out, err, cpu, wall


def last_line(text):
    lines = [l for l in text.strip().splitlines() if l.strip()]
    return lines[-1].strip() if lines else ""


def ply_face_count(path):
    try:
        with open(path, "rb") as f:
            for raw in f:
                line = raw.decode("ascii", "replace").strip()
                if line.startswith("element face"):
                    return int(line.split()[2])
                if line == "end_header":
                    break
    except OSError:
        pass
    return -1


class Meshlab:
    """The private meshlabserver under xvfb-run."""

    def __init__(self, server):
        self.server = server

    def run(self, inputs, filters, work, tag, output=None):
        """Runs the filters on the inputs; returns (log text, CPU s). Raises CaseError on failure."""
        mlx = os.path.join(work, tag + ".mlx")
        log = os.path.join(work, tag + ".log")
        with open(mlx, "w") as f:
            f.write(script_text(*filters))
        if os.path.exists(log):
            os.remove(log)
        cmd = ["xvfb-run", "-a", self.server, "-l", log, "-i"] + inputs + ["-s", mlx]
        if output:
            cmd += ["-o", output]
        rc, out, err, cpu, _ = run(cmd, cwd=work)
        if rc in (134, 139):  # meshlabserver aborts now and then on a long run: once more
            print("  meshlabserver aborted (%d) on %s: once more" % (rc, tag), flush=True)
            if os.path.exists(log):
                os.remove(log)
            rc, out, err, cpu, _ = run(cmd, cwd=work)
        text = open(log, errors="replace").read() if os.path.exists(log) else ""
        if rc != 0:
            raise CaseError("meshlabserver failed (%d) on %s: %s" % (rc, tag, last_line(text + out + err)))
        return text, cpu


def hausdorff_results(log):
    """Every Hausdorff result of the log, in order: (max, mean, rms) in % of the diagonal."""
    out = []
    for m in re.finditer(r"Values w\.r\.t\. BBox Diag \(([0-9.eE+-]+)\)\s*\n\s*min : ([0-9.eE+-]+)\s+max ([0-9.eE+-]+)"
                         r"\s+mean : ([0-9.eE+-]+)\s+RMS : ([0-9.eE+-]+)", log):
        out.append(tuple(100 * float(m.group(i)) for i in (3, 4, 5)))
    return out


class Comparison:
    def __init__(self, a, tools):
        self.a = a
        self.tools = tools
        self.meshlab = Meshlab(tools["server"])
        self.has_auto = None  # whether this CLI takes --groups cone:auto: asked on the first mesh
        self.rows = []
        self.nm_cache = {}  # path -> its non-manifold edges

    def detect_auto(self, mesh):
        """Feature detection across versions: a CLI without `cone:auto` refuses it as a usage error
        (exit 1); target ratio 1 makes the probe cheap (grouping only, no collapse)."""
        rc, _, _, _, _ = run([self.tools["conelod"], "simplify", mesh, "--groups", "cone:auto", "--target-ratio", "1",
                              "--json"])
        if rc in (0, 1):
            self.has_auto = rc == 0
            if not self.has_auto:
                print("note: this conelod simplify refuses --groups cone:auto: fixed levels only", flush=True)

    # -- one mesh ---------------------------------------------------------------------------------
    def compare_mesh(self, mesh):
        a = self.a
        name = os.path.splitext(os.path.basename(mesh))[0]
        work = os.path.join(a.out, "work", name)
        os.makedirs(work, exist_ok=True)
        print("== %s" % name, flush=True)
        faces_in = ply_face_count(mesh)
        rc, out, err, _, _ = run([self.tools["conelod"], "group", mesh, "--json"])
        try:
            levels = json.loads(out)["levels"] if rc == 0 else None
        except (ValueError, KeyError):
            levels = None
        if levels is None:
            reason = "conelod group failed (%d): %s" % (rc, last_line(err or out))
            print("  " + reason, flush=True)
            for t in a.targets:
                self.rows.append(self.failed_row(name, faces_in, t, "-", reason))
            return
        if self.has_auto is None and "auto" in a.levels:
            self.detect_auto(mesh)
        group_counts = {i + 1: lv.get("groups", -1) for i, lv in enumerate(levels)}
        sources = []
        for s in a.levels:
            if s == "all":
                sources += [str(i) for i in range(1, len(levels) + 1)]
            elif s == "auto":
                if self.has_auto:
                    sources.append("auto")
            elif s.isdigit() and int(s) > len(levels):
                continue  # a level this mesh does not have
            else:
                sources.append(s)
        sources = list(dict.fromkeys(sources))
        if not sources:
            reason = "none of the levels asked (%s) exists: this mesh has %d" % (",".join(a.levels), len(levels))
            print("  " + reason, flush=True)
            for t in a.targets:
                self.rows.append(self.failed_row(name, faces_in, t, "-", reason))
            return

        # meshlabserver's own CPU time on this input (load, save): subtracted from the QEM runs'.
        try:
            _, self.base_cpu = self.meshlab.run([mesh], [], work, "noop", os.path.join(work, "noop.ply"))
        except CaseError as e:
            self.base_cpu = 0.0
            print("  " + str(e), flush=True)
        peers = {}  # (tool, faces) -> result dict: a peer depends only on the face count asked
        for t in a.targets:
            asked = max(1, int(round(t * faces_in)))
            for src in sources:
                row = self.case(mesh, name, work, faces_in, t, asked, src, group_counts, peers)
                self.rows.append(row)
                print("  %5g%% %-6s %s" % (100 * t, src, self.row_text(row)), flush=True)
                write_tsv(self.rows, os.path.join(a.out, "results.tsv"))  # as it goes: a stopped run keeps its rows

    def failed_row(self, name, faces_in, t, level, reason):
        row = {c: "" for c in COLUMNS}
        row.update(mesh=name, faces_in=faces_in, target_pct=100 * t, asked=max(1, int(round(t * faces_in))),
                   level=level, status="failed", error=reason)
        return row

    def row_text(self, r):
        if r["status"] == "failed":
            return "FAILED: " + r["error"]
        return "%s -> %s faces, RMS %s / %s / %s (ours / MeshLab / meshopt), intact %s%%%s" % (
            r["asked"], r["ours_faces"], fmt(r["ours_rms"]), fmt(r["meshlab_rms"]), fmt(r["meshopt_rms"]),
            fmt(r["intact_pct"], 1), ("; " + r["error"]) if r["error"] else "") + floor_text(r)

    # -- one case ---------------------------------------------------------------------------------
    def case(self, mesh, name, work, faces_in, t, asked, src, group_counts, peers):
        row = self.failed_row(name, faces_in, t, src, "")
        tag = "%g_%s" % (100 * t, src.replace(":", ""))
        groups_arg = "cone:" + src if (src.isdigit() or src == "auto") else src
        ours = os.path.join(work, "ours_%s.ply" % tag)
        cmd = [self.tools["conelod"], "simplify", mesh, "--groups", groups_arg, "--target-faces", str(asked),
               "--json", "-o", ours] + self.a.ours_args
        rc, out, err, _, _ = run(cmd)
        try:
            # Exit 2 with a JSON: a user-chosen level that cannot reach the target (the CLI says
            # which would); the mesh it reached is written and compared at its face count.
            if rc not in (0, 2):
                raise CaseError("conelod simplify failed (%d): %s" % (rc, last_line(err or out)))
            try:
                j = json.loads(out)
            except ValueError:
                raise CaseError("conelod simplify failed (%d): %s" % (rc, last_line(err or out)))
            if rc == 2 and j.get("target_reached", True):
                raise CaseError("conelod simplify failed (2): %s" % last_line(err or out))
            n = int(j["faces_out"])
            level = j.get("group_level", int(src) if src.isdigit() else "")
            row.update(group_level=level, groups=j.get("groups_before", group_counts.get(level, "")),
                       ours_faces=n, reached_pct=100.0 * n / faces_in,
                       target_reached=j.get("target_reached", n <= 1.01 * asked),
                       ours_s=float(j["seconds"]),
                       intact_pct=100.0 * float(j["integrity"]),
                       cones_over_threshold=j.get("cones_over_threshold", "n/a"), mode=j.get("mode", "n/a"))
            notes = []
            for tool in ("meshlab", "meshopt"):
                key = (tool, n)
                if key not in peers:
                    try:
                        peers[key] = getattr(self, "peer_" + tool)(mesh, work, n)
                    except CaseError as e:
                        peers[key] = {"error": str(e)}
                p = peers[key]
                if "error" in p:
                    notes.append("%s: %s" % (TOOL_LABEL[tool], p["error"]))
                    continue
                row.update({tool + "_faces": p["faces"], tool + "_exact": p["faces"] == n, tool + "_s": p["s"]})
                if p["faces"] != n:
                    notes.append("%s reached %d faces, not %d" % (TOOL_LABEL[tool], p["faces"], n))
            # The results not measured yet (a peer's is shared between levels), one run each.
            todo = [("ours", ours, None)] + [(tool, peers[(tool, n)]["path"], peers[(tool, n)])
                                             for tool in ("meshlab", "meshopt")
                                             if "error" not in peers[(tool, n)] and "rms" not in peers[(tool, n)]]
            errors = self.measure(mesh, work, "measure_" + tag, [path for _, path, _ in todo])
            for (tool, _, p), (rms, mx) in zip(todo, errors):
                if p is not None:
                    p["rms"], p["max"] = rms, mx
                else:
                    row["ours_rms"], row["ours_max"] = rms, mx
            for tool in ("meshlab", "meshopt"):
                p = peers[(tool, n)]
                if "rms" in p:
                    row[tool + "_rms"], row[tool + "_max"] = p["rms"], p["max"]
                    if p["rms"] > 0:
                        row["rms_ratio_" + tool] = row["ours_rms"] / p["rms"]
            if not row["target_reached"]:
                # Our floor against meshoptimizer's: where it stops when asked for the target
                # itself, and whether its result keeps the input's manifold edges (ours never
                # makes a non-manifold edge).
                try:
                    key = ("meshopt", asked)
                    if key not in peers:
                        peers[key] = self.peer_meshopt(mesh, work, asked)
                    row["meshopt_floor_faces"] = peers[key]["faces"]
                    row["meshopt_floor_nonmanifold_edges"] = self.nonmanifold_edges(peers[key]["path"])
                    row["input_nonmanifold_edges"] = self.nonmanifold_edges(mesh)
                except CaseError as e:
                    notes.append("meshopt's floor: %s" % e)
            row["status"] = "ok" if not notes else "peer issue"
            row["error"] = "; ".join(notes)
        except CaseError as e:
            row["status"], row["error"] = "failed", str(e)
        return row

    def peer_meshlab(self, mesh, work, n):
        """MeshLab's QEM to exactly n faces: asked for n, then corrected by what it missed by."""
        best = None
        ask = n
        tried = set()
        for attempt in range(4):
            tried.add(ask)
            path = os.path.join(work, "meshlab_%d_%d.ply" % (n, ask))
            log, cpu = self.meshlab.run([mesh], [builtin_qem(ask)], work, "meshlab_%d_%d" % (n, ask), path)
            faces = ply_face_count(path)
            if faces < 0:
                raise CaseError("MeshLab QEM wrote no mesh")
            result = {"faces": faces, "s": max(0.0, cpu - self.base_cpu), "path": path}
            if best is None or abs(faces - n) < abs(best["faces"] - n):
                best = result
            if faces == n:
                break
            ask = max(1, ask + (n - faces))
            if ask in tried:
                ask = ask + (1 if faces < n else -1)
            if ask in tried:
                break
        return best

    def nonmanifold_edges(self, path):
        """Edges used by 3+ faces (`conelod info`), once per file."""
        if path not in self.nm_cache:
            rc, out, err, _, _ = run([self.tools["conelod"], "info", path, "--json"])
            try:
                self.nm_cache[path] = int(json.loads(out)["non_manifold_edges"])
            except (ValueError, KeyError):
                raise CaseError("conelod info failed (%d): %s" % (rc, last_line(err or out)))
        return self.nm_cache[path]

    def peer_meshopt(self, mesh, work, n):
        path = os.path.join(work, "meshopt_%d.ply" % n)
        rc, out, err, _, _ = run([self.tools["meshopt"], mesh, path, "--target-faces", str(n)])
        if rc != 0:
            raise CaseError("meshopt_simplify failed (%d): %s" % (rc, last_line(err or out)))
        try:
            j = json.loads(out)
        except ValueError:
            raise CaseError("meshopt_simplify printed no JSON")
        return {"faces": int(j["faces"]), "s": float(j["time_ms"]) / 1000.0, "path": path}

    def measure(self, mesh, work, tag, results):
        """[(RMS, max)] per result: Hausdorff both ways against the input (layer 0), % of the diagonal.
        Each result in a meshlabserver run of its own: with the input and three results loaded,
        MeshLab 2020.09's Hausdorff filter aborts on the dragon."""
        errors = []
        for i, result in enumerate(results):
            filters = [hausdorff_filter(1, 0, self.a.samples, sample_edges=True),
                       hausdorff_filter(0, 1, self.a.samples, sample_edges=True)]
            run_tag = tag if len(results) == 1 else "%s_%d" % (tag, i)
            log, _ = self.meshlab.run([mesh, result], filters, work, run_tag)
            h = hausdorff_results(log)[-2:]
            if len(h) != 2:
                raise CaseError("no Hausdorff figures in %s.log" % run_tag)
            errors.append((max(h[0][2], h[1][2]), max(h[0][0], h[1][0])))
        return errors


# -- outputs ---------------------------------------------------------------------------------------
def fmt(x, digits=4):
    if x == "" or x is None:
        return "–"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, float):
        return "n/a" if x != x else "%.*f" % (digits, x)
    return str(x)


def num(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and x == x


def geomean(values):
    values = [v for v in values if num(v) and v > 0]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def write_tsv(rows, path):
    with open(path, "w") as f:
        f.write("\t".join(COLUMNS) + "\n")
        for r in rows:
            f.write("\t".join(tsv_value(r[c]) for c in COLUMNS) + "\n")


def tsv_value(v):
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return "%.6g" % v
    return str(v).replace("\t", " ").replace("\n", " ")


def mesh_table(name, rows):
    faces_in = rows[0]["faces_in"] if rows else "?"
    md = ["### %s (%s faces)\n" % (name, faces_in),
          "| target | level (groups) | asked | reached | RMS ours / MeshLab / meshopt | ratio MeshLab | ratio meshopt "
          "| max ours / MeshLab / meshopt | intact | cones over threshold | time s ours / MeshLab / meshopt | note |",
          "|---:|---|---:|---:|---|---:|---:|---|---:|---:|---|---|"]
    for r in rows:
        if r["status"] == "failed":
            md.append("| %g%% | %s | %s | – | – | – | – | – | – | – | – | failed: %s |"
                      % (r["target_pct"], r["level"], r["asked"], r["error"]))
            continue
        level = r["level"] if r["group_level"] in ("", r["level"]) or r["level"] == str(r["group_level"]) \
            else "%s → %s" % (r["level"], r["group_level"])
        md.append("| %g%% | %s (%s) | %s | %s (%.1f%%) | %s / %s / %s | %s | %s | %s / %s / %s | %s%% | %s | %s / %s / %s | %s |" % (
            r["target_pct"], level, r["groups"], r["asked"], r["ours_faces"], r["reached_pct"],
            fmt(r["ours_rms"]), fmt(r["meshlab_rms"]), fmt(r["meshopt_rms"]),
            fmt(r["rms_ratio_meshlab"], 2), fmt(r["rms_ratio_meshopt"], 2),
            fmt(r["ours_max"], 3), fmt(r["meshlab_max"], 3), fmt(r["meshopt_max"], 3),
            fmt(r["intact_pct"], 1), fmt(r["cones_over_threshold"]),
            fmt(r["ours_s"], 3), fmt(r["meshlab_s"], 3), fmt(r["meshopt_s"], 3), r["error"]))
    return "\n".join(md) + "\n"


def floor_text(r):
    """Where meshopt_simplify stops when asked for the target, and its non-manifold edges."""
    if not num(r.get("meshopt_floor_faces")):
        return ""
    return "; meshopt_simplify asked for %s stops at %s faces, with %s non-manifold edges (the input: %s)" % (
        r["asked"], r["meshopt_floor_faces"], r["meshopt_floor_nonmanifold_edges"], r["input_nonmanifold_edges"])


def overall(rows, a, has_auto):
    ok = [r for r in rows if r["status"] != "failed"]
    lines = ["## Overall\n"]
    failed = [r for r in rows if r["status"] == "failed"]
    lines.append("- cases: %d, failed: %d%s" % (len(rows), len(failed), "".join(
        "\n  - %s %g%% level %s: %s" % (r["mesh"], r["target_pct"], r["level"], r["error"]) for r in failed)))
    inexact = [r for r in ok if r["meshlab_exact"] is not True or r["meshopt_exact"] is not True]
    off = [abs(r[t + "_faces"] - r["ours_faces"]) for r in ok for t in ("meshlab", "meshopt") if num(r[t + "_faces"])]
    lines.append("- peers at exactly our face count: %d of %d cases%s%s" % (
        len(ok) - len(inexact), len(ok),
        " (the others at most %d face(s) away)" % max(off) if inexact and off else "", "".join(
            "\n  - %s %g%% level %s: %s" % (r["mesh"], r["target_pct"], r["level"], r["error"]) for r in inexact)))
    if "auto" not in a.levels:
        pass
    elif has_auto:
        auto = [r for r in rows if r["level"] == "auto"]
        missed = [r for r in auto if r["status"] == "failed" or not r["ours_faces"] <= 1.01 * r["asked"]]
        lines.append("- `cone:auto`: target reached within 1 %% in %d of %d cases%s" % (
            len(auto) - len(missed), len(auto), "".join(
                "\n  - %s %g%%: %s faces for %s asked%s" % (
                    r["mesh"], r["target_pct"], r["ours_faces"] or "no", r["asked"], floor_text(r))
                for r in missed)))
        intact = [r for r in auto if num(r["intact_pct"]) and r["intact_pct"] >= 100.0]
        lines.append("- `cone:auto`: groups 100 %% intact in %d of %d cases" % (len(intact), len(auto)))
    else:
        lines.append("- `cone:auto`: refused by this build's `conelod simplify` (exit 1): fixed levels only")
    for label, subset in (("all cases", ok), ("`cone:auto`", [r for r in ok if r["level"] == "auto"])):
        if not subset or (label != "all cases" and not has_auto):
            continue
        ml = [r["rms_ratio_meshlab"] for r in subset if num(r["rms_ratio_meshlab"])]
        mo = [r["rms_ratio_meshopt"] for r in subset if num(r["rms_ratio_meshopt"])]
        maxwin_ml = [r for r in subset if num(r["ours_max"]) and num(r["meshlab_max"]) and r["ours_max"] <= r["meshlab_max"]]
        maxwin_mo = [r for r in subset if num(r["ours_max"]) and num(r["meshopt_max"]) and r["ours_max"] <= r["meshopt_max"]]
        lines.append("- %s: RMS ours / MeshLab's QEM: geometric mean %s, worst %s, ≤ 1.1× in %d of %d, ≤ 1.0× in %d; "
                     "ours / meshopt: geometric mean %s, ≤ 1.0× in %d of %d; max error ≤ MeshLab's in %d of %d, "
                     "≤ meshopt's in %d of %d" % (
                         label, fmt(geomean(ml), 2), fmt(max(ml), 2) if ml else "n/a", sum(v <= 1.1 for v in ml),
                         len(ml), sum(v <= 1.0 for v in ml), fmt(geomean(mo), 2), sum(v <= 1.0 for v in mo), len(mo),
                         len(maxwin_ml), len(subset), len(maxwin_mo), len(subset)))
    fine = [r for r in ok if r["level"] != "auto" and num(r["groups"]) and r["groups"] > 0
            and r["asked"] >= 8 * r["groups"] and num(r["rms_ratio_meshlab"])]
    if fine:
        lines.append("- groups chosen by the user (a level, pca:K) with ≥ 8 faces per group at the target: RMS ≤ 1.25× MeshLab's in %d of %d "
                     "(geometric mean %s)" % (sum(r["rms_ratio_meshlab"] <= 1.25 for r in fine), len(fine),
                                             fmt(geomean([r["rms_ratio_meshlab"] for r in fine]), 2)))
    lines.append("")
    lines.append("RMS / max: MeshLab's Hausdorff Distance between the input and the result both ways (%d samples on "
                 "vertices, edges and faces), the larger of the two directions, %% of the input's bounding-box "
                 "diagonal. MeshLab's QEM (dialog defaults) and meshopt_simplify (target_error 1) run to the face "
                 "count ours reached. Time: ours = `conelod simplify`'s own figure (simplification only); MeshLab = "
                 "meshlabserver's CPU time minus that of a run without the filter; meshopt = the one call that made "
                 "the result. Level `a → b`: asked `a`, the CLI used level `b`." % a.samples)
    return "\n".join(lines) + "\n"


def plot(name, rows, out_dir):
    """OUT/<name>.png: RMS against faces, one curve per tool (ours: cone:auto as a curve, the fixed
    levels as points)."""
    dat = os.path.join(out_dir, "work", name, "plot.dat")
    series = []
    with open(dat, "w") as f:
        def block(title, pts, style):
            pts = sorted(set(p for p in pts if num(p[0]) and num(p[1]) and p[1] > 0))
            if not pts:
                return
            f.write("# %s\n" % title)
            for x, y in pts:
                f.write("%d\t%.6g\n" % (x, y))
            f.write("\n\n")
            series.append((title, style))
        ok = [r for r in rows if r["status"] != "failed"]
        block("MeshLab QEM", [(r["meshlab_faces"], r["meshlab_rms"]) for r in ok], "linespoints lw 2 pt 7")
        block("meshopt_simplify", [(r["meshopt_faces"], r["meshopt_rms"]) for r in ok], "linespoints lw 2 pt 5")
        block("ours, cone:auto", [(r["ours_faces"], r["ours_rms"]) for r in ok if r["level"] == "auto"],
              "linespoints lw 2 pt 9")
        block("ours, fixed levels", [(r["ours_faces"], r["ours_rms"]) for r in ok if r["level"] != "auto"],
              "points pt 1 ps 1.5")
    if not series:
        return
    png = os.path.join(out_dir, name + ".png")
    plots = ", \\\n     ".join("'%s' index %d using 1:2 with %s title \"%s\"" % (dat, i, style, title)
                              for i, (title, style) in enumerate(series))
    gp = """set terminal pngcairo size 800,500 font "DejaVu Sans,10"
set output '{png}'
set termoption noenhanced
set title "{name}: error at equal face counts"
set xlabel "faces after simplification"
set ylabel "RMS distance, % of bbox diagonal (larger of both ways)"
set logscale xy
set grid
set key top right
plot {plots}
""".format(png=png, name=name, plots=plots)
    p = subprocess.run(["gnuplot"], input=gp.encode(), stderr=subprocess.PIPE)
    if p.returncode != 0:
        print("gnuplot failed: %s" % p.stderr.decode(errors="replace"), file=sys.stderr)


TITLE = "# ConeLOD against MeshLab's QEM and meshoptimizer at equal face counts\n"


def read_tsv(path):
    """The rows of a results.tsv, with numbers and yes/no back as Python values."""
    rows = []
    with open(path) as f:
        header = f.readline().rstrip("\n").split("\t")
        for line in f:
            row = {c: "" for c in COLUMNS}
            for k, v in zip(header, line.rstrip("\n").split("\t")):
                if v in ("yes", "no"):
                    v = v == "yes"
                elif k not in ("mesh", "level", "status", "error", "mode"):
                    try:
                        v = float(v) if k.endswith(("_rms", "_max", "_s", "_pct")) or k.startswith("rms_") else int(v)
                    except ValueError:
                        try:
                            v = float(v)
                        except ValueError:
                            pass
                row[k] = v
            rows.append(row)
    return rows


def report_only(a):
    """summary.md and plots from the results.tsv of earlier runs (e.g. one run per mesh)."""
    rows = []
    for path in a.report_from.split(","):
        if not os.path.isfile(path):
            sys.exit("--report-from: no file %s" % path)
        rows += read_tsv(path)
    has_auto = any(r["level"] == "auto" for r in rows)
    if not has_auto:
        a.levels = [s for s in a.levels if s != "auto"]
    md = [TITLE]
    for name in dict.fromkeys(r["mesh"] for r in rows):
        mine = [r for r in rows if r["mesh"] == name]
        os.makedirs(os.path.join(a.out, "work", name), exist_ok=True)
        md.append(mesh_table(name, mine))
        plot(name, mine, a.out)
    md.append(overall(rows, a, has_auto))
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write("\n".join(md))
    write_tsv(rows, os.path.join(a.out, "results.tsv"))
    print("wrote %s from %d rows" % (os.path.join(a.out, "summary.md"), len(rows)))


def default_meshes(source):
    folder = os.environ.get("CONELOD_TEST_MESHES") or os.path.join(source, "..", "shared", "test_meshes")
    if not os.path.isdir(folder):
        sys.exit("no test meshes: %s is not a folder (set CONELOD_TEST_MESHES or pass --meshes)" % folder)
    return sorted(os.path.join(folder, f) for f in os.listdir(folder) if f.endswith(".ply")), folder


def holes_mesh(source_mesh, out_dir, holes=120, radius=0.012):
    """A mesh with many holes, made deterministically from `source_mesh` (the closed armadillo):
    the faces with a vertex within `radius` x the bounding-box diagonal of every (n / holes)-th
    vertex are removed. Written once to OUT_DIR/<name>_holes.ply; returns its path."""
    from meshdata import read_ply_elements, write_binary_ply
    name = os.path.splitext(os.path.basename(source_mesh))[0] + "_holes"
    path = os.path.join(out_dir, name + ".ply")
    if os.path.isfile(path):
        return path
    els = dict(read_ply_elements(source_mesh))
    verts = [(r["x"], r["y"], r["z"]) for r in els["vertex"]]
    faces = [r["vertex_indices"] for r in els["face"]]
    lo = [min(v[i] for v in verts) for i in range(3)]
    hi = [max(v[i] for v in verts) for i in range(3)]
    r2 = (radius * math.dist(lo, hi)) ** 2
    centres = [verts[i] for i in range(0, len(verts), max(1, len(verts) // holes))][:holes]
    cut = [any(sum((p[i] - c[i]) ** 2 for i in range(3)) < r2 for c in centres) for p in verts]
    kept = [f for f in faces if not any(cut[v] for v in f)]
    os.makedirs(out_dir, exist_ok=True)
    write_binary_ply(path, verts, kept, ["%d holes cut from %s by scripts/compare_qem.py"
                                         % (holes, os.path.basename(source_mesh))])
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes_pos", nargs="*", metavar="MESH", help="meshes (paths); same as --meshes")
    ap.add_argument("--build", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--meshes", default="", help="comma-separated mesh paths, or names (or parts of names) of "
                    "meshes in the test mesh folder [all of them]")
    ap.add_argument("--targets", default="0.5,0.1,0.02", help="target fractions of the input faces [0.5,0.1,0.02]")
    ap.add_argument("--levels", default="all,auto", help="comma-separated group sources: level numbers, all, "
                    "auto, pca:K [all,auto]")
    ap.add_argument("--samples", type=int, default=500000, help="Hausdorff samples per direction [500000]")
    ap.add_argument("--out", default="qem_compare", help="output folder [qem_compare]")
    ap.add_argument("--report-from", default="", help="comma-separated results.tsv files of earlier runs: write "
                    "OUT/summary.md and the plots from them, run nothing")
    ap.add_argument("--ours-args", default="", help="extra options for conelod simplify, e.g. '--keep-cones'")
    a = ap.parse_args()
    try:
        a.targets = [float(t) for t in a.targets.split(",") if t.strip()]
    except ValueError:
        sys.exit("--targets: comma-separated fractions, e.g. 0.5,0.1,0.02")
    if not a.targets or not all(0 < t <= 1 for t in a.targets):
        sys.exit("--targets: fractions in (0, 1]")
    a.levels = [s.strip() for s in a.levels.split(",") if s.strip()]
    for s in a.levels:
        if not (s in ("all", "auto") or (s.isdigit() and int(s) >= 1) or re.fullmatch(r"pca:[1-9][0-9]*", s)):
            sys.exit("--levels: %r is not a level number, all, auto or pca:K" % s)
    if a.samples < 1000:
        sys.exit("--samples: at least 1000")
    a.ours_args = a.ours_args.split()

    wanted = [m for m in a.meshes.split(",") if m.strip()] + a.meshes_pos
    meshes = []
    if wanted:
        pool = None
        for w in wanted:
            if os.path.isfile(w):
                meshes.append(os.path.abspath(w))
                continue
            if pool is None:
                pool, _ = default_meshes(a.source)
            hits = [p for p in pool if w in os.path.basename(p)]
            if not hits and w.endswith("_holes"):  # the generated mesh with many holes
                base = [p for p in pool if w[:-len("_holes")] in os.path.basename(p)]
                hits = [holes_mesh(base[0], os.path.join(os.path.abspath(a.out), "derived"))] if base else []
            if not hits:
                sys.exit("--meshes: no mesh file or test mesh named like %r" % w)
            meshes += hits
        meshes = list(dict.fromkeys(meshes))
    elif not a.report_from:
        meshes, _ = default_meshes(a.source)
        # Many holes (borders everywhere): generated from the closed armadillo. (Non-manifold
        # edges: the test meshes' stanford_dragon_vrip_res2 and stanford_bunny_bun_zipper_res4.)
        armadillo = [m for m in meshes if "armadillo" in os.path.basename(m)]
        if armadillo:
            meshes.append(holes_mesh(armadillo[0], os.path.join(os.path.abspath(a.out), "derived")))
    tools = {"conelod": os.path.join(a.build, "conelod", "conelod"),
             "server": os.path.join(a.build, "meshlab", "bin", "meshlabserver"),
             "meshopt": os.path.join(a.build, "tools", "meshopt_simplify")}
    for t in tools.values():
        if not os.path.exists(t):
            sys.exit("missing %s: build the project first (cmake --build %s --target conelod private_meshlab "
                     "meshopt_simplify)" % (t, a.build))
    a.out = os.path.abspath(a.out)
    os.makedirs(os.path.join(a.out, "work"), exist_ok=True)
    if a.report_from:
        return report_only(a)

    c = Comparison(a, tools)
    md = [TITLE]
    for mesh in meshes:
        start = len(c.rows)
        try:
            c.compare_mesh(mesh)
        except Exception as e:  # never abort the whole run: the mesh's row says what went wrong
            c.rows.append(c.failed_row(os.path.splitext(os.path.basename(mesh))[0], ply_face_count(mesh),
                                       a.targets[0], "-", "%s: %s" % (type(e).__name__, e)))
        rows = c.rows[start:]
        name = os.path.splitext(os.path.basename(mesh))[0]
        md.append(mesh_table(name, rows))
        plot(name, rows, a.out)
    md.append(overall(c.rows, a, c.has_auto))
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write("\n".join(md))
    write_tsv(c.rows, os.path.join(a.out, "results.tsv"))
    print("wrote %s, %s and a PNG per mesh" % (os.path.join(a.out, "summary.md"), os.path.join(a.out, "results.tsv")))


if __name__ == "__main__":
    main()
