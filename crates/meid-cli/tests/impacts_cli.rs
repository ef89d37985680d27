//! The per-impact table of the paper's machine in `meid simulate` (`impacts`,
//! `impact_totals`, impacts.csv) and `meid blows` (a `blow` column, times of the train).

use crate::common;

use common::{example_file, meid, ok_json, tmpdir};

#[test]
fn simulate_reports_the_impacts_of_the_paper_machine() {
    let d = tmpdir("impacts", "simulate");
    let json = ok_json(
        meid()
            .arg("simulate")
            .arg(example_file("paper-lumped.toml"))
            .args(["--duration", "0.05", "--json", "-o"])
            .arg(&d)
            .output()
            .unwrap(),
    );
    let rows = json["impacts"].as_array().unwrap();
    let first = &rows[0];
    assert_eq!(first["contact"], "slider_bed");
    assert_eq!(first["start_s"], 0.0);
    // The slider strikes the bed at rest at the file's v_s.
    assert_eq!(first["approach_velocity_m_per_s"], 1.2);
    // The first closing is the collision's slider-bed contact.
    let peak = json["peak_contact_force_slider_bed_n"].as_f64().unwrap();
    let p = first["peak_force_n"].as_f64().unwrap();
    assert!((p - peak).abs() <= 1e-9 * peak, "{p} vs {peak}");
    let ct = json["contact_time_slider_bed_s"].as_f64().unwrap();
    assert!((first["duration_s"].as_f64().unwrap() - ct).abs() <= 1e-12 * ct);
    let e = first["exit_velocity_m_per_s"].as_f64().unwrap() / 1.2;
    assert!((first["restitution"].as_f64().unwrap() - e).abs() < 1e-15);
    // Totals: the sums of each contact's rows.
    let totals = json["impact_totals"].as_array().unwrap();
    assert_eq!(totals.len(), 2);
    for t in totals {
        let mine: Vec<&serde_json::Value> = rows
            .iter()
            .filter(|r| r["contact"] == t["contact"])
            .collect();
        assert_eq!(t["impacts"].as_u64().unwrap() as usize, mine.len());
        let sum: f64 = mine
            .iter()
            .map(|r| r["impulse_n_s"].as_f64().unwrap())
            .sum();
        assert!((t["impulse_n_s"].as_f64().unwrap() - sum).abs() <= 1e-12 * sum.abs());
    }
    let csv = std::fs::read_to_string(d.join("impacts.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "contact,start_s,approach_velocity_m_per_s,peak_force_n,peak_time_s,duration_s,impulse_n_s,dissipated_j,exit_velocity_m_per_s,restitution"
    );
    assert_eq!(lines.count(), rows.len());
}

#[test]
fn blows_report_the_impacts_of_every_blow() {
    let d = tmpdir("impacts", "blows");
    let json = ok_json(
        meid()
            .arg("blows")
            .arg(example_file("paper-lumped.toml"))
            .args(["--blows", "3", "--rate-bpm", "120", "--json", "-o"])
            .arg(&d)
            .output()
            .unwrap(),
    );
    let rows = json["impacts"].as_array().unwrap();
    let interval = json["interval_s"].as_f64().unwrap();
    assert_eq!(interval, 0.5);
    // Each blow starts with the slider striking at (blow − 1) · 60/R.
    for k in 1..=3u64 {
        let strike = rows
            .iter()
            .find(|r| r["blow"] == k && r["contact"] == "slider_bed")
            .unwrap();
        let t = strike["start_s"].as_f64().unwrap();
        assert!((t - (k - 1) as f64 * interval).abs() < 1e-12, "{strike}");
    }
    // The blows' own JSON rows are the same as a single run's for the first blow.
    let one = ok_json(
        meid()
            .arg("simulate")
            .arg(example_file("paper-lumped.toml"))
            .args(["--duration", "0.5", "--json"])
            .output()
            .unwrap(),
    );
    let first: Vec<&serde_json::Value> = rows.iter().filter(|r| r["blow"] == 1).collect();
    let single = one["impacts"].as_array().unwrap();
    assert_eq!(first.len(), single.len());
    assert_eq!(first[0]["impulse_n_s"], single[0]["impulse_n_s"]);
    let csv = std::fs::read_to_string(d.join("impacts.csv")).unwrap();
    let mut lines = csv.lines();
    assert!(lines.next().unwrap().starts_with("blow,contact,start_s,"));
    assert_eq!(lines.count(), rows.len());
}
