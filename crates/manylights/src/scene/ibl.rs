//! Image-based lighting, precomputed on the CPU once per scene from its environment
//! (`scene::environment`): the split-sum approximation (Karis, "Real Shading in Unreal Engine 4",
//! 2013). Diffuse light is the irradiance's L2 spherical harmonics (Ramamoorthi and Hanrahan, "An
//! Efficient Representation for Irradiance Environment Maps", 2001): nine coefficients whose error
//! is a few percent for any environment. Specular light is the environment prefiltered with the GGX
//! lobe of each roughness, one mip level per roughness step, times a table of the BRDF's scale and
//! bias on F0 by n·v and roughness. Filtering is importance-sampled from a box-filtered pyramid of
//! the environment at the mip each sample's solid angle calls for (Křivánek and Colbert, "Real-time
//! Shading with Filtered Importance Sampling", 2008), so few samples make no noise.

use std::f32::consts::PI;
use std::sync::OnceLock;

use glam::{Vec2, Vec3};

use super::environment::{direction_at, Environment};

/// The prefiltered specular environment: level 0 is this wide (and half as high), each level half
/// the one before, level k filtered for perceptual roughness k / (levels − 1).
pub const SPECULAR_WIDTH: u32 = 128;
pub const SPECULAR_LEVELS: u32 = 6;
/// The split-sum BRDF table: n·v along its width, perceptual roughness along its height.
pub const BRDF_TABLE_SIZE: u32 = 64;

/// Width of the pyramid's finest level, which the filters and the projection read.
const PYRAMID_WIDTH: u32 = 256;
const SPECULAR_SAMPLES: u32 = 128;
const BRDF_SAMPLES: u32 = 256;

/// Coefficients of irradiance / π in the real L2 spherical-harmonic basis, with each band's cosine
/// convolution and basis constant folded in: irradiance / π at unit normal n is
/// c0 + c1 y + c2 z + c3 x + c4 xy + c5 yz + c6 (3z² − 1) + c7 xz + c8 (x² − y²). Keep in sync with
/// `environment_irradiance` in `shading/environment.wgsl`.
pub fn irradiance_sh(pyramid: &Pyramid) -> [Vec3; 9] {
    // The finest level: coarser ones leave the higher bands of a uniform environment visibly non-zero.
    let source = &pyramid.levels[0];
    // Cosine lobe convolution per band (Â_l / π) times the basis constant, squared once for the
    // projection and once for the evaluation.
    let band = [1.0, 2.0 / 3.0, 0.25];
    let basis_constant = [0.282_095, 0.488_603, 0.488_603, 0.488_603, 1.092_548, 1.092_548, 0.315_392, 1.092_548, 0.546_274];
    let band_of = [0, 1, 1, 1, 2, 2, 2, 2, 2];
    let mut coefficients = [Vec3::ZERO; 9];
    for row in 0..source.height {
        let solid_angle = Environment::texel_solid_angle(row, source.width, source.height);
        for column in 0..source.width {
            let n = Environment::texel_direction(column, row, source.width, source.height);
            let radiance = Vec3::from(source.radiance[(row * source.width + column) as usize]) * solid_angle;
            for (i, p) in sh_polynomials(n).into_iter().enumerate() {
                coefficients[i] += radiance * p;
            }
        }
    }
    std::array::from_fn(|i| coefficients[i] * basis_constant[i] * basis_constant[i] * band[band_of[i]])
}

/// Irradiance / π at unit normal `n` from [`irradiance_sh`]'s coefficients.
pub fn evaluate_irradiance(coefficients: &[Vec3; 9], n: Vec3) -> Vec3 {
    sh_polynomials(n).into_iter().zip(coefficients).map(|(p, c)| *c * p).sum()
}

fn sh_polynomials(n: Vec3) -> [f32; 9] {
    let Vec3 { x, y, z } = n;
    [1.0, y, z, x, x * y, y * z, 3.0 * z * z - 1.0, x * z, x * x - y * y]
}

