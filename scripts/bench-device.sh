#!/usr/bin/env bash
# Runs on the GPU machine (see BENCHMARKS.md): expects the release binary and sponza_lite under
# .bench/, and the Vulkan loader packages under .gl/ (the device tool's recipe). Writes the JSON of
# every configuration and the GPU description to $OUT/timings.tgz; prints the timing tables.
#
#   scripts/bench-device.sh structures   the acceleration structures' set (issue 3)
#   scripts/bench-device.sh lights       pipelines × light methods on 28k small lights (issue 4)
#   scripts/bench-device.sh decals       pipelines × decal methods on 100k decals (issue 4)
#   scripts/bench-device.sh tests        the GPU-only test binaries under .bench/tests/, if any
#   scripts/bench-device.sh table        `manylights bench`: the paper's Table 1, every pipeline and method (issue 5)
#   scripts/bench-device.sh sweeps       `manylights bench`: lights and decals from 1k to 1M (issue 5); decals to 1M deferred and
#                                        to 262k forward (issue 33)
#   scripts/bench-device.sh sweeps_once  the same sweeps with the bvh built once (issue 33)
#   scripts/bench-device.sh dense        `manylights bench`: dense lights, bvh against clustered, and auto (issue 33)
#   scripts/bench-device.sh assets       every scene of .bench/assets/ and sponza_lite with no flags against each
#                                        explicit method, alone and with 28k lights or 100k decals (issue 33)
#   scripts/bench-device.sh particles    moving particle lights through the 3D-texture grid (issue 6)
#   scripts/bench-device.sh clipmap      1M particles: clipmap cascades against the grid over the scene (issue 6)
#   scripts/bench-device.sh exact        262,144 and 1,048,576 particles as exact lights, every pipeline (issue 6)
#   scripts/bench-device.sh rays         ray-traced sun shadows and reflections on Sponza (issue 7)
#   scripts/bench-device.sh post         the post chain's effects, alone and together, on Sponza (issue 7)
#   scripts/bench-device.sh deform       Sponza's curtains waving and a skinned tube posed: GPU deformation and BLAS
#                                        refit (issues 7, 37)
#   scripts/bench-device.sh materials    every Sponza material coated, every vertex coloured, every texture on
#                                        TEXCOORD_1, fabrics and vases transmissive, or fabrics with a sheen, against
#                                        none: material extensions, vertex colours, the second UV set, transmission
#                                        and sheen (issues 37, 33)
#   scripts/bench-device.sh draws        1,024 to 40,000 draws (scripts/make-bench-scenes.py's cubes), every pipeline,
#                                        all in view or most outside it: the CPU's frame against the GPU's (issue 33)
#   scripts/bench-device.sh soak         10,000 frames of everything rebuilt per frame, memory sampled (issue 31)
#   scripts/bench-device.sh direct       shadowed local lights: exact, reference and restir on 4,096 and 28k lights (issue 34)
#   scripts/bench-device.sh direct_error restir's error against the reference, sampled and denoised (light-error)
#   scripts/bench-device.sh moving       restir and its surface motion on GasStation's animated instances (issue 34)
#   scripts/bench-device.sh tree         restir's candidates through the light tree against the enumeration, 256 to 65,536 lights (issue 35)
#   scripts/bench-device.sh particle_tree shadowed particle lights, 262,144 and 1,048,576: restir through the tree built in
#                                        their GPU rebuild against the enumeration, and their error (particle-error) (issue 35)
# Several sets run one after the other: scripts/bench-device.sh tests lights.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export XDG_RUNTIME_DIR=/tmp
out=/tmp/bench
mkdir -p "$out" "${OUT:-/tmp/out}"
bin=${BIN:-.bench/manylights}
sponza=.bench/sponza_lite/Sponza.gltf
# The paper's small lights: scattered over Sponza with ranges of 0.1–0.3 m.
for n in 28000 100000 1000000; do
  printf 'gltf = "sponza_lite/Sponza.gltf"\n[camera]\nindex = 0\n[[scatter_lights]]\ncount = %s\nseed = 1\nrange = [0.1, 0.3]\n' $n >.bench/small_$n.toml
