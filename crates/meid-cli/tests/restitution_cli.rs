//! `restitution = e` on a contact end to end: `meid simulate` states the damping it set (text
//! and `--json` notes); a restitution outside (0, 1] or given with `damping` exits 2 naming the
//! file, line and fields.

use crate::common;

use common::{example_file as example, meid, ok, ok_json, stderr, tmpdir};

/// The paper's lumped example with the slider-bed damping line replaced by `line`.
fn paper_with(line: &str) -> String {
    let text = std::fs::read_to_string(example("paper-lumped.toml")).unwrap();
    let out = text.replacen("damping = 0.0                  # C_s", line, 1);
    assert_ne!(out, text);
    out
}

#[test]
fn simulate_states_the_damping_restitution_set() {
    let d = tmpdir("restitution", "note");
    let file = d.join("e05.toml");
    std::fs::write(&file, paper_with("restitution = 0.5")).unwrap();
    let want = "contact.slider_bed: restitution e = 0.5 → damping C = 3464.6 N·s/m (ζ = C/(2√(K m*)) = 0.25528, release at zero force; m* = 1.0714 kg: the slider, 1.2 kg, against the effective mass of bed, 1/Σψ² = 10.000 kg)";
    let text = ok(meid().arg("simulate").arg(&file).output().unwrap());
    assert!(text.contains(&format!("note: {want}")), "{text}");
    let json = ok_json(
        meid()
            .args(["simulate", "--json"])
            .arg(&file)
            .output()
            .unwrap(),
    );
    let notes = json["notes"].as_array().unwrap();
    assert!(notes.iter().any(|n| n.as_str() == Some(want)), "{notes:?}");
}

#[test]
fn bad_restitution_exits_2_naming_the_line() {
    let d = tmpdir("restitution", "bad");
    for (name, line, parts) in [
        (
            "range.toml",
            "restitution = 1.5",
            vec!["contact.slider_bed.restitution", "(0, 1]", "got 1.5"],
        ),
        (
            "both.toml",
            "restitution = 0.5\ndamping = 20.0",
            vec!["contact.slider_bed.restitution: given together with contact.slider_bed.damping = 20 N·s/m"],
        ),
    ] {
        let text = paper_with(line);
        let file = d.join(name);
        std::fs::write(&file, &text).unwrap();
        let o = meid().arg("simulate").arg(&file).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = stderr(&o);
        let row = text.lines().position(|l| l.starts_with("restitution")).unwrap() + 1;
        assert!(err.contains(&format!("{name}:{row}:")), "{err}");
        for p in parts {
            assert!(err.contains(p), "{err} (want {p})");
        }
    }
}
