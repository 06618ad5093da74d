#!/usr/bin/env python3
"""Colour error of `conelod simplify` against MeshLab's quadric edge collapse at equal face counts
(issue 26). Python 3 standard library; needs the build (conelod, tools/attribute_error) and the
private meshlabserver the integration tests use (BUILD/meshlab/bin/meshlabserver, under xvfb-run).

  compare_attributes.py --build BUILD --coloured MESH.ply [--textured MESH.ply --texture IMG.ppm]
                        [--ratios 0.1,0.02] [--texture-ratios 0.1,0.02] [--samples N] [--out DIR]

Per-vertex colour (MESH.ply with red green blue): for each ratio, ours (`simplify --groups
cone:auto --target-ratio R`, default attribute weight, and --attribute-weight 0 for the
attribute-free collapse order) reaches N faces; MeshLab's "Simplification: Quadric Edge Collapse
Decimation" (dialog defaults; survivors keep their colour) runs to exactly N. Texture (MESH.ply with
texture_u/v and its image as a PPM): ours, then MeshLab's "... (with texture)" (dialog defaults) to
the same N, on the mesh with per-face texture coordinates and one vertex per position. Each result is measured by
tools/attribute_error: RMS of the RGB difference (0-255) between samples of the original surface
and the colour at their closest point on the result, and the RMS sample distance in % of the
diagonal. Prints a Markdown table.
"""
import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from meshdata import read_ply_elements  # noqa: E402
from mlx_filters import builtin_qem, script as script_text  # noqa: E402

TEX_QEM = """ <filter name="Simplification: Quadric Edge Collapse Decimation (with texture)">
  <Param type="RichInt" value="%d" name="TargetFaceNum"/>
  <Param type="RichFloat" value="0" name="TargetPerc"/>
  <Param type="RichFloat" value="0.3" name="QualityThr"/>
  <Param type="RichFloat" value="1" name="Extratcoordw"/>
  <Param type="RichBool" value="false" name="PreserveBoundary"/>
  <Param type="RichFloat" value="1" name="BoundaryWeight"/>
  <Param type="RichBool" value="true" name="OptimalPlacement"/>
  <Param type="RichBool" value="false" name="PreserveNormal"/>
  <Param type="RichBool" value="false" name="PlanarQuadric"/>
  <Param type="RichBool" value="false" name="Selected"/>
 </filter>
"""


def run(cmd, **kw):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, **kw)
    if p.returncode != 0:
        sys.exit("%s failed (%d): %s%s" % (" ".join(cmd), p.returncode, p.stdout.decode()[-2000:], p.stderr.decode()[-2000:]))
    return p.stdout.decode()


def faces_of(path):
    with open(path, "rb") as f:
        head = f.read(4096).split(b"end_header")[0].decode(errors="replace")
    for line in head.splitlines():
        if line.startswith("element face"):
            return int(line.split()[2])
    return 0


def meshlab(a, src, filter_xml, out, save):
    """MeshLab's filter to exactly `n` faces (asked again with a corrected target when it misses)."""
    mlx = os.path.join(a.out, "run.mlx")
    with open(mlx, "w") as f:
        f.write(script_text(filter_xml))
    server = os.path.join(a.build, "meshlab", "bin", "meshlabserver")
    run(["xvfb-run", "-a", server, "-l", os.path.join(a.out, "meshlab.log"), "-i", src, "-s", mlx, "-o", out, "-m"] + save,
        cwd=a.out)
    return faces_of(out)


def exact(a, src, make_filter, n, out, save):
    ask = n
    for _ in range(6):
        got = meshlab(a, src, make_filter(ask), out, save)
        if got == n:
            return got
        ask += n - got
    return got


def measure(a, original, result, texture=None):
    cmd = [os.path.join(a.build, "tools", "attribute_error"), original, result, "--samples", str(a.samples)]
    if texture:
        cmd += ["--texture", texture]
    return json.loads(run(cmd))


