#!/usr/bin/env bash
# A picture of the web viewer in headless Chromium: starts `conelod serve FILE.clod` on a free
# port, opens the viewer's page in Debian's chromium (web/shoot.mjs, playwright-core), waits until
# the refinement is done, writes OUT.png and prints the page's figures (JSON: bytes fetched before
# the first image and in all, the cut's faces and levels, frames per second).
#   scripts/web_screenshot.sh FILE.clod OUT.png [--budget F] [--pixel E] [--size WxH]
#       [--eye X,Y,Z] [--color vertex|none|level|group|node] [--fps N] [--no-hud]
#   --budget F  faces of the cut [500000]; --pixel E  screen-space error in pixels [1];
#   --size      the window [800x600]; --eye  model coordinates [in front, +Z];
#   --fps N     after the refinement, time N frames [60].
# Uses build/conelod/conelod when built here, else `conelod` on the PATH ($CONELOD overrides);
# web/node_modules from `npm ci` (scripts/setup.sh).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
usage() { sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }
die() { echo "web_screenshot.sh: $*" >&2; exit 2; }

[ $# -ge 2 ] || usage
FILE="$1" OUT="$2"
shift 2
QUERY="" SIZE=800x600 FPS=60
while [ $# -gt 0 ]; do
  [ $# -ge 2 ] || [ "$1" = --no-hud ] || usage
  case "$1" in
    --budget) [[ "$2" =~ ^[0-9]+$ ]] || die "--budget must be a number of faces"; QUERY+="&budget=$2"; shift 2 ;;
    --pixel) [[ "$2" =~ ^[0-9.]+$ ]] || die "--pixel must be a number of pixels"; QUERY+="&pixel=$2"; shift 2 ;;
    --size) [[ "$2" =~ ^[0-9]+x[0-9]+$ ]] || die "--size must be WxH"; SIZE="$2"; shift 2 ;;
    --eye) [[ "$2" =~ ^[-0-9.eE+]+,[-0-9.eE+]+,[-0-9.eE+]+$ ]] || die "--eye must be X,Y,Z"; QUERY+="&eye=$2"; shift 2 ;;
    --color) [[ "$2" =~ ^(vertex|none|level|group|node)$ ]] || die "--color must be vertex, none, level, group or node"; QUERY+="&color=$2"; shift 2 ;;
    --fps) [[ "$2" =~ ^[0-9]+$ ]] || die "--fps must be a number of frames"; FPS="$2"; shift 2 ;;
    --no-hud) QUERY+="&hud=0"; shift ;;
    *) usage ;;
  esac
done
QUERY+="&fps=$FPS"

CONELOD="${CONELOD:-}"
if [ -z "$CONELOD" ]; then
  if [ -x "$ROOT/build/conelod/conelod" ]; then CONELOD="$ROOT/build/conelod/conelod"; else CONELOD="$(command -v conelod || true)"; fi
fi
[ -n "$CONELOD" ] || die "conelod not found (build it, or run scripts/setup.sh)"
[ -d "$ROOT/web/node_modules/playwright-core" ] || die "web/node_modules is missing: run scripts/setup.sh (npm ci in web/)"
command -v node >/dev/null || die "node not found (Debian: nodejs; scripts/setup.sh installs it)"
[ -f "$FILE" ] || die "no such file: $FILE"

LOG="$(mktemp)"
cleanup() {
  if [ -n "${SERVER:-}" ]; then kill "$SERVER" 2>/dev/null || true; wait "$SERVER" 2>/dev/null || true; fi
  rm -f "$LOG"
}
trap 'rc=$?; cleanup; exit $rc' EXIT
"$CONELOD" serve "$FILE" --port 0 >"$LOG" 2>&1 &
SERVER=$!
URL=""
for _ in $(seq 100); do
  URL="$(grep -o 'http://[^ ]*' "$LOG" || true)"
  [ -n "$URL" ] && break
  kill -0 "$SERVER" 2>/dev/null || { cat "$LOG" >&2; exit 2; }
  sleep 0.1
done
[ -n "$URL" ] || die "conelod serve printed no URL: $(cat "$LOG")"
node "$ROOT/web/shoot.mjs" "$URL$QUERY" "$OUT" --size "$SIZE"
