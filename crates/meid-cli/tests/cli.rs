//! The `meid` command end to end: good runs and one test per class of bad input.

use crate::common;

use std::path::PathBuf;
use std::process::Output;

use common::{meid, paper_example as example, stderr};

fn tmpdir(tag: &str) -> PathBuf {
    common::tmpdir("cli", tag)
}

fn example_text() -> String {
    std::fs::read_to_string(example()).unwrap()
}

/// Writes `text` as a model file and runs `meid simulate` on it.
fn run_model(tag: &str, text: &str, extra: &[&str]) -> (Output, PathBuf) {
    let d = tmpdir(tag);
    let f = d.join("model.toml");
    std::fs::write(&f, text).unwrap();
    let out = meid().arg("simulate").arg(&f).args(extra).output().unwrap();
    (out, f)
}

#[test]
fn simulate_json_has_the_documented_keys() {
    let out = meid()
        .args(["simulate"])
        .arg(example())
        .arg("--json")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "energy_ratio",
        "collision_end_s",
        "slider_rebound_velocity_m_per_s",
        "damper_velocity_m_per_s",
        "peak_contact_force_slider_bed_n",
        "peak_contact_force_bed_damper_n",
    ] {
        assert!(v[key].is_number(), "missing {key}: {v}");
    }
    let r = v["energy_ratio"].as_f64().unwrap();
    assert!(r > 0.0 && r < 1.0);
}

