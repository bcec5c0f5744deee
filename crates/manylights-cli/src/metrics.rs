//! Image metrics the error tools (`particle-error`, `light-error`) share.

use manylights::renderer::Image;

pub fn luminance(p: &[f32; 4]) -> f32 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// Peak signal-to-noise ratio of two 8-bit images' colour channels, in dB (infinite when equal).
pub fn psnr(a: &Image<[u8; 4]>, b: &Image<[u8; 4]>) -> f64 {
    let squared: f64 =
        a.pixels.iter().zip(&b.pixels).flat_map(|(p, q)| (0..3).map(move |c| (f64::from(p[c]) - f64::from(q[c])).powi(2))).sum();
    let mse = squared / (a.pixels.len() * 3) as f64;
    10.0 * (255.0 * 255.0 / mse).log10()
}

/// Mean |a − b| of two 8-bit images' colour channels, 0 to 1.
pub fn mean_abs_difference(a: &Image<[u8; 4]>, b: &Image<[u8; 4]>) -> f64 {
    let sum: f64 = a.pixels.iter().zip(&b.pixels).flat_map(|(p, q)| (0..3).map(move |c| f64::from(p[c].abs_diff(q[c])) / 255.0)).sum();
    sum / (a.pixels.len() * 3) as f64
}
