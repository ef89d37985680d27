//! `meid calibrate`: model values fitted to measured records (thin: the library fits).

use std::path::PathBuf;

use anyhow::{bail, Result};

use meid::measure::calibrate::{
    calibrate, calibrated_model_text, parameters, parse_bounds, parse_fit, Problem, ResidualKind,
    Settings,
};
use meid::measure::mapping::parse_channel_flags;
use meid::measure::validate::read_measured_noting;

use crate::args::{PrintArgs, RunArgs};
use crate::measure::ProcessingArgs;

#[derive(clap::Args)]
pub struct CalibrateArgs {
    /// Model file (TOML); its values are the start of the fit.
    model: PathBuf,
    /// Measured file (UFF or CSV), optionally with the case it measured: none=FILE (the bare
    /// machine), damper=FILE, added-mass=FILE; a plain FILE is the model as specified
    /// (repeatable; the cases are fitted together).
    #[arg(
        long = "measured",
        value_name = "[CASE=]FILE",
        required_unless_present = "modal"
    )]
    measured: Vec<String>,
    /// Fit to identified modes instead of records: meid identify's JSON, modes.csv or UFF 55.
    /// Residuals: relative frequency errors of the paired modes and √W (1 − MAC), W the
    /// --mac-weight (docs/explanations/measure.md, "Correlation and model updating").
    #[arg(long = "modal", value_name = "IDENTIFIED", conflicts_with_all = ["measured", "spectrum", "channel"])]
    modal: Option<PathBuf>,
    /// Weight W of the shapes' (1 − MAC) beside the relative frequency errors (with --modal;
    /// 0: frequencies alone).
    #[arg(
        long = "mac-weight",
        value_name = "W",
        default_value_t = 1.0,
        requires = "modal"
    )]
    mac_weight: f64,
    #[command(flatten)]
    mapping: crate::correlate::MappingArgs,
    /// Model paths to fit, as --set names them, comma-separated (repeatable), e.g.
    /// contact.slider_bed.stiffness,contact.bed_damper.stiffness,structure.lumped.damping_ratios[1].
    #[arg(long = "fit", value_name = "PATH[,PATH…]", required = true)]
    fit: Vec<String>,
    /// Bounds of fitted paths, PATH=LO..HI comma-separated (repeatable; PATH=LO:HI is accepted
    /// too); default [p/10, 10 p] around the model's value p (a value ≤ 0 needs bounds).
    #[arg(long = "bounds", value_name = "PATH=LO..HI[,…]")]
    bounds: Vec<String>,
    /// Fit ESD levels (dB) between LO and HI Hz instead of the time histories (LO:HI is
    /// accepted too).
    #[arg(long = "spectrum", value_name = "LO..HI")]
    spectrum: Option<String>,
    /// Iteration limit of the Levenberg-Marquardt solver.
    #[arg(long = "max-iterations", value_name = "N", default_value_t = 50)]
    max_iterations: usize,
    /// Map a measured channel to meid's: NAME=B, NAME=floor, NAME=blow (repeatable).
    #[arg(long = "channel", value_name = "NAME=TARGET")]
    channel: Vec<String>,
    /// Write calibration.json, calibrated.toml (the model with the estimates) and the
    /// before/after overlays (calibration_<case>_<channel>.png/.svg) into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    processing: ProcessingArgs,
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    print: PrintArgs,
}

fn parse_band(s: &str) -> Result<ResidualKind> {
    let bad = || {
        anyhow::anyhow!(
            "--spectrum {s}: give LO..HI (or LO:HI) in Hz with 0 ≤ LO < HI, e.g. --spectrum 200..400"
        )
    };
    let (lo, hi) = meid::analysis::study::parse_range(s).map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
        bail!(bad());
    }
    Ok(ResidualKind::Spectrum {
        lower_hz: lo,
        upper_hz: hi,
    })
}

