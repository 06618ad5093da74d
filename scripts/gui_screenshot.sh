#!/usr/bin/env bash
# Screenshot of the real MeshLab GUI (under Xvfb) applying "Cone LOD: Normal Cone Face Grouping"
# to the bunny through the menu: Filters > Color Creation and Processing > the filter, Display
# level 2, Apply, Close.
#   scripts/gui_screenshot.sh [OUT.png] [MESH]                    MeshLab 2020.09, the installed
#       plugin (scripts/setup.sh)
#   scripts/gui_screenshot.sh --meshlab 2025.07 [OUT.png] [MESH]  MeshLab 2025.07 in its root
#       (scripts/setup.sh --meshlab 2025.07), with the plugin built there put where MeshLab's
#       Help > Plugin Info > Load Plugins puts it (its extra-plugins folder)
# Needs Xvfb, xdotool and ImageMagick (the roots have them). The menu clicks are at fixed positions
# of each version's default layout on a 1400x1000 screen (the dialog's fields relative to the
# dialog); each step waits for the window it needs, and the script fails if the filter's dialog
# never appears or the mesh does not come out coloured.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# start_xvfb; inside a MeshLab root lib.sh lies beside this script
# shellcheck source=scripts/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"

# Inside the machine (or root) whose MeshLab is used: drive the GUI.
if [ "${1:-}" = --inside ]; then
  VERSION="$2" OUT="$3" MESH="$4"
  case "$VERSION" in
    # menu: Filters, Color Creation and Processing, the filter; dialog (relative): Display level,
    # Apply, Close; the window's crop
    2020.09) MENU=(121 10 223 211 632 262); FIELD=(300 470); APPLY=(310 570); CLOSE=(108 570); ABSOLUTE=1
             CROP=935x725+0+0 ;;
    2025.07) MENU=(116 9 212 194 589 264); FIELD=(272 455); APPLY=(280 666); CLOSE=(97 666); ABSOLUTE=0
             CROP=934x730+0+0 ;;
    *) echo "gui_screenshot.sh: no click positions for MeshLab $VERSION" >&2; exit 1 ;;
  esac
  XDG_RUNTIME_DIR="$(mktemp -d)"
  export XDG_RUNTIME_DIR
  start_xvfb
  MPID=
  trap 'kill $MPID $XPID 2>/dev/null || true' EXIT
  meshlab "$MESH" >/dev/null 2>&1 &
  MPID=$!
  wait_for() { for _ in $(seq 60); do xdotool search --name "$1" >/dev/null 2>&1 && return 0; sleep 0.5; done
               echo "gui_screenshot.sh: no window named '$1'" >&2; exit 1; }
  # click X Y [N]: N clicks at screen position X Y, or (2025.07) at X Y relative to the dialog.
  click() { if [ "$ABSOLUTE" = 1 ]; then xdotool mousemove "$1" "$2" click --repeat "${3:-1}" 1
            else xdotool mousemove --window "$DIALOG" "$1" "$2" click --repeat "${3:-1}" 1; fi; }
  wait_for "MeshLab"
  sleep 8                                                        # the mesh loads and renders
  xdotool mousemove "${MENU[0]}" "${MENU[1]}" click 1; sleep 1.5  # Filters
  xdotool mousemove "${MENU[2]}" "${MENU[3]}" click 1; sleep 1.5  # Color Creation and Processing
  xdotool mousemove "${MENU[4]}" "${MENU[5]}" click 1             # Cone LOD: Normal Cone Face Grouping
  wait_for "Cone LOD: Normal Cone Face Grouping"
  DIALOG="$(xdotool search --name "Cone LOD: Normal Cone Face Grouping" | head -1)"
  sleep 1
  click "${FIELD[0]}" "${FIELD[1]}" 3; xdotool type "2"            # Display level = 2
  click "${APPLY[0]}" "${APPLY[1]}"; sleep 6                         # Apply
  click "${CLOSE[0]}" "${CLOSE[1]}"; sleep 2                         # Close: the grouped mesh and the log show
  xdotool mousemove 700 900
  import -window root -crop "$CROP" "$OUT"
  # The groups' colours: the bunny's pixels in the middle of the view must be far from grey.
  colourful="$(convert "$OUT" -crop 160x120+170+320 -colorspace HSL -channel G -separate +channel \
               -format '%[fx:mean]' info:)"
  awk -v s="$colourful" 'BEGIN { exit !(s > 0.25) }' \
    || { echo "gui_screenshot.sh: the bunny is not coloured by groups (mean saturation $colourful)" >&2; exit 1; }
  echo "wrote $OUT (MeshLab $VERSION; mean saturation of the bunny $colourful)"
  exit 0
fi

MESHLAB=2020.09
if [ "${1:-}" = --meshlab ]; then MESHLAB="$2"; shift 2; fi
OUT="${1:-$ROOT/docs/img/meshlab_grouped_bunny.png}"
MESH="${2:-$ROOT/../shared/test_meshes/stanford_bunny_bun_zipper.ply}"
[ -f "$MESH" ] || { echo "gui_screenshot.sh: no mesh $MESH" >&2; exit 1; }
if [ "$MESHLAB" = 2020.09 ]; then
  exec bash "$0" --inside 2020.09 "$OUT" "$MESH"
fi

R="$CONELOD_ROOTS/$(meshlab_suite "$MESHLAB")"
plugin="$R/conelod/build/filter_conelod/libfilter_conelod.so"
[ -f "$plugin" ] || { echo "gui_screenshot.sh: no plugin in $R: run scripts/setup.sh --meshlab $MESHLAB" >&2; exit 1; }
# Where Help > Plugin Info > Load Plugins copies a plugin: MeshLabApplication::extraPluginsLocation()
# (the AppDataLocation of organisation VCG, application MeshLab_64bit_fp, then the version).
extra="$R/root/.local/share/VCG/MeshLab_64bit_fp/MeshLabExtraPlugins/$MESHLAB"
mkdir -p "$extra" "$R/conelod/shots"
cp -f "$plugin" "$extra/libfilter_conelod.so"
cp -f "$ROOT/scripts/gui_screenshot.sh" "$ROOT/scripts/lib.sh" "$R/conelod/"
cp -f "$MESH" "$R/conelod/shots/$(basename "$MESH")"
rm -f "$R/conelod/shots/shot.png"
root_run "$R" bash /conelod/gui_screenshot.sh --inside "$MESHLAB" /conelod/shots/shot.png "/conelod/shots/$(basename "$MESH")"
cp -f "$R/conelod/shots/shot.png" "$OUT"
echo "copied to $OUT"
