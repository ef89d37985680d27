//! Bounded cost and whole output sets, end to end.
//!
//! Each run that used to abort out of memory (exit 134) or hang is refused with exit code 2 and
//! a message naming the input to reduce and the limit (`--max-memory`), or completes within the
//! limit: `--max-memory` is set below what the old code would have held, so completing proves
//! the data were streamed, not held. Output directories are replaced as a set (manifest.json
//! last); a failed run leaves the previous set as it was. References: the estimates are
//! closed forms of the inputs (samples × bytes per sample, DOFs × 6 KiB), stated in the
//! messages; the measured figures are in README.md ("Outputs and cost limits").

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{meid, ok, paper_example as example, stderr};

fn tmpdir(tag: &str) -> PathBuf {
    common::tmpdir("outputs-cli", tag)
}

/// Asserts exit code 2 and returns stderr.
fn refused(o: Output) -> String {
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "stderr: {e}");
    assert!(e.starts_with("error: "), "{e}");
    assert!(!e.contains("panicked") && !e.contains("backtrace"), "{e}");
    e
}

fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let n = e.file_name().to_string_lossy().to_string();
            let bytes = if e.path().is_file() {
                std::fs::read(e.path()).unwrap()
            } else {
                Vec::new()
            };
            (n, bytes)
        })
        .collect();
    v.sort();
    v
}