done
# Particles as the tables in BENCHMARKS.md measured them: 256 emitters, ranges of 0.5–1.5 m (the
# generator's default now scales with the scene: 0.85–2.56 m over Sponza).
for n in 262144 1048576; do
  printf 'gltf = "sponza_lite/Sponza.gltf"\n[camera]\nindex = 0\n[particles]\ncount = %s\nseed = 1\nemitters = 256\nradius = [0.5, 1.5]\nintensity = 0.2\n' $n >.bench/particles_$n.toml
done
nvidia-smi --query-gpu=name,driver_version --format=csv | tee "$out/gpu.txt"
# Timings compare configurations: the exposure is fixed (auto exposure's passes left out) unless
# FIX_EXPOSURE is set, empty to meter as `render` does with no flags.
run() { # name, frames, then render arguments
  local name=$1 frames=$2; shift 2
  echo "== $name"
  timeout 300 $bin render --width 1920 --height 1080 --warmup "${WARMUP:-50}" --frames "$frames" --timings \
    --timings-json "$out/$name.json" -o /tmp/$name.png ${FIX_EXPOSURE---exposure 0} "$@" 2>&1 | grep -v "^GPU\|^wrote"
}
bvh="--light-method bvh"
structures() {
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
}

# Every pipeline with every method, on the paper's 28k small lights and on 100k decals of the default
# size (about one scene unit) and of 0.3 m. Brute force runs 3 frames after 1: seconds each.
matrix_lights() {
  local p m
  for p in visbuffer deferred forward; do
    for m in off bvh clustered; do
      run "lights_${p}_$m" 200 --scene .bench/small_28000.toml --pipeline $p --light-method $m --decal-method off
    done
    # Lights that move every frame: the BVH rebuilt on the GPU, as the clustered lists are.
    run "lights_${p}_bvh-gpu" 200 --scene .bench/small_28000.toml --pipeline $p --light-method bvh --light-bvh-build gpu-every-frame --decal-method off
    WARMUP=1 run "lights_${p}_brute" 3 --scene .bench/small_28000.toml --pipeline $p --light-method brute --decal-method off
  done
}

matrix_decals() {
  local p m
  for p in visbuffer deferred forward; do
    for m in off bvh clustered deferred-decals; do
      [ $m = deferred-decals ] && [ $p != deferred ] && continue
      run "decals_${p}_$m" 200 --scene $sponza --decals 100000 --seed 1 --pipeline $p --light-method off --decal-method $m
      [ $m = bvh ] && run "decals_${p}_bvh-gpu" 200 --scene $sponza --decals 100000 --seed 1 --pipeline $p --light-method off \
        --decal-method bvh --decal-bvh-build gpu-every-frame
      [ $m = off ] && continue
      run "decals03_${p}_$m" 200 --scene $sponza --decals 100000 --decal-size 0.3 --seed 1 --pipeline $p --light-method off --decal-method $m
    done
    WARMUP=1 run "decals_${p}_brute" 3 --scene $sponza --decals 100000 --seed 1 --pipeline $p --light-method off --decal-method brute
  done
}

# 262,144 and 1,048,576 moving particle lights from 256 emitters over Sponza, splatted into 1 m (and
# 0.5 m) voxels, in every pipeline; no other local lights or decals.
particles() {
  local n p
  for n in 262144 1048576; do
    for p in visbuffer deferred forward; do
      run "particles_${n}_$p" 200 --scene .bench/particles_$n.toml --pipeline $p --light-method off --decal-method off
    done
    run "particles_${n}_visbuffer_half_metre" 200 --scene .bench/particles_$n.toml --particle-voxel-size 0.5 \
      --light-method off --decal-method off
    # The exact method: every particle a point light in the light BVH, rebuilt every frame.
    for p in visbuffer deferred forward; do
      run "particles_${n}_${p}_exact" 100 --scene .bench/particles_$n.toml --pipeline $p --particle-method bvh \
        --light-method bvh --decal-method off
    done
  done
  echo "== particle-error 262144"
  timeout 300 $bin particle-error --scene .bench/particles_262144.toml --width 1920 --height 1080 \
    --voxel-sizes 1,0.5,0.25 --filters nearest,trilinear,tricubic --samples 1,8 2>&1 | grep -v "^GPU"
}

