//! WGSL composition. WGSL has no includes, so shader files start with `#include "path"` lines that are
//! resolved here against the sources embedded in the binary, each file once, dependencies first.
//! `#include "$NAME"` takes the path from a substitution: that is how a pass picks an enumeration
//! method (`shading/enumerate/*.wgsl`) without copies of the shading core.
//! `#include "path" with KEY=value` includes a template: every name starting `KEY_` in it becomes
//! `value_` (once per distinct value), which is how lights and decals each get a point query over their
//! own bindings without binding-array support; inside a template, `with KEY=KEY` passes its value on.
//!
//! `MANYLIGHTS_SHADER_DIR`, when set, names a directory laid out like this crate's `src/` whose WGSL
//! files replace the embedded ones: shader edits take effect without rebuilding the binary.

use std::collections::{HashMap, HashSet};
use std::sync::OnceLock;

/// Every WGSL file, by the path the `#include` lines use.
const SOURCES: &[(&str, &str)] = &[
    ("shading/types.wgsl", include_str!("../shading/types.wgsl")),
    ("shading/scene_bindings.wgsl", include_str!("../shading/scene_bindings.wgsl")),
    ("shading/shading_input.wgsl", include_str!("../shading/shading_input.wgsl")),
    ("shading/brdf.wgsl", include_str!("../shading/brdf.wgsl")),
    ("shading/lights.wgsl", include_str!("../shading/lights.wgsl")),
    ("shading/environment.wgsl", include_str!("../shading/environment.wgsl")),
    ("shading/light_volume.wgsl", include_str!("../shading/light_volume.wgsl")),
    ("shading/material.wgsl", include_str!("../shading/material.wgsl")),
    ("shading/shade.wgsl", include_str!("../shading/shade.wgsl")),
    ("shading/light_bindings.wgsl", include_str!("../shading/light_bindings.wgsl")),
    ("shading/decal_bindings.wgsl", include_str!("../shading/decal_bindings.wgsl")),
    ("shading/decals.wgsl", include_str!("../shading/decals.wgsl")),
    ("shading/enumerate/light_loop.wgsl", include_str!("../shading/enumerate/light_loop.wgsl")),
    ("shading/enumerate/lights_brute.wgsl", include_str!("../shading/enumerate/lights_brute.wgsl")),
    ("shading/enumerate/lights_bvh.wgsl", include_str!("../shading/enumerate/lights_bvh.wgsl")),
    ("shading/enumerate/lights_tree.wgsl", include_str!("../shading/enumerate/lights_tree.wgsl")),
    ("shading/enumerate/lights_ray_query.wgsl", include_str!("../shading/enumerate/lights_ray_query.wgsl")),
    ("shading/enumerate/decals_ray_query.wgsl", include_str!("../shading/enumerate/decals_ray_query.wgsl")),
    ("shading/volume_ray_query.wgsl", include_str!("../shading/volume_ray_query.wgsl")),
    ("shading/light_tree.wgsl", include_str!("../shading/light_tree.wgsl")),
    ("shading/light_tree_probe.wgsl", include_str!("../shading/light_tree_probe.wgsl")),
    ("shading/random.wgsl", include_str!("../shading/random.wgsl")),
    ("shading/enumerate/decals_brute.wgsl", include_str!("../shading/enumerate/decals_brute.wgsl")),
    ("shading/enumerate/decals_bvh.wgsl", include_str!("../shading/enumerate/decals_bvh.wgsl")),
    ("shading/enumerate/decals_bvh_cells.wgsl", include_str!("../shading/enumerate/decals_bvh_cells.wgsl")),
    ("shading/decal_box.wgsl", include_str!("../shading/decal_box.wgsl")),
    ("shading/enumerate/decal_leaves_each.wgsl", include_str!("../shading/enumerate/decal_leaves_each.wgsl")),
    ("shading/enumerate/decal_leaves_shared_out.wgsl", include_str!("../shading/enumerate/decal_leaves_shared_out.wgsl")),
    ("shading/enumerate/lights_off.wgsl", include_str!("../shading/enumerate/lights_off.wgsl")),
    ("shading/enumerate/decals_off.wgsl", include_str!("../shading/enumerate/decals_off.wgsl")),
    ("shading/enumerate/lights_clustered.wgsl", include_str!("../shading/enumerate/lights_clustered.wgsl")),
    ("shading/enumerate/lights_cells.wgsl", include_str!("../shading/enumerate/lights_cells.wgsl")),
    ("shading/enumerate/decals_cells.wgsl", include_str!("../shading/enumerate/decals_cells.wgsl")),
    ("shading/enumerate/decals_clustered.wgsl", include_str!("../shading/enumerate/decals_clustered.wgsl")),
    ("accel/cluster_grid.wgsl", include_str!("../accel/cluster_grid.wgsl")),
    ("accel/cluster_build.wgsl", include_str!("../accel/cluster_build.wgsl")),
    ("accel/workgroup_scan.wgsl", include_str!("../accel/workgroup_scan.wgsl")),
    ("accel/volume_query.wgsl", include_str!("../accel/volume_query.wgsl")),
    ("accel/volume_query_invocation.wgsl", include_str!("../accel/volume_query_invocation.wgsl")),
    ("accel/volume_query_subgroup.wgsl", include_str!("../accel/volume_query_subgroup.wgsl")),
    ("accel/bvh_types.wgsl", include_str!("../accel/bvh_types.wgsl")),
    ("shading/camera.wgsl", include_str!("../shading/camera.wgsl")),
    ("accel/lbvh.wgsl", include_str!("../accel/lbvh.wgsl")),
    ("accel/hardware_boxes.wgsl", include_str!("../accel/hardware_boxes.wgsl")),
    ("accel/rebuilt_grid.wgsl", include_str!("../accel/rebuilt_grid.wgsl")),
    ("accel/rebuilt_cell_lists.wgsl", include_str!("../accel/rebuilt_cell_lists.wgsl")),
    ("accel/leaf_order.wgsl", include_str!("../accel/leaf_order.wgsl")),
    ("accel/radix_sort.wgsl", include_str!("../accel/radix_sort.wgsl")),
    ("passes/visbuffer_raster_indexed.wgsl", include_str!("../passes/visbuffer_raster_indexed.wgsl")),
    ("passes/visbuffer_raster_pulled.wgsl", include_str!("../passes/visbuffer_raster_pulled.wgsl")),
    ("accel/volume_query_probe.wgsl", include_str!("../accel/volume_query_probe.wgsl")),
    ("passes/visbuffer_raster.wgsl", include_str!("../passes/visbuffer_raster.wgsl")),
    ("passes/visbuffer_shade.wgsl", include_str!("../passes/visbuffer_shade.wgsl")),
    ("passes/deform.wgsl", include_str!("../passes/deform.wgsl")),
    ("shading/debug_view.wgsl", include_str!("../shading/debug_view.wgsl")),
    ("shading/pixel_hash.wgsl", include_str!("../shading/pixel_hash.wgsl")),
    ("shading/previous_vertex.wgsl", include_str!("../shading/previous_vertex.wgsl")),
    ("rays/refit.wgsl", include_str!("../rays/refit.wgsl")),
    ("post/post_types.wgsl", include_str!("../post/post_types.wgsl")),
    ("post/velocity.wgsl", include_str!("../post/velocity.wgsl")),
    ("post/velocity_raster.wgsl", include_str!("../post/velocity_raster.wgsl")),
    ("post/depth_of_field.wgsl", include_str!("../post/depth_of_field.wgsl")),
    ("post/motion_blur.wgsl", include_str!("../post/motion_blur.wgsl")),
    ("post/exposure.wgsl", include_str!("../post/exposure.wgsl")),
    ("post/bloom.wgsl", include_str!("../post/bloom.wgsl")),
    ("post/tonemap.wgsl", include_str!("../post/tonemap.wgsl")),
    ("passes/surface_raster.wgsl", include_str!("../passes/surface_raster.wgsl")),
    ("passes/depth_prepass.wgsl", include_str!("../passes/depth_prepass.wgsl")),
    ("passes/surface_motion.wgsl", include_str!("../passes/surface_motion.wgsl")),
    ("passes/forward_shade.wgsl", include_str!("../passes/forward_shade.wgsl")),
    ("passes/gbuffer.wgsl", include_str!("../passes/gbuffer.wgsl")),
    ("passes/gbuffer_raster.wgsl", include_str!("../passes/gbuffer_raster.wgsl")),
    ("passes/deferred_shade.wgsl", include_str!("../passes/deferred_shade.wgsl")),
    ("passes/gbuffer_surface.wgsl", include_str!("../passes/gbuffer_surface.wgsl")),
    ("passes/deferred_decals.wgsl", include_str!("../passes/deferred_decals.wgsl")),
    ("passes/blended_layers.wgsl", include_str!("../passes/blended_layers.wgsl")),
    ("passes/blended_shade.wgsl", include_str!("../passes/blended_shade.wgsl")),
    ("passes/transmissive_shade.wgsl", include_str!("../passes/transmissive_shade.wgsl")),
    ("particles/types.wgsl", include_str!("../particles/types.wgsl")),
    ("particles/motion.wgsl", include_str!("../particles/motion.wgsl")),
    ("particles/splat.wgsl", include_str!("../particles/splat.wgsl")),
    ("particles/lights.wgsl", include_str!("../particles/lights.wgsl")),
    ("shading/enumerate/particles_off.wgsl", include_str!("../shading/enumerate/particles_off.wgsl")),
    ("shading/enumerate/particles_grid.wgsl", include_str!("../shading/enumerate/particles_grid.wgsl")),
    ("shading/triangle_surface.wgsl", include_str!("../shading/triangle_surface.wgsl")),
    ("shading/draws.wgsl", include_str!("../shading/draws.wgsl")),
    ("shading/pixel_surface.wgsl", include_str!("../shading/pixel_surface.wgsl")),
    ("shading/depth_normal.wgsl", include_str!("../shading/depth_normal.wgsl")),
    ("shading/sun_shadow.wgsl", include_str!("../shading/sun_shadow.wgsl")),
    ("shading/sun_shadow_mask.wgsl", include_str!("../shading/sun_shadow_mask.wgsl")),
    ("shading/reflections.wgsl", include_str!("../shading/reflections.wgsl")),
    ("shading/reflections_off.wgsl", include_str!("../shading/reflections_off.wgsl")),
    ("shading/transmission.wgsl", include_str!("../shading/transmission.wgsl")),
    ("shading/transmitted_none.wgsl", include_str!("../shading/transmitted_none.wgsl")),
    ("shading/transmitted_screen.wgsl", include_str!("../shading/transmitted_screen.wgsl")),
    ("passes/transmission_background.wgsl", include_str!("../passes/transmission_background.wgsl")),
    ("shading/octahedral.wgsl", include_str!("../shading/octahedral.wgsl")),
    ("passes/denoise/denoise_types.wgsl", include_str!("../passes/denoise/denoise_types.wgsl")),
    ("passes/denoise/temporal.wgsl", include_str!("../passes/denoise/temporal.wgsl")),
    ("passes/denoise/variance.wgsl", include_str!("../passes/denoise/variance.wgsl")),
    ("passes/denoise/filter.wgsl", include_str!("../passes/denoise/filter.wgsl")),
    ("passes/denoise/compose.wgsl", include_str!("../passes/denoise/compose.wgsl")),
    ("shading/direct/unshadowed.wgsl", include_str!("../shading/direct/unshadowed.wgsl")),
    ("shading/direct/budget.wgsl", include_str!("../shading/direct/budget.wgsl")),
    ("shading/direct/reference.wgsl", include_str!("../shading/direct/reference.wgsl")),
    ("shading/direct/restir.wgsl", include_str!("../shading/direct/restir.wgsl")),
    ("shading/direct/shadow_ray.wgsl", include_str!("../shading/direct/shadow_ray.wgsl")),
    ("shading/shading_pixel.wgsl", include_str!("../shading/shading_pixel.wgsl")),
    ("rays/ray_types.wgsl", include_str!("../rays/ray_types.wgsl")),
    ("rays/trace.wgsl", include_str!("../rays/trace.wgsl")),
    ("rays/ray_hit.wgsl", include_str!("../rays/ray_hit.wgsl")),
    ("rays/trace_ray_query.wgsl", include_str!("../rays/trace_ray_query.wgsl")),
    ("rays/hardware_corners.wgsl", include_str!("../rays/hardware_corners.wgsl")),
    ("rays/trace_probe.wgsl", include_str!("../rays/trace_probe.wgsl")),
    ("passes/ray_shadows.wgsl", include_str!("../passes/ray_shadows.wgsl")),
    ("passes/shadow_filter.wgsl", include_str!("../passes/shadow_filter.wgsl")),
];

