//! Records the git commit the binary was built from, for benchmark reports: with `-dirty` appended
//! when its sources (the crates, the workspace's manifest and lock file) differ from that commit, so a
//! report never names a commit whose code it did not run.
fn main() {
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    // Changed or new files among the sources the binary is built from.
    let changes = git(&["-C", "../..", "status", "--porcelain", "--", "crates", "Cargo.toml", "Cargo.lock"]);
    let commit = match (git(&["rev-parse", "--short=12", "HEAD"]), changes) {
        (Some(commit), Some(changes)) if !changes.is_empty() => format!("{commit}-dirty"),
        (Some(commit), _) => commit,
        (None, _) => "unknown".into(),
    };
    println!("cargo:rustc-env=MANYLIGHTS_COMMIT={commit}");
    // Commits move HEAD or a branch; edits and staging change the sources or the index.
    for path in ["../../.git/HEAD", "../../.git/refs/heads", "../../.git/index", "../../crates", "../../Cargo.toml", "../../Cargo.lock"] {
        println!("cargo:rerun-if-changed={path}");
    }
}
