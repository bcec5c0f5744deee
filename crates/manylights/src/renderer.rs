//! The renderer: a device, an uploaded scene and a pipeline. `render` draws one frame for a camera;
//! images are read back on request so benchmarks time frames without readback in the way.

use glam::Vec3;

use crate::{
    accel::VolumeStructure,
    gpu::{
        cluster_grid::ClusterGrid,
        readback,
        scene::{PixelStateSize, RayBuffers},
        FrameUniforms, GpuContext, GpuScene, GpuTimer, PassTimings,
    },
    particles::{ParticleGrid, ParticleSystem, ParticleVolume},
    passes::{deform::Deform, FrameInputs, Structures},
    pipelines::{FramePipeline, FrameSetup},
    plan::{Capabilities, FramePlan, Measurements, MethodChoice, ParticlePlan, RayTracer, ShadingMethods, StructurePlan},
    post::PostFrame,
    rays::{hardware::HardwareRays, refit::BlasRefit, RayStructure, RayStructureStats},
    scene::ParticleSettings,
    scene::{Aabb, Camera, Scene},
    settings::{DecalMethod, LightMethod, RenderConfig},
    Error, Result,
};

pub use crate::gpu::readback::Image;

/// Time between frames rendered back to back: animated groups move by this much per frame.
pub const FRAME_INTERVAL: f32 = 1.0 / 60.0;

pub struct Renderer {
    pub ctx: GpuContext,
    pub scene: GpuScene,
    /// The settings the frames run with: as given, with `auto`'s methods resolved.
    pub config: RenderConfig,
    /// The light and decal methods that run, and why.
    methods_chosen: MethodChoice,
    ray_tracer: RayTracer,
    pipeline: FramePipeline,
    /// What the shading passes were composed with, decided by the configuration, the device and the
    /// structures built for the scene.
    methods: ShadingMethods,
    lights: VolumeStructure,
    decals: VolumeStructure,
    /// Present when the scene has particles and a particle method lights them.
    particles: Option<ParticleSystem>,
    timer: Option<GpuTimer>,
    /// The scene's ray hierarchy, when the frame traces rays: its top level is rebuilt when
    /// instances move.
    rays: Option<RayStructure>,
    /// What moves the scene's mesh instances, with every instance's transform and primitive count.
    motion: Option<InstanceMotion>,
    /// Deformed meshes' vertices, and their BLASes' refit when the frame traces rays.
    deform: Option<Deform>,
    refit: Option<BlasRefit>,
    /// The rays' acceleration structures with the hardware back end (`rays/hardware.rs`).
    hardware_rays: Option<HardwareRays>,
    /// Scene time of the next frame, in seconds: where animated groups are.
    pub time: f32,
    /// Frames rendered so far: a deformed mesh's BLAS copy is the frame's parity.
    frame_index: u64,
    /// `restir` keeps each pixel's reservoir for the next frame (`FramePlan::keeps_reservoirs`).
    keeps_reservoirs: bool,
    /// Animated instances' previous placement is written for the surface motions
    /// (`FramePlan::tracks_surface_motion`), as for motion blur.
    tracks_surface_motion: bool,
    /// The camera of the last frame rendered, for motion blur's velocities; `None` before the first.
    previous_camera: Option<Camera>,
    /// Test mode: after every frame, read the ray hierarchy back and check that the frame traced
    /// complete deformed BLASes of its own time (`check_ray_hierarchy`). Each frame then waits for
    /// the GPU.
    pub validate_ray_hierarchy: bool,
}

/// What moves or changes the scene's instances every frame: the node animation, if any, and the
/// deformed meshes' alternating BLAS copies; each instance's current transform (for the rays' top
/// level) and its primitive count (its draws).
struct InstanceMotion {
    animation: Option<crate::scene::animation::Animation>,
    transforms: Vec<glam::Mat4>,
    primitive_counts: Vec<usize>,
}

