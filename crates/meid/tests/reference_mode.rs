//! `structure.reference_mode` names ω_ref by the structure's mode number (issue 27, item 10).
//!
//! Closed forms: for the lumped two-mass chain (bed m_b on columns k_c over a base m_f on
//! supports k_f, nothing held) the effective modal masses along the blow `Γ_i² = (φ_iᵀ M 1)²`
//! of mass-normalised modes sum to the total mass `m_b + m_f` (Chopra §13.2: `Σ Γ_i² = 1ᵀ M 1`);
//! the bed's value in mode i is `ψ_i(bed)` with `1/ψ_i(bed)² = m_b + m_f r_i²`,
//! `r_i = φ_f/φ_b = 1 − m_b ω_i²/k_c` (the bed's row of `(K − ω² M) φ = 0`).

use meid::model::Model;

const LUMPED: &str = include_str!("../../../examples/paper-lumped.toml");
const FE_SOFT: &str = include_str!("../../../examples/paper-soft-base.toml");

fn without_reference(text: &str) -> String {
    text.lines()
        .filter(|l| !l.trim_start().starts_with("reference_mode"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn lumped_effective_masses_and_default_reference() {
    let m = Model::from_text("lumped.toml", without_reference(LUMPED), &[]).unwrap();
    let gamma = m.structure.effective_mass_kg.clone().unwrap();
    let sum: f64 = gamma.iter().sum();
    assert!((sum / 51.0 - 1.0).abs() < 1e-9, "Σ Γ² = {sum}");
    // Not given: the largest effective mass along the blow, the rigid-body mode (mode 1).
    let r = m.reference_mode().unwrap();
    assert!(!r.given);
    assert_eq!(r.number, 1);
    assert!(
        (r.frequency_hz / 6.35 - 1.0).abs() < 1e-6,
        "{}",
        r.frequency_hz
    );
    // The strike-point masses in closed form.
    let k_c = 2.5415164e7;
    for i in 0..2 {
        let w = m.structure.omega_rad_per_s[i];
        let ratio = 1.0 - 10.0 * w * w / k_c;
        let want = 10.0 + 41.0 * ratio * ratio;
        let psi = m.structure.points["bed"][i];
        assert!(((1.0 / (psi * psi)) / want - 1.0).abs() < 1e-9, "mode {i}");
    }
    assert!(
        (r.strike_point_mass_kg / {
            let w = m.structure.omega_rad_per_s[0];
            let ratio = 1.0 - 10.0 * w * w / k_c;
            10.0 + 41.0 * ratio * ratio
        } - 1.0)
            .abs()
            < 1e-9
    );
    // The same as naming it, and the default is printed as such.
    let named = Model::from_text("lumped.toml", LUMPED.into(), &[]).unwrap();
    assert_eq!(named.reference_omega(), m.reference_omega());
    assert!(named.reference_mode().unwrap().given);
    assert!(r.describe().contains("mode 1") && r.describe().contains("not given"));
}

/// The FE machine retains two of its 30 modes ("participation"): the reference mode is named
/// by its number among all modes, a retained index is refused with the retained modes listed,
/// and the default picks the vertical rigid-body mode (6.35 Hz) as the file does.
#[test]
fn fe_reference_by_structure_number() {
    let m = Model::from_text("soft.toml", FE_SOFT.into(), &[]).unwrap();
    // The structure's retained modes (the static correction's pseudo-modes, numbered 0, are
    // not modes of the structure and never a reference).
    let st = &m.structure;
    let numbers: Vec<usize> = (0..st.len())
        .filter(|&i| !st.is_pseudo(i))
        .map(|i| st.mode_numbers[i])
        .collect();
    assert_eq!(numbers.len(), 2);
    assert!((0..st.len()).all(|i| st.is_pseudo(i) == (st.mode_numbers[i] == 0)));
    assert!(numbers[0] > 1, "{numbers:?}");
    let r = m.reference_mode().unwrap();
    assert_eq!(r.number, numbers[0]);
    assert!(
        (r.frequency_hz / 6.35 - 1.0).abs() < 0.01,
        "{}",
        r.frequency_hz
    );
    // Old meaning (the first retained mode) refused, naming the field and the retained modes.
    let e = Model::from_text(
        "soft.toml",
        FE_SOFT.into(),
        &["structure.reference_mode=1".into()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("structure.reference_mode") && e.contains("not a retained mode"),
        "{e}"
    );
    assert!(e.contains(&format!("{} (", numbers[0])), "{e}");
    // The default agrees with the file's choice.
    let d = Model::from_text("soft.toml", without_reference(FE_SOFT), &[]).unwrap();
    let dr = d.reference_mode().unwrap();
    assert_eq!(dr.number, r.number);
    assert!(!dr.given);
    // Γ² of the rigid-body mode: nearly the whole machine (bed, base, columns ≈ 53 kg) moves
    // with it; the bed mode carries less.
    let g = d.structure.effective_mass_kg.clone().unwrap();
    assert!(g[0] > g[1], "{g:?}");
}

/// A reference mode that barely moves the strike point (1/ψ² more than 100 times another
/// retained mode's) is warned about, naming the field; a mode that moves it is not.
#[test]
fn reference_that_barely_moves_the_strike_point_warns() {
    let text = |psi1: f64| {
        format!(
            r#"
[structure]
reference_mode = 1
[structure.modal]
frequencies_hz = [14.0, 35.0]
damping_ratios = [0.01, 0.01]
[structure.modal.shapes]
bed = [{psi1:e}, 0.05]
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = 1.2
velocity = 1.2
[contact.slider_bed]
stiffness = 4.3e7
"#
        )
    };
    // 1/ψ² = 1e6 kg against 400 kg: 2500 times.
    let m = Model::from_text("press.toml", text(1e-3), &[]).unwrap();
    let w = m.diagnostics().warnings;
    assert!(
        w.iter().any(|x| x.contains("structure.reference_mode")
            && x.contains("barely moves the strike point")),
        "{w:?}"
    );
    // 1/ψ² = 100 kg against 400 kg: no warning.
    let m = Model::from_text("press.toml", text(0.1), &[]).unwrap();
    assert!(
        !m.diagnostics()
            .warnings
            .iter()
            .any(|x| x.contains("barely moves")),
        "{:?}",
        m.diagnostics().warnings
    );
    // Tabulated modes carry no mass matrix: no default reference.
    let m = Model::from_text("press.toml", without_reference(&text(0.1)), &[]).unwrap();
    assert!(m.reference_mode().is_none());
}
