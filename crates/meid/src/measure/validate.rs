//! Simulation beside measurement (`meid validate`): for each measured case (the bare machine,
//! the machine with its damper, or the model as specified) the model is simulated at the
//! measurement's sample rate, and both are processed **identically** ([`super::process`]:
//! same trigger rule, pre-trigger, record length, windows, zero padding):
//!
//! * the simulated blow starts at rest: `pre-trigger` seconds of zeros are put before t = 0
//!   (exact: nothing moves before the blow), and the record is taken from the trigger found by
//!   the same rule on the same channel as in the measurement;
//! * per mapped channel: the sample peak of the blow-averaged records, each record less its
//!   baseline (the median of its pre-trigger samples: an accelerometer's bias, a force cell's
//!   preload; the simulation starts at rest, baseline 0), the peak error
//!   `100 (peak_meas − peak_sim)/peak_sim` %, and the baseline removed;
//! * per dominant mode of the simulated case, on the responses (not on the blow, the input)
//!   (a mode with ω > 0 below 0.45 f_s whose simulated
//!   ESD peak lies within 30 dB of the channel's strongest): the largest bin of each ESD within
//!   ±10 % of the mode's frequency; frequency error `f_meas − f_sim` (Hz, %), level difference
//!   `L_meas − L_sim` (dB re 1 (SI unit)²·s/Hz). Spectra are zero-padded so that a bin is at most
//!   0.5 % of the lowest mode's frequency (at most 64× the record): frequencies are read ± half a
//!   padded bin on that grid, and the resolution stays 1/T of the record (both reported: a
//!   mode with few cycles in the record reads biased, alike measured and simulated);
//! * when both the bare machine and the damper are measured: the measured reductions
//!   `L_none − L_damper` (sample peaks, `20 log10`; ESD peaks at each mode, `10 log10`) beside
//!   the simulated ones computed the same way — the paper's section 5 comparison.

use std::collections::BTreeMap;

use serde::Serialize;

use super::mapping::{map_records, MeasurementSpec};
use super::process::{
    blow_spectrum, detect_blows, esd_reference, require_complete, BlowSpectrum, Blows, Processing,
};
use super::{Abscissa, Record, SimChannel};
use crate::analysis::energy::simulate;
use crate::model::{Case, Model};
use crate::{Error, Result};

/// Measured records of one case of the machine.
#[derive(Debug, Clone)]
pub struct MeasuredCase {
    pub case: Case,
    /// Files the records came from (for reports).
    pub files: Vec<String>,
    pub records: Vec<Record>,
}

/// The case's name in reports.
pub fn case_name(c: Case) -> &'static str {
    match c {
        Case::AsSpecified => "as-specified",
        Case::NoDamper => "none",
        Case::Damper => "damper",
        Case::AddedMass => "added-mass",
    }
}

/// Splits a `--measured` argument `[CASE=]FILE` (CASE: `none`, `damper`, `added-mass`,
/// `as-specified`; a plain FILE is the model as specified).
pub fn split_case(s: &str) -> (Case, std::path::PathBuf) {
    for (prefix, case) in [
        ("none=", Case::NoDamper),
        ("damper=", Case::Damper),
        ("added-mass=", Case::AddedMass),
        ("as-specified=", Case::AsSpecified),
    ] {
        if let Some(f) = s.strip_prefix(prefix) {
            return (case, std::path::PathBuf::from(f));
        }
    }
    (Case::AsSpecified, std::path::PathBuf::from(s))
}

/// Reads `[CASE=]FILE` arguments ([`split_case`]) into measured cases, several files of one
/// case read together; relative files are taken from `base_dir` when given (a model file's
/// `[measurement] files`), else as they are.
pub fn read_measured(
    args: &[String],
    base_dir: Option<&std::path::Path>,
) -> Result<Vec<MeasuredCase>> {
    Ok(read_measured_noting(args, base_dir)?.0)
}

