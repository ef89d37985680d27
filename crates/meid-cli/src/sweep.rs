//! `meid sweep`: vary quantities over lists or ranges, record every summary metric, draw the
//! energy map (2 ranges: paper Figs. 3, 12, 16) or families of curves (1 quantity, optionally
//! times a listed family parameter: Figs. 4, 5, 9, 17).

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use meid::analysis::sweep::{
    case_label, case_name, Quantity, Spacing, Sweep, SweepResult, Vary, DERIVED, METRICS,
};
use meid::model::Case;
use meid::plot::{heat_map, line_plot, HeatMap, LinePlot, Series};

use crate::args::{PrintArgs, SetArgs};
use crate::load;

#[derive(clap::Args)]
pub struct SweepArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// NAME=LIST, NAME=A..B:N or NAME=A..B:N:log; NAME is ws/w_ref, wd/w_ref, wd/ws, md/mb or a
    /// model field path (repeatable; the grid is their Cartesian product, last fastest).
    #[arg(long = "vary", value_name = "SPEC", required = true)]
    pub(crate) vary: Vec<String>,
    /// Output directory (sweep.csv, sweep.parquet, sweep.json, pictures, manifest.json, and the journal
    /// sweep.partial.csv). Without it, nothing is written: the summary and the table of every
    /// point (sweep.csv's content) go to stdout.
    #[arg(short, long, value_name = "DIR")]
    pub(crate) output: Option<PathBuf>,
    /// Reuse the finished points of an interrupted sweep (DIR/sweep.partial.csv).
    #[arg(long, conflicts_with = "force")]
    pub(crate) resume: bool,
    /// Discard the journal of an earlier sweep in DIR and start over.
    #[arg(long)]
    pub(crate) force: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub(crate) threads: Option<usize>,
    #[command(flatten)]
    pub(crate) set: SetArgs,
    /// Metric drawn in the pictures and summarised (a sweep.csv column).
    #[arg(long, value_name = "NAME", default_value = "energy_ratio")]
    pub(crate) metric: String,
    /// Run every point for S seconds instead of stopping at the end of the collision.
    #[arg(long, value_name = "S")]
    pub(crate) duration: Option<f64>,
    /// General machine: judge every point on its steady blow at this stroke rate (blows per
    /// minute; default: the file's [production] rate_bpm, else the first blow), with the
    /// column dampers_return.
    #[arg(long, value_name = "R")]
    pub(crate) rate_bpm: Option<f64>,
    /// Compare cases in one run: every point is simulated once per case (none, damper,
    /// added-mass, as-specified) and the metric columns become METRIC:CASE; the pictures draw
    /// one curve (or map) per case.
    #[arg(long, value_name = "LIST", value_delimiter = ',')]
    pub(crate) cases: Vec<String>,
    /// Compute only shard K of N (1 <= K <= N: grid points ⌊(K−1)T/N⌋..⌊KT/N⌋) into
    /// DIR/shard.csv (needs -o DIR); `meid merge` puts the shards together.
    #[arg(long, value_name = "K/N")]
    pub(crate) shard: Option<crate::shard::Shard>,
    /// Bed mass m_b (kg) for md/mb (default: the lumped mass at the bed contact point, the
    /// FE machine's bed plate, or a general FE model's elements labelled part = "bed"; see
    /// docs/explanations/studies.md).
    #[arg(long, value_name = "KG")]
    pub(crate) bed_mass: Option<f64>,
    // --json prints the result (sweep.json's content); -q: no progress bar or summary either.
    #[command(flatten)]
    pub(crate) print: PrintArgs,
}

/// The sweep of the arguments (model loaded, grid checked), as `meid sweep` and `meid merge`
/// build it.
fn prepare(a: &SweepArgs) -> Result<Sweep> {
    if !METRICS.contains(&a.metric.as_str()) && !DERIVED.contains(&a.metric.as_str()) {
        bail!(
            "unknown --metric `{}`; valid: {}",
            a.metric,
            METRICS.join(", ")
        );
    }
    let model = load(&a.model, &a.set.set, None, a.duration, None)?;
    crate::warn_model(&model, &a.print);
    let vary = a
        .vary
        .iter()
        .map(|s| Vary::parse(s))
        .collect::<meid::Result<Vec<_>>>()?;
    if let Some(m) = a.bed_mass {
        if !(m.is_finite() && m > 0.0) {
            bail!("--bed-mass must be > 0 kg (got {m})");
        }
    }
    let cases = a
        .cases
        .iter()
        .map(|c| c.trim().parse::<Case>())
        .collect::<meid::Result<Vec<_>>>()?;
    let mut sweep = Sweep::with_bed_mass(model, vary.clone(), a.bed_mass)?;
    if !cases.is_empty() {
        sweep = sweep.with_cases(cases)?;
    }
    if a.duration.is_some() {
        sweep.options.stop_at_collision_end = false;
    }
    Ok(sweep)
}

