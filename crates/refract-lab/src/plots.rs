//! The plots of a report, drawn as they would appear in a paper (`plotters`, SVG): one colour
//! per method and one marker per backend, the same in every plot; a light grid; the legend
//! beside the data, never over it; units on both axes; a logarithmic axis where the values
//! span more than a decade; error against frame time as one panel per scene with each
//! backend's Pareto front (the methods no other method beats in both error and time).
//!
//! Each SVG (for the page) has a PNG beside it at print resolution ([`PRINT_DPI`]): the same
//! SVG rasterised by `resvg`, its text set in the Ubuntu typeface egui bundles
//! (`epaint_default_fonts`), so the figure looks the same on every machine, fonts installed or
//! not.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use refract_eval::atomic_write::{write_png_rgb8, write_text_atomically};
use refract_eval::metrics::MetricsRecord;
use refract_scene::REGISTRY;

use crate::jobs::JobResult;

/// One colour per method, the same in every plot (registry order): Tableau's 10 colours, then
/// their darker halves, so that the 16 rows of the registry stay distinct.
fn method_color(method: &str) -> RGBColor {
    const PALETTE: [RGBColor; 20] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
        RGBColor(188, 189, 34),
        RGBColor(23, 190, 207),
        RGBColor(16, 60, 90),
        RGBColor(128, 64, 7),
        RGBColor(22, 80, 22),
        RGBColor(107, 20, 20),
        RGBColor(74, 52, 95),
        RGBColor(70, 43, 38),
        RGBColor(114, 60, 97),
        RGBColor(64, 64, 64),
        RGBColor(94, 95, 17),
        RGBColor(12, 95, 104),
    ];
    let index = REGISTRY.iter().position(|m| m.name == method).unwrap_or(0);
    PALETTE[index % PALETTE.len()]
}

/// One marker per backend, the same in every plot: a circle for the CPU, a triangle for the
/// GPU, a square for the reference's tracer (the legend's; `draw_chart` draws the same shapes).
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    backend: &str,
    at: (i32, i32),
    color: RGBColor,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let style = ShapeStyle::from(&color).filled();
    match backend {
        "gpu" => area.draw(&TriangleMarker::new(at, 5, style)),
        "cpu" => area.draw(&Circle::new(at, 4, style)),
        _ => area.draw(&Rectangle::new(
            [(at.0 - 4, at.1 - 4), (at.0 + 4, at.1 + 4)],
            style,
        )),
    }
}

/// A series: legend label, method (its colour), backend (its marker) and `(x, y)` points
/// sorted by `x`.
struct Series {
    label: String,
    method: String,
    backend: String,
    points: Vec<(f64, f64)>,
}

