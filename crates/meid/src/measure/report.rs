//! Text, CSV and pictures of processed channels (`meid measure`).

use std::fmt::Write as _;
use std::path::Path;

use super::process::{esd_reference, ProcessedChannel};
use crate::plot::{LinePlot, Series, SpectrumPlot};
use crate::Result;

/// A file-name-safe form of a channel name (letters, digits, `-`, `_`; the rest `_`), made
/// unique among `taken`.
pub fn file_stem(name: &str, taken: &mut Vec<String>) -> String {
    let mut s: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if s.is_empty() {
        s = "channel".into();
    }
    let base = s.clone();
    let mut k = 2;
    while taken.contains(&s) {
        s = format!("{base}_{k}");
        k += 1;
    }
    taken.push(s.clone());
    s
}

/// The human-readable table of `meid measure`.
pub fn summary_text(files: &[String], channels: &[ProcessedChannel]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "meid measure — {}", files.join(", "));
    let _ = writeln!(
        out,
        "  {:<24} {:<6} {:>9} {:>10} {:>13} {:>10} {:>12} {:>6} {:>8} {:>11} {:>9}",
        "channel",
        "unit",
        "samples",
        "rate (Hz)",
        "sample peak",
        "at (s)",
        "baseline",
        "blows",
        "averaged",
        "dominant",
        "level"
    );
    for c in channels {
        let s = &c.summary;
        let line = match (s.dominant_frequency_hz, s.dominant_level_db) {
            (Some(f), Some(l)) => format!("{f:>8.2} Hz {l:>6.2} dB"),
            _ => format!("{:>11} {:>9}", "—", "no energy"),
        };
        let _ = writeln!(
            out,
            "  {:<24} {:<6} {:>9} {:>10.1} {:>+13.5e} {:>10.6} {:>+12.4e} {:>6} {:>8} {line}",
            s.name,
            s.unit,
            s.samples,
            s.sample_rate_hz,
            s.peak,
            s.peak_time_s,
            s.baseline.mean,
            s.blows,
            s.blows_averaged,
        );
    }
    let _ = writeln!(
        out,
        "  peaks are sample peaks, with their sign: the largest |x − b| among the samples of the averaged blow records, b each record's baseline; the signal between samples may go higher (a sinusoid of frequency f reads at least cos(π f/f_s) of its amplitude);"
    );
    let removed = channels
        .iter()
        .filter(|c| c.summary.blows_averaged > 0)
        .map(|c| c.summary.baseline.samples)
        .next();
    match removed {
        Some(0) => {
            let _ = writeln!(
                out,
                "  baseline: none removed, the pre-trigger holds fewer than {} samples (peaks and averages include any DC offset: give a longer --pretrigger);",
                super::process::MIN_BASELINE_SAMPLES
            );
        }
        Some(k) => {
            let _ = writeln!(
                out,
                "  baseline: the median of each blow record's {k} pre-trigger samples (a transducer's bias or preload), removed before peaks, averages and spectra; the column is its mean over the blows;"
            );
        }
        None => {}
    }
    if let Some(c) = channels.iter().find(|c| c.summary.blows_averaged > 0) {
        let _ = writeln!(
            out,
            "  the dominant line is the largest bin above DC of the energy spectral density averaged over the blows' records ({:.6} s from {:.6} s before each trigger), ± half a bin;",
            c.summary.record_s, c.summary.pretrigger_s
        );
    }
    let names = whole_record_names(channels);
    if !names.is_empty() {
        let _ = writeln!(
            out,
            "  no blow was found for {}: their dominant line is that of the whole record's energy spectral density, not blow-averaged;",
            names.join(", ")
        );
    }
    let _ = writeln!(
        out,
        "  levels are dB re 1 (SI unit)²·s/Hz (1 (m/s^2)²·s/Hz, 1 N²·s/Hz)."
    );
    for n in notes(channels) {
        let _ = writeln!(out, "  note: {n}");
    }
    out
}

