//! `meid blows`: a train of blows at a stroke rate; steady blow-to-blow levels.

use std::path::PathBuf;

use anyhow::{Context, Result};
use meid::analysis::blows::{run_blows_each, BlowOptions};
use meid::plot::{self, LinePlot, Series};

use crate::args::{CaseArg, PrintArgs, RunArgs};

#[derive(clap::Args)]
pub struct BlowsArgs {
    /// Model file (TOML).
    pub(crate) model: PathBuf,
    /// Number of blows.
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub(crate) blows: usize,
    /// Stroke rate (blows per minute; default: the model's [production] rate_bpm, else 60).
    /// The interval 60/R must outlast each blow's collision (else exit 2, naming the largest
    /// valid rate); the machine need not be at rest.
    #[arg(long, value_name = "R")]
    pub(crate) rate_bpm: Option<f64>,
    /// Relative blow-to-blow change that counts as steady (the march's table).
    #[arg(long, value_name = "FRACTION", default_value_t = 0.01)]
    pub(crate) tolerance: f64,
    /// Only the direct periodic steady state of each case (no march): the fixed point of the
    /// blow-to-blow map, its regime and Floquet multipliers (docs/explanations/blows.md, "Production").
    #[arg(long)]
    pub(crate) steady: bool,
    /// A stroke-rate map instead: the steady state of every case at each rate of
    /// LO..HI:N (or LO..HI:N:log, or R1,R2,…) blows/min; with -o, rates.csv, rates.json and
    /// a picture of the dB changes against the rate.
    #[arg(long, value_name = "LO..HI:N", conflicts_with = "steady")]
    pub(crate) rates: Option<String>,
    /// A damper-return map instead: over one or two quantities (repeat --vary, as in `meid
    /// sweep`: e.g. --vary damper.stiffness=1e3..1e5:9:log --vary damper.damping=50..1000:9:log),
    /// each design's steady state at --rate-bpm: whether the damper returns before every strike,
    /// and its steady floor force and bed acceleration against no damper; with -o,
    /// return-map.csv, return-map.json and a picture.
    #[arg(long, value_name = "SPEC", conflicts_with_all = ["steady", "rates"])]
    pub(crate) vary: Vec<String>,
    #[command(flatten)]
    pub(crate) case: CaseArg,
    /// Write blows.csv, blows.json, history.csv and pictures into DIR.
    #[arg(short, long, value_name = "DIR")]
    pub(crate) output: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) run: RunArgs,
    #[command(flatten)]
    pub(crate) print: PrintArgs,
}

