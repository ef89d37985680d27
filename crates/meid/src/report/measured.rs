//! The "Measured against simulated" section of `meid report`: the comparison of `meid
//! validate` ([`crate::measure::validate`]) on the report's page — overlaid blow-averaged
//! records and spectra, per-mode frequency errors, level differences and peak errors, and
//! the measured dB reductions (damper vs none) beside the simulated ones, computed the same
//! way (the paper's section 5).
//!
//! The measurement and the simulation are processed identically (same trigger rule,
//! pre-trigger, record length, window); the numbers are those of `meid validate` on the same
//! files.

use std::collections::BTreeMap;
use std::path::Path;

use super::figures::sig;
use super::html::{Block, Figure, Section, Table};
use crate::measure::mapping::{parse_channel_flags, MeasurementSpec};
use crate::measure::process::Processing;
use crate::measure::validate::{read_measured, validate, MeasuredCase, Validation};
use crate::measure::SimChannel;
use crate::model::Model;
use crate::Result;

/// The data file of the section, linked under each of its figures.
pub const DATA_FILE: &str = "measured.json";

/// The measured records and how to read them: the cases (`[CASE=]FILE`), the processing and
/// the `--channel` mappings.
pub struct MeasuredInputs {
    pub cases: Vec<MeasuredCase>,
    pub processing: Processing,
    pub flags: BTreeMap<String, SimChannel>,
}

/// Runs the comparison when measured files are given: `measured` (`[CASE=]FILE`, as
/// `meid validate --measured`, relative to the working directory) or else the model's
/// `[measurement] files` (relative to the model file's directory); `channels` are
/// `NAME=TARGET` mappings over the section's; `processing`'s settings win over the section's
/// ([`MeasurementSpec::over`]). `None` when there is no measured file; with one, the
/// comparison and the records it read (for the section "Test against model",
/// [`super::testlab`]).
pub fn run(
    model_path: &Path,
    model: &Model,
    measured: &[String],
    channels: &[String],
    processing: &MeasurementSpec,
) -> Result<Option<(Validation, MeasuredInputs)>> {
    let section = model.spec.measurement.as_ref();
    let (files, base) = if !measured.is_empty() {
        (measured.to_vec(), None)
    } else {
        match section.filter(|s| !s.files.is_empty()) {
            Some(s) => (s.files.clone(), model_path.parent()),
            None => return Ok(None),
        }
    };
    let p = processing.over(section).processing()?;
    let flags = parse_channel_flags(channels, &model.spec.points.measurement)?;
    let cases = read_measured(&files, base)?;
    let v = validate(model, &cases, &p, &flags)?;
    Ok(Some((
        v,
        MeasuredInputs {
            cases,
            processing: p,
            flags,
        },
    )))
}

/// One line for the report's key results.
pub fn key_result(v: &Validation) -> String {
    let worst = v
        .cases
        .iter()
        .flat_map(|c| c.channels.iter())
        .map(|c| c.peak_error_percent)
        .filter(|e| e.is_finite())
        .fold(0.0_f64, |m, e| if e.abs() > m.abs() { e } else { m });
    // Below the printed precision: no sign ("-0.00 %" reads as a measured deficit).
    let worst = if worst.abs() < 5e-3 { 0.0 } else { worst };
    let mut s = format!(
        "Measured against simulated ({} case(s), identical processing): largest sample-peak error {:+.2} %",
        v.cases.len(),
        worst
    );
    if let Some(r) = v.reductions.first() {
        s.push_str(&format!(
            "; damper vs none, {}: measured {:.2} dB, simulated {:.2} dB",
            r.metric, r.measured_db, r.simulated_db
        ));
    }
    s.push('.');
    s
}