/// The notes of a `meid measure` run, each once: a pre-trigger shortened to the time a record
/// has before its first blow ([`super::process::group_blows`]).
pub fn notes(channels: &[ProcessedChannel]) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    for n in channels
        .iter()
        .filter_map(|c| c.summary.pretrigger_note.as_deref())
    {
        if !out.contains(&n) {
            out.push(n);
        }
    }
    out
}

/// The names of the channels whose spectrum is the whole record's (no blow averaged).
fn whole_record_names(channels: &[ProcessedChannel]) -> Vec<&str> {
    channels
        .iter()
        .filter(|c| c.summary.blows_averaged == 0)
        .map(|c| c.summary.name.as_str())
        .collect()
}

/// The warnings of a `meid measure` run: channels whose spectrum is the whole record's
/// because no blow was found on their trigger channel, and channels possibly clipped
/// ([`super::process::clipped_samples`]).
pub fn warnings(channels: &[ProcessedChannel]) -> Vec<String> {
    let whole = whole_record_names(channels);
    let mut out = Vec::new();
    if !whole.is_empty() {
        out.push(format!(
            "no blow found (no sample reaches the trigger level after one below it) for {}: their spectra are of the whole record, 0 blows averaged; lower the trigger level (--trigger-level) or choose the trigger channel (--trigger) to average blows",
            whole.join(", ")
        ));
    }
    for c in channels.iter().filter(|c| c.summary.clipped_samples > 0) {
        let s = &c.summary;
        out.push(format!(
            "channel '{}' is possibly clipped: {} samples sit in runs of {} or more at its extreme values (sample peak {:.6e} {}), as where a transducer or amplifier reaches its full scale; its peaks and spectra are then wrong — check the range of the measuring chain",
            s.name,
            s.clipped_samples,
            super::process::CLIP_RUN,
            s.peak,
            s.unit
        ));
    }
    out
}

/// A level for CSV: empty where the energy is 0 (−∞ dB).
fn level_field(c: &ProcessedChannel, e: f64) -> String {
    let (r, _) = esd_reference(c.quantity);
    if e > 0.0 {
        format!("{:.6}", c.spectrum.level_db(e, r))
    } else {
        String::new()
    }
}

/// The densities of a channel's spectrum in SI, or the error saying they cannot be written
/// (`what`: the file that would hold them). The ESD is at most `2 (T max|x|)²` (rectangular
/// window), so it is representable when `max|x| ≤ √(f64::MAX/2)/T`.
fn density_si<'a>(c: &'a ProcessedChannel, what: &str) -> Result<&'a [f64]> {
    c.spectrum.density_si().ok_or_else(|| {
        let top = c.spectrum.density.iter().fold(0.0_f64, |a, b| a.max(*b));
        let t = c.summary.record_s;
        crate::Error::Input {
            location: c.origin.clone(),
            message: format!(
                "channel '{}': its energy spectral density reaches 10^{:.1} ({})²·s/Hz, beyond the largest double ({:e}), so {what} cannot hold it; the levels in dB are printed without -o. Values with |x| ≤ {:.3e} {} keep the ESD of a {t:.6} s record representable",
                c.summary.name,
                (c.spectrum.level_db(top, 1.0)) / 10.0,
                c.summary.unit,
                f64::MAX,
                (f64::MAX / 2.0).sqrt() / t,
                c.summary.unit,
            ),
        }
    })
}

/// `frequency_hz,esd_si2_s_per_hz,level_db` of one channel's blow-averaged ESD (the level
/// empty where the ESD is 0). An error when the ESD is beyond the range of doubles.
pub fn spectrum_csv(c: &ProcessedChannel) -> Result<Vec<u8>> {
    let d = density_si(c, "<channel>_spectrum.csv")?;
    let mut s = String::from("frequency_hz,esd_si2_s_per_hz,level_db\n");
    for (f, e) in c.spectrum.frequency_hz.iter().zip(d) {
        let _ = writeln!(s, "{f:.9e},{e:.12e},{}", level_field(c, *e));
    }
    Ok(s.into_bytes())
}

