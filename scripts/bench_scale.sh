#!/usr/bin/env bash
# Scale benchmark (issue 27): the Stanford dragon (871,414 faces) subdivided 1, 2 and 3 times at
# edge midpoints (3.49 M, 13.94 M, 55.77 M faces; written to build/bench_scale/, never
# committed), through `conelod lod build --memory 1G` (2G at 55.8 M faces) at 1 and 2 threads
# and on every core, and optionally `conelod group` and `simplify` to 10 %. One table: wall
# seconds, CPU seconds (user + system), peak resident memory (GNU time's maximum RSS), peak
# bytes per input face, file bytes per input face, the 1-minute load as the step started. Then,
# for each .clod file built, two more tables: the desktop viewer's first image (conelod-viewer
# --screenshot --json --frames 0 under xvfb-run -a: first_image_ms from the process's start to
# the image on the window, open_ms the file's part) and the crack check of its cuts at 5 / 20 / 50 % (build/tools/
# lod_cracks, the eye of scripts/lod_cracks.py: cracks, overlaps, seconds, peak RSS). Takes
# minutes to hours: not part of CI.
#   scripts/bench_scale.sh [CONELOD]   default build/conelod/conelod
#   SCALE_LEVELS="1 2 3"               subdivisions to run (default: 1 2 3)
#   SCALE_MEMORY=2G                    lod build --memory for every level (default: 1G, 2G at 55.8 M faces)
#   SCALE_CHECKS="viewer cracks"       what to check of each built file (default: both; "" none)
#   SCALE_STEPS="lod"                  any of: lod group simplify (default: lod); simplify runs the
#                                      one-piece peer (--partition-above 0) and then in parts per thread count
#   SCALE_THREADS="1 2 0"              lod build, group and simplify --threads values (0: one per core; default 1 2 0)
#   CONELOD_TEST_MESHES=...            where stanford_dragon_vrip_binary.ply is (../shared/test_meshes)
#   SUBDIVIDE=...                      the splitter (default: build/tools/subdivide_ply beside CONELOD)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CONELOD="${1:-$ROOT/build/conelod/conelod}"
MESHES="${CONELOD_TEST_MESHES:-$ROOT/../shared/test_meshes}"
LEVELS="${SCALE_LEVELS:-1 2 3}"
STEPS="${SCALE_STEPS:-lod}"
THREADS="${SCALE_THREADS:-1 2 0}"
CHECKS="${SCALE_CHECKS-viewer cracks}"
VIEWER="$(dirname "$CONELOD")/../viewer/conelod-viewer"
CRACKS="$(dirname "$CONELOD")/../tools/lod_cracks"
OUT="$ROOT/build/bench_scale"
mkdir -p "$OUT"
[ -x "$CONELOD" ] || { echo "bench_scale.sh: $CONELOD not built" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "bench_scale.sh: needs GNU time (/usr/bin/time)" >&2; exit 1; }

