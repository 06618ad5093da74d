# shellcheck shell=bash
# Helpers shared by ConeLOD's scripts (setup.sh, get_test_meshes.sh). Source it; it only defines
# functions. Each returns non-zero after printing why, so callers write `helper ... || fail "..."`.
# apt-get update / install and the deb-src entry need root; downloads do not.

# need_root WHAT: fails unless running as root.
need_root() {
  [ "$(id -u)" = 0 ] && return 0
  echo "need root to $1 (run the script as root)" >&2
  return 1
}

# apt_update: `apt-get update` (quiet; its output is shown only when it fails).
apt_update() {
  need_root "run apt-get update" || return 1
  local log; log="$(mktemp)"
  if ! apt-get update -qq >"$log" 2>&1; then
    cat "$log" >&2; rm -f "$log"
    echo "apt-get update failed" >&2
    return 1
  fi
  rm -f "$log"
}

# apt_install_missing PKG...: installs those of the Debian packages that are not installed yet;
# runs apt-get update only when some are missing. Prints what it installs.
apt_install_missing() {
  local p missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  need_root "install ${missing[*]}" || return 1
  echo "installing Debian packages: ${missing[*]}"
  apt_update || return 1
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null \
    || { echo "apt-get install ${missing[*]} failed" >&2; return 1; }
}

# ensure_deb_src: when apt knows no deb-src entry, adds one (a copy of the first stanza of
# /etc/apt/sources.list.d/debian.sources with `Types: deb-src`, or else deb-src twins of the
# `deb` lines of /etc/apt/sources.list) and runs apt-get update.
ensure_deb_src() {
  if grep -rqsE '^Types:.*deb-src|^deb-src ' /etc/apt/sources.list.d/ || grep -qs '^deb-src ' /etc/apt/sources.list; then
    return 0
  fi
  need_root "add a deb-src entry to apt's sources" || return 1
  if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    awk 'BEGIN{RS="";ORS="\n\n"} NR==1{sub(/Types: deb/,"Types: deb-src"); print}' \
      /etc/apt/sources.list.d/debian.sources > /etc/apt/sources.list.d/conelod-deb-src.sources
  elif grep -qs '^deb ' /etc/apt/sources.list; then
    sed -n 's/^deb /deb-src /p' /etc/apt/sources.list > /etc/apt/sources.list.d/conelod-deb-src.list
  else
    false
  fi || { echo "could not write a deb-src entry (no debian.sources and no deb line in sources.list)" >&2; return 1; }
  echo "added a deb-src entry to apt's sources"
  apt_update
}

# apt_get_in DIR ARG...: runs `apt-get ARG...` in DIR (e.g. `download PKG`,
# `source --download-only PKG`); when that fails (package lists missing or stale), runs
# apt-get update and tries once more, showing apt's output.
apt_get_in() {
  local dir="$1"; shift
  mkdir -p "$dir" || return 1
  ( cd "$dir" && apt-get "$@" >/dev/null 2>&1 ) && return 0
  echo "apt-get $* failed; updating the package lists and trying again"
  apt_update || return 1
  ( cd "$dir" && apt-get "$@" ) || { echo "apt-get $* failed" >&2; return 1; }
}

# --- Newer MeshLab versions in Debian roots (scripts/setup.sh --meshlab, scripts/test.sh --meshlab) ---
# MeshLab 2022.02 ships in Debian 13 (trixie), 2025.07 in unstable (sid); neither installs on
# Debian 12. Each is used from a root made by debootstrap under $CONELOD_ROOTS (default
# /var/cache/conelod/roots/<suite>), with the build tools and MeshLab's own sources (the headers
# and vcglib its plugins build against) in /src/meshlab-src.

CONELOD_ROOTS="${CONELOD_ROOTS:-/var/cache/conelod/roots}"
CONELOD_MIRROR="${CONELOD_MIRROR:-http://deb.debian.org/debian}"
# What every root holds besides MeshLab: the plugin's build (the core needs zlib and meshoptimizer:
# libmeshoptimizer-dev is 0.22 in trixie and sid; the .clod writer asks for codec versions 0.18
# decodes), and Xvfb + xdotool + ImageMagick for the GUI screenshot.
ROOT_PKGS=(meshlab cmake g++ make qtbase5-dev libqt5opengl5-dev libeigen3-dev libglew-dev zlib1g-dev
           libmeshoptimizer-dev xz-utils ca-certificates xvfb xauth xdotool imagemagick fonts-dejavu-core)

