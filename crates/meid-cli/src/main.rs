//! `meid`: the command line. A thin shell over the `meid` library: each subcommand lives in
//! its own module and calls the library; the library never prints.

use std::path::Path;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

use meid::model::Model;

mod args;
mod blows;
mod compare;
mod modes;
mod montecarlo;
mod optimize;
mod outputs;
mod simulate;
mod sweep;

#[derive(Parser)]
#[command(
    name = "meid",
    version,
    about = "Momentum-exchange impact dampers for impact machines"
)]
struct Cli {
    /// Memory a run may use, e.g. 2GiB, 512MiB or bytes (default: half the physical memory).
    /// Runs estimated above it are refused before they allocate, naming the input to reduce.
    #[arg(long, global = true, value_name = "BYTES|MiB|GiB")]
    max_memory: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate one blow: energy left in the machine, contact forces, time histories.
    Simulate(simulate::SimulateArgs),
    /// Modal analysis of the model's structure: frequencies, effective masses, mode shapes.
    Modes(modes::ModesArgs),
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
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(m) = &cli.max_memory {
        match meid::limits::parse_bytes(m) {
            Ok(b) => meid::limits::set_max_memory(b),
            Err(e) => {
                eprintln!("error: {e}");
                return ExitCode::from(2);
            }
        }
    }
    let result = match cli.command {
        Command::Simulate(a) => simulate::run(a),
        Command::Modes(a) => modes::run(a),
        Command::Sweep(a) => sweep::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Optimize(a) => optimize::run(a),
        Command::Blows(a) => blows::run(a),
        Command::Montecarlo(a) => montecarlo::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
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

/// Loads a model with `--set` overrides and the common run options folded in as overrides.
pub(crate) fn load(
    path: &Path,
    set: &[String],
    method: Option<&str>,
    duration: Option<f64>,
    rate: Option<f64>,
) -> Result<Model> {
    let mut overrides = set.to_vec();
    if let Some(m) = method {
        overrides.push(format!("simulation.method=\"{m}\""));
    }
    if let Some(d) = duration {
        overrides.push(format!("simulation.duration={d:e}"));
    }
    if let Some(r) = rate {
        overrides.push(format!("simulation.sample_rate={r:e}"));
    }
    Ok(Model::from_file(path, &overrides)?)
}
