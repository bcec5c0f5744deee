#!/usr/bin/env bash
# Runs on the GPU machine (see BENCHMARKS.md): expects the release binary and sponza_lite under
# .bench/, and the Vulkan loader packages under .gl/ (the device tool's recipe). Writes JSON, two PNGs
# and the GPU description to $OUT.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export XDG_RUNTIME_DIR=/tmp
out=${OUT:-/tmp/out}
mkdir -p "$out"
bin=.bench/manylights
sponza=.bench/sponza_lite/Sponza.gltf
nvidia-smi --query-gpu=name,driver_version --format=csv | tee "$out/gpu.txt"
$bin info | tee -a "$out/gpu.txt"
run() { # name, image folder, then render arguments
  local name=$1 images=$2; shift 2
  echo "== $name"
  $bin render --width 1920 --height 1080 --warmup 100 --frames 300 --timings \
    --timings-json "$out/$name.json" -o "$images/$name.png" "$@" 2>&1
}
run sponza_256 "$out" --scene $sponza --lights 256 --seed 1
run demo_256 /tmp --scene demo --lights 256 --seed 1
run sponza_0 /tmp --scene $sponza
run sponza_1024 /tmp --scene $sponza --lights 1024 --seed 1
# The paper's 28k small lights: BVH against brute force (brute is slow: fewer frames).
run sponza_28k_bvh /tmp --scene $sponza --lights 28000 --seed 1 --light-method bvh
$bin render --width 1920 --height 1080 --warmup 3 --frames 10 --timings --scene $sponza --lights 28000 --seed 1 \
  --light-method brute --timings-json "$out/sponza_28k_brute.json" -o /tmp/brute.png 2>&1
