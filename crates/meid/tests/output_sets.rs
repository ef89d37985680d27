//! Output files: atomic writes leave no temporary behind on failure, an output set is replaced
//! as a whole (manifest written last), a streamed history is byte for byte the held one, and
//! the memory estimates refuse before allocating.
//!
//! References: the failure cases are made by a directory in place of the target (rename fails
//! after the data were written) and by a file in place of the output directory; the streamed
//! history is compared with `io::history_csv` of the recorded `History` of the same run.

use std::path::{Path, PathBuf};

use meid::analysis::energy::{simulate_observed, StreamRecorder};
use meid::io::{self, AtomicFile, OutputSet, MANIFEST};
use meid::model::{Case, Model};

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("meid-outsets-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .collect();
    v.sort();
    v
}

fn example() -> Model {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    Model::from_file(&p, &[]).unwrap()
}

#[test]
fn a_failed_atomic_write_leaves_no_temporary() {
    let d = tmpdir("atomic");
    // A non-empty directory where the file should go: the data are written to the temporary,
    // then the rename fails.
    std::fs::create_dir_all(d.join("history.csv/inside")).unwrap();
    let e = io::write_atomic(&d.join("history.csv"), &vec![b'x'; 200_000]).unwrap_err();
    assert!(e.to_string().contains("history.csv"), "{e}");
    assert_eq!(names(&d), ["history.csv"], "a temporary was left behind");
    // Dropped before its commit (any error path in between): the temporary goes too.
    let mut f = AtomicFile::create(&d.join("a.csv")).unwrap();
    f.write_all(b"partial").unwrap();
    let tmp = f.temporary_path().to_path_buf();
    assert!(tmp.exists());
    drop(f);
    assert!(!tmp.exists());
    assert_eq!(names(&d), ["history.csv"]);
    // And a committed one is in place, with no temporary.
    let mut f = AtomicFile::create(&d.join("b.csv")).unwrap();
    f.write_all(b"whole").unwrap();
    f.commit().unwrap();
    assert_eq!(std::fs::read(d.join("b.csv")).unwrap(), b"whole");
    assert_eq!(names(&d), ["b.csv", "history.csv"]);
}

#[test]
fn an_output_set_is_replaced_whole_and_a_failed_one_leaves_the_old() {
    let d = tmpdir("set");
    std::fs::write(d.join("notes.txt"), "the user's own file").unwrap();
    // First set: a.csv, map.png.
    let s = OutputSet::begin(&d).unwrap();
    io::write_atomic(&s.path("a.csv"), b"1\n").unwrap();
    io::write_atomic(&s.path("map.png"), b"png").unwrap();
    let files = s.commit("sweep").unwrap();
    assert_eq!(files, [d.join("a.csv"), d.join("map.png")]);
    let m = io::read_manifest(&d).unwrap();
    assert_eq!(m.command, "sweep");
    let listed: Vec<&str> = m.files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(listed, ["a.csv", "map.png"]);
    assert_eq!(m.files[0].bytes, 2);
    // A run that fails before its commit: the old set and its manifest stay as they were,
    // and no staging directory is left.
    let before: Vec<(String, Vec<u8>)> = names(&d)
        .into_iter()
        .map(|n| (n.clone(), std::fs::read(d.join(&n)).unwrap()))
        .collect();
    {
        let s = OutputSet::begin(&d).unwrap();
        io::write_atomic(&s.path("a.csv"), b"2\n3\n").unwrap();
        // error: dropped without commit
    }
    let after: Vec<(String, Vec<u8>)> = names(&d)
        .into_iter()
        .map(|n| (n.clone(), std::fs::read(d.join(&n)).unwrap()))
        .collect();
    assert_eq!(before, after);
    // Second set without map.png: the stale picture of the first set is removed, the user's
    // file is not touched.
    let s = OutputSet::begin(&d).unwrap();
    io::write_atomic(&s.path("a.csv"), b"2\n3\n").unwrap();
    io::write_atomic(&s.path("curve.png"), b"png").unwrap();
    s.commit("sweep").unwrap();
    assert_eq!(names(&d), ["a.csv", "curve.png", MANIFEST, "notes.txt"]);
    assert_eq!(std::fs::read(d.join("a.csv")).unwrap(), b"2\n3\n");
    // A commit that fails half-way (a directory where a file must go) leaves no manifest:
    // the directory is visibly not one whole set.
    std::fs::remove_file(d.join("a.csv")).unwrap();
    std::fs::create_dir_all(d.join("a.csv/blocked")).unwrap();
    let s = OutputSet::begin(&d).unwrap();
    io::write_atomic(&s.path("a.csv"), b"4\n").unwrap();
    assert!(s.commit("sweep").is_err());
    assert!(!d.join(MANIFEST).exists());
    assert!(names(&d).iter().all(|n| !n.starts_with(".meid-staging")));
}

#[test]
fn staging_left_by_a_killed_run_is_removed_by_the_next() {
    if !Path::new("/proc/self").exists() {
        return; // the liveness check needs /proc
    }
    let d = tmpdir("stale");
    // PID 4294967295 cannot exist (Linux PIDs are at most 2^22); PID 1 always does.
    std::fs::create_dir_all(d.join(".meid-staging.4294967295.0/x")).unwrap();
    std::fs::create_dir_all(d.join(".meid-staging.1.0")).unwrap();
    let s = OutputSet::begin(&d).unwrap();
    io::write_atomic(&s.path("a.csv"), b"1\n").unwrap();
    s.commit("simulate").unwrap();
    assert_eq!(names(&d), [".meid-staging.1.0", "a.csv", MANIFEST]);
}

#[test]
fn an_output_directory_that_is_a_file_is_named() {
    let d = tmpdir("notdir");
    let f = d.join("out");
    std::fs::write(&f, "x").unwrap();
    let e = OutputSet::begin(&f).err().unwrap().to_string();
    assert!(e.ends_with("exists and is not a directory"), "{e}");
    assert!(e.starts_with("-o "), "{e}");
}

#[test]
fn a_streamed_history_is_the_held_history_byte_for_byte() {
    let m = example();
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let mut opts = m.options();
    opts.duration = 0.05;
    let held = meid::analysis::simulate(&sys, &opts, true).unwrap();
    let held_csv = io::history_csv(held.history.as_ref().unwrap()).unwrap();
    let mut rec = StreamRecorder::new(&sys, Vec::new()).unwrap();
    let (summary, _) = simulate_observed(&sys, &opts, Some(&mut rec)).unwrap();
    let rows = rec.rows();
    let streamed = rec.finish().unwrap();
    assert_eq!(rows as usize, held.history.as_ref().unwrap().time_s.len());
    assert_eq!(rows, 1001); // 0.05 s at 20 kHz, both ends
    assert_eq!(streamed, held_csv);
    assert_eq!(summary, held.summary);
    // The file writer gives the same bytes.
    let d = tmpdir("stream");
    io::write_history_csv(&d.join("h.csv"), held.history.as_ref().unwrap()).unwrap();
    assert_eq!(std::fs::read(d.join("h.csv")).unwrap(), held_csv);
}
