//! Typed field updates (issue 33, item 1): a study's varied fields written through setters
//! compiled once on the typed model ([`meid::model::setter`]) give, value for value, the
//! model the TOML route gives (`--set PATH=LITERAL` read back strictly), and the results of
//! simulating it bit for bit.
//!
//! * Every field kind: real (`slider.velocity`, an optional contact damping, a foundation
//!   length), whole number (`simulation.max_events`, `structure.fem.machine.elements_per_side`),
//!   enumerated text (`damper.dashpot`, `simulation.method`, `contact.slider_bed.law`) and a
//!   point name (`points.measurement`); structural fields (a lumped mass and spring, the FE bed
//!   plate's thickness and mesh, the soil under a foundation) get the structure a fresh read of
//!   the file with the override builds.
//! * Each is compared with the TOML route ([`Model::with_fields`]) and with a fresh read
//!   ([`Model::from_file`] with the override): spec, structure, overrides, files, and the
//!   JSON of the simulated summary, byte for byte.
//! * Bad values (out of magnitude range, negative mass, zero event budget, unknown point,
//!   unknown dashpot, negative count) are refused by the typed route, and the error is the
//!   TOML route's, word for word.
//! * A sweep over `slider.velocity` and over an FE plate thickness, and a Monte Carlo over
//!   `slider.velocity`, give at every point the bits of an independent run of the file with
//!   the point's value as a `--set` override.
//! * The structure's key carries `[foundation]`: a soil's shear modulus changes the structure.

use std::path::{Path, PathBuf};

use meid::analysis::montecarlo::{MonteCarlo, Uncertain};
use meid::analysis::simulate;
use meid::analysis::sweep::{Sweep, Vary};
use meid::model::{Case, FieldValue, Model, StructureCache};

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

fn read(name: &str, overrides: &[String]) -> Model {
    Model::from_file(&example(name), overrides).unwrap()
}

const COARSE: &str = "structure.fem.machine.elements_per_side=4";

/// The JSON of the summary of one run of `m` as specified.
fn run_json(m: &Model) -> String {
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let run = simulate(&sys, &m.options(), false).unwrap();
    serde_json::to_string(&run.summary).unwrap()
}

/// `path = value` on `file` (with `base_ov`) by the typed route equals the TOML route and a
/// fresh read, and simulates to the same bytes.
fn check_typed(file: &str, base_ov: &[String], path: &str, value: FieldValue) {
    let base = read(file, base_ov);
    let fields = base.compile_fields(&[path]);
    assert!(fields.all_typed(), "{path}: no typed setter");
    let typed = base
        .with_values_typed(
            &fields,
            std::slice::from_ref(&value),
            Some(&StructureCache::new()),
        )
        .unwrap_or_else(|| panic!("{path}={}: the typed route refused it", value.literal()));
    let text = format!("{path}={}", value.literal());
    let toml = base
        .with_fields(std::slice::from_ref(&text), Some(&StructureCache::new()))
        .unwrap();
    let mut ov = base_ov.to_vec();
    ov.push(text.clone());
    let fresh = read(file, &ov);
    for other in [&toml, &fresh] {
        assert_eq!(typed.spec, other.spec, "{text}");
        assert_eq!(typed.structure, other.structure, "{text}");
        assert_eq!(typed.source.overrides, other.source.overrides, "{text}");
        assert_eq!(typed.files, other.files, "{text}");
        assert_eq!(typed.structure_key(), other.structure_key(), "{text}");
    }
    assert_ne!(typed.spec, base.spec, "{text} changed nothing");
    assert_eq!(run_json(&typed), run_json(&fresh), "{text}");
}