/// The prefiltered specular environment, [`SPECULAR_LEVELS`] images from [`SPECULAR_WIDTH`] wide.
pub fn prefiltered_specular(pyramid: &Pyramid) -> Vec<Environment> {
    let base = &pyramid.levels[0];
    let base_texel_solid_angle = 4.0 * PI / (base.width * base.height) as f32;
    let samples: Vec<Vec2> = (0..SPECULAR_SAMPLES).map(|i| hammersley(i, SPECULAR_SAMPLES)).collect();
    (0..SPECULAR_LEVELS)
        .map(|level| {
            let (width, height) = (SPECULAR_WIDTH >> level, (SPECULAR_WIDTH / 2) >> level);
            let alpha = (level as f32 / (SPECULAR_LEVELS - 1) as f32).powi(2);
            let mut radiance = Vec::with_capacity((width * height) as usize);
            for row in 0..height {
                for column in 0..width {
                    let n = Environment::texel_direction(column, row, width, height);
                    if level == 0 {
                        radiance.push(pyramid.sample(n, (PYRAMID_WIDTH / SPECULAR_WIDTH).ilog2() as f32).to_array());
                        continue;
                    }
                    // The view is taken along the normal (n = v = r), as the split sum assumes.
                    let basis = tangent_basis(n);
                    let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
                    for xi in &samples {
                        let (h_local, n_dot_h) = sample_ggx(*xi, alpha);
                        let h = basis * h_local;
                        let l = 2.0 * n.dot(h) * h - n;
                        let n_dot_l = n.dot(l);
                        if n_dot_l <= 0.0 {
                            continue;
                        }
                        // pdf(l) = D(h) (n·h) / (4 v·h), and v·h = n·h here.
                        let pdf = d_ggx(n_dot_h, alpha) / 4.0;
                        let sample_solid_angle = 1.0 / (SPECULAR_SAMPLES as f32 * pdf + 1e-6);
                        let lod = (0.5 * (sample_solid_angle / base_texel_solid_angle).log2() + 1.0).max(0.0);
                        sum += pyramid.sample(l, lod) * n_dot_l;
                        weight += n_dot_l;
                    }
                    radiance.push((sum / weight.max(1e-6)).to_array());
                }
            }
            Environment { width, height, radiance, sun_disc: false }
        })
        .collect()
}

/// The split-sum BRDF table, computed once per process: (scale, bias) on F0 such that
/// ∫ f cos = F0 · scale + bias for the glTF GGX BRDF (height-correlated Smith, Schlick's Fresnel,
/// as `shading/brdf.wgsl`), at texel centres: n·v = (i + ½) / size along a row, perceptual roughness
/// (j + ½) / size down the rows.
pub fn brdf_table() -> &'static [[f32; 2]] {
    static TABLE: OnceLock<Vec<[f32; 2]>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let size = BRDF_TABLE_SIZE;
        (0..size * size).map(|i| split_sum_brdf((i % size) as f32 + 0.5, (i / size) as f32 + 0.5, size)).collect()
    })
}

/// The sheen's directional albedo E(n·v, roughness) (`KHR_materials_sheen`): ∫ D V cos over the light
/// directions for a white sheen, with the Charlie distribution and the Estevez–Kulla visibility of
/// `shading/brdf.wgsl`, at the BRDF table's texel centres (its blue channel on the GPU). The
/// material below a sheen keeps 1 − max(sheen colour) × E of the light.
pub fn sheen_albedo_table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let size = BRDF_TABLE_SIZE;
        (0..size * size)
            .map(|i| sheen_albedo_at(((i % size) as f32 + 0.5) / size as f32, ((i / size) as f32 + 0.5) / size as f32))
            .collect()
    })
}

