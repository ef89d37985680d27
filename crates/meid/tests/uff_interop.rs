//! Interoperability with pyuff (PyPI, the reference UFF reader/writer of the Python test-lab
//! tools): pyuff writes files meid reads, and reads files meid writes, values equal to 1e-9
//! relative in binary and to the printed precision in ASCII (pyuff `%20.11e`: 12 significant digits, meid `%20.12e`: 13;
//! pyuff's abscissa fields `%13.5e`: 6).
//!
//! Needs a Python with pyuff: `MEID_PYUFF_PYTHON`, else `target/ci-venv-py/bin/python` (which
//! `.ci/run` creates). Without one the test prints why and passes, unless
//! `MEID_PYUFF_REQUIRED=1` (set by `.ci/run`), when it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use meid::io::uff::{self, Channel58, Mode, Node};
use meid::measure::{Abscissa, PointRef, Quantity};
use serde_json::Value;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn python() -> Option<PathBuf> {
    let p = std::env::var_os("MEID_PYUFF_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/ci-venv-py/bin/python"));
    let ok = p.exists()
        && Command::new(&p)
            .args(["-c", "import pyuff"])
            .status()
            .is_ok_and(|s| s.success());
    if ok {
        Some(p)
    } else if std::env::var("MEID_PYUFF_REQUIRED").as_deref() == Ok("1") {
        panic!("MEID_PYUFF_REQUIRED=1 but {} has no pyuff", p.display());
    } else {
        eprintln!(
            "skipped: no Python with pyuff at {} (set MEID_PYUFF_PYTHON, or run .ci/run, which creates target/ci-venv-py)",
            p.display()
        );
        None
    }
}

