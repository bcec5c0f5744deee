#!/usr/bin/env python3
"""Makes the device bench's generated glTF scenes under .bench/ (run here, before carrying .bench to
the GPU machine; scripts/bench-device.sh reads them):

  .bench/skin/tube.gltf       a skinned, morphed tube: 512 rings of 256 vertices up 8 m, 16 joints in
                              a chain bending over a 2 s loop, every vertex weighted to its two
                              nearest joints, one morph target bulging it; a 20 m floor (`deform`)
  .bench/sponza_coated/       sponza_lite with every material coated: clear coat 0.5 (roughness 0.1),
                              ior 1.7, specular 0.8 tinted (1, 0.9, 0.8), textures shared (`materials`)
  .bench/sponza_colored/      sponza_lite with a COLOR_0 (RGBA unorm8, pale tints varying vertex by vertex)
                              on every primitive, buffers and textures shared (`materials`)
  .bench/sponza_uv1/          sponza_lite with every texture read through TEXCOORD_1 (TEXCOORD_0's
                              accessor named again), buffers and textures shared (`materials`)
  .bench/sponza_glass/        sponza_lite with its fabrics and vases transmissive: transmission 0.9, ior 1.5, a
                              medium 2 cm deep tinted (0.9, 0.8, 0.6) after 5 cm (`materials`)
  .bench/sponza_sheen/        sponza_lite with its fabrics given a sheen of (0.8, 0.7, 0.6), roughness 0.5
                              (`materials`)
  .bench/many/cubes_N.gltf    N = 1,024, 10,000 and 40,000 cubes of 0.4 m, a draw each, on a grid 1 m
                              apart over a floor (EXT_mesh_gpu_instancing) (`draws`)
"""
import json
import math
import os
import struct


def tube(out):
    rings, sides, joints, height = 512, 256, 16, 8.0
    pos, nor, jts, wts, bulge, idx = [], [], [], [], [], []
    for r in range(rings):
        y = height * r / (rings - 1)
        f = y / height * (joints - 1)
        j0 = min(int(f), joints - 2)
        t = f - j0
        for s in range(sides):
            a = 2 * math.pi * s / sides
            pos += [0.3 * math.cos(a), y, 0.3 * math.sin(a)]
            nor += [math.cos(a), 0.0, math.sin(a)]
            jts += [j0, j0 + 1, 0, 0]
            wts += [1 - t, t, 0.0, 0.0]
            b = 0.15 * math.sin(math.pi * y / height)
            bulge += [b * math.cos(a), 0.0, b * math.sin(a)]
    for r in range(rings - 1):
        for s in range(sides):
            a, b = r * sides + s, r * sides + (s + 1) % sides
            idx += [a, a + sides, b, b, a + sides, b + sides]
    n = rings * sides
    keys = 9
    inverse_bind = []
    for j in range(joints):
        inverse_bind += [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -height * j / (joints - 1), 0, 1]
    turns = []
    for k in range(keys):
        angle = 0.12 * math.sin(2 * math.pi * k / (keys - 1))
        turns += [0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2)]
    blobs = [
        struct.pack(f"<{len(pos)}f", *pos), struct.pack(f"<{len(nor)}f", *nor), struct.pack(f"<{len(jts)}B", *jts),
        struct.pack(f"<{len(wts)}f", *wts), struct.pack(f"<{len(bulge)}f", *bulge), struct.pack(f"<{len(idx)}I", *idx),
        struct.pack(f"<{len(inverse_bind)}f", *inverse_bind),
        struct.pack(f"<{keys}f", *[2.0 * k / (keys - 1) for k in range(keys)]),
        struct.pack(f"<{len(turns)}f", *turns),
        struct.pack(f"<{keys}f", *[0.5 + 0.5 * math.sin(2 * math.pi * k / (keys - 1)) for k in range(keys)]),
        struct.pack("<12f", -10, 0, -10, 10, 0, -10, 10, 0, 10, -10, 0, 10),
        struct.pack("<12f", *([0, 1, 0] * 4)),
        struct.pack("<6I", 0, 2, 1, 0, 3, 2),
    ]
    buffer, views = b"", []
    for blob in blobs:
        buffer += b"\0" * ((-len(buffer)) % 4)
        views.append({"buffer": 0, "byteOffset": len(buffer), "byteLength": len(blob)})
        buffer += blob

    def accessor(view, component, count, kind, **more):
        return dict(bufferView=view, componentType=component, count=count, type=kind, **more)

    accessors = [
        accessor(0, 5126, n, "VEC3", min=[-0.3, 0, -0.3], max=[0.3, height, 0.3]), accessor(1, 5126, n, "VEC3"),
        accessor(2, 5121, n, "VEC4"), accessor(3, 5126, n, "VEC4"), accessor(4, 5126, n, "VEC3"),
        accessor(5, 5125, len(idx), "SCALAR"), accessor(6, 5126, joints, "MAT4"),
        accessor(7, 5126, keys, "SCALAR", min=[0.0], max=[2.0]), accessor(8, 5126, keys, "VEC4"), accessor(9, 5126, keys, "SCALAR"),
        accessor(10, 5126, 4, "VEC3", min=[-10, 0, -10], max=[10, 0, 10]), accessor(11, 5126, 4, "VEC3"), accessor(12, 5125, 6, "SCALAR"),
    ]
    nodes = [{"mesh": 0, "skin": 0}, {"mesh": 1}]
    for j in range(joints):
        node = {"translation": [0, 0 if j == 0 else height / (joints - 1), 0]}
        if j + 1 < joints:
            node["children"] = [3 + j]
        nodes.append(node)
    channels = [{"sampler": 0, "target": {"node": 2 + j, "path": "rotation"}} for j in range(joints)]
    channels.append({"sampler": 1, "target": {"node": 0, "path": "weights"}})
    document = {
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}], "nodes": nodes,
        "meshes": [
            {"weights": [0.0], "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "JOINTS_0": 2, "WEIGHTS_0": 3},
                                               "indices": 5, "targets": [{"POSITION": 4}]}]},
            {"primitives": [{"attributes": {"POSITION": 10, "NORMAL": 11}, "indices": 12}]},
        ],
        "skins": [{"joints": list(range(2, 2 + joints)), "inverseBindMatrices": 6}],
        "animations": [{"channels": channels, "samplers": [{"input": 7, "output": 8}, {"input": 7, "output": 9}]}],
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(buffer), "uri": "tube.bin"}],
    }
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "tube.bin"), "wb") as f:
        f.write(buffer)
    with open(os.path.join(out, "tube.gltf"), "w") as f:
        json.dump(document, f)


