//! Defects a new user's audit found (commit c54de10), each as the behaviour it now has:
//! a blow train faster than its collision, the two range syntaxes, the flag a model error is
//! blamed on, the size and number formats of error messages, frequencies below a record's
//! resolution in `meid compare`. (The `meid paper` row label is checked in `paper_cli.rs`.)

use crate::common;

use common::{meid, ok, ok_json, paper_example, stderr};

/// Runs `meid ARGS`, expects exit code 2 and returns stderr.
fn refused(args: &[&str]) -> String {
    let o = meid().args(args).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    assert!(o.stdout.is_empty(), "{args:?} printed on stdout");
    stderr(&o)
}

fn example() -> String {
    paper_example().display().to_string()
}

/// `blows --rate-bpm 1e6`: a blow every 60 µs (1e6 /min; the interval is 60/R exactly)
/// against a collision of 0.678 ms used to exit 0 with "—" for every η and negative gaps.
/// Now exit 2 naming the interval, the collision's duration and the largest valid rate; the
/// duration printed is the end of blow 1's collision that a train at that largest rate
/// reports itself (`collision_end_s` of blow 1, to the 5 digits printed), and a train at that
/// rate, where the machine is still ringing at every strike, runs with an η for every blow.
#[test]
fn blows_refuses_a_stroke_interval_shorter_than_the_collision() {
    let e = example();
    let err = refused(&["blows", &e, "--rate-bpm", "1e6", "--blows", "4"]);
    assert!(err.contains("shorter than the collision"), "{err}");
    assert!(err.contains("a blow every 6e-5 s"), "{err}");
    assert!(err.contains("--rate-bpm 1000000"), "{err}");
    assert!(err.contains("lasts 0.00067811 s"), "{err}");
    // 60 / 6.7811e-4 s = 88481 /min, rounded down to 4 digits.
    assert!(err.contains("at most 88480"), "{err}");
    let j = ok_json(
        meid()
            .args(["blows", &e, "--rate-bpm", "88480", "--blows", "4", "--json"])
            .output()
            .unwrap(),
    );
    let blows = j["blows"].as_array().unwrap();
    let t_c = blows[0]["collision_end_s"].as_f64().unwrap();
    assert!((t_c - 6.7811e-4).abs() < 5e-9, "collision end {t_c} s");
    assert_eq!(j["interval_s"].as_f64().unwrap(), 60.0 / 88480.0);
    for (k, b) in blows.iter().enumerate() {
        let eta = b["energy_ratio"].as_f64();
        assert!(
            eta.is_some_and(|v| v > 0.0 && v < 1.0),
            "blow {}: {b}",
            k + 1
        );
        // the collision ends inside its interval
        let end = b["collision_end_s"].as_f64().unwrap() - b["start_s"].as_f64().unwrap();
        assert!(
            end > 0.0 && end <= 60.0 / 88480.0,
            "blow {}: collision {end} s",
            k + 1
        );
        assert!(b["damper_gap_at_strike_m"].as_f64().unwrap() >= 0.0);
    }
    // not at rest at the strikes: that is no reason to refuse
    assert!(blows[1]["machine_energy_at_strike_j"].as_f64().unwrap() > 0.1);
    // the bare machine: a shorter collision (0.498 ms), its own limit
    let err = refused(&["blows", &e, "--rate-bpm", "1e6", "--case", "none"]);
    assert!(
        err.contains("lasts 0.00049783 s") && err.contains("at most 120500"),
        "{err}"
    );
}

