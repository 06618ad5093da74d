#!/usr/bin/env bash
# What MeshLab's dialog does with a path TYPED into a file box (issue 18): in the real GUI under
# Xvfb, Filters > Remeshing, Simplification and Reconstruction > Cone LOD: Export LOD File, type
# a path into "LOD file", Apply.
#   MeshLab 2020.09 passes on only a file chosen with "...": the filter must refuse (MeshLab shows
#   its "Filter Failure" message, which says to use "..."), and no file may appear, neither at the
#   typed path nor a default one in MeshLab's working folder; then a file chosen with "..." (its
#   file dialog takes the typed name) must be written, as the filter's help says;
#   MeshLab 2022.02 and later pass the typed path on: the file must be written there.
# Usage:
#   scripts/gui_file_box.sh MESHLAB_BIN OUT.png [MESH]      2020.09: this machine's MeshLab binary
#       (tests: the private copy that loads the build tree's plugin, tests/integration/make_private_meshlab.sh)
#   scripts/gui_file_box.sh --meshlab 2022.02|2025.07 OUT.png [MESH]   in that version's root
#       (scripts/setup.sh --meshlab VERSION), the plugin in MeshLab's extra-plugins folder
# The menu clicks are at fixed positions of each version's default layout on a 1400x1000 screen;
# the dialog's box and buttons are found from its size and picture (its height follows the help and
# the parameters). Exit 0 when MeshLab did what is expected above.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# start_xvfb; inside a MeshLab root lib.sh lies beside this script
# shellcheck source=scripts/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

if [ "${1:-}" = --inside ]; then
  VERSION="$2" MESHLAB="$3" OUT="$4" MESH="$5"
  case "$VERSION" in
    # menu: Filters, Remeshing..., Export LOD File; dialog (relative): LOD file box, Apply
    2020.09) MENU=(121 10 275 160 559 111); BOX=(300 298); APPLY=(339 774) ;;
    2022.02) MENU=(116 9 260 148 589 80); BOX=(317 238); APPLY=(360 749) ;;
    2025.07) MENU=(116 9 260 148 589 91); BOX=(317 238); APPLY=(360 838) ;;
    *) echo "gui_file_box.sh: no click positions for MeshLab $VERSION" >&2; exit 1 ;;
  esac
  work="$(mktemp -d)"
  typed="$work/typed/bunny.clod"
  mkdir -p "$work/typed" "$work/cwd"
  XDG_RUNTIME_DIR="$(mktemp -d)"
  export XDG_RUNTIME_DIR
  start_xvfb
  MPID=
  trap 'kill $MPID $XPID 2>/dev/null || true' EXIT
  (cd "$work/cwd" && exec "$MESHLAB" "$MESH" >/dev/null 2>&1) &
  MPID=$!
  wait_for() { for _ in $(seq 60); do xdotool search --name "$1" >/dev/null 2>&1 && return 0; sleep 0.5; done
               echo "gui_file_box.sh: no window named '$1'" >&2; exit 1; }
  wait_for "MeshLab"
  sleep 8
  xdotool mousemove "${MENU[0]}" "${MENU[1]}" click 1; sleep 1.5   # Filters
  xdotool mousemove "${MENU[2]}" "${MENU[3]}" click 1; sleep 1.5   # Remeshing, Simplification and Reconstruction
  xdotool mousemove "${MENU[4]}" "${MENU[5]}" click 1              # Cone LOD: Export LOD File
  wait_for "Cone LOD: Export LOD File"
  dialog="$(xdotool search --name "Cone LOD: Export LOD File" | head -1)"
  sleep 1
  # The dialog is as tall as the filter's help and parameters need: the box is the first white
  # field of the dialog at the box's x, Apply is 23 pixels above the bottom edge and 127 left of the
  # right edge, "..." 60 pixels left of the right edge (measured in 2020.09; the fixed positions
  # above are where 2022.02 and 2025.07 had them before the dialog changed, and give the column).
  eval "$(xdotool getwindowgeometry --shell "$dialog")"
  import -window "$dialog" "$work/dialog.png"
  box_y="$(convert "$work/dialog.png" -crop "1x${HEIGHT}+${BOX[0]}+0" txt:- |
           awk -F'[,:]' '!found && /#FFFFFF/ { y = $2 + 0; if (y == last + 1) run++; else { run = 1; start = y }
                                               last = y; if (run == 10) { print start + 8; found = 1 } }')"
  [ -n "$box_y" ] || { echo "gui_file_box.sh: no file box in the dialog" >&2; exit 1; }
  # A dialog taller than the room below the menu starts above the screen (2025.07: y = -32); the
  # picture has only its visible part, the clicks are in the window's own coordinates.
  [ "$Y" -ge 0 ] || box_y=$((box_y - Y))
  BOX=("${BOX[0]}" "$box_y") APPLY=($((WIDTH - 127)) $((HEIGHT - 23))) BROWSE=($((WIDTH - 60)) "$box_y")
  xdotool mousemove --window "$dialog" "${BOX[0]}" "${BOX[1]}" click 1; xdotool type "$typed"; sleep 0.5
  xdotool mousemove --window "$dialog" "${APPLY[0]}" "${APPLY[1]}" click 1
  for _ in $(seq 40); do [ -s "$typed" ] && break; sleep 0.5; done   # the export takes a few seconds
  sleep 2
  import -window root -crop 934x800+0+0 "$OUT"
  others="$(find "$work/cwd" -type f | head -5)"
  if [ "$VERSION" = 2020.09 ]; then
    [ ! -e "$typed" ] && [ -z "$others" ] \
      || { echo "gui_file_box.sh: MeshLab 2020.09 wrote a file ($typed / $others) for a typed path" >&2; exit 1; }
    failure="$(xdotool search --name "Filter Failure" | head -1)"
    [ -n "$failure" ] || { echo "gui_file_box.sh: MeshLab 2020.09 showed no message for the typed path" >&2; exit 1; }
    xdotool mousemove --window "$failure" 20 20 click 1 key Return; sleep 1   # OK (no window manager: click, then Return)
    # What the help says 2020.09 takes: a file chosen with "...", here typed into its file dialog.
    chosen="$work/chosen/bunny.clod"
    mkdir -p "$work/chosen"
    xdotool mousemove --window "$dialog" "${BROWSE[0]}" "${BROWSE[1]}" click 1
    wait_for "^Save$"
    sleep 1
    xdotool type "$chosen"; xdotool key Return; sleep 1
    xdotool mousemove --window "$dialog" "${APPLY[0]}" "${APPLY[1]}" click 1
    for _ in $(seq 40); do [ -s "$chosen" ] && break; sleep 0.5; done
    sleep 1
    [ -s "$chosen" ] && [ ! -e "$typed" ] \
      || { echo "gui_file_box.sh: MeshLab 2020.09 did not write the file chosen with '...' ($chosen)" >&2; exit 1; }
    echo "MeshLab 2020.09: the typed path was refused, no file written; the file chosen with '...' was written" \
         "($(stat -c %s "$chosen") bytes; screenshot $OUT)"
  else
    [ -s "$typed" ] && [ -z "$others" ] \
      || { echo "gui_file_box.sh: MeshLab $VERSION did not write the typed path $typed" >&2; exit 1; }
    echo "MeshLab $VERSION: the typed path was written ($(stat -c %s "$typed") bytes; screenshot $OUT)"
  fi
  rm -rf "$work"
  exit 0