/// The results grouped into series by everything but the `x` axis; `x` and `y` from each result.
fn series(
    results: &[JobResult],
    x: impl Fn(&JobResult) -> Option<f64>,
    y: impl Fn(&MetricsRecord) -> Option<f64>,
    group: impl Fn(&JobResult) -> String,
) -> Vec<Series> {
    let mut groups: BTreeMap<String, Series> = BTreeMap::new();
    for r in results {
        let (Some(m), Some(x)) = (r.metrics.as_ref(), x(r)) else {
            continue;
        };
        let Some(y) = y(m) else { continue };
        let label = group(r);
        groups
            .entry(label.clone())
            .or_insert_with(|| Series {
                label,
                method: r.job.method.clone(),
                backend: r.job.backend.clone(),
                points: Vec::new(),
            })
            .points
            .push((x, y));
    }
    let mut out: Vec<Series> = groups.into_values().collect();
    for s in &mut out {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    out
}

fn label_except(r: &JobResult, skip: &[&str]) -> String {
    let mut parts = Vec::new();
    if !skip.contains(&"method") {
        parts.push(r.job.method.clone());
    }
    if !skip.contains(&"scene") {
        parts.push(r.job.scene.clone());
    }
    if !skip.contains(&"backend") {
        parts.push(r.job.backend.clone());
    }
    if !skip.contains(&"res") {
        parts.push(format!("{}²", r.job.res));
    }
    if let Some(i) = r.job.ior.filter(|_| !skip.contains(&"ior")) {
        parts.push(format!("IOR {i}"));
    }
    for (k, v) in &r.job.params {
        if !skip.contains(&k.as_str()) {
            parts.push(format!("{k}={v}"));
        }
    }
    parts.join(" ")
}

/// An axis over `values`: logarithmic (base 10, the values' logarithms drawn on a linear axis
/// labelled back in the values) when they are all positive and span more than a decade.
#[derive(Clone, Copy)]
struct Axis {
    log: bool,
    lo: f64,
    hi: f64,
}

impl Axis {
    fn over(values: impl Iterator<Item = f64>, from_zero: bool) -> Self {
        let (mut lo, mut hi) = (f64::MAX, f64::MIN);
        for v in values {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
        if lo > hi {
            (lo, hi) = (0.0, 1.0);
        }
        let log = lo > 0.0 && hi / lo > 10.0;
        let (lo, hi) = if log {
            (lo.log10(), hi.log10())
        } else {
            (lo, hi)
        };
        let pad = if hi > lo {
            0.06 * (hi - lo)
        } else {
            0.5 * lo.abs().max(1.0)
        };
        let lo = if from_zero && !log {
            (lo - pad).max(0.0)
        } else {
            lo - pad
        };
        Self {
            log,
            lo,
            hi: hi + pad,
        }
    }

    fn map(self, v: f64) -> f64 {
        if self.log { v.log10() } else { v }
    }

    fn label(self, v: f64) -> String {
        let v = if self.log { 10f64.powf(v) } else { v };
        if v == 0.0 {
            "0".to_owned()
        } else if v.abs() >= 100.0 {
            format!("{v:.0}")
        } else if v.abs() >= 1.0 {
            format!("{v:.1}")
        } else {
            format!("{v:.3}")
        }
    }

    fn describe(self, text: &str) -> String {
        if self.log {
            format!("{text}, log scale")
        } else {
            text.to_owned()
        }
    }
}

/// The height in pixels [`draw_legend`] takes.
fn legend_height(methods: &[String], backends: &[String]) -> u32 {
    (28 + 19 * (methods.len() + backends.len()) + 20) as u32
}

/// The legend beside the plots: each method's colour, then each backend's marker.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    methods: &[String],
    backends: &[String],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let text = ("sans-serif", 13).into_font().color(&BLACK);
    let mut y = 28;
    for method in methods {
        let color = method_color(method);
        area.draw(&Rectangle::new([(6, y - 5), (22, y + 5)], color.filled()))?;
        area.draw(&Text::new(method.clone(), (30, y - 7), text.clone()))?;
        y += 19;
    }
    y += 10;
    for backend in backends {
        draw_marker(area, backend, (14, y), RGBColor(60, 60, 60))?;
        area.draw(&Text::new(
            backend.to_uppercase(),
            (30, y - 7),
            text.clone(),
        ))?;
        y += 19;
    }
    Ok(())
}

/// Draws one chart into `area`: a light grid, labelled axes, the series as markers (joined by
/// lines with `lines`), and `front` as a dashed line per backend.
#[allow(clippy::too_many_arguments)]
fn draw_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[&Series],
    lines: bool,
    front: bool,
    (x, y): (Axis, Axis),
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 16))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(58)
        .build_cartesian_2d(x.lo..x.hi, y.lo..y.hi)?;
    chart
        .configure_mesh()
        .bold_line_style(RGBColor(222, 222, 222))
        .light_line_style(RGBColor(243, 243, 243))
        .x_desc(x.describe(x_label))
        .y_desc(y.describe(y_label))
        .x_label_formatter(&|v| x.label(*v))
        .y_label_formatter(&|v| y.label(*v))
        .axis_desc_style(("sans-serif", 13))
        .draw()?;
    let to = |p: &(f64, f64)| (x.map(p.0), y.map(p.1));
    if front {
        let mut backends: Vec<&str> = series.iter().map(|s| s.backend.as_str()).collect();
        backends.sort_unstable();
        backends.dedup();
        for backend in backends {
            let points: Vec<(f64, f64)> = series
                .iter()
                .filter(|s| s.backend == backend)
                .flat_map(|s| s.points.iter().copied())
                .collect();
            let line = pareto_front(&points);
            chart.draw_series(DashedLineSeries::new(
                line.iter().map(to),
                5,
                4,
                ShapeStyle::from(&RGBColor(90, 90, 90)).stroke_width(1),
            ))?;
        }
    }
    for s in series {
        let color = method_color(&s.method);
        if lines {
            chart.draw_series(LineSeries::new(
                s.points.iter().map(to),
                color.stroke_width(2),
            ))?;
        }
        let style = ShapeStyle::from(&color).filled();
        let points = s.points.iter().map(to);
        // The markers of `draw_marker`, in the chart's coordinates.
        match s.backend.as_str() {
            "gpu" => {
                chart.draw_series(points.map(|p| TriangleMarker::new(p, 5, style)))?;
            }
            "cpu" => {
                chart.draw_series(points.map(|p| Circle::new(p, 4, style)))?;
            }
            _ => {
                chart.draw_series(
                    points.map(|p| EmptyElement::at(p) + Rectangle::new([(-4, -4), (4, 4)], style)),
                )?;
            }
        }
    }
    Ok(())
}