#[test]
fn output_directory_gets_history_and_summary() {
    let d = tmpdir("out");
    let out = meid()
        .arg("simulate")
        .arg(example())
        .arg("-o")
        .arg(&d)
        .args(["--duration", "0.01", "--quiet"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(out.stdout.is_empty(), "--quiet prints nothing");
    let csv = std::fs::read_to_string(d.join("history.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for col in [
        "time_s",
        "bed_acceleration_m_per_s2",
        "floor_force_n",
        "contact_force_slider_bed_n",
        "ke_slider_j",
        "dissipated_j",
    ] {
        assert!(header.split(',').any(|c| c == col), "missing column {col}");
    }
    // 0.01 s at 20 kHz: samples 0..=200.
    assert_eq!(csv.lines().count(), 1 + 201);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap();
    assert!(s["energy_ratio"].is_number());
}

#[test]
fn set_overrides_a_field() {
    let a = meid()
        .arg("simulate")
        .arg(example())
        .arg("--json")
        .output()
        .unwrap();
    let b = meid()
        .arg("simulate")
        .arg(example())
        .args(["--json", "--set", "contact.bed_damper.stiffness=1.26e8"])
        .output()
        .unwrap();
    assert!(b.status.success(), "{}", stderr(&b));
    let ra = serde_json::from_slice::<serde_json::Value>(&a.stdout).unwrap()["energy_ratio"]
        .as_f64()
        .unwrap();
    let rb = serde_json::from_slice::<serde_json::Value>(&b.stdout).unwrap()["energy_ratio"]
        .as_f64()
        .unwrap();
    assert!(ra != rb && (ra - rb).abs() < 0.01, "{ra} {rb}");
}

#[test]
fn syntax_error_names_file_line_and_column() {
    let text = example_text().replace("mass = 1.2                     # m_s, kg", "mass = = 1.2");
    let (out, f) = run_model("syntax", &text, &[]);
    assert!(!out.status.success());
    let e = stderr(&out);
    let line = text
        .lines()
        .position(|l| l.contains("mass = = 1.2"))
        .unwrap()
        + 1;
    assert!(e.contains(&format!("{}:{line}:", f.display())), "{e}");
}

#[test]
fn unknown_key_gets_did_you_mean() {
    let text = example_text().replace(
        "stiffness = 1.8e3              # k_d, N/m",
        "stifness = 1.8e3",
    );
    let (out, _) = run_model("unknown", &text, &[]);
    assert!(!out.status.success());
    let e = stderr(&out);
    assert!(
        e.contains("unknown field `stifness`") && e.contains("did you mean `stiffness`?"),
        "{e}"
    );
}

#[test]
fn negative_mass_is_rejected_with_range_and_position() {
    let text = example_text().replace(
        "mass = 3.5                     # m_d",
        "mass = -3.5                     # m_d",
    );
    let (out, f) = run_model("negmass", &text, &[]);
    assert!(!out.status.success());
    let e = stderr(&out);
    let line = text
        .lines()
        .position(|l| l.contains("mass = -3.5"))
        .unwrap()
        + 1;
    assert!(
        e.contains("damper.mass") && e.contains("> 0 kg") && e.contains("-3.5"),
        "{e}"
    );
    assert!(e.contains(&format!("{}:{line}:", f.display())), "{e}");
}

#[test]
fn nan_is_rejected() {
    let text = example_text().replace(
        "velocity = 1.2                 # v_s, m/s",
        "velocity = nan",
    );
    let (out, _) = run_model("nan", &text, &[]);
    assert!(!out.status.success());
    let e = stderr(&out);
    assert!(e.contains("slider.velocity") && e.contains("NaN"), "{e}");
}

#[test]
fn zero_contact_stiffness_is_rejected() {
    let (out, _) = run_model(
        "zerok",
        &example_text(),
        &["--set", "contact.slider_bed.stiffness=0"],
    );
    assert!(!out.status.success());
    let e = stderr(&out);
    assert!(
        e.contains("contact.slider_bed.stiffness") && e.contains("> 0 N/m"),
        "{e}"
    );
    assert!(
        e.contains("--set contact.slider_bed.stiffness=0"),
        "error must name the override: {e}"
    );
}

#[test]
fn unknown_point_name_lists_valid_names() {
    let text = example_text().replace("measurement = \"bed\"", "measurement = \"bedd\"");
    let (out, _) = run_model("point", &text, &[]);
    assert!(!out.status.success());
    let e = stderr(&out);
    assert!(
        e.contains("unknown point 'bedd'") && e.contains("base, bed"),
        "{e}"
    );
}

#[test]
fn missing_file_is_reported() {
    let out = meid()
        .args(["simulate", "/nonexistent/model.toml"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("/nonexistent/model.toml"));
}

/// The text summary gives every value with 7 significant digits: a blow at 1e-12 m/s (energies
/// of 1e-25 J, forces of 1e-9 N) no longer reads as "0.000000 J" and "0.000 N", and each printed
/// value agrees with the JSON's to those digits. The dopri5 peaks are labelled estimates.
#[test]
fn small_values_print_with_their_digits() {
    let run = |extra: &[&str]| {
        meid()
            .arg("simulate")
            .arg(example())
            .args(["--set", "slider.velocity=1e-12"])
            .args(extra)
            .output()
            .unwrap()
    };
    let text = run(&[]);
    assert!(text.status.success(), "{}", stderr(&text));
    let text = String::from_utf8_lossy(&text.stdout).to_string();
    let json = run(&["--json"]);
    let v: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    let line = |start: &str| -> String {
        text.lines()
            .find(|l| l.trim_start().starts_with(start))
            .unwrap_or_else(|| panic!("no line '{start}' in\n{text}"))
            .to_string()
    };
    let first_number = |l: &str, after: &str| -> f64 {
        let rest = &l[l.find(after).expect("label") + after.len()..];
        rest.split_whitespace()
            .next()
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("no number in '{l}'"))
    };
    for (label, key) in [
        ("slider energy before / after", "slider_energy_before_j"),
        ("damper energy after", "damper_energy_after_j"),
        (
            "peak contact force slider-bed",
            "peak_contact_force_slider_bed_n",
        ),
    ] {
        let l = line(label);
        assert!(!l.contains(" 0.000"), "{l}");
        let printed = first_number(&l, label);
        let want = v[key].as_f64().expect(key);
        assert!(want > 0.0 && want < 1e-8, "{key} = {want}");
        assert!((printed / want - 1.0).abs() < 1e-6, "{l} vs {want}");
    }
    // (At 1e-12 m/s dopri5 needs an absolute tolerance below the bed's 8e-16 m motion.)
    let dopri = run(&["--method", "dopri5", "--set", "simulation.atol=1e-22"]);
    let dopri = String::from_utf8_lossy(&dopri.stdout).to_string();
    assert!(
        dopri.contains("peaks over the run (estimates on dopri5's dense output"),
        "{dopri}"
    );
    assert!(text.contains("peaks over the run (exact, on the continuous solution)"));
}
