#!/usr/bin/env bash
# Runs the viewer's frame-rate goal, `shadowlab bench gpu` and gpu:afsm's goals on a Linux
# machine with a datacenter GPU (H100/H200 class, no display, no Rust toolchain) and writes
# to OUTDIR, in this order:
#
# - viewer-{sm,cascaded,afsm}.txt: `view --benchmark-frames 120` at 1920x1080 on chessboard
#   with gpu:sm, gpu:cascaded and gpu:afsm, the error overlay on (goal: 60 frames a second),
#   under Xvfb (a window needs a display). A GPU whose Vulkan driver cannot present to Xvfb
#   draws the frames offscreen, which the report says;
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
# - gpu-bench.log: everything printed.
#
#   scripts/gpu-bench.sh BINARY OUTDIR [viewer]
#
# With `viewer`, only the viewer's benchmarks run.
#
# BINARY is a `shadowlab` built elsewhere (`cargo build --release -p shadowlab-cli`, on the
# same architecture and a glibc no newer than the GPU machine's) and copied over.
#
# The Vulkan loader: when `ldconfig -p` lists no libvulkan.so.1 or no libGLdispatch.so.0,
# the script unpacks Debian's packages from the .deb files in $SHADOWLAB_VULKAN_DEBS
# (default: the folder `.gl` beside BINARY) into / with `dpkg -x` and runs ldconfig. NVIDIA's
# Vulkan driver lives in libGLX_nvidia: on an H200 machine without glvnd's libraries it gave
# the loader no vkCreateInstance, and with them it ran. Fetch them on any Debian machine
# with `apt-get download libvulkan1 libglvnd0 libglx0 libgl1 libegl1 libgles2 libopengl0`
# (add `-oAPT::Architecture=amd64` from another architecture) and copy them beside the
# binary.
#
# The NVIDIA driver's Vulkan ICD: when no ICD manifest in the loader's standard folders
# names NVIDIA, the script looks for nvidia_icd.json where container runtimes put it
# (/usr/local/nvidia/share/vulkan/icd.d, /usr/share/vulkan/icd.d, /etc/vulkan/icd.d) and
# points VK_DRIVER_FILES at it.
#
# Xvfb: when the machine has no Xvfb, the script unpacks the .deb files in
# $SHADOWLAB_X_DEBS (default: the folder `.x` beside BINARY) into a private folder and runs
# Xvfb from there; only xkbcomp and the keyboard data, which Xvfb looks for at fixed paths,
# go into /usr. Fetch them with `apt-get download xvfb x11-xkb-utils xkb-data` and the
# libraries `ldd` names for Xvfb, xkbcomp and libX11's clients (libxcursor1, libxi6,
# libxrandr2, libxkbcommon-x11-0 and the libxcb extensions).
#
# The adapter is the first whose name contains $SHADOWLAB_ADAPTER (default: NVIDIA). The
# whole run is cut at $SHADOWLAB_BENCH_SECONDS (default 480): a step still running then is
# ended and the next ones skipped, so the JSON of the steps before it is kept (the CPU
# twins' frames and hairball's loading are most of the time).
set -euo pipefail

