//! The chart types: line plots, heat maps, area plots, spectra. See the module docs of
//! [`crate::plot`] for conventions.

use std::ops::Range;
use std::path::Path;

use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axis::{fmt_tick, nice_ticks, LogAxis};
use super::contour::marching_squares;
use super::{
    write_figure, AreaPlot, Figure, HeatMap, LinePlot, LineStyle, MarkedPoint, Marker, PlotFiles,
    Series, SpectrumPlot, FONT,
};
use crate::{Error, Result};

/// Tableau 10 (its grey replaced by black, grey being the "failed" colour).
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(0, 0, 0),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];
/// Overlay colours on a viridis map (none of them in viridis).
const OVERLAY: [RGBColor; 4] = [
    RGBColor(228, 26, 28),
    RGBColor(255, 255, 255),
    RGBColor(255, 127, 0),
    RGBColor(247, 129, 191),
];
/// Neutral colour of failed (non-finite) points.
const FAILED: RGBColor = RGBColor(150, 150, 150);

/// The stroke of series `s` drawn at position `k`: its own colour or the palette's, its
/// own width or 2 px.
fn stroke(s: &Series, k: usize, palette: &[RGBColor]) -> ShapeStyle {
    let c = s
        .color
        .map_or(palette[k % palette.len()], |[r, g, b]| RGBColor(r, g, b));
    c.stroke_width(if s.width == 0 { 2 } else { s.width })
}

fn usable(v: f64, log: bool) -> bool {
    v.is_finite() && (!log || v > 0.0)
}

/// Min and max of the usable values.
fn extent(values: impl Iterator<Item = f64>, log: bool) -> Option<(f64, f64)> {
    values
        .filter(|v| usable(*v, log))
        .fold(None, |acc, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
}

/// Axis range with a 4 % margin (in log space for a log axis); a single value is widened.
fn padded((lo, hi): (f64, f64), log: bool) -> Range<f64> {
    if log {
        let (l, h) = (lo.log10(), hi.log10());
        let (l, h) = if h - l < 1e-12 {
            (l - 0.5, h + 0.5)
        } else {
            let m = 0.04 * (h - l);
            (l - m, h + m)
        };
        10f64.powf(l)..10f64.powf(h)
    } else if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
        let w = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        lo - w..hi + w
    } else {
        let m = 0.04 * (hi - lo);
        lo - m..hi + m
    }
}

/// Calls `$f($args..., x_coord, y_coord)` with linear or logarithmic (1-2-5 labelled)
/// coordinates.
macro_rules! with_axes {
    ($xlog:expr, $ylog:expr, $xr:expr, $yr:expr, $f:ident($($arg:expr),*)) => {
        match ($xlog, $ylog) {
            (false, false) => $f($($arg,)* RangedCoordf64::from($xr), RangedCoordf64::from($yr)),
            (true, false) => $f($($arg,)* LogAxis::new($xr), RangedCoordf64::from($yr)),
            (false, true) => $f($($arg,)* RangedCoordf64::from($xr), LogAxis::new($yr)),
            (true, true) => $f($($arg,)* LogAxis::new($xr), LogAxis::new($yr)),
        }
    };
}

fn check_label(field: &str, label: &str) -> Result<()> {
    if label.trim().is_empty() {
        Err(Error::invalid(
            field,
            "an axis label with quantity and unit is required, e.g. \"time (s)\"",
        ))
    } else {
        Ok(())
    }
}

fn check_series(field: &str, series: &[Series]) -> Result<()> {
    for (k, s) in series.iter().enumerate() {
        if s.x.len() != s.y.len() {
            return Err(Error::invalid(
                field,
                format!(
                    "series {k} ('{}'): {} x values but {} y values",
                    s.label,
                    s.x.len(),
                    s.y.len()
                ),
            ));
        }
    }
    Ok(())
}

fn check_markers(markers: &[Marker]) -> Result<()> {
    if let Some(m) = markers.iter().find(|m| !m.x.is_finite()) {
        return Err(Error::invalid(
            "markers",
            format!("marker '{}': x must be finite, got {}", m.label, m.x),
        ));
    }
    Ok(())
}

fn check_range(field: &str, r: Option<(f64, f64)>, log: bool) -> Result<()> {
    if let Some((a, b)) = r {
        if !(usable(a, log) && usable(b, log) && a < b) {
            return Err(Error::invalid(
                field,
                format!(
                    "({a}, {b}) must be finite and increasing{}",
                    if log {
                        ", and positive on a log axis"
                    } else {
                        ""
                    }
                ),
            ));
        }
    }
    Ok(())
}

fn e2s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

// ---------------------------------------------------------------- shared frame

type Chart<'a, DB, X, Y> = ChartContext<'a, DB, Cartesian2d<X, Y>>;

/// The frame every main chart shares: caption (none when `title` is empty), margin and
/// the axis label areas (`x_area` px below the frame for tick labels and description).
fn frame<'a, DB, X, Y>(
    area: &'a DrawingArea<DB, Shift>,
    title: &str,
    caption_size: u32,
    x_area: u32,
    xc: X,
    yc: Y,
) -> std::result::Result<Chart<'a, DB, X, Y>, String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let mut b = ChartBuilder::on(area);
    if !title.is_empty() {
        b.caption(title, (FONT, caption_size));
    }
    b.margin(18)
        .x_label_area_size(x_area)
        .y_label_area_size(88)
        .build_cartesian_2d(xc, yc)
        .map_err(e2s)
}

