//! Records the git commit the binary was built from, for benchmark reports: with `-dirty` appended
//! when tracked files differ from it, so a report never names a commit whose code it did not run.
fn main() {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = match (git(&["rev-parse", "--short=12", "HEAD"]), git(&["status", "--porcelain", "--untracked-files=no"])) {
        (Some(commit), Some(changes)) if !changes.is_empty() => format!("{commit}-dirty"),
        (Some(commit), _) => commit,
        (None, _) => "unknown".into(),
    };
    println!("cargo:rustc-env=MANYLIGHTS_COMMIT={commit}");
    // Commits move HEAD or a branch; edits and staging change the sources or the index.
    for path in ["../../.git/HEAD", "../../.git/refs/heads", "../../.git/index", "../../crates", "../../Cargo.toml"] {
        println!("cargo:rerun-if-changed={path}");
    }
}