# dragon_sub{K}.ply: the dragon subdivided K times (each from the previous one), by
# build/tools/subdivide_ply when it is built (seconds), else by the same split in Python (minutes;
# the same bytes).
SUBDIVIDE="${SUBDIVIDE:-$(dirname "$CONELOD")/../tools/subdivide_ply}"
subdivide() {  # src dst
  if [ -x "$SUBDIVIDE" ]; then
    "$SUBDIVIDE" "$1" "$2"
    return
  fi
  python3 - "$1" "$2" <<'PY'
import sys
from array import array
src, dst = sys.argv[1], sys.argv[2]
with open(src, "rb") as f:
    head = b""
    while not head.endswith(b"end_header\n"):
        head += f.readline()
    lines = head.decode().split("\n")
    nv = int([l for l in lines if l.startswith("element vertex")][0].split()[2])
    nf = int([l for l in lines if l.startswith("element face")][0].split()[2])
    assert "property float x" in lines and "format binary_little_endian 1.0" in lines
    pos = array("f")
    pos.frombytes(f.read(nv * 12))  # x y z floats only (the file has no other vertex property)
    body = f.read(nf * 13)
faces = array("i")
for o in range(0, nf * 13, 13):
    assert body[o] == 3
    faces.frombytes(body[o + 1:o + 13])
del body
mid = {}
def midpoint(a, b):
    k = a * 4294967296 + b if a < b else b * 4294967296 + a
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
del mid, faces
n_v, n_f = len(pos) // 3, len(out) // 3
with open(dst + ".part", "wb") as w:
    w.write(("ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
             "property float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n" % (n_v, n_f)).encode())
    w.write(pos.tobytes())
    three = b"\x03"
    for f in range(0, n_f, 65536):
        chunk = out[3 * f:3 * min(n_f, f + 65536)].tobytes()
        w.write(b"".join(three + chunk[12 * i:12 * i + 12] for i in range(len(chunk) // 12)))
import os
os.replace(dst + ".part", dst)
print("bench_scale.sh: wrote %s: %d vertices, %d faces" % (dst, n_v, n_f))
PY
}
prev="$MESHES/stanford_dragon_vrip_binary.ply"
for k in 1 2 3; do
  mesh="$OUT/dragon_sub$k.ply"
  need=0
  for want in $LEVELS; do
    if [ "$want" -ge "$k" ]; then need=1; fi
  done
  if [ "$need" = 1 ] && [ ! -f "$mesh" ]; then subdivide "$prev" "$mesh"; fi
  prev="$mesh"
done

faces_of() { head -c 400 "$1" | tr -d '\0' | awk '/^element face/ {print $3; exit}'; }
echo "bench_scale.sh: $(nproc) cores, $(awk '/MemTotal/ {printf "%.1f GiB", $2 / 1048576}' /proc/meminfo), load: $(cut -d' ' -f1-3 /proc/loadavg)"
printf "| faces | step | threads | wall s | CPU s | CPU us/face | peak RSS MiB | peak B/face | file B/face | load |\n"
printf "|---|---|---|---|---|---|---|---|---|---|\n"
row() {  # faces, step, threads, output file or -, then the command
  local faces="$1" step="$2" threads="$3" file="$4"
  shift 4
  local load
  load=$(cut -d' ' -f1 /proc/loadavg)  # the 1-minute load as the step starts (other work slows wall times)
  if ! /usr/bin/time -f "%e %U %S %M" -o "$OUT/time.txt" "$@" >"$OUT/log.txt" 2>&1; then
    echo "bench_scale.sh: failed: $*" >&2
    tail -5 "$OUT/log.txt" >&2
    return 1
  fi
  read -r wall user sys kib < <(tail -1 "$OUT/time.txt")
  local bytes=0
  if [ "$file" != - ]; then bytes=$(stat -c %s "$file"); fi
  awk -v f="$faces" -v s="$step" -v t="$threads" -v w="$wall" -v u="$user" -v y="$sys" -v k="$kib" -v b="$bytes" -v l="$load" \
    'BEGIN { c = u + y; printf "| %.2f M | %s | %s | %.1f | %.1f | %.2f | %.0f | %.0f | %s | %s |\n", f / 1e6, s, t, w, c,
             c * 1e6 / f, k / 1024, k * 1024 / f, (b > 0 ? sprintf("%.1f", b / f) : ""), l }'
}
for k in $LEVELS; do
  mesh="$OUT/dragon_sub$k.ply"
  faces=$(faces_of "$mesh")
  memory=1G
  if [ "$k" -ge 3 ]; then memory=2G; fi
  memory="${SCALE_MEMORY:-$memory}"
  for step in $STEPS; do
    case "$step" in
      lod)
        for t in $THREADS; do
          row "$faces" "lod build --memory $memory" "$t" "$OUT/dragon_sub$k.clod" \
            "$CONELOD" lod build "$mesh" -o "$OUT/dragon_sub$k.clod" --memory "$memory" --threads "$t"
        done ;;
      group)
        for t in $THREADS; do
          row "$faces" "group" "$t" - "$CONELOD" group "$mesh" -o "$OUT/grouped.ply" --threads "$t"
        done ;;
      simplify)
        # The peer: the one-piece collapse (--partition-above 0), then in parts on each --threads.
        row "$faces" "simplify --groups cone:auto 10 % one piece" 1 - \
          "$CONELOD" simplify "$mesh" --groups cone:auto --target-ratio 0.1 --partition-above 0 --threads 1 -o "$OUT/simplified.ply"
        for t in $THREADS; do
          row "$faces" "simplify --groups cone:auto 10 %" "$t" - \
            "$CONELOD" simplify "$mesh" --groups cone:auto --target-ratio 0.1 --threads "$t" -o "$OUT/simplified.ply"
        done ;;
      *) echo "bench_scale.sh: unknown step $step" >&2; exit 1 ;;
    esac
  done
