#!/usr/bin/env bash
# Fetches real OBJ meshes for the cut-out and up-axis checks (docs/CLI.md, "--up" and the
# OBJ cut-outs) from Debian's `sweethome3d-furniture` package into real-meshes/cutouts/
# (ignored by git; outside the verdict table's real-meshes/*/*.obj):
#   bush           foliage cut out by `map_d` (an RGBA leaf image)
#   christmas_tree branches cut out by their `map_Kd` image's alpha
#   bonsai-tree    leaves cut out by their `map_Kd` image's alpha
#   armchair1      written Z-up (its catalogue entry turns it with a 90° rotation about X,
#                  the turn `--up z` makes)
# All four are by Scopia, CC-BY-3.0 (the library's LICENSE.TXT is copied beside each).
# Usage: scripts/fetch-cutout-meshes.sh [DEST]   (needs apt-get, unzip; run `apt-get update` first)
set -euo pipefail
cd "$(dirname "$0")/.."
dest="${1:-real-meshes/cutouts}"
version="1.8-1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

(cd "$work" && apt-get download "sweethome3d-furniture=$version" >/dev/null)
dpkg-deb -x "$work"/sweethome3d-furniture_*.deb "$work/x"
archive="$work/x/usr/share/sweethome3d/furniture/Scopia.sh3f"
mkdir -p "$dest"
for name in bush christmas_tree bonsai-tree armchair1; do
    rm -rf "${dest:?}/$name"
    mkdir -p "$dest/$name"
    unzip -q -j -o "$archive" "scopia/$name/*" -d "$dest/$name"
    unzip -q -o -p "$archive" LICENSE.TXT > "$dest/$name/LIBRARY-LICENSE.TXT"
    echo "$dest/$name/$name.obj (Scopia, sweethome3d-furniture $version)"
done
