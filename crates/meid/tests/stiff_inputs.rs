//! Stiff and ill-conditioned inputs: lumped springs far stiffer than the rest are made rigid
//! (their masses merged, exact in the limit k → ∞), spreads the eigen-solver cannot resolve are
//! warned about, spreads the closed-form propagator cannot carry are errors or warnings.
//!
//! The reported defect: `--set 'structure.lumped.springs[0].stiffness=1e16'` on the paper's
//! lumped model made the damper fly off, left an energy residual of 0.45, or (1e20) gave no
//! events and a contact force growing linearly, without a warning.

use std::f64::consts::TAU;
use std::path::Path;

use meid::analysis::energy::simulate;
use meid::model::{Case, Model};

const KF: f64 = 8.1195270e4;
const MB: f64 = 10.0;
const MF: f64 = 41.0;

fn paper(overrides: &[&str]) -> meid::Result<Model> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/paper-lumped.toml"
    );
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Model::from_file(Path::new(path), &o)
}

fn column(k: f64) -> String {
    format!("structure.lumped.springs[0].stiffness={k:e}")
}

/// With a 1e16 N/m column the bed and the base move as one: one mode, ω² = k_f/(m_b + m_f),
/// ψ = 1/√(m_b + m_f) at both, floor force k_f ψ; the merge is reported as a note.
#[test]
fn rigid_column_is_merged_to_the_closed_form_limit() {
    for k in [1e16, 1e20] {
        let m = paper(&[&column(k)]).unwrap();
        let s = &m.structure;
        assert_eq!(s.len(), 1);
        let w = (KF / (MB + MF)).sqrt();
        assert!(
            (s.omega_rad_per_s[0] - w).abs() <= 1e-14 * w,
            "{} vs {w}",
            s.omega_rad_per_s[0]
        );
        let psi = 1.0 / (MB + MF).sqrt();
        for p in ["bed", "base"] {
            assert!((s.point(p).unwrap()[0].abs() - psi).abs() <= 1e-14 * psi);
        }
        let fk = s.floor_force.as_ref().unwrap().stiffness[0].abs();
        assert!((fk - KF * psi).abs() <= 1e-13 * KF * psi);
        let d = m.diagnostics();
        assert!(
            d.notes
                .iter()
                .any(|n| n.contains("springs[0].stiffness") && n.contains("rigid")),
            "{:?}",
            d.notes
        );
        assert!(d.warnings.is_empty(), "{:?}", d.warnings);
        // Static flexibility of the rigid limit: 1/k_f at both points, all captured.
        for r in &d.truncation {
            assert!((r.static_flexibility_m_per_n - 1.0 / KF).abs() <= 1e-13 / KF);
            assert!((r.captured_share - 1.0).abs() <= 1e-12);
        }
    }
    // The paper's own column is not touched.
    let m = paper(&[]).unwrap();
    assert_eq!(m.structure.len(), 2);
    // Only the damper's mass ratio at O_b (m_d/m_eff), no note about the column.
    let notes = m.diagnostics().notes;
    assert!(
        notes.len() == 1 && notes[0].contains("m_d/m_eff"),
        "{notes:?}"
    );
}

/// The merged model conserves energy and gives the rigid-limit result: the energy ratio of the
/// unmerged model approaches it as 1/k (first-order perturbation), so (E(k) − E_∞)·k is the
/// same for k = 1e11, 1e12, 1e13 (measured: 1.00e7, 9.8e6, 9.8e6).
#[test]
fn merged_model_conserves_energy_and_is_the_limit() {
    let run = |k: f64| {
        let m = paper(&[&column(k)]).unwrap();
        let sys = m.impact_system(Case::AsSpecified).unwrap();
        simulate(&sys, &m.options(), false).unwrap().summary
    };
    let lim = run(1e16);
    let r = lim.energy_balance_residual.unwrap();
    assert!(r <= 1e-9, "{r}");
    assert!(
        lim.energy_balance_residual_run_end <= 1e-9,
        "{}",
        lim.energy_balance_residual_run_end
    );
    let e_inf = lim.energy_ratio.unwrap();
    // The damper stays on its spring: it does not fly off at constant speed.
    assert!(lim.switching_events >= 2, "{}", lim.switching_events);
    let c: Vec<f64> = [1e11, 1e12, 1e13]
        .iter()
        .map(|&k| {
            let s = run(k);
            assert!(s.energy_balance_residual_run_end <= 1e-9);
            (s.energy_ratio.unwrap() - e_inf) * k
        })
        .collect();
    eprintln!("E_inf = {e_inf}, (E(k) - E_inf) k = {c:?}");
    assert!(c.iter().all(|&x| x > 0.0), "{c:?}");
    assert!((c[1] / c[2] - 1.0).abs() < 0.05, "{c:?}");
    assert!((c[0] / c[1] - 1.0).abs() < 0.05, "{c:?}");
    // The same limit from a file written as one 51 kg mass.
    let one = format!(
        r#"
[structure.lumped]
damping_ratios = 0.01
masses = [ {{ name = "bed", mass = {m} }} ]
springs = [ {{ name = "supports", nodes = ["bed", "ground"], stiffness = {KF} }} ]
[points]
bed_contact = "bed"
damper_anchor = "bed"
measurement = "bed"
[slider]
mass = 1.2
velocity = 1.2
[damper]
mass = 3.5
stiffness = 1.8e3
damping = 7.0e2
[contact.slider_bed]
stiffness = 4.2980449e7
[contact.bed_damper]
stiffness = 1.2535964e8
"#,
        m = MB + MF
    );
    let m = Model::from_text("one.toml", one, &[]).unwrap();
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let e1 = simulate(&sys, &m.options(), false)
        .unwrap()
        .summary
        .energy_ratio
        .unwrap();
    assert!((e1 - e_inf).abs() <= 1e-9 * e_inf, "{e1} vs {e_inf}");
}

