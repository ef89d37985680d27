//! General machine files (`[[impactor]]`, `[[damper]]`, `[[contact]]`): parsing, bad input
//! (errors naming the file, line and field), preloads, and the run of a file.

use meid::model::network::NetworkModel;
use meid::model::Model;

/// A two-mass lumped structure, one impactor, one damper under "left".
pub(crate) const BASE: &str = include_str!("data/general_two_mass.toml");

fn load(text: &str) -> meid::Result<NetworkModel> {
    NetworkModel::from_text("m.toml", text.to_string(), &[])
}

/// The error of `text`, as a string; panics when it loads.
fn error_of(text: &str) -> String {
    match load(text) {
        Ok(_) => panic!("loaded:\n{text}"),
        Err(e) => e.to_string(),
    }
}

/// The line (1-based) of the first occurrence of `needle` in `text`.
pub(crate) fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("{needle} not in the text"))
        + 1
}

#[test]
fn a_general_file_runs_and_restitution_sets_the_damping() {
    let m = load(BASE).unwrap();
    assert_eq!(m.network.contacts.len(), 2);
    assert_eq!(m.notes.len(), 1, "{:?}", m.notes);
    let sol = m.solve(&m.options().unwrap()).unwrap();
    assert!(sol.energy_ratio.is_some());
    assert!(sol.residual_run_end <= 1e-9);
    assert!(!sol.impacts.is_empty());
    // The paper machine's loader refuses it, saying which command runs it.
    let e = Model::from_text("m.toml", BASE.to_string(), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("general machine") && e.contains("meid simulate"),
        "{e}"
    );
}

