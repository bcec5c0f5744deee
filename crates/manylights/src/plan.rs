//! The frame plan: what the renderer builds, resolved from the settings, the device's capabilities
//! and the scene's measured statistics before anything is built. Every choice of shader variant,
//! query walk, leaf size and structure build is made here, in pure functions tested without a GPU.

use crate::settings::{BvhBuild, DebugView, DecalMethod, LightMethod, ParticleMethod, RenderConfig};
use crate::{Error, Result};

/// Where and when a structure's groups get their BVHs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroupBuild {
    /// Once, on the CPU (binned SAH): for groups whose volumes do not change.
    CpuOnce,
    /// Every frame, on the GPU (LBVH): timed as `<label>_blas_build`.
    GpuEveryFrame,
    /// Never: the items in the scene's order with their instances, for methods that read only those,
    /// in any order (brute force, off). Millions of volumes then cost no build at all.
    None,
}

/// How many lights a leaf of the particle lights' group (rebuilt every frame) holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DynamicLeaves {
    /// The most a leaf holds (`accel::MAX_LEAF_SIZE`).
    Widest,
    /// At most this many.
    AtMost(u32),
}

/// The shader variant of the shading core: the methods it is composed with, one per kind of light
/// source and for decals, whether glossy surfaces trace reflections (`shading/reflections.wgsl`) and
/// points trace shadow rays towards lamps (`shading/light_shadows.wgsl`), and how point queries walk.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct ShadingMethods {
    pub lights: LightMethod,
    pub decals: DecalMethod,
    pub particles: ParticleMethod,
    pub reflections: bool,
    /// Shadow rays towards local lights that cast them (`--light-shadow-rays` above 0).
    pub light_shadows: bool,
    /// The device has subgroup operations: passes may walk BVHs a subgroup at a time
    /// (`accel/volume_query_subgroup.wgsl`), where that is faster ([`query_walks`]).
    pub subgroups: bool,
    /// The decals crowd: their centre overlap reaches [`DENSE_DECAL_OVERLAP`], so their CPU-built
    /// groups have wide leaves, and queries walk them a subgroup at a time, sharing each leaf's decals
    /// out among the lanes ([`query_walks`]).
    pub dense_decals: bool,
    /// The decals' structure is one crowded group placed once, with cell lists: `bvh` decals are read
    /// from the list of a point's cell instead of walked (`shading/enumerate/decals_bvh_cells.wgsl`).
    pub decal_cell_lists: bool,
    /// A debug view is shown: the shading core counts its work (`DEBUG_VIEWS` in
    /// `shading/debug_view.wgsl`, a pipeline constant: [`ShadingMethods::debug_views_constant`]).
    pub debug_views: bool,
}

impl ShadingMethods {
    /// The shading core's pipeline constant for its debug views' counters.
    pub fn debug_views_constant(&self) -> (&'static str, f64) {
        ("DEBUG_VIEWS", f64::from(u8::from(self.debug_views)))
    }

    /// The WGSL module that defines `shade_local_lights`.
    pub fn light_enumeration_module(&self) -> &'static str {
        match self.lights {
            LightMethod::Off => "shading/enumerate/lights_off.wgsl",
            LightMethod::Brute => "shading/enumerate/lights_brute.wgsl",
            LightMethod::Bvh => "shading/enumerate/lights_bvh.wgsl",
            LightMethod::Clustered => "shading/enumerate/lights_clustered.wgsl",
        }
    }

    /// The WGSL module that defines `apply_decals`: the decal method's, or, for `bvh` decals with
    /// cell lists where subgroups share them out, the one that reads the lists.
    pub fn decal_enumeration_module(&self) -> &'static str {
        match self.decals {
            DecalMethod::Bvh if self.decal_cell_lists && self.subgroups => "shading/enumerate/decals_bvh_cells.wgsl",
            DecalMethod::Off => "shading/enumerate/decals_off.wgsl",
            DecalMethod::Brute => "shading/enumerate/decals_brute.wgsl",
            DecalMethod::Bvh => "shading/enumerate/decals_bvh.wgsl",
            DecalMethod::Clustered => "shading/enumerate/decals_clustered.wgsl",
            // Already blended into the G-buffer when shading runs.
            DecalMethod::DeferredDecals => "shading/enumerate/decals_off.wgsl",
        }
    }

    /// The WGSL module that defines `shade_particle_lights`.
    pub fn particle_lighting_module(&self) -> &'static str {
        match self.particles {
            ParticleMethod::Off => "shading/enumerate/particles_off.wgsl",
            ParticleMethod::Grid => "shading/enumerate/particles_grid.wgsl",
            // The particles are among the lights: `shade_local_lights` reaches them.
            ParticleMethod::Bvh => "shading/enumerate/particles_off.wgsl",
        }
    }
}

