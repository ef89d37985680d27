//! `meid`: the command line. A thin shell over the `meid` library: each subcommand lives in
//! its own module and calls the library; the library never prints.

use std::path::Path;
use std::process::ExitCode;

use anyhow::Result;
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use meid::model::Model;

// Standard output and error go through `ui` (a closed pipe ends quietly, never a panic): these
// shadow the standard macros in every module declared below.
macro_rules! print {
    ($($arg:tt)*) => { $crate::ui::write_stdout(format_args!($($arg)*), false) };
}
macro_rules! println {
    () => { $crate::ui::write_stdout(format_args!(""), true) };
    ($($arg:tt)*) => { $crate::ui::write_stdout(format_args!($($arg)*), true) };
}
#[allow(unused_macros)]
macro_rules! eprint {
    ($($arg:tt)*) => { $crate::ui::write_stderr(format_args!($($arg)*), false) };
}
#[allow(unused_macros)]
macro_rules! eprintln {
    () => { $crate::ui::write_stderr(format_args!(""), true) };
    ($($arg:tt)*) => { $crate::ui::write_stderr(format_args!($($arg)*), true) };
}

mod args;
mod blows;
mod blows_general;
mod calibrate;
mod compare;
mod correlate;
mod frf;
mod json;
mod measure;
mod model;
mod modes;
mod montecarlo;
mod optimize;
mod outputs;
mod paper;
mod placement;
mod production;
mod progress;
mod report;
mod return_map;
mod shard;
mod shell;
mod simulate;
mod sweep;
mod sweep_general;
mod ui;
mod validate;

#[derive(Parser)]
#[command(
    name = "meid",
    version = concat!(env!("CARGO_PKG_VERSION"), " (commit ", env!("MEID_GIT_COMMIT"), ")"),
    about = "Momentum-exchange impact dampers for impact machines"
)]
pub(crate) struct Cli {
    /// Memory a run may use, e.g. 2GiB, 512MiB or bytes (default: half the physical memory).
    /// Runs estimated above it are refused before they allocate, naming the input to reduce.
    #[arg(long, global = true, value_name = "BYTES|MiB|GiB")]
    max_memory: Option<String>,
    /// Colour `error:`/`warning:` and emphasis: auto (a terminal, unless NO_COLOR is set),
    /// always or never.
    #[arg(long, global = true, value_enum, default_value_t = ui::ColorChoice::Auto)]
    color: ui::ColorChoice,
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Simulate one blow: energy left in the machine, contact forces, time histories.
    Simulate(simulate::SimulateArgs),
    /// Modal analysis of the model's structure: frequencies, effective masses, mode shapes.
    Modes(modes::ModesArgs),
    /// Model-file tools: `expand` writes [structure.fem.machine] as the general model it
    /// generates.
    Model(model::ModelArgs),
    /// Vary model quantities over lists or ranges and record every summary metric.
    Sweep(sweep::SweepArgs),
    /// No damper vs impact damper vs added mass: time histories, spectra, dB reductions.
    Compare(compare::CompareArgs),
    /// Find the damper that minimises an objective.
    Optimize(optimize::OptimizeArgs),
    /// A train of blows at a stroke rate: blow-to-blow levels and steady state.
    Blows(blows::BlowsArgs),
    /// Monte Carlo over uncertain inputs (seeded): mean, percentiles, histogram.
    Montecarlo(montecarlo::MonteCarloArgs),
    /// One page about the model's machine: modes, energy map, none/damper/added mass,
    /// blow train, optimiser, Monte Carlo (index.html with pictures and data).
    Report(report::ReportArgs),
    /// The paper reproduced: every study of its Figs. 2-19, its numbers beside meid's, and why
    /// they differ, as one HTML page.
    Paper(paper::PaperArgs),
    /// Read measured records (UFF 58/58b, CSV): peaks, blows, dominant spectral lines.
    Measure(measure::MeasureArgs),
    /// Frequency response functions (H1, H2, Hv) with coherence from measured blows: CSV, UFF
    /// 58 type 4, pictures.
    Frf(frf::FrfArgs),
    /// Modes from FRFs: LSCF poles with a stabilisation diagram, LSFD shapes, damping corrected
    /// for the exponential window.
    Identify(frf::IdentifyArgs),
    /// Identified modes against the model's: point mapping (by name or coordinates, with
    /// sign), MAC and auto-MAC, paired modes, frequency errors, blind-point warnings, and the
    /// model's test geometry (UFF 15, 82, 2412, 55).
    Correlate(correlate::CorrelateArgs),
    /// The simulation beside measured records: frequency, level and peak errors, reductions.
    Validate(validate::ValidateArgs),
    /// Fit model values (damping ratios, contact stiffnesses, …) to measured records, or to
    /// identified modes (--modal): estimates with confidence intervals, residual, before/after
    /// overlays or correlation table, the calibrated model file.
    Calibrate(calibrate::CalibrateArgs),
    /// Put the shards of a sweep or Monte Carlo (--shard K/N) together: the unsharded run's files.
    Merge(shard::MergeArgs),
    /// Shell completion script for bash, zsh, fish, elvish or powershell, on stdout.
    Completions(shell::CompletionsArgs),
    /// The manual page (roff) on stdout, or every page into a directory with -o.
    Man(shell::ManArgs),
}

