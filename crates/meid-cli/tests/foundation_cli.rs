//! `[foundation]` and `[[receiver]]` on the command line: the `foundation` and `receivers` members
//! of `simulate --json` and `compare --json` (each case), the verdict sentence, the paper's
//! lumped machine on soil instead of its four springs, and bad input (exit 2, field and range).

use crate::common;

use std::process::Output;

use common::{example_file, meid, ok, ok_json, paper_example, stderr, tmpdir};

fn refused(o: Output) -> String {
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "stderr: {e}");
    assert!(!e.contains("panicked"), "{e}");
    e
}

/// The paper's lumped machine with its floating base on soil springs given directly (the four
/// springs' total k_f) instead of the `supports` spring: the same machine, named differently.
fn paper_on_soil() -> String {
    let text = std::fs::read_to_string(paper_example()).unwrap();
    let text = text
        .replace(
            "  { name = \"supports\", nodes = [\"base\", \"ground\"], stiffness = 8.1195270e4 },\n",
            "",
        )
        .replace("floor = [\"supports\"]", "floor = [\"soil\"]");
    assert!(!text.contains("supports\", nodes"));
    text.replace(
        "[points]",
        "[foundation]\nmass = \"base\"\nlength = 0.5\nwidth = 0.4\nsoil = { stiffness_z = 8.1195270e4 }\n\n[[receiver]]\nname = \"office\"\ndistance = 10.0\nbuilding = \"residential\"\n\n[points]",
    )
}

#[test]
fn simulate_json_carries_foundation_and_receivers() {
    let j = ok_json(
        meid()
            .arg("simulate")
            .arg(example_file("hammer-on-soil.toml"))
            .arg("--json")
            .output()
            .unwrap(),
    );
    let f = &j["foundation"];
    assert!(f["peak_block_displacement_m"].as_f64().unwrap() > 0.0);
    let checks = f["checks"].as_array().unwrap();
    let names: Vec<&str> = checks
        .iter()
        .map(|c| c["check"].as_str().unwrap())
        .collect();
    assert!(
        names.contains(&"block amplitude") && names.contains(&"pad stress"),
        "{names:?}"
    );
    // A check without an allowable value is not applicable, never passed.
    let anvil = checks
        .iter()
        .find(|c| c["check"] == "anvil amplitude")
        .unwrap();
    assert_eq!(anvil["verdict"], "not applicable");
    let r = j["receivers"].as_array().unwrap();
    assert_eq!(r.len(), 2);
    let house = &r[1];
    assert_eq!(house["building_line"], 2);
    let v = house["verdict"].as_str().unwrap();
    assert!(
        v.starts_with("the receiver at 40 m, building line 2, "),
        "{v}"
    );
    assert!(v.contains("long-term limit (5.000 mm/s)"), "{v}");
    // The sentence's number is the check's margin.
    let din = &house["checks"][0];
    let m = din["margin"].as_f64().unwrap();
    assert!(
        v.contains(&format!("{:.0} %", 100.0 * m.abs())),
        "{v} / {m}"
    );
    // Human output prints the sentence.
    let out = ok(meid()
        .arg("simulate")
        .arg(example_file("hammer-on-soil.toml"))
        .output()
        .unwrap());
    assert!(out.contains(v), "{out}");
}

#[test]
fn models_without_a_foundation_have_no_foundation_member() {
    let j = ok_json(
        meid()
            .arg("simulate")
            .arg(paper_example())
            .arg("--json")
            .output()
            .unwrap(),
    );
    assert!(j.get("foundation").is_none() && j.get("receivers").is_none());
}