pub(crate) fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            bail!("--threads must be >= 1");
        }
        b = b.num_threads(n);
    }
    b.build().context("cannot start the worker threads")
}

/// `meid sweep` of the paper's machine (a general machine's: [`crate::sweep_general::run`],
/// chosen by `main`).
pub fn run(a: SweepArgs) -> Result<()> {
    if a.rate_bpm.is_some() {
        anyhow::bail!("--rate-bpm: the paper machine's sweep is of the first blow; its damper's return at a stroke rate is `meid blows MODEL --rate-bpm R --vary …`");
    }
    let sweep = prepare(&a)?;
    let total = sweep.len();
    if let Some(shard) = a.shard {
        let Some(dir) = &a.output else {
            bail!("--shard needs -o DIR: the shard's rows go to DIR/shard.csv (then `meid merge`)");
        };
        if a.resume || a.force {
            bail!("--shard runs its slice afresh: drop --resume/--force");
        }
        let range = shard.range(total);
        let bar = crate::progress::bar(a.print.quiet || a.print.json, range.len(), "points");
        let progress = |done: usize, _total: usize| bar.set_position(done as u64);
        let points = pool(a.threads)?.install(|| sweep.run_range(range.clone(), &progress))?;
        bar.finish_and_clear();
        let mut rows = sweep.columns().join(",");
        rows.push('\n');
        for p in &points {
            rows.push_str(&sweep.row(p));
        }
        let files = crate::shard::write(
            dir,
            "sweep",
            shard,
            range.clone(),
            total,
            &sweep.fingerprint_text(),
            rows.as_bytes(),
        )?;
        if a.print.json {
            crate::json::print(&serde_json::json!({
                "shard": shard.k, "shards": shard.n, "first": range.start,
                "end": range.end, "total": total, "files": files,
            }))?;
        } else if a.print.human() {
            println!(
                "meid sweep — shard {}/{}: points {}..{} of {total} ({} failed)",
                shard.k,
                shard.n,
                range.start,
                range.end,
                points.iter().filter(|p| p.error.is_some()).count()
            );
            for f in files {
                println!("  wrote {}", f.display());
            }
        }
        return Ok(());
    }
    let bar = crate::progress::bar(a.print.quiet, total, "points");
    let progress = |done: usize, _total: usize| bar.set_position(done as u64);
    if a.resume && a.output.is_none() {
        bail!("--resume needs -o DIR: the journal of the sweep is DIR/sweep.partial.csv");
    }
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    if let Some(dir) = &a.output {
        let journal = dir.join("sweep.partial.csv");
        if !a.resume && !a.force {
            let rows = journal_rows(&journal);
            if rows > 0 {
                bail!(
                    "{} holds {rows} finished point(s) of an earlier sweep; add --resume to reuse \
                     them (a different sweep's journal is refused), or --force to discard them",
                    journal.display()
                );
            }
        }
    }
    let pool = pool(a.threads)?;
    let t0 = std::time::Instant::now();
    let result = match &a.output {
        Some(dir) => {
            let journal = dir.join("sweep.partial.csv");
            pool.install(|| sweep.run_resumable(&journal, a.resume, &progress))?
        }
        None => pool.install(|| sweep.run(&progress)),
    };
    bar.finish_and_clear();
    let elapsed = t0.elapsed().as_secs_f64();
    output(&a, &sweep, &result, set, elapsed)
}