def cubes(side, out):
    positions, normals, indices = [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            normal = [0.0, 0.0, 0.0]
            normal[axis] = sign
            u, v = [0.0] * 3, [0.0] * 3
            u[(axis + 1) % 3], v[(axis + 2) % 3] = 1.0, sign
            first = len(positions)
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                positions.append([0.2 * (normal[k] + su * u[k] + sv * v[k]) for k in range(3)])
                normals.append(normal)
            indices += [first, first + 1, first + 2, first, first + 2, first + 3]
    half = side / 2 + 5
    translations = [[i - side / 2, 0.2, j - side / 2] for i in range(side) for j in range(side)]
    floor = [[-half, 0, -half], [half, 0, -half], [half, 0, half], [-half, 0, half]]
    blobs = [
        b"".join(struct.pack("<3f", *p) for p in positions), b"".join(struct.pack("<3f", *n) for n in normals),
        struct.pack(f"<{len(indices)}I", *indices), b"".join(struct.pack("<3f", *t) for t in translations),
        b"".join(struct.pack("<3f", *p) for p in floor), struct.pack("<12f", *([0, 1, 0] * 4)), struct.pack("<6I", 0, 2, 1, 0, 3, 2),
    ]
    buffer, views = b"", []
    for blob in blobs:
        views.append({"buffer": 0, "byteOffset": len(buffer), "byteLength": len(blob)})
        buffer += blob
    vec3 = lambda view, count, **more: dict(bufferView=view, componentType=5126, count=count, type="VEC3", **more)
    document = {
        "asset": {"version": "2.0"}, "extensionsUsed": ["EXT_mesh_gpu_instancing"], "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 3}}}}, {"mesh": 1}],
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]},
            {"primitives": [{"attributes": {"POSITION": 4, "NORMAL": 5}, "indices": 6, "material": 0}]},
        ],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.7, 0.6, 1], "metallicFactor": 0}}],
        "accessors": [
            vec3(0, 24, min=[-0.2] * 3, max=[0.2] * 3), vec3(1, 24), dict(bufferView=2, componentType=5125, count=36, type="SCALAR"),
            vec3(3, len(translations)), vec3(4, 4, min=[-half, 0, -half], max=[half, 0, half]), vec3(5, 4),
            dict(bufferView=6, componentType=5125, count=6, type="SCALAR"),
        ],
        "bufferViews": views,
        "buffers": [{"byteLength": len(buffer), "uri": f"cubes_{side * side}.bin"}],
    }
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, f"cubes_{side * side}.bin"), "wb") as f:
        f.write(buffer)
    with open(os.path.join(out, f"cubes_{side * side}.gltf"), "w") as f:
        json.dump(document, f)