#[test]
fn paper_machine_on_soil_springs_is_the_paper_machine_and_compare_checks_each_case() {
    let dir = tmpdir("foundation", "paper");
    let path = dir.join("paper-on-soil.toml");
    std::fs::write(&path, paper_on_soil()).unwrap();
    let run = |p: &std::path::Path| {
        ok_json(
            meid()
                .arg("simulate")
                .arg(p)
                .arg("--json")
                .output()
                .unwrap(),
        )
    };
    let (a, b) = (run(&paper_example()), run(&path));
    assert_eq!(a["energy_ratio"], b["energy_ratio"]);
    assert_eq!(a["peak_floor_force_n"], b["peak_floor_force_n"]);
    // The soil force's exact peak is the force to the floor's.
    let soil = b["foundation"]["block_peaks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|p| p["channel"] == "floor_force_n")
        .unwrap()["peak"]
        .as_f64()
        .unwrap();
    let floor = b["peak_floor_force_n"].as_f64().unwrap();
    assert!((soil / floor - 1.0).abs() < 1e-9, "{soil} vs {floor}");

    let c = ok_json(
        meid()
            .arg("compare")
            .arg(&path)
            .args(["--json", "--duration", "0.5"])
            .output()
            .unwrap(),
    );
    for case in ["no-damper", "damper", "added-mass"] {
        let checks = c["foundation"][case]["checks"].as_array().unwrap();
        assert!(!checks.is_empty(), "{case}");
        let r = c["receivers"][case][0]["verdict"].as_str().unwrap();
        assert!(
            r.starts_with("the receiver at 10 m, building line 2"),
            "{r}"
        );
    }
    // The damper lowers the base's motion, so the receiver's PPV.
    let ppv = |case: &str| c["receivers"][case][0]["ppv_m_per_s"].as_f64().unwrap();
    assert!(ppv("damper") != ppv("no-damper"));
}

#[test]
fn both_hammer_examples_run() {
    for name in ["hammer-foundation.toml", "hammer-on-soil.toml"] {
        ok(meid()
            .arg("simulate")
            .arg(example_file(name))
            .arg("-q")
            .output()
            .unwrap());
    }
}

#[test]
fn bad_foundation_input_names_the_field_and_the_valid_range() {
    let cases = [
        (
            "foundation.soil.poisson=0.5",
            "foundation.soil.poisson",
            "[0, 0.5)",
        ),
        (
            "foundation.soil.poisson=-0.1",
            "foundation.soil.poisson",
            "[0, 0.5)",
        ),
        (
            "foundation.soil.shear_modulus=-3e8",
            "foundation.soil.shear_modulus",
            "> 0 Pa",
        ),
        (
            "foundation.soil.shear_modulus=0",
            "foundation.soil.shear_modulus",
            "> 0 Pa",
        ),
        (
            "foundation.soil.density=0",
            "foundation.soil.density",
            "> 0 kg/m³",
        ),
        (
            "receiver[0].distance=3.9",
            "receiver[0].distance",
            "r > 3.9392",
        ),
        (
            "foundation.embedment=3.5",
            "foundation.embedment",
            "valid 0..=3 m",
        ),
        (
            "receiver[1].building=\"office\"",
            "receiver[1].building",
            "\"residential\" (line 2)",
        ),
        (
            "foundation.mass=\"tup\"",
            "foundation.mass",
            "valid: anvil, block",
        ),
    ];
    for (set, field, range) in cases {
        let e = refused(
            meid()
                .arg("simulate")
                .arg(example_file("hammer-on-soil.toml"))
                .args(["--set", set, "-q"])
                .output()
                .unwrap(),
        );
        assert!(e.contains(field) && e.contains(range), "--set {set}: {e}");
        assert!(e.contains("--set"), "--set {set}: {e}");
    }
}

#[test]
fn receivers_need_a_foundation_and_a_foundation_a_lumped_structure() {
    let dir = tmpdir("foundation", "needs");
    let receivers = dir.join("receivers.toml");
    let text = std::fs::read_to_string(paper_example()).unwrap()
        + "\n[[receiver]]\nname = \"x\"\ndistance = 10.0\nbuilding = \"residential\"\n";
    std::fs::write(&receivers, text).unwrap();
    let e = refused(
        meid()
            .arg("simulate")
            .arg(&receivers)
            .arg("-q")
            .output()
            .unwrap(),
    );
    assert!(e.contains("receivers need a [foundation]"), "{e}");

    let fem = dir.join("fem.toml");
    let text = std::fs::read_to_string(example_file("paper-soft-base.toml")).unwrap()
        + "\n[foundation]\nmass = \"base\"\nlength = 1.0\nwidth = 1.0\nsoil = { stiffness_z = 1e5 }\n";
    std::fs::write(&fem, text).unwrap();
    let e = refused(meid().arg("simulate").arg(&fem).arg("-q").output().unwrap());
    assert!(
        e.contains("foundation:") && e.contains("[structure.lumped]"),
        "{e}"
    );
}
