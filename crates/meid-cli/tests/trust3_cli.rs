//! Issue 27 ("trust3"), the command-line side: resumed and merged studies never take rows
//! computed from another version of a file the model reads, nor rows edited, torn or holding
//! values a run never writes; input files are checked by kind and size before they are read;
//! an interrupted run leaves no staging directory and a second writer into one directory is
//! refused; non-finite results become errors naming the value; `model expand` writes nothing
//! a model load refuses; errors name the file or field.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{example_file, meid, ok, stderr, tmpdir};

/// `meid modes --uff` of the lumped example with `sets`: a UFF modes file (2411 + 55).
fn modes_uff(dir: &Path, sets: &[&str]) -> Vec<u8> {
    let mut c = meid();
    c.args(["modes", "--uff", "-q", "-o"])
        .arg(dir)
        .arg(example_file("paper-lumped.toml"));
    for s in sets {
        c.args(["--set", s]);
    }
    ok(c.output().unwrap());
    std::fs::read(dir.join("modes.uff")).unwrap()
}

/// The lumped example with its structure read from `modes.uff` beside it (nodes 1 = base,
/// 2 = bed: the points in name order).
fn imported_model(dir: &Path) -> PathBuf {
    let src = std::fs::read_to_string(example_file("paper-lumped.toml")).unwrap();
    let start = src.find("[structure]").unwrap();
    let end = src.find("[points]").unwrap();
    let text = format!(
        "{}[structure]\nreference_mode = 1\n[structure.modes]\nfile = \"modes.uff\"\npoints = {{ base = 1, bed = 2 }}\nimpact_direction = [0, 0, 1]\n\n{}",
        &src[..start],
        &src[end..]
    );
    let p = dir.join("imported.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn sweep_args(model: &Path) -> Vec<String> {
    vec![
        "sweep".into(),
        model.display().to_string(),
        "--vary".into(),
        "damper.mass=2,3.5,5".into(),
        "-q".into(),
    ]
}

fn run_sweep(model: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    meid()
        .args(sweep_args(model))
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// Item 3. The study fingerprint covers the content of the modes file the model reads: after
/// the file changed (the bed mass 10 → 8 kg in the model that wrote it), `sweep --resume`
/// refuses the old journal instead of reusing its rows (before: the old rows, a table equal
/// to the first run's), and `merge` refuses shards computed on the two versions.
#[test]
fn a_changed_modes_file_is_another_study_for_resume_and_merge() {
    let d = tmpdir("trust3", "fingerprint-files");
    let a = modes_uff(&d.join("a"), &[]);
    let b = modes_uff(&d.join("b"), &["structure.lumped.masses[0].mass=8"]);
    assert_ne!(a, b);
    let model = imported_model(&d);
    std::fs::write(d.join("modes.uff"), &a).unwrap();
    ok(run_sweep(&model, &d.join("out"), &[]));
    let first = read(&d.join("out/sweep.csv"));
    // The same file again: everything is reused, the table is the same.
    ok(run_sweep(&model, &d.join("out"), &["--resume"]));
    assert_eq!(read(&d.join("out/sweep.csv")), first);
    // Another mesh of modes: the journal is another study's.
    std::fs::write(d.join("modes.uff"), &b).unwrap();
    let o = run_sweep(&model, &d.join("out"), &["--resume"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("journal of a different sweep")
            && stderr(&o).contains("a file it reads"),
        "{}",
        stderr(&o)
    );
    assert_eq!(read(&d.join("out/sweep.csv")), first);
    // Fresh on the new file: other numbers.
    ok(run_sweep(&model, &d.join("fresh"), &[]));
    assert_ne!(read(&d.join("fresh/sweep.csv")), first);

    // Shards: 1/2 on version a, 2/2 on version b: refused.
    std::fs::write(d.join("modes.uff"), &a).unwrap();
    let shard = |k: &str, dir: &str| {
        ok(meid()
            .args(sweep_args(&model))
            .args(["--shard", k, "-o"])
            .arg(d.join(dir))
            .output()
            .unwrap());
    };
    shard("1/2", "s1");
    std::fs::write(d.join("modes.uff"), &b).unwrap();
    shard("2/2", "s2");
    let o = meid()
        .arg("merge")
        .arg(d.join("s1"))
        .arg(d.join("s2"))
        .arg("-o")
        .arg(d.join("merged"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("shards of different studies"),
        "{}",
        stderr(&o)
    );
}

/// The journal's rows (after its first line and header), each `ROW,CHECKSUM`.
fn journal_rows(j: &Path) -> (String, Vec<String>) {
    let text = read(j);
    let mut lines = text.lines();
    let head = format!("{}\n{}\n", lines.next().unwrap(), lines.next().unwrap());
    (head, lines.map(str::to_string).collect())
}

/// Item 4. A journal row whose energy ratio was set to NaN (checksum recomputed, as a tool
/// that rewrote the file would), a row edited without its checksum, and a row torn in half
/// are all recomputed on `--resume`: the table is the uninterrupted run's, byte for byte
/// (before: the NaN and the edited value were copied into sweep.csv with exit 0). An old
/// journal (v1, no checksums) is refused with a clear message.
#[test]
fn bad_journal_rows_are_recomputed_not_copied() {
    let d = tmpdir("trust3", "journal");
    let model = example_file("paper-lumped.toml");
    ok(run_sweep(&model, &d.join("ref"), &[]));
    let want = read(&d.join("ref/sweep.csv"));
    let j = d.join("ref/sweep.partial.csv");
    let (head, rows) = journal_rows(&j);
    assert!(head.starts_with("# meid sweep journal v2 "), "{head}");
    assert!(head.trim_end().ends_with(",row_fnv1a"), "{head}");
    assert_eq!(rows.len(), 3);
    // Row of point 0: energy_ratio is the first metric, after index, 1 value, 4 derived.
    let (row0, _) = rows[0].rsplit_once(',').unwrap();
    let mut cells: Vec<String> = row0.split(',').map(str::to_string).collect();
    cells[6] = "NaN".into();
    let nan_row = cells.join(",");
    let nan_sealed = format!("{nan_row},{}", meid::input::fnv1a_hex(nan_row.as_bytes()));
    // Row of point 1 with a digit changed, checksum left as it was.
    let edited = rows[1].replacen("e-", "1e-", 1);
    assert_ne!(edited, rows[1]);
    let torn = &rows[2][..rows[2].len() / 2];
    let o = d.join("out");
    std::fs::create_dir_all(&o).unwrap();
    std::fs::write(
        o.join("sweep.partial.csv"),
        format!("{head}{nan_sealed}\n{edited}\n{torn}\n"),
    )
    .unwrap();
    ok(run_sweep(&model, &o, &["--resume"]));
    assert_eq!(read(&o.join("sweep.csv")), want);
    assert!(!read(&o.join("sweep.csv")).contains("NaN"));
    // The journal now holds the three good rows.
    let (_, now) = journal_rows(&o.join("sweep.partial.csv"));
    let mut now = now;
    now.sort();
    let mut all = rows.clone();
    all.sort();
    assert_eq!(now, all);

    // A v1 journal: refused under --resume, naming the journal and the way out.
    let v1 = d.join("v1");
    std::fs::create_dir_all(&v1).unwrap();
    let old = head.replacen("journal v2", "journal v1", 1);
    std::fs::write(
        v1.join("sweep.partial.csv"),
        format!("{old}{}\n{}\n", rows[0], rows[1]),
    )
    .unwrap();
    let out = run_sweep(&model, &v1, &["--resume"]);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(
        e.contains("sweep.partial.csv") && e.contains("v1") && e.contains("--force"),
        "{e}"
    );
    ok(run_sweep(&model, &v1, &["--force"]));
    assert_eq!(read(&v1.join("sweep.csv")), want);
}

/// Item 4. A shard row edited to NaN is refused by `merge`, naming the file and the line; a
/// row carrying ±inf with a valid checksum is refused as a value a run never writes. Before,
/// both were copied into the merged sweep.csv with exit 0.
#[test]
fn bad_shard_rows_are_refused_by_merge() {
    let d = tmpdir("trust3", "shard-rows");
    let model = example_file("paper-lumped.toml");
    for k in ["1/2", "2/2"] {
        ok(meid()
            .args(sweep_args(&model))
            .args(["--shard", k, "-o"])
            .arg(d.join(k.replace('/', "-")))
            .output()
            .unwrap());
    }
    let merge = |out: &str| {
        meid()
            .arg("merge")
            .arg(d.join("1-2"))
            .arg(d.join("2-2"))
            .arg("-o")
            .arg(d.join(out))
            .output()
            .unwrap()
    };
    ok(merge("good"));
    let csv = d.join("2-2/shard.csv");
    let text = read(&csv);
    let lines: Vec<&str> = text.lines().collect();
    // Line 2: the first row. Its energy ratio set to NaN, checksum kept.
    let mut cells: Vec<&str> = lines[1].split(',').collect();
    cells[6] = "NaN";
    let edited = cells.join(",");
    let mut bad = lines.clone();
    bad[1] = &edited;
    std::fs::write(&csv, bad.join("\n") + "\n").unwrap();
    let o = merge("bad1");
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("shard.csv:2") && e.contains("checksum"), "{e}");
    // The same cell as inf, with a checksum that matches: refused as a value no run writes.
    let (row, _) = lines[1].rsplit_once(',').unwrap();
    let mut cells: Vec<&str> = row.split(',').collect();
    cells[6] = "inf";
    let row = cells.join(",");
    let sealed = format!("{row},{}", meid::input::fnv1a_hex(row.as_bytes()));
    let mut bad = lines.clone();
    bad[1] = &sealed;
    std::fs::write(&csv, bad.join("\n") + "\n").unwrap();
    let o = merge("bad2");
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("shard.csv:2") && e.contains("energy_ratio is inf"),
        "{e}"
    );
    assert!(!d.join("bad1/sweep.csv").exists() && !d.join("bad2/sweep.csv").exists());
}

/// Item 13. Special files are refused by kind before a byte is read (before: `/dev/zero` as a
/// model grew to gigabytes, `/dev/urandom` as a mesh never ended), a file over the memory
/// limit is refused by size, and a parse error quotes at most 60 characters of its line
/// (before: a 100 kB line was printed whole).
#[test]
fn special_and_oversized_inputs_are_refused_before_reading() {
    let d = tmpdir("trust3", "inputs");
    let o = meid().args(["simulate", "/dev/zero"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("/dev/zero: is a character device, not a regular file"),
        "{}",
        stderr(&o)
    );
    // A mesh that is a device.
    let m = d.join("mesh.toml");
    std::fs::write(
        &m,
        read(
            &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../meid/tests/data/ss_plate_tri.toml"),
        )
        .replace("ss_plate_tri.msh", "/dev/urandom"),
    )
    .unwrap();
    let t0 = Instant::now();
    let o = meid().args(["modes"]).arg(&m).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("/dev/urandom: is a character device"),
        "{}",
        stderr(&o)
    );
    assert!(t0.elapsed() < Duration::from_secs(30));
    // A directory as measured records; a FIFO as a model.
    let o = meid().arg("measure").arg(&d).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("is a directory, not a regular file"),
        "{}",
        stderr(&o)
    );
    let fifo = d.join("fifo.toml");
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        let o = meid().arg("simulate").arg(&fifo).output().unwrap();
        assert_eq!(o.status.code(), Some(2));
        assert!(stderr(&o).contains("is a FIFO"), "{}", stderr(&o));
    }
    // Over the memory limit.
    let o = meid()
        .args(["--max-memory", "1KiB", "simulate"])
        .arg(example_file("paper-lumped.toml"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("over the memory limit of 1.00 KiB"),
        "{}",
        stderr(&o)
    );
    // A 100 kB line in a model: the error quotes a clipped line.
    let long = d.join("long.toml");
    std::fs::write(
        &long,
        format!("name = \"x\"\nbad = {}\n", "7".repeat(100_000) + "x"),
    )
    .unwrap();
    let o = meid().arg("simulate").arg(&long).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).len() < 2000,
        "{} bytes of stderr",
        stderr(&o).len()
    );
}

