//! Frame graphs: each pipeline orders the passes of one frame, read top to bottom in its own file.
//! Today: the visibility-buffer pipeline. Forward and deferred pipelines plug in beside it, reusing
//! the same shading core; enumeration methods plug in through `LightMethod` and `DecalMethod`.

pub mod visbuffer;

pub use visbuffer::VisbufferPipeline;

/// How the shading core finds the local lights that reach a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LightMethod {
    /// Loop over every light.
    #[default]
    Brute,
    /// Point queries in a BVH over the lights' volumes (`accel`).
    Bvh,
}

impl LightMethod {
    pub const ALL: [LightMethod; 2] = [LightMethod::Brute, LightMethod::Bvh];

    /// The WGSL module that defines `shade_local_lights` for this method.
    pub fn enumeration_module(self) -> &'static str {
        match self {
            LightMethod::Brute => "shading/enumerate/lights_brute.wgsl",
            LightMethod::Bvh => "shading/enumerate/lights_bvh.wgsl",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            LightMethod::Brute => "brute",
            LightMethod::Bvh => "bvh",
        }
    }
}

/// How the shading core finds the decals that cover a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DecalMethod {
    /// Loop over every decal.
    #[default]
    Brute,
    /// Point queries in a BVH over the decals' boxes (`accel`).
    Bvh,
}

impl DecalMethod {
    pub const ALL: [DecalMethod; 2] = [DecalMethod::Brute, DecalMethod::Bvh];

    /// The WGSL module that defines `apply_decals` for this method.
    pub fn enumeration_module(self) -> &'static str {
        match self {
            DecalMethod::Brute => "shading/enumerate/decals_brute.wgsl",
            DecalMethod::Bvh => "shading/enumerate/decals_bvh.wgsl",
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            DecalMethod::Brute => "brute",
            DecalMethod::Bvh => "bvh",
        }
    }
}