# The particles as exact lights (the lights' BVH rebuilt every frame, walked a subgroup at a time in
# the compute pipelines); the forward pipeline's fragments take seconds a frame, so few of them.
exact() {
  local n p
  for n in 262144 1048576; do
    for p in visbuffer deferred; do
      WARMUP=10 run "exact_${n}_$p" 60 --scene .bench/particles_$n.toml --pipeline $p --particle-method bvh \
        --light-method bvh --decal-method off
    done
  done
  WARMUP=1 run exact_262144_forward 3 --scene .bench/particles_262144.toml --pipeline forward --particle-method bvh \
    --light-method bvh --decal-method off
}

# Camera-centred clipmap cascades against the one grid over the scene, 1M particles.
clipmap() {
  local n=1048576 v
  for v in 1 0.5; do
    run "particles_${n}_visbuffer_world_$v" 200 --scene .bench/particles_$n.toml --particle-voxel-size $v \
      --light-method off --decal-method off
    run "particles_${n}_visbuffer_clipmap4x64_$v" 200 --scene .bench/particles_$n.toml --particle-voxel-size $v \
      --particle-cascades 4 --particle-cascade-resolution 64 --light-method off --decal-method off
  done
  echo "== particle-error 262144, cascades"
  timeout 300 $bin particle-error --scene .bench/particles_262144.toml --width 1920 --height 1080 \
    --voxel-sizes 1,0.5 --filters trilinear --samples 1 --cascades 0,2,4 --cascade-resolution 64 2>&1 | grep -v "^GPU"
}

# Ray-traced effects on Sponza at noon (the sun through the open roof), every pipeline: shadows hard
# and soft, reflections below the default roughness threshold and on every surface (the worst case),
# one and two bounces, and with the paper's 28k small lights, which reflections' hits are lit by.
rays() {
  local p
  printf 'gltf = "sponza_lite/Sponza.gltf"\nsky = "off"\n[camera]\nindex = 0\n[sun]\ndirection = [0.25, -1.0, 0.15]\nilluminance = 2.5\n' >.bench/sun.toml
  cp .bench/sun.toml .bench/sun_small_28000.toml
  printf '[[scatter_lights]]\ncount = 28000\nseed = 1\nrange = [0.1, 0.3]\n' >>.bench/sun_small_28000.toml
  local sun=.bench/sun.toml off="--light-method off --decal-method off"
  for p in visbuffer deferred forward; do
    run "rays_${p}_none" 200 --scene $sun --pipeline $p $off
    run "rays_${p}_hard" 200 --scene $sun --pipeline $p $off --shadows hard
    run "rays_${p}_hard_reflections" 200 --scene $sun --pipeline $p $off --shadows hard --reflections
  done
  run rays_visbuffer_soft4 200 --scene $sun $off --shadows soft --shadow-rays 4
  run rays_visbuffer_soft16 200 --scene $sun $off --shadows soft --shadow-rays 16
  run rays_visbuffer_reflections 200 --scene $sun $off --reflections
  run rays_visbuffer_reflections_2 200 --scene $sun $off --reflections --bounces 2
  run rays_visbuffer_reflections_all 200 --scene $sun $off --reflections --reflection-roughness 1
  run rays_visbuffer_reflections_all_2 200 --scene $sun $off --reflections --reflection-roughness 1 --bounces 2
  # 32 lamps that cast shadows along the atrium (range 6 m), with 1 and 4 shadow rays per point.
  cp .bench/sun.toml .bench/sun_lamps.toml
  local i
  for i in $(seq 0 31); do
    printf '[[lights]]\ntype = "point"\nposition = [%s, %s, %s]\nintensity = 4.0\nrange = 6.0\n' \
      "$(( (i % 8) * 3 - 11 )).0" "$(( 1 + (i / 8) % 2 * 5 )).5" "$(( (i / 16) * 6 - 3 )).0" >>.bench/sun_lamps.toml
  done
  run rays_visbuffer_lamps_none 200 --scene .bench/sun_lamps.toml --light-method bvh --decal-method off
  run rays_visbuffer_lamps_shadows1 200 --scene .bench/sun_lamps.toml --light-method bvh --decal-method off --light-shadow-rays 1
  run rays_visbuffer_lamps_shadows4 200 --scene .bench/sun_lamps.toml --light-method bvh --decal-method off --light-shadow-rays 4
  run rays_visbuffer_lamps_all 200 --scene .bench/sun_lamps.toml --light-method bvh --decal-method off --light-shadow-rays 4 \
    --shadows hard --reflections
  run rays_visbuffer_lights_none 200 --scene .bench/sun_small_28000.toml --light-method bvh --decal-method off
  run rays_visbuffer_lights_hard_reflections 200 --scene .bench/sun_small_28000.toml --light-method bvh --decal-method off --shadows hard --reflections
  run rays_visbuffer_lights_hard_reflections_all 200 --scene .bench/sun_small_28000.toml --light-method bvh --decal-method off --shadows hard \
    --reflections --reflection-roughness 1
}

