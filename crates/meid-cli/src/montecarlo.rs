//! `meid montecarlo`: uncertain inputs, seeded and reproducible; statistics and a histogram.

use std::path::PathBuf;

use anyhow::{Context, Result};

use meid::analysis::montecarlo::{histogram_outline, MonteCarlo, Uncertain, METRICS};
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
    /// Write samples.csv, stats.json and the histogram into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    method: MethodArg,
    /// Simulated time per sample (s).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    #[command(flatten)]
    set: SetArgs,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: MonteCarloArgs) -> Result<()> {
    let model = load(
        &a.model,
        &a.set.set,
        a.method.method.as_deref(),
        a.duration,
        None,
    )?;
    let inputs = a
        .vary
        .iter()
        .map(|v| Uncertain::parse(v))
        .collect::<meid::Result<Vec<_>>>()?;
    let study = MonteCarlo {
        model,
        inputs,
        samples: a.samples,
        seed: a.seed,
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(t) = a.threads {
        pool = pool.num_threads(t);
    }
    let pool = pool.build().context("thread pool")?;
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let r = pool.install(|| study.run()).context("Monte Carlo failed")?;
    let stats = serde_json::json!({
        "seed": r.seed,
        "samples": r.samples.len(),
        "failed": r.failed,
        "inputs": r.inputs,
        "input_stats": r.input_stats,
        "metric_stats": r.metric_stats,
    });
    if let Some(set) = set {
        let dir = set.staging();
        meid::io::write_atomic(&dir.join("samples.csv"), &r.samples_csv()?)?;
        meid::io::write_json(&dir.join("stats.json"), &stats)?;
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
        println!("{}", serde_json::to_string_pretty(&stats)?);
    } else if a.print.human() {
        println!(
            "meid montecarlo — {} samples, seed {}, {} failed",
            r.samples.len(),
            r.seed,
            r.failed
        );
        println!(
            "  {:<34} {:>12} {:>12} {:>12} {:>12} {:>12}",
            "quantity", "mean", "std", "P5", "P50", "P95"
        );
        for s in r.input_stats.iter().chain(&r.metric_stats) {
            println!(
                "  {:<34} {:>12.5e} {:>12.5e} {:>12.5e} {:>12.5e} {:>12.5e}",
                s.name, s.mean, s.std, s.p5, s.p50, s.p95
            );
        }
    }
    Ok(())
}
