//! Figures and tables of reports: each function turns one analysis result into picture files
//! (`<stem>.png` and `<stem>.svg`, [`crate::plot`]) and data files (CSV) written into the page's
//! directory, and returns the captioned [`Figure`] (or the [`Table`]) that shows them.
//!
//! The functions know nothing about the page they end up on: `meid report` (one machine) and
//! `meid paper` (the paper's figures) both call them. A caption always says what is drawn, the
//! measure and the unit; a picture's `src` is its PNG (it renders in every browser), and the
//! SVG and the data are linked under the caption.
//!
//! Plot structs are written with `..Default::default()` even where every field is set, so
//! that fields added to them later keep their defaults here.
#![allow(clippy::needless_update)]

use std::fmt::Write as _;
use std::path::Path;

use super::html::{Figure, Table};
use crate::analysis::blows::BlowsRun;
use crate::analysis::compare::{CaseName, ComparisonResult, SpectrumMethod};
use crate::analysis::esd::esd_level_db;
use crate::analysis::montecarlo::{histogram_outline, Stats};
use crate::analysis::sweep::{Spacing, SweepResult};
use crate::modal::truncation::TruncationRow;
use crate::model::fem::ModeReport;
use crate::plot::{self, HeatMap, LinePlot, Series, SpectrumPlot};
use crate::{Error, Result};

/// The figure block of a picture written as `<stem>.png`/`.svg`, with its data files.
fn figure(stem: &str, alt: &str, caption: String, data: &[&str]) -> Figure {
    let mut links = vec![format!("{stem}.svg")];
    links.extend(data.iter().map(|d| d.to_string()));
    Figure {
        src: format!("{stem}.png"),
        alt: alt.into(),
        caption,
        data: links,
    }
}

/// Shortest round-trip text of a number for CSV files.
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:e}")
    } else {
        String::new()
    }
}

/// `v` with `digits` significant digits, plain or in exponent form depending on its size.
pub fn sig(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return "—".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    if (-3..=5).contains(&e) {
        let decimals = (digits as i32 - 1 - e).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.prec$e}", prec = digits.saturating_sub(1))
    }
}

/// `v` with up to 6 significant digits and no trailing zeros (`60`, `62.5`, `4.3e7`).
pub fn plain(v: f64) -> String {
    let s = sig(v, 6);
    let (mantissa, exponent) = match s.split_once('e') {
        Some((m, e)) => (m, format!("e{e}")),
        None => (s.as_str(), String::new()),
    };
    let mantissa = if mantissa.contains('.') {
        mantissa.trim_end_matches('0').trim_end_matches('.')
    } else {
        mantissa
    };
    format!("{mantissa}{exponent}")
}

/// A point marked on a map, in axis values: drawn as a labelled point (a ringed disc with
/// its label, e.g. "P" or "design", in a box beside it).
pub use crate::plot::MarkedPoint as Mark;

/// What [`energy_map`] draws: one metric of a two-quantity sweep over its grid.
#[derive(Debug, Clone, Default)]
pub struct MapSpec<'a> {
    /// The sweep (exactly two varied quantities, each with strictly increasing values).
    pub sweep: Option<&'a SweepResult>,
    /// The [`crate::analysis::sweep::METRICS`] column drawn.
    pub metric: String,
    /// Factor applied to the metric in the picture (e.g. 100 for a ratio in %; `None`: 1).
    /// The CSV keeps the sweep's values.
    pub z_scale: Option<f64>,
    /// Title above the map.
    pub title: String,
    /// Axis labels (quantity and unit, in the paper's terms: `ω_s/ω_6 (1)`).
    pub x_label: String,
    pub y_label: String,
    /// Colour-bar label with unit.
    pub colorbar_label: String,
    /// Points to mark (the current design; the paper's operating points P … U), each drawn
    /// as a labelled point.
    pub marks: Vec<Mark>,
    /// Draw the line x = y with this legend text (e.g. `ω_d = ω_s` on a ω_s/ω_ref × ω_d/ω_ref
    /// map); empty: no line.
    pub diagonal_label: String,
    /// The caption (what the map shows; the figure adds nothing to it).
    pub caption: String,
}

