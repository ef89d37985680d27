//! `meid blows --vary`: the damper-return design map at the stroke rate (see
//! `meid::analysis::return_map`).

use std::path::Path;

use anyhow::Result;
use meid::analysis::return_map::{return_map, ReturnMap};
use meid::analysis::steady::SteadyOptions;
use meid::analysis::sweep::Vary;
use meid::model::Model;
use meid::plot::{self, HeatMap, LinePlot, Marker, Series};

use crate::args::PrintArgs;

/// Runs the map of `specs` (one or two `--vary` specs) at `rate_bpm`, prints it and writes
/// return-map.csv, return-map.json and its picture into `output`.
pub fn run(
    model_path: &Path,
    model: &Model,
    specs: &[String],
    rate_bpm: f64,
    output: Option<&Path>,
    print: &PrintArgs,
) -> Result<()> {
    let vary: Vec<Vary> = specs
        .iter()
        .map(|s| Vary::parse(s))
        .collect::<meid::Result<_>>()?;
    let so = SteadyOptions {
        rate_bpm,
        ..SteadyOptions::default()
    };
    let total: usize = vary.iter().map(|v| v.values.len()).product();
    let bar = crate::progress::bar(print.quiet || print.json, total, "designs");
    let map = return_map(model, &vary, None, &so, &|done, _| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let map = map?;
    let sentence = summary(&map);
    let out = serde_json::json!({
        "model": model_path.display().to_string(),
        "summary": sentence,
        "return_map": map,
    });
    if let Some(dir) = output {
        let set = crate::outputs::begin(dir)?;
        let staging = set.staging();
        meid::io::write_json(
            &staging.join("return-map.json"),
            &crate::json::object(&out)?,
        )?;
        meid::io::write_atomic(&staging.join("return-map.csv"), map.csv().as_bytes())?;
        picture(&staging.join("return-map"), &map)?;
        set.commit("blows --vary")?;
    }
    if print.json {
        crate::json::print(&out)?;
    } else if print.human() {
        print_map(&map, &sentence);
    }
    Ok(())
}

/// The map's answer in words: how many designs return, and the best of them.
fn summary(map: &ReturnMap) -> String {
    let n = map.cells.len();
    let rate = meid::num(map.rate_bpm);
    match map.best_returning.map(|i| &map.cells[i]) {
        None => format!(
            "At {rate} blows/min the damper touches the bed in every steady blow in none of the {n} designs: give a weaker dashpot or a stiffer spring (a smaller c_d/k_d), or a lower stroke rate."
        ),
        Some(c) => {
            let at: Vec<String> = map
                .quantities
                .iter()
                .zip(&c.values)
                .map(|(q, v)| format!("{q} = {}", short(*v)))
                .collect();
            format!(
                "At {rate} blows/min the damper touches the bed in every steady blow in {} of the {n} designs ({} robust: their grid neighbours return too); the lowest steady floor force among the {} is at {}: {} dB against the machine without a damper (bed acceleration {} dB){}.",
                map.returning,
                map.robust,
                if c.robust { "robust ones" } else { "returning ones" },
                at.join(", "),
                fmt_db(c.floor_force_change_db),
                fmt_db(c.bed_acceleration_change_db),
                if c.robust {
                    ""
                } else {
                    "; none is robust, so refine the grid around it before trusting it"
                }
            )
        }
    }
}

/// `v` to 7 significant digits, shortest form (1000, not 999.9999999999998 from a log range).
fn short(v: f64) -> String {
    let r: f64 = format!("{v:.6e}").parse().unwrap_or(v);
    meid::num(r)
}

fn fmt_db(v: f64) -> String {
    if v.is_finite() {
        format!("{v:+.2}")
    } else {
        "—".into()
    }
}

fn print_map(map: &ReturnMap, sentence: &str) {
    println!(
        "meid blows — damper-return map at {} blows/min over {}",
        meid::num(map.rate_bpm),
        map.quantities.join(" × ")
    );
    println!("  {sentence}");
    let names: Vec<String> = map.quantities.iter().map(|q| format!("{q:>22}")).collect();
    println!(
        "  {}  returns  robust  regime      gap (mm)  floor (dB)  accel (dB)",
        names.join("  ")
    );
    for c in &map.cells {
        let vals: Vec<String> = c.values.iter().map(|v| format!("{v:>22.6e}")).collect();
        match &c.error {
            Some(e) => println!("  {}  failed: {e}", vals.join("  ")),
            None => println!(
                "  {}  {:>7}  {:>6}  {:<10}  {:>8}  {:>10}  {:>10}",
                vals.join("  "),
                if c.returns { "yes" } else { "no" },
                if c.robust { "yes" } else { "no" },
                c.regime.as_deref().unwrap_or("—"),
                c.damper_gap_at_strike_m
                    .map_or("—".into(), |g| format!("{:.4}", 1e3 * g)),
                fmt_db(c.floor_force_change_db),
                fmt_db(c.bed_acceleration_change_db)
            ),
        }
    }
}

/// One quantity: the dB changes against it, a marker where returning changes; two: the floor
/// force's dB change as a map, with the boundary of the return region drawn over it.
fn picture(stem: &Path, map: &ReturnMap) -> Result<()> {
    let log = |v: &[f64]| {
        v.len() > 2 && v.iter().all(|x| *x > 0.0) && {
            let r = v[1] / v[0];
            v.windows(2).all(|w| ((w[1] / w[0]) / r - 1.0).abs() < 1e-6)
        }
    };
    let title = format!(
        "steady floor force at {} blows/min against no damper (dB; negative: better)",
        meid::num(map.rate_bpm)
    );
    // The axes that vary (a quantity given one value is a constant of the map).
    let varied: Vec<usize> = (0..map.axes.len())
        .filter(|&k| map.axes[k].len() > 1)
        .collect();
    if varied.len() == 1 {
        let k = varied[0];
        let x = map.axes[k].clone();
        let mut markers = Vec::new();
        for w in map.cells.windows(2) {
            if w[0].returns != w[1].returns {
                markers.push(Marker {
                    x: (w[0].values[k] * w[1].values[k]).abs().sqrt(),
                    label: if w[1].returns {
                        "returns from here".into()
                    } else {
                        "stops returning".into()
                    },
                });
            }
        }
        let series = |label: &str, y: Vec<f64>| Series {
            label: label.into(),
            x: x.clone(),
            y,
            ..Default::default()
        };
        plot::line_plot(
            stem,
            &LinePlot {
                title,
                x_label: map.quantities[k].clone(),
                y_label: "change (dB)".into(),
                x_log: log(&x),
                series: vec![
                    series(
                        "floor force",
                        map.cells.iter().map(|c| c.floor_force_change_db).collect(),
                    ),
                    series(
                        "bed acceleration",
                        map.cells
                            .iter()
                            .map(|c| c.bed_acceleration_change_db)
                            .collect(),
                    ),
                ],
                markers,
                ..LinePlot::default()
            },
        )?;
        return Ok(());
    }
    if varied.len() != 2 {
        return Ok(());
    }
    // x: the first quantity, y: the second; cells are row-major with the first slowest.
    let (x, y) = (map.axes[0].clone(), map.axes[1].clone());
    let (nx, ny) = (x.len(), y.len());
    let field = |f: &dyn Fn(&meid::analysis::return_map::ReturnCell) -> f64| -> Vec<f64> {
        (0..nx * ny)
            .map(|k| f(&map.cells[(k % nx) * ny + k / nx]))
            .collect()
    };
    let z = field(&|c| c.floor_force_change_db);
    let indicator = field(&|c| if c.returns { 1.0 } else { -1.0 });
    let (xl, yl) = (log(&x), log(&y));
    let coord = |v: &[f64], l: bool| -> Vec<f64> {
        v.iter().map(|a| if l { a.ln() } else { *a }).collect()
    };
    let segments =
        meid::plot::contour::marching_squares(&coord(&x, xl), &coord(&y, yl), &indicator, 0.0)?;
    let back = |a: f64, l: bool| if l { a.exp() } else { a };
    let overlay_lines = segments
        .iter()
        .enumerate()
        .map(|(k, s)| Series {
            label: if k == 0 {
                "edge of the return region (± half a cell)".into()
            } else {
                String::new()
            },
            x: vec![back(s[0].0, xl), back(s[1].0, xl)],
            y: vec![back(s[0].1, yl), back(s[1].1, yl)],
            style: plot::LineStyle::Solid,
            color: Some([255, 255, 255]),
            width: 3,
        })
        .collect();
    plot::heat_map(
        stem,
        &HeatMap {
            title,
            x_label: map.quantities[0].clone(),
            y_label: map.quantities[1].clone(),
            x,
            y,
            z,
            x_log: xl,
            y_log: yl,
            overlay_lines,
            colorbar_label: "floor force change (dB)".into(),
            ..HeatMap::default()
        },
    )?;
    Ok(())
}