/// [`sheen_albedo_table`] read as the GPU's linear sampler reads it, clamped to the texel centres.
pub fn sheen_albedo(n_dot_v: f32, roughness: f32) -> f32 {
    let table = sheen_albedo_table();
    let size = BRDF_TABLE_SIZE as f32;
    let coordinate = |x: f32| {
        let texel = (x.clamp(0.5 / size, 1.0 - 0.5 / size) * size - 0.5).max(0.0);
        let low = (texel as usize).min(BRDF_TABLE_SIZE as usize - 2);
        (low, texel - low as f32)
    };
    let ((i, fx), (j, fy)) = (coordinate(n_dot_v), coordinate(roughness));
    let at = |i: usize, j: usize| table[j * BRDF_TABLE_SIZE as usize + i];
    let row = |j: usize| at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
    row(j) * (1.0 - fy) + row(j + 1) * fy
}

/// Below this perceptual roughness the sheen is as at it (`MIN_ROUGHNESS` in `shading/brdf.wgsl`).
const MIN_SHEEN_ROUGHNESS: f32 = 0.045;

/// The Charlie sheen distribution (Estevez & Kulla 2017) for perceptual roughness `roughness`.
pub fn d_charlie(n_dot_h: f32, roughness: f32) -> f32 {
    let inverse_alpha = 1.0 / roughness.max(MIN_SHEEN_ROUGHNESS).powi(2);
    let sin_sq = (1.0 - n_dot_h * n_dot_h).max(0.0);
    (2.0 + inverse_alpha) * sin_sq.powf(0.5 * inverse_alpha) / (2.0 * PI)
}

/// Estevez and Kulla's fit to the sheen's Λ, at the cosine `x` (0 to 1).
fn sheen_lambda_fit(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f32, b: f32| a + (b - a) * t;
    let (a, b, c) = (mix(21.5473, 25.3245), mix(3.82987, 3.32435), mix(0.19823, 0.16801));
    let (d, e) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    a / (1.0 + b * x.powf(c)) + d * x + e
}

fn sheen_lambda(cosine: f32, alpha: f32) -> f32 {
    if cosine < 0.5 {
        sheen_lambda_fit(cosine, alpha).exp()
    } else {
        (2.0 * sheen_lambda_fit(0.5, alpha) - sheen_lambda_fit(1.0 - cosine, alpha)).exp()
    }
}

/// The sheen's visibility, V = G / (4 n·l n·v), with Estevez and Kulla's Λ.
pub fn v_sheen(n_dot_v: f32, n_dot_l: f32, roughness: f32) -> f32 {
    let alpha = roughness.max(MIN_SHEEN_ROUGHNESS).powi(2);
    (1.0 / ((1.0 + sheen_lambda(n_dot_v, alpha) + sheen_lambda(n_dot_l, alpha)) * (4.0 * n_dot_v * n_dot_l))).clamp(0.0, 1.0)
}

/// Light directions per side of the midpoint quadrature of [`sheen_albedo_at`]: in cos θ, and in φ
/// over the half of the hemisphere the other mirrors.
const SHEEN_STEPS: u32 = 24;

fn sheen_albedo_at(n_dot_v: f32, roughness: f32) -> f32 {
    let v = Vec3::new((1.0 - n_dot_v * n_dot_v).sqrt(), 0.0, n_dot_v);
    let step = 1.0 / SHEEN_STEPS as f32;
    let mut sum = 0.0;
    for i in 0..SHEEN_STEPS {
        let n_dot_l = (i as f32 + 0.5) * step;
        let sin_l = (1.0 - n_dot_l * n_dot_l).sqrt();
        for j in 0..SHEEN_STEPS {
            let phi = (j as f32 + 0.5) * step * PI;
            let l = Vec3::new(sin_l * phi.cos(), sin_l * phi.sin(), n_dot_l);
            let h = (v + l).normalize();
            sum += d_charlie(h.z, roughness) * v_sheen(n_dot_v, n_dot_l, roughness) * n_dot_l;
        }
    }
    // dω = d(cos θ) dφ over both halves. At grazing views of smooth sheens the fitted visibility
    // lets the integral pass 1, where the layer would leave the material below less than nothing.
    (sum * step * step * PI * 2.0).min(1.0)
}

