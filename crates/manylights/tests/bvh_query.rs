//! The WGSL point query (`accel/volume_query.wgsl`, and `volume_query_subgroup.wgsl` walked a
//! subgroup at a time), run on the GPU through the two-level structure, reaches exactly the lights the
//! CPU oracle finds: for every point, the lights of every group instance whose volume, placed in the
//! world, contains it (`accel::light_contains`). Points come scattered (every lane of a subgroup far
//! from the others) and in tight clusters (neighbouring pixels' points).

use glam::{Affine3A, Quat, Vec3};
use manylights::{
    accel::{light_contains, volume_query_probe_shader, VolumeStructure, CPU_TOP_LEVEL_MAX_INSTANCES},
    gpu::{readback, shaders, GpuContext},
    plan::{rebuilt_leaves, GroupBuild, GroupLists, StructurePlan},
    scene::{GroupInstance, Groups, Light, LightKind, Spin},
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
                cast_shadows: false,
            }
        })
        .collect()
}

/// Per point: (count, Σ index, Σ index²) of the lights the GPU query reaches and the tight test keeps.
fn gpu_query(
    ctx: &GpuContext,
    lights: &[Light],
    groups: &Groups,
    (build, subgroups): (GroupBuild, bool),
    time: f32,
    points: &[Vec3],
) -> Vec<[u32; 4]> {
    let device = &ctx.device;
    // Rebuilt groups get the leaves the plan gives the walk, wider where subgroups walk them.
    let plan = StructurePlan {
        build,
        clustered: false,
        wide_leaves: false,
        rebuilt_leaves: rebuilt_leaves(subgroups),
        rebuilt_grids: true,
        cell_lists: GroupLists::None,
        light_tree: false,
        hardware: false,
    };
    let mut structure = VolumeStructure::for_lights(ctx, lights, groups, &plan, None).unwrap();
    let gpu_points: Vec<[f32; 4]> = points.iter().map(|p| p.extend(1.0).to_array()).collect();
    let storage = |contents: &[u8], usage| device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage });
    let point_buffer = storage(bytemuck::cast_slice(&gpu_points), wgpu::BufferUsages::STORAGE);
    let count_buffer = storage(bytemuck::bytes_of(&structure.instance_count()), wgpu::BufferUsages::STORAGE);
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
        entries: &[entry(0, true), entry(1, false), entry(2, true)],
    });
    let module = shaders::create_module(device, &volume_query_probe_shader(subgroups)).unwrap();
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("volume_query_probe"),
        layout: Some(&device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[None, Some(&layout), Some(&structure.bind_group_layout)],
            immediate_size: 0,
        })),
        module: &module,
        entry_point: Some("volume_query_probe"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: point_buffer.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: results.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: count_buffer.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    structure.record(ctx, &mut encoder, None, time).unwrap();
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_bind_group(2, &structure.bind_group, &[]);
        pass.dispatch_workgroups((points.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&results, 0, &readback_buffer, 0, results_size);
    ctx.queue.submit([encoder.finish()]);
    let out: Vec<[u32; 4]> = readback::map_buffer(ctx, &readback_buffer, 0, results_size).unwrap();
    ctx.check_errors().unwrap();
    out
}

/// A light of a group placed by an instance transform (similarity), as `light_in_world` places it.
fn placed(light: &Light, world_from_group: &Affine3A) -> Light {
    let scale = world_from_group.matrix3.x_axis.length();
    Light {
        position: world_from_group.transform_point3(light.position),
        direction: world_from_group.transform_vector3(light.direction) / scale,
        range: light.range * scale,
        ..*light
    }
}

fn cpu_oracle(lights: &[Light], groups: &Groups, time: f32, p: Vec3) -> [u32; 4] {
    let (ranges, instances) = groups.resolve(lights.len());
    let mut summary = [0u32; 4];
    for instance in &instances {
        let transform = instance.world_from_group_at(time);
        for i in ranges[instance.group].clone() {
            if light_contains(&placed(&lights[i], &transform), p) {
                let i = i as u32;
                summary[0] += 1;
                summary[1] = summary[1].wrapping_add(i);
                summary[2] = summary[2].wrapping_add(i.wrapping_mul(i));
            }
        }
    }
    summary
}

fn random_point(rng: &mut rand_pcg::Pcg64, half_extent: f32) -> Vec3 {
    Vec3::new(
        rng.random_range(-half_extent..half_extent),
        rng.random_range(-half_extent..half_extent),
        rng.random_range(-half_extent..half_extent),
    )
}

/// Queries 4,096 scattered points and 4,096 in clusters of 64 within 0.3 m, with every build and both
/// walks; returns the lights the scattered points reach.
fn check(ctx: &GpuContext, lights: &[Light], groups: &Groups, time: f32, rng: &mut rand_pcg::Pcg64) -> u32 {
    assert!(
        ctx.features.contains(wgpu::Features::SUBGROUP),
        "{} has no subgroup operations, so the subgroup walk would go untested",
        ctx.describe()
    );
    let scattered: Vec<Vec3> = (0..4096).map(|_| random_point(rng, 12.0)).collect();
    let clustered: Vec<Vec3> = (0..64)
        .flat_map(|_| {
            let centre = random_point(rng, 10.0);
            (0..64).map(|_| centre + random_point(rng, 0.3)).collect::<Vec<_>>()
        })
        .collect();
    let mut reached = 0;
    for (points, name) in [(&scattered, "scattered"), (&clustered, "clustered")] {
        let expected: Vec<[u32; 4]> = points.iter().map(|p| cpu_oracle(lights, groups, time, *p)).collect();
        for build in [GroupBuild::CpuOnce, GroupBuild::GpuEveryFrame] {
            for subgroups in [false, true] {
                let gpu = gpu_query(ctx, lights, groups, (build, subgroups), time, points);
                for ((p, got), expected) in points.iter().zip(&gpu).zip(&expected) {
                    assert_eq!(
                        got,
                        expected,
                        "{} lights, {build:?}, subgroups {subgroups}, {name} point {p}: GPU (count, Σi, Σi²) differs from the CPU oracle",
                        lights.len()
                    );
                }
            }
        }
        if name == "scattered" {
            reached = expected.iter().map(|e| e[0]).sum();
        }
    }
    reached
}

#[test]
fn gpu_point_queries_equal_the_cpu_oracle() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(42);
    for count in [0, 1, 5, 3000] {
        let lights = random_lights(count, &mut rng);
        let reached = check(&ctx, &lights, &Groups::default(), 0.0, &mut rng);
        if count == 3000 {
            assert!(reached > 4096, "the test points reach too few lights ({reached}) to mean much");
        }
    }
}