#[test]
fn every_field_kind_matches_the_toml_route() {
    let lumped = "paper-lumped.toml";
    let r = |v: f64| FieldValue::Real(v);
    let t = |s: &str| FieldValue::Text(s.to_string());
    for (path, value) in [
        ("slider.velocity", r(0.8)),
        ("slider.mass", r(1.7)),
        ("contact.slider_bed.stiffness", r(2.5e7)),
        ("contact.bed_damper.damping", r(35.0)),
        ("damper.damping", r(350.0)),
        ("simulation.duration", r(0.05)),
        ("simulation.max_events", FieldValue::Integer(5000)),
        ("damper.dashpot", t("two-way")),
        ("simulation.method", t("dopri5")),
        ("points.measurement", t("base")),
        // Structural: the lumped structure's own numbers.
        ("structure.lumped.masses[1].mass", r(45.0)),
        ("structure.lumped.springs[0].stiffness", r(3.0e7)),
    ] {
        check_typed(lumped, &[], path, value);
    }
    // A contact law (stiffness then in N/m^1.5; dopri5 integrates it) and a restitution-set
    // damping.
    check_typed(
        lumped,
        &[
            "contact.slider_bed.stiffness=4.0e10".to_string(),
            "simulation.method=dopri5".to_string(),
        ],
        "contact.slider_bed.law",
        t("hertz"),
    );
    // Under a Hertz contact the contact frequency, and so the lumped structure's key, follows
    // the approach velocity.
    check_typed(
        lumped,
        &[
            "contact.slider_bed.stiffness=4.0e10".to_string(),
            "contact.slider_bed.law=hertz".to_string(),
            "simulation.method=dopri5".to_string(),
        ],
        "slider.velocity",
        FieldValue::Real(0.8),
    );
    check_typed(
        "hammer-on-soil.toml",
        &[],
        "contact.slider_bed.restitution",
        FieldValue::Real(0.7),
    );
}

#[test]
fn structural_fields_match_a_fresh_read() {
    let coarse = vec![COARSE.to_string()];
    check_typed(
        "paper-soft-base.toml",
        &coarse,
        "structure.fem.machine.bed.thickness",
        FieldValue::Real(0.012),
    );
    check_typed(
        "paper-soft-base.toml",
        &coarse,
        "structure.fem.machine.elements_per_side",
        FieldValue::Integer(6),
    );
    // The soil under the block is part of the structure (its spring and dashpot).
    check_typed(
        "hammer-on-soil.toml",
        &[],
        "foundation.soil.shear_modulus",
        FieldValue::Real(1.5e8),
    );
    check_typed(
        "hammer-on-soil.toml",
        &[],
        "foundation.length",
        FieldValue::Real(8.0),
    );
}

#[test]
fn a_foundation_change_is_a_new_structure() {
    let base = read("hammer-on-soil.toml", &[]);
    let f = ["foundation.soil.shear_modulus=1.5e8".to_string()];
    let cache = StructureCache::new();
    let derived = base.with_fields(&f, Some(&cache)).unwrap();
    assert_ne!(derived.structure_key(), base.structure_key());
    assert_eq!(cache.builds(), 1);
    // The soil spring k_z ∝ G (Lysmer): the block's mode is lower on the softer soil.
    assert!(derived.structure.omega_rad_per_s[0] < base.structure.omega_rad_per_s[0]);
    assert_eq!(derived.structure, read("hammer-on-soil.toml", &f).structure);
}

#[test]
fn bad_values_give_the_toml_routes_error() {
    let base = read("paper-lumped.toml", &[]);
    for (path, value) in [
        ("slider.velocity", FieldValue::Real(1e200)),
        ("damper.mass", FieldValue::Real(-1.0)),
        ("simulation.rtol", FieldValue::Real(2.0)),
        ("simulation.max_events", FieldValue::Integer(0)),
        ("simulation.max_events", FieldValue::Integer(-3)),
        ("simulation.max_events", FieldValue::Real(5.5)),
        ("points.measurement", FieldValue::Text("nowhere".into())),
        ("damper.dashpot", FieldValue::Text("three-way".into())),
        ("slider.velocity", FieldValue::Text("fast".into())),
        ("structure.lumped.masses[0].mass", FieldValue::Real(0.0)),
    ] {
        let fields = base.compile_fields(&[path]);
        let values = std::slice::from_ref(&value);
        assert!(
            base.with_values_typed(&fields, values, None).is_none(),
            "{path}={}",
            value.literal()
        );
        let typed = base.with_values(&fields, values, None).unwrap_err();
        let text = format!("{path}={}", value.literal());
        let toml = base
            .with_fields(std::slice::from_ref(&text), None)
            .unwrap_err();
        assert_eq!(typed.to_string(), toml.to_string(), "{text}");
    }
}

