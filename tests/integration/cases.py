#!/usr/bin/env python3
"""ConeLOD integration tests: the real meshlabserver (under xvfb-run) and the conelod CLI on real
and bad meshes. One ctest test per case:  cases.py CASE --build BUILD_DIR --source SOURCE_DIR

meshlabserver runs from a private copy (BUILD/meshlab) that loads the plugin of the build tree.
"""
import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

CASES = {}


def case(fn):
    CASES[fn.__name__] = fn
    return fn


class Ctx:
    def __init__(self, build, source):
        self.build = os.path.abspath(build)
        self.source = os.path.abspath(source)
        self.meshes = os.environ.get("CONELOD_TEST_MESHES", os.path.join(self.source, "..", "shared", "test_meshes"))
        self.tmp = tempfile.mkdtemp(prefix="conelod_it_")
        self.cli = os.path.join(self.build, "conelod", "conelod")
        self.server = os.path.join(self.build, "meshlab", "bin", "meshlabserver")

    def mesh(self, name):
        path = os.path.join(self.meshes, name)
        if not os.path.exists(path):
            path = os.path.join(self.source, "test_meshes", name)
        assert os.path.exists(path), "missing test mesh " + name
        return path

    def mlx(self, name):
        return os.path.join(self.source, "scripts", "mlx", name)

    def out(self, name):
        return os.path.join(self.tmp, name)

    def meshlab(self, inputs, script, output=None, expect_ok=True):
        """Runs meshlabserver; returns (exit code, log text)."""
        log = self.out("meshlab.log")
        if os.path.exists(log):
            os.remove(log)
        cmd = ["xvfb-run", "-a", self.server, "-l", log, "-i"] + inputs + ["-s", script]
        if output:
            cmd += ["-o", output, "-m", "fq", "fc"]
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=600, cwd=self.tmp)
        text = open(log, errors="replace").read() if os.path.exists(log) else ""
        if expect_ok and p.returncode != 0:
            raise AssertionError("meshlabserver failed (%d):\n%s\n%s" % (p.returncode, p.stdout.decode(errors="replace")[-3000:], text[-3000:]))
        return p.returncode, text

    def conelod(self, *args, expect=0):
        p = subprocess.run([self.cli] + list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=600)
        assert p.returncode == expect, "conelod %s: exit %d (expected %d)\n%s%s" % (
            " ".join(args), p.returncode, expect, p.stdout.decode(), p.stderr.decode())
        return p


