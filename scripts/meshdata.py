#!/usr/bin/env python3
"""Small mesh-file tool for scripts/get_test_meshes.sh (python3 standard library only), and the
one PLY reader of the project's Python scripts and integration tests (read_ply_elements).

  meshdata.py convert IN OUT [--comment TEXT]...
      IN: OFF (ASCII) or ASCII PLY (optionally .gz). OUT: binary little-endian PLY with
      float32 x y z per vertex and `list uchar int vertex_indices` per face (other vertex
      properties are dropped; faces keep their vertex count and order).
  meshdata.py counts FILE          prints "VERTICES FACES" read from a PLY header
  meshdata.py same-data A B        exit 0 when two PLY files hold the same counts and the same
                                   bytes after their headers (header comments may differ)
"""
import argparse
import gzip
import struct
import sys


def open_maybe_gz(path):
    with open(path, "rb") as f:
        magic = f.read(2)
    return gzip.open(path, "rb") if magic == b"\x1f\x8b" else open(path, "rb")


def data_lines(stream):
    """Non-empty lines without '#' comments, as lists of tokens."""
    for raw in stream:
        line = raw.split(b"#", 1)[0].strip()
        if line:
            yield line.split()


def read_off(path):
    with open_maybe_gz(path) as f:
        lines = data_lines(f)
        first = next(lines)
        if not first[0].endswith(b"OFF"):
            raise ValueError("%s: not an OFF file (first word %r)" % (path, first[0].decode(errors="replace")))
        if first[0] != b"OFF":
            raise ValueError("%s: only plain OFF is handled, not %s" % (path, first[0].decode(errors="replace")))
        counts = first[1:] if len(first) > 1 else next(lines)
        nv, nf = int(counts[0]), int(counts[1])
        verts = []
        for _ in range(nv):
            t = next(lines)
            verts.append((float(t[0]), float(t[1]), float(t[2])))
        faces = []
        for _ in range(nf):
            t = next(lines)
            n = int(t[0])
            faces.append([int(x) for x in t[1:1 + n]])
            if len(faces[-1]) != n:
                raise ValueError("%s: face %d is short" % (path, len(faces) - 1))
    return verts, faces


def read_ply_header(f, path):
    if f.readline().strip() != b"ply":
        raise ValueError("%s: not a PLY file" % path)
    fmt, elements = None, []
    while True:
        line = f.readline()
        if not line:
            raise ValueError("%s: PLY header without end_header" % path)
        t = line.split()
        if not t or t[0] in (b"comment", b"obj_info"):
            continue
        if t[0] == b"format":
            fmt = t[1].decode()
        elif t[0] == b"element":
            elements.append((t[1].decode(), int(t[2]), []))
        elif t[0] == b"property":
            elements[-1][2].append([x.decode() for x in t[1:]])
        elif t[0] == b"end_header":
            return fmt, elements


def read_ascii_ply(path):
    with open_maybe_gz(path) as f:
        fmt, elements = read_ply_header(f, path)
        if fmt != "ascii":
            raise ValueError("%s: only ASCII PLY input is handled (format %s)" % (path, fmt))
        verts, faces = [], []
        for name, count, props in elements:
            if name == "vertex":
                names = [p[-1] for p in props]
                if any(p[0] == "list" for p in props):
                    raise ValueError("%s: list vertex properties are not handled" % path)
                ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
                for _ in range(count):
                    t = f.readline().split()
                    verts.append((float(t[ix]), float(t[iy]), float(t[iz])))
            elif name == "face":
                if len(props) != 1 or props[0][0] != "list":
                    raise ValueError("%s: face element must be a single list property" % path)
                for _ in range(count):
                    t = f.readline().split()
                    n = int(t[0])
                    faces.append([int(x) for x in t[1:1 + n]])
                    if len(faces[-1]) != n:
                        raise ValueError("%s: face %d is short" % (path, len(faces) - 1))
            else:
                for _ in range(count):
                    f.readline()
    return verts, faces


STRUCT_CODES = {"char": "b", "uchar": "B", "int8": "b", "uint8": "B", "short": "h", "ushort": "H", "int16": "h",
                "uint16": "H", "int": "i", "uint": "I", "int32": "i", "uint32": "I", "float": "f", "float32": "f",
                "double": "d", "float64": "d"}