/// A heat map of `spec.metric` over the sweep's two quantities, with contour lines, the
/// line x = y and the marks ([`marked_heat_map`]); writes `<stem>.png/.svg` and the
/// sweep table `<stem>.csv`.
pub fn energy_map(dir: &Path, stem: &str, spec: &MapSpec) -> Result<Figure> {
    let sweep = spec
        .sweep
        .ok_or_else(|| Error::invalid("energy map", "no sweep given"))?;
    let vary = &sweep.spec.vary;
    if vary.len() != 2 {
        return Err(Error::invalid(
            "energy map",
            format!("needs a sweep over two quantities, got {}", vary.len()),
        ));
    }
    let (x, y) = (&vary[0].values, &vary[1].values);
    let increasing = |v: &[f64]| v.len() >= 2 && v.windows(2).all(|w| w[0] < w[1]);
    if !increasing(x) || !increasing(y) {
        return Err(Error::invalid(
            "energy map",
            "the values of both quantities must be strictly increasing",
        ));
    }
    let (nx, ny) = (x.len(), y.len());
    // Grid order is row-major with the last quantity fastest: point (i, j) is i·ny + j.
    let mut z = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            z.push(sweep.points.get(i * ny + j).map_or(f64::NAN, |p| {
                p.metric(&spec.metric) * spec.z_scale.unwrap_or(1.0)
            }));
        }
    }
    let map = marked_heat_map(
        HeatMap {
            title: spec.title.clone(),
            x_label: spec.x_label.clone(),
            y_label: spec.y_label.clone(),
            x: x.clone(),
            y: y.clone(),
            z,
            x_log: vary[0].spacing == Spacing::Log,
            y_log: vary[1].spacing == Spacing::Log,
            colorbar_label: spec.colorbar_label.clone(),
            ..Default::default()
        },
        &spec.marks,
        &spec.diagonal_label,
    );
    plot::heat_map(dir.join(stem), &map)?;
    let csv = format!("{stem}.csv");
    crate::io::write_atomic(&dir.join(&csv), sweep.csv().as_bytes())?;
    Ok(figure(stem, &spec.title, spec.caption.clone(), &[&csv]))
}

/// Contour levels at round values (multiples of a 1-2-5 step, [`plot::nice_levels`]), at most
/// seven, strictly between the smallest and largest finite values of `z`; none when `z` is
/// constant or empty. The colour bar marks and labels each.
pub fn round_contour_levels(z: &[f64]) -> Vec<f64> {
    let (lo, hi) = z
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    plot::nice_levels(lo, hi, 7)
}

/// An energy map as the paper draws it (Figs. 3, 12, 16): `map` (grid, values, axes) with
/// contour lines ([`round_contour_levels`] unless `map` gives its own), the line x = y over
/// the range both axes share as a dashed overlay named `diagonal_label` in the legend (e.g.
/// `ω_d = ω_s` on a ω_s/ω_6 × ω_d/ω_6 map; empty: no line), and `marks` as labelled points
/// (the design, or the paper's P … U); marks at one place share a point labelled "Q = S".
/// Marks outside the grid are left out (a point off the frame would be drawn over the axes).
pub fn marked_heat_map(mut map: HeatMap, marks: &[Mark], diagonal_label: &str) -> HeatMap {
    if map.contour_levels.is_empty() {
        map.contour_levels = round_contour_levels(&map.z);
    }
    let (Some(&x0), Some(&x1), Some(&y0), Some(&y1)) =
        (map.x.first(), map.x.last(), map.y.first(), map.y.last())
    else {
        return map;
    };
    if !diagonal_label.is_empty() {
        let (a, b) = (x0.max(y0), x1.min(y1));
        if a < b {
            map.overlay_lines.push(Series {
                label: diagonal_label.into(),
                x: vec![a, b],
                y: vec![a, b],
                ..Default::default()
            });
        }
    }
    // Marks at one place (within 1e-6 relative, e.g. the paper's Q and S) share one point
    // labelled "Q = S": two boxes over each other would hide a label.
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
    for m in marks
        .iter()
        .filter(|m| (x0..=x1).contains(&m.x) && (y0..=y1).contains(&m.y))
    {
        match map
            .points
            .iter_mut()
            .find(|p| same(p.x, m.x) && same(p.y, m.y))
        {
            Some(p) => {
                p.label = format!("{} = {}", p.label, m.label);
            }
            None => map.points.push(m.clone()),
        }
    }
    map
}

/// One channel of a comparison's histories and spectra.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// The bed acceleration a_B at the measurement point B (m/s²).
    Acceleration,
    /// The force to the floor F (N).
    FloorForce,
}

impl Channel {
    /// Both channels, in the order of the comparison's spectra.
    pub const ALL: [Channel; 2] = [Channel::Acceleration, Channel::FloorForce];

    /// Index of the channel in [`crate::analysis::compare::CaseResult::spectra`].
    pub fn index(self) -> usize {
        match self {
            Channel::Acceleration => 0,
            Channel::FloorForce => 1,
        }
    }

