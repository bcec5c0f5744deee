//! The GPU context: a headless wgpu instance, the chosen adapter, its device and queue.
//!
//! Configured from the environment like wgpu's own tools: `WGPU_BACKEND` (vulkan, metal, dx12, gl)
//! restricts backends, `WGPU_ADAPTER_NAME` picks the first adapter whose name contains it
//! (case-insensitive). Otherwise a discrete GPU is preferred, then integrated, virtual, and finally a
//! CPU adapter such as Mesa's lavapipe.

use std::sync::{Arc, Mutex};

use crate::{Error, Result};

/// Storage buffers the shading passes bind at once: the scene's ten (four for geometry and
/// materials, three for the ray hierarchy, restir's reservoirs, the denoiser's samples, the surface
/// motions), the lights' seven (their light tree too), the decals' six (`shading/*_bindings.wgsl`)
/// and the blended surfaces' layer heads and layers (`passes/blended_shade.wgsl`).
const REQUIRED_STORAGE_BUFFERS: u32 = 25;
/// Features the renderer uses when the adapter has them; none is required by every scene.
/// `primitive_index` lets the visibility raster draw indexed; `subgroups` let passes walk BVHs a
/// subgroup at a time where that is faster (`plan::query_walks`).
const OPTIONAL_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::PRIMITIVE_INDEX)
    .union(wgpu::Features::SUBGROUP)
    // Our SPIR-V for shaders whose variables need no zeroing (`gpu/spirv.rs`).
    .union(wgpu::Features::PASSTHROUGH_SHADERS)
    // Forward fragments keeping `restir`'s reservoirs test depth first (`plan::FramePlan::keeps_reservoirs`).
    .union(wgpu::Features::SHADER_EARLY_DEPTH_TEST)
    // The hardware ray backend (`settings::RayBackend`, `accel/hardware.rs`).
    .union(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
    // Raster passes draw a run of draws in one indirect call, each taking its draw index as its
    // first instance (`GpuScene::draw_arguments`).
    .union(wgpu::Features::INDIRECT_FIRST_INSTANCE);

/// Clones share the device: several renderers (a benchmark's configurations) can use one.
#[derive(Clone)]
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Features requested from the device (a subset of `OPTIONAL_FEATURES`).
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    /// Iterations a shader's loops get in all, where the driver cuts them short (`gpu::loop_limit`).
    pub loop_limit: Option<u32>,
    /// Errors the device reported outside an error scope; checked after each frame.
    errors: Arc<Mutex<Vec<String>>>,
}

/// What `manylights info` prints about one adapter.
#[derive(Clone, Debug)]
pub struct AdapterSummary {
    pub info: wgpu::AdapterInfo,
    pub usable: Result<(), String>,
    /// The adapter has ray queries (`settings::RayBackend::Hardware`).
    pub ray_queries: bool,
}

/// Vulkan, Metal and DX12 unless WGPU_BACKEND says otherwise: the GL backend lacks what the renderer
/// needs, and probing it prints driver noise on headless machines. A window (the viewer) creates its
/// surface on this instance too: Vulkan, Metal and DX12 need no display handle up front.
pub fn instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle().with_env();
    desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
    wgpu::Instance::new(desc)
}

/// Why an adapter cannot run the renderer, if it cannot.
fn unusable_reason(adapter: &wgpu::Adapter) -> Result<(), String> {
    let downlevel = adapter.get_downlevel_capabilities();
    if !downlevel.flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) {
        return Err("no compute shaders".into());
    }
    if !downlevel.is_webgpu_compliant() {
        return Err("not WebGPU compliant (downlevel backend)".into());
    }
    Ok(())
}

/// Higher is better: device type first, then native backends before GL.
fn preference(info: &wgpu::AdapterInfo) -> (u8, u8) {
    let kind = match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 4,
        wgpu::DeviceType::IntegratedGpu => 3,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 1,
        wgpu::DeviceType::Other => 0,
    };
    let backend = u8::from(info.backend != wgpu::Backend::Gl);
    (kind, backend)
}

fn name_filter() -> Option<String> {
    std::env::var("WGPU_ADAPTER_NAME").ok().filter(|s| !s.is_empty()).map(|s| s.to_lowercase())
}

/// Every adapter wgpu can see, with whether the renderer can use it.
pub fn list_adapters() -> Vec<AdapterSummary> {
    let adapters = pollster::block_on(instance().enumerate_adapters(wgpu::Backends::all()));
    adapters
        .iter()
        .map(|a| AdapterSummary {
            info: a.get_info(),
            usable: unusable_reason(a),
            ray_queries: a.features().contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY),
        })
        .collect()
}

impl GpuContext {
    /// The limits the settings are checked against (`RenderConfig::validate`).
    pub fn device_limits(&self) -> crate::settings::DeviceLimits {
        crate::settings::DeviceLimits {
            max_texture_dimension_2d: self.limits.max_texture_dimension_2d,
            max_texture_dimension_3d: self.limits.max_texture_dimension_3d,
            max_buffer_size: self.limits.max_buffer_size,
        }
    }

