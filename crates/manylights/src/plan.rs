//! The frame plan: what the renderer builds, resolved from the settings, the device's capabilities
//! and the scene's measured statistics before anything is built. Every choice of shader variant,
//! query walk, leaf size and structure build is made here, in pure functions tested without a GPU.

use std::fmt;

use crate::gpu::GpuContext;
use crate::settings::{
    BvhBuild, DebugView, DecalMethod, DirectLighting, LightMethod, Named, ParticleMethod, PipelineKind, RayBackend, RaySettings,
    RenderConfig, RestirCandidates,
};
use crate::{Error, Result};

/// Up to this many lights or decals, `auto` loops over them all unless they are read from cell lists
/// ([`lights_listed`], [`decals_listed`]: one placed group, the software walk, no light tree): a
/// handful of volumes costs a loop less than walking a BVH (6 large decals on the H100 at `862a346`,
/// benchmarks/LOG.md topic 1: 5.532 ms forward against 5.813), but not less than lists. On the H200,
/// 6 large decals read from lists took 5.238 ms forward against the loop's 5.726, and 6 or 8
/// scattered lights or decals 8–18 % less than the loop in fragments, within 1.6 % of it in compute
/// (benchmarks/LOG.md, topic 1).
pub const BRUTE_FORCE_MAX: usize = 8;

/// Whether `bvh` lights rebuilt on the GPU every frame are faster than clustered lists rebuilt every
/// frame (BENCHMARKS.md, "Dense lights" and "Scaling"). Read from cell lists rebuilt in place of
/// their BVH (`listed`, [`lights_listed`]) they are in every pipeline at every overlap
/// measured, and so is an LBVH whose leaves subgroups share out above that overlap. Otherwise (several
/// placed groups, the hardware back end, the light tree) each group gets an LBVH walked from a
/// rebuilt entry grid, which wins from overlap [`DENSE_LIGHT_OVERLAP`] where subgroups share their
/// leaves out, and in compute from overlap [`REBUILT_BVH_OVERLAP`]; sparser, the LBVH's build and its
/// coarser start cost more than its walk saves, and in fragments lights walked alone diverge too much.
pub fn rebuilt_bvh_wins(pipeline: PipelineKind, caps: Capabilities, overlap: f32, listed: bool) -> bool {
    listed || (caps.subgroups && overlap >= DENSE_LIGHT_OVERLAP) || (pipeline != PipelineKind::Forward && overlap >= REBUILT_BVH_OVERLAP)
}

pub const REBUILT_BVH_OVERLAP: f32 = 4.0;

/// Where the one placed group of a structure gets cell lists, which shading reads instead of walking
/// the group's BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GroupLists {
    /// None: the groups' BVHs are walked.
    None,
    /// Built on the CPU beside the group's BVH (`accel/cell_lists.rs`): crowded decals built once,
    /// each cell's list shared out among a subgroup's lanes.
    BesideBvh,
    /// Built on the GPU in place of the group's BVH (`accel/rebuilt_cell_lists.rs`), in cells as
    /// fine as [`ListCells`] says: every frame where the group is rebuilt every frame, else once.
    InPlaceOfBvh(ListCells),
}

/// How fine the cells of lists built on the GPU are (`accel/rebuilt_cell_lists.rs`): the coarsest
/// edge tried, in the volumes' median box edges, finer ones following while lists run long. Finer
/// cells take longer to build (the scans visit every cell) and list fewer volumes that miss a
/// point, which pays where a listed entry costs more to shade: a decal's oriented-box test more
/// than a light's sphere, and anything in fragments more than in compute ([`list_cells`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListCells {
    /// 1.5 edges.
    Coarse,
    /// 1.0 edge.
    Medium,
    /// 0.5 edge.
    Fine,
}

impl ListCells {
    /// The coarsest cell edge tried, in the volumes' median box edges.
    pub fn coarsest_edge(self) -> f32 {
        match self {
            ListCells::Coarse => 1.5,
            ListCells::Medium => 1.0,
            ListCells::Fine => 0.5,
        }
    }
}

/// The cells of the lights' (`decals` false) or the decals' lists built on the GPU, where the
/// opaque surfaces shade in `stage`. On the H200, frames on Sponza, rebuilt every frame, with cells
/// of 1.5 / 1.0 / 0.5 edges against clustered lists (benchmarks/LOG.md, topic 1): 28k small lights
/// in compute 1.243 / 1.260 / 1.312 (0.625) ms against 1.292, in fragments 5.644 / 5.544 / 5.756
/// against 6.310; 4,096 decals in compute 1.319 / 1.301 / 1.317 (0.625) against 1.352, in fragments
/// 7.909 / 6.788 / 6.331 against 7.064.
pub fn list_cells(decals: bool, stage: ShadingStage) -> ListCells {
    match (decals, stage) {
        (false, ShadingStage::Compute) => ListCells::Coarse,
        (true, ShadingStage::Fragment) => ListCells::Fine,
        _ => ListCells::Medium,
    }
}

/// Whether `bvh` lights are read from cell lists built on the GPU in place of their BVH
/// (`accel/rebuilt_cell_lists.rs`), once or every frame as the BVH would be: where nothing else needs
/// the BVH (`bvh_needed`: the hardware back end, which builds its own structures, the light tree,
/// which descends it, particle lights, which join it), as the one group placed, in every pipeline, below the overlap from which subgroups sharing an LBVH's
/// leaves out in compute is faster (BENCHMARKS.md, "Dense lights": forward lights at overlap 10
/// rebuilt every frame take 0.70× clustered lists' time read from cell lists, 1.12× shared out, and
/// 0.87× walked in the BVH built once). Built once, the lists shaded faster than the BVH built once
/// (28k small lights in the visibility buffer: 0.163 against 0.176 ms).
pub fn lights_listed(caps: Capabilities, stats: &SceneStatistics, bvh_needed: bool) -> bool {
    !bvh_needed && stats.placed_light_groups == 1 && !lights_shared_out(caps, PipelineKind::Visbuffer, stats.light_overlap.unwrap_or(0.0))
}

/// Up to this many boxes holding a decal's centre, on average, decals rebuilt every frame as one
/// placed group are read from cell lists rebuilt in place of their BVH rather than shared out from
/// its leaves ([`decals_shared_out`]): on the H200 the decal sweep's 65,536 and 262,144 decals
/// (26 and 102 boxes a centre) took 0.79 and 0.87 times the shared-out LBVH's frame read from lists
/// in the visibility buffer, 0.89 and 0.89 deferred, 0.66 forward (65,536); 1,048,576 (401) 1.05
/// times, their grid too coarse for the bindings (benchmarks/LOG.md, topic 1).
pub const REBUILT_LISTED_DECAL_OVERLAP: f32 = 200.0;

/// Whether `bvh` decals are read from cell lists built on the GPU in place of their BVH
/// (`accel/rebuilt_cell_lists.rs`), once or every frame (`every_frame`) as the BVH would be: but on
/// the hardware back end (`hardware`), as the one group placed; rebuilt every frame, below
/// [`REBUILT_LISTED_DECAL_OVERLAP`] boxes a centre (measured where subgroups could share them out), built once,
/// where they are not dense enough for the lists built beside the BVH ([`decals_shared_out`]: 65,536
/// decals took 20.631 ms forward in those, 23.347 in lists rebuilt every frame). Sparse decals
/// walked in the BVH built once lost to clustered lists in fragments (1.09×, 1.20× and 1.28× at
/// 1,024, 4,096 and 16,384) and shaded slower than in lists in compute (16,384: 0.361 against 0.306
/// ms in the visibility buffer, 0.274 against 0.190 deferred; benchmarks/LOG.md, topic 1).
pub fn decals_listed(caps: Capabilities, stats: &SceneStatistics, every_frame: bool, hardware: bool) -> bool {
    !hardware
        && stats.placed_decal_groups == 1
        && if every_frame {
            stats.decal_centre_overlap.is_none_or(|overlap| overlap < REBUILT_LISTED_DECAL_OVERLAP)
        } else {
            !decals_shared_out(caps, stats.decal_centre_overlap)
        }
}

/// Why `auto` chose a method, or that it was asked for: one line for `info`, `--timings` and the
/// timings JSON.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Why {
    /// The caller named the method.
    Asked,
    /// The scene has none to find.
    NoVolumes,
    /// Few enough for a loop over all of them, where they are not read from cell lists
    /// ([`BRUTE_FORCE_MAX`]).
    Few(usize),
    /// Particles are lit as lights in the lights' BVH, which only `bvh` reads.
    ParticleLights,
    /// Restir's candidates were asked to be drawn through the light tree, which only `bvh` builds.
    LightTree,
    /// Reflections shade points outside the view, which clustered lists do not cover.
    Reflections,
    /// The BVH would be rebuilt on the GPU every frame where clustered lists, rebuilt every frame too,
    /// are faster: sparse lights ([`rebuilt_bvh_wins`]) and decals of several placed groups
    /// (BENCHMARKS.md, "Scaling").
    RebuiltEveryFrame,
    /// Lights or decals of one placed group, below the overlap where subgroups share them out
    /// faster: read from cell lists built in place of their BVH ([`lights_listed`],
    /// [`decals_listed`]).
    Listed { count: usize, overlap: f32 },
    /// Sparse decals of several placed groups, shaded in fragments: walked in their BVHs built
    /// once, they lose to clustered lists ([`decals_listed`]).
    WalkedInFragments,
    /// The mean overlap at surface points, where a BVH is faster: built once at every overlap
    /// measured (up to 100; but for sparse decals of several groups in fragments), or rebuilt every
    /// frame over volumes dense enough that subgroups share their leaves out (`shared_out`: walked so,
    /// [`ShadingMethods::dense_lights`], [`ShadingMethods::dense_decals`]).
    Overlap { count: usize, overlap: f32, shared_out: bool },
}

impl fmt::Display for Why {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Why::Asked => f.write_str("asked for"),
            Why::NoVolumes => f.write_str("none in the scene"),
            Why::Few(n) => write!(f, "{n}, at most {BRUTE_FORCE_MAX}: a loop over all is cheapest"),
            Why::ParticleLights => f.write_str("particles are lights in the lights' BVH, which only bvh reads"),
            Why::LightTree => f.write_str("restir's candidates are drawn through the light tree, which only bvh builds"),
            Why::Reflections => f.write_str("reflections shade points outside the view, where clustered lists do not reach"),
            Why::RebuiltEveryFrame => f.write_str("rebuilt every frame over sparse volumes, where clustered lists are faster than a BVH"),
            Why::Listed { count, overlap } => write!(
                f,
                "{count} reaching {overlap:.2} a surface point on average, as one group: cell lists in place of its BVH are faster"
            ),
            Why::WalkedInFragments => {
                f.write_str("sparse, in several groups, shaded in fragments, where clustered lists are faster than a BVH walk")
            }
            Why::Overlap { count, overlap, shared_out: true } => {
                write!(f, "{count} reaching {overlap:.2} a surface point on average: a BVH walk, its leaves shared out, is faster")
            }
            Why::Overlap { count, overlap, shared_out: false } => {
                write!(f, "{count} reaching {overlap:.2} a surface point on average: a BVH walk is faster")
            }
        }
    }
}

