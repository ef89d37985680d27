//! `meid frf`: frequency response functions (H1, H2, Hv) with coherence from measured blows,
//! and `meid identify`: modes from FRFs (LSCF poles, stabilisation diagram, LSFD shapes).

use std::path::PathBuf;

use anyhow::Result;

use meid::identify::{identify, Criteria, Settings};
use meid::measure::frf::{estimate, frf_csv, frf_plots, frf_uff, read_frf_files, FrfSettings};
use meid::measure::identified::{modes_csv, modes_uff, stabilisation_plot, IdentifyReport};
use meid::measure::read_records_noting;

use crate::args::PrintArgs;
use crate::measure::ProcessingArgs;

#[derive(clap::Args)]
pub struct FrfArgs {
    /// Measured files recorded together (UFF 58/58b, CSV, Parquet): the force and the responses.
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// The force channel (default: the force named blow/hammer/slider, else the only force).
    #[arg(long, value_name = "CHANNEL")]
    force: Option<String>,
    /// A response channel (repeatable; default: every acceleration, velocity and displacement
    /// channel besides the force).
    #[arg(long = "response", value_name = "CHANNEL")]
    responses: Vec<String>,
    /// Estimator: h1 (noise on the responses), h2 (noise on the force), hv (both).
    #[arg(long, default_value = "h1", value_parser = ["h1", "h2", "hv"])]
    estimator: String,
    /// FRF type: accelerance (m/s²/N), mobility (m/s/N) or receptance (m/N).
    #[arg(long = "type", default_value = "accelerance", value_parser = ["accelerance", "mobility", "receptance"])]
    kind: String,
    /// Least coherence: lines below it are named in a warning.
    #[arg(long, default_value_t = 0.8, value_name = "GAMMA2")]
    min_coherence: f64,
    /// Write frf.json, frf.csv, frf.uff (UFF 58 type 4 and coherences, type 6) and the
    /// pictures frf_magnitude, frf_phase, frf_coherence (PNG, SVG) into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    processing: ProcessingArgs,
    #[command(flatten)]
    print: PrintArgs,
}

fn check_fraction(flag: &str, v: f64) -> Result<()> {
    if !(v > 0.0 && v <= 1.0) {
        anyhow::bail!("{flag}: expected a value in (0, 1], got {v}");
    }
    Ok(())
}

pub fn run_frf(a: FrfArgs) -> Result<()> {
    check_fraction("--min-coherence", a.min_coherence)?;
    let p = a.processing.processing(None)?;
    let mut records = Vec::new();
    let mut notes = Vec::new();
    for f in &a.files {
        let (r, passed) = read_records_noting(f)?;
        if r.is_empty() {
            anyhow::bail!(
                "{}: no time response (dataset 58, function type 1) in the file",
                f.display()
            );
        }
        records.extend(r);
        notes.extend(passed);
    }
    let s = FrfSettings {
        estimator: a.estimator.parse()?,
        kind: a.kind.parse()?,
        force: a.force.clone(),
        min_coherence: a.min_coherence,
        responses: a.responses.clone(),
    };
    let set = estimate(&records, &p, &s, "B")?;
    let out = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    if let Some(out) = out {
        meid::io::write_json(&out.path("frf.json"), &set)?;
        meid::io::write_atomic(&out.path("frf.csv"), frf_csv(&set).as_bytes())?;
        meid::io::write_atomic(&out.path("frf.uff"), &frf_uff(&set)?)?;
        frf_plots(out.staging(), &set)?;
        out.commit("frf")?;
    }
    if !a.print.quiet {
        for w in notes.iter().chain(&set.warnings) {
            crate::ui::warning(w);
        }
    }
    if a.print.json {
        crate::json::print(&set)?;
    } else if a.print.human() {
        println!(
            "{:?} {} ({}) against '{}': {} blow(s) found, {} averaged; record {:.6} s (Δf = {:.6} Hz), pre-trigger {:.6} s",
            set.estimator,
            set.kind.name(),
            set.unit,
            set.force,
            set.blows,
            set.blows_averaged,
            set.record_s,
            set.frequency_resolution_hz,
            set.pretrigger_s
        );
        println!(
            "windows: force {} × {}; responses {}; added decay σ_w = {} 1/s (removed by meid identify)",
            set.force_window,
            set.response_window,
            set.response_window,
            set.window_decay_per_s
        );
        for c in &set.channels {
            println!(
                "  {:<28} {:<14} lowest coherence {:.4} at {:.4} Hz",
                c.response,
                c.response_point.label(),
                c.min_coherence,
                c.min_coherence_hz
            );
        }
        for n in &set.notes {
            println!("  note: {n}");
        }
        if let Some(dir) = &a.output {
            println!("  wrote {}", dir.display());
        }
    }
    Ok(())
}

