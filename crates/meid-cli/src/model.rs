//! `meid model`: tools on model files (thin: the library writes the text).

use std::path::PathBuf;

use anyhow::Result;

use crate::args::SetArgs;

#[derive(clap::Args)]
pub struct ModelArgs {
    #[command(subcommand)]
    command: ModelCommand,
}

#[derive(clap::Subcommand)]
enum ModelCommand {
    /// Write the model with [structure.fem.machine] replaced by the general model it generates
    /// ([structure.fem.model]: nodes, shells, frames, springs, rigid links, points): the paper's
    /// machine as a file to edit. Run as it is, it gives the same matrices and results.
    Expand(ExpandArgs),
}

#[derive(clap::Args)]
struct ExpandArgs {
    /// Model file (TOML) with a [structure.fem.machine].
    model: PathBuf,
    /// Write the expanded model file here (default: standard output).
    #[arg(short, long, value_name = "FILE")]
    output: Option<PathBuf>,
    #[command(flatten)]
    set: SetArgs,
}

pub fn run(a: ModelArgs) -> Result<()> {
    match a.command {
        ModelCommand::Expand(e) => {
            let text = meid::model::expand::expand_file(&e.model, &e.set.set)?;
            match &e.output {
                Some(path) => meid::io::write_atomic(path, text.as_bytes())?,
                None => print!("{text}"),
            }
            Ok(())
        }
    }
}
