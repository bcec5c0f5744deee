//! Outputs checked before any work, then written whole or not at all.
//!
//! A caller checks each output path with [`check_output`] before it loads or renders anything, and
//! against the other outputs and the scene's inputs with [`check_distinct`] once the scene is loaded.
//! When the work is done it stages every output with [`StagedOutputs::stage`] (a temporary file beside
//! the target, written, flushed and synced) and renames them all over their targets with
//! [`StagedOutputs::commit`]: a failure while staging leaves every previous file untouched.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::{Error, Result};

/// The formats manylights writes, each chosen by its file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Png,
    Jpeg,
    Exr,
    Json,
    Csv,
    Markdown,
}

impl OutputFormat {
    /// The tonemapped image's formats.
    pub const IMAGES: [OutputFormat; 2] = [OutputFormat::Png, OutputFormat::Jpeg];

    pub const fn extensions(self) -> &'static [&'static str] {
        match self {
            OutputFormat::Png => &["png"],
            OutputFormat::Jpeg => &["jpg", "jpeg"],
            OutputFormat::Exr => &["exr"],
            OutputFormat::Json => &["json"],
            OutputFormat::Csv => &["csv"],
            OutputFormat::Markdown => &["md"],
        }
    }

    /// The format an extension names, in any letter case.
    pub fn from_path(path: &Path) -> Option<Self> {
        let extension = path.extension()?.to_str()?.to_ascii_lowercase();
        [Self::Png, Self::Jpeg, Self::Exr, Self::Json, Self::Csv, Self::Markdown]
            .into_iter()
            .find(|format| format.extensions().contains(&extension.as_str()))
    }
}

fn output_error(path: &Path, reason: impl Into<String>) -> Error {
    Error::Output { path: path.to_owned(), reason: reason.into() }
}

/// "the folder" an output goes into: its parent, or the working directory.
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// Checks an output path before any work: its extension names one of `accepted` (returned), its folder
/// exists and takes new files, and the path holds a regular file or nothing. `flag` names the option
/// in messages (`-o`, `--exr`).
pub fn check_output(path: &Path, flag: &str, accepted: &[OutputFormat]) -> Result<OutputFormat> {
    let listed = || accepted.iter().flat_map(|f| f.extensions()).map(|e| format!(".{e}")).collect::<Vec<_>>().join(", ");
    let format = OutputFormat::from_path(path).filter(|f| accepted.contains(f)).ok_or_else(|| {
        let given = path.extension().map_or_else(|| "no extension".to_owned(), |e| format!(".{}", e.to_string_lossy()));
        output_error(path, format!("{flag} writes {} files, and this path has {given}; give a path ending in one of those", listed()))
    })?;
    // A link is written through: the file it names, existing or not, is what is checked.
    let target = through_links(path);
    let folder = folder_of(&target);
    match std::fs::metadata(folder) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(output_error(path, format!("{} is not a folder; give a path in an existing folder", folder.display()))),
        Err(_) => {
            return Err(output_error(path, format!("the folder {} does not exist; create it first or give another path", folder.display())))
        }
    }
    match std::fs::metadata(&target) {
        Ok(m) if m.is_file() && m.permissions().readonly() => {
            return Err(output_error(path, "it is read-only; make it writable (chmod u+w) or give another path".to_owned()))
        }
        Ok(m) if m.is_file() => {}
        Ok(m) if m.is_dir() => return Err(output_error(path, format!("it is a folder; give {flag} a file path"))),
        Ok(_) => {
            return Err(output_error(
                path,
                format!("it is a device, pipe or socket, not a regular file; give {flag} the path of a file to write"),
            ))
        }
        Err(_) => {}
    }
    // Whether the folder takes new files is only known by making one.
    tempfile::Builder::new()
        .prefix(".manylights-probe-")
        .tempfile_in(folder)
        .map_err(|e| output_error(path, format!("cannot create files in {}: {e}; give a folder you can write to", folder.display())))?;
    Ok(format)
}

