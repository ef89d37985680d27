//! `Sweep::with_cases` (`meid sweep --cases none,damper,added-mass`, paper Fig. 9): one run
//! compares the bare machine, the impact damper and the added mass at every point.
//!
//! References (independent of the sweep's own code path):
//! * the added-mass case at m_d/m_b = r equals a model whose bed mass was raised by hand to
//!   m_b + r m_b and run without absorber. With no structural damping the Rayleigh-Ritz added
//!   mass on a lumped model (every mode retained) is exact, so the two agree to round-off
//!   (tolerance 1e-9 relative; the modal bases differ, so not bit for bit);
//! * the "none" column does not depend on the damper's mass: bit-identical at every m_d/m_b;
//! * the "damper" column is bit for bit the plain sweep of the model as specified;
//! * a resumed sweep with cases reproduces the uninterrupted CSV byte for byte.

use std::path::{Path, PathBuf};

use meid::analysis::simulate;
use meid::analysis::sweep::{Sweep, Vary, METRICS};
use meid::model::{Case, Model};

fn example() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml")
}

fn model(overrides: &[String]) -> Model {
    Model::from_file(&example(), overrides).unwrap()
}

const UNDAMPED: &str = "structure.lumped.damping_ratios=0.0";

fn cases() -> Vec<Case> {
    vec![Case::NoDamper, Case::Damper, Case::AddedMass]
}

#[test]
fn added_mass_case_equals_the_mass_added_by_hand() {
    let ratios = [0.1, 0.35, 0.7, 1.0];
    let sweep = Sweep::new(
        model(&[UNDAMPED.into()]),
        vec![Vary::parse("md/mb=0.1,0.35,0.7,1.0").unwrap()],
    )
    .unwrap()
    .with_cases(cases())
    .unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 0);
    assert_eq!(
        sweep.columns().len(),
        1 + 1 + 4 + 3 * METRICS.len() + 1,
        "index, md/mb, 4 derived, 3 × metrics, error"
    );
    assert!(sweep
        .columns()
        .contains(&"energy_ratio:added-mass".to_string()));
    let m_b = 10.0;
    let mut checked = 0;
    for (i, &ratio) in ratios.iter().enumerate() {
        // By hand: the bed's lumped mass raised by m_d, no absorber.
        let hand = model(&[
            UNDAMPED.into(),
            format!("structure.lumped.masses[0].mass={:e}", m_b + ratio * m_b),
        ]);
        let sys = hand.impact_system(Case::NoDamper).unwrap();
        let run = simulate(&sys, &sweep.options, false).unwrap();
        let s = &run.summary;
        for (name, expected) in [
            ("energy_ratio", s.energy_ratio.unwrap()),
            ("peak_floor_force_n", s.peak_floor_force_n),
            (
                "peak_bed_acceleration_m_per_s2",
                s.peak_bed_acceleration_m_per_s2,
            ),
            ("slider_energy_after_j", s.slider_energy_after_j.unwrap()),
            (
                "contact_time_slider_bed_s",
                s.contact_time_slider_bed_s.unwrap(),
            ),
        ] {
            let got = r.value(i, &format!("{name}:added-mass"));
            assert!(
                ((got - expected) / expected).abs() < 1e-9,
                "m_d/m_b = {ratio}: {name} added-mass case {got} vs by hand {expected}"
            );
            checked += 1;
        }
        // The damper takes energy out: E_p+ with the damper is below the bare machine's.
        assert!(r.value(i, "energy_ratio:damper") < r.value(i, "energy_ratio:none"));
    }
    assert_eq!(checked, 20);
    // "none" is the same run at every mass ratio: bit for bit.
    for m in METRICS {
        let col = format!("{m}:none");
        let first = r.value(0, &col);
        for i in 1..ratios.len() {
            let v = r.value(i, &col);
            assert!(
                v.to_bits() == first.to_bits() || (v.is_nan() && first.is_nan()),
                "{col} changes with m_d/m_b: {first} vs {v}"
            );
        }
    }
}

#[test]
fn damper_column_is_the_plain_sweep_and_resume_is_exact() {
    let vary = || {
        vec![
            Vary::parse("ws/w_ref=20..200:5:log").unwrap(),
            Vary::parse("md/mb=0.35,0.7").unwrap(),
        ]
    };
    let plain = Sweep::new(model(&[]), vary()).unwrap().run(&|_, _| {});
    let with = Sweep::new(model(&[]), vary())
        .unwrap()
        .with_cases(cases())
        .unwrap();
    let r = with.run(&|_, _| {});
    for i in 0..plain.points.len() {
        for m in METRICS {
            let a = plain.value(i, m);
            let b = r.value(i, &format!("{m}:damper"));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "point {i} {m}: plain {a} vs damper case {b}"
            );
        }
    }
    // Journal and resume with cases: cut the journal after 4 points, resume, same CSV.
    let dir = std::env::temp_dir().join(format!("meid-sweep-cases-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let journal = dir.join("sweep.partial.csv");
    let full = with.run_resumable(&journal, false, &|_, _| {}).unwrap();
    assert_eq!(full.csv(), r.csv());
    let text = std::fs::read_to_string(&journal).unwrap();
    let keep: String = text.split_inclusive('\n').take(2 + 4).collect();
    std::fs::write(&journal, keep).unwrap();
    let resumed = with.run_resumable(&journal, true, &|_, _| {}).unwrap();
    assert_eq!(resumed.csv(), r.csv());
    // A case the model cannot build is refused by name.
    let bare = model(&["added_mass.mass=1.0".into()]);
    let mut spec_no_damper = bare.clone();
    spec_no_damper.spec.damper = None;
    spec_no_damper.spec.contact.bed_damper = None;
    let e = Sweep::new(
        spec_no_damper,
        vec![Vary::parse("ws/w_ref=50,100").unwrap()],
    )
    .unwrap()
    .with_cases(vec![Case::Damper])
    .unwrap_err()
    .to_string();
    assert!(e.contains("`damper`"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