/// The anisotropy the samplers get. lavapipe takes seconds per pixel when decal textures are sampled
/// anisotropically (in the visibility-buffer resolve and in fragment shaders), so on lavapipe every
/// pipeline filters trilinearly, with a warning.
fn effective_anisotropy(ctx: &GpuContext, config: &RenderConfig) -> u16 {
    if config.anisotropy > 1 && ctx.info.name.contains("llvmpipe") {
        static WARNED: std::sync::Once = std::sync::Once::new();
        WARNED.call_once(|| log::warn!("lavapipe is pathologically slow at anisotropic filtering: using --anisotropy 1 on it"));
        return 1;
    }
    config.anisotropy
}

/// One frame's timings: GPU milliseconds per pass (empty without timestamp support), and the CPU's
/// milliseconds to record and submit the frame's commands.
#[derive(Clone, Debug, Default)]
pub struct FrameTiming {
    pub passes: PassTimings,
    pub cpu_ms: f64,
}

impl FrameTiming {
    /// The frame's GPU time: the sum of its passes.
    pub fn gpu_ms(&self) -> f64 {
        self.passes.iter().map(|(_, ms)| ms).sum()
    }
}

impl Renderer {
    pub fn new(ctx: GpuContext, scene: &Scene, config: RenderConfig) -> Result<Self> {
        config.validate(&ctx.device_limits())?;
        // Before anything is built from it (the ray hierarchy, the light and decal structures).
        scene.validate()?;
        let caps = Capabilities::of(&ctx);
        let stats = crate::accel::overlap::scene_statistics(scene, Measurements::for_settings(&config, caps))?;
        let plan = FramePlan::resolve(&config, caps, &stats)?;
        // From here on the methods that run stand in the settings; `methods_chosen` says why.
        let config = plan.methods.apply(&config);
        let particle_settings = scene.particles.as_ref().filter(|s| s.count > 0);
        let light_particles = particle_settings.filter(|_| matches!(plan.particles, ParticlePlan::Lights(_)));
        check_loop_limit(&ctx, scene, &config, light_particles.map_or(0, |p| p.count as usize))?;
        let grid_particles = match particle_settings {
            Some(settings) if plan.particles == ParticlePlan::Grid => {
                Some(ParticleSystem::new(&ctx, settings, particle_volume(&ctx, scene, settings, &config)?)?)
            }
            _ => None,
        };
        // The triangles' hierarchy is built (on the CPU, once) only for frames that trace rays.
        let rays = plan.traces_rays.then(|| RayStructure::build(scene)).transpose()?;
        // Without one, the scene binds a hierarchy no ray meets.
        let no_rays = RayStructure::unused();
        let hardware_rays = match &rays {
            Some(rays) if plan.hardware_rays => Some(HardwareRays::new(&ctx, rays)?),
            _ => None,
        };
        let gpu_scene = GpuScene::upload(
            &ctx,
            scene,
            config.max_texture_size,
            effective_anisotropy(&ctx, &config),
            grid_particles.as_ref().and_then(ParticleSystem::grid_textures),
            RayBuffers {
                tlas: hardware_rays.as_ref().map(HardwareRays::tlas),
                ..rays.as_ref().filter(|r| !r.nodes.is_empty()).unwrap_or(&no_rays).buffers()
            },
            {
                let pixels = u64::from(config.width) * u64::from(config.height);
                PixelStateSize {
                    reservoirs: if plan.keeps_reservoirs { pixels } else { 0 },
                    denoise_samples: if plan.denoises { pixels } else { 0 },
                    surface_motions: if plan.tracks_surface_motion { pixels } else { 0 },
                }
            },
        )?;
        let hardware_rays = match (hardware_rays, &rays) {
            (Some(hardware), Some(rays)) => Some(hardware.with_deformed_corners(&ctx, rays, &gpu_scene.ray_triangle_buffer)?),
            _ => None,
        };
        // Clustered lists are built every frame only where the method reads them.
        let grid = ClusterGrid::for_resolution(config.width, config.height);
        let clusters = |structure: &StructurePlan| structure.clustered.then_some((grid, &gpu_scene.bind_group_layout));
        let (lights, particles) = match (light_particles, plan.particles) {
            (Some(settings), ParticlePlan::Lights(leaves)) => {
                let lights = VolumeStructure::for_lights_and_particles(
                    &ctx,
                    &scene.lights,
                    &scene.light_groups,
                    &plan.lights,
                    settings.count,
                    settings.bounds(),
                    leaves,
                )?;
                let targets = lights.dynamic_group().ok_or_else(|| Error::Gpu("the particle lights' group is missing".into()))?;
                let particles = ParticleSystem::with_lights(&ctx, settings, targets)?;
                (lights, Some(particles))
            }
            _ => {
                let lights = VolumeStructure::for_lights(&ctx, &scene.lights, &scene.light_groups, &plan.lights, clusters(&plan.lights))?;
                (lights, grid_particles)
            }
        };
        let decals = VolumeStructure::for_decals(
            &ctx,
            &scene.decals,
            &scene.decal_groups,
            &plan.decals,
            clusters(&plan.decals),
            gpu_scene.decal_material_base,
        )?;
        let methods = plan.shading_methods(decals.cell_lists(), lights.cell_lists());
        let setup = FrameSetup {
            methods,
            shadows: config.rays.sun_shadows,
            post: config.post,
            structures: Structures { lights: &lights, decals: &decals },
            size: (config.width, config.height),
            surface_motion: plan.tracks_surface_motion,
        };
        let pipeline = FramePipeline::new(&ctx, &gpu_scene, config.pipeline, setup)?;
        let timer = GpuTimer::new(&ctx);
        ctx.check_errors()?;
        let motion = (scene.animation.is_some() || !scene.deformers.is_empty()).then(|| InstanceMotion {
            animation: scene.animation.clone(),
            transforms: scene.instances.iter().map(|i| i.world_from_local).collect(),
            primitive_counts: scene.instances.iter().map(|i| scene.meshes[i.mesh].primitives.len()).collect(),
        });
        let deform = Deform::new(&ctx, scene, &gpu_scene)?;
        let refit = match &rays {
            Some(rays) => BlasRefit::new(&ctx, &gpu_scene, rays)?,
            None => None,
        };
        Ok(Self {
            ctx,
            scene: gpu_scene,
            config,
            methods_chosen: plan.methods,
            ray_tracer: plan.ray_tracer,
            pipeline,
            methods,
            lights,
            decals,
            particles,
            timer,
            rays,
            motion,
            deform,
            refit,
            hardware_rays,
            keeps_reservoirs: plan.keeps_reservoirs,
            tracks_surface_motion: plan.tracks_surface_motion,
            time: 0.0,
            frame_index: 0,
            previous_camera: None,
            validate_ray_hierarchy: false,
        })
    }

