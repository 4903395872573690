#!/usr/bin/env bash
# Renders every technique on three built-in scenes, one per light kind (bunny: directional,
# chessboard: spot, room with light=point: point), at 320×240, and keeps each visibility EXR
# and each --dump folder. Use it to show that a change keeps every pixel:
#
#   scripts/render-all.sh before/            # on the old commit
#   scripts/render-all.sh after/             # on the new one
#   scripts/render-all.sh --compare before/ after/
#
# SHADOWLAB names the binary (default: target/release/shadowlab); TECHNIQUES limits the list
# (default: every technique `shadowlab techniques` knows, or the built-in list below).
set -euo pipefail

if [ "${1:-}" = "--compare" ]; then
    [ $# -eq 3 ] || { echo "usage: $0 --compare DIR_A DIR_B" >&2; exit 2; }
    if diff -r -q "$2" "$3"; then
        echo "identical: $(find "$2" -type f | wc -l) files"
    else
        echo "the two renders differ (files above)" >&2
        exit 1
    fi
    exit 0
fi

[ $# -eq 1 ] || { echo "usage: $0 OUT_DIR | --compare DIR_A DIR_B" >&2; exit 2; }
out=$1
bin=${SHADOWLAB:-target/release/shadowlab}
[ -x "$bin" ] || { echo "$bin is missing: run cargo build --release first" >&2; exit 2; }
techniques=${TECHNIQUES:-raytrace sm pcf psm asm afsm subpixel csm vsm evsm msm cascaded lispsm}
mkdir -p "$out"

render() { # scene label, then extra arguments
    local label=$1
    shift
    for t in $techniques; do
        local dump="$out/$label-$t-dump"
        rm -rf "$dump"
        mkdir -p "$dump"
        "$bin" render "$@" --technique "$t" --width 320 --height 240 \
            --visibility "$out/$label-$t.exr" --output "$out/$label-$t.png" --dump "$dump" \
            >/dev/null 2>"$out/$label-$t.log" ||
            { echo "failed: $label $t (see $out/$label-$t.log)" >&2; exit 1; }
        rm -f "$out/$label-$t.log"
        echo "$label $t"
    done
}

render bunny --scene bunny
render chessboard --scene chessboard
render room-point --scene room --scene-param light=point
