// Group 3: the decals and their acceleration structure (`accel/structure.rs`, `VolumeStructure`).
// Decals are stored group after group in their group's space; `decal_instances` place the groups.
#include "shading/types.wgsl"
#include "accel/bvh_types.wgsl"

@group(3) @binding(0) var<storage, read> decals: array<Decal>;
@group(3) @binding(1) var<storage, read> decal_nodes: array<BvhNode>;
@group(3) @binding(2) var<storage, read> decal_primitives: array<u32>;
@group(3) @binding(3) var<storage, read> decal_instances: array<VolumeInstance>;
