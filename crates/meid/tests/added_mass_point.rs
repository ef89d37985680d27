//! `[added_mass]` at any named point (issue 10, part 9).
//!
//! Closed form: the lumped paper model is a 2-DOF chain — bed m_b = 10 kg on columns k_c over
//! the floating base m_f = 41 kg on supports k_f. A rigid mass m_a at point P adds m_a to P's
//! mass, and the natural frequencies are the roots of
//!
//! ```text
//! det(K − ω² M) = 0:   m_1 m_2 ω⁴ − (k_c m_2 + (k_c + k_f) m_1) ω² + k_c k_f = 0,
//! ```
//!
//! with (m_1, m_2) = (m_b + m_a, m_f) for P = bed and (m_b, m_f + m_a) for P = base. The
//! Rayleigh-Ritz of `ModalModel::with_point_mass` with all modes retained is exact for a lumped
//! model, so the system's frequencies must match to round-off (tolerance 1e-10 relative), and
//! its mode shapes must be mass-normalised and orthogonal for the new mass matrix.

use meid::analysis::compare::{CaseName, CompareOptions, Comparison};
use meid::model::{Case, Model};
use meid::Error;

const K_C: f64 = 2.5415164e7;
const K_F: f64 = 8.1195270e4;
const M_B: f64 = 10.0;
const M_F: f64 = 41.0;

/// The lumped paper machine without a damper, with `[added_mass]` `extra` lines.
fn text(added: &str) -> String {
    format!(
        r#"
[structure]
reference_mode = 1
[structure.lumped]
damping_ratios = [0.01, 0.01]
masses = [{{ name = "bed", mass = {M_B} }}, {{ name = "base", mass = {M_F} }}]
springs = [
  {{ name = "columns", nodes = ["bed", "base"], stiffness = {K_C:e} }},
  {{ name = "supports", nodes = ["base", "ground"], stiffness = {K_F:e} }},
]
floor = ["supports"]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = 1.2
velocity = 1.2
[contact.slider_bed]
stiffness = 4.2980449e7
{added}
"#
    )
}

fn model(added: &str) -> Result<Model, Error> {
    Model::from_text("added.toml", text(added), &[])
}

/// ω₁ < ω₂ (rad/s) of the 2-DOF chain with masses m1 (bed), m2 (base).
fn closed_form(m1: f64, m2: f64) -> [f64; 2] {
    let a = m1 * m2;
    let b = K_C * m2 + (K_C + K_F) * m1;
    let c = K_C * K_F;
    let root = (b * b - 4.0 * a * c).sqrt();
    // Stable forms of (b ∓ root)/(2a).
    let hi = (b + root) / (2.0 * a);
    let lo = c / (a * hi);
    [lo.sqrt(), hi.sqrt()]
}

/// Checks the frequencies against the closed form and the shapes against M-orthonormality.
fn check(sys: &meid::impact::ImpactSystem, m1: f64, m2: f64, what: &str) {
    let w = &sys.structure.omega_rad_per_s;
    let want = closed_form(m1, m2);
    assert_eq!(w.len(), 2);
    for i in 0..2 {
        assert!(
            (w[i] / want[i] - 1.0).abs() < 1e-10,
            "{what}: mode {} {} vs closed form {} rad/s",
            i + 1,
            w[i],
            want[i]
        );
    }
    let bed = &sys.structure.points["bed"];
    let base = &sys.structure.points["base"];
    for i in 0..2 {
        for j in 0..2 {
            let g = m1 * bed[i] * bed[j] + m2 * base[i] * base[j];
            let e = if i == j { 1.0 } else { 0.0 };
            assert!((g - e).abs() < 1e-10, "{what}: Ψᵀ M Ψ [{i}{j}] = {g}");
        }
    }
}

#[test]
fn added_mass_on_the_base_and_the_bed_match_the_two_dof_closed_form() {
    let m_a = 7.5;
    // Bare machine first: the file's own closed form.
    let bare = model("").unwrap().impact_system(Case::NoDamper).unwrap();
    check(&bare, M_B, M_F, "bare");
    let base = model(&format!("[added_mass]\nmass = {m_a}\npoint = \"base\""))
        .unwrap()
        .impact_system(Case::AsSpecified)
        .unwrap();
    check(&base, M_B, M_F + m_a, "on the base");
    assert_eq!(base.added_mass, m_a);
    let bed = model(&format!("[added_mass]\nmass = {m_a}\npoint = \"bed\""))
        .unwrap()
        .impact_system(Case::AsSpecified)
        .unwrap();
    check(&bed, M_B + m_a, M_F, "on the bed");
    // No point: the bed contact point (the behaviour before `point` existed).
    let default = model(&format!("[added_mass]\nmass = {m_a}"))
        .unwrap()
        .impact_system(Case::AsSpecified)
        .unwrap();
    assert_eq!(
        default.structure.omega_rad_per_s,
        bed.structure.omega_rad_per_s
    );
    // The two placements differ: on the base the rigid-body mode drops, on the bed the bed mode.
    let w0 = &bare.structure.omega_rad_per_s;
    assert!(base.structure.omega_rad_per_s[0] < w0[0]);
    assert!(bed.structure.omega_rad_per_s[1] < w0[1]);
}

