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
    /// Draw the model's FE mesh with its points marked by role: the strike (an arrow along the
    /// blow), the dampers joined to their anchors, the measurement points and the floor
    /// (supports, springs to ground). Paper-form models and general machines.
    Sketch(SketchArgs),
}

#[derive(clap::Args)]
struct SketchArgs {
    /// Model file (TOML) with a [structure.fem] structure.
    model: PathBuf,
    /// Write DIR/model_sketch.png and DIR/model_sketch.svg.
    #[arg(short, long, value_name = "DIR")]
    output: PathBuf,
    #[command(flatten)]
    set: SetArgs,
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
        ModelCommand::Sketch(k) => {
            std::fs::create_dir_all(&k.output).map_err(|e| {
                anyhow::anyhow!("cannot create the directory {}: {e}", k.output.display())
            })?;
            let stem = k.output.join("model_sketch");
            match meid::report::sketch::write_model_sketch(&k.model, &k.set.set, &stem)? {
                Some((files, _)) => {
                    println!("wrote {} and {}", files.png.display(), files.svg.display())
                }
                None => anyhow::bail!(
                    "{}: the structure is lumped or tabulated: there is no FE mesh to sketch",
                    k.model.display()
                ),
            }
            Ok(())
        }
    }
}