/// Axes with their descriptions and tick labels; a light grid unless `grid` is false.
fn axes<DB, X, Y>(
    chart: &mut Chart<'_, DB, X, Y>,
    x_label: &str,
    y_label: &str,
    grid: bool,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let mut mesh = chart.configure_mesh();
    if grid {
        mesh.bold_line_style(RGBColor(215, 215, 215))
            .light_line_style(RGBColor(240, 240, 240));
    } else {
        mesh.disable_mesh();
    }
    mesh.x_desc(x_label)
        .y_desc(y_label)
        .axis_desc_style((FONT, 20))
        .label_style((FONT, 15))
        .x_label_formatter(&fmt_tick)
        .y_label_formatter(&fmt_tick)
        .draw()
        .map_err(e2s)
}

/// The legend box: white at the upper right on curves, dark at the upper left on a heat map.
fn legend<'a, DB, X, Y>(
    chart: &mut Chart<'a, DB, X, Y>,
    dark: bool,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    legend_at(chart, dark, SeriesLabelPosition::UpperRight)
}

/// The corner of the frame where a legend of `entries` lines of at most `chars` characters
/// covers the fewest points of the curves `curves` (each drawn as its polyline, sampled every
/// few pixels): upper right, then upper left, lower right, lower left, upper and lower middle
/// on ties.
fn legend_corner<'a, DB, X, Y>(
    chart: &Chart<'a, DB, X, Y>,
    curves: &[Vec<(f64, f64)>],
    entries: usize,
    chars: usize,
) -> SeriesLabelPosition
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let (px, py) = chart.plotting_area().get_pixel_range();
    // Plotters' legend: 15 px text, a 24 px sample, margins of about 10 px.
    let (w, h) = (chars as f64 * 8.0 + 50.0, entries as f64 * 19.0 + 14.0);
    let mid = 0.5 * (px.start + px.end) as f64;
    let boxes = [
        (
            SeriesLabelPosition::UpperRight,
            px.end as f64 - w,
            py.start as f64,
        ),
        (
            SeriesLabelPosition::UpperLeft,
            px.start as f64,
            py.start as f64,
        ),
        (
            SeriesLabelPosition::LowerRight,
            px.end as f64 - w,
            py.end as f64 - h,
        ),
        (
            SeriesLabelPosition::LowerLeft,
            px.start as f64,
            py.end as f64 - h,
        ),
        (
            SeriesLabelPosition::UpperMiddle,
            mid - w / 2.0,
            py.start as f64,
        ),
        (
            SeriesLabelPosition::LowerMiddle,
            mid - w / 2.0,
            py.end as f64 - h,
        ),
    ];
    let mut hits = [0usize; 6];
    for c in curves {
        let pix: Vec<(f64, f64)> = c
            .iter()
            .map(|q| {
                let (x, y) = chart.backend_coord(q);
                (x as f64, y as f64)
            })
            .collect();
        let mut count = |x: f64, y: f64| {
            for (k, (_, x0, y0)) in boxes.iter().enumerate() {
                if x >= *x0 && x <= x0 + w && y >= *y0 && y <= y0 + h {
                    hits[k] += 1;
                }
            }
        };
        if let [only] = pix.as_slice() {
            count(only.0, only.1);
        }
        for seg in pix.windows(2) {
            let (a, b) = (seg[0], seg[1]);
            let n = (((b.0 - a.0).hypot(b.1 - a.1)) / 4.0)
                .ceil()
                .clamp(1.0, 1000.0) as usize;
            for i in 0..n {
                let t = i as f64 / n as f64;
                count(a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            }
        }
    }
    let best = (0..hits.len()).min_by_key(|&k| (hits[k], k)).unwrap_or(0);
    boxes
        .into_iter()
        .nth(best)
        .map_or(SeriesLabelPosition::UpperRight, |b| b.0)
}

/// [`legend`] at a given corner (curves only).
fn legend_at<'a, DB, X, Y>(
    chart: &mut Chart<'a, DB, X, Y>,
    dark: bool,
    corner: SeriesLabelPosition,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let mut l = chart.configure_series_labels();
    if dark {
        l.background_style(RGBColor(90, 90, 90).mix(0.9))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FONT, 15).into_font().color(&WHITE));
    } else {
        l.label_font((FONT, 15))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(120, 120, 120))
            .position(corner);
    }
    l.draw().map_err(e2s)
}

/// Grey × at the bottom of the frame for the x of failed (non-finite) points, with a legend
/// entry; nothing when there are none.
fn failed_marks<'a, DB, X, Y>(
    chart: &mut Chart<'a, DB, X, Y>,
    xs: &[f64],
    y_bottom: f64,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    if xs.is_empty() {
        return Ok(());
    }
    chart
        .draw_series(
            xs.iter()
                .map(|&x| Cross::new((x, y_bottom), 6, FAILED.stroke_width(2))),
        )
        .map_err(e2s)?
        .label("failed point")
        .legend(|(x, y)| Cross::new((x + 12, y), 5, FAILED.stroke_width(2)));
    Ok(())
}

/// The dash pattern a series is drawn with (`Auto` resolved to `default`).
fn dash_of(s: &Series, default: LineStyle) -> LineStyle {
    match s.style {
        LineStyle::Auto => default,
        other => other,
    }
}