/// A damper gap is never negative: at 185 /min with a two-way dashpot (then run with the
/// interval rounded to 0.32435 s; now 60/R exactly, so 184.99 /min, T = 0.324342 s) the bed is
/// against the returned damper when blow 7 strikes (contact closed), which used to be reported
/// as a gap of −5.4e-8 m; the gap is now 0 there and ≥ 0 everywhere.
#[test]
fn damper_gaps_are_never_negative() {
    let e = example();
    let j = ok_json(
        meid()
            .args([
                "blows",
                &e,
                "--rate-bpm",
                "184.99",
                "--blows",
                "8",
                "--set",
                "damper.dashpot=\"two-way\"",
                "--json",
            ])
            .output()
            .unwrap(),
    );
    let gaps: Vec<f64> = j["blows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["damper_gap_at_strike_m"].as_f64().unwrap())
        .collect();
    assert!(gaps.iter().all(|g| *g >= 0.0), "{gaps:?}");
    assert_eq!(gaps[6], 0.0, "{gaps:?}");
    assert!(gaps[1] > 1e-5, "{gaps:?}");
    assert!(j["damper_gap_at_next_strike_m"].as_f64().unwrap() >= 0.0);
}

/// `optimize --bounds P=LO..HI` and `calibrate --bounds P=LO:HI` each refused the other's
/// form; both read both now (one parser). The runs stop at a later check (the budget, the
/// iteration limit), which they reach only with the bounds parsed.
#[test]
fn both_range_forms_are_read_by_both_commands() {
    let e = example();
    for b in ["wd/ws=0.5..2", "wd/ws=0.5:2"] {
        let err = refused(&[
            "optimize",
            &e,
            "--over",
            "wd/ws",
            "--bounds",
            b,
            "--max-simulations",
            "1",
        ]);
        assert!(err.contains("--max-simulations"), "{b}: {err}");
        assert!(!err.contains("expected PATH"), "{b}: {err}");
    }
    for b in [
        "contact.slider_bed.stiffness=1e7..1e8",
        "contact.slider_bed.stiffness=1e7:1e8",
    ] {
        let err = refused(&[
            "calibrate",
            &e,
            "--measured",
            "none-such.uff",
            "--fit",
            "contact.slider_bed.stiffness",
            "--bounds",
            b,
            "--max-iterations",
            "0",
        ]);
        assert!(
            err.contains("--max-iterations must be at least 1"),
            "{b}: {err}"
        );
    }
    // a bad range names both forms
    let err = refused(&[
        "calibrate",
        &e,
        "--measured",
        "none-such.uff",
        "--fit",
        "contact.slider_bed.stiffness",
        "--bounds",
        "contact.slider_bed.stiffness=1e7",
    ]);
    assert!(err.contains("LO..HI") && err.contains("LO:HI"), "{err}");
    let help = ok(meid().args(["calibrate", "--help"]).output().unwrap());
    assert!(help.contains("PATH=LO..HI"), "{help}");
}

/// A flag folded into the model as an override is named as the user gave it:
/// `--rate 0` used to be reported as `--set simulation.sample_rate=0e0`.
#[test]
fn model_errors_name_the_flag_not_its_override() {
    let e = example();
    for (args, want, field) in [
        (&["--rate", "0"][..], "--rate 0:", "simulation.sample_rate"),
        (
            &["--rate", "NaN"][..],
            "--rate NaN:",
            "simulation.sample_rate",
        ),
        (
            &["--rate", "inf"][..],
            "--rate inf:",
            "simulation.sample_rate",
        ),
        (
            &["--duration", "0"][..],
            "--duration 0:",
            "simulation.duration",
        ),
        (
            &["--duration", "1e-400"][..],
            "--duration 0:",
            "simulation.duration",
        ),
    ] {
        let mut a = vec!["simulate", e.as_str()];
        a.extend_from_slice(args);
        let err = refused(&a);
        assert!(err.contains(want) && err.contains(field), "{args:?}: {err}");
        assert!(!err.contains("--set"), "{args:?}: {err}");
    }
    // a --set of the same field is still named as such
    let err = refused(&["simulate", &e, "--set", "simulation.sample_rate=0"]);
    assert!(err.contains("--set simulation.sample_rate=0"), "{err}");
}

/// `--max-memory 1e300` said "must be at least 1 byte and finite"; it is too large, and the
/// message gives the largest size accepted (just below 2^64 B).
#[test]
fn max_memory_too_large_says_so() {
    let e = example();
    let err = refused(&["--max-memory", "1e300", "simulate", &e]);
    assert!(err.contains("too large"), "{err}");
    assert!(err.contains("1.8446744073709552e19"), "{err}");
    assert!(!err.contains("finite"), "{err}");
    let err = refused(&["--max-memory", "0", "simulate", &e]);
    assert!(err.contains("at least 1 byte"), "{err}");
}

/// Numbers in validation errors are compact: `slider.velocity=1e100` used to print as a
/// 101-digit integer.
#[test]
fn numbers_in_errors_are_compact() {
    let e = example();
    let err = refused(&["simulate", &e, "--set", "slider.velocity=1e100"]);
    assert!(err.contains("slider.velocity = 1e100 m/s"), "{err}");
    let longest_digits = err
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest_digits < 20, "{err}");
    let err = refused(&[
        "simulate",
        &e,
        "--set",
        "structure.lumped.masses[0].mass=-1e-300",
    ]);
    assert!(err.contains("-1e-300"), "{err}");
}

