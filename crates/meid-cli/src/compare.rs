//! `meid compare`: no damper vs impact damper vs added mass (paper Figs. 10, 11, 13, 14, 18, 19).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use meid::analysis::compare::{CompareOptions, Comparison, ComparisonResult, SpectrumMethod};
use meid::analysis::esd::esd_level_db;
use meid::analysis::spectrum::{
    TransientWindow, REF_ACCELERATION_ISO1683_M_PER_S2, REF_ACCELERATION_M_PER_S2,
};
use meid::plot::{self, LinePlot, Series, SpectrumPlot};

use crate::args::{PrintArgs, RunArgs};

#[derive(clap::Args)]
pub struct CompareArgs {
    /// Model file (TOML) with a [damper] (or an [added_mass]).
    model: PathBuf,
    /// Write histories, spectra, band tables, the reduction table and pictures into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Record length (s) of a single blow: the time histories written (the exact spectrum
    /// does not depend on it).
    #[arg(long, value_name = "S", default_value_t = 2.0)]
    duration: f64,
    /// Number of blows (the record is then N · 60/rate s).
    #[arg(long, value_name = "N", default_value_t = 1)]
    blows: usize,
    /// Stroke rate for --blows (blows per minute).
    #[arg(long, value_name = "R", default_value_t = 60.0)]
    rate_bpm: f64,
    /// Acceleration level reference: 1 m/s² (default) or ISO 1683's 1e-6 m/s² (ESD levels are
    /// re its square·s/Hz).
    #[arg(long, value_parser = ["1", "iso1683"], default_value = "1")]
    reference: String,
    /// Spectra: the exact transform of the simulated response (independent of rate and
    /// record length), or the windowed FFT of the sampled record (test-lab path).
    #[arg(long, value_parser = ["exact", "fft"], default_value = "exact")]
    spectrum: String,
    /// Window of the FFT path on the responses (the blow's force gets the force window).
    #[arg(long, value_parser = ["rect", "hann", "exponential"], default_value = "rect")]
    window: String,
    /// Time constant (s) of the exponential window (default: the record length / 5).
    #[arg(long, value_name = "S")]
    tau: Option<f64>,
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
    let spectrum: SpectrumMethod = a.spectrum.parse()?;
    if spectrum == SpectrumMethod::Exact && (a.window != "rect" || a.tau.is_some()) {
        anyhow::bail!(
            "--window and --tau shape the FFT of the record; add --spectrum fft (the exact spectrum needs no window)"
        );
    }
    let record = if a.blows > 1 {
        a.blows as f64 * 60.0 / a.rate_bpm
    } else {
        a.duration
    };
    let window = match a.window.as_str() {
        "hann" => TransientWindow::Hann,
        "exponential" => TransientWindow::Exponential {
            tau_s: a.tau.unwrap_or(record / 5.0),
        },
        _ => TransientWindow::Rectangular,
    };
    let options = CompareOptions {
        duration_s: a.duration,
        blows: a.blows,
        rate_bpm: a.rate_bpm,
        spectrum,
        window,
        acceleration_reference_m_per_s2: if a.reference == "iso1683" {
            REF_ACCELERATION_ISO1683_M_PER_S2
        } else {
            REF_ACCELERATION_M_PER_S2
        },
        mode_frequencies_hz: (!a.frequencies.is_empty()).then(|| a.frequencies.clone()),
        ..CompareOptions::default()
    };
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let comparison = Comparison::new(model, options);
    let bar = crate::progress::bar(
        a.print.quiet || a.print.json,
        comparison.cases().len(),
        "cases",
    );
    let result = comparison.run_with_progress(&|done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let result = result.context("comparison failed")?;
    if let Some(set) = set {
        write_outputs(set.staging(), &result)?;
        set.commit("compare")?;
    }
    if a.print.json {
        println!("{}", serde_json::to_string_pretty(&result.summary())?);
    } else if a.print.human() {
        println!("meid compare — {}", a.model.display());
        print!("{}", result.table_text());
        if let Some(dir) = &a.output {
            println!(
                "wrote histories, spectra, bands, reductions and pictures to {}",
                dir.display()
            );
        }
    }
    Ok(())
}

fn write_outputs(dir: &Path, r: &ComparisonResult) -> Result<()> {
    for c in &r.cases {
        meid::io::write_history_csv(
            &dir.join(format!("history-{}.csv", c.case.name())),
            &c.history,
        )?;
    }
    meid::io::write_atomic(&dir.join("spectra.csv"), &r.spectra_csv()?)?;
    meid::io::write_atomic(&dir.join("bands.csv"), &r.bands_csv()?)?;
    meid::io::write_atomic(&dir.join("reductions.txt"), r.table_text().as_bytes())?;
    meid::io::write_atomic(&dir.join("reductions.csv"), &r.table_csv()?)?;
    meid::io::write_json(&dir.join("reductions.json"), &r.summary())?;

    // Time histories (paper Figs. 10/11, 13/14, 18/19): the output samples, one panel per
    // case on a common scale (overlaid, the last-drawn case hid the others).
    // The window shown: up to 1.25 × the last instant any case exceeds 2 % of the largest
    // |value| (the rest of the record is the decayed tail), stated in the title.
    let time = |title: &str, y_label: &str, pick: &dyn Fn(&meid::analysis::History) -> Vec<f64>| {
        let series: Vec<Series> = r
            .cases
            .iter()
            .map(|c| Series {
                label: c.case.label().into(),
                x: c.history.time_s.clone(),
                y: pick(&c.history),
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
        LinePlot {
            title: if zoom {
                format!(
                    "{title}, first {} s of {} s",
                    plot::axis::fmt_tick(&(shown - t0)),
                    plot::axis::fmt_tick(&(t_end - t0))
                )
            } else {
                title.into()
            },
            x_label: "time (s)".into(),
            y_label: y_label.into(),
            series,
            panels: true,
            x_range: zoom.then_some((t0, shown)),
            ..Default::default()
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

    // Energy spectral densities in dB, log frequency, with the refined peaks (exact path).
    let (ea, ef) = r.esd_references();
    let a2 = r.acceleration_reference_m_per_s2.powi(2);
    let what = match r.spectrum {
        SpectrumMethod::Exact => "exact ESD".to_string(),
        SpectrumMethod::Fft => format!("FFT ESD, {} window", r.window.name()),
    };
    let spec = |ch: usize, title: &str, reference: f64, label: String| -> SpectrumPlot {
        let series = r
            .cases
            .iter()
            .map(|c| {
                let s = &c.spectra[ch];
                let (x, y) = s.level_curve_db(&r.frequency_hz, reference);
                Series {
                    label: c.case.label().into(),
                    x,
                    y,
                    style: case_style(c.case),
                    ..Default::default()
                }
            })
            .collect();
        SpectrumPlot {
            title: title.into(),
            y_label: label,
            x_log: true,
            series,
            ..Default::default()
        }
    };
    plot::spectrum_plot(
        dir.join("acceleration-spectrum"),
        &spec(
            0,
            &format!("bed acceleration at B, energy spectral density ({what})"),
            a2,
            format!("ESD level (dB re {ea})"),
        ),
    )?;
    plot::spectrum_plot(
        dir.join("floor-force-spectrum"),
        &spec(
            1,
            &format!("force to the floor, energy spectral density ({what})"),
            1.0,
            format!("ESD level (dB re {ef})"),
        ),
    )?;
    // One-third-octave band levels as steps over each band.
    let bands = |ch: usize, title: &str, reference: f64, label: String| -> SpectrumPlot {
        let series = r
            .cases
            .iter()
            .map(|c| {
                let mut x = Vec::new();
                let mut y = Vec::new();
                for (b, e) in r.bands.iter().zip(&c.spectra[ch].band_energy) {
                    let l = esd_level_db(*e, reference);
                    x.extend([b.lower_hz, b.upper_hz]);
                    y.extend([l, l]);
                }
                Series {
                    label: c.case.label().into(),
                    x,
                    y,
                    style: case_style(c.case),
                    ..Default::default()
                }
            })
            .collect();
        SpectrumPlot {
            title: title.into(),
            y_label: label,
            x_log: true,
            series,
            ..Default::default()
        }
    };
    let band_ref = |s: &str| s.trim_end_matches("/Hz").to_string();
    plot::spectrum_plot(
        dir.join("acceleration-bands"),
        &bands(
            0,
            &format!("bed acceleration at B, one-third-octave band energy ({what})"),
            a2,
            format!("band level (dB re {})", band_ref(&ea)),
        ),
    )?;
    plot::spectrum_plot(
        dir.join("floor-force-bands"),
        &bands(
            1,
            &format!("force to the floor, one-third-octave band energy ({what})"),
            1.0,
            format!("band level (dB re {})", band_ref(&ef)),
        ),
    )?;
    Ok(())
}

/// Stroke of a case in the overlaid spectra: the added mass dashed, so that it stays
/// visible where it coincides with the bare machine.
fn case_style(case: meid::analysis::compare::CaseName) -> plot::LineStyle {
    match case {
        meid::analysis::compare::CaseName::AddedMass => plot::LineStyle::Dashed,
        _ => plot::LineStyle::Solid,
    }
}
