#!/usr/bin/env bash
# Formats every tracked C++ file with clang-format and the tree's .clang-format (Google style, 120
# columns, includes as written). Debian: clang-format (scripts/setup.sh installs it).
#   scripts/format.sh           rewrite the files in place
#   scripts/format.sh --check   change nothing; list the files that are not formatted, exit 1 if any
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
CLANG_FORMAT="${CLANG_FORMAT:-clang-format}"
command -v "$CLANG_FORMAT" >/dev/null || { echo "format.sh: $CLANG_FORMAT not found (Debian: clang-format)" >&2; exit 1; }
cd "$ROOT"
mapfile -t files < <(git ls-files '*.cpp' '*.h' | grep -v '^deps/')
if [ "${1:-}" = "--check" ]; then
  bad=0
  for f in "${files[@]}"; do
    if ! "$CLANG_FORMAT" --dry-run --Werror "$f" >/dev/null 2>&1; then echo "not formatted: $f"; bad=1; fi
  done
  [ "$bad" -eq 0 ] && echo "format.sh: ${#files[@]} files formatted"
  exit "$bad"
fi
"$CLANG_FORMAT" -i "${files[@]}"
echo "format.sh: formatted ${#files[@]} files"