/// A spring short of the merge threshold but beyond the resolved spread is warned about, with
/// its field and the suggested alternatives.
#[test]
fn unresolved_spread_is_warned_about() {
    let m = paper(&[&column(1e14)]).unwrap();
    assert_eq!(m.structure.len(), 2);
    let d = m.diagnostics();
    assert!(
        d.notes.len() == 1 && d.notes[0].contains("m_d/m_eff"),
        "{:?}",
        d.notes
    );
    assert_eq!(d.warnings.len(), 1, "{:?}", d.warnings);
    let w = &d.warnings[0];
    assert!(
        w.starts_with("structure.lumped.springs[0].stiffness"),
        "{w}"
    );
    assert!(w.contains("rigid") && w.contains("1e3"), "{w}");
    // (ω_2/ω_1)² = 7.8e9 > 1e-6/ε = 4.5e9.
    assert!(w.contains("7.81e9"), "{w}");
}

/// A spring to the ground far stiffer than the rest fixes its mass: ground —1e18— a (2 kg)
/// —1e5— b (3 kg): one mode ω² = k/m_b, ψ_b = 1/√m_b, ψ_a = 0, and the force to the floor
/// through the rigid spring is the force of the spring a-b, k u_b.
#[test]
fn rigid_spring_to_ground_fixes_its_mass() {
    let text = r#"
[structure.lumped]
masses = [ { name = "a", mass = 2.0 }, { name = "b", mass = 3.0 } ]
springs = [
  { name = "anchor", nodes = ["a", "ground"], stiffness = 1e18 },
  { nodes = ["a", "b"], stiffness = 1e5 },
]
[points]
bed_contact = "b"
measurement = "b"
[slider]
mass = 0.5
velocity = 1.0
[contact.slider_bed]
stiffness = 1e7
"#;
    let m = Model::from_text("ground.toml", text.to_string(), &[]).unwrap();
    let s = &m.structure;
    assert_eq!(s.len(), 1);
    let w = (1e5_f64 / 3.0).sqrt();
    assert!((s.omega_rad_per_s[0] - w).abs() <= 1e-14 * w);
    let psi = s.point("b").unwrap()[0];
    assert!((psi.abs() - 1.0 / 3.0_f64.sqrt()).abs() <= 1e-15);
    assert_eq!(s.point("a").unwrap()[0], 0.0);
    let fk = s.floor_force.as_ref().unwrap().stiffness[0];
    assert!((fk - 1e5 * psi).abs() <= 1e-12 * 1e5 * psi.abs(), "{fk}");
    assert!(m.diagnostics().notes[0].contains("'anchor'"));
    // The static flexibility at b is 1/k.
    let g = s.static_flexibility["b"];
    assert!((g - 1e-5).abs() <= 1e-17, "{g}");
}

/// A very light mass on a stiff spring has the same effect (its frequency is the spread): it
/// is merged into its neighbour, which it follows in the limit.
#[test]
fn light_mass_is_merged_into_its_neighbour() {
    let m = paper(&[]).unwrap();
    let mut spec = m.spec.clone();
    let l = spec.structure.lumped.as_mut().unwrap();
    l.masses.push(meid::model::MassSpec {
        name: "sensor".into(),
        mass: 1e-9,
    });
    l.springs.push(meid::model::SpringSpec {
        name: Some("glue".into()),
        nodes: ["bed".into(), "sensor".into()],
        stiffness: 1e8,
    });
    let text = toml::to_string(&spec).unwrap();
    let m2 = Model::from_text("light.toml", text, &[]).unwrap();
    assert_eq!(m2.structure.len(), 2);
    let d = m2.diagnostics();
    assert!(
        d.notes.iter().any(|n| n.contains("'glue'")),
        "{:?}",
        d.notes
    );
    // The two modes are the paper's (the sensor adds 1e-9 kg to the bed).
    for (a, b) in m
        .structure
        .omega_rad_per_s
        .iter()
        .zip(&m2.structure.omega_rad_per_s)
    {
        assert!((a - b).abs() <= 1e-9 * a, "{a} vs {b}");
    }
}

