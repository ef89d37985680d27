//! The model sketch (issue 34 item 8): the user's FE mesh with the model's points marked.

use std::path::{Path, PathBuf};

use meid::plot::mesh::SketchRole;
use meid::report::sketch::{model_sketch, write_model_sketch};

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

fn out_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../target/plot-samples")
        .join(name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Writes the sketch of `file` and returns the SVG's text after checking both files exist and
/// are not empty.
fn sketch_svg(file: &str) -> String {
    let dir = out_dir(file.trim_end_matches(".toml"));
    let (files, _) = write_model_sketch(&example(file), &[], &dir.join("model_sketch"))
        .unwrap()
        .expect("an FE model has a sketch");
    for p in [&files.png, &files.svg] {
        let len = std::fs::metadata(p).unwrap().len();
        assert!(len > 1000, "{} has {len} bytes", p.display());
    }
    std::fs::read_to_string(&files.svg).unwrap()
}

#[test]
fn sketch_of_the_paper_soft_base_marks_strike_damper_anchor_measurement_and_floor() {
    let svg = sketch_svg("paper-soft-base.toml");
    for label in [
        "strike O_b (slider)",
        "damper at O_b",
        "anchor O_f",
        "measurement B",
        "floor: 4 springs to ground",
        "pointing along −z",
    ] {
        assert!(svg.contains(label), "no '{label}' in the sketch");
    }
}

#[test]
fn sketch_of_the_off_centre_press_shows_its_strike_and_four_dampers() {
    let svg = sketch_svg("press-off-centre-4-dampers.toml");
    for label in [
        "strike S (slider)",
        "damper damper1 at D1",
        "damper damper2 at D2",
        "damper damper3 at D3",
        "damper damper4 at D4",
        "anchor O_f",
        // The generated machine strikes its bed downwards (impact_direction = −z).
        "pointing along −z",
    ] {
        assert!(svg.contains(label), "no '{label}' in the sketch");
    }
}

#[test]
fn sketch_markers_sit_at_the_projection_of_the_named_nodes() {
    let model = meid::model::Model::from_file(&example("paper-soft-base.toml"), &[]).unwrap();
    let fe =
        meid::model::fem::build_model(model.spec.structure.fem.as_ref().unwrap(), &model.source)
            .unwrap();
    let sketch = model_sketch(&model).unwrap().unwrap();
    let projected = sketch.projected_marks();
    // The projection of mesh.rs's doc: azimuth a = 35°, elevation e = 25°.
    let (a, e) = (35f64.to_radians(), 25f64.to_radians());
    let screen = |p: [f64; 3]| {
        (
            -p[0] * a.sin() + p[1] * a.cos(),
            p[2] * e.cos() - (p[0] * a.cos() + p[1] * a.sin()) * e.sin(),
        )
    };
    let mut at = std::collections::BTreeMap::new();
    for (name, role) in [
        ("O_b", SketchRole::Strike),
        ("O_f", SketchRole::Anchor),
        ("B", SketchRole::Measurement),
    ] {
        let nodes = &fe.mesh.points[name];
        let mut p = [0.0; 3];
        for &n in nodes {
            for (pd, x) in p.iter_mut().zip(fe.mesh.nodes[n]) {
                *pd += x / nodes.len() as f64;
            }
        }
        let k = sketch.marks.iter().position(|m| m.role == role).unwrap();
        let (u, v) = screen(p);
        let (pu, pv) = projected[k][0];
        assert!(
            (pu - u).abs() < 1e-12 && (pv - v).abs() < 1e-12,
            "{name}: ({pu}, {pv}) vs ({u}, {v})"
        );
        at.insert(name, p);
    }
    // The file says B is (0.08, 0.05) m from the bed centre O_b, on the bed.
    let (b, o) = (at["B"], at["O_b"]);
    assert!((b[0] - o[0] - 0.08).abs() < 1e-9 && (b[1] - o[1] - 0.05).abs() < 1e-9);
    assert!((b[2] - o[2]).abs() < 1e-9);
    // The floor marks are the spring-to-ground nodes, at the projection of their nodes too.
    let floor = sketch
        .marks
        .iter()
        .position(|m| m.role == SketchRole::Floor)
        .unwrap();
    for (p, q) in sketch.marks[floor]
        .positions_m
        .iter()
        .zip(&projected[floor])
    {
        let (u, v) = screen(*p);
        assert!((q.0 - u).abs() < 1e-12 && (q.1 - v).abs() < 1e-12);
    }
}

#[test]
fn a_lumped_model_has_no_sketch() {
    let model = meid::model::Model::from_file(&example("paper-lumped.toml"), &[]).unwrap();
    assert!(model_sketch(&model).unwrap().is_none());
}
