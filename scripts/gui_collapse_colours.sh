#!/usr/bin/env bash
# Cone LOD: Group-Preserving Quadric Edge Collapse applied as a user does in MeshLab 2020.09's
# real GUI under Xvfb (issue 24, items 13 and 14): open the bunny (a scan: it loads with vertex
# colour shown), Filters > Remeshing, Simplification and Reconstruction > the filter, Apply at its
# defaults, Close. The filter must succeed at its defaults on the freshly loaded mesh (automatic
# normal cone groups), and the display must switch to the groups' face colours, as it does after
# Normal Cone Face Grouping: the bunny's pixels must be coloured, not grey.
# Usage:
#   scripts/gui_collapse_colours.sh MESHLAB_BIN OUT.png [MESH]    MeshLab 2020.09's binary (tests:
#       the private copy that loads the build tree's plugin, tests/integration/make_private_meshlab.sh)
# The clicks are at fixed positions of 2020.09's default layout on a 1400x1000 screen (the dialog's
# buttons relative to its bottom edge). Exit 0 when the filter succeeded and the bunny shows colours.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# start_xvfb; inside a MeshLab root lib.sh lies beside this script
# shellcheck source=scripts/lib.sh
. "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
MESHLAB="$(readlink -f "$1")" OUT="$2" MESH="${3:-${CONELOD_TEST_MESHES:-$ROOT/../shared/test_meshes}/stanford_bunny_bun_zipper.ply}"
FILTER="Cone LOD: Group-Preserving Quadric Edge Collapse"
MENU=(121 10 275 160 559 186)   # Filters, Remeshing..., the filter
work="$(mktemp -d)"
XDG_RUNTIME_DIR="$(mktemp -d)"
export XDG_RUNTIME_DIR
start_xvfb
MPID=
trap 'kill $MPID $XPID 2>/dev/null || true; rm -rf "$work" "$XDG_RUNTIME_DIR"' EXIT
(cd "$work" && exec "$MESHLAB" "$MESH" >/dev/null 2>&1) &
MPID=$!
wait_for() { for _ in $(seq 60); do xdotool search --name "$1" >/dev/null 2>&1 && return 0; sleep 0.5; done
             import -window root "$OUT"; echo "gui_collapse_colours.sh: no window named '$1' (screenshot $OUT)" >&2; exit 1; }
wait_for "MeshLab"
sleep 8                                                          # the mesh loads and renders
xdotool mousemove "${MENU[0]}" "${MENU[1]}" click 1; sleep 1.5   # Filters
xdotool mousemove "${MENU[2]}" "${MENU[3]}" click 1; sleep 1.5   # Remeshing, Simplification and Reconstruction
xdotool mousemove "${MENU[4]}" "${MENU[5]}" click 1              # the filter
wait_for "$FILTER"
dialog="$(xdotool search --name "$FILTER" | head -1)"
sleep 1
eval "$(xdotool getwindowgeometry --shell "$dialog")"           # WIDTH, HEIGHT of the dialog
xdotool mousemove --window "$dialog" 354 $((HEIGHT - 24)) click 1   # Apply (at the defaults)
sleep 15                                                         # grouping and collapse of 69,451 faces
if xdotool search --name "Filter Failure" >/dev/null 2>&1; then
  import -window root "$OUT"
  echo "gui_collapse_colours.sh: the filter failed at its defaults (screenshot $OUT)" >&2
  exit 1
fi
xdotool mousemove --window "$dialog" 122 $((HEIGHT - 24)) click 1   # Close: the mesh shows
sleep 3
xdotool mousemove 1300 950
import -window root -crop 935x725+0+0 "$OUT"
# The groups' colours: the mean saturation of the middle of the view (the bunny) must be far from
# grey; with the vertex colour still shown it is about 0.
colourful="$(convert "$OUT" -crop 160x120+170+320 -colorspace HSL -channel G -separate +channel \
             -format '%[fx:mean]' info:)"
awk -v s="$colourful" 'BEGIN { exit !(s > 0.25) }' \
  || { echo "gui_collapse_colours.sh: the bunny is not shown in its groups' colours (mean saturation $colourful; screenshot $OUT)" >&2; exit 1; }
echo "MeshLab 2020.09: $FILTER at its defaults, shown in the groups' face colours (mean saturation $colourful; $OUT)"
