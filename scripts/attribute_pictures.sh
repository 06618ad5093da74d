#!/usr/bin/env bash
# The pictures of docs/attributes.md (issue 26): the original, ours (`conelod simplify`) and
# MeshLab's quadric edge collapse side by side, from one camera, unlit (what you see is the colour),
# with a caption each (faces, colour RMS 0-255, distance RMS % of the diagonal).
#   coloured dragon at 2 %: MeshLab's "Quadric Edge Collapse Decimation" to the same face count;
#   textured dragon at 2 %: MeshLab's "... (with texture)" to the same face count.
# The meshes and figures come from scripts/compare_attributes.py (meshlabserver of the build, under
# xvfb-run); the panels are web/ply.html in Debian's headless chromium (web/shoot.mjs), served by
# python3's http.server; ImageMagick puts them side by side.
#   scripts/attribute_pictures.sh [--meshes DIR] [--build BUILD] [--out DIR] [--work DIR]
#       [--size WxH] [--samples N]
#   --meshes  dragon_coloured.ply, dragon_textured.ply and Dragon_ThicknessMap.jpg
#             (scripts/get_test_meshes.sh attributes) [$CONELOD_MESH_DIR or deps/test_meshes]
#   --out     where attributes_coloured_2pct.png and attributes_textured.png go [docs/img]
#   --work    the simplified meshes and the table [a temporary folder, removed]
#   --size    one panel [420x300]; --samples  compare_attributes.py's samples [200000]
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
usage() { sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }
die() { echo "attribute_pictures.sh: $*" >&2; exit 2; }

MESHES="${CONELOD_MESH_DIR:-$ROOT/deps/test_meshes}" BUILD="$ROOT/build" OUT="$ROOT/docs/img" WORK=""
SIZE=420x300 SAMPLES=200000
while [ $# -gt 0 ]; do
  [ $# -ge 2 ] || usage
  case "$1" in
    --meshes) MESHES="$2" ;;
    --build) BUILD="$2" ;;
    --out) OUT="$2" ;;
    --work) WORK="$2" ;;
    --size) [[ "$2" =~ ^[0-9]+x[0-9]+$ ]] || die "--size must be WxH"; SIZE="$2" ;;
    --samples) [[ "$2" =~ ^[0-9]+$ ]] || die "--samples must be a number"; SAMPLES="$2" ;;
    *) usage ;;
  esac
  shift 2
done
for f in dragon_coloured.ply dragon_textured.ply Dragon_ThicknessMap.jpg; do
  [ -f "$MESHES/$f" ] || die "no $MESHES/$f (CONELOD_MESH_DIR=$MESHES scripts/get_test_meshes.sh attributes)"
done
[ -x "$BUILD/conelod/conelod" ] || die "no $BUILD/conelod/conelod: build first"
[ -x "$BUILD/meshlab/bin/meshlabserver" ] || die "no $BUILD/meshlab/bin/meshlabserver (a build with the plugin for MeshLab 2020.09)"
[ -d "$ROOT/web/node_modules/three" ] || die "web/node_modules is missing: run scripts/setup.sh (npm ci in web/)"
for tool in node convert xvfb-run python3; do command -v "$tool" >/dev/null || die "$tool not found (scripts/setup.sh)"; done
MESHES="$(cd "$MESHES" && pwd)"
mkdir -p "$OUT"
OUT="$(cd "$OUT" && pwd)"

TMP="$(mktemp -d)"
cleanup() {
  if [ -n "${SERVER:-}" ]; then kill "$SERVER" 2>/dev/null || true; wait "$SERVER" 2>/dev/null || true; fi
  rm -rf "$TMP"
}
trap 'rc=$?; cleanup; exit $rc' EXIT
[ -n "$WORK" ] || WORK="$TMP/work"
mkdir -p "$WORK"
WORK="$(cd "$WORK" && pwd)"

# The meshes and their figures.
convert "$MESHES/Dragon_ThicknessMap.jpg" "$TMP/thick.ppm"
python3 "$ROOT/scripts/compare_attributes.py" --build "$BUILD" --coloured "$MESHES/dragon_coloured.ply" \
  --textured "$MESHES/dragon_textured.ply" --texture "$TMP/thick.ppm" --ratios 0.02 --texture-ratios 0.02 \
  --samples "$SAMPLES" --out "$WORK" >"$WORK/table.md"
cat "$WORK/table.md"

# One caption per panel from the table: "LABEL: N faces (WHAT)\ncolour RMS C, distance D % of the diagonal".
caption() {  # mesh tool label
  awk -F'|' -v mesh="$1" -v tool="$2" -v label="$3" '
    function trim(s) { gsub(/^ +| +$/, "", s); return s }
    trim($2) == mesh && trim($4) == tool {
      printf "%s: %d faces\ncolour RMS %.1f, distance RMS %.3f %%", label, trim($5), trim($6), trim($7); found = 1; exit }
    END { if (!found) exit 1 }' "$WORK/table.md" || die "no row for $1 / $2 in $WORK/table.md"
}
faces_of() { sed -n '/end_header/q; s/^element face \([0-9]*\).*/\1/p' "$1"; }

