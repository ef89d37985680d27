//! `meid compare`: no damper vs impact damper vs added mass (paper Figs. 10, 11, 13, 14, 18, 19).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use meid::analysis::compare::{CompareOptions, Comparison, ComparisonResult};
use meid::analysis::spectrum::{
    Window, REF_ACCELERATION_ISO1683_M_PER_S2, REF_ACCELERATION_M_PER_S2, REF_FORCE_N,
};
use meid::plot::{self, LinePlot, Series, SpectrumPlot};

use crate::args::{PrintArgs, RunArgs};

#[derive(clap::Args)]
pub struct CompareArgs {
    /// Model file (TOML) with a [damper] (or an [added_mass]).
    model: PathBuf,
    /// Write histories, spectra, the reduction table and pictures into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Record length (s) of a single blow.
    #[arg(long, value_name = "S", default_value_t = 2.0)]
    duration: f64,
    /// Number of blows (the record is then N · 60/rate s).
    #[arg(long, value_name = "N", default_value_t = 1)]
    blows: usize,
    /// Stroke rate for --blows (blows per minute).
    #[arg(long, value_name = "R", default_value_t = 60.0)]
    rate_bpm: f64,
    /// Acceleration level reference: 1 m/s² (default) or ISO 1683's 1e-6 m/s².
    #[arg(long, value_parser = ["1", "iso1683"], default_value = "1")]
    reference: String,
    /// Spectral window over the whole record (rect suits a transient that starts at t = 0).
    #[arg(long, value_parser = ["hann", "rect", "flattop"], default_value = "rect")]
    window: String,
    /// Read mode levels at these frequencies (Hz) instead of the model's dominant modes.
    #[arg(long, value_name = "HZ", value_delimiter = ',')]
    frequencies: Vec<f64>,
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: CompareArgs) -> Result<()> {
    let model = a.run.load(&a.model, None)?;
    let window = match a.window.as_str() {
        "hann" => Window::Hann,
        "flattop" => Window::FlatTop,
        _ => Window::Rectangular,
    };
    let options = CompareOptions {
        duration_s: a.duration,
        blows: a.blows,
        rate_bpm: a.rate_bpm,
        window,
        acceleration_reference_m_per_s2: if a.reference == "iso1683" {
            REF_ACCELERATION_ISO1683_M_PER_S2
        } else {
            REF_ACCELERATION_M_PER_S2
        },
        mode_frequencies_hz: (!a.frequencies.is_empty()).then(|| a.frequencies.clone()),
        ..CompareOptions::default()
    };
    let result = Comparison::new(model, options)
        .run()
        .context("comparison failed")?;
    if let Some(dir) = &a.output {
        write_outputs(dir, &result)?;
    }
    if a.print.json {
        println!("{}", serde_json::to_string_pretty(&result.summary())?);
    } else if a.print.human() {
        println!("meid compare — {}", a.model.display());
        print!("{}", result.table_text());
        if let Some(dir) = &a.output {
            println!(
                "wrote histories, spectra, reductions and pictures to {}",
                dir.display()
            );
        }
    }
    Ok(())
}

fn write_outputs(dir: &Path, r: &ComparisonResult) -> Result<()> {
    for c in &r.cases {
        meid::io::write_atomic(
            &dir.join(format!("history-{}.csv", c.case.name())),
            &meid::io::history_csv(&c.history)?,
        )?;
    }
    meid::io::write_atomic(&dir.join("spectra.csv"), &r.spectra_csv()?)?;
    meid::io::write_atomic(&dir.join("reductions.txt"), r.table_text().as_bytes())?;
    meid::io::write_atomic(&dir.join("reductions.csv"), &r.table_csv()?)?;
    meid::io::write_json(&dir.join("reductions.json"), &r.summary())?;

    // Time histories (paper Figs. 10/11, 13/14, 18/19).
    let time = |title: &str, y_label: &str, pick: &dyn Fn(&meid::analysis::History) -> Vec<f64>| {
        LinePlot {
            title: title.into(),
            x_label: "time (s)".into(),
            y_label: y_label.into(),
            x_log: false,
            y_log: false,
            series: r
                .cases
                .iter()
                .map(|c| Series {
                    label: c.case.label().into(),
                    x: c.history.time_s.clone(),
                    y: pick(&c.history),
                })
                .collect(),
        }
    };
    plot::line_plot(
        dir.join("acceleration-time"),
        &time("bed acceleration at B", "acceleration (m/s²)", &|h| {
            h.bed_acceleration_m_per_s2.clone()
        }),
    )?;
    plot::line_plot(
        dir.join("floor-force-time"),
        &time("force to the floor", "force (N)", &|h| {
            h.floor_force_n.clone()
        }),
    )?;

    // Spectra in dB, log frequency from 1/T to the highest mode read × 4 (≤ Nyquist).
    let top = r
        .cases
        .iter()
        .flat_map(|c| c.modes.iter().map(|m| m.band_hz[1]))
        .fold(0.0_f64, f64::max);
    let f_max = (4.0 * top).min(r.sample_rate_hz / 2.0);
    let spec = |title: &str, y_label: &str, acc: bool| -> Result<SpectrumPlot> {
        let mut series = Vec::new();
        for c in &r.cases {
            let s = if acc {
                &c.acceleration_spectrum
            } else {
                &c.floor_force_spectrum
            };
            let reference = if acc {
                r.acceleration_reference_m_per_s2
            } else {
                REF_FORCE_N
            };
            let levels = s.levels_db(reference)?;
            let (x, y): (Vec<f64>, Vec<f64>) = s
                .frequency_hz
                .iter()
                .zip(levels)
                .filter(|(f, _)| **f > 0.0 && **f <= f_max)
                .map(|(f, l)| (*f, l))
                .unzip();
            series.push(Series {
                label: c.case.label().into(),
                x,
                y,
            });
        }
        Ok(SpectrumPlot {
            title: title.into(),
            y_label: y_label.into(),
            x_log: true,
            series,
        })
    };
    let acc_label = if r.acceleration_reference_m_per_s2 == REF_ACCELERATION_M_PER_S2 {
        "acceleration level (dB re 1 m/s², RMS)".to_string()
    } else {
        "acceleration level (dB re 1e-6 m/s², RMS)".to_string()
    };
    plot::spectrum_plot(
        dir.join("acceleration-spectrum"),
        &spec(
            &format!(
                "bed acceleration at B, spectrum ({} window)",
                r.window.name()
            ),
            &acc_label,
            true,
        )?,
    )?;
    plot::spectrum_plot(
        dir.join("floor-force-spectrum"),
        &spec(
            &format!("force to the floor, spectrum ({} window)", r.window.name()),
            "force level (dB re 1 N, RMS)",
            false,
        )?,
    )?;
    Ok(())
}
