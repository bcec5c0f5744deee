//! Our own SPIR-V for shaders that declare a variable in [`UNZEROED_VARIABLES`].
//!
//! WGSL zero-initialises every private and function variable, and naga writes that as an
//! initialiser on the variable, which the driver carries out at the start of every invocation or
//! call. Two arrays make that costly (benchmarks/LOG.md, topic 4): the decal layers' sums, 192 bytes
//! indexed by layer, so in local memory — zeroing them would be most of what a few small decals
//! cost, even for pixels no decal covers — and the closest-hit traversal's stack, 768 bytes zeroed
//! for every reflection ray. Their code never reads an element it has not written (`decal_layers_touched`,
//! the stack's depth), so on Vulkan these shaders are compiled here with the options wgpu's own
//! Vulkan backend uses, the initialisers are removed from the SPIR-V, and the module is passed through
//! (`Features::PASSTHROUGH_SHADERS`). Anywhere else — another backend, or the feature withheld — wgpu
//! compiles the WGSL as usual, with the same results.
//!
//! The words keep the WGSL's binding numbers, while wgpu's Vulkan backend numbers a group's
//! descriptors by their rank among its layout's entries (wgpu-hal's `create_bind_group_layout`), and
//! rewrites the bindings of the modules it compiles to match. The two agree only where each group's
//! bindings are 0, 1, 2, … without a gap, as every shading pass's are (tested below): with bindings
//! 0–3 and 7, say, wgpu numbers the fifth descriptor 4, and the module's 7 names none of them.

use crate::{Error, Result};

/// Variables (private, or local to a function) whose code writes every element before reading it,
/// so they need no zeroing. Names must be unique among the shaders' variables.
pub const UNZEROED_VARIABLES: &[&str] = &["decal_layers", "stack_nodes", "stack_entry"];

const OP_NAME: u32 = 5;
const OP_VARIABLE: u32 = 59;
const HEADER_WORDS: usize = 5;

/// How wgpu's Vulkan backend writes SPIR-V for this device, as far as these shaders care.
#[derive(Clone, Debug, PartialEq)]
struct VulkanTarget {
    lang_version: (u8, u8),
    robust_buffers: bool,
    robust_images: bool,
    native_workgroup_zeroing: bool,
    label_varyings: bool,
}

impl VulkanTarget {
    /// The device's target, or `None` where wgpu must compile the WGSL itself: not Vulkan, or no
    /// passthrough shaders.
    fn of(device: &wgpu::Device) -> Option<Self> {
        if !device.features().contains(wgpu::Features::PASSTHROUGH_SHADERS) {
            return None;
        }
        Self::of_vulkan(device)
    }

    #[cfg(any(target_os = "linux", target_os = "android", target_os = "windows", target_os = "freebsd"))]
    fn of_vulkan(device: &wgpu::Device) -> Option<Self> {
        // SAFETY: the properties are only read; the handles stay owned by wgpu.
        let hal = unsafe { device.as_hal::<wgpu::hal::api::Vulkan>() }?;
        let properties = unsafe { hal.shared_instance().raw_instance().get_physical_device_properties(hal.raw_physical_device()) };
        let extensions = hal.enabled_device_extensions();
        let enabled = |name: &str| extensions.iter().any(|e| e.to_bytes() == name.as_bytes());
        let (major, minor) = (properties.api_version >> 22 & 0x7f, properties.api_version >> 12 & 0x3ff);
        let vulkan_1_3 = (major, minor) >= (1, 3);
        // wgpu's choices (wgpu-hal's `vulkan/adapter.rs`): the newest SPIR-V the Vulkan version
        // takes; bounds checks left to the driver where robustness2 guarantees them (wgpu asks for its
        // robust buffer and image access whenever it enables the extension); varyings labelled except
        // on Qualcomm.
        Some(VulkanTarget {
            lang_version: match (major, minor) {
                (1, 0) => (1, 0),
                (1, 1) => (1, 3),
                (1, 2) => (1, 5),
                _ => (1, 6),
            },
            robust_buffers: enabled("VK_EXT_robustness2") || enabled("VK_KHR_robustness2"),
            robust_images: enabled("VK_EXT_robustness2") || enabled("VK_KHR_robustness2") || vulkan_1_3,
            native_workgroup_zeroing: vulkan_1_3 || enabled("VK_KHR_zero_initialize_workgroup_memory"),
            label_varyings: properties.vendor_id != 0x5143,
        })
    }

