//! Bounded reads of scene inputs.
//!
//! A scene load holds at most [`MAX_LOAD_INPUT_BYTES`] of file data, [`MAX_LOAD_DECODED_BYTES`] of
//! decoded images (each image at most `IMAGE_DECODE_LIMIT_MIB` while it decodes) and
//! [`MAX_LOAD_GEOMETRY_BYTES`] of vertices and indices, whatever the files say about themselves: sizes
//! are checked against caps before a byte is read or a buffer allocated, and reads stop at the cap
//! even if the file grows meanwhile.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use crate::{Error, Result};

const MIB: u64 = 1 << 20;
const GIB: u64 = 1 << 30;

/// All file bytes one scene load may read (scene file, glTF, buffers, images).
pub const MAX_LOAD_INPUT_BYTES: u64 = 4 * GIB;
/// All decoded image bytes (RGBA8) one scene load may hold.
pub const MAX_LOAD_DECODED_BYTES: u64 = 4 * GIB;
/// All vertices and indices one scene load may build (a small file's accessors can name billions).
pub const MAX_LOAD_GEOMETRY_BYTES: u64 = 4 * GIB;

/// What an input is, which sets its size cap and how errors name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A TOML scene file.
    SceneFile,
    /// A `.gltf` file: JSON, which parses into many times its size, so capped lower.
    GltfJson,
    /// A `.glb` file: binary chunks and a JSON chunk (capped like a `.gltf`).
    Glb,
    /// A glTF buffer (`.bin`), read up to its declared byte length.
    Buffer,
    /// An encoded image (PNG, JPEG).
    Image,
}

impl InputKind {
    /// The largest file of this kind that is read.
    pub const fn cap(self) -> u64 {
        match self {
            InputKind::SceneFile => 16 * MIB,
            InputKind::GltfJson => 256 * MIB,
            InputKind::Glb => 2 * GIB,
            InputKind::Buffer => 2 * GIB,
            InputKind::Image => 256 * MIB,
        }
    }

    fn what(self) -> &'static str {
        match self {
            InputKind::SceneFile => "a scene file",
            InputKind::GltfJson => "a .gltf file (use .glb for large binary data)",
            InputKind::Glb => "a .glb file",
            InputKind::Buffer => "a glTF buffer",
            InputKind::Image => "an image",
        }
    }
}

/// Sizes for messages: "3.2 GiB", "512 MiB", "700 bytes".
pub fn human_bytes(bytes: u64) -> String {
    match bytes {
        b if b >= GIB => format!("{:.1} GiB", b as f64 / GIB as f64),
        b if b >= MIB => format!("{:.1} MiB", b as f64 / MIB as f64),
        b => format!("{b} bytes"),
    }
}

/// What one scene load has read and decoded so far, and the files it read. Shared by the threads that
/// decode images.
#[derive(Debug, Default)]
pub struct LoadBudget {
    read: AtomicU64,
    decoded: AtomicU64,
    files: Mutex<Vec<PathBuf>>,
}

impl LoadBudget {
    pub fn new() -> Self {
        Self::default()
    }

    /// Counts `bytes` of input (a file, or a data URI decoded in memory) against the load's budget.
    pub fn take_input(&self, bytes: u64, source: &Path) -> Result<()> {
        take(&self.read, bytes, MAX_LOAD_INPUT_BYTES).map_err(|total| Error::Input {
            path: source.to_owned(),
            reason: format!(
                "the scene's files add up to {} or more, over the {} one scene may read; give a smaller scene",
                human_bytes(total),
                human_bytes(MAX_LOAD_INPUT_BYTES)
            ),
        })
    }

    /// Counts an image's decoded bytes against the load's budget, before it is decoded.
    pub fn take_decoded(&self, bytes: u64) -> std::result::Result<(), String> {
        take(&self.decoded, bytes, MAX_LOAD_DECODED_BYTES).map_err(|total| {
            format!(
                "the scene's images decode to {} or more, over the {} one scene may hold; give smaller images",
                human_bytes(total),
                human_bytes(MAX_LOAD_DECODED_BYTES)
            )
        })
    }

    /// The files read so far, canonical, each once, in the order first read.
    pub fn files(&self) -> Vec<PathBuf> {
        self.files.lock().map(|f| f.clone()).unwrap_or_default()
    }

    fn record(&self, path: &Path) {
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_owned());
        if let Ok(mut files) = self.files.lock() {
            if !files.contains(&canonical) {
                files.push(canonical);
            }
        }
    }
}

fn take(counter: &AtomicU64, bytes: u64, cap: u64) -> std::result::Result<(), u64> {
    let before = counter.fetch_add(bytes, Ordering::Relaxed);
    let total = before.saturating_add(bytes);
    if total > cap {
        return Err(total);
    }
    Ok(())
}

