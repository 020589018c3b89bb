//! Plots (cargo feature `report`): a [`Figure`] of log–log panels with a legend strip, lines of
//! series on log–log axes ([`lines`]) and a curve on linear axes ([`curve`]), drawn by plotters
//! into PNG and SVG in pure Rust — the PNG's text is rasterised from an embedded DejaVu Sans (no
//! fontconfig or freetype), the SVG names the font family. The legend is drawn in a strip below
//! the panels, so it never covers data.

use plotters::coord::Shift;
use plotters::coord::combinators::{BindKeyPoints, WithKeyPoints};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Once;
use thiserror::Error;

/// A plot that could not be drawn.
#[derive(Debug, Error)]
#[error("cannot draw {path}: {message}")]
pub struct PlotError {
    /// The image.
    pub path: PathBuf,
    /// Why.
    pub message: String,
}

/// The font family every text uses; registered once from the embedded DejaVu Sans.
const FONT: &str = "sans-serif";

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // the bytes are a valid TrueType font: registration cannot fail
        let _ = plotters::style::register_font(FONT, FontStyle::Normal, dejavu::sans::regular());
    });
}

/// Marker shapes, one per series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Marker {
    /// ●
    Circle,
    /// ▲
    Triangle,
    /// ■
    Square,
    /// ✕
    Cross,
}

/// One line of a panel.
#[derive(Clone, Debug)]
pub struct Series {
    /// Its name in the legend.
    pub name: String,
    /// Its colour.
    pub color: RGBColor,
    /// Its markers.
    pub marker: Marker,
    /// Points joined by the line (filled markers).
    pub line: Vec<(f64, f64)>,
    /// Points drawn alone with open markers (runs that stopped short).
    pub open: Vec<(f64, f64)>,
    /// A dashed reference line without markers.
    pub dashed: bool,
    /// Error bars: vertical segments (x, y_low, y_high), e.g. a value's uncertainty.
    pub bars: Vec<(f64, f64, f64)>,
}

/// One panel: a log–log chart.
#[derive(Clone, Debug)]
pub struct Panel {
    /// The caption above it.
    pub caption: String,
    /// The x axis' label.
    pub x_desc: String,
    /// The y axis' label.
    pub y_desc: String,
    /// Its lines.
    pub series: Vec<Series>,
}

/// A figure: a title, panels side by side, a legend strip.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The title.
    pub title: String,
    /// The panels, left to right.
    pub panels: Vec<Panel>,
    /// Series shown in the legend (by name, first occurrence).
    pub legend: Vec<Series>,
    /// An extra legend line (what open markers mean).
    pub legend_note: Option<String>,
    /// Draw an open marker before the note.
    pub note_marker: bool,
    /// Width and height in pixels.
    pub size: (u32, u32),
}

/// The colours of series, in turn.
pub const COLORS: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
];
/// The markers of series, in turn.
pub const MARKERS: [Marker; 4] = [Marker::Circle, Marker::Triangle, Marker::Square, Marker::Cross];
/// The colour of reference lines.
pub const GREY: RGBColor = RGBColor(110, 110, 110);

fn plot_error(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError { path: path.to_path_buf(), message: e.to_string() }
}

/// Draws `fig` into a PNG and an SVG file.
pub fn render(fig: &Figure, png: &Path, svg: &Path) -> Result<(), PlotError> {
    register_font();
    {
        let root = BitMapBackend::new(png, fig.size).into_drawing_area();
        draw(fig, &root).map_err(|e| plot_error(png, e))?;
        root.present().map_err(|e| plot_error(png, e))?;
    }
    let root = SVGBackend::new(svg, fig.size).into_drawing_area();
    draw(fig, &root).map_err(|e| plot_error(svg, e))?;
    root.present().map_err(|e| plot_error(svg, e))?;
    Ok(())
}