/// One row per channel and one-third-octave band: energy (SI²·s) and level (dB re 1 SI²·s;
/// empty for zero energy). An error when an energy is beyond the range of doubles.
pub fn bands_csv(channels: &[ProcessedChannel]) -> Result<Vec<u8>> {
    let mut s = String::from("channel,band_hz,lower_hz,upper_hz,energy_si2_s,level_db\n");
    for c in channels {
        density_si(c, "bands.csv")?;
        for (b, e) in &c.bands {
            let _ = writeln!(
                s,
                "{},{},{:.6},{:.6},{e:.12e},{}",
                csv_field(&c.summary.name),
                b.nominal_hz,
                b.lower_hz,
                b.upper_hz,
                level_field(c, *e)
            );
        }
    }
    Ok(s.into_bytes())
}

/// `time_s,<name>_<unit>` of one channel's blow-averaged record (time from the record start),
/// each blow record less its baseline ([`super::process::average_blows`]).
pub fn average_csv(c: &ProcessedChannel) -> Vec<u8> {
    let dt = 1.0 / c.summary.sample_rate_hz;
    let mut s = format!("time_s,average_{}\n", c.summary.unit);
    for (i, v) in c.average.iter().enumerate() {
        let _ = writeln!(s, "{:.12e},{v:.12e}", i as f64 * dt);
    }
    s.into_bytes()
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// Pictures of one channel: `<stem>_spectrum.png/.svg` and `<stem>_average.png/.svg` in `dir`.
pub fn plots(dir: &Path, stem: &str, c: &ProcessedChannel) -> Result<()> {
    let (r, rtext) = esd_reference(c.quantity);
    let (x, y): (Vec<f64>, Vec<f64>) = c
        .spectrum
        .frequency_hz
        .iter()
        .zip(&c.spectrum.density)
        .skip(1)
        .map(|(f, e)| (*f, c.spectrum.level_db(*e, r)))
        .unzip();
    // A channel that is zero throughout has no level to draw.
    if y.iter().any(|v| v.is_finite()) {
        crate::plot::spectrum_plot(
            dir.join(format!("{stem}_spectrum")),
            &SpectrumPlot {
                title: if c.spectrum.averages > 0 {
                    format!(
                        "{}: blow-averaged ESD ({} blows)",
                        c.summary.name, c.spectrum.averages
                    )
                } else {
                    format!(
                        "{}: ESD of the whole record (no blow found)",
                        c.summary.name
                    )
                },
                y_label: format!("ESD level (dB re {rtext})"),
                x_log: true,
                series: vec![Series {
                    label: c.summary.name.clone(),
                    x,
                    y,
                    ..Default::default()
                }],
                ..Default::default()
            },
        )?;
    }
    let dt = 1.0 / c.summary.sample_rate_hz;
    crate::plot::line_plot(
        dir.join(format!("{stem}_average")),
        &LinePlot {
            title: if c.spectrum.averages > 0 {
                if c.summary.baseline.samples > 0 {
                    format!(
                        "{}: blow-averaged record, less its baseline ({:+.4e} {})",
                        c.summary.name, c.summary.baseline.mean, c.summary.unit
                    )
                } else {
                    format!("{}: blow-averaged record", c.summary.name)
                }
            } else {
                format!("{}: the whole record (no blow found)", c.summary.name)
            },
            x_label: "time from the record start (s)".into(),
            y_label: format!("{} ({})", c.quantity.name(), c.summary.unit),
            series: vec![Series {
                label: c.summary.name.clone(),
                x: (0..c.average.len()).map(|i| i as f64 * dt).collect(),
                y: c.average.clone(),
                ..Default::default()
            }],
            ..LinePlot::default()
        },
    )?;
    Ok(())
}