/// [`read_measured`], with the channels the readers passed over (of quantities meid does not
/// process, such as a microphone's pressure; [`super::read_records_noting`]), one line each
/// naming the file: `meid validate` and `meid calibrate` warn of them as `meid measure` does.
pub fn read_measured_noting(
    args: &[String],
    base_dir: Option<&std::path::Path>,
) -> Result<(Vec<MeasuredCase>, Vec<String>)> {
    let mut cases: Vec<MeasuredCase> = Vec::new();
    let mut passed_over = Vec::new();
    for a in args {
        let (case, path) = split_case(a);
        let path = match base_dir {
            Some(d) if path.is_relative() => d.join(path),
            _ => path,
        };
        let (records, passed) = super::read_records_noting(&path)?;
        passed_over.extend(passed);
        let name = path.display().to_string();
        match cases.iter_mut().find(|c| c.case == case) {
            Some(c) => {
                c.files.push(name);
                c.records.extend(records);
            }
            None => cases.push(MeasuredCase {
                case,
                files: vec![name],
                records,
            }),
        }
    }
    Ok((cases, passed_over))
}

/// One mode of one channel.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModeComparison {
    /// e.g. "mode 2 (283.0 Hz)".
    pub mode: String,
    pub simulated_frequency_hz: f64,
    pub measured_frequency_hz: f64,
    pub frequency_error_hz: f64,
    pub frequency_error_percent: f64,
    pub simulated_level_db: f64,
    pub measured_level_db: f64,
    /// `L_meas − L_sim`.
    pub level_difference_db: f64,
}

/// One mapped channel of one case.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelComparison {
    pub channel: SimChannel,
    /// The measured channel's name.
    pub measured_name: String,
    pub unit: String,
    /// Sample peaks `max_n |x̄_n|` of the blow-averaged records, each record less its
    /// baseline ([`super::process::average_blows`]).
    pub simulated_peak: f64,
    pub measured_peak: f64,
    /// The baselines removed from the measured records (the simulated ones start at rest: 0).
    pub measured_baseline: super::process::BaselineRemoved,
    pub peak_error_percent: f64,
    pub level_reference: String,
    pub modes: Vec<ModeComparison>,
    /// Blow-averaged records (measured, simulated), from the record start, for overlays.
    #[serde(skip)]
    pub measured_average: Vec<f64>,
    #[serde(skip)]
    pub simulated_average: Vec<f64>,
    #[serde(skip)]
    pub measured_spectrum: BlowSpectrum,
    #[serde(skip)]
    pub simulated_spectrum: BlowSpectrum,
}

/// One measured case beside its simulation.
#[derive(Debug, Clone, Serialize)]
pub struct CaseComparison {
    pub case: String,
    pub files: Vec<String>,
    pub sample_rate_hz: f64,
    /// Blows detected in the measurement and averaged.
    pub blows_detected: usize,
    pub blows_averaged: usize,
    /// The channel blows were detected on, and the record length per blow (s).
    pub trigger: String,
    pub record_s: f64,
    pub pretrigger_s: f64,
    /// The spectra's resolution `1/T` (Hz, `T` the record length): peaks closer than this do
    /// not separate, and a mode with few cycles in the record reads biased (alike in the
    /// measurement and the simulation).
    pub frequency_resolution_hz: f64,
    /// The zero-padded grid the peaks are read on (Hz): a frequency is ± half of it on the grid.
    pub padded_bin_hz: f64,
    pub channels: Vec<ChannelComparison>,
}

/// A measured and a simulated reduction, damper vs none.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReductionRow {
    pub metric: String,
    pub measured_db: f64,
    pub simulated_db: f64,
}

/// The whole validation.
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    pub cases: Vec<CaseComparison>,
    /// Empty unless both the bare machine and the damper were measured.
    pub reductions: Vec<ReductionRow>,
}