pub fn run(a: BlowsArgs) -> Result<()> {
    let model = a.run.load(&a.model, None)?;
    crate::warn_model(&model, &a.print);
    if let Some(spec) = &a.rates {
        return crate::production::rate_map(&a.model, &model, spec, a.output.as_deref(), &a.print);
    }
    let (rate_bpm, _) = crate::production::stroke_rate(&model, a.rate_bpm)?;
    if !a.vary.is_empty() {
        return crate::return_map::run(
            &a.model,
            &model,
            &a.vary,
            rate_bpm,
            a.output.as_deref(),
            &a.print,
        );
    }
    let case = a.case.parse()?;
    if a.steady {
        let prod = crate::production::cases(&model, case, rate_bpm, &a.print)?;
        return crate::production::steady_only(&prod, a.output.as_deref(), &a.print);
    }
    let sys = model.impact_system(case)?;
    let opts = model.options();
    let b = BlowOptions {
        blows: a.blows,
        rate_bpm,
        steady_tolerance: a.tolerance,
    };
    // With -o: history.csv is streamed blow by blow into the output set; only the three
    // pictured series (time, bed acceleration, floor force) are held.
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let mut pictured: [Vec<f64>; 3] = Default::default();
    let bar = crate::progress::bar(a.print.quiet || a.print.json, a.blows, "blows");
    let progress = |done: usize, _total: usize| bar.set_position(done as u64);
    // The per-impact table of every blow, from each blow's run as it ends.
    let mut impacts: Vec<meid::analysis::impacts::BlowImpact> = Vec::new();
    let mut on_blow = |k: usize, t0: f64, sol: &meid::integrate::Solution| -> meid::Result<()> {
        impacts.extend(meid::analysis::impacts::blow_impacts(&sys, sol, k, t0)?);
        Ok(())
    };
    let r = match &set {
        Some(set) => {
            let interval = meid::analysis::blows::blow_interval_s(rate_bpm)?;
            let rows =
                a.blows as f64 * meid::analysis::energy::sample_count(interval, opts.sample_rate);
            meid::limits::check_memory(
                &format!(
                    "the pictured series of {} blows ({rows:.3e} samples × 48 B)",
                    a.blows
                ),
                48.0 * rows,
                "blows",
                "the number of blows (--blows) or simulation.sample_rate (--rate)",
            )?;
            crate::outputs::check_disk(
                set.dir(),
                &format!("history.csv ({rows:.3e} samples)"),
                rows * meid::io::HISTORY_ROW_BYTES as f64,
                "the number of blows (--blows) or simulation.sample_rate (--rate)",
            )?;
            let path = set.path("history.csv");
            let file = std::fs::File::create(&path)
                .with_context(|| format!("cannot create {}", path.display()))?;
            let mut w = meid::io::HistoryWriter::new(std::io::BufWriter::new(file))
                .with_context(|| format!("cannot write {}", path.display()))?;
            let mut sink = |h: &meid::analysis::History| -> meid::Result<()> {
                for i in 0..h.time_s.len() {
                    w.row(&h.row(i)).map_err(|e| meid::Error::io(&path, e))?;
                }
                pictured[0].extend_from_slice(&h.time_s);
                pictured[1].extend_from_slice(&h.bed_acceleration_m_per_s2);
                pictured[2].extend_from_slice(&h.floor_force_n);
                Ok(())
            };
            let r = run_blows_each(
                &sys,
                &opts,
                &b,
                Some(&mut sink),
                false,
                &progress,
                Some(&mut on_blow),
            );
            bar.finish_and_clear();
            let r = r.context("blow train failed")?;
            w.into_inner()
                .with_context(|| format!("cannot write {}", path.display()))?;
            r
        }
        None => {
            let r = run_blows_each(&sys, &opts, &b, None, false, &progress, Some(&mut on_blow));
            bar.finish_and_clear();
            r.context("blow train failed")?
        }
    };
    // The steady states after the march: the march's own refusals (a collision longer than
    // the interval, a run too long) come first, as they name the blow that failed.
    let prod = crate::production::cases(&model, case, rate_bpm, &a.print)?;
    let impacts_csv = meid::analysis::impacts::blow_impacts_csv(&impacts);
    let out = serde_json::json!({
        "rate_bpm": rate_bpm,
        "interval_s": r.interval_s,
        "verdict": prod.production.verdict,
        "steady_state": prod.selected,
        "production": prod.production,
        "blows": r.blows,
        "steady": r.steady,
        "damper_gap_at_next_strike_m": r.damper_gap_at_next_strike_m,
        "impacts": impacts,
    });
    if let Some(set) = &set {
        write_march(
            set.staging(),
            &a,
            rate_bpm,
            &r,
            &out,
            std::mem::take(&mut pictured),
            &impacts_csv,
        )?;
    }
    if let Some(set) = set {
        set.commit("blows")?;
    }
    if a.print.json {
        crate::json::print(&out)?;
    } else if a.print.human() {
        crate::production::print_production(&prod.production);
        println!();
        print_march(&a, rate_bpm, &r);
    }
    Ok(())
}

/// blows.csv, blows.json, impacts.csv and the pictures of the march into the staging directory `dir`.
fn write_march(
    dir: &std::path::Path,
    a: &BlowsArgs,
    rate_bpm: f64,
    r: &meid::analysis::blows::BlowsRun,
    out: &serde_json::Value,
    pictured: [Vec<f64>; 3],
    impacts_csv: &str,
) -> Result<()> {
    let mut w = String::from("blow,start_s,energy_ratio,machine_energy_at_strike_j,damper_energy_at_strike_j,peak_bed_acceleration_m_per_s2,peak_floor_force_n,peak_contact_force_slider_bed_n,damper_gap_at_strike_m,damper_contact_time_s\n");
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:.9e}"));
    for x in &r.blows {
        w.push_str(&format!(
            "{},{:.9e},{},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{},{}\n",
            x.blow,
            x.start_s,
            opt(x.energy_ratio),
            x.machine_energy_at_strike_j,
            x.damper_energy_at_strike_j,
            x.peak_bed_acceleration_m_per_s2,
            x.peak_floor_force_n,
            x.peak_contact_force_slider_bed_n,
            opt(x.damper_gap_at_strike_m),
            opt(x.damper_contact_time_s)
        ));
    }
    meid::io::write_atomic(&dir.join("blows.csv"), w.as_bytes())?;
    meid::io::write_atomic(&dir.join("impacts.csv"), impacts_csv.as_bytes())?;
    meid::io::write_json(&dir.join("blows.json"), &crate::json::object(out)?)?;
    let [time_s, accel, floor] = pictured;
    for (stem, title, label, y) in [
        (
            "acceleration-time",
            "bed acceleration at B",
            "acceleration (m/s²)",
            accel,
        ),
        ("floor-force-time", "force to the floor", "force (N)", floor),
    ] {
        plot::line_plot(
            dir.join(stem),
            &LinePlot {
                title: format!("{title}, {} blows at {} /min", a.blows, rate_bpm),
                x_label: "time (s)".into(),
                y_label: label.into(),
                series: vec![Series {
                    label: String::new(),
                    x: time_s.clone(),
                    y,
                    ..Default::default()
                }],
                ..LinePlot::default()
            },
        )?;
    }
    let n: Vec<f64> = r.blows.iter().map(|x| x.blow as f64).collect();
    let first_f = r.blows.first().map_or(1.0, |x| x.peak_floor_force_n);
    let first_a = r
        .blows
        .first()
        .map_or(1.0, |x| x.peak_bed_acceleration_m_per_s2);
    plot::line_plot(
        dir.join("blow-levels"),
        &LinePlot {
            title: "peak levels per blow (relative to the first blow)".into(),
            x_label: "blow number (1)".into(),
            y_label: "peak / first blow's peak (1)".into(),
            series: vec![
                Series {
                    label: "floor force".into(),
                    x: n.clone(),
                    y: r.blows
                        .iter()
                        .map(|x| x.peak_floor_force_n / first_f)
                        .collect(),
                    ..Default::default()
                },
                Series {
                    label: "bed acceleration".into(),
                    x: n,
                    y: r.blows
                        .iter()
                        .map(|x| x.peak_bed_acceleration_m_per_s2 / first_a)
                        .collect(),
                    ..Default::default()
                },
            ],
            ..LinePlot::default()
        },
    )?;
    Ok(())
}

