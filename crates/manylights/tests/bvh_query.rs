//! The WGSL point query (`accel/bvh.wgsl`), run on the GPU, reaches exactly the lights the CPU oracle
//! finds: for every point, the set of lights whose volume contains it (`accel::light_contains`).

use glam::Vec3;
use manylights::{
    accel::{gpu::LightBvhBuffers, light_contains},
    gpu::{readback, scene::GpuLight, shaders, shaders::ShaderDesc, GpuContext},
    scene::{Light, LightKind},
};
use rand::{Rng, SeedableRng};
use wgpu::util::DeviceExt;

fn random_lights(count: usize, rng: &mut rand_pcg::Pcg64) -> Vec<Light> {
    (0..count)
        .map(|i| {
            let kind = if i % 3 == 0 {
                let outer: f32 = rng.random_range(0.02..1.57);
                LightKind::Spot { inner_cone_angle: outer * 0.5, outer_cone_angle: outer }
            } else {
                LightKind::Point
            };
            let direction = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)).normalize();
            Light {
                kind,
                position: Vec3::new(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0)),
                direction,
                color: Vec3::ONE,
                intensity: 1.0,
                // Mostly small volumes, a few huge ones that overlap everything.
                range: if i % 97 == 0 { rng.random_range(10.0..30.0) } else { rng.random_range(0.2..3.0) },
            }
        })
        .collect()
}

/// Per point: (count, Σ index, Σ index²) of the lights the GPU query reaches and the tight test keeps.
fn gpu_query(ctx: &GpuContext, lights: &[Light], points: &[Vec3]) -> Vec<[u32; 4]> {
    let device = &ctx.device;
    let bvh = LightBvhBuffers::build_static(ctx, lights).unwrap();
    // Bindings cannot be empty; with no lights the query never reads the padding.
    let mut gpu_lights: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
    if gpu_lights.is_empty() {
        gpu_lights.push(bytemuck::Zeroable::zeroed());
    }
    let gpu_points: Vec<[f32; 4]> = points.iter().map(|p| p.extend(1.0).to_array()).collect();
    let storage = |contents: &[u8], usage| device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage });
    let light_buffer = storage(bytemuck::cast_slice(&gpu_lights), wgpu::BufferUsages::STORAGE);
    let point_buffer = storage(bytemuck::cast_slice(&gpu_points), wgpu::BufferUsages::STORAGE);
    let results_size = (points.len() * 16) as u64;
    let results = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: results_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size: results_size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });

    let entry = |binding, read_only| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    };
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: None,
        entries: &[entry(0, true), entry(1, true), entry(2, false)],
    });
    let module = shaders::create_module(device, &ShaderDesc::new("accel/bvh_query_probe.wgsl")).unwrap();
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("bvh_query_probe"),
        layout: Some(&device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[Some(&layout), None, Some(&bvh.bind_group_layout)],
            immediate_size: 0,
        })),
        module: &module,
        entry_point: Some("bvh_query_probe"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: light_buffer.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: point_buffer.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: results.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_bind_group(2, &bvh.bind_group, &[]);
        pass.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&results, 0, &readback_buffer, 0, results_size);
    ctx.queue.submit([encoder.finish()]);
    let out: Vec<[u32; 4]> = readback::map_buffer(ctx, &readback_buffer, 0, results_size).unwrap();
    ctx.check_errors().unwrap();
    out
}

fn cpu_oracle(lights: &[Light], p: Vec3) -> [u32; 4] {
    let mut summary = [0u32; 4];
    for (i, _) in lights.iter().enumerate().filter(|(_, l)| light_contains(l, p)) {
        let i = i as u32;
        summary[0] += 1;
        summary[1] = summary[1].wrapping_add(i);
        summary[2] = summary[2].wrapping_add(i.wrapping_mul(i));
    }
    summary
}

#[test]
fn gpu_point_queries_equal_the_cpu_oracle() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
    for count in [0, 1, 5, 3000] {
        let lights = random_lights(count, &mut rng);
        let points: Vec<Vec3> = (0..4096)
            .map(|_| Vec3::new(rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0), rng.random_range(-12.0..12.0)))
            .collect();
        let gpu = gpu_query(&ctx, &lights, &points);
        let mut reached = 0;
        for (p, got) in points.iter().zip(&gpu) {
            let expected = cpu_oracle(&lights, *p);
            assert_eq!(*got, expected, "{count} lights, point {p}: GPU (count, Σi, Σi²) differs from the CPU oracle");
            reached += expected[0];
        }
        if count == 3000 {
            assert!(reached > 4096, "the test points reach too few lights ({reached}) to mean much");
        }
    }
}
