//! `meid blows`' production part: the verdict, the direct steady state of every case, and the
//! stroke-rate map (`--rates`).

use std::path::Path;

use anyhow::Result;
use meid::analysis::compare::CaseName;
use meid::analysis::production::{self, largest_returning_rate, Production, RateRow};
use meid::analysis::steady::{steady_state, SteadyOptions, SteadyState};
use meid::model::{Case, Model};
use meid::plot::{self, LinePlot, Marker, Series};

use crate::args::PrintArgs;

/// The stroke rate a command runs at: its `--rate-bpm` (`given`), else the model's
/// `[production] rate_bpm`, else the assumed 60 /min, with where it came from
/// ([`production::stroke_rate`]); a bad `--rate-bpm` is an input error naming the option.
pub fn stroke_rate(model: &Model, given: Option<f64>) -> Result<(f64, production::RateOrigin)> {
    Ok(production::stroke_rate(model, given).map_err(|_| {
        meid::Error::invalid(
            "--rate-bpm",
            format!(
                "the stroke rate must be a finite number > 0 blows per minute (got {})",
                given.unwrap_or(f64::NAN)
            ),
        )
    })?)
}

/// The production at one rate, and the steady state of the case asked for.
pub struct Prod {
    pub production: Production,
    pub selected: SteadyState,
}

/// The three cases' steady states at `rate_bpm`, the damper's return rate and the verdict;
/// `selected` is `case`'s steady state.
pub fn cases(model: &Model, case: Case, rate_bpm: f64, print: &PrintArgs) -> Result<Prod> {
    let so = SteadyOptions::default();
    let bar = crate::progress::spinner(print.quiet || print.json, "steady states");
    let p = production::production(model, rate_bpm, &so, true);
    bar.finish_and_clear();
    let p = p?;
    let name = match case {
        Case::NoDamper => Some(CaseName::NoDamper),
        Case::Damper => Some(CaseName::Damper),
        Case::AddedMass => Some(CaseName::AddedMass),
        Case::AsSpecified => None,
    };
    let selected = match name.and_then(|c| p.case(c)) {
        Some(s) => s.clone(),
        None => {
            let sys = model.impact_system(case)?;
            steady_state(&sys, &model.options(), &SteadyOptions { rate_bpm, ..so })?
        }
    };
    Ok(Prod {
        production: p,
        selected,
    })
}

/// `--steady`: the verdict and the steady states, no march.
pub fn steady_only(prod: &Prod, output: Option<&Path>, print: &PrintArgs) -> Result<()> {
    let p = &prod.production;
    let out = serde_json::json!({
        "rate_bpm": p.rate_bpm,
        "interval_s": p.interval_s,
        "verdict": p.verdict,
        "steady_state": prod.selected,
        "production": p,
    });
    if let Some(dir) = output {
        let set = crate::outputs::begin(dir)?;
        let staging = set.staging();
        meid::io::write_json(&staging.join("steady.json"), &crate::json::object(&out)?)?;
        meid::io::write_atomic(&staging.join("steady.csv"), steady_csv(p).as_bytes())?;
        set.commit("blows --steady")?;
    }
    if print.json {
        crate::json::print(&out)?;
    } else if print.human() {
        print_production(p);
    }
    Ok(())
}

/// One row per case: regime, convergence, levels, gap, multipliers.
fn steady_csv(p: &Production) -> String {
    let mut w = String::from("case,regime,converged,residual,map_evaluations,energy_ratio,peak_floor_force_n,peak_bed_acceleration_m_per_s2,damper_gap_at_strike_m,damper_touches_bed,largest_multiplier_abs\n");
    for c in &p.cases {
        let s = &c.steady_state;
        w.push_str(&format!(
            "{},{},{},{:.3e},{},{:.9e},{:.9e},{:.9e},{},{},{}\n",
            c.case,
            s.regime.name(),
            s.converged,
            s.residual,
            s.map_evaluations,
            s.energy_ratio,
            s.peak_floor_force_n,
            s.peak_bed_acceleration_m_per_s2,
            s.damper_gap_at_strike_m
                .map_or(String::new(), |g| format!("{g:.9e}")),
            s.damper_touches_bed
                .map_or(String::new(), |b| b.to_string()),
            s.multipliers_abs
                .first()
                .map_or(String::new(), |m| format!("{m:.9e}")),
        ));
    }
    w
}

