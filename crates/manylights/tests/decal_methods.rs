//! Decals through the acceleration structure and the clustered lists give the brute-force image (linear HDR, max abs
//! difference ≤ 1e-3), with thousands of decals and lights, grouped and moving; 0 decals work, 1M
//! decals fit, and bad decals are rejected.

mod common;

use std::path::PathBuf;

use common::*;
use glam::{Affine3A, Quat, Vec3};
use manylights::{
    accel::overlap,
    accel::VolumeStructure,
    gpu::cluster_grid::ClusterGrid,
    gpu::GpuContext,
    plan::{rebuilt_leaves, Capabilities, FramePlan, GroupBuild, GroupLists, Measurements, RayQueries, StructurePlan},
    renderer::{Image, Renderer},
    scene::{
        self,
        demo::demo_scene,
        generators::{self, ScatterDecals, ScatterLights},
        Decal, GroupInstance, Groups, Material, Scene, Texture, TextureRef, Wrap,
    },
    settings::BvhBuild,
    settings::RenderConfig,
    settings::{DecalMethod, LightMethod, PipelineKind, RaySettings},
};

const TOLERANCE: f32 = 1e-3;

fn decal_config(width: u32, height: u32, decals: DecalMethod, build: BvhBuild) -> RenderConfig {
    RenderConfig { decal_method: decals, decal_bvh_build: build, ..config(width, height, LightMethod::Bvh) }
}

fn render_at(scene: &Scene, config: RenderConfig, time: f32) -> Image<[f32; 4]> {
    let mut r = renderer(scene, config);
    r.time = time;
    r.render(&scene.cameras[0]).expect("frame");
    r.read_hdr().expect("hdr")
}

fn assert_decal_methods_agree(scene: &Scene, width: u32, height: u32, time: f32) {
    let brute = render_at(scene, decal_config(width, height, DecalMethod::Brute, BvhBuild::CpuOnce), time);
    let methods =
        [(DecalMethod::Bvh, BvhBuild::CpuOnce), (DecalMethod::Bvh, BvhBuild::GpuEveryFrame), (DecalMethod::Clustered, BvhBuild::CpuOnce)];
    for (method, build) in methods {
        let image = render_at(scene, decal_config(width, height, method, build), time);
        let difference = max_abs_difference(&brute, &image);
        assert!(difference <= TOLERANCE, "{} decals ({build:?}): max abs difference {difference} from brute force", method.name());
    }
}

fn with_decals_and_lights(mut scene: Scene, decals: usize, lights: usize, seed: u64) -> Scene {
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: decals, seed, size: None }).unwrap();
    generators::add_scattered_lights(&mut scene, &ScatterLights { count: lights, seed: seed + 1, ..Default::default() }).unwrap();
    scene
}

/// Mean difference the decals make: the tests must exercise them, not an empty path.
fn decal_effect(scene: &Scene, width: u32, height: u32) -> f32 {
    let mut bare = scene.clone();
    bare.decals.clear();
    bare.decal_groups = Default::default();
    let config = decal_config(width, height, DecalMethod::Brute, BvhBuild::CpuOnce);
    let (with, without) = (render_at(scene, config.clone(), 0.0), render_at(&bare, config, 0.0));
    with.pixels.iter().zip(&without.pixels).map(|(a, b)| (luminance(*a) - luminance(*b)).abs()).sum::<f32>() / with.pixels.len() as f32
}

#[test]
fn demo_with_thousands_of_decals() {
    let scene = with_decals_and_lights(demo_scene(), 2000, 500, 21);
    assert!(decal_effect(&scene, 96, 54) > 1e-3, "the decals barely change the image");
    assert_decal_methods_agree(&scene, 128, 72, 0.0);
}

