//! The model sketch (issue 34 item 8): the user's own FE mesh, undeformed, with the model's
//! points marked by role — the strike (an arrow along the blow), the dampers (joined to their
//! anchors), the measurement points and the floor (supports and springs/dashpots to ground).
//! Drawn by [`crate::plot::mesh::sketch_plot`] in the mesh pictures' projection
//! ([`crate::plot::mesh::project`]). Lumped and tabulated structures have no mesh: no sketch.

use std::path::Path;

use crate::model::fem;
use crate::model::network::{NetworkModel, NetworkSpec};
use crate::model::{Model, ModelSpec, StructureSpec};
use crate::plot::mesh::{SketchMark, SketchPlot, SketchRole};
use crate::plot::PlotFiles;
use crate::structure::FeModel;
use crate::{Error, Result};

/// One named point to mark: its role, its label and the mesh point it is at; a damper names
/// the mesh point of its anchor (`None`: anchored to the ground).
#[derive(Debug, Clone, PartialEq)]
pub struct NamedPoint {
    pub role: SketchRole,
    pub label: String,
    pub point: String,
    pub anchor: Option<String>,
}

/// The points of a paper-form model (`[points]`): the strike and the damper at `bed_contact`,
/// the anchor at `damper_anchor` (unless "ground"), the measurement point; with the notes for
/// the key (a ground anchor, a foundation block).
pub fn paper_points(spec: &ModelSpec) -> (Vec<NamedPoint>, Vec<String>) {
    let p = &spec.points;
    let anchor = p.damper_anchor.clone().filter(|a| a != "ground");
    let mut out = vec![NamedPoint {
        role: SketchRole::Strike,
        label: format!("strike {} (slider)", p.bed_contact),
        point: p.bed_contact.clone(),
        anchor: None,
    }];
    let mut notes = Vec::new();
    if spec.damper.is_some() {
        out.push(NamedPoint {
            role: SketchRole::Damper,
            label: format!("damper at {}", p.bed_contact),
            point: p.bed_contact.clone(),
            anchor: anchor.clone(),
        });
        if anchor.is_none() {
            notes.push("the damper is anchored to the ground (points.damper_anchor)".into());
        }
    }
    out.push(NamedPoint {
        role: SketchRole::Measurement,
        label: format!("measurement {}", p.measurement),
        point: p.measurement.clone(),
        anchor: None,
    });
    if spec.foundation.is_some() {
        notes.push(
            "the floor stands on the foundation block of [foundation] (not drawn; see the report's Foundation section)"
                .into(),
        );
    }
    (out, notes)
}

/// The points of a general machine: a strike at each structure point an `[[impactor]]` hits
/// (`[[contact]] between = [impactor, point]`), each `[[damper]]` at its point joined to its
/// anchor (unless "ground").
pub fn network_points(spec: &NetworkSpec) -> (Vec<NamedPoint>, Vec<String>) {
    let is_body = |n: &str| {
        n == "ground"
            || spec.impactor.iter().any(|b| b.name == n)
            || spec.damper.iter().any(|d| d.name == n)
    };
    let mut out = Vec::new();
    let mut notes = Vec::new();
    for c in &spec.contact {
        if let [a, b] = c.between.as_slice() {
            if spec.impactor.iter().any(|i| &i.name == a) && !is_body(b) {
                out.push(NamedPoint {
                    role: SketchRole::Strike,
                    label: format!("strike {b} ({a})"),
                    point: b.clone(),
                    anchor: None,
                });
            }
        }
    }
    for d in &spec.damper {
        let anchor = (d.anchor != "ground").then(|| d.anchor.clone());
        if anchor.is_none() {
            notes.push(format!("{} is anchored to the ground", d.name));
        }
        out.push(NamedPoint {
            role: SketchRole::Damper,
            label: format!("damper {} at {}", d.name, d.point),
            point: d.point.clone(),
            anchor,
        });
    }
    (out, notes)
}

/// The mean position (m) of a named point's node set.
fn point_position(fe: &FeModel, name: &str) -> Result<[f64; 3]> {
    let nodes = fe.mesh.points.get(name).filter(|n| !n.is_empty());
    let Some(nodes) = nodes else {
        let known: Vec<&str> = fe.mesh.points.keys().map(|s| s.as_str()).collect();
        return Err(Error::invalid(
            "model sketch",
            format!(
                "point '{name}' is not a named point of the mesh; valid: {}",
                known.join(", ")
            ),
        ));
    };
    let mut sum = [0.0; 3];
    for &n in nodes {
        let p = fe.mesh.nodes.get(n).ok_or_else(|| {
            Error::invalid(
                "model sketch",
                format!("point '{name}': node {n} is not in the mesh"),
            )
        })?;
        for d in 0..3 {
            sum[d] += p[d];
        }
    }
    let k = nodes.len() as f64;
    Ok([sum[0] / k, sum[1] / k, sum[2] / k])
}

