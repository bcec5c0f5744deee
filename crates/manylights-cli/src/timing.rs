//! Statistics over timed frames, shared by `render --timings` and `bench`.

use manylights::renderer::FrameTiming;

/// Median and 95th percentile of a set of milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stat {
    pub median: f64,
    pub p95: f64,
}

impl Stat {
    /// The sorted samples at ranks round(p·(n − 1)) for p = 0.5 and 0.95 (no interpolation); `samples`
    /// must not be empty.
    pub fn of(samples: &[f64]) -> Self {
        let mut sorted = samples.to_vec();
        sorted.sort_by(f64::total_cmp);
        let rank = |p: f64| sorted[((p * (sorted.len() - 1) as f64).round() as usize).min(sorted.len() - 1)];
        Self { median: rank(0.5), p95: rank(0.95) }
    }

    pub fn to_json(self) -> serde_json::Value {
        serde_json::json!({ "median_ms": self.median, "p95_ms": self.p95 })
    }
}

/// Per-frame samples of every pass (in the order passes first appear), of the frame's GPU total and
/// of the CPU's recording time.
pub struct FrameSamples {
    pub passes: Vec<(&'static str, Vec<f64>)>,
    pub gpu_frame: Vec<f64>,
    pub cpu_frame: Vec<f64>,
}

impl FrameSamples {
    pub fn new(frames: &[FrameTiming]) -> Self {
        let mut passes: Vec<(&'static str, Vec<f64>)> = Vec::new();
        for frame in frames {
            for &(name, ms) in &frame.passes {
                match passes.iter_mut().find(|(n, _)| *n == name) {
                    Some((_, samples)) => samples.push(ms),
                    None => passes.push((name, vec![ms])),
                }
            }
        }
        let gpu_frame = frames.iter().map(FrameTiming::gpu_ms).collect();
        let cpu_frame = frames.iter().map(|f| f.cpu_ms).collect();
        Self { passes, gpu_frame, cpu_frame }
    }
}
