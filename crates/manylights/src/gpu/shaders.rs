//! WGSL composition. WGSL has no includes, so shader files start with `#include "path"` lines that are
//! resolved here against the sources embedded in the binary, each file once, dependencies first.
//! `#include "$NAME"` takes the path from a substitution: that is how a pass picks an enumeration
//! method (`shading/enumerate/*.wgsl`) without copies of the shading core.

use std::collections::HashSet;

/// Every WGSL file, by the path the `#include` lines use.
const SOURCES: &[(&str, &str)] = &[
    ("shading/types.wgsl", include_str!("../shading/types.wgsl")),
    ("shading/scene_bindings.wgsl", include_str!("../shading/scene_bindings.wgsl")),
    ("shading/shading_input.wgsl", include_str!("../shading/shading_input.wgsl")),
    ("shading/brdf.wgsl", include_str!("../shading/brdf.wgsl")),
    ("shading/lights.wgsl", include_str!("../shading/lights.wgsl")),
    ("shading/light_volume.wgsl", include_str!("../shading/light_volume.wgsl")),
    ("shading/material.wgsl", include_str!("../shading/material.wgsl")),
    ("shading/shade.wgsl", include_str!("../shading/shade.wgsl")),
    ("shading/enumerate/brute.wgsl", include_str!("../shading/enumerate/brute.wgsl")),
    ("shading/enumerate/bvh.wgsl", include_str!("../shading/enumerate/bvh.wgsl")),
    ("accel/bvh.wgsl", include_str!("../accel/bvh.wgsl")),
    ("accel/bvh_types.wgsl", include_str!("../accel/bvh_types.wgsl")),
    ("accel/lbvh.wgsl", include_str!("../accel/lbvh.wgsl")),
    ("accel/bvh_bindings.wgsl", include_str!("../accel/bvh_bindings.wgsl")),
    ("accel/bvh_query_probe.wgsl", include_str!("../accel/bvh_query_probe.wgsl")),
    ("passes/visbuffer_raster.wgsl", include_str!("../passes/visbuffer_raster.wgsl")),
    ("passes/visbuffer_shade.wgsl", include_str!("../passes/visbuffer_shade.wgsl")),
    ("passes/tonemap.wgsl", include_str!("../passes/tonemap.wgsl")),
];

/// A shader to build: an entry file and the values of its `$NAME` includes.
#[derive(Clone, Debug)]
pub struct ShaderDesc {
    pub entry: &'static str,
    pub substitutions: Vec<(&'static str, &'static str)>,
}

impl ShaderDesc {
    pub fn new(entry: &'static str) -> Self {
        Self { entry, substitutions: Vec::new() }
    }

    pub fn with(mut self, name: &'static str, path: &'static str) -> Self {
        self.substitutions.push((name, path));
        self
    }

    /// The complete WGSL source. Errors name the file that could not be resolved.
    pub fn compose(&self) -> Result<String, String> {
        let mut out = String::new();
        let mut seen = HashSet::new();
        self.append(self.entry, &mut out, &mut seen, &mut Vec::new())?;
        Ok(out)
    }

    fn append(
        &self,
        path: &'static str,
        out: &mut String,
        seen: &mut HashSet<&'static str>,
        stack: &mut Vec<&'static str>,
    ) -> Result<(), String> {
        if stack.contains(&path) {
            return Err(format!("include cycle: {} -> {path}", stack.join(" -> ")));
        }
        if !seen.insert(path) {
            return Ok(());
        }
        let (_, source) = embedded(path).ok_or_else(|| format!("unknown shader file `{path}` (included from {:?})", stack.last()))?;
        stack.push(path);
        for line in source.lines() {
            match include_target(line) {
                Some(target) => {
                    let resolved = match target.strip_prefix('$') {
                        Some(name) => self
                            .substitutions
                            .iter()
                            .find(|(n, _)| *n == name)
                            .map(|(_, p)| *p)
                            .ok_or_else(|| format!("{path}: no value given for `${name}`"))?,
                        None => embedded(target).map(|(p, _)| p).ok_or_else(|| format!("{path}: unknown include `{target}`"))?,
                    };
                    self.append(resolved, out, seen, stack)?;
                }
                None => {
                    out.push_str(line);
                    out.push('\n');
                }
            }
        }
        stack.pop();
        Ok(())
    }
}

/// The embedded file at `path`: its path with the `'static` lifetime the composer keeps, and its text.
fn embedded(path: &str) -> Option<(&'static str, &'static str)> {
    SOURCES.iter().find(|(p, _)| *p == path).copied()
}

fn include_target(line: &str) -> Option<&str> {
    line.trim().strip_prefix("#include")?.trim().strip_prefix('"')?.strip_suffix('"')
}

/// Compiles a composed shader into a module. Composition errors are programming errors caught by the
/// naga test below, so they are reported as GPU errors rather than user errors.
pub fn create_module(device: &wgpu::Device, desc: &ShaderDesc) -> crate::Result<wgpu::ShaderModule> {
    let source = desc.compose().map_err(crate::Error::Gpu)?;
    Ok(device
        .create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(desc.entry), source: wgpu::ShaderSource::Wgsl(source.into()) }))
}

/// Every shader the renderer builds, with every substitution it uses: the naga test validates each.
pub fn all_shaders() -> Vec<ShaderDesc> {
    let mut shaders = vec![
        ShaderDesc::new("passes/visbuffer_raster.wgsl"),
        ShaderDesc::new("passes/tonemap.wgsl"),
        ShaderDesc::new("accel/bvh_query_probe.wgsl"),
        ShaderDesc::new("accel/lbvh.wgsl"),
    ];
    for method in crate::pipelines::LightMethod::ALL {
        shaders.push(ShaderDesc::new("passes/visbuffer_shade.wgsl").with("LIGHT_ENUMERATION", method.enumeration_module()));
    }
    shaders
}

#[cfg(test)]
mod tests {
    use super::*;

    fn validate(desc: &ShaderDesc) {
        let source = desc.compose().unwrap_or_else(|e| panic!("{}: {e}", desc.entry));
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}:\n{}", desc.entry, e.emit_to_string(&source)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::empty())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}:\n{}", desc.entry, e.emit_to_string(&source)));
    }

    #[test]
    fn every_shader_parses_and_validates() {
        for desc in all_shaders() {
            validate(&desc);
        }
    }

    #[test]
    fn every_embedded_file_is_used() {
        let mut used = HashSet::new();
        for desc in all_shaders() {
            let mut seen = HashSet::new();
            desc.append(desc.entry, &mut String::new(), &mut seen, &mut Vec::new()).unwrap();
            used.extend(seen);
        }
        for (path, _) in SOURCES {
            assert!(used.contains(path), "{path} is embedded but no shader includes it");
        }
    }

    #[test]
    fn includes_are_resolved_once_and_missing_ones_reported() {
        let source = ShaderDesc::new("passes/visbuffer_raster.wgsl").compose().unwrap();
        assert_eq!(source.matches("struct Vertex {").count(), 1);
        assert!(!source.contains("#include"));
        let err = ShaderDesc::new("passes/visbuffer_shade.wgsl").compose().unwrap_err();
        assert!(err.contains("$LIGHT_ENUMERATION"), "{err}");
    }
}