/// Reads a whole input file of `kind`: a regular file (not a device, pipe or folder) of at most the
/// kind's cap, or, with `length`, its first `length` bytes (a glTF buffer's `byteLength`), which the
/// file must hold.
pub fn read_input(path: &Path, kind: InputKind, length: Option<u64>, budget: &LoadBudget) -> Result<Vec<u8>> {
    let fail = |reason: String| Error::Input { path: path.to_owned(), reason };
    let io = |error: std::io::Error| Error::Io { path: path.to_owned(), error };
    // Checked before opening: opening a pipe would wait for a writer.
    let metadata = std::fs::metadata(path).map_err(io)?;
    if !metadata.is_file() {
        let what = if metadata.is_dir() { "a folder" } else { "not a regular file (a device, pipe or socket)" };
        return Err(fail(format!("it is {what}, and only regular files are read; give the path of {}", kind.what())));
    }
    let cap = kind.cap();
    let wanted = match length {
        Some(length) if length > cap => {
            return Err(fail(format!(
                "its declared length of {} is over the {} manylights reads for {}; give a smaller scene",
                human_bytes(length),
                human_bytes(cap),
                kind.what()
            )))
        }
        Some(length) if length > metadata.len() => {
            return Err(fail(format!(
                "it has {} bytes, but the glTF file declares {length}; the file is truncated or the wrong one",
                metadata.len()
            )))
        }
        Some(length) => length,
        None if metadata.len() > cap => {
            return Err(fail(format!(
                "it has {}, over the {} manylights reads for {}; give a smaller file",
                human_bytes(metadata.len()),
                human_bytes(cap),
                kind.what()
            )))
        }
        None => metadata.len(),
    };
    budget.take_input(wanted, path)?;
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(wanted as usize);
    // One byte past what is wanted shows a file that grew past its cap while being read.
    let limit = if length.is_some() { wanted } else { cap + 1 };
    file.take(limit).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > cap {
        return Err(fail(format!("it grew past the {} manylights reads for {} while being read", human_bytes(cap), kind.what())));
    }
    if (bytes.len() as u64) < wanted {
        return Err(fail(format!("it ended after {} of its {wanted} bytes while being read", bytes.len())));
    }
    budget.record(path);
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::test_support::temp_dir;

    #[test]
    fn devices_pipes_and_folders_are_refused() {
        let budget = LoadBudget::new();
        for path in ["/dev/zero", "/dev/null", "/"] {
            let e = read_input(Path::new(path), InputKind::Image, None, &budget).unwrap_err().to_string();
            assert!(e.contains("only regular files are read"), "{e}");
        }
        assert_eq!(budget.files(), Vec::<PathBuf>::new());
    }

    #[test]
    fn a_sparse_file_over_the_cap_is_refused_before_reading() {
        let dir = temp_dir("sparse_input");
        let path = dir.join("huge.bin");
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(100 * GIB).unwrap();
        let budget = LoadBudget::new();
        let e = read_input(&path, InputKind::Buffer, Some(100 * GIB), &budget).unwrap_err().to_string();
        assert!(e.contains("100.0 GiB") && e.contains("2.0 GiB"), "{e}");
        let e = read_input(&path, InputKind::Image, None, &budget).unwrap_err().to_string();
        assert!(e.contains("over the 256.0 MiB"), "{e}");
    }

    #[test]
    fn a_declared_length_reads_that_many_bytes_and_no_more() {
        let dir = temp_dir("declared_length");
        let path = dir.join("b.bin");
        std::fs::write(&path, [1u8, 2, 3, 4, 5, 6]).unwrap();
        let budget = LoadBudget::new();
        assert_eq!(read_input(&path, InputKind::Buffer, Some(4), &budget).unwrap(), [1, 2, 3, 4]);
        let e = read_input(&path, InputKind::Buffer, Some(7), &budget).unwrap_err().to_string();
        assert!(e.contains("has 6 bytes, but the glTF file declares 7"), "{e}");
        assert_eq!(budget.files(), vec![path.canonicalize().unwrap()]);
    }

    #[test]
    fn the_load_budget_caps_all_reads_together() {
        let budget = LoadBudget::new();
        budget.take_input(MAX_LOAD_INPUT_BYTES - 10, Path::new("a")).unwrap();
        assert!(budget.take_input(11, Path::new("b")).unwrap_err().to_string().contains("add up to 4.0 GiB"));
        budget.take_decoded(MAX_LOAD_DECODED_BYTES).unwrap();
        assert!(budget.take_decoded(1).is_err());
    }
}
