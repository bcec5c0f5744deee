//! The four scenes of Hansen & Peters' Table 1 (i3D 2021), generated reproducibly (seeded) on any
//! scene: 6 large decals, 100 small decals, 100k small decals, 28k small lights. `scenes/paper/*.toml`
//! are the same scenes on Sponza as scene files (a test checks they agree); `manylights bench`
//! generates them on whichever scene it is given.

use super::generators::{self, LargeDecals, ScatterDecals, ScatterLights};
use super::Scene;
use crate::Result;

/// Mean edge of the paper's small decals, as a fraction of the scene's bounding-box diagonal.
pub const PAPER_DECAL_SIZE: f32 = 0.025;

/// Range of the paper's small lights, in metres (glTF's unit), uniform between the two.
pub const SMALL_LIGHT_RANGE: (f32, f32) = (0.1, 0.3);

crate::named_enum! {
    /// One of the paper's scenes, named as on the command line and in result files.
    pub enum PaperScene {
        /// Decals over whole walls and floors: the largest flat surfaces, one decal each.
        #[default]
        LargeDecals = "large-decals",
        /// 100 small decals (2.5 % of the scene's diagonal: about one metre on Sponza) on surface
        /// points, facing out along the normal.
        SmallDecals = "small-decals",
        /// 100,000 of the same.
        ManyDecals = "many-decals",
        /// 28,000 point lights of 0.1–0.3 m range just above surface points.
        SmallLights = "small-lights",
    }
}

impl PaperScene {
    /// The row label of the paper's table.
    pub fn label(self) -> &'static str {
        match self {
            Self::LargeDecals => "6 large decals",
            Self::SmallDecals => "100 small decals",
            Self::ManyDecals => "100k small decals",
            Self::SmallLights => "28k small lights",
        }
    }

    /// Whether the scene adds decals (else lights).
    pub fn has_decals(self) -> bool {
        !matches!(self, Self::SmallLights)
    }

    /// How many lights or decals the scene adds (large decals: at most that many, one per plane).
    pub fn count(self) -> usize {
        match self {
            Self::LargeDecals => 6,
            Self::SmallDecals => 100,
            Self::ManyDecals => 100_000,
            Self::SmallLights => 28_000,
        }
    }

    /// Adds the scene's lights or decals to `scene` (ungrouped), drawn with `seed`.
    pub fn add_to(self, scene: &mut Scene, seed: u64) -> Result<()> {
        let count = self.count();
        match self {
            Self::LargeDecals => generators::add_large_decals(scene, &LargeDecals { count, seed }),
            Self::SmallDecals | Self::ManyDecals => {
                // The paper's size, however many: 2.5 % of the diagonal (the default shrinks crowds).
                let size = Some(scene.bounds().diagonal() * PAPER_DECAL_SIZE);
                generators::add_scattered_decals(scene, &ScatterDecals { count, seed, size })
            }
            Self::SmallLights => {
                let params = ScatterLights { count, seed, range: Some(SMALL_LIGHT_RANGE), ..Default::default() };
                generators::add_scattered_lights(scene, &params)
            }
        }
    }
}
