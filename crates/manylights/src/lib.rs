//! manylights: real-time rendering of many lights and decals through GPU-built acceleration structures.
//!
//! Data flows one way: [`scene`] (CPU scene) → [`gpu::GpuScene`] (uploaded buffers and textures) →
//! [`passes`] (one file per pass, WGSL beside it) → an image. [`pipelines`] holds the frame graphs that
//! order the passes; [`renderer::Renderer`] ties a device, a scene and a pipeline together.

pub mod accel;
pub mod config;
pub mod error;
pub mod files;
pub mod gpu;
pub mod image_io;
pub mod particles;
pub mod passes;
pub mod pipelines;
pub mod post;
pub mod rays;
pub mod renderer;
pub mod scene;

pub use error::{Error, Result};
