//! Argument groups shared by several subcommands (`#[command(flatten)]`), so each flag is
//! declared, documented and turned into model overrides in one place.

use std::path::Path;

use anyhow::Result;
use meid::model::{Case, Model};

/// `--set PATH=VALUE` overrides of model fields.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SetArgs {
    /// Override a model field, e.g. --set contact.bed_damper.stiffness=1.26e8 (repeatable).
    #[arg(long = "set", value_name = "PATH=VALUE")]
    pub set: Vec<String>,
}

/// `--method`: the integration method.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct MethodArg {
    /// Integration method: exact (piecewise-linear, closed form) or dopri5.
    #[arg(long, value_parser = ["exact", "dopri5"])]
    pub method: Option<String>,
}

/// `--method`, `--rate` and `--set`: how a model file is loaded for one run.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct RunArgs {
    #[command(flatten)]
    pub method: MethodArg,
    /// Output sample rate (Hz).
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    #[command(flatten)]
    pub set: SetArgs,
}

impl RunArgs {
    /// Loads `path` with these overrides (and a simulated time, when the command has one).
    pub fn load(&self, path: &Path, duration: Option<f64>) -> Result<Model> {
        crate::load(
            path,
            &self.set.set,
            self.method.method.as_deref(),
            duration,
            self.rate,
        )
    }
}

/// `--json` and `--quiet`: what goes to stdout. Every analysis subcommand has them, with
/// `-o/--output DIR` (declared by each, naming the files it writes), and they mean the same
/// everywhere: `-o DIR` writes the run's files into DIR, `--json` prints the result as JSON on
/// stdout (and nothing else there), `-q` prints nothing but errors. `--json` and `-q` exclude
/// each other.
#[derive(clap::Args, Debug, Clone, Copy, Default)]
pub struct PrintArgs {
    /// Print the result as JSON on stdout.
    #[arg(long, conflicts_with = "quiet")]
    pub json: bool,
    /// Print nothing but errors (no report, warnings or progress).
    #[arg(short, long)]
    pub quiet: bool,
}

impl PrintArgs {
    /// True when the human-readable report is wanted.
    pub fn human(&self) -> bool {
        !self.json && !self.quiet
    }
}

/// `--case`: which machine to run.
#[derive(clap::Args, Debug, Clone)]
pub struct CaseArg {
    /// Which machine: as the file says, bare, with the damper, or with the added mass.
    #[arg(long, value_parser = ["as-specified", "none", "damper", "added-mass"], default_value = "as-specified")]
    pub case: String,
}

impl CaseArg {
    /// The parsed case (`meid::model::Case`'s `FromStr`).
    pub fn parse(&self) -> Result<Case> {
        Ok(self.case.parse()?)
    }
}
