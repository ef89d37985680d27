//! `meid modes`: modal analysis of the model's structure (thin: the library builds the report,
//! the VTK and the Matrix Market files).

use std::path::PathBuf;

use anyhow::Result;

use meid::io;
use meid::model::fem;

use crate::args::PrintArgs;

#[derive(clap::Args)]
pub struct ModesArgs {
    /// Model file (TOML).
    model: PathBuf,
    /// Write modes.csv, modes.json, truncation.csv, modes.vtu + modes.pvd, model_sketch.png/.svg
    /// (the mesh with the model's points) and mode_<n>.png/.svg of the selected modes (FE models)
    /// into DIR.
    #[arg(short, long, value_name = "DIR")]
    output: Option<PathBuf>,
    /// Number of lowest modes to compute and show (FE models).
    #[arg(long, value_name = "N")]
    count: Option<usize>,
    /// Also write the reduced stiffness and mass matrices as K.mtx and M.mtx (needs -o).
    #[arg(long)]
    export_matrices: bool,
    /// Also write DIR/modes.uff: units (UFF dataset 164, SI), nodes (2411) and one dataset 55 per mode
    /// (mass-normalised shapes), for test-lab tools (needs -o). Lumped/tabulated models: node k
    /// is the k-th named point by name, as the psi columns of modes.csv (docs/explanations/measure.md).
    #[arg(long, requires = "output")]
    uff: bool,
    /// Override a model field, e.g. --set structure.fem.machine.elements_per_side=12 (repeatable).
    #[arg(long = "set", value_name = "PATH=VALUE")]
    set: Vec<String>,
    #[command(flatten)]
    print: PrintArgs,
}

pub fn run(a: ModesArgs) -> Result<()> {
    if a.count == Some(0) {
        anyhow::bail!("--count must be at least 1");
    }
    if a.export_matrices && a.output.is_none() {
        anyhow::bail!("--export-matrices needs an output directory (-o DIR)");
    }
    // The output set first: `-o FILE` is refused before the solve.
    let set = a.output.as_deref().map(crate::outputs::begin).transpose()?;
    // One build and one solve: the analysis the model's modes came from.
    let (model, analysis) = fem::from_file_with_analysis(&a.model, &a.set, a.count)?;
    let report = match &analysis {
        Some(an) => an.report()?,
        None => fem::report_from_modal(&model.structure),
    }
    .with_diagnostics(model.diagnostics());
    if !a.print.quiet {
        for w in &report.warnings {
            crate::ui::warning(w);
        }
    }
    if a.print.json {
        crate::json::print(&report)?;
    } else if a.print.human() {
        print!("{}", report.to_text());
    }
    if let (Some(out), Some(set)) = (&a.output, set) {
        let dir = set.staging();
        io::write_atomic(&dir.join("modes.csv"), report.to_csv().as_bytes())?;
        io::write_atomic(
            &dir.join("truncation.csv"),
            meid::modal::truncation::to_csv(&report.truncation).as_bytes(),
        )?;
        io::write_json(&dir.join("modes.json"), &report)?;
        if let Some(an) = &analysis {
            let which: Vec<usize> = (0..an.modes.omega_rad_per_s.len()).collect();
            let vtu = io::vtk::modes_vtu(&an.model, &an.modes, &which)?;
            io::write_atomic(&dir.join("modes.vtu"), vtu.as_bytes())?;
            io::write_atomic(&dir.join("modes.pvd"), io::vtk::pvd("modes.vtu").as_bytes())?;
            // The model's points on its mesh, then the selected modes (paper Figs. 2 and 15).
            let (points, notes) = meid::report::sketch::paper_points(&model.spec);
            let title = match model.spec.name.as_deref() {
                Some(n) => format!("model sketch: {n}"),
                None => "model sketch".into(),
            };
            let sketch = meid::report::sketch::sketch_of_fe(&an.model, &title, &points, notes)?;
            meid::plot::mesh::sketch_plot(dir.join("model_sketch"), &sketch)?;
            let edges = io::vtk::mesh_edges(&an.model);
            for &i in &an.selected {
                let plot = meid::plot::mesh::MeshPlot {
                    title: format!(
                        "mode {}, {:.2} Hz",
                        i + 1,
                        an.modes.omega_rad_per_s[i] / (2.0 * std::f64::consts::PI)
                    ),
                    nodes: an.model.mesh.nodes.clone(),
                    edges: edges.clone(),
                    displacement: io::vtk::mode_translations(&an.model, &an.modes, i)?,
                };
                meid::plot::mesh::mesh_plot(dir.join(format!("mode_{}", i + 1)), &plot)?;
            }
            if a.export_matrices {
                io::matrix_market::write_symmetric(
                    &dir.join("K.mtx"),
                    an.model.stiffness.as_ref(),
                )?;
                io::matrix_market::write_symmetric(&dir.join("M.mtx"), an.model.mass.as_ref())?;
            }
        } else if a.export_matrices {
            anyhow::bail!("--export-matrices needs a [structure.fem] model");
        }
        if a.uff {
            let bytes = match &analysis {
                Some(an) => {
                    // Damping ratios of the retained modes, D_kk/(2ω_k), at their indices.
                    let st = &model.structure;
                    let n = st.omega_rad_per_s.len();
                    let mut zeta = vec![0.0; an.modes.omega_rad_per_s.len()];
                    for (k, &j) in an.selected.iter().enumerate() {
                        let w = st.omega_rad_per_s.get(k).copied().unwrap_or(0.0);
                        if let (Some(z), true) = (zeta.get_mut(j), w > 0.0) {
                            *z = st.damping.get(k * n + k).copied().unwrap_or(0.0) / (2.0 * w);
                        }
                    }
                    io::uff::modes_uff_fe(&an.model, &an.modes, &zeta)?
                }
                None => io::uff::modes_uff_points(&model.structure)?,
            };
            io::write_atomic(&dir.join("modes.uff"), &bytes)?;
        }
        set.commit("modes")?;
        if a.print.human() {
            println!("wrote {}", out.display());
        }
    }
    Ok(())
}
