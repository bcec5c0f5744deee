//! Acceleration structures over the volumes of lights and decals, after Hansen & Peters,
//! "Rendering Decals and Many Lights with Ray Tracing Acceleration Structures" (i3D 2021): one AABB
//! per volume in a BVH, and at each shading point a point query (the paper's "zero-length ray")
//! that visits exactly the AABBs containing the point, followed by the volume's tight test.
//!
//! `bvh.rs` holds the node layout shared with WGSL (`accel/bvh_types.wgsl`) and the CPU builder and
//! query, which serve static groups and are the oracle for the GPU. `volumes.rs` bounds each light's
//! and decal's volume. `lbvh.rs` builds BVHs on the GPU (Karras LBVH) in the same layout, and
//! `leaf_order.rs` puts a rebuilt group's items in the order of its leaves.
//! `entry_grid.rs` tells a query where to start in a CPU-built group's BVH, `rebuilt_grid.rs` in a
//! rebuilt one's, and `cell_lists.rs` lists
//! what reaches each cell of a grid over a group of crowded volumes, which queries read instead.
//! `structure.rs` is the two-level structure the shaders query (`accel/volume_query.wgsl`): a BVH
//! per group of volumes and a top level over the groups' instances. `clusters.rs` builds the
//! clustered method's per-froxel lists, the baseline the structures are compared against.
//! `hardware.rs` is the same two levels built by wgpu as acceleration structures of boxes, for
//! adapters with ray queries (`settings::RayBackend`).

pub mod bvh;
pub mod cell_lists;
pub mod clusters;
pub mod entry_grid;
pub mod hardware;
pub mod lbvh;
pub mod leaf_order;
pub mod light_tree;
pub mod overlap;
pub mod radix_sort;
pub mod rebuilt_cell_lists;
pub mod rebuilt_grid;
pub mod structure;
pub mod volumes;

pub use bvh::{Bvh, BvhNode, END, LEAF, MAX_DEPTH, MAX_LEAF_SIZE};

/// The test probe of the point query (`volume_query_probe.wgsl`), walked per subgroup or per invocation.
pub fn volume_query_probe_shader(subgroups: bool) -> crate::gpu::shaders::ShaderDesc {
    crate::gpu::shaders::ShaderDesc::new("accel/volume_query_probe.wgsl").with("LIGHT_QUERY", crate::plan::volume_query_module(subgroups))
}
pub use structure::{check_scene_capacity, VolumeKind, VolumeStructure, Volumes, CPU_TOP_LEVEL_MAX_INSTANCES};
pub use volumes::{decal_aabb, decal_contains, light_aabb, light_contains, Aabb};
