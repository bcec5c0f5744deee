//! The GPU scene: the CPU scene uploaded once into storage buffers and texture arrays, plus the
//! per-frame uniform buffer, all in bind group 0 (`shading/scene_bindings.wgsl`) shared by every pass.

use std::collections::BTreeSet;

use glam::Mat3;
use wgpu::util::DeviceExt;

use super::{
    bindings,
    environment::GpuEnvironment,
    frame::SceneConstants,
    textures::{TextureArray, TextureSpace},
    FrameUniforms, GpuContext,
};
use crate::{
    scene::{AlphaMode, Decal, Light, LightKind, Material, Scene, TextureRef, Wrap},
    Error, Result,
};

/// Keep in sync with `Draw` in `shading/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuDraw {
    pub world_from_local: [[f32; 4]; 4],
    pub normal_from_local: [[f32; 4]; 3],
    pub first_index: u32,
    pub first_visibility_id: u32,
    pub base_vertex: u32,
    pub material: u32,
}

/// Keep in sync with `Material` in `shading/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuMaterial {
    pub base_color_factor: [f32; 4],
    pub emissive_factor: [f32; 3],
    pub alpha_cutoff: f32,
    pub metallic_factor: f32,
    pub roughness_factor: f32,
    pub normal_scale: f32,
    /// MATERIAL_UNLIT, MATERIAL_CLEARCOAT, MATERIAL_TRANSMISSION, MATERIAL_SHEEN.
    pub flags: u32,
    pub base_color_layer: i32,
    pub emissive_layer: i32,
    pub metallic_roughness_layer: i32,
    pub normal_layer: i32,
    /// The dielectric's reflectance at normal incidence before the colour texture, the clamp to 1
    /// and the specular factor: `((ior − 1) / (ior + 1))² × colour factor`; and the factor.
    pub specular_color: [f32; 3],
    pub specular_factor: f32,
    pub clearcoat_factor: f32,
    pub clearcoat_roughness_factor: f32,
    pub clearcoat_normal_scale: f32,
    pub occlusion_strength: f32,
    pub specular_layer: i32,
    pub specular_color_layer: i32,
    pub clearcoat_layer: i32,
    pub clearcoat_roughness_layer: i32,
    pub clearcoat_normal_layer: i32,
    pub occlusion_layer: i32,
    /// Four bits a texture slot, `(wrap_v << 2) | wrap_u`, eight slots a word, in the slots' order.
    pub wrap_modes: [u32; 2],
    /// The medium behind a transmissive surface: its colour after `attenuation_distance` (0: clear).
    pub attenuation_color: [f32; 3],
    pub attenuation_distance: f32,
    pub transmission_factor: f32,
    /// In the mesh's units; 0: thin-walled.
    pub thickness_factor: f32,
    /// The index of refraction light enters by, at least 1.
    pub ior: f32,
    pub transmission_layer: i32,
    pub thickness_layer: i32,
    pub sheen_color_layer: i32,
    pub sheen_roughness_layer: i32,
    /// How far the medium's index of refraction spreads over the colours (`KHR_materials_dispersion`).
    pub dispersion: f32,
    /// The sheen's colour (black: none) and roughness (`KHR_materials_sheen`).
    pub sheen_color: [f32; 3],
    pub sheen_roughness: f32,
    /// Each texture slot's coordinates from the mesh's (`TextureRef::uv_transform`), in the slots'
    /// order: two vec4s a slot, the 2×2 matrix's columns, then the translation and the set of
    /// coordinates it transforms (`TextureRef::tex_coord`, 0 or 1, in z).
    pub uv_transforms: [[f32; 4]; 2 * TEXTURE_SLOTS],
}

/// A material's texture slots, in the order of `shading/material.wgsl`: base colour, emissive,
/// metallic-roughness, normal, specular, specular colour, clearcoat, clearcoat roughness,
/// clearcoat normal, occlusion, transmission, thickness, sheen colour, sheen roughness.
pub const TEXTURE_SLOTS: usize = 14;

/// The visibility id no triangle has (`NO_VISIBILITY_ID` in `shading/types.wgsl`): what the
/// transmissive raster clears its ids to. Below u32's largest so that every backend's clear, some
/// through an f32, writes it exactly.
pub const NO_VISIBILITY_ID: u32 = 0xFFFF_FF00;

/// `GpuMaterial::flags` (`MATERIAL_*` in `shading/types.wgsl`).
pub const MATERIAL_UNLIT: u32 = 1;
pub const MATERIAL_CLEARCOAT: u32 = 2;
pub const MATERIAL_TRANSMISSION: u32 = 4;
pub const MATERIAL_SHEEN: u32 = 16;

const NO_TEXTURE: i32 = -1;

/// Keep in sync with `Light` in `shading/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub range: f32,
    pub radiant: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub spot_scale: f32,
    pub spot_offset: f32,
    /// LIGHT_CASTS_SHADOWS when it casts ray-traced shadows.
    pub flags: u32,
    pub _pad: [u32; 2],
}

/// Set in `GpuLight::flags` (`LIGHT_CASTS_SHADOWS` in `shading/types.wgsl`).
pub const LIGHT_CASTS_SHADOWS: u32 = 1;

/// One pixel's reservoir of `restir` (`Reservoir` in `shading/types.wgsl`), written and read on the
/// GPU alone: here for its size.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuReservoir {
    pub light: u32,
    pub instance: u32,
    pub light_hash: u32,
    pub weight: f32,
    pub position: [f32; 3],
    pub normal_count: u32,
}

/// One pixel's sample of sampled lighting for the denoiser (`DenoiseSample` in `shading/types.wgsl`),
/// written by the shading core and read by `passes/denoise/` on the GPU alone: here for its size.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuDenoiseSample {
    pub diffuse: [f32; 3],
    pub normal: u32,
    pub specular: [f32; 3],
    pub albedo: u32,
    pub position: [f32; 3],
    pub specular_albedo: u32,
}

/// Keep in sync with `SurfaceMotion` in `shading/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuSurfaceMotion {
    pub moved: [f32; 3],
    pub frame: u32,
}

impl From<&Light> for GpuLight {
    fn from(l: &Light) -> Self {
        let (kind, spot_scale, spot_offset) = match l.kind {
            LightKind::Point => (0, 0.0, 1.0),
            LightKind::Spot { inner_cone_angle, outer_cone_angle } => {
                // KHR_lights_punctual's cone parameterisation.
                let scale = 1.0 / (inner_cone_angle.cos() - outer_cone_angle.cos()).max(1e-3);
                (1, scale, -outer_cone_angle.cos() * scale)
            }
        };
        Self {
            position: l.position.to_array(),
            range: l.range,
            radiant: (l.color * l.intensity).to_array(),
            kind,
            direction: l.direction.normalize_or_zero().to_array(),
            spot_scale,
            spot_offset,
            flags: if l.cast_shadows { LIGHT_CASTS_SHADOWS } else { 0 },
            _pad: [0; 2],
        }
    }
}

/// Keep in sync with `Decal` in `shading/types.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuDecal {
    /// Rows of the affine map from group space into decal space.
    pub decal_from_group: [[f32; 4]; 3],
    pub material: u32,
    pub layer: u32,
    pub weight: f32,
    pub _pad: u32,
}

