//! `meid optimize`: the damper that minimises an objective (see `meid::analysis::study`).

use std::path::PathBuf;

use anyhow::{bail, Result};

use meid::analysis::study::{parse_bounds, Objective, OptimizeStudy};
use meid::analysis::sweep::Quantity;

use crate::args::{PrintArgs, SetArgs};
use crate::load;

#[derive(clap::Args)]
pub struct OptimizeArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Variables, comma-separated: wd/ws, wd/w_ref, ws/w_ref, md/mb or model field paths
    /// (e.g. contact.bed_damper.stiffness,damper.mass).
    #[arg(
        long,
        value_name = "PATH[,PATH...]",
        required_unless_present = "place",
        value_delimiter = ','
    )]
    over: Vec<String>,
    /// energy (E_p+/E_s− at the end of the collision), bed-accel or floor-force (peaks over
    /// the model's duration); for a general machine's --place also accel:POINT and
    /// contact-force:CONTACT.
    #[arg(long, value_name = "NAME", default_value = "energy")]
    objective: String,
    #[command(flatten)]
    place: crate::placement::PlaceArgs,
    /// Bounds of a variable, PATH=LO..HI (repeatable; PATH=LO:HI is accepted too). Positive
    /// bounds are searched in log scale; LO = HI holds the variable fixed.
    #[arg(long = "bounds", value_name = "PATH=LO..HI")]
    bounds: Vec<String>,
    #[command(flatten)]
    set: SetArgs,
    /// Simulation budget: at most this many simulations run (the grid, the local searches,
    /// the optimum's own run, the w_d = w_s comparison and the check of the optimum's 2n
    /// neighbours included); default the grid + 800; refused below the method's minimum
    /// (grid + 3 for one variable: the scan, one Brent step and those two; grid + n + 3 for
    /// n variables); the neighbour check runs when 2n more remain.
    #[arg(long, value_name = "N")]
    max_simulations: Option<usize>,
    /// Points per variable of the grid searched before the local refinement, both bounds
    /// included (N^n simulations for n variables; default 33 for one or two variables, 16 for
    /// three). A basin narrower than about two grid cells can be missed; a larger N costs N^n
    /// simulations.
    #[arg(long, value_name = "N")]
    grid: Option<usize>,
    /// Bed mass m_b (kg) for md/mb (default: the lumped mass at the bed contact point, the
    /// FE machine's bed plate, or a general FE model's elements labelled part = "bed"; see
    /// docs/explanations/studies.md).
    #[arg(long, value_name = "KG")]
    bed_mass: Option<f64>,
    /// Optimise for production at this stroke rate (blows/min): the objective on the steady
    /// blow of the periodic blow train, and only designs whose damper returns to the bed
    /// before every strike are feasible (docs/explanations/blows.md, "Production"). Default: the model's
    /// [production] rate_bpm, if it has one.
    #[arg(long, value_name = "R")]
    rate_bpm: Option<f64>,
    /// Write the report (optimize.json: variables, bounds, optimum, objective values) into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: OptimizeArgs) -> Result<()> {
    let general = meid::model::network::is_general_file(&a.model);
    if general || !a.place.place.is_empty() {
        if !a.over.is_empty() {
            bail!("--over: a general machine's optimisation chooses its dampers' places and masses (--place, --dampers, --total-mass or --mass-bounds); vary its fields with `meid sweep --vary`");
        }
        if !general {
            bail!("--place: a placement study takes a general machine ([[impactor]], [[damper]], [[contact]]); {} is the paper's machine", a.model.display());
        }
        return crate::placement::run(
            &a.model,
            &a.set.set,
            &a.objective,
            &a.place,
            a.rate_bpm,
            a.output.as_deref(),
            a.print,
        );
    }
    Objective::parse(&a.objective)?;
    let model = load(&a.model, &a.set.set, None, None, None)?;
    crate::warn_model(&model, &a.print);
    let over: Vec<Quantity> = a
        .over
        .iter()
        .map(|s| Quantity::parse(s))
        .collect::<meid::Result<_>>()?;
    let bounds = a
        .bounds
        .iter()
        .map(|s| parse_bounds(s))
        .collect::<meid::Result<Vec<_>>>()?;
    for (i, (q, _)) in bounds.iter().enumerate() {
        if !over.contains(q) {
            bail!("--bounds for {} which is not in --over", q.name());
        }
        if bounds[..i].iter().any(|(p, _)| p == q) {
            bail!(
                "--bounds {}: given twice; give each variable's bounds once",
                q.name()
            );
        }
    }
    let vars = over
        .into_iter()
        .map(|q| {
            let b = bounds.iter().find(|(p, _)| *p == q).map(|(_, b)| *b);
            (q, b)
        })
        .collect();
    if let Some(m) = a.bed_mass {
        if !(m.is_finite() && m > 0.0) {
            bail!("--bed-mass must be > 0 kg (got {m})");
        }
    }
    // The output set first: `-o FILE` is refused before the search.
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let model_rate = model.stroke_rate_bpm();
    let mut study =
        OptimizeStudy::with_bed_mass(model, vars, Objective::parse(&a.objective)?, a.bed_mass)?;
    // The stroke rate asked for, else the model's [production] rate_bpm: the operating
    // condition the design is judged at (none: the first blow from rest, the paper's study).
    if let Some(r) = a.rate_bpm.or(model_rate) {
        study = study.with_stroke_rate(r)?;
    }
    study.max_simulations = a.max_simulations;
    study.grid_points = a.grid;
    let t0 = std::time::Instant::now();
    let bar = crate::progress::bar(
        a.print.quiet || a.print.json,
        study.budget(),
        "simulations (budget)",
    );
    let rep = study.run_with_progress(&|done, _| bar.set_position(done as u64));
    bar.finish_and_clear();
    let rep = rep?;
    let elapsed = t0.elapsed().as_secs_f64();
    if let Some(set) = set {
        meid::io::write_json(
            &set.staging().join("optimize.json"),
            &crate::json::object(&rep)?,
        )?;
        set.commit("optimize")?;
    }
    if a.print.json {
        crate::json::print(&rep)?;
    }
    if a.print.human() {
        print_report(&a, &rep, elapsed);
    }
    Ok(())
}

