//! Acceleration structures over the volumes of lights (and, later, decals), after Hansen & Peters,
//! "Rendering Decals and Many Lights with Ray Tracing Acceleration Structures" (i3D 2021): one AABB
//! per volume in a BVH, and at each shading point a point query (the paper's "zero-length ray")
//! that visits exactly the AABBs containing the point, followed by the volume's tight test.
//!
//! `bvh.rs` holds the node layout shared with WGSL (`accel/bvh.wgsl`) and the CPU builder and query,
//! which serve static sets and are the oracle for the GPU. `volumes.rs` bounds each light's volume.
//! `gpu.rs` uploads a light BVH as bind group 2 for `shading/enumerate/bvh.wgsl`; `lbvh.rs` builds
//! BVHs on the GPU (Karras LBVH) in the same layout.

pub mod bvh;
pub mod gpu;
pub mod lbvh;
pub mod volumes;

pub use bvh::{Bvh, BvhNode, LEAF, MAX_DEPTH, MAX_LEAF_SIZE};
pub use gpu::BvhBuild;
pub use volumes::{light_aabb, light_contains, Aabb};
