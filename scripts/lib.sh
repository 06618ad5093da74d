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
