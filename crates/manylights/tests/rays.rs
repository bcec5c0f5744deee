//! Ray traversal on the GPU (`rays/trace.wgsl`, through `rays/trace_probe.wgsl`) against a CPU
//! reference: every triangle of every instance tested in f64, no hierarchy. Instanced, rotated,
//! non-uniformly scaled, mirrored and degenerate instances; closest and any hits; alpha-masked and
//! blended materials.

mod common;

use glam::{DMat4, DVec3, Mat4, Quat, Vec3, Vec4};
use manylights::{
    gpu::{bindings, readback, shaders::ShaderDesc, GpuContext, GpuScene},
    rays::{RayStructure, ALPHA_MASKED},
    scene::{self, AlphaMode, Instance, Material, Mesh, Primitive, Scene, Texture, TextureRef, Vertex, Wrap},
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// What the GPU reports for one ray: the distance and which triangle, as (scene instance,
/// primitive, triangle within the primitive).
#[derive(Clone, Copy, Debug, PartialEq)]
struct GpuHit {
    t: f32,
    triangle: Option<(usize, usize, usize)>,
}

/// Runs the probe over `rays` (origin, t_max, direction, any-hit).
fn trace_on_gpu(scene: &Scene, rays: &[(Vec3, f32, Vec3, bool)]) -> Vec<GpuHit> {
    let ctx = GpuContext::new().expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)");
    let structure = RayStructure::build(scene).unwrap();
    let gpu_scene = GpuScene::upload(&ctx, scene, 64, 1, None, structure.buffers(), Default::default()).unwrap();
    let device = &ctx.device;
    let packed: Vec<[f32; 4]> = rays
        .iter()
        .flat_map(|&(o, t_max, d, any)| [o.extend(t_max).to_array(), d.extend(if any { 1.0 } else { 0.0 }).to_array()])
        .collect();
    use wgpu::util::DeviceExt;
    let ray_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("probe rays"),
        contents: bytemuck::cast_slice(&packed),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let hit_buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("probe hits"),
        size: (packed.len() * 16) as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let layout = bindings::layout(
        device,
        "trace_probe",
        &[bindings::storage_read(0, wgpu::ShaderStages::COMPUTE), bindings::storage_read_write(1, wgpu::ShaderStages::COMPUTE)],
    );
    let pipeline = bindings::compute_pipeline(
        device,
        "trace_probe",
        &ShaderDesc::new("rays/trace_probe.wgsl"),
        &[&gpu_scene.bind_group_layout, &layout],
    )
    .unwrap();
    let bind_group =
        bindings::bind_group(device, "trace_probe", &layout, vec![ray_buffer.as_entire_binding(), hit_buffer.as_entire_binding()]);
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &gpu_scene.bind_group, &[]);
        pass.set_bind_group(1, &bind_group, &[]);
        pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let out: Vec<[f32; 4]> = readback::read_buffer(&ctx, &hit_buffer).unwrap();
    ctx.check_errors().unwrap();
    out.chunks_exact(2)
        .map(|pair| {
            let triangle = pair[0][1].to_bits();
            let hit = (triangle != u32::MAX).then(|| {
                let tri = &structure.triangles[triangle as usize];
                let instance = &structure.instances[pair[0][2].to_bits() as usize];
                (instance.scene_instance as usize, (tri.draw_offset & !ALPHA_MASKED) as usize, tri.triangle as usize)
            });
            GpuHit { t: pair[0][0], triangle: hit }
        })
        .collect()
}

/// One hit of the CPU reference: distance, triangle, how close to the triangle's edge (its smallest
/// barycentric) and how square to it the ray meets it (|cos| to the plane's normal).
#[derive(Clone, Copy, Debug)]
struct CpuHit {
    t: f64,
    triangle: (usize, usize, usize),
    edge_distance: f64,
    facing: f64,
}

impl CpuHit {
    /// A hit rounding may turn into a miss (or a miss into a hit): at an edge or edge-on.
    fn grazing(&self) -> bool {
        self.edge_distance < 1e-4 || self.facing < 1e-3
    }
}