# meshlab_suite VERSION: the Debian suite that ships MeshLab VERSION.
meshlab_suite() {
  case "$1" in
    2022.02) echo trixie ;;
    2025.07) echo sid ;;
    *) echo "unsupported MeshLab version '$1' (supported: 2020.09, the default; 2022.02; 2025.07)" >&2; return 1 ;;
  esac
}

# root_run ROOT CMD...: runs CMD as root inside ROOT with /proc, /dev/pts and /dev/shm mounted
# for the command's duration (MeshLab and Xvfb need them) and unmounted afterwards.
root_run() {
  local r="$1"; shift
  local m mounted=()
  for m in proc dev/pts dev/shm; do
    mkdir -p "$r/$m"
    if ! mountpoint -q "$r/$m"; then
      case "$m" in
        proc) mount -t proc proc "$r/proc" ;;
        dev/pts) mount -t devpts devpts "$r/dev/pts" ;;
        dev/shm) mount -t tmpfs shm "$r/dev/shm" ;;
      esac || { echo "cannot mount $m in $r" >&2; return 1; }
      mounted=("$r/$m" "${mounted[@]}")
    fi
  done
  local rc=0
  chroot "$r" /usr/bin/env -i HOME=/root LANG=C.UTF-8 PATH=/usr/sbin:/usr/bin:/sbin:/bin "$@" || rc=$?
  for m in "${mounted[@]}"; do umount "$m" || umount -l "$m" || true; done
  return $rc
}