/// The verdict first, then a table of the steady states.
pub fn print_production(p: &Production) {
    println!(
        "meid blows — production at {} blows/min (one blow every {:.6} s), periodic steady state",
        meid::num(p.rate_bpm),
        p.interval_s
    );
    for s in &p.verdict {
        println!("  {s}");
    }
    println!();
    println!("  case         regime     E_p+/E_s-  peak floor force (N)  peak bed accel (m/s²)  damper gap (mm)  touches bed  |μ|max   evaluations");
    for c in &p.cases {
        let s = &c.steady_state;
        println!(
            "  {:<11}  {:<9}  {:>9.5}  {:>20.4}  {:>21.4}  {:>15}  {:>11}  {:>7}  {:>3}{}",
            c.case,
            s.regime.name(),
            s.energy_ratio,
            s.peak_floor_force_n,
            s.peak_bed_acceleration_m_per_s2,
            s.damper_gap_at_strike_m
                .map_or("—".into(), |g| format!("{:.4}", g * 1e3)),
            s.damper_touches_bed.map_or("—".into(), |b| if b {
                "yes".into()
            } else {
                "no".to_string()
            }),
            s.multipliers_abs
                .first()
                .map_or("—".into(), |m| format!("{m:.4}")),
            s.map_evaluations,
            if s.converged {
                String::new()
            } else {
                "  (not converged: an estimate)".into()
            }
        );
    }
    for c in &p.cases {
        for n in &c.steady_state.notes {
            println!("  note ({}): {n}", c.case);
        }
    }
}

/// `--rates`: the stroke-rate map.
pub fn rate_map(
    model_path: &Path,
    model: &Model,
    spec: &str,
    output: Option<&Path>,
    print: &PrintArgs,
) -> Result<()> {
    let (_, rates) = meid::analysis::sweep::parse_values(spec, spec, "--rates")?;
    if let Some(r) = rates.iter().find(|r| !(r.is_finite() && **r > 0.0)) {
        return Err(meid::Error::invalid(
            "--rates",
            format!("`{spec}`: every stroke rate must be > 0 blows per minute (got {r})"),
        )
        .into());
    }
    let so = SteadyOptions::default();
    let bar = crate::progress::bar(print.quiet || print.json, rates.len(), "rates");
    let progress = |done: usize, _n: usize| bar.set_position(done as u64);
    let rows = production::stroke_rate_map(model, &rates, &so, &progress);
    bar.finish_and_clear();
    let rows = rows?;
    let best = largest_returning_rate(&rows);
    let out = serde_json::json!({
        "model": model_path.display().to_string(),
        "rates_bpm": rates,
        "largest_returning_rate_bpm": best,
        "rows": rows,
    });
    if let Some(dir) = output {
        let set = crate::outputs::begin(dir)?;
        let staging = set.staging();
        meid::io::write_json(&staging.join("rates.json"), &crate::json::object(&out)?)?;
        meid::io::write_atomic(&staging.join("rates.csv"), rates_csv(&rows).as_bytes())?;
        rates_picture(&staging.join("rates-db"), &rows, best)?;
        set.commit("blows --rates")?;
    }
    if print.json {
        crate::json::print(&out)?;
    } else if print.human() {
        println!(
            "meid blows — stroke-rate map, {} rates: steady floor force and bed acceleration against the machine without a damper",
            rows.len()
        );
        match best {
            Some(r) => println!(
                "  The damper touches the bed in every steady blow up to {} blows/min (the largest rate of the map with every lower rate returning too).",
                meid::num(r)
            ),
            None if rows.iter().any(|r| r.cases.len() > 1) => println!(
                "  The damper does not return at the lowest rate of the map."
            ),
            None => {}
        }
        println!("  rate (/min)  regime (damper)  damper floor (dB)  damper accel (dB)  added floor (dB)  added accel (dB)  gap (mm)  touches");
        for r in &rows {
            let d = db_row(r);
            println!(
                "  {:>11}  {:>15}  {:>17}  {:>17}  {:>16}  {:>16}  {:>8}  {:>7}",
                meid::num(r.rate_bpm),
                d.regime,
                fmt_db(d.damper_floor),
                fmt_db(d.damper_accel),
                fmt_db(d.added_floor),
                fmt_db(d.added_accel),
                d.gap_mm.map_or("—".into(), |g| format!("{g:.4}")),
                d.touches.map_or("—", |b| if b { "yes" } else { "no" }),
            );
        }
    }
    Ok(())
}