    /// The methods the shading passes were composed with.
    pub fn shading_methods(&self) -> ShadingMethods {
        self.methods
    }

    /// What traces the point queries: the GPU's ray queries or the software BVHs.
    pub fn ray_tracer(&self) -> RayTracer {
        self.ray_tracer
    }

    /// The light and decal methods that run, and why (`auto`'s choice, or asked for).
    pub fn methods_chosen(&self) -> MethodChoice {
        self.methods_chosen
    }

    /// The ray hierarchy's sizes and CPU build times, when the frame traces rays.
    pub fn ray_structure(&self) -> Option<RayStructureStats> {
        self.rays.as_ref().map(RayStructure::stats)
    }

    /// Places animated instances where they are at `time`: their draws, and the rays' top level
    /// rebuilt over every instance, deformed meshes' instances on the BLAS copy of the frame's
    /// `parity`; with motion blur, also where animated instances were a frame interval before.
    fn move_instances(&mut self, time: f32, parity: usize) -> Result<()> {
        let Some(motion) = &mut self.motion else { return Ok(()) };
        let (moved, previous) = match &motion.animation {
            Some(animation) => {
                let moved = animation.instance_transforms(time);
                let read = self.pipeline.post().settings.motion_blur.is_some() || self.tracks_surface_motion;
                let previous = if !read {
                    Vec::new()
                } else if animation.loops_between(time - FRAME_INTERVAL, time) {
                    // On the frame where a looping animation starts over, the pose a frame earlier is
                    // the clip's end: no motion is the honest velocity.
                    moved.clone()
                } else {
                    animation.instance_transforms(time - FRAME_INTERVAL)
                };
                (moved, previous)
            }
            None => (Vec::new(), Vec::new()),
        };
        if let Some(rays) = &mut self.rays {
            for &(instance, transform) in &moved {
                motion.transforms[instance] = transform;
            }
            if rays.deformed.iter().any(crate::rays::DeformedBlas::is_posed) {
                let clock = crate::scene::deform::PoseClock::at(time, motion.animation.as_ref());
                for deformed in &mut rays.deformed {
                    deformed.set_time(&clock);
                }
            }
            rays.place(&motion.transforms, parity)?;
        }
        self.scene.move_instances(
            &self.ctx.queue,
            &moved,
            &previous,
            &motion.primitive_counts,
            self.rays.as_ref().map(RayStructure::buffers),
        );
        Ok(())
    }