impl GpuDecal {
    /// The decal's record, naming its material's record for decals (`GpuScene::decal_material_base`).
    pub fn new(d: &Decal, decal_material_base: u32) -> Self {
        Self {
            decal_from_group: affine_rows(&d.world_from_decal.inverse()),
            material: decal_material_base + d.material as u32,
            layer: d.layer,
            weight: d.weight,
            _pad: 0,
        }
    }
}

/// The three rows of an affine map, as WGSL applies them: `vec4(p, 1.0) * mat3x4(rows)`.
pub fn affine_rows(t: &glam::Affine3A) -> [[f32; 4]; 3] {
    let m = glam::Mat4::from(*t);
    [m.row(0).to_array(), m.row(1).to_array(), m.row(2).to_array()]
}

/// Samplers for every pair of glTF wrap modes (3 × 3).
const WRAP_SAMPLERS: u32 = 9;

/// How the raster pass must draw a primitive.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RasterState {
    pub alpha_mask: bool,
    pub double_sided: bool,
    /// The instance's transform has a negative determinant, which reverses its triangles' winding.
    pub mirrored: bool,
}

impl RasterState {
    /// Every combination, one raster pipeline each.
    pub fn all() -> impl Iterator<Item = RasterState> {
        (0..8).map(|bits| RasterState { alpha_mask: bits & 1 != 0, double_sided: bits & 2 != 0, mirrored: bits & 4 != 0 })
    }

    /// Winding and culling: mirrored instances reverse the winding; double-sided materials cull nothing.
    pub fn primitive(self) -> wgpu::PrimitiveState {
        wgpu::PrimitiveState {
            topology: wgpu::PrimitiveTopology::TriangleList,
            front_face: if self.mirrored { wgpu::FrontFace::Cw } else { wgpu::FrontFace::Ccw },
            cull_mode: if self.double_sided { None } else { Some(wgpu::Face::Back) },
            ..Default::default()
        }
    }
}

/// One instance of one primitive, as the raster pass draws it.
#[derive(Clone, Copy, Debug)]
pub struct DrawCommand {
    pub draw_index: u32,
    /// The primitive's range of the index buffer, and its first vertex.
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: u32,
    pub state: RasterState,
    /// World-space centre of the primitive's bounds, for front-to-back ordering, and the same in
    /// the mesh's space, to place it again when its instance moves.
    pub center: glam::Vec3,
    pub local_center: glam::Vec3,
    /// The primitive's bounds in world space, which raster passes skip the draw outside the view
    /// by, and in the mesh's space; for a deformed mesh, the whole mesh's box as the frame deforms
    /// it (`place_deformed`), `None` until its first frame.
    pub bounds: Option<crate::scene::Aabb>,
    pub local_bounds: Option<crate::scene::Aabb>,
}

/// One frame's draws of a kind in the order the raster passes draw them: indices into the scene's
/// commands (opaque or transparent), in runs of one raster state, and their indirect arguments from
/// record `first_argument` of [`GpuScene::draw_arguments`] on.
#[derive(Clone, Debug, Default)]
pub struct OrderedDraws {
    pub commands: Vec<u32>,
    /// (state, first position in `commands`, count).
    pub runs: Vec<(RasterState, u32, u32)>,
    pub first_argument: u32,
}

/// The frame's draws in view, in the orders [`GpuScene::order_draws`] gives them.
#[derive(Clone, Debug, Default)]
pub struct FrameDraws {
    /// Opaque and alpha-masked draws, front to back.
    pub opaque: OrderedDraws,
    /// Those of them that move: animated instances', deformed meshes'.
    pub moving: OrderedDraws,
    /// Alpha-blended draws, nearest first.
    pub transparent: OrderedDraws,
    /// Transmissive draws that do not blend, front to back.
    pub transmissive: OrderedDraws,
}

pub struct GpuScene {
    pub bind_group_layout: wgpu::BindGroupLayout,
    pub bind_group: wgpu::BindGroup,
    pub frame_uniforms: wgpu::Buffer,
    /// Opaque and alpha-masked draws: the raster passes' and the visibility buffer's.
    pub draw_commands: Vec<DrawCommand>,
    /// Alpha-blended draws, transmissive or not: layered and shaded after the opaque and
    /// transmissive ones by `passes::blended_shade`.
    pub transparent_draw_commands: Vec<DrawCommand>,
    /// Transmissive draws that do not blend (`Material::transmissive_unblended`): shaded after the
    /// opaque ones by `passes::transmissive_shade`, before the blended ones, writing depth.
    pub transmissive_draw_commands: Vec<DrawCommand>,
    /// This frame's orders of the draws, written by [`order_draws`](Self::order_draws).
    pub(crate) frame_draws: FrameDraws,
    /// `FrameDraws`' indirect arguments (`wgpu::util::DrawIndexedIndirectArgs`): opaque, moving,
    /// transparent, then transmissive draws, each as many records as it may hold. `None` where the device cannot
    /// take a first instance (the draw index) from indirect arguments: it draws one call per draw.
    pub(crate) draw_arguments: Option<wgpu::Buffer>,
    /// The view (clip from world) and eye `frame_draws` were made for; `None` once a draw moved.
    ordered_for: Option<(glam::Mat4, glam::Vec3)>,
    pub constants: SceneConstants,
    pub triangle_count: u64,
    /// The record of scene material m as decals use it is `decal_material_base + m` (its textures
    /// in the decals' arrays); m's own record serves surfaces.
    pub decal_material_base: u32,
    /// The scene's indices, also bound as storage: the raster pass draws indexed from it.
    pub index_buffer: wgpu::Buffer,
    /// The draws as uploaded, and the first draw of each scene instance (its primitives' draws
    /// follow): moving instances rewrites their draws (`move_instances`).
    draws: Vec<GpuDraw>,
    instance_first_draw: Vec<usize>,
    /// The mesh each draw draws, and the deformed meshes' commands (opaque, blended, transmissive),
    /// boxed anew each frame (`place_deformed`).
    draw_meshes: Vec<usize>,
    deformed_commands: [Vec<u32>; 3],
    draw_buffer: wgpu::Buffer,
    /// Every primitive's vertices, and the scene's ray hierarchy (`rays::RayStructure`): nodes,
    /// triangles, instances. Deformed meshes rewrite the first two on the GPU.
    pub vertex_buffer: wgpu::Buffer,
    pub ray_node_buffer: wgpu::Buffer,
    pub ray_triangle_buffer: wgpu::Buffer,
    pub ray_instance_buffer: wgpu::Buffer,
    /// Each mesh's primitives' (first index, index count, base vertex) in the index and vertex
    /// buffers.
    pub primitive_ranges: Vec<Vec<(u32, u32, u32)>>,
    /// Each draw's transform (world from local) a frame interval before the current one, for motion
    /// blur's velocity (`post/velocity.rs`) and the surface motions (`passes/surface_motion.rs`), and
    /// which draws move (animated instances', deformed meshes').
    pub previous_transforms: wgpu::Buffer,
    /// Where each deformed mesh's vertices were a frame before (xyz; w 1 for a deformed vertex),
    /// written by `passes/deform.rs` for the velocities; one zero record when nothing deforms.
    pub previous_positions: wgpu::Buffer,
    moving_draws: Vec<bool>,
    /// `restir`'s reservoirs, two per pixel (`GpuReservoir`), or one placeholder.
    restir_reservoirs: wgpu::Buffer,
    /// The denoiser's samples, one per pixel (`GpuDenoiseSample`), or one placeholder.
    pub denoise_samples: wgpu::Buffer,
}

