//! The pictures the CLI draws speak the paper's terms and state quantity and unit
//! (issue 11, point 6): sweep axes and legends, the JSON names of varied quantities, the
//! `compare` time histories in panels, the `montecarlo` histogram's mean and P95 markers.
//! Checked on the SVG text of real runs of the lumped paper example.

use crate::common;

use std::path::Path;

use common::{meid, ok, ok_json, paper_example as example};

/// Every `<text>` body of an SVG, unescaped.
fn texts(svg: &Path) -> Vec<String> {
    let s = std::fs::read_to_string(svg).unwrap();
    let mut out = Vec::new();
    let mut rest = s.as_str();
    while let Some(i) = rest.find("<text") {
        rest = &rest[i..];
        let open = rest.find('>').unwrap();
        let close = rest.find("</text>").unwrap();
        out.push(
            rest[open + 1..close]
                .trim()
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&amp;", "&"),
        );
        rest = &rest[close..];
    }
    out
}

/// The texts that are axis descriptions: not numbers.
fn words(t: &[String]) -> Vec<&String> {
    t.iter().filter(|x| x.parse::<f64>().is_err()).collect()
}

/// No internal name in any text: enum names, snake-case metric names, SPEC ratio names.
fn assert_no_internal_names(t: &[String], picture: &str) {
    for x in t {
        for bad in [
            "WdOverWs",
            "WsOverWref",
            "MdOverMb",
            "energy_ratio",
            "md/mb",
            "wd/ws",
            "ws/w_ref",
            "damper.mass",
        ] {
            assert!(
                !x.contains(bad),
                "{picture}: '{x}' shows the internal name {bad}"
            );
        }
    }
}

#[test]
fn sweep_family_and_json_use_the_papers_terms() {
    let d = common::tmpdir("pictures", "family");
    let v = ok_json(
        meid()
            .arg("sweep")
            .arg(example())
            .args(["--vary", "wd/ws=0.5,1,2", "--vary", "md/mb=0.35,0.7"])
            .arg("-o")
            .arg(&d)
            .arg("--json")
            .output()
            .unwrap(),
    );
    let vary = v["spec"]["vary"].as_array().unwrap();
    assert_eq!(vary[0]["quantity"].as_str(), Some("wd/ws"));
    assert_eq!(vary[1]["quantity"].as_str(), Some("md/mb"));
    let t = texts(&d.join("energy_ratio_family.svg"));
    assert_no_internal_names(&t, "family");
    for want in [
        "m_d/m_b = 0.35",
        "m_d/m_b = 0.7",
        "ω_d/ω_s (1)",
        "energy ratio E_p+/E_s− (1)",
    ] {
        assert!(t.iter().any(|x| x == want), "'{want}' missing in {t:?}");
    }
}

#[test]
fn sweep_of_a_field_names_its_symbol_and_unit_and_the_map_its_reference() {
    let d = common::tmpdir("pictures", "field");
    let v = ok_json(
        meid()
            .arg("sweep")
            .arg(example())
            .args([
                "--vary",
                "contact.slider_bed.stiffness=1e7,1e8",
                "--vary",
                "damper.mass=1,3.5",
            ])
            .arg("-o")
            .arg(&d)
            .arg("--json")
            .output()
            .unwrap(),
    );
    assert_eq!(
        v["spec"]["vary"][1]["quantity"].as_str(),
        Some("damper.mass")
    );
    let t = texts(&d.join("energy_ratio_family.svg"));
    assert_no_internal_names(&t, "field family");
    assert!(t.iter().any(|x| x == "K_s (N/m)"), "{t:?}");
    assert!(t.iter().any(|x| x == "m_d = 3.5 kg"), "{t:?}");

    let d = common::tmpdir("pictures", "map");
    ok(meid()
        .arg("sweep")
        .arg(example())
        .args([
            "--vary",
            "ws/w_ref=20..200:4:log",
            "--vary",
            "wd/w_ref=20..200:4:log",
        ])
        .arg("-o")
        .arg(&d)
        .arg("-q")
        .output()
        .unwrap());
    let t = texts(&d.join("energy_ratio_map.svg"));
    assert_no_internal_names(&t, "map");
    // The lumped example's reference mode: 39.898 rad/s, 6.35 Hz.
    assert!(
        t.iter()
            .any(|x| x.starts_with("ω_s/ω_ref (1), ω_ref = 39.89")
                && x.ends_with("(6.35 Hz, mode 1)")),
        "{t:?}"
    );
    assert!(t.iter().any(|x| x == "ω_d = ω_s"));
    assert!(t.iter().all(|x| !x.contains('…')), "a cut legend");
}

