//! `meid simulate`, `meid modes` and an FE sweep on the paper's FE machine
//! (`examples/paper-soft-base.toml`) give byte-identical output on 1 and 2 threads.
//!
//! Reference: byte-for-byte comparison of stdout and of the files written with `-o`. Before the
//! fix the lowest frequency of `meid modes --json` differed in the 9th digit and every
//! history sample of `meid simulate -o` in its last digits.

use crate::common;

use std::path::Path;

use common::{example_file, meid, ok, tmpdir};

fn example() -> std::path::PathBuf {
    example_file("paper-soft-base.toml")
}

/// Runs `meid ARGS` with `RAYON_NUM_THREADS=threads` and returns stdout.
fn run(threads: usize, args: &[&str], out: Option<&Path>) -> String {
    let mut c = meid();
    c.env("RAYON_NUM_THREADS", threads.to_string())
        .args(&args[..1])
        .arg(example())
        .args(&args[1..]);
    if let Some(d) = out {
        c.arg("-o").arg(d);
    }
    ok(c.output().unwrap())
}

fn same_files(a: &Path, b: &Path, names: &[&str]) {
    for n in names {
        let x = std::fs::read(a.join(n)).unwrap();
        assert!(!x.is_empty(), "{n} is empty");
        assert!(x == std::fs::read(b.join(n)).unwrap(), "{n} differs");
    }
}

#[test]
fn simulate_is_byte_identical_on_1_and_2_threads() {
    let (d1, d2) = (tmpdir("fem-threads", "sim1"), tmpdir("fem-threads", "sim2"));
    let s1 = run(1, &["simulate", "--json"], Some(&d1));
    let s2 = run(2, &["simulate", "--json"], Some(&d2));
    let v: serde_json::Value = serde_json::from_str(&s1).unwrap();
    let r = v["energy_ratio"].as_f64().unwrap();
    assert!(r > 0.0 && r < 1.0, "energy ratio {r}");
    assert_eq!(s1, s2);
    same_files(&d1, &d2, &["history.csv", "summary.json"]);
}

#[test]
fn modes_are_byte_identical_on_1_and_2_threads() {
    let (d1, d2) = (
        tmpdir("fem-threads", "modes1"),
        tmpdir("fem-threads", "modes2"),
    );
    let s1 = run(1, &["modes", "--json"], Some(&d1));
    let s2 = run(2, &["modes", "--json"], Some(&d2));
    let v: serde_json::Value = serde_json::from_str(&s1).unwrap();
    assert!(v["modes"].as_array().unwrap().len() >= 20, "{s1}");
    assert_eq!(s1, s2);
    same_files(&d1, &d2, &["modes.csv", "modes.json", "modes.vtu"]);
}

/// Each point rebuilds and solves the FE model (the bed thickness changes the structure).
#[test]
fn fe_sweep_is_byte_identical_on_1_and_2_threads() {
    let (d1, d2) = (
        tmpdir("fem-threads", "sweep1"),
        tmpdir("fem-threads", "sweep2"),
    );
    let vary = [
        "sweep",
        "--vary",
        "structure.fem.machine.bed.thickness=0.010,0.012",
        "--vary",
        "damper.mass=2.0,3.5",
        "--quiet",
    ];
    let mut a1 = vary.to_vec();
    a1.extend(["--threads", "1"]);
    let mut a2 = vary.to_vec();
    a2.extend(["--threads", "2"]);
    run(1, &a1, Some(&d1));
    run(2, &a2, Some(&d2));
    let csv = std::fs::read_to_string(d1.join("sweep.csv")).unwrap();
    assert_eq!(csv.lines().count(), 5, "{csv}");
    same_files(&d1, &d2, &["sweep.csv", "sweep.json"]);
}
