//! `manylights info`: what wgpu sees and what manylights would use, and what a scene holds.

use manylights::{
    accel::overlap::{decal_overlap, light_overlap, scene_statistics, Overlap},
    gpu::{context, GpuContext},
    plan::{Capabilities, Measurements, MethodChoice, RayQueries, RayTracer},
    scene::generators::surface_points,
    settings::{PipelineKind, RayBackend, RenderConfig},
};

use crate::progress;
use crate::scene_args::{describe_groups, SceneArgs};

/// Surface points sampled (uniformly by area) for the overlap statistics.
const OVERLAP_SAMPLES: usize = 100_000;

pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    let adapters = context::list_adapters();
    println!("adapters ({}):", adapters.len());
    for a in &adapters {
        let ray_queries = if a.ray_queries { "ray queries" } else { "no ray queries" };
        let status = match &a.usable {
            Ok(()) => format!("usable, {ray_queries}"),
            Err(why) => format!("unusable: {why}"),
        };
        println!("  - {} [{status}]", context::describe(&a.info));
    }
    let ctx = GpuContext::new()?;
    println!("chosen: {}", ctx.describe());
    println!("features used: {:?}", ctx.features);
    if let Some(limit) = ctx.loop_limit {
        println!(
            "  (this driver ends a shader's loops after {limit} iterations in all: brute force and clustered shading over more \
             lights or decals are refused; Mesa 25's lavapipe has no such limit)"
        );
    }
    let caps = Capabilities::of(&ctx);
    let why = match caps.ray_queries {
        RayQueries::Native => "the adapter runs ray queries",
        RayQueries::Emulated => "this CPU adapter emulates ray queries, slower than the software BVHs; --ray-backend hardware uses them",
        RayQueries::None => "the adapter has no ray queries",
    };
    println!("ray backend: auto picks {} ({why})", RayTracer::resolve(RayBackend::Auto, caps)?);
    if !ctx.has_timestamps() {
        println!("  (no timestamp queries: --timings is unavailable on this adapter)");
    }
    println!(
        "limits: max texture 2D {}, array layers {}, storage binding {} MiB, buffer {} MiB",
        ctx.limits.max_texture_dimension_2d,
        ctx.limits.max_texture_array_layers,
        ctx.limits.max_storage_buffer_binding_size / (1 << 20),
        ctx.limits.max_buffer_size / (1 << 20)
    );
    let (scene, overlay) = args.load(Some(&ctx))?;
    println!(
        "scene {}: {} triangles drawn, {} materials, {} textures",
        args.scene,
        scene.drawn_triangle_count(),
        scene.materials.len(),
        scene.textures.len()
    );
    println!("  lights: {} in {}", scene.lights.len(), describe_groups(&scene.light_groups, scene.lights.len()));
    println!("  decals: {} in {}", scene.decals.len(), describe_groups(&scene.decal_groups, scene.decals.len()));
    // What the enumeration's cost per pixel follows: volumes reaching a surface point.
    let step = progress::step("measuring how many lights and decals reach the surfaces");
    let points = surface_points(&scene, OVERLAP_SAMPLES, 1);
    let overlaps = if points.is_empty() { None } else { Some((light_overlap(&scene, &points)?, decal_overlap(&scene, &points)?)) };
    drop(step);
    if let Some((lights, decals)) = overlaps {
        let show = |what: &str, o: Overlap| {
            println!(
                "  {what} reaching a surface point: mean {:.2}, max {} ({:.1} % of points reached by any; {OVERLAP_SAMPLES} points)",
                o.mean,
                o.max,
                o.covered * 100.0
            )
        };
        show("lights", lights);
        show("decals", decals);
    }
    // What `auto` picks with the default settings (and the scene file's), per pipeline.
    let defaults = RenderConfig::default().with_particles(overlay.particles);
    let stats = scene_statistics(&scene, Measurements::for_settings(&defaults, caps))?;
    for pipeline in PipelineKind::ALL {
        let chosen = MethodChoice::resolve(&RenderConfig { pipeline, ..defaults.clone() }, caps, &stats);
        println!("  {} pipeline: lights {}; decals {}", pipeline.name(), chosen.lights, chosen.decals);
    }
    Ok(())
}