/// Sparse decals as one group placed once (here turned, and spinning) are read from cell lists built
/// on the GPU in place of their BVH, rebuilt every frame or built once as the BVH would be, and blend
/// in every pipeline as brute force does, reflections' hits too.
#[test]
fn sparse_decals_of_one_group_are_read_from_cell_lists() {
    let mut scene = with_decals_and_lights(demo_scene(), 1500, 200, 31);
    for (i, decal) in scene.decals.iter_mut().enumerate() {
        decal.layer = (i % 3) as u32;
    }
    scene.decal_groups = Groups {
        sizes: vec![scene.decals.len()],
        instances: vec![GroupInstance {
            group: 0,
            world_from_group: Affine3A::from_rotation_translation(Quat::from_rotation_y(-0.3), Vec3::new(-0.2, 0.0, 0.3)),
            spin: Some(scene::Spin { pivot: Vec3::new(0.4, 0.0, -0.4), radians_per_second: 0.4 }),
        }],
    };
    assert!(decal_effect(&scene, 64, 36) > 1e-3, "the decals barely change the image");
    for pipeline in PipelineKind::ALL {
        let reflections = RaySettings { reflection_bounces: u32::from(pipeline == PipelineKind::Visbuffer), ..Default::default() };
        let at = |method, build| RenderConfig { pipeline, rays: reflections, ..decal_config(96, 54, method, build) };
        let brute = render_at(&scene, at(DecalMethod::Brute, BvhBuild::CpuOnce), 0.7);
        // Rebuilt every frame, the lists are built in every frame; built once, in the first only.
        for (build, builds_per_frame) in [(BvhBuild::GpuEveryFrame, [true, true]), (BvhBuild::CpuOnce, [true, false])] {
            let mut listed = renderer(&scene, at(DecalMethod::Bvh, build));
            assert!(listed.shading_methods().gpu_decal_lists, "{} {build:?}: the decals are not listed", pipeline.name());
            assert!(listed.has_timestamps(), "the test needs an adapter with timestamp queries");
            listed.time = 0.7;
            for built in builds_per_frame {
                let passes = listed.render(&scene.cameras[0]).expect("frame");
                let timed = passes.iter().any(|&(name, _)| name == "decal_cell_lists_build");
                assert_eq!(timed, built, "{} {build:?}: the lists' build ran {timed} in a frame", pipeline.name());
                let difference = max_abs_difference(&brute, &listed.read_hdr().unwrap());
                assert!(difference <= TOLERANCE, "{} {build:?}: max abs difference {difference} from brute force", pipeline.name());
                listed.time = 0.7;
            }
        }
    }
}

/// Renders `scene`'s crowded decals by brute force and through their structure in every pipeline, and
/// requires the same image; the structure, built as the renderer builds it, must have wide leaves, and
/// cell lists as `cell_lists` says.
fn assert_dense_decals_agree(scene: &Scene, cell_lists: bool, time: f32) {
    let ctx = GpuContext::new().expect("a GPU adapter");
    assert!(ctx.features.contains(wgpu::Features::SUBGROUP), "the test needs an adapter with subgroup operations");
    let config = decal_config(128, 72, DecalMethod::Bvh, BvhBuild::CpuOnce);
    let caps = Capabilities { subgroups: true, early_depth_test: true, ray_queries: RayQueries::None };
    let stats = overlap::scene_statistics(scene, Measurements::for_settings(&config, caps)).unwrap();
    let plan = FramePlan::resolve(&config, caps, &stats).unwrap();
    let structure = VolumeStructure::for_decals(&ctx, &scene.decals, &scene.decal_groups, &plan.decals, None, 0).unwrap();
    let overlap = stats.decal_centre_overlap.expect("measured for bvh decals on a device with subgroups");
    assert!(structure.wide_leaves(), "{overlap} boxes hold a decal's centre: too few to count as dense");
    assert_eq!(structure.cell_lists(), cell_lists);
    assert!(decal_effect(scene, 96, 54) > 1e-3, "the decals barely change the image");
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
        let config = |method| RenderConfig { pipeline, ..decal_config(128, 72, method, BvhBuild::CpuOnce) };
        let mut bvh = renderer(scene, config(DecalMethod::Bvh));
        assert_eq!(bvh.shading_methods().decal_cell_lists, cell_lists, "{}: shading reads the cell lists", pipeline.name());
        bvh.time = time;
        bvh.render(&scene.cameras[0]).expect("frame");
        let difference = max_abs_difference(&render_at(scene, config(DecalMethod::Brute), time), &bvh.read_hdr().expect("hdr"));
        assert!(difference <= TOLERANCE, "{}: bvh differs from brute force by {difference}", pipeline.name());
    }
}