    /// File-name part: `acceleration`, `floor-force`.
    pub fn stem(self) -> &'static str {
        match self {
            Channel::Acceleration => "acceleration",
            Channel::FloorForce => "floor-force",
        }
    }

    /// What it is, in words: "bed acceleration at B", "force to the floor".
    pub fn what(self) -> &'static str {
        match self {
            Channel::Acceleration => "bed acceleration at B",
            Channel::FloorForce => "force to the floor",
        }
    }

    /// SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Channel::Acceleration => "m/s²",
            Channel::FloorForce => "N",
        }
    }

    /// Axis label with unit: "acceleration (m/s²)", "force (N)".
    pub fn axis_label(self) -> &'static str {
        match self {
            Channel::Acceleration => "acceleration (m/s²)",
            Channel::FloorForce => "force (N)",
        }
    }

    /// The channel's samples in a history.
    pub fn samples(self, h: &crate::analysis::History) -> &[f64] {
        match self {
            Channel::Acceleration => &h.bed_acceleration_m_per_s2,
            Channel::FloorForce => &h.floor_force_n,
        }
    }

    /// The comparison's exact time peak of the channel in a case.
    pub fn peak(self, c: &crate::analysis::compare::CaseResult) -> f64 {
        match self {
            Channel::Acceleration => c.peak_bed_acceleration_m_per_s2,
            Channel::FloorForce => c.peak_floor_force_n,
        }
    }

    /// The ESD level reference of the channel in `r`: `(value in SI² units, text)`, e.g.
    /// `(1, "1 N²·s/Hz")`; levels are `10 log10(ESD / value)` dB.
    pub fn esd_reference(self, r: &ComparisonResult) -> (f64, String) {
        let (ea, ef) = r.esd_references();
        match self {
            Channel::Acceleration => (r.acceleration_reference_m_per_s2.powi(2), ea),
            Channel::FloorForce => (1.0, ef),
        }
    }
}

/// How a case is named in a comparison's legends (e.g. the paper's "added mass on the
/// floating base" instead of [`CaseName::label`]).
pub type CaseLabel<'a> = &'a dyn Fn(CaseName) -> String;

/// [`CaseName::label`] as a [`CaseLabel`].
pub fn default_case_label(c: CaseName) -> String {
    c.label().into()
}

/// Stroke of a case in overlaid spectra: the added mass dashed, so that it stays visible
/// where it coincides with the bare machine.
pub fn case_style(case: CaseName) -> plot::LineStyle {
    match case {
        CaseName::AddedMass => plot::LineStyle::Dashed,
        _ => plot::LineStyle::Solid,
    }
}

/// What the comparison's spectra are, in words (exact, or FFT with its window).
pub fn spectrum_words(r: &ComparisonResult) -> String {
    match r.spectrum {
        SpectrumMethod::Exact => "exact ESD".into(),
        SpectrumMethod::Fft => format!("FFT ESD, {} window", r.window.name()),
    }
}

/// The zoom window `(t0, t0 + 1.5 (t_c − t0))` on a collision ending at `t_c`, for a picture
/// showing `t0..t_shown`; `None` when the collision takes more than 40 % of what is shown (the
/// whole picture is then the zoom) or did not start.
pub fn collision_zoom(t0: f64, t_c: f64, t_shown: f64) -> Option<(f64, f64)> {
    let end = t0 + 1.5 * (t_c - t0);
    (t_c > t0 && end.is_finite() && end - t0 < 0.4 * (t_shown - t0)).then_some((t0, end))
}

/// The title of a zoom frame on `(t0, t1)`.
pub fn zoom_title((t0, t1): (f64, f64)) -> String {
    format!("the collision: first {} ms", sig(1e3 * (t1 - t0), 3))
}

