//! `meid simulate` on a general machine (`[[impactor]]`, `[[damper]]`, `[[contact]]`): the
//! JSON summary with per-contact, per-damper and per-point peaks and the per-impact table,
//! `-o` files, and bad input exiting 2 with the file, line and field.

use crate::common;

use common::{meid, ok_json, stderr, tmpdir};

/// A free body (one mode at 0 Hz, ψ = 1/√m at "anvil") struck by a tup through an undamped
/// linear contact: an elastic collision of two bodies (m1 = 2 kg at 1 m/s onto m2 = 3 kg).
const TWO_BODIES: &str = r#"name = "tup on a free anvil"
[structure.modal]
frequencies_hz = [0.0]
damping_ratios = [0.0]
shapes = { anvil = [0.5773502691896258] }

[[impactor]]
name = "tup"
mass = 2.0
velocity = 1.0

[[contact]]
name = "tup_anvil"
between = ["tup", "anvil"]
gap = 2e-3
stiffness = 1.2e6

[simulation]
duration = 0.02
"#;

#[test]
fn simulate_json_reports_the_impacts_of_a_general_machine() {
    let d = tmpdir("network", "two-bodies");
    let file = d.join("m.toml");
    std::fs::write(&file, TWO_BODIES).unwrap();
    let out = d.join("out");
    let json = ok_json(
        meid()
            .args(["simulate", "--json", "-o"])
            .arg(&out)
            .arg(&file)
            .output()
            .unwrap(),
    );
    let (m1, m2, v, k, gap) = (2.0, 1.0 / 0.5773502691896258f64.powi(2), 1.0, 1.2e6, 2e-3);
    let impacts = json["impacts"].as_array().unwrap();
    assert_eq!(impacts.len(), 1, "{json}");
    let row = &impacts[0];
    assert_eq!(row["contact"], "tup_anvil");
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
    assert!(close(row["start_s"].as_f64().unwrap(), gap / v), "{row}");
    let m_red = m1 * m2 / (m1 + m2);
    let t_c = std::f64::consts::PI * (m_red / k).sqrt();
    assert!(close(row["duration_s"].as_f64().unwrap(), t_c), "{row}");
    assert!(close(row["restitution"].as_f64().unwrap(), 1.0), "{row}");
    // The tup rebounds as in an elastic collision; the anvil keeps the rest of the energy.
    let v1 = (m1 - m2) / (m1 + m2) * v;
    let after = json["impactors"][0]["velocity_after_m_per_s"]
        .as_f64()
        .unwrap();
    assert!(close(after, v1), "{after} vs {v1}");
    let ratio = json["energy_ratio"].as_f64().unwrap();
    assert!(close(ratio, 1.0 - (v1 / v).powi(2)), "{ratio}");
    assert_eq!(json["points"][0]["name"], "anvil");
    assert!(
        json["contacts"][0]["peak_force_n"]["peak"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    // -o: the summary and the per-impact table.
    let csv = std::fs::read_to_string(out.join("impacts.csv")).unwrap();
    assert!(
        csv.starts_with("contact,start_s,approach_velocity_m_per_s,peak_force_n,"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), 2, "{csv}");
    assert!(out.join("summary.json").exists());
}

#[test]
fn bad_general_input_exits_2_naming_file_line_and_field() {
    let d = tmpdir("network", "bad");
    let file = d.join("m.toml");
    let text = TWO_BODIES.replace(
        r#"between = ["tup", "anvil"]"#,
        r#"between = ["tup", "anvill"]"#,
    );
    std::fs::write(&file, &text).unwrap();
    let line = text.lines().position(|l| l.contains("anvill")).unwrap() + 1;
    let o = meid().arg("simulate").arg(&file).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains(&format!("m.toml:{line}:")), "{e}");
    assert!(
        e.contains("contact[0].between") && e.contains("did you mean 'anvil'"),
        "{e}"
    );
    // Commands that take the paper's machine only say so.
    let o = meid().arg("compare").arg(&file).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("general machine"), "{}", stderr(&o));
}

/// `meid simulate` of a small general machine with a Hertz contact and dopri5: two free bodies
/// (2 kg at 1 m/s onto 3 kg) through an undamped Hertz contact rebound as in the elastic
/// collision (restitution 1 to 1e-6, the tup leaving at (m1 − m2)/(m1 + m2) v); the plain
/// output names the method; with the exact method the file is refused naming the field.
#[test]
fn simulate_runs_a_general_hertz_machine_with_dopri5() {
    let d = tmpdir("network", "hertz");
    let file = d.join("hertz.toml");
    let text = TWO_BODIES
        .replace("stiffness = 1.2e6", "law = \"hertz\"\nstiffness = 1.0e9")
        .replace(
            "duration = 0.02",
            "duration = 0.02\nmethod = \"dopri5\"\nrtol = 1e-10",
        );
    std::fs::write(&file, &text).unwrap();
    let json = ok_json(
        meid()
            .args(["simulate", "--json"])
            .arg(&file)
            .output()
            .unwrap(),
    );
    assert_eq!(json["method"], "dopri5", "{json}");
    let impacts = json["impacts"].as_array().unwrap();
    assert_eq!(impacts.len(), 1, "{json}");
    let e = impacts[0]["restitution"].as_f64().unwrap();
    assert!((e - 1.0).abs() < 1e-6, "{e}");
    let (m1, m2, v) = (2.0, 1.0 / 0.5773502691896258f64.powi(2), 1.0);
    let after = json["impactors"][0]["velocity_after_m_per_s"]
        .as_f64()
        .unwrap();
    assert!((after - (m1 - m2) / (m1 + m2) * v).abs() < 1e-6, "{after}");
    let out = meid().arg("simulate").arg(&file).output().unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let plain = String::from_utf8_lossy(&out.stdout);
    assert!(
        plain.contains("dopri5 method") && plain.contains("tup_anvil"),
        "{plain}"
    );
    std::fs::write(
        &file,
        text.replace("method = \"dopri5\"", "method = \"exact\""),
    )
    .unwrap();
    let out = meid().arg("simulate").arg(&file).output().unwrap();
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let err = stderr(&out);
    assert!(
        err.contains("hertz.toml") && err.contains("contact[0].law") && err.contains("dopri5"),
        "{err}"
    );
}
