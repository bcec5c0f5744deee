//! manylights: real-time rendering of many lights and decals through GPU-built acceleration structures.
//!
//! Modules are layers, each importing only those below it (`tests/layering.rs` checks):
//! [`settings`] (what the caller chose) → [`scene`] (CPU scene) → [`gpu`] (device, uploaded
//! [`gpu::GpuScene`]) → [`plan`] (what to build, decided before anything is built) → [`accel`],
//! [`rays`], [`particles`] (structures built from the plan) → [`passes`] and [`post`] (one file per
//! pass, WGSL beside it) → [`pipelines`] (the frame graphs) → [`renderer::Renderer`], which ties a
//! device, a scene and a pipeline together.

pub mod accel;
pub mod error;
pub mod files;
pub mod gpu;
pub mod image_io;
pub mod particles;
pub mod passes;
pub mod pipelines;
pub mod plan;
pub mod post;
pub mod rays;
pub mod renderer;
pub mod scene;
pub mod settings;

pub use error::{Error, Result};