#[test]
fn paths_without_typed_setters_take_the_toml_route() {
    let base = read("paper-lumped.toml", &[]);
    // An untyped path (the damping ratios' list), and a path through an absent table.
    for path in ["structure.lumped.damping_ratios", "production.rate_bpm"] {
        let fields = base.compile_fields(&[path]);
        assert!(!fields.all_typed(), "{path}");
        let v = [FieldValue::Real(0.02)];
        assert!(base.with_values_typed(&fields, &v, None).is_none());
        let text = format!("{path}={}", v[0].literal());
        let a = base.with_values(&fields, &v, None).map(|m| m.spec);
        let b = base.with_fields(&[text], None).map(|m| m.spec);
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{path}");
    }
}

/// The bits of the energy ratio and the peaks of `m`'s run with `options`.
fn bits_of(m: &Model, options: &meid::integrate::Options) -> Vec<u64> {
    let sys = m.impact_system(Case::AsSpecified).unwrap();
    let run = simulate(&sys, options, false).unwrap();
    let s = &run.summary;
    [
        s.energy_ratio.unwrap_or(f64::NAN),
        s.peak_bed_acceleration_m_per_s2,
        s.peak_floor_force_n,
        s.peak_contact_force_slider_bed_n,
        s.peak_contact_force_bed_damper_n,
    ]
    .iter()
    .map(|v| v.to_bits())
    .collect()
}

#[test]
fn sweeps_and_monte_carlo_give_the_bits_of_single_runs() {
    for (file, base_ov, spec) in [
        ("paper-lumped.toml", vec![], "slider.velocity=0.6,1.2,2.5"),
        (
            "paper-soft-base.toml",
            vec![COARSE.to_string()],
            "structure.fem.machine.bed.thickness=0.01,0.02",
        ),
    ] {
        let base = read(file, &base_ov);
        let vary = Vary::parse(spec).unwrap();
        let path = vary.quantity.name();
        let sweep = Sweep::new(base, vec![vary.clone()]).unwrap();
        let result = sweep.run(&|_, _| {});
        for (p, v) in result.points.iter().zip(&vary.values) {
            assert!(p.error.is_none(), "{spec}: {:?}", p.error);
            let mut ov = base_ov.clone();
            ov.push(format!("{path}={v:e}"));
            let fresh = read(file, &ov);
            let want = bits_of(&fresh, &sweep.options);
            let got: Vec<u64> = [
                "energy_ratio",
                "peak_bed_acceleration_m_per_s2",
                "peak_floor_force_n",
                "peak_contact_force_slider_bed_n",
                "peak_contact_force_bed_damper_n",
            ]
            .iter()
            .map(|m| p.metric(m).to_bits())
            .collect();
            assert_eq!(got, want, "{path}={v:e}");
        }
    }
    let mc = MonteCarlo {
        model: read("paper-lumped.toml", &[]),
        inputs: vec![Uncertain::parse("slider.velocity=uniform(0.5,2.0)").unwrap()],
        samples: 4,
        seed: 7,
    };
    let result = mc.run().unwrap();
    for s in &result.samples {
        let fresh = read(
            "paper-lumped.toml",
            &[format!("slider.velocity={:e}", s.inputs[0])],
        );
        let m = s.metrics.unwrap();
        let sys = fresh.impact_system(Case::AsSpecified).unwrap();
        let run = simulate(&sys, &fresh.options(), false).unwrap();
        assert_eq!(
            m[0].to_bits(),
            run.summary.energy_ratio.unwrap_or(f64::NAN).to_bits()
        );
    }
}

#[test]
fn a_bad_sweep_point_fails_with_the_toml_routes_error() {
    let base = read("paper-lumped.toml", &[]);
    let sweep = Sweep::new(
        base.clone(),
        vec![Vary::parse("damper.mass=3.5,-1").unwrap()],
    )
    .unwrap();
    let result = sweep.run(&|_, _| {});
    assert!(result.points[0].error.is_none());
    let want = base
        .with_fields(&["damper.mass=-1e0".to_string()], None)
        .unwrap_err()
        .to_string();
    assert_eq!(result.points[1].error.as_deref(), Some(want.as_str()));
}
