//! `meid compare`: no damper vs impact damper vs added mass (paper Figs. 10, 11, 13, 14, 18, 19).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use meid::analysis::compare::{
    CaseName, CompareOptions, Comparison, ComparisonResult, SpectrumMethod,
};
use meid::analysis::production::RateOrigin;
use meid::analysis::spectrum::{
    TransientWindow, REF_ACCELERATION_ISO1683_M_PER_S2, REF_ACCELERATION_M_PER_S2,
};
use meid::model::Case;
use meid::plot;
use meid::report::figures;

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
    /// Stroke rate (blows per minute; default: the model's [production] rate_bpm). With a
    /// rate, the verdict opens with the three cases' periodic steady blow at that rate (as
    /// `meid blows --steady`); it is also the rate of the --blows train (60 when none is given).
    #[arg(long, value_name = "R")]
    rate_bpm: Option<f64>,
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
    /// Read mode levels at these frequencies (Hz) instead of the model's dominant modes; each
    /// at least the record's frequency resolution 1/T (0.5 Hz for the default 2 s record).
    #[arg(long, value_name = "HZ", value_delimiter = ',')]
    frequencies: Vec<f64>,
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: CompareArgs) -> Result<()> {
    let model = a.run.load(&a.model, None)?;
    crate::warn_model(&model, &a.print);
    let spectrum: SpectrumMethod = a.spectrum.parse()?;
    if spectrum == SpectrumMethod::Exact && (a.window != "rect" || a.tau.is_some()) {
        anyhow::bail!(
            "--window and --tau shape the FFT of the record; add --spectrum fft (the exact spectrum needs no window)"
        );
    }
    let (rate_bpm, origin) = crate::production::stroke_rate(&model, a.rate_bpm)?;
    let record = if a.blows > 1 {
        a.blows as f64 * 60.0 / rate_bpm
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
        rate_bpm,
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
    // With a stroke rate, the production verdict (the steady blow) comes first.
    let production = if origin == RateOrigin::Assumed {
        None
    } else {
        Some(crate::production::cases(&model, Case::AsSpecified, rate_bpm, &a.print)?.production)
    };
    let model_for_foundation = model.spec.foundation.is_some().then(|| model.clone());
    let comparison = Comparison::new(model, options);
    let bar = crate::progress::bar(
        a.print.quiet || a.print.json,
        comparison.cases().len(),
        "cases",
    );
    let result = comparison.run_with_progress(&|done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let result = result.context("comparison failed")?;
    // With a [foundation]: its checks and the receivers' for every case, on the steady blow
    // when a stroke rate is given or in the model (as the production verdict), else one blow
    // from rest.
    let basis = if origin == RateOrigin::Assumed {
        meid::foundation::Basis::FromRest
    } else {
        meid::foundation::Basis::Steady(meid::analysis::steady::SteadyOptions {
            rate_bpm,
            ..Default::default()
        })
    };
    let mut foundations = Vec::new();
    if let Some(m) = &model_for_foundation {
        for c in comparison.cases() {
            let case = match c {
                CaseName::NoDamper => meid::model::Case::NoDamper,
                CaseName::Damper => meid::model::Case::Damper,
                CaseName::AddedMass => meid::model::Case::AddedMass,
            };
            if let Some(f) = meid::foundation::assess_with(m, case, &basis)
                .context("foundation assessment failed")?
            {
                foundations.push((c, f));
            }
        }
    }
    let mut summary = serde_json::to_value(result.summary())?;
    if let Some(obj) = summary.as_object_mut() {
        if let Some(p) = &production {
            obj.insert("production".into(), serde_json::to_value(p)?);
        }
        if !foundations.is_empty() {
            let mut f = serde_json::Map::new();
            let mut r = serde_json::Map::new();
            for (c, fa) in &foundations {
                f.insert(c.name().into(), serde_json::to_value(&fa.foundation)?);
                r.insert(c.name().into(), serde_json::to_value(&fa.receivers)?);
            }
            obj.insert("foundation".into(), f.into());
            obj.insert("receivers".into(), r.into());
        }
    }
    if let Some(set) = set {
        write_outputs(set.staging(), &result, &summary)?;
        set.commit("compare")?;
    }
    if a.print.json {
        crate::json::print(&summary)?;
    } else if a.print.human() {
        println!("meid compare — {}", a.model.display());
        if let Some(p) = &production {
            println!(
                "  In production at {} blows/min ({}; the periodic steady blow):",
                meid::num(p.rate_bpm),
                origin.describe()
            );
            for v in &p.verdict {
                println!("    {v}");
            }
        }
        for v in result.verdict() {
            println!("  {v}");
        }
        print!("{}", result.table_text());
        for (c, fa) in &foundations {
            for r in &fa.receivers {
                println!("  {}: {}", c.label(), r.verdict);
            }
        }
        if let Some(dir) = &a.output {
            println!(
                "wrote histories, spectra, bands, reductions and pictures to {}",
                dir.display()
            );
        }
    }
    Ok(())
}

fn write_outputs(dir: &Path, r: &ComparisonResult, summary: &serde_json::Value) -> Result<()> {
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
    meid::io::write_json(&dir.join("reductions.json"), &crate::json::object(summary)?)?;

    // Per channel: the time histories (paper Figs. 10/11, 13/14, 18/19), one panel per
    // case; the energy spectral densities in dB with the refined peaks; the one-third-octave
    // band levels (the library's figures, shared with `meid report` and `meid paper`).
    let label = &figures::default_case_label;
    for ch in figures::Channel::ALL {
        plot::line_plot(
            dir.join(format!("{}-time", ch.stem())),
            &figures::history_plot(r, ch, label),
        )?;
        plot::spectrum_plot(
            dir.join(format!("{}-spectrum", ch.stem())),
            &figures::esd_plot(r, ch, label),
        )?;
        plot::spectrum_plot(
            dir.join(format!("{}-bands", ch.stem())),
            &figures::band_plot(r, ch, label),
        )?;
    }
    Ok(())
}