done

# The built files: the viewer's first image, and the crack check of the cuts at 5 / 20 / 50 %.
built=()
for k in $LEVELS; do
  case " $STEPS " in *" lod "*) built+=("$k") ;; esac
done
for check in $CHECKS; do
  [ "${#built[@]}" -gt 0 ] || break
  case "$check" in
    viewer)
      if [ ! -x "$VIEWER" ] || ! command -v xvfb-run >/dev/null; then
        echo "bench_scale.sh: $VIEWER or xvfb-run missing: no first image" >&2
        continue
      fi
      printf "\n| faces | first image ms (process start) | open ms | faces drawn | groups drawn | process RSS MiB | load |\n"
      printf "|---|---|---|---|---|---|---|\n"
      for k in "${built[@]}"; do
        faces=$(faces_of "$OUT/dragon_sub$k.ply")
        load=$(cut -d' ' -f1 /proc/loadavg)
        if ! xvfb-run -a "$VIEWER" "$OUT/dragon_sub$k.clod" --screenshot "$OUT/first_image_$k.png" --size 800x600 \
          --frames 0 --json >"$OUT/viewer.json" 2>"$OUT/log.txt"; then
          echo "bench_scale.sh: failed: conelod-viewer $OUT/dragon_sub$k.clod" >&2
          tail -5 "$OUT/log.txt" >&2
          exit 1
        fi
        python3 - "$faces" "$load" "$OUT/viewer.json" <<'PY'
import json, sys
j = json.loads(open(sys.argv[3]).read().strip().split("\n")[-1])
c = j["coarse"]
print("| %.2f M | %.0f | %.1f | %d | %d | %.0f | %s |" % (int(sys.argv[1]) / 1e6, j["first_image_ms"], j["open_ms"],
      c["faces_drawn"], c["groups_drawn"], j["process_rss_bytes"] / 1048576, sys.argv[2]))
PY
      done ;;
    cracks)
      if [ ! -x "$CRACKS" ]; then
        echo "bench_scale.sh: $CRACKS not built: no crack check" >&2
        continue
      fi
      printf "\n| faces | cut | cut faces | cracks | overlaps | seconds | peak RSS MiB | load |\n"
      printf "|---|---|---|---|---|---|---|---|\n"
      for k in "${built[@]}"; do
        faces=$(faces_of "$OUT/dragon_sub$k.ply")
        load=$(cut -d' ' -f1 /proc/loadavg)
        if ! "$CRACKS" "$OUT/dragon_sub$k.clod" --budgets 5,20,50 >"$OUT/cracks.json" 2>"$OUT/log.txt"; then
          echo "bench_scale.sh: failed: lod_cracks $OUT/dragon_sub$k.clod" >&2
          tail -5 "$OUT/log.txt" >&2
          exit 1
        fi
        python3 - "$faces" "$load" "$OUT/cracks.json" <<'PY'
import json, sys
lines = [json.loads(l) for l in open(sys.argv[3]) if l.strip()]
for j in lines[:-1]:
    print("| %.2f M | %g %% | %d | %d | %d | %.1f | %.0f | %s |" % (int(sys.argv[1]) / 1e6, j["budget_percent"], j["faces"],
          j["cracks"], j["overlaps"], j["seconds"], j["peak_rss_bytes"] / 1048576, sys.argv[2]))
s = lines[-1]
print("| %.2f M | level 0 read: %s | | | | %.1f | %.0f | |" % (int(sys.argv[1]) / 1e6, "yes" if s["input_read"] else "no (no edge to look up)",
      s["input_seconds"], s["peak_rss_bytes"] / 1048576))
PY
      done ;;
    *) echo "bench_scale.sh: unknown check $check" >&2; exit 1 ;;
  esac
done