fn fmt_db(v: Option<f64>) -> String {
    v.map_or("—".into(), |v| format!("{v:+.2}"))
}

/// The dB changes of one rate against the machine without a damper (positive: worse).
struct DbRow {
    regime: String,
    damper_floor: Option<f64>,
    damper_accel: Option<f64>,
    added_floor: Option<f64>,
    added_accel: Option<f64>,
    gap_mm: Option<f64>,
    touches: Option<bool>,
}

fn db_row(r: &RateRow) -> DbRow {
    let get = |c: CaseName| {
        r.cases
            .iter()
            .find(|x| x.case == c.name())
            .map(|x| &x.steady_state)
    };
    let none = get(CaseName::NoDamper);
    let db = |a: Option<&SteadyState>, f: fn(&SteadyState) -> f64| -> Option<f64> {
        Some(20.0 * (f(a?) / f(none?)).log10())
    };
    let floor = |s: &SteadyState| s.peak_floor_force_n;
    let accel = |s: &SteadyState| s.peak_bed_acceleration_m_per_s2;
    let d = get(CaseName::Damper);
    DbRow {
        regime: d.or(none).map_or("—".into(), |s| s.regime.name()),
        damper_floor: db(d, floor),
        damper_accel: db(d, accel),
        added_floor: db(get(CaseName::AddedMass), floor),
        added_accel: db(get(CaseName::AddedMass), accel),
        gap_mm: d.and_then(|s| s.damper_gap_at_strike_m).map(|g| 1e3 * g),
        touches: d.and_then(|s| s.damper_touches_bed),
    }
}

fn rates_csv(rows: &[RateRow]) -> String {
    let mut w = String::from("rate_bpm,case,regime,converged,energy_ratio,peak_floor_force_n,peak_bed_acceleration_m_per_s2,floor_force_change_db,bed_acceleration_change_db,damper_gap_at_strike_m,damper_touches_bed\n");
    for r in rows {
        let none = r
            .cases
            .iter()
            .find(|x| x.case == CaseName::NoDamper.name())
            .map(|x| &x.steady_state);
        for c in &r.cases {
            let s = &c.steady_state;
            let db = |f: fn(&SteadyState) -> f64| {
                none.map_or(String::new(), |n| {
                    format!("{:.6}", 20.0 * (f(s) / f(n)).log10())
                })
            };
            w.push_str(&format!(
                "{:.9e},{},{},{},{:.9e},{:.9e},{:.9e},{},{},{},{}\n",
                r.rate_bpm,
                c.case,
                s.regime.name(),
                s.converged,
                s.energy_ratio,
                s.peak_floor_force_n,
                s.peak_bed_acceleration_m_per_s2,
                db(|s| s.peak_floor_force_n),
                db(|s| s.peak_bed_acceleration_m_per_s2),
                s.damper_gap_at_strike_m
                    .map_or(String::new(), |g| format!("{g:.9e}")),
                s.damper_touches_bed
                    .map_or(String::new(), |b| b.to_string()),
            ));
        }
    }
    w
}

