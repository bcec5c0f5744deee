//! Shared helpers for the GPU tests: a renderer on whatever adapter the environment selects
//! (`scripts/test.sh` sets WGPU_ADAPTER_NAME=llvmpipe), small scenes, image statistics.

#![allow(dead_code)] // each test binary uses a different subset

use glam::{Mat4, Vec3, Vec4};
use manylights::{
    gpu::GpuContext,
    renderer::{Image, Renderer},
    scene::animation::{Animation, Channel, Interpolation, Node, Property, Trs},
    scene::{Camera, Instance, Light, LightKind, Material, Mesh, Primitive, Scene, Vertex},
    settings::BvhBuild,
    settings::ParticleFilter,
    settings::{DecalMethod, LightMethod, ParticleMethod, PipelineKind},
    settings::{Exposure, PostSettings},
    settings::{RayBackend, RaySettings},
    settings::{RenderConfig, Tonemapper},
};

/// Imports a glTF document given as JSON text (written to a file of its own under the temporary
/// directory, removed after).
pub fn import_gltf_json(json: &str) -> manylights::Result<Scene> {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let path = std::env::temp_dir().join(format!("manylights-test-{}-{n}.gltf", std::process::id()));
    std::fs::write(&path, json).unwrap();
    let scene = manylights::scene::gltf::import(&path);
    std::fs::remove_file(&path).ok();
    scene
}

pub const WIDTH: u32 = 256;
pub const HEIGHT: u32 = 144;

/// The test configuration: small, trilinear filtering, small textures (lavapipe is slow).
pub fn config(width: u32, height: u32, light_method: LightMethod) -> RenderConfig {
    RenderConfig {
        width,
        height,
        pipeline: PipelineKind::Visbuffer,
        light_method,
        light_bvh_build: BvhBuild::CpuOnce,
        decal_method: DecalMethod::Brute,
        decal_bvh_build: BvhBuild::CpuOnce,
        particle_method: ParticleMethod::Grid,
        particle_voxel_size: 1.0,
        particle_filter: ParticleFilter::Trilinear,
        particle_samples: 1,
        particle_cascades: 0,
        particle_cascade_resolution: 64,
        tonemapper: Tonemapper::Aces,
        max_texture_size: 256,
        anisotropy: 1,
        // The software BVHs, which most tests exercise; `ray_backend.rs` compares the hardware
        // back end with them.
        rays: RaySettings { backend: RayBackend::Software, ..RaySettings::default() },
        post: still_post(),
        debug_view: Default::default(),
        debug_slice_height: None,
    }
}

/// Post settings with every effect off and the exposure fixed at 1, so images compare across
/// methods and with golden images (auto exposure, the default, is tested in `post.rs`).
pub fn still_post() -> PostSettings {
    PostSettings { exposure: Exposure::Fixed(1.0), ..PostSettings::default() }
}

pub fn renderer(scene: &Scene, config: RenderConfig) -> Renderer {
    let ctx = GpuContext::new().expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)");
    Renderer::new(ctx, scene, config).expect("renderer")
}

/// Renders one frame with the given settings; returns the tonemapped and the linear image.
pub fn render_with(scene: &Scene, camera: &Camera, config: RenderConfig) -> (Image<[u8; 4]>, Image<[f32; 4]>) {
    render_on(GpuContext::new().expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)"), scene, camera, config)
}

/// As `render_with`, on a given device (one withholding features, say).
pub fn render_on(ctx: GpuContext, scene: &Scene, camera: &Camera, config: RenderConfig) -> (Image<[u8; 4]>, Image<[f32; 4]>) {
    let mut r = Renderer::new(ctx, scene, config).expect("renderer");
    r.render(camera).expect("frame");
    (r.read_ldr().expect("ldr"), r.read_hdr().expect("hdr"))
}

/// Renders one frame at the default test size with brute-force lights.
pub fn render(scene: &Scene, camera: &Camera) -> (Image<[u8; 4]>, Image<[f32; 4]>) {
    render_with(scene, camera, config(WIDTH, HEIGHT, LightMethod::Brute))
}