def read_ply(path):
    """Minimal PLY reader (ASCII and binary little endian): vertex count, faces, per-face quality."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            header.append(line)
            if line == "end_header":
                break
        body = f.read()
    fmt = [l.split()[1] for l in header if l.startswith("format")][0]
    elements, current = [], None
    for l in header:
        w = l.split()
        if w and w[0] == "element":
            current = {"name": w[1], "count": int(w[2]), "props": []}
            elements.append(current)
        elif w and w[0] == "property":
            current["props"].append(w[1:])
    sizes = {"char": "b", "uchar": "B", "int8": "b", "uint8": "B", "short": "h", "ushort": "H", "int": "i",
             "int32": "i", "uint": "I", "uint32": "I", "float": "f", "float32": "f", "double": "d", "float64": "d"}
    result = {"vertices": 0, "faces": [], "quality": []}
    if fmt == "ascii":
        tokens = body.decode().split()
        pos = 0
        for el in elements:
            for _ in range(el["count"]):
                rec = {}
                for prop in el["props"]:
                    if prop[0] == "list":
                        n = int(tokens[pos]); pos += 1
                        rec[prop[-1]] = [int(t) for t in tokens[pos:pos + n]]; pos += n
                    else:
                        rec[prop[-1]] = float(tokens[pos]); pos += 1
                if el["name"] == "face":
                    result["faces"].append(rec["vertex_indices"])
                    if "quality" in rec:
                        result["quality"].append(rec["quality"])
            if el["name"] == "vertex":
                result["vertices"] = el["count"]
        return result
    assert fmt == "binary_little_endian", fmt
    pos = 0
    for el in elements:
        if el["name"] == "vertex":
            result["vertices"] = el["count"]
        simple = all(p[0] != "list" for p in el["props"])
        if simple:
            st = struct.Struct("<" + "".join(sizes[p[0]] for p in el["props"]))
            names = [p[-1] for p in el["props"]]
            for _ in range(el["count"]):
                rec = dict(zip(names, st.unpack_from(body, pos)))
                pos += st.size
            continue
        for _ in range(el["count"]):
            rec = {}
            for prop in el["props"]:
                if prop[0] == "list":
                    cs, vs = struct.Struct("<" + sizes[prop[1]]), struct.Struct("<" + sizes[prop[2]])
                    n = cs.unpack_from(body, pos)[0]; pos += cs.size
                    rec[prop[-1]] = list(struct.unpack_from("<%d%s" % (n, sizes[prop[2]]), body, pos)); pos += n * vs.size
                else:
                    s = struct.Struct("<" + sizes[prop[0]])
                    rec[prop[-1]] = s.unpack_from(body, pos)[0]; pos += s.size
            if el["name"] == "face":
                result["faces"].append(rec["vertex_indices"])
                if "quality" in rec:
                    result["quality"].append(rec["quality"])
    return result


def last_float(log, key):
    vals = re.findall(re.escape(key) + r"\s+([0-9.eE+-]+)", log)
    assert vals, "'%s' not found in the log:\n%s" % (key, log[-2000:])
    return float(vals[-1])


# --- MeshLab integration -------------------------------------------------------------------

@case
def meshlab_lists_filters(c):
    dump = c.out("dump.txt")
    subprocess.run(["xvfb-run", "-a", c.server, "-d", dump], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                   timeout=300, cwd=c.tmp, check=True)
    text = open(dump, errors="replace").read()
    for name in ["Cone LOD: Normal Cone Face Grouping", "Cone LOD: Cluster Culling Cost"]:
        assert name in text, name + " not listed by meshlabserver -d"


@case
def mlx_scripts_in_sync(c):
    """scripts/mlx/ holds exactly one script per filter, each equal to the plugin's defaults."""
    gen = c.out("mlx")
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen", XDG_RUNTIME_DIR=c.tmp)
    subprocess.run([os.path.join(c.build, "tests", "mlx_defaults"),
                    os.path.join(c.build, "filter_conelod", "libfilter_conelod.so"), gen],
                   check=True, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    shipped = sorted(f for f in os.listdir(os.path.join(c.source, "scripts", "mlx")) if f.endswith(".mlx"))
    generated = sorted(os.listdir(gen))
    assert shipped == generated, "scripts/mlx has %s, the plugin has %s (run scripts/update_mlx.sh)" % (shipped, generated)
    def params(path):  # Qt writes XML attributes in a random order: compare their content
        root = ET.parse(path).getroot()
        return [(flt.get("name"), [sorted(p.attrib.items()) for p in flt]) for flt in root]
    for f in generated:
        assert params(os.path.join(gen, f)) == params(c.mlx(f)), \
            "scripts/mlx/%s differs from the plugin's parameters (run scripts/update_mlx.sh)" % f


@case
def meshlab_grouping_bunny(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    out = c.out("ml_bunny.ply")
    _, log = c.meshlab([bunny], c.mlx("normal_cone_face_grouping.mlx"), out)
    ply = read_ply(out)
    assert len(ply["faces"]) == 69451, len(ply["faces"])
    assert len(ply["quality"]) == 69451, "per-face quality missing from the saved PLY"
    # The same core through the CLI: same groups, face by face.
    cli_out = c.out("cli_bunny.ply")
    info = json.loads(c.conelod("group", bunny, "-o", cli_out, "--json").stdout)
    level1 = info["levels"][0]
    assert len(set(ply["quality"])) == level1["groups"], (len(set(ply["quality"])), level1["groups"])
    assert ply["quality"] == read_ply(cli_out)["quality"], "MeshLab and the CLI disagree on the groups"
    # The logged table (last occurrence: meshlabserver repeats the log).
    rows = re.findall(r"^\s*1\s+15\.0\s+(\d+)\s+([0-9.]+)", log, re.M)
    assert rows and int(rows[-1][0]) == level1["groups"], log[-2000:]
    assert len(info["levels"]) >= 4
    for lv in info["levels"]:
        assert lv["all_connected"], lv
        assert lv["threshold_deg"] >= 180 or lv["max_cone_deg"] < lv["threshold_deg"], lv


@case
def meshlab_culling_cost_bunny(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    _, log = c.meshlab([bunny], c.mlx("cluster_culling_cost.mlx"))
    two, three = last_float(log, "two_state_cost"), last_float(log, "three_state_cost")
    rejected, ideal = last_float(log, "rejected_fraction"), last_float(log, "ideal_fraction")
    cli = json.loads(c.conelod("cull-cost", bunny, "--json").stdout)
    assert abs(two - cli["two_state_cost"]) < 1e-4 and abs(three - cli["three_state_cost"]) < 1e-4, (two, three, cli)
    assert three < two < 1.0, (two, three)
    assert rejected <= ideal, (rejected, ideal)


@case
def meshlab_bad_inputs(c):
    """Bad input: a clear message in the log and a failed filter, never a crash."""
    for mesh, message in [("no_faces.ply", "has no faces"), ("nan_vertex.ply", "NaN or infinite")]:
        for script in ["normal_cone_face_grouping.mlx", "cluster_culling_cost.mlx"]:
            rc, log = c.meshlab([c.mesh(mesh)], c.mlx(script), c.out("bad.ply"), expect_ok=False)
            assert rc == 255, "%s/%s: expected a failed filter (255), got %d\n%s" % (mesh, script, rc, log[-1500:])
            assert "ConeLOD error" in log and message in log, "%s/%s: no clear message:\n%s" % (mesh, script, log[-1500:])


@case
def meshlab_awkward_inputs(c):
    """Inputs that must work: zero-area faces, non-manifold edges, several components."""
    for mesh, faces in [("zero_area_faces.ply", 4), ("stanford_bunny_bun_zipper_res4.ply", 948), ("boeing.ply", 2564)]:
        out = c.out("ok.ply")
        c.meshlab([c.mesh(mesh)], c.mlx("normal_cone_face_grouping.mlx"), out)
        ply = read_ply(out)
        assert len(ply["faces"]) == faces and len(ply["quality"]) == faces, mesh
        info = json.loads(c.conelod("group", c.mesh(mesh), "--json").stdout)
        assert all(lv["all_connected"] for lv in info["levels"]), mesh


# --- CLI ----------------------------------------------------------------------------------

@case
def cli_info(c):
    boeing = json.loads(c.conelod("info", c.mesh("boeing.ply"), "--json").stdout)
    assert boeing["components"] == 122 and boeing["faces"] == 2564, boeing
    res4 = json.loads(c.conelod("info", c.mesh("stanford_bunny_bun_zipper_res4.ply"), "--json").stdout)
    assert res4["non_manifold_edges"] == 70, res4
    bunny = json.loads(c.conelod("info", c.mesh("stanford_bunny_bun_zipper.ply"), "--json").stdout)
    assert bunny["unreferenced_vertices"] == 1113 and bunny["components"] == 1, bunny


@case
def cli_bad_inputs(c):
    for mesh, message in [("no_faces.ply", "has no faces"), ("nan_vertex.ply", "NaN or infinite")]:
        for cmd in ["group", "cull-cost"]:
            p = c.conelod(cmd, c.mesh(mesh), expect=2)
            assert message in p.stderr.decode(), p.stderr.decode()
    p = c.conelod("group", c.mesh("stanford_bunny_bun_zipper.ply"), "--threshold", "-3", expect=2)
    assert "ConeThresholdDeg" in p.stderr.decode()
    c.conelod("group", c.out("missing.ply"), expect=3)
    c.conelod("group", "--bogus", expect=1)


@case
def cli_cull_cost_perspective(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    ortho = json.loads(c.conelod("cull-cost", bunny, "--views", "200", "--json").stdout)
    near = json.loads(c.conelod("cull-cost", bunny, "--views", "200", "--camera-distance", "3", "--json").stdout)
    for r in (ortho, near):
        for key in ["views", "two_state_cost", "three_state_cost", "rejected_fraction", "ideal_fraction"]:
            assert key in r, key
        assert r["rejected_fraction"] <= r["ideal_fraction"]
    assert near["perspective"] and not ortho["perspective"]
    # An eye at 3 radii sees less than half of a closed-ish surface; far views see about half.
    assert near["ideal_fraction"] > ortho["ideal_fraction"] + 0.02, (near, ortho)
    assert abs(ortho["ideal_fraction"] - 0.5) < 0.02, ortho


# --- PCA partition and progressive cluster mesh (SPEC §2) ----------------------------------

@case
def meshlab_lists_pca_filters(c):
    dump = c.out("dump.txt")
    subprocess.run(["xvfb-run", "-a", c.server, "-d", dump], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                   timeout=300, cwd=c.tmp, check=True)
    text = open(dump, errors="replace").read()
    for name in ["Cone LOD: PCA Recursive Face Partition", "Cone LOD: Progressive Cluster Mesh"]:
        assert name in text, name + " not listed by meshlabserver -d"


@case
def meshlab_pca_partition_bunny(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    out = c.out("ml_pca.ply")
    _, log = c.meshlab([bunny], c.mlx("pca_recursive_face_partition.mlx"), out)
    ply = read_ply(out)
    assert len(ply["faces"]) == 69451 and len(ply["quality"]) == 69451, len(ply["quality"])
    assert len(set(ply["quality"])) == 64, len(set(ply["quality"]))
    assert last_float(log, "pca_clusters") == 64 and last_float(log, "all_connected") == 1, log[-1500:]
    # The same core through the CLI: the same clusters, face by face.
    cli_out = c.out("cli_pca.ply")
    info = json.loads(c.conelod("partition", bunny, "--clusters", "64", "-o", cli_out, "--json").stdout)
    assert info["clusters"] == 64 and info["all_connected"], info
    assert ply["quality"] == read_ply(cli_out)["quality"], "MeshLab and the CLI disagree on the clusters"


@case
def meshlab_progressive_bunny(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    out = c.out("ml_progressive.ply")
    _, log = c.meshlab([bunny], c.mlx("progressive_cluster_mesh.mlx"), out)
    ply = read_ply(out)  # meshlabserver saves the new (current) layer
    assert len(ply["faces"]) == last_float(log, "progressive_faces"), (len(ply["faces"]), log[-1500:])
    assert ply["vertices"] == last_float(log, "progressive_vertices")
    assert last_float(log, "misoriented_edges") == 0 and last_float(log, "non_manifold_edges") == 0, log[-1500:]
    assert last_float(log, "hausdorff_percent") < 2.5, log[-1500:]
    cli = json.loads(c.conelod("progressive", bunny, "--clusters", "1000", "-o", c.out("cli_prog.ply"),
                               "--samples", "0", "--json").stdout)
    assert cli["faces"] == len(ply["faces"]) and cli["clusters"] == 1000, cli
    assert len(set(ply["quality"])) == 1000


@case
def cli_partition_every_cut_connected(c):
    """Every node of the full tree is edge-connected and the ranges tile the faces: so every cut
    partitions the faces into edge-connected clusters (bunny, dragon, boeing with 122 components)."""
    for mesh, faces, components in [("stanford_bunny_bun_zipper.ply", 69451, 1),
                                    ("stanford_dragon_vrip_binary.ply", 871414, 151),
                                    ("boeing.ply", 2564, 122)]:
        r = json.loads(c.conelod("partition", c.mesh(mesh), "--full", "--verify", "--clusters", "500",
                                 "--json").stdout)
        assert r["tree_valid"] and r["all_connected"], (mesh, r)
        assert r["faces"] == faces and r["components"] == components, (mesh, r)
        assert r["clusters"] == max(500, components), (mesh, r)


@case
def cli_progressive_bunny(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    previous = 0
    for k in [100, 1000, 10000]:
        out = c.out("prog_%d.ply" % k)
        r = json.loads(c.conelod("progressive", bunny, "--clusters", str(k), "-o", out, "--json").stdout)
        for key in ["clusters", "faces", "vertices", "seconds"]:
            assert key in r, key
        assert r["clusters"] == k and r["manifold"] and r["input_manifold"], r
        assert r["misoriented_edges"] == 0 and r["degenerate_faces"] == 0, r
        assert r["faces"] > previous and r["hausdorff_percent"] < 6.0, r
        previous = r["faces"]
        ply = read_ply(out)
        assert len(ply["faces"]) == r["faces"] and len(set(ply["quality"])) == k


@case
def cli_cull_cost_pca(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    r = json.loads(c.conelod("cull-cost", bunny, "--pca", "500", "--views", "200", "--json").stdout)
    assert r["grouping"] == "pca" and r["pca_clusters"] == 500 and r["levels"] == 1, r
    assert r["rejected_fraction"] <= r["ideal_fraction"] and r["three_state_cost"] < r["two_state_cost"] < 1, r
    r2 = json.loads(c.conelod("cull-cost", bunny, "--pca", "1024", "--pca-levels", "3", "--views", "200",
                              "--json").stdout)
    assert r2["levels"] == 3 and r2["level1_groups"] == 1024 and r2["top_groups"] == 64, r2
    c.conelod("cull-cost", bunny, "--pca", "100", "--threshold", "10", expect=1)
    c.conelod("cull-cost", bunny, "--pca", "0", expect=1)


@case
def cli_pca_bad_inputs(c):
    for mesh, message in [("no_faces.ply", "has no faces"), ("nan_vertex.ply", "NaN or infinite")]:
        p = c.conelod("partition", c.mesh(mesh), expect=2)
        assert message in p.stderr.decode(), p.stderr.decode()
        p = c.conelod("progressive", c.mesh(mesh), "--clusters", "10", "-o", c.out("x.ply"), expect=2)
        assert message in p.stderr.decode(), p.stderr.decode()
    for mesh in ["zero_area_faces.ply", "stanford_bunny_bun_zipper_res4.ply", "boeing.ply"]:
        r = json.loads(c.conelod("partition", c.mesh(mesh), "--full", "--verify", "--json").stdout)
        assert r["tree_valid"] and r["all_connected"], (mesh, r)
        r = json.loads(c.conelod("progressive", c.mesh(mesh), "--clusters", "8", "-o", c.out("x.ply"),
                                 "--json").stdout)
        assert r["faces"] > 0 and r["non_manifold_edges"] <= 70, (mesh, r)
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    c.conelod("partition", bunny, "--min-faces", "0", expect=1)
    c.conelod("partition", bunny, "--full", "--min-faces", "5", expect=1)
    c.conelod("progressive", bunny, "--clusters", "10", expect=1)  # no -o
    c.conelod("progressive", bunny, "--clusters", "10", "--max-normal-turn", "200", "-o", c.out("x.ply"), expect=1)


@case
def cli_cluster_shape(c):
    bunny = c.mesh("stanford_bunny_bun_zipper.ply")
    out = c.out("pca_75.ply")
    c.conelod("partition", bunny, "--clusters", "75", "-o", out)
    r = json.loads(c.conelod("cluster-shape", out, "--json").stdout)
    assert r["clusters"] == 75 and r["all_connected"] and r["faces"] == 69451, r
    assert 1.0 < r["boundary_ratio"] < 3.0 and 0.1 < r["mean_compactness"] < 1.0, r
    p = c.conelod("cluster-shape", bunny, expect=2)  # no per-face quality
    assert "quality" in p.stderr.decode(), p.stderr.decode()


@case
def meshlab_pca_bad_inputs(c):
    for mesh, message in [("no_faces.ply", "has no faces"), ("nan_vertex.ply", "NaN or infinite")]:
        for script in ["pca_recursive_face_partition.mlx", "progressive_cluster_mesh.mlx"]:
            rc, log = c.meshlab([c.mesh(mesh)], c.mlx(script), c.out("bad.ply"), expect_ok=False)
            assert rc == 255, "%s/%s: expected a failed filter (255), got %d\n%s" % (mesh, script, rc, log[-1500:])
            assert "ConeLOD error" in log and message in log, "%s/%s: no clear message:\n%s" % (mesh, script, log[-1500:])
    for mesh, faces in [("zero_area_faces.ply", 4), ("stanford_bunny_bun_zipper_res4.ply", 948), ("boeing.ply", 2564)]:
        out = c.out("ok.ply")
        _, log = c.meshlab([c.mesh(mesh)], c.mlx("pca_recursive_face_partition.mlx"), out)
        ply = read_ply(out)
        assert len(ply["faces"]) == faces and len(ply["quality"]) == faces, mesh
        assert last_float(log, "all_connected") == 1, log[-1500:]
        _, log = c.meshlab([c.mesh(mesh)], c.mlx("progressive_cluster_mesh.mlx"), c.out("ok2.ply"))
        assert last_float(log, "progressive_faces") > 0, log[-1500:]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--build", required=True)
    ap.add_argument("--source", required=True)
    a = ap.parse_args()
    try:
        CASES[a.case](Ctx(a.build, a.source))
    except AssertionError as e:
        print("FAIL %s: %s" % (a.case, e))
        return 1
    print("ok %s" % a.case)
    return 0


if __name__ == "__main__":
    sys.exit(main())
