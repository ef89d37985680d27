//! Pictures of studies: line plots (families of curves), heat maps with a colour bar,
//! contour lines and overlays, stacked or overlaid area plots (energy histories) and
//! spectra in dB.
//!
//! The API takes plain data (no dependency on the impact engine). Every picture is written
//! twice, `<stem>.png` (raster, 100 px per inch-ish, small for heat maps) and `<stem>.svg`
//! (vector), each atomically: rendered to a temporary file in the target directory and
//! renamed over the final name, so a reader never sees a half-written picture.
//!
//! Rendering is plotters (bitmap and SVG back ends) with the DejaVu Sans font bundled in
//! `assets/` (Bitstream Vera licence, `assets/DejaVuSans-LICENSE.txt`), registered from
//! bytes: the machine may have no system fonts. plotters has no contour primitive, so
//! iso-lines are computed here by marching squares ([`contour`]).
//!
//! Conventions: axis labels must be given and should carry quantity and unit, e.g.
//! `"frequency (Hz)"`. Logarithmic axes are labelled at 1-2-5 values (1, 2, 5, 10, 20, …;
//! [`axis::log_ticks`]), linear axes and the colour bar at multiples of a 1-2-5 step. Non-finite values (failed design points) are never drawn as data:
//! lines break there and a grey × marks the failed abscissa at the bottom of the frame;
//! heat-map cells are painted neutral grey and listed in the legend as "failed".
//! Points ≤ 0 on a logarithmic axis are left out.

pub mod axis;
mod charts;
pub mod contour;
pub mod mesh;

pub use axis::{nice_levels, nice_ticks};
pub use charts::{area_plot, heat_map, line_plot, spectrum_plot};

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::{Error, Result};

/// How a curve is stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LineStyle {
    /// The chart's default: solid for curves, dashed for heat-map overlays.
    #[default]
    Auto,
    /// Continuous line.
    Solid,
    /// Dashes of 12 px with 6 px gaps.
    Dashed,
    /// Dots: 3 px dashes with 5 px gaps.
    Dotted,
}

/// One curve: `y` against `x` (same length), named in the legend by `label`
/// (an empty label leaves the curve out of the legend).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Abscissae.
    pub x: Vec<f64>,
    /// Ordinates; non-finite values are failed points.
    pub y: Vec<f64>,
    /// Stroke: solid, dashed or dotted (e.g. solid for the damper, dashed for the added
    /// mass on one chart). Default: the chart's own.
    pub style: LineStyle,
    /// Colour as 8-bit RGB; `None` takes the palette colour of the series' position
    /// (Tableau 10 on curves, red/white/orange/pink on heat maps).
    pub color: Option<[u8; 3]>,
    /// Stroke width in pixels; 0 takes the default (2 px).
    pub width: u32,
}

/// A shaded range of x, `from..to` (in the x axis' unit), drawn across the frame's height behind
/// the curves in a light tint of `color`; its `label` is a legend entry (once per label).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Band {
    pub from: f64,
    pub to: f64,
    pub label: String,
    /// 8-bit RGB, drawn at 20 % opacity.
    pub color: [u8; 3],
}

/// A labelled vertical line at abscissa `x` (in the x axis' unit, e.g. s), drawn across
/// the frame as a dark dashed line with `label` written beside its top, e.g.
/// "slider leaves" or "peak PE_Kd".
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Marker {
    /// Abscissa, in the unit of the x axis.
    pub x: f64,
    /// Text beside the line (empty: the line alone).
    pub label: String,
}

/// A labelled point on a heat map (e.g. the paper's operating points P, Q, R, S, T, U):
/// a white disc ringed in black at `(x, y)` (axis units) and `label` in a white box beside it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MarkedPoint {
    /// Text beside the point, e.g. "Q".
    pub label: String,
    /// Abscissa, in the unit of the x axis.
    pub x: f64,
    /// Ordinate, in the unit of the y axis.
    pub y: f64,
}