def with_wedges(src, dst):
    """The textured mesh with per-face texcoord lists (what MeshLab's texture-aware QEM needs), one
    vertex per position (as MeshLab reads a glTF or OBJ: a seam is wedges on one vertex, not a cut
    through the surface that the collapse could open)."""
    verts, faces, header = [], [], []
    for name, records in read_ply_elements(src):
        if name == "vertex":
            verts = records
        elif name == "face":
            faces = [r["vertex_indices"] for r in records]
    welded, first = [], {}
    for v in verts:
        key = (v["x"], v["y"], v["z"])
        if key not in first:
            first[key] = len(first)
        welded.append(first[key])
    with open(src, "rb") as f:
        header = [l for l in f.read(4096).split(b"end_header")[0].decode().splitlines() if l.startswith("comment")]
    import struct
    lines = ["ply", "format binary_little_endian 1.0"] + header
    lines += ["element vertex %d" % len(first), "property float x", "property float y", "property float z"]
    lines += ["element face %d" % len(faces), "property list uchar int vertex_indices",
              "property list uchar float texcoord", "end_header"]
    with open(dst, "wb") as f:
        f.write(("\n".join(lines) + "\n").encode())
        for x, y, z in first:  # in order of first use (dicts keep insertion order)
            f.write(struct.pack("<3f", x, y, z))
        for t in faces:
            uv = []
            for i in t:
                uv += [verts[i]["texture_u"], verts[i]["texture_v"]]
            f.write(struct.pack("<B3iB6f", 3, welded[t[0]], welded[t[1]], welded[t[2]], 6, *uv))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", required=True)
    ap.add_argument("--coloured")
    ap.add_argument("--textured")
    ap.add_argument("--texture")
    ap.add_argument("--ratios", default="0.1,0.02")
    ap.add_argument("--texture-ratios", default="0.1,0.02")
    ap.add_argument("--samples", type=int, default=200000)
    ap.add_argument("--out", default="attributes_out")
    a = ap.parse_args()
    a.build = os.path.abspath(a.build)
    a.out = os.path.abspath(a.out)
    os.makedirs(a.out, exist_ok=True)
    conelod = os.path.join(a.build, "conelod", "conelod")
    rows = []
    for ratio in [float(r) for r in a.ratios.split(",")] if a.coloured else []:
        if a.coloured:
            src = os.path.abspath(a.coloured)
            ours = os.path.join(a.out, "ours_%g.ply" % ratio)
            free = os.path.join(a.out, "ours_w0_%g.ply" % ratio)
            ml = os.path.join(a.out, "meshlab_%g.ply" % ratio)
            r = json.loads(run([conelod, "simplify", src, "--groups", "cone:auto", "--target-ratio", str(ratio), "-o", ours,
                                "--json"]))
            run([conelod, "simplify", src, "--groups", "cone:auto", "--target-ratio", str(ratio), "--attribute-weight", "0",
                 "-o", free])
            n = r["faces_out"]
            got = exact(a, src, lambda t: builtin_qem(target_faces=t), n, ml, ["vc"])
            for label, path, faces in (("ours", ours, n), ("ours, --attribute-weight 0", free, faces_of(free)),
                                       ("MeshLab QEM", ml, got)):
                m = measure(a, src, path)
                rows.append((os.path.basename(src), "%g %%" % (100 * ratio), label, faces, m["colour_rms"],
                             m["distance_rms_pct"]))
    for ratio in [float(r) for r in a.texture_ratios.split(",")] if a.textured else []:
        if a.textured:
            src = os.path.abspath(a.textured)
            ours = os.path.join(a.out, "tex_ours_%g.ply" % ratio)
            ml = os.path.join(a.out, "tex_meshlab_%g.ply" % ratio)
            wedged = os.path.join(a.out, "tex_wedges.ply")
            if not os.path.exists(wedged):
                with_wedges(src, wedged)
            r = json.loads(run([conelod, "simplify", src, "--groups", "cone:auto", "--target-ratio", str(ratio), "-o", ours,
                                "--json"]))
            n = r["faces_out"]
            got = exact(a, wedged, lambda t: TEX_QEM % t, n, ml, ["wt"])
            for label, path, faces in (("ours", ours, n), ("MeshLab QEM (with texture)", ml, got)):
                m = measure(a, src, path, a.texture)
                rows.append((os.path.basename(src), "%g %% (reached %d)" % (100 * ratio, n), label, faces,
                             m["colour_rms"], m["distance_rms_pct"]))
    print("| mesh | target | tool | faces | colour RMS (0-255) | distance RMS (% diag) |")
    print("|---|---|---|---:|---:|---:|")
    for row in rows:
        print("| %s | %s | %s | %d | %.2f | %.4f |" % row)


if __name__ == "__main__":
    main()
