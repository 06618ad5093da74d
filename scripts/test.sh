#!/usr/bin/env bash
# Runs every ConeLOD test: GoogleTest unit tests of the core and integration tests through the
# real meshlabserver (under xvfb-run), the plugin harness and the conelod CLI. Needs
# scripts/setup.sh once before. Real meshes come from ../shared/test_meshes, or from
# deps/test_meshes (fetched from Debian and npm packages by scripts/get_test_meshes.sh) when that
# folder is absent. Arguments go to ctest.
#   scripts/test.sh --meshlab 2022.02|2025.07   the plugin in that MeshLab's root (made by
#     scripts/setup.sh --meshlab VERSION): rebuilds it there, runs the plugin harness (every
#     filter on the bunny, failures, every shipped .mlx run as MeshLab 2022+ runs scripts),
#     checks that every filter gives the bunny the output it gives in MeshLab 2020.09 (the
#     harness digest of scripts/test.sh, run before), checks in the real GUI under Xvfb that a
#     path typed into a file box is written (scripts/gui_file_box.sh), and for 2025.07 takes a
#     screenshot of the grouped bunny in the GUI (scripts/gui_screenshot.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
MESHLAB=2020.09
if [ "${1:-}" = --meshlab ]; then
  [ $# -ge 2 ] || { echo "test.sh: --meshlab needs a version (2022.02 or 2025.07)" >&2; exit 2; }
  MESHLAB="$2"; shift 2
fi
if [ -z "${CONELOD_TEST_MESHES:-}" ]; then
  if [ -d "$ROOT/../shared/test_meshes" ]; then
    CONELOD_TEST_MESHES="$(cd "$ROOT/../shared/test_meshes" && pwd)"
  else
    bash "$ROOT/scripts/get_test_meshes.sh"
    CONELOD_TEST_MESHES="$ROOT/deps/test_meshes"
  fi
fi
export CONELOD_TEST_MESHES
if [ "$MESHLAB" != 2020.09 ]; then
  # shellcheck source=scripts/lib.sh
  . "$ROOT/scripts/lib.sh"
  suite="$(meshlab_suite "$MESHLAB")"
  R="$CONELOD_ROOTS/$suite"
  [ -f "$R/.conelod-root" ] || { echo "test.sh: run scripts/setup.sh --meshlab $MESHLAB first" >&2; exit 1; }
  reference="$BUILD/plugin_digest.txt"
  [ -f "$reference" ] || { echo "test.sh: $reference missing: run scripts/test.sh (MeshLab 2020.09) first" >&2; exit 1; }
  start=$SECONDS
  build_in_root "$R" "$ROOT" "$CONELOD_TEST_MESHES" >/dev/null
  echo "==> MeshLab $MESHLAB: plugin rebuilt in $R in $((SECONDS - start)) s"
  start=$SECONDS
  rm -f "$R/conelod/build/plugin_digest.txt"
  root_run "$R" sh -c 'cd /conelod/build && ctest -V -R it_plugin_harness'
  echo "==> MeshLab $MESHLAB: plugin harness passed in $((SECONDS - start)) s"
  if diff -u "$reference" "$R/conelod/build/plugin_digest.txt"; then
    echo "==> MeshLab $MESHLAB: every filter gives the bunny the output it gives in MeshLab 2020.09 ($(wc -l < "$reference") filters)"
  else
    echo "test.sh: MeshLab $MESHLAB gives other results than 2020.09 (above)" >&2; exit 1
  fi
  start=$SECONDS
  bash "$ROOT/scripts/gui_file_box.sh" --meshlab "$MESHLAB" "$BUILD/meshlab-$MESHLAB-typed-file-path.png" \
    "$CONELOD_TEST_MESHES/stanford_bunny_bun_zipper.ply"
  echo "==> MeshLab $MESHLAB: a path typed into the GUI's file box is written ($((SECONDS - start)) s)"
  if [ "$MESHLAB" = 2025.07 ]; then
    start=$SECONDS
    bash "$ROOT/scripts/gui_screenshot.sh" --meshlab "$MESHLAB" "$BUILD/meshlab-$MESHLAB-grouped-bunny.png" \
      "$CONELOD_TEST_MESHES/stanford_bunny_bun_zipper.ply"
    echo "==> MeshLab $MESHLAB: GUI screenshot in $((SECONDS - start)) s"
  fi
  exit 0
fi
[ -f "$ROOT/deps/meshlab-src/vcglib/vcg/complex/complex.h" ] \
  || { echo "test.sh: run scripts/setup.sh first (it fetches MeshLab's headers and vcglib)" >&2; exit 1; }
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCONELOD_TEST_MESHES="$CONELOD_TEST_MESHES" >/dev/null
cmake --build "$BUILD" -j "$(nproc)"
cd "$BUILD"
ctest --output-on-failure -j "$(nproc)" "$@"
