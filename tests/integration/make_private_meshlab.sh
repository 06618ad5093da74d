#!/usr/bin/env bash
# Builds a private copy of Debian's MeshLab (meshlabserver and the GUI) that loads the freshly built
# plugin, so that the integration tests exercise the build tree and never depend on (or touch) the
# installed plugin.
# MeshLab only looks for plugins next to its own binary, and Qt resolves a symlinked binary back
# to /usr/bin, so the binary is copied; libraries and the other plugins are symlinked.
#   make_private_meshlab.sh PLUGIN.so DEST
set -euo pipefail
plugin="$1"; dest="$2"
sys=/usr/lib/x86_64-linux-gnu/meshlab
[ -x /usr/bin/meshlabserver ] || { echo "meshlabserver not installed (run scripts/setup.sh)" >&2; exit 1; }
mkdir -p "$dest/bin" "$dest/lib/x86_64-linux-gnu/meshlab/plugins"
cp -f /usr/bin/meshlabserver "$dest/bin/meshlabserver"
cp -f /usr/bin/meshlab "$dest/bin/meshlab"
ln -sfn "$sys/libmeshlab-common.so" "$dest/lib/x86_64-linux-gnu/meshlab/libmeshlab-common.so"
for p in "$sys"/plugins/*.so; do
  [ "$(basename "$p")" = libfilter_conelod.so ] && continue
  ln -sfn "$p" "$dest/lib/x86_64-linux-gnu/meshlab/plugins/$(basename "$p")"
done
ln -sfn "$(readlink -f "$plugin")" "$dest/lib/x86_64-linux-gnu/meshlab/plugins/libfilter_conelod.so"
