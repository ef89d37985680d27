//! Event handling regressions on the paper example.

use meid::integrate::{self, NoOutput};
use meid::model::{Case, Model};

fn example(overrides: &[&str]) -> Model {
    let root =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    let sets: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Model::from_file(&root, &sets).unwrap()
}

/// At t = 0 the dashpot's relative velocity is exactly zero and moves off zero only at second
/// order; its closed-form value near s = 0 is round-off of either sign. Before round-off was
/// taken into account the search "crossed" at s ≈ 3e-17 s again and again (8040 segments for
/// this point of a 30 x 30 map, ws/w_ref = 20.2, wd/w_ref = 300). A collision of this system
/// has four switches: slider-bed, dashpot, bed-damper contact, slider flight.
#[test]
fn dashpot_at_rest_does_not_creep() {
    let model = example(&[
        "contact.slider_bed.stiffness=780388.7882256259",
        "contact.bed_damper.stiffness=501438575.32141745",
    ]);
    let sys = model.impact_system(Case::AsSpecified).unwrap();
    let mut o = model.options();
    o.stop_at_collision_end = true;
    let sol = integrate::solve(&sys, &o, &mut NoOutput).unwrap();
    // The collision lasts 3.9 ms: 18 stretches (Taylor steps of ~0.2 ms, one more at each
    // switch). The creep took 8,040.
    assert!(sol.steps <= 25, "{} stretches: {:?}", sol.steps, sol.events);
    assert_eq!(sol.events.len(), 4, "{:?}", sol.events);
    // The first switch (the dashpot turning off as the damper is pushed away) happens after
    // the bed has moved, not at round-off times.
    assert!(sol.events[0].t > 1e-9, "{:?}", sol.events[0]);
}