# Each post effect alone and all together, over the sunlit Sponza with hard shadows; motion blur with
# a still camera (every pixel's blur is zero: the gather is skipped) and with the camera moving at
# 1.5 m/s (every pixel gathers).
post() {
  printf 'gltf = "sponza_lite/Sponza.gltf"\nsky = "off"\n[camera]\nindex = 0\n[sun]\ndirection = [0.25, -1.0, 0.15]\nilluminance = 2.5\n' >.bench/sun.toml
  local sun=".bench/sun.toml --light-method off --decal-method off --shadows hard"
  run post_none 200 --scene $sun
  run post_auto_exposure 200 --scene $sun --auto-exposure
  run post_bloom 200 --scene $sun --bloom
  run post_depth_of_field 200 --scene $sun --depth-of-field
  run post_motion_blur_still 200 --scene $sun --motion-blur
  # The camera moves 1.5 m/s along x: 10 + 60 frames keep it inside the atrium.
  WARMUP=10 run post_motion_blur_moving 60 --scene $sun --motion-blur --camera-velocity 1.5,0,0
  run post_vignette 200 --scene $sun --vignette 1
  WARMUP=10 run post_all_moving 60 --scene $sun --auto-exposure --bloom --depth-of-field --motion-blur --vignette 1 \
    --camera-velocity 1.5,0,0
}

# Sponza's curtains (6 meshes, 28,416 triangles, their BLASes stored twice) waving: vertices moved and BLASes refitted
# on the GPU every frame; with hard sun shadows and reflections tracing them.
deform() {
  printf 'gltf = "sponza_lite/Sponza.gltf"\nsky = "off"\n[camera]\nindex = 0\n[sun]\ndirection = [0.25, -1.0, 0.15]\nilluminance = 2.5\n' >.bench/sun.toml
  for mesh in Curtain Curtain2; do
    printf '[[deform]]\nmesh = "%s"\namplitude = 0.08\nwavelength = 1.5\nspeed = 0.8\ndirection = [0.0, 1.0, 0.0]\n' $mesh
  done | cat .bench/sun.toml - >.bench/curtains.toml
  local off="--light-method off --decal-method off"
  run deform_still 200 --scene .bench/sun.toml $off --shadows hard --reflections
  run deform_curtains 200 --scene .bench/curtains.toml $off --shadows hard --reflections
  run deform_curtains_no_rays 200 --scene .bench/curtains.toml $off
  # A skinned, morphed tube (scripts/make-bench-scenes.py) posed every frame.
  if [ -f .bench/skin/tube.gltf ]; then
    run deform_tube 200 --scene .bench/skin/tube.gltf --shadows hard
    run deform_tube_no_rays 200 --scene .bench/skin/tube.gltf
  fi
}