    #[cfg(not(any(target_os = "linux", target_os = "android", target_os = "windows", target_os = "freebsd")))]
    fn of_vulkan(_device: &wgpu::Device) -> Option<Self> {
        None
    }

    fn options(&self) -> naga::back::spv::Options<'static> {
        use naga::back::spv;
        use naga::proc::BoundsCheckPolicy::{Restrict, Unchecked};
        let mut flags = spv::WriterFlags::FORCE_POINT_SIZE | spv::WriterFlags::DEBUG;
        flags.set(spv::WriterFlags::LABEL_VARYINGS, self.label_varyings);
        spv::Options {
            lang_version: self.lang_version,
            // Names are how the variables are found again in the words.
            flags,
            // None: naga declares the capabilities the shader uses; the renderer asks for those
            // features before using them.
            capabilities: None,
            bounds_check_policies: naga::proc::BoundsCheckPolicies {
                index: Restrict,
                buffer: if self.robust_buffers { Unchecked } else { Restrict },
                image_load: if self.robust_images { Unchecked } else { Restrict },
                binding_array: Unchecked,
            },
            zero_initialize_workgroup_memory: if self.native_workgroup_zeroing {
                spv::ZeroInitializeWorkgroupMemoryMode::Native
            } else {
                spv::ZeroInitializeWorkgroupMemoryMode::Polyfill
            },
            force_loop_bounding: true,
            ..spv::Options::default()
        }
    }
}

/// The module for one entry point of `source`, compiled here without the zeroing of
/// [`UNZEROED_VARIABLES`]; `None` where the source declares none of them or the device needs
/// wgpu to compile it.
pub fn create_module(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    stage: naga::ShaderStage,
    entry: &str,
    constants: &[(&str, f64)],
) -> Result<Option<wgpu::ShaderModule>> {
    if !UNZEROED_VARIABLES.iter().any(|name| declares_variable(source, name)) {
        return Ok(None);
    }
    let Some(target) = VulkanTarget::of(device) else { return Ok(None) };
    let (words, workgroup_size) = compile(source, stage, entry, constants, &target.options())
        .map_err(|e| Error::Gpu(format!("{label}: compiling {entry} to SPIR-V: {e}")))?;
    log::debug!("{label}: {entry} compiled to SPIR-V by manylights, without zeroing {UNZEROED_VARIABLES:?}");
    let entry_points = [wgpu::PassthroughShaderEntryPoint {
        name: entry.to_owned().into(),
        workgroup_size: (workgroup_size[0], workgroup_size[1], workgroup_size[2]),
    }];
    // SAFETY: the words are naga's SPIR-V of a module naga validated, written with wgpu's options
    // for this device, less initialisers of variables whose code writes before it reads.
    Ok(Some(unsafe {
        device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
            label: Some(label),
            entry_points: entry_points.as_slice().into(),
            spirv: Some(words.into()),
            ..Default::default()
        })
    }))
}

fn declares_variable(source: &str, name: &str) -> bool {
    source.lines().any(|line| {
        let line = line.trim_start();
        let rest = line.strip_prefix("var<private> ").or_else(|| line.strip_prefix("var "));
        rest.and_then(|rest| rest.strip_prefix(name)).is_some_and(|rest| rest.starts_with(':'))
    })
}

/// SPIR-V words of `entry` with the overrides set and the listed variables' initialisers removed,
/// and the entry's workgroup size.
fn compile(
    source: &str,
    stage: naga::ShaderStage,
    entry: &str,
    constants: &[(&str, f64)],
    options: &naga::back::spv::Options,
) -> std::result::Result<(Vec<u32>, [u32; 3]), String> {
    let (words, workgroup_size) = write(source, stage, entry, constants, options)?;
    Ok((without_initialisers(&words, UNZEROED_VARIABLES), workgroup_size))
}