/// The shader stage a pass shades in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingStage {
    Compute,
    Fragment,
}

/// Which structures a pass's point queries walk a subgroup at a time (where the device has subgroup
/// operations). A walk shared by the subgroup loads each node once for all its lanes, but lanes that
/// need nothing wait for it, and each item any lane finds is processed in a round of its own. As
/// measured (benchmarks/LOG.md, topics 3 and 4), it pays for dense lights (particles as exact lights: hundreds reach
/// every point) in every stage, for decals in fragments, whose lanes walking alone diverge most, and
/// for dense decals in compute, whose leaves the lanes then share out, each testing one decal against
/// the box around all their points; not for sparse lights, nor for sparse decals in compute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct QueryWalks {
    pub lights: bool,
    pub decals: bool,
    /// The decals' leaves are shared out among the lanes (`shading/enumerate/decal_leaves_shared_out.wgsl`);
    /// otherwise each lane tests every decal of the leaves it gets (`decal_leaves_each.wgsl`).
    pub decal_leaves_shared_out: bool,
}

/// From how many boxes hold a decal's centre, on average, decals count as dense
/// ([`ShadingMethods::dense_decals`]): sharing leaves out breaks even with walking alone around 20
/// and wins from about 28, while sparse decals shared out are slower in fragments (benchmarks/LOG.md, topic 2).
pub const DENSE_DECAL_OVERLAP: f32 = 24.0;

pub fn query_walks(methods: ShadingMethods, stage: ShadingStage) -> QueryWalks {
    let dense_lights = methods.particles == ParticleMethod::Bvh;
    let dense_decals = methods.subgroups && methods.dense_decals;
    QueryWalks {
        lights: methods.subgroups && dense_lights,
        decals: dense_decals || (methods.subgroups && stage == ShadingStage::Fragment),
        decal_leaves_shared_out: dense_decals,
    }
}

/// A point query module: walked by a whole subgroup, or by each invocation alone.
pub fn volume_query_module(subgroups: bool) -> &'static str {
    if subgroups {
        "accel/volume_query_subgroup.wgsl"
    } else {
        "accel/volume_query_invocation.wgsl"
    }
}

/// The leaves of the particle lights' group, by how its queries walk ([`query_walks`]). Particles
/// crowd, so hundreds reach each lit point, and bigger leaves trade node visits for range tests.
/// Walking alone, an invocation tests every light of a leaf it reaches, so leaves stay small;
/// walking as a subgroup, each lane tests one light of a leaf against the box around all the lanes'
/// points, so a leaf's size costs a few box tests per lane, and the widest leaves are fastest.
pub fn dynamic_leaves(subgroup_walks: bool) -> DynamicLeaves {
    if subgroup_walks {
        DynamicLeaves::Widest
    } else {
        DynamicLeaves::AtMost(16)
    }
}

/// What the plan needs of the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Capabilities {
    /// Subgroup operations (`wgpu::Features::SUBGROUP`).
    pub subgroups: bool,
}

