//! `analysis::study` (meid optimize) on the lumped paper example.
//!
//! Reference: the best point of a fine 1-D sweep of `wd/ws` (201 log-spaced points over
//! 0.3..3, spacing 1.2 %); the optimiser must land within 5 % of it (issue 4). The paper's
//! rule w_d = w_s must not beat the optimum (it is one point of the search space).

use std::path::{Path, PathBuf};

use meid::analysis::study::{Objective, OptimizeStudy};
use meid::analysis::sweep::{Quantity, Sweep, Vary};
use meid::model::Model;

fn model() -> Model {
    let p: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-lumped.toml");
    Model::from_file(&p, &[]).unwrap()
}

#[test]
fn brent_over_wd_ws_matches_fine_sweep() {
    let sweep = Sweep::new(model(), vec![Vary::parse("wd/ws=0.3..3:201:log").unwrap()]).unwrap();
    let r = sweep.run(&|_, _| {});
    let best = r.argmin("energy_ratio").unwrap();
    let x_sweep = r.points[best].values[0];
    let f_sweep = r.points[best].metric("energy_ratio");

    let study = OptimizeStudy::new(
        model(),
        vec![(Quantity::WdOverWs, Some((0.3, 3.0)))],
        Objective::Energy,
    )
    .unwrap();
    let rep = study.run().unwrap();
    let x = rep.optimum[0];
    assert!(
        (x / x_sweep - 1.0).abs() < 0.05,
        "optimum wd/ws = {x}, fine sweep best = {x_sweep}"
    );
    assert!(rep.objective_value <= f_sweep * (1.0 + 1e-9));
    assert!(rep.objective_at_wd_equal_ws >= rep.objective_value);
    assert!((rep.wd_over_ws_at_optimum / x - 1.0).abs() < 1e-12);
    assert!(rep.simulations < 100, "{} simulations", rep.simulations);
}

#[test]
fn nelder_mead_over_two_variables_does_not_lose_to_the_grid() {
    // Reference: the best point of a 15 x 15 grid over the same box; the optimiser (which
    // also evaluates the box it searches) must find a value no worse than 1 % above it.
    let sweep = Sweep::new(
        model(),
        vec![
            Vary::parse("wd/ws=0.5..2:15:log").unwrap(),
            Vary::parse("md/mb=0.1..1:15:log").unwrap(),
        ],
    )
    .unwrap();
    let r = sweep.run(&|_, _| {});
    let f_grid = r.points[r.argmin("energy_ratio").unwrap()].metric("energy_ratio");
    let study = OptimizeStudy::new(
        model(),
        vec![
            (Quantity::WdOverWs, Some((0.5, 2.0))),
            (Quantity::MdOverMb, Some((0.1, 1.0))),
        ],
        Objective::Energy,
    )
    .unwrap();
    let rep = study.run().unwrap();
    assert!(
        rep.objective_value <= f_grid * 1.01,
        "optimum {} vs grid {}",
        rep.objective_value,
        f_grid
    );
}

#[test]
fn bad_inputs_are_refused() {
    assert!(Objective::parse("speed").is_err());
    let e = OptimizeStudy::new(
        model(),
        vec![(Quantity::WdOverWs, Some((2.0, 1.0)))],
        Objective::Energy,
    )
    .unwrap_err();
    assert!(e.to_string().contains("LO < HI"), "{e}");
}
