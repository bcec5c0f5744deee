#!/usr/bin/env bash
# Makes the compressed glTF files the tests read (crates/manylights/tests/gltf/) from the shared
# assets, as a user's pipeline would: with the glTF Transform CLI (npm's @gltf-transform/cli, run by
# npx) and, for KTX2 textures, Basis Universal's encoder (npm's ktx2-encoder, `gltf-ktx2.mjs`); needs
# Node.js 18 or newer. The tests render each beside the file it was made from. Run it again after
# changing the list; the files are committed, so the tests need no Node.js.
set -euo pipefail
cd "$(dirname "$0")/.."
assets=${ASSETS:-../shared/assets}
out=crates/manylights/tests/gltf
cli=(npx --yes @gltf-transform/cli@4.5.1)
mkdir -p "$out"
# EXT_meshopt_compression (with KHR_mesh_quantization and the octahedral filter on normals).
"${cli[@]}" meshopt "$assets/duck/Duck.glb" "$out/duck-meshopt.glb"
# KHR_draco_mesh_compression (EdgeBreaker).
"${cli[@]}" draco "$assets/duck/Duck.glb" "$out/duck-draco.glb"
# KHR_mesh_quantization alone: 16-bit normalized positions and normals.
"${cli[@]}" quantize "$assets/box_textured/BoxTextured.glb" "$out/box_textured-quantized.glb"
# EXT_texture_webp (lossless).
"${cli[@]}" webp "$assets/box_textured/BoxTextured.glb" "$out/box_textured-webp.glb" --lossless true
# KHR_texture_basisu: ETC1S (BasisLZ) and UASTC.
tools=$(mktemp -d)
trap 'rm -rf "$tools"' EXIT
npm install --silent --prefix "$tools" @gltf-transform/core@4.5.1 @gltf-transform/extensions@4.5.1 ktx2-encoder@0.6.0 sharp@0.34
cp scripts/gltf-ktx2.mjs "$tools/"
for mode in etc1s uastc; do
  node "$tools/gltf-ktx2.mjs" "$assets/box_textured/BoxTextured.glb" "$out/box_textured-$mode.glb" "$mode" >/dev/null
done