#[derive(clap::Args)]
pub struct IdentifyArgs {
    /// FRF files: UFF with datasets 58 of function type 4 (e.g. `meid frf -o DIR`'s frf.uff).
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Frequency band (Hz), LO..HI (default: every line above 0 Hz).
    #[arg(long, value_name = "LO..HI")]
    band: Option<String>,
    /// Highest model order of the stabilisation diagram.
    #[arg(long, default_value_t = 32, value_name = "N")]
    max_order: usize,
    /// Modes wanted: the N most stable (default: every mode the selection rule accepts).
    #[arg(long, value_name = "N")]
    modes: Option<usize>,
    /// Stability criteria: relative frequency change, relative damping change, least MAC.
    #[arg(long, default_value_t = 0.01, value_name = "REL")]
    stable_frequency: f64,
    #[arg(long, default_value_t = 0.05, value_name = "REL")]
    stable_damping: f64,
    #[arg(long, default_value_t = 0.98, value_name = "MAC")]
    stable_mac: f64,
    /// Coherence (datasets 58 type 6 beside the FRFs) below which the band's lines are named.
    #[arg(long, default_value_t = 0.8, value_name = "GAMMA2")]
    min_coherence: f64,
    /// Write identification.json, modes.csv, modes.uff (dataset 55 per mode) and the picture
    /// stabilisation (PNG, SVG) into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run_identify(a: IdentifyArgs) -> Result<()> {
    check_fraction("--min-coherence", a.min_coherence)?;
    check_fraction("--stable-mac", a.stable_mac)?;
    for (flag, v) in [
        ("--stable-frequency", a.stable_frequency),
        ("--stable-damping", a.stable_damping),
    ] {
        if !(v > 0.0 && v < 1.0) {
            anyhow::bail!("{flag}: expected a relative change in (0, 1), got {v}");
        }
    }
    if a.modes == Some(0) {
        anyhow::bail!("--modes: expected 1 or more");
    }
    let band = a
        .band
        .as_deref()
        .map(|b| {
            meid::analysis::study::parse_range(b).map_err(|e| anyhow::anyhow!("--band {b}: {e}"))
        })
        .transpose()?;
    let files = read_frf_files(&a.files, band, a.min_coherence)?;
    let mut warnings = files.warnings.clone();
    if let Some(n) = a.modes {
        if n > files.data.outputs {
            warnings.push(format!(
                "{n} modes asked from {} measured point(s) ({}): at most {} independent shapes; measure more points",
                files.data.outputs,
                a.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", "),
                files.data.outputs
            ));
        }
    }
    let s = Settings {
        band_hz: band,
        max_order: a.max_order,
        criteria: Criteria {
            frequency: a.stable_frequency,
            damping: a.stable_damping,
            mac: a.stable_mac,
        },
        modes: a.modes,
    };
    let mut id = identify(&files.data, &s)?;
    // The library's own warning about points is the CLI's above, with the files named.
    id.warnings.retain(|w| !w.contains("measured point(s)"));
    warnings.append(&mut id.warnings);
    id.warnings = warnings;
    let points: Vec<meid::record::PointRef> = files.outputs.iter().map(|o| o.0.clone()).collect();
    let out = IdentifyReport {
        files: a.files.iter().map(|f| f.display().to_string()).collect(),
        kind: files.data.kind,
        points: points.iter().map(|p| p.label()).collect(),
        references: files.inputs.iter().map(|p| p.label()).collect(),
        identification: id,
    };
    let id = &out.identification;
    if let Some(dir) = a.output.as_deref() {
        let set = crate::outputs::begin(dir)?;
        meid::io::write_json(&set.path("identification.json"), &out)?;
        meid::io::write_atomic(&set.path("modes.csv"), modes_csv(id, &points).as_bytes())?;
        meid::io::write_atomic(&set.path("modes.uff"), &modes_uff(id, &points)?)?;
        stabilisation_plot(set.staging(), id)?;
        set.commit("identify")?;
    }
    if !a.print.quiet {
        for w in &id.warnings {
            crate::ui::warning(w);
        }
    }
    if a.print.json {
        crate::json::print(&out)?;
    } else if a.print.human() {
        print_identification(&out);
        if let Some(dir) = &a.output {
            println!("  wrote {}", dir.display());
        }
    }
    Ok(())
}

fn print_identification(out: &IdentifyReport) {
    let id = &out.identification;
    println!(
        "{} FRF(s): {} point(s) × {} reference(s), {}, {} lines in {:.4}..{:.4} Hz; orders 1..{}; window decay σ_w = {} 1/s removed",
        out.points.len() * out.references.len(),
        out.points.len(),
        out.references.len(),
        out.kind.name(),
        id.lines,
        id.band_hz.0,
        id.band_hz.1,
        id.max_order,
        id.window_decay_per_s
    );
    println!(
        "  stable: frequency {} %, damping {} %, MAC ≥ {}; a mode is stable at ≥ {} orders",
        id.criteria.frequency * 100.0,
        id.criteria.damping * 100.0,
        id.criteria.mac,
        id.min_stable_orders
    );
    println!(
        "  {:>4} {:>12} {:>10} {:>10} {:>9} {:>7} {:>7}  shape",
        "mode", "f (Hz)", "±", "ζ", "±", "orders", "MPC"
    );
    for (r, m) in id.modes.iter().enumerate() {
        let shape: Vec<String> = m.shape.iter().map(|v| format!("{v:+.3}")).collect();
        println!(
            "  {:>4} {:>12.5} {:>10.2e} {:>10.5} {:>9.1e} {:>7} {:>7.4}  {}",
            r + 1,
            m.frequency_hz,
            m.frequency_std_hz,
            m.damping_ratio,
            m.damping_ratio_std,
            m.stable_orders,
            m.mpc,
            shape.join(" ")
        );
    }
    for n in &id.notes {
        println!("  note: {n}");
    }
}