/// Decals crowded into one group placed once get cell lists (`accel/cell_lists.rs`), which shading
/// reads instead of walking, each cell's list shared out among the lanes in that cell
/// (`decals_bvh_cells.wgsl`; lavapipe's subgroups have 8 lanes): still the brute-force image, in
/// compute passes and in fragments. Rebuilt every frame, they are read from cell lists rebuilt in
/// place of their BVH (`accel/rebuilt_cell_lists.rs`), not shared out.
#[test]
fn dense_decals_read_from_cell_lists_agree_with_brute_force() {
    let mut scene = demo_scene();
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: 3000, seed: 4, size: Some(1.5) }).unwrap();
    assert_dense_decals_agree(&scene, true, 0.0);
    for pipeline in [PipelineKind::Deferred, PipelineKind::Forward] {
        let config = |method| RenderConfig { pipeline, ..decal_config(128, 72, method, BvhBuild::GpuEveryFrame) };
        let mut rebuilt = renderer(&scene, config(DecalMethod::Bvh));
        let methods = rebuilt.shading_methods();
        assert!(methods.gpu_decal_lists && !methods.dense_decals, "{}: rebuilt dense decals are not listed", pipeline.name());
        rebuilt.render(&scene.cameras[0]).expect("frame");
        let difference = max_abs_difference(&render_at(&scene, config(DecalMethod::Brute), 0.0), &rebuilt.read_hdr().expect("hdr"));
        assert!(difference <= TOLERANCE, "{}: rebuilt lists differ from brute force by {difference}", pipeline.name());
    }
}

/// Cell lists run top layer first, and shading skips the decals of layers hidden by those above them:
/// layers that leave no transmittance in albedo and none in normals (`decal_lowest_shown`). A third of
/// these crowded decals are opaque with a normal map, hiding everything below them; a third are
/// opaque without one, leaving the normals of the layers below showing; the rest are the stamps. Still
/// the brute-force image.
#[test]
fn dense_decals_under_opaque_layers_agree_with_brute_force() {
    let mut scene = demo_scene();
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: 3000, seed: 5, size: Some(1.5) }).unwrap();
    let n = Vec3::new(0.5, 0.3, 0.8).normalize();
    let texel = ((n * 0.5 + 0.5) * 255.0).round();
    scene.textures.push(Texture {
        name: "tilted".into(),
        width: 4,
        height: 4,
        rgba8: [texel.x as u8, texel.y as u8, texel.z as u8, 255].repeat(16),
    });
    let normal_map = TextureRef::new(scene.textures.len() - 1, Wrap::ClampToEdge, Wrap::ClampToEdge);
    let opaque = |color: Vec3, normal_texture: Option<TextureRef>| Material {
        base_color_factor: color.extend(1.0),
        roughness_factor: 0.4,
        normal_texture,
        ..Default::default()
    };
    scene.materials.push(opaque(Vec3::new(0.9, 0.2, 0.1), Some(normal_map)));
    scene.materials.push(opaque(Vec3::new(0.1, 0.3, 0.9), None));
    let (hiding, flat) = (scene.materials.len() - 2, scene.materials.len() - 1);
    for (i, decal) in scene.decals.iter_mut().enumerate() {
        match i % 3 {
            0 => decal.material = hiding,
            1 => decal.material = flat,
            _ => {}
        }
    }
    assert_dense_decals_agree(&scene, true, 0.0);
}