fn split_sum_brdf(column: f32, row: f32, size: u32) -> [f32; 2] {
    let n_dot_v = column / size as f32;
    let alpha = (row / size as f32).powi(2);
    let v = Vec3::new((1.0 - n_dot_v * n_dot_v).sqrt(), 0.0, n_dot_v);
    let (mut scale, mut bias) = (0.0, 0.0);
    for i in 0..BRDF_SAMPLES {
        let (h, n_dot_h) = sample_ggx(hammersley(i, BRDF_SAMPLES), alpha);
        let v_dot_h = v.dot(h);
        let l = 2.0 * v_dot_h * h - v;
        if l.z <= 0.0 || v_dot_h <= 0.0 {
            continue;
        }
        // f cos / pdf with f = D V F and pdf = D (n·h) / (4 v·h).
        let g = v_smith_ggx_correlated(n_dot_v, l.z, alpha) * 4.0 * l.z * v_dot_h / n_dot_h;
        let fresnel = (1.0 - v_dot_h).powi(5);
        scale += (1.0 - fresnel) * g;
        bias += fresnel * g;
    }
    [scale / BRDF_SAMPLES as f32, bias / BRDF_SAMPLES as f32]
}

fn d_ggx(n_dot_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d).max(1e-12)
}

fn v_smith_ggx_correlated(n_dot_v: f32, n_dot_l: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = n_dot_l * (n_dot_v * n_dot_v * (1.0 - a2) + a2).sqrt();
    let gl = n_dot_v * (n_dot_l * n_dot_l * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl).max(1e-7)
}

/// A GGX-distributed half vector about +Z for uniform `xi`, and its cosine.
fn sample_ggx(xi: Vec2, alpha: f32) -> (Vec3, f32) {
    let phi = 2.0 * PI * xi.x;
    let cos_theta = ((1.0 - xi.y) / (1.0 + (alpha * alpha - 1.0) * xi.y)).sqrt();
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    (Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta), cos_theta)
}

fn hammersley(i: u32, count: u32) -> Vec2 {
    Vec2::new(i as f32 / count as f32, i.reverse_bits() as f32 * (1.0 / 4_294_967_296.0))
}

/// Columns: a tangent, a bitangent and `n`.
fn tangent_basis(n: Vec3) -> glam::Mat3 {
    let (tangent, bitangent) = n.any_orthonormal_pair();
    glam::Mat3::from_cols(tangent, bitangent, n)
}

/// The environment resampled to [`PYRAMID_WIDTH`] × half, then box-filtered level by level down to
/// 2 × 1: what the projection and the filters read.
pub struct Pyramid {
    levels: Vec<Environment>,
}

impl Pyramid {
    pub fn new(environment: &Environment) -> Self {
        let mut levels = vec![resample(environment, PYRAMID_WIDTH, PYRAMID_WIDTH / 2)];
        while levels[levels.len() - 1].width > 2 {
            let finer = &levels[levels.len() - 1];
            let (width, height) = (finer.width / 2, finer.height / 2);
            let texel = |c: u32, r: u32| Vec3::from(finer.radiance[(r * finer.width + c) as usize]);
            let mut radiance = Vec::with_capacity((width * height) as usize);
            for row in 0..height {
                for column in 0..width {
                    let (c, r) = (column * 2, row * 2);
                    radiance.push(((texel(c, r) + texel(c + 1, r) + texel(c, r + 1) + texel(c + 1, r + 1)) * 0.25).to_array());
                }
            }
            levels.push(Environment { width, height, radiance, sun_disc: false });
        }
        Self { levels }
    }

    /// Trilinear: bilinear within the two levels around `lod`, blended.
    fn sample(&self, dir: Vec3, lod: f32) -> Vec3 {
        let lod = lod.clamp(0.0, (self.levels.len() - 1) as f32);
        let finer = lod.floor() as usize;
        let coarser = (finer + 1).min(self.levels.len() - 1);
        self.levels[finer].sample(dir).lerp(self.levels[coarser].sample(dir), lod - finer as f32)
    }
}

