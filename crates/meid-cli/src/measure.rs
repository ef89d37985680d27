//! `meid measure`: read measured records (UFF 58/58b, CSV), process them as a test lab does
//! and print one line per channel.

use std::path::PathBuf;

use anyhow::Result;

use meid::measure::mapping::{parse_window, MeasurementSpec};
use meid::measure::process::{process_all, Level, Processing};
use meid::measure::{read_records_noting, report};

use crate::args::PrintArgs;

/// Processing flags shared by `measure` and `validate` (they override `[measurement]`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ProcessingArgs {
    /// Trigger level as a fraction of the trigger channel's largest deviation from its median,
    /// in (0, 1] (default 0.1).
    #[arg(long, value_name = "FRACTION")]
    pub trigger_level: Option<f64>,
    /// Time kept before each trigger (s, default 0.01).
    #[arg(long, value_name = "S")]
    pub pretrigger: Option<f64>,
    /// Length of each blow's record (s; default the shortest interval between blows); at least
    /// 16 samples, and no longer than fits after a blow.
    #[arg(long, value_name = "S")]
    pub record: Option<f64>,
    /// Time after a trigger during which no other is taken (s, default 0.25).
    #[arg(long, value_name = "S")]
    pub holdoff: Option<f64>,
    /// Window on the responses: rectangular (default), hann or exponential (needs --tau).
    #[arg(long, value_parser = ["rectangular", "hann", "exponential"])]
    pub window: Option<String>,
    /// Time constant of the exponential window (s); it adds 1/(ωτ) to a mode's damping ratio.
    #[arg(long, value_name = "S")]
    pub tau: Option<f64>,
    /// Force window on the blow's excitation (the force named blow/hammer/slider, or mapped to
    /// blow; else the --trigger channel when it is a force); other channels are responses.
    #[arg(long)]
    pub force_window: bool,
    /// The channel blows are detected on (default: the blow force by name, else the bed
    /// acceleration at B, else the first force, else the first acceleration).
    #[arg(long, value_name = "NAME")]
    pub trigger: Option<String>,
}

impl ProcessingArgs {
    /// The flags as a `[measurement]` section to lay over a model's
    /// (`MeasurementSpec::over`; `--trigger` is not part of it).
    pub fn as_section(&self) -> MeasurementSpec {
        MeasurementSpec {
            trigger_level: self.trigger_level,
            pretrigger_s: self.pretrigger,
            record_s: self.record,
            holdoff_s: self.holdoff,
            window: self.window.clone(),
            tau_s: self.tau,
            force_window: self.force_window.then_some(true),
            ..MeasurementSpec::default()
        }
    }

    /// The section's settings with these flags over them.
    pub fn processing(&self, section: Option<&MeasurementSpec>) -> Result<Processing> {
        let s = section.cloned().unwrap_or_default();
        let mut p = s.processing()?;
        if let Some(l) = self.trigger_level {
            if !(l > 0.0 && l <= 1.0) {
                anyhow::bail!(
                    "--trigger-level: a fraction of the trigger channel's peak in (0, 1], got {l}"
                );
            }
            p.level = Level::FractionOfPeak(l);
        }
        if let Some(v) = self.pretrigger {
            p.pretrigger_s = v;
        }
        if let Some(v) = self.record {
            p.record_s = Some(v);
        }
        if let Some(v) = self.holdoff {
            p.holdoff_s = v;
        }
        if self.window.is_some() || self.tau.is_some() {
            let name =
                self.window
                    .as_deref()
                    .or(s.window.as_deref())
                    .unwrap_or(if self.tau.is_some() {
                        "exponential"
                    } else {
                        "rectangular"
                    });
            p.window = parse_window(name, self.tau.or(s.tau_s))?;
        }
        if self.force_window {
            p.force_window = true;
        }
        Ok(p)
    }
}

#[derive(clap::Args)]
pub struct MeasureArgs {
    /// Measured files: UFF (.uff, .unv; dataset 58 ASCII or binary 58b) or CSV (.csv).
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Write measure.json, bands.csv and per channel <name>_spectrum.csv/.png/.svg and
    /// <name>_average.csv/.png/.svg into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// A model whose [measurement] section sets the processing.
    #[arg(long, value_name = "MODEL.toml")]
    model: Option<PathBuf>,
    #[command(flatten)]
    processing: ProcessingArgs,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: MeasureArgs) -> Result<()> {
    let (section, point) = match &a.model {
        Some(m) => {
            let spec = meid::model::Model::from_file(m, &[])?.spec;
            (spec.measurement, spec.points.measurement)
        }
        None => (None, "B".to_string()),
    };
    let p = a.processing.processing(section.as_ref())?;
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let mut records = Vec::new();
    let mut notes = Vec::new();
    for f in &a.files {
        let (r, passed) = read_records_noting(f)?;
        if r.is_empty() {
            anyhow::bail!(
                "{}: no time response (dataset 58, function type 1, of an acceleration, velocity, displacement or force) in the file{}",
                f.display(),
                if passed.is_empty() {
                    String::new()
                } else {
                    format!("; passed over:\n  {}", passed.join("\n  "))
                }
            );
        }
        records.extend(r);
        notes.extend(passed);
    }
    let channels = process_all(&records, &p, a.processing.trigger.as_deref(), &point)?;
    let summaries: Vec<_> = channels.iter().map(|c| &c.summary).collect();
    if !a.print.quiet {
        for n in &notes {
            crate::ui::warning(n);
        }
        for w in report::warnings(&channels) {
            crate::ui::warning(w);
        }
    }
    if let Some(set) = set {
        meid::io::write_json(
            &set.path("measure.json"),
            &crate::json::object(&serde_json::json!({ "records": summaries }))?,
        )?;
        meid::io::write_atomic(&set.path("bands.csv"), &report::bands_csv(&channels)?)?;
        let mut taken = Vec::new();
        for c in &channels {
            let stem = report::file_stem(&c.summary.name, &mut taken);
            meid::io::write_atomic(
                &set.path(&format!("{stem}_spectrum.csv")),
                &report::spectrum_csv(c)?,
            )?;
            meid::io::write_atomic(
                &set.path(&format!("{stem}_average.csv")),
                &report::average_csv(c),
            )?;
            report::plots(set.staging(), &stem, c)?;
        }
        set.commit("measure")?;
    }
    if a.print.json {
        crate::json::print(&serde_json::json!({ "records": summaries }))?;
    } else if a.print.human() {
        let names: Vec<String> = a.files.iter().map(|f| f.display().to_string()).collect();
        print!("{}", report::summary_text(&names, &channels));
        if let Some(dir) = &a.output {
            println!("  wrote {}", dir.display());
        }
    }
    Ok(())
}
