//! What the image shows: the tonemapping curve and the debug views.

use crate::named_enum;

named_enum! {
    /// The tonemapping curve. Keep the discriminants in sync with `TONEMAP_*` in `shading/types.wgsl`.
    pub enum Tonemapper {
        #[default]
        Aces(0) = "aces",
        Agx(1) = "agx",
        /// Clamp only: for inspecting linear values.
        None(2) = "none",
    }
}

named_enum! {
    /// What a frame shows instead of its radiance, for looking inside the methods. Keep the
    /// discriminants in sync with `DEBUG_VIEW_*` in `shading/debug_view.wgsl`.
    pub enum DebugView {
        #[default]
        Off(0) = "off",
        /// Lights reaching each point, as a heat map up to 16.
        LightsReaching(1) = "lights-reaching",
        /// The light method's work at each point: BVH nodes visited, the froxel's list length
        /// (cluster occupancy) or lights tested, up to 128.
        LightWork(2) = "light-work",
        /// Decals covering each point, up to 16.
        DecalsCovering(3) = "decals-covering",
        /// The particle lights' radiance alone (exposed and tonemapped as usual).
        ParticleLight(4) = "particle-light",
        /// A horizontal slice through the particle grid (`RenderConfig::debug_slice_height`): the
        /// grid's colour sums where pixels' rays cross it before their surface, the scene dimmed
        /// elsewhere.
        ParticleGridSlice(5) = "particle-grid-slice",
        /// Shadow rays traced towards local lights at each point (`--direct-lighting`; with restir,
        /// its samples' and those its reuse asks of neighbours), up to 16.
        ShadowRays(6) = "shadow-rays",
        /// The confidence of the reservoir restir keeps at each pixel (candidates' worth of samples,
        /// its own and reused), up to 32.
        RestirConfidence(7) = "restir-confidence",
        /// The weight of the sample restir shades each pixel with, as its unshadowed estimate over
        /// the pixel's own candidates' sum, in quarters up to 4 (1 is cyan: reuse agrees).
        RestirWeight(8) = "restir-weight",
    }
}

impl DebugView {
    /// The count a heat map tops out at; 0 for views that are not heat maps.
    pub fn scale(self) -> u32 {
        match self {
            DebugView::LightsReaching | DebugView::DecalsCovering | DebugView::ShadowRays | DebugView::RestirWeight => 16,
            DebugView::RestirConfidence => 32,
            DebugView::LightWork => 128,
            DebugView::Off | DebugView::ParticleLight | DebugView::ParticleGridSlice => 0,
        }
    }

    /// The frame uniforms' `debug_view`, with the slice's height (metres) for the grid slice.
    pub fn uniform(self, slice_height: f32) -> [u32; 4] {
        [self as u32, self.scale(), slice_height.to_bits(), 0]
    }
}

/// The heat map of `count` out of `scale` as the shaders draw it (`heat_map` in
/// `shading/debug_view.wgsl`): black for none, then blue, cyan, green, yellow, red.
pub fn heat_map(count: u32, scale: u32) -> [f32; 3] {
    if count == 0 {
        return [0.0; 3];
    }
    let stops = [[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0]];
    let t = (count as f32 / scale.max(1) as f32).clamp(0.0, 1.0) * 4.0;
    let i = (t as usize).min(3);
    let f = t - i as f32;
    std::array::from_fn(|c| stops[i][c] + (stops[i + 1][c] - stops[i][c]) * f)
}