/// A label of a log axis: only at mantissas 1, 2 and 5 (the other grid lines stay
/// unlabelled), plain decimals between 0.01 and 10⁴, else `1e-5`.
fn log_label(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || !a.is_finite() {
        return String::new();
    }
    let m = a / 10f64.powf(a.log10().floor());
    if ![1.0, 2.0, 5.0, 10.0].iter().any(|k| (m - k).abs() < 1e-6 * k) {
        return String::new();
    }
    if (1e-2..1e4).contains(&a) {
        let s = format!("{x:.2}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        let s = format!("{x:.0e}");
        s.replace("e-0", "e-").replace("e0", "e")
    }
}

/// The grid of a log axis from `lo` to `hi`: 1…9 × 10^k when it spans at most 4 decades,
/// the decades alone otherwise ([`log_label`] labels 1, 2 and 5 of them).
fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let fine = (hi / lo).log10() <= 4.0;
    let mut ticks = Vec::new();
    for k in (lo.log10().floor() as i32)..=(hi.log10().ceil() as i32) {
        for m in 1..=9 {
            let v = f64::from(m) * 10f64.powi(k);
            if (fine || m == 1) && v >= lo * (1.0 - 1e-12) && v <= hi * (1.0 + 1e-12) {
                ticks.push(v);
            }
        }
    }
    ticks
}

/// A log range around `values`: padded by the factor `pad` on each side, at least a decade.
fn padded(values: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && *v > 0.0) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.1, 10.0);
    }
    let (lo, hi) = (lo / pad, hi * pad);
    if hi / lo < 10.0 {
        let mid = (lo * hi).sqrt();
        (mid / 10f64.sqrt(), mid * 10f64.sqrt())
    } else {
        (lo, hi)
    }
}

/// Legend entry positions (left end of the sample line, text baseline row) in a strip of
/// width `w`, and the strip's height.
fn legend_layout<DB: DrawingBackend>(
    fig: &Figure,
    area: &DrawingArea<DB, Shift>,
    w: u32,
) -> Result<(Vec<(i32, i32)>, u32), String> {
    let s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let font: TextStyle = (FONT, 17).into_text_style(area);
    let (mut x, mut y) = (LEGEND_X, 16i32);
    let mut at = Vec::new();
    for se in &fig.legend {
        let (tw, _) = area.estimate_text_size(&se.name, &font).map_err(s)?;
        let entry_w = 44 + tw as i32 + 30;
        if x + entry_w > w as i32 && x > LEGEND_X {
            x = LEGEND_X;
            y += LEGEND_ROW;
        }
        at.push((x, y));
        x += entry_w;
    }
    if fig.legend_note.is_some() {
        y += LEGEND_ROW;
    }
    Ok((at, (y + 18) as u32))
}

const LEGEND_X: i32 = 70;
const LEGEND_ROW: i32 = 28;

fn draw<DB: DrawingBackend>(fig: &Figure, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
    let s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(s)?;
    let body = root.titled(&fig.title, (FONT, 26)).map_err(s)?;
    let (w, h) = body.dim_in_pixel();
    let (at, legend_h) = legend_layout(fig, &body, w)?;
    let (charts, legend) = body.split_vertically(h.saturating_sub(legend_h));
    let areas = charts.split_evenly((1, fig.panels.len().max(1)));
    for (panel, area) in fig.panels.iter().zip(&areas) {
        draw_panel(panel, area)?;
    }
    draw_legend(fig, &legend, &at)
}

