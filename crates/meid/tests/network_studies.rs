//! Studies over a general machine (issue 29 item 7): sweeps over named fields
//! (`meid::analysis::network_study`), and where its dampers go (`meid::analysis::placement`).

use meid::analysis::network::summary;
use meid::analysis::network_study::{metrics, NetSweep, NetVary};
use meid::analysis::placement::{MassRule, NetObjective, PlacementStudy, Search};
use meid::model::network::NetworkModel;

/// network_model.rs's two-mass lumped machine struck at "left", its damper's contact given
/// by its damping (so that scaling it is exact) instead of a restitution.
fn lumped() -> String {
    crate::network_model::BASE.replacen("restitution = 0.8", "damping = 40.0", 1)
}

fn load(text: &str, set: &[&str]) -> NetworkModel {
    let set: Vec<String> = set.iter().map(|s| s.to_string()).collect();
    NetworkModel::from_text("m.toml", text.to_string(), &set).unwrap()
}

fn energy(m: &NetworkModel) -> f64 {
    let sol = m.solve(&m.options().unwrap()).unwrap();
    sol.energy_ratio.unwrap()
}

/// `damper.NAME.FIELD` sets the entry so named, as its index form does; a damper moved by
/// `damper.NAME.point` takes its contact along; unknown names and fields are refused with a
/// did-you-mean.
#[test]
fn named_paths_set_the_entry_so_named() {
    let by_name = load(
        &lumped(),
        &["damper.d_left.mass=2.5", "contact.die_left.gap=1e-4"],
    );
    let by_index = load(&lumped(), &["damper[0].mass=2.5", "contact[0].gap=1e-4"]);
    assert_eq!(by_name.spec, by_index.spec);
    assert_eq!(by_name.spec.damper[0].mass, 2.5);
    let moved = load(&lumped(), &["damper.d_left.point=\"right\""]);
    assert_eq!(moved.spec.damper[0].point, "right");
    assert_eq!(moved.spec.contact[1].between, ["right", "d_left"]);
    for (set, want) in [
        ("damper.d_lfet.mass=2", "did you mean 'd_left'"),
        ("damper.d_left.mas=2", "did you mean 'mass'"),
        ("contact.die_lfet.gap=0", "did you mean 'die_left'"),
    ] {
        let e = NetworkModel::from_text("m.toml", lumped(), &[set.to_string()])
            .unwrap_err()
            .to_string();
        assert!(e.contains(want) && e.contains(set), "{set}: {e}");
    }
}

/// Every point of a sweep is the model the file gives with the point's `--set`s, run for run
/// the same numbers (bit for bit); fields outside the structure's key reuse the file's
/// structure (no build), a field inside it builds one per value.
#[test]
fn a_sweep_point_is_the_file_with_its_fields_set_and_reuses_the_structure() {
    let base = load(&lumped(), &[]);
    let vary = vec![NetVary::parse("contact.die_left.gap=0..2e-4:3").unwrap()];
    let sweep = NetSweep::new(base.clone(), vary).unwrap();
    let r = sweep.run(&|_| {});
    assert_eq!(r.structures_built, 0, "a gap does not change the structure");
    for (i, gap) in [0.0, 1e-4, 2e-4].iter().enumerate() {
        let m = load(&lumped(), &[&format!("contact.die_left.gap={gap:e}")]);
        let s = summary(&m, &m.solve(&m.options().unwrap()).unwrap());
        let want: Vec<Option<f64>> = metrics(&s).into_iter().map(|(_, v)| v).collect();
        assert_eq!(r.points[i].metrics, want, "point {i}");
    }
    // The springs of a lumped structure are its structure: one build per value.
    let vary = vec![NetVary::parse("structure.lumped.springs[1].stiffness=1e5,2e5").unwrap()];
    let r = NetSweep::new(base, vary).unwrap().run(&|_| {});
    assert_eq!(r.structures_built, 1, "1e5 is the file's own value");
    assert!(r.points.iter().all(|p| p.error.is_none()));
}