#[test]
fn unknown_names_get_a_did_you_mean_with_file_and_line() {
    let text = BASE.replace(
        r#"between = ["die", "left"]"#,
        r#"between = ["die", "lfet"]"#,
    );
    let e = error_of(&text);
    let line = line_of(&text, "lfet");
    assert!(e.contains(&format!("m.toml:{line}:")), "{e}");
    assert!(
        e.contains("contact[0].between") && e.contains("did you mean 'left'"),
        "{e}"
    );
    let text = BASE.replace(r#"point = "left""#, r#"point = "rigth""#);
    let e = error_of(&text);
    assert!(
        e.contains("damper[0].point") && e.contains("did you mean 'right'"),
        "{e}"
    );
}

#[test]
fn unknown_keys_are_refused_with_a_did_you_mean() {
    let text = BASE
        .replace("gap_typo", "")
        .replace("stiffness = 4.3e7", "stiffness = 4.3e7\ngpa = 1e-3");
    let e = error_of(&text);
    assert!(
        e.contains(&format!("m.toml:{}", line_of(&text, "gpa"))),
        "{e}"
    );
    assert!(e.contains("`gap`"), "{e}");
}

#[test]
fn a_contact_with_itself_and_a_damper_anchored_to_itself_are_refused() {
    let text = BASE.replace(
        r#"between = ["die", "left"]"#,
        r#"between = ["die", "die"]"#,
    );
    let e = error_of(&text);
    assert!(
        e.contains("contact[0].between") && e.contains("itself"),
        "{e}"
    );
    assert!(
        e.contains(&format!("m.toml:{}", line_of(&text, r#"["die", "die"]"#))),
        "{e}"
    );
    let text = BASE.replace(r#"anchor = "ground""#, r#"anchor = "d_left""#);
    let e = error_of(&text);
    assert!(
        e.contains("damper[0].anchor") && e.contains("itself"),
        "{e}"
    );
    assert!(
        e.contains(&format!(
            "m.toml:{}",
            line_of(&text, r#"anchor = "d_left""#)
        )),
        "{e}"
    );
}

#[test]
fn bad_numbers_are_refused_naming_the_field() {
    for (from, to, field) in [
        ("mass = 1.2", "mass = -1.2", "impactor[0].mass"),
        ("mass = 1.75", "mass = -1.75", "damper[0].mass"),
        (
            "stiffness = 4.3e7",
            "stiffness = 4.3e7\ngap = nan",
            "contact[0].gap",
        ),
        (
            "restitution = 0.8",
            "restitution = 1.5",
            "contact[1].restitution",
        ),
        (
            "restitution = 0.8",
            "restitution = 0.0",
            "contact[1].restitution",
        ),
        (
            "restitution = 0.8",
            "restitution = 0.8\ndamping = 3.0",
            "contact[1].restitution",
        ),
    ] {
        let text = BASE.replacen(from, to, 1);
        let e = error_of(&text);
        assert!(e.contains(field), "{field}: {e}");
        assert!(e.starts_with("m.toml:"), "{e}");
    }
}

#[test]
fn paper_sections_are_not_mixed_with_the_arrays() {
    let e = error_of(&format!("{BASE}\n[slider]\nmass = 1.0\nvelocity = 1.0\n"));
    assert!(e.contains("[slider]") && e.contains("[[impactor]]"), "{e}");
}

/// Two free impactors pressed together by a preload: nothing holds them against each other,
/// so the preload carries no force at equilibrium: refused. A damper pressed onto the
/// structure by a preload is held by its spring: in equilibrium, and the run starts from it.
#[test]
fn preloads_need_an_equilibrium() {
    let text = format!(
        "{BASE}\n[[impactor]]\nname = \"free\"\nmass = 1.0\n\n[[contact]]\nname = \"pressed\"\nbetween = [\"die\", \"free\"]\ngap = -1e-4\nstiffness = 1e6\n"
    );
    let e = error_of(&text);
    assert!(
        e.contains("contact[3].gap") || e.contains("contact[2].gap"),
        "{e}"
    );
    assert!(e.contains("cannot be in equilibrium"), "{e}");
    // A damper pressed onto its point by a preload: held by its spring, in equilibrium.
    // (The die stands off by 1 mm: the preload lifts the bed towards it.)
    let text = BASE
        .replace(
            "stiffness = 6.3e7\nrestitution = 0.8",
            "stiffness = 6.3e7\nrestitution = 0.8\ngap = -1e-6",
        )
        .replace("stiffness = 4.3e7", "stiffness = 4.3e7\ngap = 1e-3");
    let m = load(&text).unwrap();
    let sol = m.solve(&m.options().unwrap()).unwrap();
    // At equilibrium the contact force equals the damper spring's: k_d (z_d − 0) with the
    // contact pushing the damper by K_d δ.
    let x0 = &sol.x0;
    let net = &m.network;
    let (delta, _) = net.overlap(1, x0);
    let zd = x0[net.n_modes() + 1];
    let kd = 900.0;
    assert!(delta > 0.0);
    assert!(
        ((6.3e7 * delta) - kd * zd).abs() < 1e-9 * kd * zd.abs(),
        "{delta} {zd}"
    );
    assert!(sol.residual_run_end <= 1e-9);
}

/// examples/press-off-centre-4-dampers.toml made mirror-symmetric about both bed axes: no
/// off-centre strike point S, the accelerometer B at the centre, the slider striking O_b.
pub(crate) fn symmetric_press() -> String {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/press-off-centre-4-dampers.toml");
    std::fs::read_to_string(path)
        .unwrap()
        .replacen("S = [0.15, 0.0], ", "", 1)
        .replacen(
            "spring_inset = 0.03\n",
            "spring_inset = 0.03\nb_offset = [0.0, 0.0]\n",
            1,
        )
        .replacen(
            r#"between = ["slider", "S"]"#,
            r#"between = ["slider", "O_b"]"#,
            1,
        )
}

/// examples/press-off-centre-4-dampers.toml made mirror-symmetric about both bed axes (no
/// off-centre strike point S, the accelerometer B at the centre, the slider striking O_b): the
/// four identical dampers at (±0.16, ±0.08) m then see the same motion, so their contacts' impact
/// rows are identical up to round-off. The mesh is the mirror image of itself to round-off (its
/// grid lines are symmetric sets) and so are the modes, to the eigen-solver's accuracy
/// (≈1e-12 of the mode shapes); switching times are located to 1e-13 of the fastest period.
/// 1e-9 of each quantity's scale leaves room for that and is far below what any asymmetry does:
/// B's grid lines at (0.08, 0.05) m alone make the rows differ by about 1e-3.
#[test]
fn four_dampers_at_symmetric_points_give_four_identical_impact_rows() {
    let symmetric = symmetric_press()
        // The damper impacts of the blow fall within its first 4 ms; 5 ms of the symmetric
        // machine (whose four identical one-way dashpots switch at the same instants) keep the
        // test's cost in bounds.
        .replacen("duration = 0.5", "duration = 0.005", 1);
    assert!(!symmetric.contains("\"S\"") && symmetric.contains("b_offset"));
    let m = NetworkModel::from_text("sym.toml", symmetric, &[]).unwrap();
    let sol = m.solve(&m.options().unwrap()).unwrap();
    let rows = |c: &str| -> Vec<_> { sol.impacts.iter().filter(|r| r.contact == c).collect() };
    let first = rows("bed_damper1");
    assert!(!first.is_empty());
    let f_scale = first
        .iter()
        .map(|r| r.peak_force_n.unwrap())
        .fold(0.0, f64::max);
    let v_scale = first
        .iter()
        .map(|r| r.approach_velocity_m_per_s.abs())
        .fold(0.0, f64::max);
    let t_scale = sol.t_final;
    let d_scale = first.iter().map(|r| r.duration_s).fold(0.0, f64::max);
    let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-9 * scale;
    for other in ["bed_damper2", "bed_damper3", "bed_damper4"] {
        let rs = rows(other);
        assert_eq!(rs.len(), first.len(), "{other}");
        for (a, b) in first.iter().zip(&rs) {
            let same = close(a.start_s, b.start_s, t_scale)
                && close(a.duration_s, b.duration_s, t_scale)
                && close(a.peak_time_s, b.peak_time_s, t_scale)
                && close(a.peak_force_n.unwrap(), b.peak_force_n.unwrap(), f_scale)
                && close(
                    a.approach_velocity_m_per_s,
                    b.approach_velocity_m_per_s,
                    v_scale,
                )
                && close(a.impulse_n_s, b.impulse_n_s, f_scale * d_scale)
                && close(
                    a.exit_velocity_m_per_s.unwrap_or(0.0),
                    b.exit_velocity_m_per_s.unwrap_or(0.0),
                    v_scale,
                );
            assert!(same, "{other}:\n{a:?}\n{b:?}");
        }
    }
}

/// A bed point off the bed, or named as one of the machine's own points, is an error naming
/// `structure.fem.machine.bed_points.NAME` in the file.
#[test]
fn bed_points_off_the_bed_or_with_the_machines_names_are_refused() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/press-off-centre-4-dampers.toml");
    let text = std::fs::read_to_string(path).unwrap();
    for (from, to, field, what) in [
        (
            "S = [0.15, 0.0]",
            "S = [0.25, 0.0]",
            "bed_points.S",
            "outside",
        ),
        (
            "D4 = [0.16, -0.08]",
            "B = [0.16, -0.08]",
            "bed_points.B",
            "O_b, B, O_f",
        ),
    ] {
        let e = error_of(&text.replacen(from, to, 1));
        assert!(
            e.contains(&format!("structure.fem.machine.{field}")) && e.contains(what),
            "{e}"
        );
        assert!(e.starts_with("m.toml:"), "{e}");
    }
}