/// Runs the validation (module docs). `flags`: `--channel` mappings over `[measurement]`.
pub fn validate(
    model: &Model,
    measured: &[MeasuredCase],
    p: &Processing,
    flags: &BTreeMap<String, SimChannel>,
) -> Result<Validation> {
    if measured.is_empty() {
        return Err(Error::invalid("measured", "no measured file"));
    }
    let section: Option<&MeasurementSpec> = model.spec.measurement.as_ref();
    let point = model.spec.points.measurement.clone();
    let mut cases = Vec::new();
    for m in measured {
        cases.push(one_case(model, m, p, section, flags, &point)?);
    }
    let reductions = reductions(&cases);
    Ok(Validation { cases, reductions })
}

/// The measured side of a case: channels mapped, sampling checked, blows detected on the
/// trigger channel (the blow force, else the acceleration at B, else the floor force).
#[derive(Debug, Clone)]
pub(crate) struct MeasuredBlows {
    /// Mapped channel → index into the case's records.
    pub map: BTreeMap<SimChannel, usize>,
    pub fs: f64,
    pub trigger: SimChannel,
    pub blows: Blows,
}

pub(crate) fn measured_blows(
    m: &MeasuredCase,
    p: &Processing,
    section: Option<&MeasurementSpec>,
    flags: &BTreeMap<String, SimChannel>,
    point: &str,
) -> Result<MeasuredBlows> {
    let map = map_records(&m.records, section, flags, point)?;
    if map.is_empty() {
        let names: Vec<&str> = m.records.iter().map(|r| r.name.as_str()).collect();
        return Err(Error::invalid(
            "--channel",
            format!(
                "no measured channel maps to B, floor or blow (channels: {}); name them with --channel NAME=B|floor|blow or [measurement] channels",
                names.join(", ")
            ),
        ));
    }
    // Channels must share one sampling.
    let first = &m.records[*map.values().next().unwrap_or(&0)];
    let (_, step) = first.even()?;
    let fs = 1.0 / step;
    for &i in map.values() {
        let r = &m.records[i];
        let (_, s) = r.even()?;
        if (s - step).abs() > 1e-9 * step || r.values.len() != first.values.len() {
            return Err(Error::Input {
                location: r.origin.clone(),
                message: format!("channel '{}' is not sampled like '{}' (rate or length differ): mapped channels must be recorded together", r.name, first.name),
            });
        }
    }
    let trigger = [
        SimChannel::BlowForce,
        SimChannel::BedAcceleration,
        SimChannel::FloorForce,
    ]
    .into_iter()
    .find(|c| map.contains_key(c))
    .unwrap_or(SimChannel::BedAcceleration);
    let tr = &m.records[map[&trigger]];
    let mb = detect_blows(&tr.values, fs, p)?;
    // The rule `meid measure` applies too.
    require_complete(&mb, tr.values.len(), fs, &tr.name, &tr.origin)?;
    if mb.starts.is_empty() {
        return Err(Error::Input {
            location: tr.origin.clone(),
            message: format!(
                "no complete blow found on '{}' ({} triggers at level {:e} {}): lower the trigger level, the pre-trigger or the record length",
                tr.name, mb.triggers.len(), mb.level, tr.unit()
            ),
        });
    }
    Ok(MeasuredBlows {
        map,
        fs,
        trigger,
        blows: mb,
    })
}

/// The simulated blow processed like the measured ones: the run at the measurement's rate,
/// `pre` samples at rest put before it, its blow found by the same trigger rule.
#[derive(Debug, Clone)]
pub(crate) struct SimulatedBlow {
    history: crate::analysis::History,
    pre: usize,
    fs: f64,
    /// The blow record (one) of the simulated channels.
    pub blows: Blows,
    /// The processing of the simulated records (the measured record length).
    pub processing: Processing,
}