/// naga's SPIR-V words of `entry` with the overrides set, as written, and the entry's workgroup size.
fn write(
    source: &str,
    stage: naga::ShaderStage,
    entry: &str,
    constants: &[(&str, f64)],
    options: &naga::back::spv::Options,
) -> std::result::Result<(Vec<u32>, [u32; 3]), String> {
    let module = naga::front::wgsl::parse_str(source).map_err(|e| e.emit_to_string(source))?;
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .map_err(|e| format!("{:?}", e.into_inner()))?;
    let constants: naga::back::PipelineConstants = constants.iter().map(|&(k, v)| (k.to_owned(), v)).collect();
    let (module, info) =
        naga::back::pipeline_constants::process_overrides(&module, &info, Some((stage, entry)), &constants).map_err(|e| e.to_string())?;
    let workgroup_size = module.entry_points.iter().find(|e| e.name == entry).ok_or(format!("no entry point {entry}"))?.workgroup_size;
    let pipeline = naga::back::spv::PipelineOptions { shader_stage: stage, entry_point: entry.to_owned() };
    let words = naga::back::spv::write_vec(&module, &info, options, Some(&pipeline)).map_err(|e| e.to_string())?;
    Ok((words, workgroup_size))
}

/// `words` with the initialisers of the variables named `names` removed. A name the entry point
/// does not reach has no variable there (naga writes the globals and functions it reaches).
fn without_initialisers(words: &[u32], names: &[&str]) -> Vec<u32> {
    let instructions = || {
        let mut at = HEADER_WORDS;
        std::iter::from_fn(move || {
            let count = (*words.get(at)? >> 16) as usize;
            let instruction = words.get(at..at + count.max(1))?;
            at += count.max(1);
            Some(instruction)
        })
    };
    let targets: Vec<u32> = instructions()
        .filter(|i| i[0] & 0xffff == OP_NAME && i.len() > 2 && names.contains(&literal_string(&i[2..]).as_str()))
        .map(|i| i[1])
        .collect();
    let mut out = words[..HEADER_WORDS.min(words.len())].to_vec();
    for instruction in instructions() {
        // OpVariable: result type, result id, storage class, initialiser.
        if instruction[0] & 0xffff == OP_VARIABLE && instruction.len() == 5 && targets.contains(&instruction[2]) {
            out.push((4 << 16) | OP_VARIABLE);
            out.extend_from_slice(&instruction[1..4]);
        } else {
            out.extend_from_slice(instruction);
        }
    }
    out
}