/// Draws one unbroken polyline in the given dash pattern.
fn draw_run<'a, DB, X, Y>(
    chart: &mut Chart<'a, DB, X, Y>,
    run: Vec<(f64, f64)>,
    dash: LineStyle,
    style: ShapeStyle,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    match dash {
        LineStyle::Auto | LineStyle::Solid => {
            chart.draw_series(LineSeries::new(run, style)).map(|_| ())
        }
        LineStyle::Dashed => chart
            .draw_series(DashedLineSeries::new(run, 12, 6, style))
            .map(|_| ()),
        LineStyle::Dotted => chart
            .draw_series(DashedLineSeries::new(run, 3, 5, style))
            .map(|_| ()),
    }
    .map_err(e2s)
}

/// The pieces `(from, to)` (px along the legend line) of a 24 px legend sample in a
/// dash pattern: four in every case, so that every sample has one element type.
fn legend_pieces(dash: LineStyle) -> [(i32, i32); 4] {
    match dash {
        LineStyle::Auto | LineStyle::Solid => [(0, 6), (6, 12), (12, 18), (18, 24)],
        LineStyle::Dashed => [(0, 8), (12, 20), (20, 20), (20, 20)],
        LineStyle::Dotted => [(0, 3), (7, 10), (14, 17), (21, 24)],
    }
}

/// The legend sample of a stroke: a 24 px line in the series' dash pattern.
macro_rules! legend_sample {
    ($at:expr, $dash:expr, $style:expr) => {{
        let p = legend_pieces($dash);
        let piece = |k: usize| PathElement::new(vec![(p[k].0, 0), (p[k].1, 0)], $style);
        EmptyElement::at($at) + piece(0) + piece(1) + piece(2) + piece(3)
    }};
}

