//! The report of `niebla compare`: one self-contained HTML file with the
//! images side by side at one exposure, false-color maps of the per-pixel
//! relative error, a log-log plot of relative MSE against time (SVG drawn by
//! `plotters`) and a table of time, spp and error. Images are embedded as
//! base64 PNG and the plots as inline SVG, so the file needs nothing else.

use std::fmt::Write as _;

use base64::Engine as _;
use niebla::color::rgb_to_srgb8;
use niebla::film::Image;
use plotters::prelude::*;
use plotters::style::colors::colormaps::ViridisRGB;

use super::{Reference, Run};
use crate::error::CliError;

/// Decades of relative error the error maps' color scale spans.
const ERROR_MAP_DECADES: f64 = 3.0;

/// The whole HTML document.
pub(super) fn report_html(
    title: &str,
    reference: &Reference,
    runs: &[Run],
    exposure: f32,
    budget_seconds: f64,
) -> Result<String, CliError> {
    let (w, h) = (reference.image.width, reference.image.height);
    let maps: Vec<Vec<f64>> = runs.iter().map(|r| relative_error_map(&r.image, &reference.image)).collect();
    let (error_low, error_high) = error_range(&maps);
    let threads = rayon_threads();
    let mut html = String::new();
    let _ = write!(
        html,
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>niebla compare: {title}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 1.5em; color: #222; }}
h1 {{ font-size: 1.4em; }} h2 {{ font-size: 1.15em; margin-top: 1.6em; }}
.row {{ display: flex; flex-wrap: wrap; gap: 14px; align-items: flex-start; }}
figure {{ margin: 0; }} figcaption {{ font-size: 0.85em; text-align: center; margin-top: 4px; }}
img {{ display: block; image-rendering: pixelated; max-width: 100%; height: auto; }}
table {{ border-collapse: collapse; font-size: 0.9em; }}
th, td {{ border: 1px solid #bbb; padding: 4px 10px; text-align: right; }}
th:first-child, td:first-child, td.settings {{ text-align: left; }}
td.settings {{ font-family: monospace; font-size: 0.85em; }}
.note {{ font-size: 0.85em; color: #555; max-width: 60em; }}
.column {{ max-width: 720px; }} figcaption.note {{ text-align: left; }}
</style>
</head>
<body>
<h1>niebla compare: {title}</h1>
<p class="note">{w}x{h} pixels; time budget {budget_seconds} s per integrator on {threads} threads;
reference: {reference}. Images at exposure {exposure:+} stops (sRGB).</p>
"#,
        title = escape(title),
        reference = escape(&reference.description),
    );

    // Table and convergence plot, side by side.
    html.push_str(
        "<div class=\"row\">\n<div class=\"column\">\n<h2>Time, samples and error</h2>\n<table>\n\
         <tr><th>integrator</th><th>settings</th><th>spp</th><th>time (s)</th><th>relative MSE</th>\
         <th>relative MSE &times; time (s)</th></tr>\n",
    );
    for run in runs {
        let last = run.last();
        let _ = writeln!(
            html,
            "<tr><td>{}</td><td class=\"settings\">{}</td><td>{}</td><td>{:.2}</td><td>{:.3e}</td><td>{:.3e}</td></tr>",
            escape(&run.label),
            escape(&format!("{:?}", run.settings)),
            last.spp,
            last.seconds,
            last.relative_mse,
            last.relative_mse * last.seconds
        );
    }
    html.push_str(
        "</table>\n<p class=\"note\">Relative MSE: the mean over pixels and channels of (x &minus; r)&sup2; / \
         (r&sup2; + &epsilon;), &epsilon; = (0.01 mean(r))&sup2;, r the reference. Relative MSE &times; time is \
         the inverse of the efficiency: lower is better.</p>\n<p class=\"note\">Convergence (right): relative \
         MSE after every progressive pass (each pass doubles the samples per pixel) against render time, \
         log-log; the dashed line has slope &minus;1, the rate of an unbiased Monte Carlo estimator. A curve \
         that flattens has reached its bias (or the reference's noise).</p>\n</div>\n",
    );
    html.push_str(&convergence_svg(runs)?);
    html.push_str("</div>\n");

    // Images.
    html.push_str("<h2>Images</h2>\n<div class=\"row\">\n");
    let figure = |html: &mut String, image: &Image, caption: &str, alt: &str| -> Result<(), CliError> {
        let png = png_base64(image.width, image.height, &srgb_bytes(image, exposure))?;
        let _ = writeln!(
            html,
            "<figure><img class=\"render\" src=\"data:image/png;base64,{png}\" width=\"{}\" height=\"{}\" \
             alt=\"{}\"><figcaption>{}</figcaption></figure>",
            image.width,
            image.height,
            escape(alt),
            escape(caption)
        );
        Ok(())
    };
    figure(&mut html, &reference.image, "reference", "reference")?;
    for run in runs {
        let last = run.last();
        let caption = format!("{}: {} spp, {:.2} s", run.label, last.spp, last.seconds);
        figure(&mut html, &run.image, &caption, &run.label)?;
    }
    html.push_str("</div>\n");

    // Error maps, each under its image; the color bar under the reference.
    html.push_str("<h2>Relative error</h2>\n<div class=\"row\">\n");
    let _ = writeln!(
        html,
        "<figure style=\"width: {w}px\">{}<figcaption class=\"note\">Per pixel: sqrt(mean over channels of \
         (x &minus; r)&sup2; / (r&sup2; + &epsilon;)), on one logarithmic color scale (viridis) for all maps.\
         </figcaption></figure>",
        colorbar_svg(error_low, error_high, w.clamp(240, 600))?
    );
    for (run, map) in runs.iter().zip(&maps) {
        let rgb = false_color(map, error_low, error_high);
        let png = png_base64(w, h, &rgb)?;
        let _ = writeln!(
            html,
            "<figure><img class=\"error-map\" src=\"data:image/png;base64,{png}\" width=\"{w}\" height=\"{h}\" \
             alt=\"relative error of {label}\"><figcaption>{label}: relative MSE {mse:.3e}</figcaption></figure>",
            label = escape(&run.label),
            mse = run.last().relative_mse
        );
    }
    html.push_str("</div>\n");
    html.push_str(CHECK_SCRIPT);
    html.push_str("</body>\n</html>\n");
    Ok(html)
}

/// Marks on `<body>` how many images decoded and how many plots are there,
/// so that a headless browser's DOM dump shows whether the report renders.
const CHECK_SCRIPT: &str = r#"<script>
window.addEventListener("load", function () {
  var images = document.images, decoded = 0;
  for (var i = 0; i < images.length; i++) {
    if (images[i].complete && images[i].naturalWidth > 0) decoded++;
  }
  document.body.setAttribute("data-images", String(images.length));
  document.body.setAttribute("data-images-decoded", String(decoded));
  document.body.setAttribute("data-plots", String(document.querySelectorAll("svg.plot").length));
});
</script>
"#;

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// HTML-escapes text.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// 8-bit sRGB of an image at `exposure` stops.
fn srgb_bytes(image: &Image, exposure: f32) -> Vec<u8> {
    image.pixels.iter().flat_map(|&p| rgb_to_srgb8(p, exposure)).collect()
}

/// An RGB8 image as a base64 PNG.
fn png_base64(width: u32, height: u32, rgb: &[u8]) -> Result<String, CliError> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(rgb)?;
        writer.finish()?;
    }
    Ok(base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// Per-pixel relative error `sqrt(mean_c (x - r)^2 / (r^2 + eps))` with the
/// `eps` of [`Image::relative_mse`], so that the mean of its square is the
/// relative MSE.
fn relative_error_map(image: &Image, reference: &Image) -> Vec<f64> {
    let eps = (0.01 * reference.mean().average() as f64).powi(2).max(f64::MIN_POSITIVE);
    image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(x, r)| {
            let sum: f64 = (0..3).map(|c| (x[c] as f64 - r[c] as f64).powi(2) / ((r[c] as f64).powi(2) + eps)).sum();
            (sum / 3.0).sqrt()
        })
        .collect()
}

/// The color scale of the error maps: [`ERROR_MAP_DECADES`] decades ending
/// at the decade above the largest 99th percentile of the maps.
fn error_range(maps: &[Vec<f64>]) -> (f64, f64) {
    let mut top = 0.0f64;
    for map in maps {
        let mut values: Vec<f64> = map.iter().copied().filter(|v| v.is_finite()).collect();
        if values.is_empty() {
            continue;
        }
        let k = ((values.len() - 1) as f64 * 0.99) as usize;
        let (_, p99, _) = values.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
        top = top.max(*p99);
    }
    let high = if top > 0.0 { 10f64.powf(top.log10().ceil()) } else { 1.0 };
    (high / 10f64.powf(ERROR_MAP_DECADES), high)
}

/// Viridis colors of `values` on a log scale from `low` to `high` (clamped).
fn false_color(values: &[f64], low: f64, high: f64) -> Vec<u8> {
    let (a, b) = (low.log10(), high.log10());
    values
        .iter()
        .flat_map(|&v| {
            let t = if v > 0.0 { ((v.log10() - a) / (b - a)).clamp(0.0, 1.0) } else { 0.0 };
            let RGBColor(r, g, b) = ViridisRGB.get_color(t as f32);
            [r, g, b]
        })
        .collect()
}

/// Axis ticks at 1, 2 and 5 times the powers of ten within `[low, high]`,
/// thinned to the decades when there would be more than a dozen.
fn log_ticks(low: f64, high: f64) -> Vec<f64> {
    let decades = (low.log10().floor() as i32)..=(high.log10().ceil() as i32);
    let within = |v: &f64| *v >= low * (1.0 - 1e-9) && *v <= high * (1.0 + 1e-9);
    let all: Vec<f64> =
        decades.clone().flat_map(|d| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(d))).filter(within).collect();
    if all.len() <= 12 {
        return all;
    }
    decades.map(|d| 10f64.powi(d)).filter(within).collect()
}

/// A tick label with at most three significant digits: `0.3`, `20`, `1e-4`.
fn tick_label(v: f64) -> String {
    if v > 0.0 && !(1e-3..1e5).contains(&v) {
        return format!("{v:.0e}");
    }
    let decimals = (2 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Adds `class="plot"` to an SVG document made by plotters, for the check
/// script and for styling.
fn mark_plot(svg: String) -> String {
    svg.replacen("<svg ", "<svg class=\"plot\" ", 1)
}

fn plot_error<E: std::error::Error + Send + Sync>(e: DrawingAreaErrorKind<E>) -> CliError {
    CliError::Plot(e.to_string())
}

/// The color bar of the error maps.
fn colorbar_svg(low: f64, high: f64, width: u32) -> Result<String, CliError> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, 86)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let x_axis = (low..high).log_scale().with_key_points(log_ticks(low, high));
        let mut chart = ChartBuilder::on(&root)
            .margin(10)
            .margin_left(24)
            .margin_right(24)
            .x_label_area_size(44)
            .build_cartesian_2d(x_axis, 0.0..1.0)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .disable_y_mesh()
            .disable_y_axis()
            .disable_x_mesh()
            .x_desc("relative error per pixel")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .x_label_formatter(&|v| tick_label(*v))
            .draw()
            .map_err(plot_error)?;
        let steps = 128;
        let (a, b) = (low.log10(), high.log10());
        chart
            .draw_series((0..steps).map(|i| {
                let x0 = 10f64.powf(a + (b - a) * i as f64 / steps as f64);
                let x1 = 10f64.powf(a + (b - a) * (i + 1) as f64 / steps as f64);
                let color = ViridisRGB.get_color((i as f32 + 0.5) / steps as f32);
                Rectangle::new([(x0, 0.0), (x1, 1.0)], color.filled())
            }))
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    Ok(mark_plot(svg))
}

/// Line colors of the convergence plot (Tableau 10: distinct, and legible on white).
const SERIES_COLORS: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// Relative MSE against time, log-log, one line per integrator.
fn convergence_svg(runs: &[Run]) -> Result<String, CliError> {
    let points: Vec<Vec<(f64, f64)>> = runs
        .iter()
        .map(|r| {
            r.curve
                .iter()
                .filter(|p| p.seconds > 0.0 && p.relative_mse > 0.0 && p.relative_mse.is_finite())
                .map(|p| (p.seconds, p.relative_mse))
                .collect()
        })
        .collect();
    let all = || points.iter().flatten();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN_POSITIVE, f64::MAX, f64::MIN_POSITIVE);
    for &(x, y) in all() {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (0.01, 1.0, 1e-3, 1.0);
    }
    let (x0, x1, y0, y1) = (x0 / 1.5, x1 * 1.5, y0 / 2.0, y1 * 2.0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let x_axis = (x0..x1).log_scale().with_key_points(log_ticks(x0, x1));
        let y_axis = (y0..y1).log_scale().with_key_points(log_ticks(y0, y1));
        let mut chart = ChartBuilder::on(&root)
            .caption("relative MSE against render time", ("sans-serif", 18))
            .margin(14)
            .margin_right(24)
            .x_label_area_size(48)
            .y_label_area_size(76)
            .build_cartesian_2d(x_axis, y_axis)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_desc("render time (s)")
            .y_desc("relative MSE")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .light_line_style(WHITE)
            .bold_line_style(BLACK.mix(0.12))
            .x_label_formatter(&|v| tick_label(*v))
            .y_label_formatter(&|v| tick_label(*v))
            .draw()
            .map_err(plot_error)?;
        // Slope -1 through the first integrator's first point.
        if let Some(&(x, y)) = points.iter().find_map(|p| p.first()) {
            let line = [(x0, y * x / x0), (x1, y * x / x1)];
            chart.draw_series(DashedLineSeries::new(line, 6, 4, BLACK.mix(0.35).into())).map_err(plot_error)?;
        }
        for (i, (run, pts)) in runs.iter().zip(&points).enumerate() {
            let (r, g, b) = SERIES_COLORS[i % SERIES_COLORS.len()];
            let color = RGBColor(r, g, b);
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2)))
                .map_err(plot_error)?
                .label(run.label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 22, y)], color.stroke_width(2)));
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled()))).map_err(plot_error)?;
        }
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 14))
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    Ok(mark_plot(svg))
}