# The material extensions' path, vertex colours, the second UV set, transmission and sheen: Sponza
# with every material coated, every vertex coloured, every texture on TEXCOORD_1, fabrics and vases
# transmissive, or fabrics with a sheen (scripts/make-bench-scenes.py), against Sponza as it is; 28k
# lights, every pipeline. Then GasStation's blended surfaces (from .bench/assets, as for `assets`).
materials() {
  local s p
  for s in lite coated colored uv1 glass sheen; do
    printf 'gltf = "sponza_%s/Sponza.gltf"\nsky = "off"\n[camera]\nindex = 0\n[sun]\ndirection = [0.25, -1.0, 0.15]\nilluminance = 2.5\n' $s >.bench/sun_$s.toml
    for p in visbuffer deferred forward; do
      run materials_${s}_$p 200 --scene .bench/sun_$s.toml --lights 28000 --seed 1 --light-method bvh --decal-method off --pipeline $p
    done
  done
  # With no flags, 28k lights and 100k decals.
  for p in visbuffer deferred forward; do
    for s in own "lights 28000" "decals 100000"; do
      set -- $s
      FIX_EXPOSURE= WARMUP=10 run materials_blended_${1}_$p 50 --scene .bench/assets/gas_station/GasStation.gltf --pipeline $p \
        ${2:+--$1 $2 --seed 1}
    done
  done
}

# Many draws: a cube a draw, 1,024 to 40,000 of them (scripts/make-bench-scenes.py), every pipeline,
# seen from above (all in view) and from among 40,000 (most outside the view); the JSON holds the
# CPU's time per frame beside the GPU's.
draws() {
  local n p
  printf 'gltf = "cubes_40000.gltf"\n[camera]\nposition = [0.0, 1.5, 0.0]\ntarget = [10.0, 1.0, 0.0]\n' >.bench/many/inside_40000.toml
  for p in visbuffer deferred forward; do
    for n in 1024 10000 40000; do
      run draws_${n}_$p 200 --scene .bench/many/cubes_$n.gltf --pipeline $p
    done
    run draws_inside_40000_$p 200 --scene .bench/many/inside_40000.toml --pipeline $p
  done
}

