//! The default daylight sky: Preetham, Shirley and Smits, "A Practical Analytic Model for Daylight"
//! (SIGGRAPH 1999). The Perez et al. sky luminance distribution with the paper's turbidity fits for
//! luminance Y and chromaticity x, y (its Appendix A.2), the zenith values of its Appendix A.2, and
//! the sun's colour from its spectral attenuation by Rayleigh and aerosol scattering (Appendix A.1)
//! at three wavelengths. [`light_with_sky`] gives a scene the sky as its environment and a
//! directional sun to match, as `settings::Sky` asks.

use std::f32::consts::PI;

use glam::Vec3;

use super::{environment::Environment, Scene, Sun};
use crate::settings::{
    environment::{DEFAULT_SUN_AZIMUTH_DEGREES, DEFAULT_SUN_ELEVATION_DEGREES, SKY_TURBIDITY},
    Sky,
};

/// The scene's units of light per lux (and of radiance per cd/m²): the project's noon sun of 2.5
/// (Sponza at noon, the demo) stands for about 100,000 lux.
pub const SCENE_UNITS_PER_LUX: f32 = 2.5e-5;
/// Illuminance of sunlight outside the atmosphere, in lux.
const EXTRATERRESTRIAL_SUN_LUX: f32 = 128_000.0;
/// Reflectance of the ground seen below the horizon, lit by the sun and the sky.
const GROUND_ALBEDO: f32 = 0.2;
/// The equirectangular image the sky is evaluated into: smooth enough at this size for the
/// background, and the image-based lighting filters it further.
const SKY_IMAGE_WIDTH: u32 = 512;

/// Perez coefficients A–E as linear functions of turbidity T: (slope, intercept) per coefficient,
/// for Y, x and y (Preetham et al., Appendix A.2).
const PEREZ: [[(f32, f32); 5]; 3] = [
    [(0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703)],
    [(-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452)],
    [(-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529)],
];

/// Zenith chromaticity x and y: rows for T², T, 1; columns for θs³, θs², θs, 1 (θs the sun's
/// zenith angle in radians).
const ZENITH_X: [[f32; 4]; 3] =
    [[0.00166, -0.00375, 0.00209, 0.0], [-0.02903, 0.06377, -0.03202, 0.00394], [0.11693, -0.21196, 0.06052, 0.25886]];
const ZENITH_Y: [[f32; 4]; 3] =
    [[0.00275, -0.00610, 0.00317, 0.0], [-0.04214, 0.08970, -0.04153, 0.00516], [0.15346, -0.26756, 0.06670, 0.26688]];

/// Wavelengths in micrometres standing for the red, green and blue primaries in the sun's
/// attenuation.
const RGB_WAVELENGTHS: [f32; 3] = [0.680, 0.550, 0.440];

/// The Preetham sky for one sun position and turbidity.
#[derive(Clone, Debug)]
pub struct DaylightSky {
    /// Unit vector towards the sun.
    to_sun: Vec3,
    turbidity: f32,
    /// Perez coefficients for Y, x, y.
    perez: [[f32; 5]; 3],
    /// Zenith luminance (cd/m²) and chromaticity.
    zenith: [f32; 3],
    /// Scene units per lux of this sky and its sun: [`SCENE_UNITS_PER_LUX`], or what matches a
    /// scene's own sun (`for_scene`).
    units_per_lux: f32,
}

impl DaylightSky {
    /// The sky with the sun towards `to_sun` (kept at least a degree above the horizon, where the
    /// model's fits hold).
    pub fn new(to_sun: Vec3, turbidity: f32) -> Self {
        let lowest = 1f32.to_radians().sin();
        let horizontal = Vec3::new(to_sun.x, 0.0, to_sun.z).normalize_or(Vec3::NEG_Z);
        let to_sun = to_sun.normalize_or(Vec3::Y);
        let to_sun = if to_sun.y < lowest { (horizontal * (1.0 - lowest * lowest).sqrt()).with_y(lowest) } else { to_sun };
        let perez = PEREZ.map(|row| row.map(|(slope, intercept)| slope * turbidity + intercept));
        let theta_s = to_sun.y.acos();
        let t = turbidity;
        let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * theta_s);
        let luminance = ((4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192) * 1000.0;
        let chromaticity = |m: &[[f32; 4]; 3]| {
            let angle = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
            let row = |r: &[f32; 4]| r.iter().zip(angle).map(|(c, a)| c * a).sum::<f32>();
            t * t * row(&m[0]) + t * row(&m[1]) + row(&m[2])
        };
        Self {
            to_sun,
            turbidity,
            perez,
            zenith: [luminance, chromaticity(&ZENITH_X), chromaticity(&ZENITH_Y)],
            units_per_lux: SCENE_UNITS_PER_LUX,
        }
    }