/// A shader to build: an entry file and the values of its `$NAME` includes.
#[derive(Clone, Debug)]
pub struct ShaderDesc {
    pub entry: &'static str,
    pub substitutions: Vec<(&'static str, &'static str)>,
    /// Every fragment entry point tests depth before it runs (`@early_depth_test(force)`, which needs
    /// `wgpu::Features::SHADER_EARLY_DEPTH_TEST`).
    pub early_depth_test: bool,
}

impl ShaderDesc {
    pub fn new(entry: &'static str) -> Self {
        Self { entry, substitutions: Vec::new(), early_depth_test: false }
    }

    /// Gives `$name` the file `path`, replacing any value given before.
    pub fn with(mut self, name: &'static str, path: &'static str) -> Self {
        self.substitutions.push((name, path));
        self
    }

    /// Fragment entry points test depth before they run, as shaders writing storage need where a
    /// fragment that fails the test must write nothing (a late test would discard only its colour).
    pub fn testing_depth_first(mut self, early: bool) -> Self {
        self.early_depth_test = early;
        self
    }

    /// The complete WGSL source. Errors name the file that could not be resolved.
    pub fn compose(&self) -> Result<String, String> {
        let mut out = String::new();
        let mut seen = HashSet::new();
        self.append(self.entry, None, &mut out, &mut seen, &mut Vec::new())?;
        out = hoist_enables(&out);
        if self.early_depth_test {
            out = out.replace("@fragment\n", "@fragment\n@early_depth_test(force)\n");
        }
        Ok(out)
    }

