//! `meid calibrate` end to end: a simulation of the lumped example (its history.uff) is the
//! "measurement"; from a perturbed start the fit returns the model's values, writes its output
//! set and the calibrated model; bad --fit/--bounds exit 2 naming the path.

use crate::common;

use common::{meid, ok, paper_example, stderr, tmpdir};
use serde_json::Value;

const KS: &str = "contact.slider_bed.stiffness";
const ZETA: &str = "structure.lumped.damping_ratios[1]";

fn measured(tag: &str) -> (std::path::PathBuf, std::path::PathBuf) {
    let d = tmpdir("calibrate", tag);
    let run = d.join("run");
    ok(meid()
        .args(["simulate", paper_example().to_str().unwrap(), "-o"])
        .arg(&run)
        .args(["--uff", "-q"])
        .output()
        .unwrap());
    (d, run.join("history.uff"))
}

#[test]
fn calibrate_recovers_the_simulated_values_and_writes_its_set() {
    let (d, uff) = measured("fit");
    let out = d.join("cal");
    let ex = paper_example();
    let text = ok(meid()
        .arg("calibrate")
        .arg(&ex)
        .args(["--measured", uff.to_str().unwrap(), "--pretrigger", "0"])
        .args(["--fit", &format!("{KS},{ZETA}")])
        .args([
            "--set",
            &format!("{KS}=5e7"),
            "--set",
            &format!("{ZETA}=0.015"),
        ])
        .args(["--bounds", &format!("{ZETA}=0.001:0.05")])
        .arg("-o")
        .arg(&out)
        .arg("--json")
        .output()
        .unwrap());
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["converged"], true, "{v}");
    let p = v["parameters"].as_array().unwrap();
    let ks = p[0]["value"].as_f64().unwrap();
    let zeta = p[1]["value"].as_f64().unwrap();
    // The example's values (noise-free measurement: the fit is exact to the solver's tolerance).
    assert!((ks / 4.2980449e7 - 1.0).abs() < 1e-4, "K_s {ks}");
    assert!((zeta / 0.01 - 1.0).abs() < 1e-4, "zeta {zeta}");
    assert_eq!(p[1]["lower_bound"], 0.001);
    for f in [
        "calibration.json",
        "calibrated.toml",
        "calibration_as-specified_B.png",
        "calibration_as-specified_B.svg",
        "manifest.json",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("calibration.json")).unwrap())
            .unwrap();
    assert_eq!(written, v);
    // The calibrated model is a model meid reads, with the estimates.
    let cal = out.join("calibrated.toml");
    let t = std::fs::read_to_string(&cal).unwrap();
    assert!(t.starts_with("# Calibrated by `meid calibrate`"), "{t}");
    let o = ok(meid()
        .arg("calibrate")
        .arg(&cal)
        .args(["--measured", uff.to_str().unwrap(), "--pretrigger", "0"])
        .args(["--fit", KS, "--json", "--max-iterations", "1"])
        .output()
        .unwrap());
    let again: Value = serde_json::from_str(&o).unwrap();
    assert_eq!(again["parameters"][0]["start"].as_f64().unwrap(), ks);
}

#[test]
fn bad_fit_paths_and_bounds_exit_2_with_a_clear_message() {
    let (_d, uff) = measured("bad");
    let ex = paper_example();
    let run = |extra: &[&str]| {
        let o = meid()
            .arg("calibrate")
            .arg(&ex)
            .args(["--measured", uff.to_str().unwrap(), "--pretrigger", "0"])
            .args(extra)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
        stderr(&o)
    };
    let e = run(&["--fit", "contact.slider_bed.stifness"]);
    assert!(e.contains("--fit contact.slider_bed.stifness"), "{e}");
    let e = run(&["--fit", KS, "--bounds", &format!("{KS}=5e7:1e7")]);
    assert!(
        e.contains("LO = 50000000 is not below HI = 10000000"),
        "{e}"
    );
    let e = run(&["--fit", KS, "--bounds", &format!("{KS}=1e6:1e7")]);
    assert!(e.contains("outside its bounds") && e.contains(KS), "{e}");
    let e = run(&["--fit", KS, "--spectrum", "400:200"]);
    assert!(e.contains("--spectrum"), "{e}");
    let e = run(&["--fit", "structure.lumped.damping_ratios[7]"]);
    assert!(e.contains("damping_ratios[7]"), "{e}");
}
