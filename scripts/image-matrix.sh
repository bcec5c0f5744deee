#!/usr/bin/env bash
# Renders every pipeline with every light, decal and particle method, ray effect, post effect and debug
# view into a folder, so that a refactoring can show identical images before and after:
#   scripts/image-matrix.sh BINARY OUT_DIR        (on lavapipe: WGPU_ADAPTER_NAME=llvmpipe)
#   cmp -r before/ after/ && echo identical
set -euo pipefail
bin=$1
out=$2
mkdir -p "$out"
assets="$(cd "$(dirname "$0")/../.." && pwd)/shared/assets"
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}"
size=(--width 96 --height 64)
render() {
  local name=$1
  shift
  "$bin" render "${size[@]}" -o "$out/$name.png" --exr "$out/$name.exr" "$@" >/dev/null
}
for pipeline in visbuffer deferred forward; do
  for light in off brute bvh clustered; do
    for decal in off brute bvh clustered deferred-decals; do
      [ "$decal" = deferred-decals ] && [ "$pipeline" != deferred ] && continue
      render "$pipeline-$light-$decal" --pipeline "$pipeline" --light-method "$light" --decal-method "$decal" \
        --lights 200 --decals 60
    done
  done
  render "$pipeline-gpu-builds" --pipeline "$pipeline" --light-method bvh --decal-method bvh --lights 300 --decals 80 \
    --light-bvh-build gpu-every-frame --decal-bvh-build gpu-every-frame --animate --time 0.5
  render "$pipeline-dense-decals" --pipeline "$pipeline" --light-method bvh --decal-method bvh --decals 3000 --decal-size 1.5
  render "$pipeline-particles-grid" --pipeline "$pipeline" --light-method bvh --particles 2000 --particle-method grid --time 1
  render "$pipeline-particles-grid-cascades" --pipeline "$pipeline" --particles 2000 --particle-cascades 2 \
    --particle-filter tricubic --particle-samples 4 --time 1
  render "$pipeline-particles-bvh" --pipeline "$pipeline" --light-method bvh --particles 2000 --particle-method bvh --time 1
  render "$pipeline-rays" --pipeline "$pipeline" --light-method bvh --decal-method bvh --lights 50 --decals 20 \
    --shadows soft --shadow-rays 2 --reflections --bounces 2 --light-shadow-rays 2
  render "$pipeline-hard-shadows" --pipeline "$pipeline" --light-method clustered --shadows hard
  render "$pipeline-post" --pipeline "$pipeline" --light-method bvh --lights 100 --auto-exposure --bloom \
    --depth-of-field --motion-blur --camera-velocity 1,0,0 --frames 2 --vignette 0.5 --tonemap agx
  for view in lights-reaching light-work decals-covering particle-light particle-grid-slice; do
    render "$pipeline-debug-$view" --pipeline "$pipeline" --light-method bvh --decal-method bvh --lights 100 \
      --decals 40 --particles 500 --debug-view "$view"
  done
done
render gltf-duck --scene "$assets/duck/Duck.glb" --light-method bvh --lights 40
render gltf-helmet --scene "$assets/damaged_helmet/DamagedHelmet.glb" --light-method clustered --lights 40 --decals 10
render gltf-box-textured --scene "$assets/box_textured/BoxTextured.glb" --pipeline deferred --decal-method deferred-decals --decals 10