/// Crowded decals in spinning groups get wide leaves and no cell lists (rebuilt every frame, leaves of
/// 32): shading walks them a subgroup at a time, sharing each leaf's decals out among the lanes
/// (`passes::query_walks`, `decal_leaves_shared_out.wgsl`), and still gives the brute-force image.
#[test]
fn dense_grouped_decals_shared_out_among_lanes_agree_with_brute_force() {
    let mut scene = demo_scene();
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: 3000, seed: 4, size: Some(1.5) }).unwrap();
    generators::group_for_animation(&mut scene, 6, 2).unwrap();
    assert_dense_decals_agree(&scene, false, 0.7);
    // Rebuilt on the GPU every frame, they are shared out from the LBVH's leaves.
    for pipeline in [PipelineKind::Visbuffer, PipelineKind::Forward] {
        let config = |method| RenderConfig { pipeline, ..decal_config(128, 72, method, BvhBuild::GpuEveryFrame) };
        let mut bvh = renderer(&scene, config(DecalMethod::Bvh));
        assert!(bvh.shading_methods().dense_decals, "{}: rebuilt dense decals are not shared out", pipeline.name());
        bvh.time = 0.7;
        bvh.render(&scene.cameras[0]).expect("frame");
        let difference = max_abs_difference(&render_at(&scene, config(DecalMethod::Brute), 0.7), &bvh.read_hdr().expect("hdr"));
        assert!(difference <= TOLERANCE, "{}: rebuilt bvh differs from brute force by {difference}", pipeline.name());
    }
}

/// Wall-sized decals reach more froxels than one thread walks: the clustered build spreads them over
/// workgroups (`cluster_build.wgsl`), beside small decals walked by single threads.
#[test]
fn large_decals_over_whole_walls() {
    let mut scene = with_decals_and_lights(demo_scene(), 200, 100, 8);
    generators::add_large_decals(&mut scene, &generators::LargeDecals { count: 6, seed: 3 }).unwrap();
    assert!(decal_effect(&scene, 96, 54) > 1e-3, "the decals barely change the image");
    assert_decal_methods_agree(&scene, 128, 72, 0.0);
}

#[test]
fn sponza_with_thousands_of_decals_and_lights() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/sponza/Sponza.gltf");
    let mut scene = with_decals_and_lights(scene::load_path(&path).unwrap(), 3000, 2000, 5);
    scene.ambient = Vec3::splat(0.05);
    assert!(decal_effect(&scene, 64, 36) > 1e-4, "the decals barely change the image");
    assert_decal_methods_agree(&scene, 96, 54, 0.0);
}

#[test]
fn grouped_spinning_decals_and_lights() {
    let mut scene = with_decals_and_lights(demo_scene(), 2000, 800, 8);
    generators::group_for_animation(&mut scene, 12, 3).unwrap();
    // Lights too: both structures' top levels are rebuilt for the time.
    let brute = render_at(
        &scene,
        RenderConfig { light_method: LightMethod::Brute, ..decal_config(128, 72, DecalMethod::Brute, BvhBuild::CpuOnce) },
        0.9,
    );
    for build in [BvhBuild::CpuOnce, BvhBuild::GpuEveryFrame] {
        let config = RenderConfig { light_bvh_build: build, ..decal_config(128, 72, DecalMethod::Bvh, build) };
        let bvh = render_at(&scene, config, 0.9);
        let difference = max_abs_difference(&brute, &bvh);
        assert!(difference <= TOLERANCE, "{build:?}: max abs difference {difference} from brute force");
    }
    // And moving them changes the picture.
    let at_zero = render_at(&scene, decal_config(128, 72, DecalMethod::Bvh, BvhBuild::CpuOnce), 0.0);
    assert!(max_abs_difference(&brute, &at_zero) > 0.01, "spinning groups did not move");
}