/// A tabulated structure whose modes span (1e6)² > 1e11: the closed-form propagator would
/// treat the 1 Hz mode as a free body and over 0.5 s turn it 3.1 rad from its motion: an
/// error naming the structure. Over 1 µs the neglected angle is 6e-6 rad, (ωT)²/2 = 2e-11:
/// nothing to report.
#[test]
fn unpropagatable_spread_is_an_error() {
    let text = |duration: f64| {
        format!(
            r#"
[structure.modal]
frequencies_hz = [1.0, 1.0e6]
shapes = {{ bed = [0.1, 0.1] }}
[points]
bed_contact = "bed"
measurement = "bed"
[slider]
mass = 0.5
velocity = 1.0
[contact.slider_bed]
stiffness = 1e7
[simulation]
duration = {duration}
"#
        )
    };
    let e = Model::from_text("tab.toml", text(0.5), &[])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("free body") && e.contains("structure mode 1"),
        "{e}"
    );
    assert!(e.starts_with("tab.toml:2:"), "{e}");
    let m = Model::from_text("tab.toml", text(1e-6), &[]).unwrap();
    assert!(m.diagnostics().warnings.is_empty());
    // dopri5 has no null tolerance: no error.
    let m = Model::from_text(
        "tab.toml",
        text(0.5).replace("[simulation]", "[simulation]\nmethod = \"dopri5\""),
        &[],
    )
    .unwrap();
    assert!(m.diagnostics().warnings.is_empty());
}

/// A damper spring of 1e-6 N/m next to a 283 Hz structure is below the propagator's resolution:
/// it is propagated as free, which over 0.5 s is off by (ωT)²/2 = 3.6e-8 (the run shows an
/// energy-balance residual of that order): a warning naming damper.stiffness.
#[test]
fn very_soft_damper_spring_is_warned_about() {
    let m = paper(&["damper.stiffness=1e-6"]).unwrap();
    let d = m.diagnostics();
    assert_eq!(d.warnings.len(), 1, "{:?}", d.warnings);
    assert!(
        d.warnings[0].contains("damper.stiffness"),
        "{}",
        d.warnings[0]
    );
    assert!(d.warnings[0].contains("free body"), "{}", d.warnings[0]);
    let w = (1e-6_f64 / 3.5).sqrt() * 0.5;
    assert!(0.5 * w * w > 1e-9 && w < 1.0);
    assert!(paper(&["damper.stiffness=0"])
        .unwrap()
        .diagnostics()
        .warnings
        .is_empty());
}

/// The frequency of a merged chain: a (1 kg) —k— b (2 kg) —1e17— c (3 kg) —k— ground with
/// k = 1e4 becomes a —k— (b+c, 5 kg) —k— ground: ω² = k (1/m_a + 2/m_bc ± √(1/m_a² + 4/m_bc²))/2
/// ... written out: the roots of λ² − k(1/m_a + 2/m_bc) λ + k²/(m_a m_bc) = 0.
#[test]
fn merged_chain_matches_its_two_dof_closed_form() {
    let text = r#"
[structure.lumped]
masses = [ { name = "a", mass = 1.0 }, { name = "b", mass = 2.0 }, { name = "c", mass = 3.0 } ]
springs = [
  { nodes = ["a", "b"], stiffness = 1e4 },
  { nodes = ["b", "c"], stiffness = 1e17 },
  { nodes = ["c", "ground"], stiffness = 1e4 },
]
damping_ratios = [0.01, 0.02, 0.03]
[points]
bed_contact = "a"
measurement = "c"
[slider]
mass = 0.5
velocity = 1.0
[contact.slider_bed]
stiffness = 1e6
"#;
    let m = Model::from_text("chain.toml", text.to_string(), &[]).unwrap();
    let s = &m.structure;
    assert_eq!(s.len(), 2);
    let (k, ma, mbc) = (1e4_f64, 1.0, 5.0);
    let b = k * (1.0 / ma + 2.0 / mbc);
    let c = k * k / (ma * mbc);
    let disc = (b * b - 4.0 * c).sqrt();
    let exact = [(b - disc) / 2.0, (b + disc) / 2.0];
    for (w, l) in s.omega_rad_per_s.iter().zip(exact) {
        assert!((w * w - l).abs() <= 1e-13 * l, "{} vs {l}", w * w);
    }
    // Per-mode ratios for the 3 original modes: the first two are kept.
    for (i, z) in [0.01, 0.02].iter().enumerate() {
        let d = s.damping[i * 2 + i];
        assert!((d - 2.0 * z * s.omega_rad_per_s[i]).abs() <= 1e-14 * d);
    }
    let hz: Vec<f64> = s.omega_rad_per_s.iter().map(|w| w / TAU).collect();
    assert!(s.labels[0].contains(&format!("{:.4}", hz[0])));
}