/// Writes and prints a finished sweep as `meid sweep` does (shared with `meid merge`).
fn output(
    a: &SweepArgs,
    sweep: &Sweep,
    result: &SweepResult,
    set: Option<meid::io::OutputSet>,
    elapsed: f64,
) -> Result<()> {
    let Some(set) = set else {
        if let Some(e) = sweep.all_failed_error(result) {
            return Err(e.into());
        }
        if a.print.json {
            crate::json::print(&result)?;
        } else if a.print.human() {
            summarise(sweep, result, &a.metric, elapsed, &[]);
            println!();
            print!("{}", result.csv());
        }
        return Ok(());
    };
    result.write(set.staging())?;
    // sweep.csv's rows with types and units (docs/reference/outputs.md, "Parquet").
    crate::outputs::write_parquet_table(&set.path("sweep.parquet"), &sweep.table(result))?;
    if let Some(e) = sweep.all_failed_error(result) {
        // The results (every row with its error) are written; the run is that error.
        set.commit("sweep")?;
        return Err(e.into());
    }
    draw(sweep, result, &a.metric, set.staging())?;
    let files = set.commit("sweep")?;
    if a.print.json {
        crate::json::print(&result)?;
    } else if a.print.human() {
        summarise(sweep, result, &a.metric, elapsed, &files);
    }
    Ok(())
}

/// `meid merge` of sweep shards: the rows of every shard, checked to be this sweep's and to
/// cover its grid once, written as the unsharded `meid sweep -o DIR` writes them.
pub fn merge(a: SweepArgs, shards: &[crate::shard::ShardFiles]) -> Result<()> {
    let t0 = std::time::Instant::now();
    let sweep = prepare(&a)?;
    crate::shard::check_cover(shards, &sweep.fingerprint_text(), sweep.len())?;
    let mut points = Vec::with_capacity(sweep.len());
    for s in shards {
        let text = String::from_utf8_lossy(&s.rows);
        for (i, line) in text.lines().enumerate().skip(1) {
            let p = sweep.parse_row(line).with_context(|| {
                format!(
                    "{}:{}: not a row of this sweep",
                    s.dir.join("shard.csv").display(),
                    i + 1
                )
            })?;
            if let Err(why) = meid::analysis::sweep::check_cells(&p, sweep.cases.len().max(1)) {
                bail!(
                    "{}:{}: point {}: {why}, which a run does not write; run the shard again",
                    s.dir.join("shard.csv").display(),
                    i + 1,
                    p.index
                );
            }
            if p.index < s.first || p.index >= s.end {
                bail!(
                    "{}:{}: point {} is outside the shard's range {}..{}",
                    s.dir.join("shard.csv").display(),
                    i + 1,
                    p.index,
                    s.first,
                    s.end
                );
            }
            points.push(p);
        }
    }
    let result = sweep.result_from(points)?;
    let Some(dir) = &a.output else {
        bail!("meid merge needs -o DIR");
    };
    let set = crate::outputs::begin(dir)?;
    output(&a, &sweep, &result, Some(set), t0.elapsed().as_secs_f64())
}

/// Finished points in a sweep journal: its complete lines after the journal line and the
/// header (0 for a missing, empty or header-only journal).
fn journal_rows(path: &Path) -> usize {
    std::fs::read(path).map_or(0, |b| {
        b.iter().filter(|c| **c == b'\n').count().saturating_sub(2)
    })
}

fn summarise(sweep: &Sweep, r: &SweepResult, metric: &str, elapsed: f64, files: &[PathBuf]) {
    println!(
        "meid sweep — {} points in {:.2} s ({} failed)",
        r.points.len(),
        elapsed,
        r.failures()
    );
    if let Some(m) = &r.spec.reference_mode {
        println!("  {}", m.describe());
    }
    let names: Vec<String> = sweep.vary.iter().map(|v| v.quantity.name()).collect();
    let mut shown: Vec<String> = Vec::new();
    for m in [metric, "energy_ratio"] {
        for k in 0..sweep.cases.len().max(1) {
            let column = if DERIVED.contains(&m) {
                m.to_string()
            } else {
                sweep.metric_column(k, m)
            };
            if shown.contains(&column) {
                continue;
            }
            match r.argmin(&column) {
                Some(i) => {
                    let p = &r.points[i];
                    let at: Vec<String> = names
                        .iter()
                        .zip(&p.values)
                        .map(|(n, v)| format!("{n} = {v:.6}"))
                        .collect();
                    // A minimum on the first or last value of a range may lie outside it.
                    let edges: Vec<String> = sweep
                        .vary
                        .iter()
                        .zip(&p.values)
                        .filter(|(v, x)| {
                            v.values.len() >= 3
                                && (v.values.first() == Some(x) || v.values.last() == Some(x))
                        })
                        .map(|(v, _)| v.quantity.name())
                        .collect();
                    println!(
                        "  min {column:<32} {:.6e}  at {}{}",
                        r.value(i, &column),
                        at.join(", "),
                        if edges.is_empty() {
                            String::new()
                        } else {
                            format!(
                                " (on the grid's edge in {}: the minimum may lie outside the range)",
                                edges.join(" and ")
                            )
                        }
                    );
                }
                None => println!("  min {column:<32} — (undefined at every point; no picture)"),
            }
            shown.push(column);
        }
    }
    // A run stopped at the end of the collision has its peaks from that short window only:
    // the floor force's peak over the run comes tens of ms later (on the lumped example
    // 0.18 N during the collision against 69 N over 0.5 s). Said beside the numbers.
    let peak = |m: &str| m.starts_with("peak_") || shown.iter().any(|c| c.starts_with("peak_"));
    if collision_only(sweep) && peak(metric) {
        println!(
            "  note: each run stops at the end of the collision, so the peak_* columns are peaks during the collision only (not `meid simulate`'s peaks over the run); give --duration S to run every point for S seconds"
        );
    }
    if let Some(p) = r.points.iter().find(|p| p.error.is_some()) {
        println!(
            "  first failure: point {}: {}",
            p.index,
            p.error.as_deref().unwrap_or("")
        );
    }
    for p in files {
        println!("  wrote {}", p.display());
    }
}

