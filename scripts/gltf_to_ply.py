#!/usr/bin/env python3
"""One mesh of a glTF 2.0 file (.gltf + its .bin) as a binary PLY with normals and per-vertex
texture coordinates, naming the texture image as MeshLab does (python3 standard library only).

  gltf_to_ply.py IN.gltf MESH_NAME OUT.ply [--comment TEXT]...

Writes float32 x y z nx ny nz texture_u texture_v per vertex, `list uchar int vertex_indices` per
face, and `comment TextureFile NAME` for the image of the material's base-colour texture (else its
first texture). Positions are as stored (the node's transform is not applied). glTF puts the
texture origin at the top left, PLY/OpenGL at the bottom left: texture_v = 1 - v.
"""
import argparse
import json
import os
import struct
import sys

COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
FORMATS = {5121: "B", 5123: "H", 5125: "I", 5126: "f"}


def accessor(gltf, buffers, index):
    a = gltf["accessors"][index]
    view = gltf["bufferViews"][a["bufferView"]]
    data = buffers[view["buffer"]]
    n = COMPONENTS[a["type"]]
    fmt = FORMATS[a["componentType"]]
    size = struct.calcsize("<" + fmt)
    stride = view.get("byteStride", n * size)
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    out = []
    for i in range(a["count"]):
        out.append(struct.unpack_from("<%d%s" % (n, fmt), data, start + i * stride))
    return out


def texture_image(gltf, material):
    m = gltf["materials"][material] if material is not None else {}
    refs = [m.get("pbrMetallicRoughness", {}).get("baseColorTexture")]
    for ext in m.get("extensions", {}).values():
        refs += [v for v in ext.values() if isinstance(v, dict) and "index" in v]
    for r in refs:
        if r:
            return gltf["images"][gltf["textures"][r["index"]]["source"]]["uri"]
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("gltf")
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--comment", action="append", default=[])
    a = ap.parse_args()
    with open(a.gltf) as f:
        gltf = json.load(f)
    folder = os.path.dirname(a.gltf)
    buffers = []
    for b in gltf["buffers"]:
        with open(os.path.join(folder, b["uri"]), "rb") as f:
            buffers.append(f.read())
    meshes = [m for m in gltf["meshes"] if m.get("name") == a.mesh]
    if len(meshes) != 1 or len(meshes[0]["primitives"]) != 1:
        sys.exit("%s: no mesh '%s' with one primitive" % (a.gltf, a.mesh))
    prim = meshes[0]["primitives"][0]
    pos = accessor(gltf, buffers, prim["attributes"]["POSITION"])
    nrm = accessor(gltf, buffers, prim["attributes"]["NORMAL"])
    uv = accessor(gltf, buffers, prim["attributes"]["TEXCOORD_0"])
    idx = [i[0] for i in accessor(gltf, buffers, prim["indices"])]
    image = texture_image(gltf, prim.get("material"))
    header = ["ply", "format binary_little_endian 1.0"]
    header += ["comment %s" % c for c in a.comment]
    if image:
        header.append("comment TextureFile %s" % image)
    header += ["element vertex %d" % len(pos)]
    header += ["property float %s" % p for p in ("x", "y", "z", "nx", "ny", "nz", "texture_u", "texture_v")]
    header += ["element face %d" % (len(idx) // 3), "property list uchar int vertex_indices", "end_header"]
    with open(a.out, "wb") as f:
        f.write(("\n".join(header) + "\n").encode())
        rec = struct.Struct("<8f")
        for p, n, t in zip(pos, nrm, uv):
            f.write(rec.pack(p[0], p[1], p[2], n[0], n[1], n[2], t[0], 1.0 - t[1]))
        tri = struct.Struct("<B3i")
        for i in range(0, len(idx), 3):
            f.write(tri.pack(3, idx[i], idx[i + 1], idx[i + 2]))


if __name__ == "__main__":
    main()