/// The time histories of a channel, one panel per case on a common scale (overlaid, the
/// last-drawn case hid the others), titled `channel.what()`. The window shown runs up to
/// 1.25 × the last instant any case exceeds 2 % of the largest |value| (the rest of the
/// record is the decayed tail), stated in the title; `x_range` holds it (`None`: the whole
/// record).
pub fn history_plot(r: &ComparisonResult, ch: Channel, label: CaseLabel) -> LinePlot {
    let series: Vec<Series> = r
        .cases
        .iter()
        .map(|c| Series {
            label: label(c.case),
            x: c.history.time_s.clone(),
            y: ch.samples(&c.history).to_vec(),
            ..Default::default()
        })
        .collect();
    let peak = series
        .iter()
        .flat_map(|s| s.y.iter())
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let t_end = series
        .iter()
        .flat_map(|s| s.x.iter())
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let t_last = series
        .iter()
        .flat_map(|s| s.x.iter().zip(&s.y))
        .filter(|(_, v)| v.abs() > 0.02 * peak)
        .map(|(t, _)| *t)
        .fold(f64::NEG_INFINITY, f64::max);
    let t0 = series
        .first()
        .and_then(|s| s.x.first())
        .copied()
        .unwrap_or(0.0);
    let shown = 1.25 * (t_last - t0) + t0;
    let zoom = shown.is_finite() && shown > t0 && shown < 0.8 * t_end;
    // Beside it, the collision (the latest of the cases').
    let t_c = r
        .cases
        .iter()
        .filter_map(|c| {
            let h = &c.history;
            crate::analysis::sketch::collision_end(
                &h.time_s,
                &h.contact_force_slider_bed_n,
                &h.contact_force_bed_damper_n,
            )
        })
        .fold(f64::NAN, f64::max);
    let collision = collision_zoom(t0, t_c, if zoom { shown } else { t_end });
    LinePlot {
        title: if zoom {
            format!(
                "{}, first {} s of {} s",
                ch.what(),
                plot::axis::fmt_tick(&(shown - t0)),
                plot::axis::fmt_tick(&(t_end - t0))
            )
        } else {
            ch.what().into()
        },
        x_label: "time (s)".into(),
        y_label: ch.axis_label().into(),
        series,
        panels: true,
        x_range: zoom.then_some((t0, shown)),
        zoom: collision,
        zoom_title: collision.map(zoom_title).unwrap_or_default(),
        ..Default::default()
    }
}

/// A curve of a channel's spectrum: `(x, y)` from the spectrum and the level reference.
type SpectrumCurve<'a> =
    &'a dyn Fn(&crate::analysis::compare::ChannelSpectrum, f64) -> (Vec<f64>, Vec<f64>);

/// One curve per case of a channel's spectrum, `curve(spectrum, reference)` giving its points
/// (added mass dashed).
fn case_curves(
    r: &ComparisonResult,
    ch: Channel,
    label: CaseLabel,
    curve: SpectrumCurve,
) -> Vec<Series> {
    let (reference, _) = ch.esd_reference(r);
    r.cases
        .iter()
        .filter_map(|c| {
            let (x, y) = curve(c.spectra.get(ch.index())?, reference);
            Some(Series {
                label: label(c.case),
                x,
                y,
                style: case_style(c.case),
                ..Default::default()
            })
        })
        .collect()
}

/// The energy spectral densities of a channel in dB ([`Channel::esd_reference`]) against
/// log frequency, the refined peaks merged in, one curve per case (added mass dashed).
pub fn esd_plot(r: &ComparisonResult, ch: Channel, label: CaseLabel) -> SpectrumPlot {
    let (_, text) = ch.esd_reference(r);
    SpectrumPlot {
        title: format!(
            "{}, energy spectral density ({})",
            ch.what(),
            spectrum_words(r)
        ),
        y_label: format!("ESD level (dB re {text})"),
        x_log: true,
        series: case_curves(r, ch, label, &|s, reference| {
            s.level_curve_db(&r.frequency_hz, reference)
        }),
        ..Default::default()
    }
}

/// The one-third-octave band energies of a channel, `10 log10(E_band / ref)` dB drawn as a
/// step over each band, one curve per case.
pub fn band_plot(r: &ComparisonResult, ch: Channel, label: CaseLabel) -> SpectrumPlot {
    let (_, text) = ch.esd_reference(r);
    let steps = |s: &crate::analysis::compare::ChannelSpectrum, reference: f64| {
        let mut x = Vec::new();
        let mut y = Vec::new();
        for (b, e) in r.bands.iter().zip(&s.band_energy) {
            let l = esd_level_db(*e, reference);
            x.extend([b.lower_hz, b.upper_hz]);
            y.extend([l, l]);
        }
        (x, y)
    };
    SpectrumPlot {
        title: format!(
            "{}, one-third-octave band energy ({})",
            ch.what(),
            spectrum_words(r)
        ),
        y_label: format!("band level (dB re {})", text.trim_end_matches("/Hz")),
        x_log: true,
        series: case_curves(r, ch, label, &steps),
        ..Default::default()
    }
}