/// A method and why it runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chosen<M> {
    pub method: M,
    pub why: Why,
}

impl<M: Named> fmt::Display for Chosen<M> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.why {
            Why::Asked => write!(f, "{} (asked for)", self.method.name()),
            why => write!(f, "{} (auto: {why})", self.method.name()),
        }
    }
}

/// The light and decal methods that run: the ones asked for, or `auto`'s choice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MethodChoice {
    pub lights: Chosen<LightMethod>,
    pub decals: Chosen<DecalMethod>,
}

impl MethodChoice {
    /// Resolves `auto` for `config` on a device with `caps` and a scene with `stats`
    /// ([`Measurements::for_settings`] measures the overlaps it reads).
    pub fn resolve(config: &RenderConfig, caps: Capabilities, stats: &SceneStatistics) -> Self {
        let reflections = config.rays.reflection_bounces > 0;
        let hardware = matches!(RayTracer::resolve(config.rays.backend, caps), Ok(RayTracer::Hardware));
        let lights = match config.light_method {
            LightMethod::Auto => {
                let particle_lights = stats.particles > 0 && config.particle_method == ParticleMethod::Bvh;
                let overlap = stats.light_overlap.unwrap_or(0.0);
                let as_bvh = RenderConfig { light_method: LightMethod::Bvh, ..config.clone() };
                let light_tree = restir_light_tree(&as_bvh, particle_lights, stats.light_overlap).unwrap_or(false);
                let listed = lights_listed(caps, stats, hardware || light_tree || particle_lights);
                let rebuilt_bvh_wins = rebuilt_bvh_wins(config.pipeline, caps, overlap, listed);
                let shared_out = lights_shared_out(caps, config.pipeline, overlap);
                let tree_asked =
                    config.rays.direct_lighting == DirectLighting::Restir && config.rays.restir_candidates == RestirCandidates::Tree;
                let (method, why) = match (particle_lights, stats.placed_lights, stats.light_overlap) {
                    (true, _, _) => (LightMethod::Bvh, Why::ParticleLights),
                    _ if tree_asked => (LightMethod::Bvh, Why::LightTree),
                    (false, 0, _) => (LightMethod::Off, Why::NoVolumes),
                    (false, n, _) if n <= BRUTE_FORCE_MAX && !listed => (LightMethod::Brute, Why::Few(n)),
                    _ if reflections => (LightMethod::Bvh, Why::Reflections),
                    _ if config.light_bvh_build == BvhBuild::GpuEveryFrame && !rebuilt_bvh_wins => {
                        (LightMethod::Clustered, Why::RebuiltEveryFrame)
                    }
                    (false, count, _) if listed => (LightMethod::Bvh, Why::Listed { count, overlap }),
                    (false, count, _) => (LightMethod::Bvh, Why::Overlap { count, overlap, shared_out }),
                };
                Chosen { method, why }
            }
            method => Chosen { method, why: Why::Asked },
        };
        let decals = match config.decal_method {
            DecalMethod::Auto => {
                // Decals as one placed group read from cell lists beat clustered lists at every
                // overlap of the sweeps, and so do denser ones shared out; sparser decals of several
                // groups, each walked alone, lose or come level where rebuilt every frame, and lose
                // in fragments.
                let every_frame = config.decal_bvh_build == BvhBuild::GpuEveryFrame;
                let listed = decals_listed(caps, stats, every_frame, hardware);
                let shared_out = decals_shared_out(caps, stats.decal_centre_overlap) && !listed;
                let walked = !listed && !shared_out;
                let (method, why) = match (stats.placed_decals, stats.decal_overlap) {
                    (0, _) => (DecalMethod::Off, Why::NoVolumes),
                    (n, _) if n <= BRUTE_FORCE_MAX && !listed => (DecalMethod::Brute, Why::Few(n)),
                    _ if reflections => (DecalMethod::Bvh, Why::Reflections),
                    _ if walked && every_frame => (DecalMethod::Clustered, Why::RebuiltEveryFrame),
                    _ if walked && !hardware && config.pipeline == PipelineKind::Forward => {
                        (DecalMethod::Clustered, Why::WalkedInFragments)
                    }
                    (count, overlap) if listed => (DecalMethod::Bvh, Why::Listed { count, overlap: overlap.unwrap_or(0.0) }),
                    (count, overlap) => (DecalMethod::Bvh, Why::Overlap { count, overlap: overlap.unwrap_or(0.0), shared_out }),
                };
                Chosen { method, why }
            }
            method => Chosen { method, why: Why::Asked },
        };
        Self { lights, decals }
    }

    /// `config` with the chosen methods in place of `auto`.
    pub fn apply(&self, config: &RenderConfig) -> RenderConfig {
        RenderConfig { light_method: self.lights.method, decal_method: self.decals.method, ..config.clone() }
    }
}

/// What traces a frame's point queries and rays: `settings::RayBackend` resolved for the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayTracer {
    /// The GPU's ray queries through acceleration structures wgpu builds (`accel/hardware.rs`).
    Hardware,
    /// manylights' own BVHs walked in WGSL.
    Software,
}

impl RayTracer {
    /// The tracer `backend` asks for on a device with `caps`: `auto` takes ray queries where the
    /// GPU runs them, not where a CPU emulates them (lavapipe: 1.3× to 230× slower than the software
    /// BVHs, BENCHMARKS.md, "Ray back ends"); `hardware` without them is an error naming the fix.
    pub fn resolve(backend: RayBackend, caps: Capabilities) -> Result<Self> {
        match (backend, caps.ray_queries) {
            (RayBackend::Auto, RayQueries::Native) => Ok(Self::Hardware),
            (RayBackend::Hardware, RayQueries::Native | RayQueries::Emulated) => Ok(Self::Hardware),
            (RayBackend::Hardware, RayQueries::None) => Err(Error::InvalidConfig(
                "--ray-backend hardware needs ray queries (Vulkan's VK_KHR_ray_query and VK_KHR_acceleration_structure), which this \
                 adapter lacks; use --ray-backend software or auto (`manylights info` says which adapters have them)"
                    .into(),
            )),
            (RayBackend::Auto | RayBackend::Software, _) => Ok(Self::Software),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Hardware => "hardware",
            Self::Software => "software",
        }
    }
}

impl fmt::Display for RayTracer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

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

/// How the shading core's light loops light a point with each light they find (`$DIRECT_LIGHTING`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DirectShading {
    /// `exact` without shadow rays: every light lights the point.
    #[default]
    Unshadowed,
    /// `exact` with shadow rays towards lights that cast them, within `--light-shadow-rays`.
    Budget,
    /// A shadow ray towards every light.
    Reference,
    /// Resampled importance sampling, a shadow ray per sample.
    Restir,
}

impl DirectShading {
    /// How `rays` ask local lights to be shaded.
    pub fn of(rays: &RaySettings) -> Self {
        match rays.direct_lighting {
            DirectLighting::Exact if rays.light_shadow_rays > 0 => Self::Budget,
            DirectLighting::Exact => Self::Unshadowed,
            DirectLighting::Reference => Self::Reference,
            DirectLighting::Restir => Self::Restir,
        }
    }

    /// The shading core's module for it (`shading/direct/`).
    pub fn module(self) -> &'static str {
        match self {
            Self::Unshadowed => "shading/direct/unshadowed.wgsl",
            Self::Budget => "shading/direct/budget.wgsl",
            Self::Reference => "shading/direct/reference.wgsl",
            Self::Restir => "shading/direct/restir.wgsl",
        }
    }
}

/// The shader variant of the shading core: the methods it is composed with, one per kind of light
/// source and for decals, whether glossy surfaces trace reflections (`shading/reflections.wgsl`), how
/// local lights are shadowed or sampled (`shading/direct/`), and how point queries walk.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct ShadingMethods {
    pub lights: LightMethod,
    pub decals: DecalMethod,
    pub particles: ParticleMethod,
    pub reflections: bool,
    /// How each light found lights the point: unshadowed, shadowed within a budget, each with its
    /// shadow ray, or sampled.
    pub direct: DirectShading,
    /// The opaque surfaces' shading writes per-pixel state (`restir`'s reservoirs,
    /// [`FramePlan::keeps_reservoirs`]; the denoiser's samples, [`FramePlan::denoises`]): fragment
    /// shaders then test depth before they run, so hidden fragments write nothing.
    pub keeps_pixel_state: bool,
    /// `restir`'s lighting at pixels' opaque surfaces goes to the denoiser's samples rather than into
    /// the radiance (`DENOISED_LIGHTING` in `shading/shading_pixel.wgsl`, a pipeline constant:
    /// [`ShadingMethods::denoised_constant`]).
    pub denoised: bool,
    /// The device has subgroup operations: passes may walk BVHs a subgroup at a time
    /// (`accel/volume_query_subgroup.wgsl`), where that is faster ([`query_walks`]).
    pub subgroups: bool,
    /// The decals crowd: their centre overlap reaches [`DENSE_DECAL_OVERLAP`], so their CPU-built
    /// groups have wide leaves, and queries walk them a subgroup at a time, sharing each leaf's decals
    /// out among the lanes ([`query_walks`]).
    pub dense_decals: bool,
    /// The lights crowd: their mean overlap at surface points reaches [`DENSE_LIGHT_OVERLAP`], so
    /// their groups get wide leaves and queries walk them a subgroup at a time, sharing each leaf's
    /// lights out among the lanes, as for particle lights ([`query_walks`]).
    pub dense_lights: bool,
    /// The decals' structure is one crowded group placed once, with cell lists: `bvh` decals are read
    /// from the list of a point's cell instead of walked (`shading/enumerate/decals_bvh_cells.wgsl`).
    pub decal_cell_lists: bool,
    /// The lights' or the decals' structure is one sparser group placed once, built on the GPU (once
    /// or every frame) as cell lists: `bvh` lights or decals are read from the list of a point's cell
    /// (`shading/enumerate/lights_cells.wgsl`, `decals_cells.wgsl`).
    pub gpu_light_lists: bool,
    pub gpu_decal_lists: bool,
    /// `restir` draws its candidates through the light tree instead of enumerating the lights
    /// reaching a point (`shading/enumerate/lights_tree.wgsl`, [`restir_light_tree`]).
    pub light_tree: bool,
    /// `bvh` lights and decals are queried through the GPU's ray queries
    /// (`shading/enumerate/*_ray_query.wgsl`, [`StructurePlan::hardware`]) rather than walked.
    pub hardware_lights: bool,
    pub hardware_decals: bool,
    /// Rays are traced through the GPU's ray queries (`rays/trace_ray_query.wgsl`, `rays/hardware.rs`)
    /// rather than the software hierarchy.
    pub hardware_rays: bool,
    /// A debug view is shown: the shading core counts its work (`DEBUG_VIEWS` in
    /// `shading/debug_view.wgsl`, a pipeline constant: [`ShadingMethods::debug_views_constant`]).
    pub debug_views: bool,
    /// Some material needs the core's extended material path (`MATERIAL_EXTENSIONS` in
    /// `shading/shading_input.wgsl`, a pipeline constant: [`ShadingMethods::material_constants`]);
    /// without, the shading passes compile only glTF's core material.
    pub material_extensions: bool,
    /// Some mesh has vertex colours (`VERTEX_COLORS` in `shading/material.wgsl`, a pipeline
    /// constant: [`ShadingMethods::material_constants`]); without, the shading passes do not
    /// apply them.
    pub vertex_colors: bool,
    /// Some material has an occlusion texture (`OCCLUSION_TEXTURES` in `shading/material.wgsl`, a
    /// pipeline constant: [`ShadingMethods::material_constants`]); without, the shading passes do
    /// not sample one.
    pub occlusion_textures: bool,
    /// Some texture reads the second set of coordinates (`SECOND_UV_SET` in
    /// `shading/material.wgsl`, a pipeline constant: [`ShadingMethods::material_constants`]);
    /// without, the shading passes never choose it.
    pub second_uv_set: bool,
    /// Some material lets light through (`KHR_materials_transmission`): the transmissive and
    /// transparent passes read the light behind its surfaces from a mip chain of the opaque image
    /// (`passes/transmission_background.rs`, `shading/transmitted_screen.wgsl`).
    pub transmission: bool,
    /// Some material has a sheen (`SHEEN` in `shading/shading_input.wgsl`, a pipeline constant:
    /// [`ShadingMethods::material_constants`]); without, the shading passes leave its layer out.
    pub sheen: bool,
}

