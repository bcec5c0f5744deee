// Group 2: the lights and their acceleration structure (`accel/structure.rs`, `VolumeStructure`).
// Lights are stored group after group in their group's space; `light_instances` place the groups.
#include "shading/types.wgsl"
#include "accel/bvh_types.wgsl"

@group(2) @binding(0) var<storage, read> lights: array<Light>;
@group(2) @binding(1) var<storage, read> light_nodes: array<BvhNode>;
@group(2) @binding(2) var<storage, read> light_primitives: array<u32>;
@group(2) @binding(3) var<storage, read> light_instances: array<VolumeInstance>;
// The clustered method's lists (`accel/clusters.rs`), rebuilt every frame: per froxel the range of
// its entries, and the entries as (instance, light) pairs. One-element placeholders for other methods.
@group(2) @binding(4) var<storage, read> light_cluster_ranges: array<vec2<u32>>;
@group(2) @binding(5) var<storage, read> light_cluster_entries: array<vec2<u32>>;
@group(2) @binding(6) var<uniform> light_first_instance: FirstInstance;
// Each light-structure node's emitters (`accel/light_tree.rs`), where `restir` draws its candidates
// through the light tree (`shading/light_tree.wgsl`); one placeholder otherwise.
@group(2) @binding(7) var<storage, read> light_tree: array<LightTreeNode>;
