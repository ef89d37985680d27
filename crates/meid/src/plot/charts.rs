//! The chart types: line plots, heat maps, area plots, spectra. See the module docs of
//! [`crate::plot`] for conventions.

use std::ops::Range;
use std::path::Path;

use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::contour::marching_squares;
use super::{
    write_figure, AreaPlot, Figure, HeatMap, LinePlot, PlotFiles, Series, SpectrumPlot, FONT,
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

fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// Tick label: plain decimals for moderate magnitudes, scientific notation otherwise.
fn fmt_tick(v: &f64) -> String {
    let v = *v;
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".into()
        } else {
            s.into()
        }
    } else {
        let s = format!("{v:.2e}");
        // 1.50e3 -> 1.5e3
        match s.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => s,
        }
    }
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
/// A log axis is widened to whole decades when it would otherwise show fewer than two
/// decade ticks (plotters labels a log axis at decades only).
fn padded((lo, hi): (f64, f64), log: bool) -> Range<f64> {
    if log {
        let (l, h) = (lo.log10(), hi.log10());
        let (mut l, mut h) = if h - l < 1e-12 {
            (l - 0.5, h + 0.5)
        } else {
            let m = 0.04 * (h - l);
            (l - m, h + m)
        };
        if h.floor() - l.ceil() < 1.0 {
            l = l.floor();
            h = h.ceil().max(l + 1.0);
        }
        10f64.powf(l)..10f64.powf(h)
    } else if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
        let w = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        lo - w..hi + w
    } else {
        let m = 0.04 * (hi - lo);
        lo - m..hi + m
    }
}

