#!/usr/bin/env python3
"""A generated corpus of bad (and awkward but valid) PLY inputs for the robustness tests.

corpus() returns (name, bytes, expected) triples; `expected` is what reading the file must give:
"ok" (read, maybe refused later by a command for what the mesh is) or a substring of the error
message. The bytes "fifo" stand for a named pipe (the runner makes one with os.mkfifo). Nothing here is a hand-edited file: each input is built from a small valid mesh.
"""
import gzip
import struct

# A small closed mesh: an octahedron (6 vertices, 8 faces).
V = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
F = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def header(fmt, nv, nf, vprops=("float x", "float y", "float z"), fprops=("list uchar int vertex_indices",),
           extra=""):
    h = "ply\nformat %s 1.0\n%selement vertex %s\n" % (fmt, extra, nv)
    h += "".join("property %s\n" % p for p in vprops)
    if nf is not None:
        h += "element face %s\n" % nf + "".join("property %s\n" % p for p in fprops)
    return (h + "end_header\n").encode()


def ascii_ply(verts=V, faces=F, nv=None, nf=None, **kw):
    body = "".join(" ".join(str(c) for c in v) + "\n" for v in verts)
    body += "".join("%d %s\n" % (len(f), " ".join(str(i) for i in f)) for f in faces)
    return header("ascii", len(verts) if nv is None else nv, len(faces) if nf is None else nf, **kw) + body.encode()


def binary_ply(verts=V, faces=F, endian="<", coord="f", nv=None, nf=None, index="i", count="B", **kw):
    fmt = "binary_little_endian" if endian == "<" else "binary_big_endian"
    tname = {"f": "float", "d": "double"}[coord]
    iname = {"i": "int", "I": "uint", "H": "ushort"}[index]
    cname = {"B": "uchar", "i": "int"}[count]
    kw.setdefault("vprops", ("%s x" % tname, "%s y" % tname, "%s z" % tname))
    kw.setdefault("fprops", ("list %s %s vertex_indices" % (cname, iname),))
    body = b"".join(struct.pack(endian + coord * 3, *v) for v in verts)
    body += b"".join(struct.pack(endian + count + index * len(f), len(f), *f) for f in faces)
    return header(fmt, len(verts) if nv is None else nv, len(faces) if nf is None else nf, **kw) + body


def icosphere(subdivisions=4):
    """A unit icosphere: 20 * 4^s faces (5,120 for s = 4), vertices rounded to single precision."""
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdivisions):
        mid, out = {}, []

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                verts.append(tuple((x + y) / 2 for x, y in zip(verts[a], verts[b])))
                mid[key] = len(verts) - 1
            return mid[key]
        for a, b, c in faces:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = out
    unit = []
    for v in verts:
        n = sum(x * x for x in v) ** 0.5
        unit.append(tuple(struct.unpack("<f", struct.pack("<f", x / n))[0] for x in v))
    return unit, faces


def scaled(verts, k):
    """The vertices times 2^k: exact while the coordinates stay in single precision's range."""
    return [tuple(x * 2.0 ** k for x in v) for v in verts]


