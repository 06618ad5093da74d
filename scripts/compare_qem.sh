#!/usr/bin/env bash
# Compares ConeLOD's group-preserving quadric edge collapse with MeshLab's "Quadric Edge Collapse
# Decimation" and meshoptimizer's meshopt_simplify at EQUAL face counts: for every mesh, every
# target and every normal-cone level (plus `auto`), ours runs first and the two peers run to exactly
# the faces ours reached; errors are two-sided sampled Hausdorff distances (RMS and max, % of the
# bounding-box diagonal). Writes OUT/results.tsv, OUT/summary.md and a PNG per mesh.
#
#   scripts/compare_qem.sh [--meshes bunny,dragon | MESH...] [--targets 0.5,0.1,0.02]
#                          [--levels all,auto] [--samples N] [--out DIR] [--ours-args '...']
#
# Meshes: every .ply of $CONELOD_TEST_MESHES (default ../shared/test_meshes) unless named. Needs a
# build (CONELOD_BUILD_DIR, default build/) with conelod, the private meshlabserver
# (target private_meshlab) and tools/meshopt_simplify; xvfb-run, python3 and gnuplot.
# Details: scripts/compare_qem.py and docs/group_qem.md.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
if [ "${1:-}" = "-h" ] || [ "${1:-}" = "--help" ]; then
  sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'
  exit 0
fi
exec nice python3 "$ROOT/scripts/compare_qem.py" --build "$BUILD" --source "$ROOT" "$@"
