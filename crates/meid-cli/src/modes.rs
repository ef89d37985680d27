//! `meid modes` (being built).

use std::path::PathBuf;

use anyhow::{bail, Result};

#[derive(clap::Args)]
pub struct ModesArgs {
    /// Model file (TOML).
    model: PathBuf,
}

pub fn run(a: ModesArgs) -> Result<()> {
    bail!("`meid modes` is not available yet ({})", a.model.display())
}