    /// Whether `bytes` of `what` fit one storage binding; if not, "the {what} take N MiB, over this
    /// GPU's storage binding limit of M MiB", for the caller to end with the fix.
    pub fn check_storage_binding(&self, what: &str, bytes: u64) -> std::result::Result<(), String> {
        let limit = self.limits.max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(format!("the {what} take {} MiB, over this GPU's storage binding limit of {} MiB", bytes >> 20, limit >> 20));
        }
        Ok(())
    }

    /// Picks an adapter as described in the module docs and opens a device on it.
    pub fn new() -> Result<Self> {
        Self::without(wgpu::Features::empty())
    }

    /// Like [`GpuContext::new`], but never requests `withheld`: tests use it to run the paths taken on
    /// devices that lack a feature.
    pub fn without(withheld: wgpu::Features) -> Result<Self> {
        Self::choose(&instance(), None, withheld)
    }

    /// Like [`GpuContext::new`], among the adapters of `instance` that can present to `surface`.
    pub fn for_surface(instance: &wgpu::Instance, surface: &wgpu::Surface<'_>) -> Result<Self> {
        Self::choose(instance, Some(surface), wgpu::Features::empty())
    }

    fn choose(instance: &wgpu::Instance, surface: Option<&wgpu::Surface<'_>>, withheld: wgpu::Features) -> Result<Self> {
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::all()));
        let seen: Vec<String> = adapters.iter().map(|a| describe(&a.get_info())).collect();
        let filter = name_filter();
        let adapter = adapters
            .into_iter()
            .filter(|a| unusable_reason(a).is_ok())
            .filter(|a| surface.is_none_or(|s| a.is_surface_supported(s)))
            .filter(|a| filter.as_ref().is_none_or(|f| a.get_info().name.to_lowercase().contains(f)))
            .max_by_key(|a| preference(&a.get_info()))
            .ok_or_else(|| Error::NoAdapter {
                detail: match (&filter, seen.is_empty()) {
                    (_, true) => String::new(),
                    (Some(f), false) => format!(" matching WGPU_ADAPTER_NAME=\"{f}\" (adapters present: {})", seen.join("; ")),
                    (None, false) => format!(" (adapters present but unusable: {})", seen.join("; ")),
                },
            })?;
        Self::open(adapter, withheld)
    }

    fn open(adapter: wgpu::Adapter, withheld: wgpu::Features) -> Result<Self> {
        let info = adapter.get_info();
        if adapter.limits().max_storage_buffers_per_shader_stage < REQUIRED_STORAGE_BUFFERS {
            return Err(Error::NoAdapter {
                detail: format!(
                    ": {} offers {} storage buffers per shader stage and manylights needs {REQUIRED_STORAGE_BUFFERS}",
                    info.name,
                    adapter.limits().max_storage_buffers_per_shader_stage
                ),
            });
        }
        let features = adapter.features() & (OPTIONAL_FEATURES - withheld);
        let available = adapter.limits();
        // Large scenes need large buffers and texture arrays: take what the adapter offers for the
        // limits that grow with the scene or the image, defaults for the rest.
        let limits = wgpu::Limits {
            max_buffer_size: available.max_buffer_size,
            max_storage_buffer_binding_size: available.max_storage_buffer_binding_size,
            max_texture_dimension_2d: available.max_texture_dimension_2d,
            max_texture_array_layers: available.max_texture_array_layers,
            // Shading binds the scene's, the lights' and the decals' buffers at once.
            max_storage_buffers_per_shader_stage: available.max_storage_buffers_per_shader_stage,
            max_buffers_and_acceleration_structures_per_shader_stage: available.max_buffers_and_acceleration_structures_per_shader_stage,
            ..wgpu::Limits::default().using_resolution(available.clone())
        };
        let limits = if features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
            limits.using_acceleration_structure_values(available.clone())
        } else {
            limits
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("manylights"),
            required_features: features,
            required_limits: limits.clone(),
            // wgpu calls its ray queries experimental: their API may change, and they are requested
            // only where the adapter reports every Vulkan extension they need (wgpu-hal's adapter).
            // SAFETY: the renderer uses them only through wgpu's validated API.
            experimental_features: if features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
                unsafe { wgpu::ExperimentalFeatures::enabled() }
            } else {
                wgpu::ExperimentalFeatures::disabled()
            },
            ..Default::default()
        }))
        .map_err(|e| Error::Gpu(format!("cannot open a device on {}: {e}", describe(&info))))?;

        // wgpu's default handler panics; collect errors instead so they surface as `Error::Gpu`.
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            sink.lock().unwrap_or_else(|p| p.into_inner()).push(e.to_string());
        }));
        let mut ctx = Self { adapter, device, queue, info, features, limits, loop_limit: None, errors };
        // Only software rasterisers have been seen to cut loops short; a GPU is not probed.
        if ctx.info.device_type == wgpu::DeviceType::Cpu {
            ctx.loop_limit = super::loop_limit::probe(&ctx)?;
        }
        Ok(ctx)
    }

    /// Whether the device traces ray queries in hardware (`settings::RayBackend::Hardware`).
    pub fn has_ray_queries(&self) -> bool {
        self.features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
    }

    pub fn has_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Returns the first error the device reported since the last check, if any.
    pub fn check_errors(&self) -> Result<()> {
        let mut errors = self.errors.lock().unwrap_or_else(|p| p.into_inner());
        let first = errors.drain(..).next();
        first.map_or(Ok(()), |e| Err(Error::Gpu(e)))
    }

    /// Waits until the GPU has finished all submitted work.
    pub fn wait_idle(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::Wait { submission_index: None, timeout: None })
            .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
        Ok(())
    }

    pub fn describe(&self) -> String {
        describe(&self.info)
    }
}

/// One line naming an adapter, its backend, type and driver.
pub fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?}, driver: {} {})", info.name, info.backend, info.device_type, info.driver, info.driver_info)
}
