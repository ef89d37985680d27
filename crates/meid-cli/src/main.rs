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
mod simulate;
mod sweep;

#[derive(Parser)]
#[command(
    name = "meid",
    version,
    about = "Momentum-exchange impact dampers for impact machines"
)]
struct Cli {
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
            eprintln!("error: {e:#}");
            ExitCode::from(2)
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
