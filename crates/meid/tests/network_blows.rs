//! A general machine struck at a stroke rate (`analysis::network_blows`): the steady state
//! against a closed form, against the paper engine's steady state on the paper's machine
//! written as a general one, against a long march; the start from a state; bad input.

use meid::analysis::blows::BlowOptions;
use meid::analysis::network_blows::{run_blows, steady_state};
use meid::analysis::steady::{self, Regime, SteadyOptions};
use meid::integrate::network as engine;
use meid::model::network::NetworkModel;
use meid::model::{Case, Model};

fn general(text: &str) -> NetworkModel {
    NetworkModel::from_text("test.toml", text.to_string(), &[]).unwrap()
}

fn example(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// examples/paper-lumped.toml written as a general machine (tests/data/paper_lumped_general.toml).
pub(crate) fn paper_lumped_general() -> String {
    include_str!("data/paper_lumped_general.toml").to_string()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

/// `solve` is `solve_from` at the initial state, bit for bit.
#[test]
fn solve_is_solve_from_the_initial_state() {
    let m = general(&paper_lumped_general());
    let o = m.options().unwrap();
    let a = engine::solve(&m.network, &o).unwrap();
    let x0 = engine::initial_state(&m.network).unwrap();
    let b = engine::solve_from(&m.network, x0, &o).unwrap();
    assert_eq!(a.x_final, b.x_final);
    assert_eq!(a.energy_ratio, b.energy_ratio);
    assert_eq!(a.events, b.events);
    let bad = engine::solve_from(&m.network, vec![0.0; 3], &o).unwrap_err();
    assert!(bad.to_string().contains("initial state"), "{bad}");
}

/// A mass M on a spring k to the ground (modal damping ζ) struck every T by an impactor m_s
/// at v_s through a rigid contact with restitution e (the stiff limit of a contact: an
/// instantaneous impact). Just before a strike the bed is at `y = (u, u̇)`; the impact changes
/// its velocity to `u̇ + μ (v_s − u̇)`, `μ = (1 + e) m_s/(m_s + M)` (Newton's law), i.e.
/// `y⁺ = S y + b`, `S = diag(1, 1 − μ)`, `b = (0, μ v_s)`, and the bed then decays freely for
/// T: `y' = E(T) y⁺`, `E` the damped oscillator's transition matrix. The steady state at the
/// strike is the geometric series of free decays `y* = Σ_k (E S)^k E b`, and the multipliers
/// are the eigenvalues of `E S` (`e^{AT}` times the impact's jump, `e^{AT}` itself as
/// m_s/M → 0). The energy ratio is `1 − (v'/v_s)²` with the impactor's exit velocity
/// `v' = v_s − (1 + e) M/(m_s + M)(v_s − u̇*)`. All to 1e-9.
#[test]
fn steady_state_of_a_periodically_struck_mounted_mass_is_the_geometric_series() {
    let (m, k, zeta, ms, vs, e) = (100.0_f64, 1.0e5_f64, 0.02_f64, 10.0_f64, 1.0_f64, 0.5_f64);
    let w = (k / m).sqrt();
    for cycles in [3.7, 2.2] {
        let t = cycles * 2.0 * std::f64::consts::PI / w;
        let text = format!(
            r#"
[structure]
reference_mode = 1
[structure.lumped]
damping_ratios = [{zeta}]
masses = [{{ name = "bed", mass = {m} }}]
springs = [{{ name = "mount", nodes = ["bed", "ground"], stiffness = {k} }}]
floor = ["mount"]
[[impactor]]
name = "tup"
mass = {ms}
velocity = {vs}
[[contact]]
name = "strike"
between = ["tup", "bed"]
law = "rigid"
restitution = {e}
[simulation]
duration = 1.0
"#
        );
        let model = general(&text);
        let so = SteadyOptions {
            rate_bpm: 60.0 / t,
            ..SteadyOptions::default()
        };
        let s = steady_state(&model, &so).unwrap();
        assert!(s.converged && s.regime == Regime::Period(1), "{s:?}");
        // The closed form.
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let g = (-zeta * w * t).exp();
        let (c, sn) = ((wd * t).cos(), (wd * t).sin());
        let zw = zeta * w;
        let big_e = [
            [g * (c + zw / wd * sn), g * sn / wd],
            [g * (-w * w / wd * sn), g * (c - zw / wd * sn)],
        ];
        let mu = (1.0 + e) * ms / (ms + m);
        let es = [
            [big_e[0][0], big_e[0][1] * (1.0 - mu)],
            [big_e[1][0], big_e[1][1] * (1.0 - mu)],
        ];
        let mut term = [big_e[0][1] * mu * vs, big_e[1][1] * mu * vs];
        let mut y = [0.0, 0.0];
        for _ in 0..100_000 {
            y = [y[0] + term[0], y[1] + term[1]];
            term = [
                es[0][0] * term[0] + es[0][1] * term[1],
                es[1][0] * term[0] + es[1][1] * term[1],
            ];
            if term[0].abs() + term[1].abs() < 1e-300 {
                break;
            }
        }
        // The engine's state is modal: q = √M u.
        let psi = 1.0 / m.sqrt();
        let (u, ud) = (psi * s.strike_state[0], psi * s.strike_state[1]);
        let scale = mu * vs / w;
        assert!(
            (u - y[0]).abs() < 1e-9 * scale && (ud - y[1]).abs() < 1e-9 * mu * vs,
            "T = {cycles} periods: engine (u, u̇) = ({u}, {ud}), series ({}, {})",
            y[0],
            y[1]
        );
        let v_exit = vs - (1.0 + e) * m / (ms + m) * (vs - y[1]);
        let eta = 1.0 - (v_exit / vs).powi(2);
        assert!(
            (s.energy_ratio - eta).abs() < 1e-9,
            "η {} vs {eta}",
            s.energy_ratio
        );
        let tr = es[0][0] + es[1][1];
        let det = es[0][0] * es[1][1] - es[0][1] * es[1][0];
        let disc = tr * tr - 4.0 * det;
        let mut eig = if disc < 0.0 {
            vec![det.sqrt(), det.sqrt()]
        } else {
            vec![
                (0.5 * (tr + disc.sqrt())).abs(),
                (0.5 * (tr - disc.sqrt())).abs(),
            ]
        };
        eig.sort_by(|a, b| b.total_cmp(a));
        assert_eq!(s.multipliers_abs.len(), 2);
        for (a, b) in s.multipliers_abs.iter().zip(&eig) {
            assert!(
                (a - b).abs() < 1e-9,
                "multipliers {:?} vs {eig:?}",
                s.multipliers_abs
            );
        }
        assert_eq!(s.stable, Some(true));
        assert!(s.dampers_touch.is_empty() && s.damper_touches_bed.is_none());
    }
}

/// The paper's lumped machine written as a general machine has the paper engine's steady
/// state at 20, 60 and 120 /min: energy ratio, floor force, bed acceleration and damper gap
/// to 1e-9 relative, and whether the damper touches the bed. Both searches are run to a
/// residual of 1e-12 (the default 1e-10 leaves the fixed point uncertain by about 1e-10 of
/// the blow's energy norm, 2e-9 of the 0.17 mm gap at 20 /min).
#[test]
fn the_paper_machine_as_a_general_one_has_the_paper_engines_steady_state() {
    let paper = Model::from_file(&example("paper-lumped.toml"), &[]).unwrap();
    let sys = paper.impact_system(Case::Damper).unwrap();
    let gen = general(&paper_lumped_general());
    for rate in [20.0, 60.0, 120.0] {
        let so = SteadyOptions {
            rate_bpm: rate,
            tolerance: 1e-12,
            ..SteadyOptions::default()
        };
        let p = steady::steady_state(&sys, &paper.options(), &so).unwrap();
        let g = steady_state(&gen, &so).unwrap();
        let what = format!(
            "{rate} /min: paper {} η {} F {} a {} gap {:?} touches {:?}; general {} η {} F {:?} a {} gap {:?} touches {:?} ({} evaluations)",
            p.regime.name(), p.energy_ratio, p.peak_floor_force_n, p.peak_bed_acceleration_m_per_s2,
            p.damper_gap_at_strike_m, p.damper_touches_bed,
            g.regime.name(), g.energy_ratio, g.peak_floor_force_n, g.peak_bed_acceleration_m_per_s2,
            g.damper_gap_at_strike_m, g.damper_touches_bed, g.map_evaluations
        );
        eprintln!("{what}");
        assert!(p.converged && g.converged, "{what}");
        assert_eq!(p.regime, g.regime, "{what}");
        assert!(rel(g.energy_ratio, p.energy_ratio) < 1e-9, "{what}");
        assert!(
            rel(g.peak_floor_force_n.unwrap(), p.peak_floor_force_n) < 1e-9,
            "{what}"
        );
        assert!(
            rel(
                g.peak_bed_acceleration_m_per_s2,
                p.peak_bed_acceleration_m_per_s2
            ) < 1e-9,
            "{what}"
        );
        let (gg, pg) = (
            g.damper_gap_at_strike_m.unwrap(),
            p.damper_gap_at_strike_m.unwrap(),
        );
        assert!((gg - pg).abs() <= 1e-9 * pg.abs() + 1e-15, "{what}");
        assert_eq!(g.damper_touches_bed, p.damper_touches_bed, "{what}");
        assert_eq!(g.dampers_touch.len(), 1);
        assert_eq!(g.dampers_touch[0].touches, p.damper_touches_bed.unwrap());
    }
}

/// A search whose Newton phase cannot converge within its share of the budget still marches
/// and finds the regime. With k_d = 2e3 N/m and c_d = 300 N·s/m at 60 /min the damper of the
/// paper's lumped machine settles just off the bed (gap 0.44 mm at the strike): the general
/// machine's forward-difference Newton does not descend near that grazing state (each step
/// costs 7 blows), and before the search left room for marching it spent the whole budget and
/// reported an "irregular" train with no blow. Now it hands over to the march, which settles on
/// period-1 and is refined to the paper engine's steady state (exact path Jacobian): floor
/// force and gap to 1e-9, within the budget.
#[test]
fn a_newton_search_that_stalls_hands_over_to_the_march() {
    let sets = [
        "damper.stiffness=2e3".to_string(),
        "damper.damping=300".to_string(),
    ];
    let paper = Model::from_file(&example("paper-lumped.toml"), &sets).unwrap();
    let sys = paper.impact_system(Case::Damper).unwrap();
    let gen = NetworkModel::from_text(
        "test.toml",
        paper_lumped_general(),
        &[
            "damper.damper.stiffness=2e3".to_string(),
            "damper.damper.damping=300".to_string(),
        ],
    )
    .unwrap();
    let so = SteadyOptions {
        rate_bpm: 60.0,
        tolerance: 1e-12,
        ..SteadyOptions::default()
    };
    let p = steady::steady_state(&sys, &paper.options(), &so).unwrap();
    let g = steady_state(&gen, &so).unwrap();
    let what = format!("paper {p:?}\ngeneral {g:?}");
    assert!(p.converged && g.converged, "{what}");
    assert_eq!(
        (p.regime, g.regime),
        (Regime::Period(1), Regime::Period(1)),
        "{what}"
    );
    assert!(g.map_evaluations <= so.max_evaluations, "{what}");
    assert!(
        rel(g.peak_floor_force_n.unwrap(), p.peak_floor_force_n) < 1e-9,
        "{what}"
    );
    let (gg, pg) = (
        g.damper_gap_at_strike_m.unwrap(),
        p.damper_gap_at_strike_m.unwrap(),
    );
    assert!(pg > 1e-4 && rel(gg, pg) < 1e-9, "{what}");
    assert_eq!(g.damper_touches_bed, Some(false), "{what}");
    assert_eq!(p.damper_touches_bed, Some(false), "{what}");
}

/// A 60-blow march from rest and the direct steady state agree within 1e-6 (relative) in
/// every reported level where the march has settled (within the geometric tail the slowest
/// multiplier leaves), at 60 and 120 /min on the paper's machine as a general one; the first
/// blow of the march is `simulate` with duration T.
#[test]
fn a_long_march_settles_on_the_direct_steady_state() {
    let gen = general(&paper_lumped_general());
    for rate in [60.0, 120.0] {
        let s = steady_state(
            &gen,
            &SteadyOptions {
                rate_bpm: rate,
                ..SteadyOptions::default()
            },
        )
        .unwrap();
        let march = run_blows(
            &gen,
            &BlowOptions {
                blows: 60,
                rate_bpm: rate,
                steady_tolerance: 1e-9,
            },
        )
        .unwrap();
        let n = march.blows.len();
        let (last, prev) = (&march.blows[n - 1], &march.blows[n - 2]);
        let mu = s.multipliers_abs[0];
        let close = |a: f64, b: f64, b_prev: f64| {
            let tail = (b - b_prev).abs() * mu / (1.0 - mu);
            (a - b).abs() <= (1e-6 * b.abs()).max(2.0 * tail)
        };
        let what = format!("{rate} /min: steady {s:?}\nlast {last:?}");
        assert!(
            close(
                s.energy_ratio,
                last.energy_ratio.unwrap(),
                prev.energy_ratio.unwrap()
            ),
            "{what}"
        );
        assert!(
            close(
                s.peak_floor_force_n.unwrap(),
                last.peak_floor_force_n.unwrap(),
                prev.peak_floor_force_n.unwrap()
            ),
            "{what}"
        );
        assert!(
            close(
                s.peak_bed_acceleration_m_per_s2,
                last.peak_bed_acceleration_m_per_s2,
                prev.peak_bed_acceleration_m_per_s2
            ),
            "{what}"
        );
        assert_eq!(
            s.dampers_touch[0].touches, last.dampers[0].touched,
            "{what}"
        );
        // Blow 1 is the single run of duration T.
        let mut o = gen.options().unwrap();
        o.duration = 60.0 / rate;
        let one = gen.solve(&o).unwrap();
        assert_eq!(one.energy_ratio, march.blows[0].energy_ratio);
    }
}

/// Bad stroke rates name the option: ≤ 0, NaN, and an interval shorter than the collision.
#[test]
fn bad_stroke_rates_name_the_option() {
    let gen = general(&paper_lumped_general());
    for r in [0.0, -5.0, f64::NAN] {
        let e = steady_state(
            &gen,
            &SteadyOptions {
                rate_bpm: r,
                ..SteadyOptions::default()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("--rate-bpm") && e.contains("> 0"), "{e}");
    }
    let e = run_blows(
        &gen,
        &BlowOptions {
            blows: 3,
            rate_bpm: 1.0e6,
            steady_tolerance: 0.01,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("--rate-bpm") && e.contains("shorter than the collision"),
        "{e}"
    );
    let e = run_blows(
        &gen,
        &BlowOptions {
            blows: 0,
            rate_bpm: 60.0,
            steady_tolerance: 0.01,
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("--blows"), "{e}");
}