impl SimulatedBlow {
    /// Channel `c` of the run, at rest for the pre-trigger, then the blow.
    pub fn record(&self, c: SimChannel) -> Result<Record> {
        let mut r = Record::from_history(&self.history, c)?;
        let mut v = vec![0.0; self.pre];
        v.extend_from_slice(&r.values);
        r.values = v;
        r.abscissa = Abscissa::Even {
            start_s: -(self.pre as f64) / self.fs,
            step_s: 1.0 / self.fs,
        };
        Ok(r)
    }
}

/// Simulates `sys` for records of `n` samples with `pre` samples before the trigger found on
/// `trigger` (module docs: the simulated blow starts at rest).
pub(crate) fn simulated_blow(
    model: &Model,
    sys: &crate::impact::ImpactSystem,
    fs: f64,
    n: usize,
    pre: usize,
    trigger: SimChannel,
    p: &Processing,
) -> Result<SimulatedBlow> {
    // The simulation: at rest for `pre` samples, then the blow; N + pre + margin samples.
    let margin = n / 100 + 16;
    let sim_samples = n + margin;
    let mut opts = model.options();
    opts.sample_rate = Some(fs);
    opts.duration = (sim_samples as f64 - 0.5) / fs;
    let run = simulate(sys, &opts, true)?;
    let history = run
        .history
        .ok_or_else(|| Error::numerical("validate", "the run recorded no history"))?;
    let sp = Processing {
        record_s: Some(n as f64 / fs),
        ..p.clone()
    };
    let mut out = SimulatedBlow {
        history,
        pre,
        fs,
        blows: Blows {
            triggers: Vec::new(),
            starts: Vec::new(),
            length: n,
            pretrigger: pre,
            level: 0.0,
            note: None,
        },
        processing: sp,
    };
    let st = out.record(trigger)?;
    let sb0 = detect_blows(&st.values, fs, &out.processing)?;
    let Some(&t0) = sb0.triggers.first() else {
        return Err(Error::numerical(
            "validate",
            format!(
                "the simulated {} never reaches the trigger level",
                trigger.label()
            ),
        ));
    };
    out.blows = Blows {
        triggers: vec![t0],
        starts: vec![t0.saturating_sub(pre)],
        length: n,
        pretrigger: pre,
        level: sb0.level,
        note: None,
    };
    Ok(out)
}

