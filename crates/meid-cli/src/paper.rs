//! `meid paper`: every study behind Figs. 2-19 of "Application of Momentum Exchange Impact
//! Dampers to Forging Machine", the table of the paper's numbers beside meid's and the deviation
//! study, as one self-contained HTML page (thin: the library's `report::paper` does the work).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use meid::report::paper::{self, Resolution};

use crate::args::PrintArgs;

#[derive(clap::Args)]
pub struct PaperArgs {
    /// Output directory: index.html, every figure as PNG/SVG with its data (CSV), paper.json.
    #[arg(short, long, value_name = "DIR", default_value = "meid-paper")]
    output: PathBuf,
    /// Points per axis of the energy maps (Figs. 3, 12, 16).
    #[arg(long, value_name = "N", default_value_t = Resolution::default().map_points)]
    map_points: usize,
    /// Points of each family curve (Figs. 4, 5, 9, 17).
    #[arg(long, value_name = "N", default_value_t = Resolution::default().curve_points)]
    curve_points: usize,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    threads: Option<usize>,
    // --json prints paper.json's content; -q prints nothing but errors.
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: PaperArgs) -> Result<()> {
    if a.map_points < 3 || a.curve_points < 3 {
        bail!(
            "--map-points and --curve-points must be at least 3 (got {} and {})",
            a.map_points,
            a.curve_points
        );
    }
    let res = Resolution {
        map_points: a.map_points,
        curve_points: a.curve_points,
        ..Resolution::default()
    };
    let mut pool = rayon::ThreadPoolBuilder::new();
    if let Some(n) = a.threads {
        if n == 0 {
            bail!("--threads must be >= 1");
        }
        pool = pool.num_threads(n);
    }
    let pool = pool.build().context("cannot start the worker threads")?;
    let set = crate::outputs::begin(&a.output)?;
    let t0 = std::time::Instant::now();
    let report = pool.install(|| paper::run(set.staging(), &res))?;
    meid::report::html::verify_page_file(&set.staging().join("index.html"))?;
    set.commit("paper")?;
    let elapsed = t0.elapsed().as_secs_f64();
    if a.print.json {
        crate::json::print(&report)?;
    } else if a.print.human() {
        println!(
            "meid paper — {} figures, {} table rows, {} deviation runs in {elapsed:.1} s",
            report.figures.len(),
            report.table.len(),
            report.deviations.len()
        );
        print!("{}", report.table_text());
        println!("{}", paper::deviation_summary(&report));
        println!("wrote {}", a.output.join("index.html").display());
    }
    Ok(())
}
