//! The library's modules import one way, down this list: a module may use itself and the ones above
//! it, never one below. Test modules (`#[cfg(test)]` at a file's end) may reach further, as
//! dev-dependencies do.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// Lowest first. Modules on one line are one layer and do not import each other, except as the line
/// lists them: a module may import those before it on its line.
const LAYERS: &[&[&str]] = &[
    &["error"],
    &["files", "settings"],
    &["scene"],
    &["gpu", "image_io"],
    &["plan"],
    &["accel", "rays", "particles"],
    &["passes", "post"],
    &["pipelines"],
    &["renderer"],
];

/// Names the crate root re-exports, by the module that defines them.
const ROOT_NAMES: &[(&str, &str)] = &[("Error", "error"), ("Result", "error"), ("named_enum", "settings")];

/// The module of `name` (a crate-root path segment) and its rank: layer first, then place in the line.
fn rank(name: &str) -> Option<(usize, usize)> {
    let module = ROOT_NAMES.iter().find(|(n, _)| *n == name).map_or(name, |(_, m)| m);
    LAYERS.iter().enumerate().find_map(|(layer, line)| line.iter().position(|m| *m == module).map(|place| (layer, place)))
}

fn may_import(from: &str, to: &str) -> bool {
    let (Some(from), Some(to)) = (rank(from), rank(to)) else { return false };
    from.0 > to.0 || (from.0 == to.0 && from.1 >= to.1)
}

/// The source without comments and without its trailing test module.
fn code(source: &str) -> String {
    let body = match source.find("\n#[cfg(test)]\nmod tests") {
        Some(at) => &source[..at],
        None => source,
    };
    body.lines().map(|line| line.split("//").next().unwrap_or("")).collect::<Vec<_>>().join("\n")
}

/// Every crate-root segment `code` names: `crate::x`, and each top-level item of `crate::{x, y::z}`.
fn imported_modules(code: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    for (at, _) in code.match_indices("crate::") {
        let rest = &code[at + "crate::".len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let (mut depth, mut start) = (0usize, true);
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => start = true,
                    c if start && (c.is_alphanumeric() || c == '_') => {
                        found.insert(ident(&group[i..]));
                        start = false;
                    }
                    c if start && !c.is_whitespace() => start = false,
                    _ => {}
                }
            }
        } else {
            found.insert(ident(rest));
        }
    }
    found.remove("self");
    found
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn modules_import_only_the_layers_below_them() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut problems = Vec::new();
    for file in &files {
        let relative = file.strip_prefix(&src).unwrap();
        let module = relative.components().next().unwrap().as_os_str().to_str().unwrap().trim_end_matches(".rs").to_owned();
        if module == "lib" {
            continue;
        }
        assert!(rank(&module).is_some(), "src/{} is in no layer: add `{module}` to LAYERS", relative.display());
        for imported in imported_modules(&code(&std::fs::read_to_string(file).unwrap())) {
            if imported != module && !may_import(&module, &imported) {
                problems.push(format!("src/{} ({module}) imports {imported}", relative.display()));
            }
        }
    }
    assert!(problems.is_empty(), "imports against the layers:\n{}", problems.join("\n"));
    assert!(files.len() > 50, "only {} source files found", files.len());
}

#[test]
fn the_check_finds_upward_and_grouped_imports() {
    let code = code("use crate::{\n    gpu::{GpuContext, GpuScene},\n    Error, // pipelines::X\n};\nfn f() { crate::renderer::x(); }\n#[cfg(test)]\nmod tests {\n    use crate::plan::X;\n}\n");
    let modules: Vec<String> = imported_modules(&code).into_iter().collect();
    assert_eq!(modules, ["Error", "gpu", "renderer"]);
    assert!(may_import("renderer", "gpu") && may_import("gpu", "Error") && may_import("particles", "accel"));
    assert!(!may_import("gpu", "renderer") && !may_import("accel", "particles") && !may_import("scene", "unknown"));
}
