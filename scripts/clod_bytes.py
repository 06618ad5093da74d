#!/usr/bin/env python3
"""Where the bytes of a .clod file (versions 6 to 8) are: per node level, the records and each
geometry stream (positions, triangles, vertex id mask, listed ids, attributes, blob headers), as
stored (deflated where the file deflates them), and the unit vertices and faces they hold.

    scripts/clod_bytes.py FILE.clod [--json]

The layout is vcg_ext/conelod/lod/lod_format.md's; this reads it with no check beyond what it
needs (use `conelod lod info` to check a file)."""
import json
import struct
import sys


def uv(b, at):
    x, shift = 0, 0
    while True:
        c = b[at]
        at += 1
        x |= (c & 0x7F) << shift
        shift += 7
        if not c & 0x80:
            return x, at


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    if len(args) != 1:
        sys.exit(__doc__)
    b = open(args[0], "rb").read()
    version, levels = struct.unpack_from("<II", b, 24)
    if version < 6:
        sys.exit("clod_bytes.py: version %d: only versions 6 to 9 (the compact index)" % version)
    node_count = struct.unpack_from("<Q", b, 24 + 24)[0]
    hier, geos, index = struct.unpack_from("<QQQ", b, 24 + 64)
    first_id = []
    for k in range(levels):
        faces, nodes, first = struct.unpack_from("<QQQ", b, 24 + 128 + 32 * k)
        first_id.append((first, nodes))
    attributes = struct.unpack_from("<I", b, 24 + 128 + 32 * levels)[0]

    def level_of(node):
        for k, (first, nodes) in enumerate(first_id):
            if first <= node < first + nodes:
                return k
        raise ValueError(node)

    # The index: INDX data (u64 entries, u32 block, u32 pad, u32 start per block), then the IBLKs.
    data_bytes = struct.unpack_from("<Q", b, index + 8)[0]
    entries, block = struct.unpack_from("<QI", b, index + 24)
    blocks = (entries + block - 1) // block
    first_block = index + 24 + data_bytes
    records, blobs = [], []  # records: (node, bytes); blobs: (offset, bytes, first node)
    node = 0
    for i in range(blocks):
        at = first_block + struct.unpack_from("<I", b, index + 24 + 16 + 4 * i)[0]
        end = at + 24 + struct.unpack_from("<Q", b, at + 8)[0]
        record, geometry = struct.unpack_from("<QQ", b, at + 24)
        p = at + 24 + 16
        while p < end:
            code, p = uv(b, p)
            size = (code >> 1) + 26
            records.append((node, size))
            record += size
            if code & 1:
                g, p = uv(b, p)
                blobs.append((geometry, g, node))
                geometry += g
            node += 1
    assert node == node_count, (node, node_count)

    names = ["records", "headers", "positions", "triangles", "id mask", "ids", "colours", "normals", "uvs"]
    per = [dict((n, 0) for n in names + ["nodes", "units", "unit vertices", "faces"]) for _ in range(levels)]
    for n, size in records:
        per[level_of(n)]["records"] += size
        per[level_of(n)]["nodes"] += 1
    seen = set()
    for offset, size, n in blobs:
        if offset in seen:  # a unit split across two index blocks: listed again by the second
            continue
        seen.add(offset)
        L = per[level_of(n)]
        L["units"] += 1
        p = offset + 5
        _, p = uv(b, p)
        count, p = uv(b, p)
        for _ in range(count):
            f, p = uv(b, p)
            L["faces"] += f
        vc, p = uv(b, p)
        L["unit vertices"] += vc
        for _ in range(4):
            _, p = uv(b, p)

        def stream(p, name):
            start = p
            code, p = uv(b, p)
            if version >= 7 and code & 1:
                _, p = uv(b, p)
            stored = code >> 1 if version >= 7 else code
            L[name] += stored
            L["headers"] += p - start
            return p + stored
        L["headers"] += p - offset
        head_end = p
        p = stream(p, "positions")
        p = stream(p, "triangles")
        mask = b[p:p + (vc + 7) // 8]
        L["id mask"] += len(mask)
        p += len(mask)
        fresh = sum(bin(x).count("1") for x in mask)
        if fresh < vc:
            p = stream(p, "ids")
        for bit, name in ((2, "colours"), (4, "normals"), (8, "uvs")):
            if attributes & bit:
                p = stream(p, name)
        assert p == offset + size, (offset, size, p)
        del head_end
    total = dict((n, sum(L[n] for L in per)) for n in per[0])
    if "--json" in sys.argv:
        print(json.dumps({"file": args[0], "version": version, "bytes": len(b), "levels": per, "total": total}))
        return
    shown = [n for n in names if total[n]]
    print("%s: version %d, %d bytes" % (args[0], version, len(b)))
    print("level " + " ".join("%11s" % n for n in shown + ["unit verts", "faces"]) + "  pos bits/coord")
    for k, L in enumerate(per + [total]):
        print("%5s " % (k if k < levels else "all") + " ".join("%11d" % L[n] for n in shown) +
              " %11d %11d  %6.2f" % (L["unit vertices"], L["faces"],
                                      8.0 * L["positions"] / max(1, 3 * L["unit vertices"])))


if __name__ == "__main__":
    main()
