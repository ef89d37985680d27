//! Sweeps, optimisation and Monte Carlo vary what they say (issue 10, part 7).
//!
//! * `simulation.*` fields take effect per point: every point equals, bit for bit, an
//!   independent single run of the model file with the point's value as a `--set` override;
//!   a duration shorter than the collision (the lumped paper example's collision ends at
//!   0.678 ms) leaves the energy ratio undefined.
//! * Whole-number fields (`structure.fem.machine.elements_per_side`) are written as integers;
//!   a non-integral value is an error naming the field.
//! * `md/mb` on FE models: m_b of the parametric machine is its bed plate, ρ L_x L_y t (closed
//!   form from the file's numbers); a given m_b is applied before the quantities are checked.
//! * An error that hits every point is reported as that error, with its kind.

use std::path::{Path, PathBuf};

use meid::analysis::montecarlo::{MonteCarlo, Uncertain};
use meid::analysis::simulate;
use meid::analysis::study::{Objective, OptimizeStudy};
use meid::analysis::sweep::{field_kind, field_literal, FieldKind, Quantity, Sweep, Vary};
use meid::model::{Case, Model};
use meid::Error;

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

fn lumped(overrides: &[&str]) -> Model {
    let ov: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Model::from_file(&example("paper-lumped.toml"), &ov).unwrap()
}

/// The FE soft-base example on a coarse mesh (6 elements per side: cheap).
fn fe(overrides: &[&str]) -> Model {
    let mut ov = vec!["structure.fem.machine.elements_per_side=6".to_string()];
    ov.extend(overrides.iter().map(|s| s.to_string()));
    Model::from_file(&example("paper-soft-base.toml"), &ov).unwrap()
}

/// A single run of `m` with the options a sweep point uses (stop at the collision end unless
/// `full`).
fn single(m: &Model, full: bool) -> meid::analysis::Summary {
    let mut o = m.options();
    o.stop_at_collision_end = !full;
    simulate(&m.impact_system(Case::AsSpecified).unwrap(), &o, false)
        .unwrap()
        .summary
}

fn bits(x: Option<f64>) -> u64 {
    x.unwrap_or(f64::NAN).to_bits()
}

#[test]
fn varied_duration_takes_effect_per_point() {
    let sweep = Sweep::new(
        lumped(&[]),
        vec![Vary::parse("simulation.duration=1e-4,0.5").unwrap()],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 0);
    let (short, long) = (&r.points[0], &r.points[1]);
    // The collision of the file's run ends at 0.678 ms > 1e-4 s: not ended, ratio undefined.
    let whole = single(&lumped(&[]), false);
    let end = whole.collision_end_s.unwrap();
    assert!(end > 1e-4, "collision end {end} s");
    assert!(short.metric("energy_ratio").is_nan());
    assert!(short.metric("collision_end_s").is_nan());
    assert_eq!(short.metric("simulated_time_s"), 1e-4);
    // Each point is the independent run of the file with the point's duration, run to its end.
    for (p, d) in [
        (short, "simulation.duration=1e-4"),
        (long, "simulation.duration=0.5"),
    ] {
        let s = single(&lumped(&[d]), true);
        assert_eq!(p.metric("simulated_time_s"), s.simulated_time_s, "{d}");
        assert_eq!(
            bits(Some(p.metric("energy_ratio"))),
            bits(s.energy_ratio),
            "{d}"
        );
        assert_eq!(
            p.metric("peak_floor_force_n").to_bits(),
            s.peak_floor_force_n.to_bits(),
            "{d}"
        );
        assert_eq!(p.metric("steps"), s.steps as f64, "{d}");
    }
    assert_eq!(long.metric("simulated_time_s"), 0.5);
    let e = long.metric("energy_ratio");
    assert!(
        e.is_finite() && (e - 0.1464).abs() < 1e-3,
        "energy ratio {e}"
    );
}