/// Largest difference of any channel between two linear images.
pub fn max_abs_difference(a: &Image<[f32; 4]>, b: &Image<[f32; 4]>) -> f32 {
    a.pixels.iter().zip(&b.pixels).flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs())).fold(0.0, f32::max)
}

pub fn luminance(p: [f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// A unit quad in the XY plane facing +Z, scaled by `world_from_local`.
pub fn quad_mesh() -> Mesh {
    let v = |x: f32, y: f32| Vertex {
        position: [x, y, 0.0],
        u: x * 0.5 + 0.5,
        normal: [0.0, 0.0, 1.0],
        v: 0.5 - y * 0.5,
        tangent: [1.0, 0.0, 0.0, 1.0],
        ..Vertex::default()
    };
    Mesh {
        name: "quad".into(),
        primitives: vec![Primitive {
            vertices: vec![v(-1.0, -1.0), v(1.0, -1.0), v(1.0, 1.0), v(-1.0, 1.0)],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
        }],
    }
}

/// A white, fully rough wall 20 m wide at z = 0 facing +Z, no sun, no ambient, and a camera 4 m in
/// front of it looking straight at it.
pub fn wall_scene(lights: Vec<Light>) -> (Scene, Camera) {
    let scene = Scene {
        meshes: vec![quad_mesh()],
        materials: vec![Material { base_color_factor: Vec4::ONE, metallic_factor: 0.0, roughness_factor: 1.0, ..Default::default() }],
        instances: vec![Instance { mesh: 0, world_from_local: Mat4::from_scale(Vec3::new(10.0, 10.0, 1.0)) }],
        lights,
        ambient: Vec3::ZERO,
        ..Default::default()
    };
    let camera = Camera::look_at("front", Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 60f32.to_radians(), 0.1);
    (scene, camera)
}

pub fn point_light(position: Vec3, intensity: f32, range: f32) -> Light {
    Light { kind: LightKind::Point, position, direction: Vec3::NEG_Z, color: Vec3::ONE, intensity, range, cast_shadows: false }
}

pub fn pixel<T: Copy>(image: &Image<T>, x: u32, y: u32) -> T {
    image.pixels[(y * image.width + x) as usize]
}

/// The albedo of [`ambient_wall`].
pub const AMBIENT_WALL_COLOR: Vec3 = Vec3::new(0.2, 0.3, 0.4);

/// A wall at z = 0 facing +Z, lit by a white uniform environment (`ambient`) only, so that its linear
/// radiance is its albedo (times one minus its metallic) plus its specular reflection of the
/// environment; material 0 is the wall's. The camera is 4 m in front of it.
pub fn ambient_wall() -> (Scene, Camera) {
    let scene = Scene {
        meshes: vec![quad_mesh()],
        materials: vec![Material {
            base_color_factor: AMBIENT_WALL_COLOR.extend(1.0),
            metallic_factor: 0.0,
            roughness_factor: 0.8,
            ..Default::default()
        }],
        instances: vec![Instance { mesh: 0, world_from_local: Mat4::from_scale(Vec3::new(10.0, 10.0, 1.0)) }],
        ambient: Vec3::ONE,
        ..Default::default()
    };
    (scene, Camera::look_at("front", Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 60f32.to_radians(), 0.1))
}

/// Flies scene instance `instance` (one node, its rest transform kept but for its translation) from
/// `from` to `to` over 0.1 s by a glTF-style linear translation channel.
pub fn fly(scene: &mut Scene, instance: usize, from: Vec3, to: Vec3) {
    let (scale, rotation, translation) = scene.instances[instance].world_from_local.to_scale_rotation_translation();
    scene.animation = Some(Animation {
        name: "fly".into(),
        nodes: vec![Node::from_trs(None, Trs { translation, rotation, scale })],
        channels: vec![Channel {
            node: 0,
            property: Property::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 0.1],
            values: vec![from.extend(0.0), to.extend(0.0)],
        }],
        instances: vec![(instance, 0)],
        duration: 0.1,
    });
}