    /// Appends `path` (with its template argument, if any) and its includes, unless already there.
    fn append(
        &self,
        path: &'static str,
        template: Option<(&str, &str)>,
        out: &mut String,
        seen: &mut HashSet<String>,
        stack: &mut Vec<&'static str>,
    ) -> Result<(), String> {
        if stack.contains(&path) {
            return Err(format!("include cycle: {} -> {path}", stack.join(" -> ")));
        }
        let key = match template {
            Some((name, value)) => format!("{path} with {name}={value}"),
            None => path.to_string(),
        };
        if !seen.insert(key) {
            return Ok(());
        }
        let (_, embedded_source) =
            embedded(path).ok_or_else(|| format!("unknown shader file `{path}` (included from {:?})", stack.last()))?;
        let source = match shader_dir() {
            Some(dir) => from_dir(dir, path)?,
            None => embedded_source,
        };
        stack.push(path);
        for line in source.lines() {
            match include_target(line) {
                Some((target, arguments)) => {
                    let template = match arguments {
                        Some(arguments) => {
                            let (name, value) = arguments
                                .split_once('=')
                                .map(|(n, v)| (n.trim(), v.trim()))
                                .filter(|(n, v)| !n.is_empty() && !v.is_empty())
                                .ok_or_else(|| format!("{path}: expected `with NAME=value`, got `with {arguments}`"))?;
                            // A template passing its own name passes its value.
                            let value = match template {
                                Some((outer, outer_value)) if value == outer => outer_value,
                                _ => value,
                            };
                            Some((name, value))
                        }
                        None => None,
                    };
                    let resolved = match target.strip_prefix('$') {
                        Some(name) => self
                            .substitutions
                            .iter()
                            .rfind(|(n, _)| *n == name)
                            .map(|(_, p)| *p)
                            .ok_or_else(|| format!("{path}: no value given for `${name}`"))?,
                        None => embedded(target).map(|(p, _)| p).ok_or_else(|| format!("{path}: unknown include `{target}`"))?,
                    };
                    self.append(resolved, template, out, seen, stack)?;
                }
                None => {
                    match template {
                        Some((name, value)) => out.push_str(&line.replace(&format!("{name}_"), &format!("{value}_"))),
                        None => out.push_str(line),
                    }
                    out.push('\n');
                }
            }
        }
        stack.pop();
        Ok(())
    }
}