fi

if [ "${1:-}" = --meshlab ]; then
  MESHLAB_VERSION="$2" OUT="$3" MESH="${4:-$ROOT/../shared/test_meshes/stanford_bunny_bun_zipper.ply}"
  R="$CONELOD_ROOTS/$(meshlab_suite "$MESHLAB_VERSION")"
  plugin="$R/conelod/build/filter_conelod/libfilter_conelod.so"
  [ -f "$plugin" ] || { echo "gui_file_box.sh: no plugin in $R: run scripts/setup.sh --meshlab $MESHLAB_VERSION" >&2; exit 1; }
  extra="$R/root/.local/share/VCG/MeshLab_64bit_fp/MeshLabExtraPlugins/$MESHLAB_VERSION"  # as in gui_screenshot.sh
  mkdir -p "$extra" "$R/conelod/shots"
  cp -f "$plugin" "$extra/libfilter_conelod.so"
  cp -f "$ROOT/scripts/gui_file_box.sh" "$ROOT/scripts/lib.sh" "$R/conelod/"
  cp -f "$MESH" "$R/conelod/shots/$(basename "$MESH")"
  root_run "$R" bash /conelod/gui_file_box.sh --inside "$MESHLAB_VERSION" meshlab /conelod/shots/file_box.png \
    "/conelod/shots/$(basename "$MESH")"
  cp -f "$R/conelod/shots/file_box.png" "$OUT"
  exit 0
fi

MESHLAB_BIN="$1" OUT="$2" MESH="${3:-$ROOT/../shared/test_meshes/stanford_bunny_bun_zipper.ply}"
exec bash "$0" --inside 2020.09 "$(readlink -f "$MESHLAB_BIN")" "$OUT" "$MESH"
