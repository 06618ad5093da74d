#!/usr/bin/env bash
# Regenerates scripts/mlx/ from the built plugin: one script per filter, every parameter at its
# default (meshlabserver aborts on a script that misses one). Run after changing a filter's
# parameters; the test it_mlx_scripts_in_sync fails until you do. QT_HASH_SEED=0: Qt then writes
# the attributes in the same order every time, so a regeneration changes only what changed.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
tmp="$(mktemp -d)"
QT_HASH_SEED=0 QT_QPA_PLATFORM=offscreen XDG_RUNTIME_DIR="$tmp" "$BUILD/tests/mlx_defaults" \
  "$BUILD/filter_conelod/libfilter_conelod.so" "$tmp/mlx" >/dev/null
rm -f "$ROOT"/scripts/mlx/*.mlx
cp "$tmp"/mlx/*.mlx "$ROOT/scripts/mlx/"
rm -rf "$tmp"
ls "$ROOT/scripts/mlx"