impl GpuScene {
    /// The opaque draws in view (indices into `draw_commands`) in the order raster passes submit
    /// them: opaque before alpha-masked (whose discard defeats early depth tests), each front to
    /// back from `eye`. Raster passes on our benchmark GPUs are bound by fragment work, and early-Z
    /// rejects what nearer draws hide.
    fn draw_order(&self, view: &glam::Mat4, eye: glam::Vec3) -> Vec<u32> {
        front_to_back(&self.draw_commands, view, eye)
    }

    /// Boxes the deformed meshes' draws as this frame deforms them (`boxes`: a mesh and its box in
    /// its own space, from `passes::deform::Deform::write_time`), so raster passes skip those outside
    /// the view as they skip other draws. Call after `move_instances`, before `order_draws`; the
    /// last order is kept while no deformed draw crosses the view's edge.
    pub fn place_deformed(&mut self, boxes: &[(usize, crate::scene::Aabb)]) {
        let view = self.ordered_for.map(|(view, _)| view);
        let seen = |command: &DrawCommand, view: &glam::Mat4| !command.bounds.is_some_and(|b| b.outside_view(view));
        let mut reorder = false;
        let lists = [&mut self.draw_commands, &mut self.transparent_draw_commands, &mut self.transmissive_draw_commands];
        for (commands, deformed) in lists.into_iter().zip(&self.deformed_commands) {
            for &c in deformed {
                let command = &mut commands[c as usize];
                let mesh = self.draw_meshes[command.draw_index as usize];
                let Some(&(_, local)) = boxes.iter().find(|(m, _)| *m == mesh) else { continue };
                if command.local_bounds == Some(local) {
                    continue;
                }
                let seen_before = view.map(|v| seen(command, &v));
                let world_from_local = glam::Mat4::from_cols_array_2d(&self.draws[command.draw_index as usize].world_from_local);
                command.local_center = local.center();
                command.center = world_from_local.transform_point3(command.local_center);
                command.local_bounds = Some(local);
                command.bounds = Some(local.transformed(&glam::Affine3A::from_mat4(world_from_local)));
                reorder |= view.is_some_and(|v| seen_before != Some(seen(command, &v)));
            }
        }
        if reorder {
            self.ordered_for = None;
        }
    }

    /// How many of the scene's draws (opaque, blended and transmissive) the last frame drew: those
    /// in its view.
    pub fn drawn_count(&self) -> usize {
        let d = &self.frame_draws;
        d.opaque.commands.len() + d.transparent.commands.len() + d.transmissive.commands.len()
    }

    /// Orders the frame's draws in the view `view` (clip from world) from `eye`
    /// ([`frame_draws`](Self::frame_draws)), leaving out those wholly outside it, and writes their
    /// indirect arguments, which land before the next submitted frame; keeps the last order where
    /// neither the view nor a draw moved. Call once a frame, after instances move.
    pub fn order_draws(&mut self, queue: &wgpu::Queue, view: glam::Mat4, eye: glam::Vec3) {
        if self.ordered_for == Some((view, eye)) {
            return;
        }
        self.ordered_for = Some((view, eye));
        let opaque = self.draw_order(&view, eye);
        let moving: Vec<u32> =
            opaque.iter().copied().filter(|&c| self.moving_draws[self.draw_commands[c as usize].draw_index as usize]).collect();
        // Nearest first: early depth tests skip what a nearer transmissive one hides. Blended layers
        // are sorted per pixel: their draws need only their runs of one raster state.
        let transparent = front_to_back(&self.transparent_draw_commands, &view, eye);
        let transmissive = front_to_back(&self.transmissive_draw_commands, &view, eye);
        let opaque_count = self.draw_commands.len() as u32;
        let transparent_end = 2 * opaque_count + self.transparent_draw_commands.len() as u32;
        self.frame_draws = FrameDraws {
            opaque: ordered(&self.draw_commands, opaque, 0),
            moving: ordered(&self.draw_commands, moving, opaque_count),
            transparent: ordered(&self.transparent_draw_commands, transparent, 2 * opaque_count),
            transmissive: ordered(&self.transmissive_draw_commands, transmissive, transparent_end),
        };
        let Some(buffer) = &self.draw_arguments else { return };
        let d = &self.frame_draws;
        for (list, commands) in [
            (&d.opaque, &self.draw_commands),
            (&d.moving, &self.draw_commands),
            (&d.transparent, &self.transparent_draw_commands),
            (&d.transmissive, &self.transmissive_draw_commands),
        ] {
            if list.commands.is_empty() {
                continue;
            }
            let mut arguments: Vec<[u32; 5]> = Vec::with_capacity(list.commands.len());
            for &c in &list.commands {
                let c = &commands[c as usize];
                // wgpu::util::DrawIndexedIndirectArgs: index count, instance count, first index,
                // base vertex, first instance (the draw index the shaders read).
                arguments.push([c.index_count, 1, c.first_index, c.base_vertex, c.draw_index]);
            }
            queue.write_buffer(buffer, u64::from(list.first_argument) * DRAW_ARGUMENT_BYTES, bytemuck::cast_slice(&arguments));
        }
    }

