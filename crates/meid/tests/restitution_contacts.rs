//! `restitution = e` on the model's contacts: a slider striking a free mass (a clean two-body
//! impact in the impact system) separates with e times its approach velocity, for the linear
//! law (both release rules, exact method: to 1e-12) and Hunt-Crossley (dopri5 at rtol 1e-12,
//! n = 1 and 1.5, two approach velocities: to 1e-10); the damping set on the paper's model follows the documented reduced
//! masses; bad values are refused naming the file, line and fields.

use meid::impact::restitution::{x_of_e, zeta_of_e};
use meid::impact::{ContactLaw, Release, Switch};
use meid::integrate::{solve, Method, NoOutput, Options};
use meid::model::{Case, Model};
use std::path::PathBuf;

const ES: [f64; 5] = [0.1, 0.3, 0.5, 0.7, 0.9];

/// A slider (1.2 kg) striking a free 10 kg mass: a lumped structure of one mass and no springs
/// (one rigid-body mode).
fn free_mass(v_s: f64, contact: &str) -> String {
    format!(
        r#"name = "slider against a free mass"
[structure.lumped]
masses = [{{ name = "bed", mass = 10.0 }}]

[points]
bed_contact = "bed"
measurement = "bed"

[slider]
mass = 1.2
velocity = {v_s:?}

[contact.slider_bed]
{contact}
"#
    )
}

/// The slider's exit velocity relative to the bed over its approach velocity, from the run's
/// final state (no force acts after the release, so the velocities are those at release).
fn measured_restitution(m: &Model, method: Method) -> f64 {
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let opts = Options {
        method,
        duration: 2e-3,
        sample_rate: None,
        rtol: 1e-12,
        atol: 1e-18,
        ..Options::default()
    };
    let sol = solve(&sys, &opts, &mut NoOutput).unwrap();
    assert!(!sol.mode_final.on(Switch::SliderBed), "still in contact");
    let nd = sys.dofs();
    let a = sys.relative_vector(Switch::SliderBed);
    let rate: f64 = (0..nd).map(|i| a[i] * sol.x_final[nd + i]).sum();
    -rate / sys.slider.velocity
}

#[test]
fn linear_restitution_is_met_exactly() {
    for release in ["force", "overlap"] {
        for e in ES {
            let text = free_mass(
                1.2,
                &format!(
                    "law = \"linear\"\nstiffness = 4.3e7\nrestitution = {e}\nrelease = \"{release}\""
                ),
            );
            let m = Model::from_text("free.toml", text, &[]).unwrap();
            let got = measured_restitution(&m, Method::Exact);
            assert!((got - e).abs() <= 1e-12, "{release} e {e}: measured {got}");
        }
    }
}

#[test]
fn hunt_crossley_restitution_is_met() {
    for n in [1.5, 1.0] {
        for v_s in [1.2, 6.2] {
            for e in ES {
                let text = free_mass(
                    v_s,
                    &format!(
                        "law = \"hunt-crossley\"\nstiffness = 3.0e9\nexponent = {n:?}\nrestitution = {e}"
                    ),
                );
                let m = Model::from_text("free.toml", text, &[]).unwrap();
                let got = measured_restitution(&m, Method::Dopri5);
                assert!(
                    (got - e).abs() <= 1e-10,
                    "n {n} v_s {v_s} e {e}: measured {got}"
                );
            }
        }
    }
}