    /// Whether `render` returns per-pass GPU timings.
    pub fn has_timestamps(&self) -> bool {
        self.timer.is_some()
    }

    /// Renders one frame and waits for it; returns per-pass GPU milliseconds (empty without
    /// timestamp support).
    pub fn render(&mut self, camera: &Camera) -> Result<PassTimings> {
        Ok(self.render_frames(camera, 1)?.pop().map(|frame| frame.passes).unwrap_or_default())
    }

    /// Renders `count` frames submitted back to back, as an application's frame loop does, waiting
    /// only when the timer's slots are full and at the end; each frame advances `time` by
    /// [`FRAME_INTERVAL`]. Returns each frame's timings.
    ///
    /// When the clustered lists, the rebuilt cell lists or the blended surfaces' layers were too short
    /// for a frame, they grow and the frames are rendered again from the same time, so every returned
    /// frame is complete.
    pub fn render_frames(&mut self, camera: &Camera, count: u32) -> Result<Vec<FrameTiming>> {
        let start = self.time;
        if !start.is_finite() {
            return Err(Error::InvalidConfig(format!("scene time {start} s is not a finite number of seconds")));
        }
        // Settings the camera cannot serve (depth of field through an orthographic lens) fail here,
        // before anything of a frame is recorded.
        self.pipeline.post().check_camera(camera, (self.config.width, self.config.height))?;
        // What a frame carries over to the next, restored when the frames are rendered again.
        let (start_frame, start_camera) = (self.frame_index, self.previous_camera.clone());
        self.pipeline.post().save_state(&self.ctx);
        loop {
            let timings = self.submit_frames(camera, count)?;
            // Both are asked: each grows its own lists.
            let lights_fitted = self.lights.lists_fitted(&self.ctx)?;
            let decals_fitted = self.decals.lists_fitted(&self.ctx)?;
            let layers_fitted = self.pipeline.blended_layers_fitted(&self.ctx)?;
            if lights_fitted && decals_fitted && layers_fitted {
                return Ok(timings);
            }
            self.time = start;
            self.frame_index = start_frame;
            self.previous_camera = start_camera.clone();
            self.pipeline.post().restore_state(&self.ctx);
            // The reservoirs and the denoiser's history kept before these frames were overwritten:
            // they start afresh.
            self.scene.clear_reservoirs(&self.ctx);
            self.pipeline.clear_denoiser_history(&self.ctx);
        }
    }