    /// Uploads `scene`. `max_texture_size` caps the layer size of the texture arrays; `anisotropy` is
    /// the sampler's maximum anisotropy (1 = trilinear); `particle_grids` are the particle system's
    /// colour and direction textures, bound for shading (1×1×1 placeholders without particles);
    /// `rays` is the scene's ray-tracing hierarchy, for ray-traced effects (`rays::RayStructure`);
    /// `pixel_state` the pixels `restir` keeps a reservoir and the denoiser a sample for (0: none).
    pub fn upload(
        ctx: &GpuContext,
        scene: &Scene,
        max_texture_size: u32,
        anisotropy: u16,
        particle_grids: Option<[&wgpu::Texture; 2]>,
        rays: RayBuffers,
        pixel_state: PixelStateSize,
    ) -> Result<Self> {
        scene.validate()?;
        let device = &ctx.device;

        let textures = SceneTextures::upload(ctx, scene, max_texture_size)?;
        let materials = textures.materials(scene);
        let Geometry { vertices, indices, primitive_ranges } = concatenate_primitives(scene);
        let DrawList { draws, draw_meshes, instance_first_draw, draw_commands, transparent_draw_commands, transmissive_draw_commands } =
            DrawList::new(scene, &primitive_ranges)?;

        let limit = ctx.limits.max_storage_buffer_binding_size;
        // Deformed meshes' vertices are rewritten on the GPU every frame (`passes/deform.rs`).
        let vertex_buffer = storage_buffer(device, "vertices", &vertices, limit, wgpu::BufferUsages::empty())?;
        let index_buffer = storage_buffer(device, "indices", &indices, limit, wgpu::BufferUsages::INDEX)?;
        let draw_buffer = storage_buffer(device, "draws", &draws, limit, wgpu::BufferUsages::COPY_DST)?;
        let transforms: Vec<[[f32; 4]; 4]> = draws.iter().map(|d| d.world_from_local).collect();
        let previous_transforms = storage_buffer(device, "previous draw transforms", &transforms, limit, wgpu::BufferUsages::COPY_DST)?;
        let moving_draws = moving_draws(scene, &instance_first_draw, draws.len());
        let deformed: BTreeSet<usize> = scene.deformers.iter().map(|d| d.mesh).collect();
        let deformed_commands = [&draw_commands, &transparent_draw_commands, &transmissive_draw_commands].map(|commands| {
            (0..commands.len() as u32).filter(|&c| deformed.contains(&draw_meshes[commands[c as usize].draw_index as usize])).collect()
        });
        let deformed_vertices = if scene.deformers.is_empty() { 0 } else { vertices.len() };
        let previous_positions =
            storage_buffer(device, "previous positions", &vec![[0f32; 4]; deformed_vertices], limit, wgpu::BufferUsages::empty())?;
        let material_buffer = storage_buffer(device, "materials", &materials, limit, wgpu::BufferUsages::empty())?;
        // The top level and the instances are rewritten when instances move (`move_instances`).
        // Deformed meshes' BLASes are refitted on the GPU (`rays/refit.rs`); tests read them back.
        let copy = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let ray_node_buffer = storage_records(device, "ray hierarchy nodes", rays.nodes, limit, copy)?;
        let ray_triangle_buffer = storage_records(device, "ray triangles", rays.triangles, limit, copy)?;
        let ray_instance_buffer = storage_records(device, "ray instances", rays.instances, limit, copy)?;
        let restir_reservoirs = pixel_buffer(
            device,
            "restir's reservoirs",
            2 * pixel_state.reservoirs,
            std::mem::size_of::<GpuReservoir>(),
            limit,
            "--restir-reuse off",
        )?;
        let denoise_samples = pixel_buffer(
            device,
            "the denoiser's samples",
            pixel_state.denoise_samples,
            std::mem::size_of::<GpuDenoiseSample>(),
            limit,
            "--denoise off",
        )?;
        // Where animated instances' surfaces were a frame before (`GpuSurfaceMotion`, written by
        // `passes/surface_motion.rs`): bound only.
        let surface_motions = pixel_buffer(
            device,
            "the surface motions",
            pixel_state.surface_motions,
            std::mem::size_of::<GpuSurfaceMotion>(),
            limit,
            "--restir-reuse off --denoise off",
        )?;
        let frame_uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let samplers = material_samplers(device, anisotropy);
        let (particle_views, particle_sampler) = particle_grid_bindings(device, particle_grids);
        let environment = GpuEnvironment::upload(device, &ctx.queue, scene, ctx.limits.max_texture_dimension_2d);

        let bind_group_layout = Self::create_bind_group_layout(device, rays.tlas.is_some());
        let bind_group = bindings::bind_group(
            device,
            "scene",
            &bind_group_layout,
            vec![
                frame_uniforms.as_entire_binding(),
                vertex_buffer.as_entire_binding(),
                index_buffer.as_entire_binding(),
                draw_buffer.as_entire_binding(),
                material_buffer.as_entire_binding(),
                wgpu::BindingResource::TextureView(&textures.surface_color.view),
                wgpu::BindingResource::TextureView(&textures.surface_data.view),
            ]
            .into_iter()
            .chain(samplers.iter().map(wgpu::BindingResource::Sampler))
            .chain(particle_views.iter().map(wgpu::BindingResource::TextureView))
            .chain([wgpu::BindingResource::Sampler(&particle_sampler)])
            .chain([&ray_node_buffer, &ray_triangle_buffer, &ray_instance_buffer].map(|b| b.as_entire_binding()))
            .chain([&textures.decal_color, &textures.decal_data].map(|t| wgpu::BindingResource::TextureView(&t.view)))
            .chain([&environment.background, &environment.specular, &environment.brdf_table].map(wgpu::BindingResource::TextureView))
            .chain([wgpu::BindingResource::Sampler(&environment.sampler)])
            .chain([&restir_reservoirs, &denoise_samples, &surface_motions].map(|b| b.as_entire_binding()))
            .chain(rays.tlas.map(wgpu::Tlas::as_binding))
            .collect(),
        );
        // Room for every opaque draw twice (all of them, the moving ones) and every other one.
        let argument_count = (2 * draw_commands.len() + transparent_draw_commands.len() + transmissive_draw_commands.len()).max(1) as u64;
        let draw_arguments = ctx.features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE).then(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("draw arguments"),
                size: argument_count * DRAW_ARGUMENT_BYTES,
                usage: wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        ctx.check_errors()?;

        Ok(Self {
            bind_group_layout,
            bind_group,
            frame_uniforms,
            draw_commands,
            transparent_draw_commands,
            transmissive_draw_commands,
            frame_draws: FrameDraws::default(),
            draw_arguments,
            ordered_for: None,
            constants: SceneConstants { sun: scene.sun, environment: environment.lighting, bounds: scene.bounds() },
            triangle_count: scene.drawn_triangle_count() as u64,
            decal_material_base: scene.materials.len() as u32,
            index_buffer,
            draws,
            instance_first_draw,
            draw_meshes,
            deformed_commands,
            draw_buffer,
            previous_transforms,
            previous_positions,
            moving_draws,
            vertex_buffer,
            ray_node_buffer,
            ray_triangle_buffer,
            ray_instance_buffer,
            primitive_ranges,
            restir_reservoirs,
            denoise_samples,
        })
    }