def corpus():
    good = binary_ply()
    c = []
    add = lambda name, data, expected: c.append((name, data, expected))
    # Not PLY at all.
    add("empty", b"", "is empty")
    add("only_magic", b"ply\n", "end_header")
    add("obj", b"# a cube\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "only PLY is read")
    add("off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "only PLY is read")
    add("stl_ascii", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\nendfacet\nendsolid x\n",
        "only PLY is read")
    add("stl_binary", b"\0" * 80 + struct.pack("<I", 1) + b"\0" * 50, "only PLY is read")
    add("gzip", gzip.compress(good, mtime=0), "gzip")
    add("garbage", bytes((i * 37 + 11) % 256 for i in range(500)), "only PLY is read")
    # Broken headers.
    add("no_end_header", good.split(b"end_header")[0], "no end_header")
    add("no_format", good.replace(b"format binary_little_endian 1.0\n", b""), "no 'format'")
    add("unknown_format", good.replace(b"binary_little_endian", b"binary_middle_endian"), "unknown format")
    add("count_negative", ascii_ply(nv=-5), "not a whole number")
    add("count_text", ascii_ply(nv="many"), "not a whole number")
    add("count_float", ascii_ply(nv="6.0"), "not a whole number")
    add("count_1e9_small_file", binary_ply(nv=10 ** 9), "truncated or corrupt")
    add("count_1e8_200_bytes", header("binary_little_endian", 10 ** 8, 0) + b"\0" * 120, "truncated or corrupt")
    add("count_huge", ascii_ply(nv=10 ** 20), "not a whole number")
    add("count_2pow32", ascii_ply(nv=2 ** 32), "2^32")
    add("unknown_type", ascii_ply(vprops=("quad x", "float y", "float z")), "unknown type")
    add("float_list_count", ascii_ply(fprops=("list float int vertex_indices",)), "integer type")
    add("property_first", b"ply\nformat ascii 1.0\nproperty float x\n" + ascii_ply()[len(b"ply\nformat ascii 1.0\n"):],
        "before any element")
    add("unknown_keyword", good.replace(b"end_header", b"frobnicate\nend_header"), "unknown keyword")
    add("no_z", ascii_ply(verts=[v[:2] for v in V], vprops=("float x", "float y")), "x, y, z")
    add("no_vertex_indices", ascii_ply(fprops=("list uchar int corners",)), "no vertex_indices")
    add("no_vertex_element", b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        "no vertex element")
    add("empty_element", good.replace(b"end_header", b"element junk 1000000000\nend_header"), "without properties")
    add("header_too_long", b"ply\nformat ascii 1.0\n" + b"comment " + b"x" * 100 + b"\n" * 1 + b"".join(
        b"comment %d\n" % i for i in range(120000)) + b"end_header\n", "longer than 1 MiB")
    add("two_vertex_elements", ascii_ply().replace(b"element face", b"element vertex 0\nproperty float x\nproperty float y\n"
                                                   b"property float z\nelement face"), "two 'vertex'")
    add("face_before_vertex", b"ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
        b"element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n3 0 1 2\n0 0 0\n1 0 0\n0 1 0\n",
        "before the vertex element")
    # Broken bodies.
    add("truncated_binary", good[:len(good) - 40], "ends early")
    add("truncated_ascii", ascii_ply()[:-20], "ends early")
    add("list_past_end", binary_ply(faces=F[:-1], nf=8) + struct.pack("<B", 200) + b"\0" * 12, "ends early")
    add("not_a_number", ascii_ply(verts=[("abc", 0, 0)] + V[1:]), "not a number")
    add("long_token", ascii_ply(verts=[("1" * 500, 0, 0)] + V[1:]), "not a number")
    for k in (0, 1, 2):
        add("face_%d_corners" % k, ascii_ply(faces=F[:-1] + [F[-1][:k]]), "a face needs at least 3")
    add("index_negative", ascii_ply(faces=F[:-1] + [(0, 1, -1)]), "uses vertex -1")
    add("index_past_end", ascii_ply(faces=F[:-1] + [(0, 1, 6)]), "uses vertex 6")
    add("index_uint_huge", binary_ply(faces=F[:-1] + [(0, 1, 4000000000)], index="I"), "uses vertex")
    add("polygon_5000", ascii_ply(faces=F + [tuple(i % 6 for i in range(5000))]), "at most 4096")
    add("bowtie_quad", ascii_ply(verts=[(0, 0, 0), (1, 1, 0), (1, 0, 0), (0, 1, 0)], faces=[(0, 1, 2, 3)]),
        "edges cross")
    add("double_1e300", binary_ply(verts=[(1e300, 0, 0)] + V[1:], coord="d"), "beyond single precision")
    # Ambiguous files (issue 24): refused rather than guessed.
    add("fractional_indices", ascii_ply(faces=F[:-1] + [(0.5, 2.7, 4.2)], fprops=("list uchar float vertex_indices",)),
        "not a whole number")
    add("duplicate_property", ascii_ply(verts=[v + (9,) for v in V], vprops=("float x", "float y", "float z", "float x")),
        "twice")
    add("both_index_lists", ascii_ply(fprops=("list uchar int vertex_indices", "list uchar int vertex_index")).replace(
        b"\n".join(b"3 %d %d %d" % f for f in F), b"\n".join(b"3 %d %d %d 3 0 1 2" % f for f in F)),
        "both a vertex_indices and a vertex_index")
    add("fifo", "fifo", "is a FIFO")  # a named pipe: refused before it is opened (open() blocks)
    # Read, then refused by what the mesh is (exit 2 in every command that needs faces).
    add("nan_coordinates", ascii_ply(verts=[("nan", 0, 0)] + V[1:]), "ok")
    add("inf_coordinates", ascii_ply(verts=[("inf", 0, 0)] + V[1:]), "ok")
    add("coordinates_1e19", ascii_ply(verts=[tuple(x * 1e19 for x in v) for v in V]), "ok")
    add("no_faces", ascii_ply(faces=[]), "ok")
    add("unreferenced_vertex_1e20", binary_ply(verts=V + [(1e20, 0, 0)]), "ok")  # crashed the sampled distance
    add("scaled_2pow-100", binary_ply(verts=scaled(V, -100)), "ok")  # the progressive mesh took 100x as long
    add("scaled_1e-40", binary_ply(verts=[tuple(x * 1e-40 for x in v) for v in V]), "ok")  # denormal coordinates
    add("all_zero_area", ascii_ply(verts=[(0, 0, 0), (1, 0, 0), (2, 0, 0)], faces=[(0, 1, 2)]), "ok")
    # Awkward but valid: read exactly.
    add("big_endian_double", binary_ply(endian=">", coord="d"), "ok")
    add("big_endian_float", binary_ply(endian=">"), "ok")
    add("ushort_indices_int_counts", binary_ply(index="H", count="i"), "ok")
    add("extra_properties", ascii_ply(verts=[v + (7,) for v in V], faces=F, vprops=("float x", "float y", "float z", "int flags"),
                  fprops=("list uchar int vertex_indices", "int flags")).replace(
            b"\n".join(b"3 %d %d %d" % f for f in F), b"\n".join(b"3 %d %d %d 1" % f for f in F)), "ok")
    add("crlf_header", ascii_ply().replace(b"\n", b"\r\n"), "ok")
    add("quads", ascii_ply(verts=[(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1)],
                           faces=[(0, 3, 2, 1), (0, 1, 5, 4)]), "ok")
    add("corner_on_diagonal_7gon", ascii_ply(verts=[(1, 0, 0), (2, 0, 0), (3, 1, 0), (3, 3, 0), (1, 4, 0), (0, 4, 0),
                                                    (1, 2, 0)], faces=[tuple(range(7))]), "ok")
    add("nonconvex_7gon", ascii_ply(verts=[(0, 0, 0), (4, 0, 0), (4, 3, 0), (3, 1, 0), (2, 3, 0), (1, 1, 0), (0, 3, 0)],
                                    faces=[tuple(range(7))]), "ok")
    add("face_quality_nan", ascii_ply(fprops=("list uchar int vertex_indices", "float quality")).replace(
        b"\n".join(b"3 %d %d %d" % f for f in F), b"\n".join(b"3 %d %d %d nan" % f for f in F)), "ok")
    add("face_quality_2e9", ascii_ply(fprops=("list uchar int vertex_indices", "float quality")).replace(
        b"\n".join(b"3 %d %d %d" % f for f in F), b"\n".join(b"3 %d %d %d 2e9" % f for f in F)), "ok")
    return c