/// The optimum in words and numbers, and how to reproduce it.
fn print_report(a: &OptimizeArgs, rep: &meid::analysis::study::OptimizeReport, elapsed: f64) {
    let n_free = rep.variables.iter().filter(|v| !v.fixed).count();
    let method = match n_free {
        0 => "every variable fixed".to_string(),
        1 => format!("{}-point scan + Brent", rep.grid_points_per_variable),
        _ => format!(
            "{} grid ({} simulations) + bounded Nelder-Mead from the best {} grid points",
            vec![rep.grid_points_per_variable.to_string(); n_free].join("×"),
            rep.grid_simulations,
            rep.local_searches
        ),
    };
    println!(
        "meid optimize — minimise {}{} ({method}; {} of at most {} simulations in {}{})",
        rep.metric,
        rep.rate_bpm.map_or(String::new(), |r| format!(
            " of the steady blow at {} blows/min",
            meid::num(r)
        )),
        rep.simulations,
        rep.max_simulations,
        if elapsed >= 0.1 {
            format!("{elapsed:.2} s")
        } else {
            format!("{:.2} ms", 1e3 * elapsed)
        },
        if rep.converged {
            ""
        } else {
            ", budget reached"
        }
    );
    for (v, x) in rep.variables.iter().zip(&rep.optimum) {
        if v.fixed {
            println!("  {:<32} {x:.6e}   (fixed: LO = HI)", v.quantity.name());
            continue;
        }
        println!(
            "  {:<32} {x:.6e}   (bounds {:.4e}..{:.4e}{})",
            v.quantity.name(),
            v.lower,
            v.upper,
            if v.log { ", log" } else { "" }
        );
    }
    println!(
        "  objective at the optimum          {:.6e}",
        rep.objective_value
    );
    println!("  what it is: {}", rep.local_check.statement);
    println!(
        "  w_d/w_s at the optimum            {:.6}",
        rep.wd_over_ws_at_optimum
    );
    // +0.00, never -0.00, when the rule is the optimum (to rounding).
    let rule_pct = 100.0 * (rep.objective_at_wd_equal_ws / rep.objective_value - 1.0);
    let rule_pct = if rule_pct.abs() < 0.005 {
        0.0
    } else {
        rule_pct
    };
    println!(
        "  objective with w_d = w_s (paper)  {:.6e}  ({:+.2} % vs optimum)",
        rep.objective_at_wd_equal_ws, rule_pct
    );
    let mut reproduce = format!("meid simulate {}", a.model.display());
    for s in a.set.set.iter().chain(&rep.overrides) {
        reproduce.push_str(&format!(" --set {s}"));
    }
    println!("  reproduce: {reproduce}");
    if rep.failures > 0 {
        println!("  failed simulations                {}", rep.failures);
    }
    if let (Some(rate), Some(st)) = (rep.rate_bpm, &rep.steady_state) {
        println!(
            "  at {} blows/min (steady blow)     {}, damper {}; {} design(s) refused: their damper does not return",
            meid::num(rate),
            st.regime.name(),
            match st.damper_touches_bed {
                Some(true) => "touches the bed before every strike",
                Some(false) => "does not return",
                None => "absent",
            },
            rep.infeasible.unwrap_or(0)
        );
    }
    if let Some(dir) = &a.output {
        println!("  wrote {}", dir.join("optimize.json").display());
    }
}
