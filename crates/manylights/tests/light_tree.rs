//! The light tree's draws (`shading/light_tree.wgsl`, `accel/light_tree.rs`), run on the GPU: each
//! draw reports the probability of the leaf it reaches, which equals the product of the child choices
//! a CPU oracle computes from the same importance; the oracle's probabilities of all leaves and of
//! the draws that find no light sum to one; and the histogram of many draws matches them.

use std::collections::HashMap;

use glam::Vec3;
use manylights::{
    accel::{light_aabb, light_tree::light_tree_nodes, light_tree::LightTreeNode, Bvh, BvhNode, VolumeStructure},
    gpu::{readback, scene::GpuLight, shaders, shaders::ShaderDesc, GpuContext},
    plan::{DynamicLeaves, GroupBuild, GroupLists, StructurePlan},
    scene::{Groups, Light, LightKind},
};
use rand::{Rng, SeedableRng};
use wgpu::util::DeviceExt;

const DRAWS: u32 = 1 << 16;

fn random_lights(count: usize, rng: &mut rand_pcg::Pcg64) -> Vec<Light> {
    (0..count)
        .map(|i| Light {
            kind: LightKind::Point,
            position: Vec3::new(rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0), rng.random_range(-10.0..10.0)),
            direction: Vec3::NEG_Z,
            color: Vec3::new(rng.random_range(0.1..1.0), rng.random_range(0.1..1.0), rng.random_range(0.1..1.0)),
            intensity: rng.random_range(0.5..20.0),
            range: if i % 61 == 0 { rng.random_range(10.0..30.0) } else { rng.random_range(1.0..6.0) },
            cast_shadows: false,
        })
        .collect()
}

/// `shading/light_tree.wgsl`'s importance, on the CPU.
fn importance(node: &BvhNode, emitters: &LightTreeNode, p: Vec3, n: Vec3) -> f32 {
    if p.cmplt(Vec3::from(node.min)).any() || p.cmpgt(Vec3::from(node.max)).any() {
        return 0.0;
    }
    let (low, high) = (Vec3::from(emitters.min), Vec3::from(emitters.max));
    let gap = (low - p).max(p - high).max(Vec3::ZERO);
    let nearest_ratio_sq = gap.length_squared() / (emitters.range * emitters.range);
    // Also zero where the ratio is not a number, as the shader's test has it.
    if nearest_ratio_sq.is_nan() || nearest_ratio_sq >= 1.0 {
        return 0.0;
    }
    let window = 1.0 - nearest_ratio_sq * nearest_ratio_sq;
    let (centre, half_extent) = (0.5 * (low + high), 0.5 * (high - low));
    if n.dot(centre - p) + n.abs().dot(half_extent) <= 0.0 {
        return 0.0;
    }
    let to_centre = centre - p;
    let (distance_sq, radius_sq) = (to_centre.length_squared(), half_extent.length_squared());
    let mut cosine = 1.0;
    if distance_sq > radius_sq {
        let cos_centre = n.dot(to_centre) / (distance_sq * n.length_squared()).max(1e-30).sqrt();
        let cos_sphere = (1.0 - radius_sq / distance_sq).sqrt();
        if cos_centre < cos_sphere {
            let sin_centre = (1.0 - cos_centre * cos_centre).max(0.0).sqrt();
            cosine = (cos_centre * cos_sphere + sin_centre * (radius_sq / distance_sq).sqrt()).max(1e-6);
        }
    }
    emitters.power * cosine * window * window / distance_sq.max(radius_sq.max(1e-8))
}

/// Every leaf's probability (by its first item) and the probability that a draw finds no light.
fn oracle(bvh: &Bvh, tree: &[LightTreeNode], p: Vec3, n: Vec3) -> (HashMap<u32, f64>, f64) {
    let mut leaves = HashMap::new();
    let mut failed = 0.0;
    let mut stack = vec![(0usize, 1.0f64)];
    while let Some((index, probability)) = stack.pop() {
        let node = &bvh.nodes[index];
        if node.is_leaf() {
            leaves.insert(node.leaf_first(), probability);
            continue;
        }
        let (first, second) = (node.entry as usize, bvh.nodes[node.entry as usize].skip as usize);
        let a = importance(&bvh.nodes[first], &tree[first], p, n);
        let b = importance(&bvh.nodes[second], &tree[second], p, n);
        if a + b <= 0.0 || (a + b).is_nan() {
            failed += probability;
            continue;
        }
        let chance = f64::from(a / (a + b));
        stack.push((first, probability * chance));
        stack.push((second, probability * (1.0 - chance)));
    }
    (leaves, failed)
}

