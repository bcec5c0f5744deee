//! Whether the driver cuts shader loops short. Mesa's llvmpipe (lavapipe) before its loop limiter was
//! removed ends every loop of an invocation once all of them together have run 65,535 iterations, so
//! a brute-force loop over more lights would silently leave lights out. The probe runs one loop longer
//! than that and counts the iterations it gets; [`GpuContext::new`] runs it on CPU adapters only.

use wgpu::util::DeviceExt;

use super::{readback, GpuContext};
use crate::Result;

/// Iterations the probe asks for: more than any known limiter allows.
const PROBE_ITERATIONS: u32 = 100_000;

/// The loop's bound comes from a buffer, so no compiler can fold the loop away.
const PROBE_WGSL: &str = "
@group(0) @binding(0) var<storage, read_write> counts: array<u32, 2>;

@compute @workgroup_size(1)
fn probe() {
    let bound = counts[0];
    var done = 0u;
    for (var i = 0u; i < bound; i++) {
        done += 1u;
    }
    counts[1] = done;
}
";

/// The iterations a shader's loops get in all, when fewer than [`PROBE_ITERATIONS`]: `None` means no
/// limit was found.
pub(crate) fn probe(ctx: &GpuContext) -> Result<Option<u32>> {
    let device = &ctx.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("loop limit probe"),
        source: wgpu::ShaderSource::Wgsl(PROBE_WGSL.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("loop limit probe"),
        layout: None,
        module: &module,
        entry_point: Some("probe"),
        compilation_options: Default::default(),
        cache: None,
    });
    let counts = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("loop limit probe"),
        contents: bytemuck::cast_slice(&[PROBE_ITERATIONS, 0]),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("loop limit probe"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry { binding: 0, resource: counts.as_entire_binding() }],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let [_, done] = readback::read_buffer::<u32>(ctx, &counts)?[..] else { return Ok(None) };
    Ok((done < PROBE_ITERATIONS).then_some(done))
}

/// What a frame's loops may need beyond the driver's limit: the brute-force and clustered loops over
/// `lights` and `decals` (a cluster's list can hold them all). The message names the driver's
/// limit and the ways out; `None` when every light and decal is shaded.
pub fn loop_limit_problem(limit: Option<u32>, driver: &str, loops: &[(&str, &str, usize)]) -> Option<String> {
    let limit = limit? as usize;
    let total: usize = loops.iter().map(|&(_, _, count)| count).sum();
    if total <= limit {
        return None;
    }
    let looped: Vec<String> = loops.iter().filter(|l| l.2 > 0).map(|(what, method, count)| format!("{count} {what} by {method}")).collect();
    Some(format!(
        "this driver ({driver}) ends a shader's loops after {limit} iterations in all, so shading {} would leave some out; \
         use --light-method bvh / --decal-method bvh, or install Mesa 25's lavapipe (on Debian 12: \
         apt-get install -t bookworm-backports mesa-vulkan-drivers), which has no such limit",
        looped.join(" and ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loops_past_the_limit_are_refused_and_name_what_loops() {
        let loops = [("lights", "brute force", 60_000), ("decals", "clustered shading", 6_000)];
        assert_eq!(loop_limit_problem(None, "any", &loops), None);
        assert_eq!(loop_limit_problem(Some(65_535), "llvmpipe", &loops[..1]), None);
        let message = loop_limit_problem(Some(65_535), "llvmpipe (Mesa 22.3.6)", &loops).unwrap();
        assert!(message.contains("65535 iterations") && message.contains("60000 lights by brute force"), "{message}");
        assert!(message.contains("6000 decals by clustered shading") && message.contains("bookworm-backports"), "{message}");
    }
}