/// The comparison's figures: per channel (bed acceleration at B, force to the floor) the
/// time histories ([`history_plot`]), the energy spectral densities ([`esd_plot`]) and the
/// one-third-octave band levels ([`band_plot`]). Writes `<prefix>-*.png/.svg` and the data
/// `<prefix>-histories.csv`, `<prefix>-spectra.csv`, `<prefix>-bands.csv`,
/// `<prefix>-reductions.csv`.
pub fn comparison_figures(dir: &Path, prefix: &str, r: &ComparisonResult) -> Result<Vec<Figure>> {
    let histories = format!("{prefix}-histories.csv");
    let spectra = format!("{prefix}-spectra.csv");
    let bands_csv = format!("{prefix}-bands.csv");
    let reductions = format!("{prefix}-reductions.csv");
    crate::io::write_atomic(&dir.join(&histories), histories_csv(r).as_bytes())?;
    crate::io::write_atomic(&dir.join(&spectra), &r.spectra_csv()?)?;
    crate::io::write_atomic(&dir.join(&bands_csv), &r.bands_csv()?)?;
    crate::io::write_atomic(&dir.join(&reductions), &r.table_csv()?)?;
    let mut out = Vec::new();
    let Some(first) = r.cases.first() else {
        return Ok(out);
    };
    let record_s = first.history.time_s.last().copied().unwrap_or(0.0);
    let what = match r.spectrum {
        SpectrumMethod::Exact => "exact energy spectral density of the whole response, free decay included (independent of record length and sample rate)".to_string(),
        SpectrumMethod::Fft => format!(
            "FFT energy spectral density of the sampled record, {} window (depends on record, window and rate)",
            r.window.name()
        ),
    };
    for ch in Channel::ALL {
        let w = ch.what();
        let p = history_plot(r, ch, &default_case_label);
        let shown = p.x_range.map_or(record_s, |(a, b)| b - a);
        let stem = format!("{prefix}-{}-time", ch.stem());
        plot::line_plot(dir.join(&stem), &p)?;
        out.push(figure(
            &stem,
            &format!("{w} against time, three cases"),
            format!(
                "{} {} ({}) after one blow, one panel per case on a common scale: without damper, with the impact damper and with the added mass; the first {} s of the {} s record (output samples at {} Hz; the peaks in the tables are located on the continuous solution: {}).",
                capitalise(w),
                if ch == Channel::Acceleration { "a_B" } else { "F" },
                ch.unit(),
                sig(shown, 3),
                plain(record_s),
                plain(r.sample_rate_hz),
                r.peak_accuracy
            ),
            &[&histories],
        ));
        let esd = esd_plot(r, ch, &default_case_label);
        let bands = band_plot(r, ch, &default_case_label);
        let esd_caption = format!(
            "{}: {what} in {}, the three cases (the added mass dashed); the dominant modes' peaks are located by refinement.",
            capitalise(w),
            esd.y_label
        );
        let bands_caption = format!(
            "{}: energy in each one-third-octave band (IEC 61260-1, base 10), the integral of the ESD over the band, in {}; the three cases.",
            capitalise(w),
            bands.y_label.trim_start_matches("band level ")
        );
        for (p, kind, alt, caption, data) in [
            (esd, "spectrum", "spectrum", esd_caption, &spectra),
            (
                bands,
                "bands",
                "one-third-octave levels",
                bands_caption,
                &bands_csv,
            ),
        ] {
            let stem = format!("{prefix}-{}-{kind}", ch.stem());
            plot::spectrum_plot(dir.join(&stem), &p)?;
            out.push(figure(
                &stem,
                &format!("{w} {alt}, three cases"),
                caption,
                &[data],
            ));
        }
    }
    Ok(out)
}

pub(crate) fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

/// The time histories of every case side by side: `time_s` and, per case, the bed
/// acceleration (m/s²) and the floor force (N).
fn histories_csv(r: &ComparisonResult) -> String {
    let mut s = String::from("time_s");
    for c in &r.cases {
        let _ = write!(
            s,
            ",{0}_bed_acceleration_m_per_s2,{0}_floor_force_n",
            c.case.name()
        );
    }
    s.push('\n');
    let n = r
        .cases
        .iter()
        .map(|c| c.history.time_s.len())
        .min()
        .unwrap_or(0);
    for i in 0..n {
        s.push_str(&num(r.cases[0].history.time_s[i]));
        for c in &r.cases {
            let _ = write!(
                s,
                ",{},{}",
                num(c.history.bed_acceleration_m_per_s2[i]),
                num(c.history.floor_force_n[i])
            );
        }
        s.push('\n');
    }
    s
}