/// Per draw at `p` facing `n`: (first item of the leaf reached, or `None` where no light was found,
/// and the reported probability).
fn gpu_draws(ctx: &GpuContext, structure: &mut VolumeStructure, p: Vec3, n: Vec3) -> Vec<(Option<u32>, f32)> {
    let device = &ctx.device;
    let storage = |contents: &[u8], usage| device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: None, contents, usage });
    let probe = storage(bytemuck::cast_slice(&[p.extend(1.0).to_array(), n.extend(0.0).to_array()]), wgpu::BufferUsages::STORAGE);
    let size = u64::from(DRAWS) * 16;
    let draws = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: None,
        size,
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
    let layout =
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[entry(0, true), entry(1, false)] });
    let module = shaders::create_module(device, &ShaderDesc::new("shading/light_tree_probe.wgsl")).unwrap();
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("light_tree_probe"),
        layout: Some(&device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: &[None, Some(&layout), Some(&structure.bind_group_layout)],
            immediate_size: 0,
        })),
        module: &module,
        entry_point: Some("light_tree_probe"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: probe.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: draws.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    // Places the instance (the top level and its instance records).
    structure.record(ctx, &mut encoder, None, 0.0).unwrap();
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.set_bind_group(2, &structure.bind_group, &[]);
        pass.dispatch_workgroups(DRAWS.div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&draws, 0, &readback_buffer, 0, size);
    ctx.queue.submit([encoder.finish()]);
    let out: Vec<[u32; 4]> = readback::map_buffer(ctx, &readback_buffer, 0, size).unwrap();
    ctx.check_errors().unwrap();
    out.into_iter().map(|[_, drawn, probability, first]| ((drawn == 1).then_some(first), f32::from_bits(probability))).collect()
}

#[test]
fn the_trees_draws_have_the_probabilities_they_report_and_these_sum_to_one() {
    let ctx = GpuContext::new().expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
    let lights = random_lights(600, &mut rng);
    // One group, placed once at the origin.
    let groups = Groups::default();
    let plan = StructurePlan {
        build: GroupBuild::CpuOnce,
        clustered: false,
        wide_leaves: false,
        rebuilt_leaves: DynamicLeaves::AtMost(1),
        rebuilt_grids: false,
        cell_lists: GroupLists::None,
        light_tree: true,
        hardware: false,
    };
    let mut structure = VolumeStructure::for_lights(&ctx, &lights, &groups, &plan, None).unwrap();
    // The oracle's tree: the structure builds the same BVH over the same boxes.
    let boxes: Vec<_> = lights.iter().map(light_aabb).collect();
    let bvh = Bvh::build(&boxes).unwrap();
    let records: Vec<GpuLight> = lights.iter().map(GpuLight::from).collect();
    let tree = light_tree_nodes(&bvh, &records);
    for _ in 0..6 {
        let p = Vec3::new(rng.random_range(-8.0..8.0), rng.random_range(-8.0..8.0), rng.random_range(-8.0..8.0));
        let n = Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)).normalize();
        let (leaves, failed) = oracle(&bvh, &tree, p, n);
        let total: f64 = leaves.values().sum::<f64>() + failed;
        assert!((total - 1.0).abs() <= 1e-9, "at {p}: the oracle's probabilities sum to {total}");
        let draws = gpu_draws(&ctx, &mut structure, p, n);
        let mut counts: HashMap<Option<u32>, u32> = HashMap::new();
        for &(leaf, reported) in &draws {
            *counts.entry(leaf).or_default() += 1;
            if let Some(first) = leaf {
                let expected = leaves[&first];
                assert!(
                    (f64::from(reported) - expected).abs() <= 1e-4 * expected,
                    "at {p}: leaf {first} reported {reported}, its probability is {expected}"
                );
            }
        }
        // Each leaf's share of the draws, and the share that found no light, within five standard
        // deviations of its probability.
        let expected = leaves.iter().map(|(&first, &p)| (Some(first), p)).chain([(None, failed)]);
        for (leaf, probability) in expected {
            let share = f64::from(counts.get(&leaf).copied().unwrap_or(0)) / f64::from(DRAWS);
            let deviation = (probability * (1.0 - probability) / f64::from(DRAWS)).sqrt();
            assert!(
                (share - probability).abs() <= 5.0 * deviation + 2.0 / f64::from(DRAWS),
                "at {p}: {leaf:?} drawn {share} of the time, its probability {probability}"
            );
        }
        assert!(leaves.len() >= 10, "at {p}: only {} leaves can be drawn", leaves.len());
    }
}