/// Labelled vertical lines across the frame: dark grey dashes from the bottom to the top of
/// the y range, the label beside the top (left of the line in the right half of the frame, so
/// that it does not run under the legend in the upper right corner),
/// successive labels 18 px lower so that neighbours do not overwrite one another.
fn draw_markers<'a, DB, X, Y>(
    chart: &mut Chart<'a, DB, X, Y>,
    markers: &[Marker],
    with_labels: bool,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    if markers.is_empty() {
        return Ok(());
    }
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let ink = RGBColor(60, 60, 60);
    let (px_lo, _) = chart.plotting_area().get_pixel_range();
    let width = (px_lo.end - px_lo.start).max(1) as f64;
    for (k, m) in markers.iter().enumerate() {
        if !(m.x >= xr.start.min(xr.end) && m.x <= xr.start.max(xr.end)) {
            continue;
        }
        chart
            .draw_series(std::iter::once(DashedPathElement::new(
                vec![(m.x, yr.start), (m.x, yr.end)],
                6,
                4,
                ink.stroke_width(2),
            )))
            .map_err(e2s)?;
        if with_labels && !m.label.is_empty() {
            let (px, _) = chart.backend_coord(&(m.x, yr.end));
            let frac = (px - px_lo.start) as f64 / width;
            let right = frac > 0.5;
            let dy = 6 + 20 * (k as i32 % 4);
            let font = (FONT, 15).into_font().color(&ink);
            let (w, h) = chart
                .plotting_area()
                .estimate_text_size(&m.label, &font)
                .map_err(e2s)?;
            let (w, h) = (w as i32, h as i32);
            // Text and its white backing box, left or right of the line.
            let (x_text, x_box, anchor) = if right {
                (-6, (-9 - w, -3), HPos::Right)
            } else {
                (6, (3, 9 + w), HPos::Left)
            };
            let label = EmptyElement::at((m.x, yr.end))
                + Rectangle::new(
                    [(x_box.0, dy - 2), (x_box.1, dy + h + 2)],
                    WHITE.mix(0.8).filled(),
                )
                + Text::new(
                    m.label.clone(),
                    (x_text, dy),
                    font.pos(Pos::new(anchor, VPos::Top)),
                );
            chart.draw_series(std::iter::once(label)).map_err(e2s)?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- line plots

/// Draws a family of curves with a legend to `<path_stem>.png` and `<path_stem>.svg`.
/// Non-finite y values break the curves and are marked by grey × at the bottom axis.
/// With `panels`, each series gets its own panel (common x axis and y range).
pub fn line_plot(path_stem: impl AsRef<Path>, plot: &LinePlot) -> Result<PlotFiles> {
    check_label("x_label", &plot.x_label)?;
    check_label("y_label", &plot.y_label)?;
    check_series("series", &plot.series)?;
    check_markers(&plot.markers)?;
    check_range("x_range", plot.x_range, plot.x_log)?;
    check_range("zoom", plot.zoom, plot.x_log)?;
    if let Some(b) = plot
        .bands
        .iter()
        .find(|b| !(b.from.is_finite() && b.to.is_finite() && b.from <= b.to))
    {
        return Err(Error::invalid(
            "bands",
            format!(
                "band '{}' from {} to {}: needs finite bounds, from <= to",
                b.label, b.from, b.to
            ),
        ));
    }
    let drawable = |s: &Series| {
        s.x.iter()
            .zip(&s.y)
            .any(|(x, y)| plot.in_x_range(*x) && usable(*y, plot.y_log))
    };
    if !plot.series.iter().any(drawable) {
        return Err(Error::invalid(
            "series",
            "no drawable point (finite, positive on a log axis, inside x_range)",
        ));
    }
    let in_zoom = |s: &Series| {
        s.x.iter()
            .zip(&s.y)
            .any(|(x, y)| inside(*x, plot.x_log, plot.zoom) && usable(*y, plot.y_log))
    };
    if plot.zoom.is_some() && !plot.series.iter().any(in_zoom) {
        return Err(Error::invalid(
            "zoom",
            "no drawable point inside the zoom's range",
        ));
    }
    write_figure(path_stem.as_ref(), plot)
}

/// `x` is drawable on an axis (log or not) and inside `range` (`None`: everywhere).
fn inside(x: f64, log: bool, range: Option<(f64, f64)>) -> bool {
    usable(x, log) && range.is_none_or(|(a, b)| x >= a && x <= b)
}

impl LinePlot {
    fn in_x_range(&self, x: f64) -> bool {
        inside(x, self.x_log, self.x_range)
    }

    fn panel_count(&self) -> usize {
        if self.panels {
            self.series.len().max(1)
        } else {
            1
        }
    }
}

/// What one frame of a line plot shows.
struct LinesView<'a> {
    title: &'a str,
    caption_size: u32,
    x_label: &'a str,
    x_area: u32,
    /// (palette position, series).
    series: Vec<(usize, &'a Series)>,
    marker_labels: bool,
    /// The horizontal range drawn (`None`: all points).
    x_range: Option<(f64, f64)>,
    /// Draw the legend (the zoom frame beside a plot has none).
    legend: bool,
}

impl Figure for LinePlot {
    fn size(&self) -> (u32, u32) {
        let n = self.panel_count() as u32;
        let width = if self.zoom.is_some() { 1600 } else { 1000 };
        if n > 1 {
            (width, 90 + 250 * n)
        } else {
            (width, 680)
        }
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let Some(zoom) = self.zoom else {
            return self.draw_frames(area, &self.title, self.x_range, true);
        };
        let width = area.dim_in_pixel().0;
        let (left, right) = area.split_horizontally(width * 3 / 5);
        self.draw_frames(&left, &self.title, self.x_range, true)?;
        self.draw_frames(&right, &self.zoom_title, Some(zoom), false)
    }
}

impl LinePlot {
    /// The plot's frame (or stacked panels) on `area`, showing `x_range` (`None`: the data's
    /// extent, padded) with the y range fitted to the points inside it.
    fn draw_frames<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        title: &str,
        x_range: Option<(f64, f64)>,
        legend: bool,
    ) -> std::result::Result<(), String> {
        let pts = || {
            self.series
                .iter()
                .flat_map(|s| s.x.iter().copied().zip(s.y.iter().copied()))
        };
        let xe = match x_range {
            Some(r) => r,
            None => extent(
                pts().filter(|p| usable(p.1, self.y_log)).map(|p| p.0),
                self.x_log,
            )
            .ok_or("no drawable point")?,
        };
        let ye = extent(
            pts()
                .filter(|p| inside(p.0, self.x_log, x_range))
                .map(|p| p.1),
            self.y_log,
        )
        .ok_or("no drawable point")?;
        let xr = if x_range.is_some() {
            xe.0..xe.1
        } else {
            padded(xe, self.x_log)
        };
        let yr = padded(ye, self.y_log);
        let n = self.panel_count();
        if n == 1 {
            let view = LinesView {
                title,
                caption_size: 26,
                x_label: &self.x_label,
                x_area: 58,
                series: self.series.iter().enumerate().collect(),
                marker_labels: legend,
                x_range,
                legend,
            };
            return with_axes!(
                self.x_log,
                self.y_log,
                xr,
                yr,
                draw_lines(area, self, &view)
            );
        }
        let body = if title.is_empty() {
            area.clone()
        } else {
            area.titled(title, (FONT, 26)).map_err(e2s)?
        };
        for (k, (panel, s)) in body
            .split_evenly((n, 1))
            .iter()
            .zip(&self.series)
            .enumerate()
        {
            let last = k + 1 == n;
            let view = LinesView {
                title: &s.label,
                caption_size: 19,
                x_label: if last { &self.x_label } else { "" },
                x_area: if last { 58 } else { 30 },
                series: vec![(k, s)],
                marker_labels: k == 0 && legend,
                x_range,
                legend,
            };
            with_axes!(
                self.x_log,
                self.y_log,
                xr.clone(),
                yr.clone(),
                draw_lines(panel, self, &view)
            )?;
        }
        Ok(())
    }
}

fn draw_lines<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    p: &LinePlot,
    view: &LinesView<'_>,
    xc: X,
    yc: Y,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let y_bottom = yc.range().start;
    let y_top = yc.range().end;
    let x_span = xc.range();
    let mut chart = frame(area, view.title, view.caption_size, view.x_area, xc, yc)?;
    axes(&mut chart, view.x_label, &p.y_label, true)?;

    let mut failed_x = Vec::new();
    let mut any_label = false;
    let (mut curves, mut entries, mut chars) = (Vec::new(), 0usize, 0usize);
    let mut band_labels: Vec<&str> = Vec::new();
    for b in &p.bands {
        let (lo, hi) = (b.from.max(x_span.start), b.to.min(x_span.end));
        if lo >= hi || lo.is_nan() || hi.is_nan() {
            continue;
        }
        let fill = RGBColor(b.color[0], b.color[1], b.color[2])
            .mix(0.2)
            .filled();
        let drawn = chart
            .draw_series(std::iter::once(Rectangle::new(
                [(lo, y_bottom), (hi, y_top)],
                fill,
            )))
            .map_err(e2s)?;
        if view.legend && !b.label.is_empty() && !band_labels.contains(&b.label.as_str()) {
            band_labels.push(&b.label);
            any_label = true;
            entries += 1;
            chars = chars.max(b.label.chars().count());
            drawn
                .label(&b.label)
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], fill));
        }
    }
    for &(k, s) in &view.series {
        let style = stroke(s, k, &PALETTE);
        let dash = dash_of(s, LineStyle::Solid);
        // Split into runs of drawable points.
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for (&x, &y) in s.x.iter().zip(&s.y) {
            if !inside(x, p.x_log, view.x_range) {
                if runs.last().is_some_and(|r| !r.is_empty()) {
                    runs.push(Vec::new());
                }
                continue;
            }
            if usable(y, p.y_log) {
                if let Some(run) = runs.last_mut() {
                    run.push((x, y));
                }
            } else {
                if !y.is_finite() {
                    failed_x.push(x);
                }
                if runs.last().is_some_and(|r| !r.is_empty()) {
                    runs.push(Vec::new());
                }
            }
        }
        // An empty series carries the legend entry (not in panels: there the caption
        // names the curve).
        let legend = chart
            .draw_series(LineSeries::new(Vec::<(f64, f64)>::new(), style))
            .map_err(e2s)?;
        if !s.label.is_empty() && !p.panels && view.legend {
            any_label = true;
            entries += 1;
            chars = chars.max(s.label.chars().count());
            legend
                .label(&s.label)
                .legend(move |c| legend_sample!(c, dash, style));
        }
        for run in runs.into_iter().filter(|r| !r.is_empty()) {
            curves.push(run.clone());
            if run.len() == 1 {
                chart
                    .draw_series(run.iter().map(|&q| Circle::new(q, 3, style.filled())))
                    .map_err(e2s)?;
            } else {
                draw_run(&mut chart, run, dash, style)?;
            }
        }
    }
    draw_markers(&mut chart, &p.markers, view.marker_labels)?;
    if !failed_x.is_empty() && view.legend {
        any_label = true;
        entries += 1;
        chars = chars.max(16);
    }
    failed_marks(&mut chart, &failed_x, y_bottom)?;
    if any_label {
        let corner = legend_corner(&chart, &curves, entries, chars);
        legend_at(&mut chart, false, corner)?;
    }
    Ok(())
}