/// Every hit of the ray, nearest first, over every triangle of every opaque or masked primitive, in
/// f64.
fn cpu_trace(scene: &Scene, origin: DVec3, dir: DVec3) -> Vec<CpuHit> {
    let mut hits = Vec::new();
    for (ii, instance) in scene.instances.iter().enumerate() {
        let m: DMat4 = instance.world_from_local.as_dmat4();
        for (pi, primitive) in scene.meshes[instance.mesh].primitives.iter().enumerate() {
            if scene.materials[primitive.material].alpha_mode == AlphaMode::Blend {
                continue;
            }
            for (ti, corners) in primitive.indices.chunks_exact(3).enumerate() {
                let [v0, v1, v2] =
                    [0, 1, 2].map(|k| m.transform_point3(Vec3::from(primitive.vertices[corners[k] as usize].position).as_dvec3()));
                let (e1, e2) = (v1 - v0, v2 - v0);
                let p = dir.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-300 {
                    continue;
                }
                let s = origin - v0;
                let b1 = s.dot(p) / det;
                let q = s.cross(e1);
                let b2 = dir.dot(q) / det;
                if b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0 {
                    continue;
                }
                let t = e2.dot(q) / det;
                if t > 0.0 {
                    let facing = e1.cross(e2).normalize().dot(dir).abs() / dir.length();
                    hits.push(CpuHit { t, triangle: (ii, pi, ti), edge_distance: b1.min(b2).min(1.0 - b1 - b2), facing });
                }
            }
        }
    }
    hits.sort_by(|a, b| a.t.total_cmp(&b.t));
    hits
}

/// The nearest hit when rounding cannot change which it is: no grazing hit before it and no other
/// hit within `tolerance` of it.
fn unambiguous_nearest(hits: &[CpuHit], tolerance: f64) -> Option<CpuHit> {
    let first = *hits.first()?;
    let clear_of_the_next = hits.get(1).is_none_or(|next| next.t - first.t > tolerance);
    (!first.grazing() && clear_of_the_next).then_some(first)
}

/// A random soup of triangles in the unit cube, some of them large, some tiny and some degenerate.
fn triangle_soup(rng: &mut Pcg64, count: usize) -> Mesh {
    let mut vertices = Vec::new();
    for i in 0..count {
        let centre = Vec3::new(rng.random(), rng.random(), rng.random());
        let size = if i % 7 == 0 { 0.5 } else { 0.08 };
        for k in 0..3 {
            // Every 31st triangle is degenerate: its corners lie on a line.
            let offset = if i % 31 == 0 {
                Vec3::X * (k as f32) * size
            } else {
                Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)) * size
            };
            vertices.push(Vertex {
                position: (centre + offset).to_array(),
                normal: [0.0, 1.0, 0.0],
                tangent: [1.0, 0.0, 0.0, 1.0],
                ..Default::default()
            });
        }
    }
    Mesh { name: "soup".into(), primitives: vec![Primitive { indices: (0..vertices.len() as u32).collect(), vertices, material: 0 }] }
}

/// The Duck, placed five times (as imported; rotated and non-uniformly scaled; mirrored; squashed
/// flat to nothing, which rays cannot hit; far off), beside a triangle soup placed twice.
fn instanced_scene() -> Scene {
    let mut scene = scene::load_path(&common_assets().join("duck/Duck.glb")).unwrap();
    let duck = scene.instances[0].clone();
    let size = scene.bounds().diagonal();
    let mut rng = Pcg64::seed_from_u64(7);
    scene.meshes.push(triangle_soup(&mut rng, 400));
    let soup = scene.meshes.len() - 1;
    let place = |translation: Vec3, rotation: Quat, scale: Vec3| Mat4::from_scale_rotation_translation(scale, rotation, translation * size);
    let more = [
        (duck.mesh, place(Vec3::new(1.2, 0.0, 0.0), Quat::from_rotation_y(1.0), Vec3::new(1.5, 0.7, 1.0)) * duck.world_from_local),
        (duck.mesh, place(Vec3::new(-1.2, 0.3, 0.0), Quat::from_rotation_x(0.4), Vec3::new(-1.0, 1.0, 1.0)) * duck.world_from_local),
        (duck.mesh, place(Vec3::new(0.0, 1.2, 0.0), Quat::IDENTITY, Vec3::new(1.0, 0.0, 1.0)) * duck.world_from_local),
        (soup, place(Vec3::new(0.0, -1.0, 0.0), Quat::from_rotation_z(0.3), Vec3::splat(size))),
        (soup, place(Vec3::new(0.5, 0.2, 0.8), Quat::from_rotation_y(-2.0), Vec3::new(0.5 * size, size, 2.0 * size))),
    ];
    scene.instances.extend(more.into_iter().map(|(mesh, world_from_local)| Instance { mesh, world_from_local }));
    scene
}

fn common_assets() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets")
}