fn one_case(
    model: &Model,
    m: &MeasuredCase,
    p: &Processing,
    section: Option<&MeasurementSpec>,
    flags: &BTreeMap<String, SimChannel>,
    point: &str,
) -> Result<CaseComparison> {
    let MeasuredBlows {
        map,
        fs,
        trigger,
        blows: mb,
    } = measured_blows(m, p, section, flags, point)?;
    let tr = &m.records[map[&trigger]];
    let n = mb.length;
    let pre = mb.pretrigger;
    let sys = model.impact_system(m.case)?;
    let sim = simulated_blow(model, &sys, fs, n, pre, trigger, p)?;
    let sb = sim.blows.clone();
    let sp = sim.processing.clone();
    let sim_record = |c: SimChannel| sim.record(c);
    // Zero padding: a bin ≤ 0.5 % of the lowest mode compared, at most 64× the record.
    let modes: Vec<(String, f64)> = sys
        .structure
        .omega_rad_per_s
        .iter()
        .enumerate()
        .filter(|(_, w)| **w > 0.0 && **w / (2.0 * std::f64::consts::PI) < 0.45 * fs)
        .map(|(i, w)| {
            let f = w / (2.0 * std::f64::consts::PI);
            (format!("mode {} ({f:.2} Hz)", i + 1), f)
        })
        .collect();
    let f_min = modes.iter().map(|m| m.1).fold(f64::INFINITY, f64::min);
    let want = if f_min.is_finite() {
        (fs / (0.005 * f_min)).ceil() as usize
    } else {
        n
    };
    let n_fft = want
        .max(n)
        .min(n.saturating_mul(64))
        .next_power_of_two()
        .max(n);
    let band = 0.10;
    let mut channels = Vec::new();
    for (&c, &i) in &map {
        let r = &m.records[i];
        let s = sim_record(c)?;
        let ms = blow_spectrum(&r.values, c.role(), fs, &mb, p, Some(n_fft))?;
        let ss = blow_spectrum(&s.values, c.role(), fs, &sb, &sp, Some(n_fft))?;
        // Each record less its baseline (a bias, a preload): like the simulation, at rest.
        let measured = super::process::BlowRecords::new(&r.values, &mb)?;
        let ma = measured.average()?;
        let sa = super::process::average_blows(&s.values, &sb)?;
        let measured_baseline = measured.removed();
        let peak = |v: &[f64]| v.iter().fold(0.0_f64, |a, x| a.max(x.abs()));
        let (mp, spk) = (peak(&ma), peak(&sa));
        let peak_error_percent = 100.0 * (mp - spk) / spk;
        if !mp.is_finite() || (spk > 0.0 && !peak_error_percent.is_finite()) {
            return Err(Error::Input {
                location: r.origin.clone(),
                message: format!(
                    "channel '{}' ({}): the measured sample peak {} {u} is {} times the simulated {} {u}, so the peak error ({} %) is not a finite number; a sample of this size is not a measurement in {u}: check the file's values and unit label",
                    r.name,
                    c.label(),
                    crate::num(mp),
                    crate::num(mp / spk),
                    crate::num(spk),
                    crate::num(peak_error_percent),
                    u = r.unit()
                ),
            });
        }
        let (rref, rtext) = esd_reference(r.quantity);
        let mut rows = Vec::new();
        let strongest = modes
            .iter()
            .filter_map(|(_, f)| {
                ss.peak_in_band(f * (1.0 - band), f * (1.0 + band))
                    .map(|x| x.1)
            })
            .fold(0.0_f64, f64::max);
        // The blow is the input, broadband: its spectrum has no modes to read.
        let read_modes = if c == SimChannel::BlowForce {
            &[][..]
        } else {
            &modes[..]
        };
        for (name, f) in read_modes {
            let (lo, hi) = (f * (1.0 - band), f * (1.0 + band));
            let (Some(sv), Some(mv)) = (ss.peak_in_band(lo, hi), ms.peak_in_band(lo, hi)) else {
                continue;
            };
            if sv.1.is_nan() || sv.1 <= 0.0 || sv.1 < strongest * 1e-3 {
                continue;
            }
            let (ls, lm) = (ss.level_db(sv.1, rref), ms.level_db(mv.1, rref));
            rows.push(ModeComparison {
                mode: name.clone(),
                simulated_frequency_hz: sv.0,
                measured_frequency_hz: mv.0,
                frequency_error_hz: mv.0 - sv.0,
                frequency_error_percent: 100.0 * (mv.0 - sv.0) / sv.0,
                simulated_level_db: ls,
                measured_level_db: lm,
                level_difference_db: lm - ls,
            });
        }
        channels.push(ChannelComparison {
            channel: c,
            measured_name: r.name.clone(),
            unit: r.unit().to_string(),
            simulated_peak: spk,
            measured_peak: mp,
            measured_baseline,
            peak_error_percent,
            level_reference: rtext,
            modes: rows,
            measured_average: ma,
            simulated_average: sa,
            measured_spectrum: ms,
            simulated_spectrum: ss,
        });
    }
    Ok(CaseComparison {
        case: case_name(m.case).into(),
        files: m.files.clone(),
        sample_rate_hz: fs,
        blows_detected: mb.triggers.len(),
        blows_averaged: mb.starts.len(),
        trigger: tr.name.clone(),
        record_s: n as f64 / fs,
        pretrigger_s: pre as f64 / fs,
        frequency_resolution_hz: fs / n as f64,
        padded_bin_hz: fs / n_fft as f64,
        channels,
    })
}