/// Spectra in dB against frequency (Hz): a [`line_plot`] with a linear level axis and a
/// linear or logarithmic (1-2-5 labelled) frequency axis labelled "frequency (Hz)".
pub fn spectrum_plot(path_stem: impl AsRef<Path>, plot: &SpectrumPlot) -> Result<PlotFiles> {
    let lines = LinePlot {
        title: plot.title.clone(),
        x_label: "frequency (Hz)".into(),
        y_label: plot.y_label.clone(),
        x_log: plot.x_log,
        y_log: false,
        series: plot.series.clone(),
        markers: plot.markers.clone(),
        bands: Vec::new(),
        panels: false,
        x_range: plot.x_range,
        ..Default::default()
    };
    line_plot(path_stem, &lines)
}

// ---------------------------------------------------------------- area plots

/// Stacked or overlaid filled histories (e.g. energies against time) to
/// `<path_stem>.png/.svg`. Non-finite values count as 0 in the fill and are marked by a
/// grey × at the bottom axis. The legend lists the labelled series (none: no legend).
pub fn area_plot(path_stem: impl AsRef<Path>, plot: &AreaPlot) -> Result<PlotFiles> {
    check_label("x_label", &plot.x_label)?;
    check_label("y_label", &plot.y_label)?;
    check_series("series", &plot.series)?;
    check_markers(&plot.markers)?;
    if plot.series.is_empty() {
        return Err(Error::invalid("series", "nothing to draw"));
    }
    for (k, s) in plot.series.iter().enumerate() {
        if s.x.len() < 2 || s.x.iter().any(|v| !v.is_finite()) {
            return Err(Error::invalid(
                "series",
                format!("series {k} ('{}'): needs ≥ 2 finite x values", s.label),
            ));
        }
        if plot.stacked && s.x != plot.series[0].x {
            return Err(Error::invalid(
                "series",
                format!(
                    "stacked series must share x; series {k} ('{}') differs from series 0",
                    s.label
                ),
            ));
        }
    }
    write_figure(path_stem.as_ref(), plot)
}

impl AreaPlot {
    /// (lower, upper) boundary of each band.
    fn bands(&self) -> Vec<(Vec<f64>, Vec<f64>)> {
        let mut base: Vec<f64> = vec![0.0; self.series.first().map_or(0, |s| s.x.len())];
        self.series
            .iter()
            .map(|s| {
                let y: Vec<f64> =
                    s.y.iter()
                        .map(|v| if v.is_finite() { *v } else { 0.0 })
                        .collect();
                if self.stacked {
                    let top: Vec<f64> = base.iter().zip(&y).map(|(b, v)| b + v).collect();
                    let band = (base.clone(), top.clone());
                    base = top;
                    band
                } else {
                    (vec![0.0; y.len()], y)
                }
            })
            .collect()
    }
}