/// Random rays: half aimed at a random point of a random triangle (so most hit), half in random
/// directions, all from random points around the scene.
fn random_rays(scene: &Scene, count: usize, rng: &mut Pcg64) -> Vec<(Vec3, Vec3)> {
    let bounds = scene.bounds();
    let (low, high) = (bounds.min - bounds.diagonal() * 0.2, bounds.max + bounds.diagonal() * 0.2);
    (0..count)
        .map(|i| {
            let origin = Vec3::new(rng.random_range(low.x..high.x), rng.random_range(low.y..high.y), rng.random_range(low.z..high.z));
            let dir = if i % 2 == 0 {
                let instance = &scene.instances[rng.random_range(0..scene.instances.len())];
                let primitive = &scene.meshes[instance.mesh].primitives[0];
                let t = rng.random_range(0..primitive.triangle_count());
                let (mut a, mut b): (f32, f32) = (rng.random(), rng.random());
                if a + b > 1.0 {
                    (a, b) = (1.0 - a, 1.0 - b);
                }
                let corner = |k: usize| Vec3::from(primitive.vertices[primitive.indices[3 * t + k] as usize].position);
                let target = instance.world_from_local.transform_point3(corner(0) * (1.0 - a - b) + corner(1) * a + corner(2) * b);
                target - origin
            } else {
                Vec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
            };
            (origin, dir.normalize_or(Vec3::Y))
        })
        .collect()
}

#[test]
fn gpu_traversal_finds_the_nearest_hit_of_every_ray_as_the_cpu_reference_does() {
    let scene = instanced_scene();
    let mut rng = Pcg64::seed_from_u64(1);
    let rays = random_rays(&scene, 4096, &mut rng);
    let tolerance = 1e-5 * scene.bounds().diagonal() as f64;
    let closest: Vec<_> = rays.iter().map(|&(o, d)| (o, f32::INFINITY, d, false)).collect();
    let gpu = trace_on_gpu(&scene, &closest);
    let mut exact = 0;
    for (i, (&(o, d), g)) in rays.iter().zip(&gpu).enumerate() {
        let hits = cpu_trace(&scene, o.as_dvec3(), d.as_dvec3());
        if let Some(nearest) = unambiguous_nearest(&hits, 10.0 * tolerance) {
            exact += 1;
            assert_eq!(g.triangle, Some(nearest.triangle), "ray {i} ({o}, {d}): reference {nearest:?}, GPU {g:?}");
            assert!((g.t as f64 - nearest.t).abs() <= tolerance, "ray {i}: t {} against the reference's {}", g.t, nearest.t);
            continue;
        }
        // Otherwise the GPU's answer must still be one of the ray's hits, with only grazing hits
        // (which rounding may skip) before it, or a miss if every hit grazes.
        match g.triangle {
            Some(triangle) => {
                let k = hits.iter().position(|h| h.triangle == triangle && (h.t - g.t as f64).abs() <= tolerance);
                let k = k.unwrap_or_else(|| panic!("ray {i}: the GPU hit {triangle:?} at {}, which the reference does not", g.t));
                assert!(
                    hits[..k].iter().all(|h| h.grazing() || h.t > hits[k].t - 10.0 * tolerance),
                    "ray {i}: the GPU skipped a hit: {hits:?}, GPU {g:?}"
                );
            }
            None => assert!(hits.iter().all(CpuHit::grazing), "ray {i}: the GPU missed {hits:?}"),
        }
    }
    // Half the rays aim at a triangle; some of those meet the flattened duck, whose coplanar
    // triangles make every hit on it a tie.
    assert!(exact > 1500, "only {exact} of 4096 rays had an unambiguous nearest hit: the test lost its coverage");
}

#[test]
fn any_hit_rays_are_occluded_exactly_when_something_lies_before_their_end() {
    let scene = instanced_scene();
    let mut rng = Pcg64::seed_from_u64(2);
    let tolerance = 1e-4 * scene.bounds().diagonal() as f64;
    let mut rays = Vec::new();
    let mut expected = Vec::new();
    for (o, d) in random_rays(&scene, 2048, &mut rng) {
        let hits = cpu_trace(&scene, o.as_dvec3(), d.as_dvec3());
        if hits.is_empty() {
            rays.push((o, f32::INFINITY, d, true));
            expected.push(false);
        } else if let Some(nearest) = unambiguous_nearest(&hits, tolerance) {
            // Ending halfway to the nearest hit: nothing in the way; past it: occluded.
            rays.push((o, (nearest.t * 0.5) as f32, d, true));
            expected.push(false);
            rays.push((o, (nearest.t * 1.5) as f32, d, true));
            expected.push(true);
        }
    }
    let gpu = trace_on_gpu(&scene, &rays);
    for (i, ((ray, hit), occluded)) in rays.iter().zip(&gpu).zip(&expected).enumerate() {
        assert_eq!(hit.triangle.is_some(), *occluded, "ray {i} {ray:?}: {hit:?}");
    }
    assert!(expected.iter().filter(|&&o| o).count() > 500);
}