/// What the plan needs of the scene, measured at load ([`Measurements`] says which).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SceneStatistics {
    /// Particles the scene launches (0 without any).
    pub particles: u32,
    /// Instances of non-empty decal groups: the structure's placed groups.
    pub placed_decal_groups: usize,
    /// How many decal boxes of its group hold a decal's centre, on average over a sample of them
    /// (`accel::overlap::centre_overlap`), measured where [`Measurements::decal_centre_overlap`]
    /// asks: `None` where it was not.
    pub decal_centre_overlap: Option<f32>,
}

/// Which statistics the plan reads for these settings, so that nothing else is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Measurements {
    /// The decals' centre overlap: only `bvh` decals built on the CPU for a device whose queries can
    /// share leaves out may get wide leaves.
    pub decal_centre_overlap: bool,
}

impl Measurements {
    pub fn for_settings(config: &RenderConfig, caps: Capabilities) -> Self {
        Self {
            decal_centre_overlap: config.decal_method == DecalMethod::Bvh && config.decal_bvh_build == BvhBuild::CpuOnce && caps.subgroups,
        }
    }
}

/// How one structure (lights or decals) is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StructurePlan {
    pub build: GroupBuild,
    /// The clustered method's per-froxel lists are built every frame.
    pub clustered: bool,
    /// The CPU-built groups get wide leaves, for queries that share each leaf out among a subgroup's
    /// lanes (`accel::Bvh::build_wide`).
    pub wide_leaves: bool,
    /// The one placed group gets cell lists where they fit its budget (`accel/cell_lists.rs`); shading
    /// then reads them instead of walking ([`FramePlan::shading_methods`]).
    pub cell_lists: bool,
}

/// How particles light the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParticlePlan {
    /// No particles, or a method that ignores them.
    None,
    /// Splatted into the grid's 3D textures every frame.
    Grid,
    /// Point lights in a group of the lights' structure rebuilt every frame, with these leaves.
    Lights(DynamicLeaves),
}

/// Everything the renderer builds for a scene, decided before anything is built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FramePlan {
    pub lights: StructurePlan,
    pub decals: StructurePlan,
    pub particles: ParticlePlan,
    /// The frame traces rays: the scene's triangles get a ray hierarchy.
    pub traces_rays: bool,
    /// The shading core's variant, with the decals' cell lists as planned
    /// ([`FramePlan::shading_methods`] gives the one for the lists actually built).
    planned_methods: ShadingMethods,
}

impl FramePlan {
    /// The plan for `config` on a device with `caps`, for a scene with `stats` (measured as
    /// [`Measurements::for_settings`] asks). Errors name settings that cannot work together.
    pub fn resolve(config: &RenderConfig, caps: Capabilities, stats: &SceneStatistics) -> Result<Self> {
        let has_particles = stats.particles > 0;
        let particle_lights = has_particles && config.particle_method == ParticleMethod::Bvh;
        if particle_lights && config.light_method != LightMethod::Bvh {
            return Err(Error::InvalidConfig(format!(
                "--particle-method bvh makes the particles lights in the lights' BVH, which --light-method {} does not read; use --light-method bvh",
                config.light_method.name()
            )));
        }
        let unlisted = ShadingMethods {
            lights: config.light_method,
            decals: config.decal_method,
            particles: config.particle_method,
            reflections: config.rays.reflection_bounces > 0,
            light_shadows: config.rays.light_shadow_rays > 0,
            subgroups: caps.subgroups,
            dense_decals: false,
            decal_cell_lists: false,
            debug_views: config.debug_view != DebugView::Off,
        };
        let lights = StructurePlan {
            build: group_build(
                config.light_method == LightMethod::Bvh,
                config.light_method == LightMethod::Clustered,
                config.light_bvh_build,
            ),
            clustered: config.light_method == LightMethod::Clustered,
            wide_leaves: false,
            cell_lists: false,
        };
        // Decals crowded enough that their queries share leaves out get wide leaves, and, as one
        // group placed once, cell lists.
        let dense_decals = stats.decal_centre_overlap.is_some_and(|overlap| overlap >= DENSE_DECAL_OVERLAP)
            && Measurements::for_settings(config, caps).decal_centre_overlap;
        let decal_build = group_build(
            config.decal_method == DecalMethod::Bvh,
            matches!(config.decal_method, DecalMethod::Clustered | DecalMethod::DeferredDecals),
            config.decal_bvh_build,
        );
        let decals = StructurePlan {
            build: decal_build,
            clustered: config.decal_method == DecalMethod::Clustered,
            wide_leaves: dense_decals,
            cell_lists: dense_decals && stats.placed_decal_groups == 1,
        };
        let particles = match (has_particles, config.particle_method) {
            (false, _) | (true, ParticleMethod::Off) => ParticlePlan::None,
            (true, ParticleMethod::Grid) => ParticlePlan::Grid,
            (true, ParticleMethod::Bvh) => ParticlePlan::Lights(dynamic_leaves(query_walks(unlisted, ShadingStage::Compute).lights)),
        };
        Ok(Self {
            lights,
            decals,
            particles,
            traces_rays: config.rays.traces_rays(),
            planned_methods: ShadingMethods { dense_decals, decal_cell_lists: decals.cell_lists, ..unlisted },
        })
    }

