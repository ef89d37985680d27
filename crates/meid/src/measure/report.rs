//! Text, CSV and pictures of processed channels (`meid measure`).

use std::fmt::Write as _;
use std::path::Path;

use super::process::{esd_reference, ProcessedChannel};
use crate::analysis::esd::esd_level_db;
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
        "  {:<24} {:<6} {:>9} {:>10} {:>13} {:>10} {:>6} {:>11} {:>9}",
        "channel",
        "unit",
        "samples",
        "rate (Hz)",
        "sample peak",
        "at (s)",
        "blows",
        "dominant",
        "level"
    );
    for c in channels {
        let s = &c.summary;
        let _ = writeln!(
            out,
            "  {:<24} {:<6} {:>9} {:>10.1} {:>13.5e} {:>10.6} {:>6} {:>8.2} Hz {:>6.2} dB",
            s.name,
            s.unit,
            s.samples,
            s.sample_rate_hz,
            s.peak,
            s.peak_time_s,
            s.blows,
            s.dominant_frequency_hz,
            s.dominant_level_db
        );
    }
    let _ = writeln!(
        out,
        "  peaks are sample peaks (the largest |x| among the samples; the signal between samples may go higher);"
    );
    let _ = writeln!(
        out,
        "  the dominant line is the largest bin above DC of the blow-averaged energy spectral density, ± half a bin;"
    );
    let _ = writeln!(
        out,
        "  levels are dB re 1 (SI unit)²·s/Hz (1 (m/s^2)²·s/Hz, 1 N²·s/Hz)."
    );
    out
}

/// `frequency_hz,esd_<unit>2_s_per_hz,level_db` of one channel's blow-averaged ESD.
pub fn spectrum_csv(c: &ProcessedChannel) -> Vec<u8> {
    let (r, _) = esd_reference(c.quantity);
    let mut s = String::from("frequency_hz,esd_si2_s_per_hz,level_db\n");
    for (f, e) in c.spectrum.frequency_hz.iter().zip(&c.spectrum.density) {
        let _ = writeln!(s, "{f:.9e},{e:.12e},{:.6}", esd_level_db(*e, r));
    }
    s.into_bytes()
}

/// One row per channel and one-third-octave band: energy (SI²·s) and level (dB re 1 SI²·s).
pub fn bands_csv(channels: &[ProcessedChannel]) -> Vec<u8> {
    let mut s = String::from("channel,band_hz,lower_hz,upper_hz,energy_si2_s,level_db\n");
    for c in channels {
        for (b, e) in &c.bands {
            let _ = writeln!(
                s,
                "{},{},{:.6},{:.6},{e:.12e},{:.6}",
                csv_field(&c.summary.name),
                b.nominal_hz,
                b.lower_hz,
                b.upper_hz,
                esd_level_db(*e, 1.0)
            );
        }
    }
    s.into_bytes()
}

/// `time_s,<name>_<unit>` of one channel's blow-averaged record (time from the record start).
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
        .map(|(f, e)| (*f, esd_level_db(*e, r)))
        .unzip();
    // A channel that is zero throughout has no level to draw.
    if y.iter().any(|v| v.is_finite()) {
        crate::plot::spectrum_plot(
            dir.join(format!("{stem}_spectrum")),
            &SpectrumPlot {
                title: format!(
                    "{}: blow-averaged ESD ({} blows)",
                    c.summary.name, c.spectrum.averages
                ),
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
            title: format!("{}: blow-averaged record", c.summary.name),
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