/// A SPIR-V literal string: UTF-8, nul-terminated, packed little-endian into words.
fn literal_string(words: &[u32]) -> String {
    let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).take_while(|&b| b != 0).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::shaders::ShaderDesc;

    fn target() -> VulkanTarget {
        VulkanTarget {
            lang_version: (1, 6),
            robust_buffers: true,
            robust_images: true,
            native_workgroup_zeroing: true,
            label_varyings: true,
        }
    }

    /// (OpVariable instructions, those with an initialiser) of `words`.
    fn variables(words: &[u32]) -> (usize, usize) {
        let (mut all, mut initialised, mut at) = (0, 0, HEADER_WORDS);
        while at < words.len() {
            let count = (words[at] >> 16) as usize;
            assert!(count > 0 && at + count <= words.len(), "malformed instruction at word {at}");
            if words[at] & 0xffff == OP_VARIABLE {
                all += 1;
                initialised += usize::from(count == 5);
            }
            at += count;
        }
        (all, initialised)
    }

    /// Compiles `entry` of `source` both ways and checks that exactly `removed` initialisers went,
    /// with nothing else changed, and that the words read back as a valid module.
    fn assert_initialisers_removed(source: &str, stage: naga::ShaderStage, entry: &str, constants: &[(&str, f64)], removed: usize) {
        let options = target().options();
        let (as_written, _) = write(source, stage, entry, constants, &options).unwrap();
        let (words, workgroup_size) = compile(source, stage, entry, constants, &options).unwrap();
        let module = naga::front::wgsl::parse_str(source).unwrap();
        assert_eq!(workgroup_size, module.entry_points.iter().find(|e| e.name == entry).unwrap().workgroup_size);
        // A word fewer per initialiser, every instruction still well formed.
        assert_eq!(words.len() + removed, as_written.len());
        let (before, before_initialised) = variables(&as_written);
        let (after, after_initialised) = variables(&words);
        assert_eq!(after, before);
        assert_eq!(after_initialised + removed, before_initialised);
        let back = naga::front::spv::parse_u8_slice(bytemuck::cast_slice(&words), &Default::default()).unwrap();
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all()).validate(&back).unwrap();
    }

    #[test]
    fn the_decal_layers_lose_their_zeroing_and_nothing_else_changes() {
        use crate::plan::ShadingMethods;
        use crate::settings::{DecalMethod, LightMethod};
        let methods = ShadingMethods { lights: LightMethod::Bvh, decals: DecalMethod::Bvh, subgroups: true, ..Default::default() };
        let source = crate::passes::visbuffer_shade::shader(methods).compose().unwrap();
        assert_initialisers_removed(&source, naga::ShaderStage::Compute, "visbuffer_shade", &[("DEBUG_VIEWS", 1.0)], 1);
    }

    #[test]
    fn the_closest_hit_stack_loses_its_zeroing_and_nothing_else_changes() {
        let source = ShaderDesc::new("rays/trace_probe.wgsl").compose().unwrap();
        let entry = naga::front::wgsl::parse_str(&source).unwrap().entry_points[0].name.clone();
        assert_initialisers_removed(&source, naga::ShaderStage::Compute, &entry, &[], 2);
    }

    /// Every shader variant whose SPIR-V this module writes and passes through: its entry, WGSL and
    /// parsed module.
    fn passed_through_shaders() -> Vec<(&'static str, String, naga::Module)> {
        crate::passes::catalogue::all_shaders()
            .into_iter()
            .map(|desc| (desc.entry, desc.compose().unwrap()))
            .filter(|(_, source)| UNZEROED_VARIABLES.iter().any(|name| declares_variable(source, name)))
            .map(|(entry, source)| {
                let module = naga::front::wgsl::parse_str(&source).unwrap();
                (entry, source, module)
            })
            .collect()
    }

    #[test]
    fn every_shader_with_those_variables_compiles_for_each_entry_point() {
        let mut compiled = 0;
        for (shader, source, module) in passed_through_shaders() {
            for entry in module.entry_points.iter().filter(|e| e.stage != naga::ShaderStage::Vertex) {
                compile(&source, entry.stage, &entry.name, &[], &target().options())
                    .unwrap_or_else(|e| panic!("{shader} {}: {e}", entry.name));
                compiled += 1;
            }
        }
        assert!(compiled > 100, "only {compiled} entry points compiled");
    }

    #[test]
    fn shaders_without_those_variables_are_left_to_wgpu() {
        let source = ShaderDesc::new("passes/depth_prepass.wgsl").compose().unwrap();
        assert!(!UNZEROED_VARIABLES.iter().any(|name| declares_variable(&source, name)));
        assert!(declares_variable("var<private> decal_layers: array<f32, 4>;", "decal_layers"));
        assert!(!declares_variable("var<private> decal_layers_touched: u32;", "decal_layers"));
        assert!(!declares_variable("// var<private> decal_layers: u32;", "decal_layers"));
        assert!(declares_variable("    var stack_nodes: array<u32, RAY_STACK_SIZE>;", "stack_nodes"));
    }

    /// The words keep the WGSL's binding numbers, which must then be the ranks wgpu's Vulkan backend
    /// gives the layouts' entries (module docs): 0, 1, 2, … in every group.
    #[test]
    fn shaders_passed_through_number_each_groups_bindings_from_zero_without_gaps() {
        let shaders = passed_through_shaders();
        for (shader, _, module) in &shaders {
            let mut groups: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
            for (_, global) in module.global_variables.iter() {
                if let Some(binding) = &global.binding {
                    groups.entry(binding.group).or_default().push(binding.binding);
                }
            }
            for (group, mut bindings) in groups {
                bindings.sort_unstable();
                let expected: Vec<u32> = (0..bindings.len() as u32).collect();
                assert_eq!(bindings, expected, "{shader}: group {group}'s bindings");
            }
        }
        assert!(shaders.len() > 50, "only {} shaders checked", shaders.len());
    }

    #[test]
    fn truncated_words_stop_the_scan_without_a_panic() {
        let words = [0x0723_0203, 0x0001_0600, 0, 10, 0, (5 << 16) | OP_VARIABLE, 1, 2];
        assert_eq!(without_initialisers(&words, &["x"]), words[..5].to_vec());
    }
}