/// A sweep over a damper's place: `[right, left]` moves the damper and its contact; the
/// place the blow strikes takes more energy out than the other end of the structure.
#[test]
fn a_sweep_over_a_damper_point_moves_it() {
    let base = load(&lumped(), &[]);
    let vary = vec![NetVary::parse("damper.d_left.point=[right,left]").unwrap()];
    let r = NetSweep::new(base.clone(), vary).unwrap().run(&|_| {});
    let e = |i: usize| r.points[i].metrics[0].unwrap();
    assert_eq!(e(1), energy(&base));
    assert_eq!(
        e(0),
        energy(&load(&lumped(), &["damper.d_left.point=\"right\""]))
    );
    let bad = NetSweep::new(
        base,
        vec![NetVary::parse("damper.d_left.point=[rigth]").unwrap()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        bad.contains("--vary") && bad.contains("did you mean 'right'"),
        "{bad}"
    );
}

fn place(model: NetworkModel, candidates: &[&str], counts: (usize, usize)) -> PlacementStudy {
    PlacementStudy {
        template: model.spec.damper[0].name.clone(),
        candidates: candidates.iter().map(|s| s.to_string()).collect(),
        counts,
        repeat: false,
        masses: MassRule::Total(1.75),
        objective: NetObjective::Energy,
        search: Search::Auto,
        max_combinations: 256,
        mass_evaluations: 20,
        rate_bpm: None,
        model,
    }
}

/// Issue 29's check as a study: n identical dampers at one point, each with 1/n of the mass,
/// spring, dashpot and contact of one damper of the total mass, move as that damper: the same
/// energy ratio for n = 1..4 (1e-12), and the one-damper placement equals the file's damper.
#[test]
fn n_dampers_at_one_point_with_the_total_mass_equal_one() {
    let base = load(&lumped(), &[]);
    let mut s = place(base.clone(), &["left"], (1, 4));
    s.repeat = true;
    let r = s.run().unwrap();
    assert_eq!(r.placements.len(), 4);
    let one = r.placements.iter().find(|p| p.dampers == 1).unwrap();
    assert_eq!(one.objective.unwrap(), energy(&base));
    for p in &r.placements {
        let (a, b) = (p.objective.unwrap(), one.objective.unwrap());
        assert!(
            (a - b).abs() <= 1e-12 * b,
            "{} dampers: {a} vs {b}",
            p.dampers
        );
        assert_eq!(p.masses_kg, vec![1.75 / p.dampers as f64; p.dampers]);
    }
}

/// Two modes: the blow at "left" excites mode 1 only; "far" moves in mode 2 only, "mid" in
/// both (the lumped machine's bodies and contacts on a modal structure). A damper at "far"
/// never meets a moving structure: its placement keeps the energy of the machine without
/// damper (to round-off). The one damper goes to "left" (where the structure moves most); the
/// exhaustive and the heuristic search agree on one and two dampers.
fn modal() -> String {
    let text = lumped();
    let machine = &text[text.find("[[impactor]]").unwrap()..];
    format!(
        "name = \"two modes\"\n[structure.modal]\nfrequencies_hz = [120.0, 300.0]\ndamping_ratios = [0.01, 0.01]\nshapes = {{ left = [0.3, 0.0], mid = [0.15, 0.2], far = [0.0, 0.3] }}\n\n{machine}"
    )
}

#[test]
fn the_optimiser_places_the_damper_where_the_structure_moves() {
    let base = load(&modal(), &[]);
    let r = place(base.clone(), &["far", "mid", "left"], (1, 1))
        .run()
        .unwrap();
    assert_eq!(r.search, "exhaustive");
    assert_eq!(r.best.points, ["left"]);
    assert_eq!(r.evaluations.len(), 3);
    let mut spec = base.spec.clone();
    spec.damper.clear();
    spec.contact.retain(|c| c.name != "left_damper");
    let bare = base.with_spec(spec, base.source.clone(), None).unwrap();
    let far = r.placements.iter().find(|p| p.points == ["far"]).unwrap();
    // The same numbers up to the round-off of a larger state (the idle damper's two rows).
    let (f, b) = (far.objective.unwrap(), energy(&bare));
    assert!((f - b).abs() <= 1e-12 * b, "{f} vs {b}");
    assert!(r.best.objective.unwrap() < far.objective.unwrap());
    let mut ex = place(base.clone(), &["far", "mid", "left"], (1, 2));
    ex.search = Search::Exhaustive;
    let mut he = place(base, &["far", "mid", "left"], (1, 2));
    he.search = Search::Heuristic;
    let (ex, he) = (ex.run().unwrap(), he.run().unwrap());
    assert_eq!(he.search, "heuristic (greedy + swap)");
    assert_eq!(ex.best.points, he.best.points);
    assert_eq!(ex.best.objective, he.best.objective);
    for (a, b) in ex.best_per_count.iter().zip(&he.best_per_count) {
        assert_eq!((&a.points, a.objective), (&b.points, b.objective));
    }
}

/// Bad input: each error names its option.
#[test]
fn bad_placement_input_names_the_option() {
    let base = load(&modal(), &[]);
    type Change = Box<dyn Fn(&mut PlacementStudy)>;
    let cases: Vec<(Change, &str, &str)> = vec![
        (
            Box::new(|s| s.candidates = vec!["lfet".into()]),
            "--place",
            "did you mean 'left'",
        ),
        (Box::new(|s| s.counts = (1, 4)), "--dampers", "3 candidate"),
        (
            Box::new(|s| s.masses = MassRule::Total(0.0)),
            "--total-mass",
            "> 0",
        ),
        (
            Box::new(|s| s.masses = MassRule::Total(-1.0)),
            "--total-mass",
            "> 0",
        ),
        (
            Box::new(|s| s.template = "d_lef".into()),
            "--template",
            "did you mean 'd_left'",
        ),
        (
            Box::new(|s| {
                s.search = Search::Exhaustive;
                s.max_combinations = 2;
            }),
            "--max-combinations",
            "3 placements",
        ),
        (
            Box::new(|s| s.objective = NetObjective::Accel("fra".into())),
            "--objective",
            "did you mean 'far'",
        ),
        (
            Box::new(|s| s.objective = NetObjective::ContactForce("left_damper".into())),
            "--objective",
            "die_left",
        ),
    ];
    for (change, option, what) in cases {
        let mut s = place(base.clone(), &["far", "mid", "left"], (1, 1));
        change(&mut s);
        let e = s.check().unwrap_err().to_string();
        assert!(e.contains(option) && e.contains(what), "{option}: {e}");
    }
}

/// examples/press-off-centre-4-dampers.toml made mirror-symmetric (the slider on O_b, no S)
/// on a coarse mesh: one damper at D1, D2, D3 or D4 (mirror images about the bed's axes) keeps
/// the same energy. The modes are mirror images to the eigen-solver's accuracy; 1e-9 of the
/// ratio leaves room for that, far below what moving a damper does (≈1e-2).
#[test]
fn mirror_image_placements_keep_the_same_energy() {
    let text = crate::network_model::symmetric_press()
        .replacen("elements_per_side = 20", "elements_per_side = 8", 1)
        .replacen("duration = 0.5", "duration = 0.004", 1);
    let m = NetworkModel::from_text("sym.toml", text, &[]).unwrap();
    let r = place(m, &["D1", "D2", "D3", "D4", "O_b"], (1, 1))
        .run()
        .unwrap();
    let e = |p: &str| {
        r.placements
            .iter()
            .find(|x| x.points == [p])
            .unwrap()
            .objective
            .unwrap()
    };
    for p in ["D2", "D3", "D4"] {
        assert!(
            (e(p) - e("D1")).abs() <= 1e-9 * e("D1"),
            "{p}: {} vs {}",
            e(p),
            e("D1")
        );
    }
    assert!(
        (e("O_b") - e("D1")).abs() > 1e-4 * e("D1"),
        "the centre differs"
    );
}