    /// The sky where the scene's own sun is and as bright as the sky that sun implies (its
    /// illuminance over the model's sun's there: the scene's units, lux from a glTF file or the
    /// project's), or at the default position and brightness when it has none (or a dark one).
    pub fn for_scene(scene: &Scene) -> Self {
        let Some(own) = scene.sun.filter(|sun| sun.illuminance > 0.0 && sun.illuminance.is_finite()) else {
            let (elevation, azimuth) = (DEFAULT_SUN_ELEVATION_DEGREES.to_radians(), DEFAULT_SUN_AZIMUTH_DEGREES.to_radians());
            let to_sun = Vec3::new(elevation.cos() * azimuth.sin(), elevation.sin(), -elevation.cos() * azimuth.cos());
            return Self::new(to_sun, SKY_TURBIDITY);
        };
        let mut sky = Self::new(-own.direction, SKY_TURBIDITY);
        sky.units_per_lux *= own.illuminance / sky.sun().illuminance;
        sky
    }

    /// Sky radiance (linear sRGB, scene units) seen along unit `dir` at or above the horizon,
    /// without the sun's disc.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        // The fits diverge at the horizon (1 / cos θ): look no lower than just above it.
        let cos_theta = dir.y.max(0.01);
        let cos_gamma = dir.dot(self.to_sun).clamp(-1.0, 1.0);
        let gamma = cos_gamma.acos();
        let theta_s = self.to_sun.y.acos();
        let perez = |c: &[f32; 5], cos_theta: f32, gamma: f32, cos_gamma: f32| {
            (1.0 + c[0] * (c[1] / cos_theta).exp()) * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * cos_gamma * cos_gamma)
        };
        let [luminance, x, y] = std::array::from_fn(|i| {
            self.zenith[i] * perez(&self.perez[i], cos_theta, gamma, cos_gamma) / perez(&self.perez[i], 1.0, theta_s, self.to_sun.y)
        });
        xyy_to_linear_srgb(x, y, luminance) * self.units_per_lux
    }

    /// The directional sun this sky implies: sunlight outside the atmosphere attenuated along the
    /// sun's air mass.
    pub fn sun(&self) -> Sun {
        let zenith_degrees = self.to_sun.y.acos().to_degrees();
        // Kasten's relative optical air mass, as the paper uses.
        let air_mass = 1.0 / (self.to_sun.y + 0.15 * (93.885 - zenith_degrees).powf(-1.253));
        let beta = 0.046_083_66 * self.turbidity - 0.045_860_26;
        let transmittance = Vec3::from(RGB_WAVELENGTHS.map(|lambda| {
            let rayleigh = (-0.008735 * lambda.powf(-4.08) * air_mass).exp();
            let aerosol = (-beta * lambda.powf(-1.3) * air_mass).exp();
            rayleigh * aerosol
        }));
        let luminance = luminance(transmittance);
        Sun {
            direction: -self.to_sun,
            color: transmittance / luminance,
            illuminance: EXTRATERRESTRIAL_SUN_LUX * self.units_per_lux * luminance,
        }
    }

    /// The sky as an equirectangular environment ([`Environment`]'s layout), with the ground below
    /// the horizon lit by the sun and the sky. The sun's disc is left out: the directional sun lights
    /// the scene, and the disc is drawn from it.
    pub fn environment(&self) -> Environment {
        let (width, height) = (SKY_IMAGE_WIDTH, SKY_IMAGE_WIDTH / 2);
        let mut radiance = vec![[0.0; 3]; (width * height) as usize];
        let mut sky_irradiance = Vec3::ZERO;
        for row in 0..height / 2 {
            for column in 0..width {
                let dir = Environment::texel_direction(column, row, width, height);
                let sky = self.radiance(dir);
                radiance[(row * width + column) as usize] = sky.to_array();
                sky_irradiance += sky * dir.y * Environment::texel_solid_angle(row, width, height);
            }
        }
        let sun = self.sun();
        let ground = (sun.color * sun.illuminance * self.to_sun.y + sky_irradiance) * GROUND_ALBEDO / PI;
        radiance[(width * height / 2) as usize..].fill(ground.to_array());
        Environment { width, height, radiance, sun_disc: true }
    }
}

