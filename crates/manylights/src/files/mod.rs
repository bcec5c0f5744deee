//! Files in and out, safely: every input is read bounded, every output is written whole or not at all.
//!
//! - [`read`]: only regular files, each kind under a size cap checked before reading, and a budget for
//!   all the bytes one scene load reads and decodes, so no input (a `/dev/zero` URI, a sparse 100 GB
//!   buffer) can exhaust memory.
//! - [`write`]: outputs checked before any work starts (format from the extension, an existing folder
//!   that takes files, a regular file or nothing at the path, no two outputs or an output and an input
//!   the same file), then written to a temporary file beside the target, synced and renamed over it, so
//!   a failure leaves the previous file as it was.
//! - [`guard`]: third-party parsers run inside a guard that turns a panic into an error naming the file.

pub mod guard;
pub mod read;
pub mod write;

pub use read::{read_input, InputKind, LoadBudget};
pub use write::{check_distinct, check_output, write_atomic, OutputFormat, OutputPlan, StagedOutputs};