/// Links followed before a path is taken as it is: more means a loop.
const MAX_LINKS: usize = 16;

/// The file a path writes to: itself, or what its symbolic links point to, followed even where the
/// file they name does not exist yet.
fn through_links(path: &Path) -> PathBuf {
    let mut path = path.to_owned();
    for _ in 0..MAX_LINKS {
        match std::fs::read_link(&path) {
            Ok(target) => path = folder_of(&path).join(target),
            Err(_) => break,
        }
    }
    path
}

/// An output's identity: the canonical file it writes to, or, for a file not written yet, its
/// canonical folder joined with its name.
fn identity(path: &Path) -> PathBuf {
    let path = through_links(path);
    if let Ok(canonical) = path.canonicalize() {
        return canonical;
    }
    let folder = folder_of(&path).canonicalize().unwrap_or_else(|_| folder_of(&path).to_owned());
    path.file_name().map_or(folder.clone(), |name| folder.join(name))
}

fn same_file(a: &Path, b: &Path) -> bool {
    identity(a) == identity(b) || same_file::is_same_file(a, b).unwrap_or(false)
}

/// Checks that no two outputs, named with their flags, are the same file, and that no output is one
/// of the scene's `inputs` (the files it was read from).
pub fn check_distinct(outputs: &[(&str, &Path)], inputs: &[PathBuf]) -> Result<()> {
    for (i, &(flag, path)) in outputs.iter().enumerate() {
        if let Some(&(other, _)) = outputs[..i].iter().find(|(_, earlier)| same_file(earlier, path)) {
            return Err(output_error(path, format!("{other} and {flag} name the same file; give each its own path")));
        }
        if let Some(input) = inputs.iter().find(|input| same_file(input, path)) {
            return Err(output_error(
                path,
                format!("{flag} would overwrite {}, which the scene is read from; give another output path", input.display()),
            ));
        }
    }
    Ok(())
}

/// A command's outputs, each checked as it is added ([`check_output`], and against those before it),
/// then against the scene's inputs once the scene is loaded.
#[derive(Default)]
pub struct OutputPlan {
    outputs: Vec<(String, PathBuf)>,
}

impl OutputPlan {
    pub fn new() -> Self {
        Self::default()
    }

    /// Checks `path`, named by `flag`, and returns its format.
    pub fn add(&mut self, flag: &str, path: &Path, accepted: &[OutputFormat]) -> Result<OutputFormat> {
        let format = check_output(path, flag, accepted)?;
        self.outputs.push((flag.to_owned(), path.to_owned()));
        self.check_inputs(&[])?;
        Ok(format)
    }

    /// Checks that no output is one of `inputs` (the files the scene was read from).
    pub fn check_inputs(&self, inputs: &[PathBuf]) -> Result<()> {
        let outputs: Vec<(&str, &Path)> = self.outputs.iter().map(|(flag, path)| (flag.as_str(), path.as_path())).collect();
        check_distinct(&outputs, inputs)
    }
}

/// Outputs written to temporary files beside their targets, waiting to replace them.
#[derive(Default)]
pub struct StagedOutputs {
    staged: Vec<(PathBuf, tempfile::NamedTempFile)>,
}

impl StagedOutputs {
    pub fn new() -> Self {
        Self::default()
    }

