//! `meid optimize` (being built).

use std::path::PathBuf;

use anyhow::{bail, Result};

#[derive(clap::Args)]
pub struct OptimizeArgs {
    /// Model file (TOML).
    model: PathBuf,
}

pub fn run(a: OptimizeArgs) -> Result<()> {
    bail!(
        "`meid optimize` is not available yet ({})",
        a.model.display()
    )
}
