//! `meid correlate`: identified modes against the model's (thin: the library maps, computes
//! the MAC, pairs and draws).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use meid::measure::correlate::{
    correlate, geometry_uff, read_identified, Mapping, ModelModes, Settings,
};
use meid::model::fem;

use crate::args::PrintArgs;

/// How measured points map to the model's points (shared with `calibrate --modal`).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct MappingArgs {
    /// Map a measured point (its label, e.g. 'bed:1 +Z', or its entity) to a model point:
    /// LABEL=POINT, comma-separated (repeatable). Unmapped points map by name: their entity or
    /// node number naming a model point.
    #[arg(long = "map", value_name = "LABEL=POINT[,…]")]
    pub map: Vec<String>,
    /// Map by coordinates instead: the measured nodes' coordinates (m) in this UFF file
    /// (dataset 15 or 2411), each to the nearest model point within --tolerance.
    #[arg(long, value_name = "FILE.uff")]
    pub geometry: Option<PathBuf>,
    /// Distance (m) within which a measured node maps to a model point (with --geometry).
    #[arg(long, value_name = "M", default_value_t = 1e-3, requires = "geometry")]
    pub tolerance: f64,
    /// Smallest MAC of a pair of modes.
    #[arg(long, value_name = "MAC", default_value_t = 0.5)]
    pub min_mac: f64,
}

impl MappingArgs {
    /// The library's mapping.
    pub fn mapping(&self) -> Result<Mapping> {
        let mut explicit = BTreeMap::new();
        for item in &self.map {
            for m in item.split(',') {
                let Some((label, point)) = m.split_once('=') else {
                    bail!("--map {m}: give LABEL=POINT, e.g. --map 'bed:1 +Z=bed'");
                };
                explicit.insert(label.trim().to_string(), point.trim().to_string());
            }
        }
        if !(self.min_mac.is_finite() && (0.0..=1.0).contains(&self.min_mac)) {
            bail!("--min-mac {}: give a MAC in 0..1", self.min_mac);
        }
        let geometry = match &self.geometry {
            None => None,
            Some(path) => {
                if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
                    bail!("--tolerance {}: give a distance ≥ 0 in m", self.tolerance);
                }
                let u = meid::io::uff::read_uff(path)?;
                if u.nodes.is_empty() {
                    bail!(
                        "{}: no node (UFF dataset 15 or 2411): --geometry needs the measured nodes' coordinates",
                        path.display()
                    );
                }
                let nodes = u.nodes.iter().map(|n| (n.label, n.xyz)).collect();
                Some((path.display().to_string(), nodes, self.tolerance))
            }
        };
        Ok(Mapping { explicit, geometry })
    }
}

#[derive(clap::Args)]
pub struct CorrelateArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Identified modes: meid identify's JSON (--json or identification.json), modes.csv, or
    /// a UFF file of datasets 55 (modes.uff).
    #[arg(long = "modes", value_name = "IDENTIFIED")]
    modes: PathBuf,
    #[command(flatten)]
    mapping: MappingArgs,
    /// Off-diagonal auto-MAC above which the measured points are called blind.
    #[arg(long, value_name = "MAC", default_value_t = 0.9)]
    blind_mac: f64,
    /// Compare the lowest N model modes (default: all the model retains); more than the
    /// measured points is an error.
    #[arg(long, value_name = "N")]
    model_modes: Option<usize>,
    /// Override a model field, e.g. --set structure.lumped.springs[0].stiffness=2e7 (repeatable).
    #[arg(long = "set", value_name = "PATH=VALUE")]
    set: Vec<String>,
    /// Write correlation.json, pairs.csv, mac.csv, auto_mac.csv, mac.png/.svg,
    /// auto_mac.png/.svg and geometry.uff (the model's points as UFF 15 nodes, an 82 trace
    /// line, 2412 rods and its modes as datasets 55, for test-lab viewers) into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    #[command(flatten)]
    print: PrintArgs,
}

/// The model's named points' coordinates: an FE model's at the mean of each point's nodes;
/// `None` for a model without a mesh.
pub fn point_coordinates(an: Option<&fem::FemAnalysis>) -> Option<BTreeMap<String, [f64; 3]>> {
    let mesh = &an?.model.mesh;
    let mut out = BTreeMap::new();
    for (name, nodes) in &mesh.points {
        let xyz: Vec<[f64; 3]> = nodes
            .iter()
            .filter_map(|&k| mesh.nodes.get(k).copied())
            .collect();
        if xyz.is_empty() {
            continue;
        }
        let n = xyz.len() as f64;
        let mean = |a: usize| xyz.iter().map(|p| p[a]).sum::<f64>() / n;
        out.insert(name.clone(), [mean(0), mean(1), mean(2)]);
    }
    Some(out)
}

/// Loads the model (with its FE analysis, for the points' coordinates).
pub fn load(path: &Path, set: &[String]) -> Result<(meid::model::Model, ModelModes)> {
    let (model, analysis) = fem::from_file_with_analysis(path, set, None)?;
    let mm = ModelModes::new(&model, point_coordinates(analysis.as_ref()));
    Ok((model, mm))
}

pub fn run(a: CorrelateArgs) -> Result<()> {
    if !(a.blind_mac.is_finite() && (0.0..=1.0).contains(&a.blind_mac)) {
        bail!("--blind-mac {}: give a MAC in 0..1", a.blind_mac);
    }
    let mapping = a.mapping.mapping()?;
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    let (model, mm) = load(&a.model, &a.set)?;
    crate::warn_model(&model, &a.print);
    let ident = read_identified(&a.modes)?;
    let settings = Settings {
        min_mac: a.mapping.min_mac,
        blind_mac: a.blind_mac,
        model_modes: a.model_modes,
        by_frequency: false,
    };
    let mut c = correlate(&ident, &mm, &mapping, &settings)?;
    if let Some(set) = set {
        let dir = set.staging();
        meid::io::write_json(&set.path("correlation.json"), &crate::json::object(&c)?)?;
        meid::io::write_atomic(&dir.join("pairs.csv"), c.pairs_csv().as_bytes())?;
        let csv = meid::measure::correlate::Correlation::matrix_csv;
        meid::io::write_atomic(&dir.join("mac.csv"), csv(&c.mac, "identified").as_bytes())?;
        meid::io::write_atomic(
            &dir.join("auto_mac.csv"),
            csv(&c.auto_mac, "model").as_bytes(),
        )?;
        let notes = c.plots(dir)?;
        c.notes.extend(notes);
        meid::io::write_atomic(&dir.join("geometry.uff"), &geometry_uff(&model, &mm)?)?;
        set.commit("correlate")?;
    }
    if !a.print.quiet {
        for w in &c.warnings {
            crate::ui::warning(w);
        }
    }
    if a.print.json {
        crate::json::print(&c)?;
    } else if a.print.human() {
        println!(
            "{} — {}",
            crate::ui::bold("meid correlate"),
            model.spec.name.as_deref().unwrap_or("model")
        );
        print!("{}", c.to_text());
        if let Some(dir) = &a.output {
            println!("wrote {}", dir.display());
        }
    }
    Ok(())
}
