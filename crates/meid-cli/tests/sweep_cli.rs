//! `meid sweep` and `meid optimize` end to end on the lumped paper example (and the FE
//! soft-base example on a coarse mesh).
//!
//! References: thread-count independence and resume are byte-for-byte comparisons; the
//! minimum over w_d/w_s at w_s/w_ref = 150 must lie in [0.8, 1.25] (paper section 4.1); the FE
//! machine's bed mass is its plate's ρ L_x L_y t; a sweep over `simulation.duration` shorter
//! than the collision (0.678 ms) has no energy ratio; errors at every point are reported as
//! themselves with exit code 2; `[added_mass] point` takes the model's point names.

use crate::common;

use std::path::PathBuf;

use common::{meid, ok, paper_example as example};

fn tmpdir(tag: &str) -> PathBuf {
    common::tmpdir("sweep-cli", tag)
}

fn sweep(dir: &PathBuf, extra: &[&str]) -> String {
    let mut c = meid();
    c.arg("sweep")
        .arg(example())
        .args(["--vary", "wd/ws=0.3..3:21:log", "--vary", "md/mb=0.35,0.7"])
        .arg("-o")
        .arg(dir)
        .args(extra);
    ok(c.output().unwrap())
}

#[test]
fn sweep_threads_resume_and_pictures() {
    let d1 = tmpdir("t1");
    let d2 = tmpdir("t2");
    let out = sweep(&d1, &["--threads", "1"]);
    assert!(out.contains("min energy_ratio"), "{out}");
    sweep(&d2, &["--threads", "2", "--quiet"]);
    let a = std::fs::read(d1.join("sweep.csv")).unwrap();
    assert_eq!(a, std::fs::read(d2.join("sweep.csv")).unwrap());
    // The Parquet table does not depend on the thread count either (pyarrow reads it:
    // crates/meid-py/tests/test_parquet.py).
    let p = std::fs::read(d1.join("sweep.parquet")).unwrap();
    assert_eq!(&p[..4], b"PAR1");
    assert_eq!(p, std::fs::read(d2.join("sweep.parquet")).unwrap());
    for f in [
        "sweep.json",
        "energy_ratio_family.png",
        "energy_ratio_family.svg",
    ] {
        assert!(d1.join(f).exists(), "{f}");
    }
    // Interrupted run: keep the journal's first lines, cut the last one.
    let j = std::fs::read_to_string(d1.join("sweep.partial.csv")).unwrap();
    let keep: String = j.lines().take(2 + 15).map(|l| format!("{l}\n")).collect();
    let cut = &j.lines().nth(2 + 15).unwrap()[..20];
    let d3 = tmpdir("resume");
    std::fs::write(d3.join("sweep.partial.csv"), format!("{keep}{cut}")).unwrap();
    sweep(&d3, &["--resume", "--quiet"]);
    assert_eq!(a, std::fs::read(d3.join("sweep.csv")).unwrap());
}

#[test]
fn sweep_map_minimum_near_wd_equal_ws() {
    let d = tmpdir("map");
    let out = ok(meid()
        .arg("sweep")
        .arg(example())
        .args([
            "--vary",
            "ws/w_ref=150",
            "--vary",
            "wd/ws=0.3..3:41:log",
            "--quiet",
            "-o",
        ])
        .arg(&d)
        .output()
        .unwrap());
    assert!(out.is_empty());
    let csv = std::fs::read_to_string(d.join("sweep.csv")).unwrap();
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let ix = header.iter().position(|h| *h == "wd/ws").unwrap();
    let ie = header.iter().position(|h| *h == "energy_ratio").unwrap();
    let (mut best, mut at) = (f64::INFINITY, 0.0);
    for r in rows {
        let f: Vec<&str> = r.split(',').collect();
        let e: f64 = f[ie].parse().unwrap();
        if e < best {
            best = e;
            at = f[ix].parse().unwrap();
        }
    }
    assert!((0.8..=1.25).contains(&at), "minimum at wd/ws = {at}");

    // Heat map of two ranges with the w_d = w_s line.
    let d = tmpdir("heat");
    ok(meid()
        .arg("sweep")
        .arg(example())
        .args([
            "--vary",
            "ws/w_ref=50..300:6:log",
            "--vary",
            "wd/w_ref=50..300:6:log",
            "--quiet",
            "-o",
        ])
        .arg(&d)
        .output()
        .unwrap());
    assert!(d.join("energy_ratio_map.png").exists());
}