# The camera frames the original's bounding box, for all three panels.
box_of() {
  python3 -c '
import sys
sys.path.insert(0, sys.argv[1])
from meshdata import read_ply_elements
v = dict(read_ply_elements(sys.argv[2]))["vertex"]
lo = [min(r[k] for r in v) for k in "xyz"]
hi = [max(r[k] for r in v) for k in "xyz"]
print(",".join("%.6g" % x for x in lo + hi))' "$ROOT/scripts" "$1"
}

# Serve the page, three.js and the meshes (python3's http.server on a free port).
SRV="$TMP/srv"
mkdir -p "$SRV"
ln -s "$ROOT/web/ply.html" "$SRV/ply.html"
ln -s "$(cd "$ROOT/web/node_modules" && pwd)" "$SRV/node_modules"
for f in "$MESHES"/dragon_coloured.ply "$MESHES"/dragon_textured.ply "$MESHES"/Dragon_ThicknessMap.jpg "$WORK"/*.ply; do
  ln -s "$f" "$SRV/$(basename "$f")"
done
python3 -u -m http.server 0 --bind 127.0.0.1 --directory "$SRV" >"$TMP/http.log" 2>&1 &
SERVER=$!
PORT=""
for _ in $(seq 100); do
  PORT="$(sed -n 's/.* port \([0-9]*\) .*/\1/p' "$TMP/http.log")"
  [ -n "$PORT" ] && break
  kill -0 "$SERVER" 2>/dev/null || die "http.server failed: $(cat "$TMP/http.log")"
  sleep 0.1
done
[ -n "$PORT" ] || die "http.server printed no port"

# The dragon stands along -z; seen from +y, a little from above; dark background (its colours are light).
VIEW="eye=0,1,-0.3&up=0,0,-1&zoom=1.45&bg=3a3f4b"
BOX="$(box_of "$MESHES/dragon_coloured.ply")"
URL="http://127.0.0.1:$PORT/ply.html?$VIEW&box=$BOX&ply="
node "$ROOT/web/shoot.mjs" --size "$SIZE" --timeout 300 \
  "${URL}dragon_coloured.ply" "$TMP/c0.png" "${URL}ours_0.02.ply" "$TMP/c1.png" "${URL}meshlab_0.02.ply" "$TMP/c2.png" \
  "${URL}dragon_textured.ply" "$TMP/t0.png" "${URL}tex_ours_0.02.ply" "$TMP/t1.png" "${URL}tex_meshlab_0.02.ply" "$TMP/t2.png" \
  >"$TMP/shoot.log" || { cat "$TMP/shoot.log" >&2; die "web/shoot.mjs failed"; }

panel() {  # picture caption out.png (ImageMagick reads % as an escape: doubled)
  convert "$1" -background white -fill black -font DejaVu-Sans -pointsize 14 -gravity center \
    \( -size "${SIZE%x*}x" caption:"${2//%/%%}" \) -append -bordercolor white -border 4 "$3"
}
ORIG="$(faces_of "$MESHES/dragon_coloured.ply")"
panel "$TMP/c0.png" "original: $ORIG faces (vertex colours)
dragon_coloured.ply" "$TMP/p0.png"
panel "$TMP/c1.png" "$(caption dragon_coloured.ply ours 'ours, 2 %')" "$TMP/p1.png"
panel "$TMP/c2.png" "$(caption dragon_coloured.ply 'MeshLab QEM' 'MeshLab QEM, 2 %')" "$TMP/p2.png"
convert "$TMP/p0.png" "$TMP/p1.png" "$TMP/p2.png" +append -colors 256 "PNG8:$OUT/attributes_coloured_2pct.png"

REACHED="$(faces_of "$WORK/tex_ours_0.02.ply")"
PCT="$(awk -v a="$REACHED" -v b="$(faces_of "$MESHES/dragon_textured.ply")" 'BEGIN { printf "%.1f", 100 * a / b }')"
panel "$TMP/t0.png" "original: $(faces_of "$MESHES/dragon_textured.ply") faces (texture)
dragon_textured.ply" "$TMP/p0.png"
panel "$TMP/t1.png" "$(caption dragon_textured.ply ours "ours, $PCT %")" "$TMP/p1.png"
panel "$TMP/t2.png" "$(caption dragon_textured.ply 'MeshLab QEM (with texture)' "MeshLab QEM with texture, $PCT %")" "$TMP/p2.png"
convert "$TMP/p0.png" "$TMP/p1.png" "$TMP/p2.png" +append -colors 256 "PNG8:$OUT/attributes_textured.png"
ls -l "$OUT/attributes_coloured_2pct.png" "$OUT/attributes_textured.png"
