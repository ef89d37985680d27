//! Cross-check with sdypy-EMA (PyPI, the Python test-lab tool's LSCF): on the same FRFs (the
//! 3-DOF chain of `identify_checks` with 1 % noise), sdypy-EMA's stable poles closest to meid's
//! modes lie within 0.1 % of meid's frequencies.
//!
//! Needs a Python with sdypy-EMA: `MEID_EMA_PYTHON`, else `target/ci-venv-py/bin/python`
//! (which `.ci/run` creates). Without one the test prints why and passes, unless
//! `MEID_EMA_REQUIRED=1` (set by `.ci/run`), when it fails.

use std::path::{Path, PathBuf};
use std::process::Command;

use meid::identify::{identify, Settings};

use crate::identify_checks::{chain, frfs, lines};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn python() -> Option<PathBuf> {
    let p = std::env::var_os("MEID_EMA_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target/ci-venv-py/bin/python"));
    let ok = p.exists()
        && Command::new(&p)
            .args(["-c", "from sdypy import EMA"])
            .status()
            .is_ok_and(|s| s.success());
    if ok {
        Some(p)
    } else if std::env::var("MEID_EMA_REQUIRED").as_deref() == Ok("1") {
        panic!("MEID_EMA_REQUIRED=1 but {} has no sdypy-EMA", p.display());
    } else {
        eprintln!(
            "skipped: no Python with sdypy-EMA at {} (set MEID_EMA_PYTHON, or run .ci/run, which creates target/ci-venv-py)",
            p.display()
        );
        None
    }
}

#[test]
fn sdypy_ema_finds_meids_frequencies() {
    let Some(py) = python() else { return };
    let (w, _) = chain();
    let f_exact: Vec<f64> = w.iter().map(|w| w / (2.0 * std::f64::consts::PI)).collect();
    let f = lines(0.0, 1.6 * f_exact[2], 0.1);
    let d = frfs(&f, 0.0, 0.01, 7);
    let (lo, hi) = (0.5 * f_exact[0], 1.5 * f_exact[2]);
    let id = identify(
        &d,
        &Settings {
            band_hz: Some((lo, hi)),
            max_order: 24,
            modes: Some(3),
            ..Settings::default()
        },
    )
    .unwrap();
    assert_eq!(id.modes.len(), 3);
    let csv = std::env::temp_dir().join(format!("meid-ema-{}.csv", std::process::id()));
    let mut s = String::from("frequency_hz");
    for o in 0..d.outputs {
        s.push_str(&format!(",re{o},im{o}"));
    }
    s.push('\n');
    for (k, fk) in f.iter().enumerate() {
        s.push_str(&format!("{fk}"));
        for o in 0..d.outputs {
            s.push_str(&format!(",{:e},{:e}", d.h[o][k].re, d.h[o][k].im));
        }
        s.push('\n');
    }
    std::fs::write(&csv, s).unwrap();
    let mut args: Vec<String> = vec![
        root().join(".ci/interop_ema.py").display().to_string(),
        csv.display().to_string(),
        lo.to_string(),
        hi.to_string(),
        "30".into(),
    ];
    args.extend(id.modes.iter().map(|m| m.frequency_hz.to_string()));
    let out = Command::new(&py).args(&args).output().unwrap();
    let _ = std::fs::remove_file(&csv);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let theirs = v["frequency_hz"].as_array().unwrap();
    assert_eq!(theirs.len(), 3);
    for (m, t) in id.modes.iter().zip(theirs) {
        let t = t.as_f64().unwrap();
        assert!(
            ((m.frequency_hz - t) / t).abs() < 1e-3,
            "meid {} Hz, sdypy-EMA {t} Hz",
            m.frequency_hz
        );
    }
}