    /// The shading core's variant, once the decals' structure is built: cell lists are read where
    /// they were planned and fitted their budget (`lists_built`); otherwise the wide leaves are walked.
    pub fn shading_methods(&self, lists_built: bool) -> ShadingMethods {
        ShadingMethods { decal_cell_lists: self.planned_methods.decal_cell_lists && lists_built, ..self.planned_methods }
    }
}

/// How a structure's groups are built: as asked where the method walks their BVHs; once on the CPU
/// where it only reads the items in the CPU-built BVH's leaf order, which keeps neighbours together
/// in memory (as `bvh` has them, so the methods compare fairly: clustered lists, deferred decals);
/// not at all for brute force and off.
fn group_build(walks_bvh: bool, reads_items_in_leaf_order: bool, asked: BvhBuild) -> GroupBuild {
    match (walks_bvh, reads_items_in_leaf_order, asked) {
        (true, _, BvhBuild::CpuOnce) => GroupBuild::CpuOnce,
        (true, _, BvhBuild::GpuEveryFrame) => GroupBuild::GpuEveryFrame,
        (false, true, _) => GroupBuild::CpuOnce,
        (false, false, _) => GroupBuild::None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SUBGROUPS: Capabilities = Capabilities { subgroups: true };

    fn config(lights: LightMethod, decals: DecalMethod) -> RenderConfig {
        RenderConfig { light_method: lights, decal_method: decals, ..Default::default() }
    }

    #[test]
    fn builds_follow_the_methods() {
        let stats = SceneStatistics::default();
        let plan = FramePlan::resolve(&config(LightMethod::Brute, DecalMethod::Clustered), SUBGROUPS, &stats).unwrap();
        assert_eq!((plan.lights.build, plan.lights.clustered), (GroupBuild::None, false));
        assert_eq!((plan.decals.build, plan.decals.clustered), (GroupBuild::CpuOnce, true));
        let gpu = RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, ..config(LightMethod::Bvh, DecalMethod::DeferredDecals) };
        let plan = FramePlan::resolve(&gpu, SUBGROUPS, &stats).unwrap();
        assert_eq!((plan.lights.build, plan.decals.build, plan.decals.clustered), (GroupBuild::GpuEveryFrame, GroupBuild::CpuOnce, false));
        // A GPU build asked of a method that reads no BVH is ignored.
        let clustered = RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, ..config(LightMethod::Clustered, DecalMethod::Off) };
        assert_eq!(FramePlan::resolve(&clustered, SUBGROUPS, &stats).unwrap().lights.build, GroupBuild::CpuOnce);
    }

    #[test]
    fn crowded_decals_get_wide_leaves_and_one_placed_group_cell_lists() {
        let bvh = config(LightMethod::Bvh, DecalMethod::Bvh);
        assert!(Measurements::for_settings(&bvh, SUBGROUPS).decal_centre_overlap);
        assert!(!Measurements::for_settings(&bvh, Capabilities { subgroups: false }).decal_centre_overlap);
        let gpu_built = RenderConfig { decal_bvh_build: BvhBuild::GpuEveryFrame, ..bvh.clone() };
        assert!(!Measurements::for_settings(&gpu_built, SUBGROUPS).decal_centre_overlap);
        let stats = |overlap, placed| SceneStatistics { decal_centre_overlap: Some(overlap), placed_decal_groups: placed, particles: 0 };
        let sparse = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_DECAL_OVERLAP - 0.5, 1)).unwrap();
        assert!(!sparse.decals.wide_leaves && !sparse.decals.cell_lists && !sparse.shading_methods(true).dense_decals);
        let dense = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_DECAL_OVERLAP, 1)).unwrap();
        assert!(dense.decals.wide_leaves && dense.decals.cell_lists);
        let methods = dense.shading_methods(true);
        assert!(methods.dense_decals && methods.decal_cell_lists);
        assert_eq!(methods.decal_enumeration_module(), "shading/enumerate/decals_bvh_cells.wgsl");
        // Lists over their budget leave the wide leaves walked.
        assert!(!dense.shading_methods(false).decal_cell_lists && dense.shading_methods(false).dense_decals);
        let instanced = FramePlan::resolve(&bvh, SUBGROUPS, &stats(40.0, 3)).unwrap();
        assert!(instanced.decals.wide_leaves && !instanced.decals.cell_lists);
        // An overlap measured for other settings decides nothing.
        let alone = FramePlan::resolve(&bvh, Capabilities { subgroups: false }, &stats(40.0, 1)).unwrap();
        assert!(!alone.decals.wide_leaves && !alone.shading_methods(true).dense_decals);
    }

    #[test]
    fn particle_lights_need_the_light_bvh_and_get_leaves_for_their_walk() {
        let with_particles = SceneStatistics { particles: 1000, ..Default::default() };
        let exact = RenderConfig { particle_method: ParticleMethod::Bvh, ..config(LightMethod::Bvh, DecalMethod::Off) };
        let plan = FramePlan::resolve(&exact, SUBGROUPS, &with_particles).unwrap();
        assert_eq!(plan.particles, ParticlePlan::Lights(DynamicLeaves::Widest));
        let alone = FramePlan::resolve(&exact, Capabilities { subgroups: false }, &with_particles).unwrap();
        assert_eq!(alone.particles, ParticlePlan::Lights(DynamicLeaves::AtMost(16)));
        let brute = RenderConfig { light_method: LightMethod::Brute, ..exact.clone() };
        let err = FramePlan::resolve(&brute, SUBGROUPS, &with_particles).unwrap_err().to_string();
        assert!(err.contains("--light-method bvh"), "{err}");
        // Without particles nothing is asked of them.
        assert_eq!(FramePlan::resolve(&brute, SUBGROUPS, &SceneStatistics::default()).unwrap().particles, ParticlePlan::None);
        let grid = RenderConfig { particle_method: ParticleMethod::Grid, ..config(LightMethod::Off, DecalMethod::Off) };
        assert_eq!(FramePlan::resolve(&grid, SUBGROUPS, &with_particles).unwrap().particles, ParticlePlan::Grid);
    }

    #[test]
    fn the_shader_key_carries_every_choice() {
        let mut bvh = config(LightMethod::Bvh, DecalMethod::Brute);
        bvh.rays.reflection_bounces = 2;
        bvh.rays.light_shadow_rays = 1;
        bvh.debug_view = DebugView::LightWork;
        let methods = FramePlan::resolve(&bvh, SUBGROUPS, &SceneStatistics::default()).unwrap().shading_methods(true);
        assert!(methods.reflections && methods.light_shadows && methods.debug_views && methods.subgroups);
        assert_eq!(methods.light_enumeration_module(), "shading/enumerate/lights_bvh.wgsl");
        assert_eq!(methods.debug_views_constant(), ("DEBUG_VIEWS", 1.0));
    }
}