/// Axis label in the paper's terms with unit (`ω_d/ω_s (1)`, `K_s (N/m)`), ω_ref named
/// by its mode and frequency when the reference is known.
fn label(q: &Quantity, w_ref: Option<f64>, number: Option<usize>) -> String {
    let l = q.axis_label();
    let mode = number.map_or(String::new(), |k| format!(", mode {k}"));
    match (q, w_ref) {
        (Quantity::WsOverWref | Quantity::WdOverWref, Some(w)) => format!(
            "{l}, ω_ref = {} rad/s ({} Hz{mode})",
            meid::plot::axis::fmt_tick(&w),
            meid::plot::axis::fmt_tick(&(w / (2.0 * std::f64::consts::PI)))
        ),
        _ => l,
    }
}

fn metric_label(m: &str) -> String {
    meid::analysis::sweep::metric_label(m)
}

/// True when every run stops at the end of the collision (no `--duration`, nor a varied
/// `simulation.duration`): the `peak_*` metrics are then peaks during the collision only.
fn collision_only(sweep: &Sweep) -> bool {
    sweep.options.stop_at_collision_end
        && !sweep.vary.iter().any(|v| {
            v.quantity == meid::analysis::sweep::Quantity::Field("simulation.duration".into())
        })
}

/// A picture's label of `metric`: [`metric_label`], with "during the collision" before the unit
/// for a `peak_*` metric of runs that stop there ("peak floor force during the collision (N)").
fn picture_label(sweep: &Sweep, metric: &str) -> String {
    let l = metric_label(metric);
    if !(metric.starts_with("peak_") && collision_only(sweep)) {
        return l;
    }
    match l.rfind(" (") {
        Some(i) => format!("{} during the collision{}", &l[..i], &l[i..]),
        None => format!("{l} during the collision"),
    }
}

/// The metric in words for a picture's title: its [`picture_label`] without the unit.
fn metric_name(sweep: &Sweep, m: &str) -> String {
    let l = picture_label(sweep, m);
    match l.rfind(" (") {
        Some(i) => l[..i].to_string(),
        None => l,
    }
}

/// Sorted order of a value list (pictures need increasing axes).
fn increasing(v: &Vary) -> Option<Vec<usize>> {
    let mut idx: Vec<usize> = (0..v.values.len()).collect();
    idx.sort_by(|&a, &b| v.values[a].total_cmp(&v.values[b]));
    let ok = idx.windows(2).all(|w| v.values[w[0]] < v.values[w[1]]);
    ok.then_some(idx)
}