/// Decals are tested in their group's space: a group placed by a rotated, scaled instance gives the
/// image of the same decals placed in the world directly, normal maps included.
#[test]
fn a_rotated_scaled_instance_renders_as_its_decals_placed_in_the_world() {
    let mut world = with_decals_and_lights(demo_scene(), 2000, 300, 17);
    world.ambient = Vec3::splat(0.2);
    let world_from_group = Affine3A::from_scale_rotation_translation(
        Vec3::splat(1.7),
        Quat::from_axis_angle(Vec3::new(0.3, 1.0, -0.4).normalize(), 0.9),
        Vec3::new(0.5, -0.2, 1.1),
    );
    let mut grouped = world.clone();
    for decal in &mut grouped.decals {
        decal.world_from_decal = world_from_group.inverse() * decal.world_from_decal;
    }
    grouped.decal_groups =
        Groups { sizes: vec![grouped.decals.len()], instances: vec![GroupInstance { group: 0, world_from_group, spin: None }] };
    assert!(decal_effect(&world, 96, 54) > 1e-3, "the decals barely change the image");
    let expected = render_at(&world, decal_config(128, 72, DecalMethod::Brute, BvhBuild::CpuOnce), 0.0);
    for method in [DecalMethod::Brute, DecalMethod::Bvh, DecalMethod::Clustered] {
        let image = render_at(&grouped, decal_config(128, 72, method, BvhBuild::CpuOnce), 0.0);
        let difference = max_abs_difference(&expected, &image);
        assert!(difference <= TOLERANCE, "{} decals through the instance: max abs difference {difference}", method.name());
    }
}

#[test]
fn frames_rendered_back_to_back_move_the_groups() {
    let mut scene = with_decals_and_lights(demo_scene(), 500, 300, 4);
    generators::group_for_animation(&mut scene, 4, 9).unwrap();
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut r = Renderer::new(ctx, &scene, decal_config(64, 36, DecalMethod::Bvh, BvhBuild::CpuOnce)).unwrap();
    r.render_frames(&scene.cameras[0], 30).unwrap();
    let after_30 = r.read_hdr().unwrap();
    // The last of 30 frames is drawn at 29 frame intervals.
    let expected =
        render_at(&scene, decal_config(64, 36, DecalMethod::Brute, BvhBuild::CpuOnce), 29.0 * manylights::renderer::FRAME_INTERVAL);
    let difference = max_abs_difference(&expected, &after_30);
    assert!(difference <= TOLERANCE, "frame 30 differs by {difference} from a frame rendered at its time");
}

#[test]
fn no_decals() {
    let scene = with_decals_and_lights(demo_scene(), 0, 100, 1);
    assert!(scene.decals.is_empty());
    assert_decal_methods_agree(&scene, 64, 36, 0.0);
}

#[test]
fn a_million_decals_fit() {
    // 1M decals (64 MiB) and their BVH (64 MiB) stay under lavapipe's 128 MiB storage bindings.
    let base = demo_scene();
    let mut scene = base.clone();
    generators::add_scattered_decals(&mut scene, &ScatterDecals { count: 1 << 20, seed: 2, size: Some(0.05) }).unwrap();
    let config = decal_config(64, 36, DecalMethod::Bvh, BvhBuild::GpuEveryFrame);
    let with = render_at(&scene, config.clone(), 0.0);
    let without = render_at(&base, config, 0.0);
    assert!(with.pixels.iter().all(|p| p.iter().all(|c| c.is_finite())));
    assert!(max_abs_difference(&with, &without) > 0.01, "a million decals changed nothing");
}

