#!/usr/bin/env bash
# ConeLOD benchmarks: configures build-bench/ (Release, benchmarks on, no plugin, no tests), builds
# and runs bench_grouping (speed and memory of BuildConeHierarchy).
#   scripts/bench.sh [MESH.ply...] [--benchmark_* flags]
#   default meshes: ../shared/test_meshes/{stanford_bunny_bun_zipper,stanford_dragon_vrip_binary}.ply
#   MESHLAB_SRC=/path/to/meshlab-src   where vcglib is (default: deps/meshlab-src)
#   LOD=1                              also run bench_lod (the .clod file: build, first image, reader
#                                      memory against vcglib) on the same meshes
#   CHECK=1                            also run check_grouping on the meshes and on synthetic ones
#                                      (guarantees + result digests, to compare two versions)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="$ROOT/build-bench"
MESHLAB_SRC="${MESHLAB_SRC:-$ROOT/deps/meshlab-src}"

cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DCONELOD_BUILD_BENCHMARKS=ON \
  -DCONELOD_BUILD_PLUGIN=OFF -DCONELOD_BUILD_TESTS=OFF -DMESHLAB_SRC="$MESHLAB_SRC" >/dev/null
cmake --build "$BUILD" -j"$(nproc)" --target bench_grouping check_grouping bench_lod >/dev/null

"$BUILD/bench/bench_grouping" "$@"
if [ "${CHECK:-0}" = 1 ]; then
  meshes=()
  for a in "$@"; do [[ "$a" == --* ]] || meshes+=("$a"); done
  if [ ${#meshes[@]} -eq 0 ]; then
    meshes=("$ROOT/../shared/test_meshes/stanford_bunny_bun_zipper.ply"
            "$ROOT/../shared/test_meshes/stanford_dragon_vrip_binary.ply")
  fi
  "$BUILD/bench/check_grouping" --synthetic "${meshes[@]}"
fi
if [ "${LOD:-0}" = 1 ]; then
  meshes=()
  for a in "$@"; do [[ "$a" == --* ]] || meshes+=("$a"); done
  "$BUILD/bench/bench_lod" "${meshes[@]}"
fi