#[test]
fn compare_draws_each_case_in_its_panel_and_every_axis_has_a_unit() {
    let d = common::tmpdir("pictures", "compare");
    ok(meid()
        .arg("compare")
        .arg(example())
        .args(["--duration", "0.5"])
        .arg("-o")
        .arg(&d)
        .arg("-q")
        .output()
        .unwrap());
    for stem in [
        "acceleration-time",
        "floor-force-time",
        "acceleration-spectrum",
        "floor-force-spectrum",
        "acceleration-bands",
        "floor-force-bands",
    ] {
        let t = texts(&d.join(format!("{stem}.svg")));
        // Every description with a unit in parentheses: "time (s)", "force (N)", "dB re …".
        let w = words(&t);
        let units = w
            .iter()
            .filter(|x| x.contains(" (") && x.ends_with(')'))
            .count();
        assert!(units >= 2, "{stem}: axis descriptions without units: {w:?}");
        // A history names each case on its panel of the whole record and of the collision
        // zoomed beside it; a spectrum once, in its legend.
        let zoomed = stem.ends_with("-time");
        for case in ["without damper", "impact damper", "added mass"] {
            assert_eq!(
                t.iter().filter(|x| *x == case).count(),
                if zoomed { 2 } else { 1 },
                "{stem}: case '{case}' named once per frame (legend or panel caption)"
            );
        }
        assert_eq!(
            t.iter().any(|x| x.starts_with("the collision: first")),
            zoomed,
            "{stem}: the collision zoomed beside the histories, only there"
        );
    }
    // The time histories: one "acceleration (m/s²)" axis per panel, whole and zoomed.
    let t = texts(&d.join("acceleration-time.svg"));
    assert_eq!(t.iter().filter(|x| *x == "acceleration (m/s²)").count(), 6);
}

#[test]
fn montecarlo_histogram_marks_mean_and_p95_of_stats_json() {
    let d = common::tmpdir("pictures", "mc");
    ok(meid()
        .arg("montecarlo")
        .arg(example())
        .args([
            "--vary",
            "contact.slider_bed.stiffness=lognormal(4.3e7,0.2)",
            "--samples",
            "24",
        ])
        .arg("-o")
        .arg(&d)
        .arg("-q")
        .output()
        .unwrap());
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("stats.json")).unwrap()).unwrap();
    let s = stats["metric_stats"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == "energy_ratio")
        .unwrap();
    let t = texts(&d.join("histogram-energy_ratio.svg"));
    let fmt = |v: f64| meid::plot::axis::fmt_tick(&v);
    let mean = format!("mean {}", fmt(s["mean"].as_f64().unwrap()));
    let p95 = format!("P95 {}", fmt(s["p95"].as_f64().unwrap()));
    assert!(t.contains(&mean), "{mean} missing: {t:?}");
    assert!(t.contains(&p95), "{p95} missing: {t:?}");
    assert!(t.iter().any(|x| x == "energy ratio E_p+/E_s− (1)"));
}

/// `meid simulate -o`: the blow's pictures, each whole with the collision zoomed beside it,
/// titled with the summary's exact peaks; without a damper, no damper curve.
#[test]
fn simulate_draws_the_blow_whole_and_its_collision() {
    let d = common::tmpdir("pictures", "simulate");
    ok(meid()
        .arg("simulate")
        .arg(example())
        .args(["-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap();
    let a = summary["peak_bed_acceleration_m_per_s2"].as_f64().unwrap();
    for stem in [
        "bed_acceleration",
        "floor_force",
        "contact_forces",
        "displacements",
        "energies",
    ] {
        assert!(d.join(format!("{stem}.png")).is_file(), "{stem}.png");
        let t = texts(&d.join(format!("{stem}.svg")));
        assert_no_internal_names(&t, stem);
        assert!(
            t.iter().any(|x| x.starts_with("the collision: first")),
            "{stem}: the collision beside the whole record: {t:?}"
        );
    }
    let t = texts(&d.join("bed_acceleration.svg"));
    let title = t
        .iter()
        .find(|x| x.starts_with("Bed acceleration a_B, exact peak "))
        .expect("title");
    let quoted: f64 = title["Bed acceleration a_B, exact peak ".len()..]
        .split(' ')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!((quoted - a).abs() <= 5e-4 * a.abs(), "{title} vs {a}");
    let t = texts(&d.join("energies.svg"));
    for label in [
        "slider, kinetic",
        "dissipated",
        "damper, kinetic + spring + contact",
    ] {
        assert!(t.iter().any(|x| x == label), "energies: {label} in {t:?}");
    }

    let d = common::tmpdir("pictures", "simulate-none");
    ok(meid()
        .arg("simulate")
        .arg(example())
        .args(["--case", "none", "-q", "-o"])
        .arg(&d)
        .output()
        .unwrap());
    let t = texts(&d.join("contact_forces.svg"));
    assert!(t.iter().any(|x| x == "slider-bed"), "{t:?}");
    assert!(
        !t.iter().any(|x| x == "bed-damper"),
        "no damper curve: {t:?}"
    );
}
