#!/usr/bin/env bash
# Runs `shadowlab bench gpu` on a Linux machine with a datacenter GPU (H100/H200 class, no
# display, no Rust toolchain) and writes OUTDIR/gpu-bench.json and OUTDIR/gpu-bench.log.
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
# whole run is cut at 8 minutes (the suite itself takes about 2 on such a GPU, most of it
# the CPU twins' frames and hairball's loading).
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
say "running: $binary bench gpu --json $out/gpu-bench.json (adapter: $SHADOWLAB_ADAPTER)"
set +e
timeout 480 "$binary" --quiet bench gpu --json "$out/gpu-bench.json" 2>&1 | tee -a "$log"
status=${PIPESTATUS[0]}
set -e
say "exit status $status"
exit "$status"
