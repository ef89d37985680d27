//! `meid compare` (being built).

use std::path::PathBuf;

use anyhow::{bail, Result};

#[derive(clap::Args)]
pub struct CompareArgs {
    /// Model file (TOML).
    model: PathBuf,
}

pub fn run(a: CompareArgs) -> Result<()> {
    bail!(
        "`meid compare` is not available yet ({})",
        a.model.display()
    )
}