/// `source` with its `enable` directives first, each once: WGSL wants them before any declaration,
/// and an included module may need one (`enable wgpu_ray_query;` in the ray-query enumerations).
fn hoist_enables(source: &str) -> String {
    let mut enables: Vec<&str> = Vec::new();
    let mut body = String::with_capacity(source.len());
    for line in source.lines() {
        if line.starts_with("enable ") {
            if !enables.contains(&line) {
                enables.push(line);
            }
        } else {
            body.push_str(line);
            body.push('\n');
        }
    }
    enables.iter().map(|e| format!("{e}\n")).collect::<String>() + &body
}

/// The embedded file at `path`: its path with the `'static` lifetime the composer keeps, and its text.
fn embedded(path: &str) -> Option<(&'static str, &'static str)> {
    SOURCES.iter().find(|(p, _)| *p == path).copied()
}

/// The directory `MANYLIGHTS_SHADER_DIR` names, if set.
fn shader_dir() -> Option<&'static str> {
    static DIR: OnceLock<Option<String>> = OnceLock::new();
    DIR.get_or_init(|| std::env::var("MANYLIGHTS_SHADER_DIR").ok().filter(|d| !d.is_empty())).as_deref()
}

/// The file at `path` under `dir`, read once and kept for the process's life (shaders are composed
/// again for every pipeline).
fn from_dir(dir: &str, path: &str) -> Result<&'static str, String> {
    static FILES: OnceLock<std::sync::Mutex<HashMap<String, &'static str>>> = OnceLock::new();
    let mut files = FILES.get_or_init(Default::default).lock().unwrap_or_else(|p| p.into_inner());
    let file = std::path::Path::new(dir).join(path);
    let key = file.to_string_lossy().into_owned();
    if let Some(text) = files.get(&key) {
        return Ok(text);
    }
    let text = std::fs::read_to_string(&file)
        .map_err(|e| format!("MANYLIGHTS_SHADER_DIR: cannot read {}: {e} (unset it to use the built-in shaders)", file.display()))?;
    let text: &'static str = Box::leak(text.into_boxed_str());
    files.insert(key, text);
    Ok(text)
}