    /// Empties `restir`'s kept reservoirs, so the next frame reuses nothing.
    pub fn clear_reservoirs(&self, ctx: &GpuContext) {
        let mut encoder = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("clear reservoirs") });
        encoder.clear_buffer(&self.restir_reservoirs, 0, None);
        ctx.queue.submit([encoder.finish()]);
    }

    /// Moves scene instances: `moved` holds (instance, world from local), `previous` the same
    /// instances' transforms a frame interval earlier (for motion blur; empty when no pass reads them),
    /// `primitive_counts` each instance's primitive count (its draws). Rewrites their draws, previous
    /// transforms, their commands' centres (draw order) and mirroring (winding) and, when the frame
    /// traces rays, the rays' top level and instances from `rays` (already placed with the same
    /// transforms). The
    /// writes land before the next submitted frame and after the ones already submitted, so every
    /// frame draws and traces one consistent placement.
    pub fn move_instances(
        &mut self,
        queue: &wgpu::Queue,
        moved: &[(usize, glam::Mat4)],
        previous: &[(usize, glam::Mat4)],
        primitive_counts: &[usize],
        rays: Option<RayBuffers>,
    ) {
        for &(instance, world_from_local) in previous {
            let first = self.instance_first_draw[instance];
            let transforms = vec![world_from_local.to_cols_array_2d(); primitive_counts[instance]];
            let offset = (first * std::mem::size_of::<[[f32; 4]; 4]>()) as u64;
            queue.write_buffer(&self.previous_transforms, offset, bytemuck::cast_slice(&transforms));
        }
        let mut touched: Option<std::ops::Range<usize>> = None;
        let mut draw_placements = std::collections::HashMap::new();
        for &(instance, world_from_local) in moved {
            let first = self.instance_first_draw[instance];
            let draws = first..first + primitive_counts[instance];
            let (world, normal) = draw_transforms(&world_from_local);
            for (index, draw) in self.draws[draws.clone()].iter_mut().enumerate() {
                (draw.world_from_local, draw.normal_from_local) = (world, normal);
                draw_placements.insert((first + index) as u32, world_from_local);
            }
            touched = Some(touched.map_or(draws.clone(), |t| t.start.min(draws.start)..t.end.max(draws.end)));
        }
        if !draw_placements.is_empty() {
            self.ordered_for = None;
        }
        for command in self.draw_commands.iter_mut().chain(&mut self.transparent_draw_commands).chain(&mut self.transmissive_draw_commands)
        {
            if let Some(world_from_local) = draw_placements.get(&command.draw_index) {
                command.center = world_from_local.transform_point3(command.local_center);
                command.bounds = command.local_bounds.map(|b| b.transformed(&glam::Affine3A::from_mat4(*world_from_local)));
                command.state.mirrored = world_from_local.determinant() < 0.0;
            }
        }
        if let Some(range) = touched.filter(|r| !r.is_empty()) {
            let offset = (range.start * std::mem::size_of::<GpuDraw>()) as u64;
            queue.write_buffer(&self.draw_buffer, offset, bytemuck::cast_slice(&self.draws[range]));
        }
        if let Some(rays) = rays.filter(|r| !r.instances.bytes.is_empty()) {
            queue.write_buffer(&self.ray_node_buffer, 0, &rays.nodes.bytes[..rays.top_level_nodes * rays.nodes.record_size]);
            queue.write_buffer(&self.ray_instance_buffer, 0, rays.instances.bytes);
        }
    }

    /// Keep in sync with `shading/scene_bindings.wgsl` (and, with the hardware ray back end,
    /// `rays/trace_ray_query.wgsl`).
    fn create_bind_group_layout(device: &wgpu::Device, hardware_rays: bool) -> wgpu::BindGroupLayout {
        let all = wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE;
        let float_array = wgpu::TextureSampleType::Float { filterable: true };
        let mut entries = vec![
            bindings::uniform(0, all),                                                   // frame uniforms
            bindings::storage_read(1, all),                                              // vertices
            bindings::storage_read(2, all),                                              // indices
            bindings::storage_read(3, all),                                              // draws
            bindings::storage_read(4, all),                                              // materials
            bindings::texture(5, all, float_array, wgpu::TextureViewDimension::D2Array), // colour textures (sRGB)
            bindings::texture(6, all, float_array, wgpu::TextureViewDimension::D2Array), // data textures (linear)
        ];
        // 7..=15: one material sampler per pair of wrap modes
        entries.extend((0..WRAP_SAMPLERS).map(|i| bindings::sampler(7 + i, all)));
        let float = wgpu::TextureSampleType::Float { filterable: true };
        entries.push(bindings::texture(16, all, float, wgpu::TextureViewDimension::D3)); // particle colour grid
        entries.push(bindings::texture(17, all, float, wgpu::TextureViewDimension::D3)); // particle direction grid
        entries.push(bindings::sampler(18, all)); // particle grid sampler
        entries.push(bindings::storage_read(19, all)); // ray hierarchy nodes
        entries.push(bindings::storage_read(20, all)); // ray triangles
        entries.push(bindings::storage_read(21, all)); // ray instances
        entries.push(bindings::texture(22, all, float_array, wgpu::TextureViewDimension::D2Array)); // decal colour textures
        entries.push(bindings::texture(23, all, float_array, wgpu::TextureViewDimension::D2Array)); // decal data textures
        let d2 = wgpu::TextureViewDimension::D2;
        entries.push(bindings::texture(24, all, float, d2)); // environment (background)
        entries.push(bindings::texture(25, all, float, d2)); // prefiltered environment
        entries.push(bindings::texture(26, all, float, d2)); // BRDF table: split sum, sheen albedo
        entries.push(bindings::sampler(27, all)); // environment sampler
                                                  // restir's reservoirs, written by shading, which no vertex stage does
        entries.push(bindings::storage_read_write(28, wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE));
        entries.push(bindings::storage_read_write(29, wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE)); // the denoiser's samples
        entries.push(bindings::storage_read_write(30, wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE)); // surface motions
        if hardware_rays {
            entries.push(bindings::acceleration_structure(31, all)); // the rays' top-level acceleration structure
        }
        bindings::layout(device, "scene", &entries)
    }

    pub fn write_frame(&self, queue: &wgpu::Queue, uniforms: &FrameUniforms) {
        queue.write_buffer(&self.frame_uniforms, 0, bytemuck::bytes_of(uniforms));
    }
}

/// `commands` with their indices, but for those wholly outside the view `view` (clip from world).
fn in_view<'a>(commands: &'a [DrawCommand], view: &'a glam::Mat4) -> impl Iterator<Item = (u32, &'a DrawCommand)> + 'a {
    commands.iter().enumerate().filter(|(_, c)| !c.bounds.is_some_and(|b| b.outside_view(view))).map(|(i, c)| (i as u32, c))
}

/// Bytes of one `wgpu::util::DrawIndexedIndirectArgs`.
pub const DRAW_ARGUMENT_BYTES: u64 = 20;

/// `commands` in view (indices into them) by raster state, each state's front to back from `eye`.
fn front_to_back(commands: &[DrawCommand], view: &glam::Mat4, eye: glam::Vec3) -> Vec<u32> {
    // Sorted by keys made once per draw (a non-negative float's bits order as the float does); ties
    // keep the commands' order.
    let mut keyed: Vec<(RasterState, u32, u32)> =
        in_view(commands, view).map(|(i, c)| (c.state, c.center.distance_squared(eye).to_bits(), i)).collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, _, i)| i).collect()
}

/// `order` of `commands` in runs of one raster state, its arguments from record `first_argument`.
fn ordered(commands: &[DrawCommand], order: Vec<u32>, first_argument: u32) -> OrderedDraws {
    let mut runs: Vec<(RasterState, u32, u32)> = Vec::new();
    for (position, &c) in order.iter().enumerate() {
        let state = commands[c as usize].state;
        match runs.last_mut() {
            Some((last, _, count)) if *last == state => *count += 1,
            _ => runs.push((state, position as u32, 1)),
        }
    }
    OrderedDraws { commands: order, runs, first_argument }
}

/// A draw's transforms as the shaders read them: world from local, and the inverse transpose of its
/// upper 3×3 in columns, the first carrying the sign of the determinant in w.
fn draw_transforms(world_from_local: &glam::Mat4) -> ([[f32; 4]; 4], [[f32; 4]; 3]) {
    let normal_from_local = Mat3::from_mat4(*world_from_local).inverse().transpose();
    let handedness = Mat3::from_mat4(*world_from_local).determinant().signum();
    let columns = [normal_from_local.x_axis.extend(handedness), normal_from_local.y_axis.extend(0.0), normal_from_local.z_axis.extend(0.0)];
    (world_from_local.to_cols_array_2d(), columns.map(|c| c.to_array()))
}

/// The scene's texture arrays. Surfaces' and decals' textures go into separate arrays, each at the
/// size of its own largest image: decal stamps are small, and sampled at the scene's texture size
/// they apply more slowly (benchmarks/LOG.md, topic 2).
struct SceneTextures {
    surface_color: TextureArray,
    surface_data: TextureArray,
    decal_color: TextureArray,
    decal_data: TextureArray,
}