/// A structure stores its decals in leaf order, so the decals deferred decals draw in layer order are
/// the stored ones: their layers never decrease, each layer's range holds that layer's decals, and
/// every decal is drawn once. A BVH rebuilt on the GPU puts its items in a new leaf order every
/// frame, out of the CPU's sight: clustered lists (binned in the CPU's order) and deferred decals
/// refuse such a structure with an error saying to build once on the CPU.
#[test]
fn decals_keep_their_layers_in_leaf_order_and_gpu_rebuilds_refuse_cpu_ordered_uses() {
    let ctx = GpuContext::new().expect("a GPU adapter");
    let mut scene = with_decals_and_lights(demo_scene(), 200, 0, 3);
    for (i, decal) in scene.decals.iter_mut().enumerate() {
        decal.layer = (i * 7 % 4) as u32;
    }
    let frame_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &[] });
    let grid = ClusterGrid::for_resolution(64, 36);
    let structure = |build, clustered: bool| {
        let plan = StructurePlan {
            build,
            clustered,
            wide_leaves: false,
            rebuilt_leaves: rebuilt_leaves(false),
            rebuilt_grids: true,
            cell_lists: GroupLists::None,
            light_tree: false,
            hardware: false,
        };
        VolumeStructure::for_decals(&ctx, &scene.decals, &scene.decal_groups, &plan, clustered.then_some((grid, &frame_layout)), 0)
    };
    let message = structure(GroupBuild::GpuEveryFrame, true).err().expect("clustered lists over GPU rebuilds are an error").to_string();
    assert!(message.contains("clustered") && message.contains("once on the CPU"), "{message}");
    let rebuilt = structure(GroupBuild::GpuEveryFrame, false).expect("a GPU-rebuilt structure");
    let message = rebuilt.pairs_in_layer_order().expect_err("layer order over GPU rebuilds is an error").to_string();
    assert!(message.contains("layer order") && message.contains("once on the CPU"), "{message}");
    let built = structure(GroupBuild::CpuOnce, false).unwrap();
    let mut stored: Vec<u32> = built.scene_indices().to_vec();
    assert!(stored.iter().enumerate().any(|(i, &s)| s != i as u32), "the decals are not reordered: the test would prove nothing");
    let (pairs, ranges) = built.pairs_in_layer_order().expect("layer order of a CPU-built structure");
    let layer_of = |item: u32| scene.decals[built.scene_indices()[item as usize] as usize].layer;
    let layers: Vec<u32> = pairs.iter().map(|&[_, item]| layer_of(item)).collect();
    assert!(layers.windows(2).all(|w| w[0] <= w[1]), "deferred decals would draw layers out of order: {layers:?}");
    for range in &ranges {
        let in_range = &layers[range.start as usize..range.end as usize];
        assert!(in_range.iter().all(|&l| l == in_range[0]), "a layer's range mixes layers {in_range:?}");
    }
    assert_eq!(ranges.len(), 4, "four layers in use");
    stored.sort_unstable();
    assert!(stored.iter().enumerate().all(|(i, &s)| s == i as u32), "the stored decals are not a permutation of the scene's");
    let mut drawn: Vec<u32> = pairs.iter().map(|&[_, item]| item).collect();
    drawn.sort_unstable();
    assert!(drawn.iter().enumerate().all(|(i, &d)| d == i as u32), "every stored decal is drawn once");
}

#[test]
fn non_finite_or_degenerate_decals_are_rejected() {
    let mut scene = with_decals_and_lights(demo_scene(), 10, 0, 1);
    let material = scene.decals[0].material;
    let cases = [
        (Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)), "NaN or infinite"),
        (Affine3A::from_scale(Vec3::new(1.0, f32::INFINITY, 1.0)), "NaN or infinite"),
        (Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)), "degenerate"),
    ];
    for (transform, reason) in cases {
        scene.decals[3] = Decal { world_from_decal: transform, material, layer: 0, weight: 1.0 };
        let ctx = GpuContext::new().expect("a GPU adapter");
        let err =
            Renderer::new(ctx, &scene, decal_config(64, 36, DecalMethod::Bvh, BvhBuild::CpuOnce)).err().expect("a bad decal is an error");
        let message = err.to_string();
        assert!(message.contains("decal 3") && message.contains(reason), "{message}");
    }
}

#[test]
fn grouping_for_animation_changes_nothing_at_time_zero() {
    let scene = with_decals_and_lights(demo_scene(), 1000, 1000, 12);
    let mut grouped = scene.clone();
    generators::group_for_animation(&mut grouped, 16, 5).unwrap();
    let config = decal_config(96, 54, DecalMethod::Bvh, BvhBuild::CpuOnce);
    let (before, after) = (render_at(&scene, config.clone(), 0.0), render_at(&grouped, config, 0.0));
    let difference = max_abs_difference(&before, &after);
    assert!(difference <= TOLERANCE, "grouped scene differs by {difference} at time 0");
}