/// `compare --frequencies 1e-9` printed rows of bands labelled "0 Hz 0.0-0.0". A named
/// frequency must now be at least the record's frequency resolution 1/T (0.5 Hz for the
/// default 2 s record, 0.25 Hz for 4 s); bands below 1 Hz keep their digits.
#[test]
fn compare_refuses_frequencies_below_the_record_resolution() {
    let e = example();
    let err = refused(&["compare", &e, "--frequencies", "1e-9"]);
    assert!(
        err.contains("--frequencies") && err.contains("0.5 Hz"),
        "{err}"
    );
    assert!(err.contains("2 s record"), "{err}");
    let err = refused(&["compare", &e, "--frequencies", "0.3", "--duration", "2"]);
    assert!(err.contains("0.3 Hz is below 0.5 Hz"), "{err}");
    // 0.3 Hz with a 4 s record: accepted; its bands start at the 0.16 Hz band
    let out = ok(meid()
        .args(["compare", &e, "--frequencies", "0.3,283", "--duration", "4"])
        .output()
        .unwrap());
    assert!(out.contains("0.16 Hz") && out.contains("0.315 Hz"), "{out}");
    assert!(out.contains("0.14-0.18"), "{out}");
    assert!(!out.contains(" 0 Hz") && !out.contains("0.0-0.0"), "{out}");
}

/// `meid blows` printed the last blow's levels as "the steady" levels to 4 decimals: 110.5651 N
/// after 10 blows, 110.5272 N after 40 (the train still moving by 0.08 N a blow). It now says
/// they are blow N's levels, an estimate, with the last blow-to-blow change beside them; that
/// change bounds the distance to the 40-blow level here.
#[test]
fn blows_steady_levels_are_given_as_estimates_with_their_last_change() {
    let e = example();
    let text = ok(meid()
        .args(["blows", &e, "--blows", "10"])
        .output()
        .unwrap());
    // The march's line (the production verdict and steady states come before it).
    let line = text
        .lines()
        .find(|l| l.trim_start().starts_with("steady ("))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(line.contains("blow 10's levels, an estimate"), "{line}");
    let after = |key: &str| -> (f64, f64) {
        let rest = &line[line.find(key).unwrap() + key.len()..];
        let mut w = rest.split_whitespace();
        let level: f64 = w.next().unwrap().parse().unwrap();
        w.next(); // unit
        assert_eq!(w.next(), Some("±"), "{line}");
        (level, w.next().unwrap().parse().unwrap())
    };
    let (force, df) = after("floor force ");
    let (acc, da) = after("bed acceleration ");
    let j = ok_json(
        meid()
            .args(["blows", &e, "--blows", "40", "--json"])
            .output()
            .unwrap(),
    );
    let f40 = j["steady"]["peak_floor_force_n"].as_f64().unwrap();
    let a40 = j["steady"]["peak_bed_acceleration_m_per_s2"]
        .as_f64()
        .unwrap();
    assert!((force - 110.5651).abs() < 1e-4 && (f40 - 110.5272).abs() < 1e-4);
    assert!((force - f40).abs() <= df, "{force} ± {df} vs {f40}");
    assert!((acc - a40).abs() <= da, "{acc} ± {da} vs {a40}");
}

/// A rate so low that one blow alone exceeds the run-length limit used to say "Reduce the
/// number of blows (--blows) to at most 0"; it now names the rate to give.
#[test]
fn blows_too_slow_a_rate_names_the_lowest_valid_rate() {
    let e = example();
    let err = refused(&["blows", &e, "--rate-bpm", "0.0001", "--blows", "3"]);
    assert!(!err.contains("at most 0"), "{err}");
    assert!(err.contains("Give --rate-bpm at least"), "{err}");
    let r_min: f64 = err
        .rsplit("at least ")
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    // The rate named runs (one blow of 60/R_min s is within the limit).
    let o = meid()
        .args([
            "blows",
            &e,
            "--rate-bpm",
            &r_min.to_string(),
            "--blows",
            "1",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
}
