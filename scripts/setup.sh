#!/usr/bin/env bash
# ConeLOD set-up for a fresh Debian bookworm machine (run as root; idempotent).
#  1. installs the Debian packages the build, the tests and the screenshots need;
#  2. fetches MeshLab 2020.09's plugin headers and vcglib from Debian's own `meshlab`
#     source package (the ABI of the installed /usr/bin/meshlab) into deps/meshlab-src;
#  3. builds ConeLOD in Release (build/), installs the plugin into MeshLab's plugin folder
#     and `conelod` and `conelod-viewer` into /usr/local/bin.
# Every step fails loudly: the script stops at the first error and says which step failed.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
DEPS="$ROOT/deps"
SRC="$DEPS/meshlab-src"
BUILD="${CONELOD_BUILD_DIR:-$ROOT/build}"
JOBS="$(nproc)"
# shellcheck source=scripts/lib.sh
. "$ROOT/scripts/lib.sh"

step() { printf '\n==> %s\n' "$*"; }
fail() { printf '\nsetup.sh: FAILED: %s\n' "$*" >&2; exit 1; }
trap 'fail "command \"$BASH_COMMAND\" exited with status $? (line $LINENO)"' ERR

[ "$(id -u)" = 0 ] || fail "run as root (it installs Debian packages and the MeshLab plugin)"
grep -q bookworm /etc/os-release || echo "setup.sh: warning: written for Debian bookworm; continuing" >&2

PKGS=(meshlab qtbase5-dev libqt5opengl5-dev libeigen3-dev libglew-dev xvfb xauth dpkg-dev
      xz-utils cmake g++ make libgtest-dev libgmock-dev libbenchmark-dev imagemagick xdotool
      python3 gnuplot-nox clang libclang-rt-14-dev fonts-dejavu-core)

step "Debian packages"
apt_install_missing "${PKGS[@]}" || fail "Debian packages"
echo "all ${#PKGS[@]} packages present"

step "MeshLab 2020.09 source (headers + vcglib) from Debian's source package"
if [ ! -f "$SRC/src/common/interfaces.h" ] || [ ! -f "$SRC/vcglib/vcg/complex/complex.h" ]; then
  ensure_deb_src || fail "deb-src entry for apt-get source"
  apt_get_in "$DEPS/download" source --download-only meshlab || fail "apt-get source --download-only meshlab"
  tarball="$(ls "$DEPS"/download/meshlab_2020.09*.orig.tar.xz 2>/dev/null | head -1)"
  [ -n "$tarball" ] || fail "meshlab 2020.09 orig tarball not found in $DEPS/download"
  rm -rf "$SRC"; mkdir -p "$SRC"
  tar xJf "$tarball" -C "$SRC" --strip-components=1 --wildcards 'meshlab-*/vcglib' 'meshlab-*/src/common' \
    || fail "unpacking $tarball"
fi
echo "headers in $SRC"

step "Build (Release) in $BUILD"
cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DMESHLAB_SRC="$SRC" >/dev/null \
  || fail "cmake configure"
cmake --build "$BUILD" -j "$JOBS" || fail "build"

step "Install the plugin, the conelod CLI and conelod-viewer"
cmake --install "$BUILD" >/dev/null || fail "install"
PLUGDIR=/usr/lib/x86_64-linux-gnu/meshlab/plugins
[ -f "$PLUGDIR/libfilter_conelod.so" ] || fail "plugin not installed in $PLUGDIR"
command -v conelod >/dev/null || fail "conelod not on PATH"
command -v conelod-viewer >/dev/null || fail "conelod-viewer not on PATH (Qt5 Widgets missing at configure time?)"
echo "plugin: $PLUGDIR/libfilter_conelod.so"
echo "cli:    $(command -v conelod)"
echo "viewer: $(command -v conelod-viewer)"
echo "setup.sh: done"