# Test binaries built with `cargo test --release --no-run`, run here against the GPU, each test in its
# own process (after a dozen devices opened and closed in one process, the NVIDIA driver listed no
# adapter to the next).
tests() {
  local binary test
  for binary in .bench/tests/*; do
    echo "== $binary"
    for test in $("$binary" --list 2>/dev/null | sed -n 's/: test$//p'); do
      WGPU_ADAPTER_NAME=nvidia "$binary" --exact "$test" 2>&1 | grep -E -A2 "^test |panicked" | grep -v "^stack backtrace\|^--$\|^$"
    done
  done
}

# 10,000 frames at 1080p with animated groups of lights and decals rebuilt on the GPU every frame and
# 262,144 exact particle lights: process and GPU memory sampled once a second (scripts/soak.sh).
soak() {
  echo "== soak"
  FRAMES=${SOAK_FRAMES:-10000}
  scripts/soak.sh render $bin $sponza "$out/soak" "$FRAMES"
  tail -n 3 "$out/soak/render-soak.log"
}

# Each scene with no flags (auto methods, auto exposure, as a new user runs it) against every explicit
# method of what it varies, the rest left at the defaults: the scene's own lights, 28,000 scattered
# lights, 100,000 scattered decals.
assets() {
  local scene name variant m
  for scene in $sponza $(ls .bench/assets/*/*.glb .bench/assets/*/*.gltf 2>/dev/null | sort -u -t/ -k3,3); do
    name=$(basename "${scene%.*}")
    for variant in own lights decals; do
      local extra="" flag="--light-method"
      case $variant in
        lights) extra="--lights 28000 --seed 1" ;;
        decals) extra="--decals 100000 --seed 1"; flag="--decal-method" ;;
      esac
      FIX_EXPOSURE= WARMUP=10 run "assets_${name}_${variant}_none" 50 --scene "$scene" $extra
      for m in off brute bvh clustered; do
        # A loop over 28k lights or 100k decals runs 30 to 500 times slower: fewer frames time it.
        if [ $m = brute ] && [ $variant != own ]; then
          FIX_EXPOSURE= WARMUP=2 run "assets_${name}_${variant}_$m" 10 --scene "$scene" $extra $flag $m
        else
          FIX_EXPOSURE= WARMUP=10 run "assets_${name}_${variant}_$m" 50 --scene "$scene" $extra $flag $m
        fi
      done
    done
  done
}

# The bench command's own report (bench.md, .json, .csv, plots) lands in the archive under bench-<set>/.
# Shadowed local lights (issue 34): scenes/shadowed-lights.toml (4,096 lights of 1–3 m) and the
# paper's 28k small lights, each light found lighting the point unshadowed (exact), with a shadow ray
# of its own (reference) or sampled with one and four shadow rays (restir), restir in every pipeline;
# and how restir and the reference grow from 256 to 65,536 lights of the same ranges.
direct() {
  local p n scene=.bench/shadowed_4096.toml
  sed 's#"../../shared/assets/sponza/Sponza.gltf"#"sponza_lite/Sponza.gltf"#' scenes/shadowed-lights.toml >$scene
  for p in visbuffer deferred forward; do
    run "direct_${p}_4096_exact" 100 --scene $scene --pipeline $p --direct-lighting exact
    run "direct_${p}_4096_restir1" 100 --scene $scene --pipeline $p
  done
  run direct_visbuffer_4096_restir1_sampled 100 --scene $scene --denoise off
  run direct_visbuffer_4096_restir1_spatiotemporal 100 --scene $scene --restir-reuse spatiotemporal
  run direct_visbuffer_4096_restir4 100 --scene $scene --restir-shadow-rays 4
  run direct_visbuffer_4096_reference 30 --scene $scene --direct-lighting reference
  run direct_deferred_4096_reference 30 --scene $scene --pipeline deferred --direct-lighting reference
  for n in 256 1024 16384 65536; do
    sed "s/^count = 4096/count = $n/" $scene >.bench/shadowed_$n.toml
    run "direct_visbuffer_${n}_exact" 100 --scene .bench/shadowed_$n.toml --direct-lighting exact
    run "direct_visbuffer_${n}_restir1" 100 --scene .bench/shadowed_$n.toml
    run "direct_visbuffer_${n}_reference" 20 --scene .bench/shadowed_$n.toml --direct-lighting reference
  done
  run direct_visbuffer_small28k_exact 100 --scene .bench/small_28000.toml --direct-lighting exact
  run direct_visbuffer_small28k_restir1 100 --scene .bench/small_28000.toml --direct-lighting restir
  run direct_visbuffer_small28k_reference 30 --scene .bench/small_28000.toml --direct-lighting reference
}

# Animated instances under restir: GasStation (.bench/assets/gas_station) with 4,096 scattered lights;
# reuse records where its moving surfaces were (`surface_motion`), which reuse off does not need.
moving() {
  local scene=.bench/assets/gas_station/GasStation.gltf
  run moving_gasstation_4096_exact 100 --scene $scene --lights 4096 --seed 1 --direct-lighting exact
  run moving_gasstation_4096_restir1 100 --scene $scene --lights 4096 --seed 1 --direct-lighting restir
  run moving_gasstation_4096_restir1_sampled 100 --scene $scene --lights 4096 --seed 1 --direct-lighting restir --denoise off
  run moving_gasstation_4096_restir1_no_reuse 100 --scene $scene --lights 4096 --seed 1 --direct-lighting restir --denoise off --restir-reuse off
}

# restir's candidates drawn through the light tree against the enumeration, on the shadowed-lights
# scene from 256 to 65,536 lights, and the error of each at 960×540 (`light-error`).
tree() {
  local n c scene=.bench/shadowed.toml
  sed 's#"../../shared/assets/sponza/Sponza.gltf"#"sponza_lite/Sponza.gltf"#' scenes/shadowed-lights.toml >$scene
  for n in ${TREE_COUNTS:-256 1024 4096 16384 65536}; do
    sed "s/^count = 4096/count = $n/" $scene >.bench/shadowed_$n.toml
    for c in enumeration tree; do
      run "tree_visbuffer_${n}_${c}" 100 --scene .bench/shadowed_$n.toml --restir-candidates $c
      run "tree_visbuffer_${n}_${c}_sampled" 100 --scene .bench/shadowed_$n.toml --restir-candidates $c --denoise off
    done
  done
  for n in 4096 65536; do
    for c in enumeration tree; do
      echo "== light-error $n $c"
      timeout 300 $bin light-error --scene .bench/shadowed_$n.toml --width 960 --height 540 --frames 16 \
        --restir-candidates $c --json "$out/tree_light_error_${n}_${c}.json" | tail -4
    done
  done
}

# Shadowed particle lights (issue 35): exact (unshadowed), restir through the light tree and through
# the enumeration (denoised and sampled), and the reference, then restir's error after 16 frames
# against the reference (`particle-error --restir-frames`), at 1920×1080.
particle_tree() {
  local n c p="--light-method bvh --particle-method bvh --direct-lighting"
  for n in ${PARTICLE_COUNTS:-262144 1048576}; do
    run "ptree_${n}_exact" 100 --scene .bench/particles_$n.toml $p exact
    for c in tree enumeration; do
      run "ptree_${n}_${c}" 100 --scene .bench/particles_$n.toml $p restir --restir-candidates $c
      run "ptree_${n}_${c}_sampled" 100 --scene .bench/particles_$n.toml $p restir --restir-candidates $c --denoise off
    done
    WARMUP=2 run "ptree_${n}_reference" 5 --scene .bench/particles_$n.toml $p reference
    for c in tree enumeration; do
      echo "== particle-error $n $c"
      timeout 300 $bin particle-error --scene .bench/particles_$n.toml --width 1920 --height 1080 --voxel-sizes 0.25 \
        --filters tricubic --samples 8 --restir-frames 16 --restir-candidates $c | tail -5
    done
  done
}

# restir's error against the reference (`light-error`), sampled and denoised: 4,096 lights at
# 1920×1080, and 256 to 65,536 lights at 960×540.
direct_error() {
  local n scene=.bench/shadowed_4096.toml
  sed 's#"../../shared/assets/sponza/Sponza.gltf"#"sponza_lite/Sponza.gltf"#' scenes/shadowed-lights.toml >$scene
  echo "== light-error 4096"
  timeout 300 $bin light-error --scene $scene --width 1920 --height 1080 --frames 16 --json "$out/light_error_4096.json" | tail -4
  for n in 256 1024 16384 65536; do
    sed "s/^count = 4096/count = $n/" $scene >.bench/shadowed_$n.toml
    echo "== light-error $n (960×540)"
    timeout 200 $bin light-error --scene .bench/shadowed_$n.toml --width 960 --height 540 --frames 16 --json "$out/light_error_$n.json" | tail -4
  done
}

bench() { # set name, then bench arguments
  local name=$1; shift
  echo "== bench $name"
  timeout 570 $bin bench --scene $sponza --out "$out/bench-$name" "$@" && cat "$out/bench-$name/bench.md"
}

for set in "${@:-structures}"; do
  case $set in
    structures) structures ;;
    lights) matrix_lights ;;
    decals) matrix_decals ;;
    tests) tests ;;
    particles) particles ;;
    clipmap) clipmap ;;
    exact) exact ;;
    rays) rays ;;
    post) post ;;
    deform) deform ;;
    materials) materials ;;
    draws) draws ;;
    soak) soak ;;
    direct) direct ;;
    direct_error) direct_error ;;
    table) bench table --sweeps none --dense none ;;
    sweeps)
      bench sweeps --scenes none --dense none
      # Decals where fragments and the G-buffer shade them differently from the visibility buffer.
      bench sweeps_deferred --scenes none --dense none --sweeps decals --sweep-pipeline deferred
      bench sweeps_forward --scenes none --dense none --sweeps decals --sweep-max 262144 --sweep-pipeline forward ;;
    sweeps_once)
      bench sweeps_once --scenes none --dense none --sweep-build cpu-once
      bench sweeps_once_deferred --scenes none --dense none --sweeps decals --sweep-pipeline deferred --sweep-build cpu-once
      bench sweeps_once_forward --scenes none --dense none --sweeps decals --sweep-max 262144 --sweep-pipeline forward --sweep-build cpu-once ;;
    dense) bench dense --scenes none --sweeps none ;;
    assets) assets ;;
    moving) moving ;;
    tree) tree ;;
    particle_tree) particle_tree ;;
    *) echo "unknown set $set (structures, lights, decals, tests, table, sweeps, sweeps_once, dense, assets, particles, exact, clipmap, rays, post, deform, soak, direct, direct_error, moving, tree or particle_tree)" >&2; exit 2 ;;
  esac
done
tar -C "$out" -czf "${OUT:-/tmp/out}/timings.tgz" .