fn draw_panel<DB: DrawingBackend>(panel: &Panel, area: &DrawingArea<DB, Shift>) -> Result<(), String> {
    let s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let xs = panel.series.iter().flat_map(|se| se.line.iter().chain(&se.open).map(|p| p.0));
    let ys = panel.series.iter().filter(|se| !se.dashed).flat_map(|se| se.line.iter().chain(&se.open).map(|p| p.1));
    let (x0, x1) = padded(xs, 1.3);
    let (y0, y1) = padded(ys, 2.0);
    let x_axis = (x0..x1).log_scale().with_key_points(log_ticks(x0, x1));
    let y_axis = (y0..y1).log_scale().with_key_points(log_ticks(y0, y1));
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.caption, (FONT, 20))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(x_axis, y_axis)
        .map_err(s)?;
    chart
        .configure_mesh()
        .x_desc(&panel.x_desc)
        .y_desc(&panel.y_desc)
        .x_label_formatter(&|x| log_label(*x))
        .y_label_formatter(&|y| log_label(*y))
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()
        .map_err(s)?;
    let inside = |p: &&(f64, f64)| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1;
    for se in &panel.series {
        let style = ShapeStyle { color: se.color.to_rgba(), filled: true, stroke_width: 2 };
        if se.dashed {
            let pts: Vec<(f64, f64)> = se.line.clone();
            chart.draw_series(DashedLineSeries::new(pts, 8, 6, ShapeStyle { filled: false, ..style })).map_err(s)?;
            continue;
        }
        chart.draw_series(LineSeries::new(se.line.iter().copied(), style)).map_err(s)?;
        let filled: Vec<(f64, f64)> = se.line.iter().filter(inside).copied().collect();
        draw_markers(&mut chart, &filled, se.marker, style).map_err(s)?;
        let open: Vec<(f64, f64)> = se.open.iter().filter(inside).copied().collect();
        draw_markers(&mut chart, &open, se.marker, ShapeStyle { filled: false, ..style }).map_err(s)?;
        let bars = se.bars.iter().filter(|b| b.0 >= x0 && b.0 <= x1).map(|&(x, lo, hi)| {
            let (lo, hi) = (lo.clamp(y0, y1), hi.clamp(y0, y1));
            PathElement::new(vec![(x, lo), (x, hi)], ShapeStyle { stroke_width: 1, ..style })
        });
        chart.draw_series(bars).map_err(s)?;
    }
    Ok(())
}

type LogAxis = WithKeyPoints<LogCoord<f64>>;
type LogChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<LogAxis, LogAxis>>;

fn draw_markers<DB: DrawingBackend>(
    chart: &mut LogChart<'_, DB>,
    pts: &[(f64, f64)],
    marker: Marker,
    style: ShapeStyle,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    match marker {
        Marker::Circle => chart.draw_series(pts.iter().map(|p| Circle::new(*p, 5, style)))?,
        Marker::Triangle => chart.draw_series(pts.iter().map(|p| TriangleMarker::new(*p, 7, style)))?,
        Marker::Square => {
            chart.draw_series(pts.iter().map(|p| EmptyElement::at(*p) + Rectangle::new([(-5, -5), (5, 5)], style)))?
        }
        Marker::Cross => chart.draw_series(pts.iter().map(|p| Cross::new(*p, 6, style)))?,
    };
    Ok(())
}

fn draw_legend<DB: DrawingBackend>(
    fig: &Figure,
    area: &DrawingArea<DB, Shift>,
    at: &[(i32, i32)],
) -> Result<(), String> {
    let s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let font: TextStyle = (FONT, 17).into_text_style(area);
    for (se, &(x, y)) in fig.legend.iter().zip(at) {
        let style = ShapeStyle { color: se.color.to_rgba(), filled: true, stroke_width: 2 };
        if se.dashed {
            area.draw(&DashedPathElement::new(vec![(x, y), (x + 34, y)], 6, 4, ShapeStyle { filled: false, ..style }))
                .map_err(s)?;
        } else {
            area.draw(&PathElement::new(vec![(x, y), (x + 34, y)], style)).map_err(s)?;
            let c = (x + 17, y);
            match se.marker {
                Marker::Circle => area.draw(&Circle::new(c, 5, style)),
                Marker::Triangle => area.draw(&TriangleMarker::new(c, 7, style)),
                Marker::Square => area.draw(&Rectangle::new([(c.0 - 5, c.1 - 5), (c.0 + 5, c.1 + 5)], style)),
                Marker::Cross => area.draw(&Cross::new(c, 6, style)),
            }
            .map_err(s)?;
        }
        area.draw(&Text::new(se.name.clone(), (x + 44, y - 9), font.clone())).map_err(s)?;
    }
    if let Some(note) = &fig.legend_note {
        let y = at.iter().map(|p| p.1).max().unwrap_or(16) + LEGEND_ROW;
        if fig.note_marker {
            let open = ShapeStyle { color: GREY.to_rgba(), filled: false, stroke_width: 2 };
            area.draw(&Circle::new((LEGEND_X + 17, y), 5, open)).map_err(s)?;
        }
        area.draw(&Text::new(note.clone(), (LEGEND_X + 44, y - 9), font)).map_err(s)?;
    }
    Ok(())
}

