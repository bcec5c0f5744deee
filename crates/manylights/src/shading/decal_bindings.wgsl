// Group 3: the decals and their acceleration structure (`accel/structure.rs`, `VolumeStructure`).
// Decals are stored group after group in their group's space; `decal_instances` place the groups.
#include "shading/types.wgsl"
#include "accel/bvh_types.wgsl"

@group(3) @binding(0) var<storage, read> decals: array<Decal>;
@group(3) @binding(1) var<storage, read> decal_nodes: array<BvhNode>;
@group(3) @binding(2) var<storage, read> decal_primitives: array<u32>;
@group(3) @binding(3) var<storage, read> decal_instances: array<VolumeInstance>;
// The clustered method's lists (`accel/clusters.rs`), rebuilt every frame: per froxel the range of
// its entries, and the entries as (instance, decal) pairs. One-element placeholders for other methods.
@group(3) @binding(4) var<storage, read> decal_cluster_ranges: array<vec2<u32>>;
@group(3) @binding(5) var<storage, read> decal_cluster_entries: array<vec2<u32>>;
@group(3) @binding(6) var<uniform> decal_first_instance: FirstInstance;