/// The section: with `v`, its tables and pictures (written into `dir` with
/// [`Validation::plots`], the numbers into [`DATA_FILE`]); without, how to give
/// measurements.
pub fn section(dir: &Path, v: Option<&Validation>) -> Result<Section> {
    let mut blocks = Vec::new();
    match v {
        None => blocks.push(Block::Paragraph(
            "No measurement compared: give measured records with meid report MODEL.toml --measured [CASE=]FILE … (UFF 58/58b or CSV; CASE: none, damper, added-mass) and, when the channel names do not say it, --channel NAME=B|floor|blow; or list them in the model's [measurement] files (docs/explanations/measure.md). The comparison is that of meid validate.".into(),
        )),
        Some(v) => {
            crate::io::write_json(&dir.join(DATA_FILE), v)?;
            blocks.push(Block::Paragraph(
                "The simulation beside the measured records, processed identically (meid validate): the same trigger rule on the same channel, pre-trigger, record length per blow, windows and zero padding; the simulated blow starts at rest. Peaks are sample peaks of the blow-averaged records; levels are energy spectral density peaks in dB re 1 (SI unit)²·s/Hz, read within ±10 % of each simulated mode's frequency (frequencies ± half a padded bin).".into(),
            ));
            blocks.push(Block::List(
                v.cases
                    .iter()
                    .map(|c| {
                        format!(
                            "case {}: {} — {} blow(s) detected on '{}', {} averaged; record {} s from {} s before the trigger, {} Hz",
                            c.case,
                            c.files.join(", "),
                            c.blows_detected,
                            c.trigger,
                            c.blows_averaged,
                            sig(c.record_s, 4),
                            sig(c.pretrigger_s, 3),
                            sig(c.sample_rate_hz, 6)
                        )
                    })
                    .collect(),
            ));
            blocks.push(Block::Table(peaks_table(v)));
            blocks.push(Block::Table(modes_table(v)));
            if v.reductions.is_empty() {
                blocks.push(Block::Paragraph(
                    "No measured reduction: it needs records of the bare machine and of the machine with its damper (--measured none=FILE --measured damper=FILE).".into(),
                ));
            } else {
                blocks.push(Block::Table(reductions_table(v)));
            }
            v.plots(dir)?;
            for c in &v.cases {
                for ch in &c.channels {
                    let stem = format!("{}_{}", c.case, ch.channel.target());
                    for (kind, what) in [
                        ("history", "blow-averaged records against time from the trigger"),
                        ("spectrum", "energy spectral densities of the blow-averaged records"),
                    ] {
                        let src = format!("{stem}_{kind}.png");
                        if !dir.join(&src).is_file() {
                            continue;
                        }
                        blocks.push(Block::Figure(Figure {
                            src,
                            alt: format!("{} ({}), measured and simulated {kind}", ch.channel.label(), c.case),
                            caption: format!(
                                "{} ({}), case {}: measured ('{}') and simulated {what}, in {}; processed identically.",
                                ch.channel.label(),
                                ch.unit,
                                c.case,
                                ch.measured_name,
                                if kind == "history" { ch.unit.clone() } else { format!("dB re {}", ch.level_reference) }
                            ),
                            data: vec![format!("{stem}_{kind}.svg"), DATA_FILE.into()],
                        }));
                    }
                }
            }
        }
    }
    Ok(Section {
        id: "measured".into(),
        heading: "Measured against simulated".into(),
        blocks,
    })
}

/// `v` with a sign and 2 decimals; a value that rounds to zero is "0.00" (not "-0.00",
/// which would read as a deficit).
fn signed(v: f64) -> String {
    if (100.0 * v).round() == 0.0 {
        "0.00".into()
    } else {
        format!("{v:+.2}")
    }
}

fn header(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// Sample peaks per case and channel, measured and simulated, and the error.
pub fn peaks_table(v: &Validation) -> Table {
    let rows = v
        .cases
        .iter()
        .flat_map(|c| {
            c.channels.iter().map(move |ch| {
                vec![
                    c.case.clone(),
                    ch.channel.label().into(),
                    ch.measured_name.clone(),
                    sig(ch.measured_peak, 5),
                    sig(ch.simulated_peak, 5),
                    ch.unit.clone(),
                    signed(ch.peak_error_percent),
                    if ch.measured_baseline.samples > 0 {
                        sig(ch.measured_baseline.mean, 5)
                    } else {
                        "none removed".into()
                    },
                ]
            })
        })
        .collect();
    Table {
        caption: "Sample peaks of the blow-averaged records, each record less its baseline (the median of its pre-trigger samples; the simulation starts at rest), measured and simulated; error 100 (measured − simulated)/simulated; the measured baseline removed, mean over the blows.".into(),
        header: header(&[
            "case",
            "channel",
            "measured channel",
            "measured peak",
            "simulated peak",
            "unit",
            "peak error (%)",
            "measured baseline",
        ]),
        rows,
        ..Default::default()
    }
}

/// Per dominant mode: frequencies and their error, ESD levels and their difference.
pub fn modes_table(v: &Validation) -> Table {
    let mut rows = Vec::new();
    for c in &v.cases {
        for ch in &c.channels {
            for m in &ch.modes {
                rows.push(vec![
                    c.case.clone(),
                    ch.channel.label().into(),
                    m.mode.clone(),
                    format!("{:.3}", m.measured_frequency_hz),
                    format!("{:.3}", m.simulated_frequency_hz),
                    signed(m.frequency_error_percent),
                    format!("{:.2}", m.measured_level_db),
                    format!("{:.2}", m.simulated_level_db),
                    signed(m.level_difference_db),
                    ch.level_reference.clone(),
                ]);
            }
        }
    }
    Table {
        caption: "Dominant modes: frequency of the measured and simulated ESD peaks near each simulated mode, frequency error (f_meas − f_sim)/f_sim, ESD levels and their difference L_meas − L_sim.".into(),
        header: header(&[
            "case",
            "channel",
            "mode",
            "f measured (Hz)",
            "f simulated (Hz)",
            "frequency error (%)",
            "level measured (dB)",
            "level simulated (dB)",
            "level difference (dB)",
            "level reference",
        ]),
        rows,
        ..Default::default()
    }
}

/// Measured reductions, damper vs none, beside the simulated ones.
pub fn reductions_table(v: &Validation) -> Table {
    Table {
        caption: "Reductions with the damper, measured and simulated the same way (positive: quieter with the damper); the paper's section 5 comparison.".into(),
        header: header(&[
            "metric",
            "measured (dB)",
            "simulated (dB)",
            "measured − simulated (dB)",
        ]),
        rows: v
            .reductions
            .iter()
            .map(|r| {
                vec![
                    r.metric.clone(),
                    format!("{:.2}", r.measured_db),
                    format!("{:.2}", r.simulated_db),
                    signed(r.measured_db - r.simulated_db),
                ]
            })
            .collect(),
        ..Default::default()
    }
}