impl Figure for AreaPlot {
    fn size(&self) -> (u32, u32) {
        (1000, 680)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let bands = self.bands();
        let xe = extent(
            self.series
                .iter()
                .flat_map(|s| s.x.iter().copied())
                .chain(self.markers.iter().map(|m| m.x)),
            false,
        )
        .ok_or("no x values")?;
        let ye = extent(
            bands
                .iter()
                .flat_map(|(lo, hi)| lo.iter().chain(hi.iter()).copied()),
            false,
        )
        .ok_or("no y values")?;
        let xr = xe.0..xe.1;
        // Room above the highest band for the legend and the marker labels.
        let yr = padded((ye.0, ye.1 + 0.12 * (ye.1 - ye.0)), false);
        let y_bottom = yr.start;
        let mut chart = frame(
            area,
            &self.title,
            26,
            58,
            RangedCoordf64::from(xr),
            RangedCoordf64::from(yr),
        )?;
        axes(&mut chart, &self.x_label, &self.y_label, true)?;
        let fill_alpha = if self.stacked { 0.55 } else { 0.25 };
        let mut failed_x = Vec::new();
        let mut any_label = false;
        for (k, (s, (lo, hi))) in self.series.iter().zip(&bands).enumerate() {
            let line = stroke(s, k, &PALETTE);
            let c = line.color;
            let mut outline: Vec<(f64, f64)> =
                s.x.iter().copied().zip(hi.iter().copied()).collect();
            let top = outline.clone();
            outline.extend(s.x.iter().copied().zip(lo.iter().copied()).rev());
            let fill = c.mix(fill_alpha).filled();
            let drawn = chart
                .draw_series(std::iter::once(Polygon::new(outline, fill)))
                .map_err(e2s)?;
            if !s.label.is_empty() {
                any_label = true;
                drawn
                    .label(&s.label)
                    .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 20, y + 6)], fill));
            }
            draw_run(&mut chart, top, dash_of(s, LineStyle::Solid), line)?;
            failed_x.extend(
                s.x.iter()
                    .zip(&s.y)
                    .filter(|(_, y)| !y.is_finite())
                    .map(|(x, _)| *x),
            );
        }
        draw_markers(&mut chart, &self.markers, true)?;
        any_label |= !failed_x.is_empty();
        failed_marks(&mut chart, &failed_x, y_bottom)?;
        if any_label {
            legend(&mut chart, false)?;
        }
        Ok(())
    }
}

// ---------------------------------------------------------------- heat maps

/// Cell edges around strictly increasing centres: midpoints (geometric on a log axis),
/// the outer edges half a cell beyond the outer centres.
fn cell_edges(c: &[f64], log: bool) -> Vec<f64> {
    let n = c.len();
    let mid = |a: f64, b: f64| if log { (a * b).sqrt() } else { 0.5 * (a + b) };
    let beyond = |a: f64, b: f64| {
        if log {
            a * (a / b).sqrt()
        } else {
            a + 0.5 * (a - b)
        }
    };
    let mut e = Vec::with_capacity(n + 1);
    e.push(beyond(c[0], c[1]));
    for i in 1..n {
        e.push(mid(c[i - 1], c[i]));
    }
    e.push(beyond(c[n - 1], c[n - 2]));
    e
}

fn check_axis(field: &str, c: &[f64], log: bool) -> Result<()> {
    if c.len() < 2 {
        return Err(Error::invalid(
            field,
            format!("needs at least 2 values, got {}", c.len()),
        ));
    }
    if c.iter().any(|v| !usable(*v, log)) {
        return Err(Error::invalid(
            field,
            if log {
                "values must be finite and positive on a log axis"
            } else {
                "values must be finite"
            },
        ));
    }
    if c.windows(2).any(|w| w[1] <= w[0]) {
        return Err(Error::invalid(field, "values must be strictly increasing"));
    }
    Ok(())
}

/// A heat map with colour bar, contour lines, overlay curves and labelled points to
/// `<path_stem>.png/.svg`. Non-finite cells are painted grey ("failed" in the legend).
/// Contours are traced by marching squares ([`super::contour`]) in the plotted
/// coordinates (log10 of a log axis).
pub fn heat_map(path_stem: impl AsRef<Path>, map: &HeatMap) -> Result<PlotFiles> {
    check_label("x_label", &map.x_label)?;
    check_label("y_label", &map.y_label)?;
    check_label("colorbar_label", &map.colorbar_label)?;
    check_axis("x", &map.x, map.x_log)?;
    check_axis("y", &map.y, map.y_log)?;
    if map.z.len() != map.x.len() * map.y.len() {
        return Err(Error::invalid(
            "z",
            format!(
                "{} values, expected nx·ny = {}·{}",
                map.z.len(),
                map.x.len(),
                map.y.len()
            ),
        ));
    }
    if let Some(l) = map.contour_levels.iter().find(|l| !l.is_finite()) {
        return Err(Error::invalid(
            "contour_levels",
            format!("levels must be finite, got {l}"),
        ));
    }
    check_series("overlay_lines", &map.overlay_lines)?;
    if let Some(p) = map
        .points
        .iter()
        .find(|p| !usable(p.x, map.x_log) || !usable(p.y, map.y_log))
    {
        return Err(Error::invalid(
            "points",
            format!(
                "point '{}' at ({}, {}): coordinates must be finite (and positive on a log axis)",
                p.label, p.x, p.y
            ),
        ));
    }
    write_figure(path_stem.as_ref(), map)
}

