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

/// A point marked on a map, in axis values.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mark {
    /// Legend text (empty: unnamed).
    pub label: String,
    pub x: f64,
    pub y: f64,
}

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
    /// as a square with a cross, named in the legend.
    pub marks: Vec<Mark>,
    /// Draw the line x = y with this legend text (e.g. `ω_d = ω_s` on a ω_s/ω_ref × ω_d/ω_ref
    /// map); empty: no line.
    pub diagonal_label: String,
    /// The caption (what the map shows; the figure adds nothing to it).
    pub caption: String,
}

/// A heat map of `spec.metric` over the sweep's two quantities, with contour lines, the
/// line x = y and the marks (each a square and a cross); writes `<stem>.png/.svg` and the
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
    let (lo, hi) = z
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let contour_levels: Vec<f64> = if lo < hi {
        (1..8).map(|k| lo + (hi - lo) * k as f64 / 8.0).collect()
    } else {
        Vec::new()
    };
    let x_log = vary[0].spacing == Spacing::Log;
    let y_log = vary[1].spacing == Spacing::Log;
    let mut overlay_lines = Vec::new();
    if !spec.diagonal_label.is_empty() {
        let a = x[0].max(y[0]);
        let b = x[nx - 1].min(y[ny - 1]);
        if a < b {
            overlay_lines.push(Series {
                label: spec.diagonal_label.clone(),
                x: vec![a, b],
                y: vec![a, b],
                ..Default::default()
            });
        }
    }
    for mark in &spec.marks {
        let (dx, dy) = (mark.x, mark.y);
        // Half-sizes: 2.5 % of each axis span (in log or linear measure).
        let half = |v: &[f64], log: bool, at: f64| -> (f64, f64) {
            let (a, b) = (v[0], v[v.len() - 1]);
            if log {
                let f = (b / a).powf(0.025);
                (at / f, at * f)
            } else {
                let h = 0.025 * (b - a);
                (at - h, at + h)
            }
        };
        let (x0, x1) = half(x, x_log, dx);
        let (y0, y1) = half(y, y_log, dy);
        overlay_lines.push(Series {
            label: mark.label.clone(),
            x: vec![x0, x1, x1, x0, x0],
            y: vec![y0, y0, y1, y1, y0],
            ..Default::default()
        });
        overlay_lines.push(Series {
            label: String::new(),
            x: vec![x0, x1],
            y: vec![dy, dy],
            ..Default::default()
        });
        overlay_lines.push(Series {
            label: String::new(),
            x: vec![dx, dx],
            y: vec![y0, y1],
            ..Default::default()
        });
    }
    let map = HeatMap {
        title: spec.title.clone(),
        x_label: spec.x_label.clone(),
        y_label: spec.y_label.clone(),
        x: x.clone(),
        y: y.clone(),
        z,
        x_log,
        y_log,
        contour_levels,
        overlay_lines,
        colorbar_label: spec.colorbar_label.clone(),
        ..Default::default()
    };
    plot::heat_map(dir.join(stem), &map)?;
    let csv = format!("{stem}.csv");
    crate::io::write_atomic(&dir.join(&csv), sweep.csv().as_bytes())?;
    Ok(figure(stem, &spec.title, spec.caption.clone(), &[&csv]))
}

/// The reference text of the ESD levels, e.g. `1 (m/s²)²·s/Hz`, without `/Hz` for bands.
fn band_reference(s: &str) -> String {
    s.trim_end_matches("/Hz").to_string()
}