pub fn run(a: CalibrateArgs) -> Result<()> {
    if let Some(modal) = &a.modal {
        return run_modal(&a, modal);
    }
    let model = a.run.load(&a.model, None)?;
    crate::warn_model(&model, &a.print);
    let paths = parse_fit(&a.fit)?;
    let bounds = parse_bounds(&a.bounds)?;
    let params = parameters(&model, &paths, &bounds)?;
    if a.max_iterations == 0 {
        bail!("--max-iterations must be at least 1");
    }
    let settings = Settings {
        residual: match &a.spectrum {
            Some(s) => parse_band(s)?,
            None => ResidualKind::TimeHistory,
        },
        max_iterations: a.max_iterations,
        ..Settings::default()
    };
    let p = a.processing.processing(model.spec.measurement.as_ref())?;
    let flags = parse_channel_flags(&a.channel, &model.spec.points.measurement)?;
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let (cases, passed_over) = read_measured_noting(&a.measured, None)?;
    if !a.print.quiet {
        for n in &passed_over {
            crate::ui::warning(n);
        }
    }
    let problem = Problem::new(&model, params, &cases, &p, &flags, settings)?;
    let c = calibrate(&problem)?;
    if let Some(set) = set {
        meid::io::write_json(&set.path("calibration.json"), &crate::json::object(&c)?)?;
        let text = calibrated_model_text(&model, problem.parameters(), &c.values())?;
        meid::io::write_atomic(&set.path("calibrated.toml"), text.as_bytes())?;
        c.plots(set.staging())?;
        set.commit("calibrate")?;
    }
    print_result(&a, &c, c.to_text(), "", &model, " and the overlays")
}

/// `meid calibrate --modal`: model values fitted to identified modes.
fn run_modal(a: &CalibrateArgs, modal: &std::path::Path) -> Result<()> {
    use meid::measure::correlate::{read_identified, Settings as CorrelateSettings};
    use meid::measure::modal_update::{calibrate_modal, ModalProblem};
    let model = a.run.load(&a.model, None)?;
    crate::warn_model(&model, &a.print);
    let paths = parse_fit(&a.fit)?;
    let bounds = parse_bounds(&a.bounds)?;
    let params = parameters(&model, &paths, &bounds)?;
    if a.max_iterations == 0 {
        bail!("--max-iterations must be at least 1");
    }
    let mapping = a.mapping.mapping()?;
    // An FE model's point coordinates, for the mapping by coordinates.
    let coordinates = if mapping.geometry.is_some() {
        let (_, an) = meid::model::fem::from_file_with_analysis(&a.model, &a.run.set.set, None)?;
        crate::correlate::point_coordinates(an.as_ref())
    } else {
        None
    };
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let ident = read_identified(modal)?;
    let settings = Settings {
        max_iterations: a.max_iterations,
        ..Settings::default()
    };
    let corr = CorrelateSettings {
        min_mac: a.mapping.min_mac,
        ..CorrelateSettings::default()
    };
    let problem = ModalProblem::new(
        &model,
        params,
        &ident,
        coordinates,
        mapping,
        corr,
        a.mac_weight,
        settings,
    )?;
    let c = calibrate_modal(&problem)?;
    if let Some(set) = set {
        meid::io::write_json(&set.path("calibration.json"), &crate::json::object(&c)?)?;
        let text = calibrated_model_text(&model, problem.parameters(), &c.values())?;
        meid::io::write_atomic(&set.path("calibrated.toml"), text.as_bytes())?;
        set.commit("calibrate")?;
    }
    if !a.print.quiet {
        for w in c.warnings.iter().chain(&c.after.warnings) {
            crate::ui::warning(w);
        }
    }
    print_result(a, &c, c.to_text(), " --modal", &model, "")
}

/// A calibration's result on stdout: its JSON, or its table with the title (`mode` after
/// `meid calibrate`) and where the calibrated model was written (or how to get it: `-o DIR`
/// writes the model file `and_more`).
fn print_result(
    a: &CalibrateArgs,
    result: &impl serde::Serialize,
    text: String,
    mode: &str,
    model: &meid::model::Model,
    and_more: &str,
) -> Result<()> {
    if a.print.json {
        crate::json::print(result)?;
    } else if a.print.human() {
        println!(
            "{}{mode} — {}",
            crate::ui::bold("meid calibrate"),
            model.spec.name.as_deref().unwrap_or("model")
        );
        print!("{text}");
        match &a.output {
            Some(dir) => println!(
                "wrote {} (calibrated model: {})",
                dir.display(),
                dir.join("calibrated.toml").display()
            ),
            None => println!("give -o DIR to write the calibrated model file{and_more}"),
        }
    }
    Ok(())
}