/// The staging directories in `dir`.
fn staging(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|r| {
            r.flatten()
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| n.starts_with(".meid-staging"))
                .collect()
        })
        .unwrap_or_default()
}

/// A long `simulate -o dir` (a 200 s record of the lumped example), started.
fn long_run(dir: &Path) -> std::process::Child {
    meid()
        .args(["simulate", "-q", "--duration", "200", "-o"])
        .arg(dir)
        .arg(example_file("paper-lumped.toml"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until `dir` holds a staging directory (the run is writing).
fn wait_for_staging(dir: &Path) {
    let t0 = Instant::now();
    while staging(dir).is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no staging directory appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Item 14. SIGINT ends a run with exit code 130, SIGTERM with 143, and neither leaves its
/// staging directory (before: the process died by the signal, leaving
/// `DIR/.meid-staging.PID.N` with the partial history until the next run into DIR). While a
/// run writes into DIR, a second run into DIR is refused.
#[test]
fn signals_clean_up_and_a_second_writer_is_refused() {
    for (sig, code) in [("-INT", 130), ("-TERM", 143)] {
        let d = tmpdir("trust3", &format!("signal{sig}"));
        let mut child = long_run(&d);
        wait_for_staging(&d);
        if sig == "-INT" {
            // A second writer into the same directory while the first runs.
            let o = meid()
                .args(sweep_args(&example_file("paper-lumped.toml")))
                .arg("-o")
                .arg(&d)
                .output()
                .unwrap();
            assert_eq!(o.status.code(), Some(2));
            assert!(
                stderr(&o).contains("another meid run is writing into this directory"),
                "{}",
                stderr(&o)
            );
        }
        let st = Command::new("kill")
            .arg(sig)
            .arg(child.id().to_string())
            .status()
            .unwrap();
        assert!(st.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{sig}: {status:?}");
        assert!(staging(&d).is_empty(), "{sig}: {:?}", staging(&d));
        // The directory is free again.
        ok(meid()
            .args(["simulate", "-q", "-o"])
            .arg(&d)
            .arg(example_file("paper-lumped.toml"))
            .output()
            .unwrap());
    }
}

/// Item 7. `compare --duration` shorter than one sample is an error naming the record, the
/// sampling interval and what to give (before: −inf/NaN dB with exit 0). A measured sample of
/// 1e307 in `validate` is an error naming the value (before: "error +inf %").
#[test]
fn non_finite_results_are_errors_naming_the_value() {
    let ex = example_file("paper-lumped.toml");
    let o = meid()
        .arg("compare")
        .arg(&ex)
        .args(["--duration", "1e-5"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("shorter than one sampling interval") && e.contains("5e-5 s"),
        "{e}"
    );

    let d = tmpdir("trust3", "validate");
    ok(meid()
        .args(["simulate", "-q", "--case", "none", "-o"])
        .arg(d.join("none"))
        .arg(&ex)
        .output()
        .unwrap());
    let csv = d.join("none/history.csv");
    let text = read(&csv);
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let head: Vec<&str> = lines[0].split(',').collect();
    let col = head
        .iter()
        .position(|h| h.starts_with("bed_acceleration"))
        .unwrap_or_else(|| panic!("{head:?}"));
    let k = lines.len() / 3;
    let mut cells: Vec<String> = lines[k].split(',').map(str::to_string).collect();
    cells[col] = "1e307".into();
    lines[k] = cells.join(",");
    std::fs::write(&csv, lines.join("\n") + "\n").unwrap();
    let o = meid()
        .arg("validate")
        .arg(&ex)
        .arg("--measured")
        .arg(format!("none={}", csv.display()))
        .args(["--pretrigger", "0"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("history.csv") && e.contains("1e307"), "{e}");
}

/// Item 8. `model expand` refuses what a model load refuses — a negative contact stiffness, a
/// NaN damper mass given through `--set` — and writes nothing (before: both were written into
/// the expanded file with exit 0).
#[test]
fn model_expand_refuses_invalid_values_and_writes_nothing() {
    let d = tmpdir("trust3", "expand");
    for (set, field) in [
        (
            "contact.slider_bed.stiffness=-1",
            "contact.slider_bed.stiffness",
        ),
        ("damper.mass=nan", "damper.mass"),
    ] {
        let out = d.join("x.toml");
        let o = meid()
            .args(["model", "expand"])
            .arg(example_file("paper-soft-base.toml"))
            .args(["--set", set, "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{set}: {}", stderr(&o));
        assert!(stderr(&o).contains(field), "{set}: {}", stderr(&o));
        assert!(!out.exists(), "{set}: written");
    }
}

/// Item 15. A sweep journal that cannot be written (a file-size limit: EFBIG, as a full disk
/// gives ENOSPC) is reported as that file's error, not as a "numerical failure".
#[test]
fn a_journal_write_error_names_the_journal() {
    let d = tmpdir("trust3", "efbig");
    let bin = env!("CARGO_BIN_EXE_meid");
    // 4 blocks of 512 B: the journal's first line and header fit, its rows do not.
    let script = format!(
        "trap '' XFSZ; ulimit -f 4; exec '{bin}' sweep '{}' --vary damper.mass=2..5:40 -q -o '{}'",
        example_file("paper-lumped.toml").display(),
        d.display()
    );
    let o = Command::new("bash")
        .arg("-c")
        .arg(&script)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("sweep.partial.csv") && !e.contains("numerical failure"),
        "{e}"
    );
}