if [ $# -lt 2 ] || [ $# -gt 3 ] || { [ $# = 3 ] && [ "$3" != viewer ]; }; then
    echo "usage: $0 BINARY OUTDIR [viewer]" >&2
    exit 2
fi
only_viewer=${3:-}
binary=$(realpath "$1")
out=$2
[ -x "$binary" ] || { echo "$binary is not an executable" >&2; exit 2; }
mkdir -p "$out"
log="$out/gpu-bench.log"
: >"$log"
say() { echo "$*" | tee -a "$log"; }

if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1' ||
    ! ldconfig -p 2>/dev/null | grep -q 'libGLdispatch\.so\.0'; then
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
# One deadline for the whole run: the viewer first, then `bench gpu`, the engines suite on
# the GPU and gpu:afsm's goals.
deadline=$((SECONDS + ${SHADOWLAB_BENCH_SECONDS:-480}))
left() { echo $((deadline - SECONDS > 1 ? deadline - SECONDS : 1)); }
run() {
    say "running: $* (adapter: $SHADOWLAB_ADAPTER)"
    timeout "$(left)" "$binary" --quiet "$@" 2>&1 | tee -a "$log"
    return "${PIPESTATUS[0]}"
}

# A display for the viewer: the machine's Xvfb, or one unpacked from .deb files. Only the
# viewer sees it: NVIDIA's Vulkan driver offers no device when DISPLAY names an X server
# without GLX, as this Xvfb is. Unpacked, Xvfb runs on its own libraries and the viewer on
# their X client libraries alone (not their OpenGL dispatch, which NVIDIA's driver links).
view_libs=""
start_xvfb() {
    local xvfb=Xvfb prefix server_libs=""
    if ! command -v Xvfb >/dev/null 2>&1; then
        local debs=${SHADOWLAB_X_DEBS:-$(dirname "$binary")/.x}
        ls "$debs"/*.deb >/dev/null 2>&1 || return 1
        prefix=$(mktemp -d)
        for f in "$debs"/*.deb; do dpkg -x "$f" "$prefix"; done
        [ -e /usr/bin/xkbcomp ] || cp "$prefix/usr/bin/xkbcomp" /usr/bin/
        [ -e /usr/share/X11/xkb ] || { mkdir -p /usr/share/X11 && cp -r "$prefix/usr/share/X11/xkb" /usr/share/X11/; }
        server_libs="$prefix/usr/lib/x86_64-linux-gnu:$prefix/lib/x86_64-linux-gnu"
        mkdir "$prefix/client"
        for l in "$prefix"/usr/lib/x86_64-linux-gnu/lib{X,x}*.so.* "$prefix"/usr/lib/x86_64-linux-gnu/lib{bsd,md}.so.*; do
            [ -e "$l" ] && ln -sf "$l" "$prefix/client/"
        done
        view_libs="$prefix/client"
        xvfb="$prefix/usr/bin/Xvfb"
        say "Xvfb unpacked from $debs"
    fi
    LD_LIBRARY_PATH="$server_libs" "$xvfb" :99 -screen 0 2400x1200x24 -nolisten tcp >"$out/xvfb.log" 2>&1 &
    for _ in $(seq 50); do
        [ -e /tmp/.X11-unix/X99 ] && return 0
        sleep 0.1
    done
    cat "$out/xvfb.log" >>"$log"
    return 1
}

set +e
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
display=${DISPLAY:-}
if [ -n "$display" ] || { start_xvfb && display=:99; }; then
    viewer=(view --scene chessboard --width 1920 --height 1080 --error-overlay --benchmark-frames 120)
    ways="window offscreen"
    for t in sm cascaded afsm; do
        for how in $ways; do
            extra=()
            [ "$how" = offscreen ] && extra=(--offscreen)
            say "running: $binary ${viewer[*]} --technique gpu:$t ${extra[*]} (display $display)"
            DISPLAY=$display LD_LIBRARY_PATH="$view_libs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" \
                timeout "$(($(left) < 60 ? $(left) : 60))" "$binary" "${viewer[@]}" \
                --technique "gpu:$t" "${extra[@]}" >"$out/viewer-$t.txt" 2>&1
            code=$?
            say "exit status $code"
            grep -v 'extension "GLX" missing' "$out/viewer-$t.txt" >>"$log"
            grep -v 'extension "GLX" missing' "$out/viewer-$t.txt" | tail -n 30
            # Drawn into the window (or offscreen by the benchmark's own choice): done.
            grep -q "frames per second" "$out/viewer-$t.txt" && break
            # A window that failed once is not tried again.
            [ "$how" = window ] && ways=offscreen
        done
    done
else
    say "no display and no Xvfb (nor .deb files to unpack one from): the viewer's benchmark is skipped"
fi
unset DISPLAY
[ -n "$only_viewer" ] && exit 0
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
set -e
say "bench gpu's exit status $status"
exit "$status"
