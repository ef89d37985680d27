//! `meid report MODEL`: the page about one machine (issue 11, points 5 and 7).
//!
//! * The written `index.html` passes `report::html::check_page` (every `src`/`href` resolves
//!   inside the page's directory, every figure has a caption) for the lumped and the FE
//!   soft-base example, and holds every required section with its figures and tables.
//! * The page's numbers are the library's own studies: the comparison in `report.json` is
//!   `meid compare --json`'s, the blow trains are `meid blows --json`'s, bit for bit.
//! * The energy map's centre is the design: ω_s/ω_1 of the lumped example is 150 by the
//!   closed form of its two-mode structure (the file's comment), and E_p+/E_s− there is the
//!   comparison's damper value.
//! * Records exported by `meid simulate --uff` and given back with `--measured` are the
//!   simulation: the "Measured against simulated" section shows 0 % peak errors and measured
//!   reductions equal to the simulated ones.
//! * A model with a `[foundation]` and a damper (examples/paper-on-soil.toml) has the section
//!   "Foundation and surroundings" with its two charts and tables for all three cases; each
//!   receiver's verdict sentence gives |PPV/limit − 1| of `report.json`'s numbers, and a
//!   receiver that fails in some case is in the page's verdict.
//! * Bad input exits with code 2 and a message naming the option.

use crate::common;

use std::path::Path;

use common::{example_file, meid, ok, paper_example, stderr, tmpdir};
use meid::report::html::check_page;

const SECTIONS: [&str; 11] = [
    "results",
    "model",
    "modes",
    "energy-map",
    "cases",
    "measured",
    "test-against-model",
    "blows",
    "optimiser",
    "montecarlo",
    "method",
];

/// The HTML of section `id` (up to the next section).
fn section<'a>(html: &'a str, id: &str) -> &'a str {
    let start = html
        .find(&format!("<section id=\"{id}\">"))
        .unwrap_or_else(|| panic!("section {id} missing"));
    let rest = &html[start..];
    let end = rest.find("</section>").unwrap();
    &rest[..end]
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn check_report(dir: &Path, with_mc: bool) -> String {
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    assert_eq!(check_page(dir, &html), vec![], "check_page");
    for id in SECTIONS {
        section(&html, id);
    }
    assert!(!html.contains("<script"), "no scripts");
    let figures = |id: &str| section(&html, id).matches("<figure").count();
    let tables = |id: &str| section(&html, id).matches("<table").count();
    assert_eq!(figures("energy-map"), 1, "the energy map");
    assert_eq!(
        figures("cases"),
        6,
        "histories, spectra and 1/3-octave levels of a_B and F"
    );
    assert_eq!(tables("cases"), 3, "peaks, reductions and impacts");
    assert_eq!(figures("blows"), 2);
    assert_eq!(tables("model"), 1);
    assert!(tables("modes") >= 2, "modes and truncation");
    assert_eq!(tables("optimiser"), 1);
    assert_eq!(figures("montecarlo"), if with_mc { 2 } else { 0 });
    // Every reduction names its measure beside it.
    let cases = section(&html, "cases");
    for measure in [
        "time-peak",
        "esd-peak",
        "band-level",
        "signal-energy",
        "energy-ratio",
    ] {
        assert!(cases.contains(&format!("<td>{measure}</td>")), "{measure}");
    }
    // The manifest lists index.html and every picture the page names.
    let manifest = std::fs::read_to_string(dir.join("manifest.json")).unwrap();
    assert!(manifest.contains("index.html") && manifest.contains("energy-map.png"));
    html
}

