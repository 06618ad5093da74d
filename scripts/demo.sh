#!/usr/bin/env bash
# The main job on a bundled mesh: groups the Stanford bunny by normal cones, writes a PLY coloured
# by group (out/bunny_groups.ply: per-face quality = group id) and prints the per-level table and
# the culling cost. Open the PLY in MeshLab to see the groups.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUNNY="$ROOT/../shared/test_meshes/stanford_bunny_bun_zipper.ply"
[ -f "$BUNNY" ] || { bash "$ROOT/scripts/get_test_meshes.sh" bunny; BUNNY="$ROOT/deps/test_meshes/stanford_bunny_bun_zipper.ply"; }
CONELOD="$(command -v conelod || echo "$ROOT/build/conelod/conelod")"
mkdir -p "$ROOT/out"
"$CONELOD" group "$BUNNY" -o "$ROOT/out/bunny_groups.ply" --level 2
echo
"$CONELOD" cull-cost "$BUNNY"
