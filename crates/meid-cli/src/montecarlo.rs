//! `meid montecarlo`: uncertain inputs, seeded and reproducible; statistics and a histogram.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use meid::analysis::montecarlo::{
    histogram_outline, read_samples_exact_csv, samples_exact_csv, MonteCarlo, Uncertain, METRICS,
};
use meid::plot::{self, AreaPlot, Marker, Series};

use crate::args::{MethodArg, PrintArgs, SetArgs};
use crate::load;

#[derive(clap::Args)]
pub struct MonteCarloArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Uncertain input PATH=DIST(a,b): normal(mean,std), lognormal(mean,cov), uniform(low,high)
    /// (repeatable), e.g. contact.slider_bed.stiffness=lognormal(4.3e7,0.2).
    #[arg(long = "vary", value_name = "PATH=DIST", required = true)]
    vary: Vec<String>,
    /// Number of samples.
    #[arg(long, value_name = "N", default_value_t = 200)]
    samples: usize,
    /// Seed of the generator (same seed, same result for any thread count).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Metric of the histogram picture.
    #[arg(long, default_value = "energy_ratio", value_parser = METRICS)]
    metric: String,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    /// Write samples.csv, samples.parquet, stats.json and the histogram into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    method: MethodArg,
    /// Compute only shard K of N (1 <= K <= N: samples ⌊(K−1)S/N⌋..⌊KS/N⌋) into
    /// DIR/shard.csv (needs -o DIR); `meid merge` puts the shards together.
    #[arg(long, value_name = "K/N")]
    shard: Option<crate::shard::Shard>,
    /// Simulated time per sample (s).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    #[command(flatten)]
    set: SetArgs,
    #[command(flatten)]
    print: PrintArgs,
}

fn prepare(a: &MonteCarloArgs) -> Result<MonteCarlo> {
    let model = load(
        &a.model,
        &a.set.set,
        a.method.method.as_deref(),
        a.duration,
        None,
    )?;
    crate::warn_model(&model, &a.print);
    let inputs = a
        .vary
        .iter()
        .map(|v| Uncertain::parse(v))
        .collect::<meid::Result<Vec<_>>>()?;
    Ok(MonteCarlo {
        model,
        inputs,
        samples: a.samples,
        seed: a.seed,
    })
}

fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        pool = pool.num_threads(t);
    }
    pool.build().context("thread pool")
}

pub fn run(a: MonteCarloArgs) -> Result<()> {
    let study = prepare(&a)?;
    let pool = pool(a.threads)?;
    if let Some(shard) = a.shard {
        let Some(dir) = &a.output else {
            bail!(
                "--shard needs -o DIR: the shard's samples go to DIR/shard.csv (then `meid merge`)"
            );
        };
        let range = shard.range(study.samples);
        study.check(range.len())?;
        let bar = crate::progress::bar(a.print.quiet || a.print.json, range.len(), "samples");
        let progress = |done: usize, _total: usize| bar.set_position(done as u64);
        let samples = pool.install(|| study.run_range(range.clone(), &progress));
        bar.finish_and_clear();
        let rows = samples_exact_csv(&samples, study.inputs.len())?;
        let files = crate::shard::write(
            dir,
            "montecarlo",
            shard,
            range.clone(),
            study.samples,
            &study.fingerprint(),
            &rows,
        )?;
        if a.print.json {
            crate::json::print(&serde_json::json!({
                "shard": shard.k, "shards": shard.n, "first": range.start,
                "end": range.end, "total": study.samples, "files": files,
            }))?;
        } else if a.print.human() {
            println!(
                "meid montecarlo — shard {}/{}: samples {}..{} of {} ({} failed)",
                shard.k,
                shard.n,
                range.start,
                range.end,
                study.samples,
                samples.iter().filter(|s| s.error.is_some()).count()
            );
            for f in files {
                println!("  wrote {}", f.display());
            }
        }
        return Ok(());
    }
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let bar = crate::progress::bar(a.print.quiet || a.print.json, study.samples, "samples");
    let progress = |done: usize, _total: usize| bar.set_position(done as u64);
    let r = pool.install(|| study.run_with_progress(&progress));
    bar.finish_and_clear();
    let r = r.context("Monte Carlo failed")?;
    output(&a, &study, &r, set)
}

/// `meid merge` of Monte Carlo shards: every sample of the study from the shards (checked to
/// be this study's and to cover it once), the statistics and files as the unsharded run.
pub fn merge(a: MonteCarloArgs, shards: &[crate::shard::ShardFiles]) -> Result<()> {
    let study = prepare(&a)?;
    study.check(study.samples)?;
    crate::shard::check_cover(shards, &study.fingerprint(), study.samples)?;
    let mut samples = Vec::with_capacity(study.samples);
    for s in shards {
        let file = s.dir.join("shard.csv");
        let rows =
            read_samples_exact_csv(&s.rows, study.inputs.len(), &file.display().to_string())?;
        for r in &rows {
            if r.index < s.first || r.index >= s.end {
                bail!(
                    "{}: sample {} is outside the shard's range {}..{}",
                    file.display(),
                    r.index,
                    s.first,
                    s.end
                );
            }
        }
        if rows.len() != s.end - s.first {
            bail!(
                "{}: {} samples, the shard's range {}..{} has {}",
                file.display(),
                rows.len(),
                s.first,
                s.end,
                s.end - s.first
            );
        }
        samples.extend(rows);
    }
    samples.sort_by_key(|s| s.index);
    let r = study.finish(samples).context("Monte Carlo failed")?;
    let Some(dir) = &a.output else {
        bail!("meid merge needs -o DIR");
    };
    let set = crate::outputs::begin(dir)?;
    output(&a, &study, &r, Some(set))
}

