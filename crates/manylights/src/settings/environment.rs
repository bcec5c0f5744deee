//! What lights a scene from afar: the default daylight sky, an environment image, or neither.

named_enum! {
    /// Whether the scene gets the analytic daylight sky (`scene::sky`): seen in the background and in
    /// reflections, lighting surfaces through image-based lighting, with a sun to match. An
    /// environment image (`--environment`, a scene file's `environment`) takes its place.
    pub enum Sky {
        /// The daylight sky where the scene has no lights of its own (glTF point and spot lights,
        /// scene-file `[[lights]]`; scattered lights and particles do not count). A sun of its own
        /// places the sky's sun and sets the sky's brightness, in whatever units the sun is in.
        #[default]
        Auto = "auto",
        /// The daylight sky always; a scene's own sun keeps its light and places and scales the sky.
        Daylight = "daylight",
        /// No sky or environment image: the scene's uniform `ambient` light only.
        Off = "off",
    }
}

/// Where the daylight sky puts its sun when the scene has none: degrees above the horizon, and
/// degrees from −Z towards +X.
pub const DEFAULT_SUN_ELEVATION_DEGREES: f32 = 40.0;
pub const DEFAULT_SUN_AZIMUTH_DEGREES: f32 = 30.0;
/// Atmospheric turbidity of the daylight sky (Preetham et al.): 2 is a very clear day, 3 a clear one.
pub const SKY_TURBIDITY: f32 = 3.0;