/// Calls `$f($args..., x_coord, y_coord)` with linear or logarithmic coordinates.
macro_rules! with_axes {
    ($xlog:expr, $ylog:expr, $xr:expr, $yr:expr, $f:ident($($arg:expr),*)) => {
        match ($xlog, $ylog) {
            (false, false) => $f($($arg,)* RangedCoordf64::from($xr), RangedCoordf64::from($yr)),
            (true, false) => $f($($arg,)* LogCoord::from($xr.log_scale()), RangedCoordf64::from($yr)),
            (false, true) => $f($($arg,)* RangedCoordf64::from($xr), LogCoord::from($yr.log_scale())),
            (true, true) => $f($($arg,)* LogCoord::from($xr.log_scale()), LogCoord::from($yr.log_scale())),
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

fn e2s<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

// ---------------------------------------------------------------- shared frame

type Chart<'a, DB, X, Y> = ChartContext<'a, DB, Cartesian2d<X, Y>>;

/// The frame every main chart shares: caption, margin and the axis label areas.
fn frame<'a, DB, X, Y>(
    area: &'a DrawingArea<DB, Shift>,
    title: &str,
    xc: X,
    yc: Y,
) -> std::result::Result<Chart<'a, DB, X, Y>, String>
where
    DB: DrawingBackend + 'a,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    ChartBuilder::on(area)
        .caption(title, (FONT, 26))
        .margin(18)
        .x_label_area_size(58)
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
            .position(SeriesLabelPosition::UpperRight);
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

// ---------------------------------------------------------------- line plots

/// Draws a family of curves with a legend to `<path_stem>.png` and `<path_stem>.svg`.
/// Non-finite y values break the curves and are marked by grey × at the bottom axis.
pub fn line_plot(path_stem: impl AsRef<Path>, plot: &LinePlot) -> Result<PlotFiles> {
    check_label("x_label", &plot.x_label)?;
    check_label("y_label", &plot.y_label)?;
    check_series("series", &plot.series)?;
    let drawable = |s: &Series| {
        s.x.iter()
            .zip(&s.y)
            .any(|(x, y)| usable(*x, plot.x_log) && usable(*y, plot.y_log))
    };
    if !plot.series.iter().any(drawable) {
        return Err(Error::invalid(
            "series",
            "no drawable point (finite, and positive on a log axis)",
        ));
    }
    write_figure(path_stem.as_ref(), plot)
}

impl Figure for LinePlot {
    fn size(&self) -> (u32, u32) {
        (1000, 680)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        let pts = || {
            self.series
                .iter()
                .flat_map(|s| s.x.iter().copied().zip(s.y.iter().copied()))
        };
        let xe = extent(
            pts().filter(|p| usable(p.1, self.y_log)).map(|p| p.0),
            self.x_log,
        )
        .ok_or("no drawable point")?;
        let ye = extent(
            pts().filter(|p| usable(p.0, self.x_log)).map(|p| p.1),
            self.y_log,
        )
        .ok_or("no drawable point")?;
        let xr = padded(xe, self.x_log);
        let yr = padded(ye, self.y_log);
        with_axes!(self.x_log, self.y_log, xr, yr, draw_lines(area, self))
    }
}

fn draw_lines<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    p: &LinePlot,
    xc: X,
    yc: Y,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let y_bottom = yc.range().start;
    let mut chart = frame(area, &p.title, xc, yc)?;
    axes(&mut chart, &p.x_label, &p.y_label, true)?;

    let mut failed_x = Vec::new();
    let mut any_label = false;
    for (k, s) in p.series.iter().enumerate() {
        let style = colour(k).stroke_width(2);
        // Split into runs of drawable points.
        let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        for (&x, &y) in s.x.iter().zip(&s.y) {
            if usable(x, p.x_log) && usable(y, p.y_log) {
                if let Some(run) = runs.last_mut() {
                    run.push((x, y));
                }
            } else {
                if usable(x, p.x_log) && !y.is_finite() {
                    failed_x.push(x);
                }
                if runs.last().is_some_and(|r| !r.is_empty()) {
                    runs.push(Vec::new());
                }
            }
        }
        // An empty series carries the legend entry.
        let legend = chart
            .draw_series(LineSeries::new(Vec::<(f64, f64)>::new(), style))
            .map_err(e2s)?;
        if !s.label.is_empty() {
            any_label = true;
            legend
                .label(&s.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        }
        for run in runs.into_iter().filter(|r| !r.is_empty()) {
            if run.len() == 1 {
                chart
                    .draw_series(run.iter().map(|&q| Circle::new(q, 3, style.filled())))
                    .map_err(e2s)?;
            } else {
                chart
                    .draw_series(LineSeries::new(run, style))
                    .map_err(e2s)?;
            }
        }
    }
    any_label |= !failed_x.is_empty();
    failed_marks(&mut chart, &failed_x, y_bottom)?;
    if any_label {
        legend(&mut chart, false)?;
    }
    Ok(())
}

/// Spectra in dB against frequency (Hz): a [`line_plot`] with a linear level axis and a
/// linear or logarithmic frequency axis labelled "frequency (Hz)".
pub fn spectrum_plot(path_stem: impl AsRef<Path>, plot: &SpectrumPlot) -> Result<PlotFiles> {
    let lines = LinePlot {
        title: plot.title.clone(),
        x_label: "frequency (Hz)".into(),
        y_label: plot.y_label.clone(),
        x_log: plot.x_log,
        y_log: false,
        series: plot.series.clone(),
    };
    line_plot(path_stem, &lines)
}

// ---------------------------------------------------------------- area plots

/// Stacked or overlaid filled histories (e.g. energies against time) to
/// `<path_stem>.png/.svg`. Non-finite values count as 0 in the fill and are marked by a
/// grey × at the bottom axis.
pub fn area_plot(path_stem: impl AsRef<Path>, plot: &AreaPlot) -> Result<PlotFiles> {
    check_label("x_label", &plot.x_label)?;
    check_label("y_label", &plot.y_label)?;
    check_series("series", &plot.series)?;
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
        let xe = extent(self.series.iter().flat_map(|s| s.x.iter().copied()), false)
            .ok_or("no x values")?;
        let ye = extent(
            bands
                .iter()
                .flat_map(|(lo, hi)| lo.iter().chain(hi.iter()).copied()),
            false,
        )
        .ok_or("no y values")?;
        let xr = xe.0..xe.1;
        let yr = padded(ye, false);
        let y_bottom = yr.start;
        let mut chart = frame(
            area,
            &self.title,
            RangedCoordf64::from(xr),
            RangedCoordf64::from(yr),
        )?;
        axes(&mut chart, &self.x_label, &self.y_label, true)?;
        let fill_alpha = if self.stacked { 0.55 } else { 0.25 };
        let mut failed_x = Vec::new();
        for (k, (s, (lo, hi))) in self.series.iter().zip(&bands).enumerate() {
            let c = colour(k);
            let mut outline: Vec<(f64, f64)> =
                s.x.iter().copied().zip(hi.iter().copied()).collect();
            let top = outline.clone();
            outline.extend(s.x.iter().copied().zip(lo.iter().copied()).rev());
            let fill = c.mix(fill_alpha).filled();
            let drawn = chart
                .draw_series(std::iter::once(Polygon::new(outline, fill)))
                .map_err(e2s)?;
            if !s.label.is_empty() {
                drawn
                    .label(&s.label)
                    .legend(move |(x, y)| Rectangle::new([(x, y - 6), (x + 20, y + 6)], fill));
            }
            chart
                .draw_series(LineSeries::new(top, c.stroke_width(2)))
                .map_err(e2s)?;
            failed_x.extend(
                s.x.iter()
                    .zip(&s.y)
                    .filter(|(_, y)| !y.is_finite())
                    .map(|(x, _)| *x),
            );
        }
        failed_marks(&mut chart, &failed_x, y_bottom)?;
        legend(&mut chart, false)?;
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

/// A heat map with colour bar, contour lines and overlay curves to
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
    write_figure(path_stem.as_ref(), map)
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
        with_axes!(
            self.x_log,
            self.y_log,
            xr,
            yr,
            draw_heat(&main, self, &ex, &ey)
        )?;
        draw_colorbar(&bar, self)
    }
}

fn viridis(z: f64, (lo, hi): (f64, f64)) -> RGBColor {
    let t = ((z - lo) / (hi - lo)).clamp(0.0, 1.0);
    ViridisRGB::get_color(t)
}

fn draw_heat<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    map: &HeatMap,
    ex: &[f64],
    ey: &[f64],
    xc: X,
    yc: Y,
) -> std::result::Result<(), String>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let nx = map.x.len();
    let zr = map.z_range();
    let mut chart = frame(area, &map.title, xc, yc)?;
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
    for (k, segments) in contours.iter().enumerate() {
        let drawn = chart
            .draw_series(
                segments
                    .iter()
                    .map(|s| PathElement::new(vec![s[0], s[1]], BLACK.stroke_width(1))),
            )
            .map_err(e2s)?;
        if k == 0 {
            any_label = true;
            let mut text = String::from("contours at ");
            let shown: Vec<String> = map.contour_levels.iter().take(6).map(fmt_tick).collect();
            text.push_str(&shown.join(", "));
            if map.contour_levels.len() > 6 {
                text.push_str(", …");
            }
            drawn.label(text).legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1))
            });
        }
    }
    for (k, s) in map.overlay_lines.iter().enumerate() {
        let style = OVERLAY[k % OVERLAY.len()].stroke_width(2);
        let pts: Vec<(f64, f64)> =
            s.x.iter()
                .copied()
                .zip(s.y.iter().copied())
                .filter(|(x, y)| usable(*x, map.x_log) && usable(*y, map.y_log))
                .collect();
        let drawn = chart
            .draw_series(DashedLineSeries::new(pts, 12, 6, style))
            .map_err(e2s)?;
        if !s.label.is_empty() {
            any_label = true;
            drawn
                .label(&s.label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        }
    }
    if any_label {
        legend(&mut chart, true)?;
    }
    Ok(())
}

fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    map: &HeatMap,
) -> std::result::Result<(), String> {
    let (lo, hi) = map.z_range();
    // Align with the main frame: caption (~26 px + gap) + margin on top, label area below.
    let mut chart = ChartBuilder::on(area)
        .margin_top(18 + 40)
        .margin_bottom(18 + 58)
        .margin_right(50)
        .margin_left(4)
        .y_label_area_size(96)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(e2s)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(&map.colorbar_label)
        .axis_desc_style((FONT, 20))
        .label_style((FONT, 15))
        .y_label_formatter(&fmt_tick)
        .draw()
        .map_err(e2s)?;
    let steps = 256;
    chart
        .draw_series((0..steps).map(|k| {
            let a = lo + (hi - lo) * k as f64 / steps as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / steps as f64;
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                viridis(0.5 * (a + b), (lo, hi)).filled(),
            )
        }))
        .map_err(e2s)?;
    chart
        .draw_series(
            map.contour_levels
                .iter()
                .filter(|l| **l >= lo && **l <= hi)
                .map(|&l| PathElement::new(vec![(0.0, l), (1.0, l)], BLACK.stroke_width(2))),
        )
        .map_err(e2s)?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(0.0, lo), (1.0, hi)],
            BLACK.stroke_width(1),
        )))
        .map_err(e2s)?;
    Ok(())
}
