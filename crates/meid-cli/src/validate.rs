//! `meid validate`: the simulation beside measured records (thin: the library compares).

use std::path::PathBuf;

use anyhow::Result;

use meid::measure::mapping::parse_channel_flags;
use meid::measure::validate::{read_measured_noting, validate};

use crate::args::{PrintArgs, RunArgs};
use crate::measure::ProcessingArgs;

#[derive(clap::Args)]
pub struct ValidateArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Measured file (UFF or CSV), optionally with the case it measured: none=FILE (the bare
    /// machine), damper=FILE, added-mass=FILE; a plain FILE is the model as specified
    /// (repeatable; several files of one case are read together).
    #[arg(long = "measured", value_name = "[CASE=]FILE", required = true)]
    measured: Vec<String>,
    /// Map a measured channel to meid's: NAME=B (bed acceleration at the measurement point),
    /// NAME=floor (force to the floor), NAME=blow (slider-bed force). Repeatable; over the
    /// model's [measurement] channels.
    #[arg(long = "channel", value_name = "NAME=TARGET")]
    channel: Vec<String>,
    /// Write validation.json and the overlaid histories and spectra (<case>_<channel>_history
    /// and _spectrum, .png and .svg) into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    processing: ProcessingArgs,
    #[command(flatten)]
    run: RunArgs,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: ValidateArgs) -> Result<()> {
    let model = a.run.load(&a.model, None)?;
    crate::warn_model(&model, &a.print);
    let p = a.processing.processing(model.spec.measurement.as_ref())?;
    let flags = parse_channel_flags(&a.channel, &model.spec.points.measurement)?;
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let (cases, passed_over) = read_measured_noting(&a.measured, None)?;
    if !a.print.quiet {
        for n in &passed_over {
            crate::ui::warning(n);
        }
    }
    let v = validate(&model, &cases, &p, &flags)?;
    if let Some(set) = set {
        meid::io::write_json(&set.path("validation.json"), &crate::json::object(&v)?)?;
        v.plots(set.staging())?;
        set.commit("validate")?;
    }
    if a.print.json {
        crate::json::print(&v)?;
    } else if a.print.human() {
        println!(
            "{} — {}",
            crate::ui::bold("meid validate"),
            model.spec.name.as_deref().unwrap_or("model")
        );
        print!("{}", v.to_text());
        if let Some(dir) = &a.output {
            println!("wrote {}", dir.display());
        }
    }
    Ok(())
}
