//! The machine in production from the command line: the damper-return map (`blows --vary`),
//! the optimum at a stroke rate (`optimize --rate-bpm`), the unit-slip warnings, and bad input.

use crate::common;

use common::{example_file, meid, ok, ok_json, stderr, tmpdir};

/// The paper's lumped damper (τ = c_d/k_d = 0.39 s) does not return at 60 /min and makes the
/// steady floor force worse than no damper; a weak dashpot on a soft spring (k_d = 1e3 N/m,
/// c_d = 80 N·s/m: τ = 0.08 s) returns. The map's files are written as a set.
#[test]
fn the_return_map_separates_returning_designs() {
    let out = tmpdir("production", "return-map");
    let v = ok_json(
        meid()
            .args(["blows"])
            .arg(example_file("paper-lumped.toml"))
            .args([
                "--rate-bpm",
                "60",
                "--vary",
                "damper.stiffness=1e3",
                "--vary",
                "damper.damping=80,700",
                "--json",
                "-o",
            ])
            .arg(&out)
            .output()
            .unwrap(),
    );
    let cells = v["return_map"]["cells"].as_array().expect("cells");
    assert_eq!(cells.len(), 2);
    assert_eq!(cells[0]["returns"], true, "{}", cells[0]);
    assert_eq!(cells[0]["robust"], false, "{}", cells[0]);
    assert_eq!(cells[1]["returns"], false, "{}", cells[1]);
    assert!(cells[1]["floor_force_change_db"].as_f64().unwrap() > 0.0);
    assert_eq!(v["return_map"]["best_returning"], 0);
    let summary = v["summary"].as_str().unwrap();
    assert!(
        summary.starts_with("At 60 blows/min the damper touches the bed in every steady blow in 1 of the 2 designs (0 robust")
            && summary.contains("damper.stiffness = 1000, damper.damping = 80:")
            && summary.contains("refine the grid"),
        "{summary}"
    );
    for f in ["return-map.csv", "return-map.json", "return-map.svg"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("return-map.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(
        csv.starts_with("damper.stiffness,damper.damping,returns,robust,"),
        "{csv}"
    );
}

/// At 60 /min, the floor-force optimum over c_d (k_d = 1e3 N/m) is a design whose damper
/// returns, and designs that do not are refused as infeasible, not failed.
#[test]
fn optimize_at_a_stroke_rate_keeps_to_returning_designs() {
    let v = ok_json(
        meid()
            .args(["optimize"])
            .arg(example_file("paper-lumped.toml"))
            .args([
                "--set",
                "damper.stiffness=1e3",
                "--over",
                "damper.damping",
                "--bounds",
                "damper.damping=20..2000",
                "--objective",
                "floor-force",
                "--rate-bpm",
                "60",
                "--grid",
                "9",
                "--max-simulations",
                "40",
                "--json",
            ])
            .output()
            .unwrap(),
    );
    assert_eq!(v["rate_bpm"], 60.0);
    let st = &v["steady_state"];
    assert_eq!(st["converged"], true, "{st}");
    assert_eq!(st["damper_touches_bed"], true, "{st}");
    // The objective is the steady blow's largest floor force.
    assert_eq!(v["objective_value"], st["peak_floor_force_n"]);
    assert!(v["infeasible"].as_u64().unwrap() >= 1, "{v}");
    // The optimum's c_d: the paper's 700 N·s/m does not return at 60 /min.
    assert!(
        v["optimum"][0].as_f64().unwrap() < 700.0,
        "{}",
        v["optimum"]
    );
}

#[test]
fn unit_slips_are_warned_with_the_likely_unit() {
    let o = meid()
        .args(["simulate"])
        .arg(example_file("paper-lumped.toml"))
        .args(["--set", "slider.velocity=1200"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    let e = stderr(&o);
    assert!(
        e.contains("warning: --set slider.velocity=1200: slider.velocity = 1200 m/s is faster than any forging blow")
            && e.contains("is it in mm/s (1.2 m/s)?"),
        "{e}"
    );
    // The paper's machine has none.
    let o = meid()
        .args(["simulate"])
        .arg(example_file("paper-soft-base.toml"))
        .output()
        .unwrap();
    assert!(!stderr(&o).contains("is it in"), "{}", stderr(&o));
}

/// Bad stroke rates and maps: exit 2, naming the option and what is valid.
#[test]
fn bad_rates_and_maps_name_the_option() {
    let lumped = example_file("paper-lumped.toml");
    let cases: [(&[&str], &str); 7] = [
        (&["--rates", "0..60:5"], "--rates"),
        (&["--rates", "20..60:1"], "--rates"),
        (&["--rates", "NaN,60"], "--rates"),
        (&["--rates=-5,60"], "every stroke rate must be > 0"),
        (&["--rate-bpm", "0", "--steady"], "--rate-bpm"),
        (&["--rate-bpm", "NaN", "--steady"], "--rate-bpm"),
        (
            &[
                "--vary",
                "damper.mass=1,2",
                "--vary",
                "damper.stiffness=1e3,1e4",
                "--vary",
                "damper.damping=1,2",
            ],
            "one or two quantities",
        ),
    ];
    for (args, want) in cases {
        let o = meid()
            .arg("blows")
            .arg(&lumped)
            .args(args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
    }
    let o = meid()
        .arg("optimize")
        .arg(&lumped)
        .args(["--over", "damper.damping", "--rate-bpm=-1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--rate-bpm -1"), "{}", stderr(&o));
    let _ = ok(meid()
        .arg("blows")
        .arg(&lumped)
        .args(["--rates", "20,60", "--quiet"])
        .output()
        .unwrap());
}

/// The lumped example with `[production] rate_bpm = R` appended, written to a fresh directory.
fn with_stroke_rate(tag: &str, rate: &str) -> std::path::PathBuf {
    let dir = tmpdir("production", tag);
    let text = std::fs::read_to_string(example_file("paper-lumped.toml")).unwrap();
    let path = dir.join("press.toml");
    std::fs::write(&path, format!("{text}\n[production]\nrate_bpm = {rate}\n")).unwrap();
    path
}

/// A stroke rate in the model file is the rate `blows` and `compare` judge the machine at
/// (a command's --rate-bpm overrides it); compare then opens with the steady blow's verdict,
/// and without any rate it says the single blow is not production.
#[test]
fn the_model_stroke_rate_is_the_operating_condition() {
    let model = with_stroke_rate("rate-30", "30");
    let steady = |extra: &[&str]| {
        ok_json(
            meid()
                .arg("blows")
                .arg(&model)
                .args(["--steady", "--json"])
                .args(extra)
                .output()
                .unwrap(),
        )
    };
    assert_eq!(steady(&[])["rate_bpm"], 30.0);
    assert_eq!(steady(&["--rate-bpm", "20"])["rate_bpm"], 20.0);

    let o = meid().arg("compare").arg(&model).output().unwrap();
    let text = ok(o);
    let lines: Vec<&str> = text.lines().collect();
    assert!(
        lines[1].starts_with("  In production at 30 blows/min (the model's [production] rate_bpm; the periodic steady blow):"),
        "{text}"
    );
    let v = ok_json(
        meid()
            .arg("compare")
            .arg(&model)
            .arg("--json")
            .output()
            .unwrap(),
    );
    assert_eq!(v["production"]["rate_bpm"], 30.0, "{}", v["production"]);
    assert_eq!(v["production"]["cases"].as_array().map(Vec::len), Some(3));
    // The production verdict equals `blows --steady`'s at the same rate.
    assert_eq!(v["production"]["verdict"], steady(&[])["verdict"]);

    let plain = ok_json(
        meid()
            .arg("compare")
            .arg(example_file("paper-lumped.toml"))
            .args(["--json", "--blows", "3"])
            .output()
            .unwrap(),
    );
    assert!(plain.get("production").is_none(), "no rate, no production");
    let verdict = plain["verdict"][0].as_str().unwrap();
    assert!(
        verdict.starts_with("Over a train of 3 blows from rest at 60 /min (the train's largest peaks), the impact damper changes"),
        "{verdict}"
    );
}

/// A stroke rate that is not a rate: exit 2 naming the field, its line and the valid range.
#[test]
fn a_bad_model_stroke_rate_names_the_field() {
    for bad in ["0", "-60", "nan"] {
        let model = with_stroke_rate(&format!("bad-rate-{bad}"), bad);
        let o = meid().arg("simulate").arg(&model).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("production.rate_bpm must be a finite number > 0 blows per minute")
                && e.contains("press.toml:"),
            "{bad}: {e}"
        );
    }
}