impl SceneTextures {
    fn upload(ctx: &GpuContext, scene: &Scene, max_texture_size: u32) -> Result<Self> {
        let arrays = |materials: BTreeSet<usize>| -> Result<(TextureArray, TextureArray)> {
            let materials: Vec<&Material> = materials.iter().map(|&m| &scene.materials[m]).collect();
            let (srgb_used, linear_used) = texture_usage(&materials);
            let upload =
                |used: &[usize], space| TextureArray::upload(&ctx.device, &ctx.queue, &scene.textures, used, space, max_texture_size);
            Ok((upload(&srgb_used, TextureSpace::Srgb)?, upload(&linear_used, TextureSpace::Linear)?))
        };
        let (surface_color, surface_data) = arrays(scene.meshes.iter().flat_map(|m| m.primitives.iter().map(|p| p.material)).collect())?;
        let (decal_color, decal_data) = arrays(scene.decals.iter().map(|d| d.material).collect())?;
        Ok(Self { surface_color, surface_data, decal_color, decal_data })
    }

    /// Every material's record for each use, the decals' after the surfaces'
    /// ([`GpuScene::decal_material_base`]).
    fn materials(&self, scene: &Scene) -> Vec<GpuMaterial> {
        let surfaces = scene.materials.iter().map(|m| gpu_material(m, &self.surface_color, &self.surface_data));
        surfaces.chain(scene.materials.iter().map(|m| gpu_material(m, &self.decal_color, &self.decal_data))).collect()
    }
}

/// Every primitive's vertices and indices, concatenated, and where each primitive starts.
struct Geometry {
    vertices: Vec<crate::scene::Vertex>,
    indices: Vec<u32>,
    /// (first index, index count, base vertex) by mesh and primitive.
    primitive_ranges: Vec<Vec<(u32, u32, u32)>>,
}

fn concatenate_primitives(scene: &Scene) -> Geometry {
    let mut vertices = Vec::new();
    let mut indices = Vec::new();
    let mut primitive_ranges = Vec::new();
    for mesh in &scene.meshes {
        primitive_ranges.push(
            mesh.primitives
                .iter()
                .map(|p| {
                    let range = (indices.len() as u32, p.indices.len() as u32, vertices.len() as u32);
                    vertices.extend_from_slice(&p.vertices);
                    indices.extend_from_slice(&p.indices);
                    range
                })
                .collect::<Vec<_>>(),
        );
    }
    Geometry { vertices, indices, primitive_ranges }
}

/// One draw per instance and primitive, and the commands that draw them: opaque, blended and
/// transmissive.
struct DrawList {
    draws: Vec<GpuDraw>,
    /// The mesh each draw draws.
    draw_meshes: Vec<usize>,
    instance_first_draw: Vec<usize>,
    draw_commands: Vec<DrawCommand>,
    transparent_draw_commands: Vec<DrawCommand>,
    transmissive_draw_commands: Vec<DrawCommand>,
}

impl DrawList {
    fn new(scene: &Scene, primitive_ranges: &[Vec<(u32, u32, u32)>]) -> Result<Self> {
        let mut list = Self {
            draws: Vec::new(),
            draw_meshes: Vec::new(),
            instance_first_draw: Vec::with_capacity(scene.instances.len()),
            draw_commands: Vec::new(),
            transparent_draw_commands: Vec::new(),
            transmissive_draw_commands: Vec::new(),
        };
        // Visibility ids number the drawn triangles from 0 (the background is told by depth).
        let mut next_visibility_id = 0u64;
        let deformed: BTreeSet<usize> = scene.deformers.iter().map(|d| d.mesh).collect();
        for instance in &scene.instances {
            list.instance_first_draw.push(list.draws.len());
            let (world_from_local, normal_from_local) = draw_transforms(&instance.world_from_local);
            let handedness = normal_from_local[0][3];
            let mesh = &scene.meshes[instance.mesh];
            for (primitive, &(first_index, index_count, base_vertex)) in mesh.primitives.iter().zip(&primitive_ranges[instance.mesh]) {
                let material = &scene.materials[primitive.material];
                let commands = if material.transmissive_unblended() {
                    &mut list.transmissive_draw_commands
                } else if material.drawn_over_opaque() {
                    &mut list.transparent_draw_commands
                } else {
                    &mut list.draw_commands
                };
                commands.push(DrawCommand {
                    draw_index: list.draws.len() as u32,
                    first_index,
                    index_count,
                    base_vertex,
                    center: instance.world_from_local.transform_point3(primitive_center(primitive)),
                    local_center: primitive_center(primitive),
                    bounds: (!deformed.contains(&instance.mesh))
                        .then(|| primitive_bounds(primitive).transformed(&glam::Affine3A::from_mat4(instance.world_from_local))),
                    local_bounds: (!deformed.contains(&instance.mesh)).then(|| primitive_bounds(primitive)),
                    state: RasterState {
                        alpha_mask: matches!(material.alpha_mode, AlphaMode::Mask { .. }),
                        double_sided: material.double_sided,
                        mirrored: handedness < 0.0,
                    },
                });
                list.draw_meshes.push(instance.mesh);
                list.draws.push(GpuDraw {
                    world_from_local,
                    normal_from_local,
                    first_index,
                    first_visibility_id: next_visibility_id as u32,
                    base_vertex,
                    material: primitive.material as u32,
                });
                next_visibility_id += u64::from(index_count / 3);
            }
        }
        if next_visibility_id > u64::from(NO_VISIBILITY_ID) {
            return Err(Error::InvalidScene(format!(
                "the scene draws {next_visibility_id} triangles; the visibility buffer numbers at most {NO_VISIBILITY_ID}"
            )));
        }
        Ok(list)
    }
}

/// Which draws move: those of instances the node animation moves and of deformed meshes.
fn moving_draws(scene: &Scene, instance_first_draw: &[usize], draw_count: usize) -> Vec<bool> {
    let mut moving = vec![false; draw_count];
    let mut deformed = vec![false; scene.meshes.len()];
    for deformer in &scene.deformers {
        deformed[deformer.mesh] = true;
    }
    let animated = scene.animation.iter().flat_map(|a| &a.instances).map(|&(instance, _)| instance);
    let deforming = scene.instances.iter().enumerate().filter(|(_, i)| deformed[i.mesh]).map(|(instance, _)| instance);
    for instance in animated.chain(deforming) {
        let first = instance_first_draw[instance];
        moving[first..first + scene.meshes[scene.instances[instance].mesh].primitives.len()].fill(true);
    }
    moving
}

/// One sampler per (wrap u, wrap v) pair, in the order of `shading/scene_bindings.wgsl`.
fn material_samplers(device: &wgpu::Device, anisotropy: u16) -> Vec<wgpu::Sampler> {
    let address_modes = [wgpu::AddressMode::Repeat, wgpu::AddressMode::MirrorRepeat, wgpu::AddressMode::ClampToEdge];
    (0..WRAP_SAMPLERS)
        .map(|i| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("material sampler"),
                address_mode_u: address_modes[i as usize % 3],
                address_mode_v: address_modes[i as usize / 3],
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                anisotropy_clamp: anisotropy,
                ..Default::default()
            })
        })
        .collect()
}

/// The particle grids shading samples, the particle system's (`particles/`) or 1×1×1 placeholders,
/// and their sampler.
fn particle_grid_bindings(device: &wgpu::Device, grids: Option<[&wgpu::Texture; 2]>) -> ([wgpu::TextureView; 2], wgpu::Sampler) {
    let placeholder = || {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some("no particle grid"),
            size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D3,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        })
    };
    let views = match grids {
        Some(grids) => grids.map(|t| t.create_view(&Default::default())),
        None => [placeholder(), placeholder()].map(|t| t.create_view(&Default::default())),
    };
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("particle grid sampler"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..Default::default()
    });
    (views, sampler)
}

