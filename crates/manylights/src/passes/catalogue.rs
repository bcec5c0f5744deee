//! Every shader the renderer builds, for the tests that validate and compile them all.

use crate::gpu::shaders::ShaderDesc;
use crate::plan::{DirectShading, ShadingMethods};
use crate::settings::{DecalMethod, LightMethod, ParticleMethod, PipelineKind};

/// Every shader the renderer builds, with every substitution it uses: the naga test validates each.
pub fn all_shaders() -> Vec<ShaderDesc> {
    let mut shaders = vec![
        ShaderDesc::new("passes/visbuffer_raster_indexed.wgsl"),
        ShaderDesc::new("passes/visbuffer_raster_pulled.wgsl"),
        ShaderDesc::new("passes/deform.wgsl"),
        ShaderDesc::new("rays/refit.wgsl"),
        ShaderDesc::new("post/velocity.wgsl"),
        ShaderDesc::new("post/velocity_raster.wgsl"),
        ShaderDesc::new("post/depth_of_field.wgsl"),
        ShaderDesc::new("post/motion_blur.wgsl"),
        ShaderDesc::new("post/exposure.wgsl"),
        ShaderDesc::new("post/bloom.wgsl"),
        ShaderDesc::new("post/tonemap.wgsl"),
        crate::accel::volume_query_probe_shader(false),
        crate::accel::volume_query_probe_shader(true),
        ShaderDesc::new("accel/lbvh.wgsl"),
        ShaderDesc::new("accel/leaf_order.wgsl"),
        ShaderDesc::new("accel/rebuilt_grid.wgsl"),
        ShaderDesc::new("accel/rebuilt_cell_lists.wgsl"),
        ShaderDesc::new("accel/radix_sort.wgsl"),
        ShaderDesc::new("accel/cluster_build.wgsl"),
        ShaderDesc::new("passes/deferred_decals.wgsl"),
        ShaderDesc::new("passes/depth_prepass.wgsl"),
        ShaderDesc::new("passes/surface_motion.wgsl"),
        ShaderDesc::new("passes/gbuffer_raster.wgsl"),
        ShaderDesc::new("particles/motion.wgsl"),
        ShaderDesc::new("particles/splat.wgsl"),
        ShaderDesc::new("particles/lights.wgsl"),
        ShaderDesc::new("rays/trace_probe.wgsl"),
        ShaderDesc::new("shading/light_tree_probe.wgsl"),
        ShaderDesc::new("passes/ray_shadows.wgsl").with("RAY_TRACE", "rays/trace.wgsl"),
        ShaderDesc::new("passes/ray_shadows.wgsl").with("RAY_TRACE", "rays/trace_ray_query.wgsl"),
        ShaderDesc::new("rays/hardware_corners.wgsl"),
        ShaderDesc::new("accel/hardware_boxes.wgsl"),
        ShaderDesc::new("passes/shadow_filter.wgsl"),
        ShaderDesc::new("passes/transmission_background.wgsl"),
        ShaderDesc::new("passes/denoise/temporal.wgsl"),
        ShaderDesc::new("passes/denoise/variance.wgsl"),
        ShaderDesc::new("passes/denoise/filter.wgsl"),
        ShaderDesc::new("passes/denoise/compose.wgsl"),
    ];
    // `auto` composes as the method it resolves to.
    for lights in LightMethod::ALL.into_iter().filter(|&m| m != LightMethod::Auto) {
        for decals in DecalMethod::ALL.into_iter().filter(|&m| m != DecalMethod::Auto) {
            // Every particle method (`Bvh` lights with the particles' lights, which subgroups walk
            // together), with and without reflections, every direct-lighting module, with and
            // without subgroup walks, and with sparse and dense decals.
            let directs = [DirectShading::Unshadowed, DirectShading::Budget, DirectShading::Reference, DirectShading::Restir];
            let variants: Vec<_> = ParticleMethod::ALL
                .iter()
                .flat_map(|&p| [false, true].into_iter().flat_map(move |r| directs.map(move |d| (p, r, d))))
                .collect();
            for (particles, reflections, direct) in variants {
                // Dense decals, and their cell lists, change only the BVH's shader.
                let mut densities: Vec<(bool, bool, bool, bool, bool)> = if decals == DecalMethod::Bvh {
                    vec![
                        (false, false, false, false, false),
                        (true, false, false, false, false),
                        (true, true, false, false, false),
                        (true, true, true, false, false),
                    ]
                } else {
                    vec![(false, false, false, false, false), (true, false, false, false, false)]
                };
                // Sparse lights and decals read from cell lists built on the GPU, which particle lights never
                // join; the lights' module meets the decals' only through the core, so two decal
                // methods do, and two light methods for the decals'.
                let listed_lights = lights == LightMethod::Bvh && particles != ParticleMethod::Bvh;
                for subgroups in [false, true] {
                    if listed_lights && matches!(decals, DecalMethod::Off | DecalMethod::Bvh) {
                        densities.push((subgroups, false, false, true, decals == DecalMethod::Bvh));
                    }
                    if decals == DecalMethod::Bvh && matches!(lights, LightMethod::Off | LightMethod::Brute) {
                        densities.push((subgroups, false, false, false, true));
                    }
                }
                for (subgroups, dense_decals, decal_cell_lists, gpu_light_lists, gpu_decal_lists) in densities {
                    let methods = ShadingMethods {
                        lights,
                        decals,
                        particles,
                        reflections,
                        direct,
                        // Forward fragments keeping restir's reservoirs test depth first.
                        keeps_pixel_state: direct == DirectShading::Restir,
                        // A pipeline constant: the same composed shader either way.
                        denoised: direct == DirectShading::Restir,
                        subgroups,
                        dense_decals,
                        // Dense lights walk as a subgroup, as subgroup-walked decals do.
                        dense_lights: subgroups && lights == LightMethod::Bvh,
                        decal_cell_lists,
                        gpu_light_lists,
                        gpu_decal_lists,
                        light_tree: false,
                        hardware_lights: false,
                        hardware_decals: false,
                        hardware_rays: false,
                        debug_views: false,
                        // A pipeline constant: the same composed shader either way.
                        material_extensions: true,
                        vertex_colors: true,
                        occlusion_textures: true,
                        second_uv_set: true,
                        sheen: true,
                        transmission: false,
                    };
                    if decals.works_in(PipelineKind::Forward) {
                        shaders.push(super::forward_shade::shader(methods));
                    }
                    shaders.push(super::blended_shade::shader(methods));
                    // Reflections leave the transmissive pass as it is: one shader for both.
                    if !reflections {
                        shaders.push(super::transmissive_shade::shader(ShadingMethods { transmission: true, ..methods }));
                    }
                    if decals.works_in(PipelineKind::Visbuffer) {
                        shaders.push(super::visbuffer_shade::shader(methods));
                    }
                    shaders.push(super::deferred_shade::shader(methods));
                }
            }
        }
    }
    // `restir` drawing its candidates through the light tree, with every particle method whose
    // lights have one, walked alone and as subgroups.
    for particles in [ParticleMethod::Off, ParticleMethod::Grid] {
        for subgroups in [false, true] {
            let methods = ShadingMethods {
                lights: LightMethod::Bvh,
                decals: DecalMethod::Bvh,
                particles,
                direct: DirectShading::Restir,
                keeps_pixel_state: true,
                denoised: true,
                light_tree: true,
                subgroups,
                ..Default::default()
            };
            shaders.extend(every_shading_pass(methods));
        }
    }
    // The hardware back end's ray queries for `bvh` lights and decals, with every direct-lighting
    // module, with and without reflections and particle grids, and with restir's light tree for the
    // lights (its draws walk the software tree) while decals are queried.
    for direct in [DirectShading::Unshadowed, DirectShading::Budget, DirectShading::Reference, DirectShading::Restir] {
        for (reflections, particles, light_tree) in
            [(false, ParticleMethod::Off, false), (true, ParticleMethod::Grid, false), (true, ParticleMethod::Off, true)]
        {
            let restir = direct == DirectShading::Restir;
            let methods = ShadingMethods {
                lights: LightMethod::Bvh,
                decals: DecalMethod::Bvh,
                particles,
                reflections,
                direct,
                keeps_pixel_state: restir,
                denoised: restir,
                light_tree: light_tree && restir,
                hardware_lights: !(light_tree && restir),
                hardware_decals: true,
                hardware_rays: true,
                subgroups: true,
                ..Default::default()
            };
            shaders.extend(every_shading_pass(methods));
        }
    }
    shaders
}

/// The shaders of every pass that calls the shading core, composed with `methods`.
fn every_shading_pass(methods: ShadingMethods) -> [ShaderDesc; 5] {
    [
        super::forward_shade::shader(methods),
        super::blended_shade::shader(methods),
        super::transmissive_shade::shader(methods),
        super::visbuffer_shade::shader(methods),
        super::deferred_shade::shader(methods),
    ]
}
