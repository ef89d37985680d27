//! `meid paper` end to end at a reduced resolution (9 × 9 maps, 13-point curves; the full run
//! is timed in docs/performance.md, not here).
//!
//! References: the page passes `report::html::check_page` (every src/href resolves inside the
//! output directory, every figure captioned); every paper figure 2-19 is present with a caption
//! naming it; the table has a row for every number the paper states (the ids of
//! `report::paper::claims::PAPER_NUMBERS`) and the qualitative claims; the closed-form checkable
//! numbers: the tuned modal frequencies (6.35 / 283 Hz, 141 / 292 Hz) within 3 % (the lumped
//! models to 1e-6 relative: their springs are solved in closed form from the two frequencies),
//! and the paper's arithmetic 41.2 % ↔ −10 log10(1 − 0.412) = 2.306 dB, 25.9 % ↔ 1.302 dB.

use crate::common;

use common::{meid, ok};

#[test]
fn paper_page_figures_table_and_closed_forms() {
    let dir = common::tmpdir("paper-cli", "run");
    let mut c = meid();
    c.args(["paper", "--map-points", "9", "--curve-points", "13", "-o"])
        .arg(&dir);
    let out = ok(c.output().unwrap());
    assert!(out.contains("meid paper —"), "{out}");
    assert!(out.contains("pct-damper-arithmetic"), "{out}");
    let html = std::fs::read_to_string(dir.join("index.html")).unwrap();
    let problems = meid::report::html::check_page(&dir, &html);
    assert!(problems.is_empty(), "{problems:?}");
    // Every paper figure 2-19, each inside a caption.
    let captions: Vec<&str> = html
        .split("<figcaption>")
        .skip(1)
        .map(|c| c.split("</figcaption>").next().unwrap())
        .collect();
    for n in 2..=19 {
        let tag = format!("Reproduces paper Fig. {n}");
        let hits = captions
            .iter()
            .filter(|c| {
                c.contains(&format!("{tag}:"))
                    || c.contains(&format!("{tag}("))
                    || c.contains(&format!("{tag} "))
            })
            .count();
        assert!(hits >= 1, "no captioned figure reproduces paper Fig. {n}");
    }
    // Energy maps as the paper draws them: the operating points are labelled points (text
    // of the picture, Q and S sharing one), the rule ω_d = ω_s is a legend entry, the axes are
    // named after the paper's reference mode.
    let texts = |stem: &str| {
        meid::plot::svg_texts(&std::fs::read_to_string(dir.join(format!("{stem}.svg"))).unwrap())
    };
    for (stem, want) in [
        (
            "fig03a-soft-lumped",
            &["P", "Q = S", "R", "ω_d = ω_s", "ω_s/ω_6 (1)", "ω_d/ω_6 (1)"][..],
        ),
        ("fig03a-soft-fe", &["P", "Q = S", "R", "ω_d = ω_s"][..]),
        ("fig12-stiff-lumped", &["T", "ω_d = ω_s", "ω_s/ω_6 (1)"][..]),
        (
            "fig16-nobase-lumped",
            &["U", "ω_d = ω_s", "ω_s/ω_4 (1)", "ω_d/ω_4 (1)"][..],
        ),
        ("fig16-nobase-fe", &["U", "ω_d = ω_s", "ω_s/ω_4 (1)"][..]),
    ] {
        let t = texts(stem);
        for w in want {
            assert!(t.iter().any(|s| s == w), "{stem}: no text {w:?} in {t:?}");
        }
    }
    // Energy histories (Figs. 6-8): the slider's leaving and the PE K_d maximum are marked.
    let t = texts("fig06-Q-soft-lumped");
    for w in ["slider leaves", "PE K_d maximum"] {
        assert!(
            t.iter().any(|s| s.starts_with(w)),
            "fig06: no {w:?} in {t:?}"
        );
    }
    // Each figure's data file and vector picture exist (check_page covered the links).
    assert!(html.contains(".csv\">") && html.contains(".svg\">"));
    // The table: every paper number has a row.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("paper.json")).unwrap()).unwrap();
    let table = json["table"].as_array().unwrap();
    let ids: Vec<&str> = table.iter().map(|r| r["id"].as_str().unwrap()).collect();
    for p in meid::report::paper::claims::PAPER_NUMBERS {
        assert!(ids.contains(&p.id), "no row for {}", p.id);
        assert!(html.contains(p.source.split(',').next().unwrap()) || html.contains(p.what));
    }
    for id in [
        "pct-added",
        "pct-damper-arithmetic",
        "pct-added-arithmetic",
        "q-fig9",
        "q-timing",
    ] {
        assert!(ids.contains(&id), "no row {id}");
    }
    let row = |id: &str| table.iter().find(|r| r["id"] == id).unwrap();
    let val = |id: &str, k: &str| row(id)[k].as_f64().unwrap();
    for (id, hz) in [
        ("f6-soft", 6.35),
        ("f10-soft", 283.0),
        ("f6-stiff", 141.0),
        ("f10-stiff", 292.0),
    ] {
        let l = val(id, "lumped");
        let f = val(id, "fe");
        assert!(((l - hz) / hz).abs() < 1e-6, "{id}: lumped {l} Hz vs {hz}");
        assert!(((f - hz) / hz).abs() < 0.03, "{id}: FE {f} Hz vs {hz}");
        assert_eq!(row(id)["verdict"], "reproduced");
    }
    let implied = |p: f64| -10.0 * (1.0 - p / 100.0).log10();
    assert!((implied(41.2) - 2.306).abs() < 5e-4);
    assert!((implied(25.9) - 1.302).abs() < 5e-4);
    assert!((val("pct-damper-arithmetic", "lumped") - implied(41.2)).abs() < 1e-12);
    assert!((val("pct-added-arithmetic", "lumped") - implied(25.9)).abs() < 1e-12);
    assert_eq!(row("pct-damper-arithmetic")["verdict"], "not-reproduced");
    // Each row's measure names its own case (the damper's percentage row once said "(the added
    // mass on the bed)"): only the added-mass rows mention the added mass.
    for id in [
        "pct-damper",
        "power-damper",
        "T-acc",
        "T-force",
        "U-acc",
        "U-force",
    ] {
        let measure = row(id)["measure"].as_str().unwrap();
        assert!(!measure.contains("added mass"), "{id}: {measure}");
    }
    assert!(row("pct-damper")["measure"]
        .as_str()
        .unwrap()
        .contains("impact damper"));
    assert!(row("pct-added")["measure"]
        .as_str()
        .unwrap()
        .contains("added mass on the bed"));
    // Every non-reproduced dB number got a deviation study.
    let dev = json["deviations"].as_array().unwrap();
    for r in table {
        let id = r["id"].as_str().unwrap();
        if r["verdict"] != "reproduced" && ["T-acc", "U-acc", "exp-force", "eta-md1"].contains(&id)
        {
            assert!(
                dev.iter().any(|d| d["number"] == id),
                "no deviation rows for {id}"
            );
        }
    }
    // Every row not reproduced has a deviation study (the peaks of Figs. 5 and 17, the
    // percentages, the qualitative claims included), and every deviation row says what kind
    // of evidence it is.
    for r in table {
        if r["verdict"] != "reproduced" {
            let id = r["id"].as_str().unwrap();
            assert!(
                dev.iter().any(|d| d["number"] == id),
                "no deviation rows for {id}"
            );
        }
    }
    for d in dev {
        let e = d["evidence"].as_str().unwrap();
        assert!(["physics", "reading", "search"].contains(&e), "{d}");
    }
    assert!(html.contains("Matches found by a parameter search"));
    assert!(html.contains("parameter-search candidates"));
    // Fig. 17's verdict reads the three curves the paper draws.
    let pn = row("peak-none");
    for q in ["m_d/m_b = 0.35", "m_d/m_b = 0.7", "m_d/m_b = 1"] {
        assert!(pn["fe_text"].as_str().unwrap().contains(q), "{pn}");
    }
    // The marked points' values are simulated at the points: R on the soft lumped map equals a
    // direct simulation at ω_s/ω_6 = 150, ω_d/ω_6 = 220, m_d = 0.35 m_b, and the caption
    // prints it.
    let marked = json["marked_points"].as_array().unwrap();
    let at = |machine: &str, name: &str| {
        marked
            .iter()
            .find(|m| m[0] == machine && m[1]["name"] == name)
            .map(|m| m[1]["energy_ratio"].as_f64().unwrap())
            .unwrap()
    };
    let direct = |ws: f64, wd: f64| {
        let text = include_str!("../../../examples/paper-lumped.toml");
        let base = meid::model::Model::from_text("l", text.into(), &[]).unwrap();
        let w = base.reference_omega().unwrap();
        let (w_s, w_d) = (ws * w, wd * w);
        let m = meid::model::Model::from_text(
            "l",
            text.into(),
            &[
                format!("contact.slider_bed.stiffness={:e}", 1.2 * w_s * w_s),
                "damper.mass=3.5".into(),
                format!("contact.bed_damper.stiffness={:e}", 3.5 * w_d * w_d),
            ],
        )
        .unwrap();
        let sys = m.impact_system(meid::model::Case::Damper).unwrap();
        let mut o = m.options();
        o.stop_at_collision_end = true;
        meid::analysis::simulate(&sys, &o, false)
            .unwrap()
            .summary
            .energy_ratio
            .unwrap()
    };
    for (name, wd) in [("P", 25.0), ("Q", 150.0), ("R", 220.0)] {
        let e = at("soft base, lumped", name);
        let d = direct(150.0, wd);
        assert!(
            (e / d - 1.0).abs() < 1e-12,
            "{name}: page {e} vs direct {d}"
        );
    }
    let r = at("soft base, lumped", "R");
    assert!(
        html.contains(&format!("R = (150, 220): E = {r:.4}")),
        "R's value not printed"
    );
    assert_eq!(at("soft base, lumped", "S"), at("soft base, lumped", "Q"));
    // The physics findings, computed by the run: the bed-mass study's FE reduction is the
    // table's vibration power reduction (another path: the comparison), Eq. 24 rises after the
    // collision while the machine's own energy decays.
    let physics = json["physics"].as_array().unwrap();
    let finding = |id: &str| -> Vec<&serde_json::Value> {
        physics.iter().filter(|f| f["id"] == id).collect()
    };
    let value = |id: &str, name: &str| {
        finding(id)
            .into_iter()
            .flat_map(|f| f["values"].as_array().unwrap().iter())
            .find(|v| v[0] == name)
            .map(|v| v[1].as_f64().unwrap())
            .unwrap()
    };
    for id in [
        "bed-strike-mass",
        "no-damper-curve",
        "percent-db",
        "eq24",
        "damper-mass",
    ] {
        assert!(!finding(id).is_empty(), "no finding {id}");
    }
    let fe_db = value("bed-strike-mass", "FE: vibration power reduction at S");
    assert!(
        (fe_db / val("power-damper", "fe") - 1.0).abs() < 1e-9,
        "{fe_db}"
    );
    let l_db = value("bed-strike-mass", "lumped: vibration power reduction at S");
    assert!(
        (l_db / val("power-damper", "lumped") - 1.0).abs() < 1e-9,
        "{l_db}"
    );
    assert!((value("percent-db", "41.2 % as dB") - implied(41.2)).abs() < 1e-12);
    assert!((value("percent-db", "3 dB as %") - 100.0 * (1.0 - 10f64.powf(-0.3))).abs() < 1e-12);
    let eq24 = finding("eq24")[0]["values"].as_array().unwrap().clone();
    let v = |name: &str| {
        eq24.iter().find(|v| v[0] == name).unwrap()[1]
            .as_f64()
            .unwrap()
    };
    assert!(
        v("E_p/E_s− (Eq. 24) at the end of the record")
            > v("E_p+/E_s− at the end of the collision")
    );
    assert!(
        v("(KE_p + PE_p)/E_s− at the end of the record")
            < v("(KE_p + PE_p)/E_s− at the end of the collision")
    );
    let _ = std::fs::remove_dir_all(&dir);
}