/// Records of one kind as bytes, with the size of one record.
#[derive(Clone, Copy, Debug)]
pub struct Records<'a> {
    pub bytes: &'a [u8],
    pub record_size: usize,
}

impl<'a> Records<'a> {
    pub fn of<T: bytemuck::Pod>(records: &'a [T]) -> Self {
        Self { bytes: bytemuck::cast_slice(records), record_size: std::mem::size_of::<T>() }
    }
}

/// The scene's ray hierarchy as its bindings hold it (`rays::RayStructure::buffers`): the nodes, the
/// top level's `top_level_nodes` first, the triangles and the instances.
#[derive(Clone, Copy, Debug)]
pub struct RayBuffers<'a> {
    pub nodes: Records<'a>,
    pub top_level_nodes: usize,
    pub triangles: Records<'a>,
    pub instances: Records<'a>,
    /// The top-level acceleration structure of the hardware back end (`rays/hardware.rs`), bound
    /// as binding 31 where present.
    pub tlas: Option<&'a wgpu::Tlas>,
}

/// A read-only storage buffer, also usable as `usage`; empty arrays get one zeroed element because
/// bindings cannot be empty.
fn storage_buffer<T: bytemuck::Pod>(
    device: &wgpu::Device,
    label: &str,
    data: &[T],
    limit: u64,
    usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    storage_records(device, label, Records::of(data), limit, usage)
}

/// Per-pixel state the shading core writes: how many pixels keep a `restir` reservoir (two each:
/// the frame's and the one before), a denoiser's sample and a surface motion (0: none, one
/// placeholder record).
#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStateSize {
    pub reservoirs: u64,
    pub denoise_samples: u64,
    pub surface_motions: u64,
}

/// `records` zeroed records of `record_size` bytes for pixels (one placeholder for none); the error
/// names `what` and the option, `lighter`, that does without it.
pub fn pixel_buffer(
    device: &wgpu::Device,
    what: &str,
    records: u64,
    record_size: usize,
    limit: u64,
    lighter: &str,
) -> Result<wgpu::Buffer> {
    let bytes = records.max(1) * record_size as u64;
    if bytes > limit {
        return Err(Error::InvalidConfig(format!(
            "{what} take {:.1} MiB, over this GPU's storage binding limit of {:.1} MiB; render fewer pixels or use {lighter}",
            bytes as f64 / 1048576.0,
            limit as f64 / 1048576.0
        )));
    }
    Ok(device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

fn storage_records(device: &wgpu::Device, label: &str, records: Records, limit: u64, usage: wgpu::BufferUsages) -> Result<wgpu::Buffer> {
    let bytes = records.bytes.len() as u64;
    if bytes > limit {
        return Err(Error::InvalidScene(format!(
            "the scene's {label} take {:.1} MiB, over this GPU's storage binding limit of {:.1} MiB; use a smaller scene or a GPU with a larger limit",
            bytes as f64 / 1048576.0,
            limit as f64 / 1048576.0
        )));
    }
    let zero = vec![0; records.record_size];
    let contents = if records.bytes.is_empty() { &zero } else { records.bytes };
    Ok(device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::STORAGE | usage,
    }))
}

fn primitive_center(primitive: &crate::scene::Primitive) -> glam::Vec3 {
    primitive_bounds(primitive).center()
}

fn primitive_bounds(primitive: &crate::scene::Primitive) -> crate::scene::Aabb {
    let mut bounds = crate::scene::Aabb::EMPTY;
    for v in &primitive.vertices {
        bounds.grow_point(glam::Vec3::from(v.position));
    }
    bounds
}

/// Scene textures used as colour (sRGB) and as data (linear); a texture used both ways is in both.
fn texture_usage(materials: &[&Material]) -> (Vec<usize>, Vec<usize>) {
    let mut srgb = BTreeSet::new();
    let mut linear = BTreeSet::new();
    for m in materials {
        for (t, is_srgb) in m.textures() {
            if is_srgb {
                srgb.insert(t.texture)
            } else {
                linear.insert(t.texture)
            };
        }
    }
    (srgb.into_iter().collect(), linear.into_iter().collect())
}

fn wrap_bits(t: Option<TextureRef>) -> u32 {
    let code = |w: Wrap| match w {
        Wrap::Repeat => 0,
        Wrap::MirroredRepeat => 1,
        Wrap::ClampToEdge => 2,
    };
    t.map_or(0, |t| (code(t.wrap_v) << 2) | code(t.wrap_u))
}

/// A material's record with its textures' layers in `color` and `data`; textures not there (the
/// material has no use that uploaded them) are NO_TEXTURE.
fn gpu_material(m: &Material, color: &TextureArray, data: &TextureArray) -> GpuMaterial {
    let layer = |t: Option<TextureRef>, array: &TextureArray| t.and_then(|t| array.layers.get(&t.texture).copied()).unwrap_or(NO_TEXTURE);
    let alpha_cutoff = match m.alpha_mode {
        AlphaMode::Mask { cutoff } => cutoff,
        AlphaMode::Opaque | AlphaMode::Blend => 0.0,
    };
    let specular = &m.specular;
    let ior_reflectance = ((specular.ior - 1.0) / (specular.ior + 1.0)).powi(2);
    let clearcoat = m.clearcoat.unwrap_or(crate::scene::Clearcoat::untextured(0.0, 0.0));
    let transmission = m.transmission.unwrap_or(crate::scene::Transmission::thin(0.0));
    let sheen = m.sheen.unwrap_or(crate::scene::Sheen::untextured(glam::Vec3::ZERO, 0.0));
    // Slot order matches the WGSL (`TEXTURE_SLOTS`).
    let slots = [
        m.base_color_texture,
        m.emissive_texture,
        m.metallic_roughness_texture,
        m.normal_texture,
        specular.texture,
        specular.color_texture,
        clearcoat.texture,
        clearcoat.roughness_texture,
        clearcoat.normal_texture,
        m.occlusion_texture,
        transmission.texture,
        transmission.thickness_texture,
        sheen.color_texture,
        sheen.roughness_texture,
    ];
    let mut wrap_modes = [0u32; 2];
    for (k, slot) in slots.iter().enumerate() {
        wrap_modes[k / 8] |= wrap_bits(*slot) << (4 * (k % 8));
    }
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    let flags = flag(m.unlit, MATERIAL_UNLIT)
        | flag(m.clearcoat.is_some(), MATERIAL_CLEARCOAT)
        | flag(m.transmission.is_some(), MATERIAL_TRANSMISSION)
        | flag(m.sheen.is_some(), MATERIAL_SHEEN);
    GpuMaterial {
        base_color_factor: m.base_color_factor.to_array(),
        emissive_factor: m.emissive_factor.to_array(),
        alpha_cutoff,
        metallic_factor: m.metallic_factor,
        roughness_factor: m.roughness_factor,
        normal_scale: m.normal_scale,
        flags,
        base_color_layer: layer(m.base_color_texture, color),
        emissive_layer: layer(m.emissive_texture, color),
        metallic_roughness_layer: layer(m.metallic_roughness_texture, data),
        normal_layer: layer(m.normal_texture, data),
        specular_color: (specular.color_factor * ior_reflectance).to_array(),
        specular_factor: specular.factor,
        clearcoat_factor: clearcoat.factor,
        clearcoat_roughness_factor: clearcoat.roughness_factor,
        clearcoat_normal_scale: clearcoat.normal_scale,
        occlusion_strength: m.occlusion_strength,
        specular_layer: layer(specular.texture, data),
        specular_color_layer: layer(specular.color_texture, color),
        clearcoat_layer: layer(clearcoat.texture, data),
        clearcoat_roughness_layer: layer(clearcoat.roughness_texture, data),
        clearcoat_normal_layer: layer(clearcoat.normal_texture, data),
        occlusion_layer: layer(m.occlusion_texture, data),
        wrap_modes,
        attenuation_color: transmission.attenuation_color.to_array(),
        attenuation_distance: if transmission.attenuation_distance.is_finite() { transmission.attenuation_distance } else { 0.0 },
        transmission_factor: transmission.factor,
        thickness_factor: transmission.thickness_factor,
        ior: specular.ior.max(1.0),
        transmission_layer: layer(transmission.texture, data),
        thickness_layer: layer(transmission.thickness_texture, data),
        sheen_color_layer: layer(sheen.color_texture, color),
        sheen_roughness_layer: layer(sheen.roughness_texture, data),
        dispersion: transmission.dispersion,
        sheen_color: sheen.color_factor.to_array(),
        sheen_roughness: sheen.roughness_factor,
        uv_transforms: uv_transforms(slots),
    }
}

