#!/usr/bin/env bash
# Scale benchmark: the Stanford dragon (871,414 faces) subdivided once at edge midpoints (3.49 M
# faces, written to build/bench_scale/, never committed) through `conelod group`, `simplify` to
# 50 % and `lod build`: wall time and peak memory (GNU time's maximum resident set size) of each.
# Takes minutes: not part of CI.
#   scripts/bench_scale.sh [CONELOD]   default build/conelod/conelod
#   CONELOD_TEST_MESHES=...            where stanford_dragon_vrip_binary.ply is (../shared/test_meshes)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CONELOD="${1:-$ROOT/build/conelod/conelod}"
MESHES="${CONELOD_TEST_MESHES:-$ROOT/../shared/test_meshes}"
OUT="$ROOT/build/bench_scale"
mkdir -p "$OUT"
[ -x "$CONELOD" ] || { echo "bench_scale.sh: $CONELOD not built" >&2; exit 1; }
MESH="$OUT/dragon_subdivided.ply"
if [ ! -f "$MESH" ]; then
  python3 - "$MESHES/stanford_dragon_vrip_binary.ply" "$MESH" <<'PY'
import struct, sys
from array import array
src, dst = sys.argv[1], sys.argv[2]
data = open(src, "rb").read()
end = data.index(b"end_header\n") + len(b"end_header\n")
head = data[:end].decode().split("\n")
nv = int([l for l in head if l.startswith("element vertex")][0].split()[2])
nf = int([l for l in head if l.startswith("element face")][0].split()[2])
assert "property float x" in head and "format binary_little_endian 1.0" in head
pos = array("f", data[end:end + nv * 12])  # x y z floats only (the file has no other vertex property)
body = memoryview(data)[end + nv * 12:]
faces = array("i")
o = 0
for _ in range(nf):
    assert body[o] == 3
    faces.frombytes(body[o + 1:o + 13])
    o += 13
mid = {}
def midpoint(a, b):
    k = (a, b) if a < b else (b, a)
    m = mid.get(k)
    if m is None:
        m = len(pos) // 3
        pos.extend([(pos[3 * a + i] + pos[3 * b + i]) / 2 for i in range(3)])
        mid[k] = m
    return m
out = array("i")
for f in range(nf):
    a, b, c = faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]
    ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
    out.extend((a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca))
n_v, n_f = len(pos) // 3, len(out) // 3
with open(dst, "wb") as w:
    w.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
             "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n" % (n_v, n_f)).encode())
    w.write(pos.tobytes())
    three = b"\x03"
    for f in range(n_f):
        w.write(three)
        w.write(out[3 * f:3 * f + 3].tobytes())
print("bench_scale.sh: wrote %s: %d vertices, %d faces" % (dst, n_v, n_f))
PY
fi
run() {  # label, then the command: prints wall time and peak memory
  local label="$1"; shift
  /usr/bin/time -f "%e %M" -o "$OUT/time.txt" "$@" >/dev/null
  read -r secs kib < "$OUT/time.txt"
  printf "%-22s %8.1f s %8.0f MiB\n" "$label" "$secs" "$((kib / 1024))"
}
ls -l "$MESH" | awk '{printf "bench_scale.sh: %s, %.0f MiB\n", $NF, $5 / 1048576}'
run "info (load only)" "$CONELOD" info "$MESH"
run "group" "$CONELOD" group "$MESH" -o "$OUT/grouped.ply"
run "simplify to 50 %" "$CONELOD" simplify "$MESH" --groups cone:1 --target-ratio 0.5 -o "$OUT/simplified.ply"
run "lod build" "$CONELOD" lod build "$MESH" -o "$OUT/dragon.clod"
