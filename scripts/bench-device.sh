#!/usr/bin/env bash
# Runs on the GPU machine (see BENCHMARKS.md): expects the release binary and sponza_lite under
# .bench/, and the Vulkan loader packages under .gl/ (the device tool's recipe). Writes JSON, PNGs and
# logs to $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export XDG_RUNTIME_DIR=/tmp
out=${OUT:-/tmp/out}
mkdir -p "$out"
bin=.bench/manylights
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv | tee "$out/gpu.txt"
$bin info | tee -a "$out/gpu.txt"
run() { # name, then render arguments
  local name=$1; shift
  echo "== $name"
  $bin render --width 1920 --height 1080 --warmup 100 --frames 300 --timings \
    --timings-json "$out/$name.json" -o "$out/$name.png" "$@" 2>&1 | grep -v XDG_RUNTIME
}
run sponza_256 --scene .bench/sponza_lite/Sponza.gltf --lights 256 --seed 1
run sponza_1024 --scene .bench/sponza_lite/Sponza.gltf --lights 1024 --seed 1
run demo_256 --scene demo --lights 256 --seed 1
run sponza_0 --scene .bench/sponza_lite/Sponza.gltf
run sponza_256_again --scene .bench/sponza_lite/Sponza.gltf --lights 256 --seed 1