/// The path of an `#include "path"` line, and the text after `with` if it has one.
fn include_target(line: &str) -> Option<(&str, Option<&str>)> {
    let rest = line.trim().strip_prefix("#include")?.trim().strip_prefix('"')?;
    let (path, after) = rest.split_once('"')?;
    let after = after.trim();
    match after.strip_prefix("with ") {
        Some(arguments) => Some((path, Some(arguments.trim()))),
        None if after.is_empty() => Some((path, None)),
        None => None,
    }
}

/// Compiles a composed shader into a module. Composition errors are programming errors caught by the
/// naga test below, so they are reported as GPU errors rather than user errors.
pub fn create_module(device: &wgpu::Device, desc: &ShaderDesc) -> crate::Result<wgpu::ShaderModule> {
    let source = desc.compose().map_err(crate::Error::Gpu)?;
    Ok(wgsl_module(device, desc, source))
}

fn wgsl_module(device: &wgpu::Device, desc: &ShaderDesc, source: String) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(desc.entry), source: wgpu::ShaderSource::Wgsl(source.into()) })
}

/// The module for one stage's entry point with its override `constants`: ours where
/// [`spirv::create_module`] compiles it (shaders with variables that need no zeroing, on Vulkan),
/// otherwise [`create_module`]'s, whose pipelines set the constants themselves.
pub fn create_stage_module(
    device: &wgpu::Device,
    desc: &ShaderDesc,
    stage: naga::ShaderStage,
    entry: &str,
    constants: &[(&str, f64)],
) -> crate::Result<wgpu::ShaderModule> {
    let source = desc.compose().map_err(crate::Error::Gpu)?;
    match super::spirv::create_module(device, desc.entry, &source, stage, entry, constants)? {
        Some(module) => Ok(module),
        None => Ok(wgsl_module(device, desc, source)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn validate(desc: &ShaderDesc) {
        let source = desc.compose().unwrap_or_else(|e| panic!("{}: {e}", desc.entry));
        let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}:\n{}", desc.entry, e.emit_to_string(&source)));
        // Shaders that enable a WGSL extension run only on devices with the matching feature.
        let mut capabilities = naga::valid::Capabilities::empty();
        if source.contains("enable primitive_index;") {
            capabilities |= naga::valid::Capabilities::PRIMITIVE_INDEX;
        }
        // Subgroup built-ins need no `enable` in wgpu's WGSL (naga rejects the standard's).
        if ["subgroupAny(", "subgroupBallot("].iter().any(|op| source.contains(op)) {
            capabilities |= naga::valid::Capabilities::SUBGROUP;
        }
        if source.contains("enable wgpu_ray_query;") {
            capabilities |= naga::valid::Capabilities::RAY_QUERY;
        }
        if source.contains("@early_depth_test") {
            capabilities |= naga::valid::Capabilities::EARLY_DEPTH_TEST;
        }
        // Halves packed in 32-bit words (the denoiser's light): wgpu grants them wherever the
        // downlevel flag SHADER_F16_IN_F32 is set, every backend but old OpenGL ES.
        if source.contains("2x16float(") {
            capabilities |= naga::valid::Capabilities::SHADER_FLOAT16_IN_FLOAT32;
        }
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}:\n{}", desc.entry, e.emit_to_string(&source)));
    }

    #[test]
    fn every_shader_parses_and_validates() {
        for desc in crate::passes::catalogue::all_shaders() {
            validate(&desc);
        }
    }

    #[test]
    fn every_embedded_file_is_used() {
        let mut used = HashSet::new();
        for desc in crate::passes::catalogue::all_shaders() {
            let mut seen = HashSet::new();
            desc.append(desc.entry, None, &mut String::new(), &mut seen, &mut Vec::new()).unwrap();
            used.extend(seen.into_iter().map(|key| key.split(" with ").next().unwrap().to_string()));
        }
        for (path, _) in SOURCES {
            assert!(used.contains(*path), "{path} is embedded but no shader includes it");
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

    /// Subgroup walks where they were measured faster: dense lights (particles as exact lights) in
    /// every stage, decals in fragments, dense decals in compute too; none without subgroup operations.
    #[test]
    fn passes_walk_a_subgroup_at_a_time_where_it_pays() {
        use crate::passes::{blended_shade, deferred_shade, forward_shade, visbuffer_shade};
        use crate::plan::ShadingMethods;
        use crate::settings::{DecalMethod, LightMethod, ParticleMethod};
        let sparse = ShadingMethods { lights: LightMethod::Bvh, decals: DecalMethod::Bvh, subgroups: true, ..Default::default() };
        let dense = ShadingMethods { particles: ParticleMethod::Bvh, ..sparse };
        let walks = |desc: ShaderDesc| desc.compose().unwrap().matches("subgroupAny(").count();
        assert_eq!(walks(visbuffer_shade::shader(sparse)), 0, "compute: sparse lights and decals walk per invocation");
        assert_eq!(walks(deferred_shade::shader(dense)), 1, "compute: the dense lights' walk only");
        assert_eq!(walks(visbuffer_shade::shader(dense)), 1);
        assert_eq!(walks(forward_shade::shader(sparse)), 1, "fragments: the decals' walk");
        assert_eq!(walks(blended_shade::shader(dense)), 1, "blended surfaces in compute: the dense lights' walk only");
        assert_eq!(walks(forward_shade::shader(ShadingMethods { subgroups: false, ..dense })), 0);
        assert_eq!(walks(visbuffer_shade::shader(ShadingMethods { subgroups: false, ..dense })), 0);
        // Dense decals walk as a subgroup in compute too, and share their leaves out in every stage.
        let crowded = ShadingMethods { dense_decals: true, ..sparse };
        let shares_out = |desc: ShaderDesc| desc.compose().unwrap().contains("fn decal_box_meets_box(");
        assert_eq!(walks(visbuffer_shade::shader(crowded)), 1, "compute: the dense decals' walk");
        assert_eq!(walks(deferred_shade::shader(crowded)), 1);
        for shader in [visbuffer_shade::shader, deferred_shade::shader, forward_shade::shader, blended_shade::shader] {
            assert!(shares_out(shader(crowded)), "dense decals share their leaves out in every shading pass");
        }
        assert!(!shares_out(forward_shade::shader(sparse)), "fragments: sparse decals' leaves go to every lane whole");
        assert_eq!(walks(visbuffer_shade::shader(ShadingMethods { subgroups: false, ..crowded })), 0);
        assert!(!shares_out(visbuffer_shade::shader(ShadingMethods { subgroups: false, ..crowded })));
        // Crowded decals with cell lists are read from them in every stage, never walked.
        let listed = ShadingMethods { decal_cell_lists: true, ..crowded };
        for shader in [visbuffer_shade::shader, deferred_shade::shader, forward_shade::shader, blended_shade::shader] {
            let source = shader(listed).compose().unwrap();
            assert!(source.contains("fn decal_box_meets_box(") && !source.contains("fn decal_query_next_leaf("));
        }
        // Sparse lights and decals with cell lists built on the GPU are read from them in every stage, never
        // walked.
        let rebuilt = ShadingMethods { gpu_light_lists: true, gpu_decal_lists: true, subgroups: false, ..sparse };
        for shader in [visbuffer_shade::shader, deferred_shade::shader, forward_shade::shader, blended_shade::shader] {
            let source = shader(rebuilt).compose().unwrap();
            assert!(source.contains("cell_list_index(light_first_instance") && !source.contains("fn light_query_next_leaf("));
            assert!(source.contains("cell_list_index(decal_first_instance") && !source.contains("fn decal_query_next_leaf("));
        }
    }

    #[test]
    fn a_shader_directory_replaces_the_embedded_files() {
        let dir = std::env::temp_dir().join(format!("manylights-shaders-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("post")).unwrap();
        std::fs::write(dir.join("post/post_types.wgsl"), "// replaced\n").unwrap();
        let replaced = from_dir(dir.to_str().unwrap(), "post/post_types.wgsl").unwrap();
        assert_eq!(replaced, "// replaced\n");
        let missing = from_dir(dir.to_str().unwrap(), "post/tonemap.wgsl").unwrap_err();
        assert!(missing.contains("MANYLIGHTS_SHADER_DIR") && missing.contains("tonemap.wgsl"), "{missing}");
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn templates_are_instantiated_once_per_value() {
        use crate::plan::ShadingMethods;
        use crate::settings::{DecalMethod, LightMethod};
        let methods = ShadingMethods { lights: LightMethod::Bvh, decals: DecalMethod::Bvh, ..Default::default() };
        let source = crate::passes::visbuffer_shade::shader(methods).compose().unwrap();
        assert_eq!(source.matches("fn light_query_next_leaf(").count(), 1);
        assert_eq!(source.matches("fn decal_query_next_leaf(").count(), 1);
        assert!(!source.contains("VOLUMES_"));
        assert_eq!(include_target(r#"#include "a.wgsl" with X=y"#), Some(("a.wgsl", Some("X=y"))));
        assert_eq!(include_target(r#"#include "a.wgsl""#), Some(("a.wgsl", None)));
    }
}