#[test]
fn varied_rtol_changes_dopri5_steps() {
    let base = lumped(&["simulation.method=\"dopri5\""]);
    let sweep = Sweep::new(
        base,
        vec![Vary::parse("simulation.rtol=1e-4,1e-8").unwrap()],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 0);
    let steps: Vec<f64> = r.points.iter().map(|p| p.metric("steps")).collect();
    assert!(
        steps[1] > steps[0],
        "dopri5 steps at rtol 1e-4, 1e-8: {steps:?}"
    );
    for (p, set) in r
        .points
        .iter()
        .zip(["simulation.rtol=1e-4", "simulation.rtol=1e-8"])
    {
        let s = single(&lumped(&["simulation.method=\"dopri5\"", set]), false);
        assert_eq!(p.metric("steps"), s.steps as f64, "{set}");
        assert_eq!(
            bits(Some(p.metric("energy_ratio"))),
            bits(s.energy_ratio),
            "{set}"
        );
    }
}

#[test]
fn varied_sample_rate_and_atol_take_effect() {
    let sweep = Sweep::new(
        lumped(&[]),
        vec![Vary::parse("simulation.sample_rate=1000,20000").unwrap()],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    for (p, set) in r.points.iter().zip([
        "simulation.sample_rate=1000",
        "simulation.sample_rate=20000",
    ]) {
        let s = single(&lumped(&[set]), false);
        assert_eq!(
            p.metric("peak_bed_acceleration_m_per_s2").to_bits(),
            s.peak_bed_acceleration_m_per_s2.to_bits(),
            "{set}"
        );
    }
    let o = sweep.point_options(0).unwrap();
    assert_eq!(o.sample_rate, Some(1000.0));
    assert!(
        o.stop_at_collision_end,
        "only a varied duration runs past the collision"
    );
    let sweep = Sweep::new(
        lumped(&["simulation.method=\"dopri5\""]),
        vec![Vary::parse("simulation.atol=1e-6,1e-14").unwrap()],
    )
    .unwrap();
    assert_eq!(sweep.point_options(0).unwrap().atol, 1e-6);
    assert_eq!(sweep.point_options(1).unwrap().atol, 1e-14);
    // Out-of-range settings fail as in a model file.
    let bad = Sweep::new(lumped(&[]), vec![Vary::parse("simulation.rtol=2").unwrap()]).unwrap();
    let e = bad.point_model(0).unwrap_err().to_string();
    assert!(e.contains("simulation.rtol must be in (0, 1)"), "{e}");
}

#[test]
fn whole_number_fields_are_varied_as_integers() {
    let base = fe(&[]);
    assert_eq!(
        field_kind(&base, "structure.fem.machine.elements_per_side").unwrap(),
        FieldKind::Whole
    );
    assert_eq!(field_kind(&base, "damper.mass").unwrap(), FieldKind::Real);
    assert_eq!(
        field_kind(&base, "structure.reference_mode").unwrap(),
        FieldKind::Whole
    );
    assert_eq!(
        field_literal("x", 8.0, FieldKind::Whole, "--vary").unwrap(),
        "8"
    );
    assert_eq!(
        field_literal("x", 8.0, FieldKind::Real, "--vary").unwrap(),
        "8e0"
    );
    let e = field_kind(&base, "damper.mas").unwrap_err().to_string();
    assert!(e.contains("did you mean `mass`"), "{e}");
    let e = field_kind(&base, "structure.fem.machine.bed")
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot be set to a number"), "{e}");

    let sweep = Sweep::new(
        base,
        vec![Vary::parse("structure.fem.machine.elements_per_side=4,8").unwrap()],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 0, "{:?}", r.points[0].error);
    let e4 = r.points[0].metric("energy_ratio");
    let e8 = r.points[1].metric("energy_ratio");
    assert_ne!(e4, e8, "4 and 8 elements per side give different meshes");
    for (p, n) in r.points.iter().zip([4, 8]) {
        let m = fe(&[&format!("structure.fem.machine.elements_per_side={n}")]);
        assert_eq!(
            bits(Some(p.metric("energy_ratio"))),
            bits(single(&m, false).energy_ratio),
            "{n} elements per side"
        );
    }
    // A non-integral value is refused when the sweep is built, naming the field.
    let e = Sweep::new(
        fe(&[]),
        vec![Vary::parse("structure.fem.machine.elements_per_side=4.5,8").unwrap()],
    )
    .unwrap_err();
    assert!(matches!(e, Error::Input { .. }), "{e:?}");
    let e = e.to_string();
    assert!(
        e.contains("structure.fem.machine.elements_per_side takes a whole number")
            && e.contains("4.5"),
        "{e}"
    );
    // Optimisation cannot search a whole-number field; Monte Carlo cannot draw one.
    let e = OptimizeStudy::new(
        fe(&[]),
        vec![(
            Quantity::Field("structure.fem.machine.elements_per_side".into()),
            Some((4.0, 8.0)),
        )],
        Objective::Energy,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("whole number"), "{e}");
    let mc = MonteCarlo {
        model: fe(&[]),
        inputs: vec![
            Uncertain::parse("structure.fem.machine.elements_per_side=uniform(4,8)").unwrap(),
        ],
        samples: 2,
        seed: 1,
    };
    let e = mc.run().unwrap_err().to_string();
    assert!(e.contains("elements_per_side takes a whole number"), "{e}");
}

#[test]
fn fe_bed_mass_is_the_bed_plate() {
    // examples/paper-soft-base.toml: bed 0.432 x 0.2693 x 0.01095 m of steel (7850 kg/m³).
    let m_b = 7850.0 * 0.432 * 0.2693 * 0.01095;
    let base = fe(&[]);
    let got = base.bed_mass().unwrap();
    assert!((got / m_b - 1.0).abs() < 1e-14, "{got} vs {m_b}");
    // A mass added on the bed plate is part of the bed; one on the base is not.
    let with = fe(&[
        "structure.fem.machine.added_masses=[{plate=\"bed\",offset=[0.0,0.0],mass=2.0},{plate=\"base\",offset=[0.0,0.0],mass=5.0}]",
    ]);
    let got = with.bed_mass().unwrap();
    assert!((got / (m_b + 2.0) - 1.0).abs() < 1e-14, "{got}");
    // Struck elsewhere than on the bed plate: the model cannot tell.
    assert_eq!(fe(&["points.bed_contact=\"O_f\""]).bed_mass(), None);
    // md/mb on the FE model with the derived m_b: m_d = r m_b, K_d keeps w_d.
    let c = base.spec.contact.bed_damper.as_ref().unwrap().stiffness;
    let m = base.spec.damper.as_ref().unwrap().mass;
    let m_b_model = base.bed_mass().unwrap();
    let sweep = Sweep::new(base, vec![Vary::parse("md/mb=0.35,0.7").unwrap()]).unwrap();
    for (i, r) in [0.35, 0.7].into_iter().enumerate() {
        let pm = sweep.point_model(i).unwrap();
        let d = pm.model.spec.damper.as_ref().unwrap().mass;
        assert_eq!(d, r * m_b_model);
        let k = pm.model.spec.contact.bed_damper.as_ref().unwrap().stiffness;
        assert!(((k / d) / (c / m) - 1.0).abs() < 1e-14);
    }
}

/// A modal model (no masses: m_b unknown) with a damper.
fn modal_with_damper() -> Model {
    let text = r#"
[structure.modal]
frequencies_hz = [6.35, 283.0]
damping_ratios = 0.01
[structure.modal.shapes]
bed = [0.14, 0.30]
base = [0.14, -0.03]
[points]
bed_contact = "bed"
damper_anchor = "base"
measurement = "bed"
[slider]
mass = 1.2
velocity = 1.2
[damper]
mass = 3.5
stiffness = 1.8e3
damping = 7.0e2
[contact.slider_bed]
stiffness = 4.298e7
[contact.bed_damper]
stiffness = 1.2536e8
"#;
    Model::from_text("modal.toml", text.to_string(), &[]).unwrap()
}

#[test]
fn given_bed_mass_is_applied_before_the_check() {
    let m = modal_with_damper();
    assert_eq!(m.bed_mass(), None);
    let e = Sweep::new(m.clone(), vec![Vary::parse("md/mb=0.35,0.7").unwrap()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("--bed-mass"), "{e}");
    let sweep = Sweep::with_bed_mass(
        m.clone(),
        vec![Vary::parse("md/mb=0.35,0.7").unwrap()],
        Some(10.0),
    )
    .unwrap();
    assert_eq!(sweep.point_model(1).unwrap().derived[2], 7.0);
    // The flag overrides a derived m_b, and a bad one is refused.
    let s = Sweep::with_bed_mass(
        lumped(&[]),
        vec![Vary::parse("md/mb=0.5").unwrap()],
        Some(20.0),
    )
    .unwrap();
    assert_eq!(s.point_model(0).unwrap().derived[2], 10.0);
    assert!(Sweep::with_bed_mass(
        lumped(&[]),
        vec![Vary::parse("md/mb=0.5").unwrap()],
        Some(-1.0)
    )
    .is_err());
    // The same for the optimiser.
    let over = vec![(Quantity::MdOverMb, Some((0.2, 0.8)))];
    assert!(OptimizeStudy::new(m.clone(), over.clone(), Objective::Energy).is_err());
    let st = OptimizeStudy::with_bed_mass(m, over, Objective::Energy, Some(10.0)).unwrap();
    let p = st.evaluate(&[0.5]);
    assert_eq!(p.derived[2], 5.0);
    assert!(p.error.is_none(), "{:?}", p.error);
}

#[test]
fn an_error_at_every_point_is_that_error() {
    let sweep = Sweep::new(lumped(&[]), vec![Vary::parse("damper.mass=-1,-2").unwrap()]).unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 2);
    let e = sweep.all_failed_error(&r).unwrap();
    assert!(matches!(e, Error::Input { .. }), "{e:?}");
    let t = e.to_string();
    assert!(
        t.contains("damper.mass") && t.contains("> 0 kg") && t.contains("all 2 points"),
        "{t}"
    );
    // One point succeeds: no error.
    let sweep = Sweep::new(
        lumped(&[]),
        vec![Vary::parse("damper.mass=-1,3.5").unwrap()],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    assert_eq!(r.failures(), 1);
    assert!(sweep.all_failed_error(&r).is_none());
    // Optimisation: bounds outside the field's domain are that error before any point runs
    // (issue 15: they used to run the scan, whose every point failed).
    let e = OptimizeStudy::new(
        lumped(&[]),
        vec![(Quantity::Field("damper.mass".into()), Some((-2.0, -1.0)))],
        Objective::Energy,
    )
    .unwrap_err();
    assert!(matches!(e, Error::Input { .. }), "{e:?}");
    let t = e.to_string();
    assert!(
        t.contains("--bounds damper.mass=-2..-1")
            && t.contains("the lower bound -2 lies outside the valid domain of damper.mass")
            && t.contains("> 0 kg"),
        "{t}"
    );
    // Monte Carlo: every sample failing is that error.
    let mc = MonteCarlo {
        model: lumped(&[]),
        inputs: vec![Uncertain::parse("damper.mass=uniform(-2,-1)").unwrap()],
        samples: 3,
        seed: 1,
    };
    let e = mc.run().unwrap_err();
    assert!(matches!(e, Error::Input { .. }), "{e:?}");
    assert!(e.to_string().contains("all 3 samples failed"), "{e}");
}

#[test]
fn montecarlo_draws_simulation_fields_per_sample() {
    let run = |dist: &str| {
        MonteCarlo {
            model: lumped(&[]),
            inputs: vec![Uncertain::parse(&format!("simulation.duration={dist}")).unwrap()],
            samples: 2,
            seed: 1,
        }
        .run()
        .unwrap()
    };
    let short = run("uniform(1e-4,1e-4)");
    let long = run("uniform(0.5,0.5)");
    for s in &short.samples {
        assert!(
            s.metrics.unwrap()[0].is_nan(),
            "collision not ended in 1e-4 s"
        );
    }
    let whole = single(&lumped(&[]), true).energy_ratio.unwrap();
    for s in &long.samples {
        assert_eq!(s.metrics.unwrap()[0].to_bits(), whole.to_bits());
    }
}

#[test]
fn derived_bed_mass_follows_the_point() {
    // m_b = the point's bed mass: varying the lumped bed mass carries m_d = r m_b with it.
    let vary = || {
        vec![
            Vary::parse("structure.lumped.masses[0].mass=10,20").unwrap(),
            Vary::parse("md/mb=0.5").unwrap(),
        ]
    };
    let sweep = Sweep::new(lumped(&[]), vary()).unwrap();
    assert_eq!(sweep.point_model(0).unwrap().derived[2], 5.0);
    assert_eq!(sweep.point_model(1).unwrap().derived[2], 10.0);
    // A given m_b is fixed.
    let sweep = Sweep::with_bed_mass(lumped(&[]), vary(), Some(10.0)).unwrap();
    assert_eq!(sweep.point_model(1).unwrap().derived[2], 5.0);
    // The same on the FE machine: a thicker bed plate is a heavier bed.
    let sweep = Sweep::new(
        fe(&[]),
        vec![
            Vary::parse("structure.fem.machine.bed.thickness=0.01095,0.0219").unwrap(),
            Vary::parse("md/mb=0.35").unwrap(),
        ],
    )
    .unwrap();
    let m_b = 7850.0 * 0.432 * 0.2693 * 0.01095;
    for (i, t) in [1.0, 2.0].into_iter().enumerate() {
        let d = sweep.point_model(i).unwrap().derived[2];
        assert!((d / (0.35 * t * m_b) - 1.0).abs() < 1e-14, "{d}");
    }
}

/// Monte Carlo inputs outside `structure.` are set on the parsed model (its modes reused, no
/// rebuild of the FE model per sample): every sample equals, bit for bit, the model file read
/// again with the drawn values as `--set` overrides and simulated, on the FE machine (whose
/// rebuild is what the reuse saves) with two inputs.
#[test]
fn montecarlo_fast_path_equals_the_file_read_with_overrides() {
    let mc = MonteCarlo {
        model: fe(&[]),
        inputs: vec![
            Uncertain::parse("contact.slider_bed.stiffness=lognormal(4.3e7,0.3)").unwrap(),
            Uncertain::parse("damper.mass=uniform(2.0,5.0)").unwrap(),
        ],
        samples: 4,
        seed: 3,
    };
    let r = mc.run().unwrap();
    assert_eq!(r.failed, 0);
    for s in &r.samples {
        let drawn = mc.draw(s.index);
        assert_eq!(drawn, s.inputs);
        let ks = format!("contact.slider_bed.stiffness={:e}", drawn[0]);
        let md = format!("damper.mass={:e}", drawn[1]);
        let reread = fe(&[&ks, &md]);
        let want = single(&reread, true);
        let got = s.metrics.unwrap();
        assert_eq!(
            got[0].to_bits(),
            bits(want.energy_ratio),
            "sample {}",
            s.index
        );
        assert_eq!(
            got[1].to_bits(),
            want.peak_bed_acceleration_m_per_s2.to_bits()
        );
        assert_eq!(got[2].to_bits(), want.peak_floor_force_n.to_bits());
        assert_eq!(
            got[3].to_bits(),
            want.peak_contact_force_slider_bed_n.to_bits()
        );
        assert_eq!(
            got[4].to_bits(),
            want.peak_contact_force_bed_damper_n.to_bits()
        );
    }
}