/// Where the machine meets the ground: the nodes with a fixed translation (supports), and the
/// nodes of springs and dashpots to ground; one mark per kind.
fn floor_marks(fe: &FeModel) -> Vec<SketchMark> {
    let mesh = &fe.mesh;
    let mut supports: Vec<usize> = mesh.fixed.iter().map(|d| d / 6).collect();
    supports.dedup();
    let mut springs: Vec<usize> = mesh
        .springs
        .iter()
        .filter(|s| s.other.is_none())
        .map(|s| s.node)
        .chain(
            mesh.dashpots
                .iter()
                .filter(|d| d.other.is_none())
                .map(|d| d.node),
        )
        .collect();
    springs.sort_unstable();
    springs.dedup();
    let mut out = Vec::new();
    for (nodes, what) in [(supports, "supports"), (springs, "springs to ground")] {
        let positions: Vec<[f64; 3]> = nodes
            .iter()
            .filter_map(|&n| mesh.nodes.get(n).copied())
            .collect();
        if !positions.is_empty() {
            out.push(SketchMark {
                role: SketchRole::Floor,
                label: format!("floor: {} {what}", positions.len()),
                positions_m: positions,
                joined_to: None,
            });
        }
    }
    out
}

/// The sketch of an FE model with `points` marked (see [`paper_points`], [`network_points`]).
pub fn sketch_of_fe(
    fe: &FeModel,
    title: &str,
    points: &[NamedPoint],
    notes: Vec<String>,
) -> Result<SketchPlot> {
    let mut marks: Vec<SketchMark> = Vec::new();
    let mut anchors: Vec<(String, usize)> = Vec::new();
    for p in points {
        let joined_to = match &p.anchor {
            Some(a) => match anchors.iter().find(|(n, _)| n == a) {
                Some((_, i)) => Some(*i),
                None => {
                    marks.push(SketchMark {
                        role: SketchRole::Anchor,
                        label: format!("anchor {a}"),
                        positions_m: vec![point_position(fe, a)?],
                        joined_to: None,
                    });
                    anchors.push((a.clone(), marks.len() - 1));
                    Some(marks.len() - 1)
                }
            },
            None => None,
        };
        marks.push(SketchMark {
            role: p.role,
            label: p.label.clone(),
            positions_m: vec![point_position(fe, &p.point)?],
            joined_to,
        });
    }
    marks.extend(floor_marks(fe));
    Ok(SketchPlot {
        title: title.to_string(),
        nodes: fe.mesh.nodes.clone(),
        edges: crate::io::vtk::mesh_edges(fe),
        marks,
        impact_direction: fe.impact_direction,
        notes,
    })
}

/// The FE model of a structure that is `[structure.fem]` alone, built without solving; `None`
/// for lumped, modal or tabulated structures.
fn fe_of(structure: &StructureSpec, src: &crate::model::Source) -> Result<Option<FeModel>> {
    match &structure.fem {
        Some(f)
            if structure.lumped.is_none()
                && structure.modal.is_none()
                && structure.modes.is_none() =>
        {
            Ok(Some(fem::build_model(f, src)?))
        }
        _ => Ok(None),
    }
}

/// The sketch of a paper-form model; `None` (no mesh to draw) for a lumped or tabulated one.
pub fn model_sketch(model: &Model) -> Result<Option<SketchPlot>> {
    let Some(fe) = fe_of(&model.spec.structure, &model.source)? else {
        return Ok(None);
    };
    let (points, notes) = paper_points(&model.spec);
    let title = title_of(model.spec.name.as_deref());
    sketch_of_fe(&fe, &title, &points, notes).map(Some)
}

/// The sketch of a general machine; `None` for a lumped or tabulated structure.
pub fn network_sketch(model: &NetworkModel) -> Result<Option<SketchPlot>> {
    let Some(fe) = fe_of(&model.spec.structure, &model.source)? else {
        return Ok(None);
    };
    let (points, notes) = network_points(&model.spec);
    let title = title_of(model.spec.name.as_deref());
    sketch_of_fe(&fe, &title, &points, notes).map(Some)
}

fn title_of(name: Option<&str>) -> String {
    match name {
        Some(n) => format!("model sketch: {n}"),
        None => "model sketch".into(),
    }
}

/// Reads a model file (paper form or general machine) and writes its sketch as `<stem>.png` and
/// `<stem>.svg`. Returns the files and the sketch, or `None` when the structure has no mesh.
pub fn write_model_sketch(
    path: &Path,
    overrides: &[String],
    stem: &Path,
) -> Result<Option<(PlotFiles, SketchPlot)>> {
    let sketch = if crate::model::network::is_general_file(path) {
        network_sketch(&NetworkModel::from_file(path, overrides)?)?
    } else {
        model_sketch(&Model::from_file(path, overrides)?)?
    };
    match sketch {
        Some(s) => Ok(Some((crate::plot::mesh::sketch_plot(stem, &s)?, s))),
        None => Ok(None),
    }
}

/// The report's caption of a sketch: each marked point and its role.
pub fn caption(s: &SketchPlot) -> String {
    let marks: Vec<String> = s.marks.iter().map(|m| m.label.clone()).collect();
    let mut c = format!(
        "The model's FE mesh (undeformed) with its points: {}.",
        marks.join("; ")
    );
    for n in &s.notes {
        c.push_str(&format!(" Note: {n}."));
    }
    c
}
