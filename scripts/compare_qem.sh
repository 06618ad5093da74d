#!/usr/bin/env bash
# Compares ConeLOD's group-preserving quadric edge collapse with MeshLab's built-in "Quadric Edge
# Collapse Decimation" on each MESH: same grouped input (normal-cone groups of --level L), targets
# 50%, 10% and 1% of the faces; time, faces reached, Hausdorff distance both ways, group integrity.
# Writes a Markdown table and a PNG plot per mesh into --out (default: qem_compare/).
#
#   scripts/compare_qem.sh [--level L | --pca K] [--targets 0.5,0.1,0.01] [--samples N] [--out DIR] MESH...
#
# Needs a build (CONELOD_BUILD_DIR, default build/) with the plugin and its private meshlabserver,
# xvfb-run, python3 and gnuplot. Details: scripts/compare_qem.py and docs/group_qem.md.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
if [ $# -eq 0 ]; then
  sed -n '2,10p' "$0" | sed 's/^# \{0,1\}//'
  exit 1
fi
exec python3 "$ROOT/scripts/compare_qem.py" --build "$BUILD" --source "$ROOT" "$@"
