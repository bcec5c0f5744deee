//! GPU plumbing: device context, the uploaded scene, per-frame uniforms, timestamps, readback and
//! shader composition (and, for a few shaders, their SPIR-V). Passes build on these; nothing here knows about a particular pipeline.

pub mod bindings;
pub mod cluster_grid;
pub mod context;
pub mod environment;
pub mod frame;
pub mod loop_limit;
pub mod readback;
pub mod scene;
pub mod shaders;
pub mod spirv;
pub mod textures;
pub mod timestamps;

pub use context::GpuContext;
pub use frame::FrameUniforms;
pub use scene::GpuScene;
pub use timestamps::{GpuTimer, PassTimings};