def sponza_copy(source):
    """sponza_lite's document, its buffers and images named from a sibling folder."""
    with open(source) as f:
        document = json.load(f)
    for item in document.get("buffers", []) + document.get("images", []):
        if "uri" in item:
            item["uri"] = "../sponza_lite/" + item["uri"]
    return document


def write_sponza(document, out):
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "Sponza.gltf"), "w") as f:
        json.dump(document, f)


def with_material_extensions(source, out, extensions, chosen=lambda material: True):
    """sponza_lite with `extensions` (name: object) on each material `chosen` accepts."""
    document = sponza_copy(source)
    for material in filter(chosen, document.get("materials", [])):
        material.setdefault("extensions", {}).update(extensions)
    document["extensionsUsed"] = sorted(set(document.get("extensionsUsed", [])) | set(extensions))
    write_sponza(document, out)


def coated(source, out):
    with_material_extensions(source, out, {
        "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.1},
        "KHR_materials_ior": {"ior": 1.7},
        "KHR_materials_specular": {"specularFactor": 0.8, "specularColorFactor": [1.0, 0.9, 0.8]},
    })


def colored(source, out):
    document = sponza_copy(source)
    colors = b""
    for mesh in document["meshes"]:
        for primitive in mesh["primitives"]:
            count = document["accessors"][primitive["attributes"]["POSITION"]]["count"]
            tints = [(195 + (i * 37) % 61, 195 + (i * 91) % 61, 215 + (i * 13) % 41, 255) for i in range(count)]
            view = {"buffer": len(document["buffers"]), "byteOffset": len(colors), "byteLength": 4 * count}
            colors += b"".join(struct.pack("<4B", *t) for t in tints)
            document["bufferViews"].append(view)
            document["accessors"].append(
                {"bufferView": len(document["bufferViews"]) - 1, "componentType": 5121, "normalized": True, "count": count, "type": "VEC4"}
            )
            primitive["attributes"]["COLOR_0"] = len(document["accessors"]) - 1
    document["buffers"].append({"byteLength": len(colors), "uri": "colors.bin"})
    write_sponza(document, out)
    with open(os.path.join(out, "colors.bin"), "wb") as f:
        f.write(colors)


def glass(source, out):
    with_material_extensions(source, out, {
        "KHR_materials_transmission": {"transmissionFactor": 0.9},
        "KHR_materials_volume": {"thicknessFactor": 0.02, "attenuationDistance": 0.05, "attenuationColor": [0.9, 0.8, 0.6]},
    }, lambda material: material.get("name", "").startswith(("Fabric", "Vase")))


def sheen(source, out):
    with_material_extensions(source, out, {
        "KHR_materials_sheen": {"sheenColorFactor": [0.8, 0.7, 0.6], "sheenRoughnessFactor": 0.5},
    }, lambda material: material.get("name", "").startswith("Fabric"))


def second_set(source, out):
    document = sponza_copy(source)
    for mesh in document["meshes"]:
        for primitive in mesh["primitives"]:
            attributes = primitive["attributes"]
            if "TEXCOORD_0" in attributes:
                attributes["TEXCOORD_1"] = attributes["TEXCOORD_0"]

    def reads_second(info):
        if isinstance(info, dict):
            if "index" in info:
                info["texCoord"] = 1
            for value in info.values():
                reads_second(value)

    for material in document.get("materials", []):
        reads_second(material)
    write_sponza(document, out)


if __name__ == "__main__":
    tube(".bench/skin")
    coated(".bench/sponza_lite/Sponza.gltf", ".bench/sponza_coated")
    colored(".bench/sponza_lite/Sponza.gltf", ".bench/sponza_colored")
    second_set(".bench/sponza_lite/Sponza.gltf", ".bench/sponza_uv1")
    glass(".bench/sponza_lite/Sponza.gltf", ".bench/sponza_glass")
    sheen(".bench/sponza_lite/Sponza.gltf", ".bench/sponza_sheen")
    for side in (32, 100, 200):
        cubes(side, ".bench/many")
