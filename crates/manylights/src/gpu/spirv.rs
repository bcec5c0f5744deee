//! Our own SPIR-V for shaders that declare a private variable in [`UNINITIALISED_PRIVATES`].
//!
//! WGSL zero-initialises every private variable, and naga writes that as an initialiser on the
//! variable, which the driver carries out at the start of every invocation. The decal layers' sums
//! are a 192-byte array indexed by layer, so it lives in local memory, and zeroing it cost 0.75 ms
//! of the forward pass and 0.04–0.05 ms of the compute shading passes at 1080p on the H100, most of
//! what 100 small decals cost there, even for pixels no decal covers (BENCHMARKS.md). Its code never
//! reads a layer it has not written (`decal_layers_touched`), so on Vulkan these shaders are compiled
//! here with the options wgpu's own Vulkan backend uses, the initialiser is removed from the SPIR-V,
//! and the module is passed through (`Features::PASSTHROUGH_SHADERS`). Anywhere else — another
//! backend, or the feature withheld — wgpu compiles the WGSL as usual, with the same results.

use crate::{Error, Result};

/// Private variables whose code writes every element before reading it, so they need no zeroing.
pub const UNINITIALISED_PRIVATES: &[&str] = &["decal_layers"];

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
/// [`UNINITIALISED_PRIVATES`]; `None` where the source declares none of them or the device needs
/// wgpu to compile it.
pub fn create_module(
    device: &wgpu::Device,
    label: &str,
    source: &str,
    stage: naga::ShaderStage,
    entry: &str,
    constants: &[(&str, f64)],
) -> Result<Option<wgpu::ShaderModule>> {
    if !UNINITIALISED_PRIVATES.iter().any(|name| declares_private(source, name)) {
        return Ok(None);
    }
    let Some(target) = VulkanTarget::of(device) else { return Ok(None) };
    let (words, workgroup_size) = compile(source, stage, entry, constants, &target.options())
        .map_err(|e| Error::Gpu(format!("{label}: compiling {entry} to SPIR-V: {e}")))?;
    log::debug!("{label}: {entry} compiled to SPIR-V by manylights, without zeroing {UNINITIALISED_PRIVATES:?}");
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

fn declares_private(source: &str, name: &str) -> bool {
    source.lines().any(|line| {
        line.trim_start().strip_prefix("var<private> ").and_then(|rest| rest.strip_prefix(name)).is_some_and(|rest| rest.starts_with(':'))
    })
}

/// SPIR-V words of `entry` with the overrides set and the listed privates' initialisers removed,
/// and the entry's workgroup size.
fn compile(
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
    Ok((without_initialisers(&words, UNINITIALISED_PRIVATES), workgroup_size))
}

/// `words` with the initialisers of the variables named `names` removed. A name the entry point
/// does not use has no variable there (naga writes the globals an entry point reaches).
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

    #[test]
    fn the_decal_layers_lose_their_zeroing_and_nothing_else_changes() {
        use crate::pipelines::{DecalMethod, LightMethod, ShadingMethods};
        let methods = ShadingMethods { lights: LightMethod::Bvh, decals: DecalMethod::Bvh, subgroups: true, ..Default::default() };
        let source = crate::passes::visbuffer_shade::shader(methods).compose().unwrap();
        assert!(declares_private(&source, "decal_layers"));
        let options = target().options();
        let constants = [("DEBUG_VIEWS", 1.0)];
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        let info =
            naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all()).validate(&module).unwrap();
        let constants_map: naga::back::PipelineConstants = constants.iter().map(|&(k, v)| (k.to_owned(), v)).collect();
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &module,
            &info,
            Some((naga::ShaderStage::Compute, "visbuffer_shade")),
            &constants_map,
        )
        .unwrap();
        let pipeline = naga::back::spv::PipelineOptions { shader_stage: naga::ShaderStage::Compute, entry_point: "visbuffer_shade".into() };
        let as_written = naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline)).unwrap();

        let (words, workgroup_size) = compile(&source, naga::ShaderStage::Compute, "visbuffer_shade", &constants, &options).unwrap();
        assert_eq!(workgroup_size, module.entry_points.iter().find(|e| e.name == "visbuffer_shade").unwrap().workgroup_size);
        // One word fewer: one initialiser gone, every instruction still well formed.
        assert_eq!(words.len() + 1, as_written.len());
        let (before, before_initialised) = variables(&as_written);
        let (after, after_initialised) = variables(&words);
        assert_eq!(after, before);
        assert_eq!(after_initialised + 1, before_initialised);
        // The words read back as a valid module.
        let back = naga::front::spv::parse_u8_slice(bytemuck::cast_slice(&words), &Default::default()).unwrap();
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all()).validate(&back).unwrap();
    }

    #[test]
    fn every_shader_with_those_privates_compiles_for_each_entry_point() {
        let mut compiled = 0;
        for desc in crate::gpu::shaders::all_shaders() {
            let source = desc.compose().unwrap();
            if !UNINITIALISED_PRIVATES.iter().any(|name| declares_private(&source, name)) {
                continue;
            }
            let module = naga::front::wgsl::parse_str(&source).unwrap();
            for entry in module.entry_points.iter().filter(|e| e.stage != naga::ShaderStage::Vertex) {
                compile(&source, entry.stage, &entry.name, &[], &target().options())
                    .unwrap_or_else(|e| panic!("{} {}: {e}", desc.entry, entry.name));
                compiled += 1;
            }
        }
        assert!(compiled > 100, "only {compiled} entry points compiled");
    }

    #[test]
    fn shaders_without_those_privates_are_left_to_wgpu() {
        let source = ShaderDesc::new("passes/depth_prepass.wgsl").compose().unwrap();
        assert!(!UNINITIALISED_PRIVATES.iter().any(|name| declares_private(&source, name)));
        assert!(declares_private("var<private> decal_layers: array<f32, 4>;", "decal_layers"));
        assert!(!declares_private("var<private> decal_layers_touched: u32;", "decal_layers"));
        assert!(!declares_private("// var<private> decal_layers: u32;", "decal_layers"));
    }

    #[test]
    fn truncated_words_stop_the_scan_without_a_panic() {
        let words = [0x0723_0203, 0x0001_0600, 0, 10, 0, (5 << 16) | OP_VARIABLE, 1, 2];
        assert_eq!(without_initialisers(&words, &["x"]), words[..5].to_vec());
    }
}