/// Groups placed by instances: one group twice (rotated, scaled), an empty group, a spinning group
/// seen at a later time, and one left where it is.
#[test]
fn instanced_and_moving_groups_are_queried_in_their_own_space() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let lights = random_lights(3000, &mut rng);
    let still = |world_from_group| GroupInstance { group: 0, world_from_group, spin: None };
    let groups = Groups {
        sizes: vec![1000, 0, 1500, 500],
        instances: vec![
            still(Affine3A::IDENTITY),
            still(Affine3A::from_scale_rotation_translation(Vec3::splat(1.5), Quat::from_rotation_z(0.7), Vec3::new(3.0, -2.0, 1.0))),
            GroupInstance { group: 1, ..still(Affine3A::IDENTITY) },
            GroupInstance {
                group: 2,
                world_from_group: Affine3A::from_translation(Vec3::new(-1.0, 0.5, 2.0)),
                spin: Some(Spin { pivot: Vec3::new(2.0, 0.0, -1.0), radians_per_second: 0.9 }),
            },
            GroupInstance { group: 3, ..still(Affine3A::IDENTITY) },
        ],
    };
    let reached = check(&ctx, &lights, &groups, 0.7, &mut rng);
    assert!(reached > 4096, "the test points reach too few lights ({reached}) to mean much");
}

/// More instances than the CPU builds a top level for: the GPU builds it, and queries stay exact.
#[test]
fn many_instances_get_a_gpu_built_top_level() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(11);
    let lights = random_lights(40, &mut rng);
    let count = CPU_TOP_LEVEL_MAX_INSTANCES + 1;
    let instances = (0..count)
        .map(|i| {
            let offset = Vec3::new(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0));
            let world_from_group = Affine3A::from_scale_rotation_translation(Vec3::splat(0.3), Quat::from_rotation_y(i as f32), offset);
            let spin = (i % 3 == 0).then_some(Spin { pivot: offset, radians_per_second: 0.5 });
            GroupInstance { group: i % 2, world_from_group, spin }
        })
        .collect();
    let groups = Groups { sizes: vec![25, 15], instances };
    let reached = check(&ctx, &lights, &groups, 1.3, &mut rng);
    assert!(reached > 4096, "the test points reach too few lights ({reached}) to mean much");
}
