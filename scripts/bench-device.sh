#!/usr/bin/env bash
# Runs on the GPU machine (see BENCHMARKS.md): expects the release binary and sponza_lite under
# .bench/, and the Vulkan loader packages under .gl/ (the device tool's recipe). Writes the JSON of
# every configuration and the GPU description to $OUT/timings.tgz; prints the timing tables.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export XDG_RUNTIME_DIR=/tmp
out=/tmp/bench
mkdir -p "$out" "${OUT:-/tmp/out}"
bin=.bench/manylights
sponza=.bench/sponza_lite/Sponza.gltf
# The paper's small lights: scattered over Sponza with ranges of 0.1–0.3 m.
for n in 28000 100000 1000000; do
  printf 'gltf = "sponza_lite/Sponza.gltf"\n[camera]\nindex = 0\n[[scatter_lights]]\ncount = %s\nseed = 1\nrange = [0.1, 0.3]\n' $n >.bench/small_$n.toml
done
nvidia-smi --query-gpu=name,driver_version --format=csv | tee "$out/gpu.txt"
run() { # name, frames, then render arguments
  local name=$1 frames=$2; shift 2
  echo "== $name"
  timeout 300 $bin render --width 1920 --height 1080 --warmup 50 --frames "$frames" --timings \
    --timings-json "$out/$name.json" -o /tmp/$name.png "$@" 2>&1 | grep -v "^GPU\|^wrote"
}
bvh="--light-method bvh"
run empty 200 --scene $sponza
run lights_256_brute 200 --scene $sponza --lights 256 --seed 1
run small_28k_cpu 200 --scene .bench/small_28000.toml $bvh
run small_28k_gpu 200 --scene .bench/small_28000.toml $bvh --light-bvh-build gpu-every-frame
run small_100k_gpu 200 --scene .bench/small_100000.toml $bvh --light-bvh-build gpu-every-frame
run small_1m_gpu 200 --scene .bench/small_1000000.toml $bvh --light-bvh-build gpu-every-frame
run small_1m_cpu 200 --scene .bench/small_1000000.toml $bvh
run lights_28k_cpu 200 --scene $sponza --lights 28000 --seed 1 $bvh
run small_28k_brute 5 --scene .bench/small_28000.toml --light-method brute
run decals_100 200 --scene $sponza --decals 100 --seed 1 --decal-method bvh
run decals_10k 200 --scene $sponza --decals 10000 --seed 1 --decal-method bvh
run decals_10k_brute 5 --scene $sponza --decals 10000 --seed 1 --decal-method brute
run decals_100k 200 --scene $sponza --decals 100000 --seed 1 --decal-method bvh
run decals_100k_gpu 200 --scene $sponza --decals 100000 --seed 1 --decal-method bvh --decal-bvh-build gpu-every-frame
run decals_100k_aniso1 200 --scene $sponza --decals 100000 --seed 1 --decal-method bvh --anisotropy 1
run decals_100k_03 200 --scene $sponza --decals 100000 --decal-size 0.3 --seed 1 --decal-method bvh
run decals_1m_03_gpu 200 --scene $sponza --decals 1000000 --decal-size 0.3 --seed 1 --decal-method bvh --decal-bvh-build gpu-every-frame
run both_still 200 --scene .bench/small_28000.toml $bvh --decals 100000 --seed 1 --decal-method bvh
run both_animated 200 --scene .bench/small_28000.toml $bvh --decals 100000 --seed 1 --decal-method bvh --animate
run both_animated_2000_groups 200 --scene .bench/small_28000.toml $bvh --decals 100000 --seed 1 --decal-method bvh --animate --groups 2000
tar -C "$out" -czf "${OUT:-/tmp/out}/timings.tgz" .
