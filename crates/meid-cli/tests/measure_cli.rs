//! `meid measure`, `meid validate` and the `--uff` exports end to end.

mod common;

use common::{meid, ok, paper_example, stderr, tmpdir};
use serde_json::Value;

#[test]
fn measure_json_has_the_issue_fields_and_sample_peaks() {
    let d = tmpdir("measure", "json");
    let f = d.join("lab.csv");
    // Two blows one second apart on the hammer; the acceleration in g.
    let mut s = String::from("time_s,accel_B_g,hammer_n\n");
    for i in 0..2000 {
        let t = i as f64 * 1e-3;
        let tb = t % 1.0;
        let hammer = if (0.1..0.103).contains(&tb) {
            1000.0
        } else {
            0.0
        };
        let acc = if tb >= 0.1 {
            (-(tb - 0.1) * 20.0).exp() * (2.0 * std::f64::consts::PI * 50.0 * (tb - 0.1)).sin()
        } else {
            0.0
        };
        s.push_str(&format!("{t},{acc},{hammer}\n"));
    }
    std::fs::write(&f, s).unwrap();
    let out = ok(meid()
        .args([
            "measure",
            f.to_str().unwrap(),
            "--json",
            "--pretrigger",
            "0.05",
        ])
        .output()
        .unwrap());
    let v: Value = serde_json::from_str(&out).unwrap();
    let chans = v.as_array().unwrap();
    assert_eq!(chans.len(), 2);
    let keys: Vec<&str> = chans[0]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    let mut want = vec![
        "name",
        "unit",
        "samples",
        "sample_rate_hz",
        "peak",
        "peak_time_s",
        "blows",
        "dominant_frequency_hz",
        "dominant_level_db",
    ];
    let mut got = keys.clone();
    want.sort();
    got.sort();
    assert_eq!(got, want);
    let a = &chans[0];
    assert_eq!(a["name"], "accel_B");
    assert_eq!(a["unit"], "m/s^2");
    assert_eq!(a["samples"], 2000);
    assert!((a["sample_rate_hz"].as_f64().unwrap() - 1000.0).abs() < 1e-6);
    assert_eq!(a["blows"], 2);
    assert!((a["dominant_frequency_hz"].as_f64().unwrap() - 50.0).abs() <= 1.0);
    assert_eq!(chans[1]["unit"], "N");
    assert_eq!(chans[1]["peak"], 1000.0);
    // The text says the peak is a sample peak.
    let text = ok(meid()
        .args(["measure", f.to_str().unwrap(), "--pretrigger", "0.05"])
        .output()
        .unwrap());
    assert!(text.contains("sample peak"), "{text}");
    // -o writes the set.
    let o = d.join("out");
    ok(meid()
        .args([
            "measure",
            f.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap());
    for name in [
        "measure.json",
        "bands.csv",
        "accel_B_spectrum.csv",
        "accel_B_spectrum.png",
        "hammer_average.svg",
        "manifest.json",
    ] {
        assert!(o.join(name).exists(), "{name}");
    }
}

#[test]
fn bad_units_exit_2_naming_file_and_column() {
    let d = tmpdir("measure", "bad");
    let f = d.join("lab.csv");
    std::fs::write(&f, "time_s,accel_B_furlongs\n0,1\n0.001,2\n").unwrap();
    let o = meid()
        .args(["measure", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("lab.csv:1: column 2 'accel_B_furlongs'"), "{e}");
    let f = d.join("lab.uff");
    std::fs::write(&f, "    -1\n    58\nx\n").unwrap();
    let o = meid()
        .args(["measure", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("lab.uff: dataset 1 (58 starting at line 1)"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn uff_exports_read_back_and_validate_to_zero() {
    let d = tmpdir("measure", "uff");
    let ex = paper_example();
    let ex = ex.to_str().unwrap();
    for case in ["none", "damper"] {
        let o = d.join(case);
        ok(meid()
            .args([
                "simulate",
                ex,
                "--case",
                case,
                "-o",
                o.to_str().unwrap(),
                "--uff",
                "-q",
            ])
            .output()
            .unwrap());
        assert!(o.join("history.uff").exists());
    }
    // history.uff holds the numbers of history.csv.
    let csv = d.join("none/history.csv");
    let uff = d.join("none/history.uff");
    let a: Value = serde_json::from_str(&ok(meid()
        .args(["measure", csv.to_str().unwrap(), "--json"])
        .output()
        .unwrap()))
    .unwrap();
    let b: Value = serde_json::from_str(&ok(meid()
        .args(["measure", uff.to_str().unwrap(), "--json"])
        .output()
        .unwrap()))
    .unwrap();
    for (x, y) in a.as_array().unwrap().iter().zip(b.as_array().unwrap()) {
        assert_eq!(x["name"], y["name"]);
        assert_eq!(x["peak"], y["peak"]);
        assert_eq!(x["samples"], y["samples"]);
    }
    // --uff needs -o.
    let o = meid().args(["simulate", ex, "--uff"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    // Validation of the simulation against itself.
    let out = ok(meid()
        .args([
            "validate",
            ex,
            "--measured",
            &format!("none={}", d.join("none/history.uff").display()),
            "--measured",
            &format!("damper={}", d.join("damper/history.uff").display()),
            "--pretrigger",
            "0",
            "--json",
        ])
        .output()
        .unwrap());
    let v: Value = serde_json::from_str(&out).unwrap();
    for c in v["cases"].as_array().unwrap() {
        for ch in c["channels"].as_array().unwrap() {
            assert!(ch["peak_error_percent"].as_f64().unwrap().abs() < 1e-9);
            for m in ch["modes"].as_array().unwrap() {
                assert_eq!(m["frequency_error_hz"], 0.0);
                assert!(m["level_difference_db"].as_f64().unwrap().abs() < 1e-9);
            }
        }
    }
    let red = v["reductions"].as_array().unwrap();
    assert!(!red.is_empty());
    for r in red {
        assert!(
            (r["measured_db"].as_f64().unwrap() - r["simulated_db"].as_f64().unwrap()).abs() < 1e-9
        );
    }
    // Without --pretrigger 0 the error says why.
    let o = meid()
        .args([
            "validate",
            ex,
            "--measured",
            d.join("none/history.uff").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--pretrigger"), "{}", stderr(&o));
    // Modes export: 2411 + 55.
    let m = d.join("modes");
    ok(meid()
        .args(["modes", ex, "-o", m.to_str().unwrap(), "--uff", "-q"])
        .output()
        .unwrap());
    let t = std::fs::read_to_string(m.join("modes.uff")).unwrap();
    assert!(
        t.contains("  2411") && t.matches("\n    55").count() == 2,
        "{t}"
    );
}
