//! `meid correlate` and `meid calibrate --modal` end to end on the lumped example: its own
//! test geometry (geometry.uff: UFF 15 + 82 + 2412 + 55) read back as identified modes and
//! mapped by coordinates correlates at MAC 1; the modes of the example with a stiffer column
//! bring `calibrate --modal` back to that stiffness; bad input exits 2 naming file and field.

use crate::common;

use common::{meid, ok, ok_json, paper_example, stderr, tmpdir};

const KC: &str = "structure.lumped.springs[0].stiffness";

/// `meid correlate … -o DIR` with a hand-written identified JSON (shapes of the right pattern:
/// in phase, then in opposition), then with its own geometry.uff as both the modes and the
/// geometry.
#[test]
fn correlate_writes_its_set_and_pairs_its_own_modes() {
    let d = tmpdir("correlate", "own");
    let id = d.join("modes.json");
    std::fs::write(
        &id,
        r#"{"points": ["bed:1 +Z", "base:2 -Z"], "modes": [
            {"frequency_hz": 6.4, "damping_ratio": 0.01, "shape": [1.0, -1.0]},
            {"frequency_hz": 280.0, "damping_ratio": 0.01, "shape": [1.0, 0.25]}]}"#,
    )
    .unwrap();
    let out = d.join("corr");
    let v = ok_json(
        meid()
            .args(["correlate", paper_example().to_str().unwrap(), "--modes"])
            .arg(&id)
            .arg("-o")
            .arg(&out)
            .arg("--json")
            .output()
            .unwrap(),
    );
    for key in ["pairs", "mac", "auto_mac", "warnings", "notes"] {
        assert!(v.get(key).is_some(), "{key}: {v}");
    }
    let pairs = v["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), 2, "{v}");
    assert_eq!(pairs[0]["model_mode"], 1);
    assert_eq!(pairs[1]["model_mode"], 2);
    assert_eq!(v["points"][1]["sign"], -1.0);
    for f in [
        "correlation.json",
        "pairs.csv",
        "mac.csv",
        "auto_mac.csv",
        "mac.png",
        "mac.svg",
        "auto_mac.png",
        "geometry.uff",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    // The geometry meid wrote, as identified modes mapped by its own coordinates.
    let geo = out.join("geometry.uff");
    let text = ok(meid()
        .args(["correlate", paper_example().to_str().unwrap(), "--modes"])
        .arg(&geo)
        .arg("--geometry")
        .arg(&geo)
        .output()
        .unwrap());
    assert!(text.contains("coordinates"), "{text}");
    let v = ok_json(
        meid()
            .args(["correlate", paper_example().to_str().unwrap(), "--modes"])
            .arg(&geo)
            .arg("--geometry")
            .arg(&geo)
            .arg("--json")
            .output()
            .unwrap(),
    );
    for p in v["pairs"].as_array().unwrap() {
        assert_eq!(p["identified_mode"], p["model_mode"]);
        assert!(p["mac"].as_f64().unwrap() > 0.99999, "{p}");
        assert!(p["error_percent"].as_f64().unwrap().abs() < 1e-3, "{p}");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// The example's modes with the column stiffness 8 % higher (written by correlate -o as
/// geometry.uff, 6 digits) fitted from the example's stiffness: back to it within 1 %, and the
/// calibrated model file holds the value.
#[test]
fn calibrate_modal_recovers_the_perturbed_stiffness() {
    let d = tmpdir("correlate", "update");
    let id = d.join("modes.json");
    std::fs::write(
        &id,
        r#"{"points": ["bed:1 +Z"], "modes": [{"frequency_hz": 280.0, "shape": [1.0]}]}"#,
    )
    .unwrap();
    let k_true = 1.08 * 2.5415164e7;
    let pert = d.join("pert");
    ok(meid()
        .args(["correlate", paper_example().to_str().unwrap(), "--modes"])
        .arg(&id)
        .arg("--set")
        .arg(format!("{KC}={k_true:e}"))
        .arg("-o")
        .arg(&pert)
        .arg("-q")
        .output()
        .unwrap());
    let geo = pert.join("geometry.uff");
    let upd = d.join("upd");
    let v = ok_json(
        meid()
            .args(["calibrate", paper_example().to_str().unwrap(), "--modal"])
            .arg(&geo)
            .arg("--geometry")
            .arg(&geo)
            .args(["--fit", KC, "--json", "-o"])
            .arg(&upd)
            .output()
            .unwrap(),
    );
    let k = v["parameters"][0]["value"].as_f64().unwrap();
    assert!(((k - k_true) / k_true).abs() < 1e-2, "{k} vs {k_true}");
    assert_eq!(v["pairs"].as_array().unwrap().len(), 2);
    let toml = std::fs::read_to_string(upd.join("calibrated.toml")).unwrap();
    assert!(toml.contains(&format!("{k:e}")), "{toml}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Bad input exits 2 with the file, the field and what is valid.
#[test]
fn correlate_bad_input_exits_2() {
    let d = tmpdir("correlate", "bad");
    let run = |name: &str, json: &str, extra: &[&str]| {
        let f = d.join(name);
        std::fs::write(&f, json).unwrap();
        let o = meid()
            .args(["correlate", paper_example().to_str().unwrap(), "--modes"])
            .arg(&f)
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        stderr(&o)
    };
    let e = run(
        "unmapped.json",
        r#"{"points": ["anvil:1 +Z"], "modes": [{"frequency_hz": 280.0, "shape": [1.0]}]}"#,
        &[],
    );
    assert!(
        e.contains("unmapped.json")
            && e.contains("anvil:1 +Z")
            && e.contains("base, bed")
            && e.contains("--map"),
        "{e}"
    );
    let e = run(
        "noshape.json",
        r#"{"points": ["bed:1 +Z"], "modes": [{"frequency_hz": 280.0}]}"#,
        &[],
    );
    assert!(
        e.contains("noshape.json") && e.contains("modes[0].shape"),
        "{e}"
    );
    let e = run(
        "few.json",
        r#"{"points": ["bed:1 +Z"], "modes": [{"frequency_hz": 280.0, "shape": [1.0]}]}"#,
        &["--model-modes", "2"],
    );
    assert!(
        e.contains("few.json") && e.contains("fewer than the 2 modes asked"),
        "{e}"
    );
    let e = run(
        "mapped.json",
        r#"{"points": ["x:1 +Z"], "modes": [{"frequency_hz": 280.0, "shape": [1.0]}]}"#,
        &["--map", "x=anvil"],
    );
    assert!(
        e.contains("--map") && e.contains("anvil") && e.contains("base, bed"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&d);
}
