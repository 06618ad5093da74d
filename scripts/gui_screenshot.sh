#!/usr/bin/env bash
# Screenshot of the real MeshLab GUI (under Xvfb) applying "Cone LOD: Normal Cone Face Grouping"
# to the bunny through the menu: Filters > Color Creation and Processing > the filter > Apply.
#   scripts/gui_screenshot.sh [OUT.png] [MESH]
# Needs the installed plugin (scripts/setup.sh), Xvfb, xdotool and ImageMagick. The clicks are at
# fixed positions of MeshLab 2020.09's default layout on a 1400x1000 screen; each step waits for
# the window it needs, and the script fails if the filter's dialog never appears.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
OUT="${1:-$ROOT/docs/img/meshlab_grouped_bunny.png}"
MESH="${2:-$ROOT/../shared/test_meshes/stanford_bunny_bun_zipper.ply}"
DISP=":$((90 + RANDOM % 9))"
export DISPLAY="$DISP" XDG_RUNTIME_DIR="$(mktemp -d)"
Xvfb "$DISP" -screen 0 1400x1000x24 >/dev/null 2>&1 &
XPID=$!
trap 'kill $MPID $XPID 2>/dev/null || true' EXIT
sleep 2
meshlab "$MESH" >/dev/null 2>&1 &
MPID=$!
wait_for() { for _ in $(seq 60); do xdotool search --name "$1" >/dev/null 2>&1 && return 0; sleep 0.5; done
             echo "gui_screenshot.sh: no window named '$1'" >&2; exit 1; }
wait_for "MeshLab"
sleep 6                                           # the mesh loads and renders
xdotool mousemove 121 10 click 1; sleep 1.5        # Filters
xdotool mousemove 223 211 click 1; sleep 1.5       # Color Creation and Processing
xdotool mousemove 632 262 click 1                  # Cone LOD: Normal Cone Face Grouping
wait_for "Cone LOD: Normal Cone Face Grouping"
sleep 1
xdotool mousemove 300 470 click --repeat 3 1; xdotool type "2"   # DisplayLevel = 2
xdotool mousemove 310 570 click 1; sleep 5         # Apply
xdotool mousemove 108 570 click 1; sleep 2         # Close the dialog: the grouped mesh and the log show
xdotool mousemove 700 900
import -window root -crop 935x725+0+0 "$OUT"
echo "wrote $OUT"