    /// Writes `bytes` to a temporary file beside `path`, flushed and synced to disk. On failure the
    /// temporary file is removed and `path` is untouched.
    pub fn stage(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        // A link to a file is written through, so the link stays.
        let target = through_links(path);
        let name = target.file_name().map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
        // The OS's words without the temporary file's name, which the user never asked for.
        let fail = |e: std::io::Error| {
            let plain = e.raw_os_error().map_or_else(|| e.to_string(), |code| std::io::Error::from_raw_os_error(code).to_string());
            output_error(path, format!("{plain}; nothing was replaced: free some space or give another path"))
        };
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".partial");
        match std::fs::metadata(&target) {
            // A replaced file keeps its permissions.
            Ok(existing) => {
                builder.permissions(existing.permissions());
            }
            // What a plain create gives (0666 less the umask), not the temporary file's private 0600.
            #[cfg(unix)]
            Err(_) => {
                use std::os::unix::fs::PermissionsExt;
                builder.permissions(std::fs::Permissions::from_mode(0o666));
            }
            #[cfg(not(unix))]
            Err(_) => {}
        }
        let mut file = builder.tempfile_in(folder_of(&target)).map_err(fail)?;
        // Through the plain file, whose errors are the OS's own.
        file.as_file_mut().write_all(bytes).map_err(fail)?;
        file.as_file_mut().flush().map_err(fail)?;
        file.as_file().sync_all().map_err(fail)?;
        self.staged.push((target, file));
        Ok(())
    }

    /// Renames every staged file over its target. Renames are what a file system does reliably;
    /// should one still fail, the targets renamed before it hold their new contents.
    pub fn commit(self) -> Result<()> {
        let mut folders = Vec::new();
        for (target, file) in self.staged {
            file.persist(&target).map_err(|e| output_error(&target, format!("{}; give a path you can write to", e.error)))?;
            folders.push(folder_of(&target).to_owned());
        }
        // The renames themselves reach the disk with their folders.
        #[cfg(unix)]
        for folder in folders {
            if let Ok(dir) = std::fs::File::open(&folder) {
                let _ = dir.sync_all();
            }
        }
        Ok(())
    }
}

/// Writes one file whole or not at all.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut staged = StagedOutputs::new();
    staged.stage(path, bytes)?;
    staged.commit()
}

