//! `meid frf` and `meid identify` end to end: meid's own simulated blow (the lumped example,
//! no damper) to FRFs to modes that match `meid modes`; bad input named by file, channel and
//! value (exit 2), doubtful input named in warnings.

use crate::common;

use common::{meid, ok, ok_json, paper_example, stderr, tmpdir};

/// One blow of the bare lumped machine, 2 s at 20 kHz, as `history.uff`.
fn simulated_blow(d: &std::path::Path) -> std::path::PathBuf {
    let sim = d.join("sim");
    ok(meid()
        .args([
            "simulate",
            paper_example().to_str().unwrap(),
            "--case",
            "none",
        ])
        .args([
            "--duration",
            "2",
            "-q",
            "--uff",
            "-o",
            sim.to_str().unwrap(),
        ])
        .output()
        .unwrap());
    sim.join("history.uff")
}

#[test]
fn simulated_blow_to_frf_to_the_modes_of_meid_modes() {
    let d = tmpdir("frf", "e2e");
    let uff = simulated_blow(&d);
    let frf_dir = d.join("frf");
    let frf = ok_json(
        meid()
            .args([
                "frf",
                uff.to_str().unwrap(),
                "--response",
                "bed_acceleration",
            ])
            .args(["--window", "exponential", "--tau", "0.5", "--json"])
            .args(["-o", frf_dir.to_str().unwrap()])
            .output()
            .unwrap(),
    );
    assert_eq!(frf["force"], "contact_force_slider_bed");
    assert_eq!(frf["unit"], "m/s^2/N");
    assert_eq!(frf["window_decay_per_s"], 2.0);
    assert_eq!(frf["channels"].as_array().unwrap().len(), 1);
    for f in [
        "frf.json",
        "frf.csv",
        "frf.uff",
        "frf_magnitude.png",
        "frf_phase.svg",
        "frf_coherence.png",
    ] {
        assert!(frf_dir.join(f).is_file(), "{f} not written");
    }
    let id_dir = d.join("id");
    let id = ok_json(
        meid()
            .args(["identify", frf_dir.join("frf.uff").to_str().unwrap()])
            .args(["--band", "2..400", "--max-order", "20", "--json"])
            .args(["-o", id_dir.to_str().unwrap()])
            .output()
            .unwrap(),
    );
    for f in [
        "identification.json",
        "modes.csv",
        "modes.uff",
        "stabilisation.png",
        "stabilisation.svg",
    ] {
        assert!(id_dir.join(f).is_file(), "{f} not written");
    }
    assert!(id["warnings"].is_array() && id["notes"].is_array());
    assert_eq!(id["window_decay_per_s"], 2.0);
    let modes = ok_json(
        meid()
            .args(["modes", paper_example().to_str().unwrap(), "--json"])
            .output()
            .unwrap(),
    );
    let got = id["modes"].as_array().unwrap();
    let want = modes["modes"].as_array().unwrap();
    assert_eq!(got.len(), want.len(), "{id:#}");
    for (g, w) in got.iter().zip(want) {
        let (fg, fw) = (
            g["frequency_hz"].as_f64().unwrap(),
            w["frequency_hz"].as_f64().unwrap(),
        );
        assert!(((fg - fw) / fw).abs() < 5e-3, "{fg} Hz vs {fw} Hz");
        // The example's modal damping ratio is 1 % in both modes.
        let z = g["damping_ratio"].as_f64().unwrap();
        assert!(((z - 0.01) / 0.01).abs() < 0.1, "ζ = {z} at {fg} Hz");
        assert_eq!(g["shape"].as_array().unwrap().len(), 1);
    }
    // modes.uff reads back as datasets 55 with the frequencies.
    let back = meid::io::uff::read_uff(&id_dir.join("modes.uff")).unwrap();
    assert_eq!(back.modes.len(), got.len());
}

#[test]
fn frf_without_a_force_or_a_blow_is_refused_naming_the_channel() {
    let d = tmpdir("frf", "bad");
    // Accelerations only.
    let f = d.join("accel_only.csv");
    let mut s = String::from("time_s,accel_B_m_per_s2\n");
    for i in 0..1000 {
        s.push_str(&format!("{},{}\n", i as f64 * 1e-3, (i as f64 * 0.3).sin()));
    }
    std::fs::write(&f, s).unwrap();
    let o = meid().args(["frf", f.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("accel_only.csv") && e.contains("no force channel") && e.contains("accel_B"),
        "{e}"
    );
    // A force that stays at zero: no blow.
    let f = d.join("dead_hammer.csv");
    let mut s = String::from("time_s,accel_B_m_per_s2,hammer_n\n");
    for i in 0..1000 {
        s.push_str(&format!(
            "{},{},0\n",
            i as f64 * 1e-3,
            (i as f64 * 0.3).sin()
        ));
    }
    std::fs::write(&f, s).unwrap();
    let o = meid().args(["frf", f.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("dead_hammer.csv") && e.contains("'hammer'") && e.contains("no blow found"),
        "{e}"
    );
    // A file with no FRF for identify.
    let o = meid()
        .args(["identify", d.join("dead_hammer.csv").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

/// Two blows (records of 1.5 s) whose response is noise unrelated to the force: the coherence is
/// low, and both
/// `frf` and `identify` say on which channel and where; asking for more modes than points is
/// named too.
#[test]
fn low_coherence_and_too_few_points_are_named() {
    let d = tmpdir("frf", "coherence");
    let f = d.join("noise.csv");
    let mut s = String::from("time_s,accel_B_m_per_s2,hammer_n\n");
    let mut rng = meid::rng::SplitMix64::new(5);
    for i in 0..4000 {
        let t = i as f64 * 1e-3;
        let hammer = if i % 2000 >= 100 && i % 2000 < 103 {
            1000.0
        } else {
            0.0
        };
        s.push_str(&format!("{t},{},{hammer}\n", rng.next_normal()));
    }
    std::fs::write(&f, s).unwrap();
    let out = d.join("frf");
    let o = meid()
        .args([
            "frf",
            f.to_str().unwrap(),
            "--pretrigger",
            "0.05",
            "--record",
            "1.5",
        ])
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("noise.csv") && e.contains("'accel_B'") && e.contains("coherence below 0.8 at"),
        "{e}"
    );
    let o = meid()
        .args(["identify", out.join("frf.uff").to_str().unwrap()])
        .args(["--max-order", "8", "--modes", "3", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains("frf.uff") && e.contains("coherence below 0.8 at"),
        "{e}"
    );
    assert!(e.contains("3 modes asked from 1 measured point(s)"), "{e}");
}
