#!/usr/bin/env bash
# Pictures of docs/feature_simplify.md and docs/pixel_budget.md: the input, our simplification,
# the paper's pure curvature order and MeshLab's QEM side by side, feature edges (dihedral angle
# <= 135 deg, border edges) in red over a grey wireframe, rendered headlessly by tools/render_mesh.
# Needs the meshes written by:  scripts/compare_feature.py --pure --keep out/cmp_final \
#                                 fandisk.ply mech_holes_shark.ply stanford_bunny_bun_zipper.ply
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
MESHES="${CONELOD_TEST_MESHES:-$ROOT/../shared/test_meshes}"
CMP="${1:-$ROOT/out/cmp_final}"
IMG="$ROOT/docs/img"
R="$BUILD/tools/render_mesh"
tmp="$(mktemp -d)"
mkdir -p "$IMG"

panel() {  # mesh view label out.png
  "$R" "$1" "$tmp/p.ppm" --wire --view "$2" --size 330 270 --zoom "$zoom" >/dev/null
  faces=$("$BUILD/conelod/conelod" info "$1" --json | python3 -c "import json,sys; print(json.load(sys.stdin)['faces'])")
  convert "$tmp/p.ppm" -font DejaVu-Sans -pointsize 14 -gravity North -annotate +0+4 "$3 ($faces faces)" "$4"
}

for stem in fandisk mech_holes_shark stanford_bunny_bun_zipper; do
  case "$stem" in
    fandisk) view="-1,-1,-1"; zoom=1.3 ;;
    mech_holes_shark) view="-1,-1,-1"; zoom=1.05 ;;
    *) view="0.3,-0.2,-1"; zoom=1.15 ;;
  esac
  panel "$MESHES/$stem.ply" "$view" "input" "$tmp/a.png"
  panel "$CMP/${stem}_ours.ply" "$view" "ours" "$tmp/b.png"
  panel "$CMP/${stem}_ours_pure.ply" "$view" "ours, paper's order" "$tmp/c.png"
  panel "$CMP/${stem}_qem.ply" "$view" "MeshLab QEM" "$tmp/d.png"
  convert "$tmp/a.png" "$tmp/b.png" "$tmp/c.png" "$tmp/d.png" +append -strip "$IMG/feature_${stem}.png"
  echo "$IMG/feature_${stem}.png"
done

# The covered pixels of the bunny at 1920 x 1080 (worst of the six axis directions), shrunk.
"$BUILD/conelod/conelod" budget "$MESHES/stanford_bunny_bun_zipper.ply" --mask "$tmp/mask.pgm" >/dev/null
convert "$tmp/mask.pgm" -resize 640x360 -bordercolor grey70 -border 1 -font DejaVu-Sans -pointsize 14 \
  -gravity North -annotate +0+6 "bunny at 1920 x 1080: covered pixels in black" -strip "$IMG/budget_bunny_mask.png"
echo "$IMG/budget_bunny_mask.png"
rm -rf "$tmp"
