//! One error type for the library. Every message names the problem and, where there is one, the fix:
//! the CLI prints it as is and exits non-zero.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    // `error` rather than `source`: its message is already part of this one, and must not be
    // printed again as a cause.
    #[error("cannot read {path}: {error} (check that the path exists and is readable)")]
    Io { path: PathBuf, error: std::io::Error },

    #[error("cannot read {path}: {reason}")]
    Input { path: PathBuf, reason: String },

    /// A third-party parser panicked on the file (`files::guard`): a check of ours is missing.
    #[error(
        "{path}: the {parser} failed on this file ({message}); the file is malformed: re-export it, or check it \
         with a validator for its format"
    )]
    ParserPanic { path: PathBuf, parser: &'static str, message: String },

    #[error("{path}: not a valid glTF 2.0 file: {reason}")]
    Gltf { path: PathBuf, reason: String },

    #[error(
        "{path}: the file requires the glTF extension `{extension}`, which manylights does not support; \
         re-export the scene without it (supported: {supported})"
    )]
    UnsupportedGltfExtension { path: PathBuf, extension: String, supported: String },

    #[error("{path}: {reason}")]
    SceneFile { path: PathBuf, reason: String },

    #[error("invalid scene: {0}")]
    InvalidScene(String),

    #[error("invalid settings: {0}")]
    InvalidConfig(String),

    #[error(
        "no usable GPU adapter found{detail}. Install a Vulkan driver: on Debian/Ubuntu without a GPU, \
         `sudo apt-get install mesa-vulkan-drivers` gives Mesa's software rasteriser (lavapipe); \
         `manylights info` lists what wgpu can see, and WGPU_ADAPTER_NAME / WGPU_BACKEND select one"
    )]
    NoAdapter { detail: String },

    #[error("the GPU reported an error: {0}")]
    Gpu(String),

    #[error("cannot write {path}: {reason}")]
    Output { path: PathBuf, reason: String },
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

/// A third-party message on one line: its lines joined, outer whitespace trimmed.
pub(crate) fn one_line(text: &str) -> String {
    text.lines().map(str::trim).filter(|l| !l.is_empty()).collect::<Vec<_>>().join("; ")
}