#[test]
fn with_a_damper_the_added_mass_case_defaults_to_the_damper_mass_at_the_point() {
    let ex =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    let m_d = 3.5;
    // No [added_mass]: the damper's mass at the bed contact point.
    let m = Model::from_file(&ex, &[]).unwrap();
    assert_eq!(m.added_mass(), Some((m_d, "bed".to_string())));
    check(
        &m.impact_system(Case::AddedMass).unwrap(),
        M_B + m_d,
        M_F,
        "m_d on the bed",
    );
    // `added_mass.point` alone: the damper's mass at that point; the file still runs its damper.
    let m = Model::from_file(&ex, &["added_mass.point=\"base\"".into()]).unwrap();
    assert_eq!(m.added_mass(), Some((m_d, "base".to_string())));
    check(
        &m.impact_system(Case::AddedMass).unwrap(),
        M_B,
        M_F + m_d,
        "m_d on the base",
    );
    assert!(m.impact_system(Case::AsSpecified).unwrap().damper.is_some());
    // A mass given beside the damper sets the compared mass.
    let m = Model::from_file(
        &ex,
        &[
            "added_mass.point=\"base\"".into(),
            "added_mass.mass=5".into(),
        ],
    )
    .unwrap();
    check(
        &m.impact_system(Case::AddedMass).unwrap(),
        M_B,
        M_F + 5.0,
        "5 kg on the base",
    );
}

#[test]
fn compare_puts_the_added_mass_at_its_point() {
    let ex =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    let m = Model::from_file(&ex, &["added_mass.point=\"base\"".into()]).unwrap();
    let opts = CompareOptions {
        duration_s: 0.5,
        ..CompareOptions::default()
    };
    let r = Comparison::new(m, opts).run().unwrap();
    assert_eq!(r.added_mass, Some((3.5, "base".to_string())));
    let case = r
        .cases
        .iter()
        .find(|c| c.case == CaseName::AddedMass)
        .unwrap();
    // The reference-mode band is centred on that case's own rigid-body mode: m_f + m_d.
    let want = closed_form(M_B, M_F + 3.5)[0] / (2.0 * std::f64::consts::PI);
    let centre = case.modes[0].centre_hz;
    assert!((centre / want - 1.0).abs() < 1e-10, "{centre} vs {want} Hz");
    assert!(r
        .table_text()
        .contains("added mass: 3.5 kg fixed at point base"));
    let s = r.summary();
    assert_eq!(s.added_mass_point.as_deref(), Some("base"));
}

#[test]
fn bad_added_mass_settings_are_clear_errors() {
    let e = model("[added_mass]\nmass = 2.0\npoint = \"floor\"")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("added_mass.point") && e.contains("'floor'") && e.contains("valid: base, bed"),
        "{e}"
    );
    assert!(e.starts_with("added.toml:"), "located in the file: {e}");
    let e = model("[added_mass]\npoint = \"base\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("added_mass.mass is missing"), "{e}");
    let e = model("[added_mass]\nmass = -1.0").unwrap_err().to_string();
    assert!(e.contains("added_mass.mass") && e.contains("> 0"), "{e}");
    let e = model("[added_mass]\nmass = 1.0\npont = \"base\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean `point`"), "{e}");
}

/// An added mass at a point no mode moves: the root of the clamped cantilever
/// (`tests/data/eb_cantilever.toml`, ψ(root) = 0 in every mode). Before: accepted, and the
/// added-mass case was the bare structure (same frequencies, same response) under the name of an
/// absorber. Now refused at `added_mass.point`; at the tip it reads.
#[test]
fn an_added_mass_at_a_point_that_does_not_move_is_refused() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/eb_cantilever.toml");
    let set = |p: &str| {
        vec![
            "added_mass.mass=1.0".to_string(),
            format!("added_mass.point=\"{p}\""),
        ]
    };
    let e = Model::from_file(&path, &set("root")).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::Input { .. }), "{msg}");
    assert!(
        msg.contains("added_mass.point: 'root' does not move in any retained mode"),
        "{msg}"
    );
    Model::from_file(&path, &set("tip")).unwrap();
}
