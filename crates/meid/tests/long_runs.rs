//! Long runs complete: the damper settling against the vibrating bed does not stall the exact
//! engine (it stopped at t = 23.77 s with "switches chatter" on the lumped example: the
//! round-off floor of the switch decisions was scaled by the whole state, which the slider
//! flying away after the blow, 23 m off at 1 m/s, dominated).

use meid::analysis::simulate;
use meid::integrate::Method;
use meid::model::{Case, Model};

fn example(name: &str) -> Model {
    let path = format!("{}/../../examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Model::from_file(path.as_ref(), &[]).expect("example")
}

#[test]
fn sixty_second_runs_of_the_examples_complete_exactly() {
    sixty_second_runs(Method::Exact);
}

/// The same with dopri5 (0.3-1.0 s each): both methods reach 60 s with their energy balance
/// and the stored energy gone.
#[test]
fn sixty_second_runs_of_the_examples_complete_with_dopri5() {
    sixty_second_runs(Method::Dopri5);
}

fn sixty_second_runs(method: Method) {
    let bound = if method == Method::Exact { 1e-9 } else { 1e-6 };
    for name in [
        "paper-lumped",
        "paper-soft-base",
        "paper-stiff-base",
        "paper-no-base",
    ] {
        let m = example(name);
        let sys = m.impact_system(Case::Damper).expect("system");
        let mut o = m.options();
        o.method = method;
        o.duration = 60.0;
        o.sample_rate = None;
        let run = simulate(&sys, &o, false).unwrap_or_else(|e| panic!("{name}: {e}"));
        let s = &run.summary;
        assert!(
            (s.simulated_time_s - 60.0).abs() < 1e-9,
            "{name}: ended at {}",
            s.simulated_time_s
        );
        assert!(
            s.energy_balance_residual_run_end <= bound,
            "{name}: residual {}",
            s.energy_balance_residual_run_end
        );
        // The motion decays: at 60 s nearly all of the blow's energy has been dissipated or
        // carried off by the slider.
        let e = meid::analysis::energy::EnergyTerms::at(
            &sys,
            run.solution.mode_final,
            &run.solution.x_final,
        );
        let stored = e.total() - e.ke_slider;
        assert!(
            stored < 1e-6 * s.slider_energy_before_j,
            "{name}: {stored} J still stored"
        );
    }
}

/// On the lumped example the damper returns to the bed about every 0.16 s (the one-way dashpot
/// switching with the 6.35 Hz rigid-body mode): 60 s is some 730 switches, none of them a
/// zero-length chatter.
#[test]
fn the_lumped_example_keeps_switching_past_the_old_stall() {
    let m = example("paper-lumped");
    let sys = m.impact_system(Case::Damper).expect("system");
    let mut o = m.options();
    o.duration = 60.0;
    o.sample_rate = None;
    let run = simulate(&sys, &o, false).expect("60 s run");
    let late = run.solution.events.iter().filter(|e| e.t > 23.77).count();
    assert!(late > 200, "{late} switches after 23.77 s");
    let gaps: Vec<f64> = run
        .solution
        .events
        .windows(2)
        .map(|w| w[1].t - w[0].t)
        .collect();
    let shortest = gaps.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        shortest > 1e-9,
        "shortest stretch between switches {shortest} s"
    );
}
