//! The frame graph and the methods that find the lights, decals and particle lights reaching a point.

use crate::named_enum;

named_enum! {
    /// Which frame graph renders (`pipelines/`).
    pub enum PipelineKind {
        /// Visibility buffer, shading in compute (`pipelines/visbuffer.rs`).
        #[default]
        Visbuffer = "visbuffer",
        /// G-buffer raster, then decals and lights in compute (`pipelines/deferred.rs`).
        Deferred = "deferred",
        /// Depth prepass, then shading in the fragment stage (`pipelines/forward.rs`).
        Forward = "forward",
    }
}

named_enum! {
    /// How the shading core finds the local lights that reach a point.
    pub enum LightMethod {
        /// The fastest of the others for the scene, pipeline and settings, chosen from statistics
        /// measured at load (`plan::MethodChoice`).
        #[default]
        Auto = "auto",
        /// No local lights: the baseline the others are measured against.
        Off = "off",
        /// Loop over every light.
        Brute = "brute",
        /// Point queries in a BVH over the lights' volumes (`accel`).
        Bvh = "bvh",
        /// Per-froxel lists built every frame (`accel/clusters.rs`); view frustum only.
        Clustered = "clustered",
    }
}

named_enum! {
    /// How the shading core finds the decals that cover a point.
    pub enum DecalMethod {
        /// The fastest of the others for the scene, pipeline and settings, chosen from statistics
        /// measured at load (`plan::MethodChoice`).
        #[default]
        Auto = "auto",
        /// No decals: the baseline the others are measured against.
        Off = "off",
        /// Loop over every decal.
        Brute = "brute",
        /// Point queries in a BVH over the decals' boxes (`accel`).
        Bvh = "bvh",
        /// Per-froxel lists built every frame (`accel/clusters.rs`); view frustum only.
        Clustered = "clustered",
        /// Decal boxes rasterised into the G-buffer before lighting (Kim 2012); deferred pipeline only.
        DeferredDecals = "deferred-decals",
    }
}

impl DecalMethod {
    /// Whether `pipeline` can apply decals this way: deferred decals need a G-buffer to blend into.
    pub fn works_in(self, pipeline: PipelineKind) -> bool {
        self != DecalMethod::DeferredDecals || pipeline == PipelineKind::Deferred
    }
}

named_enum! {
    /// How the shading core lights a point with the particle lights (`particles/`).
    pub enum ParticleMethod {
        /// No particle lights.
        #[default]
        Off = "off",
        /// Sample the two 3D textures the particles are splatted into every frame.
        Grid = "grid",
        /// Exact: every particle a point light in the lights' BVH, rebuilt on the GPU every frame
        /// (needs `LightMethod::Bvh`, which then shades them).
        Bvh = "bvh",
    }
}

named_enum! {
    /// When the BVHs over a structure's groups of lights or decals are built, for the `bvh` method.
    pub enum BvhBuild {
        /// Once, on the CPU (binned SAH): for groups whose volumes do not change.
        #[default]
        CpuOnce = "cpu-once",
        /// Every frame, on the GPU (LBVH), as groups whose volumes change need: timed as
        /// `<label>_blas_build`.
        GpuEveryFrame = "gpu-every-frame",
    }
}

/// The light and decal methods a scene file's `[methods]` asks for, each taken unless the command
/// line makes its own choice.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MethodOverlay {
    pub lights: Option<LightMethod>,
    pub decals: Option<DecalMethod>,
}
