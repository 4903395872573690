#!/usr/bin/env bash
# The verdict table: every technique at its defaults (`compare --scene MESH` and the image
# size, nothing else) on every real mesh: the ones carried in crates/shadowlab/assets and
# the ones scripts/fetch-real-meshes.sh fetches into real-meshes/.
# Usage: scripts/verdict-table.sh [OUT_DIR] [WIDTH] [HEIGHT]   (needs python3)
# Environment: SHADOWLAB (the binary; default target/release/shadowlab), MESHES (a list
# of mesh paths replacing the default list).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-verdict-table}"
width="${2:-480}"
height="${3:-360}"
bin="${SHADOWLAB:-target/release/shadowlab}"
assets=crates/shadowlab/assets
if [ -z "${MESHES:-}" ]; then
    MESHES="$assets/bunny.obj $assets/teapot.obj $assets/dragon-11k.ply \
$assets/chessboard/chessboard.obj $assets/fence/fence.obj $assets/bike/bike.obj \
$assets/gltf/2CylinderEngine.glb $(ls real-meshes/*/*.obj 2>/dev/null | tr '\n' ' ')"
fi
mkdir -p "$out"
for mesh in $MESHES; do
    name="$(basename "${mesh%.*}")"
    rm -f "$out/$name/metrics.json"
    if "$bin" compare --scene "$mesh" --width "$width" --height "$height" \
        --out "$out/$name" --force --quiet; then
        echo "$name" >&2
    else
        echo "$name: compare failed (above)" >&2
    fi
done
python3 - "$out" $MESHES <<'PY'
import json, os, sys
out, meshes = sys.argv[1], sys.argv[2:]
names = None
rows = []
for mesh in meshes:
    name = os.path.splitext(os.path.basename(mesh))[0]
    path = os.path.join(out, name, "metrics.json")
    if not os.path.exists(path):
        rows.append(f"| {name} | compare failed (see its error) |")
        continue
    m = json.load(open(path))
    res = {r["label"]: r for r in m["results"] if r["label"] != "raytrace"}
    names = names or list(res)
    shadowed = m.get("reference", {}).get("shadowed_share")
    cells = []
    for t in names:
        r = res[t]
        frames = r.get("frames_run")
        tag = f" ({frames} fr)" if frames and frames > 1 else ""
        cells.append(f"{100 * r['mismatch_rate']:.3f}% / {r['mean_abs_error']:.4f}{tag}")
    spp = m["reference"]["samples_per_pixel"]
    sh = "" if shadowed is None else f"{100 * shadowed:.1f}%"
    rows.append(f"| {name} | {m['triangles']} | {spp} | {sh} | " + " | ".join(cells) + " |")
print("| mesh | triangles | ref spp | shadowed | " + " | ".join(names) + " |")
print("|---|---:|---:|---:|" + "---:|" * len(names))
print("\n".join(rows))
PY