/// One log–log panel with a line per series (name, points (x, y)); `labels` are the title, the
/// caption and the axes; with `slope_one` a dashed line of slope 1 through the first series'
/// ends.
pub fn lines(
    series: &[(String, Vec<(f64, f64)>)],
    labels: [&str; 4],
    slope_one: bool,
    png: &Path,
    svg: &Path,
) -> Result<(), PlotError> {
    let mut lines: Vec<Series> = series
        .iter()
        .enumerate()
        .filter(|(_, (_, pts))| !pts.is_empty())
        .map(|(i, (name, pts))| Series {
            name: name.clone(),
            color: COLORS[i % COLORS.len()],
            marker: MARKERS[i % MARKERS.len()],
            line: pts.iter().copied().filter(|p| p.0 > 0.0 && p.1 > 0.0).collect(),
            open: vec![],
            dashed: false,
            bars: vec![],
        })
        .collect();
    if let Some((first, last)) =
        lines.first().filter(|_| slope_one).and_then(|s| Some((*s.line.first()?, *s.line.last()?)))
    {
        lines.push(Series {
            name: "slope 1 (linear in N)".into(),
            color: GREY,
            marker: Marker::Circle,
            line: vec![first, (last.0, first.1 * last.0 / first.0)],
            open: vec![],
            dashed: true,
            bars: vec![],
        });
    }
    let panel =
        Panel { caption: labels[1].into(), x_desc: labels[2].into(), y_desc: labels[3].into(), series: lines.clone() };
    let fig = Figure {
        title: labels[0].into(),
        panels: vec![panel],
        legend: lines,
        legend_note: None,
        note_marker: false,
        size: (1000, 700),
    };
    render(&fig, png, svg)
}

/// A curve y(x) on linear axes (a force–displacement curve): filled markers for converged
/// points, open ones for the others, written as PNG and SVG.
pub fn curve(
    title: &str,
    descs: (&str, &str),
    points: &[(f64, f64, bool)],
    png: &Path,
    svg: &Path,
) -> Result<(), PlotError> {
    register_font();
    let size = (1000, 700);
    draw_curve(&BitMapBackend::new(png, size).into_drawing_area(), title, descs, points)
        .map_err(|e| plot_error(png, e))?;
    draw_curve(&SVGBackend::new(svg, size).into_drawing_area(), title, descs, points)
        .map_err(|e| plot_error(svg, e))?;
    Ok(())
}

fn draw_curve<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    points: &[(f64, f64, bool)],
) -> Result<(), String> {
    let s = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(s)?;
    let range = |f: fn(&(f64, f64, bool)) -> f64, pad: f64| {
        let (lo, hi) = points.iter().map(f).fold((0.0f64, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        (lo * pad, (hi * pad).max(lo * pad + f64::EPSILON))
    };
    let ((x0, x1), (y0, y1)) = (range(|p| p.0, 1.05), range(|p| p.1, 1.1));
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(52)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(s)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style((FONT, 15))
        .axis_desc_style((FONT, 17))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(225, 225, 225))
        .draw()
        .map_err(s)?;
    let style = ShapeStyle { color: COLORS[0].to_rgba(), filled: true, stroke_width: 2 };
    chart.draw_series(LineSeries::new(points.iter().map(|p| (p.0, p.1)), style)).map_err(s)?;
    let marker = |p: &(f64, f64, bool)| Circle::new((p.0, p.1), 5, ShapeStyle { filled: p.2, ..style });
    chart.draw_series(points.iter().map(marker)).map_err(s)?;
    root.present().map_err(s)
}