#[test]
fn long_runs_are_refused_before_they_allocate() {
    let d = tmpdir("long");
    let ex = example();
    // simulate --duration 1e9 -o: the run's own time bound (1e7 periods) names the duration.
    let e = refused(
        meid()
            .arg("simulate")
            .arg(&ex)
            .args(["--duration", "1e9", "-o"])
            .arg(d.join("s"))
            .output()
            .unwrap(),
    );
    assert!(e.contains("--duration"), "{e}");
    // compare --duration 1e9: three records of 2e13 samples.
    let e = refused(
        meid()
            .arg("compare")
            .arg(&ex)
            .args(["--duration", "1e9"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("duration") && e.contains("--max-memory"), "{e}");
    // The same check, below the limit it is set to: 3 × 40001 samples × 160 B = 18.3 MiB.
    let e = refused(
        meid()
            .args(["--max-memory", "1MiB", "compare"])
            .arg(&ex)
            .output()
            .unwrap(),
    );
    assert!(e.contains("18.31 MiB") && e.contains("1.00 MiB"), "{e}");
    // blows --blows 100000: 9.5e7 periods of the 953 Hz contact, over the 1e7 a run may span.
    let e = refused(
        meid()
            .arg("blows")
            .arg(&ex)
            .args(["--blows", "100000"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("--blows") && e.contains("at most 10498"), "{e}");
    // montecarlo --samples 1e12.
    let e = refused(
        meid()
            .arg("montecarlo")
            .arg(&ex)
            .args([
                "--vary",
                "contact.slider_bed.stiffness=lognormal(4.3e7,0.2)",
                "--samples",
                "1000000000000",
            ])
            .output()
            .unwrap(),
    );
    assert!(e.contains("--samples") && e.contains("--max-memory"), "{e}");
    // sweep over a range of 1e12 values.
    let e = refused(
        meid()
            .arg("sweep")
            .arg(&ex)
            .args(["--vary", "wd/ws=1..2:1000000000000"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("vary") && e.contains("TiB"), "{e}");
    // --rate 1e15 with -o: the history file would not fit the disk.
    let e = refused(
        meid()
            .arg("simulate")
            .arg(&ex)
            .args(["--rate", "1e15", "-o"])
            .arg(d.join("r"))
            .output()
            .unwrap(),
    );
    assert!(e.contains("--rate") && e.contains("on disk"), "{e}");
    // A size that is not one.
    let e = refused(
        meid()
            .args(["--max-memory", "lots", "simulate"])
            .arg(&ex)
            .output()
            .unwrap(),
    );
    assert!(e.contains("--max-memory") && e.contains("2GiB"), "{e}");
}

#[test]
fn rate_1e15_without_output_computes_no_sample() {
    // Nothing is recorded without -o: the peaks are exact on the continuous solution.
    let out = ok(meid()
        .args(["--max-memory", "1MiB", "simulate"])
        .arg(example())
        .args(["--rate", "1e15", "--json"])
        .output()
        .unwrap());
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["energy_ratio"].as_f64().unwrap() > 0.0);
}

#[test]
fn a_long_history_is_streamed_to_disk() {
    // 5 s at 20 kHz: 100001 samples; held, the history would take 16 MB, over the 2 MiB
    // allowed; streamed, it completes and equals the same run's summary peaks.
    let d = tmpdir("stream");
    ok(meid()
        .args(["--max-memory", "2MiB", "simulate"])
        .arg(example())
        .args(["--duration", "5", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let h = std::fs::read_to_string(d.join("history.csv")).unwrap();
    assert_eq!(h.lines().count(), 1 + 100_001);
    let last: f64 = h
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((last - 5.0).abs() < 1e-9, "{last}");
    // The in-memory path refuses the same history under the same limit (compare holds its
    // records).
    let e = refused(
        meid()
            .args(["--max-memory", "2MiB", "compare"])
            .arg(example())
            .args(["--duration", "5"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("100001") || e.contains("1.000e5"), "{e}");
}

#[test]
fn blow_trains_stream_their_history() {
    // 20 blows at 60 /min: 400001 samples. history.csv is streamed; only the pictured series
    // (48 B per sample, 18.3 MiB) are held, so 24 MiB suffices where the held history
    // (61 MiB) would not.
    let d = tmpdir("blows");
    ok(meid()
        .args(["--max-memory", "24MiB", "blows"])
        .arg(example())
        .args(["--blows", "20", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let h = std::fs::read_to_string(d.join("history.csv")).unwrap();
    assert_eq!(h.lines().count(), 1 + 400_001);
    for f in [
        "blows.csv",
        "blows.json",
        "impacts.csv",
        "acceleration-time.png",
        "floor-force-time.svg",
        "blow-levels.png",
        "manifest.json",
    ] {
        assert!(d.join(f).exists(), "{f}");
    }
    // Below the pictured series' need: refused with the estimate.
    let e = refused(
        meid()
            .args(["--max-memory", "8MiB", "blows"])
            .arg(example())
            .args(["--blows", "20", "-o"])
            .arg(tmpdir("blows-small"))
            .output()
            .unwrap(),
    );
    assert!(e.contains("--blows") && e.contains("8.00 MiB"), "{e}");
}

#[test]
fn fe_models_over_the_limit_are_refused_before_assembly() {
    // elements_per_side = 400 (the documented maximum): 1.22e6 DOFs × 6 KiB = 7.0 GiB
    // (measured: 6.5 GiB, 172 s); under a 1 GiB limit it is refused at once.
    let e = refused(
        meid()
            .args(["--max-memory", "1GiB", "modes"])
            .arg(common::example_file("paper-soft-base.toml"))
            .args(["--set", "structure.fem.machine.elements_per_side=400"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("elements_per_side") && e.contains("DOFs"), "{e}");
    // A Gmsh mesh of 100 × 100 quads (60 k DOFs, 355 MiB estimated) under 64 MiB.
    let d = tmpdir("gmsh");
    std::fs::write(d.join("plate.msh"), plate_msh(100, 100)).unwrap();
    let toml = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/clamped_plate.toml"),
    )
    .unwrap()
    .replace("clamped_plate.msh", "plate.msh");
    std::fs::write(d.join("plate.toml"), toml).unwrap();
    let e = refused(
        meid()
            .args(["--max-memory", "64MiB", "modes"])
            .arg(d.join("plate.toml"))
            .output()
            .unwrap(),
    );
    assert!(e.contains("Gmsh mesh") && e.contains("plate.toml"), "{e}");
    // The same mesh within the default limit runs.
    let out = ok(meid()
        .arg("modes")
        .arg(d.join("plate.toml"))
        .output()
        .unwrap());
    assert!(out.contains("lanczos"), "{out}");
}

/// A Gmsh 4.1 mesh of an `nx × ny` quad plate 0.4 × 0.3 m with physical groups "centre"
/// (point), "edges" (boundary lines) and "plate" (surface), like tests/data/clamped_plate.msh.
fn plate_msh(nx: usize, ny: usize) -> String {
    use std::fmt::Write;
    let (lx, ly) = (0.4, 0.3);
    let id = |i: usize, j: usize| j * (nx + 1) + i + 1;
    let n = (nx + 1) * (ny + 1);
    let c = id(nx / 2, ny / 2);
    let mut s = String::new();
    s += "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n0 1 \"centre\"\n1 2 \"edges\"\n2 3 \"plate\"\n$EndPhysicalNames\n";
    let _ = write!(
        s,
        "$Entities\n1 1 1 0\n1 {} {} 0 1 1\n1 0 0 0 {lx} {ly} 0 1 2 0\n1 0 0 0 {lx} {ly} 0 1 3 1 1\n$EndEntities\n",
        lx / 2.0,
        ly / 2.0
    );
    let xy = |k: usize| {
        let (j, i) = ((k - 1) / (nx + 1), (k - 1) % (nx + 1));
        (lx * i as f64 / nx as f64, ly * j as f64 / ny as f64)
    };
    let _ = write!(s, "$Nodes\n2 {n} 1 {n}\n0 1 0 1\n{c}\n");
    let (x, y) = xy(c);
    let _ = write!(s, "{x} {y} 0\n2 1 0 {}\n", n - 1);
    let others: Vec<usize> = (1..=n).filter(|&k| k != c).collect();
    for k in &others {
        let _ = writeln!(s, "{k}");
    }
    for &k in &others {
        let (x, y) = xy(k);
        let _ = writeln!(s, "{x} {y} 0");
    }
    s += "$EndNodes\n";
    let mut b = Vec::new();
    for i in 0..nx {
        b.push((id(i, 0), id(i + 1, 0)));
    }
    for j in 0..ny {
        b.push((id(nx, j), id(nx, j + 1)));
    }
    for i in (1..=nx).rev() {
        b.push((id(i, ny), id(i - 1, ny)));
    }
    for j in (1..=ny).rev() {
        b.push((id(0, j), id(0, j - 1)));
    }
    let total = b.len() + nx * ny + 1;
    let _ = write!(
        s,
        "$Elements\n3 {total} 1 {total}\n0 1 15 1\n1 {c}\n1 1 1 {}\n",
        b.len()
    );
    let mut e = 2;
    for (p, q) in b {
        let _ = writeln!(s, "{e} {p} {q}");
        e += 1;
    }
    let _ = writeln!(s, "2 1 3 {}", nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let _ = writeln!(
                s,
                "{e} {} {} {} {}",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
            e += 1;
        }
    }
    s += "$EndElements\n";
    s
}

#[test]
fn a_failed_run_leaves_the_previous_output_set() {
    let ex = example();
    // simulate: a second run refused after its output set was begun.
    let d = tmpdir("keep-simulate");
    ok(meid()
        .arg("simulate")
        .arg(&ex)
        .args(["-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let before = snapshot(&d);
    let names: Vec<&str> = before.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        names,
        [
            "bed_acceleration.png",
            "bed_acceleration.svg",
            "contact_forces.png",
            "contact_forces.svg",
            "displacements.png",
            "displacements.svg",
            "energies.png",
            "energies.svg",
            "floor_force.png",
            "floor_force.svg",
            "history.csv",
            "impacts.csv",
            "manifest.json",
            "summary.json",
            "truncation.csv"
        ]
    );
    refused(
        meid()
            .arg("simulate")
            .arg(&ex)
            .args(["--rate", "1e15", "-o"])
            .arg(&d)
            .output()
            .unwrap(),
    );
    assert_eq!(snapshot(&d), before);
    // compare: the same with a record over the limit.
    let d = tmpdir("keep-compare");
    ok(meid()
        .arg("compare")
        .arg(&ex)
        .args(["--duration", "0.2", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let before = snapshot(&d);
    assert!(before.iter().any(|(n, _)| n == "manifest.json"));
    refused(
        meid()
            .args(["--max-memory", "1MiB", "compare"])
            .arg(&ex)
            .args(["-o"])
            .arg(&d)
            .output()
            .unwrap(),
    );
    assert_eq!(snapshot(&d), before);
    // sweep: a 1-D sweep after a 2-D one replaces the map pictures by the curve; no file of
    // the old set stays beside the new sweep.csv.
    let d = tmpdir("keep-sweep");
    ok(meid()
        .arg("sweep")
        .arg(&ex)
        .args([
            "--vary",
            "wd/ws=0.5..2:3",
            "--vary",
            "ws/w_ref=100..200:3",
            "-q",
            "-o",
        ])
        .arg(&d)
        .output()
        .unwrap());
    assert!(d.join("energy_ratio_map.png").exists());
    ok(meid()
        .arg("sweep")
        .arg(&ex)
        .args(["--vary", "wd/ws=0.5..2:3", "--force", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let names: Vec<String> = snapshot(&d).into_iter().map(|(n, _)| n).collect();
    assert_eq!(
        names,
        [
            "energy_ratio_curve.png",
            "energy_ratio_curve.svg",
            "manifest.json",
            "sweep.csv",
            "sweep.json",
            "sweep.parquet",
            "sweep.partial.csv"
        ]
    );
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["command"], "sweep");
    assert_eq!(m["files"].as_array().unwrap().len(), 5);
}

#[test]
fn output_path_that_is_a_file_is_named() {
    let d = tmpdir("file");
    let f = d.join("taken");
    std::fs::write(&f, "x").unwrap();
    for cmd in ["simulate", "compare", "blows"] {
        let e = refused(
            meid()
                .arg(cmd)
                .arg(example())
                .arg("-o")
                .arg(&f)
                .output()
                .unwrap(),
        );
        assert!(
            e.contains(&format!(
                "-o {}: exists and is not a directory",
                f.display()
            )),
            "{cmd}: {e}"
        );
        assert!(!e.contains("File exists"), "{e}");
    }
}

#[test]
fn os_errors_are_printed_once() {
    let e = refused(
        meid()
            .args(["simulate", "/no/such/model.toml"])
            .output()
            .unwrap(),
    );
    assert_eq!(e.matches("os error 2").count(), 1, "{e}");
}

fn sweep_cmd(dir: &Path) -> std::process::Command {
    let mut c = meid();
    c.arg("sweep")
        .arg(example())
        .args(["--vary", "wd/ws=0.5..2:3", "-q", "-o"])
        .arg(dir);
    c
}

#[test]
fn sweep_journals_are_kept_unless_asked() {
    let d = tmpdir("journal");
    ok(sweep_cmd(&d).output().unwrap());
    let csv = std::fs::read(d.join("sweep.csv")).unwrap();
    let journal = std::fs::read(d.join("sweep.partial.csv")).unwrap();
    // A second run without --resume would truncate the journal: refused, journal unchanged.
    let e = refused(sweep_cmd(&d).output().unwrap());
    assert!(
        e.contains("--resume") && e.contains("--force") && e.contains("3 finished point"),
        "{e}"
    );
    assert_eq!(std::fs::read(d.join("sweep.partial.csv")).unwrap(), journal);
    // --resume reuses the 3 points; --force starts over; both give the same table.
    ok(sweep_cmd(&d).arg("--resume").output().unwrap());
    assert_eq!(std::fs::read(d.join("sweep.csv")).unwrap(), csv);
    ok(sweep_cmd(&d).arg("--force").output().unwrap());
    assert_eq!(std::fs::read(d.join("sweep.csv")).unwrap(), csv);
    // --resume on an empty or a header-only journal: nothing to resume, a fresh start.
    let first_two: String = String::from_utf8(journal.clone())
        .unwrap()
        .lines()
        .take(2)
        .map(|l| format!("{l}\n"))
        .collect();
    for (tag, text) in [
        ("empty", String::new()),
        ("header-only", first_two.clone()),
        ("cut-header", first_two[..first_two.len() - 7].to_string()),
    ] {
        std::fs::write(d.join("sweep.partial.csv"), &text).unwrap();
        ok(sweep_cmd(&d).arg("--resume").output().unwrap());
        assert_eq!(std::fs::read(d.join("sweep.csv")).unwrap(), csv, "{tag}");
    }
    // A journal with points of a different sweep is still refused under --resume.
    let e = refused(
        meid()
            .arg("sweep")
            .arg(example())
            .args(["--vary", "wd/ws=0.5..2:4", "-q", "--resume", "-o"])
            .arg(&d)
            .output()
            .unwrap(),
    );
    assert!(e.contains("different sweep"), "{e}");
}

#[test]
fn sweep_without_output_writes_nothing() {
    let d = tmpdir("no-output");
    let out = ok(meid()
        .current_dir(&d)
        .arg("sweep")
        .arg(example())
        .args(["--vary", "wd/ws=0.5..2:3"])
        .output()
        .unwrap());
    assert!(out.contains("min energy_ratio"), "{out}");
    // The table of every point follows the summary: the header and 3 rows.
    let table: Vec<&str> = out
        .lines()
        .skip_while(|l| !l.starts_with("index,wd/ws,"))
        .collect();
    assert_eq!(table.len(), 4, "{out}");
    assert!(snapshot(&d).is_empty(), "{:?}", snapshot(&d));
    let e = refused(
        meid()
            .current_dir(&d)
            .arg("sweep")
            .arg(example())
            .args(["--vary", "wd/ws=0.5..2:3", "--resume"])
            .output()
            .unwrap(),
    );
    assert!(e.contains("--resume needs -o"), "{e}");
}