/// Writes a new file whole or not at all, failing if something appears at `path` meanwhile.
pub fn write_new(path: &Path, bytes: &[u8]) -> Result<()> {
    let mut staged = StagedOutputs::new();
    staged.stage(path, bytes)?;
    for (target, file) in staged.staged {
        file.persist_noclobber(&target).map_err(|e| output_error(&target, format!("{}; give another path", e.error)))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::test_support::temp_dir;

    #[test]
    fn formats_follow_extensions_in_any_case() {
        assert_eq!(OutputFormat::from_path(Path::new("a/B.PNG")), Some(OutputFormat::Png));
        assert_eq!(OutputFormat::from_path(Path::new("b.jpeg")), Some(OutputFormat::Jpeg));
        assert_eq!(OutputFormat::from_path(Path::new("c.Jpg")), Some(OutputFormat::Jpeg));
        assert_eq!(OutputFormat::from_path(Path::new("d.bmp")), None);
        assert_eq!(OutputFormat::from_path(Path::new("png")), None);
    }

    #[test]
    fn bad_output_paths_are_refused_with_the_fix() {
        let dir = temp_dir("check_output");
        let images = &OutputFormat::IMAGES;
        let refuse = |path: &Path, wanted: &str| {
            let e = check_output(path, "-o", images).unwrap_err().to_string();
            assert!(e.contains(wanted), "{e}");
        };
        refuse(&dir.join("x.bmp"), "-o writes .png, .jpg, .jpeg files, and this path has .bmp");
        refuse(&dir.join("x"), "this path has no extension");
        refuse(&dir.join("missing/x.png"), "does not exist; create it first");
        std::fs::create_dir(dir.join("folder.png")).unwrap();
        refuse(&dir.join("folder.png"), "it is a folder");
        std::fs::write(dir.join("file"), "").unwrap();
        refuse(&dir.join("file/x.png"), "is not a folder");
        assert_eq!(check_output(&dir.join("fine.JPG"), "-o", images).unwrap(), OutputFormat::Jpeg);
        let locked = dir.join("locked.png");
        std::fs::write(&locked, "").unwrap();
        let mut permissions = std::fs::metadata(&locked).unwrap().permissions();
        permissions.set_readonly(true);
        std::fs::set_permissions(&locked, permissions).unwrap();
        refuse(&locked, "it is read-only");
        #[cfg(unix)]
        {
            // A link into a missing folder is checked where it writes.
            let link = dir.join("away.png");
            std::os::unix::fs::symlink(dir.join("missing/away.png"), &link).unwrap();
            refuse(&link, "does not exist; create it first");
        }
        // The probe leaves nothing behind: the folders, the files and the link made here only.
        let left: Vec<_> = std::fs::read_dir(&*dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left.len(), if cfg!(unix) { 4 } else { 3 }, "{left:?}");
    }

    #[test]
    fn devices_are_not_outputs() {
        let e = check_output(Path::new("/dev/full"), "-o", &OutputFormat::IMAGES).unwrap_err().to_string();
        assert!(e.contains("no extension"), "{e}");
        // Named with an image's extension, a device is still refused.
        let link_dir = temp_dir("device_link");
        let link = link_dir.join("full.png");
        #[cfg(unix)]
        std::os::unix::fs::symlink("/dev/full", &link).unwrap();
        let e = check_output(&link, "-o", &OutputFormat::IMAGES).unwrap_err().to_string();
        assert!(e.contains("not a regular file"), "{e}");
    }

    #[test]
    fn outputs_may_not_repeat_or_overwrite_inputs() {
        let dir = temp_dir("check_distinct");
        let input = dir.join("scene.gltf");
        std::fs::write(&input, "{}").unwrap();
        let inputs = vec![input.canonicalize().unwrap()];
        let a = dir.join("a.png");
        let e = check_distinct(&[("-o", &a), ("--exr", &dir.join("./a.png"))], &inputs).unwrap_err().to_string();
        assert!(e.contains("-o and --exr name the same file"), "{e}");
        let e = check_distinct(&[("-o", &dir.join(".").join("scene.gltf"))], &inputs).unwrap_err().to_string();
        assert!(e.contains("would overwrite") && e.contains("scene.gltf"), "{e}");
        #[cfg(unix)]
        {
            std::fs::hard_link(&input, dir.join("linked.png")).unwrap();
            let e = check_distinct(&[("-o", &dir.join("linked.png"))], &inputs).unwrap_err().to_string();
            assert!(e.contains("would overwrite"), "{e}");
        }
        check_distinct(&[("-o", &a), ("--exr", &dir.join("a.exr"))], &inputs).unwrap();
    }

    #[test]
    fn a_failed_write_leaves_the_previous_file_and_no_temporary() {
        let dir = temp_dir("atomic_write");
        let path = dir.join("out.png");
        write_atomic(&path, b"first").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"first");
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        // Staged but never committed: the target keeps its bytes and the temporary file goes.
        let mut staged = StagedOutputs::new();
        staged.stage(&path, b"third").unwrap();
        drop(staged);
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(&*dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["out.png"], "no temporary file is left");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let plain = dir.join("plain");
            std::fs::write(&plain, "").unwrap();
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode(&path), mode(&plain), "outputs get the permissions of plainly created files");
        }
    }

    #[test]
    fn a_link_to_a_file_is_written_through() {
        let dir = temp_dir("write_through_link");
        let real = dir.join("real.png");
        std::fs::write(&real, "old").unwrap();
        let link = dir.join("link.png");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&real, &link).unwrap();
            write_atomic(&link, b"new").unwrap();
            assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
            assert_eq!(std::fs::read(&real).unwrap(), b"new");
            // A link to a file not written yet names that file, for checks and writes alike.
            let later = dir.join("later.png");
            let dangling = dir.join("dangling.exr");
            std::os::unix::fs::symlink("later.png", &dangling).unwrap();
            let e = check_distinct(&[("-o", &later), ("--exr", &dangling)], &[]).unwrap_err().to_string();
            assert!(e.contains("-o and --exr name the same file"), "{e}");
            write_atomic(&dangling, b"through").unwrap();
            assert_eq!(std::fs::read(&later).unwrap(), b"through");
            assert!(std::fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
        }
    }
}