/// The legend text of the contour lines, complete (never cut off): "contours every Δ from
/// a to b" for evenly spaced levels, the list for up to five others, else their count.
pub(crate) fn contour_legend(levels: &[f64]) -> String {
    let mut l: Vec<f64> = levels.to_vec();
    l.sort_by(f64::total_cmp);
    l.dedup();
    match l.len() {
        0 => String::new(),
        1 => format!("contour at {}", fmt_tick(&l[0])),
        n => {
            let step = (l[n - 1] - l[0]) / (n - 1) as f64;
            let even = n >= 3
                && l.windows(2)
                    .all(|w| ((w[1] - w[0]) - step).abs() <= 1e-6 * step.abs());
            if even {
                format!(
                    "contours every {} from {} to {}",
                    fmt_tick(&step),
                    fmt_tick(&l[0]),
                    fmt_tick(&l[n - 1])
                )
            } else if n <= 5 {
                let shown: Vec<String> = l.iter().map(fmt_tick).collect();
                format!("contours at {}", shown.join(", "))
            } else {
                format!("{n} contour levels (marked on the colour bar)")
            }
        }
    }
}

impl HeatMap {
    fn z_range(&self) -> (f64, f64) {
        match extent(self.z.iter().copied(), false) {
            None => (0.0, 1.0),
            Some((lo, hi)) if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) => {
                let w = if lo == 0.0 { 0.5 } else { 0.05 * lo.abs() };
                (lo - w, hi + w)
            }
            Some(r) => r,
        }
    }

    /// Contour segments in data coordinates, per level.
    fn contours(&self) -> Vec<Vec<[(f64, f64); 2]>> {
        let tx: Vec<f64> = self
            .x
            .iter()
            .map(|v| if self.x_log { v.log10() } else { *v })
            .collect();
        let ty: Vec<f64> = self
            .y
            .iter()
            .map(|v| if self.y_log { v.log10() } else { *v })
            .collect();
        let back = |v: f64, log: bool| if log { 10f64.powf(v) } else { v };
        self.contour_levels
            .iter()
            .map(|&level| {
                marching_squares(&tx, &ty, &self.z, level)
                    .unwrap_or_default()
                    .into_iter()
                    .map(|s| s.map(|(x, y)| (back(x, self.x_log), back(y, self.y_log))))
                    .collect()
            })
            .collect()
    }
}

const COLORBAR_WIDTH: u32 = 190;

impl Figure for HeatMap {
    fn size(&self) -> (u32, u32) {
        (1100, 760)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let (w, _) = self.size();
        let (main, bar) = area.split_horizontally(w - COLORBAR_WIDTH);
        let ex = cell_edges(&self.x, self.x_log);
        let ey = cell_edges(&self.y, self.y_log);
        let xr = ex[0]..ex[ex.len() - 1];
        let yr = ey[0]..ey[ey.len() - 1];
        let rows = with_axes!(
            self.x_log,
            self.y_log,
            xr,
            yr,
            draw_heat(&main, self, &ex, &ey)
        )?;
        let base = bar.get_base_pixel().1;
        draw_colorbar(&bar, self, (rows.start - base)..(rows.end - base))
    }
}

fn viridis(z: f64, (lo, hi): (f64, f64)) -> RGBColor {
    let t = ((z - lo) / (hi - lo)).clamp(0.0, 1.0);
    ViridisRGB::get_color(t)
}

/// Draws the map; returns the pixel rows (absolute) of the plotting frame, for the colour
/// bar to match.
fn draw_heat<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    map: &HeatMap,
    ex: &[f64],
    ey: &[f64],
    xc: X,
    yc: Y,
) -> std::result::Result<Range<i32>, String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let nx = map.x.len();
    let zr = map.z_range();
    let mut chart = frame(area, &map.title, 26, 58, xc, yc)?;
    axes(&mut chart, &map.x_label, &map.y_label, false)?;
    chart
        .draw_series(map.z.iter().enumerate().map(|(k, &z)| {
            let (i, j) = (k % nx, k / nx);
            let c = if z.is_finite() {
                viridis(z, zr)
            } else {
                FAILED
            };
            Rectangle::new([(ex[i], ey[j]), (ex[i + 1], ey[j + 1])], c.filled())
        }))
        .map_err(e2s)?;

    let mut any_label = false;
    if map.z.iter().any(|z| !z.is_finite()) {
        any_label = true;
        chart
            .draw_series(std::iter::empty::<Rectangle<(f64, f64)>>())
            .map_err(e2s)?
            .label("failed")
            .legend(|(x, y)| Rectangle::new([(x, y - 6), (x + 20, y + 6)], FAILED.filled()));
    }
    let contours = map.contours();
    let contour_style = BLACK.stroke_width(1);
    for (k, segments) in contours.iter().enumerate() {
        let drawn = chart
            .draw_series(
                segments
                    .iter()
                    .map(|s| PathElement::new(vec![s[0], s[1]], contour_style)),
            )
            .map_err(e2s)?;
        if k == 0 {
            any_label = true;
            drawn
                .label(contour_legend(&map.contour_levels))
                .legend(move |c| legend_sample!(c, LineStyle::Solid, contour_style));
        }
    }
    for (k, s) in map.overlay_lines.iter().enumerate() {
        let style = stroke(s, k, &OVERLAY);
        let dash = dash_of(s, LineStyle::Dashed);
        let pts: Vec<(f64, f64)> =
            s.x.iter()
                .copied()
                .zip(s.y.iter().copied())
                .filter(|(x, y)| usable(*x, map.x_log) && usable(*y, map.y_log))
                .collect();
        let legend_entry = chart
            .draw_series(std::iter::empty::<PathElement<(f64, f64)>>())
            .map_err(e2s)?;
        if !s.label.is_empty() {
            any_label = true;
            legend_entry
                .label(&s.label)
                .legend(move |c| legend_sample!(c, dash, style));
        }
        if pts.len() >= 2 {
            draw_run(&mut chart, pts, dash, style)?;
        }
    }
    draw_points(&mut chart, &map.points)?;
    if any_label {
        legend(&mut chart, true)?;
    }
    let (_, rows) = chart.plotting_area().get_pixel_range();
    Ok(rows)
}