fn reductions(cases: &[CaseComparison]) -> Vec<ReductionRow> {
    let none = cases.iter().find(|c| c.case == "none");
    let damper = cases.iter().find(|c| c.case == "damper");
    let (Some(a), Some(b)) = (none, damper) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for ca in &a.channels {
        let Some(cb) = b.channels.iter().find(|c| c.channel == ca.channel) else {
            continue;
        };
        out.push(ReductionRow {
            metric: format!("{}: sample peak (20 log10)", ca.channel.label()),
            measured_db: 20.0 * (ca.measured_peak / cb.measured_peak).log10(),
            simulated_db: 20.0 * (ca.simulated_peak / cb.simulated_peak).log10(),
        });
        for ma in &ca.modes {
            let Some(mb) = cb.modes.iter().find(|m| m.mode == ma.mode) else {
                continue;
            };
            out.push(ReductionRow {
                metric: format!("{}: ESD peak at {}", ca.channel.label(), ma.mode),
                measured_db: ma.measured_level_db - mb.measured_level_db,
                simulated_db: ma.simulated_level_db - mb.simulated_level_db,
            });
        }
    }
    out
}

/// `v`, or 0 when it prints as 0.00 (two decimals): a round-off of −1e-14 % is no "−0.00 %".
fn no_negative_zero(v: f64) -> f64 {
    if (100.0 * v).round() == 0.0 {
        0.0
    } else {
        v
    }
}

