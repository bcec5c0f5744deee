//! PNG plots of a sweep: per-frame GPU build time and shading time against the count, log–log, one
//! series per method, with the growth references: n log n for builds, the mean overlap for
//! shading (both anchored at the bvh's measurement they are compared with).

use anyhow::anyhow;
use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::measure::{Measurement, Outcome, PassGroup};
use super::{RunInfo, SweepArg};

const WIDTH: u32 = 1400;
const HEIGHT: u32 = 560;
const METHODS: [(&str, RGBColor); 3] =
    [("bvh", RGBColor(31, 119, 180)), ("clustered", RGBColor(255, 127, 14)), ("brute", RGBColor(44, 160, 44))];
const REFERENCE: RGBColor = RGBColor(128, 128, 128);
/// The name the plots' font is registered under.
const FONT: &str = "hack";

/// Text is drawn with egui's embedded Hack font, so the plots need no system fonts.
fn register_font() -> anyhow::Result<()> {
    static REGISTERED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok =
        *REGISTERED.get_or_init(|| plotters::style::register_font(FONT, FontStyle::Normal, epaint_default_fonts::HACK_REGULAR).is_ok());
    ok.then_some(()).ok_or_else(|| anyhow!("the plot font failed to load"))
}

/// The sweep's plot as PNG bytes.
pub(crate) fn sweep(info: &RunInfo, sweep: SweepArg, rows: &[&Measurement]) -> anyhow::Result<Vec<u8>> {
    register_font()?;
    let what = if sweep == SweepArg::Lights { "lights" } else { "decals" };
    let mut pixels = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let title = format!("{what} sweep: {}, {}×{}, {}", info.device, info.width, info.height, rows[0].config.pipeline.name());
        let root = root.titled(&title, (FONT, 22)).map_err(plot_error)?;
        let (left, right) = root.split_horizontally(WIDTH / 2);
        panel(&left, &format!("GPU build per frame (ms) against {what}"), PassGroup::Build, rows).map_err(plot_error)?;
        panel(&right, &format!("shading pass (ms) against {what}"), PassGroup::Shade, rows).map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&pixels, WIDTH, HEIGHT, image::ExtendedColorType::Rgb8)
        .map_err(|e| anyhow!("encoding a plot: {e}"))?;
    Ok(png)
}

fn plot_error(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("drawing a plot: {e}")
}

/// A method's name, colour and points.
type Line = (&'static str, RGBColor, Vec<(f64, f64)>);

/// (count, median ms) of a method's timed measurements of `group`.
fn series(rows: &[&Measurement], method: &str, group: PassGroup) -> Vec<(f64, f64)> {
    rows.iter()
        .filter(|r| r.method() == method)
        .filter_map(|r| match &r.outcome {
            Outcome::Timed(t) => Some((r.scene.parse::<f64>().ok()?, t.group(group)?.median)),
            _ => None,
        })
        .filter(|&(_, ms)| ms > 0.0)
        .collect()
}

fn panel(
    area: &DrawingArea<BitMapBackend, Shift>,
    caption: &str,
    group: PassGroup,
    rows: &[&Measurement],
) -> Result<(), Box<dyn std::error::Error>> {
    let lines: Vec<Line> = METHODS.iter().map(|&(m, c)| (m, c, series(rows, m, group))).collect();
    let reference = reference(rows, group);
    let points: Vec<(f64, f64)> =
        lines.iter().flat_map(|(_, _, s)| s.iter().copied()).chain(reference.iter().flat_map(|(_, s)| s.iter().copied())).collect();
    if points.is_empty() {
        area.titled(&format!("{caption}: nothing timed"), (FONT, 18))?;
        return Ok(());
    }
    let (x_min, x_max) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    let (y_min, y_max) = points.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d((x_min * 0.8..x_max * 1.25).log_scale(), (y_min * 0.7..y_max * 1.4).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("count")
        .y_desc("ms (median)")
        .x_label_formatter(&|x| if *x >= 1e6 { format!("{:.1}M", x / 1e6) } else { format!("{:.0}k", x / 1e3) })
        .y_label_formatter(&|y| format!("{y:.3}"))
        .label_style((FONT, 14))
        .draw()?;
    for (method, color, points) in lines.into_iter().filter(|(_, _, s)| !s.is_empty()) {
        chart
            .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))?
            .label(method)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        chart.draw_series(points.into_iter().map(|p| Circle::new(p, 4, color.filled())))?;
    }
    if let Some((label, points)) = reference {
        chart
            .draw_series(DashedLineSeries::new(points, 6, 4, REFERENCE.stroke_width(1)))?
            .label(label)
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], REFERENCE.stroke_width(1)));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font((FONT, 14))
        .draw()?;
    Ok(())
}

/// The growth the issue allows, through the bvh's measurements: builds grow at most as n log n (from
/// the smallest count), shading with the mean overlap (through the largest count, where overlaps
/// dominate the per-pixel constant).
fn reference(rows: &[&Measurement], group: PassGroup) -> Option<(&'static str, Vec<(f64, f64)>)> {
    let bvh = series(rows, "bvh", group);
    match group {
        PassGroup::Build => {
            let &(n0, ms0) = bvh.first()?;
            let n_log_n = |n: f64| n * n.log2();
            Some(("n log n", bvh.iter().map(|&(n, _)| (n, ms0 * n_log_n(n) / n_log_n(n0))).collect()))
        }
        _ => {
            let overlaps: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.method() == "bvh")
                .filter_map(|r| Some((r.scene.parse::<f64>().ok()?, r.overlap?)))
                .filter(|&(_, o)| o > 0.0)
                .collect();
            let &(n1, ms1) = bvh.last()?;
            let &(_, o1) = overlaps.iter().find(|(n, _)| *n == n1)?;
            Some(("proportional to mean overlap", overlaps.iter().map(|&(n, o)| (n, ms1 * o / o1)).collect()))
        }
    }
}