/// Labelled points: a white disc ringed in black, the label in a white box to its upper
/// right.
fn draw_points<'a, DB, X, Y>(
    chart: &mut Chart<'a, DB, X, Y>,
    points: &[MarkedPoint],
) -> std::result::Result<(), String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let font = TextStyle::from((FONT, 18).into_font());
    for p in points {
        let (w, h) = chart
            .plotting_area()
            .estimate_text_size(&p.label, &font)
            .map_err(e2s)?;
        let (w, h) = (w as i32, h as i32);
        let disc = EmptyElement::at((p.x, p.y))
            + Circle::new((0, 0), 6, WHITE.filled())
            + Circle::new((0, 0), 6, BLACK.stroke_width(2));
        chart.draw_series(std::iter::once(disc)).map_err(e2s)?;
        if !p.label.is_empty() {
            let boxed = EmptyElement::at((p.x, p.y))
                + Rectangle::new([(9, -13 - h), (17 + w, -7)], WHITE.mix(0.92).filled())
                + Rectangle::new([(9, -13 - h), (17 + w, -7)], BLACK.stroke_width(1))
                + Text::new(
                    p.label.clone(),
                    (13, -10 - h),
                    font.clone().pos(Pos::new(HPos::Left, VPos::Top)),
                );
            chart.draw_series(std::iter::once(boxed)).map_err(e2s)?;
        }
    }
    Ok(())
}

/// The colour bar, drawn by hand in pixels so that everything sits where a reader expects:
/// the gradient over exactly the rows of the map's frame, tick marks on its right edge,
/// tick labels to the right of the marks (never under them), contour levels as black lines
/// across the gradient, and the rotated label just right of the widest tick label.
fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    map: &HeatMap,
    rows: Range<i32>,
) -> std::result::Result<(), String> {
    let (lo, hi) = map.z_range();
    let (top, bottom) = (rows.start, rows.end);
    let (x0, x1) = (14, 42);
    let span = (bottom - top).max(1);
    let to_px = |z: f64| bottom - ((z - lo) / (hi - lo) * span as f64).round() as i32;
    for r in top..bottom {
        let z = lo + (hi - lo) * ((bottom - r) as f64 - 0.5) / span as f64;
        area.draw(&Rectangle::new(
            [(x0, r), (x1, r + 1)],
            viridis(z, (lo, hi)).filled(),
        ))
        .map_err(e2s)?;
    }
    for &l in map.contour_levels.iter().filter(|l| **l >= lo && **l <= hi) {
        let y = to_px(l);
        area.draw(&PathElement::new(
            vec![(x0, y), (x1, y)],
            BLACK.stroke_width(1),
        ))
        .map_err(e2s)?;
    }
    area.draw(&Rectangle::new(
        [(x0, top), (x1, bottom)],
        BLACK.stroke_width(1),
    ))
    .map_err(e2s)?;
    let font = TextStyle::from((FONT, 15).into_font());
    let mut widest = 0;
    for t in nice_ticks(lo, hi, 7) {
        let y = to_px(t);
        area.draw(&PathElement::new(
            vec![(x1, y), (x1 + COLORBAR_TICK, y)],
            BLACK.stroke_width(1),
        ))
        .map_err(e2s)?;
        let text = fmt_tick(&t);
        let (w, _) = area.estimate_text_size(&text, &font).map_err(e2s)?;
        widest = widest.max(w as i32);
        area.draw(&Text::new(
            text,
            (x1 + COLORBAR_TICK + COLORBAR_GAP, y),
            font.clone().pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(e2s)?;
    }
    let label_x = x1 + COLORBAR_TICK + COLORBAR_GAP + widest + 16;
    area.draw(&Text::new(
        map.colorbar_label.clone(),
        (label_x, (top + bottom) / 2),
        TextStyle::from((FONT, 20).into_font().transform(FontTransform::Rotate270))
            .pos(Pos::new(HPos::Center, VPos::Center)),
    ))
    .map_err(e2s)?;
    Ok(())
}

/// Length of a colour-bar tick mark (px).
const COLORBAR_TICK: i32 = 6;
/// Space between a colour-bar tick mark and its label (px).
const COLORBAR_GAP: i32 = 5;