fn example(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// The paper's lumped model with both contact dampings replaced by `restitution` lines.
fn paper_with(slider_bed: &str, bed_damper: &str) -> String {
    let text = std::fs::read_to_string(example("paper-lumped.toml")).unwrap();
    let text = text.replacen("damping = 0.0                  # C_s", slider_bed, 1);
    let text = text.replacen("damping = 0.0                  # C_d", bed_damper, 1);
    assert!(!text.contains("# C_s") && !text.contains("# C_d"));
    text
}

/// On the paper's lumped model (both modes kept, so 1/Σψ(bed)² is the bed's 10 kg):
/// C_s = 2ζ√(K_s m*) with 1/m* = 1/m_s + 1/m_b, C_d the same with m_d, for each release rule;
/// the notes say what was set.
#[test]
fn paper_model_damping_follows_the_reduced_masses() {
    for (rule, release) in [("force", Release::Force), ("overlap", Release::Overlap)] {
        let text = paper_with("restitution = 0.5", "restitution = 0.7")
            .replace("release = \"force\"", &format!("release = \"{rule}\""));
        let m = Model::from_text("paper.toml", text, &[]).unwrap();
        let sys = m.impact_system(Case::AsSpecified).unwrap();
        let (ks, kd) = (4.2980449e7_f64, 1.2535964e8_f64);
        let ms = 1.0 / (1.0 / 1.2 + 1.0 / 10.0);
        let md = 1.0 / (1.0 / 3.5 + 1.0 / 10.0);
        let cs = 2.0 * zeta_of_e(0.5, release).unwrap() * (ks * ms).sqrt();
        let cd = 2.0 * zeta_of_e(0.7, release).unwrap() * (kd * md).sqrt();
        let damping = |law: ContactLaw| match law {
            ContactLaw::Linear { damping, .. } => damping,
            other => panic!("{other:?}"),
        };
        let got_s = damping(sys.slider_bed.law);
        let got_d = damping(sys.bed_damper.unwrap().law);
        assert!(
            (got_s - cs).abs() <= 1e-12 * cs,
            "{rule}: C_s {got_s} vs {cs}"
        );
        assert!(
            (got_d - cd).abs() <= 1e-12 * cd,
            "{rule}: C_d {got_d} vs {cd}"
        );
        // The no-damper and added-mass cases keep the slider-bed law.
        for case in [Case::NoDamper, Case::AddedMass] {
            let other = m.impact_system(case).unwrap();
            assert_eq!(other.slider_bed, sys.slider_bed, "{case:?}");
        }
        let notes = m.diagnostics().notes;
        let note = notes
            .iter()
            .find(|n| n.starts_with("contact.slider_bed: restitution e = 0.5 → damping C = "))
            .unwrap_or_else(|| panic!("{notes:?}"));
        assert!(
            note.contains("m* = 1.0714 kg") && note.contains("1/Σψ² = 10.000 kg"),
            "{note}"
        );
        assert!(
            notes
                .iter()
                .any(|n| n.starts_with("contact.bed_damper: restitution e = 0.7")),
            "{notes:?}"
        );
    }
    // Hunt-Crossley on the slider: α = 2x/(3 v_s).
    let text = paper_with(
        "law = \"hunt-crossley\"\nrestitution = 0.5",
        "damping = 0.0",
    )
    .replacen(
        "law = \"linear\"\nstiffness = 4.2980449e7",
        "stiffness = 3e9",
        1,
    );
    let m = Model::from_text("paper.toml", text, &[]).unwrap();
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let ContactLaw::HuntCrossley { alpha, .. } = sys.slider_bed.law else {
        panic!("{:?}", sys.slider_bed.law)
    };
    let want = 2.0 * x_of_e(0.5).unwrap() / (3.0 * 1.2);
    assert!((alpha - want).abs() <= 1e-15 * want, "{alpha} vs {want}");
}

/// The 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).unwrap() + 1
}

#[test]
fn bad_restitution_is_refused_with_its_position() {
    let cases: Vec<(String, &str, &[&str])> = vec![
        (paper_with("restitution = 0.0", "damping = 0.0"), "restitution = 0.0", &["contact.slider_bed.restitution", "(0, 1]", "got 0"]),
        (paper_with("restitution = 1.5", "damping = 0.0"), "restitution = 1.5", &["contact.slider_bed.restitution", "(0, 1]", "got 1.5"]),
        (paper_with("restitution = nan", "damping = 0.0"), "restitution = nan", &["contact.slider_bed.restitution", "got NaN"]),
        (
            paper_with("restitution = 0.5\ndamping = 20.0", "damping = 0.0"),
            "restitution = 0.5",
            &["contact.slider_bed.restitution: given together with contact.slider_bed.damping = 20 N·s/m"],
        ),
        (
            paper_with("damping = 0.0", "restitution = 0.5\ndamping = 0.0"),
            "restitution = 0.5",
            &["contact.bed_damper.restitution: given together with contact.bed_damper.damping = 0 N·s/m"],
        ),
        (
            paper_with("restitution = 0.5", "damping = 0.0")
                .replacen("law = \"linear\"\nstiffness = 4.2980449e7", "law = \"hertz\"\nstiffness = 3e9", 1),
            "restitution = 0.5",
            &["contact.slider_bed.restitution", "hertz law", "hunt-crossley"],
        ),
        (
            paper_with("restitution = 0.5\nalpha = 0.2", "damping = 0.0")
                .replacen("law = \"linear\"\nstiffness = 4.2980449e7", "law = \"hunt-crossley\"\nstiffness = 3e9", 1),
            "restitution = 0.5",
            &["contact.slider_bed.restitution: given together with contact.slider_bed.alpha = 0.2 s/m"],
        ),
        (
            paper_with("damping = 0.0", "restitution = 0.5")
                .replacen("law = \"linear\"\nstiffness = 1.2535964e8", "law = \"hunt-crossley\"\nstiffness = 3e9", 1),
            "restitution = 0.5",
            &["contact.bed_damper.restitution", "approach velocity", "give alpha"],
        ),
    ];
    for (text, needle, parts) in cases {
        let err = Model::from_text("bad.toml", text.clone(), &[])
            .map(|_| ())
            .unwrap_err()
            .to_string();
        let at = format!("bad.toml:{}:", line_of(&text, needle));
        assert!(err.contains(&at), "{err} (want {at})");
        for p in parts {
            assert!(err.contains(p), "{err} (want {p})");
        }
    }
    // The example names C_s = 0: a restitution given with --set is refused, naming the --set.
    let err = Model::from_file(
        &example("paper-lumped.toml"),
        &["contact.slider_bed.restitution=0.5".into()],
    )
    .map(|_| ())
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("--set contact.slider_bed.restitution=0.5")
            && err.contains("given together with contact.slider_bed.damping = 0 N·s/m"),
        "{err}"
    );
}