/// dB change against the rate, damper (solid) and added mass (dashed), floor force and bed
/// acceleration; regime changes of the damper case and the largest returning rate marked.
fn rates_picture(stem: &Path, rows: &[RateRow], best: Option<f64>) -> Result<()> {
    let x: Vec<f64> = rows.iter().map(|r| r.rate_bpm).collect();
    let d: Vec<DbRow> = rows.iter().map(db_row).collect();
    let series = |label: &str, y: Vec<Option<f64>>, style: plot::LineStyle| Series {
        label: label.into(),
        x: x.clone(),
        y: y.into_iter().map(|v| v.unwrap_or(f64::NAN)).collect(),
        style,
        ..Default::default()
    };
    let mut markers = Vec::new();
    if let Some(b) = best {
        markers.push(Marker {
            x: b,
            label: format!("damper returns up to {:.4} /min", b),
        });
    }
    let bands = regime_bands(&x, &d);
    plot::line_plot(
        stem,
        &LinePlot {
            title: "steady level against the machine without a damper (positive: worse)".into(),
            x_label: "stroke rate (blows/min)".into(),
            y_label: "change (dB)".into(),
            series: vec![
                series(
                    "damper: floor force",
                    d.iter().map(|r| r.damper_floor).collect(),
                    plot::LineStyle::Solid,
                ),
                series(
                    "damper: bed acceleration",
                    d.iter().map(|r| r.damper_accel).collect(),
                    plot::LineStyle::Solid,
                ),
                series(
                    "added mass: floor force",
                    d.iter().map(|r| r.added_floor).collect(),
                    plot::LineStyle::Dashed,
                ),
                series(
                    "added mass: bed acceleration",
                    d.iter().map(|r| r.added_accel).collect(),
                    plot::LineStyle::Dashed,
                ),
            ],
            markers,
            bands,
            ..LinePlot::default()
        },
    )?;
    Ok(())
}

/// The damper's regimes along the rates as shaded bands, one per run of rates with the same
/// regime and touching, each reaching halfway to its neighbouring rates: green where it touches
/// the bed in every steady blow (period-1), blue for a longer period that touches, red where it
/// does not touch, grey for an irregular train.
fn regime_bands(x: &[f64], d: &[DbRow]) -> Vec<plot::Band> {
    let mut bands = Vec::new();
    let n = x.len();
    if n < 2 || d.iter().all(|r| r.touches.is_none()) {
        return bands;
    }
    // Edges between rates (midpoints), the ends half a step out.
    let edge = |i: usize| -> f64 {
        if i == 0 {
            x[0] - 0.5 * (x[1] - x[0])
        } else if i == n {
            x[n - 1] + 0.5 * (x[n - 1] - x[n - 2])
        } else {
            0.5 * (x[i - 1] + x[i])
        }
    };
    let mut start = 0;
    for i in 1..=n {
        if i < n && d[i].regime == d[start].regime && d[i].touches == d[start].touches {
            continue;
        }
        let r = &d[start];
        let (label, color) = match (r.regime.as_str(), r.touches) {
            ("irregular", _) => ("irregular train".to_string(), [127, 127, 127]),
            (_, Some(false)) => ("damper does not touch the bed".to_string(), [214, 39, 40]),
            ("period-1", Some(true)) => ("period-1, damper touches".to_string(), [44, 160, 44]),
            (k, Some(true)) => (format!("{k}, damper touches"), [31, 119, 180]),
            (k, None) => (k.to_string(), [127, 127, 127]),
        };
        bands.push(plot::Band {
            from: edge(start).max(f64::MIN_POSITIVE),
            to: edge(i),
            label,
            color,
        });
        start = i;
    }
    bands
}