/// `environment` at `width` × `height`: the mean of the texels whose centres fall in each new texel,
/// or where none does (enlarging), the bilinear sample at its centre.
pub fn resample(environment: &Environment, width: u32, height: u32) -> Environment {
    let mut sums = vec![(Vec3::ZERO, 0u32); (width * height) as usize];
    for row in 0..environment.height {
        let target_row = (u64::from(row) * u64::from(height) / u64::from(environment.height)) as u32;
        for column in 0..environment.width {
            let target_column = (u64::from(column) * u64::from(width) / u64::from(environment.width)) as u32;
            let sum = &mut sums[(target_row * width + target_column) as usize];
            sum.0 += Vec3::from(environment.radiance[(row * environment.width + column) as usize]);
            sum.1 += 1;
        }
    }
    let radiance = sums
        .iter()
        .enumerate()
        .map(|(i, &(sum, count))| {
            let (column, row) = (i as u32 % width, i as u32 / width);
            let mean = if count > 0 {
                sum / count as f32
            } else {
                environment.sample(direction_at((column as f32 + 0.5) / width as f32, (row as f32 + 0.5) / height as f32))
            };
            mean.to_array()
        })
        .collect();
    Environment { width, height, radiance, sun_disc: false }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_uniform_environment_gives_its_radiance_as_irradiance_and_specular() {
        let radiance = Vec3::new(0.2, 0.5, 1.5);
        let uniform = Environment::uniform(radiance);
        let pyramid = Pyramid::new(&uniform);
        let sh = irradiance_sh(&pyramid);
        for n in [Vec3::X, Vec3::Y, Vec3::NEG_Z, Vec3::new(1.0, -2.0, 0.5).normalize()] {
            let irradiance = evaluate_irradiance(&sh, n);
            assert!(irradiance.abs_diff_eq(radiance, 2e-3 * radiance.max_element()), "{n}: {irradiance}");
        }
        for level in prefiltered_specular(&pyramid) {
            assert!(level.radiance.iter().all(|&r| Vec3::from(r).abs_diff_eq(radiance, 1e-4)));
        }
    }

    #[test]
    fn irradiance_follows_the_cosine_law_for_light_from_above() {
        // Radiance 1 over the upper hemisphere: irradiance π on an upward normal, 0 downwards and π/2
        // sideways; L2 harmonics hold these within a few percent.
        let mut sky = Environment::uniform(Vec3::ZERO);
        (sky.width, sky.height) = (64, 32);
        sky.radiance = (0..64 * 32).map(|i| if i < 64 * 16 { [1.0; 3] } else { [0.0; 3] }).collect();
        let sh = irradiance_sh(&Pyramid::new(&sky));
        for (n, expected) in [(Vec3::Y, 1.0), (Vec3::NEG_Y, 0.0), (Vec3::X, 0.5)] {
            let irradiance = evaluate_irradiance(&sh, n).x;
            assert!((irradiance - expected).abs() < 0.06, "{n}: {irradiance}");
        }
    }

    #[test]
    fn the_brdf_table_matches_its_limits_and_a_quadrature() {
        let table = brdf_table();
        let at = |n_dot_v: f32, roughness: f32| {
            let size = BRDF_TABLE_SIZE as f32;
            let texel = |x: f32| ((x * size) as u32).min(BRDF_TABLE_SIZE - 1);
            let (i, j) = (texel(n_dot_v), texel(roughness));
            table[(j * BRDF_TABLE_SIZE + i) as usize]
        };
        // Near a mirror, all light is reflected, as Schlick's Fresnel splits it.
        let [scale, bias] = at(1.0, 0.0);
        assert!((scale + bias - 1.0).abs() < 0.01 && bias < 0.01, "{scale} {bias}");
        let [scale, bias] = at(0.3, 0.0);
        assert!((scale + bias - 1.0).abs() < 0.01 && (bias - (1.0f32 - 0.3).powi(5)).abs() < 0.02, "{scale} {bias}");
        // At roughness 1 GGX is uniform (D = 1/π) and Smith's V at n·v = 1 is 1 / (2 (1 + n·l)): the
        // albedo is ∫₀¹ μ / (1 + μ) dμ = 1 − ln 2 (the table's last texel is a little off n·v = 1).
        let [scale, bias] = at(1.0, 1.0);
        assert!((scale + bias - (1.0 - 2f32.ln())).abs() < 0.015, "{scale} {bias}");
        // Elsewhere, a midpoint quadrature of the same integral over the hemisphere of light directions.
        let quadrature = |n_dot_v: f32, roughness: f32| {
            let (alpha, steps) = (roughness * roughness, 200);
            let v = Vec3::new((1.0 - n_dot_v * n_dot_v).sqrt(), 0.0, n_dot_v);
            let (mut scale, mut bias) = (0.0, 0.0);
            for i in 0..steps {
                let theta = (i as f32 + 0.5) / steps as f32 * PI / 2.0;
                for j in 0..2 * steps {
                    let phi = (j as f32 + 0.5) / steps as f32 * PI;
                    let l = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                    let h = (v + l).normalize();
                    let solid_angle = theta.sin() * (PI / 2.0 / steps as f32) * (PI / steps as f32);
                    let f = d_ggx(h.z, alpha) * v_smith_ggx_correlated(n_dot_v, l.z, alpha) * l.z * solid_angle;
                    let fresnel = (1.0 - v.dot(h)).powi(5);
                    (scale, bias) = (scale + (1.0 - fresnel) * f, bias + fresnel * f);
                }
            }
            [scale, bias]
        };
        for (n_dot_v, roughness) in [(0.5, 0.5), (0.9, 0.25), (0.2, 0.3), (0.7, 0.8)] {
            let centre = |x: f32| (((x * BRDF_TABLE_SIZE as f32) as u32) as f32 + 0.5) / BRDF_TABLE_SIZE as f32;
            let [scale, bias] = at(n_dot_v, roughness);
            let [expected_scale, expected_bias] = quadrature(centre(n_dot_v), centre(roughness));
            assert!(
                (scale - expected_scale).abs() < 0.01 && (bias - expected_bias).abs() < 0.01,
                "{n_dot_v} {roughness}: {scale} {bias} vs {expected_scale} {expected_bias}"
            );
        }
    }

    #[test]
    fn the_sheen_albedo_table_matches_a_fine_quadrature_and_is_a_number() {
        let fine = |n_dot_v: f32, roughness: f32| {
            let v = Vec3::new((1.0 - n_dot_v * n_dot_v).sqrt(), 0.0, n_dot_v);
            let steps = 400;
            let mut sum = 0.0f64;
            for i in 0..steps {
                let theta = (i as f32 + 0.5) / steps as f32 * PI / 2.0;
                for j in 0..2 * steps {
                    let phi = (j as f32 + 0.5) / steps as f32 * PI;
                    let l = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                    let solid_angle = theta.sin() * (PI / 2.0 / steps as f32) * (PI / steps as f32);
                    let f = d_charlie((v + l).normalize().z, roughness) * v_sheen(n_dot_v, l.z, roughness) * l.z;
                    sum += f64::from(f * solid_angle);
                }
            }
            sum as f32
        };
        let centre = |x: f32| (((x * BRDF_TABLE_SIZE as f32) as u32) as f32 + 0.5) / BRDF_TABLE_SIZE as f32;
        for (n_dot_v, roughness) in [(0.5, 0.5), (0.9, 0.25), (0.2, 0.3), (0.7, 0.8), (0.1, 0.1), (0.95, 1.0)] {
            let (mu, r) = (centre(n_dot_v), centre(roughness));
            let (table, expected) = (sheen_albedo(mu, r), fine(mu, r));
            assert!((table - expected).abs() < 0.01, "E({mu}, {r}): table {table}, quadrature {expected}");
        }
        // Grazing views of smooth sheens clamp at 1; nothing may be NaN.
        let outside: Vec<(usize, f32)> =
            sheen_albedo_table().iter().copied().enumerate().filter(|(_, e)| !(0.0..=1.0).contains(e)).collect();
        assert!(outside.is_empty(), "sheen albedos outside [0, 1]: {:?}", &outside[..outside.len().min(8)]);
    }
}
