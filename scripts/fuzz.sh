#!/usr/bin/env bash
# Fuzzes the .clod reader (vcg_ext/fuzz/lod_reader_fuzz.cpp) and the PLY input path
# (vcg_ext/fuzz/ply_reader_fuzz.cpp: read, check, group) with libFuzzer under ASan + UBSan, each for
# a bounded time. PLY seeds: the generated bad-input corpus (tests/integration/bad_inputs.py) and
# the small meshes below; inputs that once crashed are kept in vcg_ext/fuzz/regressions/ply/ and
# always run first. Builds into build-fuzz/ (ignored by git) with clang++; the seed corpus is written
# at run time by `conelod lod build` from small generated meshes (nothing binary is committed). The
# fuzz build ignores CRC mismatches (FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION) so that mutations
# reach the structural checks behind them.
#   scripts/fuzz.sh [SECONDS]          default 60 (FUZZ_SECONDS also works)
#   CONELOD=/path/to/conelod           the CLI that writes the seeds (default: build/conelod/conelod,
#                                      built by scripts/setup.sh)
#   MESHLAB_SRC=/path/to/meshlab-src   where vcglib is (default: deps/meshlab-src)
# Crashes are written to build-fuzz/crashes/ and make the script fail.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="$ROOT/build-fuzz"
SECONDS_TO_RUN="${1:-${FUZZ_SECONDS:-60}}"
MESHLAB_SRC="${MESHLAB_SRC:-$ROOT/deps/meshlab-src}"
CONELOD="${CONELOD:-$ROOT/build/conelod/conelod}"
CXX_FUZZ="${CXX_FUZZ:-clang++}"

[ -f "$MESHLAB_SRC/vcglib/vcg/complex/complex.h" ] || { echo "fuzz.sh: vcglib not found under $MESHLAB_SRC (run scripts/setup.sh)" >&2; exit 1; }
[ -x "$CONELOD" ] || { echo "fuzz.sh: $CONELOD not built (run scripts/setup.sh or set CONELOD)" >&2; exit 1; }
command -v "$CXX_FUZZ" >/dev/null || { echo "fuzz.sh: $CXX_FUZZ not found (Debian: clang, libclang-rt-14-dev)" >&2; exit 1; }
mkdir -p "$OUT/corpus" "$OUT/seeds" "$OUT/crashes" "$OUT/ply_corpus" "$OUT/ply_crashes"

# build_fuzzer NAME SOURCE... [-DFLAG...]: one libFuzzer binary under ASan + UBSan in $OUT/NAME.
build_fuzzer() {
  local name="$1"; shift
  "$CXX_FUZZ" -std=c++14 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -I"$ROOT/vcg_ext" -isystem "$MESHLAB_SRC/vcglib" -isystem /usr/include/eigen3 "$@" -lz -lmeshoptimizer \
    -o "$OUT/$name"
}

# run_fuzzer NAME CORPUS CRASHES WHAT: fuzzes for SECONDS_TO_RUN, fails on a crash, a leak or a
# file left in CRASHES.
run_fuzzer() {
  local name="$1" corpus="$2" crashes="$3" what="$4" status
  (cd "$OUT" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    "./$name" -max_total_time="$SECONDS_TO_RUN" -rss_limit_mb=1024 -malloc_limit_mb=256 -timeout=10 \
    -artifact_prefix="$crashes/" -print_final_stats=1 "$corpus" 2>&1 | tail -n 12) && status=0 || status=$?
  if [ "$status" -ne 0 ] || [ -n "$(ls -A "$crashes")" ]; then
    echo "fuzz.sh: FAILED: $what crashed or leaked; inputs in $crashes (keep them in vcg_ext/fuzz/regressions/)" >&2
    exit 1
  fi
  echo "fuzz.sh: $what: no crash in ${SECONDS_TO_RUN} s"
}

# The reader, the refiner and the cone tests they use: nothing else of the core is needed.
build_fuzzer lod_reader_fuzz -DFUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION \
  "$ROOT/vcg_ext/fuzz/lod_reader_fuzz.cpp" "$ROOT/vcg_ext/conelod/lod/lod_reader.cpp" \
  "$ROOT/vcg_ext/conelod/lod/lod_refine.cpp" "$ROOT/vcg_ext/conelod/grouping/normal_cone.cpp"
# The PLY input path: the checked reader (and its file checks), the input check and the grouping.
build_fuzzer ply_reader_fuzz \
  "$ROOT/vcg_ext/fuzz/ply_reader_fuzz.cpp" "$ROOT/vcg_ext/conelod/mesh/ply_format.cpp" \
  "$ROOT/vcg_ext/conelod/mesh/safe_file.cpp" \
  "$ROOT/vcg_ext/conelod/mesh/mesh_check.cpp" "$ROOT/vcg_ext/conelod/mesh/indexed_mesh.cpp" \
  "$ROOT/vcg_ext/conelod/grouping/cone_grouping.cpp" "$ROOT/vcg_ext/conelod/grouping/normal_cone.cpp"

