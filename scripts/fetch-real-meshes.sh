#!/usr/bin/env bash
# Fetches the real meshes that the verdict table is measured on (scripts/verdict-table.sh)
# from Debian's `sweethome3d-furniture` package into real-meshes/ (ignored by git).
# Each model keeps its LICENSE file beside it; the libraries' licences are CC0 (BlendSwap
# CC-0), CC-BY-3.0 (BlendSwap CC-BY) and CC-BY-3.0-US (Andrew Kator & Jennifer Legaz).
# Usage: scripts/fetch-real-meshes.sh [DEST]   (needs apt-get, unzip; run `apt-get update` first)
set -euo pipefail
cd "$(dirname "$0")/.."
dest="${1:-real-meshes}"
version="1.8-1"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# library archive : model folder (the OBJ inside is named after the folder)
models=(
    BlendSwap-CC-0:blendswap-cc-0/decorativePlant
    BlendSwap-CC-0:blendswap-cc-0/motorbike
    BlendSwap-CC-0:blendswap-cc-0/peterbilt
    BlendSwap-CC-0:blendswap-cc-0/poolTable
    BlendSwap-CC-0:blendswap-cc-0/oakChair
    BlendSwap-CC-0:blendswap-cc-0/radiator3
    BlendSwap-CC-0:blendswap-cc-0/cactus
    BlendSwap-CC-BY:blendswap-cc-by/horse
    BlendSwap-CC-BY:blendswap-cc-by/fountain
    BlendSwap-CC-BY:blendswap-cc-by/wheelchair
    BlendSwap-CC-BY:blendswap-cc-by/spider_plant
    KatorLegaz:katorlegaz/office-chair
    KatorLegaz:katorlegaz/utility-shelving
)

(cd "$work" && apt-get download "sweethome3d-furniture=$version" >/dev/null)
dpkg-deb -x "$work"/sweethome3d-furniture_*.deb "$work/x"
mkdir -p "$dest"
for entry in "${models[@]}"; do
    library="${entry%%:*}"
    folder="${entry#*:}"
    name="${folder##*/}"
    archive="$work/x/usr/share/sweethome3d/furniture/$library.sh3f"
    rm -rf "${dest:?}/$name"
    mkdir -p "$dest/$name"
    unzip -q -j -o "$archive" "$folder/*" -d "$dest/$name"
    unzip -q -o -p "$archive" LICENSE.TXT > "$dest/$name/LIBRARY-LICENSE.TXT"
    echo "$dest/$name/$name.obj ($library, sweethome3d-furniture $version)"
done