#[test]
fn sweep_and_optimize_errors_are_clear() {
    let o = meid()
        .arg("sweep")
        .arg(example())
        .args(["--vary", "wd/ws=1..2:1", "-o"])
        .arg(tmpdir("err"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("N >= 2"));
    let o = meid()
        .arg("optimize")
        .arg(example())
        .args(["--over", "wd/xx"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown ratio"));
}

#[test]
fn optimize_reports_optimum_and_paper_rule() {
    let out = ok(meid()
        .arg("optimize")
        .arg(example())
        .args(["--over", "wd/ws", "--bounds", "wd/ws=0.3..3", "--json"])
        .output()
        .unwrap());
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let x = v["optimum"][0].as_f64().unwrap();
    assert!((0.8..=1.25).contains(&x), "{x}");
    assert!(v["simulations"].as_u64().unwrap() > 0);
    assert!(
        v["objective_at_wd_equal_ws"].as_f64().unwrap() >= v["objective_value"].as_f64().unwrap()
    );
}

/// Column `name` of `dir/sweep.csv`, one string per row (the error column is last, so the
/// columns before it split on commas).
fn column(dir: &std::path::Path, name: &str) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let k = head.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(k).unwrap_or("").to_string())
        .collect()
}

fn number(s: &str) -> f64 {
    s.parse().unwrap_or(f64::NAN)
}

/// The FE soft-base example on a coarse mesh (cheap).
const COARSE: [&str; 2] = ["--set", "structure.fem.machine.elements_per_side=6"];

#[test]
fn sweep_over_simulation_fields_changes_the_rows() {
    let d = tmpdir("sim-duration");
    ok(meid()
        .arg("sweep")
        .arg(example())
        .args(["--vary", "simulation.duration=1e-4,0.5", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    // 1e-4 s ends before the collision (0.678 ms): no energy ratio; 0.5 s: 14.64 %.
    let e = column(&d, "energy_ratio");
    assert_eq!(e[0], "", "{e:?}");
    assert!((number(&e[1]) - 0.1464).abs() < 1e-3, "{e:?}");
    let t = column(&d, "simulated_time_s");
    assert_eq!((number(&t[0]), number(&t[1])), (1e-4, 0.5));
    // No picture of a metric undefined at every point, and no error.
    let d = tmpdir("sim-short");
    let out = ok(meid()
        .arg("sweep")
        .arg(example())
        .args(["--vary", "simulation.duration=1e-4,2e-4", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    assert!(out.contains("undefined at every point"), "{out}");
    // rtol with dopri5: the step count follows it.
    let d = tmpdir("sim-rtol");
    ok(meid()
        .arg("sweep")
        .arg(example())
        .args(["--set", "simulation.method=\"dopri5\""])
        .args(["--vary", "simulation.rtol=1e-4,1e-8", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let s = column(&d, "steps");
    assert!(number(&s[1]) > number(&s[0]), "dopri5 steps {s:?}");
}

#[test]
fn sweep_over_a_whole_number_field_of_the_fe_model() {
    let d = tmpdir("fe-int");
    ok(meid()
        .arg("sweep")
        .arg(common::example_file("paper-soft-base.toml"))
        .args(COARSE)
        .args([
            "--vary",
            "structure.fem.machine.elements_per_side=4,8",
            "-q",
            "-o",
        ])
        .arg(&d)
        .output()
        .unwrap());
    assert_eq!(column(&d, "error"), vec!["", ""]);
    let e = column(&d, "energy_ratio");
    assert!(
        number(&e[0]).is_finite() && number(&e[1]).is_finite() && e[0] != e[1],
        "{e:?}"
    );
    let o = meid()
        .arg("sweep")
        .arg(common::example_file("paper-soft-base.toml"))
        .args(COARSE)
        .args([
            "--vary",
            "structure.fem.machine.elements_per_side=4.5",
            "-o",
        ])
        .arg(tmpdir("fe-int-bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = common::stderr(&o);
    assert!(
        err.contains("structure.fem.machine.elements_per_side takes a whole number"),
        "{err}"
    );
}

#[test]
fn md_over_mb_on_the_fe_model() {
    // Derived m_b: the bed plate, 7850 kg/m³ x 0.432 x 0.2693 x 0.01095 m.
    let m_b = 7850.0 * 0.432 * 0.2693 * 0.01095;
    let d = tmpdir("fe-mdmb");
    ok(meid()
        .arg("sweep")
        .arg(common::example_file("paper-soft-base.toml"))
        .args(COARSE)
        .args(["--vary", "md/mb=0.35,0.7", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let m = column(&d, "damper_mass_kg");
    for (s, r) in m.iter().zip([0.35, 0.7]) {
        assert!(
            (number(s) / (r * m_b) - 1.0).abs() < 1e-14,
            "{s} vs {}",
            r * m_b
        );
    }
    // --bed-mass wins.
    let d = tmpdir("fe-mdmb-flag");
    ok(meid()
        .arg("sweep")
        .arg(common::example_file("paper-soft-base.toml"))
        .args(COARSE)
        .args(["--vary", "md/mb=0.35,0.7", "--bed-mass", "10", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let m: Vec<f64> = column(&d, "damper_mass_kg")
        .iter()
        .map(|s| number(s))
        .collect();
    assert_eq!(m, vec![3.5, 7.0]);
}

/// A modal model with a damper: no masses, so m_b must be given.
fn modal_file(dir: &std::path::Path) -> PathBuf {
    let p = dir.join("modal.toml");
    std::fs::write(
        &p,
        r#"
[structure.modal]
frequencies_hz = [6.35, 283.0]
damping_ratios = 0.01
[structure.modal.shapes]
bed = [0.14, 0.30]
base = [0.14, -0.03]
[points]
bed_contact = "bed"
damper_anchor = "base"
measurement = "bed"
[slider]
mass = 1.2
velocity = 1.2
[damper]
mass = 3.5
stiffness = 1.8e3
damping = 7.0e2
[contact.slider_bed]
stiffness = 4.298e7
[contact.bed_damper]
stiffness = 1.2536e8
"#,
    )
    .unwrap();
    p
}

#[test]
fn bed_mass_flag_for_sweep_and_optimize() {
    let d = tmpdir("bed-mass");
    let model = modal_file(&d);
    let o = meid()
        .arg("sweep")
        .arg(&model)
        .args(["--vary", "md/mb=0.35,0.7", "-o"])
        .arg(d.join("a"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        common::stderr(&o).contains("give --bed-mass"),
        "{}",
        common::stderr(&o)
    );
    ok(meid()
        .arg("sweep")
        .arg(&model)
        .args(["--vary", "md/mb=0.35,0.7", "--bed-mass", "10", "-q", "-o"])
        .arg(d.join("b"))
        .output()
        .unwrap());
    let m: Vec<f64> = column(&d.join("b"), "damper_mass_kg")
        .iter()
        .map(|s| number(s))
        .collect();
    assert_eq!(m, vec![3.5, 7.0]);
    let o = meid()
        .arg("optimize")
        .arg(&model)
        .args([
            "--over",
            "md/mb",
            "--grid",
            "9",
            "--max-simulations",
            "12",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let v = common::ok_json(
        meid()
            .arg("optimize")
            .arg(&model)
            .args(["--over", "md/mb", "--bed-mass", "10"])
            .args([
                "--bounds",
                "md/mb=0.2..0.8",
                "--grid",
                "9",
                "--max-simulations",
                "12",
                "--json",
            ])
            .output()
            .unwrap(),
    );
    let x = v["optimum"][0].as_f64().unwrap();
    let m_d = v["point"]["derived"][2].as_f64().unwrap();
    assert!((m_d / (10.0 * x) - 1.0).abs() < 1e-14, "{m_d} vs 10 x {x}");
}

#[test]
fn an_error_at_every_point_is_reported_as_that_error() {
    let o = meid()
        .arg("sweep")
        .arg(example())
        .args(["--vary", "damper.mass=-1,-2", "-o"])
        .arg(tmpdir("all-fail"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = common::stderr(&o);
    assert!(
        err.contains("damper.mass") && err.contains("> 0 kg") && err.contains("all 2 points"),
        "{err}"
    );
    assert!(!err.contains("no drawable point"), "{err}");
}

#[test]
fn added_mass_point_from_the_command_line() {
    let v = common::ok_json(
        meid()
            .arg("simulate")
            .arg(example())
            .args([
                "--case",
                "added-mass",
                "--set",
                "added_mass.point=\"base\"",
                "--json",
            ])
            .output()
            .unwrap(),
    );
    assert!(v["energy_ratio"].as_f64().unwrap().is_finite());
    let o = meid()
        .arg("simulate")
        .arg(example())
        .args(["--case", "added-mass", "--set", "added_mass.point=\"roof\""])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = common::stderr(&o);
    assert!(
        err.contains("added_mass.point")
            && err.contains("'roof'")
            && err.contains("valid: base, bed"),
        "{err}"
    );
}

#[test]
fn sweep_cases_columns_and_one_curve_per_case() {
    let d = tmpdir("cases");
    let mut c = meid();
    c.arg("sweep")
        .arg(example())
        .args([
            "--vary",
            "md/mb=0.35,0.7,1.0",
            "--cases",
            "none,damper,added-mass",
        ])
        .arg("-o")
        .arg(&d);
    let out = ok(c.output().unwrap());
    assert!(out.contains("min energy_ratio:added-mass"), "{out}");
    let csv = std::fs::read_to_string(d.join("sweep.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for col in [
        "energy_ratio:none",
        "energy_ratio:damper",
        "energy_ratio:added-mass",
    ] {
        assert!(header.contains(&col), "{col} missing: {header:?}");
    }
    let json = std::fs::read_to_string(d.join("sweep.json")).unwrap();
    assert!(json.contains("\"cases\""), "{json}");
    let svg = std::fs::read_to_string(d.join("energy_ratio_curve.svg")).unwrap();
    for label in ["without damper", "impact damper", "added mass"] {
        assert!(svg.contains(label), "legend lacks {label}");
    }
    // A case listed twice is an input error (exit code 2).
    let mut c = meid();
    c.arg("sweep")
        .arg(example())
        .args(["--vary", "md/mb=0.35", "--cases", "none,none"]);
    let o = c.output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}
