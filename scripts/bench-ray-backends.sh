#!/usr/bin/env bash
# Times the two ray back ends (`--ray-backend software|hardware`) against each other on this
# machine's GPU, which needs ray queries (`manylights info` says whether it has them; Mesa 25's
# lavapipe does, with WGPU_ADAPTER_NAME=llvmpipe, as a sanity check rather than a speed claim): bvh
# lights, bvh decals, hard sun shadows with reflections, and a shadow ray per lamp, each configuration
# with both back ends. Prints each one's median shading and frame time (GPU timestamps) and writes
# the JSON under ${OUT:-ray-backends}/.
#
#   scripts/bench-ray-backends.sh [SCENE [WIDTH HEIGHT]]
#
# SCENE defaults to Sponza from the shared assets, WIDTH×HEIGHT to 1920×1080; FRAMES (default 50)
# frames are timed after WARMUP (default 10); BIN names the binary (default target/release/manylights).
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:-../shared/assets/sponza/Sponza.gltf}
width=${2:-1920}
height=${3:-1080}
bin=${BIN:-target/release/manylights}
out=${OUT:-ray-backends}
mkdir -p "$out"
[ -x "$bin" ] || cargo build --release -p manylights-cli
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
configurations=(
  "lights|--lights 4000 --light-method bvh --decal-method off"
  "decals|--decals 20000 --decal-method bvh --light-method off"
  "rays|--shadows hard --reflections --light-method off --decal-method off"
  "lamp_shadows|--lights 256 --light-method bvh --direct-lighting reference"
)
printf '%-14s %-9s %12s %12s\n' configuration backend "shade ms" "frame ms"
for entry in "${configurations[@]}"; do
  name=${entry%%|*}
  read -r -a flags <<<"${entry#*|}"
  for backend in software hardware; do
    json="$out/${name}_$backend.json"
    "$bin" render --scene "$scene" --width "$width" --height "$height" --exposure 0 --seed 1 \
      --warmup "${WARMUP:-10}" --frames "${FRAMES:-50}" --ray-backend "$backend" "${flags[@]}" \
      --timings-json "$json" -o "$out/${name}_$backend.png" >/dev/null
    python3 - "$json" "$name" "$backend" <<'PY'
import json, sys
report = json.load(open(sys.argv[1]))
shade = sum(p["median_ms"] for name, p in report["passes"].items() if name.endswith("_shade"))
print(f"{sys.argv[2]:<14} {sys.argv[3]:<9} {shade:12.3f} {report['frame']['median_ms']:12.3f}")
PY
  done
done