#[test]
fn lumped_report_passes_the_page_check_and_reads_the_library_studies() {
    let d = tmpdir("report", "lumped");
    let out = d.join("page");
    ok(meid()
        .arg("report")
        .arg(paper_example())
        .args([
            "-q",
            "--map-points",
            "11",
            "--vary",
            "contact.slider_bed.stiffness=lognormal(4.3e7,0.2)",
            "--samples",
            "16",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap());
    let html = check_report(&out, true);
    // No [foundation]: no "Foundation and surroundings" section and no foundation member.
    assert!(!html.contains("<section id=\"foundation\">"));
    let report = json(&out.join("report.json"));
    assert!(report.get("foundation").is_none() && report.get("receivers").is_none());
    // No stroke rate anywhere: the production line says its 60 /min is assumed, and does
    // not lead.
    assert_eq!(report["rate_origin"], "assumed");
    let keys = report["key_results"].as_array().unwrap();
    assert!(
        keys[0].as_str().unwrap().starts_with("Energy left"),
        "{keys:?}"
    );
    assert!(
        keys.iter().any(|k| k
            .as_str()
            .unwrap()
            .contains("assumed: the model gives no stroke rate")),
        "{keys:?}"
    );

    // The comparison is `meid compare`'s (same record length), bit for bit (the report
    // carries the model's warnings and notes once, at its top level).
    let mut compare: serde_json::Value = serde_json::from_str(&ok(meid()
        .arg("compare")
        .arg(paper_example())
        .args(["--json", "--duration", "2"])
        .output()
        .unwrap()))
    .unwrap();
    let c = compare.as_object_mut().unwrap();
    assert_eq!(c.remove("warnings"), Some(report["warnings"].clone()));
    c.remove("notes");
    assert_eq!(report["comparison"], compare);

    // The blow train with the damper is `meid blows`'s (10 blows at 60 /min).
    let blows: serde_json::Value = serde_json::from_str(&ok(meid()
        .arg("blows")
        .arg(paper_example())
        .args(["--json", "--case", "damper", "--blows", "10"])
        .output()
        .unwrap()))
    .unwrap();
    let damper = report["blow_trains"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["case"] == "damper")
        .unwrap();
    assert_eq!(damper["blows"], blows["blows"]);
    assert_eq!(damper["steady"], blows["steady"]);

    // The impacts table is `meid simulate`'s per-impact rows over the same record, per case,
    // and its totals are theirs.
    let cases = section(&html, "cases");
    assert!(cases.contains("Impacts in the blow"));
    for (case, flag, contacts) in [
        ("no-damper", "none", &["slider_bed"][..]),
        ("damper", "damper", &["slider_bed", "bed_damper"][..]),
    ] {
        let sim: serde_json::Value = serde_json::from_str(&ok(meid()
            .arg("simulate")
            .arg(paper_example())
            .args(["--json", "--duration", "2", "--case", flag])
            .output()
            .unwrap()))
        .unwrap();
        assert_eq!(report["impacts"][case], sim["impacts"], "{case}");
        for c in contacts {
            let total: f64 = sim["impacts"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|r| r["contact"] == *c)
                .map(|r| r["impulse_n_s"].as_f64().unwrap())
                .sum();
            assert!(total > 0.0, "{case} {c}");
            assert!(
                cases.contains(&format!("<td>{c}</td>")),
                "{case}: no row for {c}"
            );
        }
    }

    // The map's centre is the design. Lumped structure (examples/paper-lumped.toml): the
    // two-mode closed form ω² = (b ∓ √(b² − 4c))/2 with b = k_c/m_b + (k_c + k_f)/m_f,
    // c = k_c k_f/(m_b m_f) gives ω_1, and ω_s = √(K_s/m_s).
    let (kc, kf, mb, mf): (f64, f64, f64, f64) = (2.5415164e7, 8.1195270e4, 10.0, 41.0);
    let b = kc / mb + (kc + kf) / mf;
    let c = kc * kf / (mb * mf);
    let w1 = ((b - (b * b - 4.0 * c).sqrt()) / 2.0).sqrt();
    let ws = (4.2980449e7_f64 / 1.2).sqrt();
    let wd = (1.2535964e8_f64 / 3.5).sqrt();
    let map = &report["energy_map"];
    assert_eq!(map["axes"]["kind"], "ratios");
    let design = map["design"].as_array().unwrap();
    let rel = |a: f64, b: f64| (a / b - 1.0).abs();
    // The small-root formula loses digits to cancellation (b² ≫ 4c): 1e-7 is its accuracy.
    assert!(
        rel(design[0].as_f64().unwrap(), ws / w1) < 1e-7,
        "{design:?}"
    );
    assert!(
        rel(design[1].as_f64().unwrap(), wd / w1) < 1e-7,
        "{design:?}"
    );
    assert!((ws / w1 - 150.0).abs() < 0.01, "the file's w_s/w_6 = 150");
    // The design point of the map is the comparison's damper run (K_s, K_d rebuilt from the
    // ratios: equal to rounding).
    let damper_eta = compare["cases"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["case"] == "damper")
        .unwrap()["energy_ratio"]
        .as_f64()
        .unwrap();
    let eta = map["design_energy_ratio"].as_f64().unwrap();
    assert!(rel(eta, damper_eta) < 1e-9, "{eta} vs {damper_eta}");

    // The Monte Carlo is `meid montecarlo`'s.
    let mc: serde_json::Value = serde_json::from_str(&ok(meid()
        .arg("montecarlo")
        .arg(paper_example())
        .args([
            "--json",
            "--vary",
            "contact.slider_bed.stiffness=lognormal(4.3e7,0.2)",
            "--samples",
            "16",
        ])
        .output()
        .unwrap()))
    .unwrap();
    assert_eq!(report["montecarlo"]["metric_stats"], mc["metric_stats"]);
}

#[test]
fn fe_report_passes_the_page_check() {
    let d = tmpdir("report", "fe");
    let out = d.join("page");
    let o = meid()
        .arg("report")
        .arg(example_file("paper-soft-base.toml"))
        .args(["--map-points", "9", "--blows", "3"])
        .args(["--set", "production.rate_bpm=60", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let text = ok(o);
    assert!(text.contains("wrote"), "{text}");
    let html = check_report(&out, false);
    // With the model's stroke rate, the key results lead with the steady blow at that rate.
    let report = json(&out.join("report.json"));
    assert_eq!(report["rate_origin"], "model");
    let first = report["key_results"][0].as_str().unwrap();
    assert!(
        first.starts_with("In production at 60 blows/min (the model's [production] rate_bpm; the periodic steady blow,"),
        "{first}"
    );
    // The FE mode table names the solver and the DOFs, and the energy map's axes name the
    // reference mode by its number in that table (the 6.35 Hz vertical rigid-body mode).
    let modes = section(&html, "modes");
    assert!(modes.contains("DOFs"), "{modes}");
    let n = report["energy_map"]["axes"]["reference_mode"]
        .as_u64()
        .unwrap();
    let f = report["modes"]["modes"][(n - 1) as usize]["frequency_hz"]
        .as_f64()
        .unwrap();
    assert!((f - 6.35).abs() < 0.01, "mode {n}: {f} Hz");
    assert!(section(&html, "energy-map").contains(&format!("ω_s/ω_{n}")));
    assert!(
        section(&html, "montecarlo").contains("--vary"),
        "says how to give one"
    );
    // The Model section opens with the sketch of the mesh (check_page above found its files),
    // its caption naming each marked point by role.
    let model = section(&html, "model");
    let fig = model
        .find("<figure")
        .expect("a figure in the Model section");
    assert!(
        fig < model.find("<table").unwrap(),
        "sketch before the table"
    );
    assert!(model.contains("src=\"model_sketch.png\""), "{model}");
    for label in [
        "strike O_b (slider)",
        "damper at O_b",
        "anchor O_f",
        "measurement B",
        "floor: 4 springs to ground",
    ] {
        assert!(model.contains(label), "no '{label}' in: {model}");
    }
    for f in ["model_sketch.png", "model_sketch.svg"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 1000, "{f}");
    }
}

#[test]
fn simulated_uff_records_given_as_measurements_match_the_simulation() {
    let d = tmpdir("report", "measured");
    for (case, dir) in [("none", "sim-none"), ("damper", "sim-damper")] {
        ok(meid()
            .current_dir(&d)
            .arg("simulate")
            .arg(example_file("paper-lumped.toml"))
            .args([
                "--case",
                case,
                "--duration",
                "0.5",
                "--uff",
                "-q",
                "-o",
                dir,
            ])
            .output()
            .unwrap());
    }
    // A simulated history starts with the blow: no pre-trigger.
    ok(meid()
        .current_dir(&d)
        .arg("report")
        .arg(example_file("paper-lumped.toml"))
        .args([
            "--measured",
            "none=sim-none/history.uff",
            "--measured",
            "damper=sim-damper/history.uff",
            "--pretrigger",
            "0",
            "--map-points",
            "3",
            "--blows",
            "1",
            "-q",
            "-o",
            "out",
        ])
        .output()
        .unwrap());
    let out = d.join("out");
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert_eq!(check_page(&out, &html), vec![], "check_page");
    let s = section(&html, "measured");
    assert!(s.contains("none=") || s.contains("case none"), "{s}");
    assert!(s.matches("<table").count() >= 3, "peaks, modes, reductions");
    let j = json(&out.join("report.json"));
    let m = &j["measured"];
    for c in m["cases"].as_array().unwrap() {
        for ch in c["channels"].as_array().unwrap() {
            let e = ch["peak_error_percent"].as_f64().unwrap();
            assert!(e.abs() < 1e-6, "{ch}");
        }
    }
    // The same records' test against the model: the blow on the bare machine's bed, both
    // modes found (0.5 s: 2 Hz lines; the frequencies within 0.1 % of `meid modes`' 6.35 and
    // 283 Hz), paired by frequency (one measured point).
    let t = &j["test_against_model"];
    assert_eq!(t["status"], "done", "{t}");
    assert_eq!(t["case"], "none");
    for (row, f) in t["modes"].as_array().unwrap().iter().zip([6.35, 283.0]) {
        let got = row["test_frequency_hz"].as_f64().unwrap();
        assert!(((got - f) / f).abs() < 1e-3, "{row}");
    }
    assert_eq!(t["correlation"]["settings"]["by_frequency"], true);
    let s = section(&html, "test-against-model");
    assert!(s.contains("2 of 2 model mode(s)"), "{s}");
    assert!(s.contains("src=\"stabilisation.png\""), "{s}");
    let reductions = m["reductions"].as_array().unwrap();
    assert!(!reductions.is_empty());
    for r in reductions {
        let (a, b) = (
            r["measured_db"].as_f64().unwrap(),
            r["simulated_db"].as_f64().unwrap(),
        );
        assert!((a - b).abs() < 1e-6, "{r}");
    }
}

#[test]
fn bad_report_options_exit_2_naming_the_option() {
    let d = tmpdir("report", "bad");
    for (args, want) in [
        (vec!["--rate-bpm", "0"], "stroke rate"),
        (vec!["--map-points", "2"], "at least 3 points"),
        (vec!["--map-points", "100000001"], "of memory"),
        (vec!["--map-span", "1"], "span factor must be > 1"),
        (
            vec!["--vary", "contact.nosuch.stiffness=normal(1,0.1)"],
            "contact.nosuch.stiffness",
        ),
        (vec!["--vary", "damper.mass"], "expected PATH=DIST"),
        (
            vec!["--measured", "none=no-such-record.uff"],
            "no-such-record.uff",
        ),
        (
            vec![
                "--measured",
                "none=no-such-record.uff",
                "--channel",
                "acc=roof",
            ],
            "unknown target 'roof'",
        ),
        (
            vec!["--fit", "structure.lumped.springs[0].stiffness"],
            "--measured none=FILE",
        ),
        (vec!["--bounds", "damper.mass=1..2"], "--fit"),
    ] {
        let o = meid()
            .current_dir(&d)
            .arg("report")
            .arg(paper_example())
            .args(&args)
            .args(["-o", "out"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{args:?}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
    // -o on an existing file.
    std::fs::write(d.join("file"), b"x").unwrap();
    let o = meid()
        .current_dir(&d)
        .arg("report")
        .arg(paper_example())
        .args(["-o", "file"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a directory"), "{}", stderr(&o));
}

/// The sentence of receiver `name` in the HTML (escapes undone).
fn receiver_sentence(html: &str, name: &str) -> String {
    let start = html
        .find(&format!("<li>The receiver &#39;{name}&#39;"))
        .unwrap_or_else(|| panic!("no sentence for {name}"));
    let rest = &html[start + 4..];
    rest[..rest.find("</li>").unwrap()].replace("&#39;", "'")
}

#[test]
fn foundation_report_has_its_section_and_the_verdict_from_the_numbers() {
    let d = tmpdir("report", "foundation");
    let out = d.join("page");
    // At 20 blows/min the damper returns to the bed before every strike (it returns at up to
    // 33.6 /min on this machine), so its steady blow is the damped one.
    ok(meid()
        .arg("report")
        .arg(example_file("paper-on-soil.toml"))
        .args([
            "-q",
            "--map-points",
            "5",
            "--blows",
            "2",
            "--rate-bpm",
            "20",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert_eq!(check_page(&out, &html), vec![], "check_page");
    let sec = section(&html, "foundation");
    assert!(sec.contains("<h2>Foundation and surroundings</h2>"));
    assert_eq!(
        sec.matches("<figure").count(),
        2,
        "PPV against distance, DIN chart"
    );
    assert_eq!(
        sec.matches("<table").count(),
        5,
        "block, impedances, checks, DIN, people"
    );
    assert!(sec.contains("People in buildings"));
    // The checks judge the steady blow at the report's stroke rate, and say so per case.
    for case in ["Without damper", "Impact damper", "Added mass"] {
        assert!(
            sec.contains(&format!(
                "{case}: the checks judge the steady blow of the train at 20 /min (period-1"
            )),
            "{case}"
        );
    }
    assert!(sec.contains("the damper returns to the bed before every strike"));
    for stem in ["foundation-ppv", "foundation-din"] {
        for ext in ["png", "svg", "csv"] {
            assert!(out.join(format!("{stem}.{ext}")).is_file(), "{stem}.{ext}");
        }
    }
    // The DIN chart's legend names the three lines, long-term (no excitation given: the
    // default), and the receivers' points in each case.
    let svg = std::fs::read_to_string(out.join("foundation-din.svg")).unwrap();
    let texts = meid::plot::svg_texts(&svg);
    for line in ["line 1", "line 2", "line 3"] {
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with(line) && t.ends_with("long-term")),
            "{texts:?}"
        );
    }
    assert!(
        texts.iter().any(|t| t == "laboratory, impact damper"),
        "{texts:?}"
    );

    let report = json(&out.join("report.json"));
    let cases = ["no-damper", "damper", "added-mass"];
    let mut fails = Vec::new();
    for (i, name) in ["workshop", "laboratory"].into_iter().enumerate() {
        let sentence = receiver_sentence(sec, name);
        // One "by N %" per case, in the comparison's order.
        let pcts: Vec<f64> = sentence
            .split(" by ")
            .skip(1)
            .map(|p| p.split(' ').next().unwrap().parse().unwrap())
            .collect();
        assert_eq!(pcts.len(), 3, "{sentence}");
        let clauses: Vec<&str> = sentence.split("; ").collect();
        for (k, case) in cases.into_iter().enumerate() {
            let r = &report["receivers"][case][i];
            assert_eq!(r["name"], name);
            let ppv = r["ppv_m_per_s"].as_f64().unwrap();
            let limit = r["checks"][0]["limit"].as_f64().unwrap();
            let want = 100.0 * (ppv / limit - 1.0);
            assert!(
                (pcts[k] - want.abs()).abs() <= 0.5 + 1e-9,
                "{name} {case}: {} vs {want} in {sentence}",
                pcts[k]
            );
            assert_eq!(clauses[k].contains("exceeds"), want > 0.0, "{sentence}");
            if want > 0.0 {
                fails.push(name);
            }
        }
    }
    // The example shows the damper's verdict: the laboratory is over its long-term limit
    // without damper and with the added mass, within it with the damper.
    let lab = receiver_sentence(sec, "laboratory");
    assert!(
        lab.contains("exceeds the long-term limit (2.5 mm/s)")
            && lab.contains("with the damper: within by"),
        "{lab}"
    );
    assert_eq!(fails, ["laboratory", "laboratory"]);
    // The page's verdict carries the failing receiver's sentence, not the passing one's.
    let verdict = section(&html, "verdict").replace("&#39;", "'");
    assert!(verdict.contains(&lab));
    assert!(!verdict.contains("The receiver 'workshop'"));
    let v = report["verdict"].as_array().unwrap();
    assert!(v.iter().any(|s| s.as_str() == Some(lab.as_str())), "{v:?}");
    let basis = &report["foundation"]["damper"]["blow_basis"];
    assert_eq!(basis["blow"], "steady blow of the train");
    assert_eq!(basis["rate_bpm"], 20.0);
    assert_eq!(basis["damper_touches_bed"], true);
}

/// At 60 blows/min (the report's default) the paper's damper does not return between blows:
/// the long-term check is made on the steady blow, where the damper no longer helps, and the
/// laboratory fails with it too.
#[test]
fn foundation_report_judges_production_where_the_damper_does_not_return() {
    let d = tmpdir("report", "foundation-60");
    let out = d.join("page");
    ok(meid()
        .arg("report")
        .arg(example_file("paper-on-soil.toml"))
        .args(["-q", "--map-points", "3", "--blows", "2", "-o"])
        .arg(&out)
        .output()
        .unwrap());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    let sec = section(&html, "foundation");
    assert!(sec.contains("the damper does not return to the bed between blows"));
    let lab = receiver_sentence(sec, "laboratory");
    assert!(lab.contains("with the damper: exceeds by"), "{lab}");
    let report = json(&out.join("report.json"));
    let basis = &report["foundation"]["damper"]["blow_basis"];
    assert_eq!(basis["rate_bpm"], 60.0);
    assert_eq!(basis["damper_touches_bed"], false);
    assert_eq!(basis["converged"], true);
}