def read_ply_elements(path):
    """Every element of a PLY file (ASCII or binary little endian, optionally .gz), in file order, as
    (name, records): one dict per record, property name -> value (a list of ints for a list
    property; ints and floats as the file stores them, except that ASCII scalars are floats)."""
    with open_maybe_gz(path) as f:
        fmt, elements = read_ply_header(f, path)
        body = f.read()
    result = []
    if fmt == "ascii":
        tokens = body.split()
        pos = 0
        for name, count, props in elements:
            records = []
            for _ in range(count):
                rec = {}
                for prop in props:
                    if prop[0] == "list":
                        n = int(tokens[pos])
                        item = float if prop[2] in ("float", "float32", "double", "float64") else int
                        rec[prop[-1]] = [item(t) for t in tokens[pos + 1:pos + 1 + n]]
                        pos += 1 + n
                    else:
                        rec[prop[-1]] = float(tokens[pos])
                        pos += 1
                records.append(rec)
            result.append((name, records))
        return result
    if fmt != "binary_little_endian":
        raise ValueError("%s: PLY format %s is not handled" % (path, fmt))
    pos = 0
    for name, count, props in elements:
        names = [p[-1] for p in props]
        records = []
        if all(p[0] != "list" for p in props):  # fixed-size records: one unpack each
            st = struct.Struct("<" + "".join(STRUCT_CODES[p[0]] for p in props))
            for _ in range(count):
                records.append(dict(zip(names, st.unpack_from(body, pos))))
                pos += st.size
        else:
            for _ in range(count):
                rec = {}
                for prop in props:
                    if prop[0] == "list":
                        cs = struct.Struct("<" + STRUCT_CODES[prop[1]])
                        n = cs.unpack_from(body, pos)[0]
                        pos += cs.size
                        vs = struct.Struct("<%d%s" % (n, STRUCT_CODES[prop[2]]))
                        rec[prop[-1]] = list(vs.unpack_from(body, pos))
                        pos += vs.size
                    else:
                        s = struct.Struct("<" + STRUCT_CODES[prop[0]])
                        rec[prop[-1]] = s.unpack_from(body, pos)[0]
                        pos += s.size
                records.append(rec)
        result.append((name, records))
    return result


def write_binary_ply(path, verts, faces, comments):
    nv = len(verts)
    for i, face in enumerate(faces):
        if len(face) > 255 or any(v < 0 or v >= nv for v in face):
            raise ValueError("face %d: bad vertex index or too many vertices" % i)
    header = ["ply", "format binary_little_endian 1.0"]
    header += ["comment " + c for c in comments]
    header += ["element vertex %d" % nv, "property float x", "property float y", "property float z",
               "element face %d" % len(faces), "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as f:
        f.write(("\n".join(header) + "\n").encode())
        pack3 = struct.Struct("<3f").pack
        f.write(b"".join(pack3(*v) for v in verts))
        f.write(b"".join(struct.pack("<B%di" % len(face), len(face), *face) for face in faces))


def header_and_data(path, data=True):
    with open(path, "rb") as f:
        fmt, elements = read_ply_header(f, path)
        counts = {name: count for name, count, _ in elements}
        return fmt, counts, f.read() if data else None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("convert")
    c.add_argument("input")
    c.add_argument("output")
    c.add_argument("--comment", action="append", default=[])
    n = sub.add_parser("counts")
    n.add_argument("file")
    s = sub.add_parser("same-data")
    s.add_argument("a")
    s.add_argument("b")
    args = ap.parse_args()
    try:
        if args.cmd == "convert":
            with open_maybe_gz(args.input) as f:
                is_ply = f.read(3) == b"ply"
            verts, faces = (read_ascii_ply if is_ply else read_off)(args.input)
            write_binary_ply(args.output, verts, faces, args.comment)
        elif args.cmd == "counts":
            _, counts, _ = header_and_data(args.file, data=False)
            print(counts.get("vertex", 0), counts.get("face", 0))
        else:
            fa, ca, da = header_and_data(args.a)
            fb, cb, db = header_and_data(args.b)
            if (fa, ca, da) != (fb, cb, db):
                print("differ: %s %s vs %s %s (%d vs %d data bytes)" % (fa, ca, fb, cb, len(da), len(db)))
                return 1
    except (OSError, ValueError, IndexError, StopIteration) as e:
        print("meshdata.py %s: %s" % (args.cmd, e or type(e).__name__), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