/// A family of curves on common axes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LinePlot {
    /// Title above the frame.
    pub title: String,
    /// Horizontal axis label with unit, e.g. `"time (s)"`.
    pub x_label: String,
    /// Vertical axis label with unit.
    pub y_label: String,
    /// Logarithmic horizontal axis.
    pub x_log: bool,
    /// Logarithmic vertical axis.
    pub y_log: bool,
    /// The curves, coloured in order from a ten-colour palette (Tableau 10).
    pub series: Vec<Series>,
    /// Labelled vertical lines (e.g. the instant the slider leaves).
    pub markers: Vec<Marker>,
    /// Shaded ranges of x behind the curves (e.g. the regimes of a stroke-rate map).
    pub bands: Vec<Band>,
    /// One panel per series, stacked top to bottom on a common x axis and a common y
    /// range, each named by its series label; for histories of several cases that would
    /// hide one another when overlaid. The title is written once above the panels.
    pub panels: bool,
    /// Horizontal range shown, `(from, to)` in the x unit; `None` fits the data. Points
    /// outside it are not drawn (e.g. the first 0.3 s of a 2 s history).
    pub x_range: Option<(f64, f64)>,
    /// A second frame beside the first (right, 40 % of a wider picture) showing only this
    /// horizontal range, `(from, to)` in the x unit, with its own y range fitted to the points
    /// inside it, e.g. the collision's first milliseconds beside the whole history. Titled
    /// `zoom_title`; no legend of its own (the left frame's applies).
    pub zoom: Option<(f64, f64)>,
    /// Title of the [`zoom`](Self::zoom) frame.
    pub zoom_title: String,
}

/// A field `z(x, y)` on a rectilinear grid, drawn as coloured cells (viridis) with a colour
/// bar, optional contour lines and overlay curves.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HeatMap {
    /// Title above the frame.
    pub title: String,
    /// Horizontal axis label with unit.
    pub x_label: String,
    /// Vertical axis label with unit.
    pub y_label: String,
    /// Cell-centre abscissae, strictly increasing (`nx ≥ 2`).
    pub x: Vec<f64>,
    /// Cell-centre ordinates, strictly increasing (`ny ≥ 2`).
    pub y: Vec<f64>,
    /// Values, row-major `ny × nx`: `z[j * nx + i]` at `(x[i], y[j])`. Non-finite = failed.
    pub z: Vec<f64>,
    /// Logarithmic horizontal axis (cell edges at geometric midpoints).
    pub x_log: bool,
    /// Logarithmic vertical axis.
    pub y_log: bool,
    /// Levels of black contour lines (also marked on the colour bar).
    pub contour_levels: Vec<f64>,
    /// Curves drawn over the map, e.g. the ω_d = ω_s diagonal, each with its legend
    /// entry; dashed unless the series' `style` says otherwise.
    pub overlay_lines: Vec<Series>,
    /// Colour bar label with unit.
    pub colorbar_label: String,
    /// Labelled points drawn over the map (operating points P, Q, R …).
    pub points: Vec<MarkedPoint>,
}

/// Several histories on a common time axis, filled, either stacked (each band is one
/// series, the top edge is the total) or overlaid (each filled down to zero).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AreaPlot {
    /// Title above the frame.
    pub title: String,
    /// Horizontal axis label with unit.
    pub x_label: String,
    /// Vertical axis label with unit.
    pub y_label: String,
    /// Stack the series (they must then share the same `x`).
    pub stacked: bool,
    /// The histories, bottom band first when stacked.
    pub series: Vec<Series>,
    /// Labelled vertical lines (e.g. "slider leaves", "peak PE_Kd", or a histogram's mean
    /// and P95).
    pub markers: Vec<Marker>,
}

/// Spectra in dB against frequency in Hz (a line plot with a linear dB axis).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpectrumPlot {
    /// Title above the frame.
    pub title: String,
    /// Level label with its reference, e.g. `"acceleration level (dB re 1 m/s²)"`.
    pub y_label: String,
    /// Logarithmic frequency axis.
    pub x_log: bool,
    /// Spectra: `x` in Hz, `y` in dB (`-inf` for empty bins is left out).
    pub series: Vec<Series>,
    /// Labelled vertical lines at frequencies in Hz (e.g. a mode's frequency).
    pub markers: Vec<Marker>,
    /// Frequency range shown, `(from, to)` in Hz; `None` fits the data.
    pub x_range: Option<(f64, f64)>,
}

