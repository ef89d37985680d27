//! `meid optimize GENERAL.toml --place POINTS --dampers N|LO..HI`: where a general machine's
//! dampers go, how many and how heavy (`meid::analysis::placement`).

use std::path::Path;

use anyhow::{bail, Result};

use meid::analysis::placement::{
    MassRule, NetObjective, PlacedResult, PlacementReport, PlacementStudy, Search,
};
use meid::model::network::NetworkModel;

use crate::args::PrintArgs;

#[derive(clap::Args, Debug, Clone, Default)]
pub struct PlaceArgs {
    /// General machine: the candidate structure points for dampers, comma-separated (e.g.
    /// D1,D2,D3,D4); the dampers placed are copies of --template scaled to their mass.
    #[arg(long, value_name = "POINT[,POINT...]", value_delimiter = ',')]
    pub place: Vec<String>,
    /// With --place: the number of dampers, N or LO..HI (default 1).
    #[arg(long, value_name = "N|LO..HI", requires = "place")]
    pub dampers: Option<String>,
    /// With --place: the total damper mass (kg), M/n to each of n dampers (default: the
    /// file's dampers' total).
    #[arg(
        long,
        value_name = "KG",
        requires = "place",
        conflicts_with = "mass_bounds"
    )]
    pub total_mass: Option<f64>,
    /// With --place: every damper's mass free in LO..HI kg, chosen per placement by the
    /// bounded Nelder-Mead search.
    #[arg(long, value_name = "LO..HI", requires = "place")]
    pub mass_bounds: Option<String>,
    /// With --place: the [[damper]] copied to every place (default: the file's first).
    #[arg(long, value_name = "NAME", requires = "place")]
    pub template: Option<String>,
    /// With --place: a point may carry several dampers.
    #[arg(long, requires = "place")]
    pub repeat: bool,
    /// With --place: exhaustive (every placement), heuristic (greedy + swap) or auto
    /// (exhaustive within --max-combinations).
    #[arg(long, value_name = "HOW", default_value = "auto")]
    pub search: String,
    /// With --place: the most placements an exhaustive search evaluates.
    #[arg(long, value_name = "N", default_value_t = 256)]
    pub max_combinations: usize,
    /// With --mass-bounds: simulations per placement for its masses.
    #[arg(long, value_name = "N", default_value_t = 40)]
    pub mass_evaluations: usize,
}

/// `N` or `LO..HI`, counts of dampers.
fn parse_counts(s: &str) -> Result<(usize, usize)> {
    let bad =
        || anyhow::anyhow!("--dampers `{s}`: give N or LO..HI (whole numbers ≥ 1), e.g. 1..4");
    let (lo, hi) = match s.split_once("..") {
        Some((a, b)) => (
            a.trim().parse().map_err(|_| bad())?,
            b.trim().parse().map_err(|_| bad())?,
        ),
        None => {
            let n = s.trim().parse().map_err(|_| bad())?;
            (n, n)
        }
    };
    Ok((lo, hi))
}

/// The study of the arguments.
fn study(
    model: NetworkModel,
    objective: &str,
    p: &PlaceArgs,
    rate_bpm: Option<f64>,
) -> Result<PlacementStudy> {
    let masses = match (&p.mass_bounds, p.total_mass) {
        (Some(b), _) => {
            let (lo, hi) = meid::analysis::study::parse_range(b).map_err(|_| {
                anyhow::anyhow!("--mass-bounds `{b}`: give LO..HI in kg, e.g. 0.5..2")
            })?;
            MassRule::Free {
                lower: lo,
                upper: hi,
            }
        }
        (None, Some(t)) => MassRule::Total(t),
        (None, None) => MassRule::Total(model.spec.damper.iter().map(|d| d.mass).sum()),
    };
    let template = match &p.template {
        Some(t) => t.clone(),
        None => match model.spec.damper.first() {
            Some(d) => d.name.clone(),
            None => bail!(
                "--place: the file has no [[damper]] to copy to the places (--template names one)"
            ),
        },
    };
    let study = PlacementStudy {
        template,
        candidates: p.place.iter().map(|s| s.trim().to_string()).collect(),
        counts: parse_counts(p.dampers.as_deref().unwrap_or("1"))?,
        repeat: p.repeat,
        masses,
        objective: NetObjective::parse(objective)?,
        search: Search::parse(&p.search)?,
        max_combinations: p.max_combinations,
        mass_evaluations: p.mass_evaluations,
        rate_bpm,
        model,
    };
    study.check()?;
    Ok(study)
}

pub fn run(
    path: &Path,
    set: &[String],
    objective: &str,
    p: &PlaceArgs,
    rate_bpm: Option<f64>,
    output: Option<&Path>,
    print: PrintArgs,
) -> Result<()> {
    let model = NetworkModel::from_file(path, set)?;
    // The operating condition: --rate-bpm, else the file's [production] rate_bpm.
    let rate_bpm = match rate_bpm {
        Some(r) => Some(meid::analysis::network_blows::stroke_rate(&model, Some(r))?),
        None => model.spec.production.as_ref().map(|p| p.rate_bpm),
    };
    let study = study(model, objective, p, rate_bpm)?;
    let out = output.map(crate::outputs::begin).transpose()?;
    let rep = study.run()?;
    if let Some(set) = out {
        meid::io::write_json(&set.path("optimize.json"), &rep)?;
        set.commit("optimize")?;
    }
    if print.json {
        crate::json::print(&rep)?;
    } else if print.human() {
        print_report(&rep, output);
    }
    Ok(())
}

fn line(r: &PlacedResult) -> String {
    let masses: Vec<String> = r.masses_kg.iter().map(|m| format!("{m:.4}")).collect();
    format!(
        "{} at [{}], masses [{}] kg: {}{}",
        r.dampers,
        r.points.join(", "),
        masses.join(", "),
        match (r.objective, r.dampers_return) {
            (Some(f), _) => format!("{f:.6e}"),
            (None, Some(false)) => "infeasible".to_string(),
            (None, _) => "failed".to_string(),
        },
        match r.dampers_return {
            Some(true) => ", every damper returns",
            Some(false) => ", a damper does NOT return between blows",
            None => "",
        }
    )
}

fn print_report(r: &PlacementReport, output: Option<&Path>) {
    println!(
        "meid optimize — general machine: minimise {}{} over the places of {} among {} ({}: {} placements of {} evaluated, {} simulations)",
        r.objective,
        r.rate_bpm.map_or(" (first blow)".to_string(), |b| format!(
            " of the steady blow at {b} /min"
        )),
        r.template,
        r.candidates.join(", "),
        r.search,
        r.placements.len(),
        r.combinations,
        r.simulations
    );
    println!("  best            {}", line(&r.best));
    if let Some(n) = r.infeasible.filter(|n| *n > 0) {
        println!(
            "  refused         {n} of {} simulations: a damper does not return between blows",
            r.simulations
        );
    }
    for b in &r.best_per_count {
        println!("  best of {:<7} {}", b.dampers, line(b));
    }
    for (i, u) in r.runner_ups.iter().enumerate() {
        println!("  runner-up {}     {}", i + 1, line(u));
    }
    for n in &r.notes {
        println!("note: {n}");
    }
    if let Some(dir) = output {
        println!("  wrote {}", dir.join("optimize.json").display());
    }
}
