#!/usr/bin/env bash
# Runs `shadowlab bench gpu` and gpu:afsm's goals on a Linux machine with a datacenter GPU
# (H100/H200 class, no display, no Rust toolchain) and writes to OUTDIR:
#
# - gpu-bench.json: `bench gpu` (every GPU technique's stage times beside its CPU twin's);
# - engines-gpu.json and engines-gpu-plots/: `bench engines --backend gpu` (every GPU
#   technique at equal shadow memory on the CPU suite's scenes, error against GPU time,
#   the Pareto front; the goal ratios gpu:csm/gpu:pcf <= 1.3, gpu:psm/gpu:sm <= 1.15,
#   gpu:msm/gpu:vsm <= 1.3, gpu:cascaded/gpu:sm <= 1.5 for the pairs built, and each
#   technique on chessboard at 1920x1080 against 2 ms);
# - afsm-scaling.json: `bench afsm-scaling`, whose GPU rows time gpu:afsm and gpu:raytrace
#   (BVH prebuilt) at 1920x1080 on 1K-1M random triangles (goal: gpu:afsm's GPU time at
#   most gpu:raytrace's at every size);
# - hairball-{afsm-1,afsm-32,raytrace}.json: `render --stats` of hairball (2.88M
#   triangles) at 1920x1080 with gpu:afsm at 1 and 32 samples a pixel and gpu:raytrace
#   (goals: gpu:afsm at most gpu:raytrace; 32 samples at most 2.5x one; 32 samples under
#   16 ms). GPU times are the counters gpu_*_ms; the 32-sample run's sub-pixel primary
#   hits are traced on the CPU (stage subpixel_hits), outside the GPU time;
# - asm-room/: `compare` of room's walkthrough over 8 frames with gpu:asm, a 2048²
#   gpu:sm and the CPU asm (goal: gpu:asm's last frame's mismatch at most 1/10 of
#   gpu:sm's within a 16 MiB pool; results[].frames[] in asm-room/metrics.json);
# - viewer-{sm,cascaded,afsm}.txt: `view --benchmark-frames 120` at 1920x1080 on chessboard with
#   gpu:sm, gpu:cascaded and gpu:afsm, the error overlay on (goal: 60 frames a second), under Xvfb when
#   the machine has it (a window needs a display; skipped otherwise);
# - gpu-bench.log: everything printed.
#
#   scripts/gpu-bench.sh BINARY OUTDIR
#
# BINARY is a `shadowlab` built elsewhere (`cargo build --release -p shadowlab-cli`, on the
# same architecture and a glibc no newer than the GPU machine's) and copied over.
#
# The Vulkan loader: when `ldconfig -p` lists no libvulkan.so.1, the script unpacks Debian's
# loader package from the .deb files in $SHADOWLAB_VULKAN_DEBS (default: the folder `.gl`
# beside BINARY) into / with `dpkg -x` and runs ldconfig. Fetch them on any Debian machine
# with `apt-get download libvulkan1` (add `-oAPT::Architecture=amd64` from another
# architecture) and copy them beside the binary.
#
# The NVIDIA driver's Vulkan ICD: when no ICD manifest in the loader's standard folders
# names NVIDIA, the script looks for nvidia_icd.json where container runtimes put it
# (/usr/local/nvidia/share/vulkan/icd.d, /usr/share/vulkan/icd.d, /etc/vulkan/icd.d) and
# points VK_DRIVER_FILES at it.
#
# The adapter is the first whose name contains $SHADOWLAB_ADAPTER (default: NVIDIA). The
# whole run is cut at 8 minutes: a step still running then is ended and the next ones
# skipped, so the JSON of the steps before it is kept (the CPU twins' frames and hairball's
# loading are most of the time).
set -euo pipefail

if [ $# -ne 2 ]; then
    echo "usage: $0 BINARY OUTDIR" >&2
    exit 2
fi
binary=$(realpath "$1")
out=$2
[ -x "$binary" ] || { echo "$binary is not an executable" >&2; exit 2; }
mkdir -p "$out"
log="$out/gpu-bench.log"
: >"$log"
say() { echo "$*" | tee -a "$log"; }

if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1'; then
    debs=${SHADOWLAB_VULKAN_DEBS:-$(dirname "$binary")/.gl}
    if ! ls "$debs"/*.deb >/dev/null 2>&1; then
        say "no Vulkan loader here and no .deb files in $debs: copy libvulkan1's .deb there (apt-get download libvulkan1)"
        exit 2
    fi
    say "unpacking the Vulkan loader from $debs"
    for f in "$debs"/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi

if ! grep -lis nvidia /usr/share/vulkan/icd.d/*.json /etc/vulkan/icd.d/*.json >/dev/null 2>&1; then
    for d in /usr/local/nvidia/share/vulkan/icd.d /usr/share/vulkan/icd.d /etc/vulkan/icd.d; do
        if [ -f "$d/nvidia_icd.json" ]; then
            export VK_DRIVER_FILES="$d/nvidia_icd.json"
            say "NVIDIA's Vulkan ICD: $VK_DRIVER_FILES"
            break
        fi
    done
fi
export SHADOWLAB_ADAPTER=${SHADOWLAB_ADAPTER:-NVIDIA}

command -v nvidia-smi >/dev/null 2>&1 && nvidia-smi -L 2>&1 | tee -a "$log" || true
# One deadline for the whole run: `bench gpu` first, then the engines suite on the GPU,
# then gpu:afsm's goals.
deadline=$((SECONDS + 480))
left() { echo $((deadline - SECONDS > 1 ? deadline - SECONDS : 1)); }
run() {
    say "running: $* (adapter: $SHADOWLAB_ADAPTER)"
    timeout "$(left)" "$binary" --quiet "$@" 2>&1 | tee -a "$log"
    return "${PIPESTATUS[0]}"
}
set +e
run bench gpu --force --json "$out/gpu-bench.json"
status=$?
run bench engines --backend gpu --force --json "$out/engines-gpu.json" --plots "$out/engines-gpu-plots"
run bench afsm-scaling --force --json "$out/afsm-scaling.json"
hair=(render --force --scene hairball --width 1920 --height 1080)
run "${hair[@]}" --technique gpu:afsm --stats "$out/hairball-afsm-1.json"
run "${hair[@]}" --technique gpu:afsm --param samples=32 --stats "$out/hairball-afsm-32.json"
run "${hair[@]}" --technique gpu:raytrace --stats "$out/hairball-raytrace.json"
run compare --force --scene room --techniques gpu:asm,gpu:sm,asm \
    --param gpu:sm.resolution=2048 --frames 8 --out "$out/asm-room"
if command -v xvfb-run >/dev/null 2>&1; then
    viewer=(view --scene chessboard --width 1920 --height 1080 --error-overlay --benchmark-frames 120)
    for t in sm cascaded afsm; do
        say "running: xvfb-run $binary ${viewer[*]} --technique gpu:$t"
        timeout "$(left)" xvfb-run -a -s "-screen 0 2400x1200x24" \
            "$binary" "${viewer[@]}" --technique "gpu:$t" 2>&1 | tee "$out/viewer-$t.txt" >>"$log"
    done
else
    say "no xvfb-run here: the viewer's benchmark is skipped"
fi
set -e
say "bench gpu's exit status $status"
exit "$status"
