//! `meid measure`, `meid validate` and the `--uff` exports end to end.

use crate::common;

use common::{meid, ok, ok_json, paper_example, stderr, tmpdir};
use serde_json::Value;

#[test]
fn measure_json_has_the_issue_fields_and_sample_peaks() {
    let d = tmpdir("measure", "json");
    let f = d.join("lab.csv");
    // Two blows one second apart on the hammer; the acceleration in g.
    let mut s = String::from("time_s,accel_B_g,hammer_n\n");
    for i in 0..2000 {
        let t = i as f64 * 1e-3;
        let tb = t % 1.0;
        let hammer = if (0.1..0.103).contains(&tb) {
            1000.0
        } else {
            0.0
        };
        let acc = if tb >= 0.1 {
            (-(tb - 0.1) * 20.0).exp() * (2.0 * std::f64::consts::PI * 50.0 * (tb - 0.1)).sin()
        } else {
            0.0
        };
        s.push_str(&format!("{t},{acc},{hammer}\n"));
    }
    std::fs::write(&f, s).unwrap();
    let out = ok(meid()
        .args([
            "measure",
            f.to_str().unwrap(),
            "--json",
            "--pretrigger",
            "0.05",
        ])
        .output()
        .unwrap());
    let v: Value = serde_json::from_str(&out).unwrap();
    let chans = v["records"].as_array().unwrap();
    assert_eq!(chans.len(), 2);
    let keys: Vec<&str> = chans[0]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    let mut want = vec![
        "name",
        "unit",
        "samples",
        "sample_rate_hz",
        "peak",
        "peak_time_s",
        "baseline",
        "blows",
        "blows_averaged",
        "record_s",
        "pretrigger_s",
        "dominant_frequency_hz",
        "dominant_level_db",
        "window",
        "clipped_samples",
    ];
    let mut got = keys.clone();
    want.sort();
    got.sort();
    assert_eq!(got, want);
    let a = &chans[0];
    assert_eq!(a["name"], "accel_B");
    assert_eq!(a["unit"], "m/s^2");
    assert_eq!(a["samples"], 2000);
    assert!((a["sample_rate_hz"].as_f64().unwrap() - 1000.0).abs() < 1e-6);
    assert_eq!(a["blows"], 2);
    // The second blow's 1 s record from 0.05 s before its trigger runs past the end.
    assert_eq!(a["blows_averaged"], 1);
    assert!((a["dominant_frequency_hz"].as_f64().unwrap() - 50.0).abs() <= 1.0);
    assert_eq!(chans[1]["unit"], "N");
    assert_eq!(chans[1]["peak"], 1000.0);
    // The text says the peak is a sample peak.
    let text = ok(meid()
        .args(["measure", f.to_str().unwrap(), "--pretrigger", "0.05"])
        .output()
        .unwrap());
    assert!(text.contains("sample peak"), "{text}");
    // -o writes the set.
    let o = d.join("out");
    ok(meid()
        .args([
            "measure",
            f.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap());
    for name in [
        "measure.json",
        "bands.csv",
        "accel_B_spectrum.csv",
        "accel_B_spectrum.png",
        "hammer_average.svg",
        "manifest.json",
    ] {
        assert!(o.join(name).exists(), "{name}");
    }
}

#[test]
fn bad_units_exit_2_naming_file_and_column() {
    let d = tmpdir("measure", "bad");
    let f = d.join("lab.csv");
    std::fs::write(&f, "time_s,accel_B_furlongs\n0,1\n0.001,2\n").unwrap();
    let o = meid()
        .args(["measure", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains("lab.csv:1: column 2 'accel_B_furlongs'"), "{e}");
    let f = d.join("lab.uff");
    std::fs::write(&f, "    -1\n    58\nx\n").unwrap();
    let o = meid()
        .args(["measure", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("lab.uff: dataset 1 (58 starting at line 1)"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn uff_exports_read_back_and_validate_to_zero() {
    let d = tmpdir("measure", "uff");
    let ex = paper_example();
    let ex = ex.to_str().unwrap();
    for case in ["none", "damper"] {
        let o = d.join(case);
        ok(meid()
            .args([
                "simulate",
                ex,
                "--case",
                case,
                "-o",
                o.to_str().unwrap(),
                "--uff",
                "-q",
            ])
            .output()
            .unwrap());
        assert!(o.join("history.uff").exists());
    }
    // history.uff holds the numbers of history.csv.
    let csv = d.join("none/history.csv");
    let uff = d.join("none/history.uff");
    // A simulated history starts with the blow: no pre-trigger.
    let a: Value = serde_json::from_str(&ok(meid()
        .args([
            "measure",
            csv.to_str().unwrap(),
            "--json",
            "--pretrigger",
            "0",
        ])
        .output()
        .unwrap()))
    .unwrap();
    let b: Value = serde_json::from_str(&ok(meid()
        .args([
            "measure",
            uff.to_str().unwrap(),
            "--json",
            "--pretrigger",
            "0",
        ])
        .output()
        .unwrap()))
    .unwrap();
    for (x, y) in a["records"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["records"].as_array().unwrap())
    {
        assert_eq!(x["name"], y["name"]);
        assert_eq!(x["peak"], y["peak"]);
        assert_eq!(x["samples"], y["samples"]);
    }
    // --uff needs -o.
    let o = meid().args(["simulate", ex, "--uff"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    // Validation of the simulation against itself.
    let out = ok(meid()
        .args([
            "validate",
            ex,
            "--measured",
            &format!("none={}", d.join("none/history.uff").display()),
            "--measured",
            &format!("damper={}", d.join("damper/history.uff").display()),
            "--pretrigger",
            "0",
            "--json",
        ])
        .output()
        .unwrap());
    let v: Value = serde_json::from_str(&out).unwrap();
    for c in v["cases"].as_array().unwrap() {
        for ch in c["channels"].as_array().unwrap() {
            assert!(ch["peak_error_percent"].as_f64().unwrap().abs() < 1e-9);
            for m in ch["modes"].as_array().unwrap() {
                assert_eq!(m["frequency_error_hz"], 0.0);
                assert!(m["level_difference_db"].as_f64().unwrap().abs() < 1e-9);
            }
        }
    }
    let red = v["reductions"].as_array().unwrap();
    assert!(!red.is_empty());
    for r in red {
        assert!(
            (r["measured_db"].as_f64().unwrap() - r["simulated_db"].as_f64().unwrap()).abs() < 1e-9
        );
    }
    // Without --pretrigger 0 the error says why.
    let o = meid()
        .args([
            "validate",
            ex,
            "--measured",
            d.join("none/history.uff").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--pretrigger"), "{}", stderr(&o));
    // Modes export: 2411 + 55.
    let m = d.join("modes");
    ok(meid()
        .args(["modes", ex, "-o", m.to_str().unwrap(), "--uff", "-q"])
        .output()
        .unwrap());
    let t = std::fs::read_to_string(m.join("modes.uff")).unwrap();
    assert!(
        t.contains("  2411") && t.matches("\n    55").count() == 2,
        "{t}"
    );
}

/// meid's own simulated history (history.uff and history.csv) starts with the blow, within the
/// default 0.01 s pre-trigger: `meid measure` with default options processes it (it was refused
/// until `--pretrigger 0`), keeping the one sample (0.00005 s at 20 kHz) the file has before the
/// first trigger, says so in a note (text and `pretrigger_note` in the JSON), and reads the same
/// sample peaks as `--pretrigger 0` but where the extra sample, t = 0, holds a peak (the machine
/// is at rest then; the slider moves at 1.2 m/s).
#[test]
fn measure_takes_a_simulated_history_with_default_options() {
    let d = tmpdir("measure", "default-pretrigger");
    let ex = paper_example();
    let run = d.join("run");
    ok(meid()
        .args([
            "simulate",
            ex.to_str().unwrap(),
            "-o",
            run.to_str().unwrap(),
            "--uff",
            "-q",
        ])
        .output()
        .unwrap());
    for file in ["history.uff", "history.csv"] {
        let f = run.join(file);
        let f = f.to_str().unwrap();
        let t = ok(meid().args(["measure", f]).output().unwrap());
        assert!(
            t.contains("note:") && t.contains("keep the 0.000050 s the file has before it"),
            "{file}: {t}"
        );
        let v: Value =
            serde_json::from_str(&ok(meid().args(["measure", f, "--json"]).output().unwrap()))
                .unwrap();
        let zero: Value = serde_json::from_str(&ok(meid()
            .args(["measure", f, "--json", "--pretrigger", "0"])
            .output()
            .unwrap()))
        .unwrap();
        for (c, z) in v["records"]
            .as_array()
            .unwrap()
            .iter()
            .zip(zero["records"].as_array().unwrap())
        {
            assert_eq!(c["blows_averaged"], 1, "{file}: {c}");
            assert!(
                (c["pretrigger_s"].as_f64().unwrap() - 5e-5).abs() < 1e-12,
                "{file}: {c}"
            );
            let note = c["pretrigger_note"].as_str().unwrap();
            assert!(
                note.contains("'contact_force_slider_bed'") && note.contains(file),
                "{note}"
            );
            assert!(z.get("pretrigger_note").is_none(), "{z}");
            // The one extra sample, t = 0, is the machine at rest; only the slider moves then.
            if c["peak_time_s"] != 0.0 {
                assert_eq!(c["peak"], z["peak"], "{file}: {c} vs {z}");
            } else {
                assert!(c["name"].as_str().unwrap().starts_with("slider_"), "{c}");
            }
        }
    }
}

/// Every CSV field of the files in `dir` other than the header and the channel names is a
/// finite number or empty; every number in the JSON files is finite (none is null).
fn assert_all_finite(dir: &std::path::Path) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if name.ends_with(".csv") {
            let t = std::fs::read_to_string(&p).unwrap();
            for line in t.lines().skip(1) {
                for (k, f) in line.split(',').enumerate() {
                    if (name == "bands.csv" && k == 0) || f.is_empty() {
                        continue;
                    }
                    let v: f64 = f.parse().unwrap_or_else(|_| panic!("{name}: '{f}'"));
                    assert!(v.is_finite(), "{name}: {line}");
                }
            }
        } else if name == "measure.json" {
            let t = std::fs::read_to_string(&p).unwrap();
            assert!(!t.contains("null"), "{t}");
        }
    }
}

/// Audit (session 11): `meid measure run/history.uff --record 0.3` (and `--record 1e9`) gave
/// the default's 283.97 Hz / 18.60 dB: the default 0.01 s pre-trigger did not fit before the
/// blow that starts a simulated record, so the whole file was processed and called
/// "blow-averaged". Now measure keeps the pre-trigger the record has (one sample, 0.00005 s)
/// and says so, while validate refuses naming --pretrigger and its range; --record is honoured
/// (283.33 Hz = 85/0.3 s, a line of the 0.3 s record); a record that fits no blow or is shorter
/// than 16 samples is refused with the valid range.
#[test]
fn measure_honours_record_and_refuses_settings_that_fit_no_blow() {
    let d = tmpdir("measure", "record");
    let ex = paper_example();
    let run = d.join("run");
    ok(meid()
        .args([
            "simulate",
            ex.to_str().unwrap(),
            "-o",
            run.to_str().unwrap(),
            "--uff",
            "-q",
        ])
        .output()
        .unwrap());
    let uff = run.join("history.uff");
    let uff = uff.to_str().unwrap();
    let measure = |extra: &[&str]| {
        let mut a = vec!["measure", uff];
        a.extend_from_slice(extra);
        meid().args(a).output().unwrap()
    };
    // The default pre-trigger does not fit before the first blow: the record's own is kept,
    // with a note.
    for extra in [&[][..], &["--record", "0.3"][..]] {
        let t = ok(measure(extra));
        assert!(
            t.contains("note:")
                && t.contains("within the pre-trigger of 0.010000 s")
                && t.contains("keep the 0.000050 s the file has before it"),
            "{extra:?}: {t}"
        );
    }
    let o = meid()
        .args(["validate", ex.to_str().unwrap(), "--measured", uff])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("give a shorter pre-trigger, between 0 and 0.000050 s"),
        "{}",
        stderr(&o)
    );
    // --record is honoured: the lines are those of the 0.3 s record, one blow averaged.
    let v: Value = serde_json::from_str(&ok(measure(&[
        "--pretrigger",
        "0",
        "--record",
        "0.3",
        "--json",
    ])))
    .unwrap();
    for c in v["records"].as_array().unwrap() {
        assert_eq!(c["blows_averaged"], 1, "{c}");
        assert!((c["record_s"].as_f64().unwrap() - 0.3).abs() < 1e-12, "{c}");
        assert_eq!(c["pretrigger_s"], 0.0, "{c}");
        let f = c["dominant_frequency_hz"].as_f64().unwrap();
        assert!(((f * 0.3) - (f * 0.3).round()).abs() < 1e-9, "{f}");
    }
    let acc = &v["records"].as_array().unwrap()[2];
    assert_eq!(acc["name"], "bed_acceleration");
    assert!(
        (acc["dominant_frequency_hz"].as_f64().unwrap() - 85.0 / 0.3).abs() < 1e-9,
        "{acc}"
    );
    // The text says what was averaged, over which record.
    let t = ok(measure(&["--pretrigger", "0", "--record", "0.3"]));
    assert!(
        t.contains("averaged over the blows' records (0.300000 s from 0.000000 s before"),
        "{t}"
    );
    // A record longer than fits: refused with the range.
    let o = measure(&["--pretrigger", "0", "--record", "1e9"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("give a record length between 0.000800 s (16 samples) and 0.500000 s")
            && e.contains("--record"),
        "{e}"
    );
    // A record too short to resolve anything: refused with the minimum.
    let o = measure(&["--pretrigger", "0", "--record", "1e-6"]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("at least 16 samples (0.000800 s)") && e.contains("--record"),
        "{e}"
    );
}

/// A CSV of `amplitude · sin(2π·50 t)` at 10 kHz for 1 s.
fn sine_csv(path: &std::path::Path, amplitude: f64) {
    let mut s = String::from("time_s,accel_B_m_per_s2\n");
    for i in 0..10_000 {
        let t = i as f64 * 1e-4;
        let x = amplitude * (2.0 * std::f64::consts::PI * 50.0 * t).sin();
        s.push_str(&format!("{t:.4},{x:e}\n"));
    }
    std::fs::write(path, s).unwrap();
}

/// Audit (session 11): `meid measure c5.csv` with a 1e300·sin(2π·50t) column printed "4.00 Hz
/// inf dB" (the line is 50 Hz), `--json` a null level and `-o` wrote inf. Now the spectrum is
/// computed from the record scaled by a power of two: the 50 Hz line and its level, the closed
/// form `E = A²T²/2` of a sinusoid with whole cycles in the record (6000 dB above that of
/// A = 1); files that cannot hold the ESD in SI are refused (exit 2) naming file, column and
/// the valid range; no file of a run that exits 0 holds inf or NaN.
#[test]
fn measure_of_huge_amplitudes_finds_the_line_and_writes_no_infinity() {
    let d = tmpdir("measure", "huge");
    let args = ["--pretrigger", "0", "--record", "0.2", "--json"];
    let level = |a: f64, name: &str| {
        let f = d.join(name);
        sine_csv(&f, a);
        let mut v = vec!["measure", f.to_str().unwrap()];
        v.extend_from_slice(&args);
        let j: Value = serde_json::from_str(&ok(meid().args(v).output().unwrap())).unwrap();
        let c = &j["records"].as_array().unwrap()[0];
        assert_eq!(c["dominant_frequency_hz"], 50.0, "{c}");
        c["dominant_level_db"].as_f64().unwrap()
    };
    // E = A² T²/2 with T = 0.2 s: 10 log10(0.02) dB for A = 1.
    let closed = |a: f64| 20.0 * a.log10() + 10.0 * (0.2_f64 * 0.2 / 2.0).log10();
    for a in [1.0, 1e150, 1e300, 1e-300] {
        let l = level(a, &format!("s{}.csv", a.log10() as i32));
        assert!(
            (l - closed(a)).abs() < 1e-6,
            "A = {a}: {l} dB, {} dB",
            closed(a)
        );
    }
    // The audit's run, defaults: the 50 Hz line at a finite level.
    let f = d.join("c5.csv");
    sine_csv(&f, 1e300);
    let t = ok(meid()
        .args(["measure", f.to_str().unwrap()])
        .output()
        .unwrap());
    assert!(t.contains("50.00 Hz") && !t.contains("inf"), "{t}");
    // -o: the ESD of 1e300 cannot be written in (m/s^2)²·s/Hz: refused, naming the column.
    let o = meid()
        .args(["measure", f.to_str().unwrap(), "-o"])
        .arg(d.join("out300"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("c5.csv, column 2: channel 'accel_B'") && e.contains("|x| ≤"),
        "{e}"
    );
    assert!(!d.join("out300/measure.json").exists());
    // 1e150: representable; every number written is finite.
    let f = d.join("c6.csv");
    sine_csv(&f, 1e150);
    let out = d.join("out150");
    ok(meid()
        .args(["measure", f.to_str().unwrap(), "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap());
    assert_all_finite(&out);
}

/// Non-finite samples and values beyond the largest double once converted to SI are refused
/// naming file, line and column (the audit's "1e300 g" would overflow on conversion).
#[test]
fn measure_refuses_non_finite_samples_with_line_and_column() {
    let d = tmpdir("measure", "nonfinite");
    for (body, want) in [
        (
            "0,1\n0.001,nan\n",
            "lab.csv:3: column 2 (accel_B): nan is not a finite number",
        ),
        (
            "0,1\n0.001,inf\n",
            "lab.csv:3: column 2 (accel_B): inf is not a finite number",
        ),
        (
            "0,1\n0.001,1e400\n",
            "lab.csv:3: column 2 (accel_B): 1e400 is not a finite number",
        ),
        (
            "0,1e308\n0.001,1\n",
            "lab.csv:2: column 2 (accel_B): 1e308 × 9.80665 (to SI) is beyond the largest double",
        ),
    ] {
        let f = d.join("lab.csv");
        std::fs::write(&f, format!("time_s,accel_B_g\n{body}")).unwrap();
        let o = meid()
            .args(["measure", f.to_str().unwrap()])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{body}");
        assert!(stderr(&o).contains(want), "{}", stderr(&o));
    }
}

/// When no blow is found at all (here the hammer channel sits at a constant 5 N, so the
/// trigger never arms), the whole record is processed as one: a warning says so, the JSON
/// gives 0 blows averaged, and the text never calls the spectrum blow-averaged.
#[test]
fn no_blow_found_is_reported_as_zero_blows_averaged() {
    let d = tmpdir("measure", "noblow");
    let f = d.join("lab.csv");
    let mut s = String::from("time_s,accel_B_m_per_s2,hammer_n\n");
    for i in 0..2000 {
        let t = i as f64 * 1e-3;
        let a = (2.0 * std::f64::consts::PI * 50.0 * t).sin();
        s.push_str(&format!("{t},{a},5\n"));
    }
    std::fs::write(&f, s).unwrap();
    let o = meid()
        .args(["measure", f.to_str().unwrap()])
        .output()
        .unwrap();
    let text = ok(o.clone());
    let e = stderr(&o);
    assert!(
        e.contains("warning") && e.contains("no blow found") && e.contains("accel_B, hammer"),
        "{e}"
    );
    assert!(
        text.contains("no blow was found for accel_B, hammer")
            && text.contains("not blow-averaged")
            && !text.contains("averaged over the blows"),
        "{text}"
    );
    let v: Value = serde_json::from_str(&ok(meid()
        .args(["measure", f.to_str().unwrap(), "--json"])
        .output()
        .unwrap()))
    .unwrap();
    let a = &v["records"].as_array().unwrap()[0];
    assert_eq!(a["blows"], 0);
    assert_eq!(a["blows_averaged"], 0);
    assert!((a["record_s"].as_f64().unwrap() - 2.0).abs() < 1e-9, "{a}");
    assert_eq!(a["dominant_frequency_hz"], 50.0);
}

/// A lab file as a spreadsheet in a decimal-comma locale writes it (`;`, `1,5`), with the
/// blow force (hammer) and the force to the floor (a response ringing at 20 Hz):
/// `--force-window` windows the hammer only, and the floor force keeps its line (session 12
/// audit: the floor force was cut to the hammer's pulse, and `;` files were refused with "no
/// time column"). A UFF file with a microphone channel beside the accelerometer reads, the
/// microphone passed over with a warning (it was refused: "unknown unit 'Pa'").
#[test]
fn force_window_on_the_hammer_only_semicolon_csv_and_a_microphone_passed_over() {
    let d = tmpdir("measure", "forcewin");
    let f = d.join("lab.csv");
    let mut s = String::from("time_s;hammer_n;force_floor_n\r\n");
    for i in 0..4000 {
        let t = i as f64 * 1e-3;
        let tb = t % 1.0;
        let hammer = if (0.1..0.103).contains(&tb) {
            1000.0
        } else {
            0.0
        };
        let floor = if tb >= 0.1 {
            let u = tb - 0.1;
            200.0 * (-u * 3.0).exp() * (2.0 * std::f64::consts::PI * 20.0 * u).sin()
        } else {
            0.0
        };
        s.push_str(&format!("{t};{hammer};{floor}\r\n").replace('.', ","));
    }
    std::fs::write(&f, s).unwrap();
    let run = |extra: &[&str]| -> Value {
        let mut args = vec![
            "measure",
            f.to_str().unwrap(),
            "--json",
            "--pretrigger",
            "0.05",
        ];
        args.extend_from_slice(extra);
        ok_json(meid().args(&args).output().unwrap())["records"].clone()
    };
    let plain = run(&[]);
    let windowed = run(&["--force-window"]);
    let (p, w) = (&plain[1], &windowed[1]);
    assert_eq!(w["name"], "force_floor");
    assert_eq!(w["window"], "rectangular");
    assert_eq!(p["dominant_frequency_hz"], w["dominant_frequency_hz"]);
    assert_eq!(w["dominant_frequency_hz"], 20.0);
    assert_eq!(p["dominant_level_db"], w["dominant_level_db"]);
    assert_eq!(windowed[0]["name"], "hammer");
    assert!(
        windowed[0]["window"]
            .as_str()
            .unwrap()
            .starts_with("rectangular × force (pulse 0.053"),
        "{}",
        windowed[0]
    );
    assert_eq!(plain[0]["blows_averaged"], 3);

    let u = d.join("lab.uff");
    let dataset = |name: &str, ty: i64, unit: &str| {
        let mut t = format!("    -1\n    58\n{name}\nNONE\nNONE\nNONE\nNONE\n    1         0    0         0 bed                1   3 NONE               0   0\n         4      2000         1  0.00000e+00  1.00000e-03  0.00000e+00\n        17    0    0    0 Time                 s                   \n{ty:>10}    0    0    0 {name:<20} {unit:<20}\n         0    0    0    0 NONE                 NONE                \n         0    0    0    0 NONE                 NONE                \n");
        for i in 0..2000 {
            let tb = i as f64 * 1e-3;
            let v = if tb >= 0.1 {
                (-(tb - 0.1) * 20.0).exp() * (2.0 * std::f64::consts::PI * 50.0 * (tb - 0.1)).sin()
            } else {
                0.0
            };
            t.push_str(&format!("{v:20.12e}"));
            if i % 4 == 3 {
                t.push('\n');
            }
        }
        t.push_str("    -1\n");
        t
    };
    std::fs::write(
        &u,
        dataset("accel_B", 12, "m/s^2") + &dataset("mic", 15, "Pa"),
    )
    .unwrap();
    let o = meid()
        .args(["measure", u.to_str().unwrap()])
        .output()
        .unwrap();
    let text = ok(o.clone());
    assert!(text.contains("accel_B") && !text.contains("mic "), "{text}");
    let e = stderr(&o);
    assert!(
        e.contains("dataset 2 (58 at line 515)")
            && e.contains("specific data type 15 (pressure, unit 'Pa')")
            && e.contains("passed over"),
        "{e}"
    );
    // `validate` and `calibrate` read the same file and warn of the same channel (they said
    // nothing of it).
    for cmd in [
        vec!["validate"],
        vec!["calibrate", "--fit", "contact.slider_bed.stiffness"],
    ] {
        let o = meid()
            .args(&cmd)
            .arg(paper_example())
            .arg("--measured")
            .arg(&u)
            .output()
            .unwrap();
        let e = stderr(&o);
        assert!(
            e.contains("specific data type 15 (pressure, unit 'Pa')") && e.contains("passed over"),
            "{cmd:?}: {e}"
        );
    }
}