/// The points no other point beats in both coordinates (lower `x` and lower `y`), by `x`.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut sorted: Vec<(f64, f64)> = points.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut front: Vec<(f64, f64)> = Vec::new();
    for p in sorted {
        if front.last().is_none_or(|last| p.1 < last.1) {
            front.push(p);
        }
    }
    front
}

/// The methods and backends of `series`, in registry and name order.
fn legend_entries(series: &[Series]) -> (Vec<String>, Vec<String>) {
    let mut methods: Vec<String> = series.iter().map(|s| s.method.clone()).collect();
    methods.sort_by_key(|m| {
        REGISTRY
            .iter()
            .position(|r| r.name == m)
            .unwrap_or(usize::MAX)
    });
    methods.dedup();
    let mut backends: Vec<String> = series.iter().map(|s| s.backend.clone()).collect();
    backends.sort();
    backends.dedup();
    (methods, backends)
}

/// Draws one SVG plot with the legend beside it; `lines` joins each series' points.
fn plot(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    lines: bool,
) -> crate::Result<()> {
    let axes = (
        Axis::over(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
            false,
        ),
        Axis::over(
            series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
            true,
        ),
    );
    let (methods, backends) = legend_entries(series);
    let height = legend_height(&methods, &backends).max(480);
    draw_svg(path, (900, height), |root| {
        let (chart, legend) = root.split_horizontally(900 - 170);
        let all: Vec<&Series> = series.iter().collect();
        draw_chart(&chart, title, x_label, y_label, &all, lines, false, axes)?;
        draw_legend(&legend, &methods, &backends)?;
        Ok(())
    })
}

/// The resolution of the PNG beside each SVG: the SVG's pixels are CSS pixels (96 per inch).
pub const PRINT_DPI: f32 = 300.0;

/// The PNG file beside SVG `svg`.
pub fn print_png(svg: &str) -> String {
    match svg.strip_suffix(".svg") {
        Some(stem) => format!("{stem}.png"),
        None => format!("{svg}.png"),
    }
}

/// Rasterises the SVG `svg` (the text of the plot `png` is beside) into `png` at
/// [`PRINT_DPI`] on white.
fn write_print_png(svg: &str, png: &Path) -> crate::Result<()> {
    let cannot = |what: &str, e: &dyn std::fmt::Display| {
        crate::LabError::invalid(format_args!("{}: cannot {what}: {e}", png.display()))
    };
    let mut options = resvg::usvg::Options::default();
    {
        let fonts = options.fontdb_mut();
        fonts.load_font_data(epaint_default_fonts::UBUNTU_LIGHT.to_vec());
        fonts.set_sans_serif_family("Ubuntu");
    }
    options.font_family = "Ubuntu".to_owned();
    let tree = resvg::usvg::Tree::from_str(svg, &options).map_err(|e| cannot("parse", &e))?;
    let scale = PRINT_DPI / 96.0;
    let empty = || crate::LabError::invalid(format_args!("{}: an empty plot", png.display()));
    let size = tree
        .size()
        .to_int_size()
        .scale_by(scale)
        .ok_or_else(empty)?;
    let mut pixmap =
        resvg::tiny_skia::Pixmap::new(size.width(), size.height()).ok_or_else(empty)?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    // Opaque pixels: the premultiplied RGBA is the straight RGBA; stored as RGB.
    let rgb: Vec<u8> = pixmap
        .data()
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    write_png_rgb8(png, size.width(), size.height(), &rgb).map_err(|e| cannot("write", &e))
}

