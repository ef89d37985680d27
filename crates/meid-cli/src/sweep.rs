//! `meid sweep` (being built).

use std::path::PathBuf;

use anyhow::{bail, Result};

#[derive(clap::Args)]
pub struct SweepArgs {
    /// Model file (TOML).
    model: PathBuf,
}

pub fn run(a: SweepArgs) -> Result<()> {
    bail!("`meid sweep` is not available yet ({})", a.model.display())
}
