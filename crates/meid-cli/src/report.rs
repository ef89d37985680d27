//! `meid report`: one page about the model's machine (thin: the library runs the studies and
//! writes the page, `meid::report::machine`).

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, Result};

use meid::analysis::montecarlo::Uncertain;
use meid::report::machine::{MachineOptions, MachineReport};

use crate::args::{PrintArgs, SetArgs};

#[derive(clap::Args)]
pub struct ReportArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Write index.html, its pictures (PNG and SVG), data (CSV), report.json and
    /// manifest.json into DIR (default: ./report-<model name>).
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Stroke rate of the blow train and the production steady state (blows per minute;
    /// default: the model's [production] rate_bpm, else 60, said to be assumed). With a rate
    /// from either, the key results lead with the steady blow at that rate.
    #[arg(long, value_name = "R")]
    rate_bpm: Option<f64>,
    /// Blows in the train.
    #[arg(long, value_name = "N", default_value_t = 10)]
    blows: usize,
    /// Grid points per axis of the energy map (odd: the design is the centre point).
    #[arg(long, value_name = "N", default_value_t = 41)]
    map_points: usize,
    /// The map spans the design's contact frequencies ÷/× this factor.
    #[arg(long, value_name = "F", default_value_t = 3.0)]
    map_span: f64,
    /// Record length (s) of the comparison's time histories (spectra and peaks do not
    /// depend on it).
    #[arg(long, value_name = "S", default_value_t = 2.0)]
    duration: f64,
    /// Monte Carlo input PATH=DIST(a,b), e.g.
    /// contact.slider_bed.stiffness=lognormal(4.3e7,0.2) (repeatable; none: no Monte Carlo).
    #[arg(long = "vary", value_name = "PATH=DIST")]
    vary: Vec<String>,
    /// Monte Carlo samples.
    #[arg(long, value_name = "N", default_value_t = 100)]
    samples: usize,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Measured file (UFF or CSV) to set beside the simulation, optionally with the case it
    /// measured: none=FILE, damper=FILE, added-mass=FILE (repeatable; as `meid validate`).
    /// Default: the model's [measurement] files.
    #[arg(long = "measured", value_name = "[CASE=]FILE")]
    measured: Vec<String>,
    /// Map a measured channel to meid's: NAME=B, NAME=floor, NAME=blow (repeatable; over the
    /// model's [measurement] channels).
    #[arg(long = "channel", value_name = "NAME=TARGET")]
    channel: Vec<String>,
    /// Update the model to the modes identified from the measured blows (section "Test
    /// against model"): model paths to fit, as --set names them, comma-separated (repeatable),
    /// e.g. structure.fem.machine.bed.thickness; as `meid calibrate --modal` (docs/reference/report.md).
    #[arg(long = "fit", value_name = "PATH[,PATH…]")]
    fit: Vec<String>,
    /// Bounds of fitted paths, PATH=LO..HI comma-separated (repeatable); default [p/10, 10 p].
    #[arg(long = "bounds", value_name = "PATH=LO..HI[,…]", requires = "fit")]
    bounds: Vec<String>,
    /// Weight W of the shapes' (1 − MAC) beside the relative frequency errors of the update
    /// (0: frequencies alone).
    #[arg(
        long = "mac-weight",
        value_name = "W",
        default_value_t = 1.0,
        requires = "fit"
    )]
    mac_weight: f64,
    /// Processing of the measured records (over the model's [measurement] section).
    #[command(flatten)]
    processing: crate::measure::ProcessingArgs,
    #[command(flatten)]
    set: SetArgs,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: ReportArgs) -> Result<()> {
    let uncertain = a
        .vary
        .iter()
        .map(|v| Uncertain::parse(v))
        .collect::<meid::Result<Vec<_>>>()?;
    if a.samples == 0 && !uncertain.is_empty() {
        anyhow::bail!("--samples must be at least 1");
    }
    let options = MachineOptions {
        rate_bpm: a.rate_bpm,
        blows: a.blows,
        map_points: a.map_points,
        map_span: a.map_span,
        record_s: a.duration,
        uncertain,
        samples: a.samples,
        seed: a.seed,
        measured: a.measured.clone(),
        channels: a.channel.clone(),
        processing: a.processing.as_section(),
        update: meid::report::testlab::UpdateRequest {
            fit: a.fit.clone(),
            bounds: a.bounds.clone(),
            mac_weight: a.mac_weight,
        },
    };
    let dir = a.output.clone().unwrap_or_else(|| {
        let stem = a
            .model
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "model".into());
        PathBuf::from(format!("report-{stem}"))
    });
    // The output set first: `-o FILE` is refused before the studies.
    let set = crate::outputs::begin(&dir)?;
    let show = a.print.human() && std::io::stderr().is_terminal();
    let t0 = std::time::Instant::now();
    let progress = |stage: &str| {
        if show {
            eprintln!("  {stage} …");
        }
    };
    let report =
        MachineReport::run(&a.model, &a.set.set, &options, &progress).context("report failed")?;
    if !a.print.quiet {
        for w in &report.modes.warnings {
            crate::ui::warning(w);
        }
        if let Some(meid::report::testlab::Outcome::Done(t)) = &report.test_against_model {
            let update = t.update.iter().flat_map(|u| &u.warnings);
            for w in t.warnings.iter().chain(update) {
                crate::ui::warning(format!("test against model: {w}"));
            }
        }
    }
    let generator = format!(
        "meid {} (commit {})",
        env!("CARGO_PKG_VERSION"),
        env!("MEID_GIT_COMMIT")
    );
    report.write(set.staging(), &generator)?;
    set.commit("report")?;
    let elapsed = t0.elapsed().as_secs_f64();
    if a.print.json {
        crate::json::print(&report.summary_json())?;
    } else if a.print.human() {
        println!("meid report — {}", a.model.display());
        for line in report.key_results() {
            println!("  {line}");
        }
        for n in &report.notes {
            println!("  left out: {n}");
        }
        println!(
            "wrote {} ({elapsed:.1} s)",
            dir.join("index.html").display()
        );
    }
    Ok(())
}
