//! `meid sweep` and `meid optimize` end to end on the lumped paper example.
//!
//! References: thread-count independence and resume are byte-for-byte comparisons; the
//! minimum over w_d/w_s at w_s/w_ref = 150 must lie in [0.8, 1.25] (paper section 4.1).

mod common;

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