#[test]
fn rays_pass_where_a_vertex_alpha_masks_the_surface_out() {
    // An alpha-masked quad at z = 0 whose vertex alpha runs from 0.1 (x = -1) to 0.9 (x = 1), cut at
    // 0.5, before an opaque quad at z = -2: rays along -Z hit the first at x > 0 only.
    let masked = Material { alpha_mode: AlphaMode::Mask { cutoff: 0.5 }, ..Default::default() };
    let mut scene = Scene { materials: vec![masked, Material::default()], ..Default::default() };
    for (material, z) in [(0, 0.0), (1, -2.0)] {
        let mut quad = common::quad_mesh();
        quad.primitives[0].material = material;
        for v in &mut quad.primitives[0].vertices {
            v.color = manylights::scene::Vertex::color_from([1.0, 1.0, 1.0, 0.5 + 0.4 * v.position[0]]);
        }
        scene.meshes.push(quad);
        scene.instances.push(Instance { mesh: material, world_from_local: Mat4::from_translation(Vec3::new(0.0, 0.0, z)) });
    }
    let xs = [-0.75, -0.25, 0.25, 0.75];
    let rays: Vec<_> = xs.iter().map(|&x| (Vec3::new(x, 0.3, 1.0), f32::INFINITY, Vec3::NEG_Z, false)).collect();
    for (&x, hit) in xs.iter().zip(trace_on_gpu(&scene, &rays)) {
        let expected = if x > 0.0 { 0 } else { 1 };
        assert_eq!(hit.triangle.map(|t| t.0), Some(expected), "ray at x = {x}: {hit:?}");
    }
}

/// A 2×2 texture whose alpha is a checkerboard: opaque top-left and bottom-right.
fn checker_texture() -> Texture {
    let texel = |opaque: bool| [255, 255, 255, if opaque { 255 } else { 0 }];
    Texture { name: "checker".into(), width: 2, height: 2, rgba8: [texel(true), texel(false), texel(false), texel(true)].concat() }
}

#[test]
fn rays_pass_alpha_masked_holes_and_blended_surfaces_but_stop_at_opaque_ones() {
    // Three unit quads (x, y in [-1, 1]) facing +Z: alpha-masked with the checker at z = 0, blended
    // at z = -1, opaque at z = -2. Rays travel along -Z through the checker's texel centres.
    let masked = Material {
        base_color_texture: Some(TextureRef::new(0, Wrap::ClampToEdge, Wrap::ClampToEdge)),
        alpha_mode: AlphaMode::Mask { cutoff: 0.5 },
        ..Default::default()
    };
    let blended = Material { base_color_factor: Vec4::new(1.0, 0.0, 0.0, 0.5), alpha_mode: AlphaMode::Blend, ..Default::default() };
    let opaque = Material::default();
    let mut scene = Scene { materials: vec![masked, blended, opaque], textures: vec![checker_texture()], ..Default::default() };
    for (material, z) in [(0, 0.0), (1, -1.0), (2, -2.0)] {
        let mut quad = common::quad_mesh();
        quad.primitives[0].material = material;
        scene.meshes.push(quad);
        scene.instances.push(Instance { mesh: material, world_from_local: Mat4::from_translation(Vec3::new(0.0, 0.0, z)) });
    }
    // The quad's u runs with x, its v against y: texel (0, 0) is at x = -0.5, y = 0.5.
    let texel_centres = [(-0.5, 0.5, true), (0.5, 0.5, false), (-0.5, -0.5, false), (0.5, -0.5, true)];
    let rays: Vec<_> = texel_centres.iter().map(|&(x, y, _)| (Vec3::new(x, y, 1.0), f32::INFINITY, Vec3::NEG_Z, false)).collect();
    let hits = trace_on_gpu(&scene, &rays);
    for (&(x, y, opaque_texel), hit) in texel_centres.iter().zip(&hits) {
        let (instance, expected_t) = if opaque_texel { (0, 1.0) } else { (2, 3.0) };
        assert_eq!(hit.triangle.map(|t| t.0), Some(instance), "ray at ({x}, {y}): {hit:?}");
        assert!((hit.t - expected_t).abs() < 1e-5, "ray at ({x}, {y}): t {}", hit.t);
    }
}