/// The exact time peaks and energy ratio of each case, in physical units.
pub fn case_peaks_table(r: &ComparisonResult) -> Table {
    let rows = r
        .cases
        .iter()
        .map(|c| {
            vec![
                c.case.label().to_string(),
                sig(c.peak_bed_acceleration_m_per_s2, 4),
                sig(c.peak_floor_force_n, 4),
                c.energy_ratio.map_or("—".into(), |e| sig(100.0 * e, 4)),
            ]
        })
        .collect();
    Table {
        caption: format!(
            "Peaks of one blow (located on the continuous solution, not on the samples: {}) and the share of the blow's energy left in the machine",
            r.peak_accuracy
        ),
        header: vec![
            "case".into(),
            "peak |a_B| (m/s²), time peak".into(),
            "peak |F_floor| (N), time peak".into(),
            "E_p+/E_s− (%), energy ratio (paper Eq. 10)".into(),
        ],
        rows,
        ..Default::default()
    }
}

/// Every dB reduction of the comparison with its measure named beside it.
pub fn reductions_table(r: &ComparisonResult) -> Table {
    let mut rows = Vec::new();
    // The baseline against itself (0 dB) says nothing: only the other cases, grouped by
    // measure (the order of first appearance), then by case.
    let mut measures: Vec<&str> = Vec::new();
    for x in &r.reductions {
        if !measures.contains(&x.measure.name()) {
            measures.push(x.measure.name());
        }
    }
    let mut shown: Vec<_> = r
        .reductions
        .iter()
        .filter(|x| x.case != CaseName::NoDamper)
        .collect();
    shown.sort_by_key(|x| measures.iter().position(|m| *m == x.measure.name()));
    for x in shown {
        rows.push(vec![
            x.case.label().to_string(),
            x.metric.clone(),
            x.measure.name().to_string(),
            format!("{:.2}", x.level_db),
            format!("{:.2}", x.no_damper_level_db),
            x.reference.clone(),
            format!("{:+.2}", x.reduction_db),
        ]);
    }
    let estimate = r.cases.iter().any(|c| c.spectrum_is_estimate);
    Table {
        caption: format!(
            "Reductions ΔL = L_none − L_case (dB; positive: quieter than without damper), each with its measure{}",
            if estimate {
                ". Spectral levels of non-linear contact stretches are interpolated between knots: estimates"
            } else {
                ""
            }
        ),
        header: vec![
            "case".into(),
            "quantity".into(),
            "measure".into(),
            "level (dB)".into(),
            "without damper (dB)".into(),
            "level reference".into(),
            "reduction (dB)".into(),
        ],
        rows,
        ..Default::default()
    }
}

/// Peak levels per blow of one train per case: the floor force and the bed acceleration.
/// Writes `<stem>-floor.png/.svg`, `<stem>-acceleration.png/.svg` and `<stem>.csv`.
pub fn blow_train_figures(
    dir: &Path,
    stem: &str,
    runs: &[(CaseName, &BlowsRun)],
    rate_bpm: f64,
) -> Result<Vec<Figure>> {
    let csv = format!("{stem}.csv");
    let mut text = String::from("case,blow,start_s,energy_ratio,peak_bed_acceleration_m_per_s2,peak_floor_force_n,damper_gap_at_strike_m,damper_contact_time_s\n");
    for (case, run) in runs {
        for b in &run.blows {
            let _ = writeln!(
                text,
                "{},{},{},{},{},{},{},{}",
                case.name(),
                b.blow,
                num(b.start_s),
                b.energy_ratio.map_or(String::new(), num),
                num(b.peak_bed_acceleration_m_per_s2),
                num(b.peak_floor_force_n),
                b.damper_gap_at_strike_m.map_or(String::new(), num),
                b.damper_contact_time_s.map_or(String::new(), num),
            );
        }
    }
    crate::io::write_atomic(&dir.join(&csv), text.as_bytes())?;
    let blows = runs.first().map_or(0, |(_, r)| r.blows.len());
    let mut out = Vec::new();
    for (suffix, quantity, label, pick) in [
        (
            "floor",
            "peak force to the floor",
            "peak |F_floor| (N)",
            (|b: &crate::analysis::blows::BlowReport| b.peak_floor_force_n)
                as fn(&crate::analysis::blows::BlowReport) -> f64,
        ),
        (
            "acceleration",
            "peak bed acceleration at B",
            "peak |a_B| (m/s²)",
            |b: &crate::analysis::blows::BlowReport| b.peak_bed_acceleration_m_per_s2,
        ),
    ] {
        let series = runs
            .iter()
            .map(|(case, run)| Series {
                label: case.label().into(),
                x: run.blows.iter().map(|b| b.blow as f64).collect(),
                y: run.blows.iter().map(pick).collect(),
                ..Default::default()
            })
            .collect();
        let s = format!("{stem}-{suffix}");
        plot::line_plot(
            dir.join(&s),
            &LinePlot {
                title: format!(
                    "{quantity} per blow, {blows} blows at {} /min",
                    plain(rate_bpm)
                ),
                x_label: "blow number (1)".into(),
                y_label: label.into(),
                series,
                ..Default::default()
            },
        )?;
        out.push(figure(
            &s,
            &format!("{quantity} per blow"),
            format!(
                "{} of each blow (exact time peak within the blow interval, {label}) in a train of {blows} blows at {} blows/min, without damper, with the impact damper and with the added mass; each blow starts from the state the previous one left.",
                capitalise(quantity),
                plain(rate_bpm)
            ),
            &[&csv],
        ));
    }
    Ok(out)
}