impl ShadingMethods {
    /// The pipeline constants of every pass that evaluates materials: the extensions' path, vertex
    /// colours, occlusion textures, the second set of coordinates and sheen, each compiled in only
    /// where the scene has it.
    pub fn material_constants(&self) -> [(&'static str, f64); 5] {
        let flag = |on: bool| f64::from(u8::from(on));
        [
            ("MATERIAL_EXTENSIONS", flag(self.material_extensions)),
            ("VERTEX_COLORS", flag(self.vertex_colors)),
            ("OCCLUSION_TEXTURES", flag(self.occlusion_textures)),
            ("SECOND_UV_SET", flag(self.second_uv_set)),
            ("SHEEN", flag(self.sheen)),
        ]
    }

    /// The shading core's pipeline constant for its debug views' counters.
    pub fn debug_views_constant(&self) -> (&'static str, f64) {
        ("DEBUG_VIEWS", f64::from(u8::from(self.debug_views)))
    }

    /// The shading core's pipeline constant for where `restir`'s lighting goes.
    pub fn denoised_constant(&self) -> (&'static str, f64) {
        ("DENOISED_LIGHTING", f64::from(u8::from(self.denoised)))
    }

    /// The WGSL module that defines `shade_local_lights`.
    pub fn light_enumeration_module(&self) -> &'static str {
        match self.lights {
            LightMethod::Off => "shading/enumerate/lights_off.wgsl",
            LightMethod::Brute => "shading/enumerate/lights_brute.wgsl",
            LightMethod::Bvh if self.light_tree => "shading/enumerate/lights_tree.wgsl",
            LightMethod::Bvh if self.hardware_lights => "shading/enumerate/lights_ray_query.wgsl",
            LightMethod::Bvh if self.gpu_light_lists => "shading/enumerate/lights_cells.wgsl",
            // `auto` is resolved before a plan is made (`MethodChoice`).
            LightMethod::Bvh | LightMethod::Auto => "shading/enumerate/lights_bvh.wgsl",
            LightMethod::Clustered => "shading/enumerate/lights_clustered.wgsl",
        }
    }

    /// The WGSL module that defines `apply_decals`: the decal method's, or, for `bvh` decals with
    /// cell lists where subgroups share them out, the one that reads the lists.
    pub fn decal_enumeration_module(&self) -> &'static str {
        match self.decals {
            DecalMethod::Bvh if self.hardware_decals => "shading/enumerate/decals_ray_query.wgsl",
            DecalMethod::Bvh if self.gpu_decal_lists => "shading/enumerate/decals_cells.wgsl",
            DecalMethod::Bvh if self.decal_cell_lists && self.subgroups => "shading/enumerate/decals_bvh_cells.wgsl",
            DecalMethod::Off => "shading/enumerate/decals_off.wgsl",
            DecalMethod::Brute => "shading/enumerate/decals_brute.wgsl",
            DecalMethod::Bvh | DecalMethod::Auto => "shading/enumerate/decals_bvh.wgsl",
            DecalMethod::Clustered => "shading/enumerate/decals_clustered.wgsl",
            // Already blended into the G-buffer when shading runs.
            DecalMethod::DeferredDecals => "shading/enumerate/decals_off.wgsl",
        }
    }

    /// The WGSL module that defines `trace_any_hit`, `trace_closest` and `ray_occluded`.
    pub fn ray_trace_module(&self) -> &'static str {
        if self.hardware_rays {
            "rays/trace_ray_query.wgsl"
        } else {
            "rays/trace.wgsl"
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

/// From how many lights reach a surface point, on average, `bvh` lights count as dense
/// ([`ShadingMethods::dense_lights`]) in the compute pipelines: sharing wide leaves out wins at
/// overlap 100, breaks even at 10 and loses there rebuilt every frame, so the walk changes between
/// the two (benchmarks/LOG.md, topic 1).
pub const DENSE_LIGHT_OVERLAP: f32 = 16.0;
/// The same in the forward pipeline, whose lanes walking alone diverge more: sharing out wins at
/// overlap 10 (built once 0.94× walking alone, rebuilt every frame 0.79×) and loses at 0.45 (1.15×,
/// 1.24×); 8 leaves room for the sampled overlap's error (`accel::overlap`, within 10 %).
pub const DENSE_FRAGMENT_LIGHT_OVERLAP: f32 = 8.0;

/// Whether `bvh` lights reaching `overlap` of them a surface point are dense in `pipeline`: walked a
/// subgroup at a time, their leaves shared out.
pub fn lights_shared_out(caps: Capabilities, pipeline: PipelineKind, overlap: f32) -> bool {
    let dense = if pipeline == PipelineKind::Forward { DENSE_FRAGMENT_LIGHT_OVERLAP } else { DENSE_LIGHT_OVERLAP };
    caps.subgroups && overlap >= dense
}

/// Whether decals whose centres `centre_overlap` of their boxes hold, on average, are dense: walked a
/// subgroup at a time, their leaves shared out.
pub fn decals_shared_out(caps: Capabilities, centre_overlap: Option<f32>) -> bool {
    caps.subgroups && centre_overlap.is_some_and(|overlap| overlap >= DENSE_DECAL_OVERLAP)
}

/// The leaves of groups rebuilt on the GPU every frame, by how queries walk them: a walk alone tests
/// every item of a leaf it reaches, and leaves of 8 about halved dense lights' frames against
/// single-item leaves; walks sharing leaves out test one item a lane, and leaves of 32 were fastest
/// (benchmarks/LOG.md, topic 1).
pub fn rebuilt_leaves(shared_walks: bool) -> DynamicLeaves {
    if shared_walks {
        DynamicLeaves::AtMost(32)
    } else {
        DynamicLeaves::AtMost(8)
    }
}

pub fn query_walks(methods: ShadingMethods, stage: ShadingStage) -> QueryWalks {
    let dense_lights = methods.particles == ParticleMethod::Bvh || methods.dense_lights;
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
    /// Fragment shaders may test depth before they run (`wgpu::Features::SHADER_EARLY_DEPTH_TEST`).
    pub early_depth_test: bool,
    /// Ray queries through acceleration structures wgpu builds (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`).
    pub ray_queries: RayQueries,
}

/// Whether a device traces ray queries, and where.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RayQueries {
    #[default]
    None,
    /// A CPU adapter (Mesa's lavapipe) emulates them: right, but slower than the software BVHs.
    Emulated,
    /// The GPU runs them.
    Native,
}

impl Capabilities {
    /// The capabilities of `ctx`'s device.
    pub fn of(ctx: &GpuContext) -> Self {
        Self {
            subgroups: ctx.features.contains(wgpu::Features::SUBGROUP),
            early_depth_test: ctx.features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST),
            ray_queries: match (ctx.has_ray_queries(), ctx.info.device_type) {
                (false, _) => RayQueries::None,
                (true, wgpu::DeviceType::Cpu) => RayQueries::Emulated,
                (true, _) => RayQueries::Native,
            },
        }
    }
}

/// What the plan needs of the scene, measured at load ([`Measurements`] says which).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct SceneStatistics {
    /// Particles the scene launches (0 without any).
    pub particles: u32,
    /// Lights and decals as placed: each group's items once per instance of it.
    pub placed_lights: usize,
    pub placed_decals: usize,
    /// How many lights or decals reach a point of the surfaces, on average, estimated from a sample
    /// of both (`accel::overlap::sampled_overlap`), where [`Measurements`] asks: `None` where not.
    pub light_overlap: Option<f32>,
    pub decal_overlap: Option<f32>,
    /// Instances of non-empty light and decal groups: the structures' placed groups.
    pub placed_light_groups: usize,
    pub placed_decal_groups: usize,
    /// How many decal boxes of its group hold a decal's centre, on average over a sample of them
    /// (`accel::overlap::centre_overlap`), measured where [`Measurements::decal_centre_overlap`]
    /// asks: `None` where it was not.
    pub decal_centre_overlap: Option<f32>,
    /// Surfaces move: the scene's animation moves instances of its meshes, or meshes deform.
    pub animated_instances: bool,
    /// Some material uses an extension the shading core evaluates beyond glTF's core material
    /// (its own index of refraction or specular, a clear coat, transmission, unlit; sheen has its
    /// own constant).
    pub material_extensions: bool,
    /// Some vertex has a colour other than white.
    pub vertex_colors: bool,
    /// Some material has an occlusion texture.
    pub occlusion_textures: bool,
    /// Some material's texture reads `TEXCOORD_1`.
    pub second_uv_set: bool,
    /// Some material lets light through.
    pub transmission: bool,
    /// Some material has a sheen.
    pub sheen: bool,
}