/// The march's table, its steady line and the damper hint.
fn print_march(a: &BlowsArgs, rate_bpm: f64, r: &meid::analysis::blows::BlowsRun) {
    println!(
        "The march from rest: {} blows every {:.6} s ({} /min)",
        a.blows, r.interval_s, rate_bpm
    );
    println!("  blow  E_p+/E_s-   peak accel (m/s²)  peak floor force (N)  machine energy at strike (J)  damper gap (mm)");
    for x in &r.blows {
        println!(
            "  {:>4}  {:>9}  {:>17.4}  {:>20.4}  {:>28.4e}  {:>15}",
            x.blow,
            x.energy_ratio.map_or("—".into(), |v| format!("{v:.5}")),
            x.peak_bed_acceleration_m_per_s2,
            x.peak_floor_force_n,
            x.machine_energy_at_strike_j,
            x.damper_gap_at_strike_m
                .map_or("—".into(), |g| format!("{:.4}", g * 1e3))
        );
    }
    let s = &r.steady;
    match s.from_blow {
        // The levels printed are the last blow's: an estimate of the steady level, which
        // they approach to about the last blow-to-blow change (10 blows of the lumped
        // example: 110.5651 N, 40 blows: 110.5272 N; last change 0.082 N).
        Some(k) => println!(
            "  steady (blow-to-blow changes < {}) from blow {k}; blow {}'s levels, an estimate of the steady levels to about the last change: floor force {:.4} N ± {:.2e} N, bed acceleration {:.4} m/s² ± {:.2e} m/s² (more blows give more digits)",
            a.tolerance,
            r.blows.len(),
            s.peak_floor_force_n,
            last_change(&r.blows, |b| b.peak_floor_force_n),
            s.peak_bed_acceleration_m_per_s2,
            last_change(&r.blows, |b| b.peak_bed_acceleration_m_per_s2)
        ),
        None => println!(
            "  not steady after {} blows: last changes floor {:.2e}, acceleration {:.2e}, energy ratio {:.2e}",
            a.blows,
            s.last_change_peak_floor_force,
            s.last_change_peak_bed_acceleration,
            s.last_change_energy_ratio
        ),
    }
    if let Some(hint) = damper_hint(r) {
        println!("  {hint}");
    }
}

/// Below this gap (m) the damper counts as back against the bed (10 µm: far below the bed's
/// travel during a collision, ~0.2 mm on the paper example).
const RETURNED_GAP_M: f64 = 1e-5;

/// One line on the damper's return: its gap to the bed at the next strike and, when it has
/// not come back, the blows in which it never touched the bed (docs/explanations/blows.md explains why
/// a one-way dashpot holds it off).
fn damper_hint(r: &meid::analysis::blows::BlowsRun) -> Option<String> {
    let gap = r.damper_gap_at_next_strike_m?;
    if gap <= RETURNED_GAP_M {
        return Some(format!(
            "damper gap at next blow: {:.4} mm (back against the bed)",
            gap.max(0.0) * 1e3
        ));
    }
    let idle: Vec<usize> = r
        .blows
        .iter()
        .filter(|x| x.damper_contact_time_s == Some(0.0))
        .map(|x| x.blow)
        .collect();
    let touch = if idle.is_empty() {
        String::new()
    } else {
        format!(
            "; it never touched the bed in {} of {} blows",
            idle.len(),
            r.blows.len()
        )
    };
    Some(format!(
        "damper gap at next blow: {:.4} mm (not returned{touch}; see docs/explanations/blows.md)",
        gap * 1e3
    ))
}

/// |x_N − x_{N−1}| of the last two blows (0 with one blow).
fn last_change(
    blows: &[meid::analysis::blows::BlowReport],
    level: impl Fn(&meid::analysis::blows::BlowReport) -> f64,
) -> f64 {
    match blows {
        [.., a, b] => (level(b) - level(a)).abs(),
        _ => 0.0,
    }
}