// `..Default::default()` on every plot literal, so that fields added to the plot API merge.
/// Draws the sweep's pictures of `metric` into `dir`: a curve over one varied quantity, a
/// family of curves over two (the second a list), or one map per case over two; none when
/// the metric is undefined at every point or an axis is not increasing.
fn draw(sweep: &Sweep, r: &SweepResult, metric: &str, dir: &Path) -> Result<Vec<PathBuf>> {
    // Quantities with a single value are fixed: the picture is over the others.
    let active: Vec<usize> = (0..sweep.vary.len())
        .filter(|&k| sweep.vary[k].values.len() > 1)
        .collect();
    let d = Drawing {
        sweep,
        r,
        metric,
        dir,
        active,
        // The cases drawn (one curve or one map each): the sweep's, or the model as specified.
        ncases: sweep.cases.len().max(1),
        stem: metric.replace('/', "_"),
    };
    let vary: Vec<&Vary> = d.active.iter().map(|&k| &sweep.vary[k]).collect();
    // No picture of a metric undefined at every point (e.g. the energy ratio when no run
    // reached the end of the collision); the summary says so.
    let defined =
        (0..d.ncases).any(|k| (0..r.points.len()).any(|i| r.value(i, &d.column(k)).is_finite()));
    if !defined {
        return Ok(Vec::new());
    }
    match vary.len() {
        1 => d.curve(vary[0]),
        2 if vary[1].spacing == Spacing::List => d.family(vary[0], vary[1]),
        2 => d.maps(vary[0], vary[1]),
        _ => Ok(Vec::new()),
    }
}

/// What the pictures of one metric of a sweep are drawn from.
struct Drawing<'a> {
    sweep: &'a Sweep,
    r: &'a SweepResult,
    metric: &'a str,
    dir: &'a Path,
    /// The varied quantities with more than one value (the pictures' axes).
    active: Vec<usize>,
    ncases: usize,
    /// The file stem of the pictures (the metric, `/` replaced).
    stem: String,
}