fn main() -> ExitCode {
    outputs::on_signal_clean_up();
    // `--color` is read before clap so that clap's own messages follow it.
    let color = ui::ColorChoice::from_args(std::env::args_os());
    ui::init_color(color);
    let matches = Cli::command().color(color.to_clap()).get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(c) => c,
        Err(e) => e.exit(),
    };
    if cli.color != color {
        ui::init_color(cli.color);
    }
    if let Some(m) = &cli.max_memory {
        match meid::limits::parse_bytes(m) {
            Ok(b) => meid::limits::set_max_memory(b),
            Err(e) => {
                ui::error(format_args!("{e}"));
                return ExitCode::from(2);
            }
        }
    }
    let result = match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Modes(a) => modes::run(a),
        Command::Model(a) => model::run(a),
        Command::Sweep(a) if meid::model::network::is_general_file(&a.model) => {
            sweep_general::run(&a)
        }
        Command::Sweep(a) => sweep::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Optimize(a) => optimize::run(a),
        Command::Blows(a) if meid::model::network::is_general_file(&a.model) => {
            blows_general::run(a)
        }
        Command::Blows(a) => blows::run(a),
        Command::Montecarlo(a) => montecarlo::run(a),
        Command::Report(a) => report::run(a),
        Command::Paper(a) => paper::run(a),
        Command::Measure(a) => measure::run(a),
        Command::Frf(a) => frf::run_frf(a),
        Command::Identify(a) => frf::run_identify(a),
        Command::Correlate(a) => correlate::run(a),
        Command::Validate(a) => validate::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Merge(a) => shard::merge(a, |name, command, shards| match (name, command) {
            ("sweep", Command::Sweep(args)) => Some(sweep::merge(args, shards)),
            ("montecarlo", Command::Montecarlo(args)) => Some(montecarlo::merge(args, shards)),
            _ => None,
        }),
        Command::Completions(a) => shell::completions(a),
        Command::Man(a) => shell::man(a),
    };
    let result = result.and_then(|()| {
        ui::finish_stdout().map_err(|e| anyhow::anyhow!("cannot write to standard output: {e}"))
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            ui::error(format_args!("{}", error_chain(&e)));
            ExitCode::from(2)
        }
    }
}

/// The error and its causes, `: `-separated, each cause left out when the text so far already
/// ends with it (an `Io` error displays its OS error and also returns it as its source: printed
/// once, not "… (os error 2): … (os error 2)").
pub(crate) fn error_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if out.is_empty() {
            out = text;
        } else if !out.ends_with(&text) {
            out.push_str(": ");
            out.push_str(&text);
        }
    }
    out
}

/// Prints the model's warnings on stderr (the structure's own, captured flexibility shares
/// below 95 %, frequency spreads the propagator resolves only approximately:
/// [`meid::model::Model::diagnostics`]) before a run, unless `--quiet`: they hold whatever the
/// run gives, and when it fails they often say why.
pub(crate) fn warn_model(model: &Model, print: &args::PrintArgs) {
    warn_diagnostics(&model.diagnostics(), print);
}

/// [`warn_model`] for diagnostics the caller keeps (`simulate` writes them out too).
pub(crate) fn warn_diagnostics(diag: &meid::model::Diagnostics, print: &args::PrintArgs) {
    json::record(diag);
    if !print.quiet {
        for w in &diag.warnings {
            ui::warning(w);
        }
    }
}

/// Loads a model with `--set` overrides and the common run options folded in as overrides.
pub(crate) fn load(
    path: &Path,
    set: &[String],
    method: Option<&str>,
    duration: Option<f64>,
    rate: Option<f64>,
) -> Result<Model> {
    let mut overrides = set.to_vec();
    // Each flag becomes a `--set` override; an error the model finds in one names the flag
    // and the value as given (`--rate 0`), not the override it was turned into.
    let mut flags: Vec<(String, String)> = Vec::new();
    let mut flag = |field: &str, value: String, shown: String| {
        let spec = format!("{field}={value}");
        flags.push((format!("--set {spec}"), shown));
        overrides.push(spec);
    };
    if let Some(m) = method {
        flag(
            "simulation.method",
            format!("\"{m}\""),
            format!("--method {m}"),
        );
    }
    // TOML spells the non-finite numbers nan, inf and -inf.
    let toml_number = |v: f64| {
        if v.is_nan() {
            "nan".to_string()
        } else {
            format!("{v:e}")
        }
    };
    if let Some(d) = duration {
        flag(
            "simulation.duration",
            toml_number(d),
            format!("--duration {}", meid::num(d)),
        );
    }
    if let Some(r) = rate {
        flag(
            "simulation.sample_rate",
            toml_number(r),
            format!("--rate {}", meid::num(r)),
        );
    }
    Model::from_file(path, &overrides).map_err(|e| match e {
        meid::Error::Input { location, message } => {
            let location = flags
                .iter()
                .fold(location, |l, (spec, shown)| l.replace(spec.as_str(), shown));
            meid::Error::Input { location, message }.into()
        }
        e => e.into(),
    })
}