/// The slots' coordinate sets and transforms as `GpuMaterial::uv_transforms` lays them out (the
/// first set, as it is, where a slot has no texture).
fn uv_transforms(slots: [Option<TextureRef>; TEXTURE_SLOTS]) -> [[f32; 4]; 2 * TEXTURE_SLOTS] {
    let mut packed = [[0.0; 4]; 2 * TEXTURE_SLOTS];
    for (k, slot) in slots.iter().enumerate() {
        let t = slot.map_or(glam::Affine2::IDENTITY, |t| t.uv_transform);
        packed[2 * k] = [t.matrix2.x_axis.x, t.matrix2.x_axis.y, t.matrix2.y_axis.x, t.matrix2.y_axis.y];
        packed[2 * k + 1] = [t.translation.x, t.translation.y, slot.map_or(0.0, |t| t.tex_coord as f32), 0.0];
    }
    packed
}

#[cfg(test)]
mod tests {
    use std::mem::{offset_of, size_of};

    use super::*;
    use crate::{gpu::FrameUniforms, scene::Vertex};

    /// Each WGSL struct of the scene's bindings (`shading/types.wgsl`, `rays/ray_types.wgsl`) against
    /// its Rust twin: same size, same members at the same offsets, so uploads are read as written.
    #[test]
    fn rust_structs_match_their_wgsl_layout() {
        let source = crate::gpu::shaders::ShaderDesc::new("shading/scene_bindings.wgsl").compose().unwrap();
        let module = naga::front::wgsl::parse_str(&source).unwrap();
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let wgsl_layout = |name: &str| -> (u32, Vec<(String, u32)>) {
            let (_, ty) = module.types.iter().find(|(_, t)| t.name.as_deref() == Some(name)).unwrap_or_else(|| panic!("no struct {name}"));
            match &ty.inner {
                naga::TypeInner::Struct { members, span } => (*span, members.iter().map(|m| (m.name.clone().unwrap(), m.offset)).collect()),
                _ => panic!("{name} is not a struct"),
            }
        };
        macro_rules! check {
            ($wgsl:literal, $rust:ty, [$($field:ident),* $(,)?]) => {{
                let (size, members) = wgsl_layout($wgsl);
                assert_eq!(size as usize, size_of::<$rust>(), "size of {}", $wgsl);
                let rust: Vec<(String, u32)> = vec![$((stringify!($field).to_string(), offset_of!($rust, $field) as u32)),*];
                let wgsl: Vec<(String, u32)> = members.into_iter().filter(|(n, _)| !n.starts_with("_pad")).collect();
                assert_eq!(wgsl, rust, "members of {}", $wgsl);
            }};
        }
        check!("Vertex", Vertex, [position, u, normal, v, tangent, color, uv1]);
        check!("Draw", GpuDraw, [world_from_local, normal_from_local, first_index, first_visibility_id, base_vertex, material]);
        check!(
            "Material",
            GpuMaterial,
            [
                base_color_factor,
                emissive_factor,
                alpha_cutoff,
                metallic_factor,
                roughness_factor,
                normal_scale,
                flags,
                base_color_layer,
                emissive_layer,
                metallic_roughness_layer,
                normal_layer,
                specular_color,
                specular_factor,
                clearcoat_factor,
                clearcoat_roughness_factor,
                clearcoat_normal_scale,
                occlusion_strength,
                specular_layer,
                specular_color_layer,
                clearcoat_layer,
                clearcoat_roughness_layer,
                clearcoat_normal_layer,
                occlusion_layer,
                wrap_modes,
                attenuation_color,
                attenuation_distance,
                transmission_factor,
                thickness_factor,
                ior,
                transmission_layer,
                thickness_layer,
                sheen_color_layer,
                sheen_roughness_layer,
                dispersion,
                sheen_color,
                sheen_roughness,
                uv_transforms
            ]
        );
        check!("Light", GpuLight, [position, range, radiant, kind, direction, spot_scale, spot_offset, flags]);
        check!("Decal", GpuDecal, [decal_from_group, material, layer, weight]);
        check!("Reservoir", GpuReservoir, [light, instance, light_hash, weight, position, normal_count]);
        check!("DenoiseSample", GpuDenoiseSample, [diffuse, normal, specular, albedo, position, specular_albedo]);
        check!("SurfaceMotion", GpuSurfaceMotion, [moved, frame]);
        check!("RayTriangle", crate::rays::RayTriangle, [v0, draw_offset, e1, triangle, e2]);
        check!("RayInstance", crate::rays::RayInstance, [local_from_world, blas_root, first_draw, scene_instance, first_triangle]);
        check!(
            "FrameUniforms",
            FrameUniforms,
            [
                clip_from_world,
                view_from_clip,
                world_from_view,
                viewport,
                sun_direction,
                sun_radiance,
                environment_irradiance,
                environment,
                light_instance_count,
                exposure,
                tonemapper,
                decal_instance_count,
                cluster_grid,
                cluster_depth,
                particle_volume,
                particle_filter,
                particle_texture_unscale,
                particle_cascades,
                ray_options,
                ray_settings,
                debug_view,
                direct_lighting,
                previous_clip_from_world
            ]
        );
    }

    #[test]
    fn spot_cone_follows_khr_lights_punctual() {
        let spot = Light {
            kind: LightKind::Spot { inner_cone_angle: 0.2, outer_cone_angle: 0.5 },
            position: glam::Vec3::ZERO,
            direction: glam::Vec3::new(0.0, -2.0, 0.0),
            color: glam::Vec3::new(1.0, 0.5, 0.25),
            intensity: 4.0,
            range: 3.0,
            cast_shadows: false,
        };
        let gpu = GpuLight::from(&spot);
        let attenuation = |angle: f32| (angle.cos() * gpu.spot_scale + gpu.spot_offset).clamp(0.0, 1.0);
        assert!((attenuation(0.2) - 1.0).abs() < 1e-5, "full intensity at the inner angle");
        assert!(attenuation(0.5).abs() < 1e-5, "zero at the outer angle");
        assert_eq!(gpu.direction, [0.0, -1.0, 0.0]);
        assert_eq!(gpu.radiant, [4.0, 2.0, 1.0]);
    }
}