# Seeds: an octahedron subdivided once and twice (32 and 128 faces, a sphere) and a bumpy variant,
# with default and two-level hierarchies; the bumpy one also with vertex colour and normals
# (attribute streams), and a sphere subdivided four times (2,048 faces), whose geometry streams
# are deflated; all version 9 (range-coded positions, a typical distance per record). The stored
# files of the tests (versions 3 to 8) join them.
python3 - "$OUT/seeds" <<'PY'
import math, sys
def sphere(levels, bump):
    p = [(1,0,0),(-1,0,0),(0,1,0),(0,-1,0),(0,0,1),(0,0,-1)]
    f = [(0,2,4),(2,1,4),(1,3,4),(3,0,4),(2,0,5),(1,2,5),(3,1,5),(0,3,5)]
    for _ in range(levels):
        mid, nf = {}, []
        def m(a, b):
            k = (min(a,b), max(a,b))
            if k not in mid:
                x = [(p[a][i]+p[b][i])/2 for i in range(3)]
                n = math.sqrt(sum(v*v for v in x)); p.append(tuple(v/n for v in x)); mid[k] = len(p)-1
            return mid[k]
        for a,b,c in f:
            ab, bc, ca = m(a,b), m(b,c), m(c,a)
            nf += [(a,ab,ca),(ab,b,bc),(ca,bc,c),(ab,bc,ca)]
        f = nf
    p = [tuple(v*(1+bump*math.sin(5*q[0])*math.cos(3*q[1])) for v in q) for q in p]
    return p, f
# The texture of the textured seed (bumpy2t: texture coordinates per face corner, two charts, and
# an image stored in the .clod's TEXR chunk): any bytes will do, the reader does not decode them.
with open(f"{sys.argv[1]}/tex.png", "wb") as o:
    o.write(b"\x89PNG\r\n\x1a\n" + bytes(range(64)))
for name, lv, bump, attr in (("oct1", 1, 0, 0), ("sphere2", 2, 0, 0), ("bumpy2", 2, 0.2, 0), ("bumpy2c", 2, 0.2, 1),
                             ("bumpy2t", 2, 0.2, 2), ("bumpy4", 4, 0.2, 0)):
    p, f = sphere(lv, bump)
    with open(f"{sys.argv[1]}/{name}.ply", "w") as o:
        o.write("ply\nformat ascii 1.0\n" + ("comment TextureFile tex.png\n" if attr == 2 else ""))
        o.write(f"element vertex {len(p)}\nproperty float x\nproperty float y\nproperty float z\n")
        if attr:
            o.write("property float nx\nproperty float ny\nproperty float nz\n"
                    "property uchar red\nproperty uchar green\nproperty uchar blue\n")
        o.write(f"element face {len(f)}\nproperty list uchar int vertex_indices\n")
        o.write("property list uchar float texcoord\nend_header\n" if attr == 2 else "end_header\n")
        for x, y, z in p:
            n = math.sqrt(x*x + y*y + z*z) or 1
            extra = (f" {x/n:.6f} {y/n:.6f} {z/n:.6f} {int(127.5*(x/n+1))} {int(127.5*(y/n+1))} {int(127.5*(z/n+1))}"
                     if attr else "")
            o.write(f"{x:.6f} {y:.6f} {z:.6f}{extra}\n")
        for a, b, c in f:
            uv = ""
            if attr == 2:  # u from the angle round z, a chart per hemisphere (a seam at the equator)
                chart = 0.5 if sum(p[v][2] for v in (a, b, c)) > 0 else 0.0
                uv = " 6" + "".join(f" {chart + 0.25 * (1 + math.atan2(p[v][1], p[v][0]) / math.pi):.6f}"
                                    f" {0.5 * (1 + p[v][2]):.6f}" for v in (a, b, c))
            o.write(f"3 {a} {b} {c}{uv}\n")
PY
for m in "$OUT"/seeds/*.ply; do
  b="$(basename "$m" .ply)"
  "$CONELOD" lod build "$m" -o "$OUT/corpus/$b.clod" >/dev/null
  "$CONELOD" lod build "$m" -o "$OUT/corpus/${b}_2levels.clod" --max-levels 2 >/dev/null
done
cp "$ROOT"/vcg_ext/tests/lod/data/*.clod "$OUT/corpus/"
echo "fuzz.sh: $(ls "$OUT/corpus" | wc -l) inputs in the corpus; fuzzing for ${SECONDS_TO_RUN} s"
run_fuzzer lod_reader_fuzz "$OUT/corpus" "$OUT/crashes" ".clod reader"

cp "$OUT"/seeds/*.ply "$OUT/ply_corpus/"
python3 - "$OUT/ply_corpus" "$ROOT/tests/integration" <<'PY'
import sys
sys.path.insert(0, sys.argv[2])
import bad_inputs
for name, data, _ in bad_inputs.corpus():
    if isinstance(data, bytes) and len(data) < 200000:  # not the FIFO; the 1 MiB header slows it
        open("%s/%s.ply" % (sys.argv[1], name), "wb").write(data)
PY
# Inputs that once crashed run first, each on its own.
for r in "$ROOT"/vcg_ext/fuzz/regressions/ply/*; do
  [ -f "$r" ] || continue
  ASAN_OPTIONS=detect_leaks=1 "$OUT/ply_reader_fuzz" "$r" >/dev/null 2>&1 ||
    { echo "fuzz.sh: FAILED: regression input $r crashes again" >&2; exit 1; }
done
run_fuzzer ply_reader_fuzz "$OUT/ply_corpus" "$OUT/ply_crashes" "PLY path"