/// The two files a picture was written to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlotFiles {
    /// `<stem>.png`.
    pub png: PathBuf,
    /// `<stem>.svg`.
    pub svg: PathBuf,
}

/// The texts of an SVG picture's `<text>` elements in document order, trimmed (as written:
/// XML escapes are kept) — to check what a picture says (labels, legends, axis names).
pub fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = &t[t.find('>')? + 1..];
            Some(body[..body.find("</text>")?].trim().to_string())
        })
        .collect()
}

/// Font family name the bundled font is registered under.
pub(crate) const FONT: &str = "sans-serif";

static FONT_BYTES: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

/// Registers the bundled DejaVu Sans for plotters (once per process).
fn ensure_font() -> Result<()> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::numerical(
            "plotting",
            "the bundled font assets/DejaVuSans.ttf could not be loaded",
        ))
    }
}

/// Something that can draw itself on any plotters back end.
pub(crate) trait Figure {
    /// Picture size in pixels (width, height).
    fn size(&self) -> (u32, u32);
    /// Draws on `area`; errors are returned as text.
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String>;
}

/// A unique temporary name next to `final_path`, keeping its extension.
fn temporary_path(dir: &Path, name: &str, ext: &str) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    dir.join(format!(".{name}.{}.{n}.tmp.{ext}", std::process::id()))
}

/// Writes `figure` as `<stem>.png` and `<stem>.svg`, each through a temporary file renamed
/// into place.
pub(crate) fn write_figure<F: Figure>(stem: &Path, figure: &F) -> Result<PlotFiles> {
    ensure_font()?;
    let name = stem
        .file_name()
        .and_then(|n| n.to_str())
        .filter(|n| !n.is_empty())
        .ok_or_else(|| {
            Error::invalid(
                "path_stem",
                format!("'{}' does not end in a file name", stem.display()),
            )
        })?
        .to_string();
    let dir = match stem.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let png = dir.join(format!("{name}.png"));
    let svg = dir.join(format!("{name}.svg"));
    let size = figure.size();
    let draw_error = |path: &Path, msg: String| Error::io(path, std::io::Error::other(msg));

    // PNG: drawn into an RGB buffer, encoded by `png`.
    let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    let rendered = (|| {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        figure.draw(&root)?;
        root.present().map_err(|e| e.to_string())
    })();
    if let Err(msg) = rendered {
        return Err(draw_error(&png, msg));
    }
    let tmp_png = temporary_path(&dir, &name, "png");
    if let Err(e) = write_png(&tmp_png, size, &rgb) {
        let _ = std::fs::remove_file(&tmp_png);
        return Err(Error::io(&png, e));
    }
    rename(&tmp_png, &png)?;

    // SVG, rendered to memory.
    let mut text = String::new();
    let rendered = (|| {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        figure.draw(&root)?;
        root.present().map_err(|e| e.to_string())
    })();
    if let Err(msg) = rendered {
        return Err(draw_error(&svg, msg));
    }
    let tmp_svg = temporary_path(&dir, &name, "svg");
    if let Err(e) = std::fs::write(&tmp_svg, text.as_bytes()) {
        let _ = std::fs::remove_file(&tmp_svg);
        return Err(Error::io(&svg, e));
    }
    rename(&tmp_svg, &svg)?;
    Ok(PlotFiles { png, svg })
}

/// Encodes an 8-bit RGB buffer of `size` (width, height) pixels as a PNG file.
fn write_png(path: &Path, size: (u32, u32), rgb: &[u8]) -> std::io::Result<()> {
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut enc = png::Encoder::new(file, size.0, size.1);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(std::io::Error::other)?;
    w.write_image_data(rgb).map_err(std::io::Error::other)?;
    w.finish().map_err(std::io::Error::other)
}

fn rename(from: &Path, to: &Path) -> Result<()> {
    std::fs::rename(from, to).map_err(|e| {
        let _ = std::fs::remove_file(from);
        Error::io(to, e)
    })
}