/// Which statistics the plan reads for these settings, so that nothing else is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Measurements {
    /// The decals' centre overlap: only `bvh` decals (asked for, or maybe `auto`'s) on a device whose
    /// queries can share leaves out may be walked so, with wide leaves where built on the CPU and
    /// leaves of 32 where rebuilt on the GPU.
    pub decal_centre_overlap: bool,
    /// The overlaps at surface points, which `auto` reads, and `bvh` lights for their walks.
    pub light_overlap: bool,
    pub decal_overlap: bool,
}

impl Measurements {
    pub fn for_settings(config: &RenderConfig, caps: Capabilities) -> Self {
        Self {
            decal_centre_overlap: matches!(config.decal_method, DecalMethod::Bvh | DecalMethod::Auto) && caps.subgroups,
            light_overlap: matches!(config.light_method, LightMethod::Auto | LightMethod::Bvh),
            decal_overlap: config.decal_method == DecalMethod::Auto,
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
    /// The leaves of groups rebuilt on the GPU every frame ([`rebuilt_leaves`]).
    pub rebuilt_leaves: DynamicLeaves,
    /// Groups rebuilt on the GPU every frame get entry grids (`accel/rebuilt_grid.rs`), rebuilt after
    /// them: where the opaque surfaces' queries walk alone, the only walks that start at a grid's
    /// cells in an LBVH.
    pub rebuilt_grids: bool,
    /// The one placed group gets cell lists where they fit their budget, and shading then reads them
    /// instead of walking ([`FramePlan::shading_methods`]).
    pub cell_lists: GroupLists,
    /// The light groups get their light tree (`accel/light_tree.rs`), with their CPU builds or
    /// alongside their GPU rebuilds: `restir` draws its candidates through it
    /// ([`ShadingMethods::light_tree`]).
    pub light_tree: bool,
    /// The groups are bottom-level acceleration structures of boxes under a top level over their
    /// instances, which wgpu builds and shading queries with ray queries (`accel/hardware.rs`): once,
    /// or every frame as `build` says. The software BVHs are then not built at all.
    pub hardware: bool,
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
    /// What traces the point queries: the GPU's ray queries, or the software BVHs.
    pub ray_tracer: RayTracer,
    /// The frame traces rays through the GPU's ray queries: the scene's triangles get acceleration
    /// structures wgpu builds (`rays/hardware.rs`) beside the software hierarchy the hits read.
    pub hardware_rays: bool,
    /// `restir` keeps each pixel's reservoir for the next frame to reuse: where its settings ask for
    /// reuse and, in the forward pipeline, where fragment shaders can test depth before they run
    /// (others would let hidden fragments overwrite the visible surface's reservoir).
    pub keeps_reservoirs: bool,
    /// `restir`'s lighting at the pixels' opaque surfaces goes to the denoiser (`passes/denoise/`)
    /// rather than into the image: where its settings ask for it and where pixels' surfaces write their
    /// samples alone (as for [`FramePlan::keeps_reservoirs`]).
    pub denoises: bool,
    /// Each frame records where animated instances' surfaces were a frame before
    /// (`passes/surface_motion.rs`), so that what pixels keep (reservoirs, the denoiser's history)
    /// follows them: where something is kept and instances move.
    pub tracks_surface_motion: bool,
    /// The light and decal methods that run, and why.
    pub methods: MethodChoice,
    /// The shading core's variant, with the decals' cell lists as planned
    /// ([`FramePlan::shading_methods`] gives the one for the lists actually built).
    planned_methods: ShadingMethods,
}

impl FramePlan {
    /// The plan for `config` on a device with `caps`, for a scene with `stats` (measured as
    /// [`Measurements::for_settings`] asks). Errors name settings that cannot work together.
    pub fn resolve(config: &RenderConfig, caps: Capabilities, stats: &SceneStatistics) -> Result<Self> {
        let methods = MethodChoice::resolve(config, caps, stats);
        let config = &methods.apply(config);
        let has_particles = stats.particles > 0;
        let particle_lights = has_particles && config.particle_method == ParticleMethod::Bvh;
        if particle_lights && config.light_method != LightMethod::Bvh {
            return Err(Error::InvalidConfig(format!(
                "--particle-method bvh makes the particles lights in the lights' BVH, which --light-method {} does not read; use --light-method bvh",
                config.light_method.name()
            )));
        }
        let light_tree = restir_light_tree(config, particle_lights, stats.light_overlap)?;
        let ray_tracer = RayTracer::resolve(config.rays.backend, caps)?;
        // Ray queries find the lights a `bvh` enumeration would walk to (particle lights too), and
        // `bvh` decals. The light tree's draws descend the software BVH.
        let hardware = ray_tracer == RayTracer::Hardware;
        let hardware_lights = hardware && config.light_method == LightMethod::Bvh && !light_tree;
        let hardware_decals = hardware && config.decal_method == DecalMethod::Bvh;
        let pixels_write_alone = config.pipeline != PipelineKind::Forward || caps.early_depth_test;
        let keeps_reservoirs = config.rays.keeps_reservoirs() && pixels_write_alone;
        let denoises = config.rays.denoises() && pixels_write_alone;
        let unlisted = ShadingMethods {
            lights: config.light_method,
            decals: config.decal_method,
            particles: config.particle_method,
            reflections: config.rays.reflection_bounces > 0,
            direct: DirectShading::of(&config.rays),
            keeps_pixel_state: keeps_reservoirs || denoises,
            denoised: denoises,
            light_tree,
            hardware_lights,
            hardware_decals,
            hardware_rays: hardware && config.rays.traces_rays(),
            subgroups: caps.subgroups,
            dense_decals: false,
            dense_lights: false,
            decal_cell_lists: false,
            gpu_light_lists: false,
            gpu_decal_lists: false,
            debug_views: config.debug_view != DebugView::Off,
            material_extensions: stats.material_extensions,
            vertex_colors: stats.vertex_colors,
            occlusion_textures: stats.occlusion_textures,
            second_uv_set: stats.second_uv_set,
            transmission: stats.transmission,
            sheen: stats.sheen,
        };
        // Lights and decals crowded enough get wide leaves, walked a subgroup at a time, their leaves
        // shared out; decals, as one group placed once, cell lists too. Groups rebuilt every frame get
        // entry grids where the opaque surfaces' queries walk alone.
        // The light tree draws a leaf's lights one by one: it keeps narrow leaves.
        let dense_lights = config.light_method == LightMethod::Bvh
            && !light_tree
            && !hardware_lights
            && stats.light_overlap.is_some_and(|overlap| lights_shared_out(caps, config.pipeline, overlap));
        let decal_build = group_build(
            config.decal_method == DecalMethod::Bvh,
            matches!(config.decal_method, DecalMethod::Clustered | DecalMethod::DeferredDecals),
            config.decal_bvh_build,
        );
        // Decals as one group placed once get cell lists in place of their BVH, built once or every
        // frame as it would be, up to an overlap; crowded ones built once get lists beside it.
        let decals_in_lists =
            config.decal_method == DecalMethod::Bvh && decals_listed(caps, stats, decal_build == GroupBuild::GpuEveryFrame, hardware);
        let dense_decals = !hardware_decals
            && !decals_in_lists
            && Measurements::for_settings(config, caps).decal_centre_overlap
            && decals_shared_out(caps, stats.decal_centre_overlap);
        let opaque_stage = if config.pipeline == PipelineKind::Forward { ShadingStage::Fragment } else { ShadingStage::Compute };
        let walks = query_walks(ShadingMethods { dense_lights, dense_decals, ..unlisted }, opaque_stage);
        let light_build =
            group_build(config.light_method == LightMethod::Bvh, config.light_method == LightMethod::Clustered, config.light_bvh_build);
        let lights_in_lists =
            config.light_method == LightMethod::Bvh && lights_listed(caps, stats, hardware || light_tree || particle_lights);
        let lights = StructurePlan {
            build: light_build,
            clustered: config.light_method == LightMethod::Clustered,
            wide_leaves: dense_lights,
            rebuilt_leaves: rebuilt_leaves(dense_lights),
            rebuilt_grids: !walks.lights && !hardware_lights,
            cell_lists: if lights_in_lists { GroupLists::InPlaceOfBvh(list_cells(false, opaque_stage)) } else { GroupLists::None },
            light_tree,
            hardware: hardware_lights,
        };
        let decal_lists_beside = stats.placed_decal_groups == 1 && dense_decals && decal_build == GroupBuild::CpuOnce;
        let decals = StructurePlan {
            build: decal_build,
            clustered: config.decal_method == DecalMethod::Clustered,
            wide_leaves: dense_decals,
            rebuilt_leaves: rebuilt_leaves(dense_decals),
            rebuilt_grids: !walks.decals && !hardware_decals,
            cell_lists: match (decals_in_lists, decal_lists_beside) {
                (true, _) => GroupLists::InPlaceOfBvh(list_cells(true, opaque_stage)),
                (false, true) => GroupLists::BesideBvh,
                (false, false) => GroupLists::None,
            },
            light_tree: false,
            hardware: hardware_decals,
        };
        let particles = match (has_particles, config.particle_method) {
            (false, _) | (true, ParticleMethod::Off) => ParticlePlan::None,
            (true, ParticleMethod::Grid) => ParticlePlan::Grid,
            (true, ParticleMethod::Bvh) => {
                let walks = query_walks(ShadingMethods { dense_lights, ..unlisted }, ShadingStage::Compute);
                ParticlePlan::Lights(dynamic_leaves(walks.lights && !light_tree))
            }
        };
        Ok(Self {
            lights,
            decals,
            particles,
            traces_rays: config.rays.traces_rays(),
            ray_tracer,
            hardware_rays: unlisted.hardware_rays,
            keeps_reservoirs,
            denoises,
            tracks_surface_motion: (keeps_reservoirs || denoises) && stats.animated_instances,
            methods,
            planned_methods: ShadingMethods {
                dense_decals,
                dense_lights,
                decal_cell_lists: decal_lists_beside,
                gpu_light_lists: lights_in_lists,
                gpu_decal_lists: decals_in_lists,
                ..unlisted
            },
        })
    }

    /// The shading core's variant, once the structures are built: cell lists are read where they were
    /// planned and fitted their budget (`decal_lists_built`, `light_lists_built`); otherwise the
    /// groups' BVHs are walked.
    pub fn shading_methods(&self, decal_lists_built: bool, light_lists_built: bool) -> ShadingMethods {
        ShadingMethods {
            decal_cell_lists: self.planned_methods.decal_cell_lists && decal_lists_built,
            gpu_light_lists: self.planned_methods.gpu_light_lists && light_lists_built,
            gpu_decal_lists: self.planned_methods.gpu_decal_lists && decal_lists_built,
            ..self.planned_methods
        }
    }
}

/// The mean number of lights reaching a surface point from which `restir`'s `auto` candidates come
/// through the light tree rather than the enumeration: on Sponza the enumeration's shading cost grows
/// with the lights reaching (1.64 ms at 6, 3.21 at 24, 6.03 at 97), the tree's far more slowly (3.25,
/// 4.02, 4.92), so the tree is faster from about 60 — at a higher error (BENCHMARKS.md, "Shadowed
/// local lights").
pub const RESTIR_TREE_OVERLAP: f32 = 64.0;

/// Whether `restir` draws its candidates through the light tree (`accel/light_tree.rs`): where
/// `--restir-candidates tree` asks, or `auto` finds the scene's lights crowding (a mean overlap of
/// [`RESTIR_TREE_OVERLAP`] at surface points) and no particle lights (`particle_lights`) among them:
/// drawn through the tree, 262,144 and 1,048,576 particles' light lay 14–16 times further from the
/// reference than enumerated, and at 262,144 it shaded slower too (BENCHMARKS.md, "Shadowed particle
/// lights"). Every `bvh` light group has the tree: built with the CPU's BVHs, or alongside each GPU
/// rebuild, the particles' too.
pub fn restir_light_tree(config: &RenderConfig, particle_lights: bool, light_overlap: Option<f32>) -> Result<bool> {
    if config.rays.direct_lighting != DirectLighting::Restir {
        return Ok(false);
    }
    let has_tree = config.light_method == LightMethod::Bvh;
    match config.rays.restir_candidates {
        RestirCandidates::Enumeration => Ok(false),
        RestirCandidates::Tree if !has_tree => Err(Error::InvalidConfig(format!(
            "--restir-candidates tree draws lights through their BVH, which --light-method {} does not build; use --light-method bvh (or --restir-candidates enumeration)",
            config.light_method.name()
        ))),
        RestirCandidates::Tree => Ok(true),
        RestirCandidates::Auto => {
            Ok(has_tree && !particle_lights && light_overlap.is_some_and(|overlap| overlap >= RESTIR_TREE_OVERLAP))
        }
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
    use crate::settings::{Denoise, RestirReuse};

    const SUBGROUPS: Capabilities = Capabilities { subgroups: true, early_depth_test: true, ray_queries: RayQueries::None };

    fn config(lights: LightMethod, decals: DecalMethod) -> RenderConfig {
        RenderConfig { light_method: lights, decal_method: decals, ..Default::default() }
    }

    #[test]
    fn the_ray_backend_takes_ray_queries_where_the_device_has_them() {
        let with = Capabilities { ray_queries: RayQueries::Native, ..SUBGROUPS };
        assert_eq!(RayTracer::resolve(RayBackend::Auto, with).unwrap(), RayTracer::Hardware);
        assert_eq!(RayTracer::resolve(RayBackend::Auto, SUBGROUPS).unwrap(), RayTracer::Software);
        // Emulated on the CPU: asked for only.
        let emulated = Capabilities { ray_queries: RayQueries::Emulated, ..SUBGROUPS };
        assert_eq!(RayTracer::resolve(RayBackend::Auto, emulated).unwrap(), RayTracer::Software);
        assert_eq!(RayTracer::resolve(RayBackend::Hardware, emulated).unwrap(), RayTracer::Hardware);
        assert_eq!(RayTracer::resolve(RayBackend::Software, with).unwrap(), RayTracer::Software);
        let refused = RayTracer::resolve(RayBackend::Hardware, SUBGROUPS).unwrap_err().to_string();
        assert!(refused.contains("--ray-backend software"), "{refused}");
        // Hardware `bvh` lights (particle lights too) and decals build no software BVH and are
        // queried by ray queries; the light tree's draws keep the software BVH.
        let bvh = config(LightMethod::Bvh, DecalMethod::Bvh);
        let plan = FramePlan::resolve(&bvh, with, &SceneStatistics::default()).unwrap();
        assert_eq!(plan.ray_tracer, RayTracer::Hardware);
        assert!(plan.lights.hardware && plan.decals.hardware && !plan.lights.rebuilt_grids && !plan.decals.rebuilt_grids);
        let methods = plan.shading_methods(false, false);
        assert_eq!(methods.light_enumeration_module(), "shading/enumerate/lights_ray_query.wgsl");
        assert_eq!(methods.decal_enumeration_module(), "shading/enumerate/decals_ray_query.wgsl");
        let clustered = FramePlan::resolve(&config(LightMethod::Clustered, DecalMethod::Brute), with, &SceneStatistics::default()).unwrap();
        assert!(!clustered.lights.hardware && !clustered.decals.hardware);
        let particles = SceneStatistics { particles: 100, ..Default::default() };
        let exact_particles = RenderConfig { particle_method: ParticleMethod::Bvh, ..bvh.clone() };
        assert!(FramePlan::resolve(&exact_particles, with, &particles).unwrap().lights.hardware);
        let tree = RenderConfig {
            rays: RaySettings { direct_lighting: DirectLighting::Restir, restir_candidates: RestirCandidates::Tree, ..Default::default() },
            ..bvh.clone()
        };
        let plan = FramePlan::resolve(&tree, with, &SceneStatistics::default()).unwrap();
        assert!(!plan.lights.hardware && plan.decals.hardware && plan.shading_methods(false, false).light_tree);
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
        assert!(
            !Measurements::for_settings(&bvh, Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None })
                .decal_centre_overlap
        );
        let gpu_built = RenderConfig { decal_bvh_build: BvhBuild::GpuEveryFrame, ..bvh.clone() };
        assert!(Measurements::for_settings(&gpu_built, SUBGROUPS).decal_centre_overlap);
        let stats =
            |overlap, placed| SceneStatistics { decal_centre_overlap: Some(overlap), placed_decal_groups: placed, ..Default::default() };
        // Sparse decals of one group built once are read from lists built once on the GPU in place of
        // their BVH; of several groups, walked.
        let sparse = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_DECAL_OVERLAP - 0.5, 1)).unwrap();
        assert!(!sparse.decals.wide_leaves && !sparse.shading_methods(true, true).dense_decals);
        assert_eq!(sparse.decals.cell_lists, GroupLists::InPlaceOfBvh(ListCells::Medium));
        assert!(sparse.shading_methods(true, true).gpu_decal_lists && !sparse.shading_methods(false, true).gpu_decal_lists);
        let grouped = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_DECAL_OVERLAP - 0.5, 2)).unwrap();
        assert_eq!(grouped.decals.cell_lists, GroupLists::None);
        let dense = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_DECAL_OVERLAP, 1)).unwrap();
        assert!(dense.decals.wide_leaves && dense.decals.cell_lists == GroupLists::BesideBvh);
        let methods = dense.shading_methods(true, true);
        assert!(methods.dense_decals && methods.decal_cell_lists);
        assert_eq!(methods.decal_enumeration_module(), "shading/enumerate/decals_bvh_cells.wgsl");
        // Lists over their budget leave the wide leaves walked.
        assert!(!dense.shading_methods(false, false).decal_cell_lists && dense.shading_methods(false, false).dense_decals);
        let instanced = FramePlan::resolve(&bvh, SUBGROUPS, &stats(40.0, 3)).unwrap();
        assert!(instanced.decals.wide_leaves && instanced.decals.cell_lists == GroupLists::None);
        // Rebuilt every frame, dense decals of several groups, or as one group crowded past the
        // rebuilt lists' overlap, are shared out from leaves of 32, with no grid.
        for (centre, placed) in [(DENSE_DECAL_OVERLAP, 2), (REBUILT_LISTED_DECAL_OVERLAP, 1)] {
            let rebuilt = FramePlan::resolve(&gpu_built, SUBGROUPS, &stats(centre, placed)).unwrap();
            assert!(rebuilt.shading_methods(true, true).dense_decals && !rebuilt.decals.rebuilt_grids);
            assert_eq!(rebuilt.decals.cell_lists, GroupLists::None);
            assert_eq!(rebuilt.decals.rebuilt_leaves, DynamicLeaves::AtMost(32));
        }
        // Sparser, as one placed group, they are read from cell lists rebuilt in place of their BVH,
        // dense or not.
        for centre in [1.0, DENSE_DECAL_OVERLAP, REBUILT_LISTED_DECAL_OVERLAP - 1.0] {
            let listed = FramePlan::resolve(&gpu_built, SUBGROUPS, &stats(centre, 1)).unwrap();
            let methods = listed.shading_methods(true, true);
            assert!(matches!(listed.decals.cell_lists, GroupLists::InPlaceOfBvh(_)));
            assert!(methods.gpu_decal_lists && !methods.decal_cell_lists && !methods.dense_decals);
            assert_eq!(methods.decal_enumeration_module(), "shading/enumerate/decals_cells.wgsl");
            assert!(!listed.shading_methods(false, true).gpu_decal_lists, "lists that were not built are not read");
        }
        assert_eq!(
            FramePlan::resolve(&gpu_built, SUBGROUPS, &stats(DENSE_DECAL_OVERLAP - 1.0, 2)).unwrap().decals.cell_lists,
            GroupLists::None
        );
        // Their cells, and the lights', are finer where an entry costs more to shade: decals more
        // than lights, fragments more than compute.
        for (pipeline, light_cells, decal_cells) in [
            (PipelineKind::Visbuffer, ListCells::Coarse, ListCells::Medium),
            (PipelineKind::Deferred, ListCells::Coarse, ListCells::Medium),
            (PipelineKind::Forward, ListCells::Medium, ListCells::Fine),
        ] {
            let lights = SceneStatistics { light_overlap: Some(0.5), placed_light_groups: 1, ..stats(1.0, 1) };
            let plan = FramePlan::resolve(&RenderConfig { pipeline, ..gpu_built.clone() }, SUBGROUPS, &lights).unwrap();
            let cells = (GroupLists::InPlaceOfBvh(light_cells), GroupLists::InPlaceOfBvh(decal_cells));
            assert_eq!((plan.lights.cell_lists, plan.decals.cell_lists), cells, "{pipeline:?}");
        }
        assert!(ListCells::Fine.coarsest_edge() < ListCells::Medium.coarsest_edge());
        assert!(ListCells::Medium.coarsest_edge() < ListCells::Coarse.coarsest_edge());
        // And `auto` walks them rather than listing them in clusters.
        let auto_rebuilt = RenderConfig { decal_method: DecalMethod::Auto, ..gpu_built.clone() };
        let placed = |centre, groups| SceneStatistics { placed_decals: 262_144, ..stats(centre, groups) };
        let crowded = MethodChoice::resolve(&auto_rebuilt, SUBGROUPS, &placed(REBUILT_LISTED_DECAL_OVERLAP, 1));
        assert_eq!(crowded.decals.why, Why::Overlap { count: 262_144, overlap: 0.0, shared_out: true });
        assert_eq!(MethodChoice::resolve(&auto_rebuilt, SUBGROUPS, &placed(DENSE_DECAL_OVERLAP, 2)).decals.method, DecalMethod::Bvh);
        // Sparser, as one placed group, it reads them from rebuilt cell lists; of several groups, it
        // takes clustered lists.
        for centre in [DENSE_DECAL_OVERLAP - 1.0, DENSE_DECAL_OVERLAP] {
            let listed = MethodChoice::resolve(&auto_rebuilt, SUBGROUPS, &placed(centre, 1));
            assert_eq!(listed.decals.why, Why::Listed { count: 262_144, overlap: 0.0 });
        }
        let grouped = placed(DENSE_DECAL_OVERLAP - 1.0, 2);
        assert_eq!(MethodChoice::resolve(&auto_rebuilt, SUBGROUPS, &grouped).decals.method, DecalMethod::Clustered);
        // Built once, sparse decals of one group are listed in every pipeline; of several groups,
        // walked in compute, and in fragments left to clustered lists.
        for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
            let auto_once = RenderConfig { decal_method: DecalMethod::Auto, pipeline, ..bvh.clone() };
            let listed = MethodChoice::resolve(&auto_once, SUBGROUPS, &placed(DENSE_DECAL_OVERLAP - 1.0, 1));
            assert_eq!(listed.decals.why, Why::Listed { count: 262_144, overlap: 0.0 });
            let walked = MethodChoice::resolve(&auto_once, SUBGROUPS, &grouped).decals;
            let expected = if pipeline == PipelineKind::Forward {
                (DecalMethod::Clustered, Why::WalkedInFragments)
            } else {
                (DecalMethod::Bvh, Why::Overlap { count: 262_144, overlap: 0.0, shared_out: false })
            };
            assert_eq!((walked.method, walked.why), expected, "{pipeline:?}");
            let dense = MethodChoice::resolve(&auto_once, SUBGROUPS, &placed(DENSE_DECAL_OVERLAP, 2)).decals;
            assert_eq!(dense.why, Why::Overlap { count: 262_144, overlap: 0.0, shared_out: true });
        }
        // An overlap measured for other settings decides nothing.
        let alone = FramePlan::resolve(
            &bvh,
            Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None },
            &stats(40.0, 1),
        )
        .unwrap();
        assert!(!alone.decals.wide_leaves && !alone.shading_methods(true, true).dense_decals);
    }

    #[test]
    fn particle_lights_need_the_light_bvh_and_get_leaves_for_their_walk() {
        let with_particles = SceneStatistics { particles: 1000, ..Default::default() };
        let exact = RenderConfig { particle_method: ParticleMethod::Bvh, ..config(LightMethod::Bvh, DecalMethod::Off) };
        let plan = FramePlan::resolve(&exact, SUBGROUPS, &with_particles).unwrap();
        assert_eq!(plan.particles, ParticlePlan::Lights(DynamicLeaves::Widest));
        let alone = FramePlan::resolve(
            &exact,
            Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None },
            &with_particles,
        )
        .unwrap();
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
    fn crowded_lights_are_walked_by_subgroups_with_wide_leaves() {
        let bvh = config(LightMethod::Bvh, DecalMethod::Off);
        let stats = |overlap| SceneStatistics { placed_lights: 28_000, light_overlap: Some(overlap), ..Default::default() };
        let sparse = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_LIGHT_OVERLAP - 1.0)).unwrap();
        assert!(!sparse.lights.wide_leaves && !sparse.shading_methods(true, true).dense_lights);
        assert_eq!(sparse.lights.rebuilt_leaves, DynamicLeaves::AtMost(8));
        assert!(!query_walks(sparse.shading_methods(true, true), ShadingStage::Fragment).lights);
        let dense = FramePlan::resolve(&bvh, SUBGROUPS, &stats(DENSE_LIGHT_OVERLAP)).unwrap();
        assert!(dense.lights.wide_leaves && dense.shading_methods(true, true).dense_lights);
        assert_eq!(dense.lights.rebuilt_leaves, DynamicLeaves::AtMost(32));
        for stage in [ShadingStage::Compute, ShadingStage::Fragment] {
            assert!(query_walks(dense.shading_methods(true, true), stage).lights);
        }
        // Without subgroups, nothing is shared out: narrow leaves, walked alone.
        let alone = FramePlan::resolve(
            &bvh,
            Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None },
            &stats(100.0),
        )
        .unwrap();
        assert!(!alone.lights.wide_leaves && !alone.shading_methods(true, true).dense_lights);
        // Rebuilt groups get entry grids exactly where their queries walk alone.
        assert!(sparse.lights.rebuilt_grids && alone.lights.rebuilt_grids && !dense.lights.rebuilt_grids);
        // Forward lanes diverge more: lights are shared out from a lower overlap.
        let forward = RenderConfig { pipeline: PipelineKind::Forward, ..bvh.clone() };
        let shared = FramePlan::resolve(&forward, SUBGROUPS, &stats(DENSE_FRAGMENT_LIGHT_OVERLAP)).unwrap();
        assert!(shared.lights.wide_leaves && shared.shading_methods(true, true).dense_lights && !shared.lights.rebuilt_grids);
        let walked_alone = FramePlan::resolve(&forward, SUBGROUPS, &stats(DENSE_FRAGMENT_LIGHT_OVERLAP - 1.0)).unwrap();
        assert!(!walked_alone.shading_methods(true, true).dense_lights);
    }

    #[test]
    fn sparse_lights_of_one_placed_group_are_listed() {
        let rebuilt =
            |pipeline| RenderConfig { pipeline, light_bvh_build: BvhBuild::GpuEveryFrame, ..config(LightMethod::Bvh, DecalMethod::Off) };
        let stats = |overlap, groups| SceneStatistics {
            placed_lights: 28_000,
            light_overlap: Some(overlap),
            placed_light_groups: groups,
            ..Default::default()
        };
        let listed = |config: &RenderConfig, stats: &SceneStatistics| {
            let plan = FramePlan::resolve(config, SUBGROUPS, stats).unwrap();
            let listed = matches!(plan.lights.cell_lists, GroupLists::InPlaceOfBvh(_));
            assert_eq!(listed, plan.shading_methods(false, true).gpu_light_lists);
            assert!(!plan.shading_methods(true, false).gpu_light_lists, "lists that were not built are not read");
            listed
        };
        for pipeline in [PipelineKind::Visbuffer, PipelineKind::Deferred, PipelineKind::Forward] {
            assert!(listed(&rebuilt(pipeline), &stats(0.5, 1)), "{pipeline:?}");
            // Dense lights are walked, their leaves shared out; several placed groups keep their
            // BVHs. Built once, the lists are built once.
            assert!(!listed(&rebuilt(pipeline), &stats(DENSE_LIGHT_OVERLAP, 1)), "{pipeline:?}");
            assert!(!listed(&rebuilt(pipeline), &stats(0.5, 2)), "{pipeline:?}");
            let once = RenderConfig { light_bvh_build: BvhBuild::CpuOnce, ..rebuilt(pipeline) };
            assert!(listed(&once, &stats(0.5, 1)) && !listed(&once, &stats(0.5, 2)) && !listed(&once, &stats(DENSE_LIGHT_OVERLAP, 1)));
            for build in [BvhBuild::CpuOnce, BvhBuild::GpuEveryFrame] {
                let auto = RenderConfig { light_method: LightMethod::Auto, light_bvh_build: build, ..rebuilt(pipeline) };
                assert_eq!(MethodChoice::resolve(&auto, SUBGROUPS, &stats(0.5, 1)).lights.why, Why::Listed { count: 28_000, overlap: 0.5 });
                assert!(listed(&auto, &stats(0.5, 1)));
            }
        }
        // Forward fragments share lights out from a lower overlap when walking; listed, they are not.
        assert!(listed(&rebuilt(PipelineKind::Forward), &stats(DENSE_FRAGMENT_LIGHT_OVERLAP, 1)));
        let no_subgroups = Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None };
        assert!(listed(&rebuilt(PipelineKind::Visbuffer), &stats(DENSE_FRAGMENT_LIGHT_OVERLAP, 1)));
        let plan = FramePlan::resolve(&rebuilt(PipelineKind::Visbuffer), no_subgroups, &stats(100.0, 1)).unwrap();
        assert_eq!(plan.lights.cell_lists, GroupLists::InPlaceOfBvh(ListCells::Coarse));
        let methods = FramePlan::resolve(&rebuilt(PipelineKind::Visbuffer), SUBGROUPS, &stats(0.5, 1)).unwrap().shading_methods(true, true);
        assert_eq!(methods.light_enumeration_module(), "shading/enumerate/lights_cells.wgsl");
        // The hardware back end and the light tree need the group's own structure: no lists, and
        // `auto` then keeps clustered lists for sparse lights rebuilt every frame.
        let auto = RenderConfig { light_method: LightMethod::Auto, ..rebuilt(PipelineKind::Visbuffer) };
        let ray_queries = Capabilities { ray_queries: RayQueries::Native, ..SUBGROUPS };
        assert_eq!(MethodChoice::resolve(&auto, ray_queries, &stats(0.5, 1)).lights.method, LightMethod::Clustered);
        let hardware = FramePlan::resolve(&RenderConfig { light_method: LightMethod::Bvh, ..auto.clone() }, ray_queries, &stats(0.5, 1));
        assert_eq!(hardware.unwrap().lights.cell_lists, GroupLists::None);
        let mut tree = RenderConfig { light_method: LightMethod::Auto, ..rebuilt(PipelineKind::Forward) };
        tree.rays.direct_lighting = DirectLighting::Restir;
        assert_eq!(MethodChoice::resolve(&tree, no_subgroups, &stats(RESTIR_TREE_OVERLAP, 1)).lights.method, LightMethod::Clustered);
        let tree_bvh = RenderConfig { light_method: LightMethod::Bvh, ..tree };
        let plan = FramePlan::resolve(&tree_bvh, no_subgroups, &stats(RESTIR_TREE_OVERLAP, 1)).unwrap();
        assert!(plan.lights.light_tree && plan.lights.cell_lists == GroupLists::None);
        // Particle lights join the lights' structure as a group of their own, rebuilt every frame.
        let particles = SceneStatistics { particles: 1000, ..stats(0.5, 1) };
        assert!(!listed(&RenderConfig { particle_method: ParticleMethod::Bvh, ..rebuilt(PipelineKind::Visbuffer) }, &particles));
    }

    #[test]
    fn rebuilt_decals_get_entry_grids_where_their_queries_walk_alone() {
        let decals = |pipeline| RenderConfig { pipeline, ..config(LightMethod::Off, DecalMethod::Bvh) };
        let stats = SceneStatistics { placed_decals: 1000, placed_decal_groups: 1, ..Default::default() };
        let plan = |pipeline, caps| FramePlan::resolve(&decals(pipeline), caps, &stats).unwrap().decals.rebuilt_grids;
        // Fragments walk decals a subgroup at a time where they can.
        assert!(plan(PipelineKind::Visbuffer, SUBGROUPS) && plan(PipelineKind::Deferred, SUBGROUPS));
        assert!(
            !plan(PipelineKind::Forward, SUBGROUPS)
                && plan(PipelineKind::Forward, Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None })
        );
    }

    #[test]
    fn the_shader_key_carries_every_choice() {
        let mut bvh = config(LightMethod::Bvh, DecalMethod::Brute);
        bvh.rays.reflection_bounces = 2;
        bvh.rays.light_shadow_rays = 1;
        bvh.debug_view = DebugView::LightWork;
        let methods = FramePlan::resolve(&bvh, SUBGROUPS, &SceneStatistics::default()).unwrap().shading_methods(true, true);
        assert!(methods.reflections && methods.direct == DirectShading::Budget && methods.debug_views && methods.subgroups);
        assert_eq!(methods.light_enumeration_module(), "shading/enumerate/lights_bvh.wgsl");
        assert_eq!(methods.debug_views_constant(), ("DEBUG_VIEWS", 1.0));
        assert_eq!(
            methods.material_constants(),
            [("MATERIAL_EXTENSIONS", 0.0), ("VERTEX_COLORS", 0.0), ("OCCLUSION_TEXTURES", 0.0), ("SECOND_UV_SET", 0.0), ("SHEEN", 0.0)]
        );
        let scenes = [
            SceneStatistics { material_extensions: true, ..Default::default() },
            SceneStatistics { vertex_colors: true, ..Default::default() },
            SceneStatistics { occlusion_textures: true, ..Default::default() },
            SceneStatistics { second_uv_set: true, ..Default::default() },
            SceneStatistics { sheen: true, ..Default::default() },
        ];
        for (index, (stats, name)) in
            scenes.iter().zip(["MATERIAL_EXTENSIONS", "VERTEX_COLORS", "OCCLUSION_TEXTURES", "SECOND_UV_SET", "SHEEN"]).enumerate()
        {
            let methods = FramePlan::resolve(&bvh, SUBGROUPS, stats).unwrap().shading_methods(true, true);
            assert_eq!(methods.material_constants()[index], (name, 1.0));
        }
    }

    #[test]
    fn shadowed_direct_lighting_traces_rays() {
        let plan = |direct_lighting, light_shadow_rays| {
            let mut config = config(LightMethod::Bvh, DecalMethod::Off);
            config.rays.direct_lighting = direct_lighting;
            config.rays.light_shadow_rays = light_shadow_rays;
            let plan = FramePlan::resolve(&config, SUBGROUPS, &SceneStatistics::default()).unwrap();
            (plan.shading_methods(true, true).direct, plan.traces_rays)
        };
        assert_eq!(plan(DirectLighting::Exact, 0), (DirectShading::Unshadowed, false));
        assert_eq!(plan(DirectLighting::Exact, 2), (DirectShading::Budget, true));
        // The budget is `exact`'s alone.
        assert_eq!(plan(DirectLighting::Reference, 2), (DirectShading::Reference, true));
        assert_eq!(plan(DirectLighting::Restir, 0), (DirectShading::Restir, true));
    }

    #[test]
    fn restir_keeps_reservoirs_where_it_reuses_them_and_forward_fragments_test_depth_first() {
        let keeps = |pipeline, reuse, caps| {
            let mut config = RenderConfig { pipeline, ..config(LightMethod::Bvh, DecalMethod::Off) };
            config.rays.direct_lighting = DirectLighting::Restir;
            config.rays.restir_reuse = reuse;
            config.rays.denoise = Denoise::Off;
            let plan = FramePlan::resolve(&config, caps, &SceneStatistics::default()).unwrap();
            assert_eq!(plan.keeps_reservoirs, plan.shading_methods(true, true).keeps_pixel_state);
            plan.keeps_reservoirs
        };
        let late = Capabilities { subgroups: true, early_depth_test: false, ray_queries: RayQueries::None };
        assert!(keeps(PipelineKind::Visbuffer, RestirReuse::Spatiotemporal, late));
        assert!(keeps(PipelineKind::Forward, RestirReuse::Temporal, SUBGROUPS));
        assert!(!keeps(PipelineKind::Forward, RestirReuse::Spatiotemporal, late));
        assert!(!keeps(PipelineKind::Deferred, RestirReuse::Off, SUBGROUPS));
    }

    #[test]
    fn restir_is_denoised_where_pixels_write_their_samples_alone() {
        let denoised = |pipeline, direct_lighting, denoise, caps| {
            let mut config = RenderConfig { pipeline, ..config(LightMethod::Bvh, DecalMethod::Off) };
            config.rays.direct_lighting = direct_lighting;
            config.rays.restir_reuse = RestirReuse::Off;
            config.rays.denoise = denoise;
            let plan = FramePlan::resolve(&config, caps, &SceneStatistics::default()).unwrap();
            let methods = plan.shading_methods(true, true);
            assert_eq!((plan.denoises, plan.denoises), (methods.denoised, methods.keeps_pixel_state));
            assert_eq!(methods.denoised_constant(), ("DENOISED_LIGHTING", f64::from(u8::from(plan.denoises))));
            plan.denoises
        };
        let late = Capabilities { subgroups: true, early_depth_test: false, ray_queries: RayQueries::None };
        assert!(denoised(PipelineKind::Visbuffer, DirectLighting::Restir, Denoise::Svgf, late));
        assert!(denoised(PipelineKind::Forward, DirectLighting::Restir, Denoise::Svgf, SUBGROUPS));
        assert!(!denoised(PipelineKind::Forward, DirectLighting::Restir, Denoise::Svgf, late));
        assert!(!denoised(PipelineKind::Deferred, DirectLighting::Restir, Denoise::Off, SUBGROUPS));
        assert!(!denoised(PipelineKind::Visbuffer, DirectLighting::Reference, Denoise::Svgf, SUBGROUPS));
    }

    #[test]
    fn restir_draws_through_the_light_tree_where_asked_or_where_lights_crowd() {
        let tree = |light_method, light_bvh_build, candidates, particle_lights, overlap| {
            let mut config = RenderConfig { light_bvh_build, ..config(light_method, DecalMethod::Off) };
            config.rays.direct_lighting = DirectLighting::Restir;
            config.rays.restir_candidates = candidates;
            restir_light_tree(&config, particle_lights, overlap)
        };
        let (bvh, cpu, gpu) = (LightMethod::Bvh, BvhBuild::CpuOnce, BvhBuild::GpuEveryFrame);
        let crowded = Some(RESTIR_TREE_OVERLAP);
        assert!(tree(bvh, cpu, RestirCandidates::Tree, false, None).unwrap());
        assert!(!tree(bvh, cpu, RestirCandidates::Enumeration, false, Some(1000.0)).unwrap());
        assert!(tree(bvh, cpu, RestirCandidates::Auto, false, crowded).unwrap());
        assert!(!tree(bvh, cpu, RestirCandidates::Auto, false, Some(RESTIR_TREE_OVERLAP - 1.0)).unwrap());
        // Groups rebuilt on the GPU and the particles' have their tree too; auto enumerates particle
        // lights, whose light the tree estimates far worse.
        assert!(tree(bvh, gpu, RestirCandidates::Auto, false, crowded).unwrap());
        assert!(tree(bvh, gpu, RestirCandidates::Tree, true, None).unwrap());
        assert!(!tree(bvh, cpu, RestirCandidates::Auto, true, Some(1000.0)).unwrap());
        // Without a BVH, auto enumerates and tree is refused with the flag that gives one.
        assert!(!tree(LightMethod::Clustered, cpu, RestirCandidates::Auto, false, Some(1000.0)).unwrap());
        let message = tree(LightMethod::Clustered, cpu, RestirCandidates::Tree, false, None).unwrap_err().to_string();
        assert!(message.contains("--light-method bvh"), "{message}");
        // Other direct lighting never draws.
        let mut exact = config(LightMethod::Bvh, DecalMethod::Off);
        exact.rays.restir_candidates = RestirCandidates::Tree;
        assert!(!restir_light_tree(&exact, false, None).unwrap());
        // The plan keeps the tree's leaves narrow, and composes the tree's module.
        let mut crowded = config(LightMethod::Bvh, DecalMethod::Off);
        crowded.rays.direct_lighting = DirectLighting::Restir;
        let stats = SceneStatistics { placed_lights: 65_536, light_overlap: Some(100.0), ..Default::default() };
        let plan = FramePlan::resolve(&crowded, SUBGROUPS, &stats).unwrap();
        assert!(plan.lights.light_tree && !plan.lights.wide_leaves);
        assert_eq!(plan.shading_methods(true, true).light_enumeration_module(), "shading/enumerate/lights_tree.wgsl");
    }

    #[test]
    fn surface_motion_is_tracked_where_pixels_keep_state_and_instances_move() {
        let tracks = |reuse, denoise, animated_instances| {
            let mut config = config(LightMethod::Bvh, DecalMethod::Off);
            config.rays.direct_lighting = DirectLighting::Restir;
            (config.rays.restir_reuse, config.rays.denoise) = (reuse, denoise);
            let stats = SceneStatistics { animated_instances, ..Default::default() };
            FramePlan::resolve(&config, SUBGROUPS, &stats).unwrap().tracks_surface_motion
        };
        assert!(tracks(RestirReuse::Temporal, Denoise::Off, true));
        assert!(tracks(RestirReuse::Off, Denoise::Svgf, true));
        assert!(!tracks(RestirReuse::Temporal, Denoise::Svgf, false));
        assert!(!tracks(RestirReuse::Off, Denoise::Off, true));
    }

    fn scene(lights: usize, light_overlap: f32, decals: usize, decal_overlap: f32) -> SceneStatistics {
        SceneStatistics {
            placed_lights: lights,
            placed_decals: decals,
            placed_light_groups: usize::from(lights > 0),
            placed_decal_groups: usize::from(decals > 0),
            light_overlap: Some(light_overlap),
            decal_overlap: Some(decal_overlap),
            ..Default::default()
        }
    }

    fn auto() -> RenderConfig {
        RenderConfig::default()
    }

    #[test]
    fn auto_is_the_default_and_picks_by_count_and_overlap() {
        assert_eq!((auto().light_method, auto().decal_method), (LightMethod::Auto, DecalMethod::Auto));
        let chosen = |config: &RenderConfig, stats| {
            let c = MethodChoice::resolve(config, SUBGROUPS, &stats);
            (c.lights.method, c.decals.method)
        };
        assert_eq!(chosen(&auto(), scene(0, 0.0, 0, 0.0)), (LightMethod::Off, DecalMethod::Off));
        // A handful is looped over in several groups, or with the hardware back end; read from
        // cell lists as one group.
        let few_grouped = SceneStatistics { placed_light_groups: 2, placed_decal_groups: 2, ..scene(BRUTE_FORCE_MAX, 3.0, 6, 1.0) };
        assert_eq!(chosen(&auto(), few_grouped), (LightMethod::Brute, DecalMethod::Brute));
        let few = MethodChoice::resolve(&auto(), SUBGROUPS, &scene(BRUTE_FORCE_MAX, 3.0, 6, 1.0));
        assert_eq!((few.lights.method, few.decals.method), (LightMethod::Bvh, DecalMethod::Bvh));
        assert_eq!((few.lights.why, few.decals.why), (Why::Listed { count: 8, overlap: 3.0 }, Why::Listed { count: 6, overlap: 1.0 }));
        let hardware =
            MethodChoice::resolve(&auto(), Capabilities { ray_queries: RayQueries::Native, ..SUBGROUPS }, &scene(6, 3.0, 6, 1.0));
        assert_eq!((hardware.lights.method, hardware.decals.method), (LightMethod::Brute, DecalMethod::Brute));
        assert_eq!(chosen(&auto(), scene(BRUTE_FORCE_MAX + 1, 3.0, 0, 0.0)).0, LightMethod::Bvh);
        // Candidates asked to come through the light tree need the BVH it is built in, for any
        // count and build.
        let mut tree = RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, ..auto() };
        tree.rays.direct_lighting = DirectLighting::Restir;
        tree.rays.restir_candidates = RestirCandidates::Tree;
        for lights in [0, 3, 28_000] {
            let grouped = SceneStatistics { placed_light_groups: 2, ..scene(lights, 0.45, 0, 0.0) };
            let choice = MethodChoice::resolve(&tree, SUBGROUPS, &grouped);
            assert_eq!((choice.lights.method, choice.lights.why), (LightMethod::Bvh, Why::LightTree), "{lights}");
            assert!(FramePlan::resolve(&tree, SUBGROUPS, &grouped).is_ok(), "{lights}");
        }
        // Built once, a BVH wins at any overlap, in every pipeline.
        for pipeline in PipelineKind::ALL {
            let config = RenderConfig { pipeline, ..auto() };
            assert_eq!(chosen(&config, scene(28_000, 0.45, 100_000, 22.8)), (LightMethod::Bvh, DecalMethod::Bvh));
            assert_eq!(chosen(&config, scene(28_000, 100.0, 100_000, 200.0)), (LightMethod::Bvh, DecalMethod::Bvh));
        }
        // Rebuilt every frame, lights of one placed group take a BVH (read as cell lists where sparse)
        // in every pipeline; clustered lists win over sparse decals, and over sparse lights of several
        // groups, not over lights whose leaves subgroups share out; reflections need what lies
        // outside the view.
        let rebuilt = RenderConfig { light_bvh_build: BvhBuild::GpuEveryFrame, decal_bvh_build: BvhBuild::GpuEveryFrame, ..auto() };
        let forward = RenderConfig { pipeline: PipelineKind::Forward, ..rebuilt.clone() };
        let no_subgroups = Capabilities { subgroups: false, early_depth_test: true, ray_queries: RayQueries::None };
        for overlap in [0.03, 0.45, 10.0, 100.0] {
            for config in [&rebuilt, &forward] {
                assert_eq!(chosen(config, scene(28_000, overlap, 0, 0.0)).0, LightMethod::Bvh, "{overlap}");
                assert_eq!(MethodChoice::resolve(config, no_subgroups, &scene(28_000, overlap, 0, 0.0)).lights.method, LightMethod::Bvh);
            }
        }
        assert_eq!(chosen(&rebuilt, scene(1000, 0.1, 1000, 0.1)), (LightMethod::Bvh, DecalMethod::Bvh));
        let listed = MethodChoice::resolve(&rebuilt, SUBGROUPS, &scene(1000, 0.1, 1000, 0.1));
        assert_eq!(listed.decals.why, Why::Listed { count: 1000, overlap: 0.1 });
        let ray_queries = Capabilities { ray_queries: RayQueries::Native, ..SUBGROUPS };
        assert_eq!(MethodChoice::resolve(&rebuilt, ray_queries, &scene(0, 0.0, 1000, 0.1)).decals.method, DecalMethod::Clustered);
        let grouped = |lights, overlap| SceneStatistics { placed_light_groups: 2, ..scene(lights, overlap, 0, 0.0) };
        assert_eq!(chosen(&rebuilt, grouped(1000, 0.1)).0, LightMethod::Clustered);
        assert_eq!(chosen(&rebuilt, grouped(1000, DENSE_LIGHT_OVERLAP)).0, LightMethod::Bvh);
        let grouped_decals = SceneStatistics { placed_decal_groups: 3, ..scene(0, 0.0, 1000, 0.1) };
        assert_eq!(chosen(&rebuilt, grouped_decals).1, DecalMethod::Clustered);
        let crowded =
            SceneStatistics { placed_decal_groups: 3, decal_centre_overlap: Some(DENSE_DECAL_OVERLAP), ..scene(0, 0.0, 1000, 50.0) };
        assert_eq!(chosen(&rebuilt, crowded).1, DecalMethod::Bvh);
        // In fragments too, sparse decals of one group are listed; of several, not.
        assert_eq!(
            MethodChoice::resolve(&forward, SUBGROUPS, &scene(0, 0.0, 4096, 1.0)).decals.why,
            Why::Listed { count: 4096, overlap: 1.0 }
        );
        assert_eq!(chosen(&forward, grouped_decals).1, DecalMethod::Clustered);
        assert_eq!(chosen(&rebuilt, grouped(28_000, REBUILT_BVH_OVERLAP)).0, LightMethod::Bvh);
        assert_eq!(chosen(&rebuilt, grouped(1 << 18, REBUILT_BVH_OVERLAP - 1.5)).0, LightMethod::Clustered);
        assert_eq!(chosen(&forward, grouped(28_000, REBUILT_BVH_OVERLAP)).0, LightMethod::Clustered);
        assert_eq!(chosen(&forward, grouped(28_000, DENSE_FRAGMENT_LIGHT_OVERLAP)).0, LightMethod::Clustered);
        assert_eq!(chosen(&forward, grouped(28_000, DENSE_LIGHT_OVERLAP)).0, LightMethod::Bvh);
        assert_eq!(MethodChoice::resolve(&forward, no_subgroups, &grouped(1000, 50.0)).lights.method, LightMethod::Clustered);
        let mut reflecting = rebuilt.clone();
        reflecting.rays.reflection_bounces = 1;
        assert_eq!(chosen(&reflecting, scene(1000, 50.0, 1000, 0.1)), (LightMethod::Bvh, DecalMethod::Bvh));
        // Particles lit as lights need the lights' BVH, even with no other light.
        let particles = RenderConfig { particle_method: ParticleMethod::Bvh, ..auto() };
        let with_particles = SceneStatistics { particles: 1000, ..scene(0, 0.0, 0, 0.0) };
        assert_eq!(chosen(&particles, with_particles).0, LightMethod::Bvh);
        // A method asked for is kept, and says so.
        let asked = MethodChoice::resolve(&config(LightMethod::Brute, DecalMethod::Clustered), SUBGROUPS, &scene(28_000, 0.45, 100, 1.0));
        assert_eq!((asked.lights.method, asked.lights.why, asked.decals.method), (LightMethod::Brute, Why::Asked, DecalMethod::Clustered));
        assert_eq!(asked.lights.to_string(), "brute (asked for)");
    }

    #[test]
    fn auto_is_resolved_before_anything_is_planned_and_says_why() {
        let three_decal_groups = SceneStatistics { placed_decal_groups: 3, ..scene(28_000, 0.45, 3, 1.0) };
        let plan = FramePlan::resolve(&auto(), SUBGROUPS, &three_decal_groups).unwrap();
        let methods = plan.shading_methods(true, true);
        assert_eq!((methods.lights, methods.decals), (LightMethod::Bvh, DecalMethod::Brute));
        assert_eq!(plan.lights.build, GroupBuild::CpuOnce);
        let why = plan.methods.lights.to_string();
        assert!(why.starts_with("bvh (auto: 28000 reaching 0.45") && why.ends_with("cell lists in place of its BVH are faster)"), "{why}");
        let grouped = SceneStatistics { placed_light_groups: 2, ..three_decal_groups };
        let why = FramePlan::resolve(&auto(), SUBGROUPS, &grouped).unwrap().methods.lights.to_string();
        assert!(why.ends_with("a BVH walk is faster)"), "{why}");
        assert_eq!(plan.methods.decals.to_string(), format!("brute (auto: 3, at most {BRUTE_FORCE_MAX}: a loop over all is cheapest)"));
        // Overlaps are measured only for `auto`, and the lights' for `bvh` lights' walks.
        let measured = Measurements::for_settings(&auto(), SUBGROUPS);
        assert!(measured.light_overlap && measured.decal_overlap && measured.decal_centre_overlap);
        let explicit = Measurements::for_settings(&config(LightMethod::Bvh, DecalMethod::Clustered), SUBGROUPS);
        assert!(explicit.light_overlap && !explicit.decal_overlap && !explicit.decal_centre_overlap);
        let clustered = Measurements::for_settings(&config(LightMethod::Clustered, DecalMethod::Brute), SUBGROUPS);
        assert!(!clustered.light_overlap && !clustered.decal_overlap && !clustered.decal_centre_overlap);
    }
}
