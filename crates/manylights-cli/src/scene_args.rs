//! Scene options shared by `render` and `info`: which scene, what lights it from afar, and what the
//! generators add to it.

use std::path::PathBuf;

use anyhow::bail;
use clap::Args;
use manylights::{
    accel::{check_scene_capacity, VolumeKind},
    files::LoadBudget,
    gpu::GpuContext,
    scene::{
        self,
        generators::{ScatterDecals, ScatterLights, ScatterParticles, DEFAULT_ANIMATION_GROUPS},
        Environment, Groups, Scene,
    },
    settings::{PipelineKind, SettingsOverlay, Sky},
};

use crate::progress;

/// The view the error tools (`particle-error`, `light-error`) compare images in.
#[derive(Args, Clone)]
pub struct ComparedView {
    #[arg(long, default_value_t = 640)]
    pub width: u32,
    #[arg(long, default_value_t = 360)]
    pub height: u32,
    /// The scene's camera to compare from [default: its first, or one framing the scene].
    #[arg(long)]
    pub camera: Option<usize>,
    #[arg(long, value_enum, default_value_t = PipelineKind::Visbuffer)]
    pub pipeline: PipelineKind,
}

#[derive(Args, Clone)]
pub struct SceneArgs {
    /// `demo` (built in), or a .gltf, .glb or .toml scene file.
    #[arg(long, default_value = "demo")]
    pub scene: String,
    /// Scatter this many extra point lights over the scene's surfaces.
    #[arg(long, default_value_t = 0)]
    pub lights: u32,
    /// Scatter this many decals (built-in materials) over the scene's surfaces.
    #[arg(long, default_value_t = 0)]
    pub decals: u32,
    /// Mean edge of the scattered decals, in metres (default: 2.5 % of the scene's diagonal).
    #[arg(long, value_name = "METRES", allow_negative_numbers = true, requires = "decals")]
    pub decal_size: Option<f32>,
    /// Seed of the light and decal scatter and of the animation groups.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Launch this many moving particle lights from emitters on the scene's upward-facing surfaces.
    #[arg(long, default_value_t = 0)]
    pub particles: u32,
    /// Emitters of the particles (with --particles).
    #[arg(long, default_value_t = 16, requires = "particles")]
    pub particle_emitters: usize,
    /// Group the lights and decals into groups that spin about their centres as frames advance.
    #[arg(long)]
    pub animate: bool,
    /// Number of groups with --animate (fewer when there are fewer lights or decals).
    #[arg(long, default_value_t = DEFAULT_ANIMATION_GROUPS, requires = "animate")]
    pub groups: usize,
    /// The daylight sky and its sun, lighting the scene through image-based lighting: where the scene
    /// has no lights of its own, a sun aside, which places and scales the sky (auto), always
    /// (daylight) or never (off: the scene's uniform ambient only). [default: the scene file's, or
    /// auto]
    #[arg(long, value_enum)]
    pub sky: Option<Sky>,
    /// Light the scene from an equirectangular HDR image (.hdr or .exr; centre column −Z, top row +Y)
    /// instead of the sky.
    #[arg(long, value_name = "FILE")]
    pub environment: Option<PathBuf>,
}

impl SceneArgs {
    /// Loads the scene and adds the scattered lights and decals, then groups them with --animate;
    /// returns it with the scene file's settings overlay. With a device, counts it could not render
    /// are refused before they are generated.
    pub fn load(&self, ctx: Option<&GpuContext>) -> anyhow::Result<(Scene, SettingsOverlay)> {
        if let Some(size) = self.decal_size {
            let sizes = scene::generators::SCATTERED_DECAL_SIZES;
            if !sizes.contains(&size) {
                bail!("--decal-size {size}: give the decals' mean edge in metres, from {} to {}", sizes.start(), sizes.end());
            }
        }
        if self.groups == 0 {
            bail!("--groups 0: animation needs at least 1 group");
        }
        let (mut scene, overlay) = {
            let _step = progress::step(format!("loading {}", self.scene));
            if self.scene == "demo" {
                (scene::demo::demo_scene(), SettingsOverlay::default())
            } else {
                scene::load(std::path::Path::new(&self.scene))?
            }
        };
        self.light_with_sky(&mut scene, overlay.sky)?;
        if let Some(ctx) = ctx {
            // One instance slot at least: what the structures need beyond the volumes themselves.
            VolumeKind::Lights.check_capacity(ctx, scene.lights.len() + self.lights as usize, 0, 1)?;
            VolumeKind::Decals.check_capacity(ctx, scene.decals.len() + self.decals as usize, 0, 1)?;
        }
        let _step =
            (self.lights > 0 || self.decals > 0 || self.particles > 0).then(|| progress::step("generating lights, decals and particles"));
        if self.lights > 0 {
            let params = ScatterLights { count: self.lights as usize, seed: self.seed, ..Default::default() };
            scene::generators::add_scattered_lights(&mut scene, &params)?;
        }
        if self.decals > 0 {
            let params = ScatterDecals { count: self.decals as usize, seed: self.seed, size: self.decal_size };
            scene::generators::add_scattered_decals(&mut scene, &params)?;
        }
        if self.particles > 0 {
            if let Some(existing) = &scene.particles {
                bail!(
                    "--particles {}: the scene file already has [particles] ({} particles); change its count there, or drop its [particles] to use --particles",
                    self.particles,
                    existing.count
                );
            }
            let params = ScatterParticles::new(self.particles, self.seed, self.particle_emitters);
            scene::generators::add_particles(&mut scene, &params)?;
        }
        if self.animate {
            scene::generators::group_for_animation(&mut scene, self.groups, self.seed)?;
        }
        if let Some(ctx) = ctx {
            check_scene_capacity(ctx, &scene)?;
        }
        Ok((scene, overlay))
    }

    /// Gives the scene its environment (--environment) and sky (--sky over the scene file's `sky`),
    /// before any light is generated: generated lights do not count as the scene's own.
    fn light_with_sky(&self, scene: &mut Scene, scene_file_sky: Option<Sky>) -> anyhow::Result<()> {
        if let (Some(sky @ (Sky::Daylight | Sky::Off)), Some(path)) = (self.sky, &self.environment) {
            bail!("--sky {sky} with --environment {}: give one, the sky or the environment image", path.display());
        }
        let sky = match &self.environment {
            Some(path) => {
                let budget = LoadBudget::new();
                scene.environment = Some(Environment::load(path, &budget)?);
                // No output may overwrite it.
                scene.source_files.extend(budget.files());
                Sky::Auto
            }
            None => self.sky.or(scene_file_sky).unwrap_or_default(),
        };
        scene::sky::light_with_sky(scene, sky);
        Ok(())
    }
}

/// "N groups, M instances (animated)" for lights or decals.
pub fn describe_groups(groups: &Groups, item_count: usize) -> String {
    let (ranges, instances) = groups.resolve(item_count);
    let motion = if groups.is_animated() { "animated" } else { "still" };
    format!("{} group(s), {} instance(s), {motion}", ranges.len(), instances.len())
}
