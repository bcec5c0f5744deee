#!/usr/bin/env bash
# Soak tests: long runs whose process and GPU memory must stay flat.
#
#   scripts/soak.sh render BIN SCENE OUT [FRAMES]   renders FRAMES frames (default 10,000) of SCENE at
#       1920x1080 with animated groups of scattered lights and decals, their BVHs rebuilt on the GPU
#       every frame, and 262,144 particles as exact lights (rebuilt every frame too).
#   scripts/soak.sh viewer BIN OUT [RESIZES]        runs the viewer under Xvfb and resizes its window
#       RESIZES times (default 300), a renderer rebuilt for each size.
#
# Each samples the process's resident memory (and, where nvidia-smi exists, the GPU memory in use)
# once a second into OUT/<mode>-memory.csv and prints the first, the median and the last sample.
set -euo pipefail

mode=${1:?"usage: scripts/soak.sh render BIN SCENE OUT [FRAMES] | viewer BIN OUT [RESIZES]"}
bin=${2:?"give the manylights binary"}

# Samples $1's memory every second until it exits; writes seconds,rss_mib,gpu_mib to $2.
sample() {
  local pid=$1 csv=$2 start=$SECONDS
  echo "seconds,rss_mib,gpu_mib" >"$csv"
  while kill -0 "$pid" 2>/dev/null; do
    local rss gpu=""
    rss=$(awk '/^VmRSS/ { printf "%.1f", $2 / 1024 }' "/proc/$pid/status" 2>/dev/null || true)
    if command -v nvidia-smi >/dev/null; then
      gpu=$(nvidia-smi --query-gpu=memory.used --format=csv,noheader,nounits 2>/dev/null | head -n1 | tr -d ' ' || true)
    fi
    [ -n "$rss" ] && echo "$((SECONDS - start)),$rss,$gpu" >>"$csv"
    sleep 1
  done
}

summarise() {
  local csv=$1
  awk -F, 'NR > 1 { n++; rss[n] = $2; gpu[n] = $3 }
    END {
      if (n == 0) { print "no samples"; exit 1 }
      m = int((n + 1) / 2)
      printf "samples %d: RSS MiB first %s, median %s, last %s; GPU MiB first %s, median %s, last %s\n",
        n, rss[1], rss[m], rss[n], gpu[1], gpu[m], gpu[n]
    }' "$csv"
}

case $mode in
  render)
    scene=${3:?"give the scene"}; out=${4:?"give the output folder"}; frames=${5:-10000}
    mkdir -p "$out"
    "$bin" render --scene "$scene" --width 1920 --height 1080 --lights 4096 --decals 4096 --animate \
      --light-method bvh --light-bvh-build gpu-every-frame --decal-method bvh --decal-bvh-build gpu-every-frame \
      --particles 262144 --particle-method bvh --frames "$frames" --warmup 0 \
      -o "$out/render-soak.png" --timings-json "$out/render-soak.json" >"$out/render-soak.log" 2>&1 &
    pid=$!
    sample "$pid" "$out/render-memory.csv"
    wait "$pid"
    summarise "$out/render-memory.csv"
    ;;
  viewer)
    out=${3:?"give the output folder"}; resizes=${4:-300}
    mkdir -p "$out"
    sets=()
    for ((i = 1; i <= resizes; i++)); do
      sets+=(--set "$((i * 3)):window=$((480 + (i * 37) % 640))x$((270 + (i * 23) % 360))")
    done
    xvfb-run -a -s "-screen 0 1600x1000x24" "$bin" view --width 640 --height 360 --lights 256 --decals 64 \
      --frames $((resizes * 3 + 3)) "${sets[@]}" --screenshot "$out/viewer-soak.png" >"$out/viewer-soak.log" 2>&1 &
    runner=$!
    # The viewer runs under xvfb-run's shell: sample the viewer itself.
    pid=""
    for _ in $(seq 100); do
      pid=$(pgrep -n -f "^$bin view" || true)
      [ -n "$pid" ] && break
      sleep 0.1
    done
    [ -n "$pid" ] && sample "$pid" "$out/viewer-memory.csv"
    wait "$runner"
    summarise "$out/viewer-memory.csv"
    ;;
  *)
    echo "error: unknown mode $mode; give render or viewer" >&2
    exit 1
    ;;
esac