/// An SVG of `size` at `path` (a white page `draw` draws on) and its print PNG beside it
/// ([`print_png`]), both written atomically; a drawing error names the file.
fn draw_svg(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), Box<dyn std::error::Error>>,
) -> crate::Result<()> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        let drawn = (|| -> Result<(), Box<dyn std::error::Error>> {
            root.fill(&WHITE)?;
            draw(&root)?;
            root.present()?;
            Ok(())
        })();
        drawn.map_err(|e| {
            crate::LabError::invalid(format_args!(
                "{}: cannot draw the plot: {e}",
                path.display()
            ))
        })?;
    }
    write_text_atomically(path, &svg)?;
    write_print_png(&svg, &path.with_extension("png"))
}

/// Error against frame time, one panel per scene (each with its own axes: scenes differ by
/// decades in time), each backend's Pareto front dashed, one legend beside the panels.
fn plot_per_scene(path: &Path, title: &str, panels: &[(String, Vec<Series>)]) -> crate::Result<()> {
    let columns = panels.len().clamp(1, 4);
    let rows = panels.len().div_ceil(columns).max(1);
    let (panel_w, panel_h) = (330u32, 260u32);
    let width = panel_w * columns as u32 + 170;
    let every: Vec<Series> = panels
        .iter()
        .flat_map(|(_, series)| series.iter())
        .map(|s| Series {
            label: s.label.clone(),
            method: s.method.clone(),
            backend: s.backend.clone(),
            points: Vec::new(),
        })
        .collect();
    let (methods, backends) = legend_entries(&every);
    let height = (panel_h * rows as u32 + 36).max(legend_height(&methods, &backends) + 36);
    draw_svg(path, (width, height), |root| {
        let root = root.titled(title, ("sans-serif", 18))?;
        let (grid, legend) = root.split_horizontally(width - 170);
        let areas = grid.split_evenly((rows, columns));
        for ((scene, series), panel) in panels.iter().zip(areas.iter()) {
            let mine: Vec<&Series> = series.iter().collect();
            let axes = (
                Axis::over(
                    mine.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
                    false,
                ),
                Axis::over(mine.iter().flat_map(|s| s.points.iter().map(|p| p.1)), true),
            );
            draw_chart(
                panel,
                scene,
                "frame time (ms)",
                "mean FLIP",
                &mine,
                false,
                true,
                axes,
            )?;
        }
        draw_legend(&legend, &methods, &backends)?;
        Ok(())
    })
}

