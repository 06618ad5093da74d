#!/usr/bin/env bash
# The core's unit tests and the CLI integration tests built with AddressSanitizer and UBSan
# (no plugin: MeshLab itself is not built with sanitizers; no viewer: Qt, D-Bus and Mesa leak at
# exit in ways LeakSanitizer reports and we cannot fix). Run by CI after scripts/test.sh. Of the web
# tests only conelod serve's own (it_web_serve_http) runs here: the page's tests drive chromium,
# whose work is not ours to sanitize, and take most of the label's time.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_ASAN_BUILD_DIR:-$ROOT/build-asan}"
MESHES="${CONELOD_TEST_MESHES:-}"
if [ -z "$MESHES" ]; then
  if [ -d "$ROOT/../shared/test_meshes" ]; then MESHES="$(cd "$ROOT/../shared/test_meshes" && pwd)"
  else bash "$ROOT/scripts/get_test_meshes.sh"; MESHES="$ROOT/deps/test_meshes"; fi
fi
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCONELOD_SANITIZE=ON -DCONELOD_BUILD_PLUGIN=OFF -DCONELOD_BUILD_VIEWER=OFF \
  -DCONELOD_TEST_MESHES="$MESHES" >/dev/null
cmake --build "$BUILD" -j "$(nproc)"
cd "$BUILD"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  CONELOD_TEST_MESHES="$MESHES" ctest --output-on-failure -j "$(nproc)" \
  -E '^it_web_(viewer|screenshot)'