impl Validation {
    /// The report as text.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        for c in &self.cases {
            let _ = writeln!(
                s,
                "case {} ({}): {} blows detected on '{}', {} averaged; record {:.4} s from {:.4} s before the trigger, {} Hz; spectral resolution 1/T = {:.4} Hz, peaks read on a {:.4} Hz padded grid",
                c.case, c.files.join(", "), c.blows_detected, c.trigger, c.blows_averaged, c.record_s, c.pretrigger_s, c.sample_rate_hz, c.frequency_resolution_hz, c.padded_bin_hz
            );
            for ch in &c.channels {
                let _ = writeln!(
                    s,
                    "  {} ('{}'): sample peak measured {:.5e} {u}, simulated {:.5e} {u}, error {:+.2} %",
                    ch.channel.label(), ch.measured_name, ch.measured_peak, ch.simulated_peak, no_negative_zero(ch.peak_error_percent), u = ch.unit
                );
                let _ = writeln!(
                    s,
                    "    measured baseline removed: {}",
                    ch.measured_baseline.describe(&ch.unit)
                );
                for m in &ch.modes {
                    let _ = writeln!(
                        s,
                        "    {:<22} f measured {:>9.3} Hz, simulated {:>9.3} Hz ({:+.2} %); ESD level {:>8.2} vs {:>8.2} dB ({:+.2} dB)",
                        m.mode, m.measured_frequency_hz, m.simulated_frequency_hz, no_negative_zero(m.frequency_error_percent), m.measured_level_db, m.simulated_level_db, no_negative_zero(m.level_difference_db)
                    );
                }
            }
        }
        if !self.reductions.is_empty() {
            let _ = writeln!(
                s,
                "reductions, damper vs none (positive: quieter with the damper):"
            );
            let _ = writeln!(
                s,
                "  {:<62} {:>10} {:>10}",
                "metric", "measured", "simulated"
            );
            for r in &self.reductions {
                let _ = writeln!(
                    s,
                    "  {:<62} {:>7.2} dB {:>7.2} dB",
                    r.metric, r.measured_db, r.simulated_db
                );
            }
        }
        let _ = writeln!(s, "levels: dB re 1 (SI unit)²·s/Hz; frequencies: the largest bin within ±10 % of the mode, ± half a padded bin on that grid, but resolved only to 1/T: a mode with few cycles in the record reads biased, alike measured and simulated; peaks are sample peaks of the blow-averaged records, each record less its baseline (the median of its pre-trigger samples)");
        s
    }

    /// Pictures: per case and channel, `<case>_<channel>_history` (blow-averaged records
    /// overlaid) and `<case>_<channel>_spectrum` (ESD levels overlaid), PNG and SVG.
    pub fn plots(&self, dir: &std::path::Path) -> Result<()> {
        use crate::plot::{LinePlot, Series, SpectrumPlot};
        for c in &self.cases {
            for ch in &c.channels {
                let stem = format!("{}_{}", c.case, ch.channel.target());
                let dt = 1.0 / c.sample_rate_hz;
                let t: Vec<f64> = (0..ch.measured_average.len())
                    .map(|i| i as f64 * dt - c.pretrigger_s)
                    .collect();
                crate::plot::line_plot(
                    dir.join(format!("{stem}_history")),
                    &LinePlot {
                        title: format!(
                            "{} ({}): blow-averaged records",
                            ch.channel.label(),
                            c.case
                        ),
                        x_label: "time from the trigger (s)".into(),
                        y_label: format!("{} ({})", ch.channel.quantity().name(), ch.unit),
                        series: vec![
                            Series {
                                label: format!("measured ({})", ch.measured_name),
                                x: t.clone(),
                                y: ch.measured_average.clone(),
                                ..Default::default()
                            },
                            Series {
                                label: "simulated".into(),
                                x: t,
                                y: ch.simulated_average.clone(),
                                // Dashed: where they agree the measured curve shows through.
                                style: crate::plot::LineStyle::Dashed,
                                ..Default::default()
                            },
                        ],
                        ..LinePlot::default()
                    },
                )?;
                let (rref, _) = esd_reference(ch.channel.quantity());
                let series = |label: String, s: &BlowSpectrum| {
                    // On the logarithmic axis: a bin when its frequency is 0.2 % above the last
                    // one drawn (every bin where they are sparser).
                    let mut last = 0.0;
                    let (x, y) = s
                        .frequency_hz
                        .iter()
                        .zip(&s.density)
                        .skip(1)
                        .filter(|(f, _)| {
                            let keep = **f >= last * 1.002;
                            if keep {
                                last = **f;
                            }
                            keep
                        })
                        .map(|(f, e)| (*f, s.level_db(*e, rref)))
                        .unzip();
                    Series {
                        label,
                        x,
                        y,
                        ..Default::default()
                    }
                };
                let ms = series(
                    format!("measured ({})", ch.measured_name),
                    &ch.measured_spectrum,
                );
                let mut ss = series("simulated".into(), &ch.simulated_spectrum);
                ss.style = crate::plot::LineStyle::Dashed;
                if ms.y.iter().chain(&ss.y).any(|v| v.is_finite()) {
                    crate::plot::spectrum_plot(
                        dir.join(format!("{stem}_spectrum")),
                        &SpectrumPlot {
                            title: format!(
                                "{} ({}): blow-averaged ESD",
                                ch.channel.label(),
                                c.case
                            ),
                            y_label: format!("ESD level (dB re {})", ch.level_reference),
                            x_log: true,
                            series: vec![ms, ss],
                            ..Default::default()
                        },
                    )?;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::no_negative_zero;

    /// A deviation that is round-off prints +0.00, not −0.00 (brief s13-lab: `meid validate`
    /// of a CSV with offsets printed "error -0.00 %" for a bed acceleration that agreed).
    #[test]
    fn round_off_prints_as_plus_zero() {
        assert_eq!(format!("{:+.2}", no_negative_zero(-6e-14)), "+0.00");
        assert_eq!(format!("{:+.2}", no_negative_zero(-0.004)), "+0.00");
        assert_eq!(format!("{:+.2}", no_negative_zero(-0.005)), "-0.01");
        assert_eq!(format!("{:+.2}", no_negative_zero(0.38)), "+0.38");
    }
}