fn script(py: &Path, args: &[&str]) -> String {
    let out = Command::new(py)
        .arg(root().join(".ci/interop_uff.py"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) || a == b
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("meid-uff-interop-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn meid_reads_what_pyuff_writes() {
    let Some(py) = python() else { return };
    let dir = tmp("read");
    script(&py, &["write", dir.to_str().unwrap()]);
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    for (file, rel) in [
        ("ascii.uff", 5e-11),
        ("binary.uff", 1e-12),
        ("uneven.uff", 5e-11),
        // pyuff 2.5.8 announces the points' bytes, not the (x, y) pairs' (session 12: refused,
        // "24000 bytes announced, but ... take 48000 bytes").
        ("uneven_binary.uff", 1e-12),
    ] {
        let f = uff::read_uff(&dir.join(file)).unwrap();
        let exp = expected[file].as_array().unwrap();
        assert_eq!(f.records.len(), exp.len(), "{file}");
        for (r, e) in f.records.iter().zip(exp) {
            assert_eq!(r.name, e["name"].as_str().unwrap());
            assert_eq!(r.unit(), e["unit"].as_str().unwrap());
            let ev: Vec<f64> = e["values"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            assert_eq!(r.values.len(), ev.len());
            for (a, b) in r.values.iter().zip(&ev) {
                assert!(close(*a, *b, rel), "{file} {}: {a} vs {b}", r.name);
            }
            match &r.abscissa {
                Abscissa::Even { start_s, step_s } => {
                    assert_eq!(*start_s, e["x0"].as_f64().unwrap());
                    // pyuff prints the increment %13.5e (6 significant digits).
                    assert!(close(*step_s, e["dx"].as_f64().unwrap(), 5e-6), "{step_s}");
                }
                Abscissa::Uneven(t) => {
                    let et = e["times"].as_array().unwrap();
                    for (a, b) in t.iter().zip(et) {
                        assert!(close(*a, b.as_f64().unwrap(), 5e-6));
                    }
                }
            }
        }
    }
    let f = uff::read_uff(&dir.join("modes.uff")).unwrap();
    let e = &expected["modes.uff"];
    let nodes: Vec<Node> = e["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| {
            let v: Vec<f64> = n
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            Node {
                label: v[0] as i64,
                xyz: [v[1], v[2], v[3]],
            }
        })
        .collect();
    assert_eq!(f.nodes, nodes);
    assert_eq!(f.modes.len(), 1);
    let m = &f.modes[0];
    assert_eq!(m.number, 2);
    assert!(close(m.frequency_hz, 283.0, 5e-6) && close(m.damping_ratio, 0.01, 5e-6));
    let z: Vec<f64> = m.shapes.iter().map(|s| s.1[2]).collect();
    assert_eq!(z, vec![0.5, -0.25, 0.125]);
    let _ = std::fs::remove_dir_all(&dir);
}

/// An even 51.2 kHz grid over 1 s that pyuff writes as (x, y) pairs with its times printed
/// `%13.5e` (6 significant digits: steps 19.5312 or 19.5313 µs, up to 5.3e-7 s off the mean near
/// 1 s) is even within the precision it was printed with: read as even at 51.2 kHz, and
/// `meid measure` processes it. The truly uneven record of the other test stays uneven.
#[test]
fn pyuff_pairs_at_51k_read_as_even() {
    let Some(py) = python() else { return };
    let dir = tmp("pairs");
    script(&py, &["write", dir.to_str().unwrap()]);
    let f = uff::read_uff(&dir.join("pairs_51k.uff")).unwrap();
    assert_eq!(f.records.len(), 1);
    let r = &f.records[0];
    assert_eq!(r.values.len(), 51200);
    let (start, step) = r.even().unwrap();
    assert!(start.abs() <= 5e-12, "{start}");
    assert!(close(step, 1.0 / 51200.0, 1e-9), "{step}");
    assert!(close(r.sample_rate_hz().unwrap(), 51200.0, 1e-9));
    let p = meid::measure::process::Processing::default();
    let c = meid::measure::process::process_all(&f.records, &p, None, "B").unwrap();
    assert_eq!(c[0].summary.samples, 51200);
    let u = uff::read_uff(&dir.join("uneven.uff")).unwrap();
    assert!(matches!(u.records[0].abscissa, Abscissa::Uneven(_)));
    assert!(u.records[0].even().is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pyuff_reads_what_meid_writes() {
    let Some(py) = python() else { return };
    let dir = tmp("write");
    let a: Vec<f64> = (0..1001)
        .map(|i| (i as f64 * 0.113).sin() * 3.7e2 * (-(i as f64) * 1e-3).exp())
        .collect();
    let f: Vec<f64> = (0..1001)
        .map(|i| {
            if i < 40 {
                8e3 * (i as f64 * 0.0785).sin()
            } else {
                1e-9 * i as f64
            }
        })
        .collect();
    for (binary, rel, step) in [(true, 1e-15, 1.0 / 51200.0), (false, 5e-12, 1.0 / 30000.0)] {
        let path = dir.join(if binary { "b.uff" } else { "a.uff" });
        let mut out = Vec::new();
        for (name, q, v, node) in [
            ("bed_acceleration", Quantity::Acceleration, &a, 1),
            ("floor_force", Quantity::Force, &f, 2),
        ] {
            let ch = Channel58 {
                name,
                point: PointRef {
                    entity: "bed".into(),
                    node,
                    direction: 3,
                },
                quantity: q,
                start_s: 0.25,
                step_s: step,
                values: v,
            };
            uff::write_58(&mut out, &ch, binary).unwrap();
        }
        std::fs::write(&path, &out).unwrap();
        let read: Value =
            serde_json::from_str(&script(&py, &["read", path.to_str().unwrap()])).unwrap();
        let sets = read.as_array().unwrap();
        assert_eq!(sets.len(), 2);
        for (s, (name, unit, v)) in sets
            .iter()
            .zip([("bed_acceleration", "m/s^2", &a), ("floor_force", "N", &f)])
        {
            assert_eq!(s["name"], name);
            assert_eq!(s["unit"], unit);
            assert_eq!(s["x_unit"], "s");
            assert_eq!(s["dir"], 3);
            let d: Vec<f64> = s["data"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            assert_eq!(d.len(), v.len());
            for (x, y) in d.iter().zip(v.iter()) {
                assert!(close(*x, *y, rel), "{name}: {x} vs {y}");
            }
            // The abscissa increment is written with as many digits as its 13 columns hold:
            // exact for 1/51200 s, 7 significant digits for 1/30000 s.
            let x: Vec<f64> = s["x"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            let last = 0.25 + 1000.0 * step;
            assert!(
                close(x[1000], last, if binary { 1e-15 } else { 1e-7 }),
                "{} vs {last}",
                x[1000]
            );
        }
    }
    // Nodes and modes.
    let nodes = vec![
        Node {
            label: 1,
            xyz: [0.0, 0.5, 1.0 / 3.0],
        },
        Node {
            label: 2,
            xyz: [1e-3, -2.0, 7.0],
        },
    ];
    let mode = Mode {
        number: 3,
        frequency_hz: 283.0,
        modal_mass: 1.0,
        damping_ratio: 0.01,
        name: "bed".into(),
        id_lines: vec!["written by meid".into()],
        shapes: vec![(1, [0.0, 0.0, 0.2835]), (2, [0.0, 0.0, -0.0691897])],
        units: None,
    };
    let mut out = Vec::new();
    uff::write_2411(&mut out, &nodes).unwrap();
    uff::write_55(&mut out, &mode).unwrap();
    let path = dir.join("m.uff");
    std::fs::write(&path, &out).unwrap();
    let read: Value =
        serde_json::from_str(&script(&py, &["read", path.to_str().unwrap()])).unwrap();
    let sets = read.as_array().unwrap();
    let n = sets[0]["nodes"].as_array().unwrap();
    for (row, node) in n.iter().zip(&nodes) {
        let v: Vec<f64> = row
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(
            v,
            vec![node.label as f64, node.xyz[0], node.xyz[1], node.xyz[2]]
        );
    }
    assert_eq!(sets[1]["mode_n"], 3);
    assert!(close(sets[1]["freq"].as_f64().unwrap(), 283.0, 5e-6));
    let r3: Vec<f64> = sets[1]["r3"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(close(r3[0], 0.2835, 5e-6) && close(r3[1], -0.0691897, 5e-6));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `meid modes --uff` of a lumped model, read by pyuff: node k is the k-th named point by name
/// (the order of modes.csv's ψ columns), the ID lines say so and name the nodes
/// (`nodes: 1 = base, 2 = bed` for examples/paper-lumped.toml), and the z translations are the
/// model's signed ψ (mode 2: base and bed in opposition) to the 6 digits of dataset 55.
#[test]
fn pyuff_reads_the_lumped_node_names() {
    let Some(py) = python() else { return };
    let dir = tmp("lumped");
    let m = meid::model::Model::from_file(&root().join("examples/paper-lumped.toml"), &[]).unwrap();
    let s = &m.structure;
    let path = dir.join("modes.uff");
    std::fs::write(&path, uff::modes_uff_points(s).unwrap()).unwrap();
    let read: Value =
        serde_json::from_str(&script(&py, &["read", path.to_str().unwrap()])).unwrap();
    let sets = read.as_array().unwrap();
    let names: Vec<&String> = s.points.keys().collect();
    assert_eq!(names, ["base", "bed"]);
    // Dataset 164 first: SI.
    assert_eq!(sets[0]["type"], 164);
    assert_eq!(sets[0]["units_code"], 1);
    assert_eq!(sets[0]["length"].as_f64(), Some(1.0));
    assert_eq!(sets[0]["force"].as_f64(), Some(1.0));
    let sets = &sets[1..];
    let nodes = sets[0]["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 2);
    for (k, row) in nodes.iter().enumerate() {
        assert_eq!(row[0].as_f64().unwrap(), k as f64 + 1.0);
        assert_eq!(row[1].as_f64().unwrap(), k as f64);
    }
    for (i, set) in sets[1..].iter().enumerate() {
        assert_eq!(set["type"], 55);
        let id: Vec<&str> = set["id"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        assert!(
            id[2].starts_with("node k = k-th point by name as in modes.csv"),
            "{id:?}"
        );
        assert_eq!(id[3], "nodes: 1 = base, 2 = bed");
        let r3: Vec<f64> = set["r3"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (k, p) in names.iter().enumerate() {
            let psi = s.points[*p][i];
            assert!(
                close(r3[k], psi, 5e-6),
                "mode {}: {p} {} vs {psi}",
                i + 1,
                r3[k]
            );
        }
    }
    assert!(s.points["base"][1] < 0.0 && s.points["bed"][1] > 0.0);
    let _ = std::fs::remove_dir_all(&dir);
}

/// pyuff writes 2411 + two datasets 55 whose shapes are `2ψ` with modal mass 4; meid imports
/// them as a structure (`[structure.modes]`): shapes divided by √4 (exact: 6-digit prints of
/// binary fractions), frequencies and damping ratios as written, and a simulation runs on them.
#[test]
fn pyuff_modes_import_as_a_structure() {
    let Some(py) = python() else { return };
    let dir = tmp("modes");
    script(&py, &["write", dir.to_str().unwrap()]);
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let e = &expected["modes_scaled.uff"];
    let text = r#"
[structure.modes]
file = "modes_scaled.uff"
points = { n1 = 1, n2 = 2, n3 = 3 }
impact_direction = [0, 0, 1]

[points]
bed_contact = "n3"
measurement = "n2"

[slider]
mass = 1.0
velocity = 1.0

[contact.slider_bed]
stiffness = 1.0e7

[simulation]
duration = 0.02
"#;
    let m = meid::model::Model::from_text(
        &dir.join("model.toml").display().to_string(),
        text.into(),
        &[],
    )
    .unwrap();
    let s = &m.structure;
    let f: Vec<f64> = s
        .omega_rad_per_s
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect();
    let ef: Vec<f64> = e["frequency_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (a, b) in f.iter().zip(&ef) {
        assert!(close(*a, *b, 1e-12), "{a} vs {b}");
    }
    let z = e["damping_ratio"].as_f64().unwrap();
    for i in 0..2 {
        let zi = s.damping[i * 2 + i] / (2.0 * s.omega_rad_per_s[i]);
        assert!(close(zi, z, 1e-12), "{zi}");
    }
    for p in ["n1", "n2", "n3"] {
        let want: Vec<f64> = e["psi"][p]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(s.point(p).unwrap(), want.as_slice(), "{p}");
    }
    assert!(
        s.notes
            .iter()
            .any(|n| n.contains("divided by √(modal mass)")),
        "{:?}",
        s.notes
    );
    let sys = m.impact_system(meid::model::Case::AsSpecified).unwrap();
    let run = meid::analysis::energy::simulate(&sys, &m.options(), false).unwrap();
    assert!(run.summary.energy_balance_residual.unwrap() < 1e-9);
    // The same modes in mm-t-s, declared by pyuff's dataset 164: converted to the same ψ
    // (to dataset 55's 6 digits), without `units` in the model.
    let mm = meid::model::Model::from_text(
        &dir.join("model.toml").display().to_string(),
        text.replace("modes_scaled.uff", "modes_mm.uff"),
        &[],
    )
    .unwrap();
    for p in ["n1", "n2", "n3"] {
        for (a, b) in mm
            .structure
            .point(p)
            .unwrap()
            .iter()
            .zip(s.point(p).unwrap())
        {
            assert!(close(*a, *b, 5e-6), "{p}: {a} vs {b}");
        }
    }
    assert!(
        mm.structure
            .notes
            .iter()
            .any(|n| n.contains("unit code 9") && n.contains("length factor 1000")),
        "{:?}",
        mm.structure.notes
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The test geometry `meid correlate -o` writes (`geometry.uff`: datasets 164, 15, 82, 2412,
/// 55) of the lumped example, read by pyuff: nodes 1 = base at x = 0 and 2 = bed at x = 1 m, one
/// trace line 1 → 2, one rod (FE descriptor 11) 1-2, and each mode's z translations the model's
/// ψ to the 6 digits of dataset 55.
#[test]
fn pyuff_reads_the_correlate_geometry() {
    let Some(py) = python() else { return };
    let dir = tmp("geometry");
    let m = meid::model::Model::from_file(&root().join("examples/paper-lumped.toml"), &[]).unwrap();
    let s = &m.structure;
    let mm = meid::measure::correlate::ModelModes::new(&m, None);
    let path = dir.join("geometry.uff");
    std::fs::write(
        &path,
        meid::measure::correlate::geometry_uff(&m, &mm).unwrap(),
    )
    .unwrap();
    let read: Value =
        serde_json::from_str(&script(&py, &["read", path.to_str().unwrap()])).unwrap();
    let sets = read.as_array().unwrap();
    let types: Vec<i64> = sets.iter().map(|s| s["type"].as_i64().unwrap()).collect();
    assert_eq!(types, [164, 15, 82, 2412, 55, 55]);
    let nodes = sets[1]["nodes"].as_array().unwrap();
    assert_eq!(nodes.len(), 2);
    for (k, row) in nodes.iter().enumerate() {
        assert_eq!(row[0].as_i64().unwrap(), k as i64 + 1);
        assert_eq!(row[1].as_f64().unwrap(), k as f64);
    }
    assert_eq!(sets[2]["trace_num"], 1);
    assert_eq!(sets[2]["nodes"], serde_json::json!([1, 2]));
    let el = &sets[3]["elements"].as_array().unwrap();
    assert_eq!(el.len(), 1);
    assert_eq!(el[0]["fe_descriptor"], 11);
    assert_eq!(el[0]["nodes"], serde_json::json!([1, 2]));
    for (i, set) in sets[4..].iter().enumerate() {
        let r3: Vec<f64> = set["r3"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        for (k, p) in ["base", "bed"].iter().enumerate() {
            let psi = s.points[*p][i];
            assert!(
                close(r3[k], psi, 5e-6),
                "mode {}: {p} {} vs {psi}",
                i + 1,
                r3[k]
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}