/// The comparison's figures: time histories of the bed acceleration at B (over the first
/// part of the record, where the bed mode rings) and of the force to the floor (whole
/// record), the energy spectral densities of both, and their one-third-octave band levels.
/// Writes `<prefix>-*.png/.svg` and the data `<prefix>-histories.csv`, `<prefix>-spectra.csv`,
/// `<prefix>-bands.csv`, `<prefix>-reductions.csv`.
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
    // The acceleration is dominated by the highest dominant mode while the contact lasts:
    // show 20 of its periods (the whole record when shorter).
    let f_high = first
        .modes
        .iter()
        .map(|m| m.centre_hz)
        .fold(0.0_f64, f64::max);
    let zoom_s = if f_high > 0.0 {
        (20.0 / f_high).min(record_s)
    } else {
        record_s
    };
    let time = |pick: &dyn Fn(&crate::analysis::History) -> &Vec<f64>, t_max: f64| {
        r.cases
            .iter()
            .map(|c| {
                let n = c.history.time_s.partition_point(|t| *t <= t_max);
                Series {
                    label: c.case.label().into(),
                    x: c.history.time_s[..n].to_vec(),
                    y: pick(&c.history)[..n].to_vec(),
                    ..Default::default()
                }
            })
            .collect::<Vec<_>>()
    };
    let rate = r.sample_rate_hz;
    let stem = format!("{prefix}-acceleration-time");
    plot::line_plot(
        dir.join(&stem),
        &LinePlot {
            title: format!("bed acceleration at B, first {} ms", sig(1e3 * zoom_s, 3)),
            x_label: "time (s)".into(),
            y_label: "acceleration (m/s²)".into(),
            series: time(&|h| &h.bed_acceleration_m_per_s2, zoom_s),
            ..Default::default()
        },
    )?;
    out.push(figure(
        &stem,
        "bed acceleration against time, three cases",
        format!(
            "Bed acceleration a_B (m/s²) at the measurement point B after one blow, without damper, with the impact damper and with the added mass: the first {} ms of the {} s record (output samples at {} Hz; the peaks in the tables are exact, located on the continuous solution).",
            sig(1e3 * zoom_s, 3),
            plain(record_s),
            plain(rate)
        ),
        &[&histories],
    ));
    let stem = format!("{prefix}-floor-force-time");
    plot::line_plot(
        dir.join(&stem),
        &LinePlot {
            title: "force to the floor".into(),
            x_label: "time (s)".into(),
            y_label: "force (N)".into(),
            series: time(&|h| &h.floor_force_n, record_s),
            ..Default::default()
        },
    )?;
    out.push(figure(
        &stem,
        "force to the floor against time, three cases",
        format!(
            "Force to the floor F (N) over the {} s record after one blow, the three cases.",
            sig(record_s, 3)
        ),
        &[&histories],
    ));

    let (ea, ef) = r.esd_references();
    let a2 = r.acceleration_reference_m_per_s2.powi(2);
    let what = match r.spectrum {
        SpectrumMethod::Exact => "exact energy spectral density of the whole response, free decay included (independent of record length and sample rate)".to_string(),
        SpectrumMethod::Fft => format!(
            "FFT energy spectral density of the sampled record, {} window (depends on record, window and rate)",
            r.window.name()
        ),
    };
    for (ch, name, what_short, reference, label) in [
        (
            0,
            "acceleration",
            "bed acceleration at B",
            a2,
            format!("ESD level (dB re {ea})"),
        ),
        (
            1,
            "floor-force",
            "force to the floor",
            1.0,
            format!("ESD level (dB re {ef})"),
        ),
    ] {
        let series = r
            .cases
            .iter()
            .filter_map(|c| {
                let s = c.spectra.get(ch)?;
                let (x, y) = s.level_curve_db(&r.frequency_hz, reference);
                Some(Series {
                    label: c.case.label().into(),
                    x,
                    y,
                    ..Default::default()
                })
            })
            .collect();
        let stem = format!("{prefix}-{name}-spectrum");
        plot::spectrum_plot(
            dir.join(&stem),
            &SpectrumPlot {
                title: format!("{what_short}, energy spectral density"),
                y_label: label.clone(),
                x_log: true,
                series,
                ..Default::default()
            },
        )?;
        out.push(figure(
            &stem,
            &format!("{what_short} spectrum, three cases"),
            format!(
                "{}: {what} in {label}, the three cases; the dominant modes' peaks are located by refinement.",
                capitalise(what_short)
            ),
            &[&spectra],
        ));
        let series = r
            .cases
            .iter()
            .filter_map(|c| {
                let s = c.spectra.get(ch)?;
                let mut x = Vec::new();
                let mut y = Vec::new();
                for (b, e) in r.bands.iter().zip(&s.band_energy) {
                    let l = esd_level_db(*e, reference);
                    x.extend([b.lower_hz, b.upper_hz]);
                    y.extend([l, l]);
                }
                Some(Series {
                    label: c.case.label().into(),
                    x,
                    y,
                    ..Default::default()
                })
            })
            .collect();
        let reference_text = band_reference(if ch == 0 { &ea } else { &ef });
        let stem = format!("{prefix}-{name}-bands");
        plot::spectrum_plot(
            dir.join(&stem),
            &SpectrumPlot {
                title: format!("{what_short}, one-third-octave band energy"),
                y_label: format!("band level (dB re {reference_text})"),
                x_log: true,
                series,
                ..Default::default()
            },
        )?;
        out.push(figure(
            &stem,
            &format!("{what_short} one-third-octave levels, three cases"),
            format!(
                "{}: energy in each one-third-octave band (IEC 61260-1, base 10), the integral of the ESD over the band, in dB re {reference_text}; the three cases.",
                capitalise(what_short)
            ),
            &[&bands_csv],
        ));
    }
    Ok(out)
}

fn capitalise(s: &str) -> String {
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
        caption: "Exact peaks of one blow (located on the continuous solution, not on the samples) and the share of the blow's energy left in the machine".into(),
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
    for x in &r.reductions {
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

/// The mode table: frequency, participation |ψ| along the impact axis at the named points
/// (1/√kg), effective vertical mass (FE models) and whether the mode is retained.
pub fn mode_table(report: &ModeReport) -> Table {
    let points: Vec<String> = report
        .modes
        .first()
        .map(|r| r.participation.keys().cloned().collect())
        .unwrap_or_default();
    let fe = report.modes.iter().any(|m| m.effective_mass_kg.is_some());
    let mut header = vec!["mode".to_string(), "frequency (Hz)".into()];
    header.extend(points.iter().map(|p| format!("|ψ({p})| (1/√kg)")));
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
                .map(|p| m.participation.get(p).map_or("—".into(), |v| sig(*v, 4))),
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
}
