// Re-encodes a glTF file's textures as KTX2 in Basis Universal (KHR_texture_basisu), with the
// ktx2-encoder package's glTF Transform transform (Basis Universal's own encoder, in WebAssembly).
// Usage: node gltf-ktx2.mjs <input> <output> <etc1s|uastc>; run by make-gltf-test-files.sh.
import { NodeIO } from "@gltf-transform/core";
import { ALL_EXTENSIONS } from "@gltf-transform/extensions";
import { ktx2 } from "ktx2-encoder/gltf-transform";
import sharp from "sharp";

const [input, output, mode] = process.argv.slice(2);
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS);
const document = await io.read(input);
const imageDecoder = async (buffer) => {
  const { data, info } = await sharp(buffer).ensureAlpha().raw().toBuffer({ resolveWithObject: true });
  return { data: new Uint8Array(data), width: info.width, height: info.height };
};
await document.transform(ktx2({ isUASTC: mode === "uastc", generateMipmap: false, imageDecoder }));
await io.write(output, document);