    fn submit_frames(&mut self, camera: &Camera, count: u32) -> Result<Vec<FrameTiming>> {
        let mut uniforms = FrameUniforms::new(
            camera,
            self.config.width,
            self.config.height,
            &self.scene.constants,
            self.config.post.exposure.fixed_scale(),
            self.config.tonemapper,
        );
        uniforms.light_instance_count = self.lights.instance_count();
        uniforms.decal_instance_count = self.decals.instance_count();
        (uniforms.ray_options, uniforms.ray_settings) = crate::gpu::frame::ray_uniforms(&self.config.rays, camera, self.config.height);
        uniforms.debug_view = self.config.debug_view.uniform(self.config.debug_slice_height.unwrap_or(camera.position().y - 1.0));
        if let Some(particles) = &self.particles {
            if let (Some(volume), Some(scales)) = (particles.volume(), particles.scales()) {
                uniforms.particle_volume = volume.dims().extend(volume.cascade_count()).to_array();
                uniforms.particle_filter = [self.config.particle_filter as u32, self.config.particle_samples, 0, 0];
                uniforms.particle_texture_unscale = [1.0 / scales.texture; 4];
                uniforms.particle_cascades = volume.gpu_cascades(camera.position());
            }
        }
        let mut timings = Vec::new();
        let mut cpu_ms = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let mut encoder = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
            if let Some(timer) = &mut self.timer {
                if timer.is_full() {
                    timings.extend(timer.read(&self.ctx)?);
                }
                timer.begin_frame();
            }
            // From here to the submit is the CPU's work for the frame (waits for the timer are before).
            let recording = std::time::Instant::now();
            let parity = (self.frame_index % 2) as usize;
            // Each frame draws its own light samples and reprojects from the camera before: the uniforms
            // are written again before its submit.
            let rays = &self.config.rays;
            let reuse = if self.keeps_reservoirs { rays.restir_reuse as u32 } else { 0 };
            uniforms.direct_lighting = [self.frame_index as u32, rays.restir_shadow_rays, parity as u32, reuse];
            let previous = self.previous_camera.as_ref().unwrap_or(camera);
            uniforms.previous_clip_from_world = previous.clip_from_world(self.config.width, self.config.height).to_cols_array_2d();
            self.scene.write_frame(&self.ctx.queue, &uniforms);
            self.move_instances(self.time, parity)?;
            // Deformed meshes first: every pass after draws or traces them, and the draws are
            // ordered and culled by their boxes at this time.
            if let Some(deform) = &mut self.deform {
                let animation = self.motion.as_ref().and_then(|m| m.animation.as_ref());
                // As for moving instances: across the loop's restart, no motion.
                let before = self.time - FRAME_INTERVAL;
                let before = if animation.is_some_and(|a| a.loops_between(before, self.time)) { self.time } else { before };
                let boxes = deform.write_time(&self.ctx.queue, self.time, before, animation);
                self.scene.place_deformed(&boxes);
                deform.record(&mut encoder, self.timer.as_mut());
            }
            self.scene.order_draws(&self.ctx.queue, camera.clip_from_world(self.config.width, self.config.height), camera.position());
            if let Some(refit) = &self.refit {
                refit.record(&mut encoder, self.timer.as_mut(), parity);
            }
            if let (Some(hardware), Some(rays)) = (&mut self.hardware_rays, &self.rays) {
                hardware.record(&mut encoder, self.timer.as_mut(), rays, parity, self.motion.is_some());
            }
            let post = PostFrame {
                camera,
                previous_camera: self.previous_camera.as_ref().unwrap_or(camera),
                size: (self.config.width, self.config.height),
                interval: self.previous_camera.is_some().then_some(FRAME_INTERVAL),
            };
            self.pipeline.post().write_uniforms(&self.ctx.queue, post)?;
            self.previous_camera = Some(camera.clone());
            // Particles first: as lights, they are the light structure's dynamic group, whose build
            // reads their boxes; their light records follow the build, in its leaves' order.
            if let Some(particles) = &self.particles {
                particles.record(&self.ctx, &mut encoder, self.timer.as_mut(), self.time, camera.position());
            }
            for structure in [&mut self.lights, &mut self.decals] {
                structure.record(&self.ctx, &mut encoder, self.timer.as_mut(), self.time)?;
                structure.record_clusters(&mut encoder, self.timer.as_mut(), &self.scene.bind_group);
            }
            if let Some(particles) = &self.particles {
                particles.record_lights(&mut encoder, self.timer.as_mut());
            }
            let inputs = FrameInputs { scene: &self.scene, lights: &self.lights, decals: &self.decals, parity };
            self.pipeline.record(&mut encoder, self.timer.as_mut(), &inputs);
            if let Some(timer) = &self.timer {
                timer.resolve(&mut encoder);
            }
            self.ctx.queue.submit([encoder.finish()]);
            cpu_ms.push(recording.elapsed().as_secs_f64() * 1e3);
            if self.validate_ray_hierarchy {
                self.check_ray_hierarchy(parity, self.time)?;
            }
            self.time += FRAME_INTERVAL;
            self.frame_index += 1;
        }
        match &mut self.timer {
            Some(timer) => timings.extend(timer.read(&self.ctx)?),
            None => self.ctx.wait_idle()?,
        }
        self.ctx.check_errors()?;
        timings.resize_with(cpu_ms.len(), PassTimings::default);
        Ok(timings.into_iter().zip(cpu_ms).map(|(passes, cpu_ms)| FrameTiming { passes, cpu_ms }).collect())
    }

    /// Test mode's check after a frame of `parity` at `time` (`validate_ray_hierarchy`): reads the ray
    /// hierarchy back and checks that the frame's top level placed every deformed mesh's instances on
    /// copy `parity`, that this copy's triangles are the mesh deformed to `time` (the CPU twin,
    /// `scene::deform`) and that each of its nodes bounds its children or triangles. A frame that
    /// traced a half-built or stale copy fails it.
    pub fn check_ray_hierarchy(&self, parity: usize, time: f32) -> Result<()> {
        let Some(rays) = &self.rays else { return Ok(()) };
        if rays.deformed.is_empty() {
            return Ok(());
        }
        let nodes: Vec<crate::accel::BvhNode> = readback::read_buffer(&self.ctx, &self.scene.ray_node_buffer)?;
        let triangles: Vec<crate::rays::RayTriangle> = readback::read_buffer(&self.ctx, &self.scene.ray_triangle_buffer)?;
        let instances: Vec<crate::rays::RayInstance> = readback::read_buffer(&self.ctx, &self.scene.ray_instance_buffer)?;
        let fail = |m: String| Err(Error::Gpu(format!("ray hierarchy of the frame at {time} s: {m}")));
        for deformed in &rays.deformed {
            let root = deformed.roots[parity];
            let other = deformed.roots[1 - parity];
            if instances.iter().any(|i| i.blas_root == other) || !instances.iter().any(|i| i.blas_root == root) {
                return fail(format!("mesh {}'s instances are not on copy {parity}", deformed.mesh));
            }
            let expected = deformed.deformed_triangles(time, self.motion.as_ref().and_then(|m| m.animation.as_ref()));
            let got = &triangles[deformed.triangles[parity].start as usize..deformed.triangles[parity].end as usize];
            if got.len() != expected.len() {
                return fail(format!("mesh {} has {} triangles stored, {} expected", deformed.mesh, got.len(), expected.len()));
            }
            let scale = (deformed.bounds.max - deformed.bounds.min).length().max(1e-6);
            for (k, (g, e)) in got.iter().zip(&expected).enumerate() {
                let errors = [(g.v0, e.v0), (g.e1, e.e1), (g.e2, e.e2)].map(|(a, b)| (glam::Vec3::from(a) - glam::Vec3::from(b)).length());
                // Written so that NaN fails too.
                if !errors.iter().all(|&error| error <= 1e-4 * scale) {
                    return fail(format!("mesh {} triangle {k} is off its deformation at this time by {errors:?}", deformed.mesh));
                }
            }
            for &n in &deformed.refit_order[parity] {
                let node = &nodes[n as usize];
                let inner = if node.is_leaf() {
                    node.leaf_range().map(|k| triangles[k].bounds()).fold(Aabb::EMPTY, Aabb::union)
                } else {
                    let first = &nodes[node.entry as usize];
                    first.bounds().union(nodes[first.skip as usize].bounds())
                };
                let bounds = node.bounds();
                if !(bounds.min.is_finite() && bounds.max.is_finite() && bounds.contains_box(&inner)) {
                    return fail(format!("mesh {} node {n} does not bound its contents", deformed.mesh));
                }
            }
            // The top level's box for the mesh, built on the CPU before the refit, must hold it.
            if !deformed.bounds.contains_box(&nodes[root as usize].bounds()) {
                return fail(format!("mesh {} outgrew the box the top level gives it", deformed.mesh));
            }
        }
        Ok(())
    }

    /// Entries the clustered lists of lights and of decals hold now, for the methods that use them.
    pub fn cluster_capacities(&self) -> (Option<u32>, Option<u32>) {
        (self.lights.cluster_capacity(), self.decals.cluster_capacity())
    }

    /// The image the last frame ends in, on the GPU: RGBA8 holding sRGB-encoded values (the viewer
    /// shows it).
    pub fn output(&self) -> &wgpu::Texture {
        &self.pipeline.targets().ldr
    }

    /// The last frame after tonemapping: RGBA8, sRGB-encoded.
    pub fn read_ldr(&self) -> Result<Image<[u8; 4]>> {
        let bytes = readback::read_texture(&self.ctx, &self.pipeline.targets().ldr, 4)?;
        Ok(self.image(bytemuck::cast_slice(&bytes).to_vec()))
    }

    /// The last frame before exposure and tonemapping: linear RGBA radiance.
    pub fn read_hdr(&self) -> Result<Image<[f32; 4]>> {
        let bytes = readback::read_texture(&self.ctx, &self.pipeline.targets().hdr, 16)?;
        Ok(self.image(bytemuck::pod_collect_to_vec(&bytes)))
    }

    fn image<T>(&self, pixels: Vec<T>) -> Image<T> {
        Image { width: self.config.width, height: self.config.height, pixels }
    }
}

