#!/usr/bin/env bash
# ConeLOD set-up for a fresh Debian bookworm machine (run as root; idempotent).
#   scripts/setup.sh                      MeshLab 2020.09 (Debian 12's), the CLI and the viewer:
#  1. installs the Debian packages the build, the tests and the screenshots need;
#  2. fetches MeshLab 2020.09's plugin headers and vcglib from Debian's own `meshlab`
#     source package (the ABI of the installed /usr/bin/meshlab) into deps/meshlab-src;
#  3. installs the web viewer's npm packages (web/, `npm ci`: three.js, meshoptimizer's decoder,
#     playwright-core for the headless-Chromium tests);
#  4. builds ConeLOD in Release (build/), installs the plugin into MeshLab's plugin folder,
#     `conelod` and `conelod-viewer` into /usr/local/bin, the web viewer into /usr/local/share/conelod/web.
#   scripts/setup.sh --meshlab 2022.02    the plugin for MeshLab 2022.02 (Debian 13) or 2025.07
#   scripts/setup.sh --meshlab 2025.07    (Debian unstable), which do not install on Debian 12:
#  1. makes (once; cached under /var/cache/conelod/roots, CONELOD_ROOTS) a debootstrap root of the
#     Debian suite that ships that MeshLab, with its sources (apt-get source) in /src/meshlab-src;
#  2. builds the plugin and its test harness there against that MeshLab's libmeshlab-common;
#  3. copies the plugin to build-meshlab-VERSION/ and says how to install it. Nothing on this
#     machine's own MeshLab changes. scripts/test.sh --meshlab VERSION then tests it.
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

MESHLAB=2020.09
while [ $# -gt 0 ]; do
  case "$1" in
    --meshlab) [ $# -ge 2 ] || fail "--meshlab needs a version (2022.02 or 2025.07)"; MESHLAB="$2"; shift 2 ;;
    --meshlab=*) MESHLAB="${1#--meshlab=}"; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    *) fail "unknown option '$1' (scripts/setup.sh [--meshlab 2022.02|2025.07])" ;;
  esac
done

[ "$(id -u)" = 0 ] || fail "run as root (it installs Debian packages and the MeshLab plugin)"

if [ "$MESHLAB" != 2020.09 ]; then
  suite="$(meshlab_suite "$MESHLAB")" || fail "--meshlab $MESHLAB"
  step "MeshLab $MESHLAB: a Debian $suite root with it, the build tools and its sources"
  start=$SECONDS
  R="$(make_meshlab_root "$MESHLAB")" || fail "making the $suite root"
  echo "root: $R ($((SECONDS - start)) s)"
  step "Build the plugin for MeshLab $MESHLAB in the root"
  start=$SECONDS
  so="$(build_in_root "$R" "$ROOT" "")" || fail "building the plugin in $R"
  OUTDIR="$ROOT/build-meshlab-$MESHLAB"
  mkdir -p "$OUTDIR"
  cp -f "$so" "$OUTDIR/libfilter_conelod.so"
  echo "built in $((SECONDS - start)) s"
  # The newest C and C++ library symbols it needs (from the suite it was built in).
  needs="$(root_run "$R" objdump -T "${so#"$R"}" | grep -o 'GLIBC_[0-9.]*\|GLIBCXX_[0-9.]*' | sort -u)"
  glibc="$(grep '^GLIBC_' <<<"$needs" | sed 's/GLIBC_//' | sort -V | tail -n 1)"
  glibcxx="$(grep '^GLIBCXX_' <<<"$needs" | sort -V | tail -n 1)"
  cat <<INSTALL

plugin for MeshLab $MESHLAB: $OUTDIR/libfilter_conelod.so
MeshLab loads it only if it is MeshLab $MESHLAB (its version series and float scalars), on x86-64
Linux with glibc $glibc or newer and a libstdc++ with $glibcxx (it was built in Debian $suite).
Install it:
  - any MeshLab $MESHLAB on such a system, no root needed (the AppImage too): Help > Plugin Info > Load Plugins,
    pick the file; MeshLab copies it into its extra-plugins folder and loads it at every start;
  - Debian's package (or any with the same layout), for every user:
      sudo cp $OUTDIR/libfilter_conelod.so /usr/lib/x86_64-linux-gnu/meshlab/plugins/
  - an extracted AppImage: ./MeshLab$MESHLAB-linux.AppImage --appimage-extract, then copy it into
    squashfs-root/usr/lib/meshlab/plugins/ and run squashfs-root/AppRun.
Test it: scripts/test.sh --meshlab $MESHLAB
INSTALL
  echo "setup.sh: done"
  exit 0
fi
grep -q bookworm /etc/os-release || echo "setup.sh: warning: written for Debian bookworm; continuing" >&2

PKGS=(meshlab qtbase5-dev libqt5opengl5-dev libeigen3-dev libglew-dev xvfb xauth dpkg-dev
      xz-utils cmake g++ make libgtest-dev libgmock-dev libbenchmark-dev imagemagick xdotool
      python3 gnuplot-nox clang libclang-rt-14-dev clang-format fonts-dejavu-core libmeshoptimizer-dev
      chromium nodejs time)

step "Debian packages"
apt_install_missing "${PKGS[@]}" || fail "Debian packages"
echo "all ${#PKGS[@]} packages present"

step "The web viewer's npm packages (web/package-lock.json: three, meshoptimizer, playwright-core)"
# Debian's nodejs comes without npm (a separate package); other builds of nodejs bring their own.
command -v npm >/dev/null || apt_install_missing npm || fail "Debian package npm"
(cd "$ROOT/web" && npm ci --no-audit --no-fund >/dev/null) || fail "npm ci in web/"
echo "web/node_modules: $(ls "$ROOT/web/node_modules" | tr '\n' ' ')"

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
[ -f /usr/local/share/conelod/web/node_modules/three/build/three.module.js ] || fail "web viewer not installed"
echo "web:    /usr/local/share/conelod/web (conelod serve FILE.clod)"
echo "setup.sh: done"