# make_meshlab_root VERSION: prints the root of MeshLab VERSION, making it when it is missing or
# was left unfinished (about a minute on a fast mirror): debootstrap of the suite with ROOT_PKGS,
# a deb-src entry, and MeshLab's sources unpacked into /src/meshlab-src. Cached: a finished root
# (marker .conelod-root) is reused, with whatever ROOT_PKGS it lacks (added since it was made) installed.
make_meshlab_root() {
  local version="$1" suite r tmp tarball
  suite="$(meshlab_suite "$version")" || return 1
  r="$CONELOD_ROOTS/$suite"
  if [ -f "$r/.conelod-root" ] && [ -f "$r/src/meshlab-src/ML_VERSION" ]; then
    local p missing=()
    for p in "${ROOT_PKGS[@]}"; do
      chroot "$r" dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'ok installed' || missing+=("$p")
    done
    if [ ${#missing[@]} -gt 0 ]; then
      echo "adding ${missing[*]} to the $suite root" >&2
      cp -L /etc/resolv.conf "$r/etc/resolv.conf" 2>/dev/null || true
      { root_run "$r" apt-get update -qq && root_run "$r" env DEBIAN_FRONTEND=noninteractive \
          apt-get install -y -qq --no-install-recommends "${missing[@]}" && root_run "$r" apt-get clean; } >&2 \
        || { echo "installing ${missing[*]} in the $suite root failed" >&2; return 1; }
    fi
    echo "$r"
    return 0
  fi
  need_root "make a Debian $suite root (debootstrap, chroot)" || return 1
  command -v debootstrap >/dev/null || apt_install_missing debootstrap >&2 || return 1
  tmp="$r.partial"
  local d m
  for d in "$tmp" "$r"; do  # an interrupted root_run may have left its mounts: never delete through them
    for m in dev/shm dev/pts proc; do mountpoint -q "$d/$m" 2>/dev/null && umount -l "$d/$m"; done
    rm -rf --one-file-system "$d"
  done
  mkdir -p "$CONELOD_ROOTS"
  echo "debootstrap $suite (MeshLab $version) into $r ..." >&2
  local pkgs; pkgs="$(IFS=,; echo "${ROOT_PKGS[*]}")"
  debootstrap --variant=minbase --include="$pkgs" "$suite" "$tmp" "$CONELOD_MIRROR" >"$CONELOD_ROOTS/$suite.log" 2>&1 \
    || { tail -20 "$CONELOD_ROOTS/$suite.log" >&2; echo "debootstrap $suite failed (log: $CONELOD_ROOTS/$suite.log)" >&2; return 1; }
  # A mirror that serves a snapshot has an expired Release file: apt must not refuse it.
  echo 'Acquire::Check-Valid-Until "false";' > "$tmp/etc/apt/apt.conf.d/99conelod"
  echo "deb-src $CONELOD_MIRROR $suite main" >> "$tmp/etc/apt/sources.list"
  cp -L /etc/resolv.conf "$tmp/etc/resolv.conf" 2>/dev/null || true
  root_run "$tmp" apt-get update -qq >&2 || { echo "apt-get update in the $suite root failed" >&2; return 1; }
  # MeshLab's Recommends are the libraries of its own plugins (debootstrap installs only Depends):
  # without them MeshLab opens with an error dialog about the plugins it cannot load.
  local recommends
  # (an alternative group, "|Recommends: a" then "Recommends: b", is already met by Depends: skipped)
  recommends="$(root_run "$tmp" apt-cache depends meshlab | awk '
    alt { alt = ($1 ~ /^[|]/); next }
    $1 ~ /^[|]/ { alt = 1; next }
    $1 == "Recommends:" && $2 !~ /^</ { print $2 }')"
  # shellcheck disable=SC2086
  root_run "$tmp" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $recommends >/dev/null \
    || { echo "installing MeshLab's recommended libraries in the $suite root failed" >&2; return 1; }
  mkdir -p "$tmp/src"
  # Only the .orig tarball is served (the .dsc and .debian.tar.xz are not): apt-get fails, the tarball is there.
  root_run "$tmp" sh -c 'cd /src && apt-get source --download-only meshlab' >/dev/null 2>&1 || true
  tarball="$(ls "$tmp"/src/meshlab_*.orig.tar.xz 2>/dev/null | head -1)"
  [ -n "$tarball" ] || { echo "apt-get source meshlab fetched no .orig.tar.xz in the $suite root" >&2; return 1; }
  mkdir -p "$tmp/src/meshlab-src"
  tar xJf "$tarball" -C "$tmp/src/meshlab-src" --strip-components=1 --wildcards \
    'meshlab-*/ML_VERSION' 'meshlab-*/src/common' 'meshlab-*/src/vcglib' \
    || { echo "unpacking $tarball failed" >&2; return 1; }
  [ "$(cat "$tmp/src/meshlab-src/ML_VERSION")" = "$version" ] \
    || { echo "the $suite root has MeshLab $(cat "$tmp/src/meshlab-src/ML_VERSION"), not $version" >&2; return 1; }
  root_run "$tmp" apt-get clean  # the downloaded packages (about 250 MB)
  date -u +%FT%TZ > "$tmp/.conelod-root"
  mv "$tmp" "$r"
  echo "$r"
}

# build_in_root ROOT SOURCE MESHES: copies the source tree SOURCE (without build outputs) into
# ROOT/conelod/src, the meshes the harness reads from MESHES into ROOT/conelod/meshes, and builds
# the plugin and its harness in ROOT/conelod/build (incremental). Prints the plugin's path in ROOT.
build_in_root() {
  local r="$1" src="$2" meshes="$3"
  rm -rf "$r/conelod/src"; mkdir -p "$r/conelod/src" "$r/conelod/meshes"
  tar -C "$src" --exclude='./build*' --exclude=./deps --exclude=./.git --exclude=./out --exclude='__pycache__' -cf - . \
    | tar -C "$r/conelod/src" -xf - || return 1
  if [ -n "$meshes" ] && [ -f "$meshes/stanford_bunny_bun_zipper.ply" ]; then
    cp -f "$meshes/stanford_bunny_bun_zipper.ply" "$r/conelod/meshes/"
  fi
  root_run "$r" cmake -S /conelod/src -B /conelod/build -DCMAKE_BUILD_TYPE=Release -DMESHLAB_SRC=/src/meshlab-src \
    -DCONELOD_PLUGIN_ONLY=ON -DCONELOD_TEST_MESHES=/conelod/meshes >/dev/null || return 1
  root_run "$r" cmake --build /conelod/build -j "$(nproc)" --target filter_conelod plugin_harness >&2 || return 1
  echo "$r/conelod/build/filter_conelod/libfilter_conelod.so"
}

# start_xvfb: starts Xvfb (1400x1000x24) on a display it finds free itself (-displayfd), exports
# DISPLAY and sets XPID; returns once the server accepts clients. Tests run side by side, so a
# display number picked by the caller could be taken by another test's server.
start_xvfb() {
  local f n=; f="$(mktemp)"
  Xvfb -displayfd 3 -screen 0 1400x1000x24 3>"$f" >/dev/null 2>&1 &
  XPID=$!
  for _ in $(seq 100); do
    n="$(tr -dc 0-9 <"$f")"
    [ -n "$n" ] && break
    kill -0 "$XPID" 2>/dev/null || break
    sleep 0.1
  done
  rm -f "$f"
  [ -n "$n" ] || { echo "Xvfb did not start" >&2; return 1; }
  export DISPLAY=":$n"
}