/// Where the particle grid lies: over the scene's bounds and a particle's reach around them (voxel
/// centres on both sides of every surface, so trilinear sampling at a surface blends both), or in
/// camera-centred cascades.
fn particle_volume(ctx: &GpuContext, scene: &Scene, settings: &ParticleSettings, config: &RenderConfig) -> Result<ParticleVolume> {
    let max_dimension = ctx.limits.max_texture_dimension_3d;
    match config.particle_cascades {
        0 => {
            let bounds = scene.bounds();
            let reach = Vec3::splat(settings.radius.1);
            let covered = Aabb::new(bounds.min - reach, bounds.max + reach);
            Ok(ParticleVolume::World(ParticleGrid::covering(&covered, config.particle_voxel_size, max_dimension)?))
        }
        cascades => ParticleVolume::clipmap(config.particle_voxel_size, config.particle_cascade_resolution, cascades, max_dimension),
    }
}

/// Refuses frames whose brute-force or clustered loops a driver would cut short
/// (`gpu::loop_limit`); warns where a BVH walk could be, which depends on the view.
fn check_loop_limit(ctx: &GpuContext, scene: &Scene, config: &RenderConfig, light_particles: usize) -> Result<()> {
    let Some(limit) = ctx.loop_limit else { return Ok(()) };
    let looped = |loops: bool, count: usize| if loops { count } else { 0 };
    let loops = [
        (
            "lights",
            config.light_method.name(),
            looped(matches!(config.light_method, LightMethod::Brute | LightMethod::Clustered), scene.lights.len()),
        ),
        (
            "decals",
            config.decal_method.name(),
            looped(matches!(config.decal_method, DecalMethod::Brute | DecalMethod::Clustered), scene.decals.len()),
        ),
    ];
    if let Some(problem) = crate::gpu::loop_limit::loop_limit_problem(Some(limit), &ctx.describe(), &loops) {
        return Err(Error::InvalidConfig(problem));
    }
    let walked = scene.lights.len() + scene.decals.len() + light_particles;
    if walked > limit as usize {
        log::warn!(
            "this driver ({}) ends a shader's loops after {limit} iterations in all: where a BVH walk meets more of the {walked} \
             lights and decals at one point, some are left out; Mesa 25's lavapipe has no such limit",
            ctx.describe()
        );
    }
    Ok(())
}
