//! `meid sweep` of a general machine (`[[impactor]]`, `[[damper]]`, `[[contact]]`): one or
//! two named paths varied (`meid::analysis::network_study`), the table, sweep.csv/json and a
//! picture (the metric over one numeric path; a map over two numeric paths).

use anyhow::{bail, Result};

use meid::analysis::network_study::{NetSweep, NetSweepResult, NetValue, NetVary};
use meid::model::network::NetworkModel;
use meid::plot::{heat_map, line_plot, HeatMap, LinePlot, Series};

use crate::sweep::SweepArgs;

/// The options of the paper machine's sweep that a general machine's does not take.
fn refuse_paper_options(a: &SweepArgs) -> Result<()> {
    for (given, flag, why) in [
        (
            !a.cases.is_empty(),
            "--cases",
            "a general machine runs as its file says (its [[damper]] entries are the dampers)",
        ),
        (
            a.bed_mass.is_some(),
            "--bed-mass",
            "md/mb belongs to the paper's machine; vary damper.NAME.mass",
        ),
        (
            a.shard.is_some(),
            "--shard",
            "a general machine's sweep runs whole",
        ),
        (
            a.resume || a.force,
            "--resume/--force",
            "a general machine's sweep keeps no journal",
        ),
    ] {
        if given {
            bail!("{flag}: not for a general machine's sweep: {why}");
        }
    }
    Ok(())
}

pub fn run(a: &SweepArgs) -> Result<()> {
    refuse_paper_options(a)?;
    let mut overrides = a.set.set.clone();
    if let Some(d) = a.duration {
        overrides.push(format!("simulation.duration={d:e}"));
    }
    let model = NetworkModel::from_file(&a.model, &overrides)?;
    let vary = a
        .vary
        .iter()
        .map(|s| NetVary::parse(s))
        .collect::<meid::Result<Vec<_>>>()?;
    let rate = match a.rate_bpm {
        Some(r) => Some(meid::analysis::network_blows::stroke_rate(&model, Some(r))?),
        None => model.spec.production.as_ref().map(|p| p.rate_bpm),
    };
    let sweep = NetSweep::new(model, vary)?.at_rate(rate)?;
    let metric = a.metric.as_str();
    if !sweep.columns().iter().any(|c| c == metric) {
        let probe = NetSweepResult {
            machine: "general",
            vary: Vec::new(),
            columns: sweep.columns().to_vec(),
            points: Vec::new(),
            structures_built: 0,
        };
        probe.column(metric)?;
    }
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let bar = crate::progress::bar(a.print.quiet || a.print.json, sweep.len(), "points");
    let pool = crate::sweep::pool(a.threads)?;
    let result = pool.install(|| sweep.run(&|done| bar.set_position(done as u64)));
    bar.finish_and_clear();
    if result.points.iter().all(|p| p.error.is_some()) {
        let e = result
            .points
            .first()
            .and_then(|p| p.error.clone())
            .unwrap_or_default();
        bail!("every point of the sweep failed; the first: {e}");
    }
    let col = result.column(metric)?;
    if let Some(set) = set {
        meid::io::write_atomic(&set.path("sweep.csv"), result.to_csv().as_bytes())?;
        meid::io::write_json(&set.path("sweep.json"), &result)?;
        picture(&result, col, set.staging())?;
        set.commit("sweep")?;
    }
    if a.print.json {
        crate::json::print(&result)?;
    } else if a.print.human() {
        summarise(&result, col);
        if a.output.is_none() {
            println!();
            print!("{}", result.to_csv());
        }
    }
    Ok(())
}

/// The best point of the metric and the failures, in words.
fn summarise(r: &NetSweepResult, col: usize) {
    let name = &r.columns[col];
    println!(
        "meid sweep — general machine, {} point(s) over {}; {} structure(s) built beyond the file's",
        r.points.len(),
        r.vary.iter().map(|v| v.path.as_str()).collect::<Vec<_>>().join(" × "),
        r.structures_built
    );
    let best = r
        .points
        .iter()
        .filter_map(|p| p.metrics[col].map(|v| (p, v)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((p, v)) = best {
        let at: Vec<String> = r
            .vary
            .iter()
            .zip(&p.values)
            .map(|(v, x)| format!("{} = {}", v.path, x.label()))
            .collect();
        println!("  lowest {name}: {v:.6e} at {}", at.join(", "));
    }
    let failed = r.points.iter().filter(|p| p.error.is_some()).count();
    if failed > 0 {
        println!("  {failed} point(s) failed (their error is in the table's last column)");
    }
}

fn numbers(v: &NetVary) -> Option<Vec<f64>> {
    v.values
        .iter()
        .map(|x| match x {
            NetValue::Number(n) => Some(*n),
            NetValue::Name(_) => None,
        })
        .collect()
}

/// sweep_curve (one numeric path) or sweep_map (two, both increasing): the metric's picture.
fn picture(r: &NetSweepResult, col: usize, dir: &std::path::Path) -> Result<()> {
    let name = &r.columns[col];
    let value = |i: usize| r.points[i].metrics[col].unwrap_or(f64::NAN);
    match r.vary.as_slice() {
        [v] => {
            let Some(x) = numbers(v) else { return Ok(()) };
            let plot = LinePlot {
                title: format!("{name} over {}", v.path),
                x_label: v.path.clone(),
                y_label: name.clone(),
                series: vec![Series {
                    label: name.clone(),
                    x,
                    y: (0..r.points.len()).map(value).collect(),
                    ..Default::default()
                }],
                ..Default::default()
            };
            line_plot(dir.join("sweep_curve"), &plot)?;
        }
        [v0, v1] => {
            let (Some(x), Some(y)) = (numbers(v1), numbers(v0)) else {
                return Ok(());
            };
            let increasing = |s: &[f64]| s.len() >= 2 && s.windows(2).all(|w| w[0] < w[1]);
            if !(increasing(&x) && increasing(&y)) {
                return Ok(());
            }
            // Grid order: v0 slowest, v1 fastest; z is row-major ny × nx (y = v0, x = v1).
            let map = HeatMap {
                title: format!("{name} over {} × {}", v1.path, v0.path),
                x_label: v1.path.clone(),
                y_label: v0.path.clone(),
                x,
                y,
                z: (0..r.points.len()).map(value).collect(),
                colorbar_label: name.clone(),
                ..Default::default()
            };
            heat_map(dir.join("sweep_map"), &map)?;
        }
        _ => {}
    }
    Ok(())
}