/// Gives `scene` the lighting `sky` asks for: `Off` removes any environment (the uniform ambient
/// remains); `Daylight` sets the daylight sky as the environment (placed and scaled by the scene's
/// own sun, [`DaylightSky::for_scene`]) and, unless the scene has a sun, the sky's sun; `Auto` does
/// the same only where the scene has no environment and none of its own lights
/// (`Scene::authored_lights`): a sun alone, as glTF files exported with one have, gets its sky.
pub fn light_with_sky(scene: &mut Scene, sky: Sky) {
    let daylight = match sky {
        Sky::Off => {
            scene.environment = None;
            return;
        }
        Sky::Daylight => true,
        Sky::Auto => scene.environment.is_none() && scene.authored_lights == 0,
    };
    if daylight {
        let model = DaylightSky::for_scene(scene);
        scene.environment = Some(model.environment());
        scene.sun = scene.sun.or(Some(model.sun()));
    }
}

fn luminance(rgb: Vec3) -> f32 {
    rgb.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// CIE xyY to linear sRGB (Rec. 709 primaries, D65), negative components clipped.
fn xyy_to_linear_srgb(x: f32, y: f32, luminance: f32) -> Vec3 {
    let xyz = Vec3::new(x * luminance / y, luminance, (1.0 - x - y) * luminance / y);
    let rgb = Vec3::new(
        3.2406 * xyz.x - 1.5372 * xyz.y - 0.4986 * xyz.z,
        -0.9689 * xyz.x + 1.8758 * xyz.y + 0.0415 * xyz.z,
        0.0557 * xyz.x - 0.2040 * xyz.y + 1.0570 * xyz.z,
    );
    rgb.max(Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sky() -> DaylightSky {
        DaylightSky::new(Vec3::new(0.0, 40f32.to_radians().sin(), -40f32.to_radians().cos()), 3.0)
    }

    #[test]
    fn the_sky_is_blue_overhead_and_brightest_near_the_sun() {
        let sky = sky();
        let zenith = sky.radiance(Vec3::Y);
        assert!(zenith.z > zenith.x && zenith.z > zenith.y * 0.9, "{zenith}");
        let near_sun = sky.radiance((sky.to_sun + Vec3::new(0.0, 0.1, 0.0)).normalize());
        let away = sky.radiance(Vec3::new(0.0, 40f32.to_radians().sin(), 40f32.to_radians().cos()));
        assert!(luminance(near_sun) > 3.0 * luminance(away), "{near_sun} {away}");
        // The paper's zenith luminance for T = 3 and the sun 50° from the zenith: about 6.5 kcd/m².
        assert!((luminance(zenith) / SCENE_UNITS_PER_LUX - 6500.0).abs() < 1500.0, "{zenith}");
    }

    #[test]
    fn the_sun_is_warm_and_about_as_bright_as_the_projects_noon_sun() {
        let sun = sky().sun();
        assert!(sun.color.x > sun.color.y && sun.color.y > sun.color.z, "{:?}", sun.color);
        assert!((1.5..3.0).contains(&sun.illuminance), "{}", sun.illuminance);
        let low = DaylightSky::new(Vec3::new(0.0, 0.1, -1.0), 3.0).sun();
        assert!(low.illuminance < sun.illuminance && low.color.z / low.color.x < sun.color.z / sun.color.x);
    }

    #[test]
    fn auto_lights_scenes_without_lights_of_their_own() {
        let mut bare = Scene::default();
        light_with_sky(&mut bare, Sky::Auto);
        assert!(bare.environment.is_some() && bare.sun.is_some());
        let mut lit = crate::scene::demo::demo_scene();
        light_with_sky(&mut lit, Sky::Auto);
        assert!(lit.environment.is_none());
        let own_sun = lit.sun;
        light_with_sky(&mut lit, Sky::Daylight);
        assert!(lit.environment.is_some() && lit.sun == own_sun);
        light_with_sky(&mut lit, Sky::Off);
        assert!(lit.environment.is_none());
    }

    /// A sun alone (a glTF file's directional light, in lux) gets the sky it implies, as much
    /// brighter as it is.
    #[test]
    fn a_scene_with_only_a_sun_gets_the_sky_of_that_sun() {
        let with_sun = |illuminance| {
            let mut scene = Scene::default();
            let direction = Vec3::new(-0.3, -0.6, 0.2).normalize();
            scene.sun = Some(Sun { direction, color: Vec3::ONE, illuminance });
            light_with_sky(&mut scene, Sky::Auto);
            assert_eq!(scene.sun.map(|s| (s.direction, s.illuminance)), Some((direction, illuminance)), "the scene's own sun stays");
            scene.environment.expect("the sky").radiance
        };
        let (project, lux) = (with_sun(2.0), with_sun(2049.0));
        for (a, b) in project.iter().zip(&lux) {
            let (a, b) = (Vec3::from(*a), Vec3::from(*b));
            assert!((b - a * 2049.0 / 2.0).abs().max_element() <= 1e-3 * b.max_element() + 1e-9, "{a} against {b}");
        }
    }
}