/// The plots the results support: an axis with at least two values gets its plot. Returns
/// `(file, title)` pairs.
pub fn write_plots(out: &Path, results: &[JobResult]) -> crate::Result<Vec<(String, String)>> {
    let distinct = |f: &dyn Fn(&JobResult) -> Option<String>| {
        let mut values: Vec<String> = results.iter().filter_map(f).collect();
        values.sort();
        values.dedup();
        values.len()
    };
    let flip = |m: &MetricsRecord| m.flip_mean;
    let mut plots = Vec::new();
    let mut add = |file: &str, title: &str, x: &str, y: &str, s: Vec<Series>, lines: bool| {
        if s.is_empty() {
            return Ok(());
        }
        plot(&out.join(file), title, x, y, &s, lines)?;
        plots.push((file.to_owned(), title.to_owned()));
        Ok::<(), crate::LabError>(())
    };
    if distinct(&|r| r.job.ior.map(|i| i.to_string())) >= 2 {
        add(
            "error-vs-ior.svg",
            "Error vs index of refraction (Wyman 2005b Fig. 11)",
            "index of refraction",
            "mean FLIP (refractor pixels)",
            series(
                results,
                |r| r.job.ior.map(f64::from),
                flip,
                |r| label_except(r, &["ior"]),
            ),
            true,
        )?;
    }
    // Every numeric method parameter swept over at least two values (seeds K, iterations, and
    // whatever parameters later methods add: linear/secant steps, tessellation).
    let mut names: Vec<&String> = results.iter().flat_map(|r| r.job.params.keys()).collect();
    names.sort();
    names.dedup();
    for name in names {
        let numeric = results
            .iter()
            .filter_map(|r| r.job.params.get(name))
            .all(|v| v.parse::<f64>().is_ok());
        // Swept: one method takes two values or more (in a comparison, `res` of the distance
        // maps and of PVRR differ, but neither is swept).
        let swept = results.iter().any(|a| {
            results.iter().any(|b| {
                a.job.method == b.job.method
                    && a.job
                        .params
                        .get(name)
                        .is_some_and(|v| b.job.params.get(name).is_some_and(|w| v != w))
            })
        });
        if !numeric || !swept {
            continue;
        }
        let title = if name == "seeds" {
            "Error vs seeds K (iterative-seeded)".to_owned()
        } else {
            format!("Error vs {name}")
        };
        add(
            &format!("error-vs-{}.svg", safe_name(name)),
            &title,
            name,
            "mean FLIP (refractor pixels)",
            series(
                results,
                |r| r.job.params.get(name).and_then(|v| v.parse().ok()),
                flip,
                |r| label_except(r, &[name.as_str()]),
            ),
            true,
        )?;
    }
    if distinct(&|r| Some(r.job.res.to_string())) >= 2 {
        add(
            "time-vs-resolution.svg",
            "Frame time vs resolution, per backend",
            "pixels (millions)",
            "median frame time (ms)",
            series(
                results,
                |r| Some(f64::from(r.job.res) * f64::from(r.job.res) / 1e6),
                |m| m.ms_per_frame,
                |r| label_except(r, &["res"]),
            ),
            true,
        )?;
    }
    // Error against frame time: a panel per scene.
    let mut scenes: Vec<&str> = Vec::new();
    for r in results.iter().filter(|r| r.metrics.is_some()) {
        if !scenes.contains(&r.job.scene.as_str()) {
            scenes.push(&r.job.scene);
        }
    }
    let panels: Vec<(String, Vec<Series>)> = scenes
        .iter()
        .map(|scene| {
            let mine: Vec<JobResult> = results
                .iter()
                .filter(|r| r.job.scene == *scene)
                .cloned()
                .collect();
            let series = series(
                &mine,
                |r| r.metrics.as_ref().and_then(|m| m.ms_per_frame),
                flip,
                |r| format!("{} {}", r.job.method, r.job.backend),
            );
            ((*scene).to_owned(), series)
        })
        .filter(|(_, series)| !series.is_empty())
        .collect();
    if !panels.is_empty() {
        let (file, title) = (
            "error-vs-time.svg",
            "Error vs frame time per scene (dashed: each backend's Pareto front)",
        );
        plot_per_scene(&out.join(file), title, &panels)?;
        plots.push((file.to_owned(), title.to_owned()));
    }
    Ok(plots)
}

/// A parameter name as a file name part.
fn safe_name(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The front keeps the points no other point beats in both time and error.
    #[test]
    fn the_pareto_front_keeps_the_unbeaten_points() {
        let points = [
            (5.0, 0.3),
            (1.0, 0.5),
            (2.0, 0.6),
            (3.0, 0.2),
            (10.0, 0.2),
            (20.0, 0.1),
        ];
        assert_eq!(
            pareto_front(&points),
            vec![(1.0, 0.5), (3.0, 0.2), (20.0, 0.1)]
        );
        assert!(pareto_front(&[]).is_empty());
    }

    /// An axis is logarithmic exactly when its positive values span more than a decade.
    #[test]
    fn axes_turn_logarithmic_past_a_decade() {
        assert!(Axis::over([1.0, 10.5].into_iter(), false).log);
        assert!(!Axis::over([1.0, 9.0].into_iter(), false).log);
        assert!(!Axis::over([0.0, 100.0].into_iter(), true).log);
        let log = Axis::over([1.0, 1000.0].into_iter(), false);
        assert_eq!(log.label(log.map(100.0)), "100");
    }
}
