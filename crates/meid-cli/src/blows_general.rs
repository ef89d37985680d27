//! `meid blows GENERAL.toml`: a general machine's train of blows at a stroke rate
//! (`meid::analysis::network_blows`), marched, or its steady state found directly (`--steady`).

use anyhow::{bail, Result};

use meid::analysis::network_blows::{stroke_rate, verdict};

use meid::analysis::blows::BlowOptions;
use meid::analysis::network_blows::{self, NetBlowReport, NetSteadyState};
use meid::analysis::steady::SteadyOptions;
use meid::model::network::NetworkModel;

use crate::blows::BlowsArgs;

/// The options of the paper machine's `meid blows` that a general machine's does not take.
fn refuse_paper_options(a: &BlowsArgs) -> Result<()> {
    if a.rates.is_some() {
        bail!("--rates: not for a general machine yet (its stroke-rate map is not built); run --steady at each --rate-bpm");
    }
    if !a.vary.is_empty() {
        bail!("--vary: not for a general machine's blows; use `meid sweep GENERAL.toml --vary … --rate-bpm R`");
    }
    if a.case.case != "as-specified" {
        bail!("--case: a general machine runs as its file says (its [[damper]] entries are the dampers)");
    }
    if a.run.rate.is_some() {
        bail!("--rate: a general machine's train records no samples");
    }
    Ok(())
}

pub fn run(a: BlowsArgs) -> Result<()> {
    refuse_paper_options(&a)?;
    let model = NetworkModel::from_file(&a.model, &a.run.set.set)?;
    let rate_bpm = stroke_rate(&model, a.rate_bpm)?;
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let out = if a.steady {
        let so = SteadyOptions {
            rate_bpm,
            ..SteadyOptions::default()
        };
        let bar = crate::progress::spinner(a.print.quiet || a.print.json, "steady state");
        let s = network_blows::steady_state(&model, &so);
        bar.finish_and_clear();
        let s = s?;
        if a.print.human() {
            print_steady(&s);
        }
        network_blows::steady_object(&s)
    } else {
        let b = BlowOptions {
            blows: a.blows,
            rate_bpm,
            steady_tolerance: a.tolerance,
        };
        let r = network_blows::run_blows(&model, &b)?;
        if a.print.human() {
            print_march(&r);
        }
        serde_json::to_value(&r)?
    };
    if let Some(set) = set {
        meid::io::write_json(&set.path("blows.json"), &crate::json::object(&out)?)?;
        set.commit("blows")?;
    }
    if a.print.json {
        crate::json::print(&out)?;
    }
    Ok(())
}

fn damper_column(b: &NetBlowReport) -> String {
    b.dampers
        .iter()
        .map(|d| {
            format!(
                "{}{:.4}",
                if d.touched { "" } else { "*" },
                d.gap_at_strike_m * 1e3
            )
        })
        .collect::<Vec<_>>()
        .join(" ")
}

fn print_blow_rows(blows: &[NetBlowReport], bed: &str) {
    println!("  blow  energy ratio  peak accel at {bed} (m/s²)  peak floor force (N)  damper gaps at strike (mm; * = did not touch)");
    for x in blows {
        println!(
            "  {:>4}  {:>12}  {:>24.4}  {:>20}  {}",
            x.blow,
            x.energy_ratio.map_or("—".into(), |v| format!("{v:.5}")),
            x.peak_bed_acceleration_m_per_s2,
            x.peak_floor_force_n
                .map_or("—".into(), |f| format!("{f:.4}")),
            damper_column(x)
        );
    }
}

fn print_steady(s: &NetSteadyState) {
    println!("{}", verdict(s));
    println!();
    println!(
        "Steady state at {} /min (interval {:.6} s): {}, converged {}, residual {:.2e}, {} blow evaluations ({} Jacobian)",
        s.rate_bpm,
        s.interval_s,
        s.regime.name(),
        s.converged,
        s.residual,
        s.map_evaluations,
        s.jacobian
    );
    if let Some(m) = s.multipliers_abs.first() {
        println!(
            "  |μ|max {m:.6}{}",
            s.periods_to_settle.map_or(String::new(), |p| format!(
                " (a disturbance decays to 1e-3 in {p:.1} periods)"
            ))
        );
    }
    for d in &s.dampers_touch {
        println!(
            "  {:<12} touches {:<5}  gap at strike {:.4} mm",
            d.name,
            d.touches,
            d.gap_at_strike_m * 1e3
        );
    }
    print_blow_rows(&s.blows, &s.bed_point);
    for n in &s.notes {
        println!("note: {n}");
    }
}

fn print_march(r: &network_blows::NetBlowsRun) {
    if let Some(last) = r.blows.last() {
        let away: Vec<&str> = last
            .dampers
            .iter()
            .filter(|d| !d.touched)
            .map(|d| d.name.as_str())
            .collect();
        if !last.dampers.is_empty() {
            if away.is_empty() {
                println!(
                    "At {} blows/min every damper touched its point in the last blow ({}).",
                    r.rate_bpm, last.blow
                );
            } else {
                println!(
                    "At {} blows/min {} did not touch their points in the last blow ({}): they do not return between blows (--steady gives the steady state).",
                    r.rate_bpm,
                    away.join(", "),
                    last.blow
                );
            }
            println!();
        }
    }
    println!(
        "The march from rest: {} blows every {:.6} s ({} /min){}",
        r.blows.len(),
        r.interval_s,
        r.rate_bpm,
        r.settled_from_blow
            .map_or(", not settled".to_string(), |b| format!(
                ", settled from blow {b}"
            ))
    );
    print_blow_rows(&r.blows, &r.bed_point);
}
