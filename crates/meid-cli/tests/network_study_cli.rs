//! `meid sweep` and `meid optimize --place` on a general machine: a sweep point equals
//! `meid simulate --set` of its values bit for bit (JSON), the outputs, bad input exiting 2.

use crate::common;

use common::{meid, ok_json, stderr, tmpdir};

/// The lumped two-mass machine of the library's tests, its damper's contact given by damping.
fn lumped() -> String {
    include_str!("../../meid/tests/data/general_two_mass.toml").replacen(
        "restitution = 0.8",
        "damping = 40.0",
        1,
    )
}

fn file(tag: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let d = tmpdir("netstudy", tag);
    let f = d.join("m.toml");
    std::fs::write(&f, lumped()).unwrap();
    (d, f)
}

/// Each point of a sweep over the damper's mass equals `meid simulate --set` at that mass, bit
/// for bit: the JSON numbers (shortest round-trip form) of the energy ratio, the contacts'
/// peak forces and the points' peak accelerations are the same text.
#[test]
fn a_general_sweep_equals_simulate_with_set_bit_for_bit() {
    let (d, f) = file("equal");
    let out = d.join("out");
    let sweep = ok_json(
        meid()
            .args([
                "sweep",
                "--json",
                "--vary",
                "damper.d_left.mass=0.5..2:3",
                "-o",
            ])
            .arg(&out)
            .arg(&f)
            .output()
            .unwrap(),
    );
    let cols: Vec<String> = sweep["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap().to_string())
        .collect();
    let points = sweep["points"].as_array().unwrap();
    assert_eq!(points.len(), 3);
    for (i, mass) in ["5e-1", "1.25e0", "2e0"].iter().enumerate() {
        let sim = ok_json(
            meid()
                .args([
                    "simulate",
                    "--json",
                    "--set",
                    &format!("damper.d_left.mass={mass}"),
                ])
                .arg(&f)
                .output()
                .unwrap(),
        );
        let row = &points[i]["metrics"];
        let col = |name: &str| &row[cols.iter().position(|c| c == name).unwrap()];
        assert_eq!(col("energy_ratio"), &sim["energy_ratio"], "point {i}");
        for c in sim["contacts"].as_array().unwrap() {
            let name = format!("peak_force_n:{}", c["name"].as_str().unwrap());
            assert_eq!(col(&name), &c["peak_force_n"]["peak"], "{name}");
        }
        for p in sim["points"].as_array().unwrap() {
            let name = format!("peak_acceleration_m_per_s2:{}", p["name"].as_str().unwrap());
            let a = p["acceleration_m_per_s2"]["peak"].as_f64().unwrap().abs();
            assert_eq!(
                col(&name).as_f64().unwrap().to_bits(),
                a.to_bits(),
                "{name}"
            );
        }
    }
    for name in [
        "sweep.csv",
        "sweep.json",
        "sweep_curve.png",
        "sweep_curve.svg",
    ] {
        assert!(out.join(name).exists(), "{name}");
    }
    let csv = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert!(
        csv.starts_with("index,damper.d_left.mass,energy_ratio,"),
        "{csv}"
    );
}

/// A placement study over the command line: the best placement, every simulation in the JSON.
#[test]
fn optimize_place_reports_every_evaluation() {
    let (_d, f) = file("place");
    let rep = ok_json(
        meid()
            .args([
                "optimize",
                "--json",
                "--place",
                "left,right",
                "--dampers",
                "1..2",
                "--total-mass",
                "1.75",
            ])
            .arg(&f)
            .output()
            .unwrap(),
    );
    assert_eq!(rep["search"], "exhaustive");
    assert_eq!(rep["combinations"], 3);
    assert_eq!(rep["evaluations"].as_array().unwrap().len(), 3);
    assert_eq!(rep["placements"].as_array().unwrap().len(), 3);
    assert!(rep["best"]["objective"].as_f64().unwrap() > 0.0);
}

/// Bad input exits 2 with a message naming the option (and what is valid).
#[test]
fn bad_general_study_input_exits_2_naming_the_option() {
    let (_d, f) = file("bad");
    for (args, want) in [
        (
            vec!["sweep", "--vary", "damper.d_lfet.mass=1,2"],
            "did you mean 'd_left'",
        ),
        (
            vec!["sweep", "--vary", "damper.d_left.point=[lfet]"],
            "did you mean 'left'",
        ),
        (
            vec![
                "sweep",
                "--vary",
                "damper.d_left.mass=1,2",
                "--metric",
                "energy",
            ],
            "--metric",
        ),
        (
            vec![
                "sweep",
                "--vary",
                "damper.d_left.mass=1,2",
                "--cases",
                "none",
            ],
            "--cases",
        ),
        (
            vec!["optimize", "--place", "left,rihgt"],
            "did you mean 'right'",
        ),
        (
            vec!["optimize", "--place", "left,right", "--dampers", "3"],
            "--dampers",
        ),
        (
            vec!["optimize", "--place", "left", "--total-mass", "0"],
            "--total-mass",
        ),
        (
            vec!["optimize", "--place", "left", "--total-mass=-1"],
            "--total-mass",
        ),
        (
            vec![
                "optimize",
                "--place",
                "left,right",
                "--dampers",
                "1..2",
                "--search",
                "exhaustive",
                "--max-combinations",
                "2",
            ],
            "--max-combinations",
        ),
        (
            vec!["optimize", "--over", "damper.mass", "--place", "left"],
            "--over",
        ),
    ] {
        let o = meid().args(&args).arg(&f).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
    }
}