/// Writes and prints a finished study as `meid montecarlo` does (shared with `meid merge`).
fn output(
    a: &MonteCarloArgs,
    study: &MonteCarlo,
    r: &meid::analysis::montecarlo::MonteCarloResult,
    set: Option<meid::io::OutputSet>,
) -> Result<()> {
    let stats = serde_json::json!({
        "seed": r.seed,
        "samples": r.samples.len(),
        "failed": r.failed,
        "inputs": r.inputs,
        "input_stats": r.input_stats,
        "metric_stats": r.metric_stats,
        "note": "mean, std and the percentiles are estimates from the `count` samples of each quantity; *_ci95 are their 95 % confidence intervals (mean: Student t; percentiles: order statistics, distribution-free; null where the samples are too few)",
    });
    if let Some(set) = set {
        let dir = set.staging();
        meid::io::write_atomic(&dir.join("samples.csv"), &r.samples_csv()?)?;
        // samples.csv's rows with types, units and exact values (docs/reference/outputs.md, "Parquet").
        crate::outputs::write_parquet_table(&dir.join("samples.parquet"), &study.table(r))?;
        meid::io::write_json(&dir.join("stats.json"), &crate::json::object(&stats)?)?;
        let values = r.metric(&a.metric)?;
        let bins = ((values.len() as f64).sqrt().ceil() as usize).clamp(5, 50);
        let (x, y) = histogram_outline(&values, bins);
        if !x.is_empty() {
            let x_label = meid::analysis::sweep::metric_label(&a.metric);
            // The mean and the 95th percentile of the metric, as `stats.json` gives them.
            let fmt = meid::plot::axis::fmt_tick;
            let markers = r
                .metric_stats
                .iter()
                .find(|s| s.name == a.metric)
                .map(|s| {
                    vec![
                        Marker {
                            x: s.mean,
                            label: format!("mean {}", fmt(&s.mean)),
                        },
                        Marker {
                            x: s.p95,
                            label: format!("P95 {}", fmt(&s.p95)),
                        },
                    ]
                })
                .unwrap_or_default();
            plot::area_plot(
                dir.join(format!("histogram-{}", a.metric)),
                &AreaPlot {
                    title: format!(
                        "{} over {} samples (seed {})",
                        x_label
                            .rsplit_once(" (")
                            .map_or(x_label.as_str(), |(w, _)| w),
                        values.len(),
                        a.seed
                    ),
                    x_label: x_label.clone(),
                    y_label: "samples per bin (1)".into(),
                    stacked: false,
                    series: vec![Series {
                        label: String::new(),
                        x,
                        y,
                        ..Default::default()
                    }],
                    markers,
                },
            )?;
        }
        set.commit("montecarlo")?;
    }
    if a.print.json {
        crate::json::print(&stats)?;
    } else if a.print.human() {
        println!(
            "meid montecarlo — {} samples, seed {}, {} failed; estimates from the samples, 95 % confidence intervals below",
            r.samples.len(),
            r.seed,
            r.failed
        );
        println!(
            "  {:<34} {:>6} {:>12} {:>12} {:>12} {:>12} {:>12}",
            "quantity", "n", "mean", "std", "P5", "P50", "P95"
        );
        for s in r.input_stats.iter().chain(&r.metric_stats) {
            println!(
                "  {:<34} {:>6} {:>12.5e} {:>12.5e} {:>12.5e} {:>12.5e} {:>12.5e}",
                s.name, s.count, s.mean, s.std, s.p5, s.p50, s.p95
            );
        }
        let ci = |(a, b): (f64, f64)| {
            if a.is_finite() && b.is_finite() {
                format!("[{a:.5e}, {b:.5e}]")
            } else if b.is_finite() {
                format!("[too few samples, {b:.5e}]")
            } else if a.is_finite() {
                format!("[{a:.5e}, too few samples]")
            } else {
                "too few samples".to_string()
            }
        };
        let side =
            |(a, b): (Option<f64>, Option<f64>)| (a.unwrap_or(f64::NAN), b.unwrap_or(f64::NAN));
        println!("  95 % confidence intervals (mean: Student t; percentiles: order statistics):");
        for s in r.input_stats.iter().chain(&r.metric_stats) {
            println!(
                "  {:<34} mean {}  P5 {}  P50 {}  P95 {}",
                s.name,
                ci(s.mean_ci95),
                ci(side(s.p5_ci95)),
                ci(side(s.p50_ci95)),
                ci(side(s.p95_ci95))
            );
        }
    }
    Ok(())
}
