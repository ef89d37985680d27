//! One JSON shape for every command (docs/reference/json.md): `--json` prints one object, with
//! `warnings` and `notes` members carrying the model's diagnostics (the same warnings stderr
//! shows), and quantities whose key names their unit.

use crate::common;

use common::{example_file, meid, ok, tmpdir};
use serde_json::Value;

/// The object a command printed, checked for the shared members.
fn object(args: &[&str]) -> Value {
    let o = meid().args(args).output().unwrap();
    let v: Value = serde_json::from_str(&ok(o)).unwrap_or_else(|e| panic!("{args:?}: {e}"));
    assert!(v.is_object(), "{args:?}: not an object");
    for key in ["warnings", "notes"] {
        assert!(v[key].is_array(), "{args:?}: no `{key}` list");
    }
    v
}

/// Every command that reads a model carries the model's warnings in its JSON: here the unit
/// slip of a slider at 1200 m/s.
#[test]
fn every_command_prints_one_object_with_warnings_and_notes() {
    let model = example_file("paper-lumped.toml");
    let model = model.to_str().unwrap();
    let slip = ["--set", "slider.velocity=1200"];
    let with_slip = |args: &[&str]| {
        let mut all = args.to_vec();
        all.extend_from_slice(&slip);
        let v = object(&all);
        let warned = v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("slider.velocity = 1200 m/s"));
        assert!(warned, "{args:?}: {}", v["warnings"]);
        v
    };
    with_slip(&["simulate", model, "--json"]);
    with_slip(&["compare", model, "--json"]);
    with_slip(&["sweep", model, "--vary", "wd/ws=0.5,1", "--json"]);
    with_slip(&[
        "optimize",
        model,
        "--over",
        "wd/ws",
        "--grid",
        "5",
        "--max-simulations",
        "12",
        "--json",
    ]);
    with_slip(&["blows", model, "--steady", "--json"]);
    with_slip(&["blows", model, "--blows", "2", "--json"]);
    with_slip(&["blows", model, "--rates", "20,60", "--json"]);
    with_slip(&[
        "montecarlo",
        model,
        "--vary",
        "contact.slider_bed.stiffness=lognormal(4.3e7,0.2)",
        "--samples",
        "4",
        "--json",
    ]);
    let modes = object(&["modes", model, "--json"]);
    assert!(modes["modes"].is_array());

    // A measured file: meid's own simulated record.
    let d = tmpdir("json_shape", "measured");
    ok(meid()
        .args(["simulate", model, "--uff", "-q", "-o"])
        .arg(d.join("run"))
        .output()
        .unwrap());
    let uff = d.join("run/history.uff");
    let uff = uff.to_str().unwrap();
    // A simulated history starts with the blow: no pre-trigger fits before it.
    let m = object(&["measure", uff, "--pretrigger", "0", "--json"]);
    assert!(
        m["records"].as_array().is_some_and(|r| !r.is_empty()),
        "{m}"
    );
    with_slip(&[
        "validate",
        model,
        "--measured",
        uff,
        "--pretrigger",
        "0",
        "--json",
    ]);
}