/// A histogram of `values` (successful Monte Carlo samples) with its mean and P95 drawn as
/// vertical lines; writes `<stem>.png/.svg` and `<stem>.csv` (the values).
pub fn histogram_figure(
    dir: &Path,
    stem: &str,
    quantity: &str,
    unit_label: &str,
    values: &[f64],
    stats: &Stats,
    caption: String,
) -> Result<Figure> {
    let bins = ((values.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
    let (x, y) = histogram_outline(values, bins);
    if x.is_empty() {
        return Err(Error::invalid(
            "histogram",
            format!("no finite value of {quantity} to draw"),
        ));
    }
    let top = y.iter().copied().fold(0.0_f64, f64::max);
    let series = vec![
        Series {
            label: format!("samples ({})", values.len()),
            x,
            y,
            ..Default::default()
        },
        Series {
            label: format!("mean {}", sig(stats.mean, 4)),
            x: vec![stats.mean, stats.mean],
            y: vec![0.0, top],
            ..Default::default()
        },
        Series {
            label: format!("P95 {}", sig(stats.p95, 4)),
            x: vec![stats.p95, stats.p95],
            y: vec![0.0, top],
            ..Default::default()
        },
    ];
    plot::line_plot(
        dir.join(stem),
        &LinePlot {
            title: format!("{quantity}: {} samples", values.len()),
            x_label: unit_label.into(),
            y_label: "samples per bin (1)".into(),
            series,
            ..Default::default()
        },
    )?;
    let csv = format!("{stem}.csv");
    let mut text = format!("{}\n", stem.replace('-', "_"));
    for v in values {
        text.push_str(&num(*v));
        text.push('\n');
    }
    crate::io::write_atomic(&dir.join(&csv), text.as_bytes())?;
    Ok(figure(
        stem,
        &format!("histogram of {quantity}"),
        caption,
        &[&csv],
    ))
}

/// The mode table: frequency, signed mass-normalised shape value ψ along the impact axis at the
/// named points (1/√kg), effective vertical mass (FE models) and whether the mode is retained.
pub fn mode_table(report: &ModeReport) -> Table {
    let points: Vec<String> = report
        .modes
        .first()
        .map(|r| r.psi_per_sqrt_kg.keys().cloned().collect())
        .unwrap_or_default();
    let fe = report.modes.iter().any(|m| m.effective_mass_kg.is_some());
    let mut header = vec!["mode".to_string(), "frequency (Hz)".into()];
    header.extend(points.iter().map(|p| format!("ψ({p}) (1/√kg)")));
    if fe {
        header.push("effective mass z (kg)".into());
    }
    header.push("retained".into());
    let mut rows = Vec::new();
    let mut row_class = Vec::new();
    for m in &report.modes {
        let mut row = vec![m.index.to_string(), sig(m.frequency_hz, 5)];
        row.extend(
            points
                .iter()
                .map(|p| m.psi_per_sqrt_kg.get(p).map_or("—".into(), |v| sig(*v, 4))),
        );
        if fe {
            row.push(
                m.effective_mass_kg
                    .as_ref()
                    .map_or("—".into(), |e| sig(e.z, 4)),
            );
        }
        row.push(if m.selected { "yes" } else { "no" }.into());
        rows.push(row);
        row_class.push(if m.selected { "ok" } else { "" }.to_string());
    }
    Table {
        caption: format!(
            "Modes of the structure ({} solver{}); retained: {}",
            report.solver,
            if report.dofs > 0 {
                format!(", {} DOFs", report.dofs)
            } else {
                String::new()
            },
            report.selection
        ),
        header,
        rows,
        row_class,
    }
}

/// The truncation table: static flexibility at each role point and the share the retained
/// modes carry (below 95 % is flagged).
pub fn truncation_table(rows: &[TruncationRow]) -> Table {
    Table {
        caption: "Static flexibility captured by the retained modes: G_PP = fᵀK⁻¹f of the full structure (elastic part) against Σ ψ²/ω² over the retained modes".into(),
        header: vec![
            "point".into(),
            "roles".into(),
            "G_PP (m/N)".into(),
            "retained modes (m/N)".into(),
            "captured share (%)".into(),
        ],
        rows: rows
            .iter()
            .map(|r| {
                vec![
                    r.point.clone(),
                    r.roles.join(", "),
                    sig(r.static_flexibility_m_per_n, 4),
                    sig(r.modal_flexibility_m_per_n, 4),
                    format!("{:.2}", 100.0 * r.captured_share),
                ]
            })
            .collect(),
        row_class: rows
            .iter()
            .map(|r| {
                if r.captured_share < crate::modal::truncation::SHARE_WARNING {
                    "no".into()
                } else {
                    "ok".into()
                }
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::sig;

    #[test]
    fn significant_digits() {
        assert_eq!(sig(6.3512, 3), "6.35");
        assert_eq!(sig(283.04, 4), "283.0");
        assert_eq!(sig(4.298e7, 4), "4.298e7");
        assert_eq!(sig(0.0123, 2), "0.012");
        assert_eq!(sig(f64::NAN, 2), "—");
        assert_eq!(sig(0.0, 3), "0");
        assert_eq!(super::plain(60.0), "60");
        assert_eq!(super::plain(62.5), "62.5");
        assert_eq!(super::plain(4.3e7), "4.3e7");
        assert_eq!(super::plain(100.0), "100");
    }

    #[test]
    fn energy_map_marks_are_labelled_points_and_the_rule_an_overlay() {
        use super::{marked_heat_map, Mark};
        let x: Vec<f64> = (0..9).map(|i| 10.0 * 1.5_f64.powi(i)).collect();
        let y = x.clone();
        let z: Vec<f64> = (0..81)
            .map(|k| ((k % 9) as f64 - (k / 9) as f64).abs())
            .collect();
        let mark = |l: &str, x: f64, y: f64| Mark {
            label: l.into(),
            x,
            y,
        };
        let marks = [
            mark("P", 150.0, 25.0),
            mark("Q", 150.0, 150.0),
            mark("R", 150.0, 220.0),
            mark("S", 150.0 * (1.0 + 1e-12), 150.0),
            mark("outside", 1e4, 20.0),
        ];
        let mut grid = crate::plot::HeatMap::default();
        (grid.x, grid.y, grid.z) = (x.clone(), y, z);
        (grid.x_log, grid.y_log) = (true, true);
        grid.x_label = "ω_s/ω_6 (1)".into();
        grid.y_label = "ω_d/ω_6 (1)".into();
        grid.colorbar_label = "E_p+/E_s− (1)".into();
        let map = marked_heat_map(grid, &marks, "ω_d = ω_s");
        // The marks inside the grid are labelled points, in order; none is drawn as a curve.
        let labels: Vec<&str> = map.points.iter().map(|p| p.label.as_str()).collect();
        assert_eq!(labels, vec!["P", "Q = S", "R"]);
        assert_eq!((map.points[0].x, map.points[0].y), (150.0, 25.0));
        // One overlay: the rule ω_d = ω_s over the range both axes share, named in the legend.
        assert_eq!(map.overlay_lines.len(), 1);
        let rule = &map.overlay_lines[0];
        assert_eq!(rule.label, "ω_d = ω_s");
        assert_eq!(rule.x, rule.y);
        assert_eq!(rule.x, vec![x[0], x[8]]);
        // Seven contours strictly inside the values' range (0 … 8).
        assert_eq!(map.contour_levels.len(), 7);
        assert!(map.contour_levels.iter().all(|l| *l > 0.0 && *l < 8.0));
        // Drawn: the labels and the legend entry are text of the picture, the axes are named
        // after the reference mode.
        let dir = std::env::temp_dir().join(format!("meid-figures-map-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let files = crate::plot::heat_map(dir.join("map"), &map).unwrap();
        let texts = crate::plot::svg_texts(&std::fs::read_to_string(&files.svg).unwrap());
        for t in ["P", "Q = S", "R", "ω_d = ω_s", "ω_s/ω_6 (1)", "ω_d/ω_6 (1)"] {
            assert!(texts.iter().any(|s| s == t), "no text {t:?} in {texts:?}");
        }
        assert!(!texts.iter().any(|s| s == "outside"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