impl Drawing<'_> {
    /// The result column of the metric in case `k`.
    fn column(&self, k: usize) -> String {
        if DERIVED.contains(&self.metric) {
            self.metric.to_string()
        } else {
            self.sweep.metric_column(k, self.metric)
        }
    }

    /// The metric in case `k` at the point with the active quantities at value indices
    /// (i, j) and the fixed ones at 0 (row-major index).
    fn value(&self, k: usize, i: usize, j: usize) -> f64 {
        let mut index = 0;
        for (q, v) in self.sweep.vary.iter().enumerate() {
            let at = match self.active.iter().position(|&a| a == q) {
                Some(0) => i,
                Some(1) => j,
                _ => 0,
            };
            index = index * v.values.len() + at;
        }
        self.r.value(index, &self.column(k))
    }

    /// A legend prefix naming the case (none without cases).
    fn case_prefix(&self, k: usize) -> String {
        match self.sweep.cases.get(k) {
            Some(c) => case_label(*c).to_string(),
            None => String::new(),
        }
    }

    /// The axis label of a varied quantity (ratios name the reference mode).
    fn axis(&self, q: &Quantity) -> String {
        let number = self.r.spec.reference_mode.as_ref().map(|m| m.number);
        label(q, self.r.spec.reference_omega_rad_per_s, number)
    }

    /// One curve per case over the one varied quantity `v`.
    #[allow(clippy::needless_update)]
    fn curve(&self, v: &Vary) -> Result<Vec<PathBuf>> {
        let Some(ix) = increasing(v) else {
            return Ok(Vec::new());
        };
        let plot = LinePlot {
            title: format!(
                "{} over {}",
                metric_name(self.sweep, self.metric),
                v.quantity.symbol()
            ),
            x_label: self.axis(&v.quantity),
            y_label: picture_label(self.sweep, self.metric),
            x_log: v.spacing == Spacing::Log,
            y_log: false,
            series: (0..self.ncases)
                .map(|k| Series {
                    label: self.case_prefix(k),
                    x: ix.iter().map(|&i| v.values[i]).collect(),
                    y: ix.iter().map(|&i| self.value(k, i, 0)).collect(),
                    ..Default::default()
                })
                .collect(),
            ..Default::default()
        };
        let f = line_plot(self.dir.join(format!("{}_curve", self.stem)), &plot)?;
        Ok(vec![f.png, f.svg])
    }

    /// Families of curves: x = the first quantity `v0`, one curve per listed value of `v1`
    /// (and case).
    #[allow(clippy::needless_update)]
    fn family(&self, v0: &Vary, v1: &Vary) -> Result<Vec<PathBuf>> {
        let Some(ix) = increasing(v0) else {
            return Ok(Vec::new());
        };
        let mut series = Vec::new();
        for k in 0..self.ncases {
            for j in 0..v1.values.len() {
                let family = v1.quantity.legend_entry(v1.values[j]);
                let prefix = self.case_prefix(k);
                series.push(Series {
                    label: if prefix.is_empty() {
                        family
                    } else {
                        format!("{prefix}, {family}")
                    },
                    x: ix.iter().map(|&i| v0.values[i]).collect(),
                    y: ix.iter().map(|&i| self.value(k, i, j)).collect(),
                    ..Default::default()
                });
            }
        }
        let plot = LinePlot {
            title: format!(
                "{} over {}",
                metric_name(self.sweep, self.metric),
                v0.quantity.symbol()
            ),
            x_label: self.axis(&v0.quantity),
            y_label: picture_label(self.sweep, self.metric),
            x_log: v0.spacing == Spacing::Log,
            series,
            ..Default::default()
        };
        let f = line_plot(self.dir.join(format!("{}_family", self.stem)), &plot)?;
        Ok(vec![f.png, f.svg])
    }

    /// One map per case over `v0` × `v1`, with contour levels and the line ω_d = ω_s where
    /// the axes allow it.
    #[allow(clippy::needless_update)]
    fn maps(&self, v0: &Vary, v1: &Vary) -> Result<Vec<PathBuf>> {
        let (Some(ix), Some(iy)) = (increasing(v0), increasing(v1)) else {
            return Ok(Vec::new());
        };
        let mut out = Vec::new();
        for k in 0..self.ncases {
            let x: Vec<f64> = ix.iter().map(|&i| v0.values[i]).collect();
            let y: Vec<f64> = iy.iter().map(|&j| v1.values[j]).collect();
            let mut z = Vec::with_capacity(x.len() * y.len());
            for &j in &iy {
                for &i in &ix {
                    z.push(self.value(k, i, j));
                }
            }
            let finite: Vec<f64> = z.iter().copied().filter(|v| v.is_finite()).collect();
            let (lo, hi) = finite
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let contour_levels = meid::plot::nice_levels(lo, hi, 7);
            let (q0, q1) = (&v0.quantity, &v1.quantity);
            let overlay_lines = rule_lines(q0, q1, &x, &y);
            let prefix = self.case_prefix(k);
            let what = format!(
                "{} over {} and {}",
                metric_name(self.sweep, self.metric),
                q0.symbol(),
                q1.symbol()
            );
            let map = HeatMap {
                title: if prefix.is_empty() {
                    what
                } else {
                    format!("{what}, {prefix}")
                },
                x_label: self.axis(q0),
                y_label: self.axis(q1),
                x,
                y,
                z,
                x_log: v0.spacing == Spacing::Log,
                y_log: v1.spacing == Spacing::Log,
                contour_levels,
                overlay_lines,
                colorbar_label: picture_label(self.sweep, self.metric),
                ..Default::default()
            };
            let name = match self.sweep.cases.get(k) {
                Some(c) => format!("{}_map_{}", self.stem, case_name(*c)),
                None => format!("{}_map", self.stem),
            };
            let f = heat_map(self.dir.join(name), &map)?;
            out.extend([f.png, f.svg]);
        }
        Ok(out)
    }
}

/// The paper's rule ω_d = ω_s on a map over `q0` × `q1` (axes `x`, `y`): the diagonal of a
/// ω_s/ω_ref × ω_d/ω_ref map (where the axes overlap), the line ω_d/ω_s = 1 when that is the
/// y axis.
#[allow(clippy::needless_update)]
fn rule_lines(q0: &Quantity, q1: &Quantity, x: &[f64], y: &[f64]) -> Vec<Series> {
    let mut overlay_lines = Vec::new();
    let diag = matches!(
        (q0, q1),
        (Quantity::WsOverWref, Quantity::WdOverWref) | (Quantity::WdOverWref, Quantity::WsOverWref)
    );
    if diag {
        let a = x[0].max(y[0]);
        let b = x[x.len() - 1].min(y[y.len() - 1]);
        if a < b {
            overlay_lines.push(Series {
                label: "ω_d = ω_s".into(),
                x: vec![a, b],
                y: vec![a, b],
                ..Default::default()
            });
        }
    }
    if matches!(q1, Quantity::WdOverWs) {
        overlay_lines.push(Series {
            label: "ω_d = ω_s".into(),
            x: vec![x[0], x[x.len() - 1]],
            y: vec![1.0, 1.0],
            ..Default::default()
        });
    }
    overlay_lines
}
